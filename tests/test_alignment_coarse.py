"""Start-up from data: levelling on the static start, heading from the GNSS
track, static detection."""

import numpy as np
import pytest

from inskit import earth
from inskit import rotations as rot
from inskit.alignment.coarse import (detect_motion_start, detect_static_start, heading_from_track, level,
                                     startup_state, static_intervals)
from inskit.errors import InputError
from inskit.simulation import ideal_imu, truth_solution
from inskit.simulation.gnss import GnssErrors, simulate_gnss
from inskit.simulation.segments import SegmentTrajectory
from inskit.types import ImuData

GYRO_BIAS = np.array([2e-4, -1e-4, 3e-4])   # rad/s
LEVER = np.array([0.3, 0.0, -1.2])


@pytest.fixture(scope="module")
def drive():
    tr = SegmentTrajectory((np.radians(40), np.radians(-3), 150.0), yaw0=np.radians(130.0))
    tr.static(20).accelerate(10, 6).cruise(10).turn(np.radians(45), rate=np.radians(10)).cruise(10)
    t = np.arange(0.0, tr.duration, 0.01)
    ideal = ideal_imu(tr, t, nodes=3)
    imu = ImuData(t, ideal.dtheta_b + np.r_[[np.zeros(3)], GYRO_BIAS * np.diff(t)[:, None]], ideal.dv_b)
    rng = np.random.default_rng(2)
    gnss, _ = simulate_gnss(tr, 0.0, tr.duration, GnssErrors(rate_hz=5.0, white_h_m=0.02, white_v_m=0.03,
                                                              velocity_sigma_m_s=0.0, lever_arm_b_m=tuple(LEVER)),
                            rng)
    return imu, gnss, truth_solution(tr, t)


def test_level_of_a_tilted_rest():
    C = rot.dcm_from_euler([0.03, -0.05, 1.0])
    f_b = C.T @ np.array([0.0, 0.0, -9.8])
    assert np.allclose(level(f_b), [0.03, -0.05], atol=1e-12)


def test_startup_recovers_attitude_position_and_gyro_bias(drive):
    imu, gnss, truth = drive
    s = startup_state(imu, gnss, LEVER)
    err = rot.attitude_error(s.state.C_nb, truth.C_nb[0])
    assert np.degrees(np.abs(err[:2])).max() < 0.01        # ideal accelerometers: exact levelling
    assert abs(np.degrees(err[2])) < 1.0                   # course of 2 cm fixes over 1 s: ~0.2 deg
    assert np.linalg.norm(earth.lla_to_ned(s.state.lla, truth.lla[0])) < 0.1
    assert np.allclose(s.gyro_bias, GYRO_BIAS, atol=2e-6)   # Earth rate removed
    assert 18.0 < s.static_end < 21.0


def test_motion_and_static_detection(drive):
    imu, gnss, _ = drive
    assert 19.5 < detect_motion_start(gnss) < 21.5
    iv = static_intervals(gnss)
    assert len(iv) == 1 and iv[0][0] < 1.0 and 17.0 < iv[0][1] < 20.5
    assert 17.0 < detect_static_start(imu) <= 20.5
    t_head, course = heading_from_track(gnss, 20.0)
    assert abs(np.degrees(rot.wrap_angle(course - np.radians(130.0)))) < 1.0


def test_refuses_a_log_that_does_not_start_at_rest(drive):
    imu, gnss, _ = drive
    k = int(np.searchsorted(imu.time, 21.0))
    with pytest.raises(InputError, match="give the initial state"):
        startup_state(imu.slice(k), gnss.select(gnss.time >= imu.time[k]))
