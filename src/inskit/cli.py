"""The ``inskit`` command line: a thin layer over the library.

Every command that reports results takes ``--json`` and then prints exactly
one JSON object on stdout; logs and progress go to stderr.  User errors print
one line ``inskit: error: ...`` and exit with status 2.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import click
import numpy as np

from .cli_output import emit as _emit
from .cli_output import FINITE, RATE_HZ
from .cli_output import log as _log
from .cli_output import log_health
from .cli_output import SEED
from .errors import InputError, InskitError
from .units import DEG, MAX_RATE_HZ








def _progress(total, desc):
    from .cli_output import progress

    return progress(total, desc, unit="epoch", unit_scale=True, leave=False)


class _Group(click.Group):
    """The top group: an ``EOFError`` out of a command (a truncated gzip file
    a reader did not catch) is a user error, not click's ``Abort`` ("inskit:
    aborted", exit 130, as for Ctrl-C)."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except EOFError as exc:
            raise InputError(f"an input file ended early ({exc or 'end of file'}): truncated or damaged?") from None


def _print_version(ctx, param, value):
    """``--version``: the installed version, looked up only when asked
    (importlib.metadata is 18 ms of every command's start-up)."""
    if not value or ctx.resilient_parsing:
        return
    from . import __version__

    click.echo(f"inskit, version {__version__}")
    ctx.exit()


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--version", is_flag=True, expose_value=False, is_eager=True, callback=_print_version,
              help="Show the version and exit.")
def cli():
    """inskit: inertial navigation and INS/GNSS integration."""


# --- mechanize -------------------------------------------------------------------
def _numbers(option, text, n, meaning):
    """``n`` finite numbers from the comma-separated ``text`` of ``option``
    (``meaning`` names them, e.g. ``"x,y,z [m]"``), or an InputError that
    names the option (not the config field it sets)."""
    parts = [p for p in str(text).replace(" ", "").split(",") if p != ""]
    try:
        x = [float(p) for p in parts]
    except ValueError:
        x = None
    if x is None or len(x) != n or not np.all(np.isfinite(x)):
        raise InputError(f"{option}: expected {n} finite comma-separated numbers {meaning}, got {text!r}")
    return x


def _parse_init(text, option="--init"):
    """``--init lat_deg,lon_deg,height_m,vn,ve,vd,roll_deg,pitch_deg,yaw_deg``:
    nine finite numbers, the height and angles within the config keys' ranges
    (:func:`inskit.config_files.check_option_init`: a wrong unit refused
    naming the option)."""
    from .config_files import check_option_init

    return check_option_init(option, _numbers(option, text, 9,
                                              "lat_deg,lon_deg,height_m,vn,ve,vd,roll_deg,pitch_deg,yaw_deg"))


def _height_ref(text, imu, log=None):
    """``--height-ref``: a number [m], or a height log interpolated onto the IMU times (``log`` takes the
    warning of a log that does not cover them)."""
    try:
        x = float(text)
    except ValueError:
        x = None
    if x is not None:
        if not np.isfinite(x):
            raise InputError(f"--height-ref: {text!r} is not a finite height in metres")
        from .config_files import check_option_height

        return check_option_height("--height-ref", x)
    from .jobs.height import height_profile_at

    if not Path(text).is_file():
        what = "a folder" if Path(text).is_dir() else "no such file"
        raise InputError(f"--height-ref: {text!r} is neither a height in metres nor a height log ({what})")
    return height_profile_at(text, imu.time, log=log or _log)


@cli.command()
@click.argument("imu_file", type=click.Path(dir_okay=False))
@click.option("--init", "init_text", help="Initial state: lat_deg,lon_deg,height_m,vn,ve,vd,roll_deg,pitch_deg,yaw_deg.")
@click.option("--init-from", type=click.Path(dir_okay=False), help="Take the initial state from a solution/truth file (at the first IMU time).")
@click.option("--frame", type=click.Choice(["ned", "wander", "ecef", "inertial"]), default="ned", show_default=True)
@click.option("--height", type=click.Choice(["free", "hold", "aid"]), default="free", show_default=True,
              help="Height channel (NED only): free, held to or aided by --height-ref.")
@click.option("--height-ref", help="External height for --height hold/aid: a constant [m], or a height log (CSV "
              "time_s, height_m: a barometer, a profile) interpolated onto the IMU times (default: the initial "
              "height).")
@click.option("--no-coning", is_flag=True, help="Single-sample attitude update (no coning/sculling compensation).")
@click.option("--gravity", type=click.Choice(["normal", "normal-simple", "j2"]), default="normal", show_default=True,
              help="Gravity model: normal (Somigliana with both height terms and the north component), "
              "normal-simple (first-order height term, no north component) or j2 (GM + J2 field).")
@click.option("--no-unit-check", is_flag=True, help="Skip the unit-plausibility checks of the IMU reader.")
@click.option("--first-row", type=click.Choice(["initial", "increment", "discard"]), default="initial",
              show_default=True, help="Increment files: the first row is the initial epoch (zero increments), a "
              "real increment (an initial epoch is prepended), or to be dropped (docs/formats.md).")
@click.option("--mount-rpy", help="Sensor mounting roll,pitch,yaw [deg]: the IMU's axes against the body's, as "
              "[imu] mount_rpy_deg of navigate and of a scenario (a simulated IMU mounted so writes its own axes).")
@click.option("--out", "out_file", type=click.Path(dir_okay=False), help="Write the solution CSV here.")
@click.option("--force", is_flag=True, help="Overwrite --out if it exists.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON summary object on stdout.")
def mechanize(imu_file, init_text, init_from, frame, height, height_ref, no_coning, gravity, no_unit_check, first_row,
              mount_rpy, out_file, force, as_json):
    """Free-inertial navigation from an IMU file and an initial state."""
    from . import io
    from .strapdown import mechanize as run_mech
    from .types import NavState

    from .files import check_folder_writable, check_outputs

    check_outputs([out_file], [imu_file, init_from], force)
    if out_file:
        check_folder_writable(Path(out_file).resolve().parent)
    from .jobs.warm import warm_compiled_code

    warm_compiled_code()  # numba's set-up beside the reading
    mount = None
    if mount_rpy:  # checked before the reading
        from .config_files import check_option_angles

        mount = check_option_angles("--mount-rpy", _numbers("--mount-rpy", mount_rpy, 3, "roll,pitch,yaw [deg]"))
    imu = io.read_imu(imu_file, check_units=not no_unit_check, first_row=first_row)
    if mount is not None:
        from .io.rtklib import rotate_to_body

        rotate_to_body(np.radians(np.asarray(mount, float)), imu.dtheta_b, imu.dv_b)  # the reader's arrays, as navigate
    if init_text and init_from:
        raise InputError("give either --init or --init-from, not both")
    if init_from:
        ref = io.read_solution(init_from, until_s=float(imu.time[0]))  # the rows around the start only
        if not ref.time[0] <= imu.time[0] <= ref.time[-1]:  # said of the option and both files (a whole read then)
            raise InputError(f"--init-from {init_from}: spans {float(ref.time[0]):.3f}..{float(ref.time[-1]):.3f} s, "
                             f"but {imu_file} starts at {float(imu.time[0]):.3f} s: mismatched time bases?")
        init = ref.interpolate(imu.time[:1]).state(0)
    elif init_text:
        x = _parse_init(init_text)
        try:
            init = NavState.from_euler(imu.time[0], [x[0] * DEG, x[1] * DEG, x[2]], x[3:6], np.array(x[6:9]) * DEG)
        except InputError as exc:  # a latitude beyond the pole, a NaN: said of the option
            raise InputError(f"--init: {exc}") from None
    else:
        raise InputError("an initial state is needed: --init ... or --init-from FILE")
    if frame != "ned" and height != "free":
        raise InputError("--height hold/aid is available with --frame ned only")
    opts = {"coning": not no_coning, "gravity": gravity}
    if frame == "ned":
        opts["height"] = height
    if height_ref is not None and height == "free":
        raise InputError("--height-ref would be ignored with --height free; use --height hold or aid")
    warnings = []  # logged as they come, and the JSON's (a script reading it saw none of them)

    def warn(msg):
        msg = msg.removeprefix("warning: ")
        _log(f"warning: {msg}")
        warnings.append(msg)

    href = None if height == "free" else (init.lla[2] if height_ref is None else _height_ref(height_ref, imu, warn))
    from .integration.gaps import find_gaps, find_rate_changes, imu_spikes, refuse_long_gaps, spikes_warning

    spiked = spikes_warning(imu_spikes(imu) if not no_unit_check else [], Path(imu_file).name)
    if spiked:  # a corrupt row integrated as it is: said, as navigate says it
        warn(spiked)
    for ch in find_rate_changes(imu):
        warn(f"{imu_file}: the sampling rate changes from {ch.rate_before_hz:.4g} Hz to "
             f"{ch.rate_after_hz:.4g} Hz near t = {ch.t_s:.3f} s (row {ch.row})")
    gaps = find_gaps(imu)
    refuse_long_gaps(gaps, str(imu_file))
    for g in gaps:
        warn(f"{imu_file}: a gap of {g.length_s:.3f} s at t = {g.start_s:.3f} s (row {g.row}); the "
             "mechanization integrates one sample's increments over it")
    t0 = time.perf_counter()
    with _progress(len(imu), f"mechanize ({frame})") as bar:
        sol = run_mech(imu, init, frame=frame, height_ref=href, progress=bar.update, chunk_size=200_000, **opts)
    elapsed = time.perf_counter() - t0
    diverged = _diverged(sol)
    if diverged:
        warn(diverged)
    if out_file:
        io.write_solution(out_file, sol, overwrite=force)
        _log(f"wrote {out_file}")
    from .rotations import wrap_angle

    end = sol.state(len(sol) - 1)
    rpy = end.euler / DEG
    summary = {
        "frame": frame,
        "gravity": gravity,
        "epochs": len(sol),
        "duration_s": float(sol.time[-1] - sol.time[0]),
        "elapsed_s": elapsed,
        "final": {
            # the longitude wrapped into (-180, 180] as the solution file writes it (it said 180.099 where the
            # file said -179.901 after crossing the antimeridian)
            "time_s": end.time, "lat_deg": end.lla[0] / DEG, "lon_deg": float(wrap_angle(end.lla[1])) / DEG,
            "height_m": end.lla[2],
            "vn_m_s": end.v_n[0], "ve_m_s": end.v_n[1], "vd_m_s": end.v_n[2],
            "roll_deg": rpy[0], "pitch_deg": rpy[1], "yaw_deg": rpy[2],
        },
        "out": out_file,
        "imu_gaps": [{"row": g.row, "start_s": g.start_s, "length_s": g.length_s} for g in gaps],
        "imu_rate_changes": [{"row": ch.row, "t_s": ch.t_s, "rate_before_hz": ch.rate_before_hz,
                              "rate_after_hz": ch.rate_after_hz} for ch in find_rate_changes(imu)],
        "warnings": warnings,
    }
    f = summary["final"]
    table = (
        f"{len(sol)} epochs over {summary['duration_s']:.1f} s in {elapsed:.2f} s ({frame}, {gravity} gravity)\n"
        f"final: lat {f['lat_deg']:.8f} deg  lon {f['lon_deg']:.8f} deg  h {f['height_m']:.2f} m\n"
        f"       v_n [{f['vn_m_s']:.3f}, {f['ve_m_s']:.3f}, {f['vd_m_s']:.3f}] m/s  "
        f"rpy [{f['roll_deg']:.3f}, {f['pitch_deg']:.3f}, {f['yaw_deg']:.3f}] deg"
    )
    _emit(summary, as_json, table)


def _diverged(sol):
    """What a free-inertial solution that left the Earth says (or None): the first epoch beyond the
    heights and speeds inskit's readers take (:data:`inskit.units.MAX_HEIGHT_M`,
    :data:`~inskit.units.MAX_SPEED_M_S`), or not finite, and where it ends."""
    from .units import MAX_HEIGHT_M, MAX_SPEED_M_S

    h, v = sol.lla[:, 2], sol.v_n
    off = (~np.isfinite(h) | ~np.isfinite(v).all(axis=1) | (np.abs(h) > MAX_HEIGHT_M)
           | (np.abs(v) > MAX_SPEED_M_S).any(axis=1))
    if not off.any():
        return None
    k = int(np.argmax(off))
    return (f"the solution diverged: from t = {float(sol.time[k]):.3f} s (epoch {k} of {len(sol)}) it lies beyond "
            f"+-{MAX_HEIGHT_M / 1000:g} km of the ellipsoid or moves faster than {MAX_SPEED_M_S:g} m/s (at the end: "
            f"height {float(h[-1]) / 1000:.4g} km, speed {float(np.linalg.norm(v[-1])):.4g} m/s): the initial "
            "state or the mounting does not fit the IMU (an IMU upside down: --mount-rpy 180,0,0; a wrong "
            "roll, pitch or height in --init), or its units are wrong; inskit's readers refuse such a solution "
            "file (evaluate, --init-from)")


PLOT_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg")


def _check_plot_file(plot_file, force, inputs=()):
    """A plot path the plotting library can write, not an input, and new
    unless ``force`` (:func:`inskit.files.check_outputs`), in a folder made
    if needed (:func:`inskit.files.check_folder_writable`: removed again if
    the command fails), checked before the work."""
    from .files import check_folder_writable, check_outputs

    if not plot_file:
        return
    if Path(plot_file).suffix.lower() not in PLOT_SUFFIXES:
        raise InputError(f"{plot_file}: unsupported plot format {Path(plot_file).suffix or '(none)'!r}; use one of "
                         f"{', '.join(PLOT_SUFFIXES)}")
    check_outputs([plot_file], inputs, force)
    check_folder_writable(Path(plot_file).resolve().parent)  # the plot's folder was not made: the work was lost


# --- evaluate ----------------------------------------------------------------------
@cli.command()
@click.argument("solution_file", type=click.Path(dir_okay=False))
@click.argument("truth_file", type=click.Path(dir_okay=False))
@click.option("--from", "t_from", type=FINITE, metavar="S", help="Score from this time [s, the files' time column].")
@click.option("--to", "t_to", type=FINITE, metavar="S", help="Score up to this time [s, the files' time column].")
@click.option("--remove-offset", "remove_offset", is_flag=False, flag_value="window", default=None,
              metavar="[FROM:TO]", help="Estimate the constant NED position offset (mean solution minus truth) over "
              "FROM:TO [s] (alone: over the window scored), subtract it and report it.")
@click.option("--per-epoch", "per_epoch_file", type=click.Path(dir_okay=False),
              help="Write the error at every epoch (.csv, .csv.gz or .parquet): time, N/E/D, horizontal, "
              "vertical, 3-D [m], velocity [m/s], roll/pitch/yaw [deg].")
@click.option("--plot", "plot_file", type=click.Path(dir_okay=False), help="Write an error plot (PNG).")
@click.option("--force", is_flag=True, help="Overwrite --plot and --per-epoch if they exist.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def evaluate(solution_file, truth_file, t_from, t_to, remove_offset, per_epoch_file, plot_file, force, as_json):
    """Errors of a navigation solution against a truth file.

    Either file may be CSV (.csv, .csv.gz) or Parquet (.parquet, as navigate
    writes at full rate); the format is told by content.  Attitude errors are
    in degrees, yaw wrapped to +-180."""
    from .jobs import evaluate as E

    _check_plot_file(plot_file, force, [solution_file, truth_file])
    interval = E.parse_interval(remove_offset) if remove_offset is not None else None
    s = E.evaluate(solution_file, truth_file, t_from=t_from, t_to=t_to, remove_offset=interval,
                   per_epoch_file=per_epoch_file, force=force, plot_file=plot_file)
    for key in ("per_epoch", "plot"):
        if key in s:
            _log(f"wrote {s[key]}")
    _emit(s, as_json, E.summary_text(s))


# --- bench ----------------------------------------------------------------------------
@cli.command()
@click.option("--quick", is_flag=True, help="Shorter runs (10 min of data instead of 1 h; 2 min for the commands).")
@click.option("--no-cli", is_flag=True, help="Leave out the end-to-end command figures (navigate_cli_epochs_per_s, ...).")
@click.option("--long", "long_runs", is_flag=True,
              help="Only navigate on 1, 4 and 8 h of 200 Hz car (forward and smoothed: wall time, peak memory, "
              "seconds per hour); minutes, and 2.4 GB of cached drives.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def bench(quick, no_cli, long_runs, as_json):
    """Throughput of the compiled kernels (epochs per second, one core) and of
    the user commands end to end (navigate, simulate, mechanize on a simulated
    hour of car: wall time, peak memory)."""
    if long_runs and (quick or no_cli):  # --long runs minutes and caches 2.4 GB: not what --quick asked for
        given = " and ".join(o for o, on in (("--quick", quick), ("--no-cli", no_cli)) if on)
        raise InputError(f"--long runs only the long navigate figures (whole commands, minutes): {given} would be "
                         f"ignored; give --long alone, or {given} without it")
    if long_runs:
        from .jobs.bench_cli import long_benchmarks

        res = long_benchmarks(progress=lambda name: _log(f"bench: {name} done"))
        table = "\n".join(f"{r['hours']:>3} h: forward {r['forward_wall_s']:7.1f} s {r['forward_peak_rss_mb']:7.0f} MiB, "
                          f"smoothed {r['smoothed_wall_s']:7.1f} s {r['smoothed_peak_rss_mb']:7.0f} MiB"
                          for r in res.get("navigate_long", []))
        if "navigate_long_forward_rss_mb_per_hour" in res:
            table += (f"\nmemory per hour of log: forward {res['navigate_long_forward_rss_mb_per_hour']:.0f} MiB, "
                      f"smoothed {res['navigate_long_smoothed_rss_mb_per_hour']:.0f} MiB")
        _emit(res, as_json, table or str(res))
        return
    from .jobs.bench import run_benchmarks

    res = run_benchmarks(quick=quick, progress=lambda name: _log(f"bench: {name} done"), cli=not no_cli)
    table = "\n".join(f"{k:<28}{v}" for k, v in res.items())
    _emit(res, as_json, table)


# --- navigate (the main job) ----------------------------------------------------------
@cli.command()
@click.argument("config_file", required=False, type=click.Path(dir_okay=False))
@click.option("--imu", "imu_file", type=click.Path(dir_okay=False), help="IMU file (overrides the config).")
@click.option("--imu-format", type=click.Choice(["inskit", "rtklibexplorer"]), help="IMU file format.")
@click.option("--gnss", "gnss_file", type=click.Path(dir_okay=False), help="GNSS file (overrides the config).")
@click.option("--gnss-format", type=click.Choice(["inskit", "rtklib-pos"]), help="GNSS file format.")
@click.option("--lever-arm", help="IMU-to-antenna lever arm in body axes [m]: x,y,z.")
@click.option("--imu-time-offset", type=FINITE, help="Seconds added to the IMU time tags.")
@click.option("--scheme", type=click.Choice(["closed", "open", "uncoupled"]), help="Integration scheme.")
@click.option("--outages", metavar="SPEC",
              help="GNSS outages: none, rtklibexplorer or windows:START-END[,START-END...] in seconds after the "
              "first GNSS epoch (e.g. windows:15-25,30-40); replaces the config's [outages] protocol and windows.")
@click.option("--smooth", is_flag=True, help="Add the RTS smoother; the summary keys then describe it.")
@click.option("--calibrate-time-offset", is_flag=True,
              help="First find the IMU time offset that minimises the GNSS innovations, then run with it "
              "(sets [imu] time_offset_search = \"calibrate\").")
@click.option("--calibrate-gnss-axes", is_flag=True,
              help="First shape the fixes' noise, north, east, down, to their innovations on the fixes the filter "
              "uses, then run with it (sets [gnss] sigma_scale_search = \"calibrate\"; the summary's "
              "gnss_axes_calibration says what each run measured).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), help="Output folder (default from config).")
@click.option("--force", is_flag=True, help="Write into an output folder that is not empty: files of the same "
              "names are replaced, and those an earlier run there listed in its summary.json go; other files stay.")
@click.option("--no-plots", is_flag=True, help="Skip the PNG plots.")
@click.option("--output-format", type=click.Choice(["parquet", "csv", "both"]),
              help="Solution files: Parquet at every IMU epoch, CSV at --output-rate, or both (default: the "
              "config's [output] format, else both).")
@click.option("--output-rate", type=RATE_HZ, metavar="HZ",
              help="Rows per second of the CSV solution files (default: [output] rate_hz, else 10 Hz; at most "
              f"{MAX_RATE_HZ:g} Hz); a rate at or above the IMU rate writes every epoch.")
@click.option("--stream", type=click.Choice(["auto", "on", "off"]),
              help="Write the solution files while the filter runs, memory bounded whatever the log's length "
              "(default: [output] stream, else auto = on); off keeps every row in memory.")
@click.option("--truth", "truth_file", type=click.Path(dir_okay=False),
              help="A truth file (e.g. from inskit simulate; sets [truth] file): the outages are also scored "
              "against it (keys ..._vs_truth_...) and its errors added to the summary.")
@click.option("--gravity", type=click.Choice(["normal", "normal-simple", "j2"]),
              help="Gravity model (overrides the config's [earth] gravity).")
@click.option("--strict", is_flag=True, help="Exit with status 3 when the run's health verdict is unhealthy.")
@click.option("--report", "with_report", is_flag=True, help="Also write report.html, one self-contained page of "
              "the run (as `inskit report`).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def navigate(config_file, imu_file, imu_format, gnss_file, gnss_format, lever_arm, imu_time_offset, scheme, outages,
             smooth, calibrate_time_offset, calibrate_gnss_axes, out_dir, force, no_plots, output_format, output_rate, stream, truth_file,
             gravity, strict, with_report, as_json):
    """INS/GNSS integration from a TOML config file or flags."""
    from .jobs import config as C
    from .jobs import navigate as N

    over = {}
    if imu_file:
        over.setdefault("imu", {})["file"] = str(Path(imu_file).resolve())
    if imu_format:
        over.setdefault("imu", {})["format"] = imu_format
    if imu_time_offset is not None:
        over.setdefault("imu", {})["time_offset_s"] = imu_time_offset
    if calibrate_time_offset:
        over.setdefault("imu", {})["time_offset_search"] = "calibrate"
    if calibrate_gnss_axes:
        over.setdefault("gnss", {})["sigma_scale_search"] = "calibrate"
    if gnss_file:
        over.setdefault("gnss", {})["file"] = str(Path(gnss_file).resolve())
    if gnss_format:
        over.setdefault("gnss", {})["format"] = gnss_format
    if lever_arm:
        la = _numbers("--lever-arm", lever_arm, 3, "x,y,z [m]")
        over.setdefault("gnss", {})["lever_arm_b_m"] = la
    if scheme:
        over.setdefault("filter", {})["scheme"] = scheme
    if outages is not None:
        over.setdefault("outages", {}).update(C.outages_from_spec(outages))
    if no_plots:
        over.setdefault("output", {})["plots"] = False
    if output_format:
        over.setdefault("output", {})["format"] = output_format
    if output_rate is not None:
        over.setdefault("output", {})["rate_hz"] = output_rate
    if stream:
        over.setdefault("output", {})["stream"] = stream
    if truth_file:
        over["truth"] = {"file": str(Path(truth_file).resolve())}
    if gravity:
        over.setdefault("earth", {})["gravity"] = gravity
    if config_file:
        cfg = C.load_config(config_file, over)
    else:
        if not (imu_file and gnss_file):
            raise InputError("give a config file, or at least --imu and --gnss")
        cfg = C.config_from_dict({}, base_dir=Path.cwd(), source="flags", overrides=over)
    from .files import check_folder_writable

    target = Path(out_dir) if out_dir else (cfg.resolve(cfg.output.dir) if cfg.output.dir else Path("out") / cfg.name)
    occupied = None if force else N.occupied_folder_message(target)  # a file there: check_folder_writable says so
    if occupied:
        raise InputError(occupied)
    N.refuse_overwriting_inputs(cfg, target, [config_file], force)
    check_folder_writable(target)  # before the computation, not after it
    cfg, extra = N.calibrated_config(cfg, log=_log)
    with _progress(None, "navigate") as bar:
        res = N.run(cfg, smooth=smooth, progress=bar.update, log=_log, stream_dir=target)
    try:
        s = N.summary(res)
        s.update(extra)
        N.check_time_offset(res.config, s, log=_log)  # the run's own (its constraint check may have changed it)
        text_extra = N.truth_errors_text(s["truth_errors"]) if "truth_errors" in s else ""
        if not as_json:  # the result first: the files and plots (a second or two) follow
            _emit(s, False, N.outage_table_text(s) + text_extra)
        files = N.write_outputs(res, target, s, replace_previous=force)
    except BaseException:  # the streamed solution files (temporary names) go with the run
        N.abort_streams(res)
        raise
    if with_report:
        from .jobs.report import build_report

        rep = build_report(target, overwrite=True)  # the folder passed navigate's own check
        s["report"] = rep["report"]
        files.append(Path(rep["report"]))
    _log(f"wrote {len(files)} files to {target}/")
    h = s["health"]
    log_health(h)
    if as_json:
        _emit(s, True)
    if strict and h["verdict"] != "healthy":
        sys.exit(3)


@cli.command()
@click.argument("scenario_file", type=click.Path(dir_okay=False))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output folder.")
@click.option("--seed", type=SEED, default=0, show_default=True, help="Seed of every random draw.")
@click.option("--force", is_flag=True, help="Overwrite files in --out.")
@click.option("--no-plot", is_flag=True, help="Skip the scenario plot.")
@click.option("--verify", is_flag=True, help="Also mechanize the ideal IMU (at the rate and at twice it) against the truth.")
@click.option("--truth-rate", type=RATE_HZ, metavar="HZ", help="Rate of the truth file [Hz] (default: the IMU "
              f"rate; at most {MAX_RATE_HZ:g} Hz).")
@click.option("--format", "file_format", type=click.Choice(["csv", "parquet"]), default="csv", show_default=True,
              help="imu, gnss and truth files as CSV or Parquet (typed, exact, about 20x faster to write); "
              "every inskit reader takes both.")
@click.option("--gravity", type=click.Choice(["normal", "normal-simple", "j2"]),
              help="Gravity model of the specific force (overrides the scenario's [earth] gravity).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def simulate(scenario_file, out_dir, seed, force, no_plot, verify, truth_rate, file_format, gravity, as_json):
    """Simulate a scenario: IMU, GNSS and truth files plus a plot."""
    from .jobs.simulate import check_simulation_outputs, clipping_warnings, verify_ideal, write_simulation
    from .simulation.scenario import load_scenario, simulate as run_sim

    from .files import check_folder_writable

    sc = load_scenario(scenario_file)
    if gravity:
        sc = sc.model_copy(update={"earth": sc.earth.model_copy(update={"gravity": gravity})})
    check_folder_writable(Path(out_dir))  # before the computation, not after it ('Not a directory' then)
    check_simulation_outputs(sc, Path(out_dir), overwrite=force, plot=not no_plot, file_format=file_format,
                             inputs=[scenario_file])
    t0 = time.perf_counter()
    steps = ["ideal IMU", "errors and GNSS", "files"]
    from .cli_output import progress

    with progress(len(steps), f"simulate {sc.name}", unit="step", leave=False) as bar:
        sim = run_sim(sc, seed, truth_rate_hz=truth_rate, progress=lambda _: bar.update(1))
        bar.update(1)
        # the self-check before the files: a check that failed or was interrupted (Ctrl-C: it mechanizes the
        # scenario twice) left the new files in place of the earlier run's beside a failed command
        v = verify_ideal(sc) if verify else None
        files = write_simulation(sim, Path(out_dir), overwrite=force, plot=not no_plot, file_format=file_format,
                                 inputs=[scenario_file])
        bar.update(1)
    res = {
        "scenario": sc.name, "seed": seed, "duration_s": float(sim.imu.time[-1]), "imu_epochs": len(sim.imu),
        "imu_rate_hz": sc.imu.rate_hz, "imu_grade": sc.imu.grade, "gravity": sc.earth.gravity,
        "gnss_fixes": len(sim.gnss),
        "elapsed_s": time.perf_counter() - t0, "files": [str(f) for f in files],
        # the segments the run holds (a duration_limit_s cuts the last one short and leaves out those after it)
        "segments": [dict(g, end_s=min(g["end_s"], sim.trajectory.duration)) for g in sim.trajectory.segments
                     if g["start_s"] < sim.trajectory.duration],
    }
    res["warnings"] = clipping_warnings(sc, sim)
    for w in res["warnings"]:
        _log(f"warning: {w}")
    text = (f"{sc.name}: {res['duration_s']:.0f} s, {len(sim.imu)} IMU epochs, {len(sim.gnss)} GNSS "
            f"fixes -> {out_dir}/ ({res['elapsed_s']:.1f} s)")
    if verify:
        res["verify"] = v
        frame, f = next(iter(v["frames"].items()))  # NED, or wander-azimuth near a pole
        text += (f"\nideal IMU mechanized ({'NED' if frame == 'ned' else frame}): horizontal max "
                 f"{f['horizontal_max_m']:.4g} m, vertical max {f['vertical_max_m']:.4g} m at {f['rate_hz']:g} Hz; "
                 f"{f['double_rate_horizontal_max_m']:.4g} m at twice the rate ({f['improvement_at_double_rate']:.1f}x)")
    _emit(res, as_json, text)


@cli.command()
@click.argument("imu_file", type=click.Path(dir_okay=False))
@click.option("--plot", "plot_file", type=click.Path(dir_okay=False), help="Write the Allan plot (PNG).")
@click.option("--toml", "toml_file", type=click.Path(dir_okay=False),
              help="Write the [noise] section for inskit navigate (TOML) to this file.")
@click.option("--force", is_flag=True, help="Overwrite --plot and --toml.")
@click.option("--no-unit-check", is_flag=True, help="Skip the unit-plausibility checks of the IMU reader.")
@click.option("--first-row", type=click.Choice(["initial", "increment", "discard"]), default="initial",
              show_default=True, help="Increment files: the first row is the initial epoch (zero increments), a "
              "real increment (an initial epoch is prepended), or to be dropped (docs/formats.md).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def allan(imu_file, plot_file, toml_file, force, no_unit_check, first_row, as_json):
    """Allan deviation of a static IMU log and the filter noise parameters it
    implies: the [noise] section of an inskit navigate config (noise_section
    in the JSON, the TOML text with --toml).

    The log must last at least 100 s and hold at least 101 samples (hours to
    see the bias instability).  A constant channel (every increment the
    same: a stuck axis, or one quantised coarser than its noise) has no
    measurable noise: its row reads 'constant' (constant: true, figures null
    in the JSON), a note names it, and the [noise] section comes from the
    other axes of its sensor; three constant gyro (or accelerometer) axes
    are refused."""
    from .analysis.allan import plot_allan
    from .files import check_folder_writable, check_outputs, same_file, staged_paths, write_text
    from .jobs.allan import allan_report, read_static_log

    _check_plot_file(plot_file, force, [imu_file])
    if toml_file:
        if plot_file and same_file(toml_file, plot_file):
            raise InputError(f"{toml_file}: given as both --plot and --toml; choose two files")
        check_outputs([toml_file], [imu_file], force)
        check_folder_writable(Path(toml_file).resolve().parent)
    imu = read_static_log(imu_file, check_units=not no_unit_check, first_row=first_row)
    try:
        r, rep = allan_report(imu)
    except InputError as exc:  # what the log is not (regular, long, static): said of the file
        raise InputError(f"{imu_file}: {exc}") from None
    gyro, acc = rep["gyro"], rep["accel"]
    res = {"file": imu_file, "duration_s": float(imu.time[-1] - imu.time[0]), **rep}
    with staged_paths() as stage:  # the plot and the TOML whole or neither (a failed one left the other)
        if plot_file:
            plot_allan(r, stage(plot_file), title=Path(imu_file).name)
            res["plot"] = plot_file
        if toml_file:
            write_text(stage(toml_file), rep["noise_toml"])
            res["toml"] = toml_file
    def rrw(v):
        return f"{v:.3g}" if v is not None else "-"

    def gyro_cols(g):
        if g["constant"]:
            return f"{'constant (no noise measurable)':>50}"
        return (f"{g['arw_deg_sqrt_h']:>15.4f}{g['bias_instability_deg_h']:>10.3f}{g['gm_tau_s']:>8.0f}"
                f"{rrw(g['rrw_deg_h_sqrt_h']):>17}")

    def accel_cols(a):
        if a["constant"]:
            return f"{'constant (no noise measurable)':>45}"
        return (f"{a['vrw_ug_sqrt_hz']:>14.2f}{a['bias_instability_ug']:>9.2f}{a['gm_tau_s']:>8.0f}"
                f"{rrw(a['rrw_ug_sqrt_h']):>14}")

    lines = [f"{'axis':<6}{'ARW deg/rt(h)':>15}{'BI deg/h':>10}{'tau s':>8}{'RRW deg/h/rt(h)':>17}   "
             f"{'VRW ug/rt(Hz)':>14}{'BI ug':>9}{'tau s':>8}{'RRW ug/rt(h)':>14}"]
    for g, a in zip(gyro, acc):
        lines.append(f"{g['axis']:<6}{gyro_cols(g)}   {accel_cols(a)}")
    lines.append("for inskit navigate" + (f" (written to {toml_file})" if toml_file else "") + ":")
    lines.append(rep["noise_toml"].rstrip())
    _emit(res, as_json, "\n".join(lines))


@cli.command()
@click.argument("scenario_file", type=click.Path(dir_okay=False))
@click.option("--outage", required=True, help="GNSS outage START,END in seconds of the scenario.")
@click.option("--seed", type=SEED, default=0, show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def schemes(scenario_file, outage, seed, as_json):
    """Uncoupled, open-loop and closed-loop integration on one simulated run."""
    from .jobs.montecarlo import compare_schemes
    from .jobs.navigate import fmt_or_na
    from .simulation.scenario import load_scenario

    a, b = _numbers("--outage", outage, 2, "START,END [s]")
    if not b > a:
        raise InputError(f"--outage: the end ({b}) must come after the start ({a})")
    sc = load_scenario(scenario_file)
    rows = compare_schemes(sc, (a, b), seed)
    res = {"scenario": sc.name, "imu_grade": sc.imu.grade, "outage_s": [a, b], "seed": seed, "schemes": rows}
    lines = [f"{sc.name} ({sc.imu.grade}), GNSS outage {a:.0f}..{b:.0f} s, seed {seed}: errors at the outage end",
             f"{'scheme':<11}{'horiz m':>10}{'vert m':>9}{'vel m/s':>9}{'att deg':>9}{'GNSS-on horiz RMS m':>21}"]
    for r in rows:
        lines.append(f"{r['scheme']:<11}{r['outage_end_horizontal_m']:>10.2f}{r['outage_end_vertical_m']:>9.2f}"
                     f"{r['outage_end_velocity_m_s']:>9.3f}{r['outage_end_attitude_deg']:>9.3f}"
                     f"{fmt_or_na(r['gnss_on_horizontal_rms_m']):>21}")
    _emit(res, as_json, "\n".join(lines))


@cli.command()
@click.argument("imu_file", type=click.Path(dir_okay=False))
@click.option("--lat", "lat_deg", type=FINITE, required=True, help="Latitude [deg].")
@click.option("--method", type=click.Choice(["accel", "gyro", "blend", "fine"]), default="blend", show_default=True)
@click.option("--m", "m_gain", type=FINITE, help="Blending gain for --method blend (default: chosen by the GA for "
              "the noise and the bias priors).")
@click.option("--start", "t_start", type=FINITE, help="Start of the static interval [s] (default: the log start).")
@click.option("--end", "t_end", type=FINITE, help="End of the static interval [s] (default: detected).")
@click.option("--imu-format", type=click.Choice(["inskit", "rtklibexplorer"]), default="inskit", show_default=True)
@click.option("--mount-rpy", help="Sensor mounting roll,pitch,yaw [deg] (see docs/formats.md).")
@click.option("--accel-bias-ug", type=FINITE, help="Accelerometer bias class (1 sigma) [micro-g] for the sigmas and m.")
@click.option("--gyro-bias-deg-h", type=FINITE, help="Gyro bias class (1 sigma) [deg/h] for the sigmas and m.")
@click.option("--no-unit-check", is_flag=True, help="Skip the unit-plausibility checks of the IMU reader.")
@click.option("--first-row", type=click.Choice(["initial", "increment", "discard"]), default="initial",
              show_default=True, help="Increment files: the first row is the initial epoch (zero increments), a "
              "real increment (an initial epoch is prepended), or to be dropped (docs/formats.md).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def align(imu_file, lat_deg, method, m_gain, t_start, t_end, imu_format, mount_rpy, accel_bias_ug, gyro_bias_deg_h,
          no_unit_check, first_row, as_json):
    """Initial alignment of a static IMU log: roll, pitch, yaw and their sigmas.

    The sigmas come from the sensor biases (which do not average out at rest)
    and the noise of the static means.  Without --accel-bias-ug and
    --gyro-bias-deg-h the biases of a consumer MEMS IMU are assumed (Bosch
    BMI160 class: 40 mg, 1 deg/s, 1 sigma per axis): conservative for a
    better IMU, and too poor a gyro to find north, so give your IMU's values.
    The output says which priors were used (sigma_basis).  An interval given
    with --end is checked to be static.  A yaw sigma of 180 deg means no
    heading information.
    """
    from .alignment import align_static

    if not -90.0 < lat_deg < 90.0:
        raise InputError(f"--lat must be within (-90, 90) deg (at a pole north is undefined), got {lat_deg:g}")
    mount = (0.0, 0.0, 0.0)
    if mount_rpy:
        from .config_files import check_option_angles

        mount = tuple(check_option_angles("--mount-rpy", _numbers("--mount-rpy", mount_rpy, 3,
                                                                  "roll,pitch,yaw [deg]")))
    if m_gain is not None and not 0.0 <= m_gain <= 1.0:
        raise InputError(f"--m must be within [0, 1], got {m_gain}")
    if m_gain is not None and method != "blend":
        raise InputError(f"--m {m_gain:g} would be ignored: it is the blending gain of --method blend, and --method "
                         f"{method} blends nothing; drop --m, or give --method blend")
    from .units import DEG_PER_HOUR, MICRO_G

    for name, v in (("--accel-bias-ug", accel_bias_ug), ("--gyro-bias-deg-h", gyro_bias_deg_h)):
        if v is not None and not v > 0:
            raise InputError(f"{name} must be > 0, got {v}")
    res = align_static(imu_file, np.radians(lat_deg), method=method, m=m_gain, t_start=t_start, t_end=t_end,
                       imu_format=imu_format, mount_rpy=np.radians(mount), check_units=not no_unit_check,
                       first_row=first_row,
                       accel_bias_sigma=None if accel_bias_ug is None else accel_bias_ug * MICRO_G,
                       gyro_bias_sigma=None if gyro_bias_deg_h is None else gyro_bias_deg_h * DEG_PER_HOUR)
    yaw_sigma = (f"{res['yaw_sigma_deg']:.4f}" if res["heading_usable"] else
                 f"{res['yaw_sigma_deg']:.0f} (no heading information)")
    lines = [f"{method} alignment over {res['static_s']:.1f} s of static data at {lat_deg:.4f} deg "
             f"([{res['static_start_s']:.1f}, {res['static_end_s']:.1f}] s)",
             f"roll  {res['roll_deg']:9.4f} deg  +- {res['roll_sigma_deg']:.4f} (1 sigma)",
             f"pitch {res['pitch_deg']:9.4f} deg  +- {res['pitch_sigma_deg']:.4f}",
             f"yaw   {res['yaw_deg']:9.4f} deg  +- {yaw_sigma}"]
    if "m" in res:
        lines.append(f"blending gain m = {res['m']:.4f}")
    if "converge_time_s" in res:
        lines.append("converged after (roll, pitch, yaw): " + ", ".join(
            "not converged" if v is None else f"{v:.1f} s" for v in res["converge_time_s"]))
        if res.get("converge_note"):
            lines.append(res["converge_note"])
    lines.append(f"heading from gyros usable: {'yes' if res['heading_usable'] else 'no'}: {res['heading_reason']}")
    lines.append(f"sigma basis: {res['sigma_basis']}")
    lines += [f"warning: {w}" for w in res["warnings"]]
    _emit(res, as_json, "\n".join(lines))


@cli.group()
def reproduce():
    """Reproduce the source documents' published experiments."""


@reproduce.command("alignment-ga")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Folder for the figures.")
@click.option("--force", is_flag=True, help="Write into a folder that already holds files, replacing those of the "
              "figures' names.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def reproduce_alignment(out_dir, force, as_json):
    """Source 002: one-step alignment blended by a GA (figures 6-9, headline case)."""
    from .jobs.reproduce_alignment import run

    from .cli_output import reproduce_into

    res, files = reproduce_into(out_dir, force, lambda d: run(d, log=_log))
    lines = [f"{'item':<72} {'published':<28} ours"]
    for e in res["entries"]:
        lines.append(f"{e['item']:<72} {str(e['published']):<28} {e['ours']}")
        if e["note"]:
            lines.append(f"{'':<4}note: {e['note']}")
    lines.append(f"figures: {', '.join(res['figures'])}")
    _emit({"experiment": "alignment-ga", "source": "002", "entries": res["entries"], "headline": res["headline"],
           "one_vs_two_step": res["one_vs_two_step"], "ga_checks": res["ga_checks"], "figures": res["figures"],
           "files": files},
          as_json, "\n".join(lines))


@cli.command()
@click.argument("scenario_file", type=click.Path(dir_okay=False))
@click.option("--grade", type=click.Choice(["navigation", "tactical", "industrial-mems", "consumer-mems"]),
              default="tactical", show_default=True, help="IMU grade of the runs (overrides the scenario's).")
@click.option("--runs", type=int, default=50, show_default=True)
@click.option("--duration", type=FINITE, help="Use only the first seconds of the scenario (at least 2 s: a GNSS "
              "update after the start, where the NEES is taken).")
@click.option("--seed", type=SEED, default=0, show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def consistency(scenario_file, grade, runs, duration, seed, as_json):
    """Monte Carlo consistency (NEES) of the closed-loop filter on a scenario."""
    from .jobs.montecarlo import consistency_study
    from .simulation.scenario import load_scenario

    sc = load_scenario(scenario_file)
    from .cli_output import progress

    with progress(runs, "monte carlo", unit="run", leave=False) as bar:
        res = consistency_study(sc, grade, runs, duration, seed, progress=bar.update)
    lines = [f"{sc.name}, {grade}, {runs} runs over {res['duration_s']:.0f} s: average NEES (3 dof each)"]
    for b, a in res["anees"].items():
        lo, hi = a["band_95"]
        lines.append(f"{b:<4} mean {a['mean']:.2f}  95 % band [{lo:.2f}, {hi:.2f}]  epochs inside "
                     f"{a['fraction_of_epochs_inside']:.0%}")
    lines.append(f"final sensor-bias errors: {res['bias_within_3_sigma']:.1%} within 3 sigma, RMS "
                 f"{res['bias_rms_normalized']:.2f} sigma")
    lines.append(f"verdict: {res['verdict']}")
    lines += [f"  {r}" for r in res["reasons"]]
    if as_json:
        _log(f"verdict: {res['verdict']}")
        for r in res["reasons"]:
            _log(f"  {r}")
    _emit(res, as_json, "\n".join(lines))


@cli.command()
@click.option("--checks", is_flag=True, help="Also run the closed-form checks (stationary, Schuler, coning).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def demo(checks, as_json):
    """Closed-form demonstration: ideal IMU, all four mechanizations."""
    from .jobs.demo import closed_form_checks, demo_run

    res, table = demo_run(log=_log)
    if checks:
        c = closed_form_checks(log=_log)
        res["checks"] = c
        s, sc, co = c["stationary"], c["schuler"], c["coning_attitude_drift"]
        table += (
            f"\nstationary 1 h: horizontal max {s['horizontal_max_m']:.2e} m, attitude max "
            f"{s['attitude_max_arcsec']:.2e} arcsec"
            f"\nSchuler 3 h: period {sc['period_s']:.1f} s (closed form {sc['closed_form_period_s']:.1f}), first peak "
            f"{sc['first_peak_m']:.1f} m (closed form {sc['closed_form_peak_m']:.1f})"
            f"\nconing 10 min: single-sample 100 Hz {co['single_sample_100hz_rad']:.3e} rad, two-sample 100 Hz "
            f"{co['two_sample_100hz_rad']:.3e} rad, two-sample 200 Hz {co['two_sample_200hz_rad']:.3e} rad"
        )
    _emit(res, as_json, table)


# --- gyro-free and platform INS (their own modules, same conventions) ---------------
from .cli_gyrofree import register as _register_gyrofree  # noqa: E402
from .cli_platform import platform as _platform_group  # noqa: E402
from .cli_platform import reproduce_integration_filters as _reproduce_integration_filters  # noqa: E402
from .cli_gnss import register as _register_gnss  # noqa: E402
from .cli_report import register as _register_report  # noqa: E402
from .cli_reproduce import register as _register_reproduce  # noqa: E402
from .cli_study import register as _register_study  # noqa: E402
from .cli_tune import register as _register_tune  # noqa: E402

_register_gyrofree(cli, reproduce)
cli.add_command(_platform_group, "platform")
reproduce.add_command(_reproduce_integration_filters, "integration-filters")
_register_gnss(cli, reproduce)
_register_report(cli)
_register_reproduce(reproduce)
_register_study(cli)
_register_tune(cli)


def main(argv=None):
    """Entry point: run the CLI, turning user errors into one line and exit 2.

    Called as the program (``argv`` None: the ``inskit`` script, ``python -m
    inskit.cli``), it ends by :func:`_exit_now` once the command is done:
    every file is written and closed by then, and the interpreter's own
    teardown of numba, LLVM, scipy and pyarrow would add a fifth of a
    second to every command; not under a profiler or a tracer, whose report
    is written at the teardown.  In process (tests, ``main([...])``) it
    raises ``SystemExit`` as usual."""
    from . import files

    files.forget_made_folders()
    code = _run(argv)
    if code != 0:  # refused or failed: no empty output folder left behind (only empty ones go)
        files.remove_made_folders()
    # a profiler or a tracer (cProfile, pyinstrument, coverage) writes its report at the teardown: keep it
    watched = sys.getprofile() is not None or sys.gettrace() is not None
    if argv is None and not watched and not os.environ.get("INSKIT_FULL_EXIT"):
        _exit_now(code)
    sys.exit(code)


def _run(argv):
    """The command's exit status (0 done, 2 a user error, 3 a bug, 130
    aborted); a ``SystemExit`` raised inside (not an ``Exception``) passes
    through."""
    debug = os.environ.get("INSKIT_DEBUG")
    if not debug:  # library warnings are not the user's messages: stderr carries ours only
        import warnings

        warnings.simplefilter("ignore")
        np.seterr(all="ignore")
    try:
        cli.main(args=argv, prog_name="inskit", standalone_mode=False)
    except click.exceptions.Abort:
        click.echo("inskit: aborted", err=True)
        return 130
    except click.exceptions.ClickException as exc:
        exc.show()
        return exc.exit_code
    except InskitError as exc:
        if debug:
            raise
        click.echo(f"inskit: error: {exc}", err=True)
        return 2
    except (OSError, MemoryError) as exc:
        if debug:
            raise
        click.echo(f"inskit: error: {exc}", err=True)
        return 2
    except Exception as exc:  # noqa: BLE001 - last line of defence: never a traceback
        if debug:
            raise
        click.echo(f"inskit: internal error: {type(exc).__name__}: {exc} "
                   "(this is a bug; set INSKIT_DEBUG=1 for the traceback)", err=True)
        return 3
    return 0


def _exit_now(code):
    """End the process with ``code`` after what an orderly exit would do
    that matters: the ``atexit`` handlers (a parent's, a library's) and the
    standard streams flushed; not the module teardown (``INSKIT_FULL_EXIT=1``
    keeps it)."""
    import atexit

    try:
        atexit._run_exitfuncs()
    except BaseException:  # noqa: BLE001 (a handler's failure does not change the command's status)
        pass
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe: nothing more can be said on it
            pass
    os._exit(code)


if __name__ == "__main__":  # pragma: no cover
    main()
