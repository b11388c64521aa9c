"""Command line of studies: ``inskit study SPEC.toml --out DIR``, a thin layer
over :func:`inskit.jobs.study.run_study`.

Wiring into :mod:`inskit.cli` (done there, not here)::

    from .cli_study import register
    register(cli)

``--json`` prints exactly one JSON object on stdout; the progress bar and logs
go to stderr; user errors raise :class:`~inskit.errors.InputError` or
:class:`~inskit.errors.ConfigError`.
"""

from __future__ import annotations


import click

from .cli_output import emit as _emit
from .cli_output import log as _log


def _bar(total, initial):
    from .cli_output import progress

    bar = progress(total, "study", unit="run", initial=initial, smoothing=0.05)
    return bar.update


@click.command("study", context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("spec_file", type=click.Path(dir_okay=False))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Results folder (Parquet tables, summary.json, study.png); rerun with the same folder to "
                   "resume an interrupted study.")
@click.option("--scheduler", metavar="ADDRESS",
              help="Address of a running Dask scheduler (tcp://host:8786); default: a local cluster.")
@click.option("--workers", type=click.IntRange(min=1),
              help="Worker processes of the local cluster (1 thread each)  [default: every core]")
@click.option("--force", is_flag=True, help="Write into a folder that is not a study's even though it holds files "
              "of the study's names (runs.parquet, summary.parquet, summary.json, study.png), replacing them.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON summary object on stdout.")
def study(spec_file, out_dir, scheduler, workers, force, as_json):
    """Monte Carlo study or sensor-grade / filter sweep on Dask (seeded per
    (case, run): results do not depend on the workers), resumable."""
    from .jobs.study import ranking_table, run_study

    res = run_study(spec_file, out_dir, scheduler=scheduler, workers=workers, progress=_bar, log=_log,
                    force=force)
    _emit(res, as_json, table=ranking_table(res))


def register(cli):
    """Add ``study`` to the ``inskit`` command group."""
    cli.add_command(study)
