"""Bad input to the integration job: clear messages, never NaN in a solution."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from inskit.errors import ConfigError, InputError
from inskit.filters.kalman import FilterDivergence, check_covariance, joseph_update
from inskit.integration import FilterSettings, GnssPosition, SensorNoise, run_filter
from inskit.jobs.config import load_config
from inskit.jobs.navigate import navigate
from inskit.io.rtklib import read_pos
from inskit.simulation import StationaryTrajectory, ideal_imu, truth_solution
from inskit.types import GnssData, ImuData, NavState

ROOT = Path(__file__).resolve().parents[1]
POS = ROOT / "data" / "drive_0708" / "gnss_1934_sf.pos.gz"


def pos_lines():
    import gzip

    return gzip.open(POS, "rt").read().splitlines(True)


def test_pos_zero_sigma_names_line(tmp_path):
    lines = pos_lines()
    i = next(k for k, l in enumerate(lines) if not l.startswith("%")) + 5
    f = lines[i].split()
    f[7] = "0.0000000"  # sdn
    lines[i] = " ".join(f) + "\n"
    p = tmp_path / "bad.pos"
    p.write_text("".join(lines))
    with pytest.raises(InputError, match=rf"bad\.pos: line {i + 1}: a position sigma is 0\.0"):
        read_pos(p)


def test_pos_nan_row_names_line(tmp_path):
    lines = pos_lines()
    i = next(k for k, l in enumerate(lines) if not l.startswith("%")) + 3
    f = lines[i].split()
    f[2] = "nan"
    lines[i] = " ".join(f) + "\n"
    p = tmp_path / "bad.pos"
    p.write_text("".join(lines))
    with pytest.raises(InputError, match=rf"line {i + 1}: column 'latitude\(deg\)'"):
        read_pos(p)


def test_gnss_data_refuses_zero_and_negative_sigma():
    with pytest.raises(InputError, match="sigma_ned"):
        GnssData([0.0, 1.0], np.zeros((2, 3)), [[0.1, 0.1, 0.1], [0.1, 0.0, 0.1]])
    with pytest.raises(InputError, match="sigma_ned"):
        GnssData([0.0, 1.0], np.zeros((2, 3)), [[0.1, -0.1, 0.1], [0.1, 0.1, 0.1]])


def test_mismatched_time_bases(tmp_path):
    cfg = load_config(ROOT / "examples" / "drive_0708.toml",
                      {"imu": {"time_offset_s": 1e6}, "output": {"plots": False}})
    with pytest.raises(InputError, match="do not overlap: mismatched time bases"):
        navigate(cfg)


def test_config_errors_name_the_field(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text('[imu]\nfile = "a.csv"\n[gnss]\nfile = "b.csv"\n[noise]\ngyro_arw_deg_sqrt_h = -1\n')
    with pytest.raises(ConfigError, match=r"c\.toml: field 'noise\.gyro_arw_deg_sqrt_h': Input should be greater"):
        load_config(p)
    p.write_text('[imu]\nfile = "a.csv"\n[gnss]\nfile = "b.csv"\nbogus = 1\n')
    with pytest.raises(ConfigError, match=r"field 'gnss\.bogus'"):
        load_config(p)
    p.write_text('[imu\n')
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_config(p)


def _static_setup(n=500):
    traj = StationaryTrajectory((0.7, 0.1, 10.0))
    t = np.arange(n) * 0.01
    imu = ideal_imu(traj, t, nodes=1)
    truth = truth_solution(traj, t)
    g = GnssData(t[::25], truth.lla[::25], np.full((len(t[::25]), 3), 0.05))
    return imu, truth, g


def test_diverging_filter_stops_with_a_message():
    imu, truth, g = _static_setup()
    dv = imu.dv_b.copy()
    dv[200] = 1e200  # a corrupt sample that survives the readers
    bad = ImuData(imu.time, imu.dtheta_b, dv)
    with pytest.raises(FilterDivergence, match="diverged"):
        run_filter(bad, truth.state(0), [GnssPosition(g)], FilterSettings())


def test_covariance_checks():
    with pytest.raises(FilterDivergence, match="positiveness"):
        check_covariance(np.diag([1.0, -1.0]))
    with pytest.raises(FilterDivergence, match="not positive definite"):
        joseph_update(np.diag([1.0, 1.0]), [1.0], [[1.0, 0.0]], [[-5.0]])


def test_gnss_outside_imu_span_is_skipped_and_counted():
    imu, truth, g = _static_setup()
    late = GnssData(g.time + 100.0, g.lla, g.sigma_ned)
    out = run_filter(imu, truth.state(0), [GnssPosition(late)], FilterSettings())
    assert out.counts["gnss_pos"]["skipped"] == len(late)
    assert np.isfinite(out.solution.lla).all()


def test_settings_refuse_impossible_values():
    with pytest.raises(InputError, match="scheme"):
        FilterSettings(scheme="tight")
    with pytest.raises(InputError, match="gyro_arw"):
        SensorNoise(0.0, 1e-3, 1e-5, 1e-4)
    with pytest.raises(InputError, match="uncoupled"):
        FilterSettings(scheme="uncoupled")


def test_cli_navigate_bad_config_one_line(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text('[imu]\nfile = "missing.csv"\n[gnss]\nfile = "missing.pos"\nformat = "rtklib-pos"\n')
    r = subprocess.run([sys.executable, "-m", "inskit.cli", "navigate", str(p), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True)
    assert r.returncode == 2
    # the first input missing, named by its key (every input is checked before any is read)
    assert r.stderr.strip().count("\n") == 0 and "missing.csv: no such file (field 'imu.file')" in r.stderr


class _RowFix:
    """Three scalar position fixes per epoch (north, east, down), gated per row."""

    name = "rows"
    gating = "row"

    def __init__(self, t, z, sigma, lla0):
        self.t, self.z, self.sigma, self.lla0 = t, z, sigma, lla0

    def times(self):
        return self.t

    def rows(self):
        return np.arange(len(self.t))

    def linearize(self, ctx, row):
        from inskit.integration.measurements import ned_difference

        H = np.zeros((3, ctx.layout.size))
        H[:, 0:3] = np.eye(3)
        return ned_difference(ctx.lla, self.lla0) - self.z[row], H, np.eye(3) * self.sigma**2


def test_row_gating_drops_only_the_bad_row():
    """One component 50 m off at one epoch: with per-row gating that row is
    refused and the other two are used; with vector gating the whole fix goes."""
    imu, truth, g = _static_setup(2000)
    t = imu.time[50::100]
    z = np.zeros((len(t), 3))
    z[5, 1] = 50.0
    meas = _RowFix(t, z, 0.5, truth.lla[0])
    out = run_filter(imu, truth.state(0), [meas], FilterSettings())
    assert out.counts["rows"]["used"] == len(t)
    assert out.counts["rows"]["rejected"] == 1
    nu, sig = out.innovations["rows"]["nu"][5], out.innovations["rows"]["sigma"][5]
    assert abs(nu[1] / sig[1]) > 10 and np.all(np.abs(nu[[0, 2]] / sig[[0, 2]]) < 4)  # recorded whole
    meas.gating = "vector"
    out2 = run_filter(imu, truth.state(0), [meas], FilterSettings())
    assert out2.counts["rows"]["used"] == len(t) - 1 and out2.counts["rows"]["rejected"] == 1


def test_a_row_gated_measurement_refused_whole_is_a_rejection_run():
    """Every row refused at several epochs in a row (the fixes jump by 20 m
    and stay) counts as consecutive rejections of the measurement, so the
    lost-filter recovery applies to row-gated measurements too (it used to
    fail on the missing time of the first rejection)."""
    imu, truth, _ = _static_setup(3000)
    t = imu.time[50::100]
    z = np.zeros((len(t), 3))
    z[5:] = 20.0
    out = run_filter(imu, truth.state(0), [_RowFix(t, z, 0.5, truth.lla[0])], FilterSettings(recovery_after_s=3.0))
    r = out.recoveries[0]
    assert r["measurement"] == "rows" and r["after_rejections"] >= 3 and r["rejected_for_s"] >= 3.0
    acc = out.innovations["rows"]["accepted"]
    assert not acc[5:8].any() and acc[-10:].all()  # refused while the jump is new; followed at the end


def test_measurements_must_follow_the_protocol():
    imu, truth, g = _static_setup()

    class NoRows:
        name = "x"

        def times(self):
            return np.array([1.0])

        def linearize(self, ctx, row):
            return None

    with pytest.raises(InputError, match="rows"):
        run_filter(imu, truth.state(0), [NoRows()], FilterSettings())
    with pytest.raises(InputError, match="unique"):
        run_filter(imu, truth.state(0), [GnssPosition(g), GnssPosition(g)], FilterSettings())


def test_open_and_closed_loop_agree_on_a_short_static_run():
    """Small errors: the open loop's output (INS minus the propagated error)
    and the closed loop's agree to well below the fixes' sigma."""
    imu, truth, g = _static_setup()
    c = run_filter(imu, truth.state(0), [GnssPosition(g)], FilterSettings(scheme="closed"))
    o = run_filter(imu, truth.state(0), [GnssPosition(g)], FilterSettings(scheme="open"))
    from inskit import earth

    d = earth.lla_to_ned(o.nav.lla, c.nav.lla)
    assert np.abs(d).max() < 0.05


def test_nan_in_a_toml_value_names_the_field(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text('[imu]\nfile = "a.csv"\n[gnss]\nfile = "b.csv"\n[noise]\ngyro_arw_deg_sqrt_h = nan\n')
    with pytest.raises(ConfigError, match="noise.gyro_arw_deg_sqrt_h.*not a finite number"):
        load_config(cfg)


def test_unsupported_plot_format_is_a_user_error(tmp_path):
    imu, truth, g = _static_setup()
    from inskit import io

    io.write_solution(tmp_path / "s.csv", truth)
    p = subprocess.run([sys.executable, "-m", "inskit.cli", "evaluate", str(tmp_path / "s.csv"),
                        str(tmp_path / "s.csv"), "--plot", str(tmp_path / "e.xyz")], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 2 and "unsupported plot format '.xyz'" in p.stderr


def test_filter_mechanizes_with_the_settings_gravity_model():
    """FilterSettings.gravity reaches the compiled propagation: with no
    measurement the filter is the free mechanization with that model, which on
    data made with the J2 model stays on the truth, while the default normal
    gravity sinks metres in 300 s (4.8e-5 m/s^2 of J2 - normal at 40 deg, grown
    by the unstable height channel)."""
    from inskit import earth
    from inskit.strapdown import mechanize

    traj = StationaryTrajectory((np.radians(40.0), 0.3, 1600.0))
    t = np.arange(0.0, 300.0, 0.02)
    imu, truth = ideal_imu(traj, t, nodes=1, gravity="j2"), truth_solution(traj, t)
    out = run_filter(imu, truth.state(0), [], FilterSettings(gravity="j2"))
    assert np.array_equal(out.solution.lla, mechanize(imu, truth.state(0), gravity="j2").lla)
    d = earth.lla_to_ned(out.solution.lla[-1], truth.lla[-1])
    assert np.abs(d).max() < 1e-4
    d = earth.lla_to_ned(run_filter(imu, truth.state(0), [], FilterSettings()).solution.lla[-1], truth.lla[-1])
    assert abs(d[2]) > 1.0
    with pytest.raises(InputError, match="gravity model 'wgs72'"):
        FilterSettings(gravity="wgs72")


def test_measurements_after_a_change_of_rate_are_used_not_skipped():
    """200 Hz then 50 Hz: an update 12 ms after its 50 Hz sample is within
    two local intervals (40 ms), not a gap; judged against the log's median
    interval (5 ms) every update of the 50 Hz half used to be skipped."""
    from inskit.integration import GnssPosition, NonHolonomic
    from inskit.simulation import StationaryTrajectory, ideal_imu, truth_solution
    from inskit.types import GnssData

    t = np.r_[np.arange(0, 20, 0.005), np.arange(20, 40.0001, 0.02)]
    traj = StationaryTrajectory((np.radians(45.0), 0.1, 100.0))
    imu = ideal_imu(traj, t, nodes=1)
    init = truth_solution(traj, t[:1]).state(0)
    tg = np.arange(1.0, 40, 1.0) + 0.012
    g = GnssData(tg, np.tile(init.lla, (len(tg), 1)), np.full((len(tg), 3), 0.5))
    out = run_filter(imu, init, [GnssPosition(g), NonHolonomic([(0.5, 39.9)], 10.0, 0.1)], FilterSettings.standard())
    assert out.counts["gnss_pos"]["skipped"] == 0 and out.counts["gnss_pos"]["used"] == 39
    assert out.counts["nhc"]["skipped"] == 0


@pytest.mark.parametrize("bad", [0, -1, 2.5])
def test_gate_max_consecutive_must_be_none_or_a_positive_integer(bad):
    with pytest.raises(InputError, match="gate_max_consecutive"):
        FilterSettings(gate_max_consecutive=bad)


@pytest.mark.parametrize("settings", [FilterSettings(scheme="closed"), FilterSettings(scheme="open"),
                                      FilterSettings(scheme="closed", compiled_updates=False)],
                         ids=["closed-compiled", "open", "closed-python"])
def test_a_streamed_run_hands_every_row_once_and_matches_the_whole_run(settings):
    """Segments of 37 rows (a node ends each): the sink sees rows 0 .. N-1
    once each, in order, with the same states, estimates and sigmas as the
    run that keeps every row; the kept rows are those rows."""
    from inskit.integration import NonHolonomic, ZeroVelocity

    imu, truth, g = _static_setup(700)
    s0 = truth.state(0)
    init = type(s0).from_euler(s0.time, s0.lla + [5e-8, -5e-8, 0.5], s0.v_n + 0.05, s0.euler + [0.002, -0.002, 0.01])
    meas = [GnssPosition(g), ZeroVelocity([(0.0, 7.0)], 10.0, 0.02), NonHolonomic([(0.0, 7.0)], 10.0, 0.1)]
    whole = run_filter(imu, init, meas, settings, segment_rows=37)
    segs = []

    def sink(sg):
        segs.append((sg.start, sg.time.copy(), sg.lla.copy(), sg.v_n.copy(), sg.q_nb.copy(), sg.aux.copy(),
                     sg.sigma.copy()))

    keep = np.array([5, 36, 37, 38, 400])
    st = run_filter(imu, init, meas, settings, sink=sink, keep_rows=keep, segment_rows=37)
    starts = [s[0] for s in segs]
    assert starts[0] == 0 and all(len(s[1]) <= 38 for s in segs)
    assert np.array_equal(np.concatenate([s[1] for s in segs]), imu.time)  # every row once, in order
    lla, v, q, aux, sig = (np.concatenate([s[i] for s in segs]) for i in range(2, 7))
    assert np.array_equal(lla, whole.nav.lla) and np.array_equal(v, whole.nav.v_n)
    assert np.array_equal(q, whole.nav.q_nb)
    assert np.array_equal(aux, whole.aux) and np.array_equal(sig, whole.sigma)
    rows = np.concatenate([[0], keep, [len(imu) - 1]])
    assert np.array_equal(st.rows, rows) and st.n_rows == len(imu)
    assert np.array_equal(st.nav.lla, whole.nav.lla[rows]) and np.array_equal(st.aux, whole.aux[rows])
    assert st.counts == whole.counts
    assert whole.counts["gnss_pos"]["used"] > 20 and whole.counts["zupt"]["used"] > 50
    with pytest.raises(InputError, match="store_sink"):
        run_filter(imu, init, meas, FilterSettings(), sink=sink, smoother=True)


def test_a_streamed_run_holds_a_fixed_record_per_update_and_nothing_per_row():
    """Memory of a streamed run beyond its input (tracemalloc's peak, a 4x
    longer log, GNSS at 1 Hz, ZUPT and NHC at 10 Hz, IMU at 100 Hz): per
    update the compiled loop's item arrays (48 B), innovation records (49 B
    and 17 B per component) and recovery slots (96 B), about 0.23 kB; the
    segment buffers and the node estimates are per segment, not per row.
    Python lists of the items (0.15 kB per update) or node estimates kept for
    every node (0.13 kB) would break the 0.3 kB bound."""
    import tracemalloc

    from inskit.integration import NonHolonomic, ZeroVelocity

    def peak(n):
        traj = StationaryTrajectory((0.7, 0.1, 10.0))
        t = np.arange(n) * 0.01
        imu, truth = ideal_imu(traj, t, nodes=1), truth_solution(traj, t)
        g = GnssData(t[::100], truth.lla[::100], np.full((len(t[::100]), 3), 0.05))
        meas = [GnssPosition(g), ZeroVelocity([(0.0, t[-1])], 10.0, 0.02), NonHolonomic([(0.0, t[-1])], 10.0, 0.1)]
        tracemalloc.start()
        try:
            out = run_filter(imu, truth.state(0), meas, FilterSettings(), sink=lambda sg: None,
                             keep_rows=np.array([1]), segment_rows=4096)
            p = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        return p, sum(c["used"] + c["rejected"] for c in out.counts.values())

    (p1, u1), (p2, u2) = peak(20_000), peak(80_000)
    assert u2 - u1 > 12_000
    assert (p2 - p1) / (u2 - u1) < 300.0


def test_a_streamed_smoother_store_holds_the_nodes_of_the_whole_run(tmp_path):
    """The node data a streamed run hands to a DiskStore, read back in
    blocks, is the in-memory store's, node for node; smoothing from it gives
    the same rows."""
    from inskit.integration import NonHolonomic
    from inskit.integration.smoother import DiskStore, backward_pass, smooth_rows

    imu, truth, g = _static_setup(700)
    s0 = truth.state(0)
    init = type(s0).from_euler(s0.time, s0.lla + [5e-8, -5e-8, 0.5], s0.v_n + 0.05, s0.euler + [0.002, -0.002, 0.01])
    meas = [GnssPosition(g), NonHolonomic([(0.0, 7.0)], 10.0, 0.1)]
    whole = run_filter(imu, init, meas, FilterSettings(), smoother=True, segment_rows=37)
    store = DiskStore(tmp_path / "st", whole.layout.size)
    st = run_filter(imu, init, meas, FilterSettings(), smoother=True, segment_rows=37, sink=lambda sg: None,
                    store_sink=store, keep_rows=np.arange(len(imu)))
    store.close()
    assert st.store is None and store.m == len(whole.store.k)
    k, Pm, Pp, Phi, dx = store.block(0, store.m)
    assert np.array_equal(k, whole.store.k) and np.array_equal(Pm, np.array(whole.store.P_minus))
    assert np.array_equal(Pp, np.array(whole.store.P_plus)) and np.array_equal(Phi, np.array(whole.store.Phi))
    assert np.array_equal(dx, np.array(whole.store.dx))
    from inskit.integration import rts_smooth

    ref = rts_smooth(whole)
    nodes = backward_pass(store.block, store.m, whole.layout.initial_covariance(), block_nodes=5)
    nodes.t = imu.time[nodes.k]
    got = smooth_rows(nodes, st.layout, st.nav, st.aux, np.arange(len(imu)))
    assert np.array_equal(got.nav.lla, ref.nav.lla) and np.array_equal(got.sigma, ref.sigma)
    store.remove()
    assert not (tmp_path / "st").exists()


def test_lost_note_names_a_lost_filter_and_the_constraint_that_broke_it():
    """A divergence's message says which measurements had been refused
    before it (a ship's 8 h log with the default non-holonomic constraint was
    lost after 6 s and stopped at 2616 s naming only the pole it reached)."""
    from inskit.integration.engine import lost_note

    names = ["gnss_pos", "nhc"]
    rec_m = np.array([0] * 10 + [1] * 100)
    rec_t = np.concatenate([np.arange(10.0), np.arange(100) * 0.1])
    acc = np.zeros(110, bool)
    acc[:2] = True  # two fixes used, then refused
    acc[10:13] = True  # three constraint updates used
    note = lost_note(names, rec_m, rec_t, acc)
    assert "gnss_pos 2 of 10 updates used (80 % refused, the last at t = 1.0 s)" in note
    assert "nhc 3 of 100 updates used (97 % refused" in note
    assert "[constraints] nhc = false" in note
    # a healthy record adds nothing
    assert lost_note(names, rec_m, rec_t, np.ones(110, bool)) == ""


@pytest.fixture(scope="module")
def tilted_car():
    """A 110 s car (20 s at rest, then a drive with turns) with an
    industrial MEMS IMU and 1 Hz fixes, started 10 deg off in roll and
    -8 deg in pitch with a 0.5 deg sigma: the tilt leaks 2.2 m/s^2 of
    gravity into the horizontal channels and every fix is refused from the
    second second on."""
    from inskit.simulation.gnss import GnssErrors, simulate_gnss
    from inskit.simulation.segments import SegmentTrajectory
    from inskit.simulation.sensors import apply_imu_errors, preset

    tr = SegmentTrajectory((np.radians(40), np.radians(-105), 1600.0), yaw0=0.4)
    tr.static(20).accelerate(12, 8).cruise(15).turn(np.radians(90), rate=np.radians(9)).cruise(20)
    tr.turn(np.radians(-60), rate=np.radians(6)).cruise(27)
    t = np.arange(0.0, tr.duration, 0.01)
    rng = np.random.default_rng(5)
    imu, _ = apply_imu_errors(ideal_imu(tr, t, nodes=3), preset("industrial-mems"), rng)
    g, _ = simulate_gnss(tr, t[0], t[-1], GnssErrors(rate_hz=1.0, white_h_m=0.5, white_v_m=1.0), rng)
    truth = truth_solution(tr, t)
    s0 = truth.state(0)
    start = NavState.from_euler(s0.time, s0.lla, s0.v_n, s0.euler + np.radians([10.0, -8.0, 0.0]))
    return imu, truth, g, start


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("constraints", [False, True])
def test_a_tilt_lost_filter_recovers_on_the_fixes(tilted_car, compiled, constraints):
    """A tilt-lost filter's fixes drift away with the square of time (its
    velocity error grows at g tan(tilt)), faster than its own velocity
    sigma allowed the rejections to 'agree', so the recovery never fired
    and the run stayed lost to its end, kilometres off.  Now the smooth
    drift is evidence of a lost state: 15 s after the first refused fix the
    filter is re-initialised on the fixes (the drift says a tilt beyond the
    error model's small angles), the record says how far it had drifted
    and the tilt that shows, and every later fix is used.  With the
    constraints, their own recoveries no longer widen the covariance while
    the fixes are refused (that let the car's yaw wander 80 deg at rest,
    and the fixes' recovery came only after a minute)."""
    from inskit.analysis import nav_error
    from inskit.integration import InitialUncertainty, NonHolonomic, ZeroVelocity

    imu, truth, g, start = tilted_car
    meas = [GnssPosition(g)]
    if constraints:
        meas += [ZeroVelocity([(imu.time[0], 19.5)], 10.0, 0.02),
                 NonHolonomic([(imu.time[0], imu.time[-1])], 10.0, 0.1)]
    noise = SensorNoise(np.radians(0.3) / 60, 0.1 / 60, np.radians(50 / 3600), 1e-2, bias_tau_s=300.0)
    settings = FilterSettings.standard(noise, InitialUncertainty(roll_pitch_rad=np.radians(0.5)),
                                       compiled_updates=compiled)
    out = run_filter(imu, start, meas, settings)
    inn = out.innovations["gnss_pos"]
    first_refused = float(inn["t"][~inn["accepted"]][0])
    assert [r["measurement"] for r in out.recoveries] == ["gnss_pos"], out.recoveries
    r = out.recoveries[0]
    assert r["fixes_position"] and first_refused + 15.0 <= r["t"] <= first_refused + 16.0, (first_refused, r)
    assert 7.0 < np.degrees(r["tilt_rad"]) < 20.0 and r["reinitialised"], r  # the tilt was 12.8 deg
    assert r["position_offset_m"] > 100.0 and r["drift_velocity_m_s"] > 10.0 and r["covariance_scale"] is None, r
    assert inn["accepted"][inn["t"] > r["t"]].all()
    e = nav_error(out.nav, truth)
    end = e.time > e.time[-1] - 10.0
    assert np.abs(np.degrees(e.att_rpy[end, :2])).max() < 0.5
    assert e.horizontal[end].max() < 3.0


def test_nis_dof_leaves_out_the_rows_refused_by_their_own_gate():
    """An update that went on without a refused satellite has a NIS over the rows it used: its degrees of
    freedom are those rows (a mean NIS per dof over all rows read a partly refused tight epoch as more
    consistent than it was); a whole update refused keeps all its rows."""
    from inskit.integration.engine import ROW_ACCEPTED as A, ROW_REFUSED_ROW as R, ROW_REFUSED_UPDATE as U
    from inskit.integration.engine import nis_dof

    dof = np.array([3, 5, 2, 4])
    status = np.array([A, A, A, A, R, A, R, A, U, U, A, A, A, A], np.int8)
    assert nis_dof(dof, status).tolist() == [3, 3, 2, 4]
    assert nis_dof(np.zeros(0, np.int64), np.zeros(0, np.int8)).tolist() == []
