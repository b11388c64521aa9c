"""Issue 4 acceptance on the bundled real drive (drive_0708, outage protocol)."""

from pathlib import Path

import numpy as np
import pytest

from inskit.jobs.config import load_config
from inskit.jobs.navigate import navigate, summary

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "drive_0708.toml"


@pytest.fixture(scope="module")
def result():
    cfg = load_config(EXAMPLE, {"output": {"plots": False}})
    return navigate(cfg, smooth=True)


def test_forward_outage_end_rms_within_3_m(result):
    s = result.score_forward.summary
    assert s["outages"] == 11
    assert s["outage_end_horizontal_rms_m"] <= 3.0


def test_gnss_on_horizontal_rms_below_3_cm(result):
    assert result.score_forward.summary["gnss_on_horizontal_rms_m"] < 0.03


def test_smoother_at_least_halves_outage_errors(result):
    f, s = result.score_forward.summary, result.score_smoothed.summary
    assert s["outage_end_horizontal_rms_m"] <= 0.5 * f["outage_end_horizontal_rms_m"]
    # also the worst error anywhere inside an outage, the harder figure
    assert s["outage_worst_horizontal_rms_m"] <= 0.5 * f["outage_worst_horizontal_rms_m"]


def test_filter_is_consistent_on_real_data(result):
    nis = result.forward.innovations["gnss_pos"]["nis"]
    # 3 degrees of freedom: mean NIS 3 for a consistent filter; allow 0.3..3x
    assert 1.0 < np.mean(nis) < 9.0
    assert result.forward.counts["gnss_pos"]["rejected"] < 0.02 * result.forward.counts["gnss_pos"]["used"]


def test_summary_keys_contract(result):
    s = summary(result)
    for k in ("outage_end_horizontal_rms_m", "outage_end_horizontal_max_m", "gnss_on_horizontal_rms_m"):
        assert isinstance(s[k], float)
        assert isinstance(s["forward"][k], float)
    assert s["solution"] == "smoothed"
    assert s["states"] == 21


def test_startup_levels_the_car(result):
    rpy = np.degrees(result.startup.state.euler)
    # parked on a street: within a few degrees of level after the mount rotation
    assert abs(rpy[0]) < 5 and abs(rpy[1]) < 5
    assert 30 < result.startup.static_end - result.imu.time[0] < 40  # the ~38 s static start


def test_time_offset_state_recovers_a_wrong_offset():
    """Start 0.06 s off the calibrated offset (-0.26 s): the time-offset state
    finds the difference and the outage protocol still scores within 3 m."""
    from inskit.jobs.navigate import summary

    cfg = load_config(EXAMPLE, {"output": {"plots": False}, "imu": {"time_offset_s": -0.20},
                                "filter": {"time_offset": True}})
    s = summary(navigate(cfg))
    assert abs(s["estimated_time_offset_s"] - 0.06) < 0.02
    assert s["outage_end_horizontal_rms_m"] <= 3.0
    assert s["gnss_on_horizontal_rms_m"] < 0.03


def test_calibration_reads_the_files_once(monkeypatch):
    """The time-offset search shifts the IMU time tags of one reading."""
    from inskit.jobs import navigate as N

    calls = []
    real = N.load_inputs

    def counting(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(N, "load_inputs", counting)
    cfg = load_config(EXAMPLE, {"output": {"plots": False}})
    best, evals = N.calibrate_time_offset(cfg, bounds=(-0.4, -0.1), tol=0.05)
    assert len(calls) == 1 and len(evals) >= 3
    assert -0.4 <= best <= -0.1
