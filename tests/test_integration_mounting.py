"""The evidence of an unmodelled IMU mounting, on constructed tracks whose
mounting is known: the direction of travel in the IMU's axes, the forward
accelerometer bias, the warning and the corrected mount."""

import math
import re

import numpy as np
import pytest

from inskit import earth
from inskit import rotations as rot
from inskit.integration import Mounting, StateLayout, Track, ins_blocks
from inskit.integration.blocks import mounting_dcm
from inskit.integration.mounting import (G0, corrected_mount_rpy_deg, gnss_velocity, mounting_check,
                                         mounting_evidence, mounting_summary, mounting_warning)
from inskit.io.rtklib import mount_dcm
from inskit.types import GnssData, NavSolution

LAT0, V = 0.7, 15.0


def drive(pitch_deg, yaw_deg, *, T=300.0, spin=None, noise_m=0.3, accel_bias_x=0.0, blocks=(), seed=1):
    """A car driving north at 15 m/s on a meridian, its IMU mounted at
    (pitch, yaw) against it (``C_nb = C_nv C_vb``), the track at 10 Hz with
    the IMU's attitude, and 1 Hz fixes of the vehicle with ``noise_m`` per
    axis.  ``spin = (t0, t1)``: the IMU's attitude also turns at 10 deg/s in
    that window (epochs the evidence must leave out)."""
    rng = np.random.default_rng(seed)
    rn, _ = earth.principal_radii(LAT0, 0.0)
    t = np.arange(0.0, T + 1e-9, 0.1)
    lla = np.stack([LAT0 + V * t / rn, np.full_like(t, 0.2), np.full_like(t, 100.0)], axis=1)
    v_n = np.tile([V, 0.0, 0.0], (len(t), 1))
    C_vb = mounting_dcm(math.radians(pitch_deg), math.radians(yaw_deg))[0]
    yaw = np.zeros_like(t)
    if spin is not None:
        a, b = spin
        yaw = np.radians(10.0) * (np.clip(t, a, b) - a)
    C_nv = rot.dcm_from_euler(np.stack([np.zeros_like(t), np.zeros_like(t), yaw], axis=1))
    C_nb = C_nv @ C_vb
    nav = NavSolution(t, lla, v_n, rot.quat_from_dcm(C_nb))
    lay = StateLayout(list(ins_blocks()) + list(blocks))
    aux = np.tile(lay.initial_aux(), (len(t), 1))
    aux[:, lay.aux_slice("ba").start] = accel_bias_x
    track = Track(nav, aux, np.ones((len(t), lay.size)), lay)
    k = np.arange(0, len(t), 10)
    g_lla = lla[k].copy()
    g_lla[:, 0] += rng.normal(0.0, noise_m, len(k)) / rn
    g_lla[:, 1] += rng.normal(0.0, noise_m, len(k)) / (earth.principal_radii(LAT0, 0.0)[1] * math.cos(LAT0))
    g_lla[:, 2] += rng.normal(0.0, noise_m, len(k))
    return track, GnssData(t[k], g_lla, np.full((len(k), 3), max(noise_m, 0.01)))


def test_fix_velocity_is_the_central_difference():
    _, gnss = drive(0.0, 0.0, noise_m=0.0)
    rows, v = gnss_velocity(gnss)
    assert rows[0] == 1 and rows[-1] == len(gnss) - 2
    # north along the meridian (the track's speed uses the start's radius: 15.0003 m/s at the end)
    assert np.allclose(v[:, 0], V, atol=1e-3) and np.abs(v[:, 1:]).max() < 1e-8


def test_evidence_finds_the_mounting_of_a_straight_drive():
    """4 deg nose-down and 2 deg left (the ``[imu] mount_rpy_deg``
    convention): the direction of travel in the IMU's axes gives them back
    within 4 standard errors.  The standard error is what white 0.3 m fixes
    leave: the central differences of a 30 s batch telescope to its end
    fixes, 0.3 m sqrt(4) / 60 s = 0.01 m/s or 0.04 deg at 15 m/s per batch,
    0.013 deg over 10 batches."""
    track, gnss = drive(4.0, 2.0)
    ev = mounting_evidence(track, gnss)
    assert ev["epochs"] > 290
    for axis, true in (("pitch", 4.0), ("yaw", 2.0)):
        assert abs(ev[f"{axis}_deg"] - true) < 4 * ev[f"{axis}_se_deg"] + 1e-3, ev
        assert 0.004 < ev[f"{axis}_se_deg"] < 0.04, ev
    assert ev["accel_bias_pitch_deg"] == 0.0


def test_turning_epochs_are_left_out():
    """The IMU's attitude turning a full circle at 10 deg/s for 36 s (no such
    path: a turn would add the lever arm's ``omega x l``) is not read as a
    mounting."""
    track, gnss = drive(0.0, 0.0, spin=(100.0, 136.0))
    ev = mounting_evidence(track, gnss)
    assert 255 <= ev["epochs"] <= 263  # 299 with a velocity, 36-37 turning
    assert abs(ev["yaw_deg"]) < 4 * ev["yaw_se_deg"] + 1e-3


def test_a_bent_pitch_shows_in_the_forward_accelerometer_bias():
    """A filter bent to the vehicle's pitch carries ``ba_x = -g sin(pitch)``: a
    forward bias of -g sin(3 deg) (0.51 m/s^2, 5 initial sigmas of 0.1) on a
    track whose attitude already follows the vehicle gives 3 deg; within 3
    initial sigmas the bias is not counted."""
    b = -G0 * math.sin(math.radians(3.0))
    track, gnss = drive(0.0, 0.0, accel_bias_x=b)
    ev = mounting_evidence(track, gnss)
    assert ev["accel_bias_prior_sigmas"] == pytest.approx(abs(b) / 0.1)
    assert ev["accel_bias_pitch_deg"] == pytest.approx(3.0, abs=1e-9)
    assert ev["pitch_deg"] == pytest.approx(ev["travel_pitch_deg"] + 3.0, abs=1e-9)
    ev2 = mounting_evidence(*drive(0.0, 0.0, accel_bias_x=0.25))
    assert ev2["accel_bias_pitch_deg"] == 0.0


def test_warning_names_the_mounting_and_the_fix():
    track, gnss = drive(4.0, 0.3)
    ev = mounting_evidence(track, gnss)
    w = mounting_warning(ev)
    assert w.startswith("mounting:") and "[constraints] mounting = true" in w
    assert re.search(r"pitch \+(3\.9[5-9]|4\.0[0-5]) deg", w), w
    assert "not significant" in w  # 0.3 deg of yaw is below the 1 deg limit
    assert mounting_warning(mounting_evidence(*drive(0.3, -0.4))) is None
    assert mounting_warning(None) is None


def test_corrected_mount_takes_the_residual_in():
    """Rotating the sensor readings by the corrected mount is the same as
    rotating by the configured one and then into the vehicle's axes by the
    residual: ``mount_dcm(M1) = C_vb mount_dcm(M0)``; angles stay on the
    configured turn (185 deg, not -175)."""
    m0 = (180.0, -6.79, 185.35)
    m1 = corrected_mount_rpy_deg(m0, 3.8, 0.3)
    C_vb = mounting_dcm(math.radians(3.8), math.radians(0.3))[0]
    assert np.allclose(mount_dcm(np.radians(m1)), C_vb @ mount_dcm(np.radians(m0)), atol=1e-12)
    assert 170.0 < m1[2] < 200.0 and 170.0 < m1[0] < 190.0
    assert corrected_mount_rpy_deg((0.0, 0.0, 0.0), 4.0, 2.0) == pytest.approx([0.0, 4.0, 2.0])


def test_check_runs_only_for_an_unmodelled_mounting_and_the_summary_reports_a_modelled_one():
    track, gnss = drive(4.0, 2.0)
    ev, w = mounting_check(track, gnss, constrained=True)
    assert ev is not None and w is not None
    assert mounting_check(track, gnss, constrained=False) == (None, None)
    assert mounting_summary(track) == {}
    modelled, _ = drive(4.0, 2.0, blocks=[Mounting()])
    assert mounting_check(modelled, gnss, constrained=True) == (None, None)
    s = mounting_summary(modelled, (0.0, 0.0, 0.0))
    assert s["mounting_rpy_deg"] == [0.0, 0.0, 0.0] and s["mounting_sigma_deg"][0] is None
    assert s["mounting_sigma_deg"][1] == pytest.approx(math.degrees(1.0))  # the constructed track's unit sigmas
