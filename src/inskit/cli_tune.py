"""Command line of ``inskit tune CONFIG --grid SECTION.KEY=V1,V2 ...``, a thin
layer over :func:`inskit.jobs.tune.tune` (settings chosen by cross-validation
on validation outages of the job's own, never on the protocol's withheld
fixes).  ``--json`` prints one JSON object on stdout; progress goes to stderr.
"""

from __future__ import annotations


import click

from .cli_output import emit as _emit
from .cli_output import FiniteFloatRange


@click.command("tune", context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("config_file", type=click.Path(dir_okay=False))
@click.option("--grid", "grids", multiple=True, required=True, metavar="SECTION.KEY=V1,V2,...",
              help="Candidate values of one config key (repeat for more keys: every combination is run), e.g. "
                   "--grid noise.bias_tau_s=300,3000 --grid constraints.nhc_sigma_m_s=0.1,0.3.")
@click.option("--hold", "hold_s", type=FiniteFloatRange(min=1.0),
              help="Length of each validation outage [s]  [default: the median length of the config's outages, "
                   "else 10 s]")
@click.option("--reaid", "reaid_s", type=FiniteFloatRange(min=0.0),
              help="Aiding kept before and after each validation outage [s]  [default: 10 s, less (down to 2 s) "
                   "where one validation outage would not fit between the config's outages]")
@click.option("--start-after", "start_after_s", type=FiniteFloatRange(min=0.0), default=60.0, show_default=True,
              help="No validation outage in the first seconds after the first fix (start-up).")
@click.option("--shifts", type=click.IntRange(min=1), default=1, show_default=True,
              help="Placements of the validation outages, shifted together within the aided stretches (each "
                   "keeping 5 s of aiding on both sides); every candidate runs once per placement and is scored "
                   "over all of them (more outages: a choice less at the mercy of a few).")
@click.option("--workers", type=click.IntRange(min=1), help="Parallel runs  [default: every core]")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def tune(config_file, grids, hold_s, reaid_s, start_after_s, shifts, workers, as_json):
    """Choose filter settings by cross-validation: each candidate is run with
    the config's own outages withheld plus validation outages placed where the
    protocol keeps GNSS on, and ranked by its error at their ends."""
    from .cli_output import progress
    from .jobs.tune import candidates, parse_grid, table_text, tune as run_tune

    grid = parse_grid(grids)
    with progress(len(candidates(grid)), "tune", unit="candidate") as bar:
        res = run_tune(config_file, grid, hold_s=hold_s, reaid_s=reaid_s, start_after_s=start_after_s,
                       workers=workers, progress=bar.update, shifts=shifts)
    _emit(res, as_json, table=table_text(res))


def register(cli):
    """Add ``tune`` to the ``inskit`` command group."""
    cli.add_command(tune)
