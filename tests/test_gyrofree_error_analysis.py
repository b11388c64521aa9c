"""Analytic bias and misalignment effects against simulation and Monte Carlo
(inskit.gyrofree.error_analysis)."""

import numpy as np

from inskit.gyrofree.error_analysis import (
    bias_rate_errors,
    constant_motion_error,
    eq24_printed,
    eq39_corrected,
    eq39_printed,
    linear_navigation_error,
    misalignment_rate_errors,
    monte_carlo_constant,
    quaternion_error_rate,
    worst_bias_pattern,
)
from inskit.gyrofree.layout import ten_layout
from inskit.gyrofree.model import ArrayErrors, simulate_array, source_misaligned_axes
from inskit.gyrofree.motion import ConstantRateMotion, HarmonicBodyMotion
from inskit.gyrofree.navigation import quat_to_source
from inskit.gyrofree.solvers import solve_closed_form

W = np.array([1.0, 2.0, 3.0])
F = np.array([50.0, 10.0, 10.0])
Z = np.zeros(3)
DEG = np.pi / 180


def test_equal_biases_cancel_in_eq14():
    """SOURCES-NOTES 1.4: equal biases give zero rate error (eq. 24 is wrong)."""
    e = bias_rate_errors(np.full(10, 1e-3), 0.1, W)
    assert np.abs(e.d_radicand).max() < 1e-15 and np.allclose(e.df_b, 1e-3)
    L = ten_layout(0.1)
    t = np.arange(0, 1, 1e-3)
    data = simulate_array(L, ConstantRateMotion().motion(t), ArrayErrors.build(10, bias=1e-3))
    sol = solve_closed_form(data, L, omega0=W)
    assert np.abs(sol.omega_ib_b - W).max() < 1e-12
    assert np.allclose(sol.f_b - F, 1e-3, atol=1e-12)


def test_eq24_is_the_worst_case_radicand_at_zero_rate():
    Fb, d = 1e-3, 0.1
    pattern = np.array([1, -1, -1, 1, -1, 1.0])  # maximises the p^2 radicand
    e = bias_rate_errors(Fb * pattern, d, np.zeros(3))
    assert np.isclose(e.d_radicand[0], 1.5 * Fb / d)
    assert np.allclose(e.d_radicand[1:], -0.5 * Fb / d)  # the other two cannot be worst at the same time
    assert np.isclose(e.d_omega[0], eq24_printed(Fb, d))  # sqrt(1.5F/d) holds at p = 0 only
    at_speed = bias_rate_errors(Fb * pattern, d, W)
    assert np.isclose(at_speed.d_omega[0], 1.5 * Fb / d / 2, rtol=0.01)  # ~ Delta(p^2)/(2|p|)
    assert at_speed.d_omega[0] < 0.1 * eq24_printed(Fb, d)


def test_worst_bias_of_the_source_scenario():
    """SOURCES-NOTES 1.8: worst pattern of 1e-6 biases, d = 0.1 m: 7.5e-6 rad/s and 5.3 mm."""
    w = worst_bias_pattern(1e-6, 0.1, W, F)
    assert np.isclose(w["max_d_omega"], 7.5e-6, rtol=0.01)
    assert np.isclose(np.linalg.norm(w["position_error_m"]), 5.3e-3, rtol=0.02)


def test_bias_formulas_against_the_solver(rng):
    L = ten_layout(0.1)
    b = rng.normal(0, 1e-4, 10)
    data = simulate_array(L, ConstantRateMotion().motion(np.arange(0, 0.5, 1e-3)), ArrayErrors.build(10, bias=b))
    sol = solve_closed_form(data, L, omega0=W)
    e = bias_rate_errors(b, 0.1, W)
    assert np.allclose(sol.f_b[0] - F, e.df_b, atol=1e-13)
    assert np.allclose(sol.omega_ib_b[0] - W, e.d_omega, atol=1e-12)
    assert np.allclose(e.d_omega, e.d_omega_linear, rtol=1e-3)


def test_corrected_eq39_matches_the_simulated_array(rng):
    """Unequal angles within the pairs and a general motion (omega_dot != 0):
    the complete eq. 39 matches the array model to rounding, the printed one
    does not (missing cos-difference terms, eq. 34's slip)."""
    th = rng.uniform(-0.5, 0.5, 6) * DEG
    L = ten_layout(0.1)
    mot = HarmonicBodyMotion.random(rng).motion(np.linspace(0, 3, 31))
    data = simulate_array(L, mot, ArrayErrors.build(10, axes_true_b=source_misaligned_axes(L, th)))
    sol = solve_closed_form(data, L, omega0=mot.omega_ib_b[0])
    for k in (0, 15, 30):
        args = (th, mot.f_b[k], mot.omega_ib_b[k], mot.omega_dot_ib_b[k], 0.1)
        assert np.allclose(sol.f_b[k] - mot.f_b[k], eq39_corrected(*args), atol=1e-12)
        assert np.abs(eq39_printed(*args) - eq39_corrected(*args)).max() > 1e-5
        e = misalignment_rate_errors(*args)
        assert np.allclose(np.abs(sol.omega_ib_b[k]) - np.abs(mot.omega_ib_b[k]),
                           np.sign(mot.omega_ib_b[k]) * e.d_omega, atol=1e-9)


def test_misalignment_all_minus_0p1_deg_is_d_independent():
    """SOURCES-NOTES 1.8: -0.1 deg on m1-m6 gives Delta f = -[0.0174, 0.0174, 0.0873],
    Delta omega = [2.6e-3, 0, 8.7e-4] and dP = [-0.06, -1.86, -2.26] m for any d."""
    th = np.full(6, -0.1 * DEG)
    for d in (0.01, 0.1, 1.0):
        e = misalignment_rate_errors(th, F, W, Z, d)
        assert np.allclose(e.df_b, [-0.0175, -0.0175, -0.0873], atol=2e-4)
        assert np.allclose(e.d_omega, [2.61e-3, 0.0, 8.70e-4], atol=2e-5)
        assert np.allclose(constant_motion_error(W, F, e.d_omega, e.df_b, [10.0])[0], [-0.06, -1.86, -2.26],
                           atol=0.01)


def test_eq25_must_be_linearised():
    """The printed eq. 25 (1/2 Omega(d omega) d eps) gives no growth from a
    zero quaternion error; the linearisation 1/2 [Omega(omega) d eps +
    Omega(d omega) eps] matches the difference of two exact attitudes."""
    q = quat_to_source([1.0, 0, 0, 0])
    dw = np.array([1e-3, -2e-3, 5e-4])
    assert np.allclose(quaternion_error_rate(q, np.zeros(4), W, dw, corrected=False), 0)
    h = 1e-3
    e_true = quat_to_source(ConstantRateMotion(W + dw).truth([h]).q_ib[0]) - \
        quat_to_source(ConstantRateMotion(W).truth([h]).q_ib[0])
    rate = quaternion_error_rate(q, np.zeros(4), W, dw)
    assert np.abs(rate * h - e_true).max() < 1e-3 * np.abs(e_true).max()  # second-order remainder ~ h |omega|


def test_linear_propagation_against_exact_constant_motion():
    t = np.arange(0, 10.0 + 1e-9, 1e-3)
    truth = ConstantRateMotion().truth(t)
    df, dw = np.array([1e-3, -2e-3, 5e-4]), np.array([1e-4, 2e-4, -1e-4])
    lin, _, _ = linear_navigation_error(truth, F, df, dw)
    exact = constant_motion_error(W, F, dw, df, t)
    assert np.linalg.norm(lin[-1] - exact[-1]) < 0.01 * np.linalg.norm(exact[-1])


# Monte Carlo, 200 seeded runs of the full chain (array model with the drawn
# errors and noise, closed form, eq. 43-44 navigation) against the analytic
# prediction at the mean errors.  The inputs are chosen so that the sampling
# error of the Monte Carlo mean (std / sqrt(200)) is below 3 % of the mean
# (measured 0.6-1.5 %), so the 10 % bound tests the model: non-linearity of the
# square roots and the propagation.  The printed eq. 24 misses by far more.
RUNS = 200


def test_bias_monte_carlo_against_analytic():
    pattern = worst_bias_pattern(1e-6, 0.1, W, F)["pattern"]
    mu = 5e-3 * pattern
    mc = monte_carlo_constant(RUNS, 7, d=0.1, bias_mean=mu, bias_sigma=1e-3, noise_sigma=1e-3)
    e = bias_rate_errors(mu, 0.1, W)
    pred = constant_motion_error(W, F, e.d_omega, e.df_b, [10.0])[0]
    mean_w = mc.d_omega.mean(axis=0)
    mean_p = mc.position_error_m.mean(axis=0)
    assert np.linalg.norm(mean_w - e.d_omega) < 0.1 * np.linalg.norm(e.d_omega)
    assert np.linalg.norm(mean_p - pred) < 0.1 * np.linalg.norm(pred)
    assert np.linalg.norm(mc.position_error_m.std(axis=0)) / np.sqrt(RUNS) < 0.03 * np.linalg.norm(pred)
    # the printed eq. 24 would predict sqrt(1.5F/d) = 0.27 rad/s on every rate
    assert eq24_printed(5e-3, 0.1) > 5 * np.abs(mean_w).max()


def test_misalignment_monte_carlo_against_analytic():
    th = -0.1 * DEG
    mc = monte_carlo_constant(RUNS, 8, d=0.1, theta_mean=th, theta_sigma=0.001 * DEG, noise_sigma=1e-3)
    e = misalignment_rate_errors(np.full(6, th), F, W, Z, 0.1)
    pred = constant_motion_error(W, F, e.d_omega, e.df_b, [10.0])[0]
    assert np.linalg.norm(mc.df_b.mean(axis=0) - e.df_b) < 0.1 * np.linalg.norm(e.df_b)
    assert np.linalg.norm(mc.d_omega.mean(axis=0) - e.d_omega) < 0.1 * np.linalg.norm(e.d_omega)
    assert np.linalg.norm(mc.position_error_m.mean(axis=0) - pred) < 0.1 * np.linalg.norm(pred)
    assert np.linalg.norm(mc.position_error_m.std(axis=0)) / np.sqrt(RUNS) < 0.03 * np.linalg.norm(pred)
