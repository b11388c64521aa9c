"""Alignment from files: simulated static logs and the real drive_0708 start."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from inskit.alignment.static import align_static
from inskit.jobs.config import load_config
from inskit.jobs.navigate import navigate
from inskit.jobs.simulate import write_simulation
from inskit.simulation.scenario import load_scenario, simulate

ROOT = Path(__file__).resolve().parents[1]
DRIVE = ROOT / "data" / "drive_0708" / "imu_1934_gpst.csv.gz"
MOUNT = np.radians([180.0, -6.79, 185.35])


@pytest.fixture(scope="module")
def static_log(tmp_path_factory):
    d = tmp_path_factory.mktemp("static")
    p = d / "s.toml"
    p.write_text('name = "s"\n[start]\nlat_deg = 45\nlon_deg = 10\nyaw_deg = 30\n[imu]\nrate_hz = 100\n'
                 'grade = "navigation"\n[[segment]]\ntype = "static"\nduration_s = 600\n')
    write_simulation(simulate(load_scenario(p), seed=4), d, plot=False)
    return d / "imu.csv"


@pytest.mark.parametrize("method", ["accel", "gyro", "blend", "fine"])
def test_navigation_grade_static_alignment(static_log, method):
    r = align_static(static_log, np.radians(45), method=method)
    # navigation grade: 25 ug -> 0.0015 deg of tilt; the gyro basis also tilts by the latitude mismatch its
    # gyro errors imply (0.003 deg/h turn-on + 0.005 deg/h of noise over 600 s: ~0.03 deg)
    tol = 0.06 if method == "gyro" else 0.01
    assert abs(r["roll_deg"]) < tol and abs(r["pitch_deg"]) < tol
    assert abs(r["yaw_deg"] - 30.0) < 0.5  # 0.003 deg/h drift -> 0.016 deg; noise over 600 s dominates
    assert r["heading_usable"]
    assert r["static_s"] > 590


def test_fine_alignment_reports_convergence(static_log):
    r = align_static(static_log, np.radians(45), method="fine")
    t = r["converge_time_s"]
    assert t[0] is not None and t[0] < 60  # tilt within a minute
    assert t[2] is not None and t[2] > t[0]  # gyrocompassing is the slow part
    assert abs(r["yaw_deg"] - 30.0) < 0.5
    # the reported sigma reflects the assumed gyro-bias class (0.2 deg/h by default), not only the data
    assert r["yaw_sigma_deg"] < 3.0


def test_drive_0708_static_start_against_the_filter():
    r = align_static(DRIVE, np.radians(40.0966), method="accel", imu_format="rtklibexplorer", mount_rpy=MOUNT)
    assert not r["heading_usable"] and "swamps the Earth rate" in r["heading_reason"]
    cfg = load_config(ROOT / "examples" / "drive_0708.toml", {"output": {"plots": False}})
    res = navigate(cfg, smooth=True)
    static = res.smoothed.nav.time < res.startup.static_end
    rpy = np.degrees(res.smoothed.nav.euler[static]).mean(axis=0)
    assert abs(r["roll_deg"] - rpy[0]) < 0.5
    assert abs(r["pitch_deg"] - rpy[1]) < 0.5


def test_cli_align_json_keys():
    r = subprocess.run([sys.executable, "-m", "inskit.cli", "align", str(DRIVE), "--lat", "40.0966",
                        "--imu-format", "rtklibexplorer", "--mount-rpy", "180,-6.79,185.35", "--method", "accel",
                        "--json"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    for k in ("roll_deg", "pitch_deg", "yaw_deg", "roll_sigma_deg", "pitch_sigma_deg", "yaw_sigma_deg"):
        assert isinstance(d[k], float)
    r = subprocess.run([sys.executable, "-m", "inskit.cli", "align", str(DRIVE), "--lat", "95"], capture_output=True,
                       text=True)
    assert r.returncode == 2 and "--lat" in r.stderr
