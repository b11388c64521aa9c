"""The simulated barometer reads the truth's height plus its offset and noise,
with the statistics it was given."""

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.simulation import StationaryTrajectory, truth_solution
from inskit.simulation.barometer import simulate_barometer


def _truth(duration=4000.0, rate=10.0, rpy=(0.0, 0.0, 0.0)):
    traj = StationaryTrajectory((np.radians(45.0), 0.1, 250.0), rpy)
    return truth_solution(traj, np.arange(0.0, duration, 1.0 / rate))


def test_offset_noise_and_random_walk_have_the_given_statistics():
    """5000 readings: the white noise's sigma within 5 % (the sample sigma's
    relative error is 1 / sqrt(2 n) = 1 %); the random walk's 39 increments
    over 100 s have sigma rw sqrt(100) within 35 % (3 times their sample
    sigma's relative error 1 / sqrt(2 x 39) = 11 %); it starts at the constant."""
    truth = _truth(4000.0)
    log = simulate_barometer(truth, rate_hz=1.25, bias_m=-20.0, bias_rw_m_sqrt_s=0.05, noise_m=0.4,
                             rng=np.random.default_rng(3))
    assert len(log.time) == 5000 and log.time[1] - log.time[0] == pytest.approx(0.8)
    assert np.allclose(log.height_true_m, 250.0, atol=1e-6) and log.bias_m[0] == -20.0
    n = log.height_m - log.height_true_m - log.bias_m
    assert n.std() == pytest.approx(0.4, rel=0.05) and abs(n.mean()) < 4 * 0.4 / np.sqrt(5000)
    steps = np.diff(log.bias_m[::125])  # 100 s apart
    assert steps.std() == pytest.approx(0.05 * 10.0, rel=0.35)


def test_lever_arm_puts_the_sensor_above_the_imu_and_the_tilt_moves_it():
    """A sensor 1 m above the IMU (l_b = [0, 0, -1]) reads 1 m higher when
    level, cos(30 deg) m higher at 30 deg of roll."""
    level = simulate_barometer(_truth(10.0), noise_m=0.0, lever_arm_b=(0.0, 0.0, -1.0))
    assert np.allclose(level.height_true_m, 251.0, atol=1e-9)
    rolled = simulate_barometer(_truth(10.0, rpy=(np.radians(30.0), 0.0, 0.0)), noise_m=0.0,
                                lever_arm_b=(0.0, 0.0, -1.0))
    assert np.allclose(rolled.height_true_m, 250.0 + np.cos(np.radians(30.0)), atol=1e-9)


def test_bad_inputs():
    t = _truth(10.0)
    with pytest.raises(InputError, match="rng"):
        simulate_barometer(t, noise_m=0.5)
    with pytest.raises(InputError, match="noise_m"):
        simulate_barometer(t, noise_m=-1.0, rng=np.random.default_rng(0))
    with pytest.raises(InputError, match="rate_hz"):
        simulate_barometer(t, rate_hz=0.0, noise_m=0.0)
