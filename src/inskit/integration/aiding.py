"""Land-vehicle aiding: odometer (wheel speed), GNSS speed and course, height.

Three plug-ins of the measurement protocol (:mod:`.measurements`) and one state
block (the height sensor's offset, :class:`.blocks.HeightBias`, lives with
the other blocks):

* :class:`OdometerScale` (block ``"odo_scale"``): the wheel-speed
  scale-factor error ``k``, a random walk.
* :class:`Odometer`: the speed of the odometer point along the body forward
  axis, optionally with the two non-holonomic zero rows (full body-velocity
  aiding at the wheel).
* :class:`GnssSpeedCourse`: horizontal GNSS velocity given as speed and
  course over ground (NMEA RMC/VTG, phone logs), fused as north/east
  velocity with the covariance propagated from speed and course.
* :class:`Height`: the height of a sensor point from a barometer or a known
  height profile, with the sensor's offset (block ``"height_bias"``) when
  the layout holds one.

Sign conventions (as everywhere in the filter): error states are
``x = estimate - truth``, innovations ``h(estimate) - measured = H x + noise``.

References: Groves 2013 §6.3 (odometers), §6.2.1 (barometric height), §14.2
and §16.2 (land-vehicle aiding, non-holonomic constraints); Brown & Hwang 2012 §7.1 (propagating a
measurement covariance through a transformation).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..rotations import skew
from ..types import check_time
from .blocks import StateBlock
from . import _updates as U
from .measurements import UpdateContext, _cross, _sensor_rate_columns, compiled_form_applies, vehicle_axes


class OdometerScale(StateBlock):
    """Odometer scale-factor error ``k`` [-]: the odometer reports ``(1 + k)``
    times the true forward speed of its point.  A random walk of PSD
    ``rw**2`` [1/s] (tyre wear, pressure and temperature change it slowly).

    The :class:`Odometer` measurement finds it by its name ``"odo_scale"``;
    its estimate ``s`` is the running estimate of ``k`` (error state
    ``s - k``, fed back closed loop as ``s -= dx``).

    Parameters
    ----------
    sigma0 : float
        Initial 1-sigma of ``k`` [-] (0.01: a tyre's radius known to 1 %).
    rw : float
        Random-walk PSD root [1/sqrt(s)].
    estimate0 : float
        Initial estimate of ``k`` (a calibration from an earlier run).
    """

    def __init__(self, sigma0=0.01, rw=1e-6, estimate0=0.0):
        super().__init__("odo_scale", ("k",), "", sigma0, rw**2, math.inf, estimate0=estimate0,
                         description="odometer scale-factor error")

    def estimate_names(self):
        return ["odo_scale"]

    def sigma_names(self):
        return ["sigma_odo_scale"]


def _check_series(time, values, name):
    t = check_time("time", time)
    v = np.ascontiguousarray(values, dtype=float)
    if v.shape != t.shape:
        raise InputError(f"`{name}` must have shape ({len(t)},) like `time`, got {v.shape}")
    if not np.isfinite(v).all():
        k = int(np.argmax(~np.isfinite(v)))
        raise InputError(f"`{name}` has a NaN or infinite value at row {k} (t = {t[k]:.3f} s)")
    return t, v


def _positive(value, n, name):
    s = np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy() if np.ndim(value) == 0 else \
        np.asarray(value, dtype=float)
    if s.shape != (n,):
        raise InputError(f"`{name}` must be a number or have shape ({n},), got {s.shape}")
    if not (np.isfinite(s).all() and (s > 0).all()):
        raise InputError(f"`{name}` must be finite and > 0, got {s[~(np.isfinite(s) & (s > 0))][0]}")
    return s


def _use_rows(use, n):
    if use is None:
        return np.arange(n)
    u = np.asarray(use, bool)
    if u.shape != (n,):
        raise InputError(f"`use` must have shape ({n},), got {u.shape}")
    return np.nonzero(u)[0]


def _lever(lever_arm_b, name="lever_arm_b"):
    lev = np.asarray(lever_arm_b, dtype=float)
    if lev.shape != (3,) or not np.isfinite(lev).all():
        raise InputError(f"`{name}` must be three finite numbers (body axes, m), got {lever_arm_b!r}")
    return lev


class Odometer:
    """Odometer (wheel-speed) measurement of the forward speed at the wheel.

    The odometer point sits at ``l_b`` from the IMU (body axes); its velocity
    in body axes is ``v_o = C_nb^T v_n + omega_ib_b x l_b``.  The sensor reads
    ``z = (1 + k) x_v^T C_vb v_o + noise`` (``x_v`` the vehicle's forward
    axis, ``C_vb`` the IMU-to-vehicle rotation, ``k`` the scale-factor error;
    signed: negative when reversing).  The prediction

    ``h = (1 + s) x_v^T C_vb (C_nb^T v_n + omega_ib_b x l_b)``

    uses ``s``, the ``odo_scale`` block's estimate when the layout holds one
    (else 0, and the scale is not estimated), and ``C_vb`` of the
    ``mounting`` block's estimate (:class:`.blocks.Mounting`; else ``I``, the
    IMU's forward axis taken for the vehicle's).  With ``C_nb_est = (I -
    [phi x]) C_nb`` (:class:`.blocks.AttitudeError`) and ``C_vn = C_vb C_bn``,

    ``H_vel = (1 + s) x_v^T C_vn``, ``H_att = -(1 + s) x_v^T C_vn [v_n x]``,
    ``H_rate = -(1 + s) x_v^T C_vb [l_b x]`` (through ``d omega`` into the
    gyro bias and scale-factor columns), ``H_odo_scale = x_v^T C_vb v_o``,
    ``H_mounting = (1 + s) x_v^T [dC_vb/dpitch v_o, dC_vb/dyaw v_o]``.

    With ``with_nhc`` the measurement has three rows ``[z, 0, 0]`` against
    ``diag(1 + s, 1, 1) C_vb v_o``: the lateral and vertical velocities of the
    wheel are zero (the non-holonomic constraint at the wheel, where it
    holds, rather than at the IMU), i.e. full body-velocity aiding.

    The state at the IMU sample before the measurement is used without
    extrapolation over ``ctx.dt`` (below one IMU interval: 0.02 m/s at
    2 m/s^2 and 100 Hz, under the usual wheel-speed noise).

    Parameters
    ----------
    time : (m,) array_like
        Measurement times [s], IMU time base, strictly increasing.
    speed_m_s : (m,) array_like
        Measured forward speed [m/s] (signed).
    sigma_m_s : float or (m,) array_like
        1-sigma of the speed noise [m/s], > 0.
    lever_arm_b : (3,) array_like
        IMU-to-odometer-point lever arm, body axes [m] (the rear-axle centre
        for a differential odometer).  Never taken from the GNSS ``lever``
        block.
    use : (m,) bool array, optional
        Which rows to use.
    with_nhc : bool
        Add the lateral and vertical zero-velocity rows.
    nhc_sigma_m_s : float
        1-sigma of those rows [m/s] (side slip, suspension motion).

    References
    ----------
    Groves 2013 §6.3.1 (wheel speed, scale-factor error), §16.2.3
    (non-holonomic constraints).
    """

    gating = "vector"

    def __init__(self, time, speed_m_s, sigma_m_s, *, lever_arm_b=(0.0, 0.0, 0.0), use=None, with_nhc=False,
                 nhc_sigma_m_s=0.1):
        self.time, self.speed = _check_series(time, speed_m_s, "speed_m_s")
        self.sigma = _positive(sigma_m_s, len(self.time), "sigma_m_s")
        self.lever_arm_b = _lever(lever_arm_b)
        self.with_nhc = bool(with_nhc)
        self.nhc_sigma = float(_positive(nhc_sigma_m_s, 1, "nhc_sigma_m_s")[0])
        self.name = "odometer_nhc" if self.with_nhc else "odometer"
        self._rows = _use_rows(use, len(self.time))

    def times(self):
        return self.time[self._rows]

    def rows(self):
        return self._rows

    def linearize(self, ctx: UpdateContext, row):
        lay = ctx.layout
        s_est = ctx.estimate("odo_scale")
        g = 1.0 if s_est is None else 1.0 + float(s_est[0])
        C_bn = ctx.C_nb.T
        lev = self.lever_arm_b
        mount = vehicle_axes(ctx)
        C_vb = np.eye(3) if mount is None else mount[0]
        C_vn = C_bn if mount is None else C_vb @ C_bn
        v_o = C_bn @ ctx.v_n
        k = 3 if self.with_nhc else 1
        gain = np.ones(k)
        gain[0] = g
        H = np.zeros((k, lay.size))
        H[:, lay.slice("vel")] = gain[:, None] * C_vn[:k]
        H[:, lay.slice("att")] = -gain[:, None] * (C_vn @ skew(ctx.v_n))[:k]
        if lev.any():
            v_o = v_o + _cross(ctx.omega_ib_b, lev)
            _sensor_rate_columns(H, ctx, -gain[:, None] * (C_vb @ skew(lev))[:k])
        v_ov = v_o if mount is None else C_vb @ v_o  # the wheel point's velocity in the vehicle's axes
        if s_est is not None:
            H[0, lay.slice("odo_scale")] = v_ov[0]
        if mount is not None:
            m = lay.slice("mounting").start
            H[:, m] = gain * (mount[1] @ v_o)[:k]
            H[:, m + 1] = gain * (mount[2] @ v_o)[:k]
        h = gain * v_ov[:k]
        z = np.zeros(k)
        z[0] = self.speed[row]
        R = np.diag(np.r_[self.sigma[row] ** 2, np.full(k - 1, self.nhc_sigma**2)])
        return h - z, H, R

    def compiled(self, layout):
        """:meth:`linearize` in compiled form (:mod:`._updates`): per row the
        speed and its sigma."""
        if not compiled_form_applies(self, Odometer) or "mounting" in layout:
            return None  # the compiled form works in the IMU's axes; the mounting block's: the Python path
        par = np.r_[self.lever_arm_b, float(self.with_nhc), self.nhc_sigma]
        return U.spec(U.KIND_ODOMETER, 3 if self.with_nhc else 1, np.column_stack([self.speed, self.sigma]), par)


def course_speed_to_ne(speed, course, sigma_speed, sigma_course):
    """North/east velocity and its covariance from speed and course over ground.

    ``v = s [cos c, sin c]``, ``P = J diag(sigma_s^2, sigma_c^2) J^T`` with
    ``J = [[cos c, -s sin c], [sin c, s cos c]]`` (first-order propagation,
    Brown & Hwang 2012 §7.1; its neglected mean offset along track is
    ``-s sigma_c^2 / 2``: 0.5 mm/s at 10 m/s and 0.01 rad).

    Parameters
    ----------
    speed, course, sigma_speed, sigma_course : float or (n,) array_like
        [m/s], [rad] clockwise from north, [m/s], [rad].

    Returns
    -------
    v_ne : (2,) or (n, 2) ndarray
    P : (2, 2) or (n, 2, 2) ndarray
    """
    s, c = np.asarray(speed, float), np.asarray(course, float)
    ss, sc = np.asarray(sigma_speed, float), np.asarray(sigma_course, float)
    cc, sn = np.cos(c), np.sin(c)
    v = np.stack([s * cc, s * sn], axis=-1)
    a, b = ss**2, (s * sc) ** 2
    P = np.empty(np.shape(v)[:-1] + (2, 2))
    P[..., 0, 0] = a * cc * cc + b * sn * sn
    P[..., 1, 1] = a * sn * sn + b * cc * cc
    P[..., 0, 1] = P[..., 1, 0] = (a - b) * cc * sn
    return v, P


class GnssSpeedCourse:
    """GNSS speed and course over ground (horizontal velocity only).

    Fused as north/east antenna velocity: the measured ``(speed, course)``
    become ``v_ne = s [cos c, sin c]`` with the covariance propagated from
    ``sigma_speed`` and ``sigma_course`` (:func:`course_speed_to_ne`), and
    the prediction is the antenna velocity's first two rows

    ``h = (v_n + C_nb (omega_ib_b x l_b))[0:2]``,
    ``H = [0, I, [(C_nb (omega x l)) x], -C_nb [l x] d omega, C_nb [omega x] (lever)]`` rows 0..1.

    Why this form and not speed and course innovations: ``h`` is linear in
    the velocity error (the same H as :class:`.measurements.GnssVelocity`),
    so no course wrapping, no ``1 / speed`` in ``d course / d v`` of the
    *estimate* (which blows up when the estimate is slow though the
    measurement is not), and a chi-square gate that means what it says; the
    only approximation is the first-order noise propagation, whose error is
    ``s sigma_c^2 / 2`` (negligible for any usable course).

    Rows are skipped (``linearize`` returns None) when the measured speed is
    below ``min_speed_m_s``, by default ``max(0.5 m/s, 3 sigma_speed)``:
    below it a receiver's course is noise or held from the last motion.

    Parameters
    ----------
    time : (m,) array_like
        Times [s], IMU time base.
    speed_m_s : (m,) array_like
        Speed over ground [m/s] (>= 0).
    course_rad : (m,) array_like
        Course over ground [rad], clockwise from true north.
    sigma_speed : float or (m,) array_like
        [m/s], > 0.
    sigma_course : float or (m,) array_like
        [rad], > 0.
    lever_arm_b : (3,) array_like
        IMU-to-antenna lever arm, body axes [m]; the ``lever`` block's
        estimate wins when the layout holds one.
    use : (m,) bool array, optional
    min_speed_m_s : float, optional
        See above.

    References
    ----------
    NMEA 0183 RMC/VTG (speed and course over ground); Groves 2013 §14.3.1.
    """

    name = "gnss_speed_course"
    gating = "vector"

    def __init__(self, time, speed_m_s, course_rad, sigma_speed, sigma_course, *, lever_arm_b=(0.0, 0.0, 0.0),
                 use=None, min_speed_m_s=None):
        self.time, self.speed = _check_series(time, speed_m_s, "speed_m_s")
        _, self.course = _check_series(self.time, course_rad, "course_rad")
        if (self.speed < 0).any():
            k = int(np.argmax(self.speed < 0))
            raise InputError(f"`speed_m_s` is a speed over ground (>= 0), got {self.speed[k]} at row {k}")
        n = len(self.time)
        self.sigma_speed = _positive(sigma_speed, n, "sigma_speed")
        self.sigma_course = _positive(sigma_course, n, "sigma_course")
        self.lever_arm_b = _lever(lever_arm_b)
        if min_speed_m_s is None:
            self.min_speed = np.maximum(0.5, 3.0 * self.sigma_speed)
        else:
            if not min_speed_m_s >= 0:
                raise InputError(f"`min_speed_m_s` must be >= 0, got {min_speed_m_s}")
            self.min_speed = np.full(n, float(min_speed_m_s))
        self.v_ne, self.P_ne = course_speed_to_ne(self.speed, self.course, self.sigma_speed, self.sigma_course)
        self._rows = _use_rows(use, n)

    def times(self):
        return self.time[self._rows]

    def rows(self):
        return self._rows

    def linearize(self, ctx: UpdateContext, row):
        if self.speed[row] < self.min_speed[row]:
            return None
        lay = ctx.layout
        lev = ctx.estimate("lever", self.lever_arm_b)
        C = ctx.C_nb
        w = ctx.omega_ib_b
        lever_v = C @ _cross(w, lev)
        H = np.zeros((3, lay.size))
        H[:, lay.slice("vel")] = np.eye(3)
        H[:, lay.slice("att")] = skew(lever_v)
        _sensor_rate_columns(H, ctx, -C @ skew(lev))
        if "lever" in lay:
            H[:, lay.slice("lever")] = C @ skew(w)
        nu = (ctx.v_n + lever_v)[:2] - self.v_ne[row]
        return nu, H[:2].copy(), self.P_ne[row].copy()

    def compiled(self, layout):
        """:meth:`linearize` in compiled form (:mod:`._updates`): per row the
        speed, the speed below which it is skipped, north/east velocity and
        its covariance."""
        if not compiled_form_applies(self, GnssSpeedCourse):
            return None
        n = len(self.time)
        data = np.column_stack([self.speed, self.min_speed, self.v_ne, self.P_ne.reshape(n, 4)])
        return U.spec(U.KIND_SPEED_COURSE, 2, data, self.lever_arm_b)


class Height:
    """Height of a sensor point: a barometer's altitude or a known height
    profile.

    The sensor at ``l_b`` from the IMU (body axes) sits at the height
    ``h_s = h - (C_nb l_b)_d``; it reads ``z = h_s + b + noise`` with the
    offset ``b`` of the ``height_bias`` block (:class:`.blocks.HeightBias`;
    0 and not estimated when the layout has none).  The prediction at the
    measurement time, ``ctx.dt`` after the IMU sample, is

    ``h(est) = h - v_d dt - (C_nb l_b)_d + b_est``,

    and the innovation ``h(est) - z``.  With the error states ``x = estimate
    - truth`` (``x_pos_d = -(h_est - h)``, ``C_nb_est = (I - [phi x]) C_nb``)

    ``H_pos = [0, 0, -1]``, ``H_vel = [0, 0, -dt]``,
    ``H_att = -[(C_nb l_b) x]`` row d, ``H_height_bias = 1``.

    A constant height (a ship at sea level, a level site) is the same
    measurement with a constant profile.

    Parameters
    ----------
    time : (m,) array_like
        Times [s], IMU time base, strictly increasing.
    height_m : (m,) array_like
        Measured ellipsoidal height of the sensor point [m].
    sigma_m : float or (m,) array_like
        1-sigma white noise of each reading [m], > 0.
    lever_arm_b : (3,) array_like
        IMU-to-sensor lever arm, body axes [m].
    use : (m,) bool array, optional

    References
    ----------
    Groves 2013 §6.2.1 (the barometric altimeter: its offset and its drift
    with the weather), ch. 16 (aiding an INS with further sensors).
    """

    name = "height"
    gating = "vector"

    def __init__(self, time, height_m, sigma_m, *, lever_arm_b=(0.0, 0.0, 0.0), use=None):
        self.time, self.height = _check_series(time, height_m, "height_m")
        self.sigma = _positive(sigma_m, len(self.time), "sigma_m")
        self.lever_arm_b = _lever(lever_arm_b)
        self._rows = _use_rows(use, len(self.time))

    def times(self):
        return self.time[self._rows]

    def rows(self):
        return self._rows

    def linearize(self, ctx: UpdateContext, row):
        lay = ctx.layout
        H = np.zeros((1, lay.size))
        p, v = lay.slice("pos").start, lay.slice("vel").start
        H[0, p + 2] = -1.0
        H[0, v + 2] = -ctx.dt
        h = float(ctx.lla[2]) - float(ctx.v_n[2]) * ctx.dt
        lev = self.lever_arm_b
        if lev.any():
            cl = ctx.C_nb @ lev
            h -= float(cl[2])
            H[0, lay.slice("att")] = -skew(cl)[2]
        b = ctx.estimate("height_bias")
        if b is not None:
            h += float(b[0])
            H[0, lay.slice("height_bias")] = 1.0
        return np.array([h - self.height[row]]), H, np.array([[self.sigma[row] ** 2]])
