"""Issue 4 acceptance on the bundled real drive (drive_0708, outage protocol)."""

from pathlib import Path

import numpy as np
import pytest

from inskit.jobs.config import load_config
from inskit.jobs.navigate import navigate, summary
from scenarios import short_car

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "drive_0708.toml"


@pytest.fixture(scope="module")
def result():
    cfg = load_config(EXAMPLE, {"output": {"plots": False}})
    return navigate(cfg, smooth=True)


def test_forward_outage_end_rms_within_3_m(result):
    s = result.score_forward.summary
    assert s["outages"] == 11
    assert s["outage_end_horizontal_rms_m"] <= 3.0


def test_forward_outage_end_rms_within_issue_14s_2_m(result):
    """Issue 14's figure: 1.98 m with the fixes' noise shaped to their
    innovations (``[gnss] sigma_scale_ned``, docs/guide.md), 2.035 m
    without; the shape's own measure agrees within the calibration's 5 %."""
    assert result.score_forward.summary["outage_end_horizontal_rms_m"] <= 2.0
    ax = summary(result)["gnss_axes"]
    assert abs(ax["vertical_to_horizontal"] - 1.0) <= 0.05, ax


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
    assert s["states"] == 26  # 21 + the two mounting states and the three GNSS error states of examples/drive_0708.toml


def test_no_mounting_warning_on_the_drive(drive_inputs):
    """The drive's [imu] mount_rpy_deg is right: run without the mounting
    states, the direction of travel lies within 0.2 deg of the IMU's forward
    axis (0.06 deg pitch, 0.00 deg yaw), far below the 1 deg warning."""
    cfg, imu, gnss, _ = drive_inputs
    off = cfg.model_copy(update={"constraints": cfg.constraints.model_copy(update={"mounting": False})})
    s = summary(navigate(off, inputs=(imu, gnss)))
    assert not [w for w in s["health"]["warnings"] if w.startswith("mounting:")], s["health"]["warnings"]
    ev = s["mounting_check"]
    assert ev["epochs"] > 500 and abs(ev["pitch_deg"]) < 0.2 and abs(ev["yaw_deg"]) < 0.2, ev


def test_the_modelled_mounting_of_the_drive_is_small_and_resolved(result):
    """With the mounting states on (the example config) the residual
    boresight after mount_rpy_deg is a fraction of a degree, well inside
    its 5 deg prior, and the detector stands down (the mounting is modelled)."""
    s = summary(result)
    m, sig = s["mounting_rpy_deg"], s["mounting_sigma_deg"]
    assert abs(m[1]) < 0.5 and abs(m[2]) < 1.0 and 0 < sig[1] < 0.5 and 0 < sig[2] < 0.5, (m, sig)
    assert s["mounting_check"] is None


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


def _shifted(gnss, t_from, n, east_m):
    """GNSS with ``n`` fixes from ``t_from`` (or all after it, n=None) moved east."""
    from inskit import earth
    from inskit.types import GnssData

    lla = gnss.lla.copy()
    i0 = int(np.searchsorted(gnss.time, t_from))
    i1 = len(lla) if n is None else i0 + n
    shift = np.zeros((i1 - i0, 3))
    shift[:, 1] = east_m if np.ndim(east_m) == 0 else east_m[: i1 - i0]
    lla[i0:i1] = [earth.ned_to_lla(d, p) for d, p in zip(shift, lla[i0:i1])]
    return GnssData(gnss.time, lla, gnss.sigma_ned, gnss.v_n, gnss.sigma_v_ned)


@pytest.fixture(scope="module")
def drive_inputs():
    from inskit.jobs.navigate import load_inputs

    cfg = load_config(EXAMPLE, {"output": {"plots": False}})
    imu, gnss = load_inputs(cfg)
    clean = navigate(cfg, inputs=(imu, gnss))
    return cfg, imu, gnss, clean


@pytest.mark.parametrize("n,east_m", [(4, 1000.0), (10, 1000.0), (30, 1000.0), (30, 10.0)])
def test_bursts_of_bad_fixes_cannot_hijack_the_filter(drive_inputs, n, east_m):
    """Issue 12: 4 fixes 1 km off used to take the outage RMS from 2.77 m to
    98 m (the fourth was accepted ungated).  Now exactly the bad fixes are
    rejected and the outage figures stay within 10 % of the clean run."""
    cfg, imu, gnss, clean = drive_inputs
    r = navigate(cfg, inputs=(imu, _shifted(gnss, gnss.time[0] + 60.0, n, east_m)))
    c0, c1 = clean.forward.counts["gnss_pos"], r.forward.counts["gnss_pos"]
    assert c1["rejected"] == c0["rejected"] + n
    assert not r.forward.recoveries
    a = clean.score_forward.summary["outage_end_horizontal_rms_m"]
    b = r.score_forward.summary["outage_end_horizontal_rms_m"]
    assert abs(b / a - 1) < 0.10
    from inskit.jobs.navigate import health

    h = health(r.forward)  # survived, but reported: the input had a burst of bad fixes
    assert h["verdict"] == "unhealthy" and any(f"{n} consecutive updates rejected" in x for x in h["reasons"])


def test_one_refused_outlier_leaves_the_run_healthy(drive_inputs):
    """One fix 1 km off, refused by the gate as it should be, made the mean NIS of gnss_pos 765 for 3 degrees of
    freedom and the verdict 'unhealthy (filter overconfident)' (a helper found it): the NIS of a rejected update
    entered the mean.  The consistency test now takes the accepted updates (mean_nis_accepted); the rejection
    is in the counts, and a burst of them still fails the run (the test above)."""
    from inskit.jobs.navigate import health

    cfg, imu, gnss, clean = drive_inputs
    r = navigate(cfg, inputs=(imu, _shifted(gnss, gnss.time[0] + 60.0, 1, 1000.0)))
    h, h0 = health(r.forward), health(clean.forward)
    m, m0 = h["measurements"]["gnss_pos"], h0["measurements"]["gnss_pos"]
    assert r.forward.counts["gnss_pos"]["rejected"] == clean.forward.counts["gnss_pos"]["rejected"] + 1
    assert m["mean_nis"] > 100 * m["dof"]  # the refused one, in the mean of all updates
    assert m["mean_nis_accepted"] == pytest.approx(m0["mean_nis_accepted"], rel=0.05)
    assert h["verdict"] == h0["verdict"] == "healthy", h["reasons"]


def test_recovery_needs_consistent_evidence_over_time(drive_inputs):
    """A lasting 20 m jump (a datum change, a lost filter) is followed after
    15 s of mutually consistent rejections; fixes alternating +-1 km (outliers
    that disagree with each other) are never accepted."""
    cfg, imu, gnss, clean = drive_inputs
    t_jump = gnss.time[0] + 418.0  # between outages 8 (400-414.75 s) and 9 (445- s)
    r = navigate(cfg, inputs=(imu, _shifted(gnss, t_jump, None, 20.0)))
    rec = r.forward.recoveries
    assert len(rec) >= 1 and 15.0 <= rec[0]["t"] - t_jump < 16.0 and rec[0]["rejected_for_s"] >= 15.0
    alt = np.where(np.arange(200) % 2 == 0, 1000.0, -1000.0)
    r2 = navigate(cfg, inputs=(imu, _shifted(gnss, gnss.time[0] + 180.0, 200, alt)))
    assert not r2.forward.recoveries
    i0 = int(np.searchsorted(gnss.time, gnss.time[0] + 180.0))
    inn = r2.forward.innovations["gnss_pos"]
    bad = (inn["t"] >= gnss.time[i0] - 1e-6) & (inn["t"] <= gnss.time[i0 + 199] + 1e-6)
    assert bad.sum() == int(r2.used[i0:i0 + 200].sum()) > 100  # every outlier outside the outages was offered
    assert not inn["accepted"][bad].any()                      # and none was accepted


def test_health_verdict(drive_inputs):
    """drive_0708 is healthy (its constraint pseudo-measurements are only
    conservative, a warning); a run that had to recover from a lost state is not."""
    from inskit.jobs.navigate import health

    cfg, imu, gnss, clean = drive_inputs
    h = health(clean.forward)
    assert h["verdict"] == "healthy", h["reasons"]
    assert h["measurements"]["gnss_pos"]["dof"] == 3 and h["measurements"]["gnss_pos"]["rejected_fraction"] < 0.01
    r = navigate(cfg, inputs=(imu, _shifted(gnss, gnss.time[0] + 418.0, None, 20.0)))
    h = health(r.forward)
    assert h["verdict"] == "unhealthy" and any("recovered from a lost state" in x for x in h["reasons"])


def test_strict_makes_an_unhealthy_run_fail(tmp_path):
    """A wrong IMU time offset (+0.4 s instead of -0.26 s) rejects most fixes:
    the verdict says so, and --strict exits with 3 after writing everything."""
    import json
    import subprocess
    import sys

    cmd = [sys.executable, "-m", "inskit.cli", "navigate", str(EXAMPLE), "--out", str(tmp_path / "o"), "--no-plots",
           "--imu-time-offset", "0.4", "--strict", "--json"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert p.returncode == 3, p.stderr
    s = json.loads(p.stdout)
    assert s["health"]["verdict"] == "unhealthy"
    assert "health: unhealthy" in p.stderr and "rejected" in p.stderr
    assert (tmp_path / "o" / "summary.json").exists()


def test_date_line_crossing():
    """Issue 12: a drive across 180 deg with an ideal IMU had 34,000 km of
    error; the GNSS difference is now taken the short way round, and the drive
    closes exactly like the same drive away from the date line."""
    from inskit import earth
    from inskit.integration import FilterSettings, GnssPosition, run_filter
    from inskit.simulation import ideal_imu, truth_solution
    from inskit.simulation.gnss import GnssErrors, simulate_gnss
    from inskit.simulation.segments import SegmentTrajectory

    tr = SegmentTrajectory((np.radians(10.0), np.radians(179.999), 50.0), yaw0=np.pi / 2, speed0=20.0)
    tr.cruise(60)
    t = np.arange(0.0, tr.duration, 0.01)
    truth = truth_solution(tr, t)
    g, _ = simulate_gnss(tr, 0.0, tr.duration, GnssErrors(rate_hz=1.0, white_h_m=0.5, white_v_m=1.0,
                                                          velocity_sigma_m_s=0.0), np.random.default_rng(1))
    assert g.lla[0, 1] > 0 > g.lla[-1, 1]  # the fixes do cross
    out = run_filter(ideal_imu(tr, t, nodes=3), truth.state(0), [GnssPosition(g)], FilterSettings.standard())
    d = earth.lla_to_ned(out.nav.lla, truth.lla)
    worst = np.hypot(d[:, 0], d[:, 1]).max()
    assert worst < 3.0 and out.counts["gnss_pos"]["rejected"] == 0
    # the same drive away from the date line, same draws: it must close the same way (within 10 %)
    tr0 = SegmentTrajectory((np.radians(10.0), np.radians(-30.0), 50.0), yaw0=np.pi / 2, speed0=20.0)
    tr0.cruise(60)
    truth0 = truth_solution(tr0, t)
    g0, _ = simulate_gnss(tr0, 0.0, tr0.duration, GnssErrors(rate_hz=1.0, white_h_m=0.5, white_v_m=1.0,
                                                             velocity_sigma_m_s=0.0), np.random.default_rng(1))
    out0 = run_filter(ideal_imu(tr0, t, nodes=3), truth0.state(0), [GnssPosition(g0)], FilterSettings.standard())
    d0 = earth.lla_to_ned(out0.nav.lla, truth0.lla)
    assert abs(worst / np.hypot(d0[:, 0], d0[:, 1]).max() - 1.0) < 0.10


def test_force_clears_only_the_earlier_runs_files(tmp_path):
    """A smoothed run then an unsmoothed one into the same folder with --force:
    no stale solution_smoothed.csv; a user's own file stays."""
    import json
    import subprocess
    import sys

    out = tmp_path / "o"
    base = [sys.executable, "-m", "inskit.cli", "navigate", str(EXAMPLE), "--out", str(out), "--no-plots"]
    assert subprocess.run(base + ["--smooth"], capture_output=True, timeout=300).returncode == 0
    assert (out / "solution_smoothed.csv").exists()
    (out / "notes.txt").write_text("mine")
    p = subprocess.run(base + ["--force", "--json"], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert not (out / "solution_smoothed.csv").exists() and (out / "notes.txt").read_text() == "mine"
    assert json.loads((out / "summary.json").read_text())["files"] == json.loads(p.stdout)["files"]


def test_navigate_with_an_odometer_log_bounds_the_blockage_drift(tmp_path):
    """[odometer] in a navigate config: the simulated blockage drive
    (examples/tc_blockage.toml, no fixes for 120 s three times) with a wheel
    speed log of 0.5 % scale error and 0.05 m/s noise.  Coasting through the
    first window drifts about 40 m; with the odometer the worst horizontal
    error in every window is several times smaller, and the scale error is
    estimated."""
    import warnings

    from inskit import analysis, io
    from inskit.files import write_csv
    from inskit.jobs.config import config_from_dict
    from inskit.jobs.navigate import navigate
    from inskit.jobs.reproduce_tight import BLOCKAGE_NAVIGATE
    from inskit.jobs.simulate import write_simulation
    from inskit.simulation.odometer import simulate_odometer
    from inskit.simulation.scenario import load_scenario, simulate

    sc = load_scenario(Path(__file__).resolve().parents[1] / "examples" / "tc_blockage.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        write_simulation(simulate(sc, seed=2), tmp_path, plot=False)
    truth = io.read_solution(tmp_path / "truth.csv")
    log = simulate_odometer(truth, rate_hz=10.0, scale_error=0.005, noise_m_s=0.05, rng=np.random.default_rng(5))
    write_csv(tmp_path / "odo.csv", {"time_s": log.time, "speed_m_s": log.speed_m_s})
    worst = {}
    for name, extra in (("without", {}), ("with", {"odometer": {"file": "odo.csv", "sigma_m_s": 0.05}})):
        cfg = config_from_dict({**BLOCKAGE_NAVIGATE, **extra}, base_dir=tmp_path, source=name)
        res = navigate(cfg)
        err = analysis.nav_error(res.forward.nav, truth)
        t = err.time - truth.time[0]
        h = np.hypot(err.pos_ned[:, 0], err.pos_ned[:, 1])
        worst[name] = [float(h[(t >= b.start_s) & (t <= b.end_s)].max()) for b in sc.raw_gnss.blockage]
        if name == "with":
            assert res.forward.counts["odometer"]["used"] > 5000
            k = float(res.forward.estimate("odo_scale")[-1, 0])
            assert abs(k - 0.005) < 3 * float(res.forward.sigma_of("odo_scale")[-1, 0]) + 5e-4
    assert worst["without"][0] > 10.0
    assert all(w < 0.5 * wo for w, wo in zip(worst["with"], worst["without"])), worst


def test_navigate_fuses_gnss_speed_and_course(tmp_path):
    """[gnss] speed_course: speed and course over ground (the true velocity
    with 0.05 m/s and 0.5 deg of noise, as stated) beside the position fixes:
    the readings are used (skipped below walking pace, where a course means
    nothing), their NIS is in band, and the run is as accurate against the
    truth."""
    import warnings

    from inskit import analysis, io
    from inskit.files import write_csv
    from inskit.jobs.config import config_from_dict
    from inskit.jobs.reproduce_tight import BLOCKAGE_NAVIGATE
    from inskit.jobs.simulate import write_simulation
    from inskit.simulation.scenario import load_scenario, simulate

    sc = load_scenario(Path(__file__).resolve().parents[1] / "examples" / "tc_blockage.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        write_simulation(simulate(sc, seed=4), tmp_path, plot=False)
    g = io.read_gnss(tmp_path / "gnss.csv")
    truth = io.read_solution(tmp_path / "truth.csv")
    rng = np.random.default_rng(1)
    v = truth.interpolate(g.time).v_n[:, :2]  # the true velocity at the fix times, then a receiver's noise
    speed = np.hypot(v[:, 0], v[:, 1]) + rng.normal(0, 0.05, len(g))
    course = np.degrees(np.arctan2(v[:, 1], v[:, 0])) + rng.normal(0, 0.5, len(g))
    write_csv(tmp_path / "sc.csv", {"time_s": g.time, "speed_m_s": np.abs(speed), "course_deg": course % 360.0,
                                    "sigma_speed_m_s": np.full(len(g), 0.05), "sigma_course_deg": np.full(len(g), 0.5)})
    rms = {}
    for name, extra in (("without", {}), ("with", {"speed_course": "sc.csv"})):
        d = {**BLOCKAGE_NAVIGATE, "gnss": {**BLOCKAGE_NAVIGATE["gnss"], **extra}}
        res = navigate(config_from_dict(d, base_dir=tmp_path, source=name))
        err = analysis.nav_error(res.forward.nav, truth)
        rms[name] = float(np.sqrt(np.mean(err.pos_ned[:, 0] ** 2 + err.pos_ned[:, 1] ** 2)))
        if name == "with":
            c = res.forward.counts["gnss_speed_course"]
            assert c["used"] > 250 and c["skipped"] > 30  # 389 readings outside the outages; the static minutes skipped
            h = summary(res)["health"]["measurements"]["gnss_speed_course"]
            assert h["rejected_fraction"] < 0.02 and 0.5 < h["mean_nis"] / h["dof"] < 1.5, h
    assert rms["with"] < 1.1 * rms["without"], rms


def test_imu_first_row_reaches_the_reader(tmp_path):
    """[imu] first_row (issue 14 item 11): an increment log that starts with a real increment is refused by
    default, naming the file and the key, and read with its initial epoch prepended under "increment"."""
    from inskit import io
    from inskit.errors import InputError
    from inskit.jobs.config import config_from_dict
    from inskit.jobs.navigate import load_inputs
    from inskit.simulation import StationaryTrajectory, ideal_imu
    from inskit.types import GnssData

    t = np.arange(0.0, 2.0 + 1e-9, 0.01)
    imu = ideal_imu(StationaryTrajectory((0.7, 0.1, 10.0)), t, nodes=1)
    cols = np.column_stack([t, imu.dtheta_b, imu.dv_b])[1:]  # the initial row left out
    np.savetxt(tmp_path / "imu.csv", cols, delimiter=",", comments="", fmt="%.17g",
               header="time_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_m_s,dv_y_m_s,dv_z_m_s")
    tg = np.arange(-0.5, 2.01, 0.5)  # from before the IMU: the run starts at its first sample
    io.write_gnss(tmp_path / "gnss.csv", GnssData(tg, np.tile([0.7, 0.1, 10.0], (len(tg), 1)), np.ones((len(tg), 3))))
    data = {"imu": {"file": "imu.csv"}, "gnss": {"file": "gnss.csv"}}
    with pytest.raises(InputError, match=r"imu\.csv: line 2 \(the first data row\) holds increments.*\[imu\] first_row"):
        load_inputs(config_from_dict(data, base_dir=tmp_path))
    data["imu"]["first_row"] = "increment"
    got, _ = load_inputs(config_from_dict(data, base_dir=tmp_path))
    assert len(got) == len(t) and got.time[0] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("smooth", [False, True], ids=["forward", "smoothed"])
def test_a_streamed_run_writes_the_same_files_and_summary(tmp_path, smooth):
    """[output] stream = "on" on the real drive (55 k epochs in segments of
    4096; smoothed: the node data on disk, the rows smoothed segment by
    segment): the solution files are those of the run that keeps every row,
    byte for byte in the CSV and value for value in the Parquet, and every
    summary figure is the same; the summary says the run was streamed and
    how many rows it kept; nothing is left under a temporary name."""
    import json

    import pyarrow.parquet as pq

    import inskit.integration.engine as E
    from inskit.jobs.navigate import write_outputs

    out = {}
    for mode in ("off", "on"):
        cfg = load_config(EXAMPLE, {"output": {"plots": False, "stream": mode}})
        seg = E.SEGMENT_ROWS
        try:
            E.SEGMENT_ROWS = 4096  # many segments on a short log (both runs: the same nodes)
            E.run_filter.__kwdefaults__["segment_rows"] = 4096
            res = navigate(cfg, stream_dir=tmp_path / mode, smooth=smooth)
        finally:
            E.SEGMENT_ROWS = seg
            E.run_filter.__kwdefaults__["segment_rows"] = seg
        s = summary(res)
        write_outputs(res, tmp_path / mode, s)
        out[mode] = (res, json.loads(json.dumps(s, default=float)))
    (r0, s0), (r1, s1) = out["off"], out["on"]
    assert r0.forward.rows is None and s0["streamed"] is False
    assert s1["streamed"] is True and 0 < s1["rows_kept"] < len(r1.imu) / 2  # 11 outages kept whole
    for k in ("elapsed_s", "files", "streamed", "rows_kept", "rows_kept_note"):
        s0.pop(k, None), s1.pop(k, None)
    assert s0 == s1
    for label in ("forward", "smoothed") if smooth else ("forward",):
        off, on = tmp_path / "off" / f"solution_{label}", tmp_path / "on" / f"solution_{label}"
        assert off.with_suffix(".csv").read_bytes() == on.with_suffix(".csv").read_bytes()
        a, b = (pq.read_table(p.with_suffix(".parquet")) for p in (off, on))
        assert a.equals(b) and a.schema.metadata == b.schema.metadata
    if smooth:
        assert s0["solution"] == "smoothed" and s0["outage_end_horizontal_rms_m"] < s0["forward"]["outage_end_horizontal_rms_m"]
    assert not list((tmp_path / "on").glob(".*"))  # no temporary file or scratch folder left


def test_a_streamed_run_that_cannot_write_leaves_nothing(tmp_path, monkeypatch):
    """The disk fills while the worker writes segment 3 of a streamed run: the
    error names the file, reaches the caller (here when the files are
    finished), and no solution file, whole or temporary, is left."""
    import inskit.integration.engine as E
    from inskit.errors import InputError
    from inskit.io import parquet as P
    from inskit.jobs.navigate import abort_streams, write_outputs

    calls = {"n": 0}
    real = P.SolutionStream.write

    def failing(self, sol, start):
        calls["n"] += 1
        if calls["n"] == 5:
            raise OSError(28, "No space left on device")
        return real(self, sol, start)

    def full(self, sol, start):
        try:
            return failing(self, sol, start)
        except OSError as exc:
            self.abort()
            raise InputError(f"{self.path}: could not be written ({exc.strerror})") from None

    monkeypatch.setattr(P.SolutionStream, "write", full)
    monkeypatch.setitem(E.run_filter.__kwdefaults__, "segment_rows", 4096)
    cfg = load_config(EXAMPLE, {"output": {"plots": False}})
    out = tmp_path / "out"
    try:
        res = navigate(cfg, stream_dir=out)
        write_outputs(res, out, summary(res))
        raise AssertionError("the write error was lost")
    except InputError as exc:
        assert "solution_forward" in str(exc) and "No space left" in str(exc)
        if "res" in locals():
            abort_streams(res)
    assert not [p for p in out.iterdir() if p.name.startswith((".part", "solution"))]


@pytest.mark.parametrize("section,fmt,other", [("gnss", "inskit", "rtklib-pos"), ("imu", "inskit", "rtklibexplorer")])
def test_a_file_of_another_format_than_configured_says_which(section, fmt, other):
    """[gnss] format defaults to "inskit": the bundled .pos given that way was refused as 'missing column(s)
    time_s ...' with no word of the format its header shows."""
    from inskit.errors import InputError
    from inskit.jobs.navigate import load_inputs

    cfg = load_config(EXAMPLE, {section: {"format": fmt, "mount_rpy_deg": [0.0, 0.0, 0.0]} if section == "imu"
                                else {"format": fmt}})
    with pytest.raises(InputError, match=rf"missing column.*; the file looks like the '{other}' format: set "
                                         rf"\[{section}\] format = \"{other}\" \(or --{section}-format {other}\)"):
        load_inputs(cfg)


def test_outages_that_leave_fewer_than_two_fixes_name_the_gnss_file():
    """It said 'fewer than two GNSS fixes are left to use': no file, no count (a one-row file, or windows
    covering every fix)."""
    from inskit.errors import InputError

    # every fix but the first (a window over the first fix is refused: the start-up takes its position from it)
    cfg = load_config(EXAMPLE, {"output": {"plots": False}, "outages": {"protocol": "windows",
                                                                         "windows_s": [[0.1, 1e6]]}})
    with pytest.raises(InputError, match=r"gnss_1934_sf\.pos\.gz: \d+ GNSS fix\(es\), 1 of them outside the "
                                         r"outages; the filter needs at least two"):
        navigate(cfg)


def test_repeated_imu_rows_are_reported_and_warned_of_when_kept(result):
    """The drive's 1138 re-read IMU rows (docs/formats.md): dropped by its config and said so in the
    summary; kept, the health verdict warns and names the key that drops them."""
    s = summary(result)
    rep = dict(s["imu_repeated_rows"])
    assert 0.0 < rep.pop("repeated_rows_longest_run_s") < 0.011  # each repeat alone, after a short interval
    assert rep == {"repeated_rows": 1138, "repeated_rows_fraction": pytest.approx(1138 / 54859),
                   "repeated_rows_dropped": True, "repeated_rows_longest_run": 1}
    assert not [r for r in s["health"]["reasons"] if r.startswith("IMU:")]  # no frozen output
    assert not [w for w in s["health"]["warnings"] if w.startswith("IMU:")]
    cfg = load_config(EXAMPLE, {"output": {"plots": False}, "imu": {"repeated_rows": "keep"}})
    said = []
    kept = summary(navigate(cfg, log=said.append))
    warn = [w for w in kept["health"]["warnings"] if w.startswith("IMU:")]
    assert len(warn) == 1 and "1138 rows (2.1%)" in warn[0] and 'repeated_rows = "drop"' in warn[0]
    assert any("1138 rows" in line and "kept as samples" in line for line in said)


def test_jittery_imu_time_tags_are_reported_and_warned_of_when_kept(result):
    """The drive's IMU time tags come from the logger's millisecond counter (8-11 ms intervals of a nominal
    10; docs/formats.md): its config smooths them over 11 rows and the summary says how far they moved; kept
    as logged, the health verdict warns and names the key."""
    s = summary(result)
    tags = s["imu_time_tags"]
    assert tags["time_smoothing_samples"] == 11
    assert 0.2 < tags["time_tag_jitter_fraction"] < 0.3  # 9 and 11 ms intervals: a quarter of them
    assert 0.0079 < tags["time_tag_interval_min_s"] < 0.0081 and 0.0109 < tags["time_tag_interval_max_s"] < 0.0112
    assert 0.5e-3 < tags["time_tags_moved_rms_s"] < 2e-3 and tags["time_tags_moved_max_s"] < 5e-3
    assert not [w for w in s["health"]["warnings"] if "time tags jitter" in w]
    cfg = load_config(EXAMPLE, {"output": {"plots": False}, "imu": {"time_smoothing_samples": 1}})
    kept = summary(navigate(cfg))
    warn = [w for w in kept["health"]["warnings"] if "time tags jitter" in w]
    assert len(warn) == 1 and "time_smoothing_samples = 11" in warn[0] and "25%" in warn[0]
    assert "time_tags_moved_rms_s" not in kept["imu_time_tags"]


def test_the_drives_smoothed_time_tags_move_no_more_than_their_jitter_explains(result):
    """No false alarm: drive_0708's tags, smoothed over 11 rows, move 0.6 ms RMS net of its 1138 rows left out
    (each spread over the window by under half an interval) for a jitter of 0.39 ms RMS, one rate all along."""
    tags = summary(result)["imu_time_tags"]
    assert tags["time_tags_beyond_jitter"] == [] and tags["time_tag_rate_changes"] == []
    assert 0.35e-3 < tags["time_tag_jitter_s"] < 0.45e-3
    assert tags["time_tags_moved_net_rms_s"] < 2 * tags["time_tag_jitter_s"]
    assert tags["time_tags_moved_net_max_s"] < 6 * tags["time_tag_jitter_s"]
    assert 4e-3 < tags["time_tags_left_out_spread_max_s"] < 5e-3
    assert not [w for w in summary(result)["health"]["warnings"] if "imu_time_tags." in w]


def test_a_window_too_long_for_the_drives_rows_left_out_is_warned_of():
    """51 rows (half a second) hold several of the drive's rows left out: the smoothing spreads them by 11 ms,
    over half an interval; the health verdict names the key, the time and row, and what to do."""
    cfg = load_config(EXAMPLE, {"output": {"plots": False}, "imu": {"time_smoothing_samples": 51}})
    s = summary(navigate(cfg))
    (found,) = s["imu_time_tags"]["time_tags_beyond_jitter"]
    assert found["key"] == "time_tags_left_out_spread_max_s" and found["value_s"] > 0.01
    warn = [w for w in s["health"]["warnings"] if "imu_time_tags." in w]
    assert len(warn) == 1 and "imu_time_tags.time_tags_left_out_spread_max_s" in warn[0]
    assert f"t = {found['t_s'] + 0.26:.3f} s (the file's time; row {found['row']}" in warn[0]
    assert "time_smoothing_samples = 5" in warn[0] and "or 1" in warn[0]


def test_the_time_tag_warning_names_a_drifting_clocks_key_time_and_row():
    from inskit.io.time_tags import smooth_time_tags
    from inskit.jobs.navigate import time_tags_warnings

    i = np.arange(6000)
    tau = 500.0 + 0.010 * i + 0.5 * 5e-8 * i**2  # the interval drifts 3 % over a minute
    tags = np.floor((tau + np.random.default_rng(1).uniform(0.0, 1.5e-3, len(i))) * 1e3) / 1e3
    for w, n_warn in ((11, 0), (1001, 2)):
        notes = {}
        smooth_time_tags("imu.csv", tags, w, info=notes)
        warn = time_tags_warnings(notes, time_offset_s=0.5)
        assert len(warn) == n_warn
    b = notes["time_tags_beyond_jitter"][1]
    assert "imu_time_tags.time_tags_moved_net_max_s" in warn[1] and "over 1001 rows" in warn[1]
    assert f"t = {b['t_s'] - 0.5:.3f} s (the file's time; row {b['row']} " in warn[1]
    assert "drift or jump of the clock" in warn[1] and "time_smoothing_samples = 5" in warn[1]


def test_bias_health_rule_counts_the_in_run_process_noise(drive_inputs):
    """The walk_0827_tight defect: a gyro bias fixed on a short static start
    wandered by its in-run sigma over the walk and was called unhealthy
    ("5.5 initial sigmas"), the in-run Gauss-Markov variation left out.  The
    rule now compares the excursion with the prior at the end of the run,
    sqrt(sigma0^2 + in-run variance accumulated): the same excursion is
    unhealthy with no in-run noise and healthy with enough of it."""
    import copy

    from inskit.integration.blocks import GyroBias
    from inskit.integration.layout import StateLayout
    from inskit.jobs.navigate import HEALTH_MAX_PRIOR_SIGMAS, health

    cfg, imu, gnss, clean = drive_inputs
    out = clean.forward
    bg = out.layout.by_role("gyro_bias")
    dev = np.abs(out.estimate(bg.name)[-1] - bg.estimate0)
    j = int(np.argmax(dev))
    T = float(out.nav.time[-1] - out.nav.time[0])

    def verdict(sigma0, sigma_ss, tau):
        block = GyroBias(sigma0=sigma0, instability=sigma_ss, tau_s=tau, estimate0=bg.estimate0)
        o = copy.copy(out)
        o.layout = StateLayout([block if b.name == bg.name else b for b in out.layout.blocks])
        assert np.isclose(block.prior_sigma(T)[j], np.sqrt(sigma0**2 + sigma_ss**2 * -np.expm1(-2 * T / tau)))
        return [r for r in health(o)["reasons"] if r.startswith(f"{bg.name}_{bg.axes[j]}")]

    small = dev[j] / (2 * HEALTH_MAX_PRIOR_SIGMAS)  # the excursion is 10 of these
    assert verdict(small, small * 1e-3, 300.0)  # no in-run noise to speak of: beyond the prior
    assert not verdict(small, 2 * dev[j], 300.0)  # an in-run sigma twice the excursion: within it


def test_prior_sigma_of_a_random_walk_and_a_gauss_markov_block():
    from inskit.integration.blocks import GyroBias

    gm = GyroBias(sigma0=1e-4, instability=3e-4, tau_s=100.0)
    assert np.allclose(gm.prior_sigma(0.0), 1e-4)
    assert np.allclose(gm.prior_sigma(1e4), np.hypot(1e-4, 3e-4))  # the steady state after many tau
    rw = GyroBias(sigma0=1e-4, instability=2e-5, tau_s=np.inf)  # instability: the random walk's root PSD
    assert np.allclose(rw.prior_sigma(400.0), np.sqrt(1e-8 + 4e-10 * 400.0))


def test_an_odometer_in_the_wrong_unit_is_refused_by_its_speed():
    """An odometer in km/h under an m/s header made the filter reject the
    GNSS (60 consecutive rejections, blamed on the fixes) and end 1.6 km off:
    its speed is checked against the track's first; a scale error of
    per cent is left to the scale-factor state."""
    from inskit import earth
    from inskit.errors import InputError
    from inskit.jobs.navigate import check_odometer_speed
    from inskit.types import GnssData

    t = np.arange(0.0, 120.0, 1.0)
    speed = np.where(t < 20.0, 0.0, 12.0)  # 20 s at rest, then 12 m/s north
    north = np.cumsum(speed)
    ref = np.array([np.radians(45.0), np.radians(7.0), 100.0])
    lla = earth.ned_to_lla(np.column_stack([north, 0 * t, 0 * t]), ref)
    gnss = GnssData(t, lla, np.full((len(t), 3), 0.02))
    to = np.arange(0.0, 120.0, 0.1)
    v = np.interp(to, t - 0.5, speed)
    check_odometer_speed("odo.csv", to, v * 1.03, gnss)  # 3 % scale: the filter's to estimate
    with pytest.raises(InputError, match=r"odo\.csv: the odometer speed is 3\.6 times .*km/h read as m/s"):
        check_odometer_speed("odo.csv", to, v * 3.6, gnss)
    with pytest.raises(InputError, match=r"2\.24 times .*mph"):
        check_odometer_speed("odo.csv", to, v * 2.237, gnss)


def test_an_odometer_that_reads_standing_still_while_the_track_moves_is_refused():
    """An odometer log of zeros (a dead sensor, a flag column read as the speed) passed the ratio test, which
    looks only where both the log and the track say the vehicle moves: `inskit navigate` with it lost the
    fixes over and over (gnss_pos 208 of 300 rejected, a 'fit' of 180 m) and searched an IMU time offset,
    never naming the log.  A log standing still over most of the track's motion is refused; a few stops of
    the wheels (a dropout) and the rest before the drive still pass."""
    from inskit import earth
    from inskit.errors import InputError
    from inskit.jobs.navigate import check_odometer_speed, check_speed_course
    from inskit.types import GnssData

    t = np.arange(0.0, 120.0, 1.0)
    speed = np.where(t < 20.0, 0.0, 12.0)  # 20 s at rest, then 12 m/s north
    ref = np.array([np.radians(45.0), np.radians(7.0), 100.0])
    lla = earth.ned_to_lla(np.column_stack([np.cumsum(speed), 0 * t, 0 * t]), ref)
    gnss = GnssData(t, lla, np.full((len(t), 3), 0.02))
    to = np.arange(0.0, 120.0, 0.1)
    v = np.interp(to, t - 0.5, speed)
    for bad, shown in ((0.0 * v, "0"), (v / 1000.0, "0.012")):  # zeros; km/s under the m/s header
        with pytest.raises(InputError, match=rf"odo\.csv: the odometer speed reads 1 m/s or less at \d+ of the \d+ "
                                             rf"moments the GNSS track moves faster than 2 m/s \(median 12 m/s "
                                             rf"against the log's {shown} m/s\).*a dead sensor"):
            check_odometer_speed("odo.csv", to, bad, gnss)
    with pytest.raises(InputError, match=r"sc\.csv: the speed over ground of the speed and course log reads"):
        check_speed_course("sc.csv", to, 0.0 * v, 0.0 * v, gnss)
    dropout = v.copy()
    dropout[(to > 50.0) & (to < 70.0)] = 0.0  # 20 s of 100 moving: kept for the filter to judge
    check_odometer_speed("odo.csv", to, dropout, gnss)


def test_an_odometer_whose_sign_is_backwards_is_refused():
    """An odometer log negative while driving forward (the other sign convention) passed the speed check, which
    takes magnitudes: `inskit navigate` lost the fixes every 16 s ('recovered from a lost state ... velocity
    error of 28 m/s') and never named the log.  Reversing a while (a quarter of the drive) still passes."""
    from inskit import earth
    from inskit.errors import InputError
    from inskit.jobs.navigate import check_odometer_speed
    from inskit.types import GnssData

    t = np.arange(0.0, 120.0, 1.0)
    speed = np.where(t < 20.0, 0.0, 12.0)
    lla = earth.ned_to_lla(np.column_stack([np.cumsum(speed), 0 * t, 0 * t]),
                           np.array([np.radians(45.0), np.radians(7.0), 100.0]))
    gnss = GnssData(t, lla, np.full((len(t), 3), 0.02))
    to = np.arange(0.0, 120.0, 0.1)
    v = np.interp(to, t - 0.5, speed)
    with pytest.raises(InputError, match=r"^odo\.csv: the odometer speed is negative \(reversing\) at \d+ of the \d+ "
                                         r"moments the vehicle moves: its sign is backwards\?"):
        check_odometer_speed("odo.csv", to, -v, gnss)
    some = np.where(to > 95.0, -v, v)  # the last quarter of the motion reversing
    check_odometer_speed("odo.csv", to, some, gnss)


def test_a_speed_and_course_log_in_the_wrong_units_is_refused_by_the_track():
    """Speed in km/h and course in radians under speed_m_s / course_deg went ahead to 1746 m and 13.7 km of outage
    error, blamed on the attitude: both are checked against the fixes' track (a drive north, then east, then
    north again: radians agree with the track while it heads north, so a quarter of the time is the test)."""
    from inskit import earth
    from inskit.errors import InputError
    from inskit.jobs.navigate import check_speed_course
    from inskit.types import GnssData

    t = np.arange(0.0, 300.0, 1.0)
    east = (t >= 100.0) & (t < 200.0)
    d = np.column_stack([np.where(east, 0.0, 12.0), np.where(east, 12.0, 0.0), 0 * t])
    ref = np.array([np.radians(45.0), np.radians(7.0), 100.0])
    gnss = GnssData(t, earth.ned_to_lla(np.cumsum(d, axis=0), ref), np.full((len(t), 3), 0.02))
    course = np.where(east, np.pi / 2, 0.0)
    speed = np.full(len(t), 12.0)
    check_speed_course("sc.csv", t, speed, course + np.radians(1.0), gnss)  # a good log, 1 deg off
    with pytest.raises(InputError, match=r"sc\.csv: the speed over ground of the speed and course log is 3\.6 times "
                                         r".*km/h read as m/s"):
        check_speed_course("sc.csv", t, speed * 3.6, course, gnss)
    with pytest.raises(InputError, match=r"sc\.csv: the course is 88\.\d deg or more from the GNSS track's course a "
                                         r"quarter of the time .*radians under the course_deg header"):
        check_speed_course("sc.csv", t, speed, np.radians(course), gnss)  # the reader's np.radians of radians


@pytest.mark.parametrize("windows", [[[100.0, 120.0], [120.5, 140.0]],    # 0.5 s apart, no fix between (touching
                                     # windows are refused when the config is loaded: test_jobs_config)
                                     [[130.0, 140.0], [100.0, 120.0], [120.5, 129.0]],  # unsorted, 0.5 s apart
                                     [[100.0, 120.0], [121.0, 140.0]]])   # 1 s apart: the fix at 121 s is withheld
def test_outage_windows_without_a_used_fix_between_are_refused(windows):
    """Windows 100-120 and 120-140 were scored as two outages: both took the
    truth figures of the one 40 s outage they make (end at 140.99 s), and
    the fix at 120 s was scored in each.  Two windows that withhold fixes
    need a used fix between them."""
    from inskit.errors import InputError
    from inskit.jobs.navigate import outage_windows
    from inskit.types import GnssData

    t = np.arange(1000.0, 1400.0, 1.0)
    gnss = GnssData(t, np.tile([0.7, 0.1, 100.0], (len(t), 1)), np.full((len(t), 3), 0.5))
    cfg = load_config(EXAMPLE, {"outages": {"protocol": "windows", "windows_s": windows}})
    with pytest.raises(InputError, match=r"outages: windows \[\d+(\.5)?, \d+\] and \[\d+(\.5)?, \d+\] s after the "
                                         r"first GNSS epoch leave no used fix between them .*merge them"):
        outage_windows(cfg, gnss)
    ok = load_config(EXAMPLE, {"outages": {"protocol": "windows", "windows_s": [[100.0, 120.0], [121.5, 140.0],
                                                                              [500.0, 600.0], [600.5, 700.0]]}})
    assert outage_windows(ok, gnss)[:2] == [(1100.0, 1120.0), (1121.5, 1140.0)]  # the fix at 121 s is used;
    # beyond the fixes the windows withhold nothing and are reported as not scored, not refused


@pytest.mark.parametrize("window", [[0.0, 70.0], [0.0, 10.0]])
def test_an_outage_window_withholding_the_first_fix_is_refused(window):
    """windows:0-70 on a car parked for 60 s started the INS at t = 0 from the fix at 71 s (position and 14 m/s of
    the moving car), scored 980 m and blamed the attitude; on drive_0708 windows:0-10 said 'start-up needs ... GNSS
    from the start; found 34.0 s'.  The start-up takes its position from the first fix: a window over it is
    refused, naming it; one starting after it is taken."""
    from inskit.errors import InputError
    from inskit.jobs.navigate import outage_windows
    from inskit.types import GnssData

    t = np.arange(1000.0, 1400.0, 1.0)
    gnss = GnssData(t, np.tile([0.7, 0.1, 100.0], (len(t), 1)), np.full((len(t), 3), 0.5))
    cfg = load_config(EXAMPLE, {"outages": {"protocol": "windows", "windows_s": [[200.0, 210.0], window]}})
    with pytest.raises(InputError, match=rf"^outages: window \[{window[0]:g}, {window[1]:g}\] s after the first GNSS "
                                         r"fix withholds the first fix, which the start-up takes the initial position "
                                         rf"from .* at {window[1]:g} s or later"):
        outage_windows(cfg, gnss)
    ok = load_config(EXAMPLE, {"outages": {"protocol": "windows", "windows_s": [[0.5, 10.0]]}})
    assert outage_windows(ok, gnss) == [(1000.5, 1010.0)]


def test_a_speed_course_log_outside_the_imu_span_is_refused(tmp_path):
    """A speed-and-course log on another time base gave 0 updates and a
    healthy run, as if it had been used; the odometer and height logs were
    refused already."""
    from inskit.errors import InputError
    from inskit.files import write_csv
    from inskit.jobs.navigate import speed_course_measurement
    from inskit.types import ImuData

    t = np.arange(10000.0, 10100.0, 1.0)
    write_csv(tmp_path / "sc.csv", {"time_s": t, "speed_m_s": np.full(len(t), 5.0), "course_deg": np.zeros(len(t)),
                                    "sigma_speed_m_s": np.full(len(t), 0.05), "sigma_course_deg": np.ones(len(t))})
    cfg = load_config(EXAMPLE, {"gnss": {"speed_course": str(tmp_path / "sc.csv")}})  # its time_offset_s: 0.001 s
    ti = np.arange(0.0, 200.0, 0.01)
    imu = ImuData(ti, np.zeros((len(ti), 3)), np.zeros((len(ti), 3)))
    with pytest.raises(InputError, match=r"sc\.csv: speed and course times 10000\.001\.\.10099\.001 s do not overlap "
                                         r"the IMU's 0\.000\.\.199\.990 s: mismatched time bases\? "
                                         r"\(gnss\.time_offset_s\)"):
        speed_course_measurement(cfg, [], np.zeros(3), imu)
    imu_on = ImuData(ti + 10050.0, imu.dtheta_b, imu.dv_b)
    assert speed_course_measurement(cfg, [], np.zeros(3), imu_on) is not None


@pytest.mark.parametrize("outages,first", [
    ({"protocol": "none"}, "outages: none (no GNSS fix withheld), so no outage table"),
    ({"protocol": "windows", "windows_s": [[9000.0, 9020.0]]},  # past the drive's last fix: withholds none
     "outages: none scored (1 window(s) withheld no GNSS fix: see the health warnings), so no outage table")])
def test_a_run_without_outages_prints_no_outage_table_header(drive_inputs, outages, first):
    """`inskit navigate --outages none` printed the outage table's two header
    lines over no row; now a line says there are no outages (or none scored)
    and the figures that do exist follow."""
    from inskit.jobs.navigate import outage_table_text

    _, imu, gnss, _ = drive_inputs
    cfg = load_config(EXAMPLE, {"output": {"plots": False}, "outages": outages})
    s = summary(navigate(cfg, inputs=(imu, gnss)))
    assert s["outage_table"] == []
    lines = outage_table_text(s).splitlines()
    assert lines[0] == first
    assert not [ln for ln in lines if "window [s after first fix]" in ln or "--- against the withheld" in ln], lines
    assert lines[1].startswith("fit to the used fixes") and lines[-1].startswith("updates: gnss_pos")


def test_aiding_warnings_name_the_log_and_why_it_made_no_update():
    """An aiding log that overlapped the IMU's span but made 0 updates was not in the health verdict: each
    cause is counted (withheld, outside the filtered span, too slow for a course, in an IMU gap, rejected)."""
    from inskit.integration import GnssSpeedCourse, Height, Odometer
    from inskit.jobs.navigate import aiding_warnings

    ti = np.arange(0.0, 100.0, 0.01)  # the filter runs over 0.01..99.99 s (from the second sample)
    t = np.arange(-5.0, 105.0, 1.0)   # 110 readings: 6 before 0.01 s, 5 after 99.99 s, 99 inside
    odo = Odometer(t, np.full(len(t), 3.0), 0.1)
    # speed and course: 11 withheld (20..30 s); 38 slower than 0.5 m/s (1..19, 31..49 s); 50 rejected (50..99 s)
    sc = GnssSpeedCourse(t, np.where(t < 50, 0.2, 3.0), np.zeros(len(t)), 0.05, 0.01, use=(t < 20) | (t > 30))
    hgt = Height(t, np.zeros(len(t)), 1.0)
    logs = [("odometer", Path("/d/odo.csv"), odo), ("speed and course", Path("/d/sc.csv"), sc),
            ("height", Path("/d/baro.csv"), hgt)]
    counts = {"odometer": {"used": 0, "rejected": 96, "skipped": 14},  # 11 outside, 3 in an IMU gap
              "gnss_speed_course": {"used": 0, "rejected": 50, "skipped": 11 + 38},
              "height": {"used": 7, "rejected": 0, "skipped": 11}}
    w = aiding_warnings(logs, counts, ti, "ekf")
    assert len(w) == 2, w  # the height log made 7 updates: no warning
    assert w[0] == ("/d/odo.csv: the odometer log made no update (of its 110 readings: 11 outside the span the "
                    "filter runs over, 0.010..99.990 s; 3 in gaps of the IMU log; 96 rejected by the innovation "
                    "gate (the filter found them inconsistent with the other measurements)): the run is as if it "
                    "had none")
    assert w[1] == ("/d/sc.csv: the speed and course log made no update (of its 110 readings: 11 withheld inside "
                    "the outage windows, like the fixes; 11 outside the span the filter runs over, 0.010..99.990 s; "
                    "38 slower than 0.5 m/s, below which a course means nothing "
                    "(gnss.speed_course_min_speed_m_s); 50 rejected by the innovation gate (the filter found them "
                    "inconsistent with the other measurements)): the run is as if it had none")
    # a scheme without a filter fuses no aiding at all
    w = aiding_warnings(logs[:1], {"gnss_pos": {"used": 9, "rejected": 0, "skipped": 0}}, ti, "uncoupled")
    assert w == ["/d/odo.csv: the odometer log made no update (of its 110 readings: the uncoupled scheme runs no "
                 "filter, so it fuses nothing but the fixes): the run is as if it had none"]


def test_the_columns_known_from_the_config_are_the_run_s(drive_inputs):
    """[output] columns is checked when the config is loaded against solution_column_names(cfg): they must be
    the columns the run's solution has (the drive: scale factors, mounting, the fixes' correlated error)."""
    from inskit.jobs.navigate import solution_column_names

    cfg, _, _, clean = drive_inputs
    names = solution_column_names(cfg)
    assert list(clean.forward.solution.columns()) == names
    assert {"sg_x", "mounting_yaw_rad", "gnss_err_n_m", "sigma_att_d_rad"} <= set(names)


def test_the_uncoupled_scheme_writes_its_solution_without_sigmas(drive_inputs, tmp_path):
    """[filter] scheme = "uncoupled" has no covariance: its sigma columns were NaN and the Parquet writer refused
    the whole solution ('refusing to write nan (column 'sigma_n_m', row 0)') after the run.  Now the solution
    files hold no sigma column, and every column they hold is finite."""
    import pyarrow.parquet as pq

    from inskit.jobs.navigate import write_outputs

    _, imu, gnss, _ = drive_inputs
    cfg = load_config(EXAMPLE, {"output": {"plots": True}, "filter": {"scheme": "uncoupled"},
                                # no GNSS error states: the uncoupled scheme has no filter (refused, would be ignored)
                                "gnss": {"error_sigma_m": None, "error_tau_s": 10.0, "sigma_scale_ned": [1.0, 1.0, 1.0]},
                                "constraints": {"mounting": False, "nhc": False, "zupt": False,
                                                # the example's NHC keys back at their defaults (with nhc = false
                                                # they would be ignored, and are refused)
                                                "nhc_sigma_m_s": 0.1, "nhc_lever_arm_b_m": [0.0, 0.0, 0.0]}})
    res = navigate(cfg, inputs=(imu, gnss))
    s = summary(res)
    files = write_outputs(res, tmp_path, s)
    t = pq.read_table(tmp_path / "solution_forward.parquet")
    assert not [c for c in t.column_names if c.startswith("sigma_")], t.column_names
    from inskit.jobs.navigate import solution_column_names

    assert sorted(t.column_names) == sorted(solution_column_names(cfg))  # what [output] columns is checked against
    assert {"lat_deg", "lon_deg", "height_m", "roll_deg"} <= set(t.column_names)
    assert all(np.isfinite(t.column(c).to_numpy()).all() for c in t.column_names)
    assert t.num_rows == len(res.forward.nav.time) and (tmp_path / "summary.json") in files
    head = (tmp_path / "solution_forward.csv").read_text().splitlines()[0]
    assert "sigma_" not in head and "nan" not in (tmp_path / "solution_forward.csv").read_text()[:20000]
    for name in ("track.png", "errors.png", "innovations.png", "biases.png"):  # the plots drew it too (they
        assert (tmp_path / name) in files and (tmp_path / name).stat().st_size > 5_000  # failed on the sigmas)


def test_a_run_whose_writing_fails_leaves_the_previous_run_as_it_was(drive_inputs, tmp_path, monkeypatch):
    """A --force rerun whose plots fail (or whose disk fills) after its solution files were written used to
    leave the new solution and innovations beside the old plots, under the old summary.json (which listed
    files of the other run), the previous run's files already removed.  Now the run's files land as a set:
    a failure leaves the folder byte for byte as the previous run left it; a run that completes replaces
    the set, and the files of the earlier run it did not write (its smoothed solution) go."""
    import json

    import inskit.jobs.plots as P
    from inskit.jobs.navigate import write_outputs

    cfg, imu, gnss, clean = drive_inputs
    out = tmp_path / "run"
    smoothed = navigate(cfg, inputs=(imu, gnss), smooth=True)
    write_outputs(smoothed, out, summary(smoothed))
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert "solution_smoothed.parquet" in before and "summary.json" in before

    def broken(res, out_dir, parallel=True):
        (Path(out_dir) / "track.png").write_bytes(b"half a figure")
        raise RuntimeError("matplotlib failed")

    monkeypatch.setattr(P, "plot_all", broken)
    cfg_plots = load_config(EXAMPLE, {"output": {"plots": True}})
    res = navigate(cfg_plots, inputs=(imu, gnss))
    with pytest.raises(RuntimeError, match="matplotlib failed"):
        write_outputs(res, out, summary(res), replace_previous=True)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # nothing new, nothing lost, no staging

    files = write_outputs(clean, out, summary(clean), replace_previous=True)  # plots off: completes
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(f.name for f in files) and "solution_smoothed.parquet" not in names
    assert json.loads((out / "summary.json").read_text())["files"] == [str(f) for f in files]


def test_the_yaw_bank_log_line_rounds_both_scores():
    """walk_0827's log said 'mean NIS per dof 0.85, next best 0.8485957923300557'."""
    from inskit.jobs.navigate import bank_line

    bank = {"scores": [0.85] * 12, "span_s": 40.0, "elapsed_s": 0.6, "chosen_yaw_deg": 169.9,
            "score": 0.8471, "runner_up_score": 0.8485957923300557}
    assert bank_line(bank).endswith("kept 169.9 deg (mean NIS per dof 0.847, next best 0.849)")
    assert bank_line({**bank, "runner_up_score": None}).endswith("next best none)")


def _walk_raw(strip_doppler=False, shift=None):
    """RawGnss of the bundled walk excerpt (40 epochs at 4 Hz), optionally
    without its Doppler or with a clock step added to every range from epoch
    ``shift[0]`` on (``shift[1]`` metres)."""
    import dataclasses

    from inskit.gnss.ranges import range_table
    from inskit.gnss.rinex import read_nav, read_obs
    from inskit.gnss.spp import spp
    from inskit.jobs.navigate import WEEK_S, RawGnss

    data = Path(__file__).resolve().parent / "data" / "gnss"
    obs = read_obs(data / "gnss_1730_first40.obs", systems=("G",))
    nav = read_nav(data / "gnss_1730.nav", systems=("G",))
    arrays = dict(obs.obs)
    if strip_doppler:
        arrays = {k: v for k, v in arrays.items() if not k.startswith("D")}
    if shift is not None:
        arrays = {k: (v.copy() if k[0] == "C" else v) for k, v in arrays.items()}
        for k in arrays:
            if k[0] == "C":
                arrays[k][shift[0]:] += shift[1]
    obs = dataclasses.replace(obs, obs=arrays)
    sol = spp(obs, nav, systems=("G",))
    table = range_table(obs, nav, rx_e=np.where(sol.solved[:, None], sol.r_e, np.nan), systems=("G",))
    week = int(np.floor(obs.time[0] / WEEK_S))
    return RawGnss(obs, nav, sol, table, week, week * WEEK_S)


def _walk_tight_cfg(tmp_path):
    from inskit.jobs.config import config_from_dict

    return config_from_dict({"imu": {"file": "imu.csv"}, "gnss": {"coupling": "tight", "obs": "o.obs",
                                                                  "nav": "n.nav", "systems": ["G"]}},
                            base_dir=tmp_path, source="walk")


def test_tight_clock_drift_without_doppler_comes_from_the_clock_slope(tmp_path):
    """Observations without Doppler: the receiver clock block started its
    drift at 0 +- 2 m/s, and a common TCXO's 1e-7 s/s (30 m/s; the walk's
    u-blox runs at -60 m/s) ran the bias away until every pseudorange was
    rejected (the simulated blockage drive without D1C: 750 of 751 updates
    rejected, 54 m horizontal RMS).  The drift now comes from the slope of the
    single-point clock bias, within a few m/s of the Doppler's."""
    from inskit.jobs.navigate import clock_blocks
    from inskit.types import NavState

    cfg = _walk_tight_cfg(tmp_path)
    with_d, without = _walk_raw(), _walk_raw(strip_doppler=True)
    assert not np.isfinite(without.table.range_rate_m_s).any()
    e0 = int(np.flatnonzero(with_d.spp.solved)[0])
    lla = np.asarray(with_d.spp.lla[e0], float)
    init = NavState(float(with_d.spp.time[e0] - with_d.offset_s), lla, np.zeros(3), np.array([1.0, 0, 0, 0]))
    use = np.ones(len(with_d.table.time), bool)
    _, ref = clock_blocks(cfg, with_d, init, np.zeros(3), use)
    _, got = clock_blocks(cfg, without, init, np.zeros(3), np.ones(len(without.table.time), bool))
    assert ref["drift_from"] == "Doppler" and ref["drift_m_s"] < -50.0
    assert got["drift_from"].startswith("single-point clock bias slope")
    assert abs(got["drift_m_s"] - ref["drift_m_s"]) < got["sigma_drift_m_s"]


def _step_codes(src, dst, first_epoch, step_m):
    """Copy of a RINEX 3 observation file with ``step_m`` added to every code
    (C..) field from epoch ``first_epoch`` (0-based) on: a receiver clock reset."""
    lines = Path(src).read_text().split("\n")
    types = {}
    for line in lines:
        if line[60:].strip() == "SYS / # / OBS TYPES":
            types[line[0]] = line[7:60].split()
    out, epoch, body = [], -1, False
    for line in lines:
        if body and line.startswith(">"):
            epoch += 1
        elif body and epoch >= first_epoch and line[:1] in types:
            for k, code in enumerate(types[line[0]]):
                a = 3 + 16 * k
                if code[0] == "C" and line[a:a + 14].strip():
                    line = line[:a] + f"{float(line[a:a + 14]) + step_m:14.3f}" + line[a + 14:]
        body = body or "END OF HEADER" in line
        out.append(line)
    Path(dst).write_text("\n".join(out))


def test_a_receiver_clock_reset_is_taken_out_of_the_ranges(tmp_path):
    """A 1 ms receiver clock reset (every pseudorange of an epoch steps by
    299.8 km): the tight filter's clock state ran on by its drift, rejected
    every later range and stopped with 'covariance lost positiveness ... the
    filter diverged (check sensor noise settings and the initial state)' (the
    simulated blockage drive with a reset at epoch 300).  The reset is now
    found in the single-point clock, taken out of the ranges and named."""
    from inskit.gnss.spp import receiver_clock_jumps
    from inskit.jobs.config import config_from_dict
    from inskit.jobs.navigate import load_raw_gnss

    data = Path(__file__).resolve().parent / "data" / "gnss"
    _step_codes(data / "gnss_1730_first40.obs", tmp_path / "o.obs", 20, 299792.458)
    cfg = config_from_dict({"imu": {"file": "imu.csv"},
                            "gnss": {"coupling": "tight", "obs": "o.obs", "nav": str(data / "gnss_1730.nav"),
                                     "systems": ["G"]}}, base_dir=tmp_path, source="walk")
    logged = []
    raw = load_raw_gnss(cfg, log=logged.append)
    assert raw.clock_jumps == ((20, 299792.458),)
    assert any("+1.000 ms" in n and "o.obs" in n for n in raw.notes)
    assert any("+1.000 ms" in m for m in logged)
    # what the filter sees: one continuous clock, as in the file without the reset (to the metres the
    # edited file's transmit times, 1 ms early for an unchanged reception, move the satellites)
    clean = _walk_raw()
    np.testing.assert_allclose(raw.table.pseudorange_m, clean.table.pseudorange_m, atol=0.01)
    ok = raw.spp.solved
    np.testing.assert_allclose(raw.spp.clock_m[ok, 0], clean.spp.clock_m[ok, 0], atol=5.0)
    assert len(receiver_clock_jumps(clean.spp)[0]) == 0


def test_tight_coupling_says_what_the_readers_and_the_single_point_solution_found(tmp_path):
    """The command line silences library warnings, so a tightly coupled run
    said nothing of the navigation records of other systems it skipped (the
    bundled walk: 8 BeiDou, 5 SBAS) nor of the epochs single-point positioning
    could not solve; now they are logged and listed in ``raw.notes``."""
    import warnings

    from inskit.jobs.config import config_from_dict
    from inskit.jobs.navigate import load_raw_gnss

    data = Path(__file__).resolve().parent / "data" / "gnss"
    cfg = config_from_dict({"imu": {"file": "imu.csv"},
                            "gnss": {"coupling": "tight", "obs": str(data / "gnss_1730_first40.obs"),
                                     "nav": str(data / "gnss_1730.nav"), "systems": ["G"]}},
                           base_dir=tmp_path, source="walk")
    logged = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # as the command line runs
        raw = load_raw_gnss(cfg, log=logged.append)
    skipped = [n for n in raw.notes if "skipped" in n and "BeiDou" in n and "SBAS" in n]
    assert skipped and skipped[0].startswith(str(data / "gnss_1730.nav"))
    assert any(skipped[0] in m for m in logged)
    assert not raw.warnings  # a note, not a health warning: nothing is wrong with the run


def test_a_constraint_refused_in_most_updates_is_named_as_not_holding():
    """The 8 h ship with the default non-holonomic constraint (a land vehicle's) was lost from its first seconds:
    its verdict said only 'nhc: 25395 of 26099 updates rejected (97%)'.  Now the reason says the constraint does
    not hold for the vehicle and how to turn it off; a few refusals keep the plain wording."""
    from types import SimpleNamespace

    from inskit.jobs.navigate import health

    def out(used, rejected):
        acc = np.r_[np.ones(used, bool), np.zeros(rejected, bool)]
        inn = {"t": np.arange(len(acc), dtype=float), "nis": np.ones(len(acc)), "accepted": acc,
               "dof": np.full(len(acc), 2.0)}
        return SimpleNamespace(counts={"nhc": {"used": used, "rejected": rejected, "skipped": 0}},
                               innovations={"nhc": inn}, layout=SimpleNamespace(blocks=[]), recoveries=[])

    r = health(out(705, 25395))["reasons"]
    assert any(x.startswith("nhc: 25395 of 26100 updates rejected (97%): the non-holonomic constraint, a land "
                            "vehicle's, does not hold") and "nhc = false" in x for x in r), r
    r = health(out(90, 10))["reasons"]
    assert "nhc: 10 of 100 updates rejected (10%)" in r, r


@pytest.fixture(scope="module")
def ship_files(tmp_path_factory):
    """Five minutes of examples/ship.toml (navigation grade, heave 1 m at 8 s) as files."""
    from inskit.jobs.simulate import write_simulation
    from inskit.simulation.scenario import load_scenario, simulate

    d = tmp_path_factory.mktemp("ship")
    sc = load_scenario(Path(__file__).resolve().parents[1] / "examples" / "ship.toml")
    sc = sc.model_copy(update={"duration_limit_s": 300.0})
    write_simulation(simulate(sc, seed=0), d, plot=False)
    return d


def test_a_fast_imu_log_in_milliseconds_is_refused_against_the_fixes_span(ship_files, tmp_path):
    """A 1 kHz rate log stamped in ms steps by exactly 1 "s": the reader's step check lets 1 Hz through (Allan
    logs), and navigate ran it as a 1 Hz IMU 100 times longer than the fixes, ten 'recovered from a lost state'
    warnings and an unhealthy verdict that never named the time unit.  Against the fixes' span it is refused."""
    from inskit.errors import InputError
    from inskit.jobs.config import config_from_dict
    from inskit.jobs.navigate import load_inputs

    t = np.arange(0.0, 6001.0)  # 6 s at 1 kHz, in ms: 20 times the fixes' 300 s
    head = "time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n"
    rows = np.column_stack([t, np.zeros((len(t), 5)), np.full(len(t), -9.8)])
    (tmp_path / "imu_ms.csv").write_text(head + "\n".join(",".join(f"{x:g}" for x in r) for r in rows) + "\n")
    cfg = config_from_dict({"imu": {"file": str(tmp_path / "imu_ms.csv")}, "gnss": {"file": str(ship_files / "gnss.csv")},
                            "output": {"dir": str(tmp_path / "out"), "plots": False}})
    with pytest.raises(InputError, match=r"^imu_ms\.csv: the IMU steps by 1 s \(median\) and spans 6000 s, 20 times "
                                         r"the fixes' 300 s \(gnss\.csv\): is its time column in milliseconds"):
        load_inputs(cfg)


def test_the_default_constraint_is_dropped_when_it_does_not_hold(ship_files):
    """A ship navigated with the default settings kept the land vehicle's non-holonomic constraint, took its
    heave for a pitch error and was lost from its sixth second (an 8 h log stopped hours later 'within 0.1 deg
    of a pole'; a helper traced it).  The job now runs again without the constraint when it was on by default
    and refused in most of its updates, and says so; a constraint the user set is kept, and named by the
    verdict."""
    from inskit.jobs.config import config_from_dict
    from inskit.jobs.navigate import run

    data = {"imu": {"file": str(ship_files / "imu.csv")},
            "gnss": {"file": str(ship_files / "gnss.csv"), "lever_arm_b_m": [-20.0, 0.0, -15.0]},
            "output": {"plots": False}}
    logs = []
    res = run(config_from_dict(data), log=logs.append)
    s = summary(res)
    assert s["constraint_check"]["nhc"] == "dropped" and res.config.constraints.nhc is False
    assert s["health"]["verdict"] == "healthy", s["health"]["reasons"]
    assert s["fit_to_used_fixes_h_rms_m"] < 3.0  # 1.5 m white fixes, every one used
    assert res.forward.counts["gnss_pos"]["rejected"] == 0
    assert any("does not hold for this vehicle" in x and "navigating again without it" in x for x in logs), logs
    kept = run(config_from_dict({**data, "constraints": {"nhc": True}}))  # the user's own choice stands
    k = summary(kept)
    assert "constraint_check" not in k and kept.config.constraints.nhc is True
    assert k["health"]["verdict"] == "unhealthy"
    assert any("the non-holonomic constraint, a land vehicle's, does not hold" in x for x in k["health"]["reasons"])


def test_a_pos_file_of_geodetic_heights_is_said(tmp_path):
    """A .pos whose header says its heights are geodetic (above the geoid) was fused as ellipsoidal without a word
    (a helper noticed it): a health warning now names the file and [gnss] height_offset_m; with the offset set,
    nothing is said."""
    import gzip

    src = Path(__file__).resolve().parents[1] / "data" / "drive_0708" / "gnss_1934_sf.pos.gz"
    p = tmp_path / "geodetic.pos"
    p.write_text("% (lat/lon/height=WGS84/geodetic,Q=1:fix,2:float,3:sbas,4:dgps,5:single,6:ppp)\n"
                 + gzip.decompress(src.read_bytes()).decode())
    over = {"output": {"plots": False}, "gnss": {"file": str(p)}, "outages": {"protocol": "none"}}
    s = summary(navigate(load_config(EXAMPLE, over)))
    w = [x for x in s["health"]["warnings"] if "geodetic" in x]
    assert len(w) == 1 and "geodetic.pos" in w[0] and "height_offset_m" in w[0], s["health"]["warnings"]
    over["gnss"]["height_offset_m"] = 0.001
    s = summary(navigate(load_config(EXAMPLE, over)))
    assert not [x for x in s["health"]["warnings"] if "geodetic" in x]


def test_innovation_file_is_written_in_blocks_and_quoted_when_a_label_needs_it(tmp_path, monkeypatch):
    """innovations.csv is made a block of updates at a time (an 8 h run's
    0.6 M lines never whole): blocks of 3 updates give the file of one
    block; a ragged measurement (rows per update vary) keeps its rows; a
    label with a comma sends the table to the quoting writer."""
    import pandas as pd

    import inskit.jobs.navigate as N

    inn = {"gnss_pos": {"t": np.arange(7.0), "nu": np.arange(21.0).reshape(7, 3) * 0.1,
                        "sigma": np.full((7, 3), 0.5), "nis": np.arange(7.0), "accepted": np.arange(7) != 3,
                        "dof": np.full(7, 3)},
           "pr": {"t": np.array([1.0, 2.0, 3.0]), "nu": np.array([np.zeros(2), np.ones(3), np.ones(1)], dtype=object),
                  "sigma": np.array([np.ones(2), np.ones(3), np.ones(1)], dtype=object), "nis": np.ones(3),
                  "accepted": np.ones(3, bool), "dof": np.array([2, 3, 1]),
                  "status": np.array([0, 0, 0, 0, 1, 0], np.int8),
                  "label": np.array(["G01", "G02", "G01", "G02", "G07", "G01"], dtype=object)},
           "empty": {"t": np.zeros(0)}}
    whole = N.write_innovations(inn, tmp_path / "whole.csv").read_bytes()
    monkeypatch.setattr(N, "INNOVATION_BLOCK_UPDATES", 3)
    assert N.write_innovations(inn, tmp_path / "blocks.csv").read_bytes() == whole
    df = pd.read_csv(tmp_path / "blocks.csv", keep_default_na=False)
    assert len(df) == 21 + 6
    g = df[df.measurement == "gnss_pos"]
    assert g.label.tolist()[:3] == ["north", "east", "down"] and g.row.tolist()[:4] == [0, 1, 2, 0]
    assert (g.status[g.t == 3] == "refused_update_gate").all() and g.accepted.sum() == 18
    pr = df[df.measurement == "pr"]
    assert pr.row.tolist() == [0, 1, 0, 1, 2, 0] and pr.label.tolist() == ["G01", "G02", "G01", "G02", "G07", "G01"]
    assert pr.status.tolist()[4] == "refused_row_gate"
    inn["pr"]["label"] = np.array(["G01", "a,b", "G01", "G02", "G07", "G01"], dtype=object)
    q = pd.read_csv(N.write_innovations(inn, tmp_path / "q.csv"), keep_default_na=False)
    assert q[q.measurement == "pr"].label.tolist()[1] == "a,b" and len(q) == 27


def test_a_streamed_run_keeps_a_grid_of_bounded_rows():
    """The kept rows' regular grid is [output] rate_hz on a short log and at
    most KEPT_GRID_ROWS rows on a long one (8 h at 10 Hz: 50 000 rows, not
    288 000); the rows around each fix stay whatever the length."""
    from inskit.jobs.config import KEPT_GRID_ROWS
    from inskit.jobs.navigate import kept_grid_rate, stream_keep_rows
    from inskit.types import GnssData

    assert kept_grid_rate(np.arange(0.0, 600.0, 0.01), 10.0) == 10.0
    t = np.arange(0.0, 28800.0, 0.05)
    assert kept_grid_rate(t, 10.0) == pytest.approx(KEPT_GRID_ROWS / t[-1])
    g = GnssData(np.arange(0.5, 28800.0, 30.0), np.zeros((960, 3)), np.ones((960, 3)))
    rows = stream_keep_rows(t, g, [], 10.0)
    assert KEPT_GRID_ROWS <= len(rows) <= KEPT_GRID_ROWS + 2 * len(g) + 2
    k = np.searchsorted(t, g.time, side="right") - 1
    assert np.isin(k, rows).all() and np.isin(k + 1, rows).all()


def test_tight_innovation_file_says_per_satellite_row_what_the_gate_did(tmp_path):
    """A simulated tight run with one satellite's pseudoranges 60 m off for
    20 epochs: innovations.csv recorded the refused satellite's rows as
    accepted (the update went on with the others); now each row says
    ``accepted`` or ``refused_row_gate`` and names its satellite, and the
    file's counts are the summary's."""
    import dataclasses
    import warnings

    import pandas as pd

    from inskit.jobs import reproduce_tight as RT
    from inskit.jobs.config import config_from_dict
    from inskit.jobs.navigate import load_inputs, load_raw_gnss, spp_fixes, write_innovations
    from inskit.jobs.simulate import write_simulation
    from inskit.simulation.scenario import load_scenario, simulate

    sc = load_scenario(Path(__file__).resolve().parents[1] / "examples" / "tc_blockage.toml")
    sc = sc.model_copy(update={"duration_limit_s": 140.0})  # before the first blockage
    write_simulation(simulate(sc, 1), tmp_path, overwrite=True, plot=False)
    base = {k: (dict(v) if isinstance(v, dict) else v) for k, v in RT.BLOCKAGE_NAVIGATE.items()}
    base["earth"] = {"gravity": sc.earth.gravity}
    base["gnss"] = {**base["gnss"], "coupling": "tight", "obs": "obs.rnx", "nav": "nav.rnx", "systems": ["G"]}
    cfg = config_from_dict(base, base_dir=tmp_path, source="tight test")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        raw = load_raw_gnss(cfg)
        imu, _ = load_inputs(cfg, None, raw)
        tab = raw.table
        sats = np.asarray(tab.sat).astype(str)
        bad_sat = sats[0]
        t_ep = np.unique(tab.time)
        bad_t = t_ep[80:100]
        bad = (sats == bad_sat) & np.isin(tab.time, bad_t)
        raw = dataclasses.replace(raw, table=dataclasses.replace(tab, pseudorange_m=np.where(
            bad, tab.pseudorange_m + 60.0, tab.pseudorange_m)))
        res = navigate(cfg, inputs=(imu, spp_fixes(raw), raw))
    s = summary(res)
    df = pd.read_csv(write_innovations(res.forward.innovations, tmp_path / "innovations.csv"))
    assert list(df.columns) == ["measurement", "t", "row", "label", "nu", "sigma", "nis", "accepted", "status"]
    pr = df[df.measurement == "pseudorange"]
    c = s["measurements"]["pseudorange"]
    refused = pr[pr.status == "refused_row_gate"]
    assert len(refused) == c["rows_rejected"] >= 15 and len(pr) == c["rows"]
    inn = res.forward.innovations["pseudorange"]  # each NIS's degrees of freedom: the rows it used
    k_used = pr.groupby("t", sort=False).status.apply(lambda x: int((x != "refused_row_gate").sum())).to_numpy()
    assert inn["nis_dof"].tolist() == k_used.tolist() and inn["nis_dof"].sum() == c["rows"] - c["rows_rejected"]
    assert (pr.accepted == (pr.status == "accepted")).all()
    assert pr.groupby("t").accepted.min().eq(0).sum() == c["rejected"]
    assert pr.groupby("t").accepted.max().eq(1).sum() == c["used"]
    # the refusals are the bad satellite's, in its bad epochs (a time offset puts the IMU on the RINEX time)
    t_raw = refused.t.to_numpy() + raw.offset_s
    assert set(refused.label) == {bad_sat}
    assert np.isin(np.round(t_raw, 3), np.round(bad_t, 3)).all()
    # its companions in those epochs were used
    both = pr[np.isin(np.round(pr.t.to_numpy() + raw.offset_s, 3), np.round(bad_t, 3))]
    assert (both[both.label != bad_sat].status == "accepted").all()
    assert (both[both.label == bad_sat].status == "refused_row_gate").sum() >= 15
    assert set(pr.label) <= set(sats)
    assert (df[df.measurement == "nhc"].label.isin(["lateral (body y)", "vertical (body z)"])).all()


def test_time_unit_hint_speaks_only_for_spans_a_thousand_times_apart():
    from inskit.jobs.navigate import time_unit_hint

    imu = np.arange(0.0, 600.0, 0.01)
    assert time_unit_hint(np.arange(0.0, 600.0), imu) == ""
    assert time_unit_hint(np.arange(0.0, 7200.0), imu) == ""  # fixes logged longer than the IMU: no unit
    assert "is the fixes' time column in milliseconds" in time_unit_hint(np.arange(0.0, 600.0) * 1000.0, imu)
    assert "is the IMU log's time column in milliseconds" in time_unit_hint(np.arange(0.0, 600.0), imu * 1000.0)
    assert time_unit_hint(np.array([5.0]), imu) == ""  # one fix: no span


TILT_CAR = short_car("tilted car", [{"type": "static", "duration_s": 30.0},
                                    {"type": "accelerate", "speed_m_s": 15.0, "duration_s": 8.0},
                                    {"type": "turn", "angle_deg": 90.0, "radius_m": 30.0},
                                    {"type": "cruise", "duration_s": 20.0},
                                    {"type": "turn", "angle_deg": -90.0, "radius_m": 30.0},
                                    {"type": "cruise", "duration_s": 30.0}])


@pytest.fixture(scope="module")
def tilted_start(tmp_path_factory):
    """The short car above, navigated from a given start 10 deg off in roll
    and -8 deg in pitch (sigma 0.5 deg) with the default constraints."""
    import warnings

    from inskit.jobs import navigate as N
    from inskit.jobs.config import config_from_dict
    from inskit.jobs.simulate import write_simulation
    from inskit.simulation.scenario import Scenario, simulate

    d = tmp_path_factory.mktemp("tilt")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        write_simulation(simulate(Scenario.model_validate(TILT_CAR), seed=3), d, plot=False, overwrite=True)
    cfg = config_from_dict({"name": "tilted", "imu": {"file": "imu.csv"},
                            "gnss": {"file": "gnss.csv", "lever_arm_b_m": [0.0, 0.0, -1.2]},
                            "init": {"mode": "given", "lat_deg": 40.0966, "lon_deg": -105.1474, "height_m": 1600.0,
                                     "rpy_deg": [10.0, -8.0, 0.0], "sigma_roll_pitch_deg": 0.5},
                            "truth": {"file": "truth.csv"}, "output": {"plots": False}}, base_dir=d, source=str(d))
    logs = []
    res = N.run(cfg, log=logs.append)
    return res, summary(res), logs


def test_a_tilt_lost_run_recovers_and_says_so(tilted_start):
    """Started with a wrong roll and pitch, the filter refused every fix and
    the GNSS recovery never fired: the run ended kilometres off.  Now it
    is re-initialised on the fixes 15 s after the first refusal, and the
    log, the verdict and the summary's ``recoveries`` say so, with how far
    the filter had drifted and the tilt that drift showed."""
    import json

    res, s, logs = tilted_start
    rec = [r for r in s["recoveries"] if r["measurement"] == "gnss_pos"]
    assert len(rec) == 1 and rec[0]["fixes_position"] and rec[0]["reinitialised"], s["recoveries"]
    assert 7.0 < rec[0]["tilt_deg"] < 20.0 and rec[0]["position_offset_m"] > 100.0, rec
    assert "tilt_rad" not in rec[0]
    assert any(w.startswith("warning: gnss_pos: recovered from a lost state at t = ")
               and "a tilt error of about" in w and "re-initialised on it" in w for w in logs), logs
    h = s["health"]
    assert any(x.startswith("gnss_pos: recovered from a lost state") and "a tilt error of about" in x
               for x in h["reasons"]), h["reasons"]
    assert h["measurements"]["gnss_pos"]["rejected_fraction"] < 0.2
    assert s["truth_errors"]["forward"]["horizontal_m"]["final"] < 2.0
    json.dumps(s["recoveries"], allow_nan=False)  # plain JSON: no NaN, no numpy scalars


def test_a_yaw_mounting_the_start_up_measured_is_said_when_the_filter_does_not_model_it():
    """An IMU yawed 4 deg against the vehicle ran 'healthy' with 36 m of outage error against 7.5 m (the filter's
    mounting check cannot see a yaw: the NHC has already turned the solution to it), while the start-up had
    measured the direction of travel 4.62 +- 0.66 deg off the x axis and left it (its own check acts beyond
    20 deg).  Said now, when the NHC runs without mounting states; not for 0.60 +- 0.65 deg, nor with them."""
    from types import SimpleNamespace

    from inskit.jobs.navigate import unmodelled_yaw_warning

    cfg = load_config(EXAMPLE, {"constraints": {"mounting": False}})
    off = {"travel_yaw_deg": 4.62, "travel_yaw_se_deg": 0.66, "rotated": False, "differ": False}
    plain, modelled = SimpleNamespace(layout=set()), SimpleNamespace(layout={"mounting"})
    w = unmodelled_yaw_warning(off, plain, cfg)
    assert w.startswith("the start-up measured the direction of travel +4.62 deg (+-0.66) off the IMU's x axis")
    assert "mounting = true" in w and "+4.6 deg to the yaw of [imu] mount_rpy_deg" in w
    assert unmodelled_yaw_warning({**off, "travel_yaw_deg": 0.60, "travel_yaw_se_deg": 0.65}, plain, cfg) is None
    assert unmodelled_yaw_warning(off, modelled, cfg) is None
    assert unmodelled_yaw_warning(off, plain, load_config(EXAMPLE, {"constraints": {
        "mounting": False, "nhc": False, "nhc_sigma_m_s": 0.1, "nhc_lever_arm_b_m": [0.0, 0.0, 0.0]}})) is None


def test_an_aiding_log_taken_while_the_fixes_are_refused_is_named_in_the_verdict():
    """An odometer 0.5 s late was taken in 5995 of 5996 updates while 72 % of the fixes were refused; the verdict
    blamed the attitude, a constraint or the mounting, never the odometer.  Such a log is named now; a healthy
    GNSS, or an aiding log itself refused, names none."""
    from inskit.jobs.navigate import aiding_suspects

    per = {"gnss_pos": {"updates": 600, "rejected_fraction": 0.72},
           "odometer": {"updates": 5996, "rejected_fraction": 1 / 5996},
           "height": {"updates": 600, "rejected_fraction": 0.4}}
    said = aiding_suspects(per)
    assert len(said) == 1 and said[0].startswith("odometer: the odometer log was taken in 100% of its 5996 updates "
                                                 "while 72% of the GNSS updates were refused")
    assert aiding_suspects({**per, "gnss_pos": {"updates": 600, "rejected_fraction": 0.01}}) == []


def test_an_odometer_log_that_lags_is_measured_and_said(tmp_path):
    """A simulated car's wheel speed (0.5 % scale error, 0.05 m/s noise) with
    its time tags 0.3 s late, fixes at 1 Hz with a receiver velocity of
    0.05 m/s: the summary's odometer_lag finds 0.30 s within 0.03 s, the
    lag far beyond chance (F above 25), the warning gives the
    time_offset_s that puts it right, and that offset leaves nothing to
    say."""
    import warnings

    from inskit import io
    from inskit.files import write_csv
    from inskit.jobs.config import config_from_dict
    from inskit.jobs.navigate import navigate
    from inskit.jobs.reproduce_tight import BLOCKAGE_NAVIGATE
    from inskit.jobs.simulate import write_simulation
    from inskit.simulation.odometer import simulate_odometer
    from inskit.simulation.scenario import Scenario, simulate

    car = short_car("lag car", [{"type": "static", "duration_s": 20.0},
                                {"type": "accelerate", "speed_m_s": 15.0, "duration_s": 8.0},
                                {"type": "turn", "angle_deg": 90.0, "radius_m": 40.0},
                                {"type": "decelerate", "speed_m_s": 5.0, "duration_s": 6.0},
                                {"type": "accelerate", "speed_m_s": 14.0, "duration_s": 6.0},
                                {"type": "cruise", "duration_s": 10.0},
                                {"type": "decelerate", "speed_m_s": 4.0, "duration_s": 6.0},
                                {"type": "accelerate", "speed_m_s": 12.0, "duration_s": 6.0}])
    car["gnss"]["velocity_sigma_m_s"] = 0.05  # a receiver's Doppler velocity: the track speed to 0.05 m/s
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        write_simulation(simulate(Scenario.model_validate(car), seed=4), tmp_path, plot=False)
    truth = io.read_solution(tmp_path / "truth.csv")
    log = simulate_odometer(truth, rate_hz=10.0, scale_error=0.005, noise_m_s=0.05, rng=np.random.default_rng(8))
    write_csv(tmp_path / "odo_late.csv", {"time_s": log.time + 0.3, "speed_m_s": log.speed_m_s})

    def run(offset):
        cfg = config_from_dict({**BLOCKAGE_NAVIGATE, "odometer": {"file": "odo_late.csv", "time_offset_s": offset}},
                               base_dir=tmp_path, source="lag car")
        return summary(navigate(cfg))

    s = run(0.0)
    lag = s["odometer_lag"]
    assert lag["lag_s"] == pytest.approx(0.3, abs=0.03) and lag["f_statistic"] > 25 and lag["time_offset_s"] == 0.0, lag
    warn = [w for w in s["health"]["warnings"] if w.startswith("odometer: odo_late.csv: its speeds fit")]
    assert len(warn) == 1 and "late" in warn[0] and f"time_offset_s = {-lag['lag_s']:.2f}" in warn[0], warn
    s = run(-0.3)
    assert abs(s["odometer_lag"]["lag_s"]) <= 0.03 and not [w for w in s["health"]["warnings"] if "speeds fit" in w]


def _simulated(segments, seed=4):
    """A :func:`short_car` driving ``segments`` with a receiver velocity of
    0.05 m/s, simulated (warnings silenced)."""
    import warnings

    from inskit.simulation.scenario import Scenario, simulate

    car = short_car("lag check", segments)
    car["gnss"]["velocity_sigma_m_s"] = 0.05
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return simulate(Scenario.model_validate(car), seed=seed)


#: a short drive that speeds up, turns and slows down: what shows an odometer's lag
LAG_CAR = [{"type": "static", "duration_s": 20.0},
           {"type": "accelerate", "speed_m_s": 15.0, "duration_s": 8.0},
           {"type": "turn", "angle_deg": 90.0, "radius_m": 40.0},
           {"type": "decelerate", "speed_m_s": 5.0, "duration_s": 6.0},
           {"type": "accelerate", "speed_m_s": 14.0, "duration_s": 6.0},
           {"type": "cruise", "duration_s": 10.0}]


def test_an_odometer_log_at_a_steady_speed_shows_no_lag():
    """Ten minutes at a steady 15 m/s, the wheel speeds tagged rightly: a lag
    is unobservable there (lag times no acceleration).  The fit at each trial
    lag had read the odometer interpolated between its samples, less noisy
    half-way between them than at one: a 10 Hz log on 1 Hz fixes fitted
    best 0.05 s off with an F statistic of about 200 and was said to lag
    (a 1 Hz log: 0.1 to 0.2 s).  The mean speed over a window about each
    trial time is as noisy at every lag, and the significance is that of
    the lag's share of the residual (the track's acceleration times it): no
    lag worth saying, whatever the log's rate; on the drive with
    accelerations a real 0.3 s is still found."""
    from inskit.jobs.navigate import odometer_lag, odometer_lag_warning
    from inskit.simulation.odometer import simulate_odometer

    steady = _simulated([{"type": "static", "duration_s": 20.0},
                         {"type": "accelerate", "speed_m_s": 15.0, "duration_s": 8.0},
                         {"type": "cruise", "duration_s": 600.0}])
    cruise = steady.truth.time > 40.0  # after the acceleration
    for rate_hz in (10.0, 1.0, 100.0):
        for seed in range(3):
            log = simulate_odometer(steady.truth, rate_hz=rate_hz, scale_error=0.005, noise_m_s=0.05,
                                    rng=np.random.default_rng(seed))
            k = log.time > steady.truth.time[cruise][0]
            lag = odometer_lag(log.time[k], log.speed_m_s[k], steady.gnss)
            assert lag["fixes"] > 500 and lag["f_statistic"] < 25.0, (rate_hz, seed, lag)
            assert odometer_lag_warning(lag, "odo.csv", 0.0) is None
    car = _simulated(LAG_CAR)
    for late_s in (0.0, 0.3):
        for rate_hz in (10.0, 1.0):
            log = simulate_odometer(car.truth, rate_hz=rate_hz, scale_error=0.005, noise_m_s=0.05,
                                    rng=np.random.default_rng(8))
            lag = odometer_lag(log.time + late_s, log.speed_m_s, car.gnss)
            assert lag["lag_s"] == pytest.approx(late_s, abs=0.03), (late_s, rate_hz, lag)
            assert (odometer_lag_warning(lag, "odo.csv", 0.0) is None) == (late_s == 0.0), (late_s, rate_hz, lag)


def test_an_odometer_lag_beyond_the_search_is_said_to_be_at_its_limit():
    """Wheel speeds tagged 2 s late, beyond the +-1 s searched: the best fit
    lies at the limit, 1 s.  The warning said the log fitted best 1.00 s late
    and that ``time_offset_s = -1.00`` puts it right (half of the lag left);
    now it says the lag is at least the limit and gives no offset that
    would put it right."""
    from inskit.jobs.navigate import ODOMETER_LAG_SPAN_S, odometer_lag, odometer_lag_warning
    from inskit.simulation.odometer import simulate_odometer

    car = _simulated(LAG_CAR)
    log = simulate_odometer(car.truth, rate_hz=10.0, scale_error=0.005, noise_m_s=0.05, rng=np.random.default_rng(8))
    for late_s, sign in ((2.0, 1.0), (-2.0, -1.0)):
        lag = odometer_lag(log.time + late_s, log.speed_m_s, car.gnss)
        assert lag["lag_s"] == pytest.approx(sign * ODOMETER_LAG_SPAN_S) and lag["at_search_limit"], lag
        warn = odometer_lag_warning(lag, "odo.csv", 0.5)
        late = "late" if sign > 0 else "early"
        assert warn.startswith(f"odometer: odo.csv: its speeds fit the GNSS track best at the limit of the "
                               f"+-1 s searched, 1.00 s {late} or more"), warn
        assert "puts them right" not in warn and f"time_offset_s = {0.5 - sign:.2f} or {'less' if sign > 0 else 'more'}" in warn
    lag = odometer_lag(log.time + 0.3, log.speed_m_s, car.gnss)
    assert not lag["at_search_limit"] and "puts them right" in odometer_lag_warning(lag, "odo.csv", 0.0)


def test_an_odometer_log_with_dropouts_shows_no_lag():
    """Fifteen stop-and-go cycles with the wheel speeds tagged rightly but 4 s
    missing from each: the speed interpolated across a dropout is a straight
    line, its misfit during a manoeuvre follows the acceleration, and the
    lag's F statistic read 138 (a lag far beyond chance) for a log without
    one.  The fixes whose trial times reach into a gap are left out: F is
    chance again, and the log tagged 0.3 s late is still found."""
    from inskit.jobs.navigate import odometer_lag, odometer_lag_warning
    from inskit.simulation.odometer import simulate_odometer

    cycle = [{"type": "accelerate", "speed_m_s": 15.0, "duration_s": 6.0}, {"type": "cruise", "duration_s": 4.0},
             {"type": "decelerate", "speed_m_s": 5.0, "duration_s": 5.0}, {"type": "cruise", "duration_s": 3.0}]
    car = _simulated([{"type": "static", "duration_s": 20.0},
                      {"type": "accelerate", "speed_m_s": 5.0, "duration_s": 3.0}] + cycle * 15)
    log = simulate_odometer(car.truth, rate_hz=10.0, scale_error=0.005, noise_m_s=0.05, rng=np.random.default_rng(1))
    phase = (log.time - 33.0) % 18.0
    keep = ~((phase < 4.0) & (log.time > 23.0))  # from 33 s, 4 s of every 18 s missing
    lag = odometer_lag(log.time[keep], log.speed_m_s[keep], car.gnss)
    assert abs(lag["lag_s"]) <= 0.03 and lag["f_statistic"] < 25.0 and 100 < lag["fixes"] < 200, lag
    lag = odometer_lag(log.time[keep] + 0.3, log.speed_m_s[keep], car.gnss)
    assert lag["lag_s"] == pytest.approx(0.3, abs=0.03) and odometer_lag_warning(lag, "odo.csv", 0.0), lag


def test_run_input_files_lists_every_file_a_run_reads_and_outputs_never_replace_them(tmp_path):
    """The output check of navigate compared five of its outputs with the IMU, fixes and RINEX files only: a
    truth, odometer, height or speed-and-course file named like an output (innovations.csv ...) was read and
    then overwritten under --force.  run_input_files lists them all; refuse_overwriting_inputs checks every
    name a run may write against them."""
    from inskit.errors import InputError
    from inskit.jobs import config as C
    from inskit.jobs.navigate import refuse_overwriting_inputs, run_input_files

    for n in ("imu.csv", "gnss.csv", "odo.csv", "h.csv", "sc.csv", "truth.csv"):
        (tmp_path / n).write_text("x\n")
    cfg = C.config_from_dict({"imu": {"file": "imu.csv"}, "gnss": {"file": "gnss.csv", "speed_course": "sc.csv"},
                              "odometer": {"file": "odo.csv"}, "height": {"file": "h.csv"},
                              "truth": {"file": "truth.csv"}}, base_dir=tmp_path, source="t")
    assert sorted(p.name for p in run_input_files(cfg)) == ["gnss.csv", "h.csv", "imu.csv", "odo.csv", "sc.csv",
                                                            "truth.csv"]
    refuse_overwriting_inputs(cfg, tmp_path / "out", force=True)  # another folder: nothing to refuse
    moved = cfg.model_copy(update={"height": cfg.height.model_copy(update={"file": tmp_path / "out" / "biases.png"})})
    with pytest.raises(InputError, match=r"out/biases\.png: would overwrite an input of this run"):
        refuse_overwriting_inputs(moved, tmp_path / "out")


def test_a_start_past_the_imu_log_names_what_set_it_and_the_log_span(tmp_path):
    """`[imu] start_s = 1e6` on a 2 s log said only 'imu.csv: fewer than 10 IMU samples after the start time
    1000000.000 s': neither the key that set the start nor where the log lies.  Now both, and the first fix
    when it is the fixes that start late."""
    from inskit import io
    from inskit.errors import InputError
    from inskit.jobs.config import config_from_dict
    from inskit.jobs.navigate import load_inputs
    from inskit.simulation import StationaryTrajectory, ideal_imu
    from inskit.types import GnssData

    t = np.arange(0.0, 2.0 + 1e-9, 0.01)
    io.write_imu(tmp_path / "imu.csv", ideal_imu(StationaryTrajectory((0.7, 0.1, 10.0)), t, nodes=1))
    tg = np.arange(0.0, 2.01, 0.5)
    io.write_gnss(tmp_path / "gnss.csv", GnssData(tg, np.tile([0.7, 0.1, 10.0], (len(tg), 1)), np.ones((len(tg), 3))))
    data = {"imu": {"file": "imu.csv", "start_s": 1e6}, "gnss": {"file": "gnss.csv"}}
    with pytest.raises(InputError, match=r"^imu\.csv: fewer than 10 IMU samples after the start time 1000000\.000 s "
                                         r"\(\[imu\] start_s\); the log's 201 samples span 0\.000\.\.2\.000 s \(after "
                                         r"\[imu\] time_offset_s\): the run needs at least 10 from its start on$"):
        load_inputs(config_from_dict(data, base_dir=tmp_path))
    late = np.array([1.95, 2.0])  # the fixes start 5 IMU samples before the log's end
    io.write_gnss(tmp_path / "gnss.csv", GnssData(late, np.tile([0.7, 0.1, 10.0], (2, 1)), np.ones((2, 3))),
                  overwrite=True)
    del data["imu"]["start_s"]
    with pytest.raises(InputError, match=r"after the start time 1\.950 s \(the first GNSS fix of gnss\.csv\)"):
        load_inputs(config_from_dict(data, base_dir=tmp_path))


def test_a_frozen_imu_output_makes_the_run_unhealthy_naming_the_stretch():
    """Rows repeating one sample 3 times in a row or more are the sensor's output frozen, not a sample read twice
    (each of drive_0708's 1138 and walk_0827's 6958 repeats is alone): the verdict says unhealthy, with the file,
    the line, the file's own time (an rtklibexplorer log's reader times carry [imu] time_offset_s) and the span."""
    from types import SimpleNamespace

    from inskit.jobs.navigate import frozen_imu_message

    notes = {"repeated_rows": 500, "repeated_rows_longest_run": 499, "repeated_rows_longest_run_s": 4.99,
             "repeated_rows_longest_run_at": "line 10003", "repeated_rows_longest_run_time_s": 243400.26,
             "reader_time_offset_s": -0.26}  # as load_inputs notes it for this reader
    imu = SimpleNamespace(file="imu_1934_gpst.csv.gz", format="rtklibexplorer", time_offset_s=-0.26)
    msg = frozen_imu_message(notes, imu)
    assert msg.startswith("IMU: imu_1934_gpst.csv.gz: 499 rows in a row from line 10003 (the file's time "
                          "243400.520 s, 4.99 s of the log) repeat one sample in all six channels: the sensor's "
                          "output froze"), msg
    # an inskit-format log: its reader's times are the file's, whatever [imu] time_offset_s
    inskit_imu = SimpleNamespace(file="imu.csv", format="inskit", time_offset_s=5.0)
    assert "(the file's time 243400.260 s," in frozen_imu_message({**notes, "reader_time_offset_s": 0.0}, inskit_imu)
    assert frozen_imu_message({**notes, "repeated_rows_longest_run": 2}, imu) is None  # double reads
    assert frozen_imu_message({"repeated_rows": 0}, imu) is None


def test_an_aiding_log_with_its_time_in_milliseconds_is_refused():
    """An odometer log with time_s in ms (0..300000 beside a 300 s IMU log) overlapped the IMU's span by its
    first three readings, so it passed the overlap test: the run warned that it 'made no update (of its 3001
    readings: 2998 outside the span ...)' and was unhealthy over 3 rejected readings, never naming the unit.
    A day-long 10 Hz log beside a short IMU log still passes."""
    from inskit.errors import InputError
    from inskit.jobs.navigate import refuse_no_overlap
    from inskit.types import ImuData

    ti = np.arange(0.0, 300.0 + 1e-9, 0.01)
    imu = ImuData(ti, np.zeros((len(ti), 3)), np.zeros((len(ti), 3)))
    t_ms = 1000.0 * np.arange(0.0, 300.0 + 1e-9, 0.1)
    with pytest.raises(InputError, match=r"^odo\.csv: odometer times step by 100 s \(median\) and span 300000 s, "
                                         r"1000 times the IMU log's 300 s: is its time column in milliseconds"):
        refuse_no_overlap("odo.csv", "odometer", t_ms, imu, "odometer.time_offset_s")
    refuse_no_overlap("odo.csv", "odometer", np.arange(0.0, 86400.0, 0.1), imu, "odometer.time_offset_s")


def test_the_notes_say_the_offset_their_reader_put_in_their_times(tmp_path):
    """The IMU reader's notes (time-tag checks, repeated rows) carry times
    with [imu] time_offset_s for the rtklibexplorer log (its reader applies
    it) but not for the inskit format (the offset is added after reading):
    the messages took the offset off both (suspected by the review of
    navigate's inputs), giving an inskit log's file time wrong by the
    offset.  load_inputs now notes the offset in the notes' times."""
    from inskit import io
    from inskit.jobs.config import config_from_dict, load_config
    from inskit.jobs.navigate import load_inputs

    cfg = load_config(EXAMPLE)
    notes = {}
    load_inputs(cfg, notes=notes)
    assert cfg.imu.format == "rtklibexplorer" and cfg.imu.time_offset_s != 0.0
    assert notes["reader_time_offset_s"] == cfg.imu.time_offset_s
    notes = {}
    load_inputs(cfg, time_offset_s=-0.3, notes=notes)  # a calibration's trial offset, not the config's
    assert notes["reader_time_offset_s"] == -0.3
    sim = _simulated(LAG_CAR[:2])
    io.write_imu(tmp_path / "imu.csv", sim.imu)
    io.write_gnss(tmp_path / "gnss.csv", sim.gnss)
    notes = {}
    load_inputs(config_from_dict({"imu": {"file": str(tmp_path / "imu.csv"), "time_offset_s": 0.5},
                                  "gnss": {"file": str(tmp_path / "gnss.csv")}}), notes=notes)
    assert notes["reader_time_offset_s"] == 0.0  # the inskit reader's times are the file's


def test_a_gyro_column_in_another_unit_is_told_by_the_tracks_turns(tmp_path):
    """Gyro rates in rad/s under a deg/s header read 57.3 times too little:
    the magnitudes cannot tell (a static log's rates are tiny either way),
    and the drive ended unhealthy, 436 m of outage error, the unit never
    named (found by the review of navigate's inputs).  The gyros' turning
    is now set against the GNSS track's over its turns: the simulated car
    reads 1.0 and runs; its gyros read 57.3 times too little, or too much,
    are refused naming the file and the likely unit; check_units = false
    runs it as it is."""
    from inskit import io
    from inskit.errors import InputError
    from inskit.jobs.config import config_from_dict
    from inskit.jobs.navigate import check_gyro_turns, navigate
    from inskit.simulation.scenario import load_scenario, simulate
    from inskit.types import ImuData

    sim = simulate(load_scenario(Path(__file__).resolve().parents[1] / "examples" / "car.toml"), seed=1)
    check_gyro_turns("imu.csv", sim.imu, sim.gnss)  # the true unit: silent
    for k, unit in ((np.pi / 180.0, "rad/s under a deg/s header"), (180.0 / np.pi, "deg/s under a rad/s header")):
        wrong = ImuData(sim.imu.time, sim.imu.dtheta_b * k, sim.imu.dv_b)
        with pytest.raises(InputError, match=rf"^imu\.csv: while the GNSS track turns \(\d+ turns of over 15 deg in 3 s "
                                             rf"at over 3 m/s\), the gyros turn a median [0-9.]+ times as much as its "
                                             rf"course: a gyro column in another unit \({unit}"):
            check_gyro_turns("imu.csv", wrong, sim.gnss)
    # navigate refuses it before the start-up; check_units = false runs it as it is
    t = sim.imu.time <= 700.0
    io.write_imu(tmp_path / "imu.csv", ImuData(sim.imu.time[t], sim.imu.dtheta_b[t] * np.pi / 180.0, sim.imu.dv_b[t]))
    io.write_gnss(tmp_path / "gnss.csv", sim.gnss.select(sim.gnss.time <= 700.0))
    cfg = {"imu": {"file": str(tmp_path / "imu.csv")},
           "gnss": {"file": str(tmp_path / "gnss.csv"), "lever_arm_b_m": [0.0, 0.0, -1.2]}}
    with pytest.raises(InputError, match=r"imu\.csv: while the GNSS track turns"):
        navigate(config_from_dict(cfg))
    navigate(config_from_dict({**cfg, "imu": {**cfg["imu"], "check_units": False}}))


def test_load_inputs_notes_the_imu_spikes_at_the_file_times(tmp_path):
    """navigate names the IMU's lone spikes (:func:`inskit.integration.gaps.imu_spikes`,
    tested in tests/test_integration_gaps.py): load_inputs notes them with the file's times
    ([imu] time_offset_s taken back off), and the summary says them."""
    from inskit import io
    from inskit.jobs import navigate as N
    from inskit.jobs.config import config_from_dict
    from inskit.types import ImuData

    n = 2000
    t = np.arange(n) * 0.01
    rng = np.random.default_rng(0)
    w = np.radians(5.0) * np.sign(rng.standard_normal((n, 3)))
    f = np.tile([0.0, 0.0, -9.81], (n, 1)) + rng.standard_normal((n, 3))
    w[700, 0], f[1500, 2] = 87.0, 60.0 * 9.80665
    io.write_imu(tmp_path / "imu.csv", ImuData(t, np.r_[np.zeros((1, 3)), w[1:] * 0.01],
                                               np.r_[np.zeros((1, 3)), f[1:] * 0.01]))
    g = _simulated(LAG_CAR[:1]).gnss
    io.write_gnss(tmp_path / "gnss.csv", g.select(g.time <= t[-1]))
    notes = {}
    N.load_inputs(config_from_dict({"imu": {"file": str(tmp_path / "imu.csv"), "time_offset_s": 0.5},
                                    "gnss": {"file": str(tmp_path / "gnss.csv")}}), notes=notes)
    assert [(s["row"], s["t_s"]) for s in notes["spikes"]] == [(700, pytest.approx(7.0)), (1500, pytest.approx(15.0))]
