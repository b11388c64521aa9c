"""Compiled updates of the standard measurements, driven from a compiled loop.

The filter loop of :mod:`.engine` asks every measurement for the protocol's
``linearize(ctx, row)`` and runs the update in Python: 30-45 us per update,
three quarters of a drive's filter time at 10 Hz ZUPT and NHC.  The standard
measurements (GNSS position and velocity, ZUPT, NHC, odometer, GNSS speed
and course, pseudorange and range rate) also offer ``compiled(layout)``: a
:class:`CompiledSpec` (a kind code, the number of innovation rows, their
data packed per row, a few parameters).  :func:`run_nodes` then runs, for a
whole stretch of update nodes, what the Python loop does per node (propagate
to the node, carry the evolving estimates, the gap noise, the smoother's
store; then per measurement: linearize by kind, the recovery from a lost
state, the chi-square gate of the vector or of each row, the Joseph update,
the closed-loop feedback, the innovation record; then the covariance check
and the node's output row), and hands back to Python only

* at an item of a measurement without a compiled form (a user's plug-in),
  which Python then updates on the same state before the loop goes on;
* every ``ctl[C_KSTOP]`` rows, for the progress callback;
* on a divergence, which Python reports with the message of its own path.

Each kind's linearization is the formula of its class's ``linearize`` (the
class docstrings give H), written out element by element; the update is the
Joseph form ``(I - K H) P (I - K H)^T + K R K^T`` of
:func:`inskit.filters.kalman.joseph_update` (Bucy & Joseph 1968; Groves 2013
eq. 3.58), expanded into one pass over the upper triangle (:func:`_joseph`)
with ``H P H^T`` over the non-zero columns of H only: O(n^2 k) instead of
O(n^3).  Both paths are the same mathematics in a different order of
rounding; ``tests/test_integration_updates.py`` compares them kind by kind
and over whole runs with rejections and recoveries.

The open-loop scheme and blocks with their own feedback stay on the Python
path (:func:`.engine.run_filter` decides).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from .. import earth
from . import _kernel as K

KIND_ZUPT, KIND_NHC, KIND_GNSS_POS, KIND_GNSS_VEL, KIND_ODOMETER, KIND_SPEED_COURSE = 0, 1, 2, 3, 4, 5
KIND_PSEUDORANGE, KIND_RANGE_RATE = 6, 7
#: rows of the fixed-size kinds' updates, at most
KMAX = 3
#: columns of a range table row: satellite position (3) and velocity (3) in the ECEF frame of reception,
#: measured value, sigma, state and aux index of the row's system time offset (-1: none)
RANGE_WIDTH = 10
# layout index array (layout_index): state and aux starts of the blocks found by name (-1 if absent)
L_X_LEVER, L_A_LEVER, L_X_TOFF, L_A_TOFF, L_X_ODO, L_A_ODO, L_X_CLOCK, L_A_CLOCK = 0, 1, 2, 3, 4, 5, 6, 7
L_X_MOUNT, L_A_MOUNT = 8, 9
L_X_GERR, L_A_GERR = 10, 11
# loop state (ctl) of run_nodes
C_I, C_KDONE, C_IN_NODE, C_KCUR, C_NODE, C_NROW, C_NREC, C_NRECOV, C_KSTOP, C_NFLAT = 0, 1, 2, 3, 4, 5, 6, 7, 8, 9
C_SIZE = 10
# per-measurement counts of run_nodes
N_USED, N_REJECTED, N_SKIPPED, N_ROWS, N_ROWS_REJECTED, N_ROW_GATED = 0, 1, 2, 3, 4, 5
N_COUNTS = 6
# return codes of run_nodes
DONE, HANDBACK, CHUNK, BAD_INNOVATION, NOT_PD, LOST_PD, BAD_ROWS = 0, 1, 2, 3, 4, 5, 6


class CompiledSpec(NamedTuple):
    """A measurement's compiled form.

    Attributes
    ----------
    kind : int
        One of the ``KIND_*`` codes.
    k : int
        Rows of every update; for a kind with ``index``, the most rows of one
        update.
    data : (rows, w) float ndarray
        Per own data row (the protocol's ``row``): what the kind reads; with
        ``index``, per row of the table instead.
    par : (p,) float ndarray
        Fixed parameters (lever arm, sigmas).
    index : (rows + 1,) int64 ndarray or None
        Update ``row`` reads the table rows ``index[row]:index[row + 1]``
        (one per satellite; an empty range skips the update).
    per_row : bool
        Gate each row on its own (the protocol's ``gating = "row"``).
    """

    kind: int
    k: int
    data: np.ndarray
    par: np.ndarray
    index: np.ndarray | None = None
    per_row: bool = False


def spec(kind, k, data, par, index=None, per_row=False):
    """A :class:`CompiledSpec` with its arrays made contiguous float64 (and
    int64 for ``index``)."""
    data = np.ascontiguousarray(data, dtype=float)
    if data.ndim != 2:
        data = data.reshape(len(data), -1)
    if index is not None:
        index = np.ascontiguousarray(index, dtype=np.int64)
    return CompiledSpec(int(kind), int(k), data, np.ascontiguousarray(np.atleast_1d(par), dtype=float).ravel(),
                        index, bool(per_row))


def layout_index(layout):
    """int64 ``[x_lever, a_lever, x_time_offset, a_time_offset, x_odo_scale,
    a_odo_scale, x_clock, a_clock, x_mounting, a_mounting, x_gnss_err,
    a_gnss_err]``: state start
    (when the layout holds the block) and aux start (when the block carries
    an estimate) of the blocks the measurements find by name; -1 if absent."""
    out = []
    for name in ("lever", "time_offset", "odo_scale", "clock", "mounting", "gnss_err"):
        s, a = layout.slice(name), layout.aux_slice(name)
        out += [-1 if s is None else s.start, -1 if a is None else a.start]
    return np.array(out, dtype=np.int64)


@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _nhc_mounted(v_n, v_o, C, pitch, yaw, Sk, xm, nu, H, M):
    """The non-holonomic rows in the vehicle's axes, ``v_v = C_vb v_o`` (``v_o
    = C_bn v_n + omega x l_b``, the body velocity at the constraint's point)
    with ``C_vb`` of :func:`.blocks.mounting_dcm` (written out: the same
    matrix and derivatives), as :meth:`.measurements.NonHolonomic.linearize`
    with a ``mounting`` block: ``H_vel = C_vn[1:3]``, ``H_att = -(C_vn [v_n
    x])[1:3]``, ``H_mounting = [dC/dpitch v_o, dC/dyaw v_o][1:3]``; rows 1, 2
    of ``C_vb`` into ``M[0:2]`` (for the lever arm's rate columns)."""
    cp, sp, cy, sy = np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    Cv = np.array([[cp * cy, cp * sy, -sp], [-sy, cy, 0.0], [sp * cy, sp * sy, cp]])
    Dp = np.array([[-sp * cy, -sp * sy, -cp], [0.0, 0.0, 0.0], [cp * cy, cp * sy, -sp]])
    Dy = np.array([[-cp * sy, cp * cy, 0.0], [-cy, -sy, 0.0], [-sp * sy, sp * cy, 0.0]])
    for r in range(2):
        b = r + 1
        cvn = np.empty(3)
        for j in range(3):  # C_vn[b, j] = sum_i C_vb[b, i] C_bn[i, j], C_bn[i, j] = C[j, i]
            cvn[j] = Cv[b, 0] * C[j, 0] + Cv[b, 1] * C[j, 1] + Cv[b, 2] * C[j, 2]
            M[r, j] = Cv[b, j]
        nu[r] = Cv[b, 0] * v_o[0] + Cv[b, 1] * v_o[1] + Cv[b, 2] * v_o[2]
        for j in range(3):
            H[r, K.V0 + j] = cvn[j]
            H[r, K.T0 + j] = -(cvn[0] * Sk[0, j] + cvn[1] * Sk[1, j] + cvn[2] * Sk[2, j])
        H[r, xm] = Dp[b, 0] * v_o[0] + Dp[b, 1] * v_o[1] + Dp[b, 2] * v_o[2]
        H[r, xm + 1] = Dy[b, 0] * v_o[0] + Dy[b, 1] * v_o[1] + Dy[b, 2] * v_o[2]


# --- linearization by kind ------------------------------------------------------------
@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _body_rate(w_raw, aux, kidx, w, sf):
    """``sf = 1 + s_g`` and the corrected rate ``w = (raw - b_g) / sf``
    (:attr:`.measurements.UpdateContext.omega_ib_b`)."""
    abg, asg = kidx[K.A_BG], kidx[K.A_SG]
    for i in range(3):
        sf[i] = 1.0 + aux[asg + i] if asg >= 0 else 1.0
        b = w_raw[i] - aux[abg + i] if abg >= 0 else w_raw[i]
        w[i] = b / sf[i]


@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _rate_columns(H, k, M, sf, w, kidx):
    """``M d(omega)`` into the gyro bias and scale-factor columns
    (:func:`.measurements._sensor_rate_columns`)."""
    xbg, xsg = kidx[K.X_BG], kidx[K.X_SG]
    for r in range(k):
        for j in range(3):
            if xbg >= 0:
                H[r, xbg + j] += -M[r, j] / sf[j]
            if xsg >= 0:
                H[r, xsg + j] += -M[r, j] * (w[j] / sf[j])


@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _skew_into(v, S):
    S[0, 0], S[0, 1], S[0, 2] = 0.0, -v[2], v[1]
    S[1, 0], S[1, 1], S[1, 2] = v[2], 0.0, -v[0]
    S[2, 0], S[2, 1], S[2, 2] = -v[1], v[0], 0.0


@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _mat3_vec(C, v, out):
    for i in range(3):
        out[i] = C[i, 0] * v[0] + C[i, 1] * v[1] + C[i, 2] * v[2]


@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _cross_into(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _lever_of(aux, lidx, par, lev):
    a = lidx[L_A_LEVER]
    for i in range(3):
        lev[i] = aux[a + i] if a >= 0 else par[i]


@njit(cache=True, error_model="numpy")
def linearize(kind, d, par, dt, lla, v_n, C, w_raw, aux, kidx, lidx, nu, H, R, vw, mw):
    """Innovation ``nu`` (k,), ``H`` (k, n) and ``R`` (k, k) of one update of
    a compiled kind, written into the first k rows of the scratch arrays
    (``H`` and ``R`` zeroed first).  ``d`` is the measurement's data row;
    ``vw`` (8, 3) and ``mw`` (2, 3, 3) are scratch.  Returns False when the
    update is skipped (the protocol's None)."""
    n = H.shape[1]
    for r in range(KMAX):
        nu[r] = 0.0
        for j in range(n):
            H[r, j] = 0.0
        for j in range(KMAX):
            R[r, j] = 0.0
    w, sf, lev, wl, tmp, v3, c3 = vw[0], vw[1], vw[2], vw[3], vw[4], vw[5], vw[6]
    Sk, M = mw[0], mw[1]
    if kind == KIND_ZUPT:
        s2 = par[0] * par[0]
        for i in range(3):
            nu[i] = v_n[i]
            H[i, K.V0 + i] = 1.0
            R[i, i] = s2
        return True
    if kind == KIND_NHC:
        # v_o = C^T v_n (+ omega x l_b, par[1:4], at the constraint's point); rows 1, 2:
        # H_vel = C_vn[1:3], H_att = -(C_vn [v_n x])[1:3], H_rate = -(C_vb [l_b x])[1:3]
        _skew_into(v_n, Sk)
        s2 = par[0] * par[0]
        xm = lidx[L_X_MOUNT]
        for i in range(3):
            v3[i] = C[0, i] * v_n[0] + C[1, i] * v_n[1] + C[2, i] * v_n[2]
        lever = par.shape[0] >= 4 and (par[1] != 0.0 or par[2] != 0.0 or par[3] != 0.0)
        if lever:
            for i in range(3):
                lev[i] = par[1 + i]
            _body_rate(w_raw, aux, kidx, w, sf)
            _cross_into(w, lev, wl)
            for i in range(3):
                v3[i] += wl[i]
        if xm >= 0:  # in the vehicle's axes (NonHolonomic.linearize with a mounting block)
            _nhc_mounted(v_n, v3, C, aux[lidx[L_A_MOUNT]], aux[lidx[L_A_MOUNT] + 1], Sk, xm, nu, H, M)
        else:
            for r in range(2):
                b = r + 1
                nu[r] = v3[b]
                for j in range(3):
                    H[r, K.V0 + j] = C[j, b]
                    H[r, K.T0 + j] = -(C[0, b] * Sk[0, j] + C[1, b] * Sk[1, j] + C[2, b] * Sk[2, j])
                    M[r, j] = 1.0 if j == b else 0.0
        if lever:  # M[0:2] holds rows 1, 2 of C_vb: into -(C_vb [l_b x])[1:3]
            _skew_into(lev, Sk)
            for r in range(2):
                m0, m1, m2 = M[r, 0], M[r, 1], M[r, 2]
                for j in range(3):
                    M[r, j] = -(m0 * Sk[0, j] + m1 * Sk[1, j] + m2 * Sk[2, j])
            _rate_columns(H, 2, M, sf, w, kidx)
        R[0, 0] = s2
        R[1, 1] = s2
        return True
    if kind == KIND_GNSS_POS:
        # d: lla (3), sigma (3); par: lever arm (3)
        _lever_of(aux, lidx, par, lev)
        atoff = lidx[L_A_TOFF]
        tau = dt + (aux[atoff] if atoff >= 0 else 0.0)
        for i in range(3):
            H[i, K.P0 + i] = 1.0
            H[i, K.V0 + i] = tau
        v_ant = v3
        cl = c3
        for i in range(3):
            cl[i] = 0.0
        xlev = lidx[L_X_LEVER]
        if lev[0] != 0.0 or lev[1] != 0.0 or lev[2] != 0.0 or xlev >= 0:
            _body_rate(w_raw, aux, kidx, w, sf)
            _cross_into(w, lev, wl)
            cwl = vw[7]
            _mat3_vec(C, wl, cwl)
            _mat3_vec(C, lev, cl)
            for i in range(3):
                v_ant[i] = v_n[i] + cwl[i]
                tmp[i] = cl[i] + cwl[i] * tau
            _skew_into(tmp, Sk)
            for i in range(3):
                for j in range(3):
                    H[i, K.T0 + j] = Sk[i, j]
            _skew_into(lev, Sk)
            for i in range(3):
                for j in range(3):
                    M[i, j] = -(C[i, 0] * Sk[0, j] + C[i, 1] * Sk[1, j] + C[i, 2] * Sk[2, j]) * tau
            _rate_columns(H, 3, M, sf, w, kidx)
            if xlev >= 0:
                _skew_into(w, Sk)
                for i in range(3):
                    for j in range(3):
                        H[i, xlev + j] = C[i, j] + (C[i, 0] * Sk[0, j] + C[i, 1] * Sk[1, j]
                                                    + C[i, 2] * Sk[2, j]) * tau
        else:
            for i in range(3):
                v_ant[i] = v_n[i]
        # ned_difference(lla, fix)
        lat, h = d[0], d[2]
        s = math.sin(lat)
        wq = math.sqrt(1.0 - earth.E2 * s * s)
        rn = earth.A * (1.0 - earth.E2) / (wq * wq * wq) + h
        re = earth.A / wq + h
        dlon = (lla[1] - d[1] + math.pi) % (2.0 * math.pi) - math.pi
        tmp[0] = (lla[0] - lat) * rn
        tmp[1] = dlon * re * math.cos(lat)
        tmp[2] = -(lla[2] - h)
        for i in range(3):
            nu[i] = tmp[i] + cl[i] + v_ant[i] * tau
            R[i, i] = d[3 + i] * d[3 + i]
        xg, ag = lidx[L_X_GERR], lidx[L_A_GERR]
        if xg >= 0 and ag >= 0:  # the fixes' time-correlated error (blocks.GnssPositionError): h = ... + e, H_e = I
            for i in range(3):
                nu[i] = nu[i] + aux[ag + i]
                H[i, xg + i] = 1.0
        if atoff >= 0:
            xt = lidx[L_X_TOFF]
            for i in range(3):
                H[i, xt] = v_ant[i]
        return True
    if kind == KIND_GNSS_VEL or kind == KIND_SPEED_COURSE:
        # GNSS velocity, d: v_n (3), sigma (3); speed and course, d: speed, min speed, v_ne (2), P_ne (4)
        if kind == KIND_SPEED_COURSE and d[0] < d[1]:
            return False
        _lever_of(aux, lidx, par, lev)
        _body_rate(w_raw, aux, kidx, w, sf)
        _cross_into(w, lev, wl)
        lever_v = v3
        _mat3_vec(C, wl, lever_v)
        kk = 3 if kind == KIND_GNSS_VEL else 2
        _skew_into(lever_v, Sk)
        for i in range(kk):
            H[i, K.V0 + i] = 1.0
            for j in range(3):
                H[i, K.T0 + j] = Sk[i, j]
        _skew_into(lev, Sk)
        for i in range(3):
            for j in range(3):
                M[i, j] = -(C[i, 0] * Sk[0, j] + C[i, 1] * Sk[1, j] + C[i, 2] * Sk[2, j])
        _rate_columns(H, kk, M, sf, w, kidx)
        xlev = lidx[L_X_LEVER]
        if xlev >= 0:
            _skew_into(w, Sk)
            for i in range(kk):
                for j in range(3):
                    H[i, xlev + j] = C[i, 0] * Sk[0, j] + C[i, 1] * Sk[1, j] + C[i, 2] * Sk[2, j]
        if kind == KIND_GNSS_VEL:
            for i in range(3):
                nu[i] = v_n[i] + lever_v[i] - d[i]
                R[i, i] = d[3 + i] * d[3 + i]
        else:
            for i in range(2):
                nu[i] = (v_n[i] + lever_v[i]) - d[2 + i]
                R[i, 0], R[i, 1] = d[4 + 2 * i], d[5 + 2 * i]
        return True
    if kind == KIND_ODOMETER:
        # d: speed, sigma; par: lever arm (3), with_nhc, nhc sigma
        kk = 3 if par[3] != 0.0 else 1
        aodo = lidx[L_A_ODO]
        g = 1.0 + aux[aodo] if aodo >= 0 else 1.0
        for i in range(3):
            lev[i] = par[i]
        v_o = v3
        for i in range(3):
            v_o[i] = C[0, i] * v_n[0] + C[1, i] * v_n[1] + C[2, i] * v_n[2]
        _skew_into(v_n, Sk)
        for r in range(kk):
            gr = g if r == 0 else 1.0
            for j in range(3):
                H[r, K.V0 + j] = gr * C[j, r]
                H[r, K.T0 + j] = -gr * (C[0, r] * Sk[0, j] + C[1, r] * Sk[1, j] + C[2, r] * Sk[2, j])
        if lev[0] != 0.0 or lev[1] != 0.0 or lev[2] != 0.0:
            _body_rate(w_raw, aux, kidx, w, sf)
            _cross_into(w, lev, wl)
            for i in range(3):
                v_o[i] = v_o[i] + wl[i]
            _skew_into(lev, Sk)
            for r in range(kk):
                gr = g if r == 0 else 1.0
                for j in range(3):
                    M[r, j] = -gr * Sk[r, j]
            _rate_columns(H, kk, M, sf, w, kidx)
        if aodo >= 0:
            H[0, lidx[L_X_ODO]] = v_o[0]
        for r in range(kk):
            gr = g if r == 0 else 1.0
            nu[r] = gr * v_o[r] - (d[0] if r == 0 else 0.0)
        R[0, 0] = d[1] * d[1]
        for r in range(1, kk):
            R[r, r] = par[4] * par[4]
        return True
    return False


@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _frame_rotation_into(lat, lon, h, C_en, w_n, out):
    """:func:`.tight._frame_rotation`: ``d (C_en w_n) / d p_n`` (3, 3)."""
    rn, re = earth.principal_radii(lat, h)
    s, cl = math.sin(lat), math.cos(lat)
    so, co = math.sin(lon), math.cos(lon)
    for i in range(3):
        out[i, 0] = (C_en[i, 2] * w_n[0] - C_en[i, 0] * w_n[2]) / rn
        out[i, 2] = 0.0
    out[0, 1] = (s * so * w_n[0] - co * w_n[1] + cl * so * w_n[2]) / (re * cl)
    out[1, 1] = (-s * co * w_n[0] - so * w_n[1] - cl * co * w_n[2]) / (re * cl)
    out[2, 1] = 0.0


@njit(cache=True, error_model="numpy")
def linearize_ranges(kind, D, par, dt, lla, v_n, C, w_raw, aux, kidx, lidx, nu, H, R, Mk, vw, mw):
    """:meth:`.tight.Pseudorange.linearize` (``KIND_PSEUDORANGE``) or
    :meth:`.tight.PseudorangeRate.linearize` (``KIND_RANGE_RATE``) of the
    k satellites in the rows of ``D`` (k, :data:`RANGE_WIDTH`), into the
    first k rows of the scratch arrays; ``Mk`` (>= k, 3), ``vw`` (14, 3)
    and ``mw`` (6, 3, 3) are scratch."""
    k = D.shape[0]
    n = H.shape[1]
    for r in range(k):
        nu[r] = 0.0
        for j in range(n):
            H[r, j] = 0.0
        for j in range(k):
            R[r, j] = 0.0
    w, sf, lev, wl, v_a, cl, c_wl, arm, r_a, v_ae, u_e, u_n = (vw[0], vw[1], vw[2], vw[3], vw[4], vw[5], vw[6],
                                                              vw[7], vw[8], vw[9], vw[10], vw[11])
    g_n, a_t = vw[12], vw[13]
    C_en, dr_dp, dv_dp, Sk, B1, B2 = mw[0], mw[1], mw[2], mw[3], mw[4], mw[5]
    tau = dt
    lat, lon, h = lla[0], lla[1], lla[2]
    sl, cla, so, co = math.sin(lat), math.cos(lat), math.sin(lon), math.cos(lon)
    C_en[0, 0], C_en[0, 1], C_en[0, 2] = -sl * co, -so, -cla * co
    C_en[1, 0], C_en[1, 1], C_en[1, 2] = -sl * so, co, -cla * so
    C_en[2, 0], C_en[2, 1], C_en[2, 2] = cla, 0.0, -sl
    _lever_of(aux, lidx, par, lev)
    _body_rate(w_raw, aux, kidx, w, sf)
    _cross_into(w, lev, wl)
    _mat3_vec(C, wl, c_wl)
    _mat3_vec(C, lev, cl)
    for i in range(3):
        v_a[i] = v_n[i] + c_wl[i]
        arm[i] = cl[i] + v_a[i] * tau
    _, re0 = earth.principal_radii(lat, 0.0)
    r_a[0] = (re0 + h) * cla * co
    r_a[1] = (re0 + h) * cla * so
    r_a[2] = (re0 * (1.0 - earth.E2) + h) * sl
    for i in range(3):
        r_a[i] += C_en[i, 0] * arm[0] + C_en[i, 1] * arm[1] + C_en[i, 2] * arm[2]
    _mat3_vec(C_en, v_a, v_ae)
    _frame_rotation_into(lat, lon, h, C_en, arm, dr_dp)
    for i in range(3):
        for j in range(3):
            dr_dp[i, j] += C_en[i, j]
    _frame_rotation_into(lat, lon, h, C_en, v_a, dv_dp)
    xlev = lidx[L_X_LEVER]
    lever_terms = lev[0] != 0.0 or lev[1] != 0.0 or lev[2] != 0.0 or xlev >= 0
    # B1 = -C [l x] (the rate's lever term), B2 = C (I + [w x] tau); the range rate's C [w x] is B2's
    _skew_into(lev, Sk)
    for i in range(3):
        for j in range(3):
            B1[i, j] = -(C[i, 0] * Sk[0, j] + C[i, 1] * Sk[1, j] + C[i, 2] * Sk[2, j])
    _skew_into(w, Sk)
    for i in range(3):
        for j in range(3):
            B2[i, j] = C[i, 0] * Sk[0, j] + C[i, 1] * Sk[1, j] + C[i, 2] * Sk[2, j]
    xc, ac = lidx[L_X_CLOCK], lidx[L_A_CLOCK]
    rate = kind == KIND_RANGE_RATE
    for i in range(3):
        a_t[i] = cl[i] + c_wl[i] * tau
    for r in range(k):
        d0, d1, d2 = r_a[0] - D[r, 0], r_a[1] - D[r, 1], r_a[2] - D[r, 2]
        rng = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        u_e[0], u_e[1], u_e[2] = d0 / rng, d1 / rng, d2 / rng
        for j in range(3):
            u_n[j] = u_e[0] * C_en[0, j] + u_e[1] * C_en[1, j] + u_e[2] * C_en[2, j]
        if not rate:
            for j in range(3):
                H[r, K.P0 + j] = u_e[0] * dr_dp[0, j] + u_e[1] * dr_dp[1, j] + u_e[2] * dr_dp[2, j]
                H[r, K.V0 + j] = u_n[j] * tau
            _skew_into(a_t, Sk)
            for j in range(3):
                H[r, K.T0 + j] = u_n[0] * Sk[0, j] + u_n[1] * Sk[1, j] + u_n[2] * Sk[2, j]
            if lever_terms:
                for j in range(3):
                    Mk[r, j] = (u_n[0] * B1[0, j] + u_n[1] * B1[1, j] + u_n[2] * B1[2, j]) * tau
                if xlev >= 0:
                    for j in range(3):
                        H[r, xlev + j] = (u_n[0] * C[0, j] + u_n[1] * C[1, j] + u_n[2] * C[2, j]) + (
                            u_n[0] * B2[0, j] + u_n[1] * B2[1, j] + u_n[2] * B2[2, j]) * tau
            extra = aux[ac] + aux[ac + 1] * tau
            H[r, xc] = 1.0
            H[r, xc + 1] = tau
            isb_x, isb_a = int(D[r, 8]), int(D[r, 9])
            if isb_x >= 0:
                extra += aux[isb_a]
                H[r, isb_x] = 1.0
            nu[r] = rng + extra - D[r, 6]
        else:
            dv0, dv1, dv2 = v_ae[0] - D[r, 3], v_ae[1] - D[r, 4], v_ae[2] - D[r, 5]
            rr = u_e[0] * dv0 + u_e[1] * dv1 + u_e[2] * dv2
            G0, G1, G2 = (dv0 - u_e[0] * rr) / rng, (dv1 - u_e[1] * rr) / rng, (dv2 - u_e[2] * rr) / rng
            for j in range(3):
                g_n[j] = G0 * C_en[0, j] + G1 * C_en[1, j] + G2 * C_en[2, j]
                H[r, K.P0 + j] = (G0 * dr_dp[0, j] + G1 * dr_dp[1, j] + G2 * dr_dp[2, j]) + (
                    u_e[0] * dv_dp[0, j] + u_e[1] * dv_dp[1, j] + u_e[2] * dv_dp[2, j])
                H[r, K.V0 + j] = u_n[j] + g_n[j] * tau
            _skew_into(c_wl, Sk)
            for j in range(3):
                H[r, K.T0 + j] = u_n[0] * Sk[0, j] + u_n[1] * Sk[1, j] + u_n[2] * Sk[2, j]
            _skew_into(a_t, Sk)
            for j in range(3):
                H[r, K.T0 + j] += g_n[0] * Sk[0, j] + g_n[1] * Sk[1, j] + g_n[2] * Sk[2, j]
            if lever_terms:
                for j in range(3):
                    acc = 0.0
                    for i in range(3):
                        acc += (u_n[i] + g_n[i] * tau) * B1[i, j]
                    Mk[r, j] = acc
                if xlev >= 0:
                    for j in range(3):
                        H[r, xlev + j] = (u_n[0] * B2[0, j] + u_n[1] * B2[1, j] + u_n[2] * B2[2, j]) + (
                            (g_n[0] * C[0, j] + g_n[1] * C[1, j] + g_n[2] * C[2, j])
                            + (g_n[0] * B2[0, j] + g_n[1] * B2[1, j] + g_n[2] * B2[2, j]) * tau)
            H[r, xc + 1] = 1.0
            nu[r] = rr + aux[ac + 1] - D[r, 6]
        R[r, r] = D[r, 7] * D[r, 7]
    if lever_terms:
        _rate_columns(H, k, Mk, sf, w, kidx)
    return True


# --- update ---------------------------------------------------------------------------
@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _innovation_stats(P, nu, H, R, k, cols, nc, PHt, S, L, w):
    """``P H^T``, ``S = H P H^T + R``, its Cholesky factor and the NIS, over
    the ``nc`` non-zero columns of H.  Returns ``(ok, nis)``; ``ok`` False
    when S is not positive definite."""
    n = P.shape[0]
    for i in range(n):
        for r in range(k):
            acc = 0.0
            for c in range(nc):
                j = cols[c]
                acc += P[i, j] * H[r, j]
            PHt[i, r] = acc
    for r in range(k):
        for s in range(k):
            acc = 0.0
            for c in range(nc):
                j = cols[c]
                acc += H[r, j] * PHt[j, s]
            S[r, s] = acc + R[r, s]
    return _cholesky_nis(S, nu, k, L, w)


@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _cholesky_nis(S, nu, k, L, w):
    """``nu^T S^-1 nu`` through the Cholesky factor ``L`` of the leading
    ``k x k`` block of S (``w = L^-1 nu``).  Returns ``(ok, nis)``; ``ok``
    False when S is not positive definite (or not finite)."""
    for r in range(k):
        for s in range(r + 1):
            acc = S[r, s]
            for m in range(s):
                acc -= L[r, m] * L[s, m]
            if r == s:
                if not acc > 0.0 or not math.isfinite(acc):
                    return False, 0.0
                L[r, r] = math.sqrt(acc)
            else:
                L[r, s] = acc / L[s, s]
    nis = 0.0
    for r in range(k):
        acc = nu[r]
        for m in range(r):
            acc -= L[r, m] * w[m]
        w[r] = acc / L[r, r]
        nis += w[r] * w[r]
    return True, nis


@njit(cache=True, error_model="numpy", no_cpython_wrapper=True, fastmath={"contract"})
def _joseph(P, nu, S, k, PHt, L, Kg, M, y, dx, KT, HP):
    """Gain ``K = P H^T S^-1``, correction ``dx = K nu`` and the Joseph-form
    posterior in place.

    ``(I - K H) P (I - K H)^T + K R K^T = P - K (H P) - (P H^T - K S) K^T``
    for any K (expand and use ``S = H P H^T + R``), so the Joseph form costs
    one pass over the upper triangle with 2k terms (``H P = (P H^T)^T``, P
    being symmetric), mirrored; ``M = P H^T - K S`` is the rounding-level
    term that keeps the result second order in an error of K.  ``KT`` and
    ``HP`` (k, n) hold K and H P by rows for the inner loops."""
    n = P.shape[0]
    for i in range(n):
        for r in range(k):
            acc = PHt[i, r]
            for m in range(r):
                acc -= L[r, m] * y[m]
            y[r] = acc / L[r, r]
        for r in range(k - 1, -1, -1):
            acc = y[r]
            for m in range(r + 1, k):
                acc -= L[m, r] * Kg[i, m]
            Kg[i, r] = acc / L[r, r]
        acc = 0.0
        for r in range(k):
            acc += Kg[i, r] * nu[r]
            KT[r, i] = Kg[i, r]
            HP[r, i] = PHt[i, r]
        dx[i] = acc
        for r in range(k):
            acc = PHt[i, r]
            for s in range(k):
                acc -= Kg[i, s] * S[s, r]
            M[i, r] = acc
    for i in range(n):
        for r in range(k):
            a, b = Kg[i, r], M[i, r]
            for j in range(i, n):
                P[i, j] -= a * HP[r, j] + b * KT[r, j]
    for i in range(n):
        for j in range(i + 1, n):
            P[j, i] = P[i, j]


@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _nis_inflated(P, nu, H, R, k, alpha, Pa, S, L, w):
    """NIS of ``nu`` with the navigation rows and columns (0..8) of P scaled
    by ``sqrt(alpha)`` each (written into ``Pa``)."""
    n = P.shape[0]
    sa = math.sqrt(alpha)
    for i in range(n):
        di = sa if i < 9 else 1.0
        for j in range(n):
            dj = sa if j < 9 else 1.0
            Pa[i, j] = P[i, j] * di * dj
    return _nis_full(Pa, nu, H, R, k, S, L, w)  # S is positive definite: P and R are


@njit(cache=True, error_model="numpy")
def inflate_to_pass(P, nu, H, R, k, thr, Pa, S, L, w):
    """:func:`.engine._inflate_to_pass`: scale the navigation blocks of P by
    the smallest ``alpha`` of 2, 8, 32, ... for which ``nu`` passes the gate
    ``thr``; P is replaced in place."""
    alpha = 2.0
    v = _nis_inflated(P, nu, H, R, k, alpha, Pa, S, L, w)
    while v > thr and alpha < 1e16:
        alpha *= 4.0
        v = _nis_inflated(P, nu, H, R, k, alpha, Pa, S, L, w)
    n = P.shape[0]
    for i in range(n):
        for j in range(n):
            P[i, j] = Pa[i, j]
    return alpha


@njit(cache=True, error_model="numpy")
def consistent(rej_t, rej_k, rej_nu, rej_rd, count, t, nu, rd, k, P):
    """:func:`.engine._consistent` over the last ``count`` rejections held
    (times ``rej_t``, rows ``rej_k``, innovations ``rej_nu``, noise
    variances ``rej_rd``) and the current innovation ``(t, nu, rd)`` of k
    rows: innovations of different lengths never agree."""
    nh = rej_t.shape[0]
    total = count + 1
    if total < 2:
        return False
    first = nh - count
    for a in range(count):
        if rej_k[first + a] != k:
            return False
    sv2 = max(P[3, 3], max(P[4, 4], P[5, 5]))
    for a in range(total):
        ia = first + a
        ta = rej_t[ia] if a < count else t
        for b in range(a + 1, total):
            ib = first + b
            tb = rej_t[ib] if b < count else t
            for r in range(k):
                na = rej_nu[ia, r] if a < count else nu[r]
                nb = rej_nu[ib, r] if b < count else nu[r]
                ra = rej_rd[ia, r] if a < count else rd[r]
                rb = rej_rd[ib, r] if b < count else rd[r]
                tol2 = 16.0 * (ra + rb + (tb - ta) ** 2 * sv2)
                if (na - nb) ** 2 > tol2:
                    return False
    return True


#: a drift of the rejected innovations is tested on this many of them at least (:func:`drift`: one degree of
#: freedom per row beyond its three coefficients)
DRIFT_MIN_POINTS = 4
#: ... and on the newest this many at most (a few seconds of fixes: the recovery's evidence, whatever
#: ``gate_max_consecutive`` holds)
DRIFT_MAX_POINTS = 8
#: a measurement fixes the position (its recovery re-initialises the filter, :func:`recover`) when its rows'
#: position columns ``Hp`` give a ``Hp^T W Hp`` whose determinant is at least this fraction of the product of
#: its diagonal (1 for a GNSS fix; a height, or a constraint without position columns, gives 0)
POSITION_RANK_RATIO = 1e-3
#: gravity [m/s^2] by which a drift's horizontal acceleration is read as a tilt error (``atan(a_h / g)``)
TILT_GRAVITY = earth.GAMMA_E


@njit(cache=True, error_model="numpy")
def _solve_small(A, b, m, x):
    """Solve the leading ``m x m`` (m <= 3) system ``A x = b`` by Gaussian
    elimination with partial pivoting (A and b are overwritten); False when
    it is singular."""
    for c in range(m):
        p = c
        for r in range(c + 1, m):
            if abs(A[r, c]) > abs(A[p, c]):
                p = r
        if not abs(A[p, c]) > 0.0:
            return False
        if p != c:
            for j in range(m):
                A[c, j], A[p, j] = A[p, j], A[c, j]
            b[c], b[p] = b[p], b[c]
        for r in range(c + 1, m):
            f = A[r, c] / A[c, c]
            for j in range(c, m):
                A[r, j] -= f * A[c, j]
            b[r] -= f * b[c]
    for c in range(m - 1, -1, -1):
        acc = b[c]
        for j in range(c + 1, m):
            acc -= A[c, j] * x[j]
        x[c] = acc / A[c, c]
    return True


@njit(cache=True, error_model="numpy")
def drift(rej_t, rej_k, rej_nu, rej_rd, count, t, nu, rd, k, thr_fit, rate, accel, g):
    """:func:`.engine._drift` over the last ``count`` rejections held and the
    current innovation ``(t, nu, rd)`` of k rows (the newest
    :data:`DRIFT_MAX_POINTS` of them): writes the rate and
    acceleration of each row into ``rate`` and ``accel`` and the variance
    of a row's rate per unit noise variance into ``g[0]``; returns -1 when
    the rejections differ in length (or their times coincide), 1 when they
    follow one smooth drift (``thr_fit[n - 3]`` the gate of the residual
    sum of squares of each row, ``n = count + 1 >= DRIFT_MIN_POINTS``),
    else 0."""
    nh = rej_t.shape[0]
    count = min(count, DRIFT_MAX_POINTS - 1)
    n = count + 1
    if n < 2:
        return -1
    first = nh - count
    for a in range(count):
        if rej_k[first + a] != k:
            return -1
    m = min(3, n)
    smooth = n >= DRIFT_MIN_POINTS
    A = np.zeros((3, 3))
    b = np.zeros(3)
    c = np.zeros(3)
    base = np.empty(3)
    for a in range(n):  # (B^T B)^-1 [1, 1]: solve B^T B c = e_1
        tau = (rej_t[first + a] if a < count else t) - t
        base[0], base[1], base[2] = 1.0, tau, 0.5 * tau * tau
        for i in range(m):
            for j in range(m):
                A[i, j] += base[i] * base[j]
    b[1] = 1.0
    if not _solve_small(A, b, m, c):
        return -1
    g[0] = c[1]
    for r in range(k):
        for i in range(3):
            b[i] = 0.0
            for j in range(3):
                A[i, j] = 0.0
        for a in range(n):
            ta = rej_t[first + a] if a < count else t
            y = rej_nu[first + a, r] if a < count else nu[r]
            w = 1.0 / (rej_rd[first + a, r] if a < count else rd[r])
            tau = ta - t
            base[0], base[1], base[2] = 1.0, tau, 0.5 * tau * tau
            for i in range(m):
                b[i] += w * base[i] * y
                for j in range(m):
                    A[i, j] += w * base[i] * base[j]
        c[2] = 0.0
        if not _solve_small(A, b, m, c):
            return -1
        if smooth:
            ss = 0.0
            for a in range(n):
                ta = rej_t[first + a] if a < count else t
                y = rej_nu[first + a, r] if a < count else nu[r]
                w = 1.0 / (rej_rd[first + a, r] if a < count else rd[r])
                tau = ta - t
                e = y - (c[0] + c[1] * tau + c[2] * 0.5 * tau * tau)
                ss += w * e * e
            smooth = ss <= thr_fit[n - 3]
        rate[r] = c[1]
        accel[r] = c[2] if m == 3 else 0.0
    return 1 if smooth else 0


@njit(cache=True, error_model="numpy")
def _position_normal(H, rd, k, G):
    """``G = Hp^T W Hp`` (3, 3) of the rows' position columns ``Hp``,
    ``W = diag(1 / rd)``; True when they fix all three axes
    (:data:`POSITION_RANK_RATIO`)."""
    for i in range(3):
        for j in range(3):
            G[i, j] = 0.0
    for r in range(k):
        w = 1.0 / rd[r]
        for i in range(3):
            for j in range(3):
                G[i, j] += H[r, i] * w * H[r, j]
    d0, d1, d2 = G[0, 0], G[1, 1], G[2, 2]
    if not (d0 > 0.0 and d1 > 0.0 and d2 > 0.0):
        return False
    det = (G[0, 0] * (G[1, 1] * G[2, 2] - G[1, 2] * G[2, 1]) - G[0, 1] * (G[1, 0] * G[2, 2] - G[1, 2] * G[2, 0])
           + G[0, 2] * (G[1, 0] * G[2, 1] - G[1, 1] * G[2, 0]))
    return det >= POSITION_RANK_RATIO * d0 * d1 * d2


@njit(cache=True, error_model="numpy")
def fixes_position(H, rd, k):
    """:func:`.engine._to_ned` is not None: the measurement's rows fix the
    position in all three axes."""
    return _position_normal(H, rd, k, np.empty((3, 3)))


@njit(cache=True, error_model="numpy")
def _to_ned(H, rd, k, y, out):
    """:func:`.engine._to_ned` applied to ``y`` (k,), into ``out`` (3,);
    False when the measurement does not fix all three axes."""
    G = np.empty((3, 3))
    if not _position_normal(H, rd, k, G):
        return False
    g = np.zeros(3)
    for r in range(k):
        w = 1.0 / rd[r]
        for i in range(3):
            g[i] += H[r, i] * w * y[r]
    return _solve_small(G, g, 3, out)


#: a drift whose horizontal acceleration says a tilt beyond this [rad] (``atan(a / g)``, 1.2 m/s^2) re-initialises
#: the filter (:func:`recover`); below it the covariance is scaled.  Scaling keeps the correlations the error model
#: built (a tilt's with the drift it causes, a yaw's with the turns), and a constraint that does not hold cannot
#: pull a freshly widened attitude away: a car with its IMU pitched 4 deg under the non-holonomic constraint kept
#: its mounting warning at 3.77 deg (2.94 deg re-initialised) and a car started 90 deg off in yaw recovered twice
#: (13 times re-initialised from 5 deg up).  Near the small-angle limit (10 deg, the yaw bank's) scaling fails: a
#: car started 10 deg off in roll came back only in part and was lost twice more in 90 s, and the drift's tilt
#: is estimated within about 3 deg from 1 Hz fixes of 0.5 m (12.8 deg read as 9.8 deg)
REINIT_ABOVE_TILT = math.radians(7.0)
#: a re-initialised filter takes the drift's velocity with this many times its fit sigma as uncertainty
REINIT_SIGMAS = 4.0


@njit(cache=True, error_model="numpy")
def recover(P, nu, H, R, rd, k, rej_t, rej_k, rej_nu, rej_rd, count, t, thr_k, thr_fit, nav_floor, fix_refused,
            Pa, S, L, w, dxr, info):
    """:func:`.engine._recovery`: True when the rejections held and the
    current innovation are evidence of a lost state.  P is then inflated in
    place for it to pass (:func:`inflate_to_pass`), or the filter is
    re-initialised (:func:`.engine._reinitialise`: ``dxr`` (n,) the
    correction to feed back, ``nu`` made the innovation left); ``info``
    (7,): whether the measurement fixes the position (1.0 or 0.0), the
    position offset [m], the drift's velocity [m/s] and horizontal
    acceleration [m/s^2], the tilt it says [rad] (NaN each when it does not
    fix the position), the covariance's scale and whether re-initialised
    (1.0 or 0.0).  ``fix_refused``: per measurement, whether it fixes the
    position and its latest update was refused."""
    G = np.empty((3, 3))
    fixes = _position_normal(H, rd, k, G)
    linear = consistent(rej_t, rej_k, rej_nu, rej_rd, count, t, nu, rd, k, P)
    for q in range(7):
        info[q] = math.nan
    info[6] = 0.0
    if not fixes:
        if not linear:
            return False
        for q in range(fix_refused.shape[0]):
            if fix_refused[q]:
                return False
        info[0] = 0.0
        info[5] = inflate_to_pass(P, nu, H, R, k, thr_k, Pa, S, L, w)
        return True
    rate = np.empty(k)
    accel = np.empty(k)
    g = np.empty(1)
    code = drift(rej_t, rej_k, rej_nu, rej_rd, count, t, nu, rd, k, thr_fit, rate, accel, g)
    if code < 0 or not (linear or code == 1):
        return False
    dp = np.empty(3)
    dv = np.empty(3)
    da = np.empty(3)
    _to_ned(H, rd, k, nu, dp)
    _to_ned(H, rd, k, rate, dv)
    _to_ned(H, rd, k, accel, da)
    a_h = math.hypot(da[0], da[1])
    tilt = math.atan2(a_h, TILT_GRAVITY)
    info[0] = 1.0
    info[1] = math.sqrt(dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2])
    info[2] = math.sqrt(dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2])
    info[3] = a_h
    info[4] = tilt
    if not tilt > REINIT_ABOVE_TILT:
        info[5] = inflate_to_pass(P, nu, H, R, k, thr_k, Pa, S, L, w)
        return True
    info[6] = 1.0
    cov = np.empty(3)  # (Hp^T W Hp)^-1's diagonal
    e = np.empty(3)
    col = np.empty(3)
    Gc = np.empty((3, 3))
    for q in range(3):
        for i in range(3):
            e[i] = 1.0 if i == q else 0.0
            for j in range(3):
                Gc[i, j] = G[i, j]
        _solve_small(Gc, e, 3, col)
        cov[q] = col[q]
    var = np.empty(9)
    for i in range(9):
        if i < 3:
            add = 0.0
        elif i < 6:
            add = REINIT_SIGMAS * REINIT_SIGMAS * g[0] * cov[i - 3]
        else:
            add = tilt * tilt
        var[i] = max(P[i, i], nav_floor[i]) + add
    n = P.shape[0]
    for i in range(9):
        for j in range(n):
            P[i, j] = 0.0
            P[j, i] = 0.0
    for i in range(9):
        P[i, i] = var[i]
    for i in range(n):
        dxr[i] = 0.0
    for i in range(3):
        dxr[i] = dp[i]
        dxr[3 + i] = dv[i]
    for r in range(k):
        acc = 0.0
        for i in range(6):
            acc += H[r, i] * dxr[i]
        nu[r] = nu[r] - acc
    scale = 1.0
    while scale < 1e16:
        if _nis_full(P, nu, H, R, k, S, L, w) <= thr_k:
            break
        for i in range(3):
            P[i, i] *= 4.0
        scale *= 4.0
    return True


@njit(cache=True, error_model="numpy")
def _nis_full(P, nu, H, R, k, S, L, w):
    """``nu^T (H P H^T + R)^-1 nu`` (NaN when not positive definite)."""
    n = P.shape[0]
    for r in range(k):
        for s in range(k):
            acc = 0.0
            for i in range(n):
                hi = H[r, i]
                if hi != 0.0:
                    for j in range(n):
                        acc += hi * P[i, j] * H[s, j]
            S[r, s] = acc + R[r, s]
    ok, v = _cholesky_nis(S, nu, k, L, w)
    return v if ok else math.nan


@njit(cache=True, error_model="numpy")
def predict_aux(aux, idx, F, t_aux, t):
    """Carry the evolving estimates from ``t_aux[0]`` to ``t`` with
    ``exp(F h)`` to third order (``I + A + A^2 / 2 + A^3 / 6``, ``A = F h``;
    exact for a clock, whose F is nilpotent), in place."""
    h = t - t_aux[0]
    m = idx.shape[0]
    if h > 0 and m > 0:
        A = F * h
        A2 = np.zeros((m, m))
        for i in range(m):
            for j in range(m):
                acc = 0.0
                for r in range(m):
                    acc += A[i, r] * A[r, j]
                A2[i, j] = acc
        G = np.empty((m, m))
        for i in range(m):
            for j in range(m):
                acc = 0.0
                for r in range(m):
                    acc += A2[i, r] * A[r, j]
                G[i, j] = (1.0 if i == j else 0.0) + A[i, j] + A2[i, j] / 2.0 + acc / 6.0
        old = np.empty(m)
        for i in range(m):
            old[i] = aux[idx[i]]
        for i in range(m):
            acc = 0.0
            for j in range(m):
                acc += G[i, j] * old[j]
            aux[idx[i]] = acc
    t_aux[0] = t


# --- the loop over update nodes ---------------------------------------------------------
@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _covariance_ok(P):
    for i in range(P.shape[0]):
        d = P[i, i]
        if not (d > 0.0) or not math.isfinite(d):
            return False
    return True


@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _begin_node(t_imu, dth_all, q_nb, P, aux, Phi, want_store, propagated, k_end, ctl, en_k, en_var, store, dyn,
                w_raw, C):
    """At a node just propagated to IMU row ``k_end``: the rate of its
    interval, the evolving estimates, the gap noise and the smoother's
    prior."""
    if propagated:
        ctl[C_KDONE] = k_end + 1
        h = t_imu[k_end] - t_imu[k_end - 1]
        for i in range(3):
            w_raw[i] = dth_all[k_end, i] / h
        predict_aux(aux, dyn[0], dyn[1], dyn[2], t_imu[k_end])
    n = P.shape[0]
    lo, hi = 0, en_k.shape[0]  # binary search of the sorted gap rows
    while lo < hi:
        mid = (lo + hi) // 2
        if en_k[mid] < k_end:
            lo = mid + 1
        else:
            hi = mid
    if lo < en_k.shape[0] and en_k[lo] == k_end:
        for i in range(n):
            P[i, i] += en_var[lo, i]
    node = ctl[C_NODE] - store[5][0]  # the store may hold the nodes of one segment only (streaming)
    if want_store:
        st_k, st_Pm, st_Phi, st_dx = store[0], store[1], store[3], store[4]
        st_k[node] = k_end
        for i in range(n):
            for j in range(n):
                st_Pm[node, i, j] = P[i, j]
                st_Phi[node, i, j] = Phi[i, j]
                Phi[i, j] = 1.0 if i == j else 0.0
            st_dx[node, i] = 0.0
    K.dcm_into(q_nb, C)
    ctl[C_KCUR] = k_end
    ctl[C_IN_NODE] = 1


@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _end_node(nav, filt, outs, flags, ctl, store, nodes):
    """The smoother's posterior and the node's output row (``write_row``)."""
    lla, v_n, q_nb = nav[0], nav[1], nav[2]
    P, aux = filt[1], filt[2]
    out_lla, out_v, out_q, out_var, obase = outs
    n = P.shape[0]
    node = ctl[C_NODE]
    k = ctl[C_KCUR]
    ko = k - obase[0]  # the output arrays may hold a segment of the run only (streaming)
    if flags[1]:
        st_Pp = store[2]
        js = node - store[5][0]
        for i in range(n):
            for j in range(n):
                st_Pp[js, i, j] = P[i, j]
    for i in range(3):
        out_lla[ko, i] = lla[i]
        out_v[ko, i] = v_n[i]
    for i in range(4):
        out_q[ko, i] = q_nb[i]
    for i in range(n):
        out_var[ko, i] = P[i, i]
    node_rows, node_aux = nodes
    r = ctl[C_NROW]
    node_rows[r] = k
    for i in range(aux.shape[0]):
        node_aux[r, i] = aux[i]
    ctl[C_NROW] = r + 1
    ctl[C_NODE] = node + 1
    ctl[C_IN_NODE] = 0


@njit(cache=True, error_model="numpy", nogil=True)  # nogil: a streamed run writes its files meanwhile
def run_nodes(imu, nav, filt, model, outs, flags, items, meas, lidx, gate, rstate, recs, recov, counts, store,
              nodes, dyn, fb, w_raw, C, ctl):
    """Run the filter over update nodes from item ``ctl[C_I]`` (see the
    module text).

    Parameters
    ----------
    imu, nav, filt, model, outs, flags
        As :func:`._kernel.propagate` (closed loop: ``flags[2]`` False;
        ``flags[1]`` keeps the smoother's store).
    items : tuple ``(k, t, m, row, en_k, en_var)``
        Per update item (sorted by IMU row, then time): its IMU row, time,
        measurement (-1: a node without one) and own data row; the rows that
        get gap noise (sorted) and their (n,) variances.
    meas : tuple ``(kind, k, d_off, d_w, data, p_off, par, i_off, index, per_row)``
        Per measurement: kind code (-1: no compiled form, handed back), rows
        of its updates, offset and width of its data rows in ``data`` (flat),
        offset of its parameters in ``par``, offset of its table index in
        ``index`` (-1: one data row per update) and whether it is gated row
        by row.
    lidx : (8,) int64
        :func:`layout_index`.
    gate : tuple ``(gpar, thr, thr_fit, nav_floor)``
        ``gpar = [gate on, max consecutive (-1: no recovery), recovery after
        s]``; ``thr[k]`` the chi-square gate of k rows, up to the most rows
        of any update (which sizes the scratch); ``thr_fit[d]`` the gate of
        a drift's residuals with d degrees of freedom (:func:`drift`);
        ``nav_floor`` the initial variances of the navigation states
        (:func:`recover`).
    rstate : tuple ``(streak, first, rej_t, rej_k, rej_nu, rej_rd, rej_n, fix_refused, recovered_t)``
        Per measurement: its run of rejections (count, time of the first),
        the newest ones held (times, rows, innovations, noise variances) and
        whether it fixes the position and its latest update was refused;
        then the time of the latest recovery on a measurement that fixes
        the position ((1,): a run of rejections begun before it is
        dropped).  The last two are shared with Python's path.
    recs : tuple ``(m, item, t, nis, accepted, k, off, nu, sigma, status)``
        Innovation records from ``ctl[C_NREC]`` on; record j's ``k`` rows of
        innovation, sigma and status (int8: accepted 0, refused by the row's
        own gate 1, refused with the whole update 2, as
        :data:`.engine.ROW_STATUS`) start at ``off[j]`` of the flat ``nu``,
        ``sigma`` and ``status`` (filled from ``ctl[C_NFLAT]`` on).
    recov : tuple ``(m, item, t, after, rejected_for, info)``
        Recoveries, from ``ctl[C_NRECOV]`` on; ``info`` (T, 7):
        :func:`recover`'s figures.
    counts : (M, N_COUNTS) int64
        used, rejected, skipped, rows, rows rejected, row-gated updates.
    store : tuple ``(k, P_minus, P_plus, Phi, dx, base)``
        Per node; node ``j`` at index ``j - base[0]`` (``base``: (1,)
        int64; a streamed run holds one segment's nodes).
    nodes : tuple ``(rows, aux)``
        The output rows written and the estimates held from each.
    dyn : tuple ``(idx, F, t_aux)``
        :meth:`StateLayout.estimate_dynamics` and the estimates' time.
    fb : tuple ``(aux_idx, x_idx)``
        The default feedback ``aux[aux_idx] -= dx[x_idx]``.
    w_raw : (3,) ndarray
        Raw rate of the node's interval (shared with Python's contexts).
    C : (3, 3) ndarray
        ``C_nb`` scratch.
    ctl : (C_SIZE,) int64
        Loop state (item, rows done, in a node, the node's row, node count,
        rows written, records, recoveries, row to stop at, flat records).

    Returns
    -------
    int
        ``DONE``, ``HANDBACK`` (at item ``ctl[C_I]``, inside its node),
        ``CHUNK`` (``ctl[C_KSTOP]`` reached, between nodes), or a divergence:
        ``BAD_INNOVATION``, ``NOT_PD``, ``BAD_ROWS`` (at item ``ctl[C_I]``),
        ``LOST_PD`` (at the node of row ``ctl[C_KCUR]``).
    """
    lla, v_n, q_nb = nav[0], nav[1], nav[2]
    P, aux = filt[1], filt[2]
    it_k, it_t, it_m, it_row, en_k, en_var = items
    kinds, mk, d_off, d_w, data, p_off, par, i_off, index, per_row = meas
    gpar, thr, thr_fit, nav_floor = gate
    streak, first_rej, rej_t, rej_k, rej_nu, rej_rd, rej_n, fix_refused, recovered_t = rstate
    rec_m, rec_i, rec_t, rec_nis, rec_acc, rec_k, rec_off, rec_nu, rec_sig, rec_st = recs
    rv_m, rv_i, rv_t, rv_after, rv_for, rv_info = recov
    rinfo = np.empty(7)
    dxr = np.empty(P.shape[0])
    st_dx = store[4]
    def_aux, def_x = fb
    t_imu = imu[0]
    kidx = model[0]
    n = P.shape[0]
    want_store = flags[1]
    gate_on = gpar[0] != 0.0
    gmc = int(gpar[1])
    recovery_after = gpar[2]
    km = thr.shape[0] - 1
    pwork = K.propagation_work(model, model[4].shape[0])
    nu = np.empty(km)
    H = np.empty((km, n))
    R = np.empty((km, km))
    cols = np.empty(n, np.int64)
    PHt = np.empty((n, km))
    S = np.empty((km, km))
    L = np.zeros((km, km))
    wv = np.empty(km)
    rd = np.empty(km)
    s_rows = np.empty(km)
    keep = np.empty(km, np.bool_)
    Kg = np.empty((n, km))
    Aw = np.empty((n, n))
    AHt = np.empty((n, km))
    y = np.empty(km)
    dx = np.empty(n)
    KT = np.empty((km, n))
    HP = np.empty((km, n))
    Mk = np.empty((km, 3))
    vw = np.empty((14, 3))
    mw = np.empty((6, 3, 3))
    n_items = it_k.shape[0]
    i = ctl[C_I]
    if ctl[C_IN_NODE]:
        K.dcm_into(q_nb, C)  # Python may have fed an update back since
    while True:
        if ctl[C_IN_NODE]:
            k_cur = ctl[C_KCUR]
            while i < n_items and it_k[i] == k_cur:
                m = it_m[i]
                if m < 0:
                    i += 1
                    continue
                kind = kinds[m]
                if kind < 0:
                    ctl[C_I] = i
                    return HANDBACK
                tm = it_t[i]
                row = it_row[i]
                pm = par[p_off[m]:]
                if i_off[m] >= 0:  # a table: the rows of this update
                    ra, rb = index[i_off[m] + row], index[i_off[m] + row + 1]
                    k = rb - ra
                    ok = k > 0
                    if ok:
                        w_m = d_w[m]
                        D = data[d_off[m] + ra * w_m:d_off[m] + rb * w_m].reshape(k, w_m)
                        ok = linearize_ranges(kind, D, pm, tm - t_imu[k_cur], lla, v_n, C, w_raw, aux, kidx, lidx,
                                              nu, H, R, Mk, vw, mw)
                else:
                    k = mk[m]
                    d = data[d_off[m] + row * d_w[m]:d_off[m] + (row + 1) * d_w[m]]
                    ok = linearize(kind, d, pm, tm - t_imu[k_cur], lla, v_n, C, w_raw, aux, kidx, lidx, nu, H, R,
                                   vw, mw)
                if not ok:
                    counts[m, N_SKIPPED] += 1
                    i += 1
                    continue
                for r in range(k):
                    rd[r] = R[r, r]
                nc = 0
                for j in range(n):
                    nz = False
                    for r in range(k):
                        if H[r, j] != 0.0:
                            nz = True
                    if nz:
                        cols[nc] = j
                        nc += 1
                fixes = 1 if gate_on and gmc >= 0 and fixes_position(H, rd, k) else 0
                st = streak[m]
                held = rej_n[m]
                if st and first_rej[m] <= recovered_t[0]:  # refused by the state before a recovery on the fixes
                    st = streak[m] = 0
                    held = rej_n[m] = 0
                    fix_refused[m] = 0
                if (gate_on and gmc >= 0 and st >= gmc and tm - first_rej[m] >= recovery_after
                        and recover(P, nu, H, R, rd, k, rej_t[m], rej_k[m], rej_nu[m], rej_rd[m],
                                    held if gmc == 0 else min(gmc, held), tm, thr[k], thr_fit, nav_floor, fix_refused,
                                    Aw, S, L, wv, dxr, rinfo)):
                    if rinfo[6] != 0.0:  # re-initialised: position and velocity reset (nu is what is left)
                        K.apply_correction(lla, v_n, q_nb, dxr, 1.0, lla, v_n, q_nb)
                        if want_store:
                            node = ctl[C_NODE] - store[5][0]
                            for e in range(n):
                                st_dx[node, e] += dxr[e]
                    if rinfo[0] != 0.0:
                        recovered_t[0] = tm
                    j = ctl[C_NRECOV]
                    rv_m[j], rv_i[j], rv_t[j], rv_after[j], rv_for[j] = m, i, tm, st, tm - first_rej[m]
                    for q in range(7):
                        rv_info[j, q] = rinfo[q]
                    ctl[C_NRECOV] = j + 1
                # the record: the whole innovation, with the sigmas of the rows' own gate when rows were refused
                jr = ctl[C_NREC]
                o = ctl[C_NFLAT]
                rec_m[jr], rec_i[jr], rec_t[jr], rec_k[jr], rec_off[jr] = m, i, tm, k, o
                for r in range(k):
                    rec_nu[o + r] = nu[r]
                    rec_st[o + r] = 0
                ctl[C_NREC] = jr + 1
                ctl[C_NFLAT] = o + k
                gate_vec = gate_on
                refused = 0
                if gate_on and per_row[m]:  # inskit.filters.kalman.gate_rows, then the rows that pass
                    gate_vec = False
                    for r in range(k):
                        acc = 0.0
                        for c in range(nc):
                            j = cols[c]
                            hp = 0.0
                            for c2 in range(nc):
                                hp += P[j, cols[c2]] * H[r, cols[c2]]
                            acc += H[r, j] * hp
                        s_rows[r] = acc + R[r, r]
                        if not (math.isfinite(nu[r]) and math.isfinite(s_rows[r]) and s_rows[r] > 0.0):
                            ctl[C_I] = i
                            return BAD_ROWS
                        keep[r] = nu[r] * nu[r] / s_rows[r] <= thr[1]
                        if not keep[r]:
                            refused += 1
                            rec_st[o + r] = 1
                    counts[m, N_ROWS] += k
                    counts[m, N_ROWS_REJECTED] += refused
                    counts[m, N_ROW_GATED] += 1
                    if refused:
                        counts[m, N_REJECTED] += 1
                        for r in range(k):
                            rec_sig[o + r] = math.sqrt(s_rows[r])
                        if refused == k:
                            nis = 0.0
                            for r in range(k):
                                nis += nu[r] * nu[r] / s_rows[r]
                            rec_nis[jr], rec_acc[jr] = nis, False
                            _hold_rejection(m, tm, nu, rd, k, streak, first_rej, rej_t, rej_k, rej_nu, rej_rd,
                                            rej_n)
                            fix_refused[m] = fixes
                            i += 1
                            continue
                        # keep the rows that pass, in order
                        kk = 0
                        for r in range(k):
                            if keep[r]:
                                nu[kk] = nu[r]
                                for j in range(n):
                                    H[kk, j] = H[r, j]
                                kk2 = 0
                                for r2 in range(k):
                                    if keep[r2]:
                                        S[kk, kk2] = R[r, r2]
                                        kk2 += 1
                                kk += 1
                        for r in range(kk):
                            for r2 in range(kk):
                                R[r, r2] = S[r, r2]
                        k = kk
                for r in range(k):
                    if not math.isfinite(nu[r]):
                        ctl[C_I] = i
                        return BAD_INNOVATION
                ok, nis = _innovation_stats(P, nu, H, R, k, cols, nc, PHt, S, L, wv)
                if not ok:
                    ctl[C_I] = i
                    return NOT_PD
                accepted = not (gate_vec and nis > thr[k])
                rec_nis[jr], rec_acc[jr] = nis, accepted
                if not refused:
                    for r in range(k):
                        rec_sig[o + r] = math.sqrt(S[r, r])
                if not accepted:
                    for r in range(k):  # a vector gate (no row refused alone): every row goes with the update
                        rec_st[o + r] = 2
                    _hold_rejection(m, tm, nu, rd, k, streak, first_rej, rej_t, rej_k, rej_nu, rej_rd, rej_n)
                    fix_refused[m] = fixes
                    counts[m, N_REJECTED] += 1
                    i += 1
                    continue
                streak[m] = 0
                rej_n[m] = 0
                fix_refused[m] = 0
                counts[m, N_USED] += 1
                _joseph(P, nu, S, k, PHt, L, Kg, AHt, y, dx, KT, HP)
                K.apply_correction(lla, v_n, q_nb, dx, 1.0, lla, v_n, q_nb)
                for e in range(def_aux.shape[0]):
                    aux[def_aux[e]] -= dx[def_x[e]]
                if want_store:
                    node = ctl[C_NODE] - store[5][0]
                    for e in range(n):
                        st_dx[node, e] += dx[e]
                K.dcm_into(q_nb, C)
                i += 1
            if not _covariance_ok(P):
                ctl[C_I] = i
                return LOST_PD
            _end_node(nav, filt, outs, flags, ctl, store, nodes)
        ctl[C_I] = i
        if i >= n_items:
            return DONE
        k_end = it_k[i]
        if k_end >= ctl[C_KSTOP]:
            return CHUNK
        propagated = k_end + 1 > ctl[C_KDONE]
        if propagated:
            # model[1] may end with the body-axis noise (n + 6 entries), which propagate_rows rotates into NED.
            # numba caches this loop with propagate_rows inlined and keys the cache on this file only:
            # inskit._numba_cache clears it when _kernel.py (or any compiled source) changes
            K.propagate_rows(imu, nav, filt, model, outs, ctl[C_KDONE], k_end + 1, flags, pwork)
        _begin_node(t_imu, imu[1], q_nb, P, aux, filt[3], want_store, propagated, k_end, ctl, en_k, en_var, store,
                    dyn, w_raw, C)


@njit(cache=True, error_model="numpy", no_cpython_wrapper=True)
def _hold_rejection(m, tm, nu, rd, k, streak, first_rej, rej_t, rej_k, rej_nu, rej_rd, rej_n):
    """One more rejection of measurement ``m``: its streak, the time of the
    run's first, and the newest rejections held, oldest first, at the end of
    the rows (the Python path's bounded list)."""
    held = rej_n[m]
    n_hold = rej_t.shape[1]
    streak[m] += 1
    if held == 0:
        first_rej[m] = tm
    for h in range(n_hold - 1):
        rej_t[m, h] = rej_t[m, h + 1]
        rej_k[m, h] = rej_k[m, h + 1]
        for r in range(rej_nu.shape[2]):
            rej_nu[m, h, r] = rej_nu[m, h + 1, r]
            rej_rd[m, h, r] = rej_rd[m, h + 1, r]
    rej_t[m, n_hold - 1] = tm
    rej_k[m, n_hold - 1] = k
    for r in range(k):
        rej_nu[m, n_hold - 1, r] = nu[r]
        rej_rd[m, n_hold - 1, r] = rd[r]
    rej_n[m] = min(held + 1, n_hold)
