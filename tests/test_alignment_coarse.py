"""Start-up from data: levelling on the static start, heading from the GNSS
track, static detection."""

import numpy as np
import pytest

from inskit import earth
from inskit import rotations as rot
from inskit.alignment.coarse import (check_static, detect_motion_start, detect_static_start, heading_from_track,
                                     level, startup_state, static_intervals)
from inskit.errors import InputError
from inskit.simulation import StationaryTrajectory, ideal_imu, truth_solution
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


def test_a_standstill_is_one_interval_at_any_fix_rate():
    """Receiver velocities of 0.05 m/s noise over 60 s of rest: tested fix by
    fix against 3 sigma, 20 Hz fixes broke the rest into 7 pieces covering
    33 of its 60 s (1 Hz: one piece of 59 s); averaged over 1 s, one piece
    at either rate."""
    tr = SegmentTrajectory((np.radians(40), np.radians(-3), 150.0))
    tr.static(60).accelerate(10, 6).cruise(10)
    for rate_hz in (1.0, 20.0):
        gnss, _ = simulate_gnss(tr, 0.0, tr.duration, GnssErrors(rate_hz=rate_hz, white_h_m=0.5, white_v_m=1.0,
                                                                  velocity_sigma_m_s=0.05),
                                np.random.default_rng(2))
        iv = static_intervals(gnss)
        assert len(iv) == 1 and iv[0][0] < 2.0 and 58.5 < iv[0][1] < 60.5, (rate_hz, iv)
        assert 19.5 < detect_motion_start(gnss) < 61.5


def test_refuses_a_log_that_does_not_start_at_rest(drive):
    imu, gnss, _ = drive
    k = int(np.searchsorted(imu.time, 21.0))
    with pytest.raises(InputError, match="give the initial state"):
        startup_state(imu.slice(k), gnss.select(gnss.time >= imu.time[k]))


def test_check_static_names_the_interval_and_what_moved(drive):
    imu, _, _ = drive
    k = int(np.searchsorted(imu.time, 15.0))
    check_static(imu.slice(0, k))  # the static start passes
    k = int(np.searchsorted(imu.time, 40.0))
    with pytest.raises(InputError, match=r"the interval \[0\.0, 40\.0\] s is not static: in the window "
                                         r"\[(19|20)\.0, (20|21)\.0\] s the mean specific force moved"):
        check_static(imu.slice(0, k))


def test_vibration_beyond_the_absolute_limit_is_motion():
    """An interval that shakes from its first window on: no relative test can see it, the absolute limit can
    (gyro noise of 10 deg/s per sample, twice the 5 deg/s limit; a car standing with its engine running shows
    1.6 deg/s)."""
    tr = StationaryTrajectory((np.radians(45.0), 0.0, 0.0), (0.0, 0.0, 0.0))
    t = np.arange(0.0, 20.0 + 1e-9, 0.01)
    ideal = ideal_imu(tr, t, nodes=1)
    rng = np.random.default_rng(1)
    dth = ideal.dtheta_b + np.r_[[np.zeros(3)], rng.normal(0, np.radians(10.0), (len(t) - 1, 3)) * 0.01]
    imu = ImuData(t, dth, ideal.dv_b)
    with pytest.raises(InputError, match=r"\[0\.0, 20\.0\] s is not static: in the window \[0\.0, 1\.0\] s "
                                         r"gyro std (9|10)(\.\d+)? deg/s, static limit 5 deg/s"):
        check_static(imu)
    with pytest.raises(InputError, match=r"static for only 0\.0 s .*\(from 0\.0 s: gyro std (9|10)"):
        detect_static_start(imu)
    quiet = ImuData(t, ideal.dtheta_b + np.r_[[np.zeros(3)], rng.normal(0, np.radians(1.0), (len(t) - 1, 3)) * 0.01],
                    ideal.dv_b)
    check_static(quiet)
    assert detect_static_start(quiet) > 19.0


def test_a_track_that_never_moves_says_how_fast_it_went_and_what_to_give(drive):
    """A log entirely at rest ended `inskit navigate` in 'the GNSS track never moves: heading cannot be found
    from it', with nothing measured and no way on (init.yaw_deg does not help: the static start-up ignores
    it).  The message now gives the fastest speed against the threshold and the initial state to give."""
    from inskit.types import GnssData

    _, gnss, _ = drive
    k = int(np.searchsorted(gnss.time, 15.0))  # the first 15 s of the drive's 20 s at rest
    still = GnssData(gnss.time[:k], gnss.lla[:k], gnss.sigma_ned[:k])
    with pytest.raises(InputError, match=r"^the GNSS track never moves \(\d+ fixes over 1\d\.\d s, the fastest "
                                         r"0\.\d\d m/s, motion above 0\.30 m/s\): no heading can be found from it; "
                                         r"a log at rest needs its initial state: init\.mode = \"given\" with "
                                         r"lat_deg, lon_deg, height_m and rpy_deg$"):
        detect_motion_start(still)
