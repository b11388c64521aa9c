"""First- and second-order low-pass filters, discretised exactly.

Source 004 (SOURCES-NOTES §2.3) filters the INS-minus-satellite differences of
position and velocity with

* a first-order filter ``F(p) = 1 / (T p + 1)``,
* a second-order filter ``F(p) = 1 / (T1^2 p^2 + 2 zeta T1 p + 1)``,

and gives no values for ``T``, ``T1``, ``zeta``.  Here each is a continuous
state-space model ``s' = A_c s + B_c u``, ``y = C s`` turned into the exact
discrete equivalent for an input held constant over each sample interval
(zero-order hold): ``A = exp(A_c dt)``, ``B = int_0^dt exp(A_c t) dt B_c``,
computed with the matrix exponential of the augmented matrix (Van Loan).  The
discrete filter then reproduces the continuous filter's output at the sample
times exactly for piecewise-constant input (a step response is exact to
rounding).

Convention: ``s[k+1] = A s[k] + B u[k]`` and ``y[k] = C s[k]``: the output at
sample ``k`` is the continuous output at ``t_k``, which depends on the input
held over the previous intervals.  The loop over samples is compiled.

References
----------
SOURCES-NOTES §2.3 (source 004, the filters and their unstated constants);
Franklin, Powell & Workman, *Digital Control of Dynamic Systems*, 3rd ed.,
1998, §6.3 (zero-order-hold equivalent).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy.linalg import expm, solve_discrete_lyapunov

from ..errors import ConfigError, InputError

__all__ = ["DiscreteFilter", "FirstOrderFilter", "SecondOrderFilter", "lti_step", "zoh_discretize"]


def zoh_discretize(A_c, B_c, dt):
    """Exact zero-order-hold discretisation of ``s' = A_c s + B_c u``.

    Parameters
    ----------
    A_c : (k, k) array_like
    B_c : (k,) array_like
        Single-input model.
    dt : float
        Sample interval [s], > 0.

    Returns
    -------
    A : (k, k) ndarray
        ``exp(A_c dt)``.
    B : (k,) ndarray
        ``int_0^dt exp(A_c t) dt B_c``.
    """
    if not dt > 0:
        raise ConfigError(f"`dt` must be > 0 s, got {dt}")
    A_c = np.atleast_2d(np.asarray(A_c, dtype=float))
    B_c = np.asarray(B_c, dtype=float).reshape(-1)
    k = A_c.shape[0]
    M = np.zeros((k + 1, k + 1))
    M[:k, :k] = A_c * dt
    M[:k, k] = B_c * dt
    E = expm(M)
    return E[:k, :k].copy(), E[:k, k].copy()


@njit(cache=True)
def lti_step(A, B, C, s, u):
    """One sample of a single-input filter, in place: ``s <- A s + B u``;
    returns ``C s`` after the update (the output one sample later).

    Parameters
    ----------
    A : (k, k) ndarray
    B, C : (k,) ndarray
    s : (k,) ndarray
        State, updated in place.
    u : float
        Input held over the interval.
    """
    k = s.shape[0]
    tmp = np.empty(k)
    for i in range(k):
        acc = B[i] * u
        for j in range(k):
            acc += A[i, j] * s[j]
        tmp[i] = acc
    y = 0.0
    for i in range(k):
        s[i] = tmp[i]
        y += C[i] * tmp[i]
    return y


@njit(cache=True)
def _run(A, B, C, s0, u, y):
    n, m = u.shape
    k = A.shape[0]
    s = np.empty(k)
    for c in range(m):
        for i in range(k):
            s[i] = s0[c, i]
        for t in range(n):
            yy = 0.0
            for i in range(k):
                yy += C[i] * s[i]
            y[t, c] = yy
            lti_step(A, B, C, s, u[t, c])


@dataclass(frozen=True)
class DiscreteFilter:
    """Exact discrete equivalent of a single-input, single-output filter.

    Attributes
    ----------
    A : (k, k) ndarray
    B, C : (k,) ndarray
    dt : float
        Sample interval [s].
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    dt: float

    @property
    def order(self):
        return self.A.shape[0]

    def steady_state(self, u0):
        """State for which a constant input ``u0`` gives a constant output (``(k,)``)."""
        return np.linalg.solve(np.eye(self.order) - self.A, self.B * float(u0))

    def run(self, u, *, initial="zero"):
        """Filter one or several channels.

        Parameters
        ----------
        u : (n,) or (n, m) array_like
            Input samples (held over each interval).
        initial : {"zero", "first"}
            Start from rest, or in the steady state of the first sample (no
            start-up transient).

        Returns
        -------
        (n,) or (n, m) ndarray
            Output samples (same shape as ``u``).
        """
        u = np.asarray(u, dtype=float)
        one = u.ndim == 1
        u2 = np.ascontiguousarray(u.reshape(len(u), -1))
        if not np.isfinite(u2).all():
            raise InputError("`u` has a NaN or infinite value")
        m = u2.shape[1]
        if initial == "zero":
            s0 = np.zeros((m, self.order))
        elif initial == "first":
            s0 = np.array([self.steady_state(u2[0, c]) for c in range(m)]) if len(u2) else np.zeros((m, self.order))
        else:
            raise InputError(f"`initial` must be 'zero' or 'first', got {initial!r}")
        y = np.empty_like(u2)
        _run(self.A, self.B, self.C, np.ascontiguousarray(s0), u2, y)
        return y[:, 0] if one else y

    def dc_gain(self):
        """Gain for a constant input (1 for the low-pass filters here)."""
        return float(self.C @ np.linalg.solve(np.eye(self.order) - self.A, self.B))

    def noise_gain(self):
        """Output variance over input variance for a white input sequence:
        ``C Sigma C^T`` with ``Sigma = A Sigma A^T + B B^T`` (steady state)."""
        S = solve_discrete_lyapunov(self.A, np.outer(self.B, self.B))
        return float(self.C @ S @ self.C)


@dataclass(frozen=True)
class FirstOrderFilter:
    """``F(p) = 1 / (T p + 1)`` (source 004, SOURCES-NOTES §2.3).

    Parameters
    ----------
    T : float
        Time constant [s], > 0.
    """

    T: float

    def __post_init__(self):
        if not (np.isfinite(self.T) and self.T > 0):
            raise ConfigError(f"first-order filter: `T` must be > 0 s, got {self.T}")

    def state_space(self):
        """Continuous ``(A_c, B_c, C)``: ``s' = (u - s)/T``, ``y = s``."""
        return np.array([[-1.0 / self.T]]), np.array([1.0 / self.T]), np.array([1.0])

    def discretize(self, dt) -> DiscreteFilter:
        """Exact ZOH equivalent: ``A = exp(-dt/T)``, ``B = 1 - A``."""
        a = math.exp(-dt / self.T)
        if not dt > 0:
            raise ConfigError(f"`dt` must be > 0 s, got {dt}")
        return DiscreteFilter(np.array([[a]]), np.array([1.0 - a]), np.array([1.0]), float(dt))

    def step_response(self, t):
        """Continuous unit-step response ``1 - exp(-t/T)`` at times ``t >= 0``."""
        t = np.asarray(t, dtype=float)
        return 1.0 - np.exp(-t / self.T)

    def settling_time(self, tol=0.05):
        """Time after which the step response stays within ``tol`` of 1:
        ``T ln(1/tol)`` (3.0 T for 5 %)."""
        return self.T * math.log(1.0 / tol)


@dataclass(frozen=True)
class SecondOrderFilter:
    """``F(p) = 1 / (T1^2 p^2 + 2 zeta T1 p + 1)`` (source 004).

    State ``s = [y, y']``: ``y'' = (u - y - 2 zeta T1 y') / T1^2``.

    Parameters
    ----------
    T1 : float
        Time constant [s] (natural period ``2 pi T1``), > 0.
    zeta : float
        Damping ratio, > 0.
    """

    T1: float
    zeta: float = 0.7071067811865476

    def __post_init__(self):
        if not (np.isfinite(self.T1) and self.T1 > 0):
            raise ConfigError(f"second-order filter: `T1` must be > 0 s, got {self.T1}")
        if not (np.isfinite(self.zeta) and self.zeta > 0):
            raise ConfigError(f"second-order filter: `zeta` must be > 0, got {self.zeta}")

    def state_space(self):
        T1, z = self.T1, self.zeta
        A = np.array([[0.0, 1.0], [-1.0 / T1**2, -2.0 * z / T1]])
        return A, np.array([0.0, 1.0 / T1**2]), np.array([1.0, 0.0])

    def discretize(self, dt) -> DiscreteFilter:
        A_c, B_c, C = self.state_space()
        A, B = zoh_discretize(A_c, B_c, dt)
        return DiscreteFilter(A, B, C, float(dt))

    def step_response(self, t):
        """Continuous unit-step response at times ``t >= 0`` (closed form for
        under-, critically and over-damped cases)."""
        t = np.asarray(t, dtype=float)
        z, T1 = self.zeta, self.T1
        x = t / T1
        if abs(z - 1.0) < 1e-9:
            return 1.0 - (1.0 + x) * np.exp(-x)
        if z < 1.0:
            wd = math.sqrt(1.0 - z * z)
            return 1.0 - np.exp(-z * x) * (np.cos(wd * x) + z / wd * np.sin(wd * x))
        r = math.sqrt(z * z - 1.0)
        p1, p2 = -z + r, -z - r  # poles in units of 1/T1
        return 1.0 + (p2 * np.exp(p1 * x) - p1 * np.exp(p2 * x)) / (p1 - p2)

    def settling_time(self, tol=0.05):
        """Last time the step response is outside ``1 +- tol`` (searched on a
        fine grid of the closed-form response, resolution 1e-4 T1)."""
        span = 40.0 * self.T1 / min(self.zeta, 1.0) + 40.0 * self.T1 * self.zeta
        t = np.linspace(0.0, span, 400_001)
        out = np.abs(self.step_response(t) - 1.0) > tol
        if not out.any():
            return 0.0
        return float(t[np.nonzero(out)[0][-1] + 1])
