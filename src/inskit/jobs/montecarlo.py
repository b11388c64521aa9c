"""Monte Carlo runs of the integration filter on simulated data.

Consistency (Bar-Shalom, Li & Kirubarajan 2001, §5.4): over ``N`` runs the
average normalised estimation error squared (ANEES) of a ``d``-dimensional
block is ``chi^2(N d) / N`` distributed when the filter is consistent; its
two-sided 95 % band is ``[chi2.ppf(0.025, N d) / N, chi2.ppf(0.975, N d) / N]``.

The filter is given the simulator's own error model (:func:`matched_settings`)
so that a failed test points at the filter, not at a model mismatch; sensor
terms the 15-state filter does not model (scale factor, misalignment,
g-sensitivity, quantization, correlated GNSS errors) are switched off in
:func:`consistency_errors`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy import stats

from .. import earth
from .. import rotations as rot
from ..integration import (FilterSettings, GnssPosition, InitialUncertainty, SensorNoise, run_filter,
                           run_uncoupled)
from ..simulation.gnss import GnssErrors, fix_times, simulate_gnss
from ..simulation.imu import ideal_imu, truth_solution
from ..simulation.sensors import ImuErrors, TriadErrors, apply_imu_errors
from ..strapdown import check_track_off_pole
from ..errors import InputError
from ..types import NavState
from ..units import DEG_PER_HOUR, MAX_SAMPLES, MICRO_G

#: initial uncertainty used by the consistency runs, per IMU grade (tilt, yaw) [deg]
GRADE_INITIAL_ATTITUDE_DEG = {"navigation": (0.2, 1.0), "tactical": (0.2, 1.0), "industrial-mems": (1.0, 3.0),
                              "consumer-mems": (1.0, 3.0)}


#: GNSS of the consistency runs (``inskit consistency``, a study without an outage): 1 Hz white fixes
CONSISTENCY_GNSS = GnssErrors(rate_hz=1.0, white_h_m=1.0, white_v_m=2.0, velocity_sigma_m_s=0.0)


def min_consistency_duration_s(gnss: GnssErrors = CONSISTENCY_GNSS) -> float:
    """The shortest run of a consistency study [s]: two GNSS intervals, so
    that a fix after the start updates the filter (the NEES is taken at the
    updates; the fix at the start is the initial epoch): 2 s at 1 Hz."""
    return 2.0 / gnss.rate_hz


def grade_initial_uncertainty(grade) -> InitialUncertainty:
    """The initial uncertainty of the consistency runs for an IMU grade."""
    tilt, yaw = GRADE_INITIAL_ATTITUDE_DEG[grade]
    return InitialUncertainty(pos_m=(1.0, 1.0, 2.0), vel_m_s=0.1, roll_pitch_rad=np.radians(tilt),
                              yaw_rad=np.radians(yaw))


def consistency_errors(errors: ImuErrors) -> ImuErrors:
    """The stochastic part of a sensor model that the 15-state filter models:
    white noise, turn-on bias and Gauss-Markov bias instability."""

    def keep(e: TriadErrors):
        return TriadErrors(turn_on_bias_sigma=e.turn_on_bias_sigma, bias_instability=e.bias_instability,
                           bias_instability_tau_s=e.bias_instability_tau_s, white_noise=e.white_noise)

    return ImuErrors(keep(errors.gyro), keep(errors.accel), errors.source)


#: the least initial bias sigma :func:`matched_settings` gives the filter: 0.001 deg/h, 0.1 ug (an ideal sensor's
#: bias is zero, and a zero sigma no covariance)
MIN_GYRO_BIAS_SIGMA = 1e-3 * DEG_PER_HOUR
MIN_ACCEL_BIAS_SIGMA = 0.1 * MICRO_G


def matched_settings(errors: ImuErrors, initial: InitialUncertainty, **kw) -> FilterSettings:
    """Filter settings that match a sensor model (15 states).

    The true bias is a random constant (turn-on) plus a Gauss-Markov term.
    One state per axis cannot be both: a Gauss-Markov state would let the
    turn-on part of the error variance decay with the correlation time (the
    filter then grows overconfident: 1.6 sigma after 200 s in the tactical
    test), so the state is a random walk driven by the Gauss-Markov PSD
    ``2 sigma^2 / tau``.  It is conservative over runs much longer than tau;
    separate Gauss-Markov states would be the exact model.
    """
    g, a = errors.gyro, errors.accel
    noise = SensorNoise(max(g.white_noise, 1e-12), max(a.white_noise, 1e-12),
                        max(g.gm_sigma * np.sqrt(2.0 / g.bias_instability_tau_s), 1e-15),
                        max(a.gm_sigma * np.sqrt(2.0 / a.bias_instability_tau_s), 1e-15), np.inf)
    # an ideal sensor has no bias at all: the filter's initial sigma is floored as its noise is (a zero sigma is
    # no covariance; the 'ideal' grade, the scenario's default, was refused by InitialUncertainty)
    init = replace(initial, gyro_bias=max(float(np.hypot(g.turn_on_bias_sigma, g.gm_sigma)), MIN_GYRO_BIAS_SIGMA),
                   accel_bias=max(float(np.hypot(a.turn_on_bias_sigma, a.gm_sigma)), MIN_ACCEL_BIAS_SIGMA))
    extra = {k: kw.pop(k) for k in ("lever_arm_b", "lever_arm", "time_offset", "scale_factors", "time_offset0",
                                    "extra_blocks") if k in kw}
    return FilterSettings.standard(noise, init, **extra, **kw)


def perturbed_start(truth_state: NavState, settings: FilterSettings, rng):
    """Initial state drawn from the filter's initial covariance of the
    navigation blocks around the truth."""
    lay = settings.layout
    x0 = rng.multivariate_normal(np.zeros(lay.size), lay.initial_covariance())
    lla = truth_state.lla.copy()
    rn, re = earth.principal_radii(lla[0], lla[2])
    lla = lla + [x0[0] / rn, x0[1] / (re * np.cos(lla[0])), -x0[2]]
    C = rot.dcm_from_rotvec(-x0[6:9]) @ truth_state.C_nb  # C_est = (I - [phi x]) C_true
    return NavState(truth_state.time, lla, truth_state.v_n + x0[3:6], rot.quat_from_dcm(C))


@dataclass
class ConsistencySpec:
    """One Monte Carlo study of filter consistency: everything a run needs.

    Picklable (the prepared ideal IMU and truth are rebuilt where a run
    happens, once per process, and never pickled), so a distributed ``map``
    can ship it to workers.
    """

    trajectory: object
    rate_hz: float
    errors: ImuErrors
    gnss_errors: GnssErrors
    settings: FilterSettings
    duration: float | None = None
    _prepared: tuple | None = field(default=None, repr=False, compare=False)

    def __getstate__(self):
        d = dict(self.__dict__)
        d["_prepared"] = None
        return d

    def prepared(self):
        """``(t, ideal IMU, truth)``, built once per process."""
        if self._prepared is None:
            T = self.trajectory.duration if self.duration is None else self.duration
            t = np.arange(0.0, T, 1.0 / self.rate_hz)
            imu = ideal_imu(self.trajectory, t, nodes=3, gravity=self.settings.gravity)  # the filter's model
            self._prepared = (t, imu, truth_solution(self.trajectory, t))
        return self._prepared


@dataclass(frozen=True)
class RunSummary:
    """What one run returns: small and picklable.

    Attributes
    ----------
    seed : int
    t : (m,) node times [s]
    nees : dict of (m,) arrays
        NEES of the ``pos``, ``vel``, ``att`` blocks at the nodes.
    bias_normalized : (6,)
        Final gyro and accelerometer bias errors over their sigmas.
    """

    seed: int
    t: np.ndarray
    nees: dict
    bias_normalized: np.ndarray


def run_errors(spec: ConsistencySpec, seed):
    """One seeded simulation + filter run: errors and covariances at the nodes."""
    t, imu_ideal, truth = spec.prepared()
    rng = np.random.default_rng(seed)
    imu, draws = apply_imu_errors(imu_ideal, spec.errors, rng)
    gnss, _ = simulate_gnss(spec.trajectory, t[0], t[-1], spec.gnss_errors, rng)
    start = perturbed_start(truth.state(0), spec.settings, rng)
    out = run_filter(imu, start, [GnssPosition(gnss)], spec.settings, smoother=True)
    k = np.asarray(out.store.k, dtype=int)
    if len(k) == 0:  # the jobs refuse such a run first, naming their option (min_consistency_duration_s)
        raise InputError(f"a consistency run of {t[-1] - t[0]:g} s holds no GNSS update after its start (the "
                         "NEES is taken at the updates): it needs at least "
                         f"{min_consistency_duration_s(spec.gnss_errors):g} s")
    sol = out.nav
    lay = spec.settings.layout
    err = np.zeros((len(k), lay.size))
    err[:, 0:3] = earth.lla_to_ned(sol.lla[k], truth.lla[k])  # NED at each true position
    err[:, 3:6] = sol.v_n[k] - truth.v_n[k]
    err[:, 6:9] = rot.attitude_error(sol.C_nb[k], truth.C_nb[k])
    err[:, lay.slice("bg")] = out.estimate("bg")[k] - draws["gyro_bias"][k]
    err[:, lay.slice("ba")] = out.estimate("ba")[k] - draws["accel_bias"][k]
    return t[k], err, np.asarray(out.store.P_plus)


def run_once(spec: ConsistencySpec, seed) -> RunSummary:
    """One run of the study, reduced to what the statistics need."""
    t, err, P = run_errors(spec, seed)
    lay = spec.settings.layout
    nees = {}
    for b in ("pos", "vel", "att"):
        s = lay.slice(b)
        e = err[:, s]
        nees[b] = np.einsum("ni,ni->n", e, np.linalg.solve(P[:, s, s], e[..., None])[..., 0])
    idx = np.r_[lay.slice("bg"), lay.slice("ba")]
    sig = np.sqrt(np.diag(P[-1])[idx])
    return RunSummary(int(seed), t, nees, err[-1, idx] / sig)


def anees_band(runs, dof, probability=0.95):
    lo = stats.chi2.ppf((1 - probability) / 2, runs * dof) / runs
    hi = stats.chi2.ppf(1 - (1 - probability) / 2, runs * dof) / runs
    return float(lo), float(hi)


def reduce_runs(results) -> dict:
    """Average NEES per block and its 95 % band, from any number of runs in
    any order (sorted by seed, so the figures do not depend on it)."""
    results = sorted(results, key=lambda r: r.seed)
    runs = len(results)
    t = results[0].t
    anees = {b: np.sum([r.nees[b] for r in results], axis=0) / runs for b in results[0].nees}
    return {
        "t": t,
        "anees": anees,
        "band": {b: anees_band(runs, 3) for b in anees},
        "bias_normalized": np.asarray([r.bias_normalized for r in results]),
        "runs": runs,
    }


def monte_carlo(trajectory, rate_hz, errors: ImuErrors, gnss_errors: GnssErrors, initial: InitialUncertainty,
                runs=50, seed=0, duration=None, progress=None, map=map, **settings_kw):
    """Monte Carlo consistency of the closed-loop filter on a trajectory.

    ``map`` runs :func:`run_once` over the seeds ``seed .. seed + runs - 1``:
    the builtin by default, or any ``map(function, iterable)`` (a process
    pool's, a cluster client's) since the spec and the results are picklable.

    Returns
    -------
    dict with ``t`` (m,), ``anees`` {block: (m,)}, ``band`` {block: (lo, hi)},
    ``bias_normalized`` (runs, 6): final bias errors over their sigmas.
    """
    settings_kw.setdefault("smoother_node_s", 0.0)  # nodes = update epochs only
    settings = matched_settings(errors, initial, **settings_kw)
    spec = ConsistencySpec(trajectory, rate_hz, errors, gnss_errors, settings, duration)
    results = []
    for r in map(_RunOnce(spec), range(seed, seed + runs)):
        results.append(r)
        if progress:
            progress(1)
    return reduce_runs(results)


class _RunOnce:
    """``run_once`` bound to a spec, picklable (for process or cluster maps)."""

    def __init__(self, spec):
        self.spec = spec

    def __call__(self, seed):
        return run_once(self.spec, seed)
def compare_schemes(scenario, outage, seed=0, schemes=("uncoupled", "open", "closed"), initial=None):
    """Run the integration schemes on one simulated scenario with a GNSS outage.

    The IMU carries the scenario's full error model; the filters get the
    matched noise model (15 states).  Returns one row per scheme with the
    errors at the end of the outage and the RMS horizontal error with GNSS on
    (after the first 60 s, outside the outage, the scenario's own outages
    and the 60 s after each; None when the scenario leaves no such time).
    """
    from ..simulation.scenario import build_trajectory, gnss_errors, imu_errors

    rng = np.random.default_rng(seed)
    tr = build_trajectory(scenario, rng)
    t = np.arange(0.0, tr.duration, 1.0 / scenario.imu.rate_hz)
    if not (0.0 <= outage[0] and outage[1] <= t[-1]):  # the errors are taken at its end
        raise InputError(f"--outage {outage[0]:g},{outage[1]:g}: the outage must lie within the scenario "
                         f"{scenario.name!r}, 0..{t[-1]:g} s")
    from .outages import gnss_data_gaps, withheld_mask

    g_err = gnss_errors(scenario)
    fixes = fix_times(t[0], t[-1], g_err)
    withheld = withheld_mask(fixes, [outage])
    if not withheld.any():  # before the simulation
        raise InputError(f"--outage {outage[0]:g},{outage[1]:g}: holds no GNSS fix of the scenario "
                         f"{scenario.name!r} (fixes at {g_err.rate_hz:g} Hz, outside its [gnss] outages_s): it "
                         "withholds nothing; give a longer outage")
    # the schemes differ only in what they did with the fixes they used: one after the start (a fix at the first
    # epoch, the initial state's, is no update) and before the outage
    used = fixes[(fixes > t[0] + 1e-6) & (fixes < outage[0]) & ~withheld]
    if not len(used):
        after = fixes[fixes > t[0] + 1e-6]
        first = f"the first after the start is at {after[0]:g} s" if len(after) else "none after the start"
        raise InputError(f"--outage {outage[0]:g},{outage[1]:g}: no GNSS fix of the scenario {scenario.name!r} "
                         f"reaches the filters before it ({first}; fixes at {g_err.rate_hz:g} Hz, outside its [gnss] "
                         "outages_s): the three schemes would all coast alike from the initial state, comparing "
                         "nothing; start the outage after a fix")
    truth = truth_solution(tr, t)  # no draw: the numbers below stay those of the seed
    # the uncoupled INS's 'use --frame wander|ecef' named an option this job has not
    check_track_off_pole(t, truth.lla[:, 0], f"scenario {scenario.name!r}",
                         "the three schemes' NED mechanization and filters are singular")
    gravity = scenario.earth.gravity  # the simulation's and the filters' model
    ideal = ideal_imu(tr, t, nodes=scenario.imu.quadrature_nodes, gravity=gravity)
    errs = imu_errors(scenario)
    imu, _ = apply_imu_errors(ideal, errs, rng)
    gnss, _ = simulate_gnss(tr, t[0], t[-1], g_err, rng)
    use = ~withheld_mask(gnss.time, [outage])
    init = initial or InitialUncertainty(pos_m=(1.0, 1.0, 2.0), vel_m_s=0.1, roll_pitch_rad=np.radians(0.5),
                                         yaw_rad=np.radians(2.0))
    # GNSS on: after the first 60 s (start-up), outside every stretch without a used fix (this outage, the
    # scenario's own outages) and the 60 s of re-convergence after each
    gnss_on = t > 60.0
    for a, b in gnss_data_gaps(gnss.time[use], float(t[0]), float(t[-1])):  # the gaps only (a few), not every fix
        gnss_on &= ~((t > a) & (t < b + 60.0)) if a > t[0] else ~(t < b + 60.0)
    rows = []
    lever = tuple(scenario.gnss.lever_arm_b_m)
    for scheme in schemes:
        settings = matched_settings(consistency_errors(errs), init, scheme="closed" if scheme == "uncoupled"
                                    else scheme, gate_probability=None, lever_arm_b=lever, gravity=gravity)
        start = perturbed_start(truth.state(0), settings, np.random.default_rng(seed + 1))
        if scheme == "uncoupled":  # GNSS resets position and velocity
            sol = run_uncoupled(imu, start, gnss, use=use, lever_arm_b=lever, gravity=gravity)
        else:
            sol = run_filter(imu, start, [GnssPosition(gnss, use, lever_arm_b=lever)], settings).nav
        k_end = int(np.searchsorted(t, outage[1]))
        d = earth.lla_to_ned(sol.lla[k_end], truth.lla[k_end])
        att = rot.attitude_error(sol.C_nb[k_end], truth.C_nb[k_end])
        on = gnss_on
        don = earth.lla_to_ned(sol.lla[on][::100], truth.lla[on][::100]) if on.any() else None
        rows.append({
            "scheme": scheme,
            "outage_end_horizontal_m": float(np.hypot(d[0], d[1])),
            "outage_end_vertical_m": float(abs(d[2])),
            "outage_end_velocity_m_s": float(np.linalg.norm(sol.v_n[k_end] - truth.v_n[k_end])),
            "outage_end_attitude_deg": float(np.degrees(np.linalg.norm(att))),
            "gnss_on_horizontal_rms_m": (None if don is None
                                         else float(np.sqrt(np.mean(don[:, 0] ** 2 + don[:, 1] ** 2)))),
        })
    return rows


#: the most runs of ``inskit consistency``, as of a study (``runs`` of a study file)
MAX_CONSISTENCY_RUNS = 1_000_000


def consistency_study(scenario, grade, runs, duration=None, seed=0, progress=None, map=map):
    """The ``inskit consistency`` job: Monte Carlo NEES of the closed-loop
    filter on a scenario's trajectory with a preset IMU grade and 1 Hz GNSS
    (1 m horizontal, 2 m vertical white noise).  Returns the JSON summary,
    with ``verdict`` and ``reasons`` (:func:`consistency_verdict`).

    Raises
    ------
    InputError
        Fewer than two runs, a ``duration`` (or a scenario) shorter than
        :func:`min_consistency_duration_s` or longer than the scenario, or
        more than :data:`inskit.units.MAX_SAMPLES` IMU samples per run.
    """
    from ..simulation.scenario import build_trajectory
    from ..simulation.sensors import preset

    if runs < 2:
        raise InputError(f"--runs must be at least 2, got {runs}")
    if runs > MAX_CONSISTENCY_RUNS:  # as a study's runs: 1e9 would run for years, with a progress bar
        raise InputError(f"--runs must be at most {MAX_CONSISTENCY_RUNS:,}, got {runs:,} (a study file, "
                         "`inskit study`, spreads many runs over workers and resumes)")
    tr = build_trajectory(scenario, np.random.default_rng(seed))
    g = CONSISTENCY_GNSS
    shortest = min_consistency_duration_s(g)
    if tr.duration < shortest:
        raise InputError(f"the scenario {scenario.name!r} lasts {tr.duration:g} s; a consistency study needs at "
                         f"least {shortest:g} s (a GNSS update at {g.rate_hz:g} Hz after the start: the NEES is "
                         "taken at the updates)")
    if duration is not None and not 0 < duration <= tr.duration:
        raise InputError(f"--duration must be within (0, {tr.duration:.0f}] s, got {duration}")
    if duration is not None and duration < shortest:
        raise InputError(f"--duration must be at least {shortest:g} s, got {duration} (a GNSS update at "
                         f"{g.rate_hz:g} Hz after the start: the NEES is taken at the updates)")
    T = tr.duration if duration is None else duration
    if T * scenario.imu.rate_hz > MAX_SAMPLES:  # before any array is made
        raise InputError(f"--duration {T:g} s at the scenario's [imu] rate_hz = {scenario.imu.rate_hz:g} Hz: "
                         f"{T * scenario.imu.rate_hz:,.0f} IMU samples per run, more than the {MAX_SAMPLES:,} one "
                         "simulation holds; give a shorter --duration")
    r = monte_carlo(tr, scenario.imu.rate_hz, consistency_errors(preset(grade)), g, grade_initial_uncertainty(grade),
                    runs=runs, seed=seed, duration=duration, progress=progress, map=map, gate_probability=None,
                    gravity=scenario.earth.gravity)
    res = {"scenario": scenario.name, "grade": grade, "runs": runs, "duration_s": float(r["t"][-1]), "anees": {}}
    for b in ("pos", "vel", "att"):
        a = r["anees"][b]
        lo, hi = r["band"][b]
        res["anees"][b] = {"mean": float(a.mean()), "band_95": [lo, hi],
                           "fraction_of_epochs_inside": float(((a >= lo) & (a <= hi)).mean()),
                           "fraction_of_epochs_above": float((a > hi).mean()),
                           "fraction_of_epochs_below": float((a < lo).mean())}
    z = r["bias_normalized"]
    res["bias_within_3_sigma"] = float((np.abs(z) < 3).mean())
    res["bias_rms_normalized"] = float(np.sqrt(np.mean(z**2)))
    res.update(consistency_verdict(res))
    return res


#: The criteria of the filter's own consistency tests (tests/test_jobs_montecarlo.py): a block's
#: average NEES, averaged over the epochs, inside the 95 % band of one epoch, and at least this
#: fraction of the epochs inside it (0.95 is expected; the epochs' NEES are correlated in time, so
#: a few stretches move the fraction a lot).
CONSISTENT_FRACTION_INSIDE = 0.60
#: Normalised final bias errors are N(0, 1) for a consistent filter: 99.7 % within 3 sigma expected.
CONSISTENT_BIAS_WITHIN_3_SIGMA = 0.97
#: ... and their RMS near 1: outside this range the bias covariance is too small or too large.
CONSISTENT_BIAS_RMS = (0.6, 1.3)


def consistency_verdict(res: dict) -> dict:
    """``verdict`` ("consistent" or "inconsistent") and ``reasons`` of a
    consistency summary (:func:`consistency_study`), by the criteria of the
    filter's own consistency tests: each NEES block's mean inside the 95 %
    band and at least :data:`CONSISTENT_FRACTION_INSIDE` of its epochs
    inside it (above it the filter is optimistic: its covariance is smaller
    than its errors; below it pessimistic); the final bias errors at least
    :data:`CONSISTENT_BIAS_WITHIN_3_SIGMA` within 3 sigma, with an RMS in
    :data:`CONSISTENT_BIAS_RMS` sigma."""
    reasons = []
    for b, a in res["anees"].items():
        lo, hi = a["band_95"]
        inside = a["fraction_of_epochs_inside"]
        if lo <= a["mean"] <= hi and inside >= CONSISTENT_FRACTION_INSIDE:
            continue
        above, below = a.get("fraction_of_epochs_above", 0.0), a.get("fraction_of_epochs_below", 0.0)
        side = ("optimistic: its covariance smaller than its errors" if (a["mean"] > hi or above >= below)
                else "pessimistic: its covariance larger than its errors")
        reasons.append(f"{b}: average NEES {a['mean']:.2f} against the 95 % band [{lo:.2f}, {hi:.2f}], inside it at "
                       f"{inside:.0%} of the epochs (at least {CONSISTENT_FRACTION_INSIDE:.0%} wanted): the filter is "
                       f"{side}")
    lo, hi = CONSISTENT_BIAS_RMS
    rms, within = res["bias_rms_normalized"], res["bias_within_3_sigma"]
    if within < CONSISTENT_BIAS_WITHIN_3_SIGMA or not lo < rms < hi:
        side = "optimistic (sigma too small)" if rms >= hi or within < CONSISTENT_BIAS_WITHIN_3_SIGMA else \
            "pessimistic (sigma too large)"
        reasons.append(f"final sensor-bias errors: {within:.1%} within 3 sigma (at least "
                       f"{CONSISTENT_BIAS_WITHIN_3_SIGMA:.0%} wanted), RMS {rms:.2f} sigma ({lo:g} to {hi:g} wanted): "
                       f"the bias estimates are {side}")
    return {"verdict": "inconsistent" if reasons else "consistent", "reasons": reasons}
