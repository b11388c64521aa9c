"""Analytic one-step alignment (source 002; issue 5 acceptance)."""

import numpy as np
import pytest

from inskit import rotations as rot
from inskit.alignment.analytic import (
    accel_basis,
    angle_errors,
    blend,
    criterion,
    eq29,
    eq29_rms,
    general_analytic,
    gyro_basis,
    ideal_static,
    measured_latitude,
    rot_east,
)
from inskit.errors import InputError
from inskit.units import ARCMIN, DEG_PER_HOUR


def random_attitudes(rng, n):
    return rot.dcm_from_euler(np.column_stack([rng.uniform(-0.5, 0.5, n), rng.uniform(-0.5, 0.5, n),
                                               rng.uniform(-np.pi, np.pi, n)]))


@pytest.mark.parametrize("lat_deg", [-80, -45, -10, 0, 10, 45, 80])
def test_error_free_sensors_recover_random_attitudes(rng, lat_deg):
    lat = np.radians(lat_deg)
    for C in random_attitudes(rng, 20):
        f, w = ideal_static(C, lat)
        for est in (accel_basis(f, w), gyro_basis(f, w, lat), blend(f, w, lat, rng.uniform()),
                    rot.orthonormalize(general_analytic(f, w, lat))):
            assert np.linalg.norm(rot.attitude_error(est, C)) < 1e-6
        assert measured_latitude(f, w) == pytest.approx(lat, abs=1e-9)
        # eq. 3 with physical magnitudes is orthonormal already for exact data
        assert np.allclose(general_analytic(f, w, lat), C, atol=1e-6)


def test_printed_eq3_is_the_transpose(rng):
    """The source's S_b R_n^-1 gives C_n^b; R_n S_b^-1 gives C_b^n."""
    lat = np.radians(30)
    C = random_attitudes(rng, 1)[0]
    f, w = ideal_static(C, lat)
    S_b = np.column_stack([np.cross(np.cross(f, w), f), -np.cross(f, w), -f])
    g_n = np.array([0, 0, np.linalg.norm(f)])
    W_n = np.linalg.norm(w) * np.array([np.cos(lat), 0, -np.sin(lat)])
    R_n = np.column_stack([np.cross(np.cross(g_n, W_n), g_n), np.cross(g_n, W_n), g_n])
    printed = S_b @ np.linalg.inv(R_n)
    assert np.allclose(printed, C.T, atol=1e-6)
    assert not np.allclose(printed, C, atol=1e-3)


def test_refuses_near_poles_and_parallel_vectors():
    C = np.eye(3)
    f, w = ideal_static(C, np.radians(89.5))
    with pytest.raises(InputError, match="vertical"):
        accel_basis(f, w)
    f, w = ideal_static(C, np.radians(45))
    with pytest.raises(InputError, match="within 2 deg of a pole"):
        gyro_basis(f, w, np.radians(89.0))
    with pytest.raises(InputError, match="vertical"):
        accel_basis(f, -f / np.linalg.norm(f) * 7e-5)  # gyro vector along gravity
    with pytest.raises(InputError, match="zero"):
        accel_basis(f, np.zeros(3))


def test_gyro_basis_is_accel_basis_rotated_about_east(rng):
    lat = np.radians(45)
    C = random_attitudes(rng, 1)[0]
    f, w = ideal_static(C, lat)
    f = f + rng.normal(0, 0.01, 3)
    w = w + rng.normal(0, 0.05 * DEG_PER_HOUR, 3)
    d = measured_latitude(f, w) - lat
    assert abs(d) > 1e-5
    assert np.allclose(gyro_basis(f, w, lat), rot_east(-d) @ accel_basis(f, w), atol=1e-12)  # exact, eq. 27
    # the blend changes only the error about east (to first order: finite rotations
    # mix the components at second order, |error| * |d| ~ 2e-5 rad here)
    e0 = angle_errors(blend(f, w, lat, 0.0), C)
    e1 = angle_errors(blend(f, w, lat, 1.0), C)
    assert abs(e0[0] - e1[0]) < 0.01 * abs(d) and abs(e0[2] - e1[2]) < 0.01 * abs(d)
    assert abs(e0[1] - e1[1]) == pytest.approx(abs(d), rel=1e-3)


def test_roll_pitch_from_accelerometers_yaw_from_gyros(rng):
    lat = np.radians(40)
    C = random_attitudes(rng, 1)[0]
    f, w = ideal_static(C, lat)
    e_gyro_only = angle_errors(accel_basis(f, w + [3e-6, -2e-6, 1e-6]), C)
    assert np.linalg.norm(e_gyro_only[:2]) < 1e-12  # tilt untouched by gyro errors
    assert abs(e_gyro_only[2]) > 1e-3
    rpy_true = rot.euler_from_dcm(C)
    rpy_acc = rot.euler_from_dcm(accel_basis(f + [1e-3, 2e-3, 0.0], w))
    assert np.abs(rpy_acc[:2] - rpy_true[:2]).max() > 1e-5  # accelerometer errors do move roll/pitch


def test_eq29_literal_matches_analytic_error_level_north():
    """Level, north-pointing IMU, biases of eq. 29's worst-case signs."""
    lat = np.radians(45)
    C = np.eye(3)
    f0, w0 = ideal_static(C, lat)
    for B, D in ((0.01, 0.04 * DEG_PER_HOUR), (0.002, 0.5 * DEG_PER_HOUR), (0.0005, 0.01 * DEG_PER_HOUR)):
        f = f0 + [-B, -B, 0.0]
        w = w0 + [0.0, D, 0.0]
        J = criterion(accel_basis(f, w), C)
        assert J == pytest.approx(eq29(B, B, D, lat), rel=0.01)


@pytest.mark.parametrize("sigma_B,sigma_D", [(0.01, 0.04), (0.001, 0.5), (0.005, 0.0), (0.0, 0.3)])
def test_eq29_matches_monte_carlo_rms(rng, sigma_B, sigma_D):
    lat = np.radians(45)
    sD = sigma_D * DEG_PER_HOUR
    J2 = []
    for C in random_attitudes(rng, 3000):
        f, w = ideal_static(C, lat)
        f = f + rng.normal(0, sigma_B, 3)
        w = w + rng.normal(0, sD, 3)
        J2.append(criterion(accel_basis(f, w), C) ** 2)
    assert np.sqrt(np.mean(J2)) == pytest.approx(eq29_rms(sigma_B, sD, lat), rel=0.05)


def test_headline_numbers():
    lat = np.radians(45)
    assert eq29(0.01, 0.01, 0.04 * DEG_PER_HOUR, lat) / ARCMIN == pytest.approx(17.17, abs=0.02)
