"""Measurements of the integration filter: a written protocol and its plug-ins.

The protocol
------------
A measurement is any object with (:class:`Measurement`):

``name`` : str
    Its key in counts and innovation records.
``gating`` : ``"vector"`` or ``"row"``
    Test the whole innovation vector against the chi-square gate, or each
    row on its own (one satellite, say) and update with the rows that pass.
``times() -> (m,) ndarray``
    The epochs [s] at which it has data, in the IMU's time base.
``rows() -> (m,) int ndarray``
    The row of its own data belonging to each epoch (passed back below).
``linearize(ctx, row) -> (innovation, H, R)`` or ``None`` to skip
    ``innovation = h(estimate) - measured`` (k,), ``H`` (k, layout.size)
    over the whole layout, ``R`` (k, k).  With error states
    ``x = estimate - truth`` the innovation is ``H x + noise`` (SYSTEM.md §2,
    where the loosely coupled ``z = P_INS - P_GPS`` with ``H = [I 0 0]`` in
    this sign).

``compiled(layout) -> CompiledSpec`` or ``None`` (optional)
    The same linearization in compiled form (:mod:`._updates`: a kind code
    and the data packed per row).  The standard plug-ins here, in
    :mod:`.aiding` and in :mod:`.tight` offer it, and the filter then runs
    their updates inside its compiled loop; a plug-in without it (or a
    subclass with its own ``linearize``) is called through ``linearize``, on
    the same state.

``ctx`` is an :class:`UpdateContext`: the navigation state at the IMU sample
just before the measurement time, how far to extrapolate, the raw and
corrected body rate, the layout and the current estimates of every block that
carries one (``ctx.estimate("lever")``).  The filter loop knows nothing about
GNSS, ZUPT or odometers (only the compiled forms of :mod:`._updates` do);
new aiding sources plug in here.  Every H is checked
against central finite differences of its own innovation over the fullest
layout (``tests/test_integration_measurements.py``), using
:func:`perturbed_context`; :func:`numerical_jacobian` does that check for any
new plug-in.
"""

from __future__ import annotations

import math
from typing import Protocol, runtime_checkable

import numpy as np

from .. import earth
from ..errors import InputError
from ..rotations import dcm_from_quat, quat_from_dcm, skew
from ..types import GnssData, fix_sigmas
from . import _kernel as K
from . import _updates as U
from .blocks import mounting_dcm
from .layout import StateLayout


@runtime_checkable
class Measurement(Protocol):
    """What the filter loop asks of an aiding measurement (see the module text)."""

    name: str
    gating: str

    def times(self) -> np.ndarray: ...

    def rows(self) -> np.ndarray: ...

    def linearize(self, ctx: "UpdateContext", row: int): ...


class UpdateContext:
    """What a measurement may use to linearize.

    Attributes
    ----------
    t : float
        Measurement time [s].
    dt : float
        ``t`` minus the navigation state's time (>= 0, below one IMU step).
    lla, v_n : (3,) ndarray
        IMU position [rad, rad, m] and NED velocity [m/s].
    C_nb : (3, 3) ndarray
    omega_raw_b : (3,) ndarray
        Raw (uncorrected) body rate [rad/s] over the last IMU interval.
    layout : StateLayout
    aux : (layout.aux_size,) ndarray
        Current estimates of the blocks that carry one.
    """

    __slots__ = ("t", "dt", "lla", "v_n", "C_nb", "omega_raw_b", "layout", "aux", "_w", "_sf")

    def __init__(self, t, dt, lla, v_n, C_nb, omega_raw_b, layout: StateLayout, aux):
        self.t, self.dt, self.lla, self.v_n, self.C_nb = t, dt, lla, v_n, C_nb
        self.omega_raw_b, self.layout, self.aux = omega_raw_b, layout, aux
        self._w = self._sf = None

    def estimate(self, name, default=None):
        """Current estimate of block ``name`` (a copy), or ``default`` when the
        layout does not hold it."""
        s = self.layout.aux_slice(name)
        if s is None:
            return default
        return self.aux[s].copy()

    def _role(self, role):
        b = self.layout.by_role(role)
        return None if b is None else self.aux[self.layout.aux_slice(b.name)]

    def __repr__(self):
        return f"UpdateContext(t={self.t:.3f}, dt={self.dt:.4f}, layout={self.layout!r})"

    @property
    def gyro_scale_factor(self):
        """``1 + s_g`` per axis (ones without a gyro scale-factor block)."""
        if self._sf is None:
            s = self._role("gyro_scale")
            self._sf = np.ones(3) if s is None else 1.0 + s
        return self._sf

    @property
    def omega_ib_b(self):
        """Corrected body rate [rad/s]: ``(raw - b_g) / (1 + s_g)``."""
        if self._w is None:
            b = self._role("gyro_bias")
            w = self.omega_raw_b if b is None else self.omega_raw_b - b
            self._w = w / self.gyro_scale_factor
        return self._w


def perturbed_context(ctx: UpdateContext, dx) -> UpdateContext:
    """The context of an estimate whose error is larger by ``dx`` (layout.size,):
    navigation state through the filter's own correction (with the sign
    reversed), estimates ``aux + dx`` on their states.  For finite-difference
    checks of H: ``innovation(perturbed) - innovation(ctx) ~ H dx``."""
    dx = np.asarray(dx, dtype=float)
    lla, v, q = np.empty(3), np.empty(3), np.empty(4)
    K.apply_correction(ctx.lla, ctx.v_n, quat_from_dcm(ctx.C_nb), dx, -1.0, lla, v, q)
    aux = ctx.aux + dx[ctx.layout.aux_state_index]
    return UpdateContext(ctx.t, ctx.dt, lla, v, dcm_from_quat(q), ctx.omega_raw_b, ctx.layout, aux)


def ned_difference(lla_a, lla_b):
    """NED vector from ``lla_b`` to ``lla_a`` [m], small-offset form (exact to
    millimetres over kilometres), for one point (scalar math: called per
    update).  Longitudes are wrapped, so the difference across 180 deg is the
    short way round."""
    lat, h = float(lla_b[0]), float(lla_b[2])
    s = math.sin(lat)
    w = math.sqrt(1.0 - earth.E2 * s * s)
    rn = earth.A * (1.0 - earth.E2) / (w * w * w) + h
    re = earth.A / w + h
    dlon = (lla_a[1] - lla_b[1] + math.pi) % (2.0 * math.pi) - math.pi
    return np.array([(lla_a[0] - lat) * rn, dlon * re * math.cos(lat), -(lla_a[2] - h)])


_TEMPLATES: dict = {}


def _cross(a, b):
    """``a x b`` for two (3,) arrays (np.cross costs 15 us a call; this runs per update)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _template(layout, rows, block):
    """H with an identity on the navigation ``block`` ("pos" or "vel"),
    cached by state size (the navigation blocks sit at fixed places)."""
    key = (layout.size, rows, block)
    H = _TEMPLATES.get(key)
    if H is None:
        H = np.zeros((rows, layout.size))
        H[:, layout.slice(block)] = np.eye(rows, 3)
        _TEMPLATES[key] = H
    return H.copy()


def compiled_form_applies(meas, cls, gating="vector") -> bool:
    """Whether ``meas`` updates by ``cls``'s own ``linearize``, gated as its
    compiled form (:mod:`._updates`) is, so that this form says the same: a
    subclass with its own ``linearize``, or a measurement switched to the
    other gating, keeps the Python path."""
    return type(meas).linearize is cls.linearize and getattr(meas, "gating", "vector") == gating


def _sensor_rate_columns(H, ctx, M):
    """Add ``M d(omega_ib_b)``'s columns: ``omega = (raw - b_g) / (1 + s_g)``,
    so ``d omega / d b_g = -I / (1 + s_g)`` and ``d omega / d s_g =
    -diag(omega / (1 + s_g))`` (M maps a rate change to the innovation)."""
    lay = ctx.layout
    sf = ctx.gyro_scale_factor
    b = lay.by_role("gyro_bias")
    if b is not None:
        H[:, lay.slice(b.name)] += -M / sf
    b = lay.by_role("gyro_scale")
    if b is not None:
        H[:, lay.slice(b.name)] += -M * (ctx.omega_ib_b / sf)


class GnssPosition:
    """GNSS antenna position fixes (loosely coupled), with lever arm and
    IMU-GNSS time offset.

    Prediction of the antenna at the fix time, ``tau = dt + offset`` after the
    IMU sample: ``p_imu + C_nb l_b + v_ant tau`` with the antenna velocity
    ``v_ant = v_n + C_nb (omega_ib_b x l_b)``, so

    ``H = [I, tau I, [(C_nb a) x], C_nb [l x] tau d omega, C_nb (I + [omega x] tau) (lever), v_ant (offset)]``

    with ``a = l_b + (omega x l_b) tau``.  ``l_b`` is the ``lever`` block's
    estimate when the layout holds one, else ``lever_arm_b``; the offset is
    the ``time_offset`` block's estimate, else 0.  With a ``gnss_err`` block
    (:class:`.blocks.GnssPositionError`, the fixes' time-correlated error)
    its estimate is added to the prediction, ``H_gnss_err = I``.

    Parameters
    ----------
    gnss : GnssData
    use : (n,) bool array, optional
        Which fixes to use (the rest are withheld, e.g. outage tests).
    sigma_floor_m : float
        Lower bound of each sigma [m].
    lever_arm_b : (3,) array_like
        IMU-to-antenna lever arm, body axes [m], when it is not estimated.
    sigma_scale_ned : (3,) array_like
        Multiplies each fix's north, east and down sigma (after the floor):
        the shape of the fixes' noise where the file's sigmas have the wrong
        one (a receiver's formal sigmas, equal on all axes, where the
        vertical really is worse: :func:`inskit.analysis.consistency.axis_scale_step`).
    """

    name = "gnss_pos"
    gating = "vector"

    def __init__(self, gnss: GnssData, use=None, sigma_floor_m=0.0, lever_arm_b=(0.0, 0.0, 0.0),
                 sigma_scale_ned=(1.0, 1.0, 1.0)):
        self.gnss = gnss
        self.use = np.ones(len(gnss), bool) if use is None else np.asarray(use, bool)
        scale = np.asarray(sigma_scale_ned, dtype=float)
        if scale.shape != (3,) or not (np.all(np.isfinite(scale)) and np.all(scale > 0)):
            raise InputError(f"sigma_scale_ned must be three finite numbers > 0 (north, east, down), got "
                             f"{sigma_scale_ned!r}")
        self.sigma = fix_sigmas(gnss.sigma_ned, sigma_floor_m, scale)
        self.lever_arm_b = np.asarray(lever_arm_b, dtype=float)
        self._rows = np.nonzero(self.use)[0]

    def times(self):
        return self.gnss.time[self._rows]

    def rows(self):
        return self._rows

    def linearize(self, ctx: UpdateContext, row):
        lay = ctx.layout
        lev = ctx.estimate("lever", self.lever_arm_b)
        off = ctx.estimate("time_offset")
        tau = ctx.dt + (0.0 if off is None else off[0])
        C = ctx.C_nb
        H = _template(lay, 3, "pos")
        H[:, 3:6] = np.eye(3) * tau
        if lev.any() or "lever" in lay:
            w = ctx.omega_ib_b
            wl = _cross(w, lev)
            v_ant = ctx.v_n + C @ wl
            cl = C @ lev
            H[:, 6:9] = skew(cl + C @ wl * tau)
            _sensor_rate_columns(H, ctx, -C @ skew(lev) * tau)
            if "lever" in lay:
                H[:, lay.slice("lever")] = C @ (np.eye(3) + skew(w) * tau)
        else:  # no lever arm: the antenna is the IMU (skip the rate terms, all zero)
            v_ant, cl = ctx.v_n, 0.0
        nu = ned_difference(ctx.lla, self.gnss.lla[row]) + cl + v_ant * tau
        if off is not None:
            H[:, lay.slice("time_offset")] = v_ant[:, None]
        err = ctx.estimate("gnss_err")
        if err is not None:
            nu = nu + err
            H[:, lay.slice("gnss_err")] = np.eye(3)
        return nu, H, np.diag(self.sigma[row] ** 2)

    def compiled(self, layout):
        """:meth:`linearize` in compiled form (:mod:`._updates`): per row the
        fix and its sigmas (a ``gnss_err`` block found by the kernel)."""
        if not compiled_form_applies(self, GnssPosition):
            return None
        return U.spec(U.KIND_GNSS_POS, 3, np.column_stack([self.gnss.lla, self.sigma]), self.lever_arm_b)


class GnssVelocity:
    """GNSS velocity of the antenna, ``h = v_n + C_nb (omega_ib_b x l_b)``.

    ``H = [0, I, [(C_nb (omega x l)) x], -C_nb [l x] d omega, C_nb [omega x] (lever)]``.

    Parameters
    ----------
    delay_s : float
        Receiver velocity latency: the velocity stamped ``t`` describes
        ``t - delay_s`` (the drive_0708 .pos velocity lags by about 0.13 s).
    sigma_scale : float
        Multiply the file's sigmas (inflate a velocity you trust less).
    lever_arm_b : (3,) array_like
        As for :class:`GnssPosition`.
    """

    name = "gnss_vel"
    gating = "vector"

    def __init__(self, gnss: GnssData, use=None, delay_s=0.0, sigma_scale=1.0, lever_arm_b=(0.0, 0.0, 0.0)):
        if not gnss.has_velocity:
            raise ValueError("the GNSS data carry no velocity")
        self.gnss = gnss
        self.use = np.ones(len(gnss), bool) if use is None else np.asarray(use, bool)
        self.delay = float(delay_s)
        self.sigma = gnss.sigma_v_ned * float(sigma_scale)
        self.lever_arm_b = np.asarray(lever_arm_b, dtype=float)
        self._rows = np.nonzero(self.use)[0]

    def times(self):
        return self.gnss.time[self._rows] - self.delay

    def rows(self):
        return self._rows

    def linearize(self, ctx: UpdateContext, row):
        lay = ctx.layout
        lev = ctx.estimate("lever", self.lever_arm_b)
        C = ctx.C_nb
        w = ctx.omega_ib_b
        lever_v = C @ _cross(w, lev)
        nu = ctx.v_n + lever_v - self.gnss.v_n[row]
        H = _template(lay, 3, "vel")
        H[:, 6:9] = skew(lever_v)
        _sensor_rate_columns(H, ctx, -C @ skew(lev))
        if "lever" in lay:
            H[:, lay.slice("lever")] = C @ skew(w)
        return nu, H, np.diag(self.sigma[row] ** 2)

    def compiled(self, layout):
        """:meth:`linearize` in compiled form (:mod:`._updates`)."""
        if not compiled_form_applies(self, GnssVelocity):
            return None
        return U.spec(U.KIND_GNSS_VEL, 3, np.column_stack([self.gnss.v_n, self.sigma]), self.lever_arm_b)


class _GridMeasurement:
    """A pseudo-measurement on a regular time grid inside given intervals."""

    gating = "vector"

    def __init__(self, intervals, rate_hz, sigma):
        self.sigma = float(sigma)
        ts = [np.arange(a, b, 1.0 / rate_hz) for a, b in intervals if b > a]
        self._t = np.concatenate(ts) if ts else np.empty(0)

    def times(self):
        return self._t

    def rows(self):
        return np.arange(len(self._t))


class ZeroVelocity(_GridMeasurement):
    """Zero-velocity update (ZUPT) while the vehicle stands still: ``h = v_n``."""

    name = "zupt"

    def linearize(self, ctx: UpdateContext, row):
        return ctx.v_n.copy(), _template(ctx.layout, 3, "vel"), np.eye(3) * self.sigma**2

    def compiled(self, layout):
        """:meth:`linearize` in compiled form (:mod:`._updates`)."""
        if not compiled_form_applies(self, ZeroVelocity):
            return None
        return U.spec(U.KIND_ZUPT, 3, np.empty((len(self._t), 0)), self.sigma)


def vehicle_axes(ctx: UpdateContext):
    """``(C_vb, dC_dpitch, dC_dyaw)`` of the ``mounting`` block's estimate
    (:func:`.blocks.mounting_dcm`), or ``None`` when the layout has no such
    block (the vehicle's axes are then the IMU's)."""
    m = ctx.estimate("mounting")
    return None if m is None else mounting_dcm(float(m[0]), float(m[1]))


class NonHolonomic(_GridMeasurement):
    """Non-holonomic constraint: a land vehicle does not slide sideways or
    jump, so its lateral and vertical velocities are zero.

    They are zero in the vehicle's axes at the point where the constraint
    holds (for the lateral slip, the centre of the unsteered rear axle):
    ``v_v = C_vb (C_bn v_n + omega_ib_b x l_b)``, with ``l_b`` the IMU to
    that point in body axes (Groves 2013 §16.2.3 and eq. 6.55, the wheel's
    lever-arm velocity), default 0: the constraint is then taken at the IMU,
    where in a turn the lateral velocity is ``omega_z l_x - omega_x l_z``.
    ``C_vb`` is of the ``mounting`` block's estimate when the layout holds
    one (:class:`.blocks.Mounting`), else ``I`` (the IMU's axes are taken
    for the vehicle's).  With ``C_vn = C_vb C_bn`` and ``v_o = C_bn v_n +
    omega x l_b``: ``H_vel = C_vn[1:3]``, ``H_att = -(C_vn [v_n x])[1:3]``,
    ``H_rate = -(C_vb [l_b x])[1:3]`` (through ``d omega`` into the gyro
    bias and scale-factor columns), ``H_mounting = [dC_vb/dpitch v_o,
    dC_vb/dyaw v_o][1:3]``.
    """

    name = "nhc"

    def __init__(self, intervals, rate_hz, sigma, lever_arm_b=(0.0, 0.0, 0.0)):
        super().__init__(intervals, rate_hz, sigma)
        lev = np.asarray(lever_arm_b, dtype=float)
        if lev.shape != (3,) or not np.all(np.isfinite(lev)):
            raise ValueError(f"`lever_arm_b` must be three finite numbers (body axes, m), got {lever_arm_b!r}")
        self.lever_arm_b = lev

    def linearize(self, ctx: UpdateContext, row):
        lay = ctx.layout
        C_bn = ctx.C_nb.T
        lev = self.lever_arm_b
        v_o = C_bn @ ctx.v_n
        H = np.zeros((2, lay.size))
        mount = vehicle_axes(ctx)
        C_vb = np.eye(3) if mount is None else mount[0]
        C_vn = C_bn if mount is None else C_vb @ C_bn
        H[:, 3:6] = C_vn[1:3]
        H[:, 6:9] = -(C_vn @ skew(ctx.v_n))[1:3]
        if lev.any():
            v_o = v_o + _cross(ctx.omega_ib_b, lev)
            _sensor_rate_columns(H, ctx, -(C_vb @ skew(lev))[1:3])
        if mount is not None:
            s = lay.slice("mounting")
            H[:, s.start] = (mount[1] @ v_o)[1:3]
            H[:, s.start + 1] = (mount[2] @ v_o)[1:3]
        return (C_vb @ v_o)[1:3], H, np.eye(2) * self.sigma**2

    def compiled(self, layout):
        """:meth:`linearize` in compiled form (:mod:`._updates`): the sigma and
        the lever arm."""
        if not compiled_form_applies(self, NonHolonomic):
            return None
        return U.spec(U.KIND_NHC, 2, np.empty((len(self._t), 0)), np.r_[self.sigma, self.lever_arm_b])


def numerical_jacobian(meas, ctx: UpdateContext, row=0, steps=None):
    """Central finite differences of a measurement's own innovation over
    every state: the check every plug-in's ``H`` must pass (the protocol's
    contract; ``innovation(perturbed by +dx) - innovation(-dx) ~ 2 H dx``).

    Parameters
    ----------
    meas : a measurement plug-in
    ctx : UpdateContext
    row : int
        The measurement's own row (an epoch) to linearize at.
    steps : dict, optional
        Step per block name (in the block's unit); 1e-3 for a block not
        named.  Choose steps large against the rounding of the innovation
        (a 2e7 m range rounds to 3.7e-9 m) and small against its curvature.

    Returns
    -------
    (k, layout.size) ndarray
    """
    lay = ctx.layout
    steps = steps or {}
    eps = np.concatenate([np.full(b.size, float(steps.get(b.name, 1e-3))) for b in lay.blocks])
    n = lay.size
    J = np.zeros((len(meas.linearize(ctx, row)[0]), n))
    for j in range(n):
        d = np.zeros(n)
        d[j] = eps[j]
        J[:, j] = (meas.linearize(perturbed_context(ctx, d), row)[0]
                   - meas.linearize(perturbed_context(ctx, -d), row)[0]) / (2.0 * eps[j])
    return J
