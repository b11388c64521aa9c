"""The CLI turns every bad input into one line on stderr and a non-zero exit."""

import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

from inskit import io
from inskit.simulation import StationaryTrajectory, ideal_imu, truth_solution
from cli_runner import in_process as _in_process


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
    assert r.returncode == 2 and "--init: expected 9 finite comma-separated numbers" in r.stderr
    r = inskit("mechanize", files / "imu.csv", "--init", "95,0,0,0,0,0,0,0,0")
    assert r.returncode == 2 and "--init: latitude must be within" in r.stderr  # said of the option
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


def test_mechanize_height_ref_takes_a_number_or_a_height_log(files, tmp_path, capsys):
    """--height-ref 50 and a log holding 50 m throughout aid the height channel
    the same way; a log that is neither a number nor a file is one error line.
    (In-process, through the entry point: four runs in a subprocess each would
    cost seconds of start-up.)"""
    def run(*args):
        return _in_process(capsys, *args)

    t = np.arange(-1.0, 61.0, 1.0)
    (tmp_path / "h.csv").write_text("time_s,height_m\n" + "".join(f"{x},50.0\n" for x in t))
    base = ("mechanize", files / "imu.csv", "--init-from", files / "truth.csv")
    ends = []
    for ref in ("50", tmp_path / "h.csv"):
        code, out, err = run(*base, "--height", "aid", "--height-ref", ref, "--json")
        assert code == 0, err
        ends.append(json.loads(out)["final"]["height_m"])
    assert ends[0] == ends[1]
    code, _, err = run(*base, "--height", "aid", "--height-ref", tmp_path / "nosuch.csv")
    assert code == 2 and "neither a height in metres nor a height log (no such file)" in err
    assert len(err.strip().splitlines()) == 1
    code, _, err = run(*base, "--height", "aid", "--height-ref", tmp_path)  # a folder was called 'no such file'
    assert code == 2 and "neither a height in metres nor a height log (a folder)" in err
    code, _, err = run(*base, "--height-ref", "50")
    assert code == 2 and "--height-ref would be ignored with --height free" in err


def test_mechanize_warnings_are_in_its_json_too(files, tmp_path, capsys):
    """`mechanize --height aid --height-ref h.csv --json` with a height log covering 10 of the IMU's 60 s
    warned on stderr that its last height is held over 50 s, and the JSON (what a script reads) had no
    warnings at all; now its ``warnings`` holds the same lines (empty when there is nothing to say)."""
    (tmp_path / "h.csv").write_text("time_s,height_m\n" + "".join(f"{x},50.0\n" for x in range(11)))
    base = ("mechanize", files / "imu.csv", "--init-from", files / "truth.csv", "--json")
    code, out, err = _in_process(capsys, *base, "--height", "aid", "--height-ref", tmp_path / "h.csv")
    assert code == 0, err
    w = json.loads(out)["warnings"]
    assert len(w) == 1 and w[0].startswith("h.csv covers 0.000..10.000 s of the IMU's 0.000..59.990 s: its end "
                                           "heights are held over 49.990 s")
    assert f"warning: {w[0]}" in err
    code, out, err = _in_process(capsys, *base)
    assert code == 0 and json.loads(out)["warnings"] == []


def test_mechanize_names_a_lone_imu_spike(files, tmp_path, capsys):
    """A corrupt row (one gyro sample of 87 rad/s) was integrated by mechanize without a word, the solution
    turned by radians; now its warnings name it, as navigate's do (inskit.integration.gaps.imu_spikes), and
    --no-unit-check leaves them out."""
    from inskit.types import ImuData

    imu = io.read_imu(files / "imu.csv")
    dth = imu.dtheta_b.copy()
    dth[300, 2] = 87.0 * float(imu.time[300] - imu.time[299])
    io.write_imu(tmp_path / "spike.csv", ImuData(imu.time, dth, imu.dv_b))
    base = ("mechanize", tmp_path / "spike.csv", "--init-from", files / "truth.csv", "--json")
    code, out, err = _in_process(capsys, *base)
    assert code == 0, err
    w = [x for x in json.loads(out)["warnings"] if "lone sample" in x]
    assert len(w) == 1 and w[0].startswith(f"IMU: spike.csv: 1 lone sample far beyond its neighbours (t = "
                                           f"{imu.time[300]:.3f} s, gyro 87 rad/s beside "), w
    code, out, err = _in_process(capsys, *base, "--no-unit-check")
    assert code == 0 and not [x for x in json.loads(out)["warnings"] if "lone sample" in x]


def test_mechanize_says_when_the_solution_leaves_the_earth(files, tmp_path, capsys):
    """`mechanize` of the bundled drive's IMU (mounted upside down) with roll 0 in --init fell to a height of
    -3259 km at 13 km/s and printed it as a result: no warning, and the --out file it wrote was refused by
    evaluate and --init-from ('height_m=-100018.8 is beyond +-100 km of the ellipsoid (a height in metres);
    another unit or column?'), blaming the units of inskit's own file.  Now a warning says that the solution
    diverged, from when, and the likely causes; a run that stays on the Earth says nothing of it."""
    from inskit.types import ImuData

    traj = StationaryTrajectory((np.radians(45), 0.1, 50.0), (0.0, 0.0, 0.5))
    imu = ideal_imu(traj, np.arange(0.0, 200.0, 0.01), nodes=1)
    flipped = ImuData(imu.time, imu.dtheta_b * [1, -1, -1], imu.dv_b * [1, -1, -1])  # rolled 180 deg
    io.write_imu(tmp_path / "flipped.csv", flipped)
    code, out, err = _in_process(capsys, "mechanize", tmp_path / "flipped.csv", "--init-from", files / "truth.csv",
                                 "--json")
    assert code == 0, err
    w = json.loads(out)["warnings"]
    assert len(w) == 1 and w[0].startswith("the solution diverged: from t = "), w
    assert "an IMU upside down: --mount-rpy 180,0,0" in w[0] and f"warning: {w[0]}" in err
    code, out, err = _in_process(capsys, "mechanize", tmp_path / "flipped.csv", "--init-from", files / "truth.csv",
                                 "--mount-rpy", "180,0,0", "--json")
    assert code == 0 and json.loads(out)["warnings"] == [] and "diverged" not in err


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
    r = inskit("allan", tmp_path / "o" / "imu.csv", "--json", "--plot", tmp_path / "a.png", "--toml",
               tmp_path / "noise.toml")
    assert r.returncode == 0, r.stderr
    a = json.loads(r.stdout)
    # tactical preset: ARW 0.125 deg/sqrt(h); two minutes of data pin the white noise within 15 %
    assert abs(a["navigate_noise_section"]["gyro_arw_deg_sqrt_h"] / 0.125 - 1) < 0.15
    assert (tmp_path / "a.png").exists()
    # the [noise] section as a file: a navigate config takes it as it is
    import tomllib

    from inskit.jobs.config import NoiseSection

    text = (tmp_path / "noise.toml").read_text()
    assert text == a["noise_toml"] and a["toml"] == str(tmp_path / "noise.toml")
    assert NoiseSection.model_validate(tomllib.loads(text)["noise"]).gyro_arw_deg_sqrt_h == pytest.approx(
        a["noise_section"]["gyro_arw_deg_sqrt_h"], rel=1e-4)
    r = inskit("allan", tmp_path / "o" / "imu.csv", "--toml", tmp_path / "noise.toml")
    assert r.returncode == 2 and "refusing to overwrite" in r.stderr


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
    nav = json.loads(r.stdout)
    t = nav["truth_errors"]
    # the smoother uses the future too: no worse than the forward filter against the truth
    assert t["smoothed"]["horizontal_m"]["rms"] <= t["forward"]["horizontal_m"]["rms"] * 1.05
    # --truth is [truth] file: every figure names its reference (no outages here: the fit and GNSS-on ones)
    assert nav["fit_to_used_fixes_h_rms_m"] == nav["gnss_on_horizontal_rms_m"]
    assert isinstance(nav["gnss_on_h_vs_truth_rms_m"], float) and nav["outages_vs_truth"] == 0
    assert json.loads((tmp_path / "nav" / "config_used.json").read_text())["truth"]["file"].endswith("truth.csv")
    r = inskit("evaluate", tmp_path / "nav" / "solution_forward.csv", tmp_path / "sim" / "truth.csv", "--json")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["horizontal_m"]["rms"] < 1.0  # 0.5 m white GNSS noise, filtered
    assert abs(s["roll_arcmin"]["final"]) < 30 and abs(s["pitch_arcmin"]["final"]) < 30
    assert not [w for w in nav["health"]["warnings"] if "radians" in w]
    assert "constraint_check" not in nav  # a car: the default non-holonomic constraint holds and stays
    # a truth whose attitude columns hold radians under their _deg headers is said by navigate --truth too
    import pandas as pd

    tr = pd.read_csv(tmp_path / "sim" / "truth.csv")
    for c in ("roll_deg", "pitch_deg", "yaw_deg"):
        tr[c] = np.radians(tr[c])
    tr.to_csv(tmp_path / "truth_rad.csv", index=False)
    r = inskit("navigate", "--imu", tmp_path / "sim" / "imu.csv", "--gnss", tmp_path / "sim" / "gnss.csv",
               "--lever-arm", "0,0,-1", "--out", tmp_path / "nav_rad", "--no-plots", "--json",
               "--truth", tmp_path / "truth_rad.csv")
    assert r.returncode == 0, r.stderr
    w = [w for w in json.loads(r.stdout)["health"]["warnings"] if "radians" in w]
    assert w and all(x.startswith(f"truth: {tmp_path / 'truth_rad.csv'}: column '") for x in w), w
    assert any("'yaw_deg'" in x for x in w), w


def test_evaluate_window_offset_and_per_epoch(files, tmp_path):
    """The stationary truth moved by a constant NED offset: --remove-offset
    finds it exactly, --from/--to bound the epochs, --per-epoch writes them."""
    from inskit import earth

    truth = io.read_solution(files / "truth.csv")
    moved = type(truth)(truth.time, earth.ned_to_lla(np.array([0.3, -0.4, 0.1]), truth.lla), truth.v_n, truth.q_nb)
    io.write_solution(tmp_path / "moved.csv", moved)
    pe = tmp_path / "per_epoch.csv"
    r = inskit("evaluate", tmp_path / "moved.csv", files / "truth.csv", "--from", 10, "--to", 20, "--per-epoch", pe,
               "--remove-offset", "--json")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)  # one JSON object
    o = s["offset_removed"]
    assert (o["north_m"], o["east_m"], o["down_m"]) == pytest.approx((0.3, -0.4, 0.1), abs=1e-6)
    assert s["horizontal_m"]["max"] < 1e-6 and s["epochs"] == 1001
    assert s["window"] == {"from_s": 10.0, "to_s": 20.0}
    import pandas as pd

    tab = pd.read_csv(pe)
    assert tab["time_s"].min() == pytest.approx(10.0) and tab["time_s"].max() == pytest.approx(20.0)
    # an explicit interval; the per-epoch file exists now: refused without --force
    r = inskit("evaluate", tmp_path / "moved.csv", files / "truth.csv", "--per-epoch", pe, "--remove-offset", "0:30")
    assert r.returncode == 2 and "refusing to overwrite" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    r = inskit("evaluate", tmp_path / "moved.csv", files / "truth.csv", "--per-epoch", pe, "--remove-offset", "0:30",
               "--force")
    assert r.returncode == 0, r.stderr
    assert "constant offset removed (mean over 0.000..30.000 s" in r.stdout and "yaw_deg" in r.stdout
    assert len(pd.read_csv(pe)) == 6000
    for args, msg in ((("--from", 30, "--to", 10), "must end after it starts"),
                      (("--to", 99), "lies outside the data"),
                      (("--remove-offset", "a:b"), "is not an interval FROM:TO")):
        r = inskit("evaluate", tmp_path / "moved.csv", files / "truth.csv", *args)
        assert r.returncode == 2 and msg in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr


def test_gravity_option_of_mechanize_and_simulate(tmp_path):
    """--gravity reaches the simulator and the mechanization and is recorded in
    the JSON summaries (default "normal"); simulated and mechanized with the same
    model the IMU reproduces the truth, with another it does not (J2 - normal:
    4.8e-5 m/s^2 down at 45 deg and 1600 m, 0.09 m of height after 60 s)."""
    scen = tmp_path / "s.toml"
    scen.write_text('name = "still"\n[start]\nlat_deg = 45\nlon_deg = 7\nheight_m = 1600\n[imu]\nrate_hz = 50\n'
                    '[[segment]]\ntype = "static"\nduration_s = 60\n')
    from click.testing import CliRunner

    from inskit.cli import cli

    def run(*args):  # in-process (no interpreter start per call); stdout alone holds the JSON
        r = CliRunner().invoke(cli, [str(a) for a in args])
        assert r.exit_code == 0, r.output
        return json.loads(r.stdout)

    assert run("simulate", scen, "--out", tmp_path / "o", "--gravity", "j2", "--json", "--no-plot")["gravity"] == "j2"
    heights = {}
    for model in ("j2", None):
        s = run("mechanize", tmp_path / "o" / "imu.csv", "--init-from", tmp_path / "o" / "truth.csv", "--json",
                *(["--gravity", model] if model else []))
        heights[s["gravity"]] = s["final"]["height_m"]
    assert abs(heights["j2"] - 1600.0) < 1e-3 and abs(heights["normal"] - 1600.0) > 0.05


def test_the_program_ends_fast_yet_runs_exit_handlers_and_keeps_its_status(tmp_path):
    """As the program (``main()`` with no arguments) the CLI skips the
    interpreter's teardown: the atexit handlers still run (a parent's, as
    ``inskit bench`` registers one to read the child's peak memory), what
    was printed is all there, and the status is the command's."""
    import subprocess
    import sys

    wrap = ("import atexit, sys\n"
            "atexit.register(lambda: sys.stderr.write('handler ran\\n'))\n"
            "from inskit.cli import main\n"
            "sys.argv = ['inskit'] + sys.argv[1:]\n"
            "main()\n")
    ok = subprocess.run([sys.executable, "-c", wrap, "--version"], capture_output=True, text=True)
    assert ok.returncode == 0 and "version" in ok.stdout and "handler ran" in ok.stderr
    bad = subprocess.run([sys.executable, "-c", wrap, "navigate", str(tmp_path / "none.toml")], capture_output=True,
                         text=True)
    assert bad.returncode == 2 and "no such config file" in bad.stderr and "handler ran" in bad.stderr
    prof = tmp_path / "prof.out"  # under a profiler the teardown stays: its report is written there
    run = subprocess.run([sys.executable, "-m", "cProfile", "-o", str(prof), "-m", "inskit.cli", "--version"],
                         capture_output=True, text=True)
    assert run.returncode == 0 and prof.is_file() and prof.stat().st_size > 1000


@pytest.mark.parametrize("argv", [
    ["simulate", "s.toml", "--out", "o", "--seed", "-1"],
    ["schemes", "s.toml", "--outage", "1,2", "--seed", "-1"],
    ["consistency", "s.toml", "--seed", "-1"],
    ["gyrofree", "simulate", "source003", "--layout", "ten", "--out", "o", "--seed", "-1"],
])
def test_a_negative_seed_is_a_usage_error_not_a_bug(capsys, argv):
    """It reached numpy's default_rng: 'internal error: ValueError: expected non-negative integer', exit 3."""
    code, out, err = _in_process(capsys, *argv)
    assert code == 2 and out == "" and "--seed" in err and "internal error" not in err, err


def test_an_end_of_file_out_of_a_command_is_a_user_error_not_an_abort(capsys, monkeypatch):
    """click turns an EOFError into Abort ('inskit: aborted', exit 130, as for Ctrl-C); a truncated gzip file
    that a reader does not catch raises one, and it is the user's input, said in one line, exit 2."""
    def truncated(*a, **k):
        raise EOFError("Compressed file ended before the end-of-stream marker was reached")

    import inskit.alignment as A

    monkeypatch.setattr(A, "align_static", truncated)
    code, out, err = _in_process(capsys, "align", __file__, "--lat", "45")
    assert code == 2 and out == "", err
    assert err.startswith("inskit: error: an input file ended early (Compressed file ended") and err.count("\n") == 1


def test_init_from_a_file_on_another_time_base_names_both(files, tmp_path, capsys):
    """It said 'requested times 0.000..0.000 s fall outside the solution span ...': no file, no option."""
    sol = io.read_solution(files / "truth.csv")
    io.write_solution(tmp_path / "late.csv", type(sol)(sol.time + 1e3, sol.lla, sol.v_n, sol.q_nb))
    code, out, err = _in_process(capsys, "mechanize", files / "imu.csv", "--init-from", tmp_path / "late.csv",
                                 "--out", tmp_path / "sol.csv")
    assert code == 2 and out == "" and not (tmp_path / "sol.csv").exists()
    assert "--init-from " in err and "late.csv: spans 1000.000..1059.990 s, but " in err, err
    assert "imu.csv starts at 0.000 s: mismatched time bases?" in err


def test_allan_names_the_log_it_refuses_and_two_outputs_in_one_file(files, tmp_path, capsys):
    imu = io.read_imu(files / "imu.csv")
    t = imu.time.copy()
    t[3000:] += 100.0
    io.write_imu(tmp_path / "gap.csv", type(imu)(t, imu.dtheta_b, imu.dv_b))
    code, out, err = _in_process(capsys, "allan", tmp_path / "gap.csv")
    assert code == 2 and out == "" and "gap.csv: the Allan deviation needs a regularly sampled log" in err, err
    code, out, err = _in_process(capsys, "allan", files / "imu.csv", "--plot", tmp_path / "a.png",
                                 "--toml", tmp_path / "a.png", "--force")
    assert code == 2 and "a.png: given as both --plot and --toml" in err and not (tmp_path / "a.png").exists()
    # --force never lets an output replace the log it reads (the shared check of every writer)
    shutil.copy(files / "imu.csv", tmp_path / "log.csv")
    before = (tmp_path / "log.csv").read_bytes()
    code, out, err = _in_process(capsys, "allan", tmp_path / "log.csv", "--toml", tmp_path / "log.csv", "--force")
    assert code == 2 and "log.csv: is an input of this command" in err and (tmp_path / "log.csv").read_bytes() == before


def test_allan_states_the_minimum_of_a_short_log_and_names_a_constant_channel(files, tmp_path, capsys):
    """`head -2 imu.csv` and a log whose gyro z is 0 everywhere were internal errors (exit 3)."""
    lines = (files / "imu.csv").read_text().splitlines()
    (tmp_path / "two.csv").write_text("\n".join(lines[:2]) + "\n")
    code, out, err = _in_process(capsys, "allan", tmp_path / "two.csv")
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    # refused by the IMU reader now, as by every command that reads the log (the Allan minimum, 101 samples
    # and 100 s, is test_allan's)
    assert "two.csv: holds 1 data row(s); an IMU log needs at least two" in err
    from inskit.simulation.sensors import apply_imu_errors, preset
    from inskit.types import ImuData

    t = np.arange(0.0, 120.0, 0.01)
    ideal = ImuData(t, np.zeros((len(t), 3)), np.tile([0.0, 0.0, -0.0980665], (len(t), 1)))
    imu, _ = apply_imu_errors(ideal, preset("tactical"), np.random.default_rng(1))
    dth = imu.dtheta_b.copy()
    dth[:, 2] = 0.0
    io.write_imu(tmp_path / "stuck.csv", ImuData(t, dth, imu.dv_b))
    code, out, err = _in_process(capsys, "allan", tmp_path / "stuck.csv")
    assert code == 0, err
    row_z = next(x for x in out.splitlines() if x.startswith("z "))
    assert row_z.split()[1:5] == ["constant", "(no", "noise", "measurable)"], out  # the gyro columns
    assert "# note: gyro z: constant over the log" in out
    code, out, err = _in_process(capsys, "allan", tmp_path / "stuck.csv", "--json")
    rep = json.loads(out)
    assert rep["gyro"][2]["constant"] is True and rep["gyro"][2]["arw_deg_sqrt_h"] is None
    assert rep["noise_section"]["gyro_arw_deg_sqrt_h"] > 0


def test_a_refused_run_leaves_no_empty_output_folder(capsys, tmp_path):
    """`inskit navigate bad.toml --out new/dir` made new/dir before finding that an input was missing;
    the folder it made is removed when the command fails, one already there (or not empty) stays."""
    cfg = tmp_path / "bad.toml"
    cfg.write_text('name = "x"\n[imu]\nfile = "nope.csv"\n[gnss]\nfile = "g.csv"\n')
    code, _, err = _in_process(capsys, "navigate", cfg, "--out", tmp_path / "new" / "dir")
    assert code == 2 and "no such file" in err
    assert not (tmp_path / "new").exists()
    (tmp_path / "kept").mkdir()
    code, _, _ = _in_process(capsys, "navigate", cfg, "--out", tmp_path / "kept")
    assert code == 2 and (tmp_path / "kept").is_dir()


@pytest.mark.parametrize("command", [["simulate", "s.toml", "--out", "o", "--truth-rate"],
                                     ["navigate", "c.toml", "--output-rate"],
                                     ["gyrofree", "simulate", "source003", "--out", "o", "--rate"]])
def test_every_rate_option_is_capped_at_the_scenario_imu_rate_cap(command, capsys, tmp_path, monkeypatch):
    """--rate 1e7 of gyrofree simulate grew to 24 GB; --truth-rate and --output-rate had no bound either."""
    monkeypatch.chdir(tmp_path)
    option = command[-1]
    code, out, err = _in_process(capsys, *command, "1e7")
    assert code == 2 and out == "", err
    assert (f"Invalid value for '{option}': 1e+07 Hz is not a rate within (0, 10000] Hz (every rate is capped at "
            "10000 Hz, as a scenario's [imu] rate_hz)") in err
    code, out, err = _in_process(capsys, *command, "0")
    assert code == 2 and f"Invalid value for '{option}': 0 Hz is not a rate within (0, 10000] Hz" in err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_init_from_a_one_row_state_file(files, tmp_path, capsys, suffix):
    """A file holding just the initial state (one row at the IMU's first time) was 'inskit: error: `lla` has a
    NaN or infinite value (nan) at row 0': the interpolation divided by its zero-length interval."""
    sol = io.read_solution(files / "truth.csv")
    one = tmp_path / f"init{suffix}"
    io.write_solution(one, sol.slice(0, 1))
    code, out, err = _in_process(capsys, "mechanize", files / "imu.csv", "--init-from", one, "--json")
    assert code == 0, err
    ref = _in_process(capsys, "mechanize", files / "imu.csv", "--init-from", files / "truth.csv", "--json")
    got, want = json.loads(out)["final"], json.loads(ref[1])["final"]
    assert got == pytest.approx(want, rel=1e-12, abs=1e-9)


def test_progress_off_a_terminal_is_a_plain_line_now_and_then():
    import io

    from inskit.cli_output import LineProgress, progress

    buf = io.StringIO()
    p = LineProgress(40, "monte carlo", unit="run", every_s=0.0, stream=buf)
    with p:
        p.update(10)
    line = buf.getvalue().strip()
    assert line.startswith("monte carlo: 10 of 40 runs, ") and line.endswith("s left"), line
    quiet = io.StringIO()
    q = LineProgress(40, "tune", every_s=3600.0, stream=quiet)
    q.update(39)
    assert quiet.getvalue() == ""  # a short job prints no progress
    assert isinstance(progress(3, "x"), LineProgress)  # pytest's stderr is not a terminal


def test_mechanize_summary_wraps_the_longitude_as_the_file_does(files, tmp_path):
    """Across the antimeridian the JSON said lon_deg 180.099 where the written solution said -179.901."""
    out = tmp_path / "sol.csv"
    r = inskit("mechanize", files / "imu.csv", "--init", "45,179.995,50,0,100,0,0,0,90", "--height", "hold",
               "--out", out, "--json")
    assert r.returncode == 0, r.stderr
    final = json.loads(r.stdout)["final"]
    sol = io.read_solution(out)
    lon_file = float(np.degrees(sol.lla[-1, 1]))
    assert -180.0 < final["lon_deg"] <= 180.0 and final["lon_deg"] < 0  # it crossed: about 6 km east of 179.995
    assert final["lon_deg"] == pytest.approx(lon_file, abs=1e-9)


SMALL_SCENARIO = """name = "small"
[start]
lat_deg = 40.0
lon_deg = -105.0
height_m = 1600.0
[imu]
rate_hz = 20.0
grade = "industrial-mems"
[gnss]
rate_hz = 1.0
[[segment]]
type = "static"
duration_s = 10.0
[[segment]]
type = "accelerate"
speed_m_s = 5.0
duration_s = 5.0
"""


def test_simulate_force_never_deletes_a_folder_of_an_output_name(capsys, tmp_path):
    """A folder out/scenario.png of the user's: `simulate --force` replaced it by the plot and removed it with
    all it held (exit 0); now refused before the work, naming it, and nothing in out changes."""
    sc = tmp_path / "small.toml"
    sc.write_text(SMALL_SCENARIO)
    out = tmp_path / "out"
    (out / "scenario.png").mkdir(parents=True)
    (out / "scenario.png" / "mine.txt").write_text("keep")
    code, stdout, err = _in_process(capsys, "simulate", sc, "--out", out, "--force", "--json")
    assert code == 2 and stdout == "", err
    assert "scenario.png: is a folder" in err and "Traceback" not in err
    assert (out / "scenario.png" / "mine.txt").read_text() == "keep"
    assert sorted(p.name for p in out.iterdir()) == ["scenario.png"]


def _static_log(path, seed):
    """130 s of a static IMU at 10 Hz with white noise, as increments."""
    from inskit.types import ImuData

    rng = np.random.default_rng(seed)
    n = 1300
    t = np.arange(n) * 0.1
    dth = rng.normal(0.0, 1e-5, (n, 3))
    dv = rng.normal(0.0, 1e-4, (n, 3)) + [0.0, 0.0, -0.981]
    dth[0] = dv[0] = 0.0
    io.write_imu(path, ImuData(t, dth, dv))


def test_allan_writes_its_plot_and_toml_as_a_set(tmp_path, capsys, monkeypatch):
    """--plot and --toml were written one after the other: a TOML that could not be written (disk full) left
    the new plot in place of the old one, beside a failed command.  Now both land or neither; the earlier
    files stay as they were and no temporary file is left in either folder."""
    import inskit.files as F

    _static_log(tmp_path / "static.csv", seed=5)
    (tmp_path / "p").mkdir()
    (tmp_path / "t").mkdir()
    plot, toml = tmp_path / "p" / "allan.png", tmp_path / "t" / "noise.toml"
    plot.write_text("old plot")
    toml.write_text("old toml")

    def full(path, text):
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(F, "write_text", full)
    code, out, err = _in_process(capsys, "allan", tmp_path / "static.csv", "--plot", plot, "--toml", toml, "--force",
                                 "--json")
    assert code == 2 and out == "" and "No space left on device" in err and "Traceback" not in err, err
    assert plot.read_text() == "old plot" and toml.read_text() == "old toml"
    assert sorted(p.name for p in tmp_path.rglob("*") if p.is_file()) == ["allan.png", "noise.toml", "static.csv"]
    monkeypatch.undo()
    code, out, err = _in_process(capsys, "allan", tmp_path / "static.csv", "--plot", plot, "--toml", toml, "--force",
                                 "--json")
    assert code == 0, err
    s = json.loads(out)
    assert s["plot"] == str(plot) and s["toml"] == str(toml) and toml.read_text() == s["noise_toml"]
    assert plot.read_bytes()[:4] == b"\x89PNG"
    assert sorted(p.name for p in tmp_path.rglob("*") if p.is_file()) == ["allan.png", "noise.toml", "static.csv"]


def test_allan_makes_the_plot_folder_before_the_work(tmp_path, capsys):
    """`allan LOG --plot new/a.png` (a folder not there yet) ran the whole analysis, then failed with
    'new/.part-NNN-a.png: could not be written (No such file or directory)' (exit 2), naming a temporary
    file; the folder is now made before the work, as --toml's is (and removed again when the command fails)."""
    _static_log(tmp_path / "static.csv", seed=6)
    plot = tmp_path / "new" / "deeper" / "a.png"
    code, out, err = _in_process(capsys, "allan", tmp_path / "static.csv", "--plot", plot, "--json")
    assert code == 0 and json.loads(out)["plot"] == str(plot), err
    assert plot.read_bytes()[:4] == b"\x89PNG" and ".part" not in err
    code, out, err = _in_process(capsys, "allan", tmp_path / "static.csv", "--plot", tmp_path / "gone" / "a.png",
                                 "--toml", tmp_path / "gone" / "a.png")
    assert code == 2 and "given as both" in err and not (tmp_path / "gone").exists()


def test_simulate_verify_runs_before_the_files_are_written(capsys, tmp_path, monkeypatch):
    """`simulate --verify --force` interrupted (Ctrl-C) or failing in its self-check had already replaced the
    earlier run's files; the check now comes first, and a failed one leaves the folder as it was."""
    import inskit.jobs.simulate as JS

    sc = tmp_path / "small.toml"
    sc.write_text(SMALL_SCENARIO)
    out = tmp_path / "out"
    code, stdout, err = _in_process(capsys, "simulate", sc, "--out", out, "--no-plot", "--json")
    assert code == 0, err
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(JS, "verify_ideal", interrupted)
    code, stdout, err = _in_process(capsys, "simulate", sc, "--out", out, "--no-plot", "--seed", 4, "--force",
                                    "--verify", "--json")
    assert code == 130 and stdout == "" and "aborted" in err and "Traceback" not in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


@pytest.mark.parametrize("flags, given", [(["--quick"], "--quick"), (["--no-cli"], "--no-cli"),
                                          (["--quick", "--no-cli"], "--quick and --no-cli")])
def test_bench_long_refuses_the_flags_it_would_ignore(flags, given):
    """`inskit bench --quick --long` ran the long benchmark (minutes, 2.4 GB of cached drives) without a word
    that --quick was ignored; now one line and exit 2 before any work."""
    r = inskit("bench", "--long", *flags, "--json")
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.strip() == (f"inskit: error: --long runs only the long navigate figures (whole commands, "
                                f"minutes): {given} would be ignored; give --long alone, or {given} without it")


def test_an_output_folder_of_other_files_is_said_to_hold_them_not_results(capsys, tmp_path):
    """`--out` on a folder holding only a user's notes.txt was refused as 'already holds results': the
    refusal is right (nothing of the user's is written among), its words now say what the folder holds
    and what --force would do there; a folder with an earlier run's summary.json still holds results."""
    cfg = tmp_path / "c.toml"
    cfg.write_text('name = "x"\n[imu]\nfile = "nope.csv"\n[gnss]\nfile = "g.csv"\n')  # refused before any read
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    code, _, err = _in_process(capsys, "navigate", cfg, "--out", out)
    assert code == 2 and err.count("\n") == 1, err
    assert f"{out}: holds other files (notes.txt) and no results of a run" in err
    assert "already holds results" not in err and "--force to write the results beside them" in err
    for name in ("a.csv", "b.csv", "c.csv"):
        (out / name).write_text("x")
    code, _, err = _in_process(capsys, "navigate", cfg, "--out", out)
    assert "holds other files (a.csv, b.csv, c.csv, ...)" in err
    (out / "summary.json").write_text("{}")
    code, _, err = _in_process(capsys, "navigate", cfg, "--out", out)
    assert code == 2 and f"{out}: already holds results (" in err and "--force to replace them" in err
    assert (out / "notes.txt").read_text() == "mine"


def test_mechanize_takes_the_mounting_of_a_mounted_imu(tmp_path, capsys):
    """A simulated IMU mounted at [imu] mount_rpy_deg writes its own axes: `inskit mechanize` had no way to say
    so and ended 277 m below the truth on a 31 s drive, silently.  --mount-rpy (navigate's [imu] mount_rpy_deg)
    rotates the readings into the body: the ideal IMU then follows its truth to centimetres."""
    from inskit import earth
    from inskit.cli import main
    from inskit.jobs.simulate import write_simulation
    from inskit.simulation.scenario import Scenario, simulate

    sc = Scenario.model_validate({
        "name": "mount", "start": {"lat_deg": 45.0, "lon_deg": 7.0},
        "imu": {"rate_hz": 100.0, "grade": "ideal", "mount_rpy_deg": [10.0, -20.0, 95.0]},
        "segment": [{"type": "static", "duration_s": 2.0}, {"type": "accelerate", "speed_m_s": 10.0, "duration_s": 5.0},
                    {"type": "turn", "angle_deg": 90.0, "rate_deg_s": 10.0}]})
    write_simulation(simulate(sc, seed=1), tmp_path, plot=False)
    truth = io.read_solution(tmp_path / "truth.csv")

    def end_error(*extra):
        with pytest.raises(SystemExit) as exc:
            main(["mechanize", str(tmp_path / "imu.csv"), "--init-from", str(tmp_path / "truth.csv"), "--json", *extra])
        assert exc.value.code == 0
        f = json.loads(capsys.readouterr().out)["final"]
        lla = np.array([[np.radians(f["lat_deg"]), np.radians(f["lon_deg"]), f["height_m"]]])
        return np.linalg.norm(earth.lla_to_ned(lla, truth.lla[-1])[0])

    assert end_error("--mount-rpy", "10,-20,95") < 0.05
    assert end_error() > 10.0  # the sensor's axes taken for the body's
