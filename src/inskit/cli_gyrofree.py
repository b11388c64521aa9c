"""Command line of the gyro-free INS (source 003): a thin layer over
:mod:`inskit.jobs_gyrofree`.

* group ``gyrofree`` with ``simulate`` and ``navigate``;
* command ``reproduce_gyrofree``, registered as ``inskit reproduce gyrofree``.

Wiring into :mod:`inskit.cli` (done there, not here)::

    from .cli_gyrofree import register
    register(cli, reproduce)

Conventions of :mod:`inskit.cli`: ``--json`` prints exactly one JSON object on
stdout, logs go to stderr, user errors raise :class:`~inskit.errors.InputError`
(``inskit.cli.main`` turns them into one line and exit status 2).
"""

from __future__ import annotations


import click

from .cli_output import emit as _emit
from .cli_output import FINITE, RATE_HZ
from .cli_output import log as _log
from .cli_output import SEED

from .errors import InputError
from .units import MAX_RATE_HZ, MAX_SAMPLES








def _fmt3(v):
    return "[" + ", ".join(f"{float(x):.6g}" for x in v) + "]"


_LAYOUT_HELP = "ten, six (the source's layouts, lever arm --d) or a layout CSV file (docs/formats.md)."


@click.group("gyrofree", context_settings={"help_option_names": ["-h", "--help"]})
def gyrofree():
    """Gyro-free INS from an array of accelerometers (source 003)."""


@gyrofree.command("simulate")
@click.argument("scenario")
@click.option("--layout", "layout_spec", default="ten", show_default=True, help=_LAYOUT_HELP)
@click.option("--d", "d", type=FINITE, help="Lever arm of ten/six [m]  [default: 0.1]")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output folder.")
@click.option("--rate", "rate_hz", type=RATE_HZ, metavar="HZ", help="Sampling rate [Hz] (default 1000 for "
              f"source003, else the scenario's IMU rate; at most {MAX_RATE_HZ:g} Hz).")
@click.option("--duration", type=FINITE, help="Length [s] (default 10 for source003, else the scenario's; at most "
              f"the scenario's, and {MAX_SAMPLES:,} samples).")
@click.option("--bias-ug", type=FINITE, default=0.0, show_default=True, help="Bias of every accelerometer [micro-g].")
@click.option("--bias-sigma-ug", type=FINITE, default=0.0, show_default=True,
              help="Random bias per accelerometer, 1 sigma [micro-g].")
@click.option("--noise-ug", type=FINITE, default=0.0, show_default=True,
              help="White noise density [micro-g/sqrt(Hz)].")
@click.option("--scale-ppm", type=FINITE, default=0.0, show_default=True, help="Scale-factor error, 1 sigma [ppm].")
@click.option("--misalignment-mrad", type=FINITE, default=0.0, show_default=True,
              help="Random sensing-axis misalignment, 1 sigma per component [mrad].")
@click.option("--source-theta-deg", help="The source's misalignment angles of m1-m6 [deg], six comma-separated "
              "numbers (eq. 26-36).")
@click.option("--seed", type=SEED, default=0, show_default=True, help="Seed of every random draw.")
@click.option("--force", is_flag=True, help="Overwrite files in --out.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def simulate(scenario, layout_spec, d, out_dir, rate_hz, duration, bias_ug, bias_sigma_ug, noise_ug, scale_ppm,
             misalignment_mrad, source_theta_deg, seed, force, as_json):
    """Simulate an accelerometer array on SCENARIO: 'source003' (the source's
    constant-rate motion, inertial frame, no gravity) or a scenario TOML file.

    Writes array.csv (one column per accelerometer), layout.csv and truth.csv.
    """
    from .jobs.gyrofree import _parse_vector, simulate_job

    theta = None if source_theta_deg is None else _parse_vector(source_theta_deg, 6, "--source-theta-deg")
    res = simulate_job(scenario, layout_spec, out_dir, d=d, rate_hz=rate_hz, duration=duration, seed=seed,
                       overwrite=force, log=_log, bias_ug=bias_ug, bias_sigma_ug=bias_sigma_ug,
                       noise_ug_sqrt_hz=noise_ug, scale_sigma_ppm=scale_ppm,
                       misalignment_sigma_mrad=misalignment_mrad, source_theta_deg=theta)
    text = (f"{res['scenario']} ({res['kind']}): {res['samples']} samples at {res['rate_hz']:g} Hz of layout "
            f"{res['layout']} ({res['accelerometers']} accelerometers) -> {out_dir}/")
    _emit(res, as_json, text)


@gyrofree.command("navigate")
@click.argument("array_file", type=click.Path(dir_okay=False))
@click.option("--layout", "layout_spec", default="ten", show_default=True, help=_LAYOUT_HELP)
@click.option("--d", "d", type=FINITE, help="Lever arm of ten/six [m]  [default: 0.1]")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output folder.")
@click.option("--solver", type=click.Choice(["auto", "closed-form", "least-squares"]), default="auto",
              show_default=True, help="auto: the closed form for the ten layout, least squares otherwise.")
@click.option("--sign-rule", type=click.Choice(["robust", "source"]), default="robust", show_default=True,
              help="Closed form: how r's sign is found (source: eq. 15, divides by p).")
@click.option("--frame", type=click.Choice(["source", "ned", "wander", "ecef", "inertial"]), default="source",
              show_default=True, help="source: eq. 43-44 in an inertial frame without gravity; others: the core "
              "mechanizations on the WGS84 Earth.")
@click.option("--init", "init_text", help="Earth frames: lat_deg,lon_deg,height_m,vn,ve,vd,roll_deg,pitch_deg,yaw_deg.")
@click.option("--init-from", type=click.Path(dir_okay=False), help="Initial state (and rate) from a truth file.")
@click.option("--omega0", help="Initial body rate p,q,r [rad/s] (its signs fix the rate's sign).")
@click.option("--noise", "noise", type=FINITE, default=0.0, show_default=True,
              help="Per-sample accelerometer noise [m/s^2] for the closed form's sign rule.")
@click.option("--filter-noise", type=FINITE, help="Per-sample accelerometer noise [m/s^2]: least squares with the "
              "rate filter.")
@click.option("--truth", "truth_file", type=click.Path(dir_okay=False), help="Truth file: add errors to the summary.")
@click.option("--force", is_flag=True, help="Overwrite files in --out.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def navigate(array_file, layout_spec, d, out_dir, solver, sign_rule, frame, init_text, init_from, omega0, noise,
             filter_noise, truth_file, force, as_json):
    """Solve ARRAY_FILE (raw outputs) for specific force and rate, then navigate.

    Writes rates.csv (IMU format, readable by `inskit mechanize --no-unit-check`)
    and solution.csv (inertial format for --frame source, NED solution
    otherwise).
    """
    from .jobs.gyrofree import navigate_job

    if filter_noise is not None and not filter_noise > 0:
        raise InputError(f"--filter-noise must be > 0 m/s^2, got {filter_noise}")
    if not noise >= 0:
        raise InputError(f"--noise must be >= 0 m/s^2, got {noise}")
    from .gyrofree.solvers import InitialRateNeeded

    try:
        res = navigate_job(array_file, layout_spec, out_dir, d=d, solver=solver, frame=frame, init=init_text,
                           init_from=init_from, omega0=omega0, rate_filter_noise=filter_noise, sign_rule=sign_rule,
                           noise_sigma=noise, truth_file=truth_file, overwrite=force, log=_log)
    except InitialRateNeeded as e:  # said in the options' words, not the Python argument's
        raise InputError(f"{e.reason}; give --omega0 p,q,r [rad/s] (an approximate initial rate: only its signs "
                         "are used) or --init-from a truth file (its first rates)") from None
    f = res["final"]
    text = f"{res['samples']} samples, solver {res['solver']}, frame {res['frame']} -> {out_dir}/"
    if "r_i_m" in f:
        text += f"\nfinal inertial position {_fmt3(f['r_i_m'])} m at {f['time_s']:.3f} s"
    else:
        text += f"\nfinal lat {f['lat_deg']:.8f} deg, lon {f['lon_deg']:.8f} deg, h {f['height_m']:.3f} m"
    if "truth_errors" in res:
        text += "\nagainst the truth: " + ", ".join(f"{k} {v:.4g}" for k, v in res["truth_errors"].items())
    _emit(res, as_json, text)


@click.command("gyrofree")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Folder for figures and tables.")
@click.option("--quick", is_flag=True, help="Coarser grids and fewer runs (a few seconds).")
@click.option("--force", is_flag=True, help="Write into a folder that already holds files, replacing those of the "
              "figures' and tables' names.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def reproduce_gyrofree(out_dir, quick, force, as_json):
    """Source 003: published vs ours, figures 11-14, sensitivity, 60 s comparison."""
    from .cli_output import reproduce_into
    from .jobs.gyrofree import reproduce_gyrofree as job

    res, files = reproduce_into(out_dir, force, lambda d: job(d, quick=quick, log=_log))
    res["files"] = files
    lines = [f"{'item':<70} {'published':<24} ours"]
    for e in res["entries"]:
        lines.append(f"{e['item']:<70} {e['published']!s:<24} {e['ours']}")
        lines.append(f"{'':<4}note: {e['note']}")
    lines.append("60 s growth (" + res["growth_grades"] + "):")
    for r in res["growth_60s"]:
        lines.append(f"  {r['unit']:<36}" + "  ".join(f"{k[4:-2]} {v:.3g} m" for k, v in r.items() if k != "unit"))
    lines.append(f"figures: {', '.join(res['figures'])}")
    _emit(res, as_json, "\n".join(lines))


def register(cli_group, reproduce_group):
    """Add ``gyrofree`` to the main group and ``gyrofree`` to ``reproduce``."""
    cli_group.add_command(gyrofree)
    reproduce_group.add_command(reproduce_gyrofree, "gyrofree")


__all__ = ["gyrofree", "register", "reproduce_gyrofree"]
