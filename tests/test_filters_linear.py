"""The generic linear Kalman driver: a hand-computed case and Monte Carlo NEES."""

import numpy as np
import pytest
from scipy import stats

from inskit.errors import InputError
from inskit.filters.linear import (
    expm_taylor,
    run_linear_kalman,
    simulate_linear,
    van_loan,
)


def test_scalar_random_walk_by_hand():
    # p0 = 4, r = 1, q = 0.5, z = (2, 1):
    # k=0: K = 4/5, x+ = 1.6, P+ = 0.8; predict P- = 1.3
    # k=1: K = 1.3/2.3, x+ = 1.6 + (1 - 1.6) 1.3/2.3, P+ = 1.3/2.3
    res = run_linear_kalman(1.0 * np.eye(1), 0.5 * np.eye(1), np.eye(1), np.eye(1), [[2.0], [1.0]], [0.0],
                            4.0 * np.eye(1))
    assert res.x_post[0, 0] == pytest.approx(1.6, abs=1e-15)
    assert res.P_post[0, 0, 0] == pytest.approx(0.8, abs=1e-15)
    assert res.P_prior[1, 0, 0] == pytest.approx(1.3, abs=1e-15)
    assert res.x_post[1, 0] == pytest.approx(1.6 - 0.6 * 1.3 / 2.3, abs=1e-14)
    assert res.P_post[1, 0, 0] == pytest.approx(1.3 / 2.3, abs=1e-14)
    assert res.innovation[1, 0] == pytest.approx(-0.6, abs=1e-14)
    assert res.nis[0] == pytest.approx(4.0 / 5.0, abs=1e-14)  # 2^2 / (4 + 1)


def test_two_state_against_textbook_form():
    """Constant velocity, position measured: compare with the plain textbook
    recursion written out here (P+ = P- - K H P-, equal to Joseph for the
    optimal gain), including a missing epoch and a missing component."""
    dt = 1.0
    Phi = np.array([[1.0, dt], [0.0, 1.0]])
    Q = np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]]) * 0.1
    H = np.array([[1.0, 0.0], [0.0, 1.0]])
    R = np.diag([4.0, 0.25])
    z = np.array([[1.0, 0.5], [np.nan, np.nan], [3.5, np.nan], [4.0, 1.2]])
    x, P = np.zeros(2), np.diag([100.0, 10.0])
    xs = []
    for k in range(len(z)):
        use = np.isfinite(z[k])
        if use.any():
            Hk, Rk = H[use], R[np.ix_(use, use)]
            K = P @ Hk.T @ np.linalg.inv(Hk @ P @ Hk.T + Rk)
            x = x + K @ (z[k, use] - Hk @ x)
            P = P - K @ Hk @ P
        xs.append((x.copy(), P.copy()))
        x, P = Phi @ x, Phi @ P @ Phi.T + Q
    res = run_linear_kalman(Phi, Q, H, R, z, np.zeros(2), np.diag([100.0, 10.0]))
    for k, (xk, Pk) in enumerate(xs):
        assert np.allclose(res.x_post[k], xk, rtol=1e-12, atol=1e-12)
        assert np.allclose(res.P_post[k], Pk, rtol=1e-10, atol=1e-12)
    assert np.isnan(res.nis[1]) and np.isnan(res.innovation[2, 1])


def test_van_loan_and_taylor():
    F = np.array([[0.0, 1.0], [0.0, 0.0]])
    Phi, Q = van_loan(F, np.array([[0.0, 0.0], [0.0, 2.0]]), 3.0)
    assert np.allclose(Phi, [[1.0, 3.0], [0.0, 1.0]])
    assert np.allclose(Q, 2.0 * np.array([[9.0, 4.5], [4.5, 3.0]]))  # q [dt^3/3, dt^2/2; dt^2/2, dt]
    G = np.array([[0.0, 1e-3], [-1e-3, -1e-4]])
    from scipy.linalg import expm

    assert np.allclose(expm_taylor(G, 10.0, 6), expm(G * 10.0), atol=1e-14)


def test_nees_monte_carlo(rng):
    """Consistency over 100 seeded runs: the average NEES (2 states) and NIS
    (1 measurement) stay inside their 95 % chi-square bands at >= 90 % of the
    epochs (a wrong gain or covariance formula pushes them far outside)."""
    dt, runs, N = 1.0, 100, 150
    Phi, Q = van_loan(np.array([[0.0, 1.0], [0.0, 0.0]]), np.diag([0.0, 0.01]), dt)
    H, R = np.array([[1.0, 0.0]]), np.array([[1.0]])
    P0 = np.diag([10.0, 1.0])
    nees = np.empty((runs, N))
    nis = np.empty((runs, N))
    for r in range(runs):
        x, z = simulate_linear(Phi, Q, H, R, np.zeros(2), P0, N, rng)
        res = run_linear_kalman(Phi, Q, H, R, z, np.zeros(2), P0)
        e = x - res.x_post
        nees[r] = np.einsum("ki,ki->k", e, np.linalg.solve(res.P_post, e[..., None])[..., 0])
        nis[r] = res.nis
    lo, hi = stats.chi2.ppf([0.025, 0.975], 2 * runs) / runs
    inside = ((nees.mean(0) > lo) & (nees.mean(0) < hi)).mean()
    assert inside > 0.9
    assert nees.mean() == pytest.approx(2.0, abs=0.15)
    lo1, hi1 = stats.chi2.ppf([0.025, 0.975], runs) / runs
    assert ((nis.mean(0) > lo1) & (nis.mean(0) < hi1)).mean() > 0.9
    # a filter told the wrong R (4x too small) is inconsistent: the test can fail
    bad = run_linear_kalman(Phi, Q, H, R / 4, z, np.zeros(2), P0)
    e = x - bad.x_post
    assert np.mean(np.einsum("ki,ki->k", e, np.linalg.solve(bad.P_post, e[..., None])[..., 0])) > 3.0


def test_shape_errors():
    with pytest.raises(InputError, match="`Phi` must have shape"):
        run_linear_kalman(np.eye(3), np.eye(2), np.eye(2), np.eye(2), np.zeros((3, 2)), np.zeros(2), np.eye(2))
    with pytest.raises(InputError, match="positive definite"):
        run_linear_kalman(np.eye(2), np.eye(2), np.eye(2), np.eye(2), np.zeros((3, 2)), np.zeros(2), -np.eye(2))
