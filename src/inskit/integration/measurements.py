"""Measurement plug-ins of the integration filter.

A measurement is any object with

* ``name`` (str), and ``times()``: the epochs [s] at which it has data;
* ``linearize(ctx, row) -> (innovation, H, R)`` or ``None`` to skip.

``ctx`` is an :class:`UpdateContext`: the navigation state at the IMU sample
just before the measurement time, how far to extrapolate, the corrected body
rate and the layout.  The filter loop knows nothing about GNSS, ZUPT or
odometers; new aiding sources plug in here.

Sign convention: ``innovation = h(estimate) - measured``, so that with error
states ``x = estimate - truth`` it is ``H x + noise`` (SYSTEM.md §2, where the
loosely coupled ``z = P_INS - P_GPS`` with ``H = [I 0 0]`` in this sign).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import earth
from ..rotations import skew
from ..types import GnssData
from .layout import StateLayout


@dataclass
class UpdateContext:
    """What a measurement may use to linearize.

    Attributes
    ----------
    t : float
        Measurement time [s].
    dt : float
        ``t`` minus the navigation state's time (>= 0, below one IMU step).
    lla, v_n : (3,) ndarray
        IMU position and NED velocity.
    C_nb : (3, 3) ndarray
    omega_ib_b : (3,) ndarray
        Corrected body rate [rad/s] over the last IMU interval.
    layout : StateLayout
    lever_arm_b : (3,) ndarray
        Current IMU-to-antenna lever arm estimate, body axes [m].
    time_offset : float
        Current IMU-GNSS time offset estimate [s]: a GNSS time tag ``t``
        matches the INS at ``t + time_offset``.
    """

    t: float
    dt: float
    lla: np.ndarray
    v_n: np.ndarray
    C_nb: np.ndarray
    omega_ib_b: np.ndarray
    layout: StateLayout
    lever_arm_b: np.ndarray
    time_offset: float = 0.0


def ned_difference(lla_a, lla_b):
    """NED vector from ``lla_b`` to ``lla_a`` [m], small-offset form (exact to
    millimetres over kilometres), for one point (scalar math: called per update)."""
    lat, h = float(lla_b[0]), float(lla_b[2])
    s = math.sin(lat)
    w = math.sqrt(1.0 - earth.E2 * s * s)
    rn = earth.A * (1.0 - earth.E2) / (w * w * w) + h
    re = earth.A / w + h
    return np.array([(lla_a[0] - lat) * rn, (lla_a[1] - lla_b[1]) * re * math.cos(lat), -(lla_a[2] - h)])


def _template(layout, rows, block):
    """H with an identity on ``block`` (cached per layout and size)."""
    key = (layout, rows, block)
    H = _TEMPLATES.get(key)
    if H is None:
        H = np.zeros((rows, layout.size))
        H[:, layout.slice(block)] = np.eye(rows, 3)
        _TEMPLATES[key] = H
    return H.copy()


_TEMPLATES: dict = {}


class GnssPosition:
    """GNSS antenna position fixes (loosely coupled), with lever arm.

    ``h = p_imu + C_nb l_b`` extrapolated to the fix time by the velocity;
    ``H = [I, 0, [(C_nb l_b) x], 0 ..., C_nb (lever state)]``.

    Parameters
    ----------
    gnss : GnssData
    use : (n,) bool array, optional
        Which fixes to use (the rest are withheld, e.g. outage tests).
    sigma_floor_m : float
        Lower bound of each sigma [m].
    """

    name = "gnss_pos"

    def __init__(self, gnss: GnssData, use=None, sigma_floor_m=0.0):
        self.gnss = gnss
        self.use = np.ones(len(gnss), bool) if use is None else np.asarray(use, bool)
        self.sigma = np.maximum(gnss.sigma_ned, sigma_floor_m)
        self._rows = np.nonzero(self.use)[0]

    def times(self):
        return self.gnss.time[self._rows]

    def rows(self):
        return self._rows

    def antenna_offset(self, ctx):
        return ctx.C_nb @ ctx.lever_arm_b

    def linearize(self, ctx: UpdateContext, row):
        lay = ctx.layout
        cl = self.antenna_offset(ctx)
        nu = ned_difference(ctx.lla, self.gnss.lla[row]) + cl + ctx.v_n * (ctx.dt + ctx.time_offset)
        H = _template(lay, 3, "pos")
        H[:, lay.slice("att")] = skew(cl)
        if lay.lever_arm:
            H[:, lay.slice("lever")] = ctx.C_nb
        if lay.time_offset:  # d h / d offset = antenna velocity
            H[:, lay.slice("dt")] = (ctx.v_n + ctx.C_nb @ np.cross(ctx.omega_ib_b, ctx.lever_arm_b))[:, None]
        return nu, H, np.diag(self.sigma[row] ** 2)


class GnssVelocity:
    """GNSS velocity (antenna), ``h = v_n + C_nb (omega_ib_b x l_b)``.

    Parameters
    ----------
    delay_s : float
        Receiver velocity latency: the velocity stamped ``t`` describes
        ``t - delay_s`` (the drive_0708 .pos velocity lags by about 0.13 s).
    sigma_scale : float
        Multiply the file's sigmas (inflate a velocity you trust less).
    """

    name = "gnss_vel"

    def __init__(self, gnss: GnssData, use=None, delay_s=0.0, sigma_scale=1.0):
        if not gnss.has_velocity:
            raise ValueError("the GNSS data carry no velocity")
        self.gnss = gnss
        self.use = np.ones(len(gnss), bool) if use is None else np.asarray(use, bool)
        self.delay = float(delay_s)
        self.sigma = gnss.sigma_v_ned * float(sigma_scale)
        self._rows = np.nonzero(self.use)[0]

    def times(self):
        return self.gnss.time[self._rows] - self.delay

    def rows(self):
        return self._rows

    def linearize(self, ctx: UpdateContext, row):
        lay = ctx.layout
        lever_v = ctx.C_nb @ np.cross(ctx.omega_ib_b, ctx.lever_arm_b)
        nu = ctx.v_n + lever_v - self.gnss.v_n[row]
        H = _template(lay, 3, "vel")
        H[:, lay.slice("att")] = skew(lever_v)
        return nu, H, np.diag(self.sigma[row] ** 2)


class _GridMeasurement:
    """A pseudo-measurement on a regular time grid inside given intervals."""

    def __init__(self, intervals, rate_hz, sigma):
        self.sigma = float(sigma)
        ts = [np.arange(a, b, 1.0 / rate_hz) for a, b in intervals if b > a]
        self._t = np.concatenate(ts) if ts else np.empty(0)

    def times(self):
        return self._t

    def rows(self):
        return np.arange(len(self._t))


class ZeroVelocity(_GridMeasurement):
    """Zero-velocity update (ZUPT) while the vehicle stands still."""

    name = "zupt"

    def linearize(self, ctx: UpdateContext, row):
        return ctx.v_n.copy(), _template(ctx.layout, 3, "vel"), np.eye(3) * self.sigma**2


class NonHolonomic(_GridMeasurement):
    """Non-holonomic constraint: a land vehicle does not slide sideways or
    jump, so the body-frame lateral and vertical velocities are zero.

    ``v_b = C_nb^T v_n``; ``H_vel = C_bn[1:3]``, ``H_att = -(C_bn [v_n x])[1:3]``.
    """

    name = "nhc"

    def linearize(self, ctx: UpdateContext, row):
        lay = ctx.layout
        C_bn = ctx.C_nb.T
        v_b = C_bn @ ctx.v_n
        H = np.zeros((2, lay.size))
        H[:, lay.slice("vel")] = C_bn[1:3]
        H[:, lay.slice("att")] = -(C_bn @ skew(ctx.v_n))[1:3]
        return v_b[1:3], H, np.eye(2) * self.sigma**2
