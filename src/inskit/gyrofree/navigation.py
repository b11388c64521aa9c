"""Navigation with the array's estimates.

* :func:`navigate_inertial`: source 003 §6, the quaternion equation of eq. 43
  and the body-to-inertial matrix of eq. 44, then ``r_ddot_i = C_ib f_b``
  (plus an optional uniform gravity; the source has none).  The source writes
  the quaternion scalar last (``eps_4`` the scalar, identity ``[0, 0, 0, 1]``);
  the package's convention is scalar first: :func:`quat_from_source` and
  :func:`quat_to_source` convert, and :func:`eq43_matrix`, :func:`eq44_dcm`
  are the source's formulas verbatim for checks.  Eq. 43 in scalar-first form
  is ``q_dot = q (x) [0, omega] / 2`` (Hamilton); eq. 44, labelled ``iC_e`` in
  the print, is ``C_b^i`` = ``C_ib`` (SOURCES-NOTES §1.6).  The integration is
  fourth-order Runge-Kutta over each sample interval with the rate and
  specific force varying linearly between the (point) samples, compiled.
* :func:`navigate_earth`: the core's NED / wander / ECEF / inertial
  mechanizations (:func:`inskit.strapdown.mechanize`) fed with the array's
  estimates as an :class:`~inskit.types.ImuData`, with gravity and Earth rate.

References
----------
SOURCES-NOTES §1.6 (eq. 43-44); SYSTEM.md §1.2, §1.4.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .. import rotations as rot
from ..errors import InputError
from ..strapdown import mechanize
from ..types import NavState, check_time
from .motion import InertialSolution
from .solvers import ArraySolution
from ..types import plain_number


def quat_from_source(eps):
    """Scalar-first quaternion ``[eps4, eps1, eps2, eps3]`` from source 003's
    scalar-last ``[eps1, eps2, eps3, eps4]`` (``(4,)`` or ``(n, 4)``)."""
    e = np.asarray(eps, float)
    return np.concatenate([e[..., 3:4], e[..., 0:3]], axis=-1)


def quat_to_source(q):
    """Source 003's scalar-last quaternion from a scalar-first one."""
    q = np.asarray(q, float)
    return np.concatenate([q[..., 1:4], q[..., 0:1]], axis=-1)


def eq43_matrix(omega):
    """The 4x4 matrix of source 003 eq. 43, ``P_dot = 1/2 M P`` (scalar last),
    for ``omega = [p, q, r]`` [rad/s]."""
    p, q, r = np.asarray(omega, float)
    return np.array([[0.0, r, -q, p], [-r, 0.0, p, q], [q, -p, 0.0, r], [-p, -q, -r, 0.0]])


def eq44_dcm(eps):
    """Source 003 eq. 44 verbatim: ``C_b^i`` from the scalar-last quaternion."""
    e1, e2, e3, e4 = np.asarray(eps, float)
    return np.array([
        [1 - 2 * (e2**2 + e3**2), 2 * (e1 * e2 - e3 * e4), 2 * (e1 * e3 + e2 * e4)],
        [2 * (e1 * e2 + e3 * e4), 1 - 2 * (e1**2 + e3**2), 2 * (e2 * e3 - e1 * e4)],
        [2 * (e1 * e3 - e2 * e4), 2 * (e2 * e3 + e1 * e4), 1 - 2 * (e1**2 + e2**2)],
    ])


@njit(cache=True, inline="always")
def _deriv(q, v, w, f, g, dq, dv):
    """``q_dot = q (x) [0, w] / 2`` (eq. 43 scalar first) and
    ``v_dot = C(q/|q|) f + g`` (eq. 44)."""
    q0, q1, q2, q3 = q[0], q[1], q[2], q[3]
    dq[0] = 0.5 * (-q1 * w[0] - q2 * w[1] - q3 * w[2])
    dq[1] = 0.5 * (q0 * w[0] + q2 * w[2] - q3 * w[1])
    dq[2] = 0.5 * (q0 * w[1] + q3 * w[0] - q1 * w[2])
    dq[3] = 0.5 * (q0 * w[2] + q1 * w[1] - q2 * w[0])
    c = rot.quat_dcm(q0, q1, q2, q3)  # homogeneous form: |q|^2 times the rotation
    inv = 1.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    dv[0] = (c[0] * f[0] + c[1] * f[1] + c[2] * f[2]) * inv + g[0]
    dv[1] = (c[3] * f[0] + c[4] * f[1] + c[5] * f[2]) * inv + g[1]
    dv[2] = (c[6] * f[0] + c[7] * f[1] + c[8] * f[2]) * inv + g[2]


@njit(cache=True)
def _inertial_kernel(t, w_all, f_all, q_in, v_in, r_in, g, q_out, v_out, r_out):
    n = t.shape[0]
    q = q_in.copy()
    v = v_in.copy()
    r = r_in.copy()
    wm = np.empty(3)
    fm = np.empty(3)
    qs = np.empty(4)
    vs = np.empty(3)
    v2 = np.empty(3)
    v3 = np.empty(3)
    k1q, k2q, k3q, k4q = np.empty(4), np.empty(4), np.empty(4), np.empty(4)
    k1v, k2v, k3v, k4v = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    for i in range(4):
        q_out[0, i] = q[i]
    for i in range(3):
        v_out[0, i] = v[i]
        r_out[0, i] = r[i]
    for k in range(1, n):
        h = t[k] - t[k - 1]
        w0 = w_all[k - 1]
        w1 = w_all[k]
        f0 = f_all[k - 1]
        f1 = f_all[k]
        for i in range(3):
            wm[i] = 0.5 * (w0[i] + w1[i])
            fm[i] = 0.5 * (f0[i] + f1[i])
        _deriv(q, v, w0, f0, g, k1q, k1v)
        for i in range(4):
            qs[i] = q[i] + 0.5 * h * k1q[i]
        for i in range(3):
            vs[i] = v[i] + 0.5 * h * k1v[i]
            v2[i] = vs[i]
        _deriv(qs, vs, wm, fm, g, k2q, k2v)
        for i in range(4):
            qs[i] = q[i] + 0.5 * h * k2q[i]
        for i in range(3):
            vs[i] = v[i] + 0.5 * h * k2v[i]
            v3[i] = vs[i]
        _deriv(qs, vs, wm, fm, g, k3q, k3v)
        for i in range(4):
            qs[i] = q[i] + h * k3q[i]
        for i in range(3):
            vs[i] = v[i] + h * k3v[i]
        _deriv(qs, vs, w1, f1, g, k4q, k4v)
        for i in range(3):
            r[i] += h / 6.0 * (v[i] + 2.0 * v2[i] + 2.0 * v3[i] + vs[i])
            v[i] += h / 6.0 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i])
        nq = 0.0
        for i in range(4):
            q[i] += h / 6.0 * (k1q[i] + 2.0 * k2q[i] + 2.0 * k3q[i] + k4q[i])
            nq += q[i] * q[i]
        nq = 1.0 / np.sqrt(nq)
        for i in range(4):
            q[i] *= nq
            q_out[k, i] = q[i]
        for i in range(3):
            v_out[k, i] = v[i]
            r_out[k, i] = r[i]


def navigate_inertial(time, omega_ib_b, f_b, *, q_ib0=(1.0, 0.0, 0.0, 0.0), v_i0=(0.0, 0.0, 0.0),
                      r_i0=(0.0, 0.0, 0.0), gravity_i=(0.0, 0.0, 0.0)) -> InertialSolution:
    """Inertial-frame navigation from point samples of rate and specific force.

    Parameters
    ----------
    time : (n,) array_like
        [s], strictly increasing; row 0 is the initial epoch.
    omega_ib_b : (n, 3) array_like
        [rad/s].
    f_b : (n, 3) array_like
        [m/s^2].
    q_ib0 : (4,) array_like
        Initial attitude, body to inertial, **scalar first** (convert the
        source's scalar-last form with :func:`quat_from_source`).
    v_i0, r_i0 : (3,) array_like
        [m/s], [m].
    gravity_i : (3,) array_like
        Uniform gravity in the inertial frame [m/s^2]; zero in source 003.

    Returns
    -------
    InertialSolution

    References
    ----------
    Source 003 eq. 43 (quaternion), 44 (``C_b^i``); SOURCES-NOTES §1.6.
    """
    t = check_time("time", time)
    n = len(t)
    w = np.ascontiguousarray(omega_ib_b, dtype=float)
    f = np.ascontiguousarray(f_b, dtype=float)
    for name, a in (("omega_ib_b", w), ("f_b", f)):
        if a.shape != (n, 3):
            raise InputError(f"`{name}` must have shape ({n}, 3), got {a.shape}")
        if not np.isfinite(a).all():
            raise InputError(f"`{name}` has a NaN or infinite value at row {int(np.argmax(~np.isfinite(a).all(1)))}")
    q0 = np.asarray(q_ib0, float).reshape(-1)
    if q0.shape != (4,) or abs(np.linalg.norm(q0) - 1) > 1e-6:
        raise InputError(f"`q_ib0` must be a unit quaternion, scalar first, got {plain_number(q_ib0)}")
    vecs = []
    for name, x in (("v_i0", v_i0), ("r_i0", r_i0), ("gravity_i", gravity_i)):
        a = np.asarray(x, float).reshape(-1)
        if a.shape != (3,) or not np.isfinite(a).all():
            raise InputError(f"`{name}` must be three finite numbers, got {plain_number(x)}")
        vecs.append(a)
    q = np.empty((n, 4))
    v = np.empty((n, 3))
    r = np.empty((n, 3))
    _inertial_kernel(t, w, f, q0 / np.linalg.norm(q0), vecs[0], vecs[1], vecs[2], q, v, r)
    return InertialSolution(t, r, v, q)


def navigate_solution_inertial(sol: ArraySolution, **initial) -> InertialSolution:
    """:func:`navigate_inertial` with an :class:`ArraySolution`'s estimates."""
    if not sol.signed:
        raise InputError("this solution holds rate magnitudes only; it cannot be navigated")
    return navigate_inertial(sol.time, sol.omega_ib_b, sol.f_b, **initial)


def navigate_earth(sol: ArraySolution, initial: NavState, *, frame="ned", **options):
    """The core mechanization (``"ned"``, ``"wander"``, ``"ecef"``,
    ``"inertial"``) fed with the array's estimates; returns a
    :class:`~inskit.types.NavSolution`.  ``options`` go to
    :func:`inskit.strapdown.mechanize` (``coning``, ``height`` ...)."""
    return mechanize(sol.imu(), initial, frame=frame, **options)


__all__ = ["eq43_matrix", "eq44_dcm", "navigate_earth", "navigate_inertial", "navigate_solution_inertial",
           "quat_from_source", "quat_to_source"]
