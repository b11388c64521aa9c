"""Jobs of the gyro-free INS: simulate an array, navigate from array outputs,
reproduce source 003.  They read files, write files and plot; the library
(:mod:`inskit.gyrofree`) does not import them.  The CLI
(:mod:`inskit.cli_gyrofree`) is a thin layer over these functions.

Units at this edge: micro-g, micro-g/sqrt(Hz), ppm, mrad, degrees; converted
to SI here.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ..files import plain_json, save_figure, write_json, write_text
from ..errors import ConfigError, InputError
from ..units import DEG, MAX_RATE_HZ, MAX_SAMPLES, MICRO_G, PPM

SOURCE_SCENARIO = "source003"


# --- helpers ---------------------------------------------------------------------------
#: the lever arm of the built-in layouts when none is given [m]
DEFAULT_D_M = 0.1


def layout_from_spec(spec, d=None):
    """``"ten"``, ``"six"`` (with lever arm ``d`` [m], default
    :data:`DEFAULT_D_M`) or a layout file path (whose positions are its own:
    a ``d`` with it would be ignored and is refused, naming ``--d``)."""
    from ..gyrofree.files import read_layout
    from ..gyrofree.layout import builtin_layout

    if spec in ("ten", "six"):
        from ..gyrofree.files import MAX_LEVER_ARM_M

        # the layout reader's limit: simulate --d 1000 wrote a layout.csv that navigate then refused
        if d is not None and not 0.0 < d <= MAX_LEVER_ARM_M:
            raise InputError(f"--d must be within (0, {MAX_LEVER_ARM_M:g}] m (the accelerometers' distance from the "
                             f"reference point; metres are expected), got {d:g}")
        return builtin_layout(spec, DEFAULT_D_M if d is None else d)
    p = Path(spec)
    if not p.exists():
        raise InputError(f"--layout: {spec!r} is neither 'ten', 'six' nor an existing layout file")
    if d is not None:
        raise InputError(f"--d {d:g} would be ignored: it is the lever arm of the built-in layouts ten and six, and "
                         f"--layout {spec} gives every accelerometer's position itself; drop --d")
    return read_layout(p)


def _check_out(out_dir, names, overwrite, inputs=()):
    """Refuse outputs that are inputs or (without ``overwrite``) exist
    (:func:`inskit.files.check_outputs`); make the folder."""
    from ..files import check_folder_writable, check_outputs

    out = Path(out_dir)
    check_outputs([out / n for n in names], [i for i in inputs if i not in (None, "ten", "six", SOURCE_SCENARIO)],
                  overwrite)

    return check_folder_writable(out)  # made here, removed again if the command then fails


def array_errors_from_datasheet(layout, rng, rate_hz, *, bias_ug=0.0, bias_sigma_ug=0.0, noise_ug_sqrt_hz=0.0,
                                scale_sigma_ppm=0.0, misalignment_sigma_mrad=0.0, source_theta_deg=None):
    """Array errors from datasheet units: fixed bias and random bias sigma
    [micro-g], white noise [micro-g/sqrt(Hz)] (per-sample sigma
    ``N sqrt(rate)``), scale-factor sigma [ppm], random axis misalignment sigma
    [mrad], or the source's six angles of m1-m6 [deg]."""
    from ..gyrofree.model import ArrayErrors, draw_errors, source_misaligned_axes

    for name, v in (("bias sigma", bias_sigma_ug), ("noise", noise_ug_sqrt_hz), ("scale-factor sigma", scale_sigma_ppm),
                    ("misalignment sigma", misalignment_sigma_mrad)):
        if not (np.isfinite(v) and v >= 0):
            raise InputError(f"the {name} must be >= 0, got {v}")
    sigma = noise_ug_sqrt_hz * MICRO_G * np.sqrt(rate_hz)
    e = draw_errors(layout, rng, bias_sigma=bias_sigma_ug * MICRO_G, bias_mean=bias_ug * MICRO_G,
                    scale_sigma=scale_sigma_ppm * PPM, misalignment_sigma=misalignment_sigma_mrad * 1e-3,
                    noise_sigma=sigma)
    if source_theta_deg is not None:
        if e.axes_true_b is not None:
            raise InputError("give either the source's misalignment angles or a random misalignment sigma, not both")
        e = ArrayErrors.build(len(layout), bias=e.bias, scale_factor=e.scale_factor, noise_sigma=sigma,
                              axes_true_b=source_misaligned_axes(layout, np.asarray(source_theta_deg) * DEG))
    return e


# --- simulate ------------------------------------------------------------------------------
def simulate_job(scenario, layout_spec, out_dir, *, d=None, rate_hz=None, duration=None, seed=0, overwrite=False,
                 log=None, **errors):
    """Simulate an accelerometer array on a scenario and write its files.

    Parameters
    ----------
    scenario : str
        ``"source003"`` (source 003's constant-rate motion, inertial frame, no
        gravity, C(0) = I) or a scenario TOML file (``examples/*.toml``).
    layout_spec : str
        ``"ten"``, ``"six"`` or a layout file.
    out_dir : path
        Receives ``array.csv`` (raw outputs), ``layout.csv`` (the layout used)
        and ``truth.csv`` (inertial format for ``source003``, the NED solution
        format otherwise; both with the true rates ``wx_rad_s ..`` and specific
        force ``fx_m_s2 ..``).
    d : float, optional
        Lever arm of the built-in layouts [m] (default :data:`DEFAULT_D_M`;
        refused with a layout file).
    rate_hz, duration : float, optional
        Sampling rate [Hz] (default 1000 Hz for ``source003``, the scenario's
        IMU rate otherwise; at most :data:`inskit.units.MAX_RATE_HZ`) and
        length [s] (default: 10 s, or the scenario's; at most the scenario's,
        and :data:`inskit.units.MAX_SAMPLES` samples at the rate).
    seed : int
        Seed of every random draw.
    **errors
        Datasheet-unit errors, see :func:`array_errors_from_datasheet`.

    Returns
    -------
    dict
        A JSON-able summary.

    Raises
    ------
    InputError
        A rate or a duration out of those bounds (named as the options
        ``--rate``, ``--duration``; a duration past the scenario's end in
        the words of ``platform simulate`` and ``consistency``), before the
        output folder is made.
    """
    from .. import io
    from ..gyrofree.files import write_array, write_inertial, write_layout
    from ..gyrofree.model import simulate_array
    from ..gyrofree.motion import ConstantRateMotion, motion_from_trajectory

    log = log or (lambda s: None)
    t0 = time.perf_counter()
    layout = layout_from_spec(layout_spec, d)
    rng = np.random.default_rng(seed)
    if scenario == SOURCE_SCENARIO:
        rate = 1000.0 if rate_hz is None else float(rate_hz)
        T = 10.0 if duration is None else float(duration)
        _check_rate(rate, T)
        out = _check_out(out_dir, ["array.csv", "layout.csv", "truth.csv"], overwrite, [scenario, layout_spec])
        motion = ConstantRateMotion()
        t = np.arange(0.0, T + 0.5 / rate, 1.0 / rate)
        mot = motion.motion(t)
        truth = motion.truth(t)
        kind = "inertial (source 003: no gravity, C(0) = I)"
    else:
        from ..simulation.imu import truth_solution
        from ..simulation.scenario import build_trajectory, load_scenario

        try:
            sc = load_scenario(scenario)
        except ConfigError:
            if rate_hz is None:
                raise
            try:  # sampled at --rate, not at the file's IMU rate: a 60 Hz vibration of a 100 Hz scenario was refused
                # under --rate 1000 (a lower --rate is refused below, by _check_motion_sampled, in its own words)
                sc = load_scenario(scenario, imu_rate_hz=rate_hz)
            except ConfigError as exc:
                if "imu.rate_hz" not in str(exc):
                    raise
                raise ConfigError(f"{exc} (imu.rate_hz is --rate {float(rate_hz):g} here)") from None
        tr = build_trajectory(sc, rng)
        rate = sc.imu.rate_hz if rate_hz is None else float(rate_hz)
        T = tr.duration if duration is None else float(duration)
        if not 0 < T <= tr.duration + 1e-9:  # as platform simulate and consistency: not clipped in silence
            raise InputError(f"--duration must be within (0, {tr.duration:.0f}] s, got {duration}")
        _check_rate(rate, T)
        _check_motion_sampled(sc, rate, scenario)
        out = _check_out(out_dir, ["array.csv", "layout.csv", "truth.csv"], overwrite, [scenario, layout_spec])
        t = np.arange(0.0, T + 1e-9, 1.0 / rate)
        log(f"gyrofree simulate: {sc.name}, {len(t)} samples")
        mot = motion_from_trajectory(tr, t)
        truth = truth_solution(tr, t)
        kind = f"Earth (scenario {sc.name})"
    err = array_errors_from_datasheet(layout, rng, rate, **errors)
    data = simulate_array(layout, mot, err, rng)
    extra = {}
    for j, a in enumerate("xyz"):
        extra[f"w{a}_rad_s"] = mot.omega_ib_b[:, j]
    for j, a in enumerate("xyz"):
        extra[f"f{a}_m_s2"] = mot.f_b[:, j]
    from ..files import staged_files

    with staged_files(out) as stage:  # the three files whole or none (a failure leaves the earlier set)
        write_array(stage(out / "array.csv"), data, overwrite=True)
        write_layout(stage(out / "layout.csv"), layout, overwrite=True)
        if scenario == SOURCE_SCENARIO:
            write_inertial(stage(out / "truth.csv"), truth, extra=extra, overwrite=True)
        else:
            from ..types import NavSolution

            io.write_solution(stage(out / "truth.csv"),
                              NavSolution(truth.time, truth.lla, truth.v_n, truth.q_nb, extra), overwrite=True)
    files = [str(out / n) for n in ("array.csv", "layout.csv", "truth.csv")]
    return {"scenario": scenario, "kind": kind, "layout": layout.label, "accelerometers": len(layout),
            "d_m": layout.d, "rate_hz": rate, "samples": len(t), "duration_s": float(t[-1] - t[0]), "seed": seed,
            "errors": {"bias_m_s2": err.bias, "scale_factor": err.scale_factor, "noise_sigma_m_s2": err.noise_sigma,
                       "misaligned": err.axes_true_b is not None},
            "elapsed_s": time.perf_counter() - t0, "files": files}


def _check_motion_sampled(sc, rate, name):
    """Refuse a sampling rate [Hz] whose point samples cannot resolve the
    scenario's periodic motion: a vibration (the top of its band) or a
    coning segment at or above the Nyquist frequency ``rate / 2``.

    The scenario's own checks hold its frequencies below the Nyquist
    frequency of its IMU; ``--rate`` lowers the rate after them.  The array's
    outputs are instantaneous samples, so such motion aliases into slow,
    false motion that the navigation integrates: the car's 14 Hz heave
    sampled at 20 Hz cost 9 m of height in 60 s, with exact data and no
    word of warning.
    """
    nyquist_hz = 0.5 * rate
    items = []
    for i, v in enumerate(sc.vibration, start=1):
        top, key = v.top_hz()
        what = f"frequency_hz {top:g} Hz" if v.kind == "sinusoidal" else f"band reaching {top:g} Hz ({key})"
        items.append((f"vibration {i} ({v.target}, {v.kind})", top, what))
    for i, seg in enumerate(sc.segment, start=1):
        if seg.type == "coning":
            items.append((f"segment {i} (coning)", seg.frequency_hz, f"frequency_hz {seg.frequency_hz:g} Hz"))
    for item, f_hz, what in items:
        if f_hz >= nyquist_hz:
            raise InputError(f"--rate {rate:g} Hz: {name}: {item}: its {what} is at or above the Nyquist "
                             f"frequency of the array's samples ({nyquist_hz:g} Hz): they would alias it into "
                             f"false slow motion; give --rate above {2.0 * f_hz:g} Hz (the scenario's IMU "
                             f"samples at {sc.imu.rate_hz:g} Hz)")


def _check_rate(rate, T):
    """Refuse a rate outside (0, MAX_RATE_HZ], and a duration of fewer than
    two or more than MAX_SAMPLES samples at it (before any array is made)."""
    if not (np.isfinite(rate) and 0 < rate <= MAX_RATE_HZ):
        raise InputError(f"--rate must be within (0, {MAX_RATE_HZ:g}] Hz, got {rate}")
    if not (np.isfinite(T) and T * rate >= 2):  # said of both options: either may be the one given
        fixes = ([f"a --rate of at least {2.0 / T:.4g} Hz"] if np.isfinite(T) and 0 < T and 2.0 / T <= MAX_RATE_HZ
                 else []) + [f"a --duration of at least {2.0 / rate:.4g} s"]
        raise InputError(f"--duration {T:g} s at --rate {rate:g} Hz covers fewer than two sampling intervals: give "
                         + " or ".join(fixes))
    if T * rate > MAX_SAMPLES:
        raise InputError(f"--duration {T:g} s at --rate {rate:g} Hz: {T * rate:,.0f} samples, more than the "
                         f"{MAX_SAMPLES:,} one simulation holds; shorten --duration or lower --rate")


# --- navigate --------------------------------------------------------------------------------
def _parse_vector(text, n, what):
    parts = [p for p in str(text).replace(" ", "").split(",") if p]
    try:
        x = [float(p) for p in parts]
    except ValueError:
        raise InputError(f"{what}: not a number in {text!r}") from None
    if len(x) != n or not np.isfinite(x).all():
        raise InputError(f"{what}: expected {n} comma-separated finite numbers, got {text!r}")
    return np.array(x)


def _truth_rate(extra, time, t):
    """The truth's body rate ``w{x,y,z}_rad_s`` at time ``t`` (linear between
    its rows), or None when it has none."""
    if all(f"w{a}_rad_s" in extra for a in "xyz"):
        return np.array([np.interp(t, time, extra[f"w{a}_rad_s"]) for a in "xyz"])
    return None


def _check_init_span(init_from, time, array_file, t_start):
    """Refuse an ``--init-from`` file whose times do not reach the array
    file's first time, naming the option and both files (as ``inskit
    mechanize --init-from`` does)."""
    if not time[0] <= t_start <= time[-1]:
        raise InputError(f"--init-from {init_from}: spans {float(time[0]):.3f}..{float(time[-1]):.3f} s, but "
                         f"{array_file} starts at {t_start:.3f} s: mismatched time bases?")


def _inertial_at(tr, t):
    """An inertial truth's state at time ``t`` inside its span, as a one-row
    :class:`~inskit.gyrofree.motion.InertialSolution`: its row at ``t`` when
    it has one, else linear in position and velocity and a normalised blend of
    the quaternions of the rows either side (:func:`inskit.rotations.quat_blend`,
    as ``NavSolution.sample``)."""
    from ..gyrofree.motion import InertialSolution
    from ..rotations import quat_blend

    j = int(np.searchsorted(tr.time, t))
    if j < len(tr.time) and abs(tr.time[j] - t) <= 1e-9 * max(1.0, abs(t)):
        i, k, w = j, j, 0.0
    else:
        i, k = j - 1, j
        w = (t - tr.time[i]) / (tr.time[k] - tr.time[i])
    return InertialSolution(np.array([t]), (tr.r_i[i] * (1 - w) + tr.r_i[k] * w)[None],
                            (tr.v_i[i] * (1 - w) + tr.v_i[k] * w)[None], quat_blend(tr.q_ib[i], tr.q_ib[k], w)[None])


def navigate_job(array_file, layout_spec, out_dir, *, d=None, solver="auto", frame="source", init=None, init_from=None,
                 omega0=None, rate_filter_noise=None, sign_rule="robust", noise_sigma=0.0, truth_file=None,
                 overwrite=False, log=None):
    """Solve an array file and navigate; write ``rates.csv`` and ``solution.csv``.

    Parameters
    ----------
    array_file : path
        Raw outputs (``docs/formats.md``, array CSV).
    layout_spec : str
        ``"ten"``, ``"six"`` or a layout file.
    out_dir : path
    d : float, optional
        Lever arm of the built-in layouts [m] (default :data:`DEFAULT_D_M`;
        refused with a layout file).
    solver : {"auto", "closed-form", "least-squares"}
    frame : {"source", "ned", "wander", "ecef", "inertial"}
        ``"source"``: source 003's inertial navigation (eq. 43-44, no
        gravity, start C = I, r = v = 0 unless ``init_from`` gives an inertial
        truth file); the others: the core mechanizations with an Earth
        initial state from ``init`` or ``init_from``.
    init : str, optional
        ``lat_deg,lon_deg,height_m,vn,ve,vd,roll_deg,pitch_deg,yaw_deg``.
    init_from : path, optional
        A truth file (from ``inskit gyrofree simulate``): initial state and,
        when present, the initial rate.
    omega0 : str, optional
        ``p,q,r`` [rad/s]: initial rate (only its signs matter without a
        filter); default from ``init_from`` or rest.
    rate_filter_noise : float, optional
        Per-sample accelerometer noise [m/s^2]: use the least-squares solver's
        rate filter with it.
    sign_rule : {"robust", "source"}
        Closed form only.
    noise_sigma : float
        Per-sample noise [m/s^2] for the closed form's sign rule.
    truth_file : path, optional
        Add errors against it to the summary.

    Returns
    -------
    dict
        A JSON-able summary.
    """
    from .. import io
    from ..gyrofree.files import read_array, read_inertial, write_inertial, write_rates
    from ..gyrofree.navigation import navigate_earth, navigate_solution_inertial
    from ..gyrofree.solvers import RateFilter, solve

    log = log or (lambda s: None)
    t0 = time.perf_counter()
    frames = ("source", "ned", "wander", "ecef", "inertial")
    if frame not in frames:
        raise InputError(f"--frame must be one of {', '.join(frames)}, got {frame!r}")
    if init and init_from:
        raise InputError("give either --init or --init-from, not both")
    layout = layout_from_spec(layout_spec, d)
    out = _check_out(out_dir, ["rates.csv", "solution.csv"], overwrite, [array_file, layout_spec, init_from, truth_file])
    data = read_array(array_file, layout)
    log(f"gyrofree navigate: {len(data)} samples, layout {layout.label}")
    warnings_ = _sampling_warnings(data, array_file)
    for w in warnings_:
        log(f"warning: {w}")
    w0 = None if omega0 is None else _parse_vector(omega0, 3, "--omega0")
    initial = None
    ref_inertial = None
    if init_from:
        t_start = float(data.time[0])
        if frame == "source":
            tr, extra = read_inertial(init_from)
            _check_init_span(init_from, tr.time, array_file, t_start)
            ref_inertial = _inertial_at(tr, t_start)
        else:
            ref = io.read_solution(init_from)
            _check_init_span(init_from, ref.time, array_file, t_start)
            initial = ref.interpolate(data.time[:1]).state(0)
            extra = ref.extra
            tr = ref
        w_file = _truth_rate(extra, tr.time, t_start)
        if w0 is None:
            w0 = w_file
        elif w_file is not None:  # both: the option wins (docs/gyrofree.md), and says so
            log(f"note: --omega0 {', '.join(f'{v:g}' for v in w0)} rad/s is used, not the initial rate of "
                f"{init_from} ({', '.join(f'{v:.4g}' for v in w_file)} rad/s)")
    elif init:
        if frame == "source":
            raise InputError("--init is for the Earth frames; the source frame starts at C = I, r = v = 0 "
                             "(or use --init-from with an inertial truth file)")
        from ..types import NavState

        from ..config_files import check_option_init

        x = check_option_init("--init", _parse_vector(init, 9, "--init"))  # as inskit mechanize --init
        initial = NavState.from_euler(data.time[0], [x[0] * DEG, x[1] * DEG, x[2]], x[3:6], x[6:9] * DEG)
    elif frame != "source":
        raise InputError(f"--frame {frame} needs an initial state: --init ... or --init-from TRUTH.csv")
    omega0_from = ("--omega0" if omega0 is not None else "--init-from" if w0 is not None else "rest")
    opts = {"omega0": w0}
    if solver in ("auto", "closed-form") and rate_filter_noise is None:
        from ..gyrofree.layout import source_index

        if solver == "closed-form" or source_index(layout) == "ten":
            solver = "closed-form"
            opts.update(sign_rule=sign_rule, noise_sigma=noise_sigma)
    if rate_filter_noise is not None:
        if solver == "closed-form":
            raise InputError("--filter-noise uses the least-squares solver's rate filter; drop --solver closed-form")
        solver = "least-squares"
        opts["rate_filter"] = RateFilter(sensor_noise=rate_filter_noise)
    if solver != "closed-form":  # options of the closed form only: not taken in silence by another solver
        why = ("--filter-noise selects the least-squares solver" if rate_filter_noise is not None else
               "--solver least-squares is given" if solver == "least-squares" else
               f"--solver auto takes least squares for layout {layout.label!r} (not the ten layout)")
        given = [o for o, on in (("--sign-rule source", sign_rule != "robust"),
                                 (f"--noise {noise_sigma:g}", noise_sigma != 0.0)) if on]
        if given:
            them = ("they are options", "them") if len(given) > 1 else ("it is an option", "it")
            raise InputError(f"{' and '.join(given)} would be ignored: {them[0]} of the closed-form solver and "
                             f"{why}; drop {them[1]}, or give --solver closed-form (the ten layout)")
    truth = None if not truth_file else _read_truth(frame, truth_file, data.time, array_file)  # before the solve
    sol = solve(data, layout, method="least-squares" if solver == "auto" else solver, **opts)
    from ..files import staged_files

    # both files whole or neither, and only once the run is through (a truth file that could not be read, after
    # them, left them behind beside a failed command)
    with staged_files(out) as stage:
        write_rates(stage(out / "rates.csv"), sol, overwrite=True)
        summary = {"array_file": str(array_file), "layout": layout.label, "solver": sol.method, "frame": frame,
                   "samples": len(sol), "duration_s": float(sol.time[-1] - sol.time[0]),
                   "omega0_rad_s": None if w0 is None else w0, "omega0_from": omega0_from}
        if frame == "source":
            kw = {}
            if ref_inertial is not None:
                kw = {"q_ib0": ref_inertial.q_ib[0], "v_i0": ref_inertial.v_i[0], "r_i0": ref_inertial.r_i[0]}
            nav = navigate_solution_inertial(sol, **kw)
            write_inertial(stage(out / "solution.csv"), nav, overwrite=True)
            summary["final"] = {"time_s": float(nav.time[-1]), "r_i_m": nav.r_i[-1], "v_i_m_s": nav.v_i[-1]}
        else:
            nav = navigate_earth(sol, initial, frame=frame)
            io.write_solution(stage(out / "solution.csv"), nav, overwrite=True)
            end = nav.state(len(nav) - 1)
            summary["final"] = {"time_s": end.time, "lat_deg": end.lla[0] / DEG, "lon_deg": end.lla[1] / DEG,
                                "height_m": end.lla[2]}
        if truth_file:
            summary["truth_errors"] = _truth_errors(frame, nav, sol, truth)
    summary["warnings"] = warnings_
    summary["elapsed_s"] = time.perf_counter() - t0
    summary["files"] = [str(out / "rates.csv"), str(out / "solution.csv")]
    return summary


def _sampling_warnings(data, name):
    """Gaps and rate changes of an array file's time column, in words, as
    ``inskit mechanize`` reports them of an IMU log; a gap beyond
    :data:`inskit.integration.gaps.MAX_GAP_S` is refused.  The solvers and
    the navigation step across a gap from its two end samples (the rate
    sign tracker integrates the angular acceleration over it), so a run
    across one completes but is degraded, and says so."""
    from ..integration.gaps import find_gaps, find_rate_changes, refuse_long_gaps

    gaps = find_gaps(data)
    refuse_long_gaps(gaps, str(name))
    out = [f"{name}: the sampling rate changes from {ch.rate_before_hz:.4g} Hz to {ch.rate_after_hz:.4g} Hz near "
           f"t = {ch.t_s:.3f} s (row {ch.row})" for ch in find_rate_changes(data)]
    out += [f"{name}: a gap of {g.length_s:.3f} s at t = {g.start_s:.3f} s (row {g.row}); the solver and the "
            "navigation step across it from its two end samples" for g in gaps]
    return out


def _read_truth(frame, truth_file, t, array_file):
    """The truth of ``--truth`` (``(truth, extra, rows)``), read and checked
    before the solve: it must cover the array's times ``t`` (a truth of the
    run's first 30 s scored 'final' at 30 s and held its rates past its end:
    a 3.86 m/s^2 'force error' of an exact solution); in the source frame it
    must hold each array time (``rows``: where, in the truth; a longer truth
    is fine)."""
    from .. import io
    from ..gyrofree.files import read_inertial

    if frame == "source":
        tr, extra = read_inertial(truth_file)
    else:
        tr = io.read_solution(truth_file)
        extra = tr.extra
    tol = 1e-9 * max(1.0, float(np.abs(t).max()))
    if tr.time[0] > t[0] + tol or tr.time[-1] < t[-1] - tol:
        raise InputError(f"{truth_file}: spans {tr.time[0]:.3f}..{tr.time[-1]:.3f} s, but {array_file} runs "
                         f"{t[0]:.3f}..{t[-1]:.3f} s: the truth must cover the whole run (its errors would be "
                         "scored against a truth held past its ends)")
    rows = None
    if frame == "source":  # the inertial truth is compared row by row: each array time must be one of its times
        rows = np.clip(np.searchsorted(tr.time, t), 0, len(tr.time) - 1)
        prev = np.clip(rows - 1, 0, len(tr.time) - 1)
        rows = np.where(np.abs(tr.time[prev] - t) < np.abs(tr.time[rows] - t), prev, rows)
        off = np.abs(tr.time[rows] - t) > tol
        if off.any():
            k = int(np.argmax(off))
            raise InputError(f"{truth_file}: holds no row at t = {t[k]:.6f} s (row {k} of {array_file}; nearest "
                             f"{tr.time[rows[k]]:.6f} s): the source frame compares the truth at the array's own "
                             "times")
    return tr, extra, rows


def _truth_errors(frame, nav, sol, truth):
    from .. import analysis

    tr, extra, rows = truth
    if frame == "source":
        e = np.linalg.norm(nav.r_i - tr.r_i[rows], axis=1)
        res = {"position_max_m": float(e.max()), "position_final_m": float(e[-1])}
    else:
        s = analysis.summarize(analysis.nav_error(nav, tr))
        res = {"horizontal_max_m": s["horizontal_m"]["max"], "down_max_m": s["down_m"]["max"],
               "3d_final_m": s["3d_m"]["final"]}
    if all(f"w{a}_rad_s" in extra for a in "xyz"):
        tt = tr.time
        w_true = np.column_stack([np.interp(sol.time, tt, extra[f"w{a}_rad_s"]) for a in "xyz"])
        f_true = np.column_stack([np.interp(sol.time, tt, extra[f"f{a}_m_s2"]) for a in "xyz"])
        res["rate_error_max_rad_s"] = float(np.abs(sol.omega_ib_b - w_true).max())
        res["force_error_max_m_s2"] = float(np.abs(sol.f_b - f_true).max())
        res["rate_sign_errors"] = int(np.sum((np.sign(sol.omega_ib_b) != np.sign(w_true)) & (np.abs(w_true) > 1e-3)))
    return res


# --- reproduce ----------------------------------------------------------------------------------
def reproduce_gyrofree(out_dir, *, quick=False, log=None):
    """Source 003: the table of published against ours, figures like the
    source's 11-14, the sensitivity figure and the 60 s comparison (plot and
    ``growth_60s.csv``), all in ``out_dir``.

    Returns
    -------
    dict
        JSON-able: ``entries`` (each with ``item``, ``published``, ``ours``,
        ``note``), ``growth_60s`` (the table), ``figures``, ``closest_reading``.
    """
    from .reproduce_gyrofree import run

    log = log or (lambda s: None)
    res = run(log, quick=quick)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    log("reproduce gyrofree: figures")
    figs = _plots(out, res)
    comp = res["comparison"]
    rows = comp["table"]
    keys = [k for k in rows[0] if k != "unit"]
    lines = ["unit," + ",".join(keys)] + [f"\"{r['unit']}\"," + ",".join(f"{r[k]:.6g}" for k in keys) for r in rows]
    write_text(out / "growth_60s.csv", "\n".join(lines) + "\n")
    write_json(out / "entries.json", res["entries"])
    return {"experiment": "gyrofree", "source": "003", "entries": res["entries"],
            "truth_check": plain_json(res["truth_check"]), "growth_60s": rows, "growth_grades": comp["grades_text"],
            "closest_reading": res["closest_reading"], "random_misalignment": res["random_misalignment"],
            "figures": [str(p) for p in figs], "tables": [str(out / "growth_60s.csv"), str(out / "entries.json")]}


def _plots(out, res):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..analysis import line_breaks
    from .reproduce_gyrofree import PUBLISHED_ANALYTIC, PUBLISHED_SIMULATED

    paths = []
    f14 = res["fig14"]
    truth, nav, t = f14["truth"], f14["navigated"], f14["time"]
    step = max(1, len(t) // 2000)
    ax_names = ("X", "Y", "Z")

    def save(fig, name):
        fig.tight_layout()
        p = out / name
        save_figure(fig, p, dpi=110)
        paths.append(p)

    # fig. 11: Euler angles
    fig, ax = plt.subplots(figsize=(8, 4.5))
    e_t, e_n = np.degrees(truth.euler[::step]), np.degrees(nav.euler[::step])
    for j, nme in enumerate(("roll", "pitch", "yaw")):
        # broken at the +-180 deg wrap: no vertical line drawn there
        ax.plot(*line_breaks(t[::step], e_t[:, j], period=360.0), color=f"C{j}", lw=1.2, label=f"{nme} (truth)")
        ax.plot(*line_breaks(t[::step], e_n[:, j], period=360.0), "--", color="k", lw=0.6,
                label="array, errors of fig. 14" if j == 0 else None)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("Euler angle of C_ib (ZYX) [deg]")
    ax.set_title("fig. 11: Euler angles, rate [1, 2, 3] rad/s")
    ax.legend(fontsize=7, ncol=2)
    ax.grid(alpha=0.3)
    save(fig, "fig11_euler_angles.png")
    # fig. 12: position per axis
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for j in range(3):
        ax.plot(t[::step], truth.r_i[::step, j], color=f"C{j}", lw=1.2, label=f"{ax_names[j]} (truth)")
        ax.plot(t[::step], nav.r_i[::step, j], "--", color="k", lw=0.6,
                label="array, errors of fig. 14" if j == 0 else None)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("inertial position [m]")
    ax.set_title("fig. 12: position along each inertial axis")
    ax.legend(fontsize=8, ncol=2)
    ax.grid(alpha=0.3)
    save(fig, "fig12_position.png")
    # fig. 13: trajectory
    fig = plt.figure(figsize=(7, 6))
    ax3 = fig.add_subplot(111, projection="3d")
    ax3.plot(*truth.r_i[::step].T, lw=1.2, label="truth")
    ax3.plot(*nav.r_i[::step].T, "--", lw=0.9, label="array (errors of fig. 14)")
    ax3.set_xlabel("X [m]")
    ax3.set_ylabel("Y [m]")
    ax3.set_zlabel("Z [m]")
    ax3.set_title("fig. 13: path in the inertial frame")
    ax3.legend(fontsize=8)
    save(fig, "fig13_trajectory.png")
    # fig. 14: position error
    fig, ax = plt.subplots(figsize=(8, 4.5))
    colors = ("C0", "C1", "C2")
    for j in range(3):
        ax.plot(t[::step], f14["simulated_m"][::step, j], color=colors[j], lw=1.3, label=f"{ax_names[j]} simulated")
        ax.plot(t[::step], f14["analytic_exact_m"][::step, j], ":", color="k", lw=0.8)
        ax.plot(t[::step], f14["analytic_linear_m"][::step, j], "--", color=colors[j], lw=0.7)
        ax.plot([10.0], [PUBLISHED_ANALYTIC[j]], "x", color=colors[j], ms=8)
        ax.plot([10.0], [PUBLISHED_SIMULATED[j]], "o", mfc="none", color=colors[j], ms=8)
    ax.plot([], [], ":", color="k", label="analytic (exact)")
    ax.plot([], [], "--", color="0.4", label="analytic (linearised eq. 25)")
    ax.plot([], [], "x", color="0.3", label="published analytic")
    ax.plot([], [], "o", mfc="none", color="0.3", label="published simulated")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("position error [m]")
    ax.set_title("fig. 14: position error, misalignment -0.1 deg on m1-m6 + bias 1e-6 m/s^2")
    ax.legend(fontsize=7, ncol=2)
    ax.grid(alpha=0.3)
    save(fig, "fig14_position_error.png")
    # sensitivity
    s = res["sensitivity"]
    fig, axs = plt.subplots(1, 3, figsize=(16, 4.8))
    styles = ("-", "--", "-.", ":")
    for (name, cur), ls in zip(s["curves"].items(), styles):
        for j in range(3):
            axs[0].semilogx(s["d"], cur[:, j], ls, color=colors[j], lw=1.1)
        axs[0].plot([], [], ls, color="0.3", label=name)
    for j in range(3):
        axs[0].axhline(PUBLISHED_ANALYTIC[j], color=colors[j], lw=0.6, alpha=0.6)
        axs[0].plot([], [], color=colors[j], label=f"{ax_names[j]} (thin: published)")
    axs[0].set_yscale("symlog", linthresh=1)  # every curve whole: the small-d errors run to tens of metres
    axs[0].set_xlabel("lever arm d [m]")
    axs[0].set_ylabel("position error at 10 s [m] (symlog)")
    axs[0].set_title("sensitivity to d")
    axs[0].legend(fontsize=6)
    axs[0].grid(alpha=0.3)
    allx = np.concatenate([s["pattern_dp"][dd][:, 0] for dd in s["pattern_dp"]])
    lim = float(np.abs(allx).max())
    for dd, mk in zip(sorted(s["pattern_dp"]), ("o", "^")):
        p = s["pattern_dp"][dd]
        sc = axs[1].scatter(p[:, 1], p[:, 2], c=p[:, 0], cmap="coolwarm", vmin=-lim, vmax=lim, marker=mk, s=18,
                            label=f"64 sign patterns, d = {dd:g} m")
    fig.colorbar(sc, ax=axs[1], label="X error at 10 s [m]")
    axs[1].plot(PUBLISHED_ANALYTIC[1], PUBLISHED_ANALYTIC[2], "k*", ms=12, label="published (-0.45, -2.04, -2.98)")
    axs[1].set_xscale("symlog", linthresh=1)
    axs[1].set_yscale("symlog", linthresh=1)
    axs[1].set_xlabel("Y error at 10 s [m] (colour: X)")
    axs[1].set_ylabel("Z error at 10 s [m]")
    axs[1].set_title("angle signs: +-0.1 deg on m1-m6")
    axs[1].legend(fontsize=7)
    axs[1].grid(alpha=0.3)
    axs[2].loglog(s["bias"], s["bias_equal_m"], label="equal biases (rate errors cancel)")
    axs[2].loglog(s["bias"], s["bias_worst_m"], label="worst sign pattern, d = 0.1 m")
    axs[2].axhline(float(np.linalg.norm(PUBLISHED_ANALYTIC)), color="k", ls="--", lw=0.8, label="|published| = 3.64 m")
    axs[2].axvline(1e-6, color="0.5", ls=":", lw=0.8, label="printed bias 1e-6 m/s^2")
    axs[2].set_xlabel("bias F [m/s^2]")
    axs[2].set_ylabel("|position error| at 10 s [m]")
    axs[2].set_title("sensitivity to the bias")
    axs[2].legend(fontsize=7)
    axs[2].grid(alpha=0.3, which="both")
    save(fig, "sensitivity.png")
    # 60 s growth
    c = res["comparison"]
    fig, ax = plt.subplots(figsize=(8, 4.8))
    for u, v in c["rms_m"].items():
        ax.semilogy(c["time"][1:], v[1:], label=u)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(f"RMS |position error| over {c['runs']} runs [m]")
    ax.set_title("60 s on the source's motion: ten-accelerometer unit vs conventional IMU")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    save(fig, "growth_60s.png")
    return paths


__all__ = ["array_errors_from_datasheet", "layout_from_spec", "navigate_job", "reproduce_gyrofree", "simulate_job"]
