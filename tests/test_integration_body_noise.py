"""White noise per body axis (SensorNoise.gyro_arw_axes / accel_vrw_axes): the propagation rotates
``diag(q_b)`` into NED with the attitude of every step, so a car's pitch-axis gyro noise lands on its tilt
about the right horizontal axis whatever its heading, and its quiet yaw axis keeps the heading tight."""

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.integration import FilterSettings, GnssPosition, SensorNoise, run_filter
from inskit.integration import _kernel as K
from inskit.integration.blocks import AttitudeError, PositionError, StateBlock, VelocityError
from inskit.integration.layout import StateLayout
from inskit.rotations import dcm_from_euler
from inskit.simulation import StationaryTrajectory, ideal_imu, truth_solution
from inskit.types import GnssData


def test_the_body_noise_is_rotated_into_ned():
    C = dcm_from_euler(np.radians([20.0, -35.0, 120.0]))
    n = 15
    q = np.r_[np.zeros(n), 1.0, 4.0, 9.0, 0.5, 0.25, 2.0]
    P = np.zeros((n, n))
    K.add_body_noise(P, C, q, n, 0.1)
    np.testing.assert_allclose(P[6:9, 6:9], C @ np.diag([1.0, 4.0, 9.0]) @ C.T * 0.1, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(P[3:6, 3:6], C @ np.diag([0.5, 0.25, 2.0]) @ C.T * 0.1, rtol=1e-13, atol=1e-15)
    P[3:9, 3:9] = 0.0
    assert not P.any()


def _run(noise, compiled=True, fixes=True):
    t = np.arange(0.0, 6.0, 0.01)
    traj = StationaryTrajectory((np.radians(45.0), 0.1, 100.0), np.radians([8.0, -5.0, 60.0]))
    imu = ideal_imu(traj, t, nodes=1)
    truth = truth_solution(traj, t)
    s0 = truth.state(0)
    init = type(s0).from_euler(s0.time, s0.lla, s0.v_n, s0.euler + np.radians([0.1, -0.1, 0.5]))
    tg = np.arange(0.5, 6.0, 0.5)
    g = GnssData(tg, truth_solution(traj, tg).lla, np.full((len(tg), 3), 0.5))
    meas = [GnssPosition(g)] if fixes else []
    return run_filter(imu, init, meas, FilterSettings.standard(noise, compiled_updates=compiled))


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "python"])
def test_equal_axes_are_the_scalar_noise(compiled):
    """The same density on every axis is ``q I`` in any frame: the run equals the scalar one."""
    a = SensorNoise(2e-3, 3e-2, 1e-5, 1e-4)
    b = SensorNoise(2e-3, 3e-2, 1e-5, 1e-4, gyro_arw_axes=(2e-3,) * 3, accel_vrw_axes=(3e-2,) * 3)
    ra, rb = _run(a, compiled), _run(b, compiled)
    np.testing.assert_allclose(rb.sigma, ra.sigma, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(rb.solution.lla, ra.solution.lla, rtol=0, atol=1e-12)


def test_a_quiet_yaw_axis_keeps_the_heading_tight():
    """Noise on the body x and y gyros only, no aiding: the heading variance grows by a small part of what the
    scalar model of the same mean density adds (the vehicle is tilted by 8 and 5 deg, so a little of the body x
    and y noise lands on the heading: ``C_nb diag(q_b) C_bn`` at its down entry)."""
    qm = np.sqrt((2 * 2e-3 ** 2 + 1e-5 ** 2) / 3)
    per = _run(SensorNoise(1e-3, 1e-3, 1e-7, 1e-5, gyro_arw_axes=(2e-3, 2e-3, 1e-5), accel_vrw_axes=(1e-3,) * 3),
               fixes=False)
    one = _run(SensorNoise(qm, 1e-3, 1e-7, 1e-5), fixes=False)
    grow = [r.sigma_of("att")[-1, 2] ** 2 - r.sigma_of("att")[0, 2] ** 2 for r in (per, one)]
    C = dcm_from_euler(np.radians([8.0, -5.0, 60.0]))
    q_down = C[2] ** 2 @ np.array([2e-3, 2e-3, 1e-5]) ** 2  # what the tilt lets onto the heading
    assert q_down < 0.05 * qm ** 2
    # the rest of the growth (the gyro-bias uncertainty) is common to both runs
    assert grow[1] - grow[0] == pytest.approx((qm ** 2 - q_down) * 6.0, rel=0.02)


def test_body_noise_belongs_to_the_velocity_and_attitude_blocks():
    assert StateLayout([PositionError(), VelocityError(), AttitudeError()]).body_noise() is None
    lay = StateLayout([PositionError(), VelocityError(), AttitudeError(gyro_arw_axes=(1e-3, 2e-3, 3e-3))])
    np.testing.assert_allclose(lay.body_noise(), [1e-6, 4e-6, 9e-6, 0.0, 0.0, 0.0])
    assert not lay.process_noise()[6:9].any()  # the attitude's noise is all in the body axes
    with pytest.raises(InputError, match="body_psd applies to the velocity and attitude blocks"):
        StateBlock("pos", ("n", "e", "d"), "m", 1.0, 0.0, role="pos", body_psd=(1.0, 1.0, 1.0))
    with pytest.raises(InputError, match="gyro_arw_axes must be three finite values > 0"):
        SensorNoise(1e-3, 1e-2, 1e-5, 1e-4, gyro_arw_axes=(1e-3, 0.0, 1e-3))
