"""Choice of the simple filters' time constants and correction gains by search.

Source 004 calls optimal "the time constants that give the best accuracy for
a given transient time" and gives neither the constants nor the transient
time (SOURCES-NOTES §2.3).  This module makes that search explicit on the
linear closed loop: the completed error model (:mod:`.error_model`) frozen at
the run's latitude and speed, discretised at the run's step, the filter on
each of the four differences, the corrections of
:mod:`.integrated` (gains from the loop frequency ``w_c`` and damping
``zeta_c``), driven by white satellite noise and constant instrument errors.

* accuracy ``J``: RMS over the last ``tail`` seconds of the four measured
  errors normalised by the satellite sigmas (deterministic response to the
  instrument errors plus the noise covariance at the end);
* transient time: the last time the normalised error of the noise-free
  response to the initial errors exceeds ``tol`` (5 %) of its start;
* search: a grid over ``T`` (or ``T1`` and ``zeta``) and ``w_c``; the best
  ``J`` among stable designs whose transient time is within the limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import earth
from ..errors import ConfigError
from ..filters.linear import van_loan
from . import error_model as em
from .corrections import SimpleFilterDesign, v_west_slope

W = earth.OMEGA_IE
WS = math.sqrt(9.8 / earth.R_SPHERE)

__all__ = ["DesignPoint", "closed_loop", "default_design", "evaluate", "search"]


def default_design(order, scheme="closed"):
    """Designs found by the searches for source 004's experiment (see
    docs/platform.md), used when no design is given: closed loop ``T = 1 s``
    (``T1 = 1 s``, ``zeta = 0.707``) with ``w_c = 6 w_s``; open loop
    ``T = 25 s`` (``T1 = 25 s``, ``zeta = 0.5``)."""
    if scheme == "open":
        return SimpleFilterDesign(order, 25.0, 0.7071067811865476 if order == 1 else 0.5)
    if order == 1:
        return SimpleFilterDesign(1, 1.0, loop_frequency=6.0 * WS)
    return SimpleFilterDesign(2, 1.0, 0.7071067811865476, loop_frequency=6.0 * WS)


@dataclass(frozen=True)
class DesignPoint:
    design: SimpleFilterDesign
    J: float
    transient_s: float
    stable: bool
    rms: tuple  # normalised RMS of d_phi, d_lambda, dV_xi, dV_eta


def closed_loop(design: SimpleFilterDesign, lat, speed_north, dt, earth_model="wgs84"):
    """Discrete closed loop ``X+ = A X + G_v v + G_u u`` over
    ``X = [x (7), filter states (4 k)]``.

    Returns
    -------
    A, G_v, G_u, H_rel : ndarray
        ``H_rel`` (4, 7) maps the source-variable state to the measured
        differences ``[d_phi, d_lambda, dv_N, dv_E]``.
    """
    F = em.error_matrix(lat, 0.0, (0.0, speed_north, 0.0), earth_model=earth_model)
    B = em.input_matrix()
    Phi, _ = van_loan(F, np.zeros((7, 7)), dt)
    M = np.zeros((14, 14))
    M[:7, :7] = F * dt
    M[:7, 7:] = np.eye(7) * dt
    Gam = __import__("scipy.linalg", fromlist=["expm"]).expm(M)[:7, 7:]  # int_0^dt exp(F s) ds
    c = float(v_west_slope(lat, 0.0, earth_model))
    H = np.zeros((4, 7))
    H[0, 3] = H[1, 4] = H[2, 5] = 1.0
    H[3, 6], H[3, 3] = -1.0, c
    k2, k3, ks = design.gains()
    # correction rates in relative variables [aE, aN, aU, dVE, dVN, dphi, dlam] from e = [phi, lam, vN, vE]
    Gr = np.zeros((7, 4))
    Gr[0, 2] = -ks
    Gr[1, 3], Gr[1, 0] = ks, -ks * c  # -ks dV_eta_hat, dV_eta = -dv_E + c d_phi
    Gr[3, 3] = k2
    Gr[4, 2] = k2
    Gr[5, 0] = k3
    Gr[6, 1] = k3
    # relative -> source rates: T (as in error_model._transform)
    T = np.zeros((7, 7))
    T[0, 1] = 1.0
    T[1, 0] = -1.0
    T[2, 2] = 1.0
    T[3, 5] = T[4, 6] = T[5, 4] = 1.0
    T[6, 3], T[6, 5] = -1.0, c
    Gc = T @ Gr
    d = design.filter().discretize(dt)
    kf = d.order
    Af = np.kron(np.eye(4), d.A)
    Bf = np.kron(np.eye(4), d.B.reshape(-1, 1))
    Cf = np.kron(np.eye(4), d.C.reshape(1, -1))
    n = 7 + 4 * kf
    A = np.zeros((n, n))
    # e_hat used over the step is C (A_f s + B_f z), z = H x + v
    A[:7, :7] = Phi + Gam @ Gc @ Cf @ Bf @ H
    A[:7, 7:] = Gam @ Gc @ Cf @ Af
    A[7:, :7] = Bf @ H
    A[7:, 7:] = Af
    Gv = np.zeros((n, 4))
    Gv[:7] = Gam @ Gc @ Cf @ Bf
    Gv[7:] = Bf
    Gu = np.zeros((n, 5))
    Gu[:7] = Gam @ B
    return A, Gv, Gu, H


def evaluate(design, *, lat, speed_north, dt, duration, sigma, x0, u, tail=7200.0, tol=0.05,
             earth_model="wgs84", coarse=60):
    """Accuracy and transient time of one design (see module docstring).

    Parameters
    ----------
    design : SimpleFilterDesign
    lat, speed_north, dt, duration : float
        [rad], [m/s], [s], [s].
    sigma : (4,) array_like
        Satellite sigmas of the four differences [rad, rad, m/s, m/s].
    x0 : (7,) array_like
        Initial errors (source variables); the filters start in the steady
        state of the first difference.
    u : (5,) array_like
        Instrument errors (source variables).
    tail : float
        Averaging window of the accuracy [s].
    coarse : int
        Steps per evaluation sample.

    Returns
    -------
    DesignPoint
    """
    A, Gv, Gu, H = closed_loop(design, lat, speed_north, dt, earth_model)
    rho = np.abs(np.linalg.eigvals(A)).max()
    n = A.shape[0]
    sig = np.asarray(sigma, float)
    x0 = np.asarray(x0, float)
    d = design.filter().discretize(dt)
    s0 = np.kron(H @ x0, d.steady_state(1.0))
    X0 = np.concatenate([x0, s0])
    steps = int(duration / dt)
    m = max(1, steps // coarse)
    Ac = np.linalg.matrix_power(A, coarse)
    # deterministic response to u: X_{k} = A X + Gu u, accumulated over coarse blocks
    S = np.zeros((n, n))
    Ak = np.eye(n)
    for _ in range(coarse):
        S = S + Ak
        Ak = A @ Ak
    bu = S @ (Gu @ np.asarray(u, float))
    Xu = np.zeros(n)
    Xi = X0.copy()
    hist_u, hist_i = [], []
    for _ in range(m):
        Xu = Ac @ Xu + bu
        Xi = Ac @ Xi
        hist_u.append(H @ Xu[:7] / sig)
        hist_i.append(H @ Xi[:7] / sig)
    hist_u = np.array(hist_u)
    hist_i = np.array(hist_i)
    tt = (np.arange(m) + 1) * coarse * dt
    # noise: covariance after `duration` by doubling
    Qv = Gv @ np.diag(sig**2) @ Gv.T
    P, Ap = Qv.copy(), A.copy()
    total = 1
    while total * 2 <= steps:
        P = Ap @ P @ Ap.T + P
        Ap = Ap @ Ap
        total *= 2
    Pz = H @ P[:7, :7] @ H.T / np.outer(sig, sig)
    ok = np.isfinite(hist_u).all() and np.isfinite(hist_i).all() and rho < 1.0
    sel = tt >= tt[-1] - tail
    rms = np.sqrt(np.mean(hist_u[sel] ** 2, axis=0) + np.clip(np.diag(Pz), 0, None))
    J = float(np.sqrt(np.mean(rms**2))) if ok else np.inf
    e = np.linalg.norm(hist_i, axis=1)
    e0 = np.linalg.norm(H @ x0 / sig)
    out = np.nonzero(e > tol * e0)[0]
    tr = float(tt[out[-1]]) if len(out) else 0.0
    return DesignPoint(design, J, tr if ok else np.inf, bool(ok), tuple(float(r) for r in rms))


def search(order, *, transient_limit, lat, speed_north, dt, duration, sigma, x0, u,
           T_values=None, zeta_values=(0.5, 0.7071067811865476, 1.0), wc_factors=None, earth_model="wgs84"):
    """Grid search of the best design within a transient time.

    Parameters
    ----------
    order : {1, 2}
    transient_limit : float
        [s].
    T_values : sequence of float, optional
        Filter time constants [s] (default: 16 values from 1 s to 1000 s).
    wc_factors : sequence of float, optional
        Loop frequencies as multiples of the Schuler frequency (default
        1..16).
    (others as in :func:`evaluate`)

    Returns
    -------
    best : DesignPoint
    table : list of DesignPoint
        Every evaluated design.
    """
    if order not in (1, 2):
        raise ConfigError(f"order must be 1 or 2, got {order}")
    T_values = np.geomspace(1.0, 1000.0, 16) if T_values is None else T_values
    wc_factors = (1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0) if wc_factors is None else wc_factors
    zetas = (0.7071067811865476,) if order == 1 else zeta_values
    table = []
    for T in T_values:
        for z in zetas:
            for f in wc_factors:
                dsg = SimpleFilterDesign(order, float(T), float(z), loop_frequency=f * WS)
                table.append(evaluate(dsg, lat=lat, speed_north=speed_north, dt=dt, duration=duration, sigma=sigma,
                                      x0=x0, u=u, earth_model=earth_model))
    ok = [p for p in table if p.stable and p.transient_s <= transient_limit]
    if not ok:
        raise ConfigError(f"no design on the grid settles within {transient_limit:.0f} s")
    return min(ok, key=lambda p: p.J), table


def search_open_loop(order, z, e_true, dt, sigma, *, transient_limit, tail, T_values=None,
                     zeta_values=(0.5, 0.7071067811865476, 1.0)):
    """Open loop: choose the filter constant on a recorded run.

    In the open loop the output error is ``e - F(z)`` with ``e`` the free
    INS error and ``z = e + v`` the INS-minus-satellite difference: a long
    ``T`` lags behind the Schuler-oscillating ``e``, a short one passes the
    satellite noise.  The filter is applied to the recorded differences for
    each candidate (exact discrete filter, starting in the steady state of the
    first difference) and scored like :func:`evaluate`; the transient time is
    the filter's own step-response settling time.

    Parameters
    ----------
    order : {1, 2}
    z : (n, 4) array_like
        Recorded differences ``[d_phi, d_lambda, dv_N, dv_E]`` (NaN rows: no
        fix, held).
    e_true : (n, 4) array_like
        True INS errors of the same quantities.
    dt : float
    sigma : (4,) array_like
        Normalisation [rad, rad, m/s, m/s].
    transient_limit, tail : float
        [s].

    Returns
    -------
    best : dict
        ``T_s``, ``zeta``, ``J``, ``transient_s``.
    table : list of dict
    """
    from ..filters.simple import FirstOrderFilter, SecondOrderFilter

    z = np.asarray(z, float).copy()
    for j in range(1, len(z)):  # hold through gaps
        if not np.isfinite(z[j]).all():
            z[j] = z[j - 1]
    e_true = np.asarray(e_true, float)
    sig = np.asarray(sigma, float)
    n_tail = int(tail / dt)
    T_values = np.geomspace(1.0, 1000.0, 16) if T_values is None else T_values
    zetas = (None,) if order == 1 else zeta_values
    table = []
    for T in T_values:
        for zt in zetas:
            f = FirstOrderFilter(float(T)) if order == 1 else SecondOrderFilter(float(T), float(zt))
            est = f.discretize(dt).run(z, initial="first")
            err = (e_true - est)[-n_tail:] / sig
            rms = np.sqrt(np.mean(err**2, axis=0))
            table.append({"T_s": float(T), "zeta": zt, "J": float(np.sqrt(np.mean(rms**2))),
                          "transient_s": f.settling_time(), "rms": rms.tolist()})
    ok = [p for p in table if p["transient_s"] <= transient_limit]
    if not ok:
        raise ConfigError(f"no filter on the grid settles within {transient_limit:.0f} s")
    return min(ok, key=lambda p: p["J"]), table
