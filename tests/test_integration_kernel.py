"""The compiled covariance step against the dense formula."""

import numpy as np
import pytest

from inskit.integration import _kernel as K
from inskit.integration.layout import StateLayout


@pytest.mark.parametrize("gm,scale,lever,offset", [(False, True, False, False), (True, True, True, True),
                                                   (True, False, False, False)])
@pytest.mark.parametrize("second_order", [True, False])
def test_sparse_covariance_step_equals_dense(rng, gm, scale, lever, offset, second_order):
    lay = StateLayout(scale_factors=scale, lever_arm=lever, time_offset=offset)
    n = lay.size
    rows, cols = lay.transition_pattern(gauss_markov_biases=gm)
    active = np.unique(rows)
    F = np.zeros((n, n))
    F[rows, cols] = rng.normal(0, 3.0, len(rows))
    M = rng.normal(size=(n, n))
    P = M @ M.T + n * np.eye(n)
    q = rng.uniform(0, 1, n)
    dt = 0.01
    Phi = np.eye(n) + F * dt
    ref = Phi @ P @ Phi.T + np.diag(q) * dt
    if not second_order:
        ref -= F @ P @ F.T * dt * dt
    got = P.copy()
    K.propagate_covariance(got, F, rows, cols, active, dt, q, np.zeros((n, n)), np.zeros((n, n)), second_order)
    assert np.allclose(got, ref, rtol=1e-12, atol=1e-12)
    assert np.array_equal(got, got.T)


def test_transition_pattern_covers_every_nonzero_of_F(rng):
    """fill_transition writes only inside the pattern (else the sparse products would miss terms)."""
    lay = StateLayout(scale_factors=True, lever_arm=True, time_offset=True)
    n = lay.size
    F = np.zeros((n, n))
    tau_inv = np.zeros(n)
    tau_inv[lay.slice("bg")] = 1 / 300.0
    tau_inv[lay.slice("ba")] = 1 / 300.0
    C = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    K.fill_transition(F, lay.kernel_index(), np.array([0.7, 0.1, 300.0]), np.array([10.0, -5.0, 0.3]), C,
                      np.array([0.5, -0.2, -9.8]), np.array([0.01, 0.02, -0.03]), tau_inv)
    rows, cols = lay.transition_pattern(gauss_markov_biases=True)
    mask = np.zeros((n, n), bool)
    mask[rows, cols] = True
    assert not np.any(F[~mask])
