"""Segment trajectories: closed-form calculus and ideal sensors that close."""

from pathlib import Path

import numpy as np
import pytest

from inskit import earth
from inskit.errors import ConfigError
from inskit.simulation import ideal_imu, truth_solution
from inskit.simulation.scenario import build_trajectory, load_scenario
from inskit.simulation.segments import Channel, SegmentTrajectory, smoothstep, smoothstep_integral
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
        _, o = tr._fused(times, ("lla", "v_n", "a_n", "rpy"))
        scale_v = max(1.0, np.abs(v_n).max())
        assert np.abs(o["lla"] - lla).max() < 1e-9  # rad and m: the same spline, at most a height rounding
        assert np.abs(o["v_n"] - v_n).max() < 1e-14 * scale_v
        assert np.abs(o["a_n"] - a_n).max() < 1e-12 and np.abs(o["rpy"] - rpy).max() < 1e-13


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
    _, o = tr._fused(t, ("lla", "v_n", "a_n", "rpy"))
    assert np.abs(o["v_n"] - v_n).max() < 1e-13 and np.abs(o["a_n"] - a_n).max() < 1e-13
    assert np.abs(o["rpy"] - rpy).max() < 1e-13 and np.abs(o["lla"] - lla).max() < 1e-9


def test_fused_kernel_in_threads_is_bit_identical(monkeypatch):
    """A long run's times split among threads (each chunk sweeping the steps from the start) give the very
    bits of one pass, at any split."""
    from inskit.simulation import segments

    root = Path(__file__).resolve().parents[1]
    tr = build_trajectory(load_scenario(root / "examples" / "aircraft.toml"), np.random.default_rng(2))
    t = np.sort(np.random.default_rng(3).uniform(0.0, tr.duration, 50001))
    monkeypatch.setattr(segments, "_PARALLEL_MIN", 10**12)
    one = tr._fused(t, ("lla", "v_n", "a_n", "rpy", "w_ib", "f_b"))[1]
    monkeypatch.setattr(segments, "_PARALLEL_MIN", 10)
    monkeypatch.setattr("os.cpu_count", lambda: 3)
    assert len(segments._chunks(len(t))) == 3
    split = tr._fused(t, ("lla", "v_n", "a_n", "rpy", "w_ib", "f_b"))[1]
    for k in one:
        assert np.array_equal(one[k], split[k]), k
