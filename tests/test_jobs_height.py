"""[height] in inskit navigate: a barometer log fused with its offset state
keeps the height through a GNSS outage; a constant height and the readers'
rules; the profile of ``inskit mechanize --height-ref FILE``."""

import warnings

import numpy as np
import pytest

from inskit import analysis, io
from inskit.errors import InputError
from inskit.files import write_csv
from inskit.jobs.config import config_from_dict
from inskit.jobs.height import height_profile_at, height_series
from inskit.jobs.navigate import navigate, summary
from inskit.types import ImuData

#: a 3-minute drive with a climb and a descent, GNSS withheld from 100 to 190 s.  The IMU is the
#: industrial-MEMS preset with a worse accelerometer bias instability (500 ug, 100 s), so that the
#: free vertical channel drifts by metres in the outage
SCENARIO = """
name = "baro_drive"
[start]
lat_deg = 45.0
lon_deg = 7.0
height_m = 300.0
yaw_deg = 10.0
transition_s = 2.0
[imu]
rate_hz = 100.0
grade = "industrial-mems"
[imu.accel]
bias_instability = 500.0
bias_instability_tau_s = 100.0
[gnss]
rate_hz = 1.0
white_h_m = 0.5
white_v_m = 1.0
velocity_sigma_m_s = 0.05
outages_s = [[100.0, 190.0]]
[[segment]]
type = "static"
duration_s = 20.0
[[segment]]
type = "accelerate"
speed_m_s = 15.0
duration_s = 10.0
[[segment]]
type = "cruise"
duration_s = 30.0
[[segment]]
type = "turn"
angle_deg = 90.0
radius_m = 40.0
[[segment]]
type = "climb"
angle_deg = 3.0
duration_s = 30.0
[[segment]]
type = "cruise"
duration_s = 30.0
[[segment]]
type = "turn"
angle_deg = -90.0
radius_m = 40.0
[[segment]]
type = "descend"
angle_deg = 2.0
duration_s = 30.0
[[segment]]
type = "cruise"
duration_s = 30.0
"""
OUTAGE = (100.0, 190.0)
BARO_SIGMA_M = 0.5
BARO_BIAS_M = 12.0
BARO_RW_M_SQRT_S = 0.02  # 1.2 m/sqrt(h)

#: the filter matched to the simulated IMU (ADIS16495-1 figures, the worse accelerometer in-run bias).  The
#: non-holonomic constraint is off: it ties the vertical velocity to the pitch and would hide the vertical
#: channel's drift, the drift a barometer is for (an aircraft, a pedestrian, a vehicle of unknown mounting)
NAVIGATE = {
    "name": "baro", "imu": {"file": "imu.csv"}, "gnss": {"file": "gnss.csv"},
    "noise": {"gyro_arw_deg_sqrt_h": 0.09, "accel_vrw_m_s_sqrt_h": 0.008, "gyro_bias_sigma_deg_h": 1.0,
              "gyro_bias_tau_s": 600.0, "accel_bias_sigma_ug": 540.0, "accel_bias_tau_s": 100.0,
              "gyro_turn_on_bias_deg_h": 200.0, "accel_turn_on_bias_mg": 1.0, "from_static": False},
    "init": {"sigma_pos_m": 1.0, "sigma_scale_factor": 0.01},
    "constraints": {"nhc": False},
    "output": {"plots": False},
}


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    from inskit.jobs.simulate import write_simulation
    from inskit.simulation.barometer import simulate_barometer
    from inskit.simulation.scenario import load_scenario, simulate

    d = tmp_path_factory.mktemp("baro")
    (d / "drive.toml").write_text(SCENARIO)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        write_simulation(simulate(load_scenario(d / "drive.toml"), seed=2), d, plot=False)
    truth = io.read_solution(d / "truth.csv")
    baro = simulate_barometer(truth, rate_hz=1.0, bias_m=BARO_BIAS_M, bias_rw_m_sqrt_s=BARO_RW_M_SQRT_S,
                              noise_m=BARO_SIGMA_M, rng=np.random.default_rng(12))
    write_csv(d / "baro.csv", {"time_s": baro.time, "height_m": baro.height_m})
    runs = {}
    for name, extra in (("without", {}), ("with", {"height": {"file": "baro.csv", "sigma_m": BARO_SIGMA_M,
                                                              "bias_rw_m_sqrt_h": BARO_RW_M_SQRT_S * 60.0}})):
        res = navigate(config_from_dict({**NAVIGATE, **extra}, base_dir=d, source=name))
        err = analysis.nav_error(res.forward.nav, truth)
        m = (err.time >= OUTAGE[0]) & (err.time <= OUTAGE[1])
        runs[name] = (res, err.pos_ned[m, 2])
    return runs, baro


def test_barometer_holds_the_height_through_the_outage(drive):
    """Without height aiding the vertical error grows to metres in the 90 s
    outage (24.5 m here); with the barometer its RMS stays within two
    barometer sigmas (0.22 m here: the filter averages the 1 Hz readings, and
    the offset is known from the GNSS-on minute to 0.15 m) and its worst is
    below a third of the free channel's."""
    runs, _ = drive
    free, aided = np.abs(runs["without"][1]), np.abs(runs["with"][1])
    assert free.max() > 5.0
    assert np.sqrt(np.mean(aided**2)) < 2.0 * BARO_SIGMA_M
    assert aided.max() < 0.3 * free.max()


def test_barometer_offset_is_estimated_within_its_sigma(drive):
    """The offset (12 m plus a 1.2 m/sqrt(h) random walk) is observable while
    the GNSS heights are there: at the outage start the estimate is within 3
    of its sigmas of the truth, that sigma below 0.3 m (the GNSS's 1 m
    vertical noise and the barometer's 0.5 m over ~100 s of fixes:
    sqrt((1 + 0.25) / 100) = 0.11 m, plus the walk); inside the outage the
    estimate holds and its sigma grows by the walk, still covering the truth.
    The updates are consistent: mean NIS of one degree of freedom in
    0.7..1.3 (5 of its sigmas, sqrt(2 / 190) = 0.1, from 1)."""
    runs, baro = drive
    res = runs["with"][0]
    t = res.forward.nav.time
    b, s = res.forward.estimate("height_bias")[:, 0], res.forward.sigma_of("height_bias")[:, 0]
    truth_b = np.interp(t, baro.time, baro.bias_m)
    for at in (OUTAGE[0] - 1.0, OUTAGE[1] - 1.0):
        k = int(np.searchsorted(t, at))
        assert abs(b[k] - truth_b[k]) < 3.0 * s[k] and s[k] < 0.3, (at, b[k], truth_b[k], s[k])
    k0, k1 = np.searchsorted(t, OUTAGE)
    assert s[k1 - 1] > s[k0]  # no GNSS: the walk grows the sigma
    h = summary(res)["health"]["measurements"]["height"]
    assert h["updates"] >= 190 and h["rejected_fraction"] == 0.0 and 0.7 < h["mean_nis"] < 1.3, h
    assert "height_bias" in summary(res)["final_estimates"]


# --- the readers' rules ---------------------------------------------------------------------
def _imu(t0=0.0, t1=20.0):
    t = np.arange(t0, t1, 0.01)
    return ImuData(t, np.zeros((len(t), 3)), np.zeros((len(t), 3)))


def _cfg(tmp_path, **height):
    return config_from_dict({"imu": {"file": "imu.csv"}, "gnss": {"file": "gnss.csv"}, "height": height},
                            base_dir=tmp_path, source="c.toml")


def test_height_series_thins_shifts_and_offsets(tmp_path):
    t = np.arange(0.0, 10.0, 0.1)  # a 10 Hz barometer
    write_csv(tmp_path / "b.csv", {"time_s": t, "height_m": 100.0 + t})
    tt, z, s = height_series(_cfg(tmp_path, file="b.csv", rate_hz=2.0, time_offset_s=0.05, offset_m=-47.0,
                                  sigma_m=0.8), _imu())
    assert np.allclose(np.diff(tt), 0.5) and tt[0] == pytest.approx(0.05)
    assert np.allclose(z, 100.0 + tt - 0.05 - 47.0) and np.all(s == 0.8)
    tc, zc, sc = height_series(_cfg(tmp_path, height_m=0.0, rate_hz=0.5, estimate_bias=False), _imu(5.0, 25.0))
    assert tc[0] == 5.0 and np.allclose(np.diff(tc), 2.0) and np.all(zc == 0.0) and np.all(sc == 1.0)


def test_height_series_refuses_a_log_off_the_imu_and_a_doubled_sigma(tmp_path):
    write_csv(tmp_path / "late.csv", {"time_s": [500.0, 501.0], "height_m": [1.0, 2.0]})
    with pytest.raises(InputError, match=r"late\.csv: height times 500\.000\.\.501\.000 s do not overlap"):
        height_series(_cfg(tmp_path, file="late.csv"), _imu())
    write_csv(tmp_path / "s.csv", {"time_s": [0.0, 1.0], "height_m": [1.0, 2.0], "sigma_m": [0.3, 0.3]})
    with pytest.raises(InputError, match=r"s\.csv: the file has a sigma_m column, so height\.sigma_m = 2 would "
                                         r"be ignored"):
        height_series(_cfg(tmp_path, file="s.csv", sigma_m=2.0), _imu())
    assert np.all(height_series(_cfg(tmp_path, file="s.csv"), _imu())[2] == 0.3)


def test_a_barometer_in_feet_is_refused_against_the_fixes_heights():
    """A barometer logged in feet went ahead: the filter refused its non-holonomic constraint as 'not holding'
    and ended 253 km off.  Its heights change 3.28 times as much as the fixes': refused; an offset of 30 m (the
    bias state's) is not."""
    from inskit.jobs.height import check_height_scale
    from inskit.types import GnssData

    t = np.arange(0.0, 300.0, 1.0)
    h = 1600.0 + 20.0 * np.sin(t / 50.0)
    gnss = GnssData(t, np.column_stack([np.full(len(t), 0.7), np.full(len(t), 0.1), h]), np.full((len(t), 3), 0.5))
    check_height_scale("baro.csv", t, h + 30.0, gnss)
    with pytest.raises(InputError, match=r"baro\.csv: its heights change 3\.28 times as much as the GNSS fixes' "
                                         r"heights .*feet read as metres"):
        check_height_scale("baro.csv", t, h * 3.2808, gnss)
    check_height_scale("flat.csv", t, np.full(len(t), 5000.0), GnssData(t, np.column_stack(
        [np.full(len(t), 0.7), np.full(len(t), 0.1), np.full(len(t), 1600.0)]), np.full((len(t), 3), 0.5)))


def test_profile_for_mechanize_is_interpolated_and_held_at_its_ends(tmp_path):
    write_csv(tmp_path / "p.csv", {"time_s": [2.0, 4.0], "height_m": [10.0, 30.0]})
    said = []
    h = height_profile_at(tmp_path / "p.csv", np.array([0.0, 3.0, 3.5, 6.0]), log=said.append)
    assert h.tolist() == [10.0, 20.0, 25.0, 30.0]
    assert said and "held over 4.000 s" in said[0]
    with pytest.raises(InputError, match="do not overlap"):
        height_profile_at(tmp_path / "p.csv", np.array([10.0, 11.0]))


def test_a_height_log_with_its_time_in_milliseconds_is_refused(tmp_path):
    """A barometer log with time_s in ms (0..300000 beside a 300 s IMU log) overlapped the IMU by its first
    readings and went in, all but three of its heights outside the run; the odometer's rule now holds for it."""
    from inskit.types import ImuData

    ti = np.arange(0.0, 300.0 + 1e-9, 0.01)
    imu = ImuData(ti, np.zeros((len(ti), 3)), np.zeros((len(ti), 3)))
    th = np.arange(0.0, 300.0 + 1e-9, 1.0)
    (tmp_path / "h.csv").write_text("time_s,height_m\n" + "".join(f"{1000.0 * float(x)!r},100.0\n" for x in th))
    cfg = config_from_dict({"imu": {"file": "imu.csv"}, "gnss": {"file": "g.csv"}, "height": {"file": "h.csv"}},
                           base_dir=tmp_path)
    with pytest.raises(InputError, match=r"^h\.csv: height times step by 1000 s \(median\) and span 300000 s, 1000 "
                                         r"times the IMU log's 300 s: is its time column in milliseconds"):
        height_series(cfg, imu)
