"""Smoothing a logger's jittery IMU time tags (:mod:`inskit.io.time_tags`)."""

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.io import csv_formats as C
from inskit.io.time_tags import interval_jitter, smooth_time_tags
from inskit.types import ImuData

T = 0.010  # the sensor's own sampling interval [s]


def _polled(n, seed=3, t0=1000.0):
    """A sensor sampling every ``T`` on its own clock and a logger that reads
    each sample up to 1.5 ms late and stamps the read with a millisecond
    counter: ``(tau, tags)``, the true sample times and the logged ones."""
    rng = np.random.default_rng(seed)
    tau = t0 + T * np.arange(n)
    late = rng.uniform(0.0, 1.5e-3, n)
    tags = np.floor((tau + late) * 1e3) / 1e3
    return tau, tags


def _ringing(tau, amp=np.radians(50.0), f=33.0):
    """Samples of a pitch rate ringing at 33 Hz (three samples a period, as
    across drive_0708's bumps) under a bump's envelope (zero at both ends of
    the log), each the mean of the rate over the interval before it, and the
    true angle over the whole log."""
    fine = np.linspace(tau[0], tau[-1], 200 * (len(tau) - 1) + 1)  # 50 us steps: trapezoid error ~1e-9 rad
    env = np.sin(np.pi * (fine - tau[0]) / (tau[-1] - tau[0])) ** 2
    om = amp * env * np.sin(2 * np.pi * f * fine)
    ang = np.r_[0.0, np.cumsum(0.5 * (om[1:] + om[:-1]) * np.diff(fine))]
    at = np.interp(tau, fine, ang)
    rate = np.zeros(len(tau))
    rate[1:] = np.diff(at) / np.diff(tau)
    return rate, at[-1] - at[0]


def _angle(t, rate):
    w = np.zeros((len(t), 3))
    w[:, 1] = rate
    imu = ImuData.from_rates(t, w, np.zeros((len(t), 3)), sampled="average")
    return imu.dtheta_b[:, 1].sum()


def test_smoothed_tags_take_out_the_attitude_error_the_jitter_leaves_across_a_bump():
    logged, smoothed = [], []
    for seed in range(20):  # one second of ringing, twenty draws of the logger's jitter
        tau, tags = _polled(101, seed=seed)
        rate, truth = _ringing(tau)
        assert abs(_angle(tau, rate) - truth) < 1e-7  # on the sensor's own clock the samples integrate exactly
        logged.append(_angle(tags, rate) - truth)
        smoothed.append(_angle(smooth_time_tags("imu.csv", tags, 11), rate) - truth)
    assert interval_jitter(tags)[0] > 0.3  # intervals of 9, 10, 11 ms of a nominal 10: many are off by >5 %
    rms_logged, rms_smoothed = (np.degrees(np.sqrt(np.mean(np.square(e)))) for e in (logged, smoothed))
    # with the tags as logged a sample weighs up to 20 % wrong: the angle is off by a tenth of a degree or more
    # (0.5 deg of pitch: 8.5 mg of gravity leak, metres in a 15 s outage); smoothed, each weighs about 10 ms
    assert rms_logged > 0.1
    assert rms_smoothed < rms_logged / 4


def test_a_steady_clock_is_left_as_it_is_and_the_mean_time_is_kept():
    t = 5.0 + 0.01 * np.arange(500)
    assert np.allclose(smooth_time_tags("imu.csv", t, 21), t, rtol=0, atol=1e-9)
    _, tags = _polled(2000)
    info = {}
    out = smooth_time_tags("imu.csv", tags, 11, info=info)
    moved = out - tags
    assert abs(moved.mean()) < 2e-5  # the IMU-to-GNSS alignment (time_offset_s) unchanged
    assert 0 < info["time_tags_moved_rms_s"] < 1e-3 and info["time_tags_moved_max_s"] < 1.5e-3
    assert info["time_smoothing_samples"] == 11
    # the smoothed tags sit on the sensor's clock: their intervals within 0.3 ms of its 10 ms (logged: +-1 ms)
    assert np.ptp(np.diff(out)[20:-20]) < 3e-4 < np.ptp(np.diff(tags))


def test_a_gap_ends_a_stretch_and_is_not_smeared():
    _, a = _polled(300, seed=1)
    _, b = _polled(300, seed=2, t0=a[-1] + 2.0)  # two seconds without data
    tags = np.r_[a, b]
    out = smooth_time_tags("imu.csv", tags, 11)
    gap_logged, gap_out = b[0] - a[-1], out[300] - out[299]
    assert abs(gap_out - gap_logged) < 2e-3
    assert np.all(np.abs(out - tags) < 1.5e-3)
    short = np.r_[a, a[-1] + 1.0 + 0.01 * np.arange(5)]  # a stretch shorter than the window keeps its tags
    assert np.array_equal(smooth_time_tags("imu.csv", short, 11)[-5:], short[-5:])


@pytest.mark.parametrize("bad", [0, 2, 10, -3, 1.5, True, "11"])
def test_a_window_that_is_no_odd_count_of_rows_is_refused(bad):
    with pytest.raises(InputError, match="time_smoothing_samples"):
        smooth_time_tags("imu.csv", 0.01 * np.arange(50), bad)


def test_the_rate_reader_smooths_and_an_increment_file_refuses(tmp_path):
    _, tags = _polled(400)
    tags -= tags[0]
    rows = "\n".join(f"{t:.3f},0.001,0.002,0.003,0.1,0.2,9.8" for t in tags)
    p = tmp_path / "rates.csv"
    p.write_text("time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n" + rows + "\n")
    info = {}
    imu = C.read_imu(p, time_smoothing=11, info=info)
    assert np.allclose(imu.time, smooth_time_tags(p, tags, 11), atol=1e-12)
    assert info["time_tag_jitter_fraction"] > 0.3 and info["time_tags_moved_rms_s"] > 0
    q = tmp_path / "inc.csv"
    q.write_text("time_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_m_s,dv_y_m_s,dv_z_m_s\n0,0,0,0,0,0,0\n"
                 "0.01,1e-5,0,0,0,0,-0.098\n0.02,1e-5,0,0,0,0,-0.098\n")
    with pytest.raises(InputError, match="time_smoothing_samples = 11 applies to rate files"):
        C.read_imu(q, time_smoothing=11)


@pytest.mark.parametrize("n, w", [(11, 11), (12, 11), (500, 11), (20000, 21), (37, 5)])
def test_the_local_line_is_scipys_order_one_savitzky_golay(n, w):
    from scipy.signal import savgol_filter

    from inskit.io.time_tags import _local_line

    x = np.cumsum(0.01 + np.random.default_rng(n).uniform(-1e-3, 1e-3, n))
    assert np.allclose(_local_line(x, w), savgol_filter(x, w, 1, mode="interp"), rtol=0, atol=1e-12)


def _two_rates(seed=0):
    """30 s at 100 Hz, then 30 s at 200 Hz with no gap between (row 3000 is
    the first 200 Hz sample), read by the logger of :func:`_polled`."""
    tau = np.r_[1000.0 + 0.010 * np.arange(3000), 1030.0 + 0.005 * np.arange(6000)]
    late = np.random.default_rng(seed).uniform(0.0, 1.5e-3, len(tau))
    return tau, np.floor((tau + late) * 1e3) / 1e3


@pytest.mark.parametrize("seed", range(5))
def test_a_rate_change_splits_the_stretch_and_the_tags_are_not_bent_across_it(seed):
    from inskit.io.time_tags import _local_line

    tau, tags = _two_rates(seed)
    info = {}
    out = smooth_time_tags("imu.csv", tags, 11, info=info)
    err, logged = out - tau, tags - tau
    # against the sensor's times the smoothed tags err by no more than the logged ones (their read jitter and
    # millisecond counter: -1 .. +1.5 ms, 0.67 ms from their mean at most), the mean lateness aside
    assert np.max(np.abs(err - err.mean())) <= np.max(np.abs(logged - logged.mean())) + 1e-9
    # one line through both rates bends the tags across the change by dT h (h + 1) / (2 N) = 6.8 ms
    bent = tags[0] + _local_line(tags - tags[0], 11) - tau
    assert np.max(np.abs(bent - bent.mean())) > 6e-3
    (change,) = info["time_tag_rate_changes"]
    assert change["row"] in (3000, 3001)  # row 3000 lies on both lines
    assert change["rate_before_hz"] == pytest.approx(100.0, rel=1e-3)
    assert change["rate_after_hz"] == pytest.approx(200.0, rel=2e-3)
    assert info["time_tags_beyond_jitter"] == []


def test_the_split_row_is_the_change_and_one_rate_is_not_split():
    from inskit.io.time_tags import rate_change_rows, split_row

    tau, tags = _two_rates()
    rows, before, after = rate_change_rows(tags)
    assert len(rows) == 1 and abs(rows[0] - 3000) <= 64  # the detection sees it within its block
    assert before[0] == pytest.approx(0.010) and after[0] == pytest.approx(0.005)
    k, dt_a, dt_b = split_row(tau, 2900, 3100)
    assert k in (3000, 3001) and dt_a == pytest.approx(0.010) and dt_b == pytest.approx(0.005)
    assert split_row(tags, 100, 356) is None  # one rate in the window
    assert split_row(tags, 100, 105) is None  # too few rows


def _drifting(n=6000, seed=1):
    """A sensor clock whose interval drifts from 10 to 10.3 ms over a minute
    (3 %: an RC oscillator warming), read by the logger of :func:`_polled`."""
    i = np.arange(n)
    tau = 500.0 + 0.010 * i + 0.5 * 5e-8 * i**2
    return tau, np.floor((tau + np.random.default_rng(seed).uniform(0.0, 1.5e-3, n)) * 1e3) / 1e3


def test_a_window_too_long_for_a_drifting_clock_is_named_and_a_short_one_is_not():
    from inskit.io.time_tags import MOVED_MAX_FACTOR, MOVED_RMS_FACTOR

    tau, tags = _drifting()
    info = {}
    out = smooth_time_tags("imu.csv", tags, 11, info=info)
    assert info["time_tags_beyond_jitter"] == [] and np.ptp(out - tau) < 1.5e-3
    assert 0.4e-3 < info["time_tag_jitter_s"] < 0.6e-3  # uniform lateness over 1.5 ms and the counter: 0.53 ms
    info = {}
    out = smooth_time_tags("imu.csv", tags, 1001, info=info)  # 10 s: the line cannot follow the drift
    assert np.ptp(out - tau) > 5e-3
    found = {b["key"]: b for b in info["time_tags_beyond_jitter"]}
    assert set(found) == {"time_tags_moved_net_rms_s", "time_tags_moved_net_max_s"}
    s = info["time_tag_jitter_s"]
    assert found["time_tags_moved_net_rms_s"]["limit_s"] == pytest.approx(MOVED_RMS_FACTOR * s)
    assert found["time_tags_moved_net_max_s"]["value_s"] > MOVED_MAX_FACTOR * s
    worst = found["time_tags_moved_net_max_s"]
    assert worst["t_s"] == tags[worst["row"]] and worst["row"] > 5000  # the end fit, where the drift is fastest


@pytest.mark.parametrize("w", [5, 11, 101, 1001])
def test_a_steady_clock_raises_no_alarm_however_long_the_window(w):
    _, tags = _polled(20000, seed=w)
    info = {}
    smooth_time_tags("imu.csv", tags, w, info=info)
    assert info["time_tags_beyond_jitter"] == [] and info["time_tag_rate_changes"] == []
    assert info["time_tags_moved_net_rms_s"] < 1.05 * info["time_tag_jitter_s"]  # white jitter: at most s
    assert info["time_tags_left_out_spread_max_s"] < 1e-9


def test_a_clock_jump_of_whole_intervals_is_named_where_it_is():
    _, tags = _polled(3000)
    tags[1500:] += 0.030  # the logger's clock steps 30 ms (under the 50 ms that end a stretch)
    info = {}
    smooth_time_tags("imu.csv", tags, 11, info=info)
    (found,) = info["time_tags_beyond_jitter"]
    assert found["key"] == "time_tags_left_out_spread_max_s" and abs(found["row"] - 1500) <= 1
    assert found["value_s"] > 0.010 and found["limit_s"] == pytest.approx(0.005)
    one = _polled(3000)[1].copy()
    one[1500:] += 0.010  # one row left out (or a jump of one interval): spread by under half an interval
    info = {}
    smooth_time_tags("imu.csv", one, 11, info=info)
    assert info["time_tags_beyond_jitter"] == [] and 4e-3 < info["time_tags_left_out_spread_max_s"] < 5e-3
