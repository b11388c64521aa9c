"""Command line and jobs of the gyro-free INS (inskit.cli_gyrofree, inskit.jobs.gyrofree).

The commands are mounted here the way ``inskit.cli`` registers them
(:func:`inskit.cli_gyrofree.register`); the subprocess cases run them through
``inskit.cli.main`` to check the one-line errors and exit codes.
"""

import json
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from inskit.cli_gyrofree import gyrofree, reproduce_gyrofree
from inskit.errors import InputError

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
HARNESS = ("import sys\nfrom inskit import cli as C\nfrom inskit.cli_gyrofree import register\n"
           "register(C.cli, C.reproduce)\nC.main(sys.argv[1:])\n")


def inskit(*args):
    return subprocess.run([sys.executable, "-c", HARNESS, *map(str, args)], capture_output=True, text=True,
                          check=False)


def invoke(cmd, *args):
    return CliRunner().invoke(cmd, [str(a) for a in args])


def test_simulate_and_navigate_the_source_scenario(tmp_path):
    r = invoke(gyrofree, "simulate", "source003", "--out", tmp_path / "sim", "--rate", 500,
               "--source-theta-deg=-0.1,-0.1,-0.1,-0.1,-0.1,-0.1", "--json")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    assert s["samples"] == 5001 and s["accelerometers"] == 10
    header = (tmp_path / "sim" / "array.csv").read_text().splitlines()[0]
    assert header == "time_s," + ",".join(f"m{k}_m_s2" for k in range(1, 11))
    r = invoke(gyrofree, "navigate", tmp_path / "sim" / "array.csv", "--layout", tmp_path / "sim" / "layout.csv",
               "--out", tmp_path / "nav", "--init-from", tmp_path / "sim" / "truth.csv", "--truth",
               tmp_path / "sim" / "truth.csv", "--json")
    assert r.exit_code == 0, r.output
    n = json.loads(r.stdout)
    assert n["solver"] == "closed-form/robust" and n["frame"] == "source"
    # SOURCES-NOTES 1.8: -0.1 deg on m1-m6 gives |dP| = |[-0.06, -1.86, -2.26]| = 2.93 m at 10 s
    assert abs(n["truth_errors"]["position_final_m"] - 2.93) < 0.02
    assert n["truth_errors"]["rate_sign_errors"] == 0
    assert (tmp_path / "nav" / "rates.csv").exists() and (tmp_path / "nav" / "solution.csv").exists()


def test_earth_scenario_with_the_core_mechanization(tmp_path):
    r = invoke(gyrofree, "simulate", EXAMPLES / "car.toml", "--out", tmp_path / "car", "--duration", 30,
               "--rate", 400, "--json")
    assert r.exit_code == 0, r.output
    r = invoke(gyrofree, "navigate", tmp_path / "car" / "array.csv", "--out", tmp_path / "nav", "--frame", "ned",
               "--solver", "least-squares", "--init-from", tmp_path / "car" / "truth.csv", "--truth",
               tmp_path / "car" / "truth.csv", "--json")
    assert r.exit_code == 0, r.output
    e = json.loads(r.stdout)["truth_errors"]
    assert e["horizontal_max_m"] < 0.01 and e["rate_error_max_rad_s"] < 1e-6


def test_rank_deficient_layout_and_bad_inputs(tmp_path):
    r = invoke(gyrofree, "simulate", "source003", "--layout", "six", "--out", tmp_path / "six", "--rate", 100)
    assert r.exit_code == 0, r.output
    r = invoke(gyrofree, "navigate", tmp_path / "six" / "array.csv", "--layout", "six", "--out", tmp_path / "n")
    assert isinstance(r.exception, InputError) and "cannot observe the sign" in str(r.exception)
    bad = tmp_path / "bad.csv"
    bad.write_text("name,x_m,y_m,z_m,axis_x,axis_y,axis_z\nm1,0.1,0,0,2,0,0\n")
    r = invoke(gyrofree, "navigate", tmp_path / "six" / "array.csv", "--layout", bad, "--out", tmp_path / "n")
    assert isinstance(r.exception, InputError) and "bad.csv: line 2" in str(r.exception)
    r = invoke(gyrofree, "simulate", "source003", "--out", tmp_path / "six")
    assert isinstance(r.exception, InputError) and "already exists" in str(r.exception)


def test_a_spinning_start_without_an_initial_rate_names_the_options(tmp_path):
    """README's `gyrofree navigate out/gf/array.csv --layout ten` on the
    source scenario (3.7 rad/s at the start) said "pass `omega0`", the Python
    argument; the command line names its own options, and --init-from works."""
    r = invoke(gyrofree, "simulate", "source003", "--out", tmp_path / "gf", "--rate", 200)
    assert r.exit_code == 0, r.output
    r = invoke(gyrofree, "navigate", tmp_path / "gf" / "array.csv", "--layout", "ten", "--out", tmp_path / "n")
    msg = str(r.exception)
    assert isinstance(r.exception, InputError) and "--omega0 p,q,r" in msg and "--init-from" in msg
    assert "`omega0`" not in msg
    r = invoke(gyrofree, "navigate", tmp_path / "gf" / "array.csv", "--layout", "ten", "--out", tmp_path / "n",
               "--init-from", tmp_path / "gf" / "truth.csv")
    assert r.exit_code == 0, r.output


def test_errors_through_main_are_one_line(tmp_path):
    """Through inskit.cli.main: one line on stderr, exit 2, nothing on stdout."""
    r = inskit("gyrofree", "simulate", "source003", "--layout", "six", "--out", tmp_path / "six", "--rate", 100)
    assert r.returncode == 0, r.stderr
    r = inskit("gyrofree", "navigate", tmp_path / "six" / "array.csv", "--layout", "six", "--out", tmp_path / "n",
               "--json")
    assert r.returncode == 2 and r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert lines[-1].startswith("inskit: error: layout 'six'") and "sign" in lines[-1]
    assert "Traceback" not in r.stderr
    assert not any((tmp_path / "n").glob("*"))  # nothing written (refused before the solve)  # the refused run leaves no empty output folder behind


def test_reproduce_gyrofree_json(tmp_path):
    r = invoke(reproduce_gyrofree, "--out", tmp_path, "--quick", "--json")
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)  # exactly one JSON object on stdout
    assert d["experiment"] == "gyrofree"
    assert all("published" in e and "ours" in e and e["note"] for e in d["entries"])
    assert len(d["growth_60s"]) == 4
    names = {Path(f).name for f in d["figures"]}
    assert names == {"fig11_euler_angles.png", "fig12_position.png", "fig13_trajectory.png",
                     "fig14_position_error.png", "sensitivity.png", "growth_60s.png"}
    assert all(Path(f).stat().st_size > 10_000 for f in d["figures"])
    rows = (tmp_path / "growth_60s.csv").read_text().splitlines()
    assert rows[0] == "unit,rms_10s_m,rms_30s_m,rms_60s_m" and len(rows) == 5


def test_rates_and_sample_counts_are_capped_naming_the_option(tmp_path):
    """`gyrofree simulate source003 --rate 1e7` grew to 24 GB before the system killed it: the rate is
    capped at the scenario's [imu] rate_hz cap, and a duration at a rate at MAX_SAMPLES samples."""
    from inskit.units import MAX_RATE_HZ, MAX_SAMPLES

    assert (MAX_RATE_HZ, MAX_SAMPLES) == (10_000, 10_000_000)
    r = invoke(gyrofree, "simulate", "source003", "--out", tmp_path / "a", "--rate", "1e7")
    assert r.exit_code == 2 and "Invalid value for '--rate': 1e+07 Hz is not a rate within (0, 10000] Hz" in r.output
    r = invoke(gyrofree, "simulate", "source003", "--out", tmp_path / "a", "--rate", 1000, "--duration", "1e5")
    assert isinstance(r.exception, InputError) and str(r.exception) == (
        "--duration 100000 s at --rate 1000 Hz: 100,000,000 samples, more than the 10,000,000 one simulation "
        "holds; shorten --duration or lower --rate")
    from inskit.jobs.gyrofree import simulate_job

    with pytest.raises(InputError, match=r"^--rate must be within \(0, 10000\] Hz, got 20000.0$"):
        simulate_job("source003", "ten", tmp_path / "b", rate_hz=2e4)
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_too_few_samples_are_said_of_the_option_given(tmp_path):
    """`gyrofree simulate SCENARIO --rate 0.05` (a 30 s scenario) said '--duration must cover at least two
    samples, got 30.141592653589793 s at 0.05 Hz', of an option the user never gave; now both options and
    what would do are named (no rate beyond the 10000 Hz cap is suggested)."""
    from inskit.jobs.gyrofree import simulate_job

    scen = tmp_path / "s.toml"
    scen.write_text('name = "t"\n[start]\nlat_deg = 45\nlon_deg = 10\n[[segment]]\ntype = "static"\n'
                    'duration_s = 30\n')
    with pytest.raises(InputError, match=r"^--duration 30 s at --rate 0.05 Hz covers fewer than two sampling "
                                         r"intervals: give a --rate of at least 0.06667 Hz or a --duration of at "
                                         r"least 40 s$"):
        simulate_job(str(scen), "ten", tmp_path / "a", rate_hz=0.05)
    with pytest.raises(InputError, match=r"^--duration 0.0001 s at --rate 1000 Hz covers fewer than two sampling "
                                         r"intervals: give a --duration of at least 0.002 s$"):
        simulate_job("source003", "ten", tmp_path / "b", duration=1e-4)


def test_a_duration_past_the_scenario_is_refused_as_platform_and_consistency_do(tmp_path):
    """`gyrofree simulate car.toml --duration 5000` clipped in silence to the scenario's 1842 s."""
    r = invoke(gyrofree, "simulate", EXAMPLES / "car.toml", "--out", tmp_path / "car", "--duration", 5000)
    assert isinstance(r.exception, InputError)
    assert str(r.exception) == "--duration must be within (0, 1842] s, got 5000.0"
    from inskit.jobs.montecarlo import consistency_study
    from inskit.simulation.scenario import load_scenario

    with pytest.raises(InputError) as other:  # the wording of the others
        consistency_study(load_scenario(EXAMPLES / "car.toml"), "tactical", 2, 5000.0)
    assert str(other.value) == str(r.exception)


def test_a_rate_below_twice_the_scenario_vibration_is_refused(tmp_path):
    """`gyrofree simulate car.toml --rate 20` sampled the car's 14 Hz heave at
    point samples below its Nyquist rate: accepted in silence, and navigating
    the exact array data left 9 m of height error in 60 s.  Refused before the
    folder is made; 30 Hz (Nyquist 15 Hz) still runs."""
    r = invoke(gyrofree, "simulate", EXAMPLES / "car.toml", "--out", tmp_path / "a", "--rate", 20,
               "--duration", 5)
    assert isinstance(r.exception, InputError)
    assert str(r.exception).startswith("--rate 20 Hz: ") and str(r.exception).endswith(
        "car.toml: vibration 1 (down, sinusoidal): its frequency_hz 14 Hz is at or above the Nyquist frequency "
        "of the array's samples (10 Hz): they would alias it into false slow motion; give --rate above 28 Hz "
        "(the scenario's IMU samples at 100 Hz)")
    assert not (tmp_path / "a").exists()
    r = invoke(gyrofree, "simulate", EXAMPLES / "car.toml", "--out", tmp_path / "b", "--rate", 30,
               "--duration", 2, "--json")
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["rate_hz"] == 30.0


def test_a_vibration_the_scenario_rate_cannot_sample_runs_at_a_rate_that_can(tmp_path):
    """A 100 Hz scenario with a 60 Hz vibration: `gyrofree simulate --rate
    1000` was refused by the scenario's own check at its 100 Hz ('at or
    above the Nyquist frequency of the IMU (50 Hz at imu.rate_hz 100)'),
    though the array is sampled at 1000 Hz.  It runs; without --rate, or
    with a --rate that cannot sample it either, it is refused."""
    text = (EXAMPLES / "car.toml").read_text().replace("frequency_hz = 14.0", "frequency_hz = 60.0")
    assert "frequency_hz = 60.0" in text
    (tmp_path / "v.toml").write_text(text)
    r = invoke(gyrofree, "simulate", tmp_path / "v.toml", "--out", tmp_path / "a", "--rate", 1000,
               "--duration", 2, "--json")
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["rate_hz"] == 1000.0
    r = invoke(gyrofree, "simulate", tmp_path / "v.toml", "--out", tmp_path / "b", "--duration", 2)
    assert "Nyquist frequency of the IMU (50 Hz at imu.rate_hz 100)" in str(r.exception)
    r = invoke(gyrofree, "simulate", tmp_path / "v.toml", "--out", tmp_path / "c", "--rate", 110, "--duration", 2)
    assert str(r.exception).endswith("(imu.rate_hz is --rate 110 here)"), r.exception


def test_a_gap_in_the_array_file_is_reported(tmp_path):
    """Half a second of rows missing from a 200 Hz array file was stepped
    across in silence (0.9 m off at 2 s on the source's motion); as
    `inskit mechanize` does of an IMU log, the gap is now a warning, on
    stderr and in the JSON."""
    r = invoke(gyrofree, "simulate", "source003", "--out", tmp_path / "gf", "--rate", 200, "--duration", 2)
    assert r.exit_code == 0, r.output
    lines = (tmp_path / "gf" / "array.csv").read_text().splitlines()
    (tmp_path / "gap.csv").write_text("\n".join(lines[:100] + lines[200:]) + "\n")
    r = invoke(gyrofree, "navigate", tmp_path / "gap.csv", "--omega0", "1,2,3", "--out", tmp_path / "nav",
               "--json")
    assert r.exit_code == 0, r.output
    w = json.loads(r.stdout)["warnings"]
    assert len(w) == 1 and "gap.csv: a gap of 0.505 s at t = 0.490 s (row 99)" in w[0]
    assert "warning: " + w[0] in r.stderr
    r = invoke(gyrofree, "navigate", tmp_path / "gf" / "array.csv", "--omega0", "1,2,3", "--out",
               tmp_path / "nav2", "--json")
    assert json.loads(r.stdout)["warnings"] == []


def test_fig11_euler_angles_are_not_joined_across_the_wrap(tmp_path, monkeypatch):
    """fig11: the yaw of the spinning unit wraps at +-180 deg every 1.7 s; the
    wrap is not drawn as a vertical line."""
    import numpy as np

    from inskit.jobs import gyrofree as JG

    figs = {}
    monkeypatch.setattr(JG, "save_figure", lambda fig, path, dpi=110: figs.setdefault(Path(path).name, fig))
    JG.reproduce_gyrofree(tmp_path, quick=True, log=lambda *a, **k: None)
    lines = figs["fig11_euler_angles.png"].axes[0].get_lines()
    assert len(lines) == 6
    for ln in lines:
        _, y = ln.get_data()
        ok = ~np.isnan(y)
        assert (np.abs(np.diff(y))[ok[1:] & ok[:-1]] < 180).all()
    _, yaw = lines[4].get_data()
    assert np.isnan(yaw).sum() >= 5  # the truth yaw wraps 6 times in the 10 s


def test_reproduce_gyrofree_returns_plain_json_values(tmp_path, monkeypatch):
    """reproduce_gyrofree's truth_check went through a copy of files.plain_json
    that left a NaN as NaN (not JSON: a strict reader refuses it); it goes
    through plain_json itself: numpy scalars and arrays as plain numbers and
    lists, as before, and NaN or infinity as None."""
    import math

    import numpy as np

    from inskit.jobs import gyrofree as JG
    from inskit.jobs import reproduce_gyrofree as RG

    tc = {"r_10s_m": np.array([350.07, np.nan, 1006.63]), "rate_hz": np.float64(500.0), "d_m": 0.1,
          "closed_form": {"position_error_max_m": np.float32(0.5), "samples": np.int64(5001), "ok": np.bool_(True),
                          "rate_error_max_rad_s": float("nan"), "force_error_max_m_s2": np.float64(np.inf)}}
    res = {"truth_check": tc, "entries": [], "closest_reading": {}, "random_misalignment": {},
           "comparison": {"table": [{"unit": "u", "rms_10s_m": 1.0}], "grades_text": ""}}
    monkeypatch.setattr(RG, "run", lambda log, quick=False: res)
    monkeypatch.setattr(JG, "_plots", lambda out, res: [])
    got = JG.reproduce_gyrofree(tmp_path, quick=True)["truth_check"]
    assert got == {"r_10s_m": [350.07, None, 1006.63], "rate_hz": 500.0, "d_m": 0.1,
                   "closed_form": {"position_error_max_m": 0.5, "samples": 5001, "ok": True,
                                   "rate_error_max_rad_s": None, "force_error_max_m_s2": None}}
    assert [type(v) for v in got["closed_form"].values()][:3] == [float, int, bool] and type(got["rate_hz"]) is float
    json.dumps(got, allow_nan=False)  # strict JSON (it raised on the NaN)


def test_init_from_takes_the_truth_at_the_array_files_first_time(tmp_path):
    """`gyrofree navigate` of an array file starting at 0.5 s with --init-from
    the whole truth (from 0 s) started the source frame from the truth's first
    row, in silence: 23.4 m off at 2 s against the truth.  The state is now
    the truth's at the array's first time; a truth that does not reach that
    time is refused naming --init-from and both files (the Earth frames said
    'requested times 0.000..0.000 s fall outside the solution span', naming
    neither)."""
    r = invoke(gyrofree, "simulate", "source003", "--out", tmp_path / "gf", "--rate", 200, "--duration", 2)
    assert r.exit_code == 0, r.output
    for name in ("array", "truth"):
        lines = (tmp_path / "gf" / f"{name}.csv").read_text().splitlines()
        (tmp_path / f"{name}_late.csv").write_text("\n".join(lines[:1] + lines[101:]) + "\n")  # from 0.5 s
    r = invoke(gyrofree, "navigate", tmp_path / "array_late.csv", "--out", tmp_path / "n", "--init-from",
               tmp_path / "gf" / "truth.csv", "--truth", tmp_path / "truth_late.csv", "--json")
    assert r.exit_code == 0, r.output
    e = json.loads(r.stdout)["truth_errors"]
    assert e["position_max_m"] < 1e-6 and e["rate_sign_errors"] == 0
    r = invoke(gyrofree, "navigate", tmp_path / "gf" / "array.csv", "--out", tmp_path / "n2", "--init-from",
               tmp_path / "truth_late.csv")
    assert isinstance(r.exception, InputError)
    assert str(r.exception) == (f"--init-from {tmp_path / 'truth_late.csv'}: spans 0.500..2.000 s, but "
                                f"{tmp_path / 'gf' / 'array.csv'} starts at 0.000 s: mismatched time bases?")
    r = invoke(gyrofree, "simulate", EXAMPLES / "car.toml", "--out", tmp_path / "car", "--rate", 100,
               "--duration", 2)
    assert r.exit_code == 0, r.output
    lines = (tmp_path / "car" / "truth.csv").read_text().splitlines()
    (tmp_path / "car_late.csv").write_text("\n".join(lines[:1] + lines[101:]) + "\n")  # from 1 s
    r = invoke(gyrofree, "navigate", tmp_path / "car" / "array.csv", "--frame", "ned", "--out", tmp_path / "n3",
               "--init-from", tmp_path / "car_late.csv")
    assert isinstance(r.exception, InputError)
    assert str(r.exception).startswith(f"--init-from {tmp_path / 'car_late.csv'}: spans 1.000..2.000 s, but ")


def test_inertial_truth_between_its_rows():
    """The source frame's initial state between two truth rows: linear in
    position and velocity, the attitude between the two rows'."""
    import numpy as np

    from inskit.gyrofree.motion import ConstantRateMotion
    from inskit.jobs.gyrofree import _inertial_at

    m = ConstantRateMotion()
    tr = m.truth(np.array([0.0, 0.01, 0.02]))
    at = _inertial_at(tr, 0.01)
    assert np.array_equal(at.r_i[0], tr.r_i[1]) and np.array_equal(at.q_ib[0], tr.q_ib[1])
    mid = _inertial_at(tr, 0.015)
    exact = m.truth(np.array([0.015]))
    assert np.allclose(mid.r_i[0], exact.r_i[0], atol=1e-3) and np.allclose(mid.q_ib[0], exact.q_ib[0], atol=1e-3)
    assert abs(np.linalg.norm(mid.q_ib[0]) - 1) < 1e-12


@pytest.mark.parametrize("init, message", [
    ("40,-105,1600e3,0,0,0,0,0,0", "--init: height_m 1.6e+06 m is beyond +-100 km of the ellipsoid: a pressure or "
                                   "another unit? expected a height in metres"),
    ("40,-105,1600,0,0,0,0,0,400", "--init: yaw 400 is outside [-360, 360] degrees: no angle needs more than a full "
                                   "turn either way (a typo, or another unit?)"),
])
def test_init_is_checked_as_mechanize_checks_it(tmp_path, init, message):
    """`gyrofree navigate --frame ned --init 40,-105,1600e3,...` (km typed as m) navigated from 1600 km up, and a
    yaw of 400 deg was taken modulo 360: refused in the words of `inskit mechanize --init`."""
    r = invoke(gyrofree, "simulate", "source003", "--out", tmp_path / "gf", "--rate", 100, "--duration", 1)
    assert r.exit_code == 0, r.output
    r = invoke(gyrofree, "navigate", tmp_path / "gf" / "array.csv", "--frame", "ned", "--init", init, "--omega0",
               "1,2,3", "--out", tmp_path / "n")
    assert isinstance(r.exception, InputError) and str(r.exception) == message


def test_options_another_solver_or_layout_would_ignore_are_refused(tmp_path):
    """`gyrofree navigate --filter-noise 0.01 --noise 0.01`, `--solver least-squares --sign-rule source` and
    `--layout FILE --d 0.2` ran and said nothing of the option they had dropped (--noise and --sign-rule are
    read by the closed form only, --d by the built-in layouts only); the defaults still run."""
    r = invoke(gyrofree, "simulate", "source003", "--out", tmp_path / "gf", "--rate", 100, "--duration", 1)
    assert r.exit_code == 0, r.output
    a, lay = tmp_path / "gf" / "array.csv", tmp_path / "gf" / "layout.csv"
    for args, message in (
            (["--noise", "0.01", "--filter-noise", "0.01"],
             "--noise 0.01 would be ignored: it is an option of the closed-form solver and --filter-noise selects "
             "the least-squares solver; drop it, or give --solver closed-form (the ten layout)"),
            (["--solver", "least-squares", "--sign-rule", "source", "--noise", "0.1"],
             "--sign-rule source and --noise 0.1 would be ignored: they are options of the closed-form solver and "
             "--solver least-squares is given; drop them, or give --solver closed-form (the ten layout)"),
            (["--layout", lay, "--d", "0.2"],
             f"--d 0.2 would be ignored: it is the lever arm of the built-in layouts ten and six, and --layout {lay} "
             "gives every accelerometer's position itself; drop --d")):
        r = invoke(gyrofree, "navigate", a, "--omega0", "1,2,3", "--out", tmp_path / "n", *args)
        assert isinstance(r.exception, InputError) and str(r.exception) == message
    r = invoke(gyrofree, "simulate", "source003", "--out", tmp_path / "s", "--layout", lay, "--d", "0.3")
    assert isinstance(r.exception, InputError) and str(r.exception).startswith("--d 0.3 would be ignored")
    r = invoke(gyrofree, "simulate", "source003", "--layout", "six", "--out", tmp_path / "six", "--rate", 100,
               "--duration", 1)
    assert r.exit_code == 0, r.output
    r = invoke(gyrofree, "navigate", tmp_path / "six" / "array.csv", "--layout", "six", "--omega0", "1,2,3",
               "--noise", "0.1", "--out", tmp_path / "n")
    assert isinstance(r.exception, InputError) and "--solver auto takes least squares for layout 'six'" in str(
        r.exception)
    for args in (["--layout", lay, "--noise", "0.01"], ["--solver", "least-squares"], ["--d", "0.1"]):
        r = invoke(gyrofree, "navigate", a, "--omega0", "1,2,3", "--out", tmp_path / "ok", "--force", *args)
        assert r.exit_code == 0, r.output


def test_omega0_beside_init_from_is_said(tmp_path):
    """--omega0 with --init-from replaced the truth file's initial rate without a word (the docs say the option
    wins); now a note names both, and the summary says where the initial rate came from."""
    r = invoke(gyrofree, "simulate", "source003", "--out", tmp_path / "gf", "--rate", 200)
    assert r.exit_code == 0, r.output
    args = ("gyrofree", "navigate", tmp_path / "gf" / "array.csv", "--layout", "ten", "--init-from",
            tmp_path / "gf" / "truth.csv",
            "--json", "--force")
    r = inskit(*args, "--out", tmp_path / "a")
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["omega0_from"] == "--init-from" and "--omega0" not in r.stderr
    r = inskit(*args, "--out", tmp_path / "b", "--omega0", "3,1,2")
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["omega0_from"] == "--omega0"
    assert "note: --omega0 3, 1, 2 rad/s is used, not the initial rate of" in r.stderr


def test_simulate_and_navigate_write_their_files_as_a_set(tmp_path, monkeypatch):
    """A failure after the first files were written left them: `gyrofree navigate ... --truth BAD` failed
    (exit 2) with rates.csv and solution.csv in --out; a simulate whose truth.csv could not be written had
    replaced array.csv and layout.csv already.  Now nothing of a failed run is left, and an earlier run's
    files stay as they were."""
    from inskit.gyrofree import files as GF

    sim = tmp_path / "sim"
    r = invoke(gyrofree, "simulate", "source003", "--out", sim, "--rate", 100, "--duration", 1, "--json")
    assert r.exit_code == 0, r.output
    before = {p.name: p.read_bytes() for p in sim.iterdir()}
    bad = tmp_path / "bad.csv"
    bad.write_text("garbage\n")
    r = invoke(gyrofree, "navigate", sim / "array.csv", "--out", tmp_path / "nav", "--init-from", sim / "truth.csv",
               "--truth", bad)
    assert r.exit_code != 0 and isinstance(r.exception, InputError)
    assert not (tmp_path / "nav").exists() or not any((tmp_path / "nav").iterdir())

    def disk_full(*a, **k):
        raise InputError("truth.csv: could not be written (No space left on device)")

    monkeypatch.setattr(GF, "write_inertial", disk_full)
    r = invoke(gyrofree, "simulate", "source003", "--out", sim, "--rate", 100, "--duration", 1, "--noise-ug", 100,
               "--force")
    assert r.exit_code != 0 and isinstance(r.exception, InputError)
    assert {p.name: p.read_bytes() for p in sim.iterdir()} == before  # the earlier set, no staging folder


def test_reproduce_refuses_a_folder_with_files_and_writes_as_a_set(tmp_path, monkeypatch):
    """`reproduce gyrofree --out D` replaced the user's D/entries.json without a word (exit 0), and a run that
    failed midway left the figures written so far; now a folder that holds files is refused before the work
    unless --force, and the files land together (their paths in D) or none does."""
    from inskit.jobs import gyrofree as JG

    def fake(out_dir, quick=False, log=None):
        (Path(out_dir) / "fig11_euler_angles.png").write_text("new fig")
        (Path(out_dir) / "entries.json").write_text("[]")
        if quick:
            raise RuntimeError("the run failed")
        return {"entries": [], "growth_60s": [], "growth_grades": "", "figures": [str(Path(out_dir) /
                "fig11_euler_angles.png")], "tables": [str(Path(out_dir) / "entries.json")]}

    monkeypatch.setattr(JG, "reproduce_gyrofree", fake)
    out = tmp_path / "out"
    out.mkdir()
    (out / "entries.json").write_text("mine")
    r = invoke(reproduce_gyrofree, "--out", out, "--json")
    assert r.exit_code != 0 and isinstance(r.exception, InputError) and "already holds files" in str(r.exception)
    r = invoke(reproduce_gyrofree, "--out", out, "--quick", "--force", "--json")
    assert r.exit_code != 0 and "the run failed" in str(r.exception)
    assert sorted(p.name for p in out.iterdir()) == ["entries.json"] and (out / "entries.json").read_text() == "mine"
    r = invoke(reproduce_gyrofree, "--out", out, "--force", "--json")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    assert s["figures"] == [str(out / "fig11_euler_angles.png")] and s["tables"] == [str(out / "entries.json")]
    assert sorted(p.name for p in out.iterdir()) == ["entries.json", "fig11_euler_angles.png"]
    assert s["files"] == [str(out / "entries.json"), str(out / "fig11_euler_angles.png")]  # exactly those written


def test_a_truth_must_cover_the_run_and_may_be_longer(tmp_path):
    """--truth with the first 30 s of a 60 s run (Earth frames) was scored: '3d_final_m' at 30 s and a 3.86 m/s^2
    'force error' from rates held past the truth's end.  Now a truth that does not cover the array's span is
    refused before the solve, naming both; in the source frame a truth longer than the array (which was refused
    as 'its times are not those of the array file') is compared at the array's own times."""
    r = invoke(gyrofree, "simulate", EXAMPLES / "car.toml", "--out", tmp_path / "car", "--rate", 100, "--duration", 4)
    assert r.exit_code == 0, r.output
    lines = (tmp_path / "car" / "truth.csv").read_text().splitlines()
    (tmp_path / "car_2s.csv").write_text("\n".join(lines[:202]) + "\n")  # 0..2 s
    r = invoke(gyrofree, "navigate", tmp_path / "car" / "array.csv", "--frame", "ned", "--out", tmp_path / "n",
               "--init-from", tmp_path / "car" / "truth.csv", "--truth", tmp_path / "car_2s.csv")
    assert isinstance(r.exception, InputError)
    assert str(r.exception) == (f"{tmp_path / 'car_2s.csv'}: spans 0.000..2.000 s, but {tmp_path / 'car' / 'array.csv'} "
                                "runs 0.000..4.000 s: the truth must cover the whole run (its errors would be scored "
                                "against a truth held past its ends)")
    assert not any((tmp_path / "n").glob("*"))  # nothing written (refused before the solve)
    r = invoke(gyrofree, "simulate", "source003", "--out", tmp_path / "gf", "--rate", 200, "--duration", 2)
    assert r.exit_code == 0, r.output
    lines = (tmp_path / "gf" / "array.csv").read_text().splitlines()
    (tmp_path / "early.csv").write_text("\n".join(lines[:202]) + "\n")  # the array's first second only
    r = invoke(gyrofree, "navigate", tmp_path / "early.csv", "--out", tmp_path / "n2", "--init-from",
               tmp_path / "gf" / "truth.csv", "--truth", tmp_path / "gf" / "truth.csv", "--json")
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["truth_errors"]["position_max_m"] < 1e-6


def test_a_lever_arm_beyond_the_layout_readers_limit_is_refused(tmp_path):
    """simulate --d 1000 wrote a layout.csv that navigate refused ('1000 m from the reference point (more than
    100 m: metres are expected)'); --d is checked against the same limit, for both commands."""
    for cmd in (("simulate", "source003"), ("navigate", tmp_path / "a.csv")):
        r = invoke(gyrofree, *cmd, "--d", 1000, "--out", tmp_path / "o")
        assert isinstance(r.exception, InputError), r.output
        assert str(r.exception) == ("--d must be within (0, 100] m (the accelerometers' distance from the reference "
                                    "point; metres are expected), got 1000")
