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

from dataclasses import dataclass, replace

import numpy as np
from scipy import stats

from .. import earth
from .. import rotations as rot
from ..simulation.gnss import GnssErrors, simulate_gnss
from ..simulation.imu import ideal_imu, truth_solution
from ..simulation.sensors import ImuErrors, TriadErrors, apply_imu_errors
from ..types import NavState
from .engine import FilterSettings, InitialUncertainty, SensorNoise, run_filter
from .layout import StateLayout
from .measurements import GnssPosition, GnssVelocity


def consistency_errors(errors: ImuErrors) -> ImuErrors:
    """The stochastic part of a sensor model that the 15-state filter models:
    white noise, turn-on bias and Gauss-Markov bias instability."""

    def keep(e: TriadErrors):
        return TriadErrors(turn_on_bias_sigma=e.turn_on_bias_sigma, bias_instability=e.bias_instability,
                           bias_instability_tau_s=e.bias_instability_tau_s, white_noise=e.white_noise)

    return ImuErrors(keep(errors.gyro), keep(errors.accel), errors.source)


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
    init = replace(initial, gyro_bias=float(np.hypot(g.turn_on_bias_sigma, g.gm_sigma)),
                   accel_bias=float(np.hypot(a.turn_on_bias_sigma, a.gm_sigma)))
    return FilterSettings(layout=StateLayout(), noise=noise, initial=init, **kw)


@dataclass
class RunResult:
    t: np.ndarray            # node times
    err: np.ndarray          # (m, 15) estimate - truth at nodes
    P: np.ndarray            # (m, 15, 15) posterior covariance at nodes
    solution: object
    truth: object


def perturbed_start(truth_state: NavState, settings: FilterSettings, rng):
    """Initial state drawn from the filter's initial covariance around the truth,
    and the initial sensor-bias estimates (zero: the truth is drawn by the sim)."""
    P0 = settings.initial_covariance()
    lay = settings.layout
    x0 = rng.multivariate_normal(np.zeros(lay.size), P0)
    p, v, a = lay.slice("pos"), lay.slice("vel"), lay.slice("att")
    lla = truth_state.lla.copy()
    rn, re = earth.principal_radii(lla[0], lla[2])
    lla = lla + [x0[p][0] / rn, x0[p][1] / (re * np.cos(lla[0])), -x0[p][2]]
    C = rot.dcm_from_rotvec(-x0[a]) @ truth_state.C_nb  # C_est = (I - [phi x]) C_true
    return NavState(truth_state.time, lla, truth_state.v_n + x0[v], rot.quat_from_dcm(C))


def run_once(trajectory, t, imu_ideal, errors: ImuErrors, gnss_errors: GnssErrors, settings: FilterSettings,
             seed, *, truth=None):
    """One seeded simulation + filter run; errors and covariances at the GNSS
    update epochs."""
    rng = np.random.default_rng(seed)
    imu, draws = apply_imu_errors(imu_ideal, errors, rng)
    gnss, _ = simulate_gnss(trajectory, t[0], t[-1], gnss_errors, rng)
    truth = truth_solution(trajectory, t) if truth is None else truth
    start = perturbed_start(truth.state(0), settings, rng)
    out = run_filter(imu, start, [GnssPosition(gnss)], settings, smoother=True)
    st = out.store
    k = np.asarray(st.k)
    sol = out.solution
    lay = settings.layout
    err = np.zeros((len(k), lay.size))
    err[:, lay.slice("pos")] = earth.lla_to_ned(sol.lla[k], truth.lla[k])  # NED at each true position
    err[:, lay.slice("vel")] = sol.v_n[k] - truth.v_n[k]
    err[:, lay.slice("att")] = rot.attitude_error(sol.C_nb[k], truth.C_nb[k])
    bg = np.column_stack([sol.extra[f"bg_{a}_rad_s"][k] for a in "xyz"])
    ba = np.column_stack([sol.extra[f"ba_{a}_m_s2"][k] for a in "xyz"])
    err[:, lay.slice("bg")] = bg - draws["gyro_bias"][k]
    err[:, lay.slice("ba")] = ba - draws["accel_bias"][k]
    return RunResult(t[k], err, np.asarray(st.P_plus), sol, truth)


def anees_band(runs, dof, probability=0.95):
    lo = stats.chi2.ppf((1 - probability) / 2, runs * dof) / runs
    hi = stats.chi2.ppf(1 - (1 - probability) / 2, runs * dof) / runs
    return float(lo), float(hi)


def monte_carlo(trajectory, rate_hz, errors: ImuErrors, gnss_errors: GnssErrors, initial: InitialUncertainty,
                runs=50, seed=0, duration=None, progress=None, **settings_kw):
    """Monte Carlo consistency of the closed-loop filter on a trajectory.

    Returns
    -------
    dict with ``t`` (m,), ``anees`` {block: (m,)}, ``band`` {block: (lo, hi)},
    ``bias_normalized`` (runs, 6): final bias errors over their sigmas.
    """
    T = trajectory.duration if duration is None else duration
    t = np.arange(0.0, T, 1.0 / rate_hz)
    ideal = ideal_imu(trajectory, t, nodes=3)
    truth = truth_solution(trajectory, t)
    settings_kw.setdefault("smoother_node_s", 0.0)  # nodes = update epochs only
    settings = matched_settings(errors, initial, **settings_kw)
    lay = settings.layout
    blocks = {"pos": lay.slice("pos"), "vel": lay.slice("vel"), "att": lay.slice("att")}
    sums = None
    bias_norm = []
    for r in range(runs):
        res = run_once(trajectory, t, ideal, errors, gnss_errors, settings, seed + r, truth=truth)
        if sums is None:
            sums = {b: np.zeros(len(res.t)) for b in blocks}
            t_nodes = res.t
        for b, s in blocks.items():
            e = res.err[:, s]
            Pb = res.P[:, s, s]
            sums[b] += np.einsum("ni,ni->n", e, np.linalg.solve(Pb, e[..., None])[..., 0])
        sig = np.sqrt(np.concatenate([np.diag(res.P[-1])[lay.slice("bg")], np.diag(res.P[-1])[lay.slice("ba")]]))
        bias_norm.append(np.concatenate([res.err[-1, lay.slice("bg")], res.err[-1, lay.slice("ba")]]) / sig)
        if progress:
            progress(1)
    return {
        "t": t_nodes,
        "anees": {b: v / runs for b, v in sums.items()},
        "band": {b: anees_band(runs, 3) for b in blocks},
        "bias_normalized": np.asarray(bias_norm),
        "runs": runs,
    }


def compare_schemes(scenario, outage, seed=0, schemes=("uncoupled", "open", "closed"), initial=None):
    """Run the integration schemes on one simulated scenario with a GNSS outage.

    The IMU carries the scenario's full error model; the filters get the
    matched noise model (15 states).  Returns one row per scheme with the
    errors at the end of the outage and the RMS horizontal error with GNSS on.
    """
    from ..simulation.scenario import build_trajectory, gnss_errors, imu_errors

    rng = np.random.default_rng(seed)
    tr = build_trajectory(scenario, rng)
    t = np.arange(0.0, tr.duration, 1.0 / scenario.imu.rate_hz)
    ideal = ideal_imu(tr, t, nodes=scenario.imu.quadrature_nodes)
    errs = imu_errors(scenario)
    imu, _ = apply_imu_errors(ideal, errs, rng)
    gnss, _ = simulate_gnss(tr, t[0], t[-1], gnss_errors(scenario), rng)
    use = ~((gnss.time >= outage[0]) & (gnss.time <= outage[1]))
    truth = truth_solution(tr, t)
    init = initial or InitialUncertainty(pos_m=(1.0, 1.0, 2.0), vel_m_s=0.1, roll_pitch_rad=np.radians(0.5),
                                         yaw_rad=np.radians(2.0))
    rows = []
    for scheme in schemes:
        settings = matched_settings(consistency_errors(errs), init, scheme=scheme, gate_probability=None,
                                    lever_arm_b=tuple(scenario.gnss.lever_arm_b_m))
        start = perturbed_start(truth.state(0), settings, np.random.default_rng(seed + 1))
        meas = [GnssPosition(gnss, use)]
        if scheme == "uncoupled" and gnss.has_velocity:  # uncoupled: GNSS resets position and velocity
            meas.append(GnssVelocity(gnss, use))
        out = run_filter(imu, start, meas, settings)
        sol = out.solution
        k_end = int(np.searchsorted(t, outage[1]))
        d = earth.lla_to_ned(sol.lla[k_end], truth.lla[k_end])
        att = rot.attitude_error(sol.C_nb[k_end], truth.C_nb[k_end])
        on = (t < outage[0]) & (t > 60.0)
        don = earth.lla_to_ned(sol.lla[on][::100], truth.lla[on][::100])
        rows.append({
            "scheme": scheme,
            "outage_end_horizontal_m": float(np.hypot(d[0], d[1])),
            "outage_end_vertical_m": float(abs(d[2])),
            "outage_end_velocity_m_s": float(np.linalg.norm(sol.v_n[k_end] - truth.v_n[k_end])),
            "outage_end_attitude_deg": float(np.degrees(np.linalg.norm(att))),
            "gnss_on_horizontal_rms_m": float(np.sqrt(np.mean(don[:, 0] ** 2 + don[:, 1] ** 2))),
        })
    return rows
