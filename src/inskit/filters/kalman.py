"""Kalman update, gating and consistency statistics."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numba import njit

from ..errors import InskitError


class FilterDivergence(InskitError):
    """The covariance lost symmetry or positiveness: the filter cannot go on."""


@lru_cache(maxsize=64)
def chi2_threshold(dof: int, probability: float) -> float:
    """Chi-square quantile: NIS above it is rejected at ``1 - probability``.

    The ``x`` with ``Q(dof/2, x/2) = 1 - probability``, ``Q`` the regularized
    upper incomplete gamma function (:func:`_gamma_q`), found by bisection to
    the last bits: the value of ``scipy.stats.chi2.ppf`` to 1e-12 (tested),
    without the import of ``scipy.special`` (0.2 to 0.3 s of every command
    that filters: its array-API layer), for the few thresholds a run needs.
    """
    dof, probability = int(dof), float(probability)
    if dof < 1:
        raise ValueError(f"chi-square degrees of freedom must be >= 1, got {dof}")
    if not 0.0 <= probability <= 1.0:
        raise ValueError(f"probability must be in [0, 1], got {probability}")
    if probability == 0.0:
        return 0.0
    if probability == 1.0:
        return float("inf")
    a = 0.5 * dof
    lower = probability <= 0.5  # compare the smaller tail: no cancellation in 1 - p
    target = probability if lower else 1.0 - probability

    def below(x):  # the root lies above x
        p, q = _gamma_pq(a, 0.5 * x)
        return p < target if lower else q > target

    lo, hi = 0.0, max(1.0, float(dof))
    while below(hi):  # bracket the root
        lo, hi = hi, 2.0 * hi
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        if below(mid):
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _gamma_pq(a: float, x: float) -> tuple[float, float]:
    """Regularized lower and upper incomplete gamma functions ``(P, Q)``,
    ``P + Q = 1``, for ``a > 0``, ``x >= 0``: the power series of ``P`` below
    ``x = a + 1``, the continued fraction of ``Q`` (modified Lentz) above,
    each where it converges fast, the smaller of the two computed directly
    (Abramowitz and Stegun 6.5.29 and 6.5.31)."""
    import math

    if x <= 0.0:
        return 0.0, 1.0
    log_front = -x + a * math.log(x) - math.lgamma(a)
    if x < a + 1.0:
        term = total = 1.0 / a
        n = a
        while abs(term) > abs(total) * 1e-17:
            n += 1.0
            term *= x / n
            total += term
        p = total * math.exp(log_front)
        return p, 1.0 - p
    tiny = 1e-300
    b = x + 1.0 - a
    c = 1.0 / tiny
    d = 1.0 / b
    h = d
    for i in range(1, 1000):
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        d = tiny if abs(d) < tiny else d
        c = b + an / c
        c = tiny if abs(c) < tiny else c
        d = 1.0 / d
        step = d * c
        h *= step
        if abs(step - 1.0) < 1e-16:
            break
    q = math.exp(log_front) * h
    return 1.0 - q, q


@dataclass(frozen=True)
class UpdateResult:
    """Outcome of one measurement update.

    Attributes
    ----------
    accepted : bool
    dx : (n,) ndarray
        State correction ``K nu`` (zero if rejected).
    P : (n, n) ndarray
        Posterior covariance (the prior if rejected).
    innovation : (m,) ndarray
    S : (m, m) ndarray
        Innovation covariance.
    nis : float
        ``nu^T S^-1 nu``.
    """

    accepted: bool
    dx: np.ndarray
    P: np.ndarray
    innovation: np.ndarray
    S: np.ndarray
    nis: float


@njit(cache=True)
def _update(P, nu, H, R):
    """Innovation covariance, NIS, gain, correction and Joseph-form covariance
    in one compiled call (called once per update: numpy's per-call overhead
    would otherwise dominate the filter's time)."""
    n = P.shape[0]
    PHt = P @ H.T
    S = H @ PHt + R
    L = np.linalg.cholesky(S)
    w = np.linalg.solve(L, nu)
    nis = np.dot(w, w)
    K = np.linalg.solve(L.T, np.linalg.solve(L, PHt.T)).T
    IKH = np.eye(n) - K @ H
    Pn = IKH @ P @ IKH.T + K @ R @ K.T
    return K @ nu, 0.5 * (Pn + Pn.T), S, nis


def joseph_update(P, innovation, H, R, *, gate_probability=None):
    """Kalman update of an error state whose prior estimate is zero.

    Parameters
    ----------
    P : (n, n) ndarray
        Prior covariance.
    innovation : (m,) array_like
        ``z - H x_prior``.
    H : (m, n) array_like
    R : (m, m) array_like
    gate_probability : float, optional
        Reject the measurement when its NIS exceeds the chi-square quantile
        of this probability (e.g. 0.9999).

    Returns
    -------
    UpdateResult
    """
    nu = np.ascontiguousarray(innovation, dtype=float)
    H = np.ascontiguousarray(H, dtype=float)
    R = np.ascontiguousarray(R, dtype=float)
    P = np.ascontiguousarray(P, dtype=float)
    if not np.isfinite(nu).all():  # P is checked by the caller after each propagation
        raise FilterDivergence("the innovation is not finite: the filter diverged")
    try:
        dx, Pn, S, nis = _update(P, nu, H, R)
    except np.linalg.LinAlgError:
        raise FilterDivergence("innovation covariance is not positive definite: the filter diverged") from None
    nis = float(nis)
    if gate_probability is not None and nis > chi2_threshold(len(nu), gate_probability):
        return UpdateResult(False, np.zeros(P.shape[0]), P, nu, S, nis)
    return UpdateResult(True, dx, Pn, nu, S, nis)


def gate_rows(P, innovation, H, R, probability):
    """Per-row gate: True for each row whose own NIS ``nu_i^2 / S_ii`` is
    within the one-degree-of-freedom chi-square quantile of ``probability``
    (one satellite among several, say, is rejected alone).

    Returns
    -------
    keep : (m,) bool ndarray
    s : (m,) ndarray
        The rows' innovation variances ``S_ii``.
    """
    H = np.asarray(H, dtype=float)
    nu = np.asarray(innovation, dtype=float)
    s = np.einsum("ij,jk,ik->i", H, P, H) + np.diag(R)
    if not np.isfinite(nu).all() or not (s > 0).all():
        raise FilterDivergence("the innovation or its variance is not finite and positive: the filter diverged")
    return nu * nu / s <= chi2_threshold(1, probability), s


def check_covariance(P, where=""):
    """Raise FilterDivergence unless P's diagonal is finite and positive (a NaN
    anywhere in P reaches the diagonal within one propagation step)."""
    d = P.diagonal()
    if not (d > 0).all() or not np.isfinite(d).all():
        raise FilterDivergence(f"covariance lost positiveness{(' ' + where) if where else ''}: "
                               "the filter diverged (check sensor noise settings and the initial state)")


def nees(error, P):
    """Normalised estimation error squared ``e^T P^-1 e`` (per row for batches)."""
    e = np.asarray(error, dtype=float)
    P = np.asarray(P, dtype=float)
    if e.ndim == 1:
        return float(e @ np.linalg.solve(P, e))
    return np.einsum("ni,ni->n", e, np.linalg.solve(P, e[..., None])[..., 0])
