"""Command-line layer of the platform INS (registered by :mod:`inskit.cli`).

* ``inskit platform simulate SCENARIO --kind semi-analytical|analytical|geometric --out DIR [--json]``
* ``inskit platform integrate SCENARIO --scheme open|closed --filter kalman|first-order|second-order --out DIR [--json]``
* ``inskit reproduce integration-filters --out DIR [--json]``

As everywhere in the CLI: ``--json`` prints exactly one JSON object on
stdout, progress and logs go to stderr, bad input raises
:class:`~inskit.errors.InputError` (one line, exit status 2 through
``inskit.cli.main``).
"""

from __future__ import annotations

from pathlib import Path

import click

from .cli_output import emit as _emit
from .cli_output import FINITE
from .cli_output import log as _log
from .cli_output import SEED
import numpy as np

from .errors import InputError
from .units import MAX_RATE_HZ

__all__ = ["platform", "reproduce_integration_filters"]








def _triple(name, text):
    if text is None:
        return None
    try:
        v = [float(x) for x in text.split(",")]
    except ValueError:
        raise InputError(f"{name}: expected three numbers x,y,z, got {text!r}") from None
    if len(v) != 3 or not np.isfinite(v).all():
        raise InputError(f"{name}: expected three finite numbers x,y,z, got {text!r}")
    return v


def _check_scenario(path):
    if not Path(path).is_file():
        raise InputError(f"{path}: no such scenario file")


def _common(f):
    f = click.option("--earth", "earth_model", type=click.Choice(["wgs84", "sphere"]), default="wgs84",
                     show_default=True, help="Earth model of world and computer (sphere: R = 6378 km).")(f)
    f = click.option("--dt", type=FINITE, default=1.0, show_default=True, help="Step of the simulation [s] (at "
                     f"least {1.0 / MAX_RATE_HZ:g} s: every rate is capped at {MAX_RATE_HZ:g} Hz).")(f)
    f = click.option("--duration", type=FINITE, help="Use only the first seconds of the scenario.")(f)
    f = click.option("--seed", type=SEED, default=0, show_default=True, help="Seed of every random draw.")(f)
    f = click.option("--gyro-drift-deg-h", help="Gyro drifts x,y,z [deg/h], platform axes (default: the scenario's "
                                                "IMU grade).")(f)
    f = click.option("--accel-bias-ug", help="Accelerometer biases x,y,z [micro-g] (default: the scenario's grade).")(f)
    f = click.option("--force", is_flag=True, help="Overwrite files in --out.")(f)
    f = click.option("--no-plots", is_flag=True, help="Skip the PNG plots.")(f)
    f = click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")(f)
    return f


def _errors_text(s):
    e = s["errors"]
    return (f"horizontal error: RMS {e['horizontal_m']['rms']:.2f} m, max {e['horizontal_m']['max']:.2f} m, "
            f"final {e['horizontal_m']['final']:.2f} m; velocity north/east RMS {e['vn_m_s']['rms']:.3f}/"
            f"{e['ve_m_s']['rms']:.3f} m/s; roll/pitch/yaw RMS {e['roll_arcmin']['rms']:.3f}/"
            f"{e['pitch_arcmin']['rms']:.3f}/{e['yaw_arcmin']['rms']:.3f} arcmin")


@click.group()
def platform():
    """Gimballed-platform INS: simulate the three kinds, integrate with satellites."""


@platform.command("simulate")
@click.argument("scenario_file", type=click.Path(dir_okay=False))
@click.option("--kind", type=click.Choice(["semi-analytical", "analytical", "geometric"]), default="semi-analytical",
              show_default=True, help="Kind of platform INS.")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output folder.")
@_common
def simulate(scenario_file, kind, out_dir, earth_model, dt, duration, seed, gyro_drift_deg_h, accel_bias_ug, force,
             no_plots, as_json):
    """Fly a scenario with a platform INS: solution (with tilt and gimbal
    angles), truth, error plots."""
    from .jobs.platform import simulate_job

    _check_scenario(scenario_file)
    s = simulate_job(scenario_file, out_dir, kind=kind, earth_model=earth_model, dt=dt, seed=seed,
                     gyro_drift_deg_h=_triple("--gyro-drift-deg-h", gyro_drift_deg_h),
                     accel_bias_ug=_triple("--accel-bias-ug", accel_bias_ug), duration=duration, overwrite=force,
                     plot=not no_plots, log=_log)
    _log(f"wrote {len(s['files'])} files to {out_dir}/")
    text = (f"{s['scenario']}: {kind} platform, {s['epochs']} epochs over {s['duration_s']:.0f} s "
            f"({s['elapsed_s']:.2f} s)\n" + _errors_text(s) +
            "\nplatform tilt max (E, N, U): " + ", ".join(f"{v:.3f}" for v in s["tilt_max_arcmin"]) + " arcmin")
    _emit(s, as_json, text)


@platform.command("integrate")
@click.argument("scenario_file", type=click.Path(dir_okay=False))
@click.option("--scheme", type=click.Choice(["open", "closed"]), default="closed", show_default=True,
              help="Open loop (estimates subtracted) or closed loop (estimates fed back).")
@click.option("--filter", "estimator", type=click.Choice(["kalman", "first-order", "second-order"]), default="kalman",
              show_default=True, help="Estimator of the INS errors.")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output folder.")
@_common
def integrate(scenario_file, scheme, estimator, out_dir, earth_model, dt, duration, seed, gyro_drift_deg_h,
              accel_bias_ug, force, no_plots, as_json):
    """Semi-analytical platform INS integrated with the scenario's satellite
    fixes (source 004's open and closed loops)."""
    from .jobs.platform import integrate_job

    _check_scenario(scenario_file)
    s = integrate_job(scenario_file, out_dir, scheme=scheme, estimator=estimator, earth_model=earth_model, dt=dt,
                      seed=seed, gyro_drift_deg_h=_triple("--gyro-drift-deg-h", gyro_drift_deg_h),
                      accel_bias_ug=_triple("--accel-bias-ug", accel_bias_ug), duration=duration, overwrite=force,
                      plot=not no_plots, log=_log)
    _log(f"wrote {len(s['files'])} files to {out_dir}/")
    text = (f"{s['scenario']}: {scheme} loop, {estimator}, {s['epochs']} epochs, {s['fixes']} fixes "
            f"({s['elapsed_s']:.2f} s)\n" + _errors_text(s))
    _emit(s, as_json, text)


@click.command("integration-filters")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Folder for the figures.")
@click.option("--quick", is_flag=True, hidden=True, help="2 h instead of 8 h (tests).")
@click.option("--force", is_flag=True, help="Write into a folder that already holds files, replacing those of the "
              "figures' and tables' names.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def reproduce_integration_filters(out_dir, quick, force, as_json):
    """Source 004: table 1 (Kalman against first- and second-order filters),
    figure 3, open against closed loop through a satellite outage."""
    from .cli_output import reproduce_into
    from .jobs.platform import reproduce_integration_filters as run

    res, files = reproduce_into(out_dir, force, lambda d: run(d, log=_log, quick=quick))
    res["files"] = files
    lines = [f"{'item':<84} {'published':<16} ours"]
    for e in res["entries"]:
        ours = e["ours"] if isinstance(e["ours"], str) else f"{e['ours']:.3g}"
        lines.append(f"{e['item']:<84} {e['published']!s:<16} {ours}")
        if e.get("note"):
            lines.append(f"{'':<4}note: {e['note']}")
    lines.append("outage (horizontal error, m): " + "; ".join(
        f"{r['filter']} {r['scheme']}: {r['start_m']:.1f} -> {r['end_m']:.1f}" for r in res["outage"]))
    lines.append(f"figures: {', '.join(res['figures'])}")
    _emit({"experiment": "integration-filters", "source": "004", **res}, as_json, "\n".join(lines))
