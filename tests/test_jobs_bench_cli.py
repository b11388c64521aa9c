"""The end-to-end bench: its drives are what it says, its command figures are measured."""

from pathlib import Path

import numpy as np
import pytest

from inskit.io import read_gnss, read_imu
from inskit.jobs import bench_cli as B
from inskit.simulation.scenario import build_trajectory, load_scenario


def test_scenario_text_is_the_car_cut_at_the_duration(tmp_path):
    p = tmp_path / "car_1h.toml"
    p.write_text(B._scenario_text(3600.0))
    sc = load_scenario(p)
    car = load_scenario(B._EXAMPLES / "car.toml")
    assert len(sc.segment) == 3 * len(car.segment)
    tr = build_trajectory(sc)
    assert tr.duration == pytest.approx(3600.0)
    assert tr.t > 3600.0  # the segments were longer: cut, not stretched


def test_bench_drive_has_the_rate_and_length_asked(tmp_path):
    d = B.bench_drive(20.0, 200.0, root=tmp_path)
    imu = read_imu(d / "imu.csv")
    assert np.median(np.diff(imu.time)) == pytest.approx(1 / 200.0)
    assert imu.time[-1] - imu.time[0] == pytest.approx(20.0, abs=1 / 200.0)
    assert len(read_gnss(d / "gnss.csv")) == 21  # 1 Hz fixes, both ends
    assert (d / "navigate.toml").is_file() and (d / "done").is_file()
    assert B.bench_drive(20.0, 200.0, root=tmp_path) == d  # cached


def test_simulate_floor_times_the_imports_and_the_writes_of_the_commands_own_files(tmp_path):
    """The floor writes the tables the command wrote (same columns, same rows), and its parts add up."""
    import pyarrow.parquet as pq

    from inskit.jobs.simulate import write_simulation
    from inskit.simulation.scenario import Scenario, simulate

    sc = Scenario.model_validate({"name": "s", "start": {"lat_deg": 45.0, "lon_deg": 7.0},
                                  "segment": [{"type": "static", "duration_s": 20.0}]})
    write_simulation(simulate(sc, seed=1), tmp_path / "sim", plot=False, file_format="parquet")
    calls = []
    real = B.subprocess.run

    def spy(args, **kw):
        r = real(args, **kw)
        dst = Path(args[-1])
        calls.append({f.name: pq.read_table(f) for f in dst.glob("*.parquet")})
        return r

    B.subprocess.run = spy
    try:
        r = B.simulate_floor(tmp_path / "sim", 2000, 1)
    finally:
        B.subprocess.run = real
    assert len(calls) == 2  # a warm-up and one repeat
    for name in ("imu.parquet", "gnss.parquet", "truth.parquet"):
        assert calls[-1][name].equals(pq.read_table(tmp_path / "sim" / name))
    assert 0 < r["simulate_cli_floor_import_s"] < 30 and 0 < r["simulate_cli_floor_write_s"] < 30
    assert r["simulate_cli_floor_s"] == pytest.approx(r["simulate_cli_floor_import_s"]
                                                      + r["simulate_cli_floor_write_s"], abs=2e-3)
    assert r["simulate_cli_floor_epochs_per_s"] == pytest.approx(2000 / r["simulate_cli_floor_s"], rel=1e-2)


@pytest.mark.slow
def test_cli_figures_are_measured(tmp_path):
    r = B.cli_benchmarks(quick=True, repeats=1, root=tmp_path)
    for k in ("navigate_cli_epochs_per_s", "simulate_cli_epochs_per_s", "mechanize_cli_epochs_per_s"):
        assert r[k] > 0 and r[f"{k}_spread"][0] <= r[k] <= r[f"{k}_spread"][1]
    assert 50 < r["navigate_peak_rss_mb"] < 24000
    assert r["navigate_cli_fixes_used"] >= 100
    assert 0 < r["simulate_cli_floor_s"] < r["simulate_cli_wall_s"]  # the floor leaves the simulation out


@pytest.mark.slow
def test_long_figures_are_measured_per_length(tmp_path):
    """bench --long on short drives (the same code path): one row per length, forward and smoothed runs timed
    and their memory read; the smoothed run holds more (its store) and is not much the faster (it does the
    forward run and more: on these short drives the start-up of both dominates and a loaded machine's noise
    exceeds the difference, so the wall times are held to a factor, not to their order)."""
    res = B.long_benchmarks(hours=(0.05, 0.1), root=tmp_path)
    r = res["navigate_long"]
    per_hour = (r[1]["forward_peak_rss_mb"] - r[0]["forward_peak_rss_mb"]) / 0.05  # the slope between the two
    assert res["navigate_long_forward_rss_mb_per_hour"] == pytest.approx(per_hour, abs=0.2)
    assert [x["hours"] for x in r] == [0.05, 0.1] and r[1]["epochs"] == 72001
    for x in r:
        assert 0 < x["forward_wall_s"] < 1.5 * x["smoothed_wall_s"] and 50 < x["forward_peak_rss_mb"] < 24000
        assert x["smoothed_peak_rss_mb"] >= x["forward_peak_rss_mb"] - 20
