"""The platform jobs and commands (issue 10, parts 4-5): files, one JSON
object on stdout, the reproduction's entries and figures."""

import json
import re

import pytest
from click.testing import CliRunner

from inskit import io
from inskit.cli_platform import platform, reproduce_integration_filters
from inskit.errors import InputError
from inskit.jobs.platform import TABLE1

SCENARIO = """
name = "north"
[start]
lat_deg = 50.0
lon_deg = 30.0
speed_m_s = 10.0
[imu]
grade = "navigation"
[gnss]
rate_hz = 1.0
white_h_m = 5.0
velocity_sigma_m_s = 0.1
outages_s = [[1200.0, 1500.0]]
[[segment]]
type = "cruise"
duration_s = 900.0
[[segment]]
type = "turn"
angle_deg = 90.0
rate_deg_s = 0.5
[[segment]]
type = "cruise"
duration_s = 900.0
"""


@pytest.fixture(scope="module")
def scenario(tmp_path_factory):
    p = tmp_path_factory.mktemp("sc") / "north.toml"
    p.write_text(SCENARIO)
    return p


def run(cmd, args):
    r = CliRunner().invoke(cmd, [str(a) for a in args], catch_exceptions=False)
    return r


@pytest.mark.parametrize("kind", ["semi-analytical", "analytical", "geometric"])
def test_platform_simulate_json(scenario, tmp_path, kind):
    ideal = tmp_path / "ideal.toml"
    ideal.write_text(SCENARIO.replace('grade = "navigation"', 'grade = "ideal"'))
    r = run(platform, ["simulate", ideal, "--kind", kind, "--out", tmp_path, "--json", "--no-plots"])
    assert r.exit_code == 0, r.stderr
    s = json.loads(r.stdout)  # exactly one JSON object
    assert s["kind"] == kind and s["epochs"] > 1800
    assert s["errors"]["horizontal_m"]["max"] < 1.0  # perfect instruments
    sol = io.read_solution(tmp_path / "solution.csv")
    assert "tilt_e_rad" in sol.extra and "gimbal_yaw_rad" in sol.extra
    # the scenario's navigation grade: its turn-on biases and white noise drive the platform
    r = run(platform, ["simulate", scenario, "--kind", kind, "--out", tmp_path / "nav", "--json"])
    s = json.loads(r.stdout)
    assert 1.0 < s["errors"]["horizontal_m"]["max"] < 5000.0
    assert (tmp_path / "nav" / "platform.png").exists() and (tmp_path / "nav" / "errors.png").exists()


def test_platform_integrate_json_and_files(scenario, tmp_path):
    r = run(platform, ["integrate", scenario, "--scheme", "closed", "--filter", "second-order", "--out", tmp_path,
                       "--json", "--gyro-drift-deg-h", "0.01,0.01,0.01"])
    assert r.exit_code == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["filter"] == "second-order" and s["fixes"] < s["epochs"]  # the outage removed fixes
    for f in ("solution.csv", "ins.csv", "truth.csv", "estimates.csv", "errors.png"):
        assert (tmp_path / f).exists()
    assert s["errors"]["horizontal_m"]["rms"] < 50.0
    assert s["settings"]["fix_interval_s"] == pytest.approx(s["settings"]["every"] * s["dt_s"])
    # refuses to overwrite, names the file
    with pytest.raises(InputError, match="already exists"):
        run(platform, ["integrate", scenario, "--out", tmp_path])
    r = run(platform, ["integrate", scenario, "--out", tmp_path, "--force", "--filter", "kalman", "--scheme", "open",
                       "--no-plots"])
    assert r.exit_code == 0 and "open loop, kalman" in r.stdout


def test_bad_input(scenario, tmp_path):
    with pytest.raises(InputError, match="no such scenario"):
        run(platform, ["simulate", tmp_path / "missing.toml", "--out", tmp_path])
    with pytest.raises(InputError, match="three finite numbers"):
        run(platform, ["simulate", scenario, "--out", tmp_path, "--gyro-drift-deg-h", "1,2"])
    with pytest.raises(InputError, match="--duration"):
        run(platform, ["simulate", scenario, "--out", tmp_path, "--duration", "1e6"])
    r = CliRunner().invoke(platform, ["simulate", str(scenario), "--out", str(tmp_path), "--kind", "strapdown"])
    assert r.exit_code == 2  # click rejects the choice


def test_reproduce_quick(tmp_path):
    """The reproduction's JSON: every published table-1 figure appears with
    ours beside it, with the compute-time ratio measured; the figures exist."""
    r = run(reproduce_integration_filters, ["--out", tmp_path, "--json", "--quick"])
    assert r.exit_code == 0, r.stderr
    res = json.loads(r.stdout)
    items = {e["item"]: e for e in res["entries"]}
    for e in res["entries"]:
        assert {"published", "ours", "note"} <= set(e)
    n_table = sum(1 for f in TABLE1.values() for k in f if k != "time_s")
    assert sum(1 for i in items if "steady-state" in i) == n_table
    ratio = items["compute time, Kalman / 1st order"]
    assert ratio["published"] == pytest.approx(2.33) and ratio["ours"] > 1.0
    assert "rank 9/12" in items["observability: azimuth error"]["ours"]
    for f in res["figures"]:
        assert (tmp_path / f.split("/")[-1]).stat().st_size > 10_000
    assert {r_["scheme"] for r_ in res["outage"]} == {"open", "closed"}
    assert (tmp_path / "table1.csv").exists() and (tmp_path / "results.json").exists()
    # every file written, and only those (the figures were listed, not table1.csv nor results.json)
    assert res["files"] == sorted(str(p) for p in tmp_path.iterdir()) and len(res["files"]) == 7


@pytest.mark.slow
def test_reproduce_full(tmp_path):
    """The full 8 h reproduction (about a minute): the source's ordering and
    the closed loop's outage memory."""
    r = run(reproduce_integration_filters, ["--out", tmp_path, "--json"])
    assert r.exit_code == 0, r.stderr
    res = json.loads(r.stdout)
    items = {e["item"]: e for e in res["entries"]}
    assert items["Kalman best on absolute velocity"]["ours"] == "yes"
    assert items["Kalman best on horizontal tilt"]["ours"] == "yes"
    g = {(o["filter"], o["scheme"]): o["growth_m"] for o in res["outage"]}
    assert g["first-order", "closed"] < 0.5 * g["first-order", "open"]
    assert g["second-order", "closed"] < 0.5 * g["second-order", "open"]


def test_integrate_without_any_fix_is_refused(tmp_path):
    """outages_s covering the whole run gave "fixes": 0, an RMS and exit 0:
    an integration with nothing to integrate with."""
    from inskit.errors import ConfigError

    p = tmp_path / "blind.toml"
    p.write_text(SCENARIO.replace("outages_s = [[1200.0, 1500.0]]", "outages_s = [[0.0, 5000.0]]"))
    with pytest.raises(ConfigError, match=r"blind\.toml: no GNSS fix reaches the filter .*outages_s"):
        run(platform, ["integrate", p, "--out", tmp_path / "o", "--no-plots"])
    assert not (tmp_path / "o" / "solution.csv").exists()


def test_the_step_is_capped_as_every_rate_and_by_the_epoch_count(scenario, tmp_path):
    """`--dt` is a rate's inverse: 1e-6 s would make 900 million epochs of the 900 s scenario."""
    with pytest.raises(InputError, match=r"^--dt must be at least 0\.0001 s \(every rate is capped at 10000 Hz\), "
                                         r"got 1e-06$"):
        run(platform, ["simulate", scenario, "--out", tmp_path / "a", "--dt", "1e-6"])
    with pytest.raises(InputError, match=r"^--dt 0\.0001 s over 1982 s: 19,820,000 epochs, more than the "
                                         r"10,000,000 one simulation holds"):
        run(platform, ["integrate", scenario, "--out", tmp_path / "a", "--dt", "1e-4"])


def test_a_step_longer_than_the_run_names_the_options(scenario, tmp_path):
    """`platform simulate --dt 200 --duration 100` answered in the library's words:
    "`duration` (100.0 s) must be at least one step (200.0 s)"."""
    with pytest.raises(InputError, match=r"^--dt 200 s is longer than the run \(100 s of --duration\): give a --dt "
                                         r"of at most 100 s$"):
        run(platform, ["simulate", scenario, "--out", tmp_path / "a", "--dt", 200, "--duration", 100])
    with pytest.raises(InputError, match=r"^--dt 5000 s is longer than the run \(1982 s, the whole scenario\)"):
        run(platform, ["integrate", scenario, "--out", tmp_path / "a", "--dt", 5000])
    assert not (tmp_path / "a").exists()


@pytest.mark.parametrize("option, value", [("--gyro-drift-deg-h", "1e8,0,0"), ("--accel-bias-ug", "0,1e12,0")])
def test_instrument_errors_beyond_the_models_are_refused_naming_the_option(scenario, tmp_path, option, value):
    """They left the Earth in three steps: "`lla` has a NaN or infinite value (inf) at row 3"."""
    for sub in ("simulate", "integrate"):
        with pytest.raises(InputError, match=rf"^{option} .*: at most "):
            run(platform, [sub, scenario, "--out", tmp_path / "a", option, value, "--duration", 100])
    assert not (tmp_path / "a").exists()


def test_gimbal_angles_are_not_joined_across_their_wrap(tmp_path, monkeypatch):
    """platform.png: a gimbal yaw passing +-180 deg is drawn as the angle it
    is, not as a vertical line swinging through the whole circle."""
    from types import SimpleNamespace

    import numpy as np

    from inskit.jobs import platform as JP

    figs = []
    monkeypatch.setattr(JP, "save_figure", lambda fig, path, dpi=110: figs.append(fig))
    t = np.arange(0.0, 100.0, 1.0)
    yaw = np.radians((170.0 + t + 180.0) % 360.0 - 180.0)  # 170 deg on, wrapping at 10 s and 370 s
    extra = {f"tilt_{a}_rad": 1e-4 * t for a in "enu"}
    extra.update({"gimbal_roll_rad": 0 * t, "gimbal_pitch_rad": 0 * t, "gimbal_yaw_rad": yaw})
    run = SimpleNamespace(truth=SimpleNamespace(time=t), solution=SimpleNamespace(extra=extra))
    JP._plot_platform(run, tmp_path / "p.png", "wrap")
    _, y = figs[0].axes[1].get_lines()[2].get_data()
    ok = ~np.isnan(y)
    assert (np.abs(np.diff(y))[ok[1:] & ok[:-1]] < 180).all() and ok.sum() == len(t)


def test_outage_plot_spans_the_errors_below_a_centimetre_and_names_its_zeros(tmp_path, monkeypatch):
    """outage.png: the errors were floored at 1 cm (np.maximum(hz, 1e-2)), so
    any below were drawn at 1 cm (the 8 h run's 1st-order open loop dips to
    8.3 mm).  The axis spans the data; an exact zero, which a log axis cannot
    show, is drawn below the smallest positive error and the legend says so."""
    import numpy as np

    from inskit.jobs import platform as JP

    figs = []
    monkeypatch.setattr(JP, "save_figure", lambda fig, path, dpi=110: figs.append(fig))
    e = {"outage_s": (3600.0, 4500.0), "duration_s": 7200.0}
    t = np.arange(0.0, 7201.0, 1.0)
    runs = {}
    for i, name in enumerate(("kalman", "first-order", "second-order")):
        lo = 10.0 ** -(3 + i)  # 1 mm, 0.1 mm, 10 um: all below the old 1 cm floor
        runs[(name, "open")] = (t, np.geomspace(lo, 300.0, len(t)), None)
        closed = np.geomspace(5.0, 2 * lo, len(t))
        if name == "first-order":
            closed[:3] = 0.0  # an exact zero (e.g. the start with no initial error)
        runs[(name, "closed")] = (t, closed, None)
    JP._plot_outage(runs, tmp_path / "outage.png", e)
    for i, (ax, name) in enumerate(zip(figs[0].axes, ("kalman", "first-order", "second-order"))):
        lo, hi = ax.get_ylim()
        plotted = np.concatenate([ln.get_ydata() for ln in ax.get_lines() if len(ln.get_ydata())])
        assert lo <= plotted.min() and hi >= plotted.max(), name
        assert lo <= 10.0 ** -(3 + i) and hi >= 300.0, name  # the whole of the errors, not clipped at 1 cm
        labels = ax.get_legend_handles_labels()[1]
        assert labels[:2] == ["open loop", "closed loop"] and "satellite outage" in labels
        zero_labels = [lab for lab in labels if "exact zero" in lab]
        if name == "first-order":
            y = ax.get_lines()[1].get_ydata()
            assert zero_labels == [f"3 exact zero(s) drawn at {y[0]:.2g} m"]
            assert 0 < y[0] < 1e-4 and (y[:3] == y[0]).all()  # below every positive error of the panel
        else:
            assert not zero_labels


@pytest.mark.parametrize("command, plots", [("simulate", ["errors.png", "platform.png"]),
                                            ("integrate", ["errors.png"])])
def test_plots_are_checked_and_written_with_the_files_as_a_set(scenario, tmp_path, monkeypatch, command, plots):
    """The plots were outside the outputs checked before the run: a user's errors.png in --out was replaced
    without --force (exit 0), and a plot that failed left the new solution.csv and truth.csv beside the
    earlier run's plots.  Now an existing plot is refused like the CSV files, and a failed plot leaves the
    folder as it was."""
    import inskit.analysis as A

    out = tmp_path / "out"
    out.mkdir()
    (out / "errors.png").write_text("mine")
    r = CliRunner().invoke(platform, [command, str(scenario), "--out", str(out), "--duration", 120])
    assert r.exit_code != 0 and isinstance(r.exception, InputError) and "errors.png" in str(r.exception)
    assert sorted(p.name for p in out.iterdir()) == ["errors.png"]
    assert (out / "errors.png").read_text() == "mine"
    (out / "errors.png").unlink()
    s = json.loads(run(platform, [command, scenario, "--out", out, "--duration", 120, "--json"]).stdout)
    assert sorted(s["files"]) == sorted(str(p) for p in out.iterdir())  # exactly the files written
    assert all((out / p).is_file() for p in plots)
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    def broken(*a, **k):
        raise RuntimeError("the plot failed")

    monkeypatch.setattr(A, "plot_errors", broken)
    r = CliRunner().invoke(platform, [command, str(scenario), "--out", str(out), "--duration", 120, "--seed", 3,
                                      "--force"])
    assert r.exit_code != 0 and "the plot failed" in str(r.exception)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_integrate_computes_its_whole_summary_before_the_files(scenario, tmp_path, monkeypatch):
    """The steady-state errors were computed after the files were written: their failure (or Ctrl-C there)
    left the new files in place of the earlier run's beside a failed command."""
    import inskit.jobs.platform as JP

    out = tmp_path / "out"
    run(platform, ["integrate", scenario, "--out", out, "--duration", 120, "--no-plots"])
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    def broken(*a, **k):
        raise RuntimeError("the summary failed")

    monkeypatch.setattr(JP, "steady_state_errors", broken)
    r = CliRunner().invoke(platform, ["integrate", str(scenario), "--out", str(out), "--duration", 120, "--seed", 5,
                                      "--no-plots", "--force"])
    assert r.exit_code != 0 and "the summary failed" in str(r.exception)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


@pytest.mark.parametrize("command", ["simulate", "integrate"])
@pytest.mark.parametrize("lat, shown", [(89.95, "89.9500"), (90.0, "90.0000")])
def test_a_scenario_near_a_pole_is_refused_naming_the_file(tmp_path, command, lat, shown):
    """A scenario at rest on the pole: 'platform integrate' said "`lla` holds a latitude of 1.5707964 rad at row 0
    (90 deg), beyond +-90 deg: degrees where radians are expected? (np.radians)"; 0.05 deg from it, where the
    north-pointing platform's azimuth rate grows with tan(lat), it ran.  Now both are refused before any file,
    as NED navigation is within 0.1 deg of a pole."""
    p = tmp_path / "pole.toml"
    p.write_text(f"name = \"pole\"\n[start]\nlat_deg = {lat}\nlon_deg = 10\n[imu]\ngrade = \"navigation\"\n"
                 "[[segment]]\ntype = \"static\"\nduration_s = 60\n")
    with pytest.raises(InputError, match=rf"^{re.escape(str(p))}: the trajectory comes within 0\.1 deg of the north "
                                         rf"pole \(latitude {shown} deg at t = 0 s\), where a platform INS, whose "
                                         r"axes point north, east and down, is singular$"):
        run(platform, [command, p, "--out", tmp_path / "o", "--no-plots"])
    assert not (tmp_path / "o").exists()


CAR_TURNS = """
name = "turns"
[start]
lat_deg = 40.0
lon_deg = -105.0
[imu]
grade = "ideal"
[gnss]
rate_hz = 1.0
[[segment]]
type = "accelerate"
speed_m_s = 15.0
duration_s = 10.0
[[segment]]
type = "turn"
angle_deg = 90.0
rate_deg_s = 10.0
[[segment]]
type = "cruise"
duration_s = 60.0
[[segment]]
type = "turn"
angle_deg = -90.0
rate_deg_s = 10.0
[[segment]]
type = "cruise"
duration_s = 60.0
"""


def test_a_step_that_does_not_resolve_the_motion_is_measured_and_said(tmp_path):
    """docs/platform.md said 'steps of 1-10 s are enough' and 'perfect sensors give a perfect solution': with
    perfect instruments a car at 10 s steps drifted 23 km, at 1 s 57 m, silently.  The command now runs the
    perfect-instrument mechanization beside the real one, reports its error as numerical_floor and warns when
    it is a tenth of the run's error or more; a step that resolves the turns leaves centimetres."""
    sc = tmp_path / "turns.toml"
    sc.write_text(CAR_TURNS)
    floors = {}
    for dt in (0.1, 5.0):
        r = run(platform, ["simulate", sc, "--dt", dt, "--out", tmp_path / f"d{dt}", "--json", "--no-plots"])
        assert r.exit_code == 0, r.stderr
        s = json.loads(r.stdout)
        floors[dt] = s["numerical_floor"]["horizontal_max_m"]
        # ideal grade: the run is the floor itself (no instrument error), so the warning is the step's
        assert s["errors"]["horizontal_m"]["max"] == pytest.approx(floors[dt], rel=1e-6)
        said = [w for w in s["warnings"] if "does not resolve the scenario's motion" in w]
        assert bool(said) == (floors[dt] > 1.0), (dt, floors[dt], s["warnings"])
    assert floors[0.1] < 0.05 and floors[5.0] > 10.0


def test_a_step_that_does_not_fit_the_fixes_or_the_duration_is_said(scenario, tmp_path):
    """integrate --dt 0.3 made the scenario's 1 Hz fixes one every 0.9 s (112 in 100 s), said only in a log
    line; --duration 100.5 at 1 s ran 100 s silently."""
    with pytest.raises(InputError, match=r"--dt 0\.3 s and the scenario's \[gnss\] rate_hz 1 .* must divide the fix "
                                         r"interval \(it gave a fix every 0\.9 s\)"):
        run(platform, ["integrate", scenario, "--dt", "0.3", "--duration", "100", "--out", tmp_path / "a"])
    r = run(platform, ["simulate", scenario, "--duration", "100.5", "--out", tmp_path / "b", "--json", "--no-plots"])
    assert json.loads(r.stdout)["warnings"][0] == "--dt 1 s does not divide --duration 100.5 s: the run ends at 100 s"
