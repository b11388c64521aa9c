"""In-motion start-up (inskit.alignment.inmotion) and the job's automatic choice.

A simulated car that starts at 15 m/s with no static period (industrial MEMS,
1 Hz GNSS, the noise of examples/car.toml), started by the navigate job's own
start-up from a wrong first yaw: the yaw bank must bring the heading within
1 deg in under 60 s, and the position RMS within 20 % of a run started from
the true state.
"""

from __future__ import annotations

import numpy as np
import pytest

from inskit import earth
from inskit import rotations as rot
from inskit.alignment.inmotion import (BANK_ABOVE_YAW_SIGMA, UNKNOWN_YAW_SIGMA, auto_startup, gnss_acceleration,
                                       gnss_velocity, inmotion_startup)
from inskit.errors import ConfigError, InputError
from inskit.jobs.config import config_from_dict
from inskit.jobs.navigate import navigate
from inskit.jobs.simulate import write_simulation
from inskit.simulation.scenario import load_scenario, simulate
from inskit.units import DEG

YAW0_DEG = 40.0
GNSS = """[gnss]
rate_hz = 1.0
white_h_m = 0.5
white_v_m = 1.0
correlated_h_m = 0.3
correlated_v_m = 0.6
correlation_time_s = 60.0
velocity_sigma_m_s = 0.05
lever_arm_b_m = [0.0, 0.0, -1.2]
"""
MOVING = f"""name = "car15"
[start]
lat_deg = 40.0966
lon_deg = -105.1474
height_m = 1600.0
yaw_deg = {YAW0_DEG}
speed_m_s = 15.0
[imu]
rate_hz = 100.0
grade = "industrial-mems"
{GNSS}
[[segment]]
type = "accelerate"
speed_m_s = 20.0
duration_s = 10.0
[[segment]]
type = "cruise"
duration_s = 20.0
[[segment]]
type = "turn"
angle_deg = 90.0
radius_m = 60.0
[[segment]]
type = "cruise"
duration_s = 30.0
[[segment]]
type = "turn"
angle_deg = -90.0
radius_m = 80.0
[[segment]]
type = "cruise"
duration_s = 40.0
"""
STATIC_FIRST = MOVING.replace("speed_m_s = 15.0\n", "").replace(
    "[[segment]]\ntype = \"accelerate\"\nspeed_m_s = 20.0",
    "[[segment]]\ntype = \"static\"\nduration_s = 20.0\n[[segment]]\ntype = \"accelerate\"\nspeed_m_s = 20.0", 1)


def _simulate(tmp, text, seed):
    p = tmp / "s.toml"
    p.write_text(text)
    sim = simulate(load_scenario(p), seed=seed)
    write_simulation(sim, tmp, plot=False)
    return sim


@pytest.fixture(scope="module")
def car(tmp_path_factory):
    d = tmp_path_factory.mktemp("car15")
    return d, _simulate(d, MOVING, 11)


def _cfg(d, **init):
    return config_from_dict({"imu": {"file": str(d / "imu.csv")},
                             "gnss": {"file": str(d / "gnss.csv"), "lever_arm_b_m": [0.0, 0.0, -1.2]},
                             "noise": {"from_static": False}, "filter": {"scale_factors": False},
                             **({"init": init} if init else {})})


def _errors(res, truth):
    """Horizontal position error [m] and yaw error [deg] of the forward solution at 1 Hz."""
    sol = res.forward.nav
    k = np.arange(0, len(sol.time), 100)
    kt = np.clip(np.searchsorted(truth.time, sol.time[k] - 1e-9), 0, len(truth.time) - 1)
    ned = np.array([earth.lla_to_ned(a, b) for a, b in zip(sol.lla[k], truth.lla[kt])])
    yaw = np.degrees(rot.wrap_angle(sol.euler[k, 2] - truth.euler[kt, 2]))
    return sol.time[k] - sol.time[0], np.hypot(ned[:, 0], ned[:, 1]), yaw


def _converged_at(t, yaw_err, tol=1.0):
    """First time after which the yaw error stays within ``tol`` deg."""
    bad = np.nonzero(np.abs(yaw_err) > tol)[0]
    return 0.0 if not len(bad) else (float(t[bad[-1] + 1]) if bad[-1] + 1 < len(t) else np.inf)


@pytest.fixture(scope="module")
def from_truth(car):
    d, sim = car
    s0 = sim.truth.state(0)
    cfg = _cfg(d, mode="given", lat_deg=float(s0.lla[0] / DEG), lon_deg=float(s0.lla[1] / DEG),
               height_m=float(s0.lla[2]), v_ned_m_s=[float(v) for v in s0.v_n],
               rpy_deg=[float(v) for v in s0.euler / DEG])
    t, dh, _ = _errors(navigate(cfg), sim.truth)
    return float(np.sqrt(np.mean(dh ** 2)))


# --- the GNSS-derived velocity and acceleration, levelling in motion ---------------------------------
def test_gnss_velocity_and_acceleration_match_the_truth(car):
    _, sim = car
    g = sim.gnss
    v, sig_h, _ = gnss_velocity(g)
    assert sig_h == pytest.approx(0.05)  # the receiver velocity (the fixes are metre-level)
    kt = np.searchsorted(sim.truth.time, g.time)
    assert np.sqrt(np.mean((v[:, :2] - sim.truth.v_n[kt, :2]) ** 2)) < 2.0 * 0.05
    a, span = gnss_acceleration(g.time, v)
    assert span == pytest.approx(2.0)
    # against the truth's velocity differenced the same way (the segment's smooth 15 -> 20 m/s profile, which
    # peaks near 0.9 m/s^2): within 4 sigma of the difference noise sqrt(2) 0.05 / 2 s
    vt = sim.truth.v_n[kt]
    a_true = (vt[2:] - vt[:-2]) / 2.0
    assert np.abs(a[1:-1, :2] - a_true[:, :2]).max() < 4 * np.sqrt(2) * 0.05 / 2.0
    assert a_true[4:6, :2].max() > 0.5  # the check is not of a zero


def test_levelling_in_motion_removes_the_acceleration(car):
    """Accelerating tilts plain levelling by a/g in pitch; corrected, the tilt is within 3 of its own
    sigma (GNSS acceleration noise and the 0.05 m/s^2 accelerometer-bias sigma)."""
    _, sim = car
    s = inmotion_startup(sim.imu, sim.gnss, (0.0, 0.0, -1.2))
    assert s.mode == "in-motion" and s.heading_time == pytest.approx(0.0)
    truth0 = sim.truth.state(0)
    err = np.degrees(rot.attitude_error(s.state.C_nb, truth0.C_nb))
    tilt_sigma = s.sigma["sigma_roll_pitch_deg"]
    assert 0.1 < tilt_sigma < 1.0
    assert abs(err[0]) < 3 * tilt_sigma and abs(err[1]) < 3 * tilt_sigma
    w, f = sim.imu.rates()
    plain = np.degrees(np.arctan2(f[1:201, 0].mean(), np.hypot(f[1:201, 1].mean(), f[1:201, 2].mean())))
    k2 = int(np.searchsorted(sim.truth.time, 2.0))
    a_mean = np.linalg.norm(sim.truth.v_n[k2] - sim.truth.v_n[0]) / 2.0  # mean along-track acceleration
    assert a_mean > 0.1
    assert plain - np.degrees(truth0.euler[1]) == pytest.approx(np.degrees(a_mean / 9.8), abs=0.05)
    assert abs(err[1]) < 0.5 * np.degrees(a_mean / 9.8)
    # yaw from the course at 15-20 m/s: 0.05 m/s noise -> ~0.1 deg per fix
    assert abs(err[2]) < 3 * s.sigma["sigma_yaw_deg"] and s.sigma["sigma_yaw_deg"] < 1.0
    assert s.sigma["sigma_vel_m_s"] == pytest.approx(0.05)
    # the position: the fix at t0 less the lever arm, metre-level like the fix
    dp = earth.lla_to_ned(s.state.lla, truth0.lla)
    assert np.linalg.norm(dp) < 3 * np.linalg.norm(sim.gnss.sigma_ned[0])


def test_a_first_yaw_guess_is_unknown_on_the_circle(car):
    _, sim = car
    s = inmotion_startup(sim.imu, sim.gnss, yaw_guess=1.0)
    assert s.state.euler[2] == pytest.approx(1.0)
    assert s.sigma["sigma_yaw_deg"] * DEG == pytest.approx(UNKNOWN_YAW_SIGMA)
    assert UNKNOWN_YAW_SIGMA > BANK_ABOVE_YAW_SIGMA


def test_no_heading_from_a_slow_track_says_what_to_do(car):
    _, sim = car
    with pytest.raises(InputError, match=r"never exceeds 30\.00 m/s .*init\.heading_speed_m_s .*init\.yaw_deg"):
        inmotion_startup(sim.imu, sim.gnss, heading_speed_m_s=30.0)


# --- the job: automatic choice, the yaw bank ----------------------------------------------------------
def test_auto_chooses_in_motion_without_rest_and_the_course_is_enough(car, from_truth):
    d, sim = car
    res = navigate(_cfg(d))
    s = res.startup
    assert s.mode == "in-motion" and "0.0 s of rest" in s.reason and s.bank is None  # 0.1 deg: no bank needed
    info = s.summary(res.imu.time[0])
    assert info["mode"] == "in-motion" and info["static_s"] == 0.0
    t, dh, yaw = _errors(res, sim.truth)
    assert _converged_at(t, yaw) < 60.0
    assert np.sqrt(np.mean(dh ** 2)) < 1.2 * from_truth


def _bank_run(car, from_truth, offset_deg):
    d, sim = car
    # the guess wrapped into [-180, 180): the config refuses an angle beyond a full turn (370 deg, a typo)
    res = navigate(_cfg(d, yaw_deg=(YAW0_DEG + offset_deg + 180.0) % 360.0 - 180.0))
    s = res.startup
    assert s.mode == "in-motion" and s.bank is not None
    assert len(s.bank["scores"]) == 12 and s.bank["span_s"] == pytest.approx(40.0)
    assert s.sigma["sigma_yaw_deg"] == pytest.approx(15.0)
    # the kept hypothesis is the one nearest the truth (within half the spacing)
    assert abs(rot.wrap_angle((s.bank["chosen_yaw_deg"] - YAW0_DEG) * DEG)) <= 15.0 * DEG + 1e-9
    t, dh, yaw = _errors(res, sim.truth)
    assert _converged_at(t, yaw) < 60.0
    rms = float(np.sqrt(np.mean(dh ** 2)))
    assert rms < 1.2 * from_truth, f"position RMS {rms:.3f} m against {from_truth:.3f} m from the truth"
    return s


@pytest.mark.parametrize("offset_deg", [90.0, 210.0, 105.0])
def test_any_initial_yaw_converges(car, from_truth, offset_deg):
    s = _bank_run(car, from_truth, offset_deg)
    assert "yaw bank: hypothesis" in s.reason


@pytest.mark.slow
@pytest.mark.parametrize("offset_deg", [30.0 * k for k in range(12)])
def test_any_initial_yaw_converges_full_sweep(car, from_truth, offset_deg):
    _bank_run(car, from_truth, offset_deg)


def test_auto_keeps_static_then_track_on_a_static_start(tmp_path):
    sim = _simulate(tmp_path, STATIC_FIRST, 12)
    s = auto_startup(sim.imu, sim.gnss, (0.0, 0.0, -1.2))
    assert s.mode == "static-then-track" and s.reason.startswith("auto: static for ")
    # 20 s at rest, then a smooth start: the track passes 0.3 m/s about 2 s later, less 1 s of margin
    assert 19.0 < s.static_end < 23.0
    # the position is the first fix's, and as uncertain: its largest axis sigma (the others stand as configured)
    assert s.sigma == {"sigma_pos_m": float(np.max(sim.gnss.sigma_ned[0]))} and s.sigma["sigma_pos_m"] > 0.5
    floored = auto_startup(sim.imu, sim.gnss, (0.0, 0.0, -1.2), floors={"sigma_pos_m": 5.0})
    assert floored.sigma == {"sigma_pos_m": 5.0}  # the config's sigma_pos_m is a floor
    assert abs(np.degrees(rot.wrap_angle(s.state.euler[2])) - YAW0_DEG) < 1.0
    # the same log cut to start while moving goes in-motion
    k = int(np.searchsorted(sim.imu.time, 25.0))
    s2 = auto_startup(sim.imu.slice(k), sim.gnss.select(sim.gnss.time >= sim.imu.time[k]), (0.0, 0.0, -1.2))
    assert s2.mode == "in-motion"


def test_init_mode_keys_are_checked():
    base = {"imu": {"file": "a.csv"}, "gnss": {"file": "b.csv"}}
    assert config_from_dict(base).init.mode == "auto"
    with pytest.raises(ConfigError, match=r"init\.yaw_deg would be ignored: it tunes the in-motion start-up"):
        config_from_dict({**base, "init": {"mode": "static-then-track", "yaw_deg": 10.0}})
    with pytest.raises(ConfigError, match=r"init\.min_static_s would be ignored"):
        config_from_dict({**base, "init": {"mode": "in-motion", "min_static_s": 3.0}})
    given = {"mode": "given", "lat_deg": 45.0, "lon_deg": 7.0, "height_m": 300.0, "rpy_deg": [0, 0, 90]}
    with pytest.raises(ConfigError, match=r"init\.yaw_hypotheses would be ignored"):
        config_from_dict({**base, "init": {**given, "yaw_hypotheses": 4}})


def test_a_bank_that_cannot_tell_the_yaws_apart_keeps_the_tracks_course():
    """On 40 s of straight driving at constant speed every yaw fits the fixes alike: a bank from the track's
    course (29.9 deg, known to a degree) kept -120 deg for scoring 0.738 against 0.741 and drove backwards
    (2168 m).  When the start-up's yaw is the track's (keep_first_on_tie), a hypothesis must score more than
    BANK_TIE better to replace it; a clear winner still does, and a user's guessed yaw keeps the old rule."""
    from types import SimpleNamespace

    from inskit.alignment.inmotion import BANK_TIE, yaw_bank
    from inskit.types import ImuData

    imu = ImuData(np.arange(0.0, 50.0, 0.01), np.zeros((5000, 3)), np.zeros((5000, 3)))

    def fake(scores):
        def run(short, state, meas, settings):
            k = int(round(((state - 10.0) % 360.0) / 30.0)) % 12  # hypothesis k at 10 + 30 k deg
            return SimpleNamespace(innovations={"gnss_pos": {"nis": np.array([2.0 * scores[k]]),
                                                             "dof": np.array([2.0])}})
        return run

    tied = [0.741] * 12
    tied[5] = 0.738
    at = (lambda y: float(np.degrees(y)))
    b = yaw_bank(imu, at, np.radians(10.0), [], None, run=fake(tied), keep_first_on_tie=True)
    assert b["chosen"] == 0 and b["tie"] and b["chosen_yaw_deg"] == pytest.approx(10.0)
    assert yaw_bank(imu, at, np.radians(10.0), [], None, run=fake(tied))["chosen"] == 5  # a guessed yaw: no prior
    clear = [5.0] * 12
    clear[3] = 5.0 * (1.0 - 2 * BANK_TIE)
    b = yaw_bank(imu, at, np.radians(10.0), [], None, run=fake(clear), keep_first_on_tie=True)
    assert b["chosen"] == 3 and not b["tie"]


def test_the_start_ups_position_sigma_is_the_fix_as_the_filter_takes_it(tmp_path):
    """A fix file whose sigmas the config puts right ([gnss] sigma_floor_m,
    sigma_scale_ned, as GnssPosition applies them): the start-up took the
    file's sigma for its position's while the filter took the fix's as
    configured (fixes of 1 m claiming 0.25 m with sigma_floor_m = 1: the
    forward down error ran at 1.56 sigma RMS, 0.30 m against 0.16 m with
    right sigmas).  Static, auto and in-motion start-ups now take the first
    fix's sigma as the filter does, and navigate hands them the config's
    keys."""
    import pandas as pd

    sim = _simulate(tmp_path, STATIC_FIRST, 12)
    raw = sim.gnss.sigma_ned[0]
    scale = (1.0, 2.0, 3.0)
    for mode in ("static-then-track", "auto"):
        s = auto_startup(sim.imu, sim.gnss, (0.0, 0.0, -1.2), mode=mode, sigma_floor_m=4.0)
        assert s.mode == "static-then-track" and s.sigma["sigma_pos_m"] == pytest.approx(4.0)
        s = auto_startup(sim.imu, sim.gnss, (0.0, 0.0, -1.2), mode=mode, sigma_scale_ned=scale)
        assert s.sigma["sigma_pos_m"] == pytest.approx(float(np.max(raw * scale)))
    k = int(np.searchsorted(sim.imu.time, 25.0))
    imu, gnss = sim.imu.slice(k), sim.gnss.select(sim.gnss.time >= sim.imu.time[k])
    s = auto_startup(imu, gnss, (0.0, 0.0, -1.2), sigma_floor_m=4.0)
    assert s.mode == "in-motion" and s.sigma["sigma_pos_m"] == pytest.approx(4.0)
    g = pd.read_csv(tmp_path / "gnss.csv")
    g[["sigma_n_m", "sigma_e_m", "sigma_d_m"]] = 0.25
    g.to_csv(tmp_path / "gnss_formal.csv", index=False)
    for gnss_keys in ({"sigma_floor_m": 1.5}, {"sigma_scale_ned": [2.0, 2.0, 6.0]}):
        cfg = config_from_dict({"imu": {"file": str(tmp_path / "imu.csv")},
                                "gnss": {"file": str(tmp_path / "gnss_formal.csv"), "lever_arm_b_m": [0.0, 0.0, -1.2],
                                         **gnss_keys}, "init": {"mode": "static-then-track"}})
        res = navigate(cfg)  # the file's 0.25 m floored at 1.5, or 0.25 m times 6 down: 1.5 m
        assert res.startup.sigma == {"sigma_pos_m": pytest.approx(1.5)}, (gnss_keys, res.startup.sigma)


def test_rest_and_motion_are_found_against_the_fixes_as_the_filter_takes_them(tmp_path):
    """A fix file claiming 2 cm for fixes of 0.5 m (white) noise, put right
    by ``[gnss] sigma_floor_m = 0.5``: the start-up judged rest and motion
    against the file's 2 cm (the track's speed noise read as motion from
    the first second: 'the log starts with 0.0 s of rest' of 20 s, an
    in-motion start with a 1.4 cm/s velocity sigma), and navigate's ZUPT
    found no rest at all.  Both now take the fixes as the filter does."""
    import dataclasses

    sim = _simulate(tmp_path, STATIC_FIRST, 12)
    formal = dataclasses.replace(sim.gnss, sigma_ned=np.full_like(sim.gnss.sigma_ned, 0.02))
    fooled = auto_startup(sim.imu, formal, (0.0, 0.0, -1.2))  # nothing says the 2 cm are wrong: fooled, as before
    assert fooled.mode == "in-motion"
    s = auto_startup(sim.imu, formal, (0.0, 0.0, -1.2), sigma_floor_m=0.5)
    assert s.mode == "static-then-track" and 19.0 < s.static_end < 23.0
    assert s.sigma == {"sigma_pos_m": pytest.approx(0.5)}  # the floor counted once, not twice
    scaled = auto_startup(sim.imu, formal, (0.0, 0.0, -1.2), sigma_scale_ned=(25.0, 25.0, 50.0))
    assert scaled.mode == "static-then-track" and scaled.sigma == {"sigma_pos_m": pytest.approx(1.0)}
    k = int(np.searchsorted(sim.imu.time, 25.0))
    s2 = auto_startup(sim.imu.slice(k), formal.select(formal.time >= sim.imu.time[k]), (0.0, 0.0, -1.2),
                      sigma_floor_m=0.5)
    assert s2.mode == "in-motion" and s2.sigma["sigma_pos_m"] == pytest.approx(0.5)
    # fixes of 0.5 m: the receiver's velocity (0.05 m/s), not the differences of 2 cm fixes (0.014 m/s)
    assert s2.sigma["sigma_vel_m_s"] == pytest.approx(0.05)

    import pandas as pd

    g = pd.read_csv(tmp_path / "gnss.csv")
    g[["sigma_n_m", "sigma_e_m", "sigma_d_m"]] = 0.02
    g.to_csv(tmp_path / "gnss_formal.csv", index=False)
    zupts = []
    for floor in (0.0, 0.5):
        cfg = config_from_dict({"imu": {"file": str(tmp_path / "imu.csv")},
                                "gnss": {"file": str(tmp_path / "gnss_formal.csv"), "lever_arm_b_m": [0.0, 0.0, -1.2],
                                         "sigma_floor_m": floor},
                                "constraints": {"zupt": True}, "noise": {"from_static": False}})
        res = navigate(cfg)
        zupts.append(res.forward.counts.get("zupt", {}).get("used", 0))
    assert zupts[0] == 0 and zupts[1] > 100, zupts  # 19 s of rest at 10 Hz


def test_in_motion_keys_that_auto_leaves_unused_are_said(tmp_path):
    """init.yaw_deg with mode "auto" on a log that starts at rest: auto
    levelled at rest (static-then-track, the yaw from the track) and the
    yaw given was dropped without a word (found by the review of navigate's
    inputs).  Now the health says which keys went unused and what would use
    them; without those keys it says nothing."""
    from inskit.jobs.navigate import summary

    _simulate(tmp_path, STATIC_FIRST, 12)
    res = navigate(_cfg(tmp_path, yaw_deg=YAW0_DEG, course_average_s=5.0))
    assert res.startup.mode == "static-then-track"
    w = [x for x in summary(res)["health"]["warnings"] if x.startswith("init: ")]
    assert w == ["init: init.course_average_s, init.yaw_deg (of the in-motion start-up) were not used: mode \"auto\" "
                 "found rest at the start and levelled there (static-then-track: the yaw from the GNSS track once "
                 "moving); set init.mode = \"in-motion\" to start from the yaw given, or leave them out"]
    res = navigate(_cfg(tmp_path))
    assert not [x for x in summary(res)["health"]["warnings"] if x.startswith("init: ")]


def test_fixes_that_claim_far_less_error_than_they_have_are_named_when_refused(tmp_path):
    """Fixes of 0.5 m noise whose file claims 1e-6 m: most were refused and
    the run unhealthy (or, on another drive, 'covariance lost positiveness
    ... check sensor noise settings'), and neither the fixes' sigmas nor
    the keys that put them right were named (found by the review of
    navigate's inputs).  The refusals' reason, and a divergence after the
    fixes were lost, now say what the fixes claim."""
    import dataclasses

    import pandas as pd

    from inskit.jobs.navigate import lost_fixes_hint, run, summary

    sim = _simulate(tmp_path, STATIC_FIRST, 12)
    g = pd.read_csv(tmp_path / "gnss.csv")
    g[["sigma_n_m", "sigma_e_m", "sigma_d_m"]] = 1e-6
    g.to_csv(tmp_path / "g6.csv", index=False)
    cfg = config_from_dict({"imu": {"file": str(tmp_path / "imu.csv")},
                            "gnss": {"file": str(tmp_path / "g6.csv"), "lever_arm_b_m": [0.0, 0.0, -1.2]}})
    s = summary(run(cfg))
    r = [x for x in s["health"]["reasons"] if x.startswith("gnss_pos: ") and "updates rejected (" in x]
    assert s["health"]["verdict"] == "unhealthy" and len(r) == 1
    assert r[0].endswith("; the fixes claim a median sigma of 1e-06 m horizontally and 1e-06 m vertically (as the "
                         "filter takes them, [gnss] sigma_floor_m = 0): fixes noisier than they claim are refused "
                         "until the filter is lost; if they are, floor them ([gnss] sigma_floor_m) or scale them "
                         "(sigma_scale_ned)"), r
    # a divergence's message after the fixes were lost gets the same; one that lost no fix, nothing
    formal = dataclasses.replace(sim.gnss, sigma_ned=np.full_like(sim.gnss.sigma_ned, 1e-6))
    lost = "covariance lost positiveness at t = 31.000 s; before it the filter was lost: gnss_pos 3 of 31 updates used"
    assert "claim a median sigma of 1e-06 m" in lost_fixes_hint(lost, formal, cfg.gnss)
    assert lost_fixes_hint("covariance lost positiveness at t = 31.000 s", formal, cfg.gnss) == ""
    assert lost_fixes_hint("...; before it the filter was lost: nhc 3 of 31 updates used", formal, cfg.gnss) == ""
    # the fixes as they are: nothing of it
    ok = config_from_dict({"imu": {"file": str(tmp_path / "imu.csv")},
                           "gnss": {"file": str(tmp_path / "gnss.csv"), "lever_arm_b_m": [0.0, 0.0, -1.2]}})
    assert not [x for x in summary(run(ok))["health"]["reasons"] if "the fixes claim" in x]
