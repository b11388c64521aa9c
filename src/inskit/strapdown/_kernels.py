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
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import earth
from ..earth import gravity_down as _gravity_down
from ..earth import gravity_ecef_xyz as _gravity_ecef_xyz
from ..earth import gravity_north as _gravity_north
from ..earth import principal_radii as _radii

W_IE = earth.OMEGA_IE
HEIGHT_FREE = 0
HEIGHT_HOLD = 1
HEIGHT_AID = 2


@njit(cache=True)
def _cross(a, b, out):
    x = a[1] * b[2] - a[2] * b[1]
    y = a[2] * b[0] - a[0] * b[2]
    z = a[0] * b[1] - a[1] * b[0]
    out[0] = x
    out[1] = y
    out[2] = z


@njit(cache=True)
def _qmul(p, q, out):
    a = p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3]
    b = p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2]
    c = p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1]
    d = p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0]
    out[0] = a
    out[1] = b
    out[2] = c
    out[3] = d


@njit(cache=True)
def _q_from_rv(x, y, z, out):
    """Quaternion of the rotation vector (x, y, z)."""
    a2 = x * x + y * y + z * z
    if a2 < 1e-16:
        k = 0.5 - a2 / 48.0
        out[0] = 1.0 - a2 / 8.0
    else:
        a = math.sqrt(a2)
        k = math.sin(0.5 * a) / a
        out[0] = math.cos(0.5 * a)
    out[1] = k * x
    out[2] = k * y
    out[3] = k * z


@njit(cache=True, inline="always")
def _rv_quat(x, y, z):
    """Quaternion of the rotation vector (x, y, z) as four scalars."""
    a2 = x * x + y * y + z * z
    if a2 < 1e-16:
        k = 0.5 - a2 / 48.0
        return 1.0 - a2 / 8.0, k * x, k * y, k * z
    a = math.sqrt(a2)
    k = math.sin(0.5 * a) / a
    return math.cos(0.5 * a), k * x, k * y, k * z


@njit(cache=True, inline="always")
def _qmul_s(a0, a1, a2, a3, b0, b1, b2, b3):
    """Hamilton product of two quaternions given as scalars (kept in registers)."""
    return (a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
            a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
            a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
            a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0)


@njit(cache=True, inline="always")
def _store_unit(q, r0, r1, r2, r3):
    """Write the normalised quaternion (r0..r3) into ``q``."""
    inv = 1.0 / math.sqrt(r0 * r0 + r1 * r1 + r2 * r2 + r3 * r3)
    q[0], q[1], q[2], q[3] = r0 * inv, r1 * inv, r2 * inv, r3 * inv


@njit(cache=True)
def _qnormalize(q):
    s = 1.0 / math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    for i in range(4):
        q[i] *= s


@njit(cache=True)
def _qrot(q, v, out):
    """out = C(q) v (rotate a vector from the right-hand frame to the left)."""
    tx = 2.0 * (q[2] * v[2] - q[3] * v[1])
    ty = 2.0 * (q[3] * v[0] - q[1] * v[2])
    tz = 2.0 * (q[1] * v[1] - q[2] * v[0])
    out0 = v[0] + q[0] * tx + q[2] * tz - q[3] * ty
    out1 = v[1] + q[0] * ty + q[3] * tx - q[1] * tz
    out2 = v[2] + q[0] * tz + q[1] * ty - q[2] * tx
    out[0] = out0
    out[1] = out1
    out[2] = out2


@njit(cache=True)
def _compensate(dth, dv, carry, coning, phi, dvc, tmp):
    """Coning/sculling-compensated rotation vector ``phi`` and velocity ``dvc``."""
    # rotation correction dth x dv / 2
    _cross(dth, dv, tmp)
    for i in range(3):
        phi[i] = dth[i]
        dvc[i] = dv[i] + 0.5 * tmp[i]
    if coning and carry[1] > 0.0:
        p = carry[2:5]
        pv = carry[5:8]
        _cross(p, dth, tmp)
        for i in range(3):
            phi[i] += tmp[i] / 12.0
        _cross(p, dv, tmp)
        for i in range(3):
            dvc[i] += tmp[i] / 12.0
        _cross(pv, dth, tmp)
        for i in range(3):
            dvc[i] += tmp[i] / 12.0


@njit(cache=True)
def _remember(dth, dv, dvel, carry, t):
    carry[0] = t
    carry[1] = 1.0
    for i in range(3):
        carry[2 + i] = dth[i]
        carry[5 + i] = dv[i]
        carry[8 + i] = dvel[i]


@njit(cache=True, inline="always")
def ned_step(dth, dv, dt, lla, v_n, q_nb, carry, coning, height_mode, h_ref, h_gains):
    """One NED mechanization step over an interval of length ``dt``, in place.

    ``lla``, ``v_n``, ``q_nb`` and ``carry`` advance to the interval's end.
    Intermediate quantities are scalars, not scratch arrays, so the compiler
    keeps them in registers (passing scratch arrays in cost 30 % of the speed:
    it cannot prove they do not alias the state).  (SYSTEM.md §1.4, source 000
    eq. 1-37..42.)
    """
    d0, d1, d2 = dth[0], dth[1], dth[2]
    u0, u1, u2 = dv[0], dv[1], dv[2]
    # rotation correction dth x dv / 2, then two-sample coning and sculling
    phi0, phi1, phi2 = d0, d1, d2
    c0 = u0 + 0.5 * (d1 * u2 - d2 * u1)
    c1 = u1 + 0.5 * (d2 * u0 - d0 * u2)
    c2 = u2 + 0.5 * (d0 * u1 - d1 * u0)
    has_prev = carry[1] > 0.0
    if coning and has_prev:
        p0, p1, p2 = carry[2], carry[3], carry[4]
        w0, w1, w2 = carry[5], carry[6], carry[7]
        phi0 += (p1 * d2 - p2 * d1) / 12.0
        phi1 += (p2 * d0 - p0 * d2) / 12.0
        phi2 += (p0 * d1 - p1 * d0) / 12.0
        c0 += ((p1 * u2 - p2 * u1) + (w1 * d2 - w2 * d1)) / 12.0
        c1 += ((p2 * u0 - p0 * u2) + (w2 * d0 - w0 * d2)) / 12.0
        c2 += ((p0 * u1 - p1 * u0) + (w0 * d1 - w1 * d0)) / 12.0
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
    tx = 2.0 * (q2 * c2 - q3 * c1)
    ty = 2.0 * (q3 * c0 - q1 * c2)
    tz = 2.0 * (q1 * c1 - q2 * c0)
    f0 = c0 + q0 * tx + q2 * tz - q3 * ty
    f1 = c1 + q0 * ty + q3 * tx - q1 * tz
    f2 = c2 + q0 * tz + q1 * ty - q2 * tx
    gd = _gravity_down(latm, hm)
    gn = _gravity_north(latm, hm)
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
    a0, a1, a2, a3 = _rv_quat(phi0, phi1, phi2)
    b0, b1, b2, b3 = _qmul_s(q0, q1, q2, q3, a0, a1, a2, a3)  # q_nb * q(phi)
    a0, a1, a2, a3 = _rv_quat(-z0, -z1, -z2)
    r0, r1, r2, r3 = _qmul_s(a0, a1, a2, a3, b0, b1, b2, b3)  # q(-zeta) * ...
    _store_unit(q_nb, r0, r1, r2, r3)
    v_n[0], v_n[1], v_n[2] = n0, n1, n2
    lla[0], lla[1], lla[2] = latnew, lonnew, hnew
    carry[0] += dt
    carry[1] = 1.0
    carry[2], carry[3], carry[4] = d0, d1, d2
    carry[5], carry[6], carry[7] = u0, u1, u2
    carry[8], carry[9], carry[10] = n0 - v0, n1 - v1, n2 - v2


@njit(cache=True)
def ned_kernel(t, dth_all, dv_all, start, lla, v_n, q_nb, carry, coning,
               height_mode, h_ref, h_gains, lla_out, v_out, q_out):
    """Local-level NED mechanization (SYSTEM.md §1.4, source 000 eq. 1-37..42)."""
    n = t.shape[0]
    if start == 1:
        for i in range(3):
            lla_out[0, i] = lla[i]
            v_out[0, i] = v_n[i]
        for i in range(4):
            q_out[0, i] = q_nb[i]
        carry[0] = t[0]
        carry[1] = 0.0
    for k in range(start, n):
        dt = t[k] - carry[0]
        href = h_ref[k] if height_mode != HEIGHT_FREE else 0.0
        ned_step(dth_all[k], dv_all[k], dt, lla, v_n, q_nb, carry, coning, height_mode, href, h_gains)
        carry[0] = t[k]
        for i in range(3):
            lla_out[k, i] = lla[i]
            v_out[k, i] = v_n[i]
        for i in range(4):
            q_out[k, i] = q_nb[i]


@njit(cache=True)
def wander_kernel(t, dth_all, dv_all, start, q_ew, h_arr, v_w, q_wb, carry, coning,
                  q_ew_out, h_out, v_out, q_out):
    """Wander-azimuth mechanization (SYSTEM.md §1.1 block diagram).

    The wander frame w is NED turned about down by the wander angle alpha; its
    transport rate has no vertical component, so nothing is singular at the
    poles.  Position is the quaternion ``q_ew`` (Earth-to-wander DCM) plus
    height; ``q_ew`` is updated with ``d/dt C_ew = C_ew [rho_w x]``.
    """
    n = t.shape[0]
    phi = np.empty(3)
    dvc = np.empty(3)
    tmp = np.empty(3)
    zeta = np.empty(3)
    fw = np.empty(3)
    dvel = np.empty(3)
    vnew = np.empty(3)
    qa = np.empty(4)
    qb = np.empty(4)
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
        dth = dth_all[k]
        dv = dv_all[k]
        h = h_arr[0]
        _compensate(dth, dv, carry, coning, phi, dvc, tmp)
        if carry[1] > 0.0:
            for i in range(3):
                tmp[i] = v_w[i] + 0.5 * carry[8 + i]
        else:
            for i in range(3):
                tmp[i] = v_w[i]
        # third row of C_ew = [cos(lat) cos(a), -cos(lat) sin(a), -sin(lat)]
        q0, q1, q2, q3 = q_ew[0], q_ew[1], q_ew[2], q_ew[3]
        c20 = 2.0 * (q1 * q3 - q0 * q2)
        c21 = 2.0 * (q2 * q3 + q0 * q1)
        c22 = q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3
        sl = -c22
        lat = math.asin(min(1.0, max(-1.0, sl)))
        alpha = math.atan2(-c21, c20)
        hm = h - 0.5 * dt * tmp[2]
        rn, re = _radii(lat, hm)
        ca, sa = math.cos(alpha), math.sin(alpha)
        # rho_w = Rz(-a) [vE/re, -vN/rn] with v_n = Rz(a) v_w
        vn_ = ca * tmp[0] - sa * tmp[1]
        ve_ = sa * tmp[0] + ca * tmp[1]
        rx_n, ry_n = ve_ / re, -vn_ / rn
        rho0 = ca * rx_n + sa * ry_n
        rho1 = -sa * rx_n + ca * ry_n
        wie0, wie1, wie2 = W_IE * c20, W_IE * c21, W_IE * c22
        zeta[0] = (wie0 + rho0) * dt
        zeta[1] = (wie1 + rho1) * dt
        zeta[2] = wie2 * dt
        _qrot(q_wb, dvc, fw)
        _cross(zeta, fw, dvel)
        gd = _gravity_down(lat, hm)
        gn = _gravity_north(lat, hm)
        cx, cy, cz = 2.0 * wie0 + rho0, 2.0 * wie1 + rho1, 2.0 * wie2
        cor0 = cy * tmp[2] - cz * tmp[1]
        cor1 = cz * tmp[0] - cx * tmp[2]
        cor2 = cx * tmp[1] - cy * tmp[0]
        dvel[0] = fw[0] - 0.5 * dvel[0] + (ca * gn - cor0) * dt
        dvel[1] = fw[1] - 0.5 * dvel[1] + (-sa * gn - cor1) * dt
        dvel[2] = fw[2] - 0.5 * dvel[2] + (gd - cor2) * dt
        for i in range(3):
            vnew[i] = v_w[i] + dvel[i]
        hnew = h - 0.5 * (v_w[2] + vnew[2]) * dt
        hm = 0.5 * (h + hnew)
        rn, re = _radii(lat, hm)
        # transport rate over the step from the mean velocity
        vx, vy = 0.5 * (v_w[0] + vnew[0]), 0.5 * (v_w[1] + vnew[1])
        vn_ = ca * vx - sa * vy
        ve_ = sa * vx + ca * vy
        rx_n, ry_n = ve_ / re, -vn_ / rn
        rho0 = (ca * rx_n + sa * ry_n) * dt
        rho1 = (-sa * rx_n + ca * ry_n) * dt
        # q_ew <- q_ew * q(rho dt)
        _q_from_rv(rho0, rho1, 0.0, qa)
        _qmul(q_ew, qa, qb)
        # Earth rate on the midpoint frame: C_we at the midpoint, third row
        for i in range(4):
            q_ew[i] = qb[i]
        _qnormalize(q_ew)
        q0, q1, q2, q3 = q_ew[0], q_ew[1], q_ew[2], q_ew[3]
        zeta[0] = 0.5 * (wie0 + W_IE * 2.0 * (q1 * q3 - q0 * q2)) * dt + rho0
        zeta[1] = 0.5 * (wie1 + W_IE * 2.0 * (q2 * q3 + q0 * q1)) * dt + rho1
        zeta[2] = 0.5 * (wie2 + W_IE * (q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3)) * dt
        _q_from_rv(phi[0], phi[1], phi[2], qa)
        _qmul(q_wb, qa, qb)
        _q_from_rv(-zeta[0], -zeta[1], -zeta[2], qa)
        _qmul(qa, qb, q_wb)
        _qnormalize(q_wb)
        for i in range(3):
            dvel[i] = vnew[i] - v_w[i]
            v_w[i] = vnew[i]
        h_arr[0] = hnew
        _remember(dth, dv, dvel, carry, t[k])
        for i in range(4):
            q_ew_out[k, i] = q_ew[i]
            q_out[k, i] = q_wb[i]
        for i in range(3):
            v_out[k, i] = v_w[i]
        h_out[k] = hnew


@njit(cache=True)
def _gravity_e(r, out):
    """Normal plumb-bob gravity resolved in e at ECEF position r."""
    gx, gy, gz = _gravity_ecef_xyz(r[0], r[1], r[2])
    out[0] = gx
    out[1] = gy
    out[2] = gz


@njit(cache=True)
def ecef_kernel(t, dth_all, dv_all, start, r_e, v_e, q_eb, carry, coning, r_out, v_out, q_out):
    """ECEF mechanization: ``dv_e/dt = C_eb f_b + g_e - 2 omega_ie x v_e`` (Groves §5.2)."""
    n = t.shape[0]
    phi = np.empty(3)
    dvc = np.empty(3)
    tmp = np.empty(3)
    fe = np.empty(3)
    rm = np.empty(3)
    g = np.empty(3)
    dvel = np.empty(3)
    vnew = np.empty(3)
    qa = np.empty(4)
    qb = np.empty(4)
    if start == 1:
        for i in range(3):
            r_out[0, i] = r_e[i]
            v_out[0, i] = v_e[i]
        for i in range(4):
            q_out[0, i] = q_eb[i]
        carry[0] = t[0]
        carry[1] = 0.0
    for k in range(start, n):
        dt = t[k] - carry[0]
        dth = dth_all[k]
        dv = dv_all[k]
        _compensate(dth, dv, carry, coning, phi, dvc, tmp)
        if carry[1] > 0.0:
            for i in range(3):
                tmp[i] = v_e[i] + 0.5 * carry[8 + i]
        else:
            for i in range(3):
                tmp[i] = v_e[i]
        for i in range(3):
            rm[i] = r_e[i] + 0.5 * dt * tmp[i]
        z = W_IE * dt
        _qrot(q_eb, dvc, fe)
        _gravity_e(rm, g)
        # (I - [zeta x]/2) fe with zeta = (0, 0, z); Coriolis -2 w x v_mid
        dvel[0] = fe[0] + 0.5 * z * fe[1] + (g[0] + 2.0 * W_IE * tmp[1]) * dt
        dvel[1] = fe[1] - 0.5 * z * fe[0] + (g[1] - 2.0 * W_IE * tmp[0]) * dt
        dvel[2] = fe[2] + g[2] * dt
        for i in range(3):
            vnew[i] = v_e[i] + dvel[i]
            r_e[i] += 0.5 * (v_e[i] + vnew[i]) * dt
            v_e[i] = vnew[i]
        _q_from_rv(phi[0], phi[1], phi[2], qa)
        _qmul(q_eb, qa, qb)
        _q_from_rv(0.0, 0.0, -z, qa)
        _qmul(qa, qb, q_eb)
        _qnormalize(q_eb)
        _remember(dth, dv, dvel, carry, t[k])
        for i in range(3):
            r_out[k, i] = r_e[i]
            v_out[k, i] = v_e[i]
        for i in range(4):
            q_out[k, i] = q_eb[i]


@njit(cache=True)
def inertial_kernel(t, dth_all, dv_all, start, t0, r_i, v_i, q_ib, carry, coning, r_out, v_out, q_out):
    """Inertial-frame mechanization: ``d2r_i/dt2 = C_ib f_b + G_i`` (SYSTEM.md §1.2).

    ``i`` coincides with ``e`` at time ``t0``; ``G_i`` is the gravitation
    (normal gravity minus centrifugal) rotated from e to i.
    """
    n = t.shape[0]
    phi = np.empty(3)
    dvc = np.empty(3)
    tmp = np.empty(3)
    fi = np.empty(3)
    rm = np.empty(3)
    re_ = np.empty(3)
    g = np.empty(3)
    dvel = np.empty(3)
    qa = np.empty(4)
    qb = np.empty(4)
    if start == 1:
        for i in range(3):
            r_out[0, i] = r_i[i]
            v_out[0, i] = v_i[i]
        for i in range(4):
            q_out[0, i] = q_ib[i]
        carry[0] = t[0]
        carry[1] = 0.0
    for k in range(start, n):
        dt = t[k] - carry[0]
        dth = dth_all[k]
        dv = dv_all[k]
        _compensate(dth, dv, carry, coning, phi, dvc, tmp)
        if carry[1] > 0.0:
            for i in range(3):
                tmp[i] = v_i[i] + 0.5 * carry[8 + i]
        else:
            for i in range(3):
                tmp[i] = v_i[i]
        for i in range(3):
            rm[i] = r_i[i] + 0.5 * dt * tmp[i]
        # e <- i at the midpoint time: r_e = Rz(-theta) r_i
        th = W_IE * (carry[0] + 0.5 * dt - t0)
        c, s = math.cos(th), math.sin(th)
        re_[0] = c * rm[0] + s * rm[1]
        re_[1] = -s * rm[0] + c * rm[1]
        re_[2] = rm[2]
        _gravity_e(re_, g)
        w2 = W_IE * W_IE
        g[0] -= w2 * re_[0]
        g[1] -= w2 * re_[1]
        gx = c * g[0] - s * g[1]
        gy = s * g[0] + c * g[1]
        _qrot(q_ib, dvc, fi)
        dvel[0] = fi[0] + gx * dt
        dvel[1] = fi[1] + gy * dt
        dvel[2] = fi[2] + g[2] * dt
        for i in range(3):
            vn = v_i[i] + dvel[i]
            r_i[i] += 0.5 * (v_i[i] + vn) * dt
            v_i[i] = vn
        _q_from_rv(phi[0], phi[1], phi[2], qa)
        _qmul(q_ib, qa, qb)
        for i in range(4):
            q_ib[i] = qb[i]
        _qnormalize(q_ib)
        _remember(dth, dv, dvel, carry, t[k])
        for i in range(3):
            r_out[k, i] = r_i[i]
            v_out[k, i] = v_i[i]
        for i in range(4):
            q_out[k, i] = q_ib[i]
