"""Consistency axis by axis (:mod:`inskit.analysis.consistency`)."""

import numpy as np
import pytest

from inskit.analysis.consistency import SETTLE_S, axis_innovation_rms, axis_scale_step, horizontal_vertical
from inskit.errors import InputError
from inskit.integration import GnssPosition, GnssPositionError
from inskit.types import GnssData

RNG = np.random.default_rng(7)


def innovations(n=20000, std=(1.0, 1.0, 2.0), rate_hz=4.0):
    t = np.arange(n) / rate_hz
    sigma = np.full((n, 3), 0.02)
    nu = RNG.standard_normal((n, 3)) * np.asarray(std) * sigma
    return t, nu, sigma


def test_the_rms_per_axis_is_the_noise_over_its_sigma():
    """20 000 normal draws: the sample RMS is within 3 % of the true
    standard deviation (its relative standard error is 1 / sqrt(2 n) = 0.5 %)."""
    t, nu, sigma = innovations()
    rms, n = axis_innovation_rms(t, nu, sigma)
    assert n == len(t) - int(SETTLE_S * 4.0)  # the first 5 s after the first update left out
    assert rms == pytest.approx([1.0, 1.0, 2.0], rel=0.03)
    assert horizontal_vertical(rms) == pytest.approx((1.0, 2.0), rel=0.03)


def test_rejected_updates_and_those_settling_after_a_break_are_left_out():
    t, nu, sigma = innovations(4000)
    t[2000:] += 60.0  # a 60 s outage
    nu[2000:2004] *= 1e3  # its end: the INS's drift, not the fixes' noise
    accepted = np.ones(len(t), bool)
    accepted[100] = False
    nu[100] *= 1e3  # a rejected outlier
    rms, n = axis_innovation_rms(t, nu, sigma, accepted)
    assert rms == pytest.approx([1.0, 1.0, 2.0], rel=0.08)
    assert n == len(t) - 2 * 20 - 1
    rms_all, _ = axis_innovation_rms(t, nu, sigma, settle_s=0.0)
    assert rms_all.min() > 10.0  # the premise: kept, they would swamp it


@pytest.mark.parametrize("rate_hz", [1.0, 0.5])
def test_fixes_at_1_hz_or_slower_with_jittered_time_tags_are_not_all_breaks(rate_hz):
    """A fixed 1 s pause made every update whose time tag came a millisecond
    late the start of a break: fixes at 1 Hz with 1 ms of jitter counted none
    of 4000 (the summary lost its gnss_axes, the calibration said the run
    made no update), fixes at 0.5 Hz none ever.  A break is judged against
    the updates' own interval too; an outage still is one."""
    t, nu, sigma = innovations(4000, rate_hz=rate_hz)
    t = t + RNG.uniform(-1e-3, 1e-3, len(t))
    t[2000:] += 60.0  # a 60 s outage
    nu[2000] *= 1e3  # its end
    rms, n = axis_innovation_rms(t, nu, sigma)
    settle = int(np.ceil(SETTLE_S * rate_hz))
    assert len(t) - 2 * settle - 2 <= n <= len(t) - 2 * settle + 2, n
    assert rms == pytest.approx([1.0, 1.0, 2.0], rel=0.08)


def test_no_update_counted_gives_nan_and_zero():
    t, nu, sigma = innovations(10)
    rms, n = axis_innovation_rms(t, nu, sigma)  # 2.5 s: all settling
    assert n == 0 and np.isnan(rms).all() and rms.shape == (3,)
    with pytest.raises(ValueError, match="nu and sigma"):
        axis_innovation_rms(t, nu[:, :2], sigma)


def test_one_step_brings_the_axes_to_their_mean_and_keeps_it():
    """Sigmas multiplied by the step's factors divide each normalised
    innovation by them: horizontal and vertical both land on
    ``sqrt((2 h^2 + v^2) / 3)``, the mean square (the mean NIS per degree
    of freedom) unchanged."""
    rms = np.array([0.45, 0.50, 0.75])
    f = axis_scale_step(rms)
    h, v = horizontal_vertical(rms)
    assert f[0] == f[1]
    new = np.array([h, h, v]) / f
    assert new == pytest.approx(np.full(3, np.sqrt((2 * h * h + v * v) / 3)), rel=1e-12)
    assert np.mean(new ** 2) == pytest.approx(np.mean(np.array([h, h, v]) ** 2), rel=1e-12)
    with pytest.raises(ValueError, match="finite and > 0"):
        axis_scale_step([0.5, 0.5, np.nan])


def test_the_gnss_position_measurement_and_error_block_take_the_scales():
    g = GnssData(np.arange(3.0), np.tile(np.radians([40.0, -105.0]).tolist() + [1600.0], (3, 1)),
                 sigma_ned=np.tile([0.01, 0.02, 0.01], (3, 1)))
    m = GnssPosition(g, sigma_floor_m=0.015, sigma_scale_ned=(0.8, 0.8, 1.5))
    assert m.sigma[0] == pytest.approx([0.012, 0.016, 0.0225])  # floor first, then the scale
    for bad in ((1.0, 1.0), (1.0, 0.0, 1.0), (1.0, 1.0, np.inf)):
        with pytest.raises(InputError, match="sigma_scale_ned"):
            GnssPosition(g, sigma_scale_ned=bad)
    b = GnssPositionError(0.02 * np.array([0.8, 0.8, 1.5]), 10.0)
    assert b.sigma0 == pytest.approx([0.016, 0.016, 0.03])
    assert b.psd == pytest.approx(2.0 * b.sigma0 ** 2 / 10.0)
    assert GnssPositionError(0.02, 10.0).sigma0 == pytest.approx([0.02] * 3)
