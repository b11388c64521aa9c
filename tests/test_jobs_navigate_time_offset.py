"""The IMU time offset checked when a run's GNSS updates are unhealthy
(``[imu] time_offset_search``, :func:`inskit.jobs.navigate.check_time_offset`).

IMU time tags a fraction of a second late or early read well and look like
any other log, yet the filter rejects fixes and loses its way; the verdict
named the symptoms (rejections, NIS, recoveries) but not the cause.  A short
simulated car, its IMU tags taken as 0.3 s late (``time_offset_s = 0.3``
given, the truth 0): the check must name an offset within 0.01 s of 0."""

import numpy as np
import pytest

from inskit import api
from inskit.jobs.config import config_from_dict
from inskit.jobs.navigate import check_time_offset, gnss_updates_unhealthy, navigate, summary
from inskit.jobs.reproduce_tight import BLOCKAGE_NAVIGATE
from scenarios import short_car, write_drive

CAR = short_car("short car", [{"type": "static", "duration_s": 30.0},
                              {"type": "accelerate", "speed_m_s": 15.0, "duration_s": 8.0},
                              {"type": "turn", "angle_deg": 90.0, "radius_m": 30.0},
                              {"type": "cruise", "duration_s": 10.0},
                              {"type": "turn", "angle_deg": -90.0, "radius_m": 30.0},
                              {"type": "decelerate", "speed_m_s": 8.0, "duration_s": 5.0},
                              {"type": "turn", "angle_deg": 180.0, "radius_m": 20.0},
                              {"type": "accelerate", "speed_m_s": 15.0, "duration_s": 5.0},
                              {"type": "cruise", "duration_s": 10.0}])
LATE_S = 0.3  # the offset given; the IMU's tags are right (0)


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    return write_drive(tmp_path_factory.mktemp("toff"), CAR, seed=2)


def config(d, offset, search="check"):
    cfg = {k: (dict(v) if isinstance(v, dict) else v) for k, v in BLOCKAGE_NAVIGATE.items()}
    cfg.update(name="short car", imu={"file": "imu.csv", "time_offset_s": offset, "time_offset_search": search},
               outages={"protocol": "none"})
    return config_from_dict(cfg, base_dir=d, source=str(d))


@pytest.fixture(scope="module")
def late(drive):
    cfg = config(drive, LATE_S)
    s = summary(navigate(cfg))
    assert gnss_updates_unhealthy(s["health"], cfg) == "gnss_pos", s["health"]  # the premise
    rec = check_time_offset(cfg, s)
    return s, rec


def test_an_unhealthy_run_names_the_offset_that_fits_the_fixes(late):
    s, rec = late
    assert rec is s["time_offset_check"] and rec["found"], rec
    assert abs(rec["best_s"]) < 0.01, rec  # the truth: 0 s
    assert rec["mean_nis_per_dof_best"] <= 3.0 < rec["mean_nis_per_dof_given"], rec
    first = s["health"]["reasons"][0]  # the cause first, then the symptoms
    assert first.startswith("gnss_pos: the fixes fit an IMU time offset of") and "[imu] time_offset_s" in first, first
    assert s["health"]["verdict"] == "unhealthy"
    offs = [o for o, _ in rec["evaluations"]]
    assert min(offs) == pytest.approx(LATE_S - 0.5) and max(offs) == pytest.approx(LATE_S + 0.5)


def test_the_named_offset_makes_the_run_healthy(drive, late):
    _, rec = late
    s = summary(navigate(config(drive, rec["best_s"])))
    assert s["health"]["verdict"] == "healthy", s["health"]["reasons"]


def test_a_healthy_run_searches_nothing(drive):
    cfg = config(drive, 0.0)
    s = summary(navigate(cfg))
    assert s["health"]["verdict"] == "healthy", s["health"]["reasons"]
    assert check_time_offset(cfg, s) is None and "time_offset_check" not in s


def test_off_searches_nothing(drive):
    cfg = config(drive, LATE_S, "off")
    s = summary(navigate(cfg))
    assert s["health"]["verdict"] == "unhealthy"
    assert check_time_offset(cfg, s) is None and "time_offset_check" not in s


def test_an_offset_that_explains_nothing_is_said_to_be_elsewhere(drive):
    """Fixes made wrong by a wrong lever arm (3 m forward of where they are):
    no time offset fits them, and the warning says so instead of naming one."""
    cfg = config(drive, 0.0)
    cfg = cfg.model_copy(update={"gnss": cfg.gnss.model_copy(update={"lever_arm_b_m": (3.0, 2.0, -1.2)})})
    s = summary(navigate(cfg))
    assert gnss_updates_unhealthy(s["health"], cfg) == "gnss_pos", s["health"]  # the premise
    rec = check_time_offset(cfg, s)
    assert not rec["found"], rec  # a lever arm sideways and along the track, through the turns: no offset fits
    assert not rec["better"], rec
    assert any("fits the fixes better" in w and "a time offset does not explain them" in w
               and "(nor 18 s either way, GPS time - UTC)" in w for w in s["health"]["warnings"]), s["health"]["warnings"]


def test_calibrate_runs_with_the_best_offset(drive):
    run = api.navigate(config(drive, LATE_S, "calibrate"))
    cal = run.summary["time_offset_calibration"]
    assert abs(cal["best_s"]) < 0.01, cal
    assert run.summary["imu_time_offset_s"] == pytest.approx(cal["best_s"])
    assert run.summary["health"]["verdict"] == "healthy", run.summary["health"]["reasons"]
    assert "time_offset_check" not in run.summary
    assert np.isfinite(run.summary["imu_time_offset_s"])


def test_an_offset_that_helps_but_not_enough_is_a_warning_not_a_cause(drive):
    """The late tags and a lever arm wrong by 2 m sideways: the offset still
    helps (the NIS falls by more than half) but leaves the fixes out of the
    band; a warning names it as one possible cause, the verdict does not
    claim it."""
    cfg = config(drive, LATE_S)
    cfg = cfg.model_copy(update={"gnss": cfg.gnss.model_copy(update={"lever_arm_b_m": (0.0, 2.0, -1.2)})})
    s = summary(navigate(cfg))
    rec = check_time_offset(cfg, s)
    assert rec["better"] and not rec["found"], rec
    assert abs(rec["best_s"]) < 0.05, rec
    assert not any("fit an IMU time offset" in r for r in s["health"]["reasons"])
    assert any("but not into the band" in w for w in s["health"]["warnings"]), s["health"]["warnings"]


def test_the_search_runs_on_the_first_minutes_only(drive, monkeypatch):
    """A long log is searched over its first TIME_OFFSET_CHECK_MAX_S seconds:
    every evaluation runs that much of the IMU, and the offset is found in it."""
    import inskit.jobs.navigate as N

    spans = []
    real = N.navigate

    def spy(cfg, *a, **kw):
        imu = kw["inputs"][0]
        spans.append(float(imu.time[-1] - imu.time[0]))
        return real(cfg, *a, **kw)

    monkeypatch.setattr(N, "navigate", spy)
    best, evals = N.search_time_offset(config(drive, LATE_S), max_s=55.0)
    assert len(spans) == len(evals) and max(spans) <= 55.0 + 0.02, spans
    assert abs(best) < 0.02, (best, evals)


def test_a_search_that_fails_is_said_and_the_run_stands(drive, monkeypatch):
    import inskit.jobs.navigate as N
    from inskit.errors import InputError

    cfg = config(drive, LATE_S)
    s = summary(navigate(cfg))

    def boom(*a, **kw):
        raise InputError("imu.csv: something the search could not read")

    monkeypatch.setattr(N, "search_time_offset", boom)
    rec = check_time_offset(cfg, s)
    assert rec["error"] == "imu.csv: something the search could not read"
    assert any("could not run: imu.csv: something" in w for w in s["health"]["warnings"])
    assert s["health"]["verdict"] == "unhealthy"


def test_the_bundled_drive_without_its_offset_is_told_it(tmp_path):
    """examples/drive_0708.toml with its time_offset_s = -0.26 left out: the
    run is lost (hundreds of fixes rejected) and the verdict's first reason
    names the offset the config's own calibration found (-0.261 s)."""
    from pathlib import Path

    from inskit.jobs.config import load_config

    root = Path(__file__).resolve().parents[1]
    cfg = load_config(root / "examples" / "drive_0708.toml")
    cfg = cfg.model_copy(update={"imu": cfg.imu.model_copy(update={"time_offset_s": 0.0}),
                                 "output": cfg.output.model_copy(update={"plots": False})})
    s = summary(navigate(cfg))
    assert s["health"]["measurements"]["gnss_pos"]["rejected_fraction"] > 0.2  # lost
    rec = check_time_offset(cfg, s)
    assert rec["found"] and abs(rec["best_s"] - (-0.26)) < 0.01, rec
    assert s["health"]["reasons"][0].startswith("gnss_pos: the fixes fit an IMU time offset of -0.26")


def test_an_imu_log_in_utc_beside_fixes_in_gps_time_is_told_the_leap_seconds(drive):
    """An IMU log stamped in UTC beside fixes in GPS time is 18 s off, far beyond the +-0.5 s searched first;
    the check then tries GPS - UTC either way and names it."""
    cfg = config(drive, 18.0)  # the truth: 0
    s = summary(navigate(cfg))
    rec = check_time_offset(cfg, s)
    assert rec["found"] and rec["gps_utc_shift_s"] == -18.0 and abs(rec["best_s"]) < 0.01, rec
    first = s["health"]["reasons"][0]
    assert "seem off by GPS time - UTC (18 s" in first and "set [imu] time_offset_s = " in first, first


def test_a_lost_filter_is_not_searched_and_the_verdict_says_it_was_lost(drive, monkeypatch):
    """A filter lost for another reason (started 10 deg off in roll, its
    recovery held off by ``gate_max_consecutive``) refused every fix; the
    check searched IMU time offsets over +-0.5 s and +-18 s (57 runs of the
    filter for the tilted car of test_jobs_navigate.py) and named the
    'best' (before the lost-filter recovery, examples/car.toml so started
    was told of -0.091 s that 'fits the fixes better').  A lost filter is no evidence
    of a time offset: nothing is searched, and the verdict's first reason
    says the filter was lost, to the end of the run."""
    import inskit.jobs.navigate as N

    cfg = config(drive, 0.0)
    cfg = cfg.model_copy(update={
        "init": cfg.init.model_copy(update={"mode": "given", "lat_deg": 40.0966, "lon_deg": -105.1474,
                                            "height_m": 1600.0, "rpy_deg": (10.0, -8.0, 0.0),
                                            "sigma_roll_pitch_deg": 0.5}),
        "filter": cfg.filter.model_copy(update={"gate_max_consecutive": 1000})})
    s = summary(navigate(cfg))
    assert gnss_updates_unhealthy(s["health"], cfg) == "gnss_pos", s["health"]  # the premise
    searched = []
    monkeypatch.setattr(N, "search_time_offset", lambda *a, **kw: searched.append(a) or (0.0, [(0.0, 1.0)]))
    rec = check_time_offset(cfg, s)
    assert not searched and rec is s["time_offset_check"] and not rec["searched"] and not rec["found"], rec
    first = s["health"]["reasons"][0]
    assert first.startswith("gnss_pos: the filter was lost: ") and "none was searched" in first, first
    assert "still lost at the end of the run" in first and first == rec["not_searched_because"]
    m = s["health"]["measurements"]["gnss_pos"]
    assert len(m["lost_stretches"]) == 1 and not m["lost_stretches"][0]["recovered"], m
    assert not any("time offset of" in w for w in s["health"]["warnings"])
    assert any("consecutive updates rejected" in r and "to the end of the run: the filter lost" in r
               for r in s["health"]["reasons"]), s["health"]["reasons"]


def test_the_runs_that_name_an_offset_have_their_evidence_outside_the_lost_stretches(late):
    """0.3 s late: one stretch of 15 refusals (a recovery), and outside it
    about a quarter of the fixes still refused: evidence about timing."""
    from inskit.jobs.navigate import timing_evidence

    s, rec = late
    m = s["health"]["measurements"]["gnss_pos"]
    assert m["lost_stretches"] and m["outside_lost"]["rejected_fraction"] > 0.15, m
    assert timing_evidence(m) and rec["searched"] and rec["found"]


def test_lost_stretches_and_the_figures_outside_them():
    """Runs of refusals lasting the recovery's 15 s or more are lost
    stretches (to the update that ended them, or to the last refusal);
    shorter runs are not; the figures outside them judge the timing."""
    from inskit.jobs.navigate import lost_stretches, outside_lost, timing_evidence

    t = np.arange(100.0)
    acc = np.ones(100, bool)
    acc[10:14] = False   # 4 s: a burst, not lost
    acc[30:46] = False   # refused 30..45, accepted at 46: lost 16 s
    acc[80:] = False     # refused from 80 to the end: lost 19 s
    lost = lost_stretches(t, acc, 15.0)
    assert lost == [{"start_s": 30.0, "end_s": 46.0, "updates": 16, "recovered": True},
                    {"start_s": 80.0, "end_s": 99.0, "updates": 20, "recovered": False}]
    nis = np.where(acc, 2.0, 500.0)
    out = outside_lost(t, acc, nis, lost, 2)
    assert out["updates"] == 64 and out["rejected_fraction"] == pytest.approx(4 / 64)
    assert out["mean_nis_per_dof"] == pytest.approx((60 * 2.0 + 4 * 500.0) / 64 / 2)
    m = {"lost_stretches": lost, "outside_lost": out}
    assert timing_evidence(m)  # the 4 refused outside: 6 %, above the 5 % limit
    acc[10:14] = True
    out = outside_lost(t, acc, np.where(acc, 2.0, 500.0), lost, 2)
    assert out["rejected_fraction"] == 0.0 and not timing_evidence({"lost_stretches": lost, "outside_lost": out})
    assert timing_evidence({"lost_stretches": [], "outside_lost": None})  # never lost: the figures speak as before
