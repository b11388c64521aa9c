"""Command line of the GNSS engine: ``inskit spp``, a thin layer over
:func:`inskit.jobs.spp.run_spp`.

Wiring into :mod:`inskit.cli` (done there, not here)::

    from .cli_gnss import register
    register(cli)

Conventions of :mod:`inskit.cli`: ``--json`` prints exactly one JSON object on
stdout, logs go to stderr, user errors raise :class:`~inskit.errors.InputError`
(``inskit.cli.main`` turns them into one line and exit status 2).
"""

from __future__ import annotations

import sys

import click

from .cli_output import emit as _emit
from .cli_output import FINITE
from .cli_output import log as _log
from .cli_output import log_health
from .cli_output import SEED
from .errors import InputError


def _f(x, fmt="8.2f"):
    return "     n/a" if x is None else format(float(x), fmt)


def _table(res):
    first = (f"{res['epochs_solved']} of {res['epochs_total']} epochs solved "
             f"({res['epochs_excluded_sats']} with excluded satellites, {res['epochs_flagged']} flagged, "
             f"{res['epochs_unsolved']} unsolved); median {res['n_sats_median']:.0f} satellites, "
             f"HDOP {res['hdop_median']:.2f}; {res['seconds']:.2f} s")
    lines = [first]
    if res.get("horizontal_rms_m") is not None:
        m, s = res["mean_neu_m"], res["std_neu_m"]
        lines.append(f"{'error vs reference [m]':<24}{'North':>8}{'East':>8}{'Up':>8}")
        lines.append(f"{'mean':<24}{_f(m[0])}{_f(m[1])}{_f(m[2])}")
        lines.append(f"{'std':<24}{_f(s[0])}{_f(s[1])}{_f(s[2])}")
        lines.append(f"horizontal RMS {res['horizontal_rms_m']:.2f} m, 3-D RMS {res['rms_3d_m']:.2f} m, "
                     f"max horizontal {res['max_horizontal_m']:.2f} m")
    else:
        lines.append("no --reference: errors not scored")
    if res["files"]:
        lines.append("files: " + ", ".join(res["files"]))
    return "\n".join(lines)


@click.command("spp", context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("obs", type=click.Path(dir_okay=False))
@click.argument("nav", type=click.Path(dir_okay=False))
@click.option("--reference", help="Score against this ECEF position: X,Y,Z [m], or 'header' for the observation "
              "header's APPROX POSITION XYZ.")
@click.option("--mask", "mask_deg", type=FINITE, default=10.0, show_default=True, help="Elevation mask [deg].")
@click.option("--iono", type=click.Choice(["klobuchar", "iono-free", "none"]), default="klobuchar",
              show_default=True, help="Ionosphere: broadcast Klobuchar (the nav header's coefficients, else a "
              "default set), dual-frequency iono-free code, or none.")
@click.option("--tropo", type=click.Choice(["saastamoinen", "none"]), default="saastamoinen", show_default=True,
              help="Troposphere model.")
@click.option("--systems", default="G,E", show_default=True, help="GNSS systems to use, comma-separated (G, E).")
@click.option("--no-raim", is_flag=True, help="Flag epochs that fail the residual test instead of excluding "
              "satellites.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), help="Output folder: spp.pos (RTKLIB format), "
              "spp_solution.csv (GNSS fixes for navigate), spp_epochs.csv, summary.json.")
@click.option("--force", is_flag=True, help="Overwrite the files of an earlier run in --out.")
@click.option("--strict", is_flag=True, help="Exit with status 3 when the run's health verdict is unhealthy.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def spp(obs, nav, reference, mask_deg, iono, tropo, systems, no_raim, out_dir, force, strict, as_json):
    """Single-point positioning of the RINEX observation file OBS with the
    broadcast ephemerides of the RINEX navigation file NAV (RINEX 2 or 3;
    GPS and Galileo code pseudoranges, Doppler velocity when present)."""
    from .jobs.spp import run_spp

    res = run_spp(obs, nav, reference=reference, mask_deg=mask_deg, iono=iono, tropo=tropo, systems=systems,
                  out=out_dir, overwrite=force, raim=not no_raim, log=_log)
    h = res["health"]
    log_health(h)
    _emit(res, as_json, _table(res))
    if strict and h["verdict"] != "healthy":
        sys.exit(3)


@click.command("tight-coupling")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Folder for the figures "
              "(and the simulated blockage drive's files).")
@click.option("--experiment", type=click.Choice(["walk", "blockage", "all"]), default="all", show_default=True)
@click.option("--seed", type=SEED, default=None, help="Seed of the simulated blockage drive [default: 1] (the walk "
              "is a real log: no seed).")
@click.option("--force", is_flag=True, help="Write into a folder that already holds files, replacing those of the "
              "figures' and the simulated drive's names.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def reproduce_tight(out_dir, experiment, seed, force, as_json):
    """Tight against loose coupling (source 000: tight coupling works with
    fewer than four satellites): the bundled walk_0827 raw log against its RTK
    track, and a simulated drive through blockages keeping 3, 2 and 1
    satellites."""
    from .jobs.reproduce_tight import run

    from .cli_output import reproduce_into

    exps = ("walk", "blockage") if experiment == "all" else (experiment,)
    if seed is not None and "blockage" not in exps:
        raise InputError("--seed would be ignored: it seeds the simulated blockage drive, and --experiment walk runs "
                         "the real walk_0827 log only; drop --seed, or use --experiment blockage or all")
    seed = 1 if seed is None else seed
    (res, text), files = reproduce_into(out_dir, force, lambda d: run(d, exps, seed=seed, log=_log))
    res["figures"] = res["files"]
    res["files"] = files  # every file written: the simulated drive's too (it listed the figures only)
    _emit(res, as_json, text + "\nfigures: " + ", ".join(res["figures"]))


def register(cli_group, reproduce_group=None):
    """Add ``spp`` to the main command group (and ``tight-coupling`` to
    ``reproduce``)."""
    cli_group.add_command(spp)
    if reproduce_group is not None:
        reproduce_group.add_command(reproduce_tight)


__all__ = ["register", "reproduce_tight", "spp"]
