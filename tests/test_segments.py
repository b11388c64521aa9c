"""Segment trajectories: closed-form calculus and ideal sensors that close."""

import re
from pathlib import Path

import numpy as np
import pytest

from inskit import earth
from inskit import rotations as rot
from inskit.errors import ConfigError
from inskit.simulation import ideal_imu, truth_solution
from inskit.simulation.scenario import build_trajectory, load_scenario
from inskit.simulation.scenario import simulate as simulate_scenario
from inskit.simulation.segments import _NO_POSITION, Channel, SegmentTrajectory, smoothstep, smoothstep_integral
from inskit.strapdown import mechanize

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def test_smoothstep_calculus():
    x = np.linspace(-0.5, 1.5, 20001)
    s, ds, dds = smoothstep(x)
    h = x[1] - x[0]
    assert np.allclose(np.gradient(s, h), ds, atol=1e-6)
    # the third derivative jumps by 60 at x = 0 and 1 (finite jerk, by design), so a
    # central difference of the first derivative is off by up to h * 60 / 2 there
    assert np.allclose(np.gradient(ds, h), dds, atol=h * 60 / 2 * 1.01)
    assert abs(ds).max() == pytest.approx(1.875, rel=1e-3)  # finite jerk, continuous acceleration
    assert np.allclose(np.cumsum(s) * h - s[0] * h, smoothstep_integral(x) - smoothstep_integral(x[0]), atol=2e-4)


def test_channel_matches_numerical_calculus_sorted_and_unsorted():
    ch = Channel(1.0)
    ch.add_pulse(2.0, 1.5, 3.0, 0.7)
    ch.add_step(4.0, 2.0, -0.3)
    t = np.linspace(0.0, 12.0, 12001)
    v, d, dd = ch.eval(t)
    assert np.allclose(np.gradient(v, t), d, atol=1e-5)
    # jerk jumps of 60 A / T^3 at the ends of each step: central-difference bound
    jump = max(60 * abs(A) / T**3 for _, T, A in ch.steps)
    assert np.allclose(np.gradient(d, t), dd, atol=(t[1] - t[0]) * jump / 2 * 1.01)
    num = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    assert np.allclose(ch.integral(t, 0.0), num, atol=1e-6)
    perm = np.random.default_rng(0).permutation(len(t))
    assert np.allclose(ch.eval(t[perm])[0], v[perm])
    assert np.allclose(ch.integral(t[perm], 0.0), ch.integral(t, 0.0)[perm])


def test_segments_do_what_they_say():
    tr = SegmentTrajectory((0.7, 0.2, 100.0), yaw0=0.0, transition_s=2.0)
    tr.static(10).accelerate(10.0, 10).turn(np.radians(90), rate=np.radians(10)).climb(np.radians(5), 20)
    kin = tr.kinematics(np.array([5.0, 20.0, tr.duration - 1e-6]))
    assert np.allclose(kin.v_n[0], 0.0)  # static
    assert np.linalg.norm(kin.v_n[1]) == pytest.approx(10.0)
    yaw_end = np.degrees(np.arctan2(kin.C_nb[2, 1, 0], kin.C_nb[2, 0, 0]))
    assert yaw_end == pytest.approx(90.0, abs=1e-6)
    # climb at 5 deg for 20 s with 2 s ramps: height gain 10 m/s * sin(5 deg) * (20 - 2) s
    assert kin.lla[2, 2] - 100.0 == pytest.approx(10 * np.sin(np.radians(5)) * 18.0, rel=1e-3)
    with pytest.raises(ConfigError, match="still moves"):
        SegmentTrajectory((0.7, 0.2, 0.0)).accelerate(5, 5).static(3)


def _ideal_error(tr, rate):
    t = np.arange(0.0, tr.duration, 1.0 / rate)
    imu = ideal_imu(tr, t, nodes=3)
    truth = truth_solution(tr, t)
    sol = mechanize(imu, truth.state(0))
    d = earth.lla_to_ned(sol.lla, truth.lla[0]) - earth.lla_to_ned(truth.lla, truth.lla[0])
    return np.hypot(d[:, 0], d[:, 1]).max()


def test_car_scenario_ideal_sensors_close_and_converge():
    sc = load_scenario(EXAMPLES / "car.toml")
    tr = build_trajectory(sc, np.random.default_rng(0))
    assert tr.duration >= 1800.0
    e100 = _ideal_error(tr, 100.0)
    e200 = _ideal_error(tr, 200.0)
    assert e100 < 0.5
    assert e100 / e200 > 3.5


@pytest.mark.parametrize("name", ["aircraft", "ship", "static"])
def test_other_scenarios_ideal_sensors(name):
    sc = load_scenario(EXAMPLES / f"{name}.toml")
    tr = build_trajectory(sc, np.random.default_rng(0))
    e1 = _ideal_error(tr, sc.imu.rate_hz)
    assert e1 < 0.5
    if e1 > 1e-6:  # above the numerical floor, the error is second order in the step
        assert e1 / _ideal_error(tr, 2 * sc.imu.rate_hz) > 3.5


def test_scenario_validation(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text('name = "x"\n[start]\nlat_deg = 95\nlon_deg = 0\n[[segment]]\ntype = "static"\nduration_s = 1\n')
    with pytest.raises(ConfigError, match=r"field 'start\.lat_deg'"):
        load_scenario(p)
    p.write_text('name = "x"\n[start]\nlat_deg = 45\nlon_deg = 0\n[[segment]]\ntype = "turn"\nangle_deg = 90\n')
    with pytest.raises(ConfigError, match="needs rate_deg_s or radius_m"):
        build_trajectory(load_scenario(p))


def test_imu_lever_arm_moves_the_sensed_point():
    """An IMU 1.5 m ahead of the truth point: mechanizing its ideal output from
    the IMU's own initial state follows the IMU's path (truth + C_nb l)."""
    lever = np.array([1.5, -0.3, 0.4])
    tr = SegmentTrajectory((0.7, 0.2, 100.0), yaw0=0.0, transition_s=2.0)
    tr.static(5).accelerate(10.0, 5).turn(np.radians(120), rate=np.radians(20)).attitude_pulse("roll", 0.2, 6)
    t = np.arange(0.0, tr.duration, 0.01)
    imu = ideal_imu(tr, t, nodes=3, lever_arm_b=lever)
    truth = truth_solution(tr, t)
    # the IMU point's trajectory, in NED offsets from the start
    off = np.einsum("nij,j->ni", truth.C_nb, lever)
    ref = truth.lla[0]
    p_imu = earth.lla_to_ned(truth.lla, ref) + off
    start = truth.state(0)
    w_nb = tr.kinematics(t[:1]).omega_nb_b[0]
    v0 = start.v_n + start.C_nb @ np.cross(w_nb, lever)
    from inskit.types import NavState

    init = NavState(0.0, earth.ned_to_lla(off[0], ref), v0, start.q_nb)
    sol = mechanize(imu, init)
    err = earth.lla_to_ned(sol.lla, ref) - p_imu
    assert np.hypot(err[:, 0], err[:, 1]).max() < 0.01
    # and without the lever-arm terms the same run is off by far more
    plain = mechanize(ideal_imu(tr, t, nodes=3), init)
    err2 = earth.lla_to_ned(plain.lla, ref) - p_imu
    assert np.hypot(err2[:, 0], err2[:, 1]).max() > 0.1


@pytest.mark.parametrize("gravity", ["normal", "normal-simple", "j2"])
def test_compiled_rates_equal_the_numpy_formulas(gravity):
    sc = load_scenario(EXAMPLES / "aircraft.toml")
    tr = build_trajectory(sc, np.random.default_rng(0))
    tq = np.linspace(0.0, tr.duration, 20001)
    from inskit.simulation import ideal_rates

    w1, f1 = tr.rates(tq, gravity=gravity)
    w2, f2 = ideal_rates(tr.kinematics(tq), gravity)
    assert np.abs(w1 - w2).max() < 1e-15 and np.abs(f1 - f2).max() < 1e-12


def test_compiled_position_integration_matches_a_reference_rk4():
    """The compiled RK4 of (lat, lon, h) against scipy's adaptive solver on
    the car scenario's first 300 s: position agrees to millimetres."""
    from scipy.integrate import solve_ivp
    tr = build_trajectory(load_scenario(EXAMPLES / "car.toml"))
    tr._integrate_position()

    def rhs(t, y):
        v_n, _, _ = tr._velocity(np.atleast_1d(t))
        rn, re = earth.principal_radii(y[0], y[2])
        return [v_n[0, 0] / rn, v_n[0, 1] / (re * np.cos(y[0])), -v_n[0, 2]]

    ref = solve_ivp(rhs, (0.0, 300.0), np.asarray(tr.lla0, float), rtol=1e-11, atol=1e-12, max_step=0.5,
                    dense_output=True)
    t = np.linspace(0.0, 300.0, 61)
    d = earth.lla_to_ned(tr._pos(t), ref.sol(t).T[0]) - earth.lla_to_ned(ref.sol(t).T, ref.sol(t).T[0])
    assert np.abs(d).max() < 1e-3


def test_duration_limit_cuts_the_run(tmp_path):
    from inskit.simulation.scenario import simulate
    text = (EXAMPLES / "car.toml").read_text()
    p = tmp_path / "short.toml"
    p.write_text(text.replace('name = "car"', 'name = "car"\nduration_limit_s = 30.0', 1))
    sc = load_scenario(p)
    assert sc.duration_limit_s == 30.0
    sim = simulate(sc, seed=1)
    assert sim.truth.time[-1] == pytest.approx(30.0, abs=1.0 / sc.imu.rate_hz)
    assert sim.imu.time[-1] <= 30.0 + 1e-9 and sim.gnss.time[-1] <= 30.0 + 1e-9
    full = build_trajectory(load_scenario(EXAMPLES / "car.toml"))
    assert full.duration > 100.0
    p.write_text(text.replace('name = "car"', 'name = "car"\nduration_limit_s = -1.0', 1))
    with pytest.raises(ConfigError):
        load_scenario(p)


def test_duration_limit_bounds_the_work_not_only_the_output(tmp_path, capsys):
    """A 20 s limit on a static segment of 1e7 s integrated the position over
    all 1e7 s (killed after a minute), and on a one-second segment repeated a
    million times built every repetition (3.6 GB, 12 s for 1001 samples); the
    JSON listed all the segments.  Now the segments stop at the limit and the
    position spline covers the run: its grid of 0.05 s has ceil(20 / 0.05) + 2
    rows."""
    import json

    from inskit.cli import main

    head = 'name = "t"\nduration_limit_s = {}\n[start]\nlat_deg = 45\nlon_deg = 10\n'
    p = tmp_path / "long.toml"
    p.write_text(head.format(20) + '[[segment]]\ntype = "static"\nduration_s = 1e7\n')
    tr = build_trajectory(load_scenario(p))
    assert tr.duration == 20.0
    tr._integrate_position()
    assert len(tr._pos.y) == int(np.ceil(20.0 / 0.05)) + 2
    p = tmp_path / "many.toml"
    p.write_text(head.format(10) + '[[segment]]\ntype = "static"\nduration_s = 1\nrepeat = 1000000\n')
    tr = build_trajectory(load_scenario(p))
    assert len(tr.segments) == 10 and tr.duration == 10.0
    with pytest.raises(SystemExit) as exc:
        main(["simulate", str(p), "--out", str(tmp_path / "o"), "--no-plot", "--json"])
    assert exc.value.code == 0
    res = json.loads(capsys.readouterr().out)
    assert res["duration_s"] == 10.0 and len(res["segments"]) == 10 and res["segments"][-1]["end_s"] == 10.0


def test_uniform_hermite_matches_scipy():
    """The simulator's position interpolation (written out to spare the
    scipy.interpolate import) against scipy's CubicHermiteSpline: the same
    cubics inside the grid and beyond its ends, to rounding (1e-14 relative)."""
    from scipy.interpolate import CubicHermiteSpline

    from inskit.simulation.segments import _UniformHermite

    rng = np.random.default_rng(1)
    h, n = 0.05, 1000
    tg = np.arange(n) * h
    y = 0.7 + np.cumsum(rng.normal(size=(n, 3)), axis=0) * 1e-6
    dy = rng.normal(size=(n, 3)) * 1e-6
    t = np.concatenate([rng.uniform(-0.1, tg[-1] + 0.1, 5000), tg[[0, 10, -1]]])
    ref = CubicHermiteSpline(tg, y, dy, axis=0)(t)
    assert np.allclose(_UniformHermite(h, y, dy)(t), ref, rtol=1e-14, atol=0)


def test_the_navigation_shortcut_is_the_kinematics_truth():
    """``SegmentTrajectory.navigation`` (what truth_solution takes without rates) and
    ``navigation_and_rates`` (with them), both by the fused kernel, give the full kinematics' position,
    velocity, attitude (scalar part >= 0), acceleration and rates to rounding."""
    from inskit import rotations as rot
    from inskit.simulation import ideal_rates

    root = Path(__file__).resolve().parents[1]
    tr = build_trajectory(load_scenario(root / "examples" / "car.toml"), np.random.default_rng(3))
    t = np.linspace(0.0, 900.0, 20001)
    kin = tr.kinematics(t)
    fast = truth_solution(tr, t)
    # position by the same spline operations; velocity ~1e-15 relative (the kernel sums in its own order)
    assert np.array_equal(fast.lla, kin.lla) and np.abs(fast.v_n - kin.v_n).max() < 1e-13
    q_ref = rot.quat_from_dcm(kin.C_nb)
    q_ref *= np.where(q_ref[:, :1] < 0, -1.0, 1.0)
    assert np.abs(fast.q_nb - q_ref).max() < 1e-14 and (fast.q_nb[:, 0] >= 0).all()
    for gravity in ("normal", "j2"):
        slow = truth_solution(tr, t, with_rates=True, gravity=gravity)
        assert np.array_equal(slow.lla, fast.lla) and np.array_equal(slow.q_nb, fast.q_nb)
        w, f = ideal_rates(kin, gravity)
        for j, a in enumerate("xyz"):
            assert np.abs(slow.extra[f"w{a}_rad_s"] - w[:, j]).max() < 1e-15
            assert np.abs(slow.extra[f"f{a}_m_s2"] - f[:, j]).max() < 1e-12
        for j, a in enumerate("ned"):
            assert np.abs(slow.extra[f"a{a}_m_s2"] - kin.a_n[:, j]).max() < 1e-12


@pytest.mark.parametrize("name", ["car", "aircraft", "ship", "static"])
def test_fused_kernel_is_the_numpy_state(name):
    """The fused kernel (:func:`segments._state_kernel`) against the NumPy form of the same formulas
    (``_state``), on sorted and shuffled times and times outside the run, per scenario (coning windows,
    banked turns, vibration)."""
    root = Path(__file__).resolve().parents[1]
    path = root / "examples" / f"{name}.toml"
    if not path.is_file():
        pytest.skip(f"no examples/{name}.toml")
    tr = build_trajectory(load_scenario(path), np.random.default_rng(5))
    rng = np.random.default_rng(6)
    t = np.concatenate([np.sort(rng.uniform(-1.0, tr.duration + 1.0, 30000)), [0.0, tr.duration]])
    for times in (t, rng.permutation(t)):
        _, lla, v_n, a_n, rpy, _ = tr._state(times)
        _, o = tr._fused(times, ("lla", "v_n", "a_n", "q_nb"))
        scale_v = max(1.0, np.abs(v_n).max())
        assert np.abs(o["lla"] - lla).max() < 1e-9  # rad and m: the same spline, at most a height rounding
        assert np.abs(o["v_n"] - v_n).max() < 1e-14 * scale_v
        # the quaternion of the same angles (half-angle products, scalar part >= 0): rpy to 1e-13 rad
        assert np.abs(o["a_n"] - a_n).max() < 1e-12 and np.abs(o["q_nb"] - rot.quat_from_euler(rpy)).max() < 1e-13
        assert np.all(o["q_nb"][:, 0] >= 0.0) and np.abs(np.linalg.norm(o["q_nb"], axis=1) - 1.0).max() < 1e-15
        # without a spline: the segments' velocity alone, what the position integrates (no oscillation)
        _, seg = tr._fused(times, ("v_n",), pos=_NO_POSITION)
        v_seg, _, _ = tr._velocity(times)
        assert np.abs(seg["v_n"] - v_seg).max() < 1e-14 * scale_v


def test_fused_kernel_with_overlapping_steps():
    """Steps of one channel that overlap or end out of order (a long step started before a short one) are
    summed as ``Channel.eval`` and ``Channel.integral`` sum them."""
    tr = SegmentTrajectory((0.7, 0.2, 100.0), yaw0=0.3, speed0=5.0)
    tr.cruise(60.0)
    tr.speed.add_step(5.0, 30.0, 4.0)       # ends at 35 s
    tr.speed.add_step(10.0, 5.0, -2.0)      # starts later, ends first (15 s)
    tr.rate_flat.add_step(20.0, 20.0, 0.05)
    tr.rate_flat.add_step(25.0, 2.0, -0.02)
    tr.rate_bank.add_step(30.0, 4.0, 0.03)
    t = np.linspace(0.0, 60.0, 6001)
    _, lla, v_n, a_n, rpy, _ = tr._state(t)
    _, o = tr._fused(t, ("lla", "v_n", "a_n", "q_nb"))
    assert np.abs(o["v_n"] - v_n).max() < 1e-13 and np.abs(o["a_n"] - a_n).max() < 1e-13
    assert np.abs(o["q_nb"] - rot.quat_from_euler(rpy)).max() < 1e-13 and np.abs(o["lla"] - lla).max() < 1e-9


def test_fused_kernel_in_threads_is_bit_identical(monkeypatch):
    """A long run's times split among threads (each chunk sweeping the steps from the start) give the very
    bits of one pass, at any split."""
    from inskit.simulation import segments

    root = Path(__file__).resolve().parents[1]
    tr = build_trajectory(load_scenario(root / "examples" / "aircraft.toml"), np.random.default_rng(2))
    t = np.sort(np.random.default_rng(3).uniform(0.0, tr.duration, 50001))
    monkeypatch.setattr(segments, "_PARALLEL_MIN", 10**12)
    one = tr._fused(t, ("lla", "v_n", "a_n", "q_nb", "w_ib", "f_b"))[1]
    monkeypatch.setattr(segments, "_PARALLEL_MIN", 10)
    monkeypatch.setattr("os.cpu_count", lambda: 3)
    assert len(segments._chunks(len(t))) == 3
    split = tr._fused(t, ("lla", "v_n", "a_n", "q_nb", "w_ib", "f_b"))[1]
    for k in one:
        assert np.array_equal(one[k], split[k]), k


# --- the scenario's rules: each segment type takes exactly its keys -------------------------------------
_HEAD = 'name = "x"\n[start]\nlat_deg = 45\nlon_deg = 7\nspeed_m_s = 10\n[imu]\nrate_hz = 100\n'
#: one valid segment of every type, from a speed of 10 m/s
_VALID = {
    "static": None,  # needs the vehicle at rest: tested from 0 m/s below
    "accelerate": {"speed_m_s": 15, "duration_s": 5},
    "decelerate": {"speed_m_s": 5, "duration_s": 5},
    "cruise": {"duration_s": 5},
    "turn": {"angle_deg": 90, "radius_m": 30},
    "banked-turn": {"angle_deg": 90, "rate_deg_s": 10},
    "climb": {"angle_deg": 5, "duration_s": 10},
    "descend": {"angle_deg": 5, "duration_s": 10},
    "pitch": {"amplitude_deg": 5, "duration_s": 6},
    "roll": {"amplitude_deg": 5, "duration_s": 6},
    "coning": {"amplitude_deg": 1, "frequency_hz": 2, "duration_s": 4},
    "figure-eight": {"radius_m": 30},
}
_ANY = {"duration_s": 5, "speed_m_s": 5, "angle_deg": 10, "rate_deg_s": 10, "radius_m": 5, "amplitude_deg": 3,
        "frequency_hz": 2}


def _segments(tmp_path, *segs, head=_HEAD, extra=""):
    """A scenario file of ``segs`` (dicts with 'type'), loaded."""
    text = head + extra
    for s in segs:
        text += "[[segment]]\n" + "".join(f"{k} = {v!r}\n".replace("'", '"') for k, v in s.items())
    p = tmp_path / "s.toml"
    p.write_text(text)
    return load_scenario(p)


@pytest.mark.parametrize("kind", ["climb", "descend"])
def test_a_climb_at_rest_is_refused(tmp_path, kind):
    """A climb at speed 0 was a silent no-op (height and pitch stayed 0), while a turn by radius at rest was
    refused: now it is refused too, naming the segment."""
    sc = _segments(tmp_path, {"type": kind, "angle_deg": 5, "duration_s": 10}, head=_HEAD.replace("speed_m_s = 10\n", ""))
    with pytest.raises(ConfigError, match=rf"segment 1 \({kind}\): the vehicle is at rest \(speed 0 m/s\): a climb "
                                          r"or descent at rest changes neither height nor attitude; accelerate first"):
        build_trajectory(sc)
    build_trajectory(_segments(tmp_path, {"type": kind, "angle_deg": 5, "duration_s": 10}))  # at 10 m/s


def test_the_rule_table_covers_every_segment_type_and_the_docs():
    from inskit.simulation.scenario import SEGMENT_RULES, SegmentSpec, segment_keys_text

    assert set(SEGMENT_RULES) == set(_VALID)
    doc = (EXAMPLES.parent / "docs" / "config.md").read_text()
    assert segment_keys_text() in doc  # the docs list the table's keys (regenerated from it)
    assert SEGMENT_RULES["figure-eight"].keys == ("radius_m",)
    assert SEGMENT_RULES["turn"].one_of == ("rate_deg_s", "radius_m")
    assert {k for r in SEGMENT_RULES.values() for k in r.keys} | {"type", "repeat"} == set(SegmentSpec.model_fields)


@pytest.mark.parametrize("kind", [k for k in _VALID if k != "static"])
def test_every_segment_type_takes_exactly_its_keys(tmp_path, kind):
    """A key the type would ignore is refused by name, with the type's keys; the valid segment builds."""
    from inskit.simulation.scenario import SEGMENT_RULES

    rule = SEGMENT_RULES[kind]
    sc = _segments(tmp_path, {"type": "cruise", "duration_s": 1}, {"type": kind, **_VALID[kind], "repeat": 1})
    build_trajectory(sc)
    for key, value in _ANY.items():
        if key in rule.keys:
            continue
        with pytest.raises(ConfigError) as exc:
            _segments(tmp_path, {"type": "cruise", "duration_s": 1}, {"type": kind, **_VALID[kind], key: value})
        msg = str(exc.value)
        assert msg.startswith(f"{tmp_path / 's.toml'}: segment 2 ({kind}): {key} is not a key of a {kind} segment")
        assert f"a {kind} segment takes {rule.takes()} and repeat" in msg
    for key in rule.needs:  # and a key it needs is needed
        seg = {k: v for k, v in _VALID[kind].items() if k != key}
        with pytest.raises(ConfigError, match=rf"segment 1 \({kind}\) needs {key}"):
            _segments(tmp_path, {"type": kind, **seg})


@pytest.mark.parametrize("seg, key", [
    ({"type": "cruise", "duration_s": 10, "radius_m": 5}, "radius_m"),
    ({"type": "climb", "angle_deg": 5, "duration_s": 10, "amplitude_deg": 3}, "amplitude_deg"),
    ({"type": "climb", "angle_deg": 5, "duration_s": 10, "frequency_hz": 2}, "frequency_hz"),
    ({"type": "figure-eight", "radius_m": 30, "duration_s": 1}, "duration_s"),
    ({"type": "static", "duration_s": 10, "speed_m_s": 3}, "speed_m_s"),
])
def test_the_reviewers_ignored_keys_are_refused(tmp_path, seg, key):
    with pytest.raises(ConfigError, match=rf"s\.toml: segment 1 \({seg['type']}\): {key} is not a key .*ignored.* "
                                          rf"a {seg['type']} segment takes"):
        _segments(tmp_path, seg)


def test_a_turn_takes_a_rate_or_a_radius_not_both(tmp_path):
    for kind in ("turn", "banked-turn"):
        with pytest.raises(ConfigError, match=rf"segment 1 \({kind}\): give rate_deg_s or radius_m, not both "
                                              r"\(got rate_deg_s 1 and radius_m 100\)"):
            _segments(tmp_path, {"type": kind, "angle_deg": 90, "radius_m": 100, "rate_deg_s": 1})
        with pytest.raises(ConfigError, match=rf"segment 1 \({kind}\) needs rate_deg_s or radius_m"):
            _segments(tmp_path, {"type": kind, "angle_deg": 90})


def test_accelerate_speeds_up_and_decelerate_slows_down(tmp_path):
    for kind, to, word in (("decelerate", 20, "below"), ("decelerate", 10, "below"), ("accelerate", 5, "above"),
                           ("accelerate", 10, "above")):
        sc = _segments(tmp_path, {"type": "cruise", "duration_s": 5}, {"type": kind, "speed_m_s": to, "duration_s": 5})
        with pytest.raises(ConfigError, match=rf"s\.toml: segment 2 \({kind}\): speed_m_s {to} is not {word} the "
                                              r"current speed 10 m/s"):
            build_trajectory(sc)
    # the current speed is the one the segments before leave, in a repeated segment too
    sc = _segments(tmp_path, {"type": "accelerate", "speed_m_s": 14, "duration_s": 5},
                   {"type": "decelerate", "speed_m_s": 0, "duration_s": 5, "repeat": 2})
    with pytest.raises(ConfigError, match=r"segment 2 \(decelerate\), repetition 2 of 2: speed_m_s 0 is not below "
                                          r"the current speed 0 m/s"):
        build_trajectory(sc)
    tr = build_trajectory(_segments(tmp_path, {"type": "decelerate", "speed_m_s": 4, "duration_s": 5},
                                    {"type": "accelerate", "speed_m_s": 12, "duration_s": 5}))
    assert tr.end_speed == pytest.approx(12.0)


def test_a_refusal_while_building_names_the_files_segment(tmp_path):
    """A figure eight adds two turns: the static after it is segment 3 of the file (the builder counted 4)."""
    sc = _segments(tmp_path, {"type": "cruise", "duration_s": 5}, {"type": "figure-eight", "radius_m": 30},
                   {"type": "static", "duration_s": 5})
    with pytest.raises(ConfigError, match=r"^.*s\.toml: segment 3 \(static\): the vehicle still moves"):
        build_trajectory(sc)
    sc = _segments(tmp_path, {"type": "turn", "angle_deg": 90, "radius_m": 30},
                   head=_HEAD.replace("speed_m_s = 10", "speed_m_s = 0"))
    with pytest.raises(ConfigError, match=r"s\.toml: segment 1 \(turn\): a turn by radius needs speed > 0"):
        build_trajectory(sc)


def test_a_climb_is_a_flight_path_angle_below_90_deg(tmp_path):
    for kind in ("climb", "descend"):
        for a in (200, 90, -90, 90.5):
            with pytest.raises(ConfigError, match=rf"segment 1 \({kind}\): angle_deg {a:g} is no flight-path angle: "
                                                  r"\|angle_deg\| must be below 90"):
                _segments(tmp_path, {"type": kind, "angle_deg": a, "duration_s": 10})
    tr = build_trajectory(_segments(tmp_path, {"type": "climb", "angle_deg": 60, "duration_s": 10},
                                    {"type": "descend", "angle_deg": -60, "duration_s": 10}))
    k = tr.kinematics(np.array([0.0, 10.0, 20.0]))
    assert k.lla[1, 2] > k.lla[0, 2] + 50 and k.lla[2, 2] == pytest.approx(k.lla[0, 2], abs=1e-6)  # up, then down
    assert k.v_n[1, 0] > 0  # still flying forwards
    with pytest.raises(ConfigError, match=r"flight-path angle must be within \(-90, 90\) deg"):
        SegmentTrajectory((0.7, 0.2, 0.0), speed0=10.0).climb(np.radians(200), 10.0)


@pytest.mark.parametrize("windows, said", [
    ("[[20.0, 10.0]]", "window 1 [20, 10] ends before it starts"),
    ("[[5.0, 8.0], [10.0, 10.0]]", "window 2 [10, 10] is empty"),
    ("[[-5.0, 8.0]]", "window 1 [-5, 8] starts before the scenario"),
])
def test_an_outage_window_that_is_no_window_is_refused(tmp_path, windows, said):
    with pytest.raises(ConfigError, match=rf"s\.toml: field 'gnss\.outages_s': {re.escape(said)}"):
        _segments(tmp_path, {"type": "cruise", "duration_s": 30}, extra=f"[gnss]\noutages_s = {windows}\n")
    with pytest.raises(ConfigError, match=r"field 'raw_gnss\.blockage\.0': end_s \(10\.0\) must come after start_s"):
        _segments(tmp_path, {"type": "cruise", "duration_s": 30},
                  extra="[[raw_gnss.blockage]]\nstart_s = 20.0\nend_s = 10.0\n")
    sc = _segments(tmp_path, {"type": "cruise", "duration_s": 30}, extra="[gnss]\noutages_s = [[10.0, 20.0]]\n")
    assert sc.gnss.outages_s == [(10.0, 20.0)]


@pytest.mark.parametrize("vib, said", [
    ('target = "roll"\namplitude = 0.1\nfrequency_hz = 5\nband_hz = [4, 6]', r'band_hz is for kind = "random"'),
    ('target = "roll"\namplitude = 0.1', r" needs frequency_hz"),
    ('target = "roll"\namplitude = 0.1\nkind = "random"\nfrequency_hz = 5\nband_hz = [4, 6]', "not both"),
    ('target = "roll"\namplitude = 0.1\nkind = "random"', "give frequency_hz .* or band_hz, one of them"),
    ('target = "roll"\namplitude = 0.1\nkind = "random"\nband_hz = [6, 4]', r"band_hz \[6, 4\] is no band"),
])
def test_a_vibration_takes_the_keys_of_its_kind(tmp_path, vib, said):
    with pytest.raises(ConfigError, match=rf"s\.toml: vibration 1 \(roll, \w+\).*{said}"):
        _segments(tmp_path, {"type": "cruise", "duration_s": 5}, extra=f"[[vibration]]\n{vib}\n")


@pytest.mark.parametrize("extra, where, said", [
    ("", "segment 1 (coning)", ("frequency_hz 200 Hz is at or above the Nyquist frequency of the IMU (50 Hz at "
                                "imu.rate_hz 100)")),
    ("[[vibration]]\ntarget = \"down\"\namplitude = 0.001\nfrequency_hz = 50\n", "vibration 1 (down, sinusoidal)",
     "frequency_hz 50 Hz is at or above the Nyquist frequency"),
    ("[[vibration]]\ntarget = \"yaw\"\namplitude = 0.1\nkind = \"random\"\nfrequency_hz = 40\n",
     "vibration 1 (yaw, random)", "the top of the band of frequency_hz 40 (1.5 x), 60 Hz, is at or above the Nyquist"),
    ("[[vibration]]\ntarget = \"yaw\"\namplitude = 0.1\nkind = \"random\"\nband_hz = [10, 55]\n",
     "vibration 1 (yaw, random)", "the top of band_hz, 55 Hz, is at or above the Nyquist"),
])
def test_motion_faster_than_the_imu_samples_is_refused(tmp_path, extra, where, said):
    """Coning at 200 Hz on a 100 Hz IMU drifted 16.5 m in 2 s in the --verify check, unannounced."""
    seg = {"type": "coning", "amplitude_deg": 1, "frequency_hz": 200 if not extra else 2, "duration_s": 2}
    with pytest.raises(ConfigError, match=re.escape(f"s.toml: {where}: {said}")):
        _segments(tmp_path, seg, extra=extra)


def test_motion_just_below_nyquist_is_simulated_and_verifies(tmp_path):
    """At 49 Hz on a 100 Hz IMU (3 quadrature nodes) the increments are within 0.1 % and the simulator's
    self-check stays at millimetres; with 2 nodes the quadrature sets a lower limit, named."""
    from inskit.jobs.simulate import verify_ideal

    for sc in (_segments(tmp_path, {"type": "coning", "amplitude_deg": 1, "frequency_hz": 49, "duration_s": 2}),
               _segments(tmp_path, {"type": "cruise", "duration_s": 2},
                         extra="[[vibration]]\ntarget = \"down\"\namplitude = 0.0005\nfrequency_hz = 49.9\n")):
        v = verify_ideal(sc)["frames"]["ned"]
        assert v["horizontal_max_m"] < 1e-3 and v["vertical_max_m"] < 5e-3, v
    head = _HEAD.replace("rate_hz = 100\n", "rate_hz = 100\nquadrature_nodes = 2\n")
    with pytest.raises(ConfigError, match=r"segment 1 \(coning\): frequency_hz 30 Hz is above the 22.6 Hz up to "
                                          r"which imu.quadrature_nodes 2 integrate the increments at imu.rate_hz 100 "
                                          r"to 0.1%"):
        _segments(tmp_path, {"type": "coning", "amplitude_deg": 1, "frequency_hz": 30, "duration_s": 2}, head=head)
    _segments(tmp_path, {"type": "coning", "amplitude_deg": 1, "frequency_hz": 22, "duration_s": 2}, head=head)


def test_a_scenario_made_in_code_is_checked_when_built():
    from inskit.simulation.scenario import Scenario

    sc = Scenario.model_validate({"name": "x", "start": {"lat_deg": 45, "lon_deg": 7},
                                  "segment": [{"type": "cruise", "duration_s": 5, "radius_m": 5}]})
    with pytest.raises(ConfigError, match=r"^segment 1 \(cruise\): radius_m is not a key"):
        build_trajectory(sc)


def _scenario(tmp_path, start, segments):
    p = tmp_path / "s.toml"
    p.write_text(f"name = \"s\"\n[start]\n{start}\n[imu]\nrate_hz = 20.0\n{segments}")
    return p


@pytest.mark.parametrize("start, where, said", [
    ("lat_deg = 89.9999\nlon_deg = 10\nspeed_m_s = 30", "segment 1 (cruise)", "north pole at t = 0.2"),
    ("lat_deg = 90\nlon_deg = 10\nyaw_deg = 90\nspeed_m_s = 10", "segment 1 (cruise)", "north pole at t = 0.00 s"),
    ("lat_deg = -89.999\nlon_deg = 10\nyaw_deg = 180\nspeed_m_s = 50", "segment 1 (cruise)", "south pole at t = 2.1"),
])
def test_a_trajectory_over_a_pole_is_refused_naming_the_segment(tmp_path, start, where, said):
    """A cruise over the pole went past 90 deg of latitude (from the pole itself, east: a longitude of 2.6e8
    rad) and was refused as "`lla` holds a latitude of 1.5707963 rad ... degrees where radians are expected?
    (np.radians)"."""
    p = _scenario(tmp_path, start, "[[segment]]\ntype = \"cruise\"\nduration_s = 10.0\n")
    with pytest.raises(ConfigError, match=rf"^{re.escape(str(p))}: {re.escape(where)}: the trajectory reaches the "
                                          rf"{said}.* while moving; .* cannot pass over a pole"):
        ideal_imu(build_trajectory(load_scenario(p)), np.arange(0.0, 10.0, 0.05))


def test_at_rest_on_the_pole_and_circling_it_past_a_full_turn_simulate(tmp_path):
    """Rest on the pole is a position; a vehicle circling the pole (or the globe) past a full turn of longitude
    was refused as "`lla` holds a longitude of 6.28 rad ... degrees where radians are expected?": now its
    longitudes are wrapped into (-180, 180] deg and its ideal IMU, mechanized in the wander-azimuth frame,
    reproduces the truth."""
    tr = build_trajectory(load_scenario(_scenario(tmp_path, "lat_deg = 90\nlon_deg = 10",
                                                  "[[segment]]\ntype = \"static\"\nduration_s = 5.0\n")))
    # at 200 Hz the interpolated latitude was pi/2 + 2 ulp at some rows, refused as 'degrees where radians ...'
    lat = truth_solution(tr, np.arange(0.0, 5.0, 0.005)).lla[:, 0]
    assert np.all(lat <= np.pi / 2) and lat == pytest.approx(np.pi / 2, abs=1e-12)
    # 89.999 deg: a circle of 700 m, 70 s at 10 m/s: 200 s is nearly three full turns of longitude
    tr = build_trajectory(load_scenario(_scenario(tmp_path, "lat_deg = 89.999\nlon_deg = 170\nyaw_deg = 90\n"
                                                  "speed_m_s = 10", "[[segment]]\ntype = \"cruise\"\n"
                                                  "duration_s = 200.0\n")))
    t = np.arange(0.0, 200.0 + 1e-9, 0.05)
    truth = truth_solution(tr, t)
    lon = truth.lla[:, 1]
    assert np.all((lon > -np.pi) & (lon <= np.pi))
    assert np.unwrap(lon)[-1] - lon[0] > 2 * 2 * np.pi  # more than two full turns of longitude
    sol = mechanize(ideal_imu(tr, t), truth.state(0), frame="wander")
    d = earth.lla_to_ecef(sol.lla) - earth.lla_to_ecef(truth.lla)
    assert np.abs(d).max() < 0.02  # 7 mm here at 20 Hz after 200 s of turning 5 deg/s; a wrap wrong by 2 pi: km


@pytest.mark.parametrize("start, seg, where, said", [
    ("speed_m_s = 300", "type = \"descend\"\nangle_deg = 80\nduration_s = 1000", "segment 2 (descend)",
     r"-100,0\d\d m at t = 34\d\.\d\d s"),
    ("speed_m_s = 3000", "type = \"climb\"\nangle_deg = 80\nduration_s = 1000", "segment 2 (climb)",
     r"100,\d\d\d m at t = 3\d\.\d\d s"),
])
def test_a_trajectory_beyond_100_km_of_height_is_refused(tmp_path, start, seg, where, said):
    """A descent at 80 deg for 1000 s at 300 m/s went 295 km into the Earth and wrote a truth file that
    inskit's own reader refused ('height_m=-100001.5 is beyond +-100 km of the ellipsoid')."""
    p = _scenario(tmp_path, f"lat_deg = 45\nlon_deg = 10\n{start}",
                  f"[[segment]]\ntype = \"cruise\"\nduration_s = 5.0\n[[segment]]\n{seg}\n")
    with pytest.raises(ConfigError, match=rf"^{re.escape(str(p))}: {re.escape(where)}: the trajectory's height "
                                          rf"reaches {said}, beyond \+-100 km"):
        simulate_scenario(load_scenario(p))


def test_a_speed_beyond_the_readers_limit_is_refused(tmp_path):
    """An accelerate to 20 km/s was simulated and wrote a truth file that inskit's own reader refused
    ('vn_m_s=12009.3 is beyond +-12000 m/s'); now the scenario is refused, naming the segment."""
    p = _scenario(tmp_path, "lat_deg = 45\nlon_deg = 10",
                  "[[segment]]\ntype = \"accelerate\"\nspeed_m_s = 20000\nduration_s = 5.0\n")
    with pytest.raises(ConfigError, match=rf"^{re.escape(str(p))}: segment 1 \(accelerate\): a velocity component "
                                          r"reaches 12,\d\d\d m/s at t = 2\.\d\d s, beyond \+-12000 m/s"):
        simulate_scenario(load_scenario(p))
    p.write_text(p.read_text().replace("20000", "11000"))
    assert simulate_scenario(load_scenario(p)).truth.v_n[:, 0].max() == pytest.approx(11000.0, rel=1e-6)


def test_a_down_vibration_beyond_100_km_is_refused_naming_the_file(tmp_path):
    """[[vibration]] target = "down", amplitude = 2e5 (metres: a unit slipped) wrote a truth file of heights to
    -190 km that inskit's reader refused."""
    p = _scenario(tmp_path, "lat_deg = 45\nlon_deg = 10", "[[vibration]]\ntarget = \"down\"\namplitude = 2e5\n"
                  "frequency_hz = 0.01\n[[segment]]\ntype = \"static\"\nduration_s = 30.0\n")
    with pytest.raises(ConfigError, match=rf"^{re.escape(str(p))}: \[\[vibration\]\]: the 'down' vibration \(200,000 m "
                                          r"of amplitude\) takes the height beyond \+-100 km of the ellipsoid"):
        simulate_scenario(load_scenario(p))
    p.write_text(p.read_text().replace("amplitude = 2e5", "amplitude = 0.5"))
    assert np.ptp(simulate_scenario(load_scenario(p)).truth.lla[:, 2]) == pytest.approx(0.5, abs=0.01)  # 30 s of 100 s


def test_the_simulation_kernels_load_from_the_cache_without_numbas_array_module():
    """The compiled kernels of a simulation allocate nothing (the caller passes their work arrays): loaded from
    the cache, a function that allocates has numba import ``numba.np.arrayobj`` and what it pulls in (40 ms of
    every ``inskit simulate``). The first run fills the cache if need be; the second loads from it."""
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    script = (
        "import sys\n"
        "import numpy as np\n"
        "from inskit.simulation.scenario import load_scenario, simulate\n"
        f"sc = load_scenario({str(root / 'examples' / 'car.toml')!r})\n"
        "sim = simulate(sc.model_copy(update={'duration_limit_s': 30.0}), seed=1)\n"
        "assert len(sim.imu) > 100 and np.isfinite(sim.truth.lla).all()\n"
        "print('arrayobj', 'numba.np.arrayobj' in sys.modules)\n"
    )
    for _ in range(2):
        p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
        assert p.returncode == 0, p.stderr[-2000:]
    assert p.stdout.split() == ["arrayobj", "False"]


def test_the_numpy_hermite_is_the_compiled_one_to_the_bit():
    """Below ``_HERMITE_COMPILED_MIN`` times the position spline runs in NumPy (no cache load for the GNSS
    fixes' few thousand times): the same numbers as the compiled sweep, inside the grid, on its nodes and
    beyond its ends (extrapolated end cubics), for a spline that reproduces a cubic exactly."""
    from inskit.simulation import segments

    h = 0.05
    tg = np.arange(41) * h
    y = np.column_stack([0.7 + 1e-6 * tg**3, -1.9 + 2e-6 * tg**2, 1600.0 - 3.0 * tg + 0.5 * tg**3])
    dy = np.column_stack([3e-6 * tg**2, 4e-6 * tg, -3.0 + 1.5 * tg**2])
    rng = np.random.default_rng(4)
    t = np.concatenate([rng.uniform(-0.3, 2.3, 5000), tg, [tg[-1] + 1e-12]])
    fast = segments._hermite_numpy(h, y, dy, t)
    slow = np.empty_like(fast)
    segments._hermite_rows(h, y, dy, t, slow)
    assert fast.shape == (len(t), 3) and np.array_equal(fast, slow)
    exact = np.column_stack([0.7 + 1e-6 * t**3, -1.9 + 2e-6 * t**2, 1600.0 - 3.0 * t + 0.5 * t**3])
    assert np.abs(fast - exact).max() < 1e-12 * 1600.0  # a cubic's Hermite spline is the cubic (to rounding)
    small = segments._UniformHermite(h, y, dy)(t[:10])
    assert np.array_equal(small, slow[:10])
