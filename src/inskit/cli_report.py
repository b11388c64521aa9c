"""Command line of the run report: ``inskit report RUN_DIR``, a thin layer
over :func:`inskit.jobs.report.build_report`.

Wiring into :mod:`inskit.cli` (done there, not here)::

    from .cli_report import register
    register(cli)

``--json`` prints exactly one JSON object on stdout; user errors raise
:class:`~inskit.errors.InputError` (``inskit.cli.main`` turns them into one
line and exit status 2).
"""

from __future__ import annotations

import click

from .cli_output import emit as _emit


@click.command("report", context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("run_dir", type=click.Path(file_okay=False))
@click.option("--out", "out_file", type=click.Path(dir_okay=False),
              help="HTML file to write (default RUN_DIR/report.html).")
@click.option("--force", is_flag=True, help="Overwrite the HTML file if it exists.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON summary object on stdout.")
def report(run_dir, out_file, force, as_json):
    """One self-contained HTML page (plotly inlined, compressed; works
    offline in Chrome/Edge 80+, Firefox 113+, Safari 16.4+) of a navigate
    run folder: health, key figures, track, sigmas, innovations, sensor
    estimates, outages and the configuration used."""
    from .jobs.report import build_report

    res = build_report(run_dir, out_file, overwrite=force)
    _emit(res, as_json, table=f"report: {res['report']} ({res['bytes'] / 1e6:.2f} MB, plots: "
                              f"{', '.join(res['plots'])}; {res['seconds']:.2f} s)")


def register(cli):
    """Add ``report`` to the ``inskit`` command group."""
    cli.add_command(report)
