"""A generic linear discrete Kalman filter over given ``Phi_k, Q_k, H_k, R_k``.

Model (SYSTEM.md §2, source 000 eq. 2-8..2-12)::

    x[k+1] = Phi[k] x[k] + w[k],   w ~ N(0, Q[k])
    z[k]   = H[k] x[k] + v[k],     v ~ N(0, R[k])

Cycle at epoch ``k``: update with ``z[k]`` (if present), then predict to
``k+1``::

    K  = P- H^T (H P- H^T + R)^-1
    x+ = x- + K (z - H x-)
    P+ = (I - K H) P- (I - K H)^T + K R K^T     (Joseph form)
    x-[k+1] = Phi[k] x+[k],  P-[k+1] = Phi[k] P+[k] Phi[k]^T + Q[k]

The Joseph form keeps ``P`` symmetric and positive where the source's
``P+ = P- - K H P-`` loses both to rounding (SOURCES-NOTES §3.5 suggests it).
A row of ``z`` that is all NaN means "no measurement at this epoch"; NaN in
some components drops those components only.

The per-epoch loop is compiled; :func:`kf_predict` and :func:`kf_update` are
the compiled primitives, callable from other compiled loops (the platform
integration kernel uses them).

References
----------
SYSTEM.md §2; SOURCES-NOTES §3.5 (source 000 eq. 2-8..2-12);
Van Loan, "Computing integrals involving the matrix exponential", IEEE TAC
23(3), 1978 (discretisation of ``F`` and ``Q_c``); Bar-Shalom, Li &
Kirubarajan, *Estimation with Applications to Tracking and Navigation*, 2001,
§5.4 (NEES/NIS).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy.linalg import expm

from ..errors import InputError

__all__ = [
    "LinearKalmanResult",
    "expm_taylor",
    "kf_predict",
    "kf_update",
    "run_linear_kalman",
    "simulate_linear",
    "van_loan",
]


@njit(cache=True)
def kf_predict(x, P, Phi, Q):
    """``x <- Phi x``, ``P <- Phi P Phi^T + Q`` (symmetrised).

    Parameters
    ----------
    x : (n,) ndarray
    P, Phi, Q : (n, n) ndarray

    Returns
    -------
    x, P : new arrays.
    """
    xn = Phi @ x
    Pn = Phi @ P @ Phi.T + Q
    return xn, 0.5 * (Pn + Pn.T)


@njit(cache=True)
def kf_update(x, P, z, H, R):
    """Joseph-form update with the finite components of ``z``.

    Parameters
    ----------
    x : (n,) ndarray
    P : (n, n) ndarray
    z : (m,) ndarray
        NaN components are skipped.
    H : (m, n) ndarray
    R : (m, m) ndarray

    Returns
    -------
    x, P : (n,), (n, n) ndarray
        Posterior (the prior itself if no component is finite).
    nu : (m,) ndarray
        Innovation ``z - H x`` (NaN where skipped).
    nis : float
        ``nu^T S^-1 nu`` over the used components (NaN if none).
    used : int
        Number of components used.
    """
    m = z.shape[0]
    n = x.shape[0]
    idx = np.empty(m, np.int64)
    c = 0
    for i in range(m):
        if np.isfinite(z[i]):
            idx[c] = i
            c += 1
    nu_full = np.full(m, np.nan)
    if c == 0:
        return x.copy(), P.copy(), nu_full, np.nan, 0
    Hs = np.empty((c, n))
    Rs = np.empty((c, c))
    nu = np.empty(c)
    for a in range(c):
        Hs[a] = H[idx[a]]
        for b in range(c):
            Rs[a, b] = R[idx[a], idx[b]]
    hx = Hs @ x
    for a in range(c):
        nu[a] = z[idx[a]] - hx[a]
        nu_full[idx[a]] = nu[a]
    PHt = P @ Hs.T
    S = Hs @ PHt + Rs
    S = 0.5 * (S + S.T)
    L = np.linalg.cholesky(S)
    w = np.linalg.solve(L, nu)
    nis = np.dot(w, w)
    K = np.linalg.solve(L.T, np.linalg.solve(L, PHt.T)).T
    IKH = np.eye(n) - K @ Hs
    Pn = IKH @ P @ IKH.T + K @ Rs @ K.T
    return x + K @ nu, 0.5 * (Pn + Pn.T), nu_full, nis, c


@njit(cache=True)
def _run(Phi, Q, H, R, z, x0, P0, xs_pr, Ps_pr, xs_po, Ps_po, nu_out, nis_out):
    N = z.shape[0]
    x = x0.copy()
    P = P0.copy()
    for k in range(N):
        xs_pr[k] = x
        Ps_pr[k] = P
        Hk = H[k if H.shape[0] > 1 else 0]
        Rk = R[k if R.shape[0] > 1 else 0]
        x, P, nu, nis, _ = kf_update(x, P, z[k], Hk, Rk)
        xs_po[k] = x
        Ps_po[k] = P
        nu_out[k] = nu
        nis_out[k] = nis
        if k < N - 1:
            Pk = Phi[k if Phi.shape[0] > 1 else 0]
            Qk = Q[k if Q.shape[0] > 1 else 0]
            x, P = kf_predict(x, P, Pk, Qk)


@dataclass(frozen=True)
class LinearKalmanResult:
    """Filter output at every epoch.

    Attributes
    ----------
    x_prior, x_post : (N, n) ndarray
        Estimates before and after the update at each epoch.
    P_prior, P_post : (N, n, n) ndarray
    innovation : (N, m) ndarray
        NaN where no measurement was used.
    nis : (N,) ndarray
        Normalised innovation squared (NaN without measurement).
    """

    x_prior: np.ndarray
    P_prior: np.ndarray
    x_post: np.ndarray
    P_post: np.ndarray
    innovation: np.ndarray
    nis: np.ndarray

    @property
    def sigma_post(self):
        """``(N, n)`` square roots of the posterior variances."""
        return np.sqrt(np.einsum("kii->ki", self.P_post))


def _stack(name, a, N, shape):
    a = np.asarray(a, dtype=float)
    if a.shape == shape:
        return np.ascontiguousarray(a[None])
    if a.ndim == 3 and a.shape[1:] == shape and a.shape[0] in (N, max(N - 1, 1)):
        return np.ascontiguousarray(a)
    raise InputError(f"`{name}` must have shape {shape} or (N or N-1, {shape[0]}, {shape[1]}) with N = {N}, "
                     f"got {a.shape}")


def run_linear_kalman(Phi, Q, H, R, z, x0, P0) -> LinearKalmanResult:
    """Run the discrete Kalman filter over all epochs (compiled loop).

    Parameters
    ----------
    Phi, Q : (n, n) or (N-1, n, n) array_like
        Transition and process-noise covariance from epoch ``k`` to ``k+1``
        (constant or one per interval).
    H : (m, n) or (N, m, n) array_like
    R : (m, m) or (N, m, m) array_like
    z : (N, m) array_like
        Measurements; NaN where absent.
    x0 : (n,) array_like
        Prior estimate at epoch 0.
    P0 : (n, n) array_like
        Prior covariance at epoch 0 (symmetric positive definite).

    Returns
    -------
    LinearKalmanResult
    """
    z = np.ascontiguousarray(np.atleast_2d(np.asarray(z, dtype=float)))
    N, m = z.shape
    x0 = np.ascontiguousarray(np.asarray(x0, dtype=float).reshape(-1))
    n = len(x0)
    P0 = np.ascontiguousarray(np.asarray(P0, dtype=float))
    if P0.shape != (n, n):
        raise InputError(f"`P0` must have shape ({n}, {n}), got {P0.shape}")
    try:
        np.linalg.cholesky(P0)
    except np.linalg.LinAlgError:
        raise InputError("`P0` must be symmetric positive definite") from None
    Phi3 = _stack("Phi", Phi, N, (n, n))
    Q3 = _stack("Q", Q, N, (n, n))
    H3 = _stack("H", H, N, (m, n))
    R3 = _stack("R", R, N, (m, m))
    xs_pr = np.empty((N, n))
    Ps_pr = np.empty((N, n, n))
    xs_po = np.empty((N, n))
    Ps_po = np.empty((N, n, n))
    nu = np.empty((N, m))
    nis = np.empty(N)
    try:
        _run(Phi3, Q3, H3, R3, z, x0, P0, xs_pr, Ps_pr, xs_po, Ps_po, nu, nis)
    except np.linalg.LinAlgError:
        raise InputError("innovation covariance not positive definite: check R (and P0, Q)") from None
    return LinearKalmanResult(xs_pr, Ps_pr, xs_po, Ps_po, nu, nis)


def van_loan(F, Qc, dt, G=None):
    """Discretise ``x' = F x + G w`` with white ``w`` of spectral density ``Qc``.

    Parameters
    ----------
    F : (n, n) array_like
    Qc : (q, q) array_like
        Spectral density of ``w`` (units of ``w^2 s``).
    dt : float
        [s].
    G : (n, q) array_like, optional
        Noise input matrix (identity by default, then ``q = n``).

    Returns
    -------
    Phi : (n, n) ndarray
        ``exp(F dt)``.
    Q : (n, n) ndarray
        ``int_0^dt exp(F s) G Qc G^T exp(F s)^T ds``.
    """
    F = np.asarray(F, dtype=float)
    n = F.shape[0]
    G = np.eye(n) if G is None else np.asarray(G, dtype=float)
    W = G @ np.asarray(Qc, dtype=float) @ G.T
    M = np.zeros((2 * n, 2 * n))
    M[:n, :n] = -F * dt
    M[:n, n:] = W * dt
    M[n:, n:] = F.T * dt
    E = expm(M)
    Phi = E[n:, n:].T
    Q = Phi @ E[:n, n:]
    return Phi, 0.5 * (Q + Q.T)


@njit(cache=True)
def expm_taylor(F, dt, order):
    """``exp(F dt)`` by its Taylor series to ``order`` (compiled, for loops
    where ``F`` changes every step and ``|F dt|`` is small; the truncation
    error is about ``|F dt|^(order+1) / (order+1)!``)."""
    n = F.shape[0]
    A = F * dt
    out = np.eye(n)
    term = np.eye(n)
    for k in range(1, order + 1):
        term = term @ A / k
        out = out + term
    return out


@njit(cache=True)
def _sim(Phi, Lq, H, Lr, x0, wq, wr, xs, zs):
    N = zs.shape[0]
    x = x0.copy()
    for k in range(N):
        xs[k] = x
        zs[k] = H[k if H.shape[0] > 1 else 0] @ x + Lr[k if Lr.shape[0] > 1 else 0] @ wr[k]
        if k < N - 1:
            x = Phi[k if Phi.shape[0] > 1 else 0] @ x + Lq[k if Lq.shape[0] > 1 else 0] @ wq[k]


def simulate_linear(Phi, Q, H, R, x0_mean, P0, N, rng):
    """Draw one realisation of the linear model (for Monte Carlo tests).

    Parameters
    ----------
    Phi, Q, H, R : as in :func:`run_linear_kalman`
    x0_mean : (n,) array_like
    P0 : (n, n) array_like
        The true initial state is drawn from ``N(x0_mean, P0)``.
    N : int
        Epochs.
    rng : numpy.random.Generator

    Returns
    -------
    x : (N, n) ndarray
        True states.
    z : (N, m) ndarray
        Measurements.
    """
    x0_mean = np.asarray(x0_mean, dtype=float)
    n = len(x0_mean)
    H3 = _stack("H", H, N, (np.asarray(H).shape[-2], n))
    m = H3.shape[1]
    Phi3 = _stack("Phi", Phi, N, (n, n))
    Q3 = _stack("Q", Q, N, (n, n))
    R3 = _stack("R", R, N, (m, m))

    def chol(S):
        w, V = np.linalg.eigh(0.5 * (S + S.T))
        return V * np.sqrt(np.clip(w, 0.0, None))

    Lq = np.ascontiguousarray(np.array([chol(q) for q in Q3]))
    Lr = np.ascontiguousarray(np.array([chol(r) for r in R3]))
    x0 = x0_mean + chol(np.asarray(P0, float)) @ rng.standard_normal(n)
    wq = rng.standard_normal((N, n))
    wr = rng.standard_normal((N, m))
    xs = np.empty((N, n))
    zs = np.empty((N, m))
    _sim(Phi3, Lq, H3, Lr, x0, wq, wr, xs, zs)
    return xs, zs
