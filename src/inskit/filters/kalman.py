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

    ``scipy.special.chdtri`` (the inverse of the upper tail) rather than
    ``scipy.stats.chi2.ppf``: the same value to 1e-12 (tested), without the
    0.7 s import of ``scipy.stats`` in every command that filters.
    """
    from scipy.special import chdtri

    return float(chdtri(dof, 1.0 - probability))


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
