"""[noise] in datasheet units to the filter's SI noise: what each key means,
checked on the blocks the filter builds from it (the bias's variance after
an hour, its steady state, its initial sigma)."""

import math

import pytest

from inskit.integration import InitialUncertainty, StateLayout, ins_blocks
from inskit.jobs.config import NoiseSection, config_from_dict
from inskit.jobs.navigate import build_settings, sensor_noise
from inskit.units import DEG, DEG_PER_HOUR, MICRO_G, MILLI_G

LOOSE = {"imu": {"file": "imu.csv"}, "gnss": {"file": "gnss.csv"}}


def _blocks(noise):
    lay = StateLayout(ins_blocks(sensor_noise(noise), InitialUncertainty()))
    return lay.block("bg"), lay.block("ba")


def test_random_walk_keys_are_the_drift_after_one_hour():
    """A random walk of PSD q drifts by sqrt(q t): after 3600 s by the key's
    value (deg/h per sqrt(h), micro-g per sqrt(h))."""
    bg, ba = _blocks(NoiseSection(gyro_bias_model="random-walk", gyro_bias_rrw_deg_h_sqrt_h=3.0,
                                  accel_bias_model="random-walk", accel_bias_rrw_ug_sqrt_h=40.0))
    assert math.isinf(bg.tau_s) and math.isinf(ba.tau_s) and bg.transition() == [] and ba.transition() == []
    assert math.sqrt(bg.psd[0] * 3600.0) == pytest.approx(3.0 * DEG_PER_HOUR, rel=1e-12)
    assert math.sqrt(ba.psd[0] * 3600.0) == pytest.approx(40.0 * MICRO_G, rel=1e-12)


def test_gauss_markov_keys_are_the_steady_state_and_separate_correlation_times():
    """First-order Gauss-Markov: d b / dt = -b / tau + w, steady-state variance
    q tau / 2 = sigma^2 (Brown & Hwang 2012 ch. 2), each sensor with its tau."""
    bg, ba = _blocks(NoiseSection(gyro_bias_sigma_deg_h=2.0, gyro_bias_tau_s=600.0, accel_bias_sigma_ug=30.0,
                                  accel_bias_tau_s=60.0))
    assert bg.tau_s == 600.0 and ba.tau_s == 60.0
    assert bg.transition()[0][3] == pytest.approx(-1.0 / 600.0) and ba.transition()[0][3] == pytest.approx(-1.0 / 60.0)
    assert math.sqrt(bg.psd[0] * bg.tau_s / 2.0) == pytest.approx(2.0 * DEG_PER_HOUR, rel=1e-12)
    assert math.sqrt(ba.psd[0] * ba.tau_s / 2.0) == pytest.approx(30.0 * MICRO_G, rel=1e-12)


def test_mixed_models_and_white_noise():
    n = sensor_noise(NoiseSection(gyro_arw_deg_sqrt_h=0.6, accel_vrw_m_s_sqrt_h=0.12,
                                  accel_bias_model="random-walk", accel_bias_rrw_ug_sqrt_h=10.0))
    assert n.gyro_arw == pytest.approx(0.01 * DEG)  # 0.6 deg/sqrt(h) = 0.01 deg/sqrt(s)
    assert n.accel_vrw == pytest.approx(0.002)      # 0.12 m/s/sqrt(h) = 0.002 m/s/sqrt(s)
    assert n.bias_tau_s == 300.0 and math.isinf(n.accel_bias_tau_s)
    # the static start's measured white noise raises, never lowers, the configured one
    m = sensor_noise(NoiseSection(), {"gyro_arw_rad_sqrt_s": 1.0, "accel_vrw_m_s_sqrt_s": 1e-9})
    assert m.gyro_arw == 1.0 and m.accel_vrw == pytest.approx(0.1 / 60.0)


def test_turn_on_sigmas_become_the_initial_bias_sigmas():
    cfg = config_from_dict({**LOOSE, "noise": {"gyro_turn_on_bias_deg_h": 200.0, "accel_turn_on_bias_mg": 1.0}})
    lay = build_settings(cfg, None).layout
    assert lay.block("bg").sigma0 == pytest.approx([200.0 * DEG_PER_HOUR] * 3)
    assert lay.block("ba").sigma0 == pytest.approx([MILLI_G] * 3)
    old = config_from_dict({**LOOSE, "init": {"sigma_gyro_bias_deg_s": 200.0 / 3600.0, "sigma_accel_bias_m_s2": MILLI_G}})
    lay_old = build_settings(old, None).layout
    assert lay_old.block("bg").sigma0 == pytest.approx(lay.block("bg").sigma0)  # the two spellings agree
    assert lay_old.block("ba").sigma0 == pytest.approx(lay.block("ba").sigma0)
    assert build_settings(config_from_dict(LOOSE), None).layout.block("bg").sigma0[0] == pytest.approx(0.05 * DEG)


def test_the_benchmark_noise_still_builds():
    from inskit.jobs.bench import _navigate_noise

    n = _navigate_noise()
    assert n.bias_tau_s == 300.0 and n.accel_bias_tau_s == 300.0
    assert n.gyro_bias_sigma == pytest.approx(50.0 * DEG_PER_HOUR)
