"""One-step analytic alignment of a stationary strapdown IMU (source 002).

Inputs are the mean specific force ``f_b`` (it points up at rest) and the mean
body rate ``w_b`` of a static interval; output is ``C_nb``.

Corrections to the printed equations (SYSTEM.md §4), derived and tested here
-----------------------------------------------------------------------------
* **Eq. 3 is transposed as printed.**  ``C_b^n S_b = R_n`` with
  ``S_b = [(a x w) x a, -a x w, -a]`` and ``R_n = [(g x W) x g, g x W, g]``
  gives ``C_b^n = R_n S_b^-1``; the printed ``S_b R_n^-1`` is ``C_n^b``.
* **Eq. 17/19 list the body vectors as columns,** which is again ``C_n^b``:
  after normalising, ``R_n`` is the identity (F = I in the source) and
  ``C_nb = S_b^T``: the three unit vectors are the *rows* of ``C_nb``.  Eq. 20
  and 23 likewise: ``C_nb = T_n T_b^T``.
* **Eq. 24-27** then read: the gyro-basis and accelerometer-basis matrices
  differ exactly (not only to first order) by a rotation about the navigation
  east axis, ``C_nb_w = Ry(-dphi) C_nb_a`` with ``dphi = phi' - phi`` (the
  measured minus the true latitude), because both bases share the east axis
  ``-(a x w)/|a x w|``.  The blend of eq. 27 is ``C_nb(m) = Ry(-m dphi) C_nb_a``.
* Consequence: the blend moves only the attitude error about east; the errors
  about north and down (roll-like tilt and heading) are the same for every m.

Angles: ``phi'`` is the complement of the angle between ``f_b`` and ``w_b``.
"""

from __future__ import annotations

import numpy as np

from .. import earth
from .. import rotations as rot
from ..errors import InputError

#: refuse when the gyro vector is within this angle of the vertical (poles)
MIN_COS_LAT = np.sin(np.radians(2.0))


def _unit(v, name):
    v = np.asarray(v, float)
    n = np.linalg.norm(v)
    if not np.isfinite(n) or n == 0:
        raise InputError(f"`{name}` is zero or not finite: no static specific force / rate to align with")
    return v / n


def measured_latitude(f_b, w_b):
    """``phi'``: the latitude the sensors imply (eq. 17), [rad]."""
    return float(np.arcsin(np.clip(_unit(f_b, "f_b") @ _unit(w_b, "w_b"), -1.0, 1.0)))


def _check(f_b, w_b, lat=None):
    a, w = _unit(f_b, "f_b"), _unit(w_b, "w_b")
    c = np.linalg.norm(np.cross(a, w))
    if c < MIN_COS_LAT:
        raise InputError(
            f"the gyro vector is within {np.degrees(np.arcsin(c)):.2f} deg of the vertical: north is undefined "
            "(near a pole, or a gyro error as large as the Earth rate); analytic alignment refused"
        )
    if lat is not None and abs(np.cos(lat)) < MIN_COS_LAT:
        raise InputError(f"latitude {np.degrees(lat):.2f} deg is within 2 deg of a pole: the Earth rate has no "
                         "horizontal component there; analytic alignment refused")
    return a, w


def accel_basis(f_b, w_b):
    """Accelerometer-basis estimate (eq. 17/19, rows): down = -f, east from f x w."""
    a, w = _check(f_b, w_b)
    y = -np.cross(a, w)
    y /= np.linalg.norm(y)
    z = -a
    x = np.cross(y, z)
    return np.vstack([x, y, z])


def gyro_basis(f_b, w_b, lat):
    """Gyro-basis estimate (eq. 20-23, corrected): ``T_n(lat) T_b^T``."""
    a, w = _check(f_b, w_b, lat)
    e = -np.cross(a, w)
    e /= np.linalg.norm(e)
    T_b = np.column_stack([w, e, np.cross(w, e)])
    wn = np.array([np.cos(lat), 0.0, -np.sin(lat)])
    en = np.array([0.0, 1.0, 0.0])
    T_n = np.column_stack([wn, en, np.cross(wn, en)])
    return T_n @ T_b.T


def general_analytic(f_b, w_b, lat, g=None, omega=earth.OMEGA_IE):
    """Eq. 3, corrected (``R_n S_b^-1``) with physical magnitudes; not
    orthonormal when the sensors err (use :func:`rotations.orthonormalize`)."""
    a, w = np.asarray(f_b, float), np.asarray(w_b, float)
    _check(a, w, lat)
    g = earth.gravity_down(lat, 0.0) if g is None else g
    g_n = np.array([0.0, 0.0, g])
    W_n = omega * np.array([np.cos(lat), 0.0, -np.sin(lat)])
    S_b = np.column_stack([np.cross(np.cross(a, w), a), -np.cross(a, w), -a])
    R_n = np.column_stack([np.cross(np.cross(g_n, W_n), g_n), np.cross(g_n, W_n), g_n])
    return R_n @ np.linalg.inv(S_b)


def rot_east(angle):
    """Rotation about the navigation east (y) axis."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def blend(f_b, w_b, lat, m):
    """The blended estimate of eq. 27: ``Ry(-m (phi' - phi)) C_nb_a``;
    m = 0 is the accelerometer basis, m = 1 the gyro basis."""
    C_a = accel_basis(f_b, w_b)
    _check(f_b, w_b, lat)
    return rot_east(-m * (measured_latitude(f_b, w_b) - lat)) @ C_a


def angle_errors(C_est, C_true):
    """``(alpha, beta, gamma)``: the attitude error about north, east, down [rad]."""
    return rot.attitude_error(C_est, C_true)


def criterion(C_est, C_true, weights=(1.0, 1.0, 1.0)):
    """J of eq. 28 [rad]: ``sqrt(k1 alpha^2 + k2 beta^2 + k3 gamma^2)``."""
    e = angle_errors(C_est, C_true)
    return float(np.sqrt(np.sum(np.asarray(weights) * e**2)))


def eq29(B_x, B_y, D_y, lat, g=None, omega=earth.OMEGA_IE):
    """Best error without blending (eq. 29) for given bias components [rad]:
    ``sqrt((B_y/g)^2 + (B_x/g)^2 + (D_y/(W cos phi) + B_y tan(phi)/g)^2)``."""
    g = earth.gravity_down(lat, 0.0) if g is None else g
    return float(np.sqrt((B_y / g) ** 2 + (B_x / g) ** 2 + (D_y / (omega * np.cos(lat)) + B_y * np.tan(lat) / g) ** 2))


def eq29_rms(sigma_B, sigma_D, lat, g=None, omega=earth.OMEGA_IE):
    """Expectation form of eq. 29 for independent zero-mean biases of sigma
    ``sigma_B`` (each accelerometer) and ``sigma_D`` (each gyro): the cross
    term averages out."""
    g = earth.gravity_down(lat, 0.0) if g is None else g
    return float(np.sqrt((sigma_B / g) ** 2 * (2.0 + np.tan(lat) ** 2) + (sigma_D / (omega * np.cos(lat))) ** 2))


def ideal_static(C_nb, lat, h=0.0):
    """Error-free static ``(f_b, w_b)`` for an attitude at a latitude."""
    g = earth.gravity_down(lat, h)
    f_n = np.array([0.0, 0.0, -g])
    w_n = earth.rate_ie_n(lat)
    return C_nb.T @ f_n, C_nb.T @ w_n
