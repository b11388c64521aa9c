import numpy as np
import pytest

from inskit.alignment.analytic import ideal_static
from inskit.alignment.optimize import expected_J, ga_best_m, realization_J, scalar_best_m
from inskit.earth import OMEGA_IE
from inskit.units import MILLI_G


@pytest.mark.parametrize("b_mg,d_pct,signs", [(0.05, 0.0, (1, 1)), (0.0, 0.5, (1, 1)), (0.1, 0.005, (-1, 1)),
                                              (0.08, 0.01, (-1, 1)), (0.1, 0.003, (1, 1))])
def test_ga_matches_scalar_minimiser_within_1_percent(b_mg, d_pct, signs):
    lat = np.radians(45)
    C = np.eye(3)
    f, w = ideal_static(C, lat)
    J = realization_J(f + signs[0] * b_mg * MILLI_G, w + signs[1] * d_pct / 100 * OMEGA_IE, lat, C)
    g, s = ga_best_m(J, seed=1), scalar_best_m(J)
    assert 0.0 <= g.m <= 1.0
    assert abs(g.J - s.J) <= 0.01 * s.J
    assert g.generations < 200  # stopped on saturation, not at the cap


def test_optimal_m_follows_the_better_sensor():
    lat = np.radians(45)
    C = np.eye(3)
    f, w = ideal_static(C, lat)
    assert scalar_best_m(realization_J(f + 0.1 * MILLI_G, w, lat, C)).m == pytest.approx(1.0)
    assert scalar_best_m(realization_J(f, w + 0.005 * OMEGA_IE, lat, C)).m == pytest.approx(0.0, abs=1e-6)


def test_expected_criterion_for_a_sensor_class():
    lat = np.radians(45)
    C = np.eye(3)
    J = expected_J(C, lat, sigma_accel=0.1 * MILLI_G, sigma_gyro=1e-4 * OMEGA_IE, draws=100)
    s = scalar_best_m(J)
    g = ga_best_m(J, seed=3)
    assert abs(g.J - s.J) <= 0.01 * s.J
    assert J(s.m) <= min(J(0.0), J(1.0)) + 1e-12
