"""Fine alignment: the stationary ZUPT filter converges to the attitude, in
the time and to the accuracy gyrocompassing allows."""

import numpy as np
import pytest

from inskit import earth
from inskit import rotations as rot
from inskit.alignment.analytic import eq29_rms
from inskit.alignment.fine import bias_floor, fine_align
from inskit.integration import SensorNoise
from inskit.simulation import StationaryTrajectory, ideal_imu, truth_solution
from inskit.types import ImuData, NavState
from inskit.units import DEG_PER_HOUR


def test_fine_alignment_converges_from_a_coarse_start():
    lat = np.radians(45.0)
    tr = StationaryTrajectory((lat, 0.2, 50.0), (0.01, -0.02, 0.7))
    t = np.arange(0.0, 600.0 + 1e-9, 0.01)
    ideal = ideal_imu(tr, t, nodes=1)
    rng = np.random.default_rng(9)
    arw, vrw = 0.005 * np.pi / 180 / 60, 1e-4    # tactical: 0.005 deg/sqrt(h), 6 ug/sqrt(Hz)
    dt = np.diff(t)[:, None]
    dth = ideal.dtheta_b.copy()
    dv = ideal.dv_b.copy()
    dth[1:] += rng.normal(0, arw * np.sqrt(dt), (len(t) - 1, 3))
    dv[1:] += rng.normal(0, vrw * np.sqrt(dt), (len(t) - 1, 3))
    imu = ImuData(t, dth, dv)
    truth = truth_solution(tr, t[:1]).state(0)
    coarse = NavState.from_euler(0.0, truth.lla, np.zeros(3), truth.euler + np.radians([0.3, -0.3, 2.0]))
    noise = SensorNoise(arw, vrw, 0.01 * DEG_PER_HOUR, 1e-6, np.inf)
    r = fine_align(imu, coarse, noise, sigma_tilt=np.radians(0.5), sigma_yaw=np.radians(3.0),
                   gyro_bias_sigma=0.1 * DEG_PER_HOUR, accel_bias_sigma=1e-4)
    err = rot.attitude_error(rot.dcm_from_euler(r.rpy), truth.C_nb)
    assert np.all(np.abs(err) < 3 * r.sigma_rpy + 1e-6)
    # heading: gyrocompassing limit ~ (gyro bias sigma) / (W cos lat), ARW-limited in 10 min
    bound = 0.1 * DEG_PER_HOUR / (earth.OMEGA_IE * np.cos(lat))
    assert r.sigma_rpy[2] < 3 * bound
    assert np.isfinite(r.converge_time_s[:2]).all() and r.converge_time_s[0] < 30.0
    assert r.sigma_history.shape == (len(t), 3)


def test_unobservable_heading_is_never_converged():
    """Issue 12: gyros whose bias (here 1 deg/s, consumer MEMS) swamps the Earth rate cannot gyrocompass; the
    filter must end with a heading sigma no better than the prior allows and report no convergence time,
    while the tilt converges to the accelerometer-bias limit B/g (SYSTEM.md §4: nothing beats it at rest)."""
    lat = np.radians(45.0)
    tr = StationaryTrajectory((lat, 0.0, 0.0), (0.0, 0.0, 0.3))
    t = np.arange(0.0, 20.0 + 1e-9, 0.02)
    ideal = ideal_imu(tr, t, nodes=1)
    rng = np.random.default_rng(4)
    bg, ba = rng.normal(0, np.radians(1.0), 3), rng.normal(0, 0.05, 3)
    dt = np.diff(t)[:, None]
    imu = ImuData(t, ideal.dtheta_b + np.r_[[np.zeros(3)], bg * dt], ideal.dv_b + np.r_[[np.zeros(3)], ba * dt])
    truth = truth_solution(tr, t[:1]).state(0)
    noise = SensorNoise(1e-4, 1e-3, 1e-7, 1e-6, np.inf)
    r = fine_align(imu, truth, noise, gyro_bias_sigma=np.radians(1.0), accel_bias_sigma=0.05)
    assert np.isnan(r.converge_time_s[2])
    assert r.sigma_rpy[2] >= r.sigma_history[0, 2] * 0.99  # the prior (90 deg, capped) is all there is
    floor = bias_floor(lat, 0.05, np.radians(1.0))
    assert r.sigma_rpy[0] >= floor[0] and r.sigma_rpy[0] == pytest.approx(0.05 / earth.gravity_down(lat, 0.0))
    assert np.isfinite(r.converge_time_s[:2]).all()


def test_bias_floor_is_eq29():
    lat = np.radians(45.0)
    B, D = 0.01, 0.04 * DEG_PER_HOUR
    assert np.sqrt(np.sum(bias_floor(lat, B, D) ** 2)) == pytest.approx(eq29_rms(B, D, lat), rel=1e-12)
