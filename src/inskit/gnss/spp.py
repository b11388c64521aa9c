"""Single-point positioning (SPP): code-pseudorange position, clocks, Doppler
velocity, DOP and residual-based fault detection and exclusion.

The solver works on a :class:`inskit.gnss.ranges.RangeTable` (corrected
pseudoranges and range rates, one row per epoch and satellite, sorted by
epoch) and runs one compiled Gauss-Newton loop per epoch over the flat row
arrays and the epoch start offsets (:func:`_solve_all`), so a day of 30 s
data (2727 epochs) takes milliseconds after the first compile.

Model, per epoch (Misra & Enge 2011, ch. 6; Groves 2013 §9.4.1)::

    P_i = | R3(OMEGA_E tau_i) r_sat,i - r_rx | + c dt_rx,sys(i) + e_i,
    e_i ~ N(0, sigma_pr,i^2)

* ``r_sat,i`` is the satellite position at transmit time in the ECEF frame
  of transmit time; it is rotated into the ECEF frame of reception by the
  Earth's rotation during the geometric travel time ``tau = rho / c``
  (Sagnac; IS-GPS-200 20.3.3.4.3.4, RTKLIB ``geodist``'s algorithm) at every
  iteration, so the rotation is independent of the receiver clock.
* **Clock rule.** One receiver clock state per GNSS system that has at least
  one usable satellite at the epoch (``clock_m[:, k]`` for ``systems[k]``,
  NaN at epochs where that system has none).  With GPS and Galileo both
  present this is the GPS clock plus the inter-system bias,
  ``clock_E - clock_G``.  Unknowns: ``3 + (systems present)``; an epoch with
  fewer satellites than unknowns is refused (status 0), never guessed.
* Weights ``1 / sigma_pr^2`` from the table.  Position covariance
  ``(H^T W H)^-1``, resolved in local east-north-up at the solution.
* **Residual test and exclusion** (RAIM-like fault detection and exclusion;
  Parkinson & Axelrad 1988 / Brown 1992, Baarda's w-test): the weighted
  post-fit sum of squares ``sum (v_i / sigma_i)^2`` is chi-square with
  ``n - k`` degrees of freedom when the sigmas are right; it is tested at the
  false-alarm probability ``p_fa`` (default 1e-3, the level RTKLIB's
  ``valsol`` uses).  On failure with redundancy ``n - k >= 2`` the satellite
  with the largest standardised residual ``|v_i| / sqrt(Q_vv,ii)``,
  ``Q_vv = W^-1 - H (H^T W H)^-1 H^T``, is removed and the epoch re-solved;
  this repeats while the redundancy allows (and at most ``max_exclusions``
  times).  An epoch that still fails is kept, flagged (status 3).
* **DOP** from the unweighted geometry ``(H^T H)^-1`` (Misra & Enge eq.
  6.37), position block rotated to ENU: ``HDOP = sqrt(q_E + q_N)``,
  ``VDOP = sqrt(q_U)``, ``PDOP``; ``GDOP = sqrt(PDOP^2 + TDOP^2)`` with TDOP
  of the first system present (the reference clock).
* **Velocity** from range rates (Doppler) at the solved position, weighted
  least squares for ``v_rx`` and one clock drift (one receiver oscillator
  drives every system, so one drift state):
  ``rr_i - u_i . v_sat,i = -u_i . v_rx + c ddt_rx`` (Misra & Enge §6.2.2),
  with the same residual test and exclusion.

Status codes of :class:`SppSolution`: 0 unsolved (too few satellites, no
convergence or singular geometry), 1 solved, 2 solved after excluding
satellites, 3 solved but flagged (residual test still failing, or HDOP above
``max_hdop``).  :meth:`SppSolution.to_gnss_data` passes statuses 1 and 2 only.

References
----------
IS-GPS-200N §20.3.3.4.3 (user algorithm, Earth rotation correction);
P. Misra, P. Enge, *Global Positioning System*, 2nd ed., 2011, ch. 6;
P. D. Groves, *Principles of GNSS, Inertial, and Multisensor Integrated
Navigation Systems*, 2nd ed., 2013, §9.4 and §17.4 (FDE);
T. Takasu, RTKLIB 2.4.3 manual, App. E.6 (single point positioning;
algorithm only, no code taken).
"""

from __future__ import annotations

import dataclasses
import math
import time as _time
import warnings
from dataclasses import dataclass

import numpy as np
from numba import njit

from .. import earth
from ..errors import InputError
from ..types import GnssData
from .constants import OMEGA_E_GPS
from .constants import C as C_LIGHT

#: Status codes of :class:`SppSolution` ``status``
UNSOLVED, SOLVED, EXCLUDED, FLAGGED = 0, 1, 2, 3
STATUS_NAMES = {UNSOLVED: "unsolved", SOLVED: "solved", EXCLUDED: "solved with exclusions",
                FLAGGED: "flagged (residual test or HDOP)"}
#: Why an epoch is unsolved (:class:`SppSolution` ``refusal``); 0 for solved epochs
NO_SATELLITES, TOO_FEW, SINGULAR, NO_CONVERGENCE = 1, 2, 3, 4
REFUSAL_NAMES = {NO_SATELLITES: "no usable satellite", TOO_FEW: "fewer satellites than unknowns",
                 SINGULAR: "singular geometry", NO_CONVERGENCE: "no convergence"}
_MAX_DOF = 256
#: Equal code sigma of the first pass without an approximate position (unmodelled atmosphere) [m]
_FIRST_PASS_SIGMA_M = 10.0


def chi2_limits(p_fa, n=_MAX_DOF):
    """Upper chi-square quantiles ``limits[d]`` for ``d`` degrees of freedom
    (``limits[0]`` unused), at false-alarm probability ``p_fa``."""
    from scipy.stats import chi2

    lim = np.full(n + 1, np.inf)
    lim[1:] = chi2.isf(p_fa, np.arange(1, n + 1))
    return lim


# --------------------------------------------------------------------------------------------
# compiled kernels
# --------------------------------------------------------------------------------------------
@njit(cache=True)
def _chol_inv(N, k):
    """Inverse of the symmetric positive definite ``N[:k, :k]`` by Cholesky;
    ``ok`` is False when a pivot falls below 1e-10 of its diagonal (singular
    geometry)."""
    L = np.zeros((k, k))
    Ni = np.zeros((k, k))
    for j in range(k):
        s = N[j, j]
        for p in range(j):
            s -= L[j, p] * L[j, p]
        if not (s > 1e-10 * N[j, j]) or not (N[j, j] > 0.0):
            return Ni, False
        L[j, j] = math.sqrt(s)
        for i in range(j + 1, k):
            s = N[i, j]
            for p in range(j):
                s -= L[i, p] * L[j, p]
            L[i, j] = s / L[j, j]
    # M = L^-1 (lower triangular), N^-1 = M^T M
    M = np.zeros((k, k))
    for i in range(k):
        M[i, i] = 1.0 / L[i, i]
        for j in range(i):
            s = 0.0
            for p in range(j, i):
                s -= L[i, p] * M[p, j]
            M[i, j] = s / L[i, i]
    for i in range(k):
        for j in range(i, k):
            s = 0.0
            for p in range(j, k):
                s += M[p, i] * M[p, j]
            Ni[i, j] = s
            Ni[j, i] = s
    return Ni, True


@njit(cache=True)
def _rotated(sx, sy, sz, x, y, z, omega, c):
    """Satellite position rotated into the ECEF frame of reception by
    ``omega * tau`` about z, with ``c tau = |R3(omega tau) r_sat - r_rx|``
    solved by two fixed-point steps from the unrotated range (the second
    step changes the angle by ~1e-11 rad, the third would by ~1e-18); also
    returns the cosine and sine used (for the satellite velocity)."""
    ct, st = 1.0, 0.0
    px, py = sx, sy
    for _ in range(2):
        dx, dy, dz = px - x, py - y, sz - z
        th = omega * math.sqrt(dx * dx + dy * dy + dz * dz) / c
        ct, st = math.cos(th), math.sin(th)
        px, py = ct * sx + st * sy, -st * sx + ct * sy
    return px, py, sz, ct, st


@njit(cache=True)
def _columns(sysidx, active, a, b, n_sys):
    """Column of each system's clock (-1 if absent) and the number of states."""
    col = -np.ones(n_sys, np.int64)
    for i in range(a, b):
        if active[i - a]:
            col[sysidx[i]] = 0
    k = 3
    for s in range(n_sys):
        if col[s] == 0:
            col[s] = k
            k += 1
    return col, k


@njit(cache=True)
def _solve_all(start, sat_pos, sat_vel, pr, sig, rr, sig_rr, sysidx, usable, x0, n_sys, lim, max_iter, tol,
               raim, max_excl, omega, c):
    n_ep = len(start) - 1
    m = len(pr)
    r = np.full((n_ep, 3), np.nan)
    clk = np.full((n_ep, n_sys), np.nan)
    status = np.zeros(n_ep, np.int64)
    why = np.zeros(n_ep, np.int64)
    nsat = np.zeros(n_ep, np.int64)
    dof_out = np.zeros(n_ep, np.int64)
    chi2_out = np.full(n_ep, np.nan)
    rms_out = np.full(n_ep, np.nan)
    cov = np.full((n_ep, 3, 3), np.nan)
    qdop = np.full((n_ep, 3, 3), np.nan)
    qclk = np.full(n_ep, np.nan)
    v = np.full((n_ep, 3), np.nan)
    drift = np.full(n_ep, np.nan)
    covv = np.full((n_ep, 3, 3), np.nan)
    vstat = np.zeros(n_ep, np.int64)
    nvel = np.zeros(n_ep, np.int64)
    used = np.zeros(m, np.bool_)
    excluded = np.zeros(m, np.bool_)
    vexcluded = np.zeros(m, np.bool_)
    resid = np.full(m, np.nan)
    rres = np.full(m, np.nan)
    kmax = 3 + n_sys
    for e in range(n_ep):
        a, b = start[e], start[e + 1]
        nrow = b - a
        why[e] = NO_SATELLITES
        if nrow == 0:
            continue
        active = usable[a:b].copy()
        x = x0[e, 0]
        y = x0[e, 1]
        z = x0[e, 2]
        if not (np.isfinite(x) and np.isfinite(y) and np.isfinite(z)):
            x, y, z = 0.0, 0.0, 0.0
        cl = np.zeros(n_sys)
        H = np.zeros((nrow, kmax))
        res = np.zeros(nrow)
        ux = np.zeros(nrow)
        uy = np.zeros(nrow)
        uz = np.zeros(nrow)
        ctv = np.ones(nrow)
        stv = np.zeros(nrow)
        n_excl = 0
        st = UNSOLVED
        Ni = np.zeros((kmax, kmax))
        k = 3
        n_act = 0
        chi2 = np.nan
        dof = 0
        dxv = np.zeros(kmax)
        col = -np.ones(n_sys, np.int64)
        while True:
            col, k = _columns(sysidx, active, a, b, n_sys)
            n_act = 0
            for j in range(nrow):
                if active[j]:
                    n_act += 1
            if n_act < k:
                why[e] = NO_SATELLITES if n_act == 0 else TOO_FEW
                break
            converged = False
            ok = True
            for it in range(max_iter):
                N = np.zeros((k, k))
                g = np.zeros(k)
                for j in range(nrow):
                    if not active[j]:
                        continue
                    i = a + j
                    px, py, pz, ct, s_ = _rotated(sat_pos[i, 0], sat_pos[i, 1], sat_pos[i, 2], x, y, z, omega, c)
                    dx, dy, dz = px - x, py - y, pz - z
                    rho = math.sqrt(dx * dx + dy * dy + dz * dz)
                    ux[j], uy[j], uz[j] = dx / rho, dy / rho, dz / rho
                    ctv[j], stv[j] = ct, s_
                    cj = col[sysidx[i]]
                    res[j] = pr[i] - rho - cl[sysidx[i]]
                    for q in range(k):
                        H[j, q] = 0.0
                    H[j, 0], H[j, 1], H[j, 2] = -ux[j], -uy[j], -uz[j]
                    H[j, cj] = 1.0
                    w = 1.0 / (sig[i] * sig[i])
                    for p in range(k):
                        g[p] += w * H[j, p] * res[j]
                        for q in range(k):
                            N[p, q] += w * H[j, p] * H[j, q]
                Ni, ok = _chol_inv(N, k)
                if not ok:
                    break
                dxv = Ni @ g
                x += dxv[0]
                y += dxv[1]
                z += dxv[2]
                for s in range(n_sys):
                    if col[s] >= 0:
                        cl[s] += dxv[col[s]]
                step = math.sqrt(dxv[0] ** 2 + dxv[1] ** 2 + dxv[2] ** 2)
                if step < tol:
                    converged = True
                    break
            if not (ok and converged):
                st = UNSOLVED
                why[e] = SINGULAR if not ok else NO_CONVERGENCE
                break
            # post-fit residuals at the converged point (the last step was < tol)
            chi2 = 0.0
            for j in range(nrow):
                if active[j]:
                    res[j] -= (H[j, 0] * dxv[0] + H[j, 1] * dxv[1] + H[j, 2] * dxv[2]
                               + dxv[col[sysidx[a + j]]])
                    chi2 += (res[j] / sig[a + j]) ** 2
            dof = n_act - k
            if dof >= 1 and dof < len(lim) and chi2 > lim[dof]:
                if raim and dof >= 2 and n_excl < max_excl:
                    worst = -1
                    wmax = -1.0
                    for j in range(nrow):
                        if not active[j]:
                            continue
                        hq = 0.0
                        for p in range(k):
                            for q in range(k):
                                hq += H[j, p] * Ni[p, q] * H[j, q]
                        qvv = sig[a + j] ** 2 - hq
                        if qvv > 1e-12 * sig[a + j] ** 2:
                            wj = abs(res[j]) / math.sqrt(qvv)
                            if wj > wmax:
                                wmax = wj
                                worst = j
                    if worst >= 0:
                        active[worst] = False
                        excluded[a + worst] = True
                        n_excl += 1
                        continue
                st = FLAGGED
            else:
                st = EXCLUDED if n_excl > 0 else SOLVED
            break
        if st == UNSOLVED:
            continue
        status[e] = st
        why[e] = 0
        r[e, 0], r[e, 1], r[e, 2] = x, y, z
        ref = -1
        for s in range(n_sys):
            if col[s] >= 0:
                clk[e, s] = cl[s]
                if ref < 0:
                    ref = col[s]
        nsat[e] = n_act
        dof_out[e] = dof
        chi2_out[e] = chi2
        ss = 0.0
        for j in range(nrow):
            if active[j]:
                used[a + j] = True
                resid[a + j] = res[j]
                ss += res[j] * res[j]
        rms_out[e] = math.sqrt(ss / n_act)
        G = np.zeros((k, k))
        for j in range(nrow):
            if active[j]:
                for p in range(k):
                    for q in range(k):
                        G[p, q] += H[j, p] * H[j, q]
        Gi, okg = _chol_inv(G, k)
        for p in range(3):
            for q in range(3):
                cov[e, p, q] = Ni[p, q]
                if okg:
                    qdop[e, p, q] = Gi[p, q]
        if okg:
            qclk[e] = Gi[ref, ref]
        # ---- velocity and clock drift from range rates, at the solved position
        vact = np.zeros(nrow, np.bool_)
        nv = 0
        for j in range(nrow):
            i = a + j
            if active[j] and np.isfinite(rr[i]) and sig_rr[i] > 0.0 and np.isfinite(sat_vel[i, 0]):
                vact[j] = True
                nv += 1
        if nv < 4:
            continue
        yv = np.zeros(nrow)
        nve = 0
        vst = UNSOLVED
        Nvi = np.zeros((4, 4))
        sol = np.zeros(4)
        while True:
            nv = 0
            for j in range(nrow):
                if vact[j]:
                    nv += 1
            if nv < 4:
                break
            Nv = np.zeros((4, 4))
            gv = np.zeros(4)
            for j in range(nrow):
                if not vact[j]:
                    continue
                i = a + j
                ct, s_ = ctv[j], stv[j]
                vx = ct * sat_vel[i, 0] + s_ * sat_vel[i, 1]
                vy = -s_ * sat_vel[i, 0] + ct * sat_vel[i, 1]
                vz = sat_vel[i, 2]
                yv[j] = rr[i] - (ux[j] * vx + uy[j] * vy + uz[j] * vz)
                hv = (-ux[j], -uy[j], -uz[j], 1.0)
                w = 1.0 / (sig_rr[i] * sig_rr[i])
                for p in range(4):
                    gv[p] += w * hv[p] * yv[j]
                    for q in range(4):
                        Nv[p, q] += w * hv[p] * hv[q]
            Nvi, okv = _chol_inv(Nv, 4)
            if not okv:
                vst = UNSOLVED
                break
            sol = Nvi @ gv
            chi2v = 0.0
            for j in range(nrow):
                if vact[j]:
                    yv[j] -= -ux[j] * sol[0] - uy[j] * sol[1] - uz[j] * sol[2] + sol[3]
                    chi2v += (yv[j] / sig_rr[a + j]) ** 2
            dofv = nv - 4
            if dofv >= 1 and dofv < len(lim) and chi2v > lim[dofv]:
                if raim and dofv >= 2 and nve < max_excl:
                    worst = -1
                    wmax = -1.0
                    for j in range(nrow):
                        if not vact[j]:
                            continue
                        hv = (-ux[j], -uy[j], -uz[j], 1.0)
                        hq = 0.0
                        for p in range(4):
                            for q in range(4):
                                hq += hv[p] * Nvi[p, q] * hv[q]
                        qvv = sig_rr[a + j] ** 2 - hq
                        if qvv > 1e-12 * sig_rr[a + j] ** 2:
                            wj = abs(yv[j]) / math.sqrt(qvv)
                            if wj > wmax:
                                wmax = wj
                                worst = j
                    if worst >= 0:
                        vact[worst] = False
                        vexcluded[a + worst] = True
                        nve += 1
                        continue
                vst = FLAGGED
            else:
                vst = EXCLUDED if nve > 0 else SOLVED
            break
        if vst == UNSOLVED:
            continue
        vstat[e] = vst
        nvel[e] = nv
        v[e, 0], v[e, 1], v[e, 2] = sol[0], sol[1], sol[2]
        drift[e] = sol[3]
        for j in range(nrow):
            if vact[j]:
                rres[a + j] = yv[j]
        for p in range(3):
            for q in range(3):
                covv[e, p, q] = Nvi[p, q]
    return (r, clk, status, why, nsat, dof_out, chi2_out, rms_out, cov, qdop, qclk, v, drift, covv, vstat, nvel,
            used, excluded, vexcluded, resid, rres)


# --------------------------------------------------------------------------------------------
# results
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SppSolution:
    """Single-point solutions over all observation epochs.

    Arrays have one row per observation epoch (``n``), solved or not; every
    quantity of an unsolved epoch is NaN (counts 0).

    Attributes
    ----------
    time : (n,) ndarray
        Receiver time tags [s since the GPS epoch, GPS scale].
    week, sow : (n,) ndarray
        GPS week and seconds of week of ``time``.
    status : (n,) int ndarray
        0 unsolved, 1 solved, 2 solved with exclusions, 3 flagged (residual
        test failing after exclusion, or HDOP above the limit).
    r_e : (n, 3) ndarray
        Antenna position, ECEF [m].
    lla : (n, 3) ndarray
        The same as latitude, longitude [rad], ellipsoidal height [m].
    systems : tuple of str
        System letters of the ``clock_m`` columns.
    clock_m : (n, n_sys) ndarray
        Receiver clock bias per system times c [m] (NaN where the system had
        no satellite).  ``clock_m[:, 1] - clock_m[:, 0]`` is the inter-system
        bias.
    v_e : (n, 3) ndarray
        Antenna velocity, ECEF [m/s] (NaN without Doppler).
    clock_drift_m_s : (n,) ndarray
        Receiver clock drift times c [m/s].
    n_sats : (n,) int ndarray
        Satellites used in the position.
    gdop, pdop, hdop, vdop : (n,) ndarray
        Dilutions of precision (local ENU; GDOP with the reference clock).
    sigma_enu : (n, 3) ndarray
        1-sigma position errors east, north, up [m] from the weighted LS
        covariance.
    cov_enu : (n, 3, 3) ndarray
        Position covariance in ENU [m^2].
    sigma_v_enu : (n, 3) ndarray
        1-sigma velocity errors east, north, up [m/s].
    cov_v_enu : (n, 3, 3) ndarray
        Velocity covariance in ENU [m^2/s^2].
    velocity_status : (n,) int ndarray
        Status of the velocity solution, codes as ``status``.
    refusal : (n,) int ndarray
        Why an epoch is unsolved (:data:`REFUSAL_NAMES`: 1 no usable
        satellite, 2 fewer satellites than unknowns, 3 singular geometry,
        4 no convergence); 0 when solved.
    excluded : tuple of str
        Per epoch, the satellites excluded by the residual test
        (comma-separated, ``""`` for none).
    velocity_excluded : tuple of str
        The same for the range-rate (Doppler) solution.
    rms_residual_m : (n,) ndarray
        RMS of the post-fit pseudorange residuals [m].
    chi2, chi2_limit : (n,) ndarray
        Weighted post-fit sum of squares and its test limit.
    redundancy : (n,) int ndarray
        Satellites minus unknowns (0: the fix cannot be tested).
    notes : tuple of str
        Warnings about the run (refused epochs, flagged epochs ...).
    """

    time: np.ndarray
    week: np.ndarray
    sow: np.ndarray
    status: np.ndarray
    r_e: np.ndarray
    lla: np.ndarray
    systems: tuple
    clock_m: np.ndarray
    v_e: np.ndarray
    clock_drift_m_s: np.ndarray
    n_sats: np.ndarray
    gdop: np.ndarray
    pdop: np.ndarray
    hdop: np.ndarray
    vdop: np.ndarray
    sigma_enu: np.ndarray
    cov_enu: np.ndarray
    sigma_v_enu: np.ndarray
    cov_v_enu: np.ndarray
    velocity_status: np.ndarray
    excluded: tuple
    velocity_excluded: tuple
    refusal: np.ndarray
    rms_residual_m: np.ndarray
    chi2: np.ndarray
    chi2_limit: np.ndarray
    redundancy: np.ndarray
    notes: tuple = ()

    def __len__(self):
        return len(self.time)

    @property
    def solved(self):
        """``(n,)`` bool: status 1 or 2 (usable fixes)."""
        return (self.status == SOLVED) | (self.status == EXCLUDED)

    @property
    def v_enu(self):
        """``(n, 3)`` velocity east, north, up [m/s]."""
        C = earth.dcm_en(self.lla[:, 0], self.lla[:, 1])
        v_ned = np.einsum("nji,nj->ni", C, self.v_e)
        return earth.ned_to_enu(v_ned)

    def to_gnss_data(self, *, with_velocity=True, statuses=(SOLVED, EXCLUDED), sigma_floor_m=0.1,
                     sigma_v_floor_m_s=0.01):
        """The usable fixes as :class:`inskit.types.GnssData`.

        Parameters
        ----------
        with_velocity : bool
            Attach the Doppler velocity when the solution has one: if no
            selected epoch has a velocity (no Doppler observed) the fixes
            come without; if only some have, :class:`InputError` (pass
            ``with_velocity=False``), since a fix set is all with or all
            without velocity.
        statuses : sequence of int
            Epoch statuses to keep (default solved and solved-with-exclusions;
            flagged epochs are left out).
        sigma_floor_m, sigma_v_floor_m_s : float
            Lower bounds of the position [m] and velocity [m/s] sigmas.

        Returns
        -------
        GnssData
            ``time`` in GPS seconds of the week of the first fix (continued
            past 604800 s across a week boundary, as
            :func:`inskit.io.rtklib.read_pos` counts), as the loosely coupled
            filter uses for real logs; NED sigmas from ``sigma_enu``.
        """
        keep = np.isin(self.status, list(statuses))
        if not keep.any():
            raise InputError(f"no SPP fix with status in {list(statuses)} "
                             f"({int((self.status == UNSOLVED).sum())} of {len(self)} epochs unsolved)")
        week0 = int(self.week[keep][0])
        t = self.time[keep] - week0 * 604800.0
        sig = np.maximum(self.sigma_enu[keep][:, [1, 0, 2]], sigma_floor_m)
        v = sv = None
        vv = self.v_enu[keep]
        miss = ~np.isfinite(vv).all(axis=1)
        if with_velocity and not miss.all():
            if miss.any():
                raise InputError(f"{int(miss.sum())} of {int(keep.sum())} SPP fixes have no Doppler velocity; "
                                 "use with_velocity=False")
            v = earth.enu_to_ned(vv)
            sv = np.maximum(self.sigma_v_enu[keep][:, [1, 0, 2]], sigma_v_floor_m_s)
        return GnssData(t, self.lla[keep], sig, v, sv)


# --------------------------------------------------------------------------------------------
# drivers
# --------------------------------------------------------------------------------------------
def _system_index(sats, systems):
    letters = np.array([s[:1] for s in np.asarray(sats, dtype=str)])
    idx = np.full(len(letters), -1, np.int64)
    for k, s in enumerate(systems):
        idx[letters == s] = k
    return idx


def solve_epochs(table, *, n_epoch=None, time=None, x0=None, systems=("G", "E"), raim=True, p_fa=1e-3,
                 max_exclusions=None, max_hdop=10.0, max_iter=20, tol_m=1e-4):
    """Solve every epoch of a range table for position, clocks and velocity.

    Parameters
    ----------
    table : inskit.gnss.ranges.RangeTable
        Corrected pseudoranges (``pseudorange_m = rho + c dt_rx + noise``),
        their sigmas, satellite positions at transmit time (Sagnac not
        applied), optional range rates; rows sorted by epoch.
    n_epoch : int, optional
        Number of observation epochs (default ``len(time)`` or
        ``table.epoch.max() + 1``).
    time : (n_epoch,) ndarray, optional
        Epoch time tags [s since the GPS epoch]; needed for epochs without
        any row (default: taken from the rows, NaN where an epoch has none).
    x0 : (3,) or (n_epoch, 3) ndarray, optional
        Starting ECEF position [m] (default the Earth's centre, from which
        Gauss-Newton converges for GNSS geometry; NaN rows start there too).
    systems : sequence of str
        Systems whose rows are used; ``clock_m`` has one column per entry.
    raim : bool
        Exclude satellites that fail the residual test (else only flag).
    p_fa : float
        False-alarm probability of the chi-square residual test.
    max_exclusions : int, optional
        Upper bound on exclusions per epoch (default: as the redundancy
        allows).
    max_hdop : float
        Solutions with a larger HDOP are flagged (status 3).
    max_iter, tol_m : int, float
        Gauss-Newton iterations and convergence threshold on the position
        step [m].

    Returns
    -------
    SppSolution
    """
    systems = tuple(systems)
    if not systems:
        raise InputError("`systems` is empty: give at least one of G, E")
    ep = np.asarray(table.epoch, dtype=np.int64)
    if time is not None:
        time = np.asarray(time, dtype=float)
        n_epoch = len(time) if n_epoch is None else n_epoch
    if n_epoch is None:
        n_epoch = int(ep.max()) + 1 if len(ep) else 0
    if len(ep) and (ep.min() < 0 or ep.max() >= n_epoch):
        raise InputError(f"range table epochs run to {int(ep.max())}, beyond n_epoch={n_epoch}")
    if len(ep) > 1 and (np.diff(ep) < 0).any():
        raise InputError("range table rows must be sorted by epoch")
    if time is None:
        time = np.full(n_epoch, np.nan)
        if len(ep):
            time[ep] = np.asarray(table.time, dtype=float)
    start = np.searchsorted(ep, np.arange(n_epoch + 1)).astype(np.int64)
    sats = np.asarray(table.sat, dtype=str)
    sysidx = _system_index(sats, systems)
    pr = np.ascontiguousarray(table.pseudorange_m, dtype=float)
    sig = np.ascontiguousarray(table.sigma_pr_m, dtype=float)
    pos = np.ascontiguousarray(table.sat_pos_e, dtype=float).reshape(-1, 3)
    vel = np.ascontiguousarray(table.sat_vel_e, dtype=float).reshape(-1, 3)
    rr = np.ascontiguousarray(table.range_rate_m_s, dtype=float)
    srr = np.ascontiguousarray(table.sigma_rr_m_s, dtype=float)
    usable = (sysidx >= 0) & np.isfinite(pr) & (sig > 0) & np.isfinite(pos).all(axis=1)
    sysidx = np.where(sysidx < 0, 0, sysidx)
    if x0 is None:
        x0a = np.zeros((n_epoch, 3))
    else:
        x0a = np.broadcast_to(np.asarray(x0, dtype=float), (n_epoch, 3)).copy()
    lim = chi2_limits(p_fa)
    me = 10_000 if max_exclusions is None else int(max_exclusions)
    out = _solve_all(start, pos, vel, pr, sig, rr, srr, sysidx, usable, x0a, len(systems), lim, int(max_iter),
                     float(tol_m), bool(raim), me, OMEGA_E_GPS, C_LIGHT)
    (r, clk, status, why, nsat, dof, chi2, rms, cov, qdop, qclk, v, drift, covv, vstat, _nvel, _used, excl, vexcl,
     _res, _rres) = out
    vexcluded = _per_epoch_names(sats, vexcl, start)
    ok = status > 0
    lla = np.full((n_epoch, 3), np.nan)
    lla[ok] = earth.ecef_to_lla(r[ok])
    cov_enu, q_enu, covv_enu = (np.full((n_epoch, 3, 3), np.nan) for _ in range(3))
    if ok.any():
        R = _enu_rows(lla[ok])
        cov_enu[ok] = R @ cov[ok] @ np.swapaxes(R, 1, 2)
        q_enu[ok] = R @ qdop[ok] @ np.swapaxes(R, 1, 2)
        covv_enu[ok] = R @ covv[ok] @ np.swapaxes(R, 1, 2)
    d = np.diagonal(q_enu, axis1=1, axis2=2)
    hdop = np.sqrt(d[:, 0] + d[:, 1])
    vdop = np.sqrt(d[:, 2])
    pdop = np.sqrt(d.sum(axis=1))
    gdop = np.sqrt(pdop**2 + qclk)
    sigma_enu = np.sqrt(np.diagonal(cov_enu, axis1=1, axis2=2))
    sigma_v = np.sqrt(np.diagonal(covv_enu, axis1=1, axis2=2))
    high = ok & (hdop > max_hdop)
    status = status.copy()
    status[high] = FLAGGED
    excluded = _per_epoch_names(sats, excl, start)
    notes = _notes(time, status, why, high, excluded)
    for n_ in notes:
        warnings.warn(n_, stacklevel=2)
    from .time import week_sow

    week, sow = week_sow(np.where(np.isfinite(time), time, 0.0))
    week = np.asarray(week, dtype=np.int64)
    sow = np.where(np.isfinite(time), np.asarray(sow, dtype=float), np.nan)
    return SppSolution(time=time, week=week, sow=sow, status=status, r_e=r, lla=lla, systems=systems,
                       clock_m=clk, v_e=v, clock_drift_m_s=drift, n_sats=nsat, gdop=gdop, pdop=pdop, hdop=hdop,
                       vdop=vdop, sigma_enu=sigma_enu, cov_enu=cov_enu, sigma_v_enu=sigma_v, cov_v_enu=covv_enu,
                       velocity_status=vstat,
                       excluded=excluded, velocity_excluded=vexcluded, refusal=why, rms_residual_m=rms, chi2=chi2,
                       chi2_limit=np.where(dof > 0, lim[np.minimum(dof, _MAX_DOF)], np.nan),
                       redundancy=np.where(ok, dof, 0), notes=tuple(notes))


def _enu_rows(lla):
    """``(n, 3, 3)`` rotation taking ECEF vectors to east, north, up."""
    C = earth.dcm_en(lla[:, 0], lla[:, 1])          # columns N, E, D in e
    return np.stack([C[:, :, 1], C[:, :, 0], -C[:, :, 2]], axis=1)


def _per_epoch_names(sats, mask, start):
    idx = np.flatnonzero(mask)
    out = [""] * (len(start) - 1)
    if len(idx):
        ep = np.searchsorted(start, idx, side="right") - 1
        for e in np.unique(ep):
            out[e] = ",".join(sats[idx[ep == e]])
    return tuple(out)


def _fmt_times(t, k=3):
    """``week W sow a, b, c`` of the first ``k`` times (the week repeated only when it changes)."""
    from .time import week_sow

    w, s = week_sow(np.asarray(t[:k], dtype=float))
    out, last = [], None
    for a, b in zip(np.atleast_1d(w), np.atleast_1d(s)):
        out.append(f"{float(b):.3f}" if a == last else f"week {int(a)} sow {float(b):.3f}")
        last = a
    return ", ".join(out) + (" ..." if len(t) > k else "")


def _notes(time, status, why, high, excluded):
    notes = []
    uns = np.flatnonzero(status == UNSOLVED)
    if len(uns):
        t = time[uns]
        t = t[np.isfinite(t)]
        parts = ", ".join(f"{int((why[uns] == c).sum())} {name}" for c, name in REFUSAL_NAMES.items()
                          if (why[uns] == c).any())
        notes.append(f"{len(uns)} of {len(status)} epochs unsolved ({parts}; unknowns: position and one clock "
                     f"per system present)" + (f", first at {_fmt_times(t)}" if len(t) else ""))
    flag = np.flatnonzero((status == FLAGGED) & ~high)
    if len(flag):
        notes.append(f"{len(flag)} epochs fail the residual test after exclusion (flagged, status 3), first at "
                     f"{_fmt_times(time[flag])}")
    if high.any():
        notes.append(f"{int(high.sum())} epochs have HDOP above the limit (flagged, status 3), first at "
                     f"{_fmt_times(time[high])}")
    nex = sum(1 for x in excluded if x)
    if nex:
        notes.append(f"satellites excluded by the residual test at {nex} epochs")
    return notes


#: a header position this far [m] from the solved ones is wrong, not merely approximate
_HEADER_FAR_M = 100.0e3


def _approx_ok(r):
    if r is None:
        return False
    r = np.asarray(r, dtype=float).reshape(-1)
    return r.shape == (3,) and bool(np.isfinite(r).all()) and 6.2e6 < float(np.linalg.norm(r)) < 6.6e6


#: how a caller of :func:`spp` sets the elevation mask and the ionospheric model, for its messages: the
#: function's own arguments (``inskit spp`` says --mask and --iono, ``inskit navigate`` its [gnss] keys)
SPP_SETTINGS = {"mask": "the mask_deg argument", "iono": "iono=\"klobuchar\""}


def spp(obs, nav, *, mask_deg=10.0, iono="klobuchar", tropo="saastamoinen", raim=True, systems=("G", "E"),
        code="C1C", doppler="D1C", alpha=None, beta=None, p_fa=1e-3, max_hdop=10.0, timing=None, settings=None):
    """Single-point positioning of every epoch of an observation file.

    Two passes, because the tropospheric and ionospheric corrections and the
    elevation mask depend on the receiver position: (1) ranges at the header
    approximate position (or, without a plausible one, ranges without
    atmosphere or mask solved from the Earth's centre), solve; (2) ranges
    again at each epoch's first-pass solution, solve again (the second
    pass's positions move the corrections by far less than a millimetre).

    Parameters
    ----------
    obs : inskit.gnss.rinex.ObsData
    nav : inskit.gnss.rinex.NavData
    mask_deg : float
        Elevation mask [deg].
    iono : {"klobuchar", "iono-free", "none"}
    tropo : {"saastamoinen", "none"}
    raim : bool
        Fault detection and exclusion by the residual test.
    systems : sequence of str
        GNSS systems to use ("G", "E").
    code, doppler : str
        RINEX 3 observation codes of the pseudorange and Doppler.
    alpha, beta : (4,) array_like, optional
        Klobuchar coefficients (default: the nav header's, else the
        default set of :mod:`inskit.gnss.atmosphere`).
    p_fa, max_hdop : float
        See :func:`solve_epochs`.
    timing : dict, optional
        If given, filled with ``ranges_s`` and ``solve_s`` (wall time) and
        ``dropped`` (the final range table's dropped-row counts by reason)
        and ``no_ephemeris`` (satellite -> ranges unused for want of an
        ephemeris).
    settings : dict, optional
        How the caller sets the elevation mask (``"mask"``) and the
        ionospheric model (``"iono"``), named in the messages that suggest
        changing them (default :data:`SPP_SETTINGS`, this function's
        arguments; a command names its own options or config keys).

    Returns
    -------
    SppSolution
    """
    from .ranges import range_table

    settings = {**SPP_SETTINGS, **(settings or {})}

    systems = tuple(systems)
    kw = {"code": code, "doppler": doppler, "systems": systems, "alpha": alpha, "beta": beta}
    n_ep = len(obs.time)
    t_rng = t_sol = 0.0
    t0 = _time.perf_counter()
    approx = getattr(obs, "approx_position_e", None)
    rx = None
    header_note = None
    if _approx_ok(approx):
        x0 = np.asarray(approx, dtype=float).reshape(3)
        tab = range_table(obs, nav, rx_e=x0, mask_deg=mask_deg, iono=iono, tropo=tropo, **kw)
        t1 = _time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            first = solve_epochs(tab, time=obs.time, x0=x0, systems=systems, raim=raim, p_fa=p_fa,
                                 max_hdop=max_hdop)
        t_rng += t1 - t0
        t_sol += _time.perf_counter() - t1
        rx = np.where((first.status > 0)[:, None], first.r_e, np.nan)
        if not np.isfinite(rx).any():
            # the header's position may be wrong (a receiver's default, another site): its elevation mask
            # then drops every satellite; solve without it, as for a header without a position
            header_note = approx
            rx = None
    if rx is None:
        # no usable approximate position: satellite states do not depend on it, so take every row (no mask,
        # no atmosphere), weight them equally and solve from the Earth's centre; the models come in pass 2
        t0 = _time.perf_counter()
        iono0 = "iono-free" if iono == "iono-free" else "none"
        tab = range_table(obs, nav, rx_e=np.array([0.0, 0.0, earth.A]), mask_deg=-90.0, iono=iono0, tropo="none",
                          **kw)
        tab = dataclasses.replace(tab, sigma_pr_m=np.full(len(tab.pseudorange_m), _FIRST_PASS_SIGMA_M))
        t1 = _time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            first = solve_epochs(tab, time=obs.time, systems=systems, raim=False, p_fa=p_fa, max_hdop=1e9)
        t_rng += t1 - t0
        t_sol += _time.perf_counter() - t1
        rx = np.where((first.status > 0)[:, None], first.r_e, np.nan)
    t2 = _time.perf_counter()
    if not np.isfinite(rx).any():
        raise InputError(f"{getattr(obs, 'path', 'observations')}: no epoch could be solved ({n_ep} epochs, "
                         f"{len(tab.pseudorange_m)} usable {code} ranges without elevation mask; "
                         f"{_unsolvable_hint(obs, nav, tab, settings=settings)}{_with(ephemeris_note(obs, nav, tab))}")
    if header_note is not None:
        far = float(np.median(np.linalg.norm(rx[np.isfinite(rx).all(axis=1)] - header_note, axis=1)))
        header_note = None if far < _HEADER_FAR_M else (
            f"{getattr(obs, 'path', 'observations')}: the header's APPROX POSITION XYZ "
            f"{np.round(approx, 1).tolist()} is {far / 1e3:.0f} km from the solved positions (the elevation "
            "mask there left no epoch solvable): ignored, solved without it")
        if header_note is not None:
            warnings.warn(header_note, stacklevel=2)
    tab = range_table(obs, nav, rx_e=rx, mask_deg=mask_deg, iono=iono, tropo=tropo, **kw)
    t3 = _time.perf_counter()
    sol = solve_epochs(tab, time=obs.time, x0=np.where(np.isfinite(rx), rx, 0.0), systems=systems, raim=raim,
                       p_fa=p_fa, max_hdop=max_hdop)
    t4 = _time.perf_counter()
    t_rng += t3 - t2
    t_sol += t4 - t3
    if timing is not None:
        timing.update(ranges_s=t_rng, solve_s=t_sol, dropped=dict(getattr(tab, "dropped", {}) or {}),
                      no_ephemeris=dict(getattr(tab, "no_ephemeris", {}) or {}))
    if not (sol.status > 0).any():
        raise InputError(f"{getattr(obs, 'path', 'observations')}: no epoch could be solved ({n_ep} epochs, "
                         f"{len(tab.pseudorange_m)} usable {code} ranges above the {mask_deg:g} deg elevation mask; "
                         f"{_unsolvable_hint(obs, nav, tab, mask_deg, settings)}{_with(ephemeris_note(obs, nav, tab))}")
    eph_note = ephemeris_note(obs, nav, tab)
    code_note = codes_note(obs, tab)
    for n_ in (code_note, eph_note):
        if n_:
            warnings.warn(n_, stacklevel=2)
    extra = tuple(n_ for n_ in (header_note, code_note, eph_note) if n_)
    if extra:
        sol = dataclasses.replace(sol, notes=extra + tuple(sol.notes))
    return sol


def codes_note(obs, tab):
    """One sentence naming the codes taken where the requested one is absent
    (``tab.settings['codes_used']``, :data:`inskit.gnss.ranges.CODE_FALLBACK`);
    empty string when the requested code served every range."""
    settings = getattr(tab, "settings", {}) or {}
    code, used = settings.get("code"), dict(settings.get("codes_used") or {})
    others = {c: n for c, n in used.items() if c != code}
    if not others:
        return ""
    total = sum(used.values())
    parts = ", ".join(f"{c} on {n}" for c, n in others.items())
    return (f"{getattr(obs, 'path', 'observations')}: code {code} absent on {sum(others.values())} of {total} "
            f"ranges: {parts} taken in its place (same band; the inter-code bias, a few dm, is not modelled)")


def _with(note):
    return f"; {note}" if note else ""


def ephemeris_note(obs, nav, tab):
    """One sentence naming the observed satellites whose ranges went unused
    for want of a broadcast record (``tab.no_ephemeris``), by cause: no
    record of that satellite in the navigation file, only unhealthy ones, or
    none within the maximum age of the epochs; empty string when none."""
    from .ephemeris import _healthy

    lost = dict(getattr(tab, "no_ephemeris", {}) or {})
    if not lost:
        return ""
    sats = np.asarray(nav.sats)
    healthy = _healthy(nav) if len(sats) else np.zeros(0, bool)
    groups = {"no record in the navigation file": [], "unhealthy records only": [],
              "no record within the maximum age of some epochs": []}
    for name in sorted(lost):
        has = sats == name
        key = ("no record in the navigation file" if not has.any() else
               "unhealthy records only" if not healthy[has].any() else
               "no record within the maximum age of some epochs")
        groups[key].append(f"{name} ({lost[name]})")
    parts = [f"{k}: {', '.join(v)}" for k, v in groups.items() if v]
    n_rows = sum(lost.values())
    return (f"{getattr(nav, 'path', 'navigation file')}: {len(lost)} observed satellite{'s' if len(lost) != 1 else ''} "
            f"without a usable ephemeris, {n_rows} range{'s' if n_rows != 1 else ''} unused (ranges per satellite): "
            + "; ".join(parts))


def clock_drift_from_bias(sol, epoch, system=None, span_s=60.0):
    """Receiver clock drift [m/s] from the single-point clock bias alone:
    the median over consecutive solved epochs within ``span_s`` of
    ``epoch`` (after it first, then before it) of the bias difference over
    the time difference.  For observations without Doppler, whose
    single-point solution has no drift; the median passes over one clock
    jump and the epochs' code noise (a few m/s with 1 s epochs).

    Parameters
    ----------
    sol : SppSolution
    epoch : int
        Epoch index near which the drift is wanted.
    system : str, optional
        System letter of the clock (default the solution's first system).
    span_s : float
        Half width of the window [s].

    Returns
    -------
    (drift [m/s], pairs used) : (float, int)
        NaN and 0 with fewer than two consecutive solved epochs in the window.
    """
    systems = list(sol.systems)
    k = systems.index(system) if system in systems else 0
    t = np.asarray(sol.time, dtype=float)
    b = np.asarray(sol.clock_m, dtype=float)[:, k]
    ok = sol.solved & np.isfinite(b)
    t0 = t[int(epoch)]
    for window in ((t >= t0) & (t <= t0 + span_s), np.abs(t - t0) <= span_s):
        idx = np.flatnonzero(ok & window)
        if idx.size >= 2:
            dt = np.diff(t[idx])
            good = dt > 0
            if good.any():
                rates = np.diff(b[idx])[good] / dt[good]
                return float(np.median(rates)), int(good.sum())
    return math.nan, 0


#: Smallest receiver clock step taken as a jump [m] (0.1 ms): far above a free-running TCXO's 1e-6 s/s over
#: a minute's gap left unpredicted (18 km) and the code noise, far below the 1 ms (299.8 km) steps of receivers
#: that keep their clock within a millisecond of GPS time by resetting it.
CLOCK_JUMP_MIN_M = 0.1e-3 * C_LIGHT


def receiver_clock_jumps(sol, system=None, min_jump_m=CLOCK_JUMP_MIN_M):
    """Steps of the receiver clock between consecutive solved epochs.

    A receiver that keeps its clock near GPS time by resetting it (a
    millisecond reset, common in consumer receivers) steps every pseudorange
    of an epoch by the same ``c dt`` (299.8 km for 1 ms).  Single-point
    positioning absorbs it into each epoch's clock; a filter whose clock
    state runs on by its drift does not (tight coupling diverged).  A step
    is the change of the single-point clock bias between consecutive
    solved epochs less what the drift predicts (the mean Doppler drift of
    the two epochs, else the rate of the previous step, else none), when it
    exceeds ``min_jump_m``; one within 1 km of a whole number of
    milliseconds is taken as exactly that number.

    Parameters
    ----------
    sol : SppSolution
    system : str, optional
        System letter of the clock (default: the solution's system with the
        most solved clocks).
    min_jump_m : float
        Smallest step taken as a jump [m].

    Returns
    -------
    (epochs, jumps_m) : ((k,) int64 ndarray, (k,) ndarray)
        Index of the first epoch after each step and the step [m].
    """
    clk = np.asarray(sol.clock_m, dtype=float)
    systems = list(sol.systems)
    if system in systems:
        k = systems.index(system)
    else:
        k = int(np.argmax(np.isfinite(clk).sum(axis=0))) if clk.size else 0
    t = np.asarray(sol.time, dtype=float)
    b = clk[:, k] if clk.size else np.zeros(len(t))
    d = np.asarray(sol.clock_drift_m_s, dtype=float)
    idx = np.flatnonzero(sol.solved & np.isfinite(b))
    ms = 1e-3 * C_LIGHT
    epochs, jumps = [], []
    rate = math.nan
    for i, j in zip(idx[:-1], idx[1:]):
        dt = t[j] - t[i]
        pred = 0.5 * (d[i] + d[j]) if np.isfinite(d[i]) and np.isfinite(d[j]) else rate
        step = b[j] - b[i] - (pred * dt if np.isfinite(pred) else 0.0)
        if abs(step) > min_jump_m:
            n_ms = round(step / ms)
            if n_ms != 0 and abs(step - n_ms * ms) < 1000.0:
                step = n_ms * ms
            epochs.append(int(j))
            jumps.append(float(step))
            continue  # the rate across a jump means nothing
        if dt > 0:
            rate = (b[j] - b[i]) / dt
    return np.array(epochs, dtype=np.int64), np.array(jumps, dtype=float)


def remove_clock_jumps(sol, table, epochs, jumps_m):
    """The single-point solution and range table with the receiver clock
    steps of :func:`receiver_clock_jumps` taken out of every later epoch's
    clock and pseudoranges (the geometry, from the ranges as measured, is
    unchanged): a clock that runs on continuously.

    Returns
    -------
    (SppSolution, RangeTable)
    """
    cum = np.zeros(len(sol.time))
    for e, j in zip(np.asarray(epochs, dtype=np.int64), np.asarray(jumps_m, dtype=float)):
        cum[e:] += j
    if not np.any(cum):
        return sol, table
    sol = dataclasses.replace(sol, clock_m=np.asarray(sol.clock_m, dtype=float) - cum[:, None])
    ep = np.asarray(table.epoch, dtype=np.int64)
    table = dataclasses.replace(table, pseudorange_m=np.asarray(table.pseudorange_m, dtype=float) - cum[ep])
    return sol, table


def clock_jump_note(sol, epochs, jumps_m, path="observations"):
    """One sentence naming the receiver clock jumps (empty string for none)."""
    if len(epochs) == 0:
        return ""
    ms = 1e-3 * C_LIGHT
    parts = [f"{j / ms:+.3f} ms at week {int(sol.week[e])} sow {float(sol.sow[e]):.3f}"
             for e, j in zip(epochs[:5], jumps_m[:5])]
    more = f" and {len(epochs) - 5} more" if len(epochs) > 5 else ""
    return (f"{path}: the receiver clock jumps {len(epochs)} time{'s' if len(epochs) != 1 else ''} "
            f"({', '.join(parts)}{more}; every pseudorange of the epoch steps with it)")


def _span(t):
    from .time import to_datetime64

    t = np.asarray(t, dtype=float)
    t = t[np.isfinite(t)]
    if not t.size:
        return "none"
    a, b = (str(to_datetime64(x).astype("datetime64[s]")).replace("T", " ") for x in (t.min(), t.max()))
    return a if a == b else f"{a} .. {b}"


def _unsolvable_hint(obs, nav, tab, mask_deg=None, settings=None):
    """Why no epoch could be solved, from the range table's dropped rows
    (a pass without mask): the navigation file's ephemeris span against
    the observation span, or too few satellites per epoch.  ``settings``
    names how the caller sets the mask and the ionospheric model
    (:data:`SPP_SETTINGS`)."""
    settings = {**SPP_SETTINGS, **(settings or {})}
    dropped = dict(getattr(tab, "dropped", {}) or {})
    text = ", ".join(f"{k} {v}" for k, v in dropped.items() if v) or "none"
    if dropped.get("no_ephemeris") and not dropped.get("below_mask") and len(tab.pseudorange_m) == 0:
        systems = sorted({str(s)[0] for s in obs.sats})
        have = sorted(set(np.asarray(nav.system).tolist()))
        missing = [s for s in systems if s not in have]
        why = (f"the navigation file {nav.path} has no record of system(s) {', '.join(missing)}"
               if missing and len(missing) == len(systems) else
               f"no ephemeris of {nav.path} is valid at the observation times: its records (toe) span "
               f"{_span(nav.toe)}, the observations {_span(obs.time)} GPS time")
        return f"rows dropped: {text}): {why}"
    if dropped.get("no_second_code") and len(tab.pseudorange_m) == 0:
        return f"rows dropped: {text}): iono-free needs a second-frequency code; use {settings['iono']}"
    ep = np.asarray(getattr(tab, "epoch", np.zeros(0, int)), dtype=np.int64)
    most = int(np.bincount(ep).max()) if ep.size else 0
    if most < 4 and mask_deg is not None and dropped.get("below_mask"):
        return (f"rows dropped: {text}): the elevation mask of {mask_deg:g} deg leaves at most {most} "
                f"satellite(s) at any epoch, fewer than the 4 a fix needs (position and one clock); lower "
                f"{settings['mask']}")
    if most < 4:
        return (f"rows dropped: {text}): at most {most} satellite(s) with an ephemeris at any epoch, fewer than "
                "the 4 a fix needs (position and one clock); does the navigation file cover the observation time "
                "and systems?")
    return f"rows dropped: {text}): no solution converged"


__all__ = [
    "EXCLUDED",
    "FLAGGED",
    "NO_CONVERGENCE",
    "NO_SATELLITES",
    "REFUSAL_NAMES",
    "SINGULAR",
    "SOLVED",
    "SPP_SETTINGS",
    "STATUS_NAMES",
    "TOO_FEW",
    "UNSOLVED",
    "SppSolution",
    "chi2_limits",
    "clock_jump_note",
    "codes_note",
    "ephemeris_note",
    "clock_drift_from_bias",
    "receiver_clock_jumps",
    "remove_clock_jumps",
    "solve_epochs",
    "spp",
]
