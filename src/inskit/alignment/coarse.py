"""Coarse start-up: levelling on a static start, heading from the GNSS track.

Levelling: at rest ``f_b = -C_bn g_n``, so ``roll = atan2(-f_y, -f_z)`` and
``pitch = atan2(f_x, sqrt(f_y^2 + f_z^2))`` (Groves 2013 eq. 5.101).
Heading: a land vehicle moves along its forward axis, so once it moves its
yaw equals the GNSS course; the gyros carry that yaw back to the start.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from .. import earth
from .. import rotations as rot
from ..errors import InputError
from ..types import GnssData, ImuData, NavState, fix_sigmas
from ..units import DEG


def level(f_b_mean):
    """Roll and pitch [rad] from a mean specific force at rest, ``(3,)``."""
    f = np.asarray(f_b_mean, float)
    return np.arctan2(-f[1], -f[2]), np.arctan2(f[0], np.hypot(f[1], f[2]))


#: span over which the receiver velocities of fixes faster than 1 Hz are averaged by :func:`gnss_speed` [s]
VELOCITY_AVERAGE_S = 1.0


def gnss_speed(gnss: GnssData, span_s=1.0):
    """Horizontal speed [m/s], course [rad] and the speed's noise sigma [m/s].

    Precise fixes (median horizontal sigma below 0.1 m, RTK) use position
    differences over about ``span_s`` (independent of a receiver velocity that
    may lag); coarser fixes use the receiver's velocity when there is one,
    averaged over the fixes within :data:`VELOCITY_AVERAGE_S` of each (one
    fix at 1 Hz, 21 at 20 Hz: a test against a multiple of the returned
    sigma then has the same false-alarm rate per second whatever the fix
    rate; per fix, 20 Hz fixes at rest broke a standstill into pieces twenty
    times as often), else position differences over a span long enough to
    average the noise.
    """
    t = gnss.time
    sig_h = float(np.median(np.hypot(gnss.sigma_ned[:, 0], gnss.sigma_ned[:, 1]) / np.sqrt(2)))
    if sig_h >= 0.1 and gnss.has_velocity:
        v = gnss.v_n[:, :2]
        sig_v = float(np.median(np.hypot(gnss.sigma_v_ned[:, 0], gnss.sigma_v_ned[:, 1]) / np.sqrt(2)))
        i0 = np.searchsorted(t, t - VELOCITY_AVERAGE_S / 2, side="left")
        i1 = np.searchsorted(t, t + VELOCITY_AVERAGE_S / 2, side="right")
        n = i1 - i0
        if n.max() > 1:
            c = np.vstack([np.zeros((1, 2)), np.cumsum(v, axis=0)])
            v = (c[i1] - c[i0]) / n[:, None]
            sig_v /= float(np.sqrt(np.median(n)))
        return np.hypot(v[:, 0], v[:, 1]), np.arctan2(v[:, 1], v[:, 0]), sig_v
    if sig_h >= 0.1:
        span_s = max(span_s, 10.0 * sig_h)  # noise of the difference ~ sqrt(2) sigma / span
    p = earth.lla_to_ned(gnss.lla, gnss.lla[0])
    h = max(1, int(round(span_s / max(np.median(np.diff(t)), 1e-3) / 2)))
    i0 = np.clip(np.arange(len(t)) - h, 0, len(t) - 1)
    i1 = np.clip(np.arange(len(t)) + h, 0, len(t) - 1)
    dt = np.maximum(t[i1] - t[i0], 1e-9)
    v = (p[i1] - p[i0]) / dt[:, None]
    sig_v = float(np.sqrt(2.0) * sig_h / np.median(dt))
    return np.hypot(v[:, 0], v[:, 1]), np.arctan2(v[:, 1], v[:, 0]), sig_v


def detect_motion_start(gnss: GnssData, threshold_m_s=0.3):
    """Time of the first GNSS epoch whose speed exceeds ``threshold_m_s`` (or
    four times the speed noise, if larger)."""
    speed, _, sig = gnss_speed(gnss)
    limit = max(threshold_m_s, 4.0 * sig)
    moving = speed > limit
    if not moving.any():
        raise InputError(
            f"the GNSS track never moves ({len(speed)} fixes over {float(gnss.time[-1] - gnss.time[0]):.1f} s, the "
            f"fastest {float(np.max(speed)) if len(speed) else 0.0:.2f} m/s, motion above {limit:.2f} m/s): no "
            "heading can be found from it; a log at rest needs its initial state: init.mode = \"given\" with "
            "lat_deg, lon_deg, height_m and rpy_deg")
    return float(gnss.time[int(np.argmax(moving))])


def static_intervals(gnss: GnssData, threshold_m_s=0.05, min_length_s=2.0, margin_s=0.5):
    """Intervals where the GNSS speed stays below ``threshold_m_s`` (or three
    times the speed noise, if larger)."""
    speed, _, sig = gnss_speed(gnss, span_s=2.0)
    still = speed < max(threshold_m_s, 3.0 * sig)
    out = []
    i = 0
    n = len(still)
    while i < n:
        if still[i]:
            j = i
            while j + 1 < n and still[j + 1]:
                j += 1
            a, b = gnss.time[i] + margin_s, gnss.time[j] - margin_s
            if b - a >= min_length_s:
                out.append((a, b))
            i = j + 1
        else:
            i += 1
    return out


def heading_from_track(gnss: GnssData, t_from, min_speed_m_s=3.0):
    """First epoch after ``t_from`` with speed above ``min_speed_m_s`` (and ten
    times the speed noise, so the course is good to ~6 deg), and its course [rad]."""
    speed, course, sig = gnss_speed(gnss)
    ok = (gnss.time >= t_from) & (speed > max(min_speed_m_s, 10.0 * sig))
    if not ok.any():
        raise InputError(f"the GNSS track never exceeds {max(min_speed_m_s, 10.0 * sig):.1f} m/s: no heading from "
                         "the track")
    i = int(np.argmax(ok))
    return float(gnss.time[i]), float(course[i])


@dataclass(frozen=True)
class Startup:
    """Result of the start-up.

    Attributes
    ----------
    state : NavState
        At the first IMU sample.
    gyro_bias, accel_bias : (3,) ndarray
        Initial sensor bias estimates [rad/s], [m/s^2].
    static_end : float
        End of the static interval used for levelling [s].
    heading_time : float
        When the heading was taken from the track [s].
    mode : str
        The start-up used: ``"static-then-track"`` or ``"in-motion"``.
    reason : str
        Why that start-up (the automatic choice of :func:`inskit.alignment.inmotion.auto_startup`).
    sigma : dict or None
        Initial sigmas the start-up found from the data, in config units
        (``sigma_pos_m``, ``sigma_vel_m_s``, ``sigma_roll_pitch_deg``,
        ``sigma_yaw_deg``); None: the configured ones stand.
    bank : dict or None
        The yaw-hypothesis bank's result (:func:`inskit.alignment.inmotion.yaw_bank`), if it ran.
    at_yaw : callable or None
        ``at_yaw(yaw) -> NavState``: the same start-up with another initial
        yaw [rad] (what the bank tries).
    axes : dict or None
        Where the vehicle's axes were found in the IMU's
        (:func:`inskit.alignment.vehicle_axes.vehicle_axes`, its summary and
        what was done), when the check ran.
    """

    state: NavState
    gyro_bias: np.ndarray
    accel_bias: np.ndarray
    static_end: float
    heading_time: float
    mode: str = "static-then-track"
    reason: str = ""
    sigma: dict | None = None
    bank: dict | None = None
    at_yaw: object = field(default=None, repr=False, compare=False)
    axes: dict | None = None

    def summary(self, t0) -> dict:
        """The ``startup`` entry of the job summary (times relative to ``t0`` [s])."""
        e = self.state.euler / DEG
        out = {"mode": self.mode, "reason": self.reason, "roll_deg": float(e[0]), "pitch_deg": float(e[1]),
               "yaw_deg": float(e[2]), "static_s": float(self.static_end - t0),
               "heading_from_track_at_s": float(self.heading_time - t0)}
        if self.sigma:
            out["sigma"] = {k: float(v) for k, v in self.sigma.items()}
        if self.bank:
            out["yaw_bank"] = self.bank
        if self.axes:
            out["vehicle_axes"] = self.axes
        return out


@njit(cache=True)
def _chain_rotations(q, dth):
    """``q * q(dth_1) * q(dth_2) * ...`` (body-frame increments), compiled."""
    q0, q1, q2, q3 = q[0], q[1], q[2], q[3]
    for k in range(dth.shape[0]):
        a0, a1, a2, a3 = rot.rotvec_quat(dth[k, 0], dth[k, 1], dth[k, 2])
        q0, q1, q2, q3 = rot.qmul(q0, q1, q2, q3, a0, a1, a2, a3)
    n = np.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    return np.array([q0 / n, q1 / n, q2 / n, q3 / n])


def fix_sigma_m(gnss: GnssData, k, sigma_floor_m=0.0, sigma_scale_ned=(1.0, 1.0, 1.0)) -> float:
    """The largest axis sigma [m] of fix ``k`` as the filter takes it
    (:class:`~inskit.integration.GnssPosition`: the file's, no smaller than
    ``sigma_floor_m``, times ``sigma_scale_ned``): a start-up's position
    taken from that fix is as uncertain."""
    return float(np.max(fix_sigmas(gnss.sigma_ned[k], sigma_floor_m, sigma_scale_ned)))


def startup_state(imu: ImuData, gnss: GnssData, lever_arm_b=(0.0, 0.0, 0.0), *, min_static_s=5.0,
                  motion_threshold_m_s=0.3, heading_speed_m_s=3.0, sigma_floor_m=0.0,
                  sigma_scale_ned=(1.0, 1.0, 1.0)) -> Startup:
    """Initial state from data: level on the static start, heading from the track.

    The IMU must start at rest (at least ``min_static_s``).  The gyro bias is
    the static mean less the Earth rate; the accelerometer bias along the
    vertical is the static norm less normal gravity (the horizontal part cannot
    be told from tilt and is left to the filter).  The position is the first
    fix's, its sigma (``sigma["sigma_pos_m"]``) that fix's as the filter
    takes it (:func:`fix_sigma_m` with ``sigma_floor_m``,
    ``sigma_scale_ned``).
    """
    t_move = detect_motion_start(gnss, motion_threshold_m_s)
    static_end = t_move - 1.0
    k_static = int(np.searchsorted(imu.time, static_end, side="right"))
    head = imu.slice(0, max(k_static, 2))  # the rates of the static start only, not of the whole log
    w, f = head.rates()
    static = (head.time > head.time[0]) & (head.time <= static_end)
    if imu.time[0] < gnss.time[0] - 1.0 or static_end - imu.time[0] < min_static_s:
        raise InputError(
            f"start-up needs the IMU at rest for {min_static_s:.0f} s at its start with GNSS from the start; "
            f"found {max(0.0, static_end - imu.time[0]):.1f} s: give the initial state instead"
        )
    f_mean = f[static].mean(axis=0)
    roll, pitch = level(f_mean)
    lla0 = gnss.lla[0]
    g = earth.gravity_down(lla0[0], lla0[2])
    accel_bias = (np.linalg.norm(f_mean) - g) * f_mean / np.linalg.norm(f_mean)
    w_mean = w[static].mean(axis=0)
    # yaw: integrate the bias-corrected gyros from the start with yaw 0 up to
    # the moment the course is known, then rotate about down to match it
    t_head, course = heading_from_track(gnss, t_move, heading_speed_m_s)
    k_head = int(np.searchsorted(imu.time, t_head))
    q = rot.quat_from_euler([roll, pitch, 0.0])
    dth = imu.dtheta_b[1:k_head + 1] - w_mean * np.diff(imu.time[:k_head + 1])[:, None]
    q = _chain_rotations(q, np.ascontiguousarray(dth))
    yaw_at_head = rot.euler_from_quat(q)[2]
    yaw0 = rot.wrap_angle(course - yaw_at_head)
    rpy0 = np.array([roll, pitch, yaw0])
    C_nb = rot.dcm_from_euler(rpy0)
    gyro_bias = w_mean - C_nb.T @ earth.rate_ie_n(lla0[0])
    # IMU position = antenna fix minus the lever arm
    p_imu = earth.ned_to_lla(-(C_nb @ np.asarray(lever_arm_b, float)), lla0)
    state = NavState.from_euler(imu.time[0], p_imu, np.zeros(3), rpy0)

    def at_yaw(yaw):
        rpy = np.array([roll, pitch, float(yaw)])
        p = earth.ned_to_lla(-(rot.dcm_from_euler(rpy) @ np.asarray(lever_arm_b, float)), lla0)
        return NavState.from_euler(imu.time[0], p, np.zeros(3), rpy)

    # the position is the first fix's, as uncertain as the filter takes that fix (its largest axis sigma, after
    # [gnss] sigma_floor_m and sigma_scale_ned): taken as 5 cm, a fix of 1 m noise kept its error through the
    # static start, the fixes' updates too weak to move it
    sigma = ({"sigma_pos_m": fix_sigma_m(gnss, 0, sigma_floor_m, sigma_scale_ned)}
             if np.isfinite(gnss.sigma_ned[0]).all() else None)
    return Startup(state, gyro_bias, accel_bias, static_end, t_head, reason=f"static for "
                   f"{static_end - imu.time[0]:.1f} s at the start (at least {min_static_s:g} s needed)",
                   sigma=sigma, at_yaw=at_yaw)


#: absolute per-window limits of "at rest" (1 s windows, RMS over the axes of the standard deviation):
#: engine vibration of a car standing still stays below (the bundled drive_0708, consumer MEMS: 1.6 deg/s,
#: 0.09 m/s^2); walking (10-20 deg/s) and handling exceed them
STATIC_GYRO_STD_MAX = 5.0 * DEG
STATIC_ACCEL_STD_MAX = 1.0


@dataclass(frozen=True)
class MotionTest:
    """Per-window result of the static test (:func:`motion_test`).

    Attributes
    ----------
    t0, t1 : (n,) ndarray
        Start and end time of each window [s].
    moving : (n,) ndarray of bool
        The window fails one of the tests.
    reasons : list of str
        For each moving window, what moved (empty for a quiet one).
    """

    t0: np.ndarray
    t1: np.ndarray
    moving: np.ndarray
    reasons: list


def _deg_s(x):
    return f"{float(x) / DEG:.3g} deg/s"


def motion_test(imu: ImuData, window_s=1.0, factor=3.0) -> MotionTest:
    """The static test of :func:`detect_static_start`, window by window.

    Per window of ``window_s``, against the first window (relative tests:
    the start of motion) and against absolute limits (an interval that moves
    from its first window on):

    * the standard deviation of the specific-force magnitude, or of the rate
      magnitude, exceeds ``factor`` times that of the first window (floors of
      0.02 m/s^2 and 0.002 rad/s keep an ideal log from tripping on rounding);
    * the mean specific-force vector has moved from that of the first few
      windows by more than ``factor`` standard errors (0.02 m/s^2 at least: a
      gentle start of motion tilts the mean before it adds vibration);
    * the mean rate vector has moved by more than 6 standard errors of the
      difference (0.002 rad/s at least: a turn that does not tilt);
    * the per-axis standard deviations (RMS over the axes) exceed
      :data:`STATIC_GYRO_STD_MAX` or :data:`STATIC_ACCEL_STD_MAX`.
    """
    w, f = imu.rates()
    dt = float(np.median(np.diff(imu.time)))
    k = max(3, int(round(window_s / dt)))
    n = (len(imu) - 1) // k
    if n < 2:
        raise InputError(f"the IMU log [{float(imu.time[0]):.3f}, {float(imu.time[-1]):.3f}] s is shorter than two "
                         f"{window_s:g} s windows: too short to tell whether it is static")
    fw = f[1:n * k + 1].reshape(n, k, 3)
    ww = w[1:n * k + 1].reshape(n, k, 3)
    fn, wn = np.linalg.norm(fw, axis=2), np.linalg.norm(ww, axis=2)
    sf, sw = fn.std(axis=1), wn.std(axis=1)
    sf_axis = np.sqrt((fw.std(axis=1) ** 2).mean(axis=1))
    sw_axis = np.sqrt((ww.std(axis=1) ** 2).mean(axis=1))
    ref_f, ref_w = max(sf[0], 0.02), max(sw[0], 0.002)
    nref = max(1, min(3, n // 4))
    mean_f, mean_w = fw.mean(axis=1), ww.mean(axis=1)
    # the reference means from the first few windows (less noisy than one)
    drift_f = np.linalg.norm(mean_f - mean_f[:nref].mean(axis=0), axis=1)
    drift_w = np.linalg.norm(mean_w - mean_w[:nref].mean(axis=0), axis=1)
    tol_f = max(factor * ref_f / np.sqrt(k), 0.02)
    # the scatter of a window's mean rate from that of sub-blocks of the reference windows (not std / sqrt(k):
    # rates interpolated from increments, or filtered, are correlated from sample to sample); a turn is a drift
    # beyond 6 sigma of the 3-vector difference, so that an hour of 1 s windows rarely trips on noise
    sub = max(1, k // 10)
    nsub = k // sub
    blocks = ww[:nref, : nsub * sub].reshape(nref, nsub, sub, 3).mean(axis=2)
    var_mean = float(np.mean(blocks.var(axis=1, ddof=1))) / nsub if nsub > 1 else float(np.mean(sw_axis[0] ** 2)) / k
    tol_w = max(6.0 * np.sqrt(var_mean * (1.0 + 1.0 / nref)), 0.002)
    tests = [
        (sf > factor * ref_f, lambda i: f"the specific-force magnitude's std {sf[i]:.3g} m/s^2 is "
                                        f"{sf[i] / ref_f:.1f} times that of the first window (limit {factor:g})"),
        (sw > factor * ref_w, lambda i: f"the rate magnitude's std {_deg_s(sw[i])} is {sw[i] / ref_w:.1f} times "
                                        f"that of the first window (limit {factor:g})"),
        (drift_f > tol_f, lambda i: f"the mean specific force moved by {drift_f[i]:.3g} m/s^2 (limit "
                                    f"{tol_f:.3g} m/s^2: the IMU tilted or accelerated)"),
        (drift_w > tol_w, lambda i: f"the mean rate moved by {_deg_s(drift_w[i])} (limit {_deg_s(tol_w)}: the "
                                    "IMU turned)"),
        (sw_axis > STATIC_GYRO_STD_MAX, lambda i: f"gyro std {_deg_s(sw_axis[i])}, static limit "
                                                  f"{_deg_s(STATIC_GYRO_STD_MAX)}"),
        (sf_axis > STATIC_ACCEL_STD_MAX, lambda i: f"accelerometer std {sf_axis[i]:.3g} m/s^2, static limit "
                                                   f"{STATIC_ACCEL_STD_MAX:g} m/s^2"),
    ]
    moving = np.zeros(n, bool)
    for flag, _ in tests:
        moving |= flag
    reasons = ["; ".join(say(i) for flag, say in tests if flag[i]) if moving[i] else "" for i in range(n)]
    t = imu.time
    return MotionTest(t[np.arange(n) * k], t[np.arange(1, n + 1) * k], moving, reasons)


def detect_static_start(imu: ImuData, window_s=1.0, factor=3.0, min_static_s=5.0):
    """End time of the static interval at the start of an IMU log.

    The log must start at rest; the interval ends one window before the
    first window that fails :func:`motion_test`.
    """
    mt = motion_test(imu, window_s, factor)
    n = len(mt.moving)
    i = int(np.argmax(mt.moving)) if mt.moving.any() else n + 1
    t_end = mt.t0[max(i - 1, 0)] if i <= n else imu.time[-1]
    if t_end - imu.time[0] < min_static_s:
        why = f" (from {float(mt.t0[i]):.1f} s: {mt.reasons[i]})" if i < n else ""
        raise InputError(f"the log is static for only {t_end - imu.time[0]:.1f} s at its start (at least "
                         f"{min_static_s:.0f} s needed){why}; give the interval with --start/--end")
    return float(t_end)


def check_static(imu: ImuData, window_s=1.0, factor=3.0):
    """Refuse an interval in which the IMU moves (:func:`motion_test`).

    Raises
    ------
    InputError
        Naming the interval, the first window that moved and what moved.
    """
    mt = motion_test(imu, window_s, factor)
    if mt.moving.any():
        i = int(np.argmax(mt.moving))
        a, b = float(imu.time[0]), float(imu.time[-1])
        raise InputError(
            f"the interval [{a:.1f}, {b:.1f}] s is not static: in the window [{float(mt.t0[i]):.1f}, "
            f"{float(mt.t1[i]):.1f}] s {mt.reasons[i]}; give --start/--end of an interval where the IMU is at "
            "rest (or leave --end out to detect the static start of the log)"
        )
