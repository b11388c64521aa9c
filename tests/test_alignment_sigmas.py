"""Honest alignment sigmas (issue 12, item 9): over seeded simulated static
logs of every grade the true attitude lies within 3 sigma (at most 2 of 100
outside, against 0.27 expected of a Gaussian), and error / sigma has an RMS
near 1 where the sigma is informative (so the sigmas are not merely huge).
The logs are made in memory by the simulation package with each grade's
preset errors (turn-on bias, bias instability, white noise, scale factor)."""

import numpy as np
import pytest

from inskit import earth
from inskit import rotations as rot
from inskit.alignment.analytic import eq29_rms
from inskit.alignment.static import DEFAULT_GRADE, NO_HEADING_SIGMA_DEG, align_imu, bias_prior
from inskit.simulation import StationaryTrajectory, ideal_imu
from inskit.simulation.sensors import apply_imu_errors, preset
from inskit.units import DEG, DEG_PER_HOUR, MICRO_G

SEEDS = 100
ANGLES = ("roll", "pitch", "yaw")
GRADES = ("navigation", "tactical", "industrial-mems", "consumer-mems")


def _static_log(grade, seed, duration_s=30.0, rate_hz=50.0):
    """A static log at a random latitude (|lat| < 60 deg) and attitude (tilt within 10 deg, any heading)."""
    rng = np.random.default_rng(seed)
    lat = rng.uniform(-60.0, 60.0) * DEG
    rpy = np.r_[rng.uniform(-10.0, 10.0, 2) * DEG, rng.uniform(-np.pi, np.pi)]
    t = np.arange(0.0, duration_s + 1e-9, 1.0 / rate_hz)
    imu, _ = apply_imu_errors(ideal_imu(StationaryTrajectory((lat, 0.0, 0.0), tuple(rpy)), t, nodes=1),
                              preset(grade), rng)
    return imu, lat, rpy


def _z(results, truths):
    """(runs, 3) errors and sigmas [deg]."""
    est = np.array([[r[f"{a}_deg"] for a in ANGLES] for r in results]) * DEG
    err = np.degrees(rot.wrap_angle(est - np.array(truths)))
    sig = np.array([[r[f"{a}_sigma_deg"] for a in ANGLES] for r in results])
    return err, sig


def _assert_honest(err, sig, label):
    for j, a in enumerate(ANGLES):
        z = err[:, j] / sig[:, j]
        outside = int(np.sum(np.abs(z) > 3.0))
        assert outside <= 2, f"{label} {a}: {outside} of {len(z)} outside 3 sigma"
        tight = sig[:, j] < 30.0  # where the linear error model holds
        if tight.sum() >= 20:
            rms = float(np.sqrt(np.mean(z[tight] ** 2)))
            assert 0.6 < rms < 1.4, f"{label} {a}: RMS of error/sigma {rms:.2f} over {tight.sum()} runs"


@pytest.mark.parametrize("grade", GRADES)
def test_one_step_sigmas_cover_the_truth(grade):
    runs = {"accel": [], "gyro": [], "blend": []}
    truths = []
    for seed in range(SEEDS):
        imu, lat, rpy = _static_log(grade, seed)
        truths.append(rpy)
        for method in runs:
            runs[method].append(align_imu(imu, lat, method=method, m=0.5 if method == "blend" else None,
                                          t_end=30.0, grade=grade))
    for method, res in runs.items():
        err, sig = _z(res, truths)
        _assert_honest(err, sig, f"{grade} {method}")
    # the grades whose gyros see the Earth rate get a heading; the MEMS ones are told they do not
    usable = np.mean([r["heading_usable"] for r in runs["accel"]])
    assert usable == (1.0 if grade in ("navigation", "tactical") else 0.0)
    # levelling with the accelerometer basis: sigma about north = B / g (40 mg -> 2.3 deg, 27 ug -> 0.0016 deg),
    # plus the scale-factor prior on the horizontal specific force of a tilted IMU (100 ppm x g sin 10 deg ~ 17 ug)
    B = bias_prior(grade=grade).accel
    tilt = np.median([r["error_sigma_ned_deg"][0] for r in runs["accel"]])
    Bg = np.degrees(B / earth.gravity_down(0.0, 0.0))
    assert 0.99 * Bg < tilt < 1.3 * Bg


@pytest.mark.parametrize("grade", ["tactical", "consumer-mems"])
def test_fine_alignment_sigmas_cover_the_truth(grade):
    res, truths = [], []
    for seed in range(SEEDS):
        imu, lat, rpy = _static_log(grade, 1000 + seed, duration_s=20.0, rate_hz=25.0)
        truths.append(rpy)
        res.append(align_imu(imu, lat, method="fine", t_end=20.0, grade=grade))
    err, sig = _z(res, truths)
    _assert_honest(err, sig, f"{grade} fine")
    for r in res:
        if not r["heading_usable"]:
            assert r["converge_time_s"][2] is None and "unobservable" in r["converge_note"]
            assert r["yaw_sigma_deg"] == NO_HEADING_SIGMA_DEG


def test_default_prior_is_the_conservative_consumer_grade():
    """No bias class given: consumer MEMS is assumed and said, for any IMU."""
    imu, lat, rpy = _static_log("navigation", 7)
    r = align_imu(imu, lat, method="accel", t_end=30.0)
    assert DEFAULT_GRADE == "consumer-mems" and "assumed consumer-mems" in r["sigma_basis"]
    assert r["accel_bias_sigma_ug"] == pytest.approx(np.hypot(40000.0, 100 * 0.664 / 0.6174), rel=1e-9)
    assert r["gyro_bias_sigma_deg_h"] == pytest.approx(np.hypot(3600.0, 20 * 0.664 / 0.6174), rel=1e-9)
    # a 1 deg/s gyro bias is 340 times the Earth rate's horizontal part: no heading, whatever the data say
    assert not r["heading_usable"] and r["yaw_sigma_deg"] == NO_HEADING_SIGMA_DEG
    assert r["error_sigma_ned_deg"][0] == pytest.approx(2.29, abs=0.01)
    # the user's classes replace the assumption and are named
    r = align_imu(imu, lat, method="accel", t_end=30.0, accel_bias_sigma=25 * MICRO_G,
                  gyro_bias_sigma=0.003 * DEG_PER_HOUR)
    assert r["sigma_basis"].startswith("given: accelerometer bias 25 ug and gyro bias 0.003 deg/h")
    assert r["heading_usable"] and r["yaw_sigma_deg"] < 1.0


def test_accel_basis_sigma_is_eq29_in_expectation():
    """Source 002 eq. 29 (SYSTEM.md §4): with the headline biases (0.01 m/s^2, 0.04 deg/h) at 45 deg and
    noise-free sensors, the accelerometer basis errs by sigma_B/g about north and east and by
    sqrt((sigma_D/(W cos phi))^2 + (tan phi sigma_B/g)^2) about down; the total is eq29_rms (14.3 arcmin)."""
    lat = np.radians(45.0)
    t = np.arange(0.0, 10.0 + 1e-9, 0.01)
    imu = ideal_imu(StationaryTrajectory((lat, 0.0, 0.0), (0.0, 0.0, 0.0)), t, nodes=1)
    B, D = 0.01, 0.04 * DEG_PER_HOUR
    r = align_imu(imu, lat, method="accel", t_end=10.0, accel_bias_sigma=B, gyro_bias_sigma=D)
    g = earth.gravity_down(lat, 0.0)
    s = np.radians(r["error_sigma_ned_deg"])
    assert s[0] == pytest.approx(B / g, rel=1e-3) and s[1] == pytest.approx(B / g, rel=1e-3)
    assert s[2] == pytest.approx(np.hypot(D / (earth.OMEGA_IE * np.cos(lat)), np.tan(lat) * B / g), rel=1e-3)
    assert np.sqrt(np.sum(s ** 2)) == pytest.approx(eq29_rms(B, D, lat), rel=1e-3)
    assert np.degrees(eq29_rms(B, D, lat)) * 60 == pytest.approx(14.3, abs=0.1)
