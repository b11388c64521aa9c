"""Where the vehicle's axes lie in the IMU's: the check behind the heading from the track.

The start-up of a land vehicle (:mod:`.coarse`, :mod:`.inmotion`) takes two
things for granted: that the IMU's x axis (after ``[imu] mount_rpy_deg``)
points forward, so that its yaw equals the GNSS course (Groves 2013 §6.1.4),
and that its z axis points down.  The non-holonomic constraint and the
odometer assume the same.  An IMU mounted sideways or backwards breaks the
first silently: the heading starts 90 or 180 deg off, the small-angle filter
never recovers and the run ends kilometres off, with nothing in its health
verdict that names the cause.  This module measures both axes from the data,
without either assumption:

* **down**: the levelled roll; beyond 90 deg the IMU's z axis points up.
* **forward**: from the levelled start with an unknown yaw ``psi0``, the
  gyros carry the attitude ``C_Lb`` in a level frame L turned by ``psi0``
  from north (the Earth rate, at most 15 deg/h, and the lever arm's
  rotation terms are left out: degrees over the check's minutes, against
  the tens of degrees it looks for).  The velocity increments rotated into
  L plus gravity are the IMU's velocity change in L (Groves 2013 eq. 5.54,
  Coriolis and transport terms left out); the GNSS velocity differenced
  over the same span is the same change in NED.  Where the acceleration
  stands clear of the noise, the angle from one to the other, averaged on
  the circle with weights ``|a|^2`` (the inverse variance of an angle under
  a fixed acceleration noise), is ``psi0``.  With ``psi0`` the heading of the
  IMU's x axis is known at every fix, and the direction of travel in the
  IMU's axes is the course less that heading, averaged on the circle over
  the moving fixes with weights ``speed^2`` (the inverse course variance).

:func:`vehicle_axes` returns the measurement; :func:`axes_rotation` the
rotation that takes the IMU's axes to the vehicle's, and
:func:`rotate_imu` applies it to the readings.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from .. import earth
from .. import rotations as rot
from ..types import GnssData, ImuData
from ..units import DEG

#: the direction of travel this far off the IMU's x axis [rad] (and beyond OFF_SE standard errors) is a
#: mounting the start-up cannot take for the vehicle's: below it the mounting states and the mounting check
#: (small angles) take over
OFF_AXIS = 20.0 * DEG
OFF_SE = 5.0
#: a direction of travel within this many standard errors of a right angle is taken as that right angle
SNAP_SE = 3.0
#: fewest fixes with the acceleration clear of the noise, and moving fixes, for a verdict
MIN_EPOCHS = 5
#: beyond this pitch [rad] the IMU's x axis points up or down: its heading is undefined
MAX_PITCH = 60.0 * DEG


@njit(cache=True)
def _level_frame_dv(q, dth, dv, dv_l, yaw):
    """Chain the body increments from ``q`` (``C_Lb`` at the first row):
    ``dv_l[k] = C_Lb(k-1/2) dv[k]`` and ``yaw[k]`` the yaw of the body in L
    after row ``k`` (row 0 is the initial epoch: zero)."""
    q0, q1, q2, q3 = q[0], q[1], q[2], q[3]
    dv_l[0, 0] = dv_l[0, 1] = dv_l[0, 2] = 0.0
    yaw[0] = np.arctan2(2.0 * (q0 * q3 + q1 * q2), 1.0 - 2.0 * (q2 * q2 + q3 * q3))
    for k in range(1, dth.shape[0]):
        h0, h1, h2, h3 = rot.rotvec_quat(0.5 * dth[k, 0], 0.5 * dth[k, 1], 0.5 * dth[k, 2])
        m0, m1, m2, m3 = rot.qmul(q0, q1, q2, q3, h0, h1, h2, h3)
        dv_l[k, 0], dv_l[k, 1], dv_l[k, 2] = rot.quat_rot(m0, m1, m2, m3, dv[k, 0], dv[k, 1], dv[k, 2])
        q0, q1, q2, q3 = rot.qmul(m0, m1, m2, m3, h0, h1, h2, h3)
        n = np.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
        q0, q1, q2, q3 = q0 / n, q1 / n, q2 / n, q3 / n
        yaw[k] = np.arctan2(2.0 * (q0 * q3 + q1 * q2), 1.0 - 2.0 * (q2 * q2 + q3 * q3))


def _circ_mean(angle, w):
    """Weighted circular mean [rad] and its standard error [rad] (the
    weighted angular spread over the square root of the effective count)."""
    c, s = np.sum(w * np.cos(angle)), np.sum(w * np.sin(angle))
    mean = float(np.arctan2(s, c))
    r = rot.wrap_angle(angle - mean)
    n_eff = float(np.sum(w) ** 2 / max(np.sum(w * w), 1e-300))
    spread = float(np.sqrt(np.sum(w * r * r) / max(np.sum(w), 1e-300)))
    return mean, spread / np.sqrt(max(n_eff, 1.0))


@dataclass
class AxesCheck:
    """What :func:`vehicle_axes` found.

    Attributes
    ----------
    roll, pitch : float
        The IMU's levelled roll and pitch at the start [rad].
    upside_down : bool
        The IMU's z axis points up (``|roll| > 90 deg``).
    travel_yaw, travel_yaw_se : float or None
        Direction of travel in the IMU's levelled axes, clockwise from its x
        axis seen from above [rad], and its standard error; None when the
        data could not tell (``reason`` says why).
    accel_epochs, moving_epochs : int
        Fixes whose acceleration stood clear of the noise (for ``psi0``), and
        moving fixes (for the travel direction).
    span_s : float
        The span of data looked at [s].
    reason : str
        Empty when measured, else why not.
    """

    roll: float
    pitch: float
    upside_down: bool
    travel_yaw: float | None
    travel_yaw_se: float | None
    accel_epochs: int
    moving_epochs: int
    span_s: float
    reason: str = ""

    @property
    def off_axis(self) -> bool:
        """The direction of travel lies off the IMU's x axis beyond :data:`OFF_AXIS` and :data:`OFF_SE`."""
        return (self.travel_yaw is not None and abs(self.travel_yaw) > OFF_AXIS
                and abs(self.travel_yaw) > OFF_SE * self.travel_yaw_se)

    @property
    def rotation_yaw(self) -> float:
        """The turn about the IMU's z axis [rad] that takes its x axis to the
        direction of travel: 0 unless :attr:`off_axis`; a whole number of
        right angles when the measured direction is within
        :data:`SNAP_SE` standard errors of one (IMUs are mostly mounted
        square to the vehicle: the simpler model the data cannot reject is
        kept, and the mounting states or check see any residual), else the
        measured direction."""
        if not self.off_axis:
            return 0.0
        k = round(self.travel_yaw / (0.5 * np.pi))
        if abs(self.travel_yaw - k * 0.5 * np.pi) <= SNAP_SE * self.travel_yaw_se:
            return float(rot.wrap_angle(k * 0.5 * np.pi))
        return float(self.travel_yaw)

    @property
    def vehicle_axes_differ(self) -> bool:
        """The IMU's axes are not the vehicle's: upside down or off its direction of travel."""
        return self.upside_down or self.off_axis

    def summary(self) -> dict:
        """The JSON form: angles in degrees."""
        deg = (lambda v: None if v is None else float(v / DEG))
        return {"roll_deg": deg(self.roll), "pitch_deg": deg(self.pitch), "upside_down": bool(self.upside_down),
                "travel_yaw_deg": deg(self.travel_yaw), "travel_yaw_se_deg": deg(self.travel_yaw_se),
                "accel_epochs": int(self.accel_epochs), "moving_epochs": int(self.moving_epochs),
                "span_s": float(self.span_s), "off_axis": bool(self.off_axis),
                "rotation_yaw_deg": float(self.rotation_yaw / DEG), "reason": self.reason}


def vehicle_axes(imu: ImuData, gnss: GnssData, roll, pitch, *, gyro_bias=(0.0, 0.0, 0.0), span_s=300.0,
                 heading_speed_m_s=3.0, accel_span_s=1.0, min_accel_m_s2=0.5) -> AxesCheck:
    """Measure where the vehicle's forward and down axes lie in the IMU's.

    Parameters
    ----------
    imu : ImuData
        Increments in the IMU's axes (after any configured mounting); its
        first sample is the epoch ``roll`` and ``pitch`` describe.
    gnss : GnssData
        The fixes the filter uses.
    roll, pitch : float
        Levelled attitude of the IMU at its first sample [rad].
    gyro_bias : (3,) array_like
        Gyro bias to take off the rates [rad/s] (the static start's).
    span_s : float
        Data looked at from the first IMU sample [s]: enough for a few
        accelerations, turns or stops.
    heading_speed_m_s : float
        Slowest fix whose course counts [m/s] (as the start-up's).
    accel_span_s : float
        Differencing span of the velocities [s].
    min_accel_m_s2 : float
        Smallest horizontal acceleration used for ``psi0`` [m/s^2] (raised to
        three times the differenced velocity noise of the fixes).

    Returns
    -------
    AxesCheck
    """
    from .inmotion import gnss_acceleration, gnss_velocity

    roll, pitch = float(roll), float(pitch)
    upside = abs(float(rot.wrap_angle(roll))) > 0.5 * np.pi
    t0 = float(imu.time[0])
    t1 = min(float(imu.time[-1]), t0 + span_s)

    def result(yaw=None, se=None, n_acc=0, n_mov=0, reason=""):
        return AxesCheck(roll, pitch, upside, yaw, se, n_acc, n_mov, t1 - t0, reason)

    if abs(pitch) > MAX_PITCH:
        return result(reason=f"the IMU's x axis points {'up' if pitch > 0 else 'down'} (pitch {pitch / DEG:.0f} "
                      "deg): its heading is undefined")
    sel = (gnss.time >= t0) & (gnss.time <= t1)
    if sel.sum() < 2 * MIN_EPOCHS:
        return result(reason=f"{int(sel.sum())} fixes over the IMU's first {t1 - t0:.0f} s")
    g_fix = gnss.select(sel)
    v_n, sig_vh, _ = gnss_velocity(g_fix, 1.0)
    t = g_fix.time
    h = max(1, int(round(accel_span_s / max(float(np.median(np.diff(t))), 1e-3) / 2)))
    i0 = np.clip(np.arange(len(t)) - h, 0, len(t) - 1)
    i1 = np.clip(np.arange(len(t)) + h, 0, len(t) - 1)
    a_n, _ = gnss_acceleration(t, v_n, accel_span_s)
    # differences across a gap of the fixes (an outage withheld, a dropout) are not the velocity or the
    # acceleration of their epoch: only fixes with regular neighbours over both differencing spans count
    step = np.diff(t)
    gap = np.r_[0, np.cumsum(step > 1.5 * float(np.median(step)))]  # gaps before each fix
    w = 2 * h + 1
    lo, hi = np.clip(np.arange(len(t)) - w, 0, len(t) - 1), np.clip(np.arange(len(t)) + w, 0, len(t) - 1)
    regular = gap[hi] == gap[lo]
    # the IMU's velocity change in L over the same spans
    k1 = int(np.searchsorted(imu.time, t1, side="right"))
    dt = np.empty(k1)
    dt[1:] = np.diff(imu.time[:k1])
    dt[0] = 0.0
    dth = np.ascontiguousarray(imu.dtheta_b[:k1] - np.asarray(gyro_bias, float) * dt[:, None])
    dv = np.ascontiguousarray(imu.dv_b[:k1])
    dv_l, yaw_l = np.empty((k1, 3)), np.empty(k1)
    _level_frame_dv(rot.quat_from_euler([roll, pitch, 0.0]), dth, dv, dv_l, yaw_l)
    cum = np.vstack([np.zeros(3), np.cumsum(dv_l[1:], axis=0)])  # cum[k]: velocity change from row 0 to row k
    ta, tb = t[i0], t[i1]
    span = tb - ta
    ok = regular & (span > 0) & (ta >= imu.time[0]) & (tb <= imu.time[k1 - 1])
    ka = np.clip(np.searchsorted(imu.time[:k1], ta), 0, k1 - 1)
    kb = np.clip(np.searchsorted(imu.time[:k1], tb), 0, k1 - 1)
    g = float(earth.gravity_down(g_fix.lla[0, 0], g_fix.lla[0, 2]))
    a_l = (cum[kb] - cum[ka]) / np.maximum(span, 1e-9)[:, None]
    a_l[:, 2] += g
    an_h, al_h = np.hypot(a_n[:, 0], a_n[:, 1]), np.hypot(a_l[:, 0], a_l[:, 1])
    sig_a = np.sqrt(2.0) * sig_vh / max(float(np.median(span[span > 0])) if np.any(span > 0) else 1.0, 1e-3)
    limit = max(min_accel_m_s2, 3.0 * sig_a)
    acc = ok & (an_h > limit) & (al_h > 0.5 * limit)
    if acc.sum() < MIN_EPOCHS:
        return result(n_acc=int(acc.sum()), reason=f"{int(acc.sum())} fixes with a horizontal acceleration above "
                      f"{limit:.2f} m/s^2 over the first {t1 - t0:.0f} s (at least {MIN_EPOCHS} needed)")
    psi0, se0 = _circ_mean(np.arctan2(a_n[acc, 1], a_n[acc, 0]) - np.arctan2(a_l[acc, 1], a_l[acc, 0]),
                           an_h[acc] ** 2)
    speed = np.hypot(v_n[:, 0], v_n[:, 1])
    mov = regular & (speed > max(heading_speed_m_s, 5.0 * sig_vh)) & (t >= imu.time[0]) & (t <= imu.time[k1 - 1])
    if mov.sum() < MIN_EPOCHS:
        return result(n_acc=int(acc.sum()), n_mov=int(mov.sum()),
                      reason=f"{int(mov.sum())} fixes faster than {heading_speed_m_s:g} m/s")
    k = np.clip(np.searchsorted(imu.time[:k1], t[mov]), 0, k1 - 1)
    course = np.arctan2(v_n[mov, 1], v_n[mov, 0])
    d, se1 = _circ_mean(course - (psi0 + yaw_l[k]), speed[mov] ** 2)
    return result(float(rot.wrap_angle(d)), float(np.hypot(se0, se1)), int(acc.sum()), int(mov.sum()))


def axes_rotation(check: AxesCheck) -> np.ndarray:
    """ZYX Euler angles [rad] of the rotation ``D`` from the IMU's axes b to
    the vehicle's v, ``C_bv = dcm_from_euler(D)``, in the convention of
    ``[imu] mount_rpy_deg`` (:func:`inskit.integration.mounting.corrected_mount_rpy_deg`
    composes it: ``dcm(M1) = dcm(M0) dcm(D)``).  The vehicle's z axis is the
    IMU's (its opposite when the IMU is upside down), its x axis the
    direction of travel (:attr:`AxesCheck.rotation_yaw`) turned into the plane normal to z: the tilt between
    the two stays (a residual is the mounting states' and the mounting
    check's).  Zero when the axes agree."""
    yaw = check.rotation_yaw
    if not check.upside_down and yaw == 0.0:
        return np.zeros(3)
    C_Lb = rot.dcm_from_euler([check.roll, check.pitch, 0.0])
    z_v = C_Lb[:, 2] * (-1.0 if check.upside_down else 1.0)
    u = np.array([np.cos(yaw), np.sin(yaw), 0.0])  # the direction of travel, level, from the IMU's heading
    x_v = u - (u @ z_v) * z_v
    x_v /= np.linalg.norm(x_v)
    C_Lv = np.column_stack([x_v, np.cross(z_v, x_v), z_v])
    return rot.euler_from_dcm(C_Lb.T @ C_Lv)


def rotate_imu(imu: ImuData, D) -> ImuData:
    """The readings in the vehicle's axes: ``x_v = dcm_from_euler(D)^T x_b``
    (:func:`axes_rotation`)."""
    C_vb = rot.dcm_from_euler(np.asarray(D, float)).T
    return ImuData(imu.time, imu.dtheta_b @ C_vb.T, imu.dv_b @ C_vb.T)
