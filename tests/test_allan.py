"""Allan deviation: recovery of simulated noise terms (issue 3 acceptance)."""

import numpy as np
import pytest

from inskit.analysis.allan import allan_deviation, allan_imu, fit_allan, gm_avar
from inskit.simulation.sensors import ImuErrors, apply_imu_errors, triad_from_datasheet
from inskit.types import ImuData
from inskit.units import DEG, DEG_PER_HOUR, MICRO_G


def test_white_noise_slope_and_level():
    rng = np.random.default_rng(0)
    dt, n = 0.01, 200_000
    N = 1e-3
    inc = rng.standard_normal(n) * N * np.sqrt(dt)
    tau, a = allan_deviation(inc, dt)
    ok = tau < 100
    assert np.allclose(a[ok] * np.sqrt(tau[ok]), N, rtol=0.1)


def test_gm_allan_formula_peak():
    tau = np.logspace(-1, 3, 2000)
    a = np.sqrt(gm_avar(tau, 1.0, 10.0))
    assert a.max() == pytest.approx(0.6174, rel=2e-3)
    assert tau[np.argmax(a)] == pytest.approx(18.9, rel=0.02)


@pytest.fixture(scope="module")
def three_hours():
    n = int(3 * 3600 * 100)
    t = np.arange(n) * 0.01
    ideal = ImuData(t, np.zeros((n, 3)), np.zeros((n, 3)))
    g = triad_from_datasheet("gyro", noise=0.1, bias_instability=1.0, bias_instability_tau_s=100.0)
    a = triad_from_datasheet("accel", noise=50.0, bias_instability=20.0, bias_instability_tau_s=100.0)
    imu, _ = apply_imu_errors(ideal, ImuErrors(g, a), np.random.default_rng(2026))
    return allan_imu(imu)


def test_gyro_arw_and_bias_instability_recovered(three_hours):
    for f in three_hours["gyro_fit"]:
        assert f.white / (DEG / 60.0) == pytest.approx(0.1, rel=0.10)
        assert f.bias_instability / DEG_PER_HOUR == pytest.approx(1.0, rel=0.25)


def test_accel_vrw_and_bias_instability_recovered(three_hours):
    for f in three_hours["accel_fit"]:
        assert f.white / MICRO_G == pytest.approx(50.0, rel=0.10)
        assert f.bias_instability / MICRO_G == pytest.approx(20.0, rel=0.25)


def test_fit_reports_rate_random_walk_when_present():
    tau = np.logspace(-2, 3.5, 60)
    K = 1e-5
    a = np.sqrt(1e-6 / tau + K**2 * tau / 3)
    f = fit_allan(tau, a)
    assert f.rate_random_walk == pytest.approx(K, rel=0.1)
    assert f.white == pytest.approx(1e-3, rel=0.1)
