"""The CLI turns every bad input into one line on stderr and a non-zero exit."""

import json
import subprocess
import sys

import numpy as np
import pytest

from inskit import io
from inskit.simulation import StationaryTrajectory, ideal_imu, truth_solution


def inskit(*args):
    return subprocess.run([sys.executable, "-m", "inskit.cli", *map(str, args)], capture_output=True, text=True)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli")
    traj = StationaryTrajectory((np.radians(45), 0.1, 50.0), (0.0, 0.0, 0.5))
    t = np.arange(0.0, 60.0, 0.01)
    io.write_imu(d / "imu.csv", ideal_imu(traj, t, nodes=1))
    io.write_solution(d / "truth.csv", truth_solution(traj, t))
    return d


def test_version():
    r = inskit("--version")
    assert r.returncode == 0 and "inskit" in r.stdout


def test_mechanize_and_evaluate_json(files, tmp_path):
    out = tmp_path / "sol.csv"
    r = inskit("mechanize", files / "imu.csv", "--init-from", files / "truth.csv", "--height", "hold",
               "--out", out, "--json")
    assert r.returncode == 0, r.stderr
    summary = json.loads(r.stdout)  # exactly one JSON object on stdout
    assert summary["epochs"] == 6000
    r = inskit("evaluate", out, files / "truth.csv", "--json", "--plot", tmp_path / "e.png")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["horizontal_m"]["max"] < 1e-3  # ideal data, 1 min
    assert (tmp_path / "e.png").exists()
    # the table form
    r = inskit("evaluate", out, files / "truth.csv")
    assert "horizontal_m" in r.stdout


BAD = {
    "missing_column": ("time_s,gyro_x_deg_s\n0,1\n1,2\n", "no complete set of IMU columns"),
    "nan": ("time_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_m_s,dv_y_m_s,dv_z_m_s\n"
            "0,0,0,0,0,0,-0.098\n0.01,0,,0,0,0,-0.098\n", "line 3: column 'dtheta_y_rad' is empty"),
    "duplicate": ("time_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_m_s,dv_y_m_s,dv_z_m_s\n"
                  "0,0,0,0,0,0,-0.098\n0,0,0,0,0,0,-0.098\n", "line 3: duplicate timestamp"),
    "backwards": ("time_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_m_s,dv_y_m_s,dv_z_m_s\n"
                  "1,0,0,0,0,0,-0.098\n0.5,0,0,0,0,0,-0.098\n", "goes back in time"),
    "no_initial_row": ("time_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_m_s,dv_y_m_s,dv_z_m_s\n"
                       "0.01,0,0,0,0,0,-0.098\n0.02,0,0,0,0,0,-0.098\n",
                       "line 2 (the first data row) holds increments (dv_z_m_s=-0.098)"),
    "g_as_ms2": ("time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n"
                 "0,0,0,0,0,0,-1\n0.01,0,0,0,0,0,-1\n", "looks like values in g"),
    "deg_as_rad": ("time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n"
                   "0,25,0,0,0,0,-9.8\n0.01,25,0,0,0,0,-9.8\n", "looks like values in deg/s"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_imu_gives_one_line(case, tmp_path):
    text, expected = BAD[case]
    p = tmp_path / "bad.csv"
    p.write_text(text)
    r = inskit("mechanize", p, "--init", "45,0,0,0,0,0,0,0,0")
    assert r.returncode == 2
    assert r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("inskit: error: ") and "bad.csv" in lines[0] and expected in lines[0]
    assert "Traceback" not in r.stderr


def test_first_row_option(tmp_path):
    """--first-row increment: the first row's increments are real, an initial epoch 0.01 s earlier is prepended
    and the --init state is taken there (mechanize starts at the first IMU time)."""
    p = tmp_path / "inc.csv"
    p.write_text(BAD["no_initial_row"][0])
    r = inskit("mechanize", p, "--init", "45,0,0,0,0,0,0,0,0", "--first-row", "increment", "--json")
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["duration_s"] == pytest.approx(0.02)
    r = inskit("mechanize", p, "--init", "45,0,0,0,0,0,0,0,0", "--first-row", "discard", "--json")
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["duration_s"] == pytest.approx(0.01)


def test_bad_init_and_overwrite(files, tmp_path):
    r = inskit("mechanize", files / "imu.csv", "--init", "45,0,0")
    assert r.returncode == 2 and "9 comma-separated numbers" in r.stderr
    r = inskit("mechanize", files / "imu.csv", "--init", "95,0,0,0,0,0,0,0,0")
    assert r.returncode == 2 and "latitude" in r.stderr
    out = tmp_path / "keep.csv"
    out.write_text("precious\n")
    r = inskit("mechanize", files / "imu.csv", "--init", "45,0,0,0,0,0,0,0,0", "--out", out)
    assert r.returncode == 2 and "refusing to overwrite" in r.stderr
    assert out.read_text() == "precious\n"


def test_evaluate_mismatched_time_bases(files, tmp_path):
    sol = io.read_solution(files / "truth.csv")
    shifted = type(sol)(sol.time + 1e5, sol.lla, sol.v_n, sol.q_nb)
    io.write_solution(tmp_path / "late.csv", shifted)
    r = inskit("evaluate", tmp_path / "late.csv", files / "truth.csv")
    assert r.returncode == 2 and "do not overlap" in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_simulate_and_allan_json(tmp_path):
    scen = tmp_path / "s.toml"
    scen.write_text('name = "still"\n[start]\nlat_deg = 45\nlon_deg = 7\n[imu]\nrate_hz = 100\ngrade = "tactical"\n'
                    '[[segment]]\ntype = "static"\nduration_s = 120\n')
    r = inskit("simulate", scen, "--out", tmp_path / "o", "--seed", 3, "--json", "--no-plot")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["imu_epochs"] == 12001 and s["seed"] == 3
    r = inskit("simulate", scen, "--out", tmp_path / "o")
    assert r.returncode == 2 and "refusing to overwrite" in r.stderr
    r = inskit("allan", tmp_path / "o" / "imu.csv", "--json", "--plot", tmp_path / "a.png")
    assert r.returncode == 0, r.stderr
    a = json.loads(r.stdout)
    # tactical preset: ARW 0.125 deg/sqrt(h); two minutes of data pin the white noise within 15 %
    assert abs(a["navigate_noise_section"]["gyro_arw_deg_sqrt_h"] / 0.125 - 1) < 0.15
    assert (tmp_path / "a.png").exists()


def test_simulate_navigate_evaluate_pipeline(tmp_path):
    """The user path on simulated data: scenario -> files -> navigate (flags only) -> evaluate vs truth."""
    scen = tmp_path / "drive.toml"
    scen.write_text(
        'name = "drive"\n[start]\nlat_deg = 45\nlon_deg = 7\nheight_m = 300\n'
        '[imu]\nrate_hz = 100\ngrade = "industrial-mems"\n'
        '[gnss]\nrate_hz = 1\nwhite_h_m = 0.5\nwhite_v_m = 1.0\nvelocity_sigma_m_s = 0.05\nlever_arm_b_m = [0, 0, -1]\n'
        '[[segment]]\ntype = "static"\nduration_s = 30\n'
        '[[segment]]\ntype = "accelerate"\nspeed_m_s = 12\nduration_s = 10\n'
        '[[segment]]\ntype = "turn"\nangle_deg = 90\nradius_m = 30\n'
        '[[segment]]\ntype = "cruise"\nduration_s = 40\n'
        '[[segment]]\ntype = "turn"\nangle_deg = -120\nradius_m = 25\n'
        '[[segment]]\ntype = "cruise"\nduration_s = 40\n')
    assert inskit("simulate", scen, "--out", tmp_path / "sim", "--no-plot").returncode == 0
    r = inskit("navigate", "--imu", tmp_path / "sim" / "imu.csv", "--gnss", tmp_path / "sim" / "gnss.csv",
               "--lever-arm", "0,0,-1", "--out", tmp_path / "nav", "--no-plots", "--json", "--smooth",
               "--truth", tmp_path / "sim" / "truth.csv")
    assert r.returncode == 0, r.stderr
    t = json.loads(r.stdout)["truth_errors"]
    # the smoother uses the future too: no worse than the forward filter against the truth
    assert t["smoothed"]["horizontal_m"]["rms"] <= t["forward"]["horizontal_m"]["rms"] * 1.05
    r = inskit("evaluate", tmp_path / "nav" / "solution_forward.csv", tmp_path / "sim" / "truth.csv", "--json")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["horizontal_m"]["rms"] < 1.0  # 0.5 m white GNSS noise, filtered
    assert abs(s["roll_arcmin"]["final"]) < 30 and abs(s["pitch_arcmin"]["final"]) < 30
