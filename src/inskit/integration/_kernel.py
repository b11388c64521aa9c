"""Compiled propagation of the INS/GNSS error-state filter between updates.

One call integrates IMU rows ``k0 .. k1-1``: sensor corrections, the NED
mechanization (the very step of :func:`inskit.strapdown._kernels.ned_step`),
the transition matrix ``F`` of the error model, the covariance
``P <- Phi P Phi^T + Q dt`` with ``Phi = I + F dt`` and, when asked, the
transition accumulated over the segment (for the RTS smoother).

``F`` is filled only on its non-zero pattern (``rows``, ``cols`` from
:meth:`StateLayout.transition_pattern`), and the products ``F P`` and
``F (F P)^T`` run over that pattern alone: about 80 entries for 21 states
instead of 441.

Error model (x = estimate - truth; phi: ``C_nb_est = (I - [phi x]) C_nb``),
after Groves 2013 eq. 14.64 and Savage 2000 ch. 12, written for land and air
vehicles (position error in NED metres):

* ``d pos = vel``
* ``d vel = [f_n x] phi - (2 w_ie + w_en) x vel + (2 g / R) pos_D e_D
  - C_nb ba - C_nb diag(f_b) sa``
* ``d phi = -w_in x phi + d w_en(vel) + C_nb bg + C_nb diag(w_b) sg``
* ``d b = -b / tau`` for each sensor-error block (random walk when tau = inf).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import earth
from ..strapdown._kernels import _qmul_s, _radii, _rv_quat, _store_unit, ned_step

W_IE = earth.OMEGA_IE
# indices into the layout array
I_POS, I_VEL, I_ATT, I_BG, I_BA, I_SG, I_SA, I_LEVER, I_N = 0, 1, 2, 3, 4, 5, 6, 7, 8


@njit(cache=True)
def _dcm(q, C):
    q0, q1, q2, q3 = q[0], q[1], q[2], q[3]
    C[0, 0] = q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3
    C[0, 1] = 2 * (q1 * q2 - q0 * q3)
    C[0, 2] = 2 * (q1 * q3 + q0 * q2)
    C[1, 0] = 2 * (q1 * q2 + q0 * q3)
    C[1, 1] = q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3
    C[1, 2] = 2 * (q2 * q3 - q0 * q1)
    C[2, 0] = 2 * (q1 * q3 - q0 * q2)
    C[2, 1] = 2 * (q2 * q3 + q0 * q1)
    C[2, 2] = q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3


@njit(cache=True)
def _skew_into(F, r, c, a0, a1, a2, sign):
    F[r, c + 1] = -a2 * sign
    F[r, c + 2] = a1 * sign
    F[r + 1, c] = a2 * sign
    F[r + 1, c + 2] = -a0 * sign
    F[r + 2, c] = -a1 * sign
    F[r + 2, c + 1] = a0 * sign


@njit(cache=True)
def fill_transition(F, idx, lla, v_n, C, f_b, w_b, tau_inv):
    """Write the non-zero entries of the continuous-time F for this epoch."""
    lat, h = lla[0], lla[2]
    rn, re = _radii(lat, h)
    sl, cl = math.sin(lat), math.cos(lat)
    tl = sl / cl
    vn, ve = v_n[0], v_n[1]
    wie0, wie2 = W_IE * cl, -W_IE * sl
    wen0, wen1, wen2 = ve / re, -vn / rn, -ve * tl / re
    p, v, a = idx[I_POS], idx[I_VEL], idx[I_ATT]
    for i in range(3):
        F[p + i, v + i] = 1.0
    # gravity gradient on the down channel: d g_D / d pos_D = 2 g / R
    g = 9.80665
    F[v + 2, p + 2] = 2.0 * g / math.sqrt(rn * re)
    # velocity: Coriolis/transport and specific force
    _skew_into(F, v, v, 2 * wie0 + wen0, wen1, 2 * wie2 + wen2, -1.0)
    f0 = C[0, 0] * f_b[0] + C[0, 1] * f_b[1] + C[0, 2] * f_b[2]
    f1 = C[1, 0] * f_b[0] + C[1, 1] * f_b[1] + C[1, 2] * f_b[2]
    f2 = C[2, 0] * f_b[0] + C[2, 1] * f_b[1] + C[2, 2] * f_b[2]
    _skew_into(F, v, a, f0, f1, f2, 1.0)
    # attitude: frame rate and transport-rate error
    _skew_into(F, a, a, wie0 + wen0, wen1, wie2 + wen2, -1.0)
    F[a + 0, v + 1] = 1.0 / re
    F[a + 1, v + 0] = -1.0 / rn
    F[a + 2, v + 1] = -tl / re
    ba, bg, sa, sg = idx[I_BA], idx[I_BG], idx[I_SA], idx[I_SG]
    for i in range(3):
        for j in range(3):
            F[v + i, ba + j] = -C[i, j]
            F[a + i, bg + j] = C[i, j]
            if sa >= 0:
                F[v + i, sa + j] = -C[i, j] * f_b[j]
            if sg >= 0:
                F[a + i, sg + j] = C[i, j] * w_b[j]
    n = idx[I_N]
    for i in range(n):
        if tau_inv[i] != 0.0:
            F[i, i] = -tau_inv[i]


@njit(cache=True, fastmath={"contract"})
def propagate_covariance(P, F, rows, cols, active, dt, q_psd, A, B, second_order):
    """``P <- (I + F dt) P (I + F dt)^T + diag(q_psd) dt`` over F's pattern.

    ``active`` lists the rows of F that hold any pattern entry (9 of 21 with
    random-walk sensor errors).  ``A = F P`` is non-zero only on those rows,
    so ``A + A^T`` touches only their rows and columns and ``F P F^T`` only
    the active-by-active block: the update costs O(pattern * n + active^2)
    instead of O(n^2).  Without ``second_order`` the ``dt^2 F P F^T`` term is
    dropped (Euler integration of the Riccati equation): cheaper, but not
    guaranteed positive semi-definite when uncertainties are large (a MEMS car
    run lost positiveness at 177 s), so the filter keeps it.
    """
    n = P.shape[0]
    na = active.shape[0]
    for r in range(na):
        i = active[r]
        for m in range(n):
            A[i, m] = 0.0
    for e in range(rows.shape[0]):
        i, j = rows[e], cols[e]
        fij = F[i, j]
        for m in range(n):
            A[i, m] += fij * P[j, m]
    # P + dt (A + A^T): row and column of every active index
    for r in range(na):
        i = active[r]
        for m in range(n):
            val = dt * A[i, m]
            P[i, m] += val
            P[m, i] += val
    if second_order:
        # dt^2 F P F^T = dt^2 F A^T on the active block
        for r in range(na):
            i = active[r]
            for c in range(na):
                B[i, active[c]] = 0.0
        for e in range(rows.shape[0]):
            i, j = rows[e], cols[e]
            fij = F[i, j] * dt * dt
            for c in range(na):
                m = active[c]
                B[i, m] += fij * A[m, j]
        for r in range(na):
            i = active[r]
            for c in range(na):
                m = active[c]
                P[i, m] += B[i, m]
    # keep the active block exactly symmetric against rounding
    for r in range(na):
        i = active[r]
        for c in range(r + 1, na):
            m = active[c]
            v = 0.5 * (P[i, m] + P[m, i])
            P[i, m] = v
            P[m, i] = v
    for i in range(n):
        P[i, i] += q_psd[i] * dt


@njit(cache=True, fastmath={"contract"})
def _sparse_step(M, F, rows, cols, dt, tmp):
    """``M <- (I + F dt) M`` for a square or vector M over F's pattern."""
    tmp[:] = 0.0
    for e in range(rows.shape[0]):
        i, j = rows[e], cols[e]
        fij = F[i, j] * dt
        for m in range(M.shape[1]):
            tmp[i, m] += fij * M[j, m]
    M += tmp


@njit(cache=True)
def apply_correction(lla, v_n, q_nb, x, idx, sign, out_lla, out_v, out_q):
    """Navigation state corrected by ``sign * x`` (sign=1: subtract the
    estimated errors, as closed-loop feedback and open-loop output both do).
    The outputs may be the inputs themselves (in-place feedback)."""
    p, v, a = idx[I_POS], idx[I_VEL], idx[I_ATT]
    lat, lon, h = lla[0], lla[1], lla[2]
    rn, re = _radii(lat, h)
    out_lla[0] = lat - sign * x[p] / rn
    out_lla[1] = lon - sign * x[p + 1] / (re * math.cos(lat))
    out_lla[2] = h + sign * x[p + 2]
    for i in range(3):
        out_v[i] = v_n[i] - sign * x[v + i]
    a0, a1, a2, a3 = _rv_quat(sign * x[a], sign * x[a + 1], sign * x[a + 2])
    r0, r1, r2, r3 = _qmul_s(a0, a1, a2, a3, q_nb[0], q_nb[1], q_nb[2], q_nb[3])
    _store_unit(out_q, r0, r1, r2, r3)


@njit(cache=True)
def propagate(t, dth_all, dv_all, k0, k1, lla, v_n, q_nb, carry, coning, corr, x, P, q_psd, tau_inv,
              idx, rows, cols, active, want_phi, Phi, open_loop, out_lla, out_v, out_q, out_sig, out_corr, w_last,
              second_order=True):
    """Integrate IMU rows ``k0 .. k1-1`` with covariance propagation.

    ``corr`` holds the sensor-error estimates ``[bg, ba, sg, sa]`` applied to
    the raw increments.  ``w_last`` receives the last corrected body rate.
    """
    n = idx[I_N]
    F = np.zeros((n, n))
    A = np.empty((n, n))
    B = np.zeros((n, n))
    tmp = np.empty((n, n))
    xt = np.empty((n, 1))
    xtmp = np.empty((n, 1))
    C = np.empty((3, 3))
    dth = np.empty(3)
    dv = np.empty(3)
    f_b = np.empty(3)
    w_b = np.empty(3)
    o_lla = np.empty(3)
    o_v = np.empty(3)
    o_q = np.empty(4)
    has_sf = idx[I_SG] >= 0
    no_gains = np.zeros(2)
    for k in range(k0, k1):
        dt = t[k] - carry[0]
        for i in range(3):
            g_sf = 1.0 + corr[6 + i] if has_sf else 1.0
            a_sf = 1.0 + corr[9 + i] if has_sf else 1.0
            dth[i] = (dth_all[k, i] - corr[i] * dt) / g_sf
            dv[i] = (dv_all[k, i] - corr[3 + i] * dt) / a_sf
            w_b[i] = dth[i] / dt
            f_b[i] = dv[i] / dt
        _dcm(q_nb, C)
        ned_step(dth, dv, dt, lla, v_n, q_nb, carry, coning, 0, 0.0, no_gains)
        carry[0] = t[k]
        fill_transition(F, idx, lla, v_n, C, f_b, w_b, tau_inv)
        propagate_covariance(P, F, rows, cols, active, dt, q_psd, A, B, second_order)
        if open_loop:
            for i in range(n):
                xt[i, 0] = x[i]
            _sparse_step(xt, F, rows, cols, dt, xtmp)
            for i in range(n):
                x[i] = xt[i, 0]
        if want_phi:
            _sparse_step(Phi, F, rows, cols, dt, tmp)
        if open_loop:
            apply_correction(lla, v_n, q_nb, x, idx, 1.0, o_lla, o_v, o_q)
            for i in range(3):
                out_lla[k, i] = o_lla[i]
                out_v[k, i] = o_v[i]
            for i in range(4):
                out_q[k, i] = o_q[i]
        else:
            for i in range(3):
                out_lla[k, i] = lla[i]
                out_v[k, i] = v_n[i]
            for i in range(4):
                out_q[k, i] = q_nb[i]
        for i in range(9):
            out_sig[k, i] = P[i, i]  # variances; the caller takes the square roots in one pass
        for i in range(corr.shape[0]):
            out_corr[k, i] = corr[i]
    for i in range(3):
        w_last[i] = w_b[i]
