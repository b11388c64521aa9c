"""Analytic effects of accelerometer bias and misalignment (source 003 §5,
eq. 21-42, in the corrected forms of SOURCES-NOTES §1.4-1.5), their
propagation into navigation errors, and the Monte Carlo check.

Bias (eq. 21-25, SOURCES-NOTES §1.4):

* eq. 21: a bias F integrates directly to ``dV = F t``, ``dP = F t^2/2``;
* eq. 22: ``Delta f_b1 = (b1 + b2)/2`` and likewise;
* eq. 14 on the biases: ``Delta(p^2) = (b1-b2-b3+b4-b5+b6)/(4d)``,
  ``Delta(q^2) = (-b1+b2+b3-b4-b5+b6)/(4d)``,
  ``Delta(r^2) = (-b1+b2-b3+b4+b5-b6)/(4d)``.  **Equal biases cancel**: the
  rate errors are zero.  The printed eq. 24, ``Delta p = +-sqrt(1.5 F/d)``, is
  the worst case over bias signs of the radicand (6F/(4d)) and is the rate
  error only at ``p = 0``; the three bounds cannot be reached together (when
  one radicand error is +1.5F/d the others are -0.5F/d).  In general
  ``Delta p = sqrt(p^2 + Delta(p^2)) - |p| ~ Delta(p^2) / (2|p|)``;
* eq. 25 prints ``Delta eps_dot = 1/2 Omega(Delta omega) Delta eps``, second
  order (no growth from zero); linearised it is
  ``Delta eps_dot = 1/2 [Omega(omega) Delta eps + Omega(Delta omega) eps]``
  (:func:`quaternion_error_rate`).

Misalignment (eq. 26-42, SOURCES-NOTES §1.5), angles theta_1..6 of m1-m6 in
their body planes (:func:`~inskit.gyrofree.model.source_misaligned_axes`):

* specific-force errors, complete (eq. 39 misses the cos-difference terms and
  eq. 34 has ``(dpr - d p_dot)`` for ``(dqr + d p_dot)``):
  ``Delta f_b1 = 1/2 [(c1+c2-2) f_b1 + (c2-c1) d(q^2+r^2) + (s1+s2) f_b3 + (s1-s2) d(pr - q_dot)]``,
  ``Delta f_b2 = 1/2 [(c3+c4-2) f_b2 + (c4-c3) d(p^2+r^2) + (s3+s4) f_b3 + (s3-s4) d(qr + p_dot)]``,
  ``Delta f_b3 = 1/2 [(c5+c6-2) f_b3 + (c6-c5) d(p^2+q^2) + (s5+s6) f_b1 + (s5-s6) d(pr + q_dot)]``;
* rate errors (eq. 41-42): eq. 14 applied to the misaligned outputs, minus the
  truth.  Unequal angles within a pair leak ``(s_k2 - s_k1) f / (4d)`` into
  the radicands (a 1/d effect that dominates); equal angles give rate errors
  independent of d.

Propagation (:func:`linear_navigation_error`): with the estimated attitude
``C' = C (I + [phi x])`` and ``psi = C phi`` (inertial axes),
``psi_dot = C Delta omega``, ``Delta v_dot = psi x (C f) + C Delta f``,
``Delta r_dot = Delta v``: three quadratures along the true attitude (the
first-order content of the corrected eq. 25 with eq. 44 and
``r_ddot = C_ib f_b``).  For constant motion :func:`constant_motion_error`
gives the exact (non-linear) difference of the closed-form trajectories.

References
----------
SOURCES-NOTES §1.4, §1.5, §1.8; SYSTEM.md §5.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .layout import ten_layout
from .model import ArrayErrors, simulate_array, source_misaligned_axes
from .motion import ConstantRateMotion, InertialSolution

_P2 = np.array([1, -1, -1, 1, -1, 1], float)
_Q2 = np.array([-1, 1, 1, -1, -1, 1], float)
_R2 = np.array([-1, 1, -1, 1, 1, -1], float)


def _biases(b):
    b = np.asarray(b, float).reshape(-1)
    if b.shape not in ((6,), (10,)):
        raise InputError(f"biases must be given for the 6 or 10 accelerometers, got {b.shape[0]}")
    return np.concatenate([b, np.zeros(10 - len(b))])


def bias_direct(F, t):
    """Eq. 21: velocity and position errors ``F t`` and ``F t^2 / 2`` of a
    specific-force error F [m/s^2] at times ``t`` [s]."""
    t = np.asarray(t, float)
    return F * t, 0.5 * F * t**2


def eq24_printed(F, d):
    """The printed eq. 24, ``sqrt(1.5 F / d)`` [rad/s]: the worst-case radicand
    error ``6F/(4d)`` as a rate error, valid only at zero rate."""
    return np.sqrt(1.5 * np.asarray(F, float) / d)


@dataclass(frozen=True)
class RateErrors:
    """Errors of the closed-form estimates for given sensor errors.

    Attributes
    ----------
    df_b : (3,) ndarray
        Specific-force error [m/s^2].
    d_radicand : (3,) ndarray
        Errors of ``p^2, q^2, r^2`` from eq. 14 [(rad/s)^2].
    d_omega : (3,) ndarray
        Rate error, exact through the square roots (eq. 41-42) [rad/s].
    d_omega_linear : (3,) ndarray
        First order, ``Delta(p^2) / (2 p)`` (infinite at zero rate).
    d_omega_dot : (2,) ndarray
        Errors of ``p_dot`` (eq. 19) and ``q_dot`` (eq. 17) [rad/s^2].
    """

    df_b: np.ndarray
    d_radicand: np.ndarray
    d_omega: np.ndarray
    d_omega_linear: np.ndarray
    d_omega_dot: np.ndarray


def _rates_from_radicand(omega, d_rad):
    w = np.asarray(omega, float)
    s = np.where(w < 0, -1.0, 1.0)
    exact = s * (np.sqrt(np.maximum(w * w + d_rad, 0.0)) - np.abs(w))
    with np.errstate(divide="ignore", invalid="ignore"):
        lin = np.where(w != 0, d_rad / (2 * np.where(w != 0, w, 1.0)), np.inf * np.sign(d_rad))
    return exact, lin


def bias_rate_errors(bias, d, omega) -> RateErrors:
    """Bias effects on the closed form (eq. 22-24 corrected, SOURCES-NOTES §1.4).

    Parameters
    ----------
    bias : (6,) or (10,) array_like
        Accelerometer biases b1.. [m/s^2] (m7-m10 zero when six are given).
    d : float
        Lever arm [m].
    omega : (3,) array_like
        True rate [rad/s] (signs kept: the error of the signed estimate).
    """
    b = _biases(bias)
    df = np.array([(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2])
    drad = np.array([_P2 @ b[:6], _Q2 @ b[:6], _R2 @ b[:6]]) / (4 * d)
    exact, lin = _rates_from_radicand(omega, drad)
    dqd = (-b[0] - b[1] + b[4] + b[5] - 2 * b[6] + 2 * b[7]) / (4 * d)
    dpd = (b[2] + b[3] - b[4] - b[5] + 2 * b[8] - 2 * b[9]) / (4 * d)
    return RateErrors(df, drad, exact, lin, np.array([dpd, dqd]))


def misaligned_outputs(theta, f_b, omega, omega_dot, d):
    """Outputs of m1-m6 with misaligned sensing axes, source 003 eq. 27, 28,
    31, 32, 35, 36 in their physics form (SOURCES-NOTES §1.5: eq. 31 reads
    ``dqr + d p_dot`` where the print has ``dpr + dp``)."""
    th = np.asarray(theta, float).reshape(6)
    c, s = np.cos(th), np.sin(th)
    f1, f2, f3 = np.asarray(f_b, float)
    p, q, r = np.asarray(omega, float)
    pd, qd, _ = np.asarray(omega_dot, float)
    return np.array([
        c[0] * (f1 - d * (q * q + r * r)) + s[0] * (f3 + d * p * r - d * qd),
        c[1] * (f1 + d * (q * q + r * r)) + s[1] * (f3 - d * p * r + d * qd),
        c[2] * (f2 - d * (p * p + r * r)) + s[2] * (f3 + d * q * r + d * pd),
        c[3] * (f2 + d * (p * p + r * r)) + s[3] * (f3 - d * q * r - d * pd),
        c[4] * (f3 - d * (p * p + q * q)) + s[4] * (f1 + d * p * r + d * qd),
        c[5] * (f3 + d * (p * p + q * q)) + s[5] * (f1 - d * p * r - d * qd),
    ])


def eq39_corrected(theta, f_b, omega, omega_dot, d):
    """Specific-force error of misalignment, complete form (SOURCES-NOTES §1.5)."""
    th = np.asarray(theta, float).reshape(6)
    c, s = np.cos(th), np.sin(th)
    f1, f2, f3 = np.asarray(f_b, float)
    p, q, r = np.asarray(omega, float)
    pd, qd, _ = np.asarray(omega_dot, float)
    return 0.5 * np.array([
        (c[0] + c[1] - 2) * f1 + (c[1] - c[0]) * d * (q * q + r * r) + (s[0] + s[1]) * f3 + (s[0] - s[1]) * d * (p * r - qd),
        (c[2] + c[3] - 2) * f2 + (c[3] - c[2]) * d * (p * p + r * r) + (s[2] + s[3]) * f3 + (s[2] - s[3]) * d * (q * r + pd),
        (c[4] + c[5] - 2) * f3 + (c[5] - c[4]) * d * (p * p + q * q) + (s[4] + s[5]) * f1 + (s[4] - s[5]) * d * (p * r + qd),
    ])


def eq39_printed(theta, f_b, omega, omega_dot, d):
    """Eq. 39 as printed: no cos-difference terms, and ``(dpr - d p_dot)`` in
    the second line (eq. 34)."""
    th = np.asarray(theta, float).reshape(6)
    c, s = np.cos(th), np.sin(th)
    f1, f2, f3 = np.asarray(f_b, float)
    p, _, r = np.asarray(omega, float)
    pd, qd, _ = np.asarray(omega_dot, float)
    return 0.5 * np.array([
        (c[0] + c[1] - 2) * f1 + (s[0] + s[1]) * f3 + (s[0] - s[1]) * (d * p * r - d * qd),
        (c[2] + c[3] - 2) * f2 + (s[2] + s[3]) * f3 + (s[2] - s[3]) * (d * p * r - d * pd),
        (c[4] + c[5] - 2) * f3 + (s[4] + s[5]) * f1 + (s[4] - s[5]) * (d * p * r + d * qd),
    ])


def misalignment_rate_errors(theta, f_b, omega, omega_dot, d) -> RateErrors:
    """Misalignment effects on the closed form: corrected eq. 39 and eq. 41-42.

    Parameters
    ----------
    theta : (6,) array_like
        Angles of m1-m6 [rad].
    f_b, omega, omega_dot : (3,) array_like
        True specific force [m/s^2], rate [rad/s], angular acceleration
        [rad/s^2].
    d : float
        [m].
    """
    fm = misaligned_outputs(theta, f_b, omega, omega_dot, d)
    f0 = misaligned_outputs(np.zeros(6), f_b, omega, omega_dot, d)
    df = eq39_corrected(theta, f_b, omega, omega_dot, d)
    drad = np.array([_P2 @ (fm - f0), _Q2 @ (fm - f0), _R2 @ (fm - f0)]) / (4 * d)
    exact, lin = _rates_from_radicand(omega, drad)
    dm = fm - f0
    dqd = (-dm[0] - dm[1] + dm[4] + dm[5]) / (4 * d)
    dpd = (dm[2] + dm[3] - dm[4] - dm[5]) / (4 * d)
    return RateErrors(df, drad, exact, lin, np.array([dpd, dqd]))


def quaternion_error_rate(eps, deps, omega, domega, *, corrected=True):
    """Eq. 25 in the source's scalar-last quaternion ``eps``.

    ``corrected``: ``1/2 [Omega(omega) deps + Omega(domega) eps]`` (the
    linearisation); otherwise the printed ``1/2 Omega(domega) deps``.
    ``Omega`` is eq. 43's matrix (:func:`~inskit.gyrofree.navigation.eq43_matrix`).
    """
    from .navigation import eq43_matrix

    if corrected:
        return 0.5 * (eq43_matrix(omega) @ np.asarray(deps, float) + eq43_matrix(domega) @ np.asarray(eps, float))
    return 0.5 * eq43_matrix(domega) @ np.asarray(deps, float)


def _cumtrapz(y, t):
    out = np.zeros_like(y)
    dt = np.diff(t)[:, None]
    out[1:] = np.cumsum(0.5 * (y[1:] + y[:-1]) * dt, axis=0)
    return out


def linear_navigation_error(truth: InertialSolution, f_b, df_b, domega):
    """First-order position, velocity and attitude errors along a true
    inertial trajectory for specific-force and rate errors.

    Parameters
    ----------
    truth : InertialSolution
        True attitude at (finely spaced) times; errors start at zero at
        ``truth.time[0]``.
    f_b : (3,) or (n, 3) array_like
        True specific force [m/s^2].
    df_b, domega : (3,) or (n, 3) array_like
        Errors of the specific force [m/s^2] and rate [rad/s].

    Returns
    -------
    dr_i, dv_i, psi_i : (n, 3) ndarray
        Position [m], velocity [m/s] and attitude (small rotation, inertial
        axes) [rad] errors: estimate minus truth.

    Notes
    -----
    Trapezoid quadratures; the relative error is about ``(|omega| dt)^2/12``.
    """
    n = len(truth.time)
    C = truth.C_ib

    def rows(x):
        a = np.asarray(x, float)
        return np.broadcast_to(a, (n, 3)) if a.shape == (3,) else a

    Cf = np.einsum("nij,nj->ni", C, rows(f_b))
    psi = _cumtrapz(np.einsum("nij,nj->ni", C, rows(domega)), truth.time)
    acc = np.cross(psi, Cf) + np.einsum("nij,nj->ni", C, rows(df_b))
    dv = _cumtrapz(acc, truth.time)
    dr = _cumtrapz(dv, truth.time)
    return dr, dv, psi


def constant_motion_error(omega, f_b, domega, df_b, t):
    """Exact position error of constant-rate navigation: the closed-form
    trajectory with ``omega + domega``, ``f_b + df_b`` minus the true one
    (same start, :class:`~inskit.gyrofree.motion.ConstantRateMotion`)."""
    t = np.atleast_1d(np.asarray(t, float))
    est = ConstantRateMotion(np.asarray(omega, float) + domega, np.asarray(f_b, float) + df_b).truth(t)
    tru = ConstantRateMotion(omega, f_b).truth(t)
    return est.r_i - tru.r_i


def sign_patterns(m):
    """All ``2^m`` patterns of +-1 (``(2^m, m)``), for worst-case searches."""
    return np.array(list(itertools.product((-1.0, 1.0), repeat=m)))


def worst_bias_pattern(F, d, omega, f_b, T=10.0):
    """Worst sign pattern of equal-magnitude biases F on ten accelerometers
    for the constant scenario (exact propagation).

    Returns
    -------
    dict
        ``pattern`` (10,), ``d_omega`` (3,) [rad/s], ``position_error_m`` (3,)
        at T, and ``max_d_omega`` over all patterns [rad/s].
    """
    pats = sign_patterns(10)
    best = None
    max_dw = 0.0
    for s in pats:
        e = bias_rate_errors(F * s, d, omega)
        max_dw = max(max_dw, float(np.abs(e.d_omega).max()))
        dp = constant_motion_error(omega, f_b, e.d_omega, e.df_b, [T])[0]
        if best is None or np.linalg.norm(dp) > np.linalg.norm(best[2]):
            best = (s, e.d_omega, dp)
    return {"pattern": best[0], "d_omega": best[1], "position_error_m": best[2], "max_d_omega": max_dw}


# --- Monte Carlo -----------------------------------------------------------------------
@dataclass(frozen=True)
class MonteCarloResult:
    """Per-run errors of the closed-form unit on the constant scenario.

    Attributes
    ----------
    df_b, d_omega : (runs, 3) ndarray
        Mean over the run of the specific-force [m/s^2] and rate [rad/s]
        errors of the solver.
    position_error_m : (runs, 3) ndarray
        Inertial position error at the end [m].
    """

    df_b: np.ndarray
    d_omega: np.ndarray
    position_error_m: np.ndarray


def monte_carlo_constant(runs, seed, *, d=0.1, duration=10.0, rate_hz=200.0, bias_mean=0.0, bias_sigma=0.0,
                         theta_mean=0.0, theta_sigma=0.0, noise_sigma=0.0, omega=(1.0, 2.0, 3.0),
                         f_b=(50.0, 10.0, 10.0)) -> MonteCarloResult:
    """Seeded Monte Carlo of the ten-accelerometer unit on source 003's scenario.

    Each run draws biases ``bias_mean + N(0, bias_sigma)`` (per accelerometer;
    ``bias_mean`` a number or ``(10,)``), misalignment angles of m1-m6
    ``theta_mean + N(0, theta_sigma)`` [rad] in the source's planes, white
    noise ``noise_sigma`` per sample, simulates the array, solves it with the
    closed form (robust signs) and navigates in the inertial frame.
    One ``numpy.random.default_rng(seed)`` feeds every draw.
    """
    if runs < 1:
        raise InputError(f"`runs` must be >= 1, got {runs}")
    from .navigation import navigate_solution_inertial
    from .solvers import solve_closed_form

    rng = np.random.default_rng(seed)
    layout = ten_layout(d)
    motion = ConstantRateMotion(omega, f_b)
    t = np.arange(0.0, duration + 0.5 / rate_hz, 1.0 / rate_hz)
    mot = motion.motion(t)
    r_true = motion.truth(t[-1:]).r_i[0]
    out = {"df": np.empty((runs, 3)), "dw": np.empty((runs, 3)), "dp": np.empty((runs, 3))}
    for i in range(runs):
        b = np.asarray(bias_mean, float) + rng.standard_normal(10) * bias_sigma
        th = np.asarray(theta_mean, float) + rng.standard_normal(6) * theta_sigma
        axes = source_misaligned_axes(layout, np.broadcast_to(th, (6,)))
        err = ArrayErrors.build(10, bias=b, axes_true_b=axes, noise_sigma=noise_sigma)
        data = simulate_array(layout, mot, err, rng)
        sol = solve_closed_form(data, layout, omega0=omega, noise_sigma=noise_sigma)
        nav = navigate_solution_inertial(sol)
        out["df"][i] = (sol.f_b - mot.f_b).mean(axis=0)
        out["dw"][i] = (sol.omega_ib_b - mot.omega_ib_b).mean(axis=0)
        out["dp"][i] = nav.r_i[-1] - r_true
    return MonteCarloResult(out["df"], out["dw"], out["dp"])


__all__ = ["MonteCarloResult", "RateErrors", "bias_direct", "bias_rate_errors", "constant_motion_error",
           "eq24_printed", "eq39_corrected", "eq39_printed", "linear_navigation_error", "misaligned_outputs",
           "misalignment_rate_errors", "monte_carlo_constant", "quaternion_error_rate", "sign_patterns",
           "worst_bias_pattern"]
