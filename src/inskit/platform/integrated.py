"""Integrated platform INS / satellite navigation: open and closed loop, three estimators.

Source 004 (SOURCES-NOTES §2.3) forms differences INS minus satellite (SNS) of
latitude, longitude and the horizontal velocities and filters them to
estimate the INS errors:

* **open loop** (fig. 1): the estimates are subtracted from the INS output;
  the INS itself runs free;
* **closed loop** (fig. 2): the estimates drive corrections into the INS, so
  the corrected INS keeps its accuracy (its "memory") when the satellites
  are lost.

Estimators:

* ``"kalman"``: a 12-state Kalman filter on the completed source-004 error
  model (:mod:`.error_model`) with the five instrument errors as random
  constants, transition ``Phi = exp(A dt)`` (4th-order Taylor, ``A`` from the
  indicated state and the accelerometer output every step) and the
  measurement ``z = [d_phi, d_lambda, dV_xi, dV_eta]``, ``H = [0 | I4 | 0]``.
  Closed loop: at every fix the estimated navigation errors are removed from
  the INS (platform torqued back by ``-alpha_hat``, latitude, longitude and
  velocity reset), which is the limit of the source's continuous
  corrections ``k alpha_hat`` with ``k = -1/dt``; with
  ``compensate_instruments`` the estimated drifts and accelerometer errors are
  also fed back (torquer and accelerometer compensation), the source's
  suggested next step.
* ``"first-order"``, ``"second-order"``: the filters of
  :mod:`inskit.filters.simple` on ``[d_phi, d_lambda, dv_N, dv_E]``
  (relative velocity, as the source says); only these four are estimated.
  Closed loop: continuous corrections held between fixes,
  ``d_phi' += k3 d_phi_hat``, ``d_lambda' += k3 d_lambda_hat``,
  ``dV' += k2 dV_hat`` and the tilt corrected from the velocity estimates
  (source 004's alternative correction):
  ``alpha_y' += ks dV_xi_hat``, ``alpha_x' -= ks dV_eta_hat``.  Without a
  fix the running mean of the corrective actions (time constant
  ``memory_s``) is held: in steady state the tilt correction balances the
  gyro drift, and holding it is the "memory" of the closed loop.  With
  ``ks = w_c^2/g - 1/R``, ``k2 = -2 zeta_c w_c``, ``k3 = -w_c`` the corrected
  Schuler loop has natural frequency ``w_c`` and damping ``zeta_c``
  (SOURCES-NOTES §2.5 flag 3: velocity feedback into the tilt changes the
  Schuler frequency, the velocity gain damps).

The whole loop (RK4 mechanization of the semi-analytical platform, estimator,
corrections) is one compiled kernel.

References
----------
SYSTEM.md §3; SOURCES-NOTES §2.2-2.5 (source 004 fig. 1-2, eq. 1-3, table 1).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from .. import earth
from .. import rotations as rot
from ..errors import ConfigError
from ..filters.linear import expm_taylor, kf_predict, kf_update
from ..filters.simple import lti_step
from ..types import NavSolution
from ..units import ARCMIN, DEG_PER_HOUR
from . import _kernels as K
from .error_model import _re_prime, f_source
from .mechanization import (
    KINDS,
    _noise,
    initial_state,
    solution_from_state,
    vertical_reference,
)
from .corrections import SimpleFilterDesign, v_west_slope  # noqa: F401 (re-exported)
from .sensors import InitialErrors, PlatformErrors
from .world import PlatformTruth, SnsFixes, model_code

ESTIMATORS = {"kalman": 0, "first-order": 1, "second-order": 2}
SCHEMES = {"open": 0, "closed": 1}
W = earth.OMEGA_IE

__all__ = [
    "ESTIMATORS",
    "SCHEMES",
    "IntegratedRun",
    "KalmanTuning",
    "SimpleFilterDesign",
    "estimator_cost",
    "integrate_platform",
]


@dataclass(frozen=True)
class KalmanTuning:
    """Initial sigmas and process noise of the 12-state filter (SI units).

    The source gives none (SOURCES-NOTES §2.3 [unstated]); the defaults take
    the initial sigmas from the experiment's own magnitudes (satellite-level
    position and velocity errors, the drift and accelerometer error as
    1-sigma values) and a small process noise that keeps the filter from
    locking onto its constants.

    Attributes
    ----------
    sigma_tilt, sigma_azimuth : float
        [rad] (1 arcmin, 10 arcmin).
    sigma_position : float
        [rad] (1e-5).
    sigma_velocity : float
        [m/s] (0.1).
    sigma_drift : float
        [rad/s] (0.01 deg/h).
    sigma_accel : float
        [m/s^2] (1e-4).
    q_tilt : float
        Angle random walk density [rad/sqrt(s)] added to the gyro noise
        (1e-4 deg/sqrt(h)).
    q_velocity : float
        Velocity random walk density [m/s/sqrt(s)] added to the accelerometer
        noise (1e-6).
    q_drift, q_accel : float
        Random-walk densities of the instrument states (1e-4 deg/h per
        sqrt(h); 1e-7 m/s^2 per sqrt(s)).
    compensate_instruments : bool
        Closed loop: feed the drift and accelerometer estimates back.
    """

    sigma_tilt: float = ARCMIN
    sigma_azimuth: float = 10 * ARCMIN
    sigma_position: float = 1e-5
    sigma_velocity: float = 0.1
    sigma_drift: float = 0.01 * DEG_PER_HOUR
    sigma_accel: float = 1e-4
    q_tilt: float = 1e-4 * np.pi / 180 / 60.0
    q_velocity: float = 1e-6
    q_drift: float = 1e-4 * DEG_PER_HOUR / 60.0
    q_accel: float = 1e-7
    compensate_instruments: bool = True

    def P0(self):
        s = [self.sigma_tilt, self.sigma_tilt, self.sigma_azimuth, self.sigma_position, self.sigma_position,
             self.sigma_velocity, self.sigma_velocity] + [self.sigma_drift] * 3 + [self.sigma_accel] * 2
        return np.diag(np.square(s))

    def qc(self, errors: PlatformErrors):
        qa = self.q_tilt**2 + errors.gyro_noise**2
        qv = self.q_velocity**2 + errors.accel_noise**2
        return np.array([qa, qa, qa, 0.0, 0.0, qv, qv] + [self.q_drift**2] * 3 + [self.q_accel**2] * 2)


@dataclass
class IntegratedRun:
    """Result of an integrated run.

    Attributes
    ----------
    scheme, estimator : str
    solution : NavSolution
        The system's output: the corrected INS (closed loop) or INS minus
        estimates (open loop); ``tilt_*`` columns are its attitude error
        against the truth (a diagnostic).
    ins : NavSolution
        The INS itself (free in open loop).
    truth : PlatformTruth
    estimates : (n, 12) or (n, 4) ndarray
        Kalman posterior (before the closed-loop reset) in source variables,
        or the simple filters' ``[d_phi, d_lambda, dv_N, dv_E]``.
    sigma : (n, 12) ndarray or None
        Kalman posterior sigmas.
    compensation : (n, 5) ndarray
        Accumulated instrument compensation (source variables).
    elapsed_s : float
        Wall time of the compiled run.
    settings : dict
    state : (n, 10) ndarray
        Raw INS state at each epoch (after the closed-loop reset).
    """

    scheme: str
    estimator: str
    solution: NavSolution
    ins: NavSolution
    truth: PlatformTruth
    estimates: np.ndarray
    sigma: np.ndarray | None
    compensation: np.ndarray
    elapsed_s: float
    settings: dict = field(default_factory=dict)
    state: np.ndarray | None = None


@njit(cache=True)

def _v_west(lat, h, vE, model):
    _, RE = K.radii(lat, h, model)
    return -(vE + W * RE * math.cos(lat))


@njit(cache=True)
def _wrap(a):
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@njit(cache=True)
def _kalman_transition(lat, h, vE, vN, vU, fm, model, dt):
    F = f_source(lat, h, vE, vN, vU, fm[0], fm[1], fm[2], model)
    A = np.zeros((12, 12))
    A[:7, :7] = F
    A[0, 7] = A[1, 8] = A[2, 9] = 1.0
    A[5, 10] = A[6, 11] = 1.0
    return expm_taylor(A, dt, 4)


@njit(cache=True)
def _integrated(model, hold, t, lat_t, lon_t, f_t, href, vuref, y0, eps, ba, sa, st, ng, na,
                sns_lat, sns_lon, sns_v, every, est, closed, P0, qc, compensate, R4, Af, Bf, Cf, ss, gains,
                out_y, out_x, out_sig, out_comp):
    n = t.shape[0]
    y = y0.copy()
    corr = np.zeros(K.NCORR)
    x = np.zeros(12)
    P = P0.copy()
    H = np.zeros((4, 12))
    for i in range(4):
        H[i, 3 + i] = 1.0
    kf = Af.shape[0]
    s = np.zeros((4, kf))
    e_hat = np.zeros(4)
    started = False
    last_fix = -10**9
    comp = np.zeros(5)  # eps_xi, eps_eta, eps_zeta, da_xi, da_eta
    k2, k3, ks, tau_mem = gains[0], gains[1], gains[2], gains[3]
    mem = np.zeros(7)
    for k in range(n):
        j = 2 * k
        lat, lon = y[4], y[5]
        h = href[j] if hold else y[6]
        vE, vN = y[7], y[8]
        _, RE = K.radii(lat, h, model)
        c = W * (RE * math.sin(lat) - _re_prime(lat, model) * math.cos(lat))
        avail = np.isfinite(sns_lat[k])
        if avail:
            last_fix = k
        if est == 0:
            if avail:
                z = np.empty(4)
                z[0] = lat - sns_lat[k]
                z[1] = _wrap(lon - sns_lon[k])
                z[2] = vN - sns_v[k, 0]
                z[3] = _v_west(lat, h, vE, model) - _v_west(sns_lat[k], h, sns_v[k, 1], model)
                x, P, _, _, _ = kf_update(x, P, z, H, R4)
            out_x[k] = x
            for i in range(12):
                out_sig[k, i] = math.sqrt(P[i, i])
            if closed and avail:
                dvE = -x[6] + c * x[3]
                y[4] -= x[3]
                y[5] -= x[4]
                y[8] -= x[5]
                y[7] -= dvE
                dq = K.qrotvec(x[1], -x[0], -x[2])  # -alpha in ENU: -(-a_y, a_x, a_z)
                qn = K.qmul(y[0:4], dq)
                for i in range(4):
                    y[i] = qn[i]
                for i in range(7):
                    x[i] = 0.0
                if compensate:
                    for i in range(5):
                        comp[i] += x[7 + i]
                        x[7 + i] = 0.0
        else:
            if avail:
                z = np.empty(4)
                z[0] = lat - sns_lat[k]
                z[1] = _wrap(lon - sns_lon[k])
                z[2] = vN - sns_v[k, 0]
                z[3] = vE - sns_v[k, 1]
                if not started:
                    for ch in range(4):
                        for i in range(kf):
                            s[ch, i] = ss[i] * z[ch]
                        e_hat[ch] = z[ch]
                    started = True
                else:
                    for ch in range(4):
                        e_hat[ch] = lti_step(Af, Bf, Cf, s[ch], z[ch])
            for i in range(4):
                out_x[k, i] = e_hat[i]
        for i in range(10):
            out_y[k, i] = y[i]
        for i in range(5):
            out_comp[k, i] = comp[i]
        if k == n - 1:
            break
        # corrections held over the next step
        for i in range(K.NCORR):
            corr[i] = 0.0
        if est == 0 and closed and compensate:
            corr[0] = comp[1]   # -eps_enu: eps_E = -eps_eta
            corr[1] = -comp[0]
            corr[2] = -comp[2]
            corr[7] = comp[4]   # -da_E = +da_eta
            corr[8] = -comp[3]
        dt = t[k + 1] - t[k]
        if est > 0 and closed and started:
            if k - last_fix < every:
                dveta = -e_hat[3] + c * e_hat[0]
                corr[0] = -ks * e_hat[2]
                corr[1] = -ks * dveta
                corr[3] = k3 * e_hat[0]
                corr[4] = k3 * e_hat[1]
                corr[5] = k2 * e_hat[3]
                corr[6] = k2 * e_hat[2]
                a = min(1.0, dt / tau_mem)
                for i in range(7):
                    mem[i] += a * (corr[i] - mem[i])
            else:
                # no fix: keep the averaged corrective actions (the loop's "memory")
                for i in range(7):
                    corr[i] = mem[i]
        if est == 0:
            fm = K.accel_output(K.SEMI, t[k] - t[0], y, lat_t[j], lon_t[j], f_t[j], ba, sa, na[k], corr)
            vU = vuref[j] if hold else y[9]
            Phi = _kalman_transition(lat, h, vE, vN, vU, fm, model, dt)
            Q = np.zeros((12, 12))
            for i in range(12):
                Q[i, i] = qc[i] * dt
            x, P = kf_predict(x, P, Phi, Q)
        y = K.rk4_step(K.SEMI, model, hold, t[0], t[k], dt, y, j, lat_t, lon_t, f_t, href, vuref,
                       eps, ba, sa, st, ng[k], na[k], corr)


def _filter_arrays(design: SimpleFilterDesign | None, dt):
    if design is None:
        return np.zeros((1, 1)), np.zeros(1), np.zeros(1), np.zeros(1)
    d = design.filter().discretize(dt)
    return d.A, d.B, d.C, d.steady_state(1.0)


def _measurement_R(sns: SnsFixes, lat0, h0, model):
    s = sns.sigma
    _, re = earth.principal_radii(lat0, h0) if model == "wgs84" else (None, earth.R_SPHERE + h0)
    c = W * re * np.sin(lat0)
    return np.diag([s[0] ** 2, s[1] ** 2, s[2] ** 2, s[3] ** 2 + (c * s[0]) ** 2])


def integrate_platform(truth: PlatformTruth, sns: SnsFixes, *, scheme="closed", estimator="kalman",
                       errors: PlatformErrors | None = None, initial: InitialErrors | None = None,
                       kalman: KalmanTuning | None = None, design: SimpleFilterDesign | None = None,
                       vertical="altimeter", every=1, rng=None) -> IntegratedRun:
    """Run the integrated semi-analytical platform INS / SNS system.

    Parameters
    ----------
    truth : PlatformTruth
    sns : SnsFixes
        Satellite fixes on the truth's epochs (:func:`.world.simulate_sns`).
    scheme : {"open", "closed"}
    estimator : {"kalman", "first-order", "second-order"}
    errors : PlatformErrors, optional
    initial : InitialErrors, optional
    kalman : KalmanTuning, optional
    design : SimpleFilterDesign, optional
        Filter constant and loop gains for the simple filters (default:
        :func:`inskit.platform.design.default_design` for the order and
        scheme).
    vertical : {"altimeter", "free"}
    every : int
        Epochs between fixes: the simple filters' fresh corrections are
        applied that long; after that their running mean is held.
    rng : numpy.random.Generator, optional
        For sensor noise.

    Returns
    -------
    IntegratedRun
    """
    if scheme not in SCHEMES:
        raise ConfigError(f"`scheme` must be 'open' or 'closed', got {scheme!r}")
    if estimator not in ESTIMATORS:
        raise ConfigError(f"`estimator` must be one of {', '.join(ESTIMATORS)}, got {estimator!r}")
    if len(sns.lat) != len(truth.time):
        raise ConfigError("the satellite fixes must be given on the truth's epochs")
    errors = errors or PlatformErrors()
    initial = initial or InitialErrors()
    kalman = kalman or KalmanTuning()
    est = ESTIMATORS[estimator]
    if est > 0 and design is None:
        from .design import default_design

        design = default_design(est, scheme)
    if est > 0 and design.order != est:
        raise ConfigError(f"the {estimator} estimator needs a design of order {est}, got {design.order}")
    model = model_code(truth.earth)
    n = len(truth.time)
    y0 = initial_state(KINDS["semi-analytical"], truth, initial)
    href, vuref = vertical_reference(truth, errors)
    ng = _noise(n, errors.gyro_noise, truth.dt, rng)
    na = _noise(n, errors.accel_noise, truth.dt, rng)
    Af, Bf, Cf, ss = _filter_arrays(design if est > 0 else None, truth.dt)
    g0 = float(K.gravity(truth.lla[0, 0], truth.lla[0, 2], model)[1])
    gains = np.array((*design.gains(g0), design.memory_s) if est > 0 else (0.0, 0.0, 0.0, 1.0))
    R4 = _measurement_R(sns, truth.lla[0, 0], truth.lla[0, 2], truth.earth)
    out_y = np.empty((n, 10))
    out_x = np.zeros((n, 12 if est == 0 else 4))
    out_sig = np.zeros((n, 12))
    out_comp = np.zeros((n, 5))
    sv = np.ascontiguousarray(sns.v_ne)
    args = (model, vertical == "altimeter", truth.time, np.ascontiguousarray(truth.lla[:, 0]),
            np.ascontiguousarray(truth.lla[:, 1]), truth.f_enu, href, vuref, y0, np.array(errors.gyro_drift),
            np.array(errors.accel_bias), np.array(errors.accel_scale), np.array(errors.torquer_scale), ng, na,
            np.ascontiguousarray(sns.lat), np.ascontiguousarray(sns.lon), sv, int(every), est,
            scheme == "closed", kalman.P0(), kalman.qc(errors), kalman.compensate_instruments, R4, Af, Bf, Cf, ss,
            gains)
    out_xk = np.zeros((n, 12))
    t0 = time.perf_counter()
    _integrated(*args, out_y, out_xk, out_sig, out_comp)
    elapsed = time.perf_counter() - t0
    out_x = out_xk if est == 0 else out_xk[:, :4].copy()
    ins = solution_from_state("semi-analytical", truth, out_y)
    if scheme == "closed":
        sol = ins
    else:
        sol = _open_loop_output(ins, out_x, est, truth)
    settings = {"scheme": scheme, "estimator": estimator, "every": int(every)}
    if est > 0:
        k2, k3, ks, _ = gains
        settings.update({"order": design.order, "T_s": design.T, "zeta": design.zeta if design.order == 2 else None,
                         "loop_frequency_rad_s": design.loop_frequency, "loop_damping": design.loop_damping,
                         "k2_1_s": k2, "k3_1_s": k3, "ks_1_m": ks, "memory_s": design.memory_s})
    return IntegratedRun(scheme, estimator, sol, ins, truth, out_x, out_sig if est == 0 else None, out_comp,
                         elapsed, settings, out_y)


def _open_loop_output(ins: NavSolution, est_x, est, truth: PlatformTruth):
    lla = ins.lla.copy()
    v = ins.v_n.copy()
    C = ins.C_nb
    if est == 0:
        lat = lla[:, 0]
        c = v_west_slope(lat, lla[:, 2], truth.earth)
        dvE = -est_x[:, 6] + c * est_x[:, 3]
        lla[:, 0] -= est_x[:, 3]
        lla[:, 1] -= est_x[:, 4]
        v[:, 0] -= est_x[:, 5]
        v[:, 1] -= dvE
        a_ned = np.column_stack([est_x[:, 0], -est_x[:, 1], -est_x[:, 2]])
        C = rot.dcm_from_rotvec(a_ned) @ C
    else:
        lla[:, 0] -= est_x[:, 0]
        lla[:, 1] -= est_x[:, 1]
        v[:, 0] -= est_x[:, 2]
        v[:, 1] -= est_x[:, 3]
    extra = dict(ins.extra)
    tilt_ned = rot.attitude_error(C, rot.dcm_from_quat(truth.q_nb[::2]))
    extra["tilt_e_rad"], extra["tilt_n_rad"], extra["tilt_u_rad"] = tilt_ned[:, 1], tilt_ned[:, 0], -tilt_ned[:, 2]
    return NavSolution(ins.time, lla, v, rot.quat_from_dcm(C), extra)


@njit(cache=True)
def _cost_kernel(est, z, lat, h, vE, vN, vU, f, model, dt, P0, qc, R4, Af, Bf, Cf, out):
    n = z.shape[0]
    x = np.zeros(12)
    P = P0.copy()
    H = np.zeros((4, 12))
    for i in range(4):
        H[i, 3 + i] = 1.0
    s = np.zeros((4, Af.shape[0]))
    for k in range(n):
        if est == 0:
            x, P, _, _, _ = kf_update(x, P, z[k], H, R4)
            Phi = _kalman_transition(lat[k], h[k], vE[k], vN[k], vU[k], f[k], model, dt)
            Q = np.zeros((12, 12))
            for i in range(12):
                Q[i, i] = qc[i] * dt
            x, P = kf_predict(x, P, Phi, Q)
            out[k] = x[3]
        else:
            acc = 0.0
            for ch in range(4):
                acc += lti_step(Af, Bf, Cf, s[ch], z[k, ch])
            out[k] = acc


def estimator_cost(run: IntegratedRun, *, repeats=3):
    """Wall time [s] of the estimator alone (no mechanization) on the
    measurements of a finished run, the best of ``repeats`` compiled runs.

    The Kalman filter's cost includes building ``F`` and ``Phi`` each step
    (it must, the model varies along the trajectory)."""
    tr = run.truth
    ins = run.ins
    n = len(ins)
    lla_t = tr.lla[::2]
    z = np.column_stack([ins.lla[:, 0] - lla_t[:, 0], ins.lla[:, 1] - lla_t[:, 1],
                         ins.v_n[:, 0] - tr.v_n[::2, 0], ins.v_n[:, 1] - tr.v_n[::2, 1]])
    z = np.ascontiguousarray(z + 1e-9)
    est = ESTIMATORS[run.estimator]
    model = model_code(tr.earth)
    f = np.ascontiguousarray(tr.f_enu[::2])
    design = None
    if est > 0:
        s = run.settings
        design = SimpleFilterDesign(s["order"], s["T_s"], s["zeta"] or 0.7071067811865476,
                                    s["loop_frequency_rad_s"], s["loop_damping"], s["memory_s"])
    Af, Bf, Cf, _ = _filter_arrays(design, tr.dt)
    kt = KalmanTuning()
    out = np.empty(n)
    R4 = np.diag([1e-10, 1e-10, 1e-2, 1e-2])
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        _cost_kernel(est, z, np.ascontiguousarray(ins.lla[:, 0]), np.ascontiguousarray(ins.lla[:, 2]),
                     np.ascontiguousarray(ins.v_n[:, 1]), np.ascontiguousarray(ins.v_n[:, 0]),
                     np.ascontiguousarray(-ins.v_n[:, 2]), f, model, tr.dt, kt.P0(), kt.qc(PlatformErrors()), R4,
                     Af, Bf, Cf, out)
        best = min(best, time.perf_counter() - t0)
    return best
