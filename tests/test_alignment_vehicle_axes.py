"""inskit.alignment.vehicle_axes: the direction of travel and the down axis
found in the IMU's axes from the GNSS acceleration against the specific
force, on a simulated car whose IMU is mounted at known angles."""

import warnings

import numpy as np
import pytest

from inskit import rotations as rot
from inskit.alignment.inmotion import auto_startup
from inskit.alignment.vehicle_axes import OFF_AXIS, axes_rotation, rotate_imu, vehicle_axes
from inskit.simulation.scenario import Scenario, simulate
from inskit.units import DEG
from scenarios import short_car

SHORT = short_car("short car", [{"type": "static", "duration_s": 40.0},
                                {"type": "accelerate", "speed_m_s": 15.0, "duration_s": 10.0},
                                {"type": "cruise", "duration_s": 20.0},
                                {"type": "turn", "angle_deg": 90.0, "radius_m": 40.0},
                                {"type": "cruise", "duration_s": 20.0},
                                {"type": "turn", "angle_deg": -90.0, "radius_m": 40.0},
                                {"type": "decelerate", "speed_m_s": 0.0, "duration_s": 10.0},
                                {"type": "static", "duration_s": 10.0}], lever_arm_b_m=None)


def sim(mount, seed=1):
    sc = Scenario.model_validate(SHORT)
    sc = sc.model_copy(update={"imu": sc.imu.model_copy(update={"mount_rpy_deg": tuple(mount)})})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = simulate(sc, seed=seed)
    return r.imu, r.gnss


def check(mount, gnss_keep=None):
    imu, gnss = sim(mount)
    if gnss_keep is not None:
        gnss = gnss.select(gnss_keep(gnss.time))
    s = auto_startup(imu, gnss)
    e = s.state.euler
    return imu, vehicle_axes(imu, gnss, e[0], e[1], gyro_bias=s.gyro_bias)


@pytest.mark.parametrize("mount,travel_deg", [((0.0, 0.0, 0.0), 0.0), ((0.0, 0.0, 180.0), 180.0),
                                              ((0.0, 0.0, 90.0), 90.0), ((0.0, 0.0, -120.0), -120.0),
                                              ((0.0, 0.0, 30.0), 30.0), ((180.0, 0.0, 0.0), 0.0),
                                              ((180.0, 0.0, 185.0), 175.0)])
def test_the_direction_of_travel_and_the_down_axis_are_found_in_the_imu_axes(mount, travel_deg):
    # travel_deg: the vehicle's x axis seen from above, clockwise from the IMU's x (an IMU upside down turns
    # the other way about its own z: mount yaw 185 is travel 175)
    _, c = check(mount)
    assert c.reason == "" and c.upside_down == (abs(mount[0]) > 90)
    err = abs(rot.wrap_angle(c.travel_yaw - travel_deg * DEG))
    # 1 Hz fixes with 0.5 m noise over ~150 s of driving: a few degrees; 3 standard errors
    assert err < max(3.0 * c.travel_yaw_se, 0.5 * DEG), (c.summary(), mount)
    assert c.travel_yaw_se < 3.0 * DEG
    assert c.off_axis == (abs(travel_deg) > OFF_AXIS / DEG)


@pytest.mark.parametrize("mount", [(0.0, 0.0, 90.0), (180.0, 0.0, 185.0), (0.0, 0.0, -120.0)])
def test_the_rotation_takes_the_readings_back_into_the_vehicle_axes(mount):
    imu, c = check(mount)
    back = rotate_imu(imu, axes_rotation(c))
    square, _ = sim((0.0, 0.0, 0.0))
    # dcm(D) should be the mount's dcm, but for the measured angle's error (a few degrees)
    C = rot.dcm_from_euler(axes_rotation(c)).T @ rot.dcm_from_euler(np.radians(mount))
    angle = np.degrees(np.linalg.norm(rot.rotvec_from_dcm(C)))
    assert angle < 3.0 * c.travel_yaw_se / DEG + 0.5, angle
    # the readings of a rotated triad keep their norms; the mean specific force at rest comes back to -g on z
    assert np.allclose(np.linalg.norm(back.dv_b, axis=1), np.linalg.norm(imu.dv_b, axis=1), atol=1e-12)
    f_rest = back.dv_b[1:3000].sum(axis=0) / (back.time[2999] - back.time[0])
    f_sq = square.dv_b[1:3000].sum(axis=0) / (square.time[2999] - square.time[0])
    assert f_rest == pytest.approx(f_sq, abs=0.1)


def test_a_right_angle_within_three_standard_errors_is_taken_as_exact():
    _, c = check((0.0, 0.0, 180.0))
    assert abs(c.rotation_yaw) == pytest.approx(np.pi)
    _, c = check((0.0, 0.0, 30.0))
    assert c.rotation_yaw == c.travel_yaw


def test_fixes_across_a_gap_do_not_make_an_acceleration():
    # an outage withheld from the fixes: differences across it are not the vehicle's acceleration (it made
    # 165 deg of a 180 deg mount before the gap test)
    _, c = check((0.0, 0.0, 180.0), gnss_keep=lambda t: (t < 55.0) | (t > 85.0))
    assert c.travel_yaw_se < 3.0 * DEG, c.summary()
    assert abs(rot.wrap_angle(c.travel_yaw - np.pi)) < max(3.0 * c.travel_yaw_se, 0.5 * DEG), c.summary()


def test_a_log_without_acceleration_says_why_it_cannot_tell():
    imu, gnss = sim((0.0, 0.0, 0.0))
    c = vehicle_axes(imu.slice(0, 3900), gnss.select(gnss.time < 39.0), 0.0, 0.0)  # the static start only
    assert c.travel_yaw is None and not c.vehicle_axes_differ and "acceleration" in c.reason
    assert np.all(axes_rotation(c) == 0.0)
