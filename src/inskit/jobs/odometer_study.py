"""Simulated odometer study: GNSS outages bridged with and without wheel speed.

One seeded simulation of a scenario (default ``examples/car.toml``): its IMU,
its GNSS fixes with 60 s outages withheld while the car drives, and a
simulated odometer (:func:`inskit.simulation.odometer.simulate_odometer`,
scale error ``k``, white noise).  The closed-loop filter runs twice on the
same IMU, start and fixes, with the non-holonomic constraint both times:

* without the odometer;
* with it (:class:`inskit.integration.aiding.Odometer`, and the
  ``odo_scale`` state estimating ``k``).

Each run is scored against the simulated truth (:func:`inskit.analysis.nav_error`):
horizontal error at the end of each outage and the worst inside it; and the
estimated ``k`` against the simulated one.

The filter gets the simulator's own noise model of the IMU grade
(:func:`.montecarlo.matched_settings`, :func:`.montecarlo.grade_initial_uncertainty`)
plus scale-factor states; the start is drawn from its initial covariance
(:func:`.montecarlo.perturbed_start`).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from .. import analysis
from ..errors import ConfigError
from ..integration import GnssPosition, NonHolonomic, run_filter
from ..integration.aiding import Odometer, OdometerScale
from ..simulation.odometer import simulate_odometer
from ..simulation.scenario import Scenario, imu_errors, load_scenario, simulate
from .montecarlo import GRADE_INITIAL_ATTITUDE_DEG, grade_initial_uncertainty, matched_settings, perturbed_start
from .outages import withheld_mask

#: the default scenario, relative to the repository root
DEFAULT_SCENARIO = Path(__file__).resolve().parents[3] / "examples" / "car.toml"
#: four 60 s outages of examples/car.toml, all while it drives (it moves over 63-461 s,
#: 486-597 s and 616-1810 s): a climb and a turn, the figure-eight, and two on the long cruise
DEFAULT_OUTAGES_S = ((200.0, 260.0), (500.0, 560.0), (800.0, 860.0), (1300.0, 1360.0))


def _score(err, windows):
    h = err.horizontal
    rows = []
    for a, b in windows:
        inside = np.nonzero((err.time >= a) & (err.time <= b))[0]
        if len(inside) == 0:
            rows.append({"end_horizontal_m": None, "worst_horizontal_m": None})
            continue
        rows.append({"end_horizontal_m": float(h[inside[-1]]), "worst_horizontal_m": float(h[inside].max())})
    return rows


def odometer_study(scenario_path=DEFAULT_SCENARIO, seed=1, outages=DEFAULT_OUTAGES_S, scale_error=0.005,
                   noise=0.05, *, odometer_rate_hz=10.0, odometer_lever_arm_b=(0.0, 0.0, 0.0),
                   nhc_sigma_m_s=0.1, nhc_rate_hz=10.0, scale_sigma0=0.01, progress=None) -> dict:
    """Outage errors with and without a simulated odometer, side by side.

    Parameters
    ----------
    scenario_path : path or Scenario
        A scenario file, or a :class:`Scenario` already loaded (tests pass a
        short one).  Its IMU lever arm must be zero: the truth then is the
        IMU's own trajectory, which the errors are taken of.
    seed : int
        Seeds the simulation; the odometer's noise and the start draw come
        from children of ``SeedSequence(seed)``, so they change no IMU or
        GNSS number.
    outages : sequence of (start, end)
        GNSS outage windows [s of scenario time]; at least one.
    scale_error : float
        The odometer's true scale-factor error ``k`` [-].
    noise : float
        Its white noise [m/s].
    odometer_rate_hz : float
    odometer_lever_arm_b : (3,) array_like
        IMU-to-odometer point, body axes [m].
    nhc_sigma_m_s, nhc_rate_hz : float
        The non-holonomic constraint of both runs.
    scale_sigma0 : float
        Initial sigma of the ``odo_scale`` state.
    progress : callable, optional
        Called with a short text after each stage.

    Returns
    -------
    dict
        ``scenario``, ``seed``, ``duration_s``, ``scale_error``, ``noise_m_s``;
        ``outages``: per window ``start_s``, ``end_s``, ``without`` and
        ``with`` (each ``end_horizontal_m``, ``worst_horizontal_m``);
        ``summary``: RMS over the outages of both figures per run and the
        horizontal RMS with GNSS on; ``odo_scale``: ``true``, ``estimate``
        and ``sigma`` at the end, and the estimate at the start of the first
        outage; ``measurements``: the filter's counts; ``elapsed_s``.
    """
    t_start = time.perf_counter()
    say = progress or (lambda s: None)
    sc = scenario_path if isinstance(scenario_path, Scenario) else load_scenario(scenario_path)
    name = sc.name
    if any(sc.imu.lever_arm_b_m):
        raise ConfigError(f"scenario {name!r}: the odometer study scores the IMU against the truth point; "
                          f"give imu.lever_arm_b_m = [0, 0, 0] (got {list(sc.imu.lever_arm_b_m)})")
    if sc.imu.grade not in GRADE_INITIAL_ATTITUDE_DEG:
        raise ConfigError(f"scenario {name!r}: the study needs an IMU grade with a noise model "
                          f"({', '.join(GRADE_INITIAL_ATTITUDE_DEG)}), got {sc.imu.grade!r}")
    windows = [(float(a), float(b)) for a, b in outages]
    if not windows or any(not b > a for a, b in windows):
        raise ConfigError(f"outages must be one or more (start, end) windows with end > start, got {outages!r}")
    sim = simulate(sc, seed)
    truth, gnss = sim.truth, sim.gnss
    t0, t1 = float(sim.imu.time[0]), float(sim.imu.time[-1])
    for a, b in windows:
        if a < t0 or b > t1:
            raise ConfigError(f"outage ({a:g}, {b:g}) s lies outside the scenario ({t0:g}..{t1:.1f} s)")
    say(f"simulated {name}: {len(sim.imu)} IMU samples, {len(gnss)} fixes")
    rng_odo, rng_start = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(3)[1:])
    lever_odo = np.asarray(odometer_lever_arm_b, float)
    odo = simulate_odometer(truth, rate_hz=odometer_rate_hz, scale_error=scale_error, noise_m_s=noise,
                            lever_arm_b=lever_odo, rng=rng_odo)
    lever = np.asarray(sc.gnss.lever_arm_b_m, float)
    errors, init = imu_errors(sc), grade_initial_uncertainty(sc.imu.grade)
    plain = matched_settings(errors, init, scale_factors=True, lever_arm_b=tuple(lever), gravity=sc.earth.gravity)
    with_odo = matched_settings(errors, init, scale_factors=True, lever_arm_b=tuple(lever),
                                extra_blocks=(OdometerScale(scale_sigma0),), gravity=sc.earth.gravity)
    start = perturbed_start(truth.state(0), plain, rng_start)
    used = ~withheld_mask(gnss.time, windows)
    common = [GnssPosition(gnss, used, lever_arm_b=lever), NonHolonomic([(t0, t1)], nhc_rate_hz, nhc_sigma_m_s)]
    odometer = Odometer(odo.time, odo.speed_m_s, max(noise, 1e-3), lever_arm_b=lever_odo)
    runs = {}
    for label, settings, meas in (("without", plain, common), ("with", with_odo, common + [odometer])):
        runs[label] = run_filter(sim.imu, start, meas, settings)
        say(f"filter {label} odometer done")
    errs = {k: analysis.nav_error(r.nav, truth) for k, r in runs.items()}
    scores = {k: _score(e, windows) for k, e in errs.items()}
    table = [{"k": i, "start_s": a, "end_s": b, "without": scores["without"][i], "with": scores["with"][i]}
             for i, (a, b) in enumerate(windows)]
    on = ~withheld_mask(errs["with"].time, windows)

    def rms(label, key):
        v = [s[key] for s in scores[label] if s[key] is not None]
        return float(np.sqrt(np.mean(np.square(v)))) if v else None

    summary = {label: {"outage_end_horizontal_rms_m": rms(label, "end_horizontal_m"),
                       "outage_worst_horizontal_rms_m": rms(label, "worst_horizontal_m"),
                       "gnss_on_horizontal_rms_m": float(np.sqrt(np.mean(errs[label].horizontal[on] ** 2)))}
               for label in runs}
    out = runs["with"]
    k_est = out.estimate("odo_scale")[:, 0]
    k_sig = out.sigma_of("odo_scale")[:, 0]
    first = int(np.searchsorted(out.nav.time, windows[0][0]))
    return {
        "scenario": name,
        "seed": int(seed),
        "duration_s": t1 - t0,
        "scale_error": float(scale_error),
        "noise_m_s": float(noise),
        "outages": table,
        "summary": summary,
        "odo_scale": {"true": float(scale_error), "estimate": float(k_est[-1]), "sigma": float(k_sig[-1]),
                      "estimate_at_first_outage": float(k_est[min(first, len(k_est) - 1)]),
                      "sigma_at_first_outage": float(k_sig[min(first, len(k_sig) - 1)])},
        "measurements": {k: r.counts for k, r in runs.items()},
        "elapsed_s": time.perf_counter() - t_start,
    }


def odometer_study_table(res: dict) -> str:
    """The study as a text table (for the CLI to print)."""
    lines = [f"odometer study: {res['scenario']}, seed {res['seed']}, odometer scale error "
             f"{res['scale_error']:.4f}, noise {res['noise_m_s']:.3f} m/s",
             "",
             "outage [s]        horizontal error [m]: at the end      worst inside",
             "                  without odometer   with        without   with"]
    for r in res["outages"]:
        w, o = r["without"], r["with"]

        def f(x):
            return "      -" if x is None else f"{x:8.2f}"
        lines.append(f"{r['start_s']:7.1f}-{r['end_s']:7.1f}  {f(w['end_horizontal_m'])}          "
                     f"{f(o['end_horizontal_m'])}    {f(w['worst_horizontal_m'])}  {f(o['worst_horizontal_m'])}")
    s = res["summary"]
    lines.append(f"RMS              {s['without']['outage_end_horizontal_rms_m']:8.2f}          "
                 f"{s['with']['outage_end_horizontal_rms_m']:8.2f}    "
                 f"{s['without']['outage_worst_horizontal_rms_m']:8.2f}  "
                 f"{s['with']['outage_worst_horizontal_rms_m']:8.2f}")
    lines.append(f"GNSS on, horizontal RMS: without {s['without']['gnss_on_horizontal_rms_m']:.3f} m, "
                 f"with {s['with']['gnss_on_horizontal_rms_m']:.3f} m")
    k = res["odo_scale"]
    lines.append(f"odometer scale: true {k['true']:.5f}, estimated {k['estimate']:.5f} +- {k['sigma']:.5f} "
                 f"(1 sigma) at the end; {k['estimate_at_first_outage']:.5f} +- {k['sigma_at_first_outage']:.5f} "
                 "at the first outage")
    return "\n".join(lines)
