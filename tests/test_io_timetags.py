"""inskit.io.timetags: a constant-rate stream whose tags a millisecond counter rounded gets its uniform grid back;
what is not such a stream (gaps, a jump of the rate, tags further than half an interval off) keeps its tags."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from inskit.io.rtklib import read_rtklibexplorer_imu
from inskit.io.timetags import regular_time_tags

DRIVE_IMU = Path(__file__).resolve().parents[1] / "data" / "drive_0708" / "imu_1934_gpst.csv.gz"


def test_rounded_tags_of_a_uniform_stream_get_their_grid_back():
    """100.0013 Hz samples stamped by an integer-millisecond counter (intervals 9, 10, 11 ms): the grid comes back
    to well below the rounding, and the rates are then integrated over 10 ms steps."""
    true = 1000.0 + np.arange(5000) * 0.0099987 + 0.00037
    tags = np.floor(true * 1000.0) / 1000.0
    assert set(np.round(np.diff(tags) * 1000).astype(int)) == {9, 10}
    reg, info = regular_time_tags(tags)
    assert info["regular_fraction"] == 1.0 and info["parts"] == 1
    # the rounding (floor) makes the tags 0.5 ms early on average: the grid keeps that mean, removes the scatter
    np.testing.assert_allclose(reg - true, -0.0005, atol=2e-5)
    np.testing.assert_allclose(np.diff(reg), 0.0099987, rtol=1e-6)


def test_uniform_tags_stay_as_they_are_and_gaps_break_the_grid():
    t = np.r_[np.arange(200) * 0.01, 10.0 + np.arange(300) * 0.01]
    reg, info = regular_time_tags(t)
    np.testing.assert_allclose(reg, t, rtol=0, atol=1e-12)
    assert info["parts"] == 2 and info["max_shift_s"] < 1e-12


def test_a_stream_that_is_not_uniform_keeps_its_tags():
    """Tags scattered by more than half an interval (samples taken when the logger got to them) keep their
    logged values: a grid would move samples across their neighbours' intervals."""
    rng = np.random.default_rng(1)
    t = np.cumsum(rng.uniform(0.002, 0.018, 400))
    reg, info = regular_time_tags(t)
    np.testing.assert_array_equal(reg, t)
    assert info["regular_fraction"] == 0.0
    assert np.all(np.diff(reg) > 0)


def test_a_drifting_rate_is_followed_piecewise():
    """A rate that changes by 1 % half-way: each half gets its own grid, every tag within half an interval."""
    t = np.r_[np.arange(1000) * 0.01, 10.0 + np.arange(1000) * 0.0101]
    tags = np.floor(t * 1000.0) / 1000.0
    reg, info = regular_time_tags(tags)
    assert info["regular_fraction"] == 1.0 and info["parts"] >= 2
    assert np.max(np.abs(reg - tags)) < 0.005
    assert np.all(np.diff(reg) > 0)


def test_the_drive_log_is_one_uniform_stream():
    """data/drive_0708: the tags come from counter_ms; every one lies within 1.5 ms of one 100.0 Hz grid, and the
    reader integrates the same rates over it (time_tags = "regular")."""
    t = pd.read_csv(DRIVE_IMU).gps_sow_s.to_numpy()
    reg, info = regular_time_tags(t)
    assert info["regular_fraction"] == 1.0 and info["parts"] == 1
    assert info["max_shift_s"] < 0.0016
    assert np.ptp(np.diff(reg)) < 1e-9 and np.mean(np.diff(reg)) == pytest.approx(0.01, rel=1e-4)
    a, _ = read_rtklibexplorer_imu(DRIVE_IMU)
    b, _ = read_rtklibexplorer_imu(DRIVE_IMU, regular_time=True)
    np.testing.assert_allclose(b.time, reg, rtol=0, atol=1e-9)
    wa, fa = a.rates()
    wb, fb = b.rates()
    np.testing.assert_allclose(wb[1:], wa[1:], rtol=1e-9, atol=1e-12)  # the same rates, other intervals
    np.testing.assert_allclose(fb[1:], fa[1:], rtol=1e-9, atol=1e-12)
