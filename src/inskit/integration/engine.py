"""The integration filter loop: compiled propagation, plug-in updates.

Schemes (SYSTEM.md §2 table 2-2 and §3, source 004 figures 1 and 2):

* ``"closed"``: loosely coupled, closed loop.  After every update the error
  estimates are fed back into the mechanization (position, velocity,
  attitude) and into the sensor corrections (biases, scale factors), and the
  error state is reset to zero.  The correction survives an outage.
* ``"open"``: loosely coupled, open loop.  The INS runs free on the raw
  sensors; the filter's error estimate is propagated and subtracted from the
  INS output only; nothing is fed back.
* ``"uncoupled"``: no filter: every GNSS fix resets the INS position (and
  velocity, when the GNSS gives one).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import earth
from .. import rotations as rot
from ..errors import InputError
from ..filters.kalman import FilterDivergence, check_covariance, joseph_update
from ..types import ImuData, NavSolution, NavState
from . import _kernel as K
from .layout import StateLayout
from .measurements import GnssPosition, GnssVelocity, UpdateContext, ned_difference

SCHEMES = ("closed", "open", "uncoupled")


@dataclass(frozen=True)
class SensorNoise:
    """Continuous-time noise of the inertial sensors (SI units).

    Attributes
    ----------
    gyro_arw : float
        Angle random walk [rad/s/sqrt(Hz)] (= rad/sqrt(s)).
    accel_vrw : float
        Velocity random walk [m/s^2/sqrt(Hz)].
    gyro_bias_sigma, accel_bias_sigma : float
        Steady-state sigma of the first-order Gauss-Markov biases [rad/s],
        [m/s^2]; with ``bias_tau_s = inf`` they are the random-walk PSDs
        [rad/s^2/sqrt(Hz)], [m/s^3/sqrt(Hz)] instead.
    bias_tau_s : float
        Correlation time of the biases [s]; ``inf`` for random walk.
    scale_sigma : float
        Random-walk PSD of scale-factor errors [1/sqrt(s)].
    """

    gyro_arw: float
    accel_vrw: float
    gyro_bias_sigma: float
    accel_bias_sigma: float
    bias_tau_s: float = np.inf
    scale_sigma: float = 1e-6
    time_offset_rw: float = 1e-6     # random walk of the IMU-GNSS time offset [s/sqrt(s)]


@dataclass(frozen=True)
class InitialUncertainty:
    """1-sigma initial errors (SI units)."""

    pos_m: tuple = (1.0, 1.0, 1.0)
    vel_m_s: float = 0.1
    roll_pitch_rad: float = np.radians(1.0)
    yaw_rad: float = np.radians(5.0)
    gyro_bias: float = np.radians(0.05)
    accel_bias: float = 0.1
    scale: float = 0.01
    lever_m: float = 0.1
    time_offset_s: float = 0.05


@dataclass(frozen=True)
class FilterSettings:
    """Everything the loop needs besides data and measurements."""

    layout: StateLayout = StateLayout()
    noise: SensorNoise = SensorNoise(1e-3, 1e-2, 1e-5, 1e-4)
    initial: InitialUncertainty = InitialUncertainty()
    scheme: str = "closed"
    gate_probability: float | None = 0.9999
    #: after this many consecutive rejections of one measurement the next is
    #: applied ungated: a run of rejections means the filter is lost (say after
    #: an outage), not that every measurement is an outlier
    gate_max_consecutive: int | None = 3
    lever_arm_b: tuple = (0.0, 0.0, 0.0)
    gyro_bias0: tuple = (0.0, 0.0, 0.0)
    accel_bias0: tuple = (0.0, 0.0, 0.0)
    time_offset0: float = 0.0
    coning: bool = True
    smoother_node_s: float = 0.25
    #: keep the F P F^T dt^2 term of Phi P Phi^T.  Dropping it (Euler steps)
    #: changes a static run's sigmas by ~1e-6 after an hour, but it is not
    #: positive semi-definite when uncertainties are large: a simulated MEMS
    #: car lost positiveness after 177 s without it.  Off only for experiments.
    covariance_second_order: bool = True

    def __post_init__(self):
        if self.scheme not in SCHEMES:
            raise InputError(f"filter scheme must be one of {SCHEMES}, got {self.scheme!r}")
        n = self.noise
        for name in ("gyro_arw", "accel_vrw", "gyro_bias_sigma", "accel_bias_sigma"):
            if not getattr(n, name) > 0:
                raise InputError(f"noise.{name} must be > 0, got {getattr(n, name)}")
        if not n.bias_tau_s > 0:
            raise InputError(f"noise.bias_tau_s must be > 0 (inf for random walk), got {n.bias_tau_s}")
        i = self.initial
        for name in ("vel_m_s", "roll_pitch_rad", "yaw_rad", "gyro_bias", "accel_bias", "scale", "lever_m"):
            if not getattr(i, name) > 0:
                raise InputError(f"initial uncertainty {name} must be > 0, got {getattr(i, name)}")
        if not all(s > 0 for s in i.pos_m):
            raise InputError(f"initial position sigmas must be > 0, got {i.pos_m}")

    def process_noise(self):
        """Diagonal PSDs ``q`` and inverse correlation times of every state."""
        lay, n = self.layout, self.noise
        q = np.zeros(lay.size)
        tau_inv = np.zeros(lay.size)
        q[lay.slice("vel")] = n.accel_vrw**2
        q[lay.slice("att")] = n.gyro_arw**2
        gm = np.isfinite(n.bias_tau_s)
        for b, s in (("bg", n.gyro_bias_sigma), ("ba", n.accel_bias_sigma)):
            if gm:
                q[lay.slice(b)] = 2.0 * s**2 / n.bias_tau_s
                tau_inv[lay.slice(b)] = 1.0 / n.bias_tau_s
            else:
                q[lay.slice(b)] = s**2
        for b in ("sg", "sa"):
            if lay.slice(b) is not None:
                q[lay.slice(b)] = n.scale_sigma**2
        if lay.time_offset:
            q[lay.slice("dt")] = n.time_offset_rw**2
        return q, tau_inv

    def initial_covariance(self):
        lay, i = self.layout, self.initial
        d = np.zeros(lay.size)
        d[lay.slice("pos")] = np.asarray(i.pos_m, float) ** 2
        d[lay.slice("vel")] = i.vel_m_s**2
        a = lay.slice("att")
        d[a] = [i.roll_pitch_rad**2, i.roll_pitch_rad**2, i.yaw_rad**2]
        d[lay.slice("bg")] = i.gyro_bias**2
        d[lay.slice("ba")] = i.accel_bias**2
        for b in ("sg", "sa"):
            if lay.slice(b) is not None:
                d[lay.slice(b)] = i.scale**2
        if lay.lever_arm:
            d[lay.slice("lever")] = i.lever_m**2
        if lay.time_offset:
            d[lay.slice("dt")] = i.time_offset_s**2
        return np.diag(d)


@dataclass
class SmootherStore:
    """What the forward pass keeps for the RTS smoother, per node."""

    k: list = field(default_factory=list)
    P_minus: list = field(default_factory=list)
    P_plus: list = field(default_factory=list)
    Phi: list = field(default_factory=list)
    dx: list = field(default_factory=list)


@dataclass
class FilterOutput:
    """Result of a filter run.

    Attributes
    ----------
    solution : NavSolution
        At every IMU sample; ``extra`` holds ``sigma_*`` columns and the
        sensor-error estimates (``bg_*_rad_s``, ``ba_*_m_s2``, ...).
    counts : dict
        Per measurement name: ``{"used": n, "rejected": n, "skipped": n}``.
    innovations : dict
        Per measurement name: arrays ``t``, ``nu`` (m, k), ``sigma`` (m, k),
        ``nis``, ``accepted``.
    settings : FilterSettings
    store : SmootherStore or None
    """

    solution: NavSolution
    counts: dict
    innovations: dict
    settings: FilterSettings
    store: SmootherStore | None = None


def _nodes(imu, measurements, smoother_node_s, want_store):
    """Update epochs grouped by the IMU row that precedes them."""
    t = imu.time
    items = []
    skipped = {}
    for m in measurements:
        tm = np.asarray(m.times(), float)
        rows = m.rows()
        k = np.searchsorted(t, tm, side="right") - 1
        ok = (k >= 1) & (tm <= t[-1])
        skipped[m.name] = int((~ok).sum())
        for kk, tt, r in zip(k[ok], tm[ok], rows[ok]):
            items.append((int(kk), float(tt), m, int(r)))
    if want_store and smoother_node_s > 0:
        grid = np.arange(t[0] + smoother_node_s, t[-1], smoother_node_s)
        kg = np.searchsorted(t, grid, side="right") - 1
        for kk in np.unique(kg[kg >= 1]):
            items.append((int(kk), float(t[kk]), None, -1))
    items.sort(key=lambda it: (it[0], it[1]))
    return items, skipped


def run_filter(imu: ImuData, initial: NavState, measurements, settings: FilterSettings, *,
               smoother=False, progress=None) -> FilterOutput:
    """Run the integration filter forward over the IMU data.

    Parameters
    ----------
    imu : ImuData
        ``imu.time[0]`` is the initial epoch.
    initial : NavState
        Initial IMU state at ``imu.time[0]``.
    measurements : list of measurement plug-ins
    settings : FilterSettings
    smoother : bool
        Keep what the RTS smoother needs (closed loop only).
    progress : callable, optional
        Called with the number of IMU rows done since the last call.

    Returns
    -------
    FilterOutput
    """
    if abs(initial.time - imu.time[0]) > 1e-6:
        raise InputError(f"the initial state ({initial.time:.3f} s) must be at the first IMU sample "
                         f"({imu.time[0]:.3f} s)")
    if smoother and settings.scheme != "closed":
        raise InputError("the RTS smoother works on the closed-loop filter only")
    lay = settings.layout
    n = lay.size
    idx = lay.kernel_index()
    q_psd, tau_inv = settings.process_noise()
    rows_pat, cols_pat = lay.transition_pattern(gauss_markov_biases=bool(np.any(tau_inv)))
    active = np.unique(rows_pat)
    P = settings.initial_covariance()
    x = np.zeros(n)
    corr = np.zeros(12)
    corr[0:3] = settings.gyro_bias0
    corr[3:6] = settings.accel_bias0
    lever = np.asarray(settings.lever_arm_b, float).copy()
    offset = np.array([float(settings.time_offset0)])  # IMU-GNSS time offset estimate [s]
    lla, v_n, q_nb = initial.lla.copy(), initial.v_n.copy(), initial.q_nb.copy()
    carry = np.zeros(11)
    carry[0] = imu.time[0]
    N = len(imu)
    out_lla = np.empty((N, 3))
    out_v = np.empty((N, 3))
    out_q = np.empty((N, 4))
    out_sig = np.empty((N, 9))
    out_corr = np.empty((N, 12))
    w_last = np.zeros(3)
    open_loop = settings.scheme == "open"
    uncoupled = settings.scheme == "uncoupled"
    want_store = smoother
    store = SmootherStore() if want_store else None
    Phi = np.eye(n)

    def write_row(k):
        if open_loop:
            K.apply_correction(lla, v_n, q_nb, x, idx, 1.0, out_lla[k], out_v[k], out_q[k])
        else:
            out_lla[k], out_v[k], out_q[k] = lla, v_n, q_nb
        out_sig[k] = P.diagonal()[:9]  # variances until the end of the run
        out_corr[k] = corr

    out_offset = np.full(N, np.nan) if lay.time_offset else None
    write_row(0)
    if out_offset is not None:
        out_offset[0] = offset[0]
    items, skipped = _nodes(imu, measurements, settings.smoother_node_s, want_store)
    counts = {m.name: {"used": 0, "rejected": 0, "skipped": skipped[m.name]} for m in measurements}
    innov = {m.name: {"t": [], "nu": [], "sigma": [], "nis": [], "accepted": []} for m in measurements}
    rejected_streak = {}
    k_done = 1
    i = 0
    n_items = len(items)
    while i < n_items:
        k_end = items[i][0]
        j = i
        while j < n_items and items[j][0] == k_end:
            j += 1
        if k_end + 1 > k_done:
            K.propagate(imu.time, imu.dtheta_b, imu.dv_b, k_done, k_end + 1, lla, v_n, q_nb, carry, settings.coning,
                        corr, x, P, q_psd, tau_inv, idx, rows_pat, cols_pat, active, want_store, Phi, open_loop,
                        out_lla, out_v, out_q, out_sig, out_corr, w_last, settings.covariance_second_order)
            if progress is not None:
                progress(k_end + 1 - k_done)
            k_done = k_end + 1
        if want_store:
            store.k.append(k_end)
            store.P_minus.append(P.copy())
            store.Phi.append(Phi.copy())
            Phi[:] = np.eye(n)
        dx_total = np.zeros(n)
        C_nb = np.empty((3, 3))
        K._dcm(q_nb, C_nb)
        for _, tm, meas, row in items[i:j]:
            if meas is None:
                continue
            if uncoupled:
                _reset_uncoupled(meas, row, lla, v_n, C_nb, lever, tm - imu.time[k_end], w_last)
                counts[meas.name]["used"] += 1
                continue
            if lay.lever_arm:
                lev = lever - (x[lay.slice("lever")] if open_loop else 0.0)
            else:
                lev = lever
            if open_loop:
                o_lla, o_v, o_q = np.empty(3), np.empty(3), np.empty(4)
                K.apply_correction(lla, v_n, q_nb, x, idx, 1.0, o_lla, o_v, o_q)
                ctx = UpdateContext(tm, tm - imu.time[k_end], o_lla, o_v, rot.dcm_from_quat(o_q), w_last, lay, lev,
                                    offset[0])
            else:
                ctx = UpdateContext(tm, tm - imu.time[k_end], lla, v_n, C_nb, w_last, lay, lev, offset[0])
            lin = meas.linearize(ctx, row)
            if lin is None:
                counts[meas.name]["skipped"] += 1
                continue
            nu, H, R = lin
            gate = settings.gate_probability
            streak = rejected_streak.get(meas.name, 0)
            if settings.gate_max_consecutive is not None and streak >= settings.gate_max_consecutive:
                gate = None
            res = joseph_update(P, nu, H, R, gate_probability=gate)
            rejected_streak[meas.name] = 0 if res.accepted else streak + 1
            rec = innov[meas.name]
            rec["t"].append(tm)
            rec["nu"].append(res.innovation)
            rec["sigma"].append(np.sqrt(np.diag(res.S)))
            rec["nis"].append(res.nis)
            rec["accepted"].append(res.accepted)
            if not res.accepted:
                counts[meas.name]["rejected"] += 1
                continue
            counts[meas.name]["used"] += 1
            P = res.P
            if open_loop:
                x += res.dx
            else:
                _feedback(res.dx, lay, idx, lla, v_n, q_nb, corr, lever, offset)
                dx_total += res.dx
                K._dcm(q_nb, C_nb)
        check_covariance(P, f"at t = {imu.time[k_end]:.3f} s")
        if want_store:
            store.P_plus.append(P.copy())
            store.dx.append(dx_total)
        write_row(k_end)
        if out_offset is not None:
            out_offset[k_end] = offset[0]
        i = j
    if k_done < N:
        K.propagate(imu.time, imu.dtheta_b, imu.dv_b, k_done, N, lla, v_n, q_nb, carry, settings.coning,
                    corr, x, P, q_psd, tau_inv, idx, rows_pat, cols_pat, active, False, Phi, open_loop,
                    out_lla, out_v, out_q, out_sig, out_corr, w_last, settings.covariance_second_order)
        if progress is not None:
            progress(N - k_done)
    check_covariance(P, "at the end of the run")
    if not (np.isfinite(out_lla).all() and np.isfinite(out_v).all() and np.isfinite(out_q).all()):
        raise FilterDivergence("the navigation solution became NaN: the filter diverged")
    np.sqrt(np.maximum(out_sig, 0.0, out=out_sig), out=out_sig)
    extra = _extra_columns(out_sig, out_corr, lay)
    if out_offset is not None:  # held between updates
        idx_valid = np.maximum.accumulate(np.where(np.isfinite(out_offset), np.arange(N), 0))
        extra["time_offset_s"] = out_offset[idx_valid]
    sol = NavSolution._trusted(imu.time, out_lla, out_v, out_q, extra)
    innovations = {k: {kk: np.asarray(vv) for kk, vv in v.items()} for k, v in innov.items()}
    return FilterOutput(sol, counts, innovations, settings, store)


def _extra_columns(sig, corr, lay):
    names = ["sigma_n_m", "sigma_e_m", "sigma_d_m", "sigma_vn_m_s", "sigma_ve_m_s", "sigma_vd_m_s",
             "sigma_att_n_rad", "sigma_att_e_rad", "sigma_att_d_rad"]
    extra = {nm: sig[:, i] for i, nm in enumerate(names)}
    for i, a in enumerate("xyz"):
        extra[f"bg_{a}_rad_s"] = corr[:, i]
        extra[f"ba_{a}_m_s2"] = corr[:, 3 + i]
        if lay.scale_factors:
            extra[f"sg_{a}"] = corr[:, 6 + i]
            extra[f"sa_{a}"] = corr[:, 9 + i]
    return extra


def _feedback(dx, lay, idx, lla, v_n, q_nb, corr, lever, offset):
    """Closed loop: remove the estimated errors from the navigation state and
    the sensor corrections (in place)."""
    K.apply_correction(lla, v_n, q_nb, dx, idx, 1.0, lla, v_n, q_nb)
    corr[0:3] -= dx[lay.slice("bg")]
    corr[3:6] -= dx[lay.slice("ba")]
    if lay.scale_factors:
        corr[6:9] -= dx[lay.slice("sg")]
        corr[9:12] -= dx[lay.slice("sa")]
    if lay.lever_arm:
        lever -= dx[lay.slice("lever")]
    if lay.time_offset:
        offset -= dx[lay.slice("dt")]


def _reset_uncoupled(meas, row, lla, v_n, C_nb, lever, dt, w_b):
    """Uncoupled scheme: overwrite the INS position or velocity with GNSS."""
    if isinstance(meas, GnssPosition):
        target = meas.gnss.lla[row]
        d = ned_difference(lla, target) + C_nb @ lever + v_n * dt
        rn, re = earth.principal_radii(lla[0], lla[2])
        lla[0] -= d[0] / rn
        lla[1] -= d[1] / (re * np.cos(lla[0]))
        lla[2] += d[2]
    elif isinstance(meas, GnssVelocity):
        v_n[:] = meas.gnss.v_n[row] - C_nb @ np.cross(w_b, lever)
