"""Ideal IMU output from a reference trajectory.

References
----------
SYSTEM.md §1.4 (the NED navigation equation solved for the specific force);
Groves 2013 §5.4.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import earth
from ..earth import gravity_nd as _gravity_nd
from ..earth import principal_radii as _radii
from .. import rotations as rot
from ..types import ImuData, NavSolution, check_time

W_IE = earth.OMEGA_IE


def ideal_rates(kin, gravity="normal"):
    """True body rate ``omega_ib_b`` and specific force ``f_b`` of a motion.

    ``f_n = a_n + (2 omega_ie_n + omega_en_n) x v_n - g_n`` and
    ``omega_ib_b = C_bn (omega_ie_n + omega_en_n) + omega_nb_b``.

    Parameters
    ----------
    kin : Kinematics
    gravity : {"normal", "normal-simple", "j2"}
        The gravity model ``g_n`` (:func:`inskit.earth.gravity_n`): a
        mechanization with the same model reproduces the motion.

    Returns
    -------
    omega_ib_b, f_b : (n, 3) ndarray
        [rad/s], [m/s^2].
    """
    lat, h = kin.lla[:, 0], kin.lla[:, 2]
    w_ie = earth.rate_ie_n(lat)
    w_en = earth.rate_en_n(lat, h, kin.v_n)
    f_n = kin.a_n + np.cross(2.0 * w_ie + w_en, kin.v_n) - earth.gravity_n(lat, h, gravity)
    C_bn = np.swapaxes(kin.C_nb, -1, -2)
    f_b = np.einsum("nij,nj->ni", C_bn, f_n)
    w_ib = np.einsum("nij,nj->ni", C_bn, w_ie + w_en) + kin.omega_nb_b
    return w_ib, f_b


def _lever_arm_terms(trajectory, tq, w_ib, lever_arm_b, delta=1e-4):
    """``omega_dot x l + omega x (omega x l)`` in b: what an IMU at ``l_b`` from
    the trajectory point senses beyond the point's specific force.  The angular
    acceleration is a central difference of the exact body rate (step 0.1 ms:
    truncation ~1e-9 relative for motions below 100 Hz)."""
    l = np.asarray(lever_arm_b, float)
    wp, _ = ideal_rates(trajectory.kinematics(tq + delta))
    wm, _ = ideal_rates(trajectory.kinematics(tq - delta))
    w_dot = (wp - wm) / (2 * delta)
    return np.cross(w_dot, l) + np.cross(w_ib, np.cross(w_ib, l))


def ideal_imu(trajectory, time, *, nodes=6, t_before=None, lever_arm_b=None, gravity="normal"):
    """Exact angle and velocity increments of a trajectory.

    Each increment is the integral of the true rates over ``(t[k-1], t[k]]``
    by ``nodes``-point Gauss-Legendre quadrature (exact for polynomials of
    degree ``2 nodes - 1``; for a 1 Hz motion sampled at 100 Hz the error of six
    nodes is far below double precision).

    Parameters
    ----------
    trajectory : object with ``kinematics(t)``
    time : (n,) array_like
        Sample times [s].
    nodes : int
    t_before : float, optional
        Start of the interval of row 0; by default row 0 gets a zero increment
        (it is the initial epoch).
    lever_arm_b : (3,) array_like, optional
        IMU position relative to the trajectory point, body axes [m]: the
        accelerometers then also sense ``omega_dot x l + omega x (omega x l)``
        (the gyros sense the same rate anywhere on a rigid body).
    gravity : {"normal", "normal-simple", "j2"}
        Gravity model of the specific force (:func:`inskit.earth.gravity_n`).

    Returns
    -------
    ImuData
    """
    t = check_time("time", time)
    x, w = np.polynomial.legendre.leggauss(int(nodes))
    t0 = np.empty_like(t)
    t0[1:] = t[:-1]
    t0[0] = t[0] if t_before is None else t_before
    half = 0.5 * (t - t0)
    mid = 0.5 * (t + t0)
    tq = (mid[:, None] + half[:, None] * x[None, :]).ravel()
    earth.gravity_model_code(gravity)  # an unknown model: InputError naming the choices
    if hasattr(trajectory, "rates"):  # compiled fast path (same formulas, tested equal)
        w_ib, f_b = trajectory.rates(tq, gravity=gravity)
    else:
        w_ib, f_b = ideal_rates(trajectory.kinematics(tq), gravity)
    if lever_arm_b is not None and np.any(np.asarray(lever_arm_b, float) != 0):
        f_b = f_b + _lever_arm_terms(trajectory, tq, w_ib, lever_arm_b)
    n = len(t)
    dth = np.einsum("nj,njk->nk", np.broadcast_to(w, (n, len(w))), w_ib.reshape(n, len(w), 3)) * half[:, None]
    dv = np.einsum("nj,njk->nk", np.broadcast_to(w, (n, len(w))), f_b.reshape(n, len(w), 3)) * half[:, None]
    return ImuData(t, dth, dv)


#: the relative error of one increment of a sinusoid that :func:`max_oscillation_hz` allows
INCREMENT_TOLERANCE = 1e-3


def sinusoid_increment_error(nodes, ratio):
    """Relative error of the ``nodes``-point Gauss-Legendre increment
    (:func:`ideal_imu`) of a sinusoid of frequency ``ratio`` times the
    sample rate, over one sample interval.

    Around the interval's middle the sinusoid is ``sin(th) cos(a x) +
    cos(th) sin(a x)``, ``x`` in [-1, 1], ``a = pi ratio``; the odd part
    integrates to 0 both exactly and on the symmetric nodes, so the error is
    that of ``int cos(a x) dx = 2 sin(a) / a``, whatever the phase.
    """
    x, w = np.polynomial.legendre.leggauss(int(nodes))
    a = np.pi * float(ratio)
    if a == 0.0:
        return 0.0
    exact = 2.0 * np.sin(a) / a
    return float(abs(np.dot(w, np.cos(a * x)) / exact - 1.0))


def max_oscillation_hz(rate_hz, nodes):
    """``(limit_hz, inclusive, reason)``: the highest frequency of a motion
    (coning, oscillation, vibration) whose increments at ``rate_hz`` with
    ``nodes`` quadrature nodes (:func:`ideal_imu`) are still accurate.

    Two limits, the lower one binding:

    * the Nyquist frequency ``rate_hz / 2``, exclusive (``reason``
      ``"nyquist"``).  At or above it the increments alias: they are exact
      integrals of the motion, but one sample per half period cannot tell the
      motion from a slower one, and a mechanization of them does not
      reproduce the truth.  At ``f = rate_hz`` each increment of a sinusoid
      is close to zero whatever its amplitude; coning of 5 deg at 100 Hz on a
      100 Hz IMU drifts 154 m horizontally in 10 s in the ``--verify``
      check, at 200 Hz 21 m (and 448 m vertically).
    * the quadrature (``reason`` ``"quadrature"``): the increment of a
      sinusoid by ``nodes``-point Gauss-Legendre quadrature is within
      :data:`INCREMENT_TOLERANCE` (0.1 %) of the exact one
      (:func:`sinusoid_increment_error`; exact for polynomials of degree
      ``2 nodes - 1`` only).  From 3 nodes (the scenario default) that holds
      up to Nyquist (error 7e-4 at ``rate_hz / 2``, 1.6e-4 at 0.4 x the
      rate); 2 nodes reach 0.23 x the rate, 1 node (the midpoint) 0.025 x.

    Below both limits the ``--verify`` check does not break before Nyquist
    (measured on a 100 Hz IMU with 3 nodes): 0.5 mm of vertical vibration
    during a drive leaves 0.016 mm vertically at 10 Hz, 3 mm at 48 Hz;
    coning of 2 deg leaves 0.7 mm horizontally in 10 s at 20 Hz, 2 cm at
    48 Hz, still 6.8x smaller at twice the rate.  The errors grow smoothly
    towards Nyquist (the strapdown coning and sculling errors, which grow
    with amplitude and frequency, not a failure of the data), so no margin
    below it is needed.  Coning and heave at one frequency together scull:
    1 deg with 0.5 mm (5 g at 49 Hz) leave 7 mm horizontally in 2 s at
    20 Hz and 0.6 m at 49 Hz, growing as about f^5 and 7x smaller at twice
    the rate, a limit of the strapdown algorithm that strong enough motion
    reaches at any frequency, not one of the sampling.  With too few nodes the quadrature is what breaks
    it: the 0.5 mm at 40 Hz with 1 node (increment error 32 %) drift 1.25 m
    vertically in 30 s, with 2 nodes (1.1 %) 4.5 cm, with 3 nodes (0.016 %)
    0.9 mm.  The limits concern a motion's fundamental frequency; the
    harmonics a large coning angle adds are of second order in the angle.
    """
    rate = float(rate_hz)
    nyquist = 0.5 * rate
    if sinusoid_increment_error(nodes, 0.5) <= INCREMENT_TOLERANCE:
        return nyquist, False, "nyquist"
    lo, hi = 0.0, 0.5  # the error grows monotonically with the frequency below Nyquist: bisect
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if sinusoid_increment_error(nodes, mid) <= INCREMENT_TOLERANCE:
            lo = mid
        else:
            hi = mid
    return lo * rate, True, "quadrature"


def truth_solution(trajectory, time, *, with_rates=False, gravity="normal"):
    """The true navigation solution of a trajectory at ``time``.

    With ``with_rates`` the solution's ``extra`` also carries the rates: NED
    acceleration ``an_m_s2, ae_m_s2, ad_m_s2`` (time derivative of ``v_n``),
    the true body rate ``wx_rad_s, wy_rad_s, wz_rad_s`` (``omega_ib_b``) and
    specific force ``fx_m_s2, fy_m_s2, fz_m_s2`` (with the gravity model
    ``gravity``, :func:`ideal_rates`).  A trajectory with a
    ``navigation(t)`` method (:class:`.segments.SegmentTrajectory`) gives
    the solution without its kinematics when no rates are asked for.
    """
    navigation = getattr(trajectory, "navigation", None)
    if navigation is not None and not with_rates:  # no rates wanted: no kinematics (a third of a simulation's time)
        t, lla, v_n, q = navigation(np.asarray(time, dtype=float))
        return NavSolution(t, lla, v_n, q, {})
    both = getattr(trajectory, "navigation_and_rates", None)
    if both is not None:  # the fused kernel: navigation and rates in one pass
        t, lla, v_n, q, a_n, w_ib, f_b = both(np.asarray(time, dtype=float), gravity)
        return NavSolution(t, lla, v_n, q, _rate_columns(a_n, w_ib, f_b))
    kin = trajectory.kinematics(np.asarray(time, dtype=float))
    extra = {}
    if with_rates:
        w_ib, f_b = ideal_rates(kin, gravity)
        extra = _rate_columns(kin.a_n, w_ib, f_b)
    return NavSolution(kin.t, kin.lla, kin.v_n, rot.quat_from_dcm(kin.C_nb), extra)


def _rate_columns(a_n, w_ib, f_b):
    """The ``extra`` columns of a truth with rates (:func:`truth_solution`)."""
    extra = {}
    for j, a in enumerate("ned"):
        extra[f"a{a}_m_s2"] = a_n[:, j]
    for j, a in enumerate("xyz"):
        extra[f"w{a}_rad_s"] = w_ib[:, j]
    for j, a in enumerate("xyz"):
        extra[f"f{a}_m_s2"] = f_b[:, j]
    return extra


@njit(cache=True)
def rates_at(lat, h, vn, ve, vd, an, ae, ad, r, p, y, dr, dp, dy, gravity=0):
    """``(w_x, w_y, w_z, f_x, f_y, f_z)``: :func:`ideal_rates` at one point
    from curvilinear position, NED velocity and acceleration, and ZYX Euler
    angles with their rates: ``f_b = C_bn (a_n + (2 w_ie + w_en) x v_n - g_n)``
    and ``w_ib_b = C_bn (w_ie + w_en) + E(roll, pitch) rpy_dot`` (SYSTEM.md
    §1.4); ``g_n`` of the gravity model coded ``gravity``
    (:func:`inskit.earth.gravity_nd`).  Shared by :func:`rates_kernel` and
    the segment trajectories' fused kernel."""
    sl, cl = math.sin(lat), math.cos(lat)
    rn, re = _radii(lat, h)
    wie0, wie2 = W_IE * cl, -W_IE * sl
    wen0, wen1, wen2 = ve / re, -vn / rn, -ve * sl / cl / re
    cx, cy, cz = 2 * wie0 + wen0, wen1, 2 * wie2 + wen2
    gn, gd = _gravity_nd(lat, h, gravity)
    fn0 = an + (cy * vd - cz * ve) - gn
    fn1 = ae + (cz * vn - cx * vd)
    fn2 = ad + (cx * ve - cy * vn) - gd
    cr, sr, cp, sp, cy_, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    # C_nb rows (ZYX); C_bn = C_nb^T, so f_b[i] = sum_j C_nb[j, i] f_n[j]
    c00, c01, c02 = cp * cy_, sr * sp * cy_ - cr * sy, cr * sp * cy_ + sr * sy
    c10, c11, c12 = cp * sy, sr * sp * sy + cr * cy_, cr * sp * sy - sr * cy_
    c20, c21, c22 = -sp, sr * cp, cr * cp
    win0, win1, win2 = wie0 + wen0, wen1, wie2 + wen2
    return (c00 * win0 + c10 * win1 + c20 * win2 + dr - dy * sp,
            c01 * win0 + c11 * win1 + c21 * win2 + dp * cr + dy * sr * cp,
            c02 * win0 + c12 * win1 + c22 * win2 - dp * sr + dy * cr * cp,
            c00 * fn0 + c10 * fn1 + c20 * fn2,
            c01 * fn0 + c11 * fn1 + c21 * fn2,
            c02 * fn0 + c12 * fn1 + c22 * fn2)


@njit(cache=True)
def rates_kernel(lat, h, v_n, a_n, rpy, drpy, w_out, f_out, gravity=0):
    """Compiled :func:`ideal_rates` (:func:`rates_at` at every row, one pass,
    no temporaries) into ``w_out`` and ``f_out``."""
    for k in range(lat.shape[0]):
        w_out[k, 0], w_out[k, 1], w_out[k, 2], f_out[k, 0], f_out[k, 1], f_out[k, 2] = rates_at(
            lat[k], h[k], v_n[k, 0], v_n[k, 1], v_n[k, 2], a_n[k, 0], a_n[k, 1], a_n[k, 2],
            rpy[k, 0], rpy[k, 1], rpy[k, 2], drpy[k, 0], drpy[k, 1], drpy[k, 2], gravity)
