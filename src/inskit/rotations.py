"""Attitude math: DCM, quaternion, Euler angles, rotation vector.

One convention, stated once (see :mod:`inskit`):

* ``C_ab`` maps vectors from frame b to frame a: ``x_a = C_ab @ x_b``.
* Quaternions are ``[q0, q1, q2, q3]`` (scalar first), Hamilton product;
  ``q_ab`` represents the same rotation as ``C_ab``.
* Euler angles are ``[roll, pitch, yaw]`` of the ZYX sequence:
  ``C_nb = Rz(yaw) @ Ry(pitch) @ Rx(roll)``.
* A rotation vector ``phi`` (axis times angle) gives ``C = exp([phi x])``.

Every function takes a single item (``(3,)``, ``(4,)``, ``(3, 3)``) or a batch
(``(n, 3)``, ``(n, 4)``, ``(n, 3, 3)``) and returns the same batch shape.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numba.extending import register_jitable


# --- scalar core ------------------------------------------------------------------
# One implementation of each primitive, written with arithmetic and numpy
# ufuncs only and marked ``register_jitable``: the compiled kernels
# (strapdown, integration) inline them on scalars, and the batch functions
# below call them on whole arrays.  (As :mod:`inskit.earth` does.)
@register_jitable
def qmul(a0, a1, a2, a3, b0, b1, b2, b3):
    """Hamilton product ``a * b`` of two quaternions given by components."""
    return (a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
            a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
            a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
            a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0)


@register_jitable
def rotvec_quat(x, y, z):
    """Quaternion of the rotation vector ``(x, y, z)`` [rad] (scalars), exact
    at any angle: ``[cos(a/2), sin(a/2)/a * phi]``, with the series of both
    below ``a = 1e-8`` (their error there is below 1e-33).  Batches go through
    :func:`quat_from_rotvec`, which runs this in a compiled loop."""
    a2 = x * x + y * y + z * z
    if a2 < 1e-16:
        k = 0.5 - a2 / 48.0
        return 1.0 - a2 / 8.0, k * x, k * y, k * z
    a = np.sqrt(a2)
    k = np.sin(0.5 * a) / a
    return np.cos(0.5 * a), k * x, k * y, k * z


@register_jitable
def euler_quat(roll, pitch, yaw):
    """``q_nb`` of the ZYX Euler angles [rad] (scalars, or arrays of one
    shape), scalar part >= 0: the half-angle products, a unit quaternion to
    rounding (no normalisation).  Batches go through :func:`quat_from_euler`."""
    cr, sr = np.cos(0.5 * roll), np.sin(0.5 * roll)
    cp, sp = np.cos(0.5 * pitch), np.sin(0.5 * pitch)
    cy, sy = np.cos(0.5 * yaw), np.sin(0.5 * yaw)
    q0 = cr * cp * cy + sr * sp * sy
    sgn = 1.0 - 2.0 * (q0 < 0.0)
    return (sgn * q0, sgn * (sr * cp * cy - cr * sp * sy), sgn * (cr * sp * cy + sr * cp * sy),
            sgn * (cr * cp * sy - sr * sp * cy))


@njit(cache=True)
def _rotvec_quat_rows(phi, out):
    for i in range(phi.shape[0]):
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = rotvec_quat(phi[i, 0], phi[i, 1], phi[i, 2])


@register_jitable
def quat_dcm(q0, q1, q2, q3):
    """The nine entries ``C00, C01, .., C22`` of the DCM of ``q`` (row major)."""
    return (q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3, 2.0 * (q1 * q2 - q0 * q3), 2.0 * (q1 * q3 + q0 * q2),
            2.0 * (q1 * q2 + q0 * q3), q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3, 2.0 * (q2 * q3 - q0 * q1),
            2.0 * (q1 * q3 - q0 * q2), 2.0 * (q2 * q3 + q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3)


@register_jitable
def quat_rot(q0, q1, q2, q3, v0, v1, v2):
    """``C(q) v`` for a unit quaternion, without forming the DCM."""
    tx = 2.0 * (q2 * v2 - q3 * v1)
    ty = 2.0 * (q3 * v0 - q1 * v2)
    tz = 2.0 * (q1 * v1 - q2 * v0)
    return (v0 + q0 * tx + q2 * tz - q3 * ty,
            v1 + q0 * ty + q3 * tx - q1 * tz,
            v2 + q0 * tz + q1 * ty - q2 * tx)


def skew(v):
    """Skew-symmetric matrix ``[v x]`` so that ``skew(a) @ b == cross(a, b)``.

    Parameters
    ----------
    v : (3,) or (n, 3) array_like

    Returns
    -------
    (3, 3) or (n, 3, 3) ndarray
    """
    v = np.asarray(v, dtype=float)
    if v.shape == (3,):
        x, y, w = v
        return np.array([[0.0, -w, y], [w, 0.0, -x], [-y, x, 0.0]])
    z = np.zeros_like(v[..., 0])
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    return np.stack(
        [np.stack([z, -w, y], -1), np.stack([w, z, -x], -1), np.stack([-y, x, z], -1)], -2
    )


def unskew(m):
    """Vector of a skew-symmetric matrix (the antisymmetric part's axial vector)."""
    m = np.asarray(m, dtype=float)
    return 0.5 * np.stack(
        [m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0], m[..., 1, 0] - m[..., 0, 1]], -1
    )


# --- Euler angles --------------------------------------------------------------
def dcm_from_euler(rpy):
    """``C_nb`` from ``[roll, pitch, yaw]`` [rad] of a ZYX rotation."""
    rpy = np.asarray(rpy, dtype=float)
    cr, sr = np.cos(rpy[..., 0]), np.sin(rpy[..., 0])
    cp, sp = np.cos(rpy[..., 1]), np.sin(rpy[..., 1])
    cy, sy = np.cos(rpy[..., 2]), np.sin(rpy[..., 2])
    return np.stack(
        [
            np.stack([cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy], -1),
            np.stack([cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy], -1),
            np.stack([-sp, sr * cp, cr * cp], -1),
        ],
        -2,
    )


def euler_from_dcm(C_nb):
    """``[roll, pitch, yaw]`` [rad] from ``C_nb``; yaw in (-pi, pi].

    At pitch = +-90 deg roll and yaw are not separable; roll is then reported
    as 0 and the combined rotation goes to yaw.
    """
    C = np.asarray(C_nb, dtype=float)
    pitch = np.arcsin(np.clip(-C[..., 2, 0], -1.0, 1.0))
    roll = np.arctan2(C[..., 2, 1], C[..., 2, 2])
    yaw = np.arctan2(C[..., 1, 0], C[..., 0, 0])
    gimbal = np.hypot(C[..., 2, 1], C[..., 2, 2]) < 1e-12
    if np.any(gimbal):
        roll = np.where(gimbal, 0.0, roll)
        yaw = np.where(gimbal, np.arctan2(-C[..., 0, 1], C[..., 1, 1]), yaw)
    return np.stack([roll, pitch, yaw], -1)


# --- quaternions ------------------------------------------------------------------
def quat_multiply(p, q):
    """Hamilton product ``p * q`` (so ``q_ac = quat_multiply(q_ab, q_bc)``)."""
    p = np.asarray(p, dtype=float)
    q = np.asarray(q, dtype=float)
    if p.shape == (4,) and q.shape == (4,):
        return np.array(qmul(*p.tolist(), *q.tolist()))
    return np.stack(np.broadcast_arrays(*qmul(p[..., 0], p[..., 1], p[..., 2], p[..., 3],
                                              q[..., 0], q[..., 1], q[..., 2], q[..., 3])), -1)


def quat_conjugate(q):
    """Conjugate (the inverse of a unit quaternion): ``q_ba`` from ``q_ab``."""
    q = np.asarray(q, dtype=float)
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def quat_normalize(q):
    """Unit quaternion with a non-negative scalar part."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., :1] < 0.0, -q, q)


def quat_blend(q0, q1, w):
    """Normalised linear blend ``(1 - w) q0 + w q1`` of unit quaternions,
    the shorter way round (``q1`` negated where ``q0 . q1 < 0``): the
    interpolation of attitude between two samples (single ``(4,)`` or
    batched ``(n, 4)`` with ``w`` scalar or ``(n,)``)."""
    q0, q1 = np.asarray(q0, dtype=float), np.asarray(q1, dtype=float)
    w = np.asarray(w, dtype=float)[..., None]
    q1 = np.where((np.sum(q0 * q1, axis=-1) < 0)[..., None], -q1, q1)
    q = q0 * (1 - w) + q1 * w
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def dcm_from_quat(q):
    """DCM ``C_ab`` from the unit quaternion ``q_ab``."""
    q = np.asarray(q, dtype=float)
    if q.shape == (4,):  # one quaternion (called per filter update): no stacking
        return np.array(quat_dcm(float(q[0]), float(q[1]), float(q[2]), float(q[3]))).reshape(3, 3)
    c = quat_dcm(q[..., 0], q[..., 1], q[..., 2], q[..., 3])
    return np.stack(c, -1).reshape(q.shape[:-1] + (3, 3))


def quat_from_dcm(C):
    """Unit quaternion (scalar part >= 0) from a DCM, by Shepperd's method."""
    C = np.asarray(C, dtype=float)
    tr = C[..., 0, 0] + C[..., 1, 1] + C[..., 2, 2]
    # four candidate solutions; pick the numerically largest denominator
    cand = np.stack([tr, C[..., 0, 0], C[..., 1, 1], C[..., 2, 2]], -1)
    k = np.argmax(cand, axis=-1)
    c = C
    s0 = 2.0 * np.sqrt(np.maximum(1.0 + tr, 0.0))
    s1 = 2.0 * np.sqrt(np.maximum(1.0 + 2.0 * c[..., 0, 0] - tr, 0.0))
    s2 = 2.0 * np.sqrt(np.maximum(1.0 + 2.0 * c[..., 1, 1] - tr, 0.0))
    s3 = 2.0 * np.sqrt(np.maximum(1.0 + 2.0 * c[..., 2, 2] - tr, 0.0))
    d21, d02, d10 = c[..., 2, 1] - c[..., 1, 2], c[..., 0, 2] - c[..., 2, 0], c[..., 1, 0] - c[..., 0, 1]
    a01, a02, a12 = c[..., 0, 1] + c[..., 1, 0], c[..., 0, 2] + c[..., 2, 0], c[..., 1, 2] + c[..., 2, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        cands = np.stack(
            [
                np.stack([0.25 * s0, d21 / s0, d02 / s0, d10 / s0], -1),
                np.stack([d21 / s1, 0.25 * s1, a01 / s1, a02 / s1], -1),
                np.stack([d02 / s2, a01 / s2, 0.25 * s2, a12 / s2], -1),
                np.stack([d10 / s3, a02 / s3, a12 / s3, 0.25 * s3], -1),
            ],
            -2,
        )
    q = np.take_along_axis(cands, k[..., None, None], axis=-2)[..., 0, :]
    return quat_normalize(q)


def quat_from_rotvec(phi):
    """Unit quaternion of the rotation vector ``phi`` [rad] (exact at any angle)."""
    phi = np.asarray(phi, dtype=float)
    if phi.shape == (3,):
        return np.array(rotvec_quat(float(phi[0]), float(phi[1]), float(phi[2])))
    flat = np.ascontiguousarray(phi.reshape(-1, 3))
    out = np.empty((flat.shape[0], 4))
    _rotvec_quat_rows(flat, out)
    return out.reshape(phi.shape[:-1] + (4,))


def rotvec_from_quat(q):
    """Rotation vector [rad] (angle in [0, pi]) of a unit quaternion."""
    q = quat_normalize(q)
    s = np.linalg.norm(q[..., 1:], axis=-1)
    a = 2.0 * np.arctan2(s, q[..., 0])
    small = s < 1e-8
    with np.errstate(invalid="ignore", divide="ignore"):
        k = np.where(small, 2.0 / np.maximum(q[..., 0], 1e-300) * (1.0 + s * s / 6.0), a / np.where(small, 1.0, s))
    return k[..., None] * q[..., 1:]


def dcm_from_rotvec(phi):
    """DCM ``exp([phi x])`` of a rotation vector [rad] (Rodrigues)."""
    return dcm_from_quat(quat_from_rotvec(phi))


def rotvec_from_dcm(C):
    """Rotation vector [rad] of a DCM."""
    return rotvec_from_quat(quat_from_dcm(C))


def quat_from_euler(rpy):
    """``q_nb`` from ``[roll, pitch, yaw]`` [rad] (ZYX), scalar part >= 0
    (:func:`euler_quat` on every row).

    The half-angle products are a unit quaternion to rounding, so no
    normalisation (a third of the time of an hour of truth at 100 Hz)."""
    rpy = np.asarray(rpy, dtype=float)
    q = np.empty(rpy.shape[:-1] + (4,))
    q[..., 0], q[..., 1], q[..., 2], q[..., 3] = euler_quat(rpy[..., 0], rpy[..., 1], rpy[..., 2])
    return q


def euler_from_quat(q):
    """``[roll, pitch, yaw]`` [rad] from ``q_nb``: :func:`euler_from_dcm` of
    :func:`dcm_from_quat`, from the five DCM entries it reads (the same
    expressions, so the same numbers), the other two only at gimbal lock."""
    q = np.asarray(q, dtype=float)
    q0, q1, q2, q3 = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    c20 = 2.0 * (q1 * q3 - q0 * q2)
    c21 = 2.0 * (q2 * q3 + q0 * q1)
    c22 = q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3
    out = np.empty(q.shape[:-1] + (3,))
    out[..., 0] = np.arctan2(c21, c22)
    out[..., 1] = np.arcsin(np.clip(-c20, -1.0, 1.0))
    out[..., 2] = np.arctan2(2.0 * (q1 * q2 + q0 * q3), q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3)
    gimbal = np.hypot(c21, c22) < 1e-12
    if np.any(gimbal):
        c01 = 2.0 * (q1 * q2 - q0 * q3)
        c11 = q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3
        out[..., 0] = np.where(gimbal, 0.0, out[..., 0])
        out[..., 2] = np.where(gimbal, np.arctan2(-c01, c11), out[..., 2])
    return out


def quat_rotate(q, v):
    """Rotate vectors: ``C(q) @ v`` for ``q_ab`` and ``v_b``, returning ``v_a``."""
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    return np.stack(np.broadcast_arrays(*quat_rot(q[..., 0], q[..., 1], q[..., 2], q[..., 3],
                                                  v[..., 0], v[..., 1], v[..., 2])), -1)


def orthonormalize(C):
    """Nearest rotation matrix (in the Frobenius sense) by SVD."""
    u, _, vt = np.linalg.svd(np.asarray(C, dtype=float))
    return u @ vt


def attitude_error(C_est, C_true):
    """Small-angle attitude error ``psi`` [rad], resolved in the reference frame.

    ``C_est = (I - [psi x]) C_true`` to first order, i.e. ``psi`` is the
    rotation vector of ``C_true @ C_est.T``; exact for any angle.
    """
    return rotvec_from_dcm(np.asarray(C_true) @ np.swapaxes(np.asarray(C_est), -1, -2))


def wrap_angle(a):
    """Wrap angles [rad] into (-pi, pi]."""
    a = np.asarray(a, dtype=float)
    return -((-a + np.pi) % (2.0 * np.pi) - np.pi)
