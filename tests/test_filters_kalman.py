"""Gating thresholds and the Joseph update against independent formulas."""

import numpy as np
import pytest
from scipy.stats import chi2

from inskit.filters.kalman import chi2_threshold, joseph_update


@pytest.mark.parametrize("dof", [1, 2, 3, 6, 8, 15, 40, 120])
@pytest.mark.parametrize("p", [1e-9, 1e-3, 0.05, 0.5, 0.95, 0.99, 0.9999, 1 - 1e-9])
def test_chi2_threshold_is_the_chi_square_quantile(dof, p):
    """The hand-made quantile (bisection on the incomplete gamma) against scipy's, both tails."""
    assert chi2_threshold(dof, p) == pytest.approx(chi2.ppf(p, dof), rel=1e-12)


def test_chi2_threshold_edges():
    assert chi2_threshold(3, 0.0) == 0.0 and chi2_threshold(3, 1.0) == np.inf
    for dof, p in ((0, 0.9), (2, 1.5), (2, -0.1)):
        with pytest.raises(ValueError):
            chi2_threshold(dof, p)


def test_joseph_update_equals_the_textbook_update_and_gates():
    rng = np.random.default_rng(3)
    A = rng.standard_normal((5, 5))
    P = A @ A.T + 5 * np.eye(5)
    H = rng.standard_normal((2, 5))
    R = np.diag([0.5, 0.2])
    nu = np.array([0.3, -0.1])
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    res = joseph_update(P, nu, H, R, gate_probability=0.9999)
    assert res.accepted
    np.testing.assert_allclose(res.dx, K @ nu, rtol=1e-10)
    np.testing.assert_allclose(res.P, (np.eye(5) - K @ H) @ P, rtol=1e-9, atol=1e-12)
    assert res.nis == pytest.approx(float(nu @ np.linalg.solve(S, nu)))
    far = np.sqrt(np.diag(S)) * 10.0  # NIS ~ 100+: far outside the 0.9999 gate of 2 dof (18.4)
    assert not joseph_update(P, far, H, R, gate_probability=0.9999).accepted
