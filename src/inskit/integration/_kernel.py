"""Compiled propagation of the INS/GNSS error-state filter between updates.

One call integrates IMU rows ``k0 .. k1-1``: sensor corrections, the NED
mechanization (the very step of :func:`inskit.strapdown.kernels.ned_step`),
the transition matrix ``F`` of the error model, the covariance
``P <- Phi P Phi^T + Q dt`` with ``Phi = I + F dt`` and, when asked, the
transition accumulated over the segment (for the RTS smoother).

``F`` is filled only on its non-zero pattern (``rows``, ``cols`` from
:meth:`StateLayout.transition_pattern`), and the products ``F P`` and
``F (F P)^T`` run over that pattern alone: about 90 entries for 21 states
instead of 441.  The kernel fills the navigation-error entries and the
couplings of the four inertial-sensor roles at every epoch; every other
entry is a constant declared by a block, written once per call from
``(crow, ccol, cval)``.

Error model (x = estimate - truth; phi: ``C_nb_est = (I - [phi x]) C_nb``),
after Groves 2013 eq. 14.64-14.71, position error in NED metres:

* ``d pos = vel``;
* ``d vel = [f_n x] phi - (2 w_ie + w_en) x vel - (d g / d h) pD`` (the
  gradient of the selected gravity model, :func:`inskit.earth.gravity_down_dh_model`)
  - C_nb S_a^-1 (ba + diag(f_b) sa)``;
* ``d phi = -w_in x phi + d w_en(vel) + C_nb S_g^-1 (bg + diag(w_b) sg)``,
  ``S = diag(1 + s)`` the current scale-factor corrections;
* blocks' own constant entries (``-1 / tau`` of Gauss-Markov states, clock
  drift into bias, ...).

Dropped on purpose, as in Groves' short-term model, because each is of order
``|v| / R`` (3e-6 1/s at 20 m/s, a 2e-4 relative change of an error over a
60 s outage) and each sparse entry costs about 3 % of the propagation:

* the transport of the position error, ``(vN pD - vD pN) / R_N`` in ``d pN``
  and ``(vE tanL pN) / R_N + vE pD / R_E - (vD / R_E + vN tanL / R_N) pE`` in
  ``d pE``;
* the velocity error's own transport-rate term ``v x d w_en(vel)``;
* the height gradient of gravity's north component (8e-9 1/s^2);
* position into the Earth and transport rates, Coriolis and gravity's
  latitude dependence (below 1e-8 1/s^2 for speeds under 300 m/s).

``tests/test_integration_kernel.py`` checks that F plus exactly these terms
equals the finite-difference Jacobian of the compiled NED step.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import earth
from ..earth import gravity_down_dh_model, principal_radii, radii_and_gravity_gradient
from ..rotations import qmul, quat_dcm, rotvec_quat
from ..strapdown.kernels import ned_step, store_unit

W_IE = earth.OMEGA_IE
# kernel index array (StateLayout.kernel_index): state starts of the sensor
# roles, their starts in aux, the state size
X_BG, X_BA, X_SG, X_SA, A_BG, A_BA, A_SG, A_SA, N_STATES = 0, 1, 2, 3, 4, 5, 6, 7, 8
P0, V0, T0 = 0, 3, 6  # the navigation blocks' fixed starts


@njit(cache=True, inline="always")
def dcm_into(q, C):
    """``C <- C(q)`` (3, 3)."""
    c = quat_dcm(q[0], q[1], q[2], q[3])
    C[0, 0], C[0, 1], C[0, 2] = c[0], c[1], c[2]
    C[1, 0], C[1, 1], C[1, 2] = c[3], c[4], c[5]
    C[2, 0], C[2, 1], C[2, 2] = c[6], c[7], c[8]


@njit(cache=True)
def fill_transition(F, kidx, lla, v_n, C, f_b, w_b, sc, gravity=0):
    """Write the epoch-dependent entries of the continuous-time F.

    Parameters
    ----------
    F : (n, n) ndarray
        Written in place on the navigation rows and the sensor couplings;
        other entries are left as they are (constants).
    kidx : (9,) int64
        :meth:`StateLayout.kernel_index`.
    lla, v_n : (3,) ndarray
        Navigation state (rad, rad, m; m/s).
    C : (3, 3) ndarray
        ``C_nb``.
    f_b, w_b : (3,) ndarray
        Corrected specific force [m/s^2] and angular rate [rad/s].
    sc : (12,) ndarray
        :func:`sensor_corrections` of the current estimates: the corrections
        ``(raw - b dt) / (1 + s)`` make a bias error enter as ``-1 / (1 + s)``
        and a scale-factor error as ``-f / (1 + s)``.
    gravity : int
        Code of the gravity model (:data:`inskit.earth.GRAVITY_MODELS`): its
        own ``d g_D / d h`` enters the height row, so F stays the Jacobian of
        the mechanization step that uses that model.
    """
    lat, h = lla[0], lla[2]
    sl, cl = math.sin(lat), math.cos(lat)
    rn, re, dgd_dh = radii_and_gravity_gradient(sl, h)
    if gravity != 0:
        dgd_dh = gravity_down_dh_model(lat, h, gravity)
    tl = sl / cl
    vn, ve = v_n[0], v_n[1]
    wie0, wie2 = W_IE * cl, -W_IE * sl
    wen0, wen1, wen2 = ve / re, -vn / rn, -ve * tl / re
    p, v, a = P0, V0, T0
    # position: velocity
    for i in range(3):
        F[p + i, v + i] = 1.0
    # gravity with height (x_D = -(h_est - h_true))
    F[v + 2, p + 2] = -dgd_dh
    # velocity: -(2 w_ie + w_en) x dv
    w0, w1, w2 = 2.0 * wie0 + wen0, wen1, 2.0 * wie2 + wen2
    F[v + 0, v + 1] = w2
    F[v + 0, v + 2] = -w1
    F[v + 1, v + 0] = -w2
    F[v + 1, v + 2] = w0
    F[v + 2, v + 0] = w1
    F[v + 2, v + 1] = -w0
    # velocity: specific force, [f_n x] phi
    f0 = C[0, 0] * f_b[0] + C[0, 1] * f_b[1] + C[0, 2] * f_b[2]
    f1 = C[1, 0] * f_b[0] + C[1, 1] * f_b[1] + C[1, 2] * f_b[2]
    f2 = C[2, 0] * f_b[0] + C[2, 1] * f_b[1] + C[2, 2] * f_b[2]
    F[v + 0, a + 1] = -f2
    F[v + 0, a + 2] = f1
    F[v + 1, a + 0] = f2
    F[v + 1, a + 2] = -f0
    F[v + 2, a + 0] = -f1
    F[v + 2, a + 1] = f0
    # attitude: -w_in x phi and the transport-rate error
    u0, u1, u2 = wie0 + wen0, wen1, wie2 + wen2
    F[a + 0, a + 1] = u2
    F[a + 0, a + 2] = -u1
    F[a + 1, a + 0] = -u2
    F[a + 1, a + 2] = u0
    F[a + 2, a + 0] = u1
    F[a + 2, a + 1] = -u0
    F[a + 0, v + 1] = 1.0 / re
    F[a + 1, v + 0] = -1.0 / rn
    F[a + 2, v + 1] = -tl / re
    ba, bg, sa, sg = kidx[X_BA], kidx[X_BG], kidx[X_SA], kidx[X_SG]
    for j in range(3):
        ig = sc[6 + j]
        ia = sc[9 + j]
        for i in range(3):
            if ba >= 0:
                F[v + i, ba + j] = -C[i, j] * ia
            if bg >= 0:
                F[a + i, bg + j] = C[i, j] * ig
            if sa >= 0:
                F[v + i, sa + j] = -C[i, j] * f_b[j] * ia
            if sg >= 0:
                F[a + i, sg + j] = C[i, j] * w_b[j] * ig


@njit(cache=True, fastmath={"contract"})
def propagate_covariance(P, F, rows, cols, active, dt, q_psd, A, B, T, second_order):
    """``P <- (I + F dt) P (I + F dt)^T + diag(q_psd) dt`` over F's pattern.

    ``active`` lists the rows of F that hold any pattern entry.  ``A = F P``
    is non-zero only on those rows, so ``A + A^T`` touches only their rows and
    columns and ``F P F^T`` only the active-by-active block: the update costs
    O(pattern * n + active^2) instead of O(n^2).  Without ``second_order`` the
    ``dt^2 F P F^T`` term is dropped (Euler integration of the Riccati
    equation): cheaper, but not guaranteed positive semi-definite when
    uncertainties are large (a MEMS car run lost positiveness at 177 s), so the
    filter keeps it.  ``A`` (n, n), ``B`` (n, n) and ``T`` (n, len(active))
    are scratch.
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
        # dt^2 F P F^T = dt^2 F A^T on the active block; B[i, c] for active
        # column c, from At[j, c] = A[active[c], j] so the inner loop is contiguous
        for j in range(n):
            for c in range(na):
                T[j, c] = A[active[c], j]
        for r in range(na):
            i = active[r]
            for c in range(na):
                B[i, c] = 0.0
        dt2 = dt * dt
        for e in range(rows.shape[0]):
            i, j = rows[e], cols[e]
            fij = F[i, j] * dt2
            for c in range(na):
                B[i, c] += fij * T[j, c]
        for r in range(na):
            i = active[r]
            for c in range(na):
                P[i, active[c]] += B[i, c]
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


@njit(cache=True, inline="always")
def add_body_noise(P, C, q_psd, n, dt):
    """``P[blk] += C diag(q_b) C^T dt`` on the attitude and velocity blocks,
    ``q_b = q_psd[n:n+3]`` (gyro) and ``q_psd[n+3:n+6]`` (accelerometer):
    white noise per body axis, rotated into NED by the attitude of the step."""
    for blk, off in ((T0, n), (V0, n + 3)):
        for i in range(3):
            for j in range(i, 3):
                s = 0.0
                for m in range(3):
                    s += C[i, m] * q_psd[off + m] * C[j, m]
                s *= dt
                P[blk + i, blk + j] += s
                if j != i:
                    P[blk + j, blk + i] += s


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
def apply_correction(lla, v_n, q_nb, x, sign, out_lla, out_v, out_q):
    """Navigation state corrected by ``sign * x`` (sign=1: subtract the
    estimated errors, as closed-loop feedback and open-loop output both do;
    sign=-1 adds them, making an erroneous state from a true one).  The
    outputs may be the inputs themselves (in-place feedback)."""
    p, v, a = P0, V0, T0
    lat, lon, h = lla[0], lla[1], lla[2]
    rn, re = principal_radii(lat, h)
    out_lla[0] = lat - sign * x[p] / rn
    out_lla[1] = lon - sign * x[p + 1] / (re * math.cos(lat))
    out_lla[2] = h + sign * x[p + 2]
    for i in range(3):
        out_v[i] = v_n[i] - sign * x[v + i]
    a0, a1, a2, a3 = rotvec_quat(sign * x[a], sign * x[a + 1], sign * x[a + 2])
    r0, r1, r2, r3 = qmul(a0, a1, a2, a3, q_nb[0], q_nb[1], q_nb[2], q_nb[3])
    store_unit(out_q, r0, r1, r2, r3)


@njit(cache=True)
def sensor_corrections(kidx, aux):
    """(12,) ``[b_g, b_a, 1 / (1 + s_g), 1 / (1 + s_a)]`` from the estimates
    (zeros and ones for absent blocks): constant between updates, so made once
    per propagation call."""
    sc = np.zeros(12)
    abg, aba, asg, asa = kidx[A_BG], kidx[A_BA], kidx[A_SG], kidx[A_SA]
    for i in range(3):
        if abg >= 0:
            sc[i] = aux[abg + i]
        if aba >= 0:
            sc[3 + i] = aux[aba + i]
        sc[6 + i] = 1.0 / (1.0 + aux[asg + i]) if asg >= 0 else 1.0
        sc[9 + i] = 1.0 / (1.0 + aux[asa + i]) if asa >= 0 else 1.0
    return sc


@njit(cache=True, inline="always")
def correct_increments(sc, dth_raw, dv_raw, dt, dth, dv, w_b, f_b):
    """Sensor corrections of one interval, ``(raw - bias dt) / (1 + scale)``,
    and the corrected rate and specific force (``sc``: :func:`sensor_corrections`)."""
    inv_dt = 1.0 / dt
    for i in range(3):
        dth[i] = (dth_raw[i] - sc[i] * dt) * sc[6 + i]
        dv[i] = (dv_raw[i] - sc[3 + i] * dt) * sc[9 + i]
        w_b[i] = dth[i] * inv_dt
        f_b[i] = dv[i] * inv_dt


@njit(cache=True)
def propagation_work(model, n_active):
    """Scratch of :func:`propagate_rows` for a layout: ``F`` with the blocks'
    constant entries written, and the work arrays of the covariance step.
    Every entry :func:`propagate_rows` reads is written first, so one work
    tuple serves any number of calls (only F's constants carry over)."""
    kidx, crow, ccol, cval = model[0], model[5], model[6], model[7]
    n = kidx[N_STATES]
    F = np.zeros((n, n))
    for e in range(crow.shape[0]):
        F[crow[e], ccol[e]] = cval[e]
    return (F, np.empty((n, n)), np.zeros((n, n)), np.empty((n, n_active)), np.empty((n, n)),
            np.empty((n, 1)), np.empty((n, 1)), np.empty(16))


@njit(cache=True)
def propagate(imu, nav, filt, model, out, k0, k1, flags):
    """Integrate IMU rows ``k0 .. k1-1`` with covariance propagation.

    Parameters
    ----------
    imu : tuple ``(t, dtheta_b, dv_b)``
        The whole IMU log.
    nav : tuple ``(lla, v_n, q_nb, carry)``
        Navigation state and mechanization carry, advanced in place.
    filt : tuple ``(x, P, aux, Phi)``
        Error state (propagated in open loop only), covariance, auxiliary
        estimates (applied to the raw increments) and the accumulated
        transition (when ``want_phi``).
    model : tuple ``(kidx, q_psd, rows, cols, active, crow, ccol, cval)``
        Layout index, process noise, F pattern and active rows, constant
        entries of F.
    out : tuple ``(lla, v_n, q_nb, var, base)``
        Per-row outputs; ``var`` receives the variances of every state (the
        estimates in ``aux`` change only at updates: the caller records them
        there).  Row ``k`` goes to index ``k - base[0]`` (``base``: (1,)
        int64), so the arrays may hold the whole run (base 0) or one segment
        of it (a streamed run, :func:`inskit.integration.engine.run_filter`).
    flags : tuple ``(coning, want_phi, open_loop, second_order, gravity, cov_step)``
        ``gravity``: the code of the gravity model (:data:`inskit.earth.GRAVITY_MODELS`).
        ``cov_step``: the covariance (and ``Phi``, and the open-loop error
        state) is stepped at the row that brings the gathered time nearest to
        this [s] (at 100 Hz, 0.01 s steps every row, jitter or not; at
        200 Hz every second row), and always at
        ``k1 - 1`` (the caller's calls end where an update, a node or the run
        needs it); 0 steps it at every row.  A step of several rows uses
        their mean rate and specific force (``sum dtheta / sum dt``) and the
        attitude at the start of its last row; the strapdown integrates every
        row either way (SYSTEM.md §2: the error model's propagation interval
        need not be the mechanization's, Groves 2013 §3.2.2).
    """
    propagate_rows(imu, nav, filt, model, out, k0, k1, flags, propagation_work(model, model[4].shape[0]))


@njit(cache=True)
def propagate_rows(imu, nav, filt, model, out, k0, k1, flags, work):
    """:func:`propagate` with the scratch ``work`` of :func:`propagation_work`
    (the compiled update loop keeps one for a whole run)."""
    t, dth_all, dv_all = imu
    lla, v_n, q_nb, carry = nav
    x, P, aux, Phi = filt
    kidx, q_psd, rows, cols, active, crow, ccol, cval = model
    out_lla, out_v, out_q, out_var, obase = out
    coning, want_phi, open_loop, second_order, gravity, cov_step = flags
    b = obase[0]
    F, A, B, T, tmp, xt, xtmp, gather = work
    n = kidx[N_STATES]
    C = np.empty((3, 3))
    dth = np.empty(3)
    dv = np.empty(3)
    f_b = np.empty(3)
    w_b = np.zeros(3)
    o_lla = np.empty(3)
    o_v = np.empty(3)
    o_q = np.empty(4)
    no_gains = np.zeros(2)
    sc = sensor_corrections(kidx, aux)
    body_noise = q_psd.shape[0] >= n + 6
    # gather[0]: time gathered since the last covariance step; 1..3, 4..6: the rows' summed corrected
    # angle and velocity increments (a step of one row uses that row's rate and specific force exactly)
    gather[0] = 0.0
    for i in range(1, 7):
        gather[i] = 0.0
    for k in range(k0, k1):
        dt = t[k] - carry[0]
        correct_increments(sc, dth_all[k], dv_all[k], dt, dth, dv, w_b, f_b)
        dcm_into(q_nb, C)
        ned_step(dth, dv, dt, lla, v_n, q_nb, carry, coning, 0, 0.0, no_gains, gravity)
        carry[0] = t[k]
        step = dt
        if cov_step > 0.0:
            gather[0] += dt
            for i in range(3):
                gather[1 + i] += dth[i]
                gather[4 + i] += dv[i]
            if gather[0] < cov_step - 0.5 * dt and k < k1 - 1:  # the nearest row to cov_step
                step = 0.0
            elif gather[0] != dt:  # several rows: their mean rate and specific force
                step = gather[0]
                inv = 1.0 / step
                for i in range(3):
                    w_b[i] = gather[1 + i] * inv
                    f_b[i] = gather[4 + i] * inv
        if step > 0.0:
            gather[0] = 0.0
            for i in range(1, 7):
                gather[i] = 0.0
            fill_transition(F, kidx, lla, v_n, C, f_b, w_b, sc, gravity)
            propagate_covariance(P, F, rows, cols, active, step, q_psd, A, B, T, second_order)
            if body_noise:
                add_body_noise(P, C, q_psd, n, step)
            if open_loop:
                for i in range(n):
                    xt[i, 0] = x[i]
                _sparse_step(xt, F, rows, cols, step, xtmp)
                for i in range(n):
                    x[i] = xt[i, 0]
            if want_phi:
                _sparse_step(Phi, F, rows, cols, step, tmp)
        if open_loop:
            apply_correction(lla, v_n, q_nb, x, 1.0, o_lla, o_v, o_q)
            for i in range(3):
                out_lla[k - b, i] = o_lla[i]
                out_v[k - b, i] = o_v[i]
            for i in range(4):
                out_q[k - b, i] = o_q[i]
        else:
            for i in range(3):
                out_lla[k - b, i] = lla[i]
                out_v[k - b, i] = v_n[i]
            for i in range(4):
                out_q[k - b, i] = q_nb[i]
        for i in range(n):
            out_var[k - b, i] = P[i, i]  # variances; the caller takes the square roots in one pass
