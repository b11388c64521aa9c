"""The accelerometer-array sensor model: true and measured outputs.

Accelerometer k at body position ``r_k`` with true unit sensing axis ``e'_k``
reads

``y_k = (1 + s_k) e'_k . (f_b + omega_dot x r_k + omega x (omega x r_k)) + b_k + n_k``

(SOURCES-NOTES §1.1; source 003 eq. 4-6 with the force-rebalance proof mass
``x = 0``): ``s_k`` scale-factor error, ``e'_k`` the sensing axis after its
misalignment (a small tilt of the nominal ``e_k``), ``b_k`` bias, ``n_k``
white noise (one draw per sample, sigma in m/s^2).  The solvers know only the
nominal layout (``r_k``, ``e_k``); the difference is the error.

Samples are instantaneous (point) values at the sample times, as the
quadratic terms require: the mean of ``omega^2`` over an interval is not the
square of the mean rate.

References
----------
SYSTEM.md §5; SOURCES-NOTES §1.1, §1.5 (misalignment of the sensing axes of
m1-m6 in the body planes: m1, m2 and m3, m4 tilt toward b3, m5, m6 toward b1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..types import check_time
from .layout import ArrayLayout
from .motion import RigidMotion


@dataclass(frozen=True)
class ArrayData:
    """Raw outputs of an accelerometer array.

    Attributes
    ----------
    time : (n,) ndarray
        Sample times [s], strictly increasing.
    outputs : (n, m) ndarray
        Specific force along each sensing axis [m/s^2], one column per
        accelerometer in the order of ``names``.
    names : tuple of str
        Accelerometer names (those of the layout).
    """

    time: np.ndarray
    outputs: np.ndarray
    names: tuple

    def __post_init__(self):
        t = check_time("time", self.time)
        y = np.ascontiguousarray(self.outputs, dtype=float)
        names = tuple(self.names)
        if y.ndim != 2 or y.shape != (len(t), len(names)):
            raise InputError(f"`outputs` must have shape ({len(t)}, {len(names)}) (samples, accelerometers), "
                             f"got {y.shape}")
        bad = ~np.isfinite(y)
        if bad.any():
            i, j = np.argwhere(bad)[0]
            raise InputError(f"`outputs` has a NaN or infinite value at row {i}, accelerometer {names[j]}")
        object.__setattr__(self, "time", t)
        object.__setattr__(self, "outputs", y)
        object.__setattr__(self, "names", names)

    def __len__(self):
        return len(self.time)

    def check_layout(self, layout: ArrayLayout):
        """Refuse a layout whose accelerometers are not these columns."""
        if tuple(layout.names) != self.names:
            missing = [n for n in layout.names if n not in self.names]
            extra = [n for n in self.names if n not in layout.names]
            detail = []
            if missing:
                detail.append(f"no column for {', '.join(missing)}")
            if extra:
                detail.append(f"columns {', '.join(extra)} are not in the layout")
            if not detail:
                detail.append("the columns are in another order")
            raise InputError(f"the array data do not match layout '{layout.label}': {'; '.join(detail)} "
                             f"(data: {', '.join(self.names)}; layout: {', '.join(layout.names)})")

    def slice(self, start, stop=None):
        s = slice(start, stop)
        return ArrayData(self.time[s], self.outputs[s], self.names)


@dataclass(frozen=True)
class ArrayErrors:
    """Errors of the m accelerometers of an array (SI units).

    Attributes
    ----------
    bias : (m,) ndarray
        [m/s^2].
    scale_factor : (m,) ndarray
        Fractional scale-factor errors [-].
    axes_true_b : (m, 3) ndarray or None
        True (misaligned) unit sensing axes; ``None``: the nominal ones.
    noise_sigma : (m,) ndarray
        White-noise sigma of one sample [m/s^2].
    """

    bias: np.ndarray
    scale_factor: np.ndarray
    axes_true_b: np.ndarray | None
    noise_sigma: np.ndarray

    @classmethod
    def none(cls, m):
        z = np.zeros(m)
        return cls(z, z, None, z)

    @classmethod
    def build(cls, m, *, bias=0.0, scale_factor=0.0, axes_true_b=None, noise_sigma=0.0):
        """Errors from scalars (same for all) or ``(m,)`` arrays, validated."""
        def vec(name, x):
            a = np.broadcast_to(np.asarray(x, float), (m,)).copy() if np.ndim(x) == 0 else np.asarray(x, float)
            if a.shape != (m,):
                raise InputError(f"`{name}` must be a number or have shape ({m},), got {a.shape}")
            if not np.isfinite(a).all():
                raise InputError(f"`{name}` has a NaN or infinite value")
            return a

        ns = vec("noise_sigma", noise_sigma)
        if (ns < 0).any():
            raise InputError(f"`noise_sigma` must be >= 0, got {ns.min()}")
        ax = None
        if axes_true_b is not None:
            ax = np.asarray(axes_true_b, float)
            if ax.shape != (m, 3) or not np.isfinite(ax).all():
                raise InputError(f"`axes_true_b` must be a finite ({m}, 3) array, got shape {ax.shape}")
            nrm = np.linalg.norm(ax, axis=1)
            if (np.abs(nrm - 1) > 1e-3).any():
                raise InputError("`axes_true_b` must hold unit vectors")
            ax = ax / nrm[:, None]
        return cls(vec("bias", bias), vec("scale_factor", scale_factor), ax, ns)


def tilt_axes(axes_b, toward_b, angles):
    """Tilt unit axes by ``angles`` [rad] toward given directions.

    ``e' = cos(theta) e + sin(theta) u`` with ``u`` the unit part of ``toward``
    perpendicular to ``e`` (source 003 eq. 26: ``S_theta1 = [cos, 0, sin]``
    is ``b1`` tilted toward ``b3``).

    Parameters
    ----------
    axes_b : (m, 3) array_like
    toward_b : (m, 3) array_like
        Any vectors not parallel to the axes.
    angles : (m,) array_like
        [rad]; negative tilts away from ``toward``.

    Returns
    -------
    (m, 3) ndarray
    """
    e = np.asarray(axes_b, float)
    u = np.asarray(toward_b, float)
    th = np.asarray(angles, float).reshape(-1)
    u = u - np.sum(u * e, axis=1, keepdims=True) * e
    nu = np.linalg.norm(u, axis=1)
    if (nu < 1e-12).any():
        raise InputError("a tilt direction is parallel to its sensing axis")
    u = u / nu[:, None]
    return np.cos(th)[:, None] * e + np.sin(th)[:, None] * u


#: Tilt directions of the source's misalignment model (SOURCES-NOTES §1.5):
#: m1, m2 toward b3; m3, m4 toward b3; m5, m6 toward b1.
SOURCE_TILT_TOWARD = np.array([[0, 0, 1], [0, 0, 1], [0, 0, 1], [0, 0, 1], [1, 0, 0], [1, 0, 0]], float)


def source_misaligned_axes(layout: ArrayLayout, theta):
    """Sensing axes with source 003's misalignment angles on m1-m6.

    ``S_theta1,2 = [cos, 0, sin]``, ``S_theta3,4 = [0, cos, sin]``,
    ``S_theta5,6 = [sin, 0, cos]`` (eq. 26-36); m7-m10 stay nominal (the source
    does not model them).

    Parameters
    ----------
    layout : ArrayLayout
        The six- or ten-accelerometer layout.
    theta : (6,) array_like
        ``theta_1 .. theta_6`` [rad].
    """
    th = np.asarray(theta, float).reshape(-1)
    if th.shape != (6,):
        raise InputError(f"`theta` must hold the six angles of m1-m6, got shape {th.shape}")
    if len(layout) not in (6, 10):
        raise InputError(f"the source's misalignment model is for its six- and ten-accelerometer layouts, "
                         f"not for {len(layout)} accelerometers")
    ax = np.array(layout.axes_b)
    ax[:6] = tilt_axes(ax[:6], SOURCE_TILT_TOWARD, th)
    return ax


def draw_errors(layout: ArrayLayout, rng, *, bias_sigma=0.0, bias_mean=0.0, scale_sigma=0.0,
                misalignment_sigma=0.0, noise_sigma=0.0) -> ArrayErrors:
    """Draw one set of array errors (a seeded Monte Carlo run).

    Parameters
    ----------
    layout : ArrayLayout
    rng : numpy.random.Generator
    bias_sigma : float
        [m/s^2], independent per accelerometer, around ``bias_mean``
        (a number or ``(m,)``).
    scale_sigma : float
        Fractional, independent per accelerometer.
    misalignment_sigma : float
        [rad]: each sensing axis tilts by a 2-D Gaussian small angle (sigma per
        component) in a random direction perpendicular to it.
    noise_sigma : float
        Per-sample white noise [m/s^2] (not drawn here: applied by
        :func:`simulate_array`).
    """
    if rng is None:
        raise InputError("drawing array errors needs an explicit `rng` (numpy.random.default_rng(seed))")
    m = len(layout)
    bias = np.asarray(bias_mean, float) + rng.standard_normal(m) * bias_sigma
    sf = rng.standard_normal(m) * scale_sigma
    axes = None
    if misalignment_sigma > 0:
        e = layout.axes_b
        ref = np.where(np.abs(e[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
        u1 = np.cross(e, ref)
        u1 /= np.linalg.norm(u1, axis=1, keepdims=True)
        u2 = np.cross(e, u1)
        a = rng.standard_normal((m, 2)) * misalignment_sigma
        axes = e + a[:, :1] * u1 + a[:, 1:] * u2
        axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    return ArrayErrors.build(m, bias=bias, scale_factor=sf, axes_true_b=axes, noise_sigma=noise_sigma)


def true_specific_forces(layout: ArrayLayout, motion: RigidMotion):
    """``(n, m, 3)`` specific force at each accelerometer's position, body axes:
    ``f_b + omega_dot x r_k + omega x (omega x r_k)``."""
    r = layout.positions_b[None, :, :]
    w = motion.omega_ib_b[:, None, :]
    dw = motion.omega_dot_ib_b[:, None, :]
    return motion.f_b[:, None, :] + np.cross(dw, r) + np.cross(w, np.cross(w, r))


def simulate_array(layout: ArrayLayout, motion: RigidMotion, errors: ArrayErrors | None = None,
                   rng=None) -> ArrayData:
    """Outputs of the array for a motion, exact or with errors.

    Parameters
    ----------
    layout : ArrayLayout
        Nominal positions and axes.
    motion : RigidMotion
    errors : ArrayErrors, optional
        ``None``: error-free outputs.
    rng : numpy.random.Generator
        Required when the errors include noise.

    Returns
    -------
    ArrayData
    """
    if not isinstance(motion, RigidMotion):
        raise InputError("`motion` must be a RigidMotion (see motion_from_trajectory, ConstantRateMotion)")
    m = len(layout)
    fk = true_specific_forces(layout, motion)
    if errors is None:
        y = np.einsum("nkj,kj->nk", fk, layout.axes_b)
        return ArrayData(motion.time, y, layout.names)
    if errors.bias.shape != (m,):
        raise InputError(f"the errors are for {errors.bias.shape[0]} accelerometers, the layout has {m}")
    axes = layout.axes_b if errors.axes_true_b is None else errors.axes_true_b
    y = np.einsum("nkj,kj->nk", fk, axes) * (1.0 + errors.scale_factor) + errors.bias
    if np.any(errors.noise_sigma > 0):
        if rng is None:
            raise InputError("simulating noise needs an explicit `rng` (numpy.random.default_rng(seed))")
        y = y + rng.standard_normal(y.shape) * errors.noise_sigma
    return ArrayData(motion.time, y, layout.names)


__all__ = [
    "SOURCE_TILT_TOWARD",
    "ArrayData",
    "ArrayErrors",
    "draw_errors",
    "simulate_array",
    "source_misaligned_axes",
    "tilt_axes",
    "true_specific_forces",
]
