"""Rigid-body motions for accelerometer arrays.

An array needs, at every sample time, the specific force at the reference
point ``f_b``, the body rate ``omega_ib_b`` and its exact time derivative
``omega_dot_ib_b`` (:class:`RigidMotion`).  Three sources:

* :func:`motion_from_trajectory`: any of the simulator's Earth trajectories
  (:mod:`inskit.simulation`), whose kinematics carry the exact
  ``omega_dot_nb_b``; the Earth and transport rates are differentiated here
  in closed form.
* :class:`ConstantRateMotion`: source 003's scenario (constant body rate and
  body-frame specific force, inertial frame, no gravity) with its closed-form
  attitude, velocity and position (SOURCES-NOTES §1.7).
* :class:`HarmonicBodyMotion`: rate and specific force as sums of sinusoids in
  the body (random motions for tests, rates that cross zero).

Gravity is taken as uniform over the array: the gravity gradient (about
``3e-6 s^-2`` times the lever arm, 3e-7 m/s^2 at 0.1 m) is neither simulated
nor modelled.

References
----------
SYSTEM.md §1.4 (NED kinematics), §5; SOURCES-NOTES §1.1, §1.7.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import earth
from .. import rotations as rot
from ..errors import InputError
from ..simulation.imu import ideal_rates
from ..simulation.trajectory import radii_derivatives
from ..types import check_time


@dataclass(frozen=True)
class RigidMotion:
    """True motion of the array's reference point at sample times.

    Attributes
    ----------
    time : (n,) ndarray
        [s].
    f_b : (n, 3) ndarray
        Specific force at the reference point, body axes [m/s^2].
    omega_ib_b : (n, 3) ndarray
        Body rate relative to inertial space [rad/s].
    omega_dot_ib_b : (n, 3) ndarray
        Its time derivative (the same in body and inertial axes, since
        ``omega x omega = 0``) [rad/s^2].
    """

    time: np.ndarray
    f_b: np.ndarray
    omega_ib_b: np.ndarray
    omega_dot_ib_b: np.ndarray

    def __post_init__(self):
        t = check_time("time", self.time)
        object.__setattr__(self, "time", t)
        for name in ("f_b", "omega_ib_b", "omega_dot_ib_b"):
            a = np.ascontiguousarray(getattr(self, name), dtype=float)
            if a.shape != (len(t), 3):
                raise InputError(f"`{name}` must have shape ({len(t)}, 3), got {a.shape}")
            if not np.isfinite(a).all():
                raise InputError(f"`{name}` has a NaN or infinite value")
            object.__setattr__(self, name, a)

    def __len__(self):
        return len(self.time)


def angular_acceleration_ib_b(kin):
    """Exact ``omega_ib_b`` and ``omega_dot_ib_b`` of Earth-referenced kinematics.

    ``omega_ib_b = C_bn omega_in_n + omega_nb_b`` with
    ``omega_in_n = omega_ie_n + omega_en_n``, so (``dC_bn/dt = -[omega_nb_b x] C_bn``)

    ``omega_dot_ib_b = C_bn d(omega_in_n)/dt - omega_nb_b x (C_bn omega_in_n) + omega_dot_nb_b``,

    where ``d(omega_ie_n)/dt = W_ie [-sin L, 0, -cos L] dL/dt`` and
    ``omega_en_n = [v_E/(R_E+h), -v_N/(R_N+h), -v_E tan L/(R_E+h)]`` is
    differentiated with ``dL/dt = v_N/(R_N+h)``, ``dh/dt = -v_D`` and the
    analytic radius derivatives.

    Parameters
    ----------
    kin : Kinematics
        With ``omega_dot_nb_b`` (every simulator trajectory provides it).

    Returns
    -------
    omega_ib_b, omega_dot_ib_b : (n, 3) ndarray
        [rad/s], [rad/s^2].

    References
    ----------
    SYSTEM.md §1.4 (transport rate); Groves 2013 eq. 5.44.
    """
    if kin.omega_dot_nb_b is None:
        raise InputError("the trajectory gives no exact angular acceleration (`omega_dot_nb_b` is None)")
    lat, h = kin.lla[:, 0], kin.lla[:, 2]
    vN, vE, vD = kin.v_n[:, 0], kin.v_n[:, 1], kin.v_n[:, 2]
    aN, aE = kin.a_n[:, 0], kin.a_n[:, 1]
    rn, re = earth.principal_radii(lat, h)
    d_rn, d_re = radii_derivatives(lat)
    dlat = vN / rn
    dh = -vD
    drn = d_rn * dlat + dh
    dre = d_re * dlat + dh
    sl, cl = np.sin(lat), np.cos(lat)
    tl = sl / cl
    W = earth.OMEGA_IE
    w_in = np.column_stack([W * cl + vE / re, -vN / rn, -W * sl - vE * tl / re])
    dw_in = np.column_stack([
        -W * sl * dlat + aE / re - vE * dre / re**2,
        -aN / rn + vN * drn / rn**2,
        -W * cl * dlat - (aE * tl + vE * dlat / cl**2) / re + vE * tl * dre / re**2,
    ])
    C_bn = np.swapaxes(kin.C_nb, -1, -2)
    w_in_b = np.einsum("nij,nj->ni", C_bn, w_in)
    w_ib = w_in_b + kin.omega_nb_b
    dw_ib = np.einsum("nij,nj->ni", C_bn, dw_in) - np.cross(kin.omega_nb_b, w_in_b) + kin.omega_dot_nb_b
    return w_ib, dw_ib


def motion_from_trajectory(trajectory, time) -> RigidMotion:
    """The exact :class:`RigidMotion` of a simulator trajectory at ``time``.

    Parameters
    ----------
    trajectory : object with ``kinematics(t)``
        :class:`~inskit.simulation.HarmonicTrajectory`,
        :class:`~inskit.simulation.segments.SegmentTrajectory`, ...
    time : (n,) array_like
        [s].
    """
    t = check_time("time", time)
    kin = trajectory.kinematics(t)
    _, f_b = ideal_rates(kin)
    w, dw = angular_acceleration_ib_b(kin)
    return RigidMotion(t, f_b, w, dw)


@dataclass(frozen=True)
class InertialSolution:
    """Motion in an inertial frame i: position, velocity, attitude (a truth or
    a navigation solution).

    Attributes
    ----------
    time : (n,) ndarray
    r_i, v_i : (n, 3) ndarray
        [m], [m/s].
    q_ib : (n, 4) ndarray
        Body to inertial, scalar first.
    """

    time: np.ndarray
    r_i: np.ndarray
    v_i: np.ndarray
    q_ib: np.ndarray

    @property
    def C_ib(self):
        return rot.dcm_from_quat(self.q_ib)

    @property
    def euler(self):
        """``(n, 3)`` roll, pitch, yaw [rad] of ``C_ib`` (ZYX)."""
        return rot.euler_from_quat(self.q_ib)

    def __len__(self):
        return len(self.time)


@dataclass(frozen=True)
class ConstantRateMotion:
    """Constant body rate and constant body-frame specific force, in an
    inertial frame without gravity (source 003 §6: ``[50, 10, 10] m/s^2``,
    ``[1, 2, 3] rad/s``).

    Starting from ``C_ib(0) = I``, ``v(0) = r(0) = 0`` (unstated in the source;
    SOURCES-NOTES §1.7), with ``w = |omega|``, ``n = omega / w``,
    ``f_par = (n.f) n``, ``f_perp = f - f_par``:

    * ``C_ib(t) = exp(t [omega x])``,
    * ``v(t) = f_par t + f_perp sin(wt)/w + (n x f)(1 - cos wt)/w``,
    * ``r(t) = f_par t^2/2 + f_perp (1 - cos wt)/w^2 + (n x f)(t/w - sin(wt)/w^2)``.

    Parameters
    ----------
    omega_b : (3,) array_like
        [rad/s], non-zero.
    f_b : (3,) array_like
        [m/s^2].
    """

    omega_b: tuple = (1.0, 2.0, 3.0)
    f_b: tuple = (50.0, 10.0, 10.0)

    def __post_init__(self):
        w = np.asarray(self.omega_b, float).reshape(3)
        f = np.asarray(self.f_b, float).reshape(3)
        if not (np.isfinite(w).all() and np.isfinite(f).all()):
            raise InputError("`omega_b` and `f_b` must be finite")
        if np.linalg.norm(w) == 0:
            raise InputError("`omega_b` must be non-zero (use any trajectory for pure translation)")
        object.__setattr__(self, "omega_b", tuple(w))
        object.__setattr__(self, "f_b", tuple(f))

    def motion(self, time) -> RigidMotion:
        t = check_time("time", time)
        n = len(t)
        return RigidMotion(t, np.tile(self.f_b, (n, 1)), np.tile(self.omega_b, (n, 1)), np.zeros((n, 3)))

    def truth(self, time) -> InertialSolution:
        """Closed-form position, velocity and attitude at ``time`` [s] (``(n,)``)."""
        t = np.atleast_1d(np.asarray(time, float))
        w_vec = np.asarray(self.omega_b)
        f = np.asarray(self.f_b)
        w = np.linalg.norm(w_vec)
        n = w_vec / w
        f_par = np.dot(n, f) * n
        f_perp = f - f_par
        nxf = np.cross(n, f)
        s, c = np.sin(w * t)[:, None], np.cos(w * t)[:, None]
        tt = t[:, None]
        v = f_par * tt + f_perp * s / w + nxf * (1 - c) / w
        r = f_par * tt**2 / 2 + f_perp * (1 - c) / w**2 + nxf * (tt / w - s / w**2)
        q = rot.quat_from_rotvec(tt * w_vec)
        return InertialSolution(t, r, v, q)


@dataclass(frozen=True)
class HarmonicBodyMotion:
    """Body rate and specific force, each component ``c + sum_k A_k sin(w_k t + phi_k)``.

    Parameters
    ----------
    omega_terms, f_terms : tuple of 3 tuples
        Per axis ``(c, [(A, w, phi), ...])`` in rad/s (m/s^2), rad/s, rad.
    """

    omega_terms: tuple
    f_terms: tuple

    @staticmethod
    def _eval(t, terms):
        x = np.empty((len(t), 3))
        dx = np.empty((len(t), 3))
        for j, (c, waves) in enumerate(terms):
            x[:, j] = c
            dx[:, j] = 0.0
            for A, w, ph in waves:
                x[:, j] += A * np.sin(w * t + ph)
                dx[:, j] += A * w * np.cos(w * t + ph)
        return x, dx

    def motion(self, time) -> RigidMotion:
        t = check_time("time", time)
        w, dw = self._eval(t, self.omega_terms)
        f, _ = self._eval(t, self.f_terms)
        return RigidMotion(t, f, w, dw)

    @classmethod
    def random(cls, rng, *, rate_scale=2.0, force_scale=20.0, max_freq_hz=1.0, waves=3, offset=True):
        """A random smooth motion: per axis ``waves`` sinusoids of random
        amplitude (up to ``rate_scale`` rad/s, ``force_scale`` m/s^2), frequency
        (up to ``max_freq_hz``) and phase, plus a random constant when
        ``offset``."""
        def terms(scale):
            out = []
            for _ in range(3):
                c = rng.uniform(-scale, scale) if offset else 0.0
                ws = [(rng.uniform(0.1, 1.0) * scale / waves, 2 * np.pi * rng.uniform(0.05, max_freq_hz),
                       rng.uniform(0, 2 * np.pi)) for _ in range(waves)]
                out.append((c, ws))
            return tuple(out)

        return cls(terms(rate_scale), terms(force_scale))

    @classmethod
    def zero_crossing(cls, amplitude=(1.0, 1.5, 2.0), freq_hz=(0.11, 0.07, 0.05), f_b=(50.0, 10.0, 10.0)):
        """Sinusoidal rates ``A_i sin(2 pi f_i t + phi_i)`` that cross zero at
        different times, with a constant specific force."""
        ph = (0.3, 1.1, 2.0)
        om = tuple((0.0, [(float(a), 2 * np.pi * float(f), p)]) for a, f, p in zip(amplitude, freq_hz, ph))
        ft = tuple((float(x), []) for x in f_b)
        return cls(om, ft)


__all__ = ["ConstantRateMotion", "HarmonicBodyMotion", "InertialSolution", "RigidMotion", "angular_acceleration_ib_b",
           "motion_from_trajectory"]
