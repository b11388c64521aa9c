"""Compiled per-epoch loops of the strapdown mechanizations.

Hand-written (numba) because they run once per IMU sample: hours of 100-200
Hz data must integrate in seconds.  Nothing here allocates inside the loop;
small vectors live in scratch arrays made before it.

Conventions of every kernel
---------------------------
* ``t[k]`` are sample times; ``dth[k]``, ``dv[k]`` are the angle and velocity
  increments over ``(t_prev, t[k]]`` where ``t_prev`` is ``t[k-1]`` (or the
  carried time for the first sample of a chunk).
* ``start`` is 1 when row 0 is the initial epoch (its increments unused) and 0
  when the chunk continues a run.
* ``carry`` (float64, 11): ``[t_prev, has_prev, dth_prev(3), dv_prev(3),
  dvel_prev(3)]``: what the two-sample algorithms and the midpoint
  extrapolation need from the previous step.  Updated in place.
* The navigation state arrays passed in are updated in place to the state at
  the last sample, so a later chunk continues seamlessly.

Algorithms (SYSTEM.md §1.2, §1.4; Savage, *Strapdown Analytics*, 2000,
ch. 7; Groves 2013 §5.5): two-sample coning ``phi = dth + dth_prev x dth / 12``
and sculling ``(dth_prev x dv + dv_prev x dth) / 12`` for a constant-rate-of-
change of the rates, the rotation correction ``dth x dv / 2``, the rotation of
the navigation frame over the interval ``-zeta x (C dv) / 2``, gravity, Earth and
transport rates evaluated at the interval midpoint, trapezoidal position.

Gravity: every kernel takes ``gravity``, the integer code of the model
(:data:`inskit.earth.GRAVITY_MODELS`; 0, the full normal gravity, by default)
and evaluates it through :func:`inskit.earth.gravity_nd` (local-level frames)
or :func:`inskit.earth.gravity_ecef_model` (ECEF and inertial).
"""

from __future__ import annotations

import math

from numba import njit

from .. import earth
from ..earth import gravity_ecef_model as _gravity_ecef
from ..earth import gravity_nd as _gravity_nd
from ..earth import principal_radii as _radii
from ..rotations import qmul, quat_rot, rotvec_quat

W_IE = earth.OMEGA_IE
HEIGHT_FREE = 0
HEIGHT_HOLD = 1
HEIGHT_AID = 2


@njit(cache=True, inline="always")
def store_unit(q, r0, r1, r2, r3):
    """Write the normalised quaternion ``(r0..r3)`` into ``q``."""
    inv = 1.0 / math.sqrt(r0 * r0 + r1 * r1 + r2 * r2 + r3 * r3)
    q[0], q[1], q[2], q[3] = r0 * inv, r1 * inv, r2 * inv, r3 * inv


@njit(cache=True, inline="always")
def coning_sculling(d0, d1, d2, u0, u1, u2, carry, coning):
    """Compensated rotation vector and velocity increment of one interval.

    Rotation correction ``dth x dv / 2`` always; with ``coning`` and a
    previous interval in ``carry``, two-sample coning ``dth_prev x dth / 12``
    and sculling ``(dth_prev x dv + dv_prev x dth) / 12`` (Savage 2000 §7;
    SYSTEM.md §1.4).  Shared by all four mechanizations and the filter.

    Returns
    -------
    phi0, phi1, phi2, c0, c1, c2 : float
        Rotation vector [rad] and velocity increment [m/s] in body axes.
    """
    phi0, phi1, phi2 = d0, d1, d2
    c0 = u0 + 0.5 * (d1 * u2 - d2 * u1)
    c1 = u1 + 0.5 * (d2 * u0 - d0 * u2)
    c2 = u2 + 0.5 * (d0 * u1 - d1 * u0)
    if coning and carry[1] > 0.0:
        p0, p1, p2 = carry[2], carry[3], carry[4]
        w0, w1, w2 = carry[5], carry[6], carry[7]
        phi0 += (p1 * d2 - p2 * d1) / 12.0
        phi1 += (p2 * d0 - p0 * d2) / 12.0
        phi2 += (p0 * d1 - p1 * d0) / 12.0
        c0 += ((p1 * u2 - p2 * u1) + (w1 * d2 - w2 * d1)) / 12.0
        c1 += ((p2 * u0 - p0 * u2) + (w2 * d0 - w0 * d2)) / 12.0
        c2 += ((p0 * u1 - p1 * u0) + (w0 * d1 - w1 * d0)) / 12.0
    return phi0, phi1, phi2, c0, c1, c2


@njit(cache=True, inline="always")
def remember(d0, d1, d2, u0, u1, u2, e0, e1, e2, carry):
    """Keep this interval's increments and velocity change for the next one."""
    carry[1] = 1.0
    carry[2], carry[3], carry[4] = d0, d1, d2
    carry[5], carry[6], carry[7] = u0, u1, u2
    carry[8], carry[9], carry[10] = e0, e1, e2


@njit(cache=True, inline="always")
def ned_step(dth, dv, dt, lla, v_n, q_nb, carry, coning, height_mode, h_ref, h_gains, gravity=0):
    """One NED mechanization step over an interval of length ``dt``, in place.

    ``gravity`` is the code of the gravity model (:func:`inskit.earth.gravity_nd`).

    ``lla``, ``v_n``, ``q_nb`` and ``carry`` advance to the interval's end.
    Intermediate quantities are scalars, not scratch arrays, so the compiler
    keeps them in registers (passing scratch arrays in cost 30 % of the speed:
    it cannot prove they do not alias the state).  (SYSTEM.md §1.4, source 000
    eq. 1-37..42.)
    """
    d0, d1, d2 = dth[0], dth[1], dth[2]
    u0, u1, u2 = dv[0], dv[1], dv[2]
    phi0, phi1, phi2, c0, c1, c2 = coning_sculling(d0, d1, d2, u0, u1, u2, carry, coning)
    has_prev = carry[1] > 0.0
    lat, lon, h = lla[0], lla[1], lla[2]
    v0, v1, v2 = v_n[0], v_n[1], v_n[2]
    # midpoint extrapolation of velocity and position for the rates
    if has_prev:
        m0, m1, m2 = v0 + 0.5 * carry[8], v1 + 0.5 * carry[9], v2 + 0.5 * carry[10]
    else:
        m0, m1, m2 = v0, v1, v2
    rn, re = _radii(lat, h)
    hm = h - 0.5 * dt * m2
    latm = lat + 0.5 * dt * m0 / rn
    rn, re = _radii(latm, hm)
    sl, cl = math.sin(latm), math.cos(latm)
    wie_n, wie_d = W_IE * cl, -W_IE * sl
    wen_n, wen_e, wen_d = m1 / re, -m0 / rn, -m1 * sl / cl / re
    z0 = (wie_n + wen_n) * dt
    z1 = wen_e * dt
    z2 = (wie_d + wen_d) * dt
    # specific-force velocity increment in n: (I - [zeta x]/2) C_nb dvc
    q0, q1, q2, q3 = q_nb[0], q_nb[1], q_nb[2], q_nb[3]
    f0, f1, f2 = quat_rot(q0, q1, q2, q3, c0, c1, c2)
    gn, gd = _gravity_nd(latm, hm, gravity)
    # Coriolis and centripetal: (2 w_ie + w_en) x v_mid
    cx = 2.0 * wie_n + wen_n
    cy = wen_e
    cz = 2.0 * wie_d + wen_d
    dv0 = f0 - 0.5 * (z1 * f2 - z2 * f1) + (gn - (cy * m2 - cz * m1)) * dt
    dv1 = f1 - 0.5 * (z2 * f0 - z0 * f2) - (cz * m0 - cx * m2) * dt
    dv2 = f2 - 0.5 * (z0 * f1 - z1 * f0) + (gd - (cx * m1 - cy * m0)) * dt
    n0, n1, n2 = v0 + dv0, v1 + dv1, v2 + dv2
    # height channel
    if height_mode == HEIGHT_HOLD:
        n2 = -(h_ref - h) / dt
        hnew = h_ref
    else:
        hnew = h - 0.5 * (v2 + n2) * dt
        if height_mode == HEIGHT_AID:
            err = hnew - h_ref
            hnew -= h_gains[0] * err * dt
            n2 += h_gains[1] * err * dt
    hm = 0.5 * (h + hnew)
    rn, re = _radii(latm, hm)
    latnew = lat + 0.5 * (v0 + n0) * dt / rn
    latm = 0.5 * (lat + latnew)
    rn, re = _radii(latm, hm)
    sl, cl = math.sin(latm), math.cos(latm)
    lonnew = lon + 0.5 * (v1 + n1) * dt / (re * cl)
    # attitude: q_nb <- q(-zeta) * q_nb * q(phi), zeta at the true midpoint
    vme = 0.5 * (v1 + n1)
    vmn = 0.5 * (v0 + n0)
    z0 = (W_IE * cl + vme / re) * dt
    z1 = -vmn / rn * dt
    z2 = (-W_IE * sl - vme * sl / cl / re) * dt
    a0, a1, a2, a3 = rotvec_quat(phi0, phi1, phi2)
    b0, b1, b2, b3 = qmul(q0, q1, q2, q3, a0, a1, a2, a3)  # q_nb * q(phi)
    a0, a1, a2, a3 = rotvec_quat(-z0, -z1, -z2)
    r0, r1, r2, r3 = qmul(a0, a1, a2, a3, b0, b1, b2, b3)  # q(-zeta) * ...
    store_unit(q_nb, r0, r1, r2, r3)
    v_n[0], v_n[1], v_n[2] = n0, n1, n2
    lla[0], lla[1], lla[2] = latnew, lonnew, hnew
    carry[0] += dt
    remember(d0, d1, d2, u0, u1, u2, n0 - v0, n1 - v1, n2 - v2, carry)


@njit(cache=True, inline="always")
def start_rows(start, t0, a, b, q, a_out, b_out, q_out, carry):
    """Row 0 is the initial state when ``start`` is 1: write it, reset the carry."""
    if start == 1:
        for i in range(3):
            a_out[0, i] = a[i]
            b_out[0, i] = b[i]
        for i in range(4):
            q_out[0, i] = q[i]
        carry[0] = t0
        carry[1] = 0.0


@njit(cache=True)
def ned_kernel(t, dth_all, dv_all, start, lla, v_n, q_nb, carry, coning,
               height_mode, h_ref, h_gains, lla_out, v_out, q_out, gravity=0):
    """Local-level NED mechanization (SYSTEM.md §1.4, source 000 eq. 1-37..42)."""
    n = t.shape[0]
    start_rows(start, t[0], lla, v_n, q_nb, lla_out, v_out, q_out, carry)
    for k in range(start, n):
        dt = t[k] - carry[0]
        href = h_ref[k] if height_mode != HEIGHT_FREE else 0.0
        ned_step(dth_all[k], dv_all[k], dt, lla, v_n, q_nb, carry, coning, height_mode, href, h_gains, gravity)
        carry[0] = t[k]
        for i in range(3):
            lla_out[k, i] = lla[i]
            v_out[k, i] = v_n[i]
        for i in range(4):
            q_out[k, i] = q_nb[i]


@njit(cache=True)
def wander_kernel(t, dth_all, dv_all, start, q_ew, h_arr, v_w, q_wb, carry, coning,
                  q_ew_out, h_out, v_out, q_out, gravity=0):
    """Wander-azimuth mechanization (SYSTEM.md §1.1 block diagram).

    The wander frame w is NED turned about down by the wander angle alpha; its
    transport rate has no vertical component, so nothing is singular at the
    poles.  Position is the quaternion ``q_ew`` (Earth-to-wander DCM) plus
    height; ``q_ew`` is updated with ``d/dt C_ew = C_ew [rho_w x]``.
    """
    n = t.shape[0]
    if start == 1:
        for i in range(4):
            q_ew_out[0, i] = q_ew[i]
            q_out[0, i] = q_wb[i]
        for i in range(3):
            v_out[0, i] = v_w[i]
        h_out[0] = h_arr[0]
        carry[0] = t[0]
        carry[1] = 0.0
    for k in range(start, n):
        dt = t[k] - carry[0]
        d0, d1, d2 = dth_all[k, 0], dth_all[k, 1], dth_all[k, 2]
        u0, u1, u2 = dv_all[k, 0], dv_all[k, 1], dv_all[k, 2]
        h = h_arr[0]
        phi0, phi1, phi2, c0, c1, c2 = coning_sculling(d0, d1, d2, u0, u1, u2, carry, coning)
        m0, m1, m2 = v_w[0], v_w[1], v_w[2]
        if carry[1] > 0.0:
            m0 += 0.5 * carry[8]
            m1 += 0.5 * carry[9]
            m2 += 0.5 * carry[10]
        # third row of C_ew = [cos(lat) cos(a), -cos(lat) sin(a), -sin(lat)]
        q0, q1, q2, q3 = q_ew[0], q_ew[1], q_ew[2], q_ew[3]
        c20 = 2.0 * (q1 * q3 - q0 * q2)
        c21 = 2.0 * (q2 * q3 + q0 * q1)
        c22 = q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3
        lat = math.asin(min(1.0, max(-1.0, -c22)))
        alpha = math.atan2(-c21, c20)
        hm = h - 0.5 * dt * m2
        rn, re = _radii(lat, hm)
        ca, sa = math.cos(alpha), math.sin(alpha)
        # rho_w = Rz(-a) [vE/re, -vN/rn] with v_n = Rz(a) v_w
        vn_ = ca * m0 - sa * m1
        ve_ = sa * m0 + ca * m1
        rx_n, ry_n = ve_ / re, -vn_ / rn
        rho0 = ca * rx_n + sa * ry_n
        rho1 = -sa * rx_n + ca * ry_n
        wie0, wie1, wie2 = W_IE * c20, W_IE * c21, W_IE * c22
        z0 = (wie0 + rho0) * dt
        z1 = (wie1 + rho1) * dt
        z2 = wie2 * dt
        f0, f1, f2 = quat_rot(q_wb[0], q_wb[1], q_wb[2], q_wb[3], c0, c1, c2)
        gn, gd = _gravity_nd(lat, hm, gravity)
        cx, cy, cz = 2.0 * wie0 + rho0, 2.0 * wie1 + rho1, 2.0 * wie2
        e0 = f0 - 0.5 * (z1 * f2 - z2 * f1) + (ca * gn - (cy * m2 - cz * m1)) * dt
        e1 = f1 - 0.5 * (z2 * f0 - z0 * f2) + (-sa * gn - (cz * m0 - cx * m2)) * dt
        e2 = f2 - 0.5 * (z0 * f1 - z1 * f0) + (gd - (cx * m1 - cy * m0)) * dt
        n0, n1, n2 = v_w[0] + e0, v_w[1] + e1, v_w[2] + e2
        hnew = h - 0.5 * (v_w[2] + n2) * dt
        hm = 0.5 * (h + hnew)
        rn, re = _radii(lat, hm)
        # transport rate over the step from the mean velocity
        vx, vy = 0.5 * (v_w[0] + n0), 0.5 * (v_w[1] + n1)
        vn_ = ca * vx - sa * vy
        ve_ = sa * vx + ca * vy
        rx_n, ry_n = ve_ / re, -vn_ / rn
        rho0 = (ca * rx_n + sa * ry_n) * dt
        rho1 = (-sa * rx_n + ca * ry_n) * dt
        # q_ew <- q_ew * q(rho dt)
        a0, a1, a2, a3 = rotvec_quat(rho0, rho1, 0.0)
        r0, r1, r2, r3 = qmul(q0, q1, q2, q3, a0, a1, a2, a3)
        store_unit(q_ew, r0, r1, r2, r3)
        # Earth rate on the midpoint frame: C_we at the midpoint, third row
        q0, q1, q2, q3 = q_ew[0], q_ew[1], q_ew[2], q_ew[3]
        z0 = 0.5 * (wie0 + W_IE * 2.0 * (q1 * q3 - q0 * q2)) * dt + rho0
        z1 = 0.5 * (wie1 + W_IE * 2.0 * (q2 * q3 + q0 * q1)) * dt + rho1
        z2 = 0.5 * (wie2 + W_IE * (q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3)) * dt
        a0, a1, a2, a3 = rotvec_quat(phi0, phi1, phi2)
        b0, b1, b2, b3 = qmul(q_wb[0], q_wb[1], q_wb[2], q_wb[3], a0, a1, a2, a3)
        a0, a1, a2, a3 = rotvec_quat(-z0, -z1, -z2)
        r0, r1, r2, r3 = qmul(a0, a1, a2, a3, b0, b1, b2, b3)
        store_unit(q_wb, r0, r1, r2, r3)
        v_w[0], v_w[1], v_w[2] = n0, n1, n2
        h_arr[0] = hnew
        carry[0] = t[k]
        remember(d0, d1, d2, u0, u1, u2, e0, e1, e2, carry)
        for i in range(4):
            q_ew_out[k, i] = q_ew[i]
            q_out[k, i] = q_wb[i]
        for i in range(3):
            v_out[k, i] = v_w[i]
        h_out[k] = hnew


@njit(cache=True)
def cartesian_kernel(t, dth_all, dv_all, start, rotating, t0, r, v, q, carry, coning, r_out, v_out, q_out,
                     gravity=0):
    """ECEF (``rotating``) or inertial-frame mechanization: one loop for both.

    * ECEF: ``dv_e/dt = C_eb f_b + g_e - 2 omega_ie x v_e`` with the frame's
      rotation over the interval in the attitude and specific-force terms
      (Groves §5.2);
    * inertial: ``d2r_i/dt2 = C_ib f_b + G_i`` (SYSTEM.md §1.2), ``i``
      coinciding with ``e`` at ``t0``; ``G_i`` is the gravitation (normal
      gravity minus centrifugal) rotated from e to i at the midpoint time.

    Gravity at the midpoint position, trapezoidal position.
    """
    n = t.shape[0]
    start_rows(start, t[0], r, v, q, r_out, v_out, q_out, carry)
    w2 = W_IE * W_IE
    for k in range(start, n):
        dt = t[k] - carry[0]
        d0, d1, d2 = dth_all[k, 0], dth_all[k, 1], dth_all[k, 2]
        u0, u1, u2 = dv_all[k, 0], dv_all[k, 1], dv_all[k, 2]
        phi0, phi1, phi2, c0, c1, c2 = coning_sculling(d0, d1, d2, u0, u1, u2, carry, coning)
        m0, m1, m2 = v[0], v[1], v[2]
        if carry[1] > 0.0:
            m0 += 0.5 * carry[8]
            m1 += 0.5 * carry[9]
            m2 += 0.5 * carry[10]
        x, y, zr = r[0] + 0.5 * dt * m0, r[1] + 0.5 * dt * m1, r[2] + 0.5 * dt * m2
        f0, f1, f2 = quat_rot(q[0], q[1], q[2], q[3], c0, c1, c2)
        if rotating:
            z = W_IE * dt
            g0, g1, g2 = _gravity_ecef(x, y, zr, gravity)
            # (I - [zeta x]/2) f with zeta = (0, 0, z); Coriolis -2 w x v_mid
            e0 = f0 + 0.5 * z * f1 + (g0 + 2.0 * W_IE * m1) * dt
            e1 = f1 - 0.5 * z * f0 + (g1 - 2.0 * W_IE * m0) * dt
            e2 = f2 + g2 * dt
        else:
            # e <- i at the midpoint time: r_e = Rz(-theta) r_i
            th = W_IE * (carry[0] + 0.5 * dt - t0)
            c, s = math.cos(th), math.sin(th)
            xe, ye = c * x + s * y, -s * x + c * y
            g0, g1, g2 = _gravity_ecef(xe, ye, zr, gravity)
            g0 -= w2 * xe
            g1 -= w2 * ye
            e0 = f0 + (c * g0 - s * g1) * dt
            e1 = f1 + (s * g0 + c * g1) * dt
            e2 = f2 + g2 * dt
        n0, n1, n2 = v[0] + e0, v[1] + e1, v[2] + e2
        r[0] += 0.5 * (v[0] + n0) * dt
        r[1] += 0.5 * (v[1] + n1) * dt
        r[2] += 0.5 * (v[2] + n2) * dt
        v[0], v[1], v[2] = n0, n1, n2
        a0, a1, a2, a3 = rotvec_quat(phi0, phi1, phi2)
        b0, b1, b2, b3 = qmul(q[0], q[1], q[2], q[3], a0, a1, a2, a3)
        if rotating:
            a0, a1, a2, a3 = rotvec_quat(0.0, 0.0, -W_IE * dt)
            b0, b1, b2, b3 = qmul(a0, a1, a2, a3, b0, b1, b2, b3)
        store_unit(q, b0, b1, b2, b3)
        carry[0] = t[k]
        remember(d0, d1, d2, u0, u1, u2, e0, e1, e2, carry)
        for i in range(3):
            r_out[k, i] = r[i]
            v_out[k, i] = v[i]
        for i in range(4):
            q_out[k, i] = q[i]


def ecef_kernel(t, dth_all, dv_all, start, r_e, v_e, q_eb, carry, coning, r_out, v_out, q_out, gravity=0):
    """ECEF mechanization (see :func:`cartesian_kernel`)."""
    cartesian_kernel(t, dth_all, dv_all, start, True, 0.0, r_e, v_e, q_eb, carry, coning, r_out, v_out, q_out,
                     gravity)


def inertial_kernel(t, dth_all, dv_all, start, t0, r_i, v_i, q_ib, carry, coning, r_out, v_out, q_out, gravity=0):
    """Inertial-frame mechanization (see :func:`cartesian_kernel`)."""
    cartesian_kernel(t, dth_all, dv_all, start, False, t0, r_i, v_i, q_ib, carry, coning, r_out, v_out, q_out,
                     gravity)
