"""Closed-form reference trajectories.

A trajectory is any object with ``kinematics(t) -> Kinematics`` for an array of
times: everything an ideal IMU needs, with derivatives computed analytically
(no numerical differentiation), so the sensor output is exact.  The
trajectories of this module and of :mod:`.segments` also give the exact
angular acceleration ``omega_dot_nb_b`` (the time derivative of
``omega_nb_b``), which accelerometers away from the reference point sense
(lever arms, accelerometer arrays: :mod:`inskit.gyrofree`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import earth
from .. import rotations as rot


@dataclass(frozen=True)
class Kinematics:
    """True motion at times ``t`` (each array has ``n`` rows).

    Attributes
    ----------
    t : (n,) ndarray
    lla : (n, 3) ndarray
        Latitude, longitude [rad], height [m].
    v_n : (n, 3) ndarray
        NED velocity [m/s].
    a_n : (n, 3) ndarray
        Time derivative of ``v_n`` [m/s^2] (of its NED components).
    C_nb : (n, 3, 3) ndarray
    omega_nb_b : (n, 3) ndarray
        Body rate relative to NED, resolved in b [rad/s].
    omega_dot_nb_b : (n, 3) ndarray or None
        Time derivative of the components of ``omega_nb_b`` [rad/s^2], exact
        (from the second derivatives of the attitude); ``None`` for a
        trajectory that does not provide it.
    """

    t: np.ndarray
    lla: np.ndarray
    v_n: np.ndarray
    a_n: np.ndarray
    C_nb: np.ndarray
    omega_nb_b: np.ndarray
    omega_dot_nb_b: np.ndarray | None = None


def radii_derivatives(lat):
    """``dR_N/dlat`` and ``dR_E/dlat`` [m/rad] of the WGS84 radii."""
    s, c = np.sin(lat), np.cos(lat)
    w2 = 1.0 - earth.E2 * s * s
    d_rn = 3.0 * earth.A * (1.0 - earth.E2) * earth.E2 * s * c / w2**2.5
    d_re = earth.A * earth.E2 * s * c / w2**1.5
    return d_rn, d_re


def euler_rates_to_body(rpy, drpy, ddrpy=None):
    """Body rate ``omega_nb_b`` from ZYX Euler angles and their rates and, when
    the second derivatives are given, its exact time derivative.

    ``omega_nb_b = [dr - dy sp, dp cr + dy sr cp, -dp sr + dy cr cp]``
    (r roll, p pitch, y yaw; ``sp = sin(pitch)`` ...), differentiated term by
    term.

    Parameters
    ----------
    rpy, drpy : (n, 3) ndarray
        Roll, pitch, yaw [rad] and their rates [rad/s].
    ddrpy : (n, 3) ndarray, optional
        Their second derivatives [rad/s^2].

    Returns
    -------
    omega_nb_b : (n, 3) ndarray
        [rad/s].
    omega_dot_nb_b : (n, 3) ndarray or None
        [rad/s^2]; ``None`` without ``ddrpy``.
    """
    r, p = rpy[:, 0], rpy[:, 1]
    dr, dp, dy = drpy[:, 0], drpy[:, 1], drpy[:, 2]
    sr, cr, sp, cp = np.sin(r), np.cos(r), np.sin(p), np.cos(p)
    omega = np.column_stack([dr - dy * sp, dp * cr + dy * sr * cp, -dp * sr + dy * cr * cp])
    if ddrpy is None:
        return omega, None
    ddr, ddp, ddy = ddrpy[:, 0], ddrpy[:, 1], ddrpy[:, 2]
    domega = np.column_stack([
        ddr - ddy * sp - dy * cp * dp,
        ddp * cr - dp * sr * dr + ddy * sr * cp + dy * (cr * dr * cp - sr * sp * dp),
        -ddp * sr - dp * cr * dr + ddy * cr * cp - dy * (sr * dr * cp + cr * sp * dp),
    ])
    return omega, domega


def kinematics_from_curvilinear(t, lat, lon, h, dlat, dlon, dh, ddlat, ddlon, ddh, rpy, drpy, ddrpy=None):
    """Kinematics from latitude, longitude, height and Euler angles with their
    first and second time derivatives (all analytic).

    ``v_N = (R_N+h) dlat``, ``v_E = (R_E+h) cos(lat) dlon``, ``v_D = -dh``
    (SYSTEM.md §1.4 inverted) and their exact time derivatives; body rate from
    the ZYX Euler-angle rates; with ``ddrpy`` (second derivatives of the
    Euler angles) also the exact angular acceleration ``omega_dot_nb_b``
    (:func:`euler_rates_to_body`).
    """
    rn, re = earth.principal_radii(lat, h)
    d_rn, d_re = radii_derivatives(lat)
    cl, sl = np.cos(lat), np.sin(lat)
    v_n = np.column_stack([rn * dlat, re * cl * dlon, -dh])
    a_n = np.column_stack(
        [
            d_rn * dlat**2 + dh * dlat + rn * ddlat,
            (d_re * dlat + dh) * cl * dlon - re * sl * dlat * dlon + re * cl * ddlon,
            -ddh,
        ]
    )
    omega_nb_b, omega_dot_nb_b = euler_rates_to_body(rpy, drpy, ddrpy)
    return Kinematics(t, np.column_stack([lat, lon, h]), v_n, a_n, rot.dcm_from_euler(rpy), omega_nb_b,
                      omega_dot_nb_b)


def _harmonic(t, terms):
    """Value and first two derivatives of ``c0 + c1 t + sum A sin(w t + p)``."""
    c0, c1, waves = terms
    x = c0 + c1 * t
    dx = c1 + 0.0 * t
    ddx = 0.0 * t
    for amp, w, ph in waves:
        s, c = np.sin(w * t + ph), np.cos(w * t + ph)
        x = x + amp * s
        dx = dx + amp * w * c
        ddx = ddx - amp * w * w * s
    return x, dx, ddx


@dataclass(frozen=True)
class HarmonicTrajectory:
    """Motion whose north, east, up displacements and Euler angles are each
    ``c0 + c1 t + sum_k A_k sin(w_k t + p_k)``: turns, speed changes and
    climbs in closed form.

    Parameters
    ----------
    lla0 : (3,) array_like
        Reference latitude, longitude [rad] and height [m].
    north, east, up : tuple
        ``(c0, c1, [(A, w, p), ...])`` in metres, m/s, (m, rad/s, rad);
        latitude is ``lat0 + north / R0`` and longitude
        ``lon0 + east / (R0 cos lat0)`` with ``R0 = 6378137 m`` (a definition,
        not an approximation: the trajectory is what these formulas say).
    roll, pitch, yaw : tuple
        Same form in radians.
    """

    lla0: tuple
    north: tuple = (0.0, 0.0, ())
    east: tuple = (0.0, 0.0, ())
    up: tuple = (0.0, 0.0, ())
    roll: tuple = (0.0, 0.0, ())
    pitch: tuple = (0.0, 0.0, ())
    yaw: tuple = (0.0, 0.0, ())

    def kinematics(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        lat0, lon0, h0 = self.lla0
        r0 = earth.A
        n, dn, ddn = _harmonic(t, self.north)
        e, de, dde = _harmonic(t, self.east)
        u, du, ddu = _harmonic(t, self.up)
        ke = 1.0 / (r0 * np.cos(lat0))
        ang = [_harmonic(t, a) for a in (self.roll, self.pitch, self.yaw)]
        rpy = np.column_stack([a[0] for a in ang])
        drpy = np.column_stack([a[1] for a in ang])
        ddrpy = np.column_stack([a[2] for a in ang])
        return kinematics_from_curvilinear(
            t, lat0 + n / r0, lon0 + e * ke, h0 + u, dn / r0, de * ke, du, ddn / r0, dde * ke, ddu, rpy, drpy,
            ddrpy
        )


def StationaryTrajectory(lla, rpy=(0.0, 0.0, 0.0)):
    """A vehicle at rest on the Earth with a fixed attitude."""
    return HarmonicTrajectory(
        tuple(lla), roll=(rpy[0], 0.0, ()), pitch=(rpy[1], 0.0, ()), yaw=(rpy[2], 0.0, ())
    )


@dataclass(frozen=True)
class ConingTrajectory:
    """A stationary vehicle whose body performs classical coning motion.

    ``C_nb(t) = C_nb0 @ C_c(t)`` with ``C_c(t) = Rz(W t) Rx(a) Rz(-W t)``: a
    rotation by the half-angle ``a`` about an axis that turns in the body xy
    plane at ``W = 2 pi frequency``.  The body rate is, in closed form,
    ``W [-sin a sin Wt, sin a cos Wt, cos a - 1]`` (angular acceleration
    ``W^2 [-sin a cos Wt, -sin a sin Wt, 0]``); its integral over an
    interval is given by :meth:`coning_increment`.
    """

    lla: tuple
    rpy0: tuple = (0.0, 0.0, 0.0)
    half_angle: float = np.radians(1.0)
    frequency: float = 1.0

    def _cone(self, t):
        w = 2.0 * np.pi * self.frequency
        a = self.half_angle
        axis = np.column_stack([np.cos(w * t), np.sin(w * t), 0.0 * t])
        return rot.dcm_from_rotvec(a * axis)

    def kinematics(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        n = len(t)
        w = 2.0 * np.pi * self.frequency
        a = self.half_angle
        C0 = rot.dcm_from_euler(np.asarray(self.rpy0, dtype=float))
        omega = w * np.column_stack([-np.sin(a) * np.sin(w * t), np.sin(a) * np.cos(w * t),
                                     np.full(n, np.cos(a) - 1.0)])
        domega = w * w * np.column_stack([-np.sin(a) * np.cos(w * t), -np.sin(a) * np.sin(w * t), np.zeros(n)])
        lla = np.tile(np.asarray(self.lla, dtype=float), (n, 1))
        z = np.zeros((n, 3))
        return Kinematics(t, lla, z, z, C0 @ self._cone(t), omega, domega)

    def coning_increment(self, t0, t1):
        """Closed-form integral of the coning body rate over ``(t0, t1]`` [rad]."""
        w = 2.0 * np.pi * self.frequency
        a = self.half_angle
        return np.column_stack(
            [np.sin(a) * (np.cos(w * t1) - np.cos(w * t0)), np.sin(a) * (np.sin(w * t1) - np.sin(w * t0)),
             w * (np.cos(a) - 1.0) * (t1 - t0)]
        )
