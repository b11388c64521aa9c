"""The compiled updates (integration._updates) against the Python path of
every measurement's own ``linearize``: kind by kind on one context, and whole
filter runs (rejections, recoveries, gap noise, the smoother's store, a
user's plug-in among compiled ones) with ``compiled_updates`` on and off.

The two paths are the same mathematics in a different order of rounding, so
they agree to rounding, not bit for bit: one update's rounding is ~1e-16
relative, and a stable filter does not amplify it.  The tolerances below are
1e-9 relative (in metres for positions: 1e-9 of the 6.4e6 m Earth radius is
6 mm; the runs agree to ~1e-9 m, far inside it), 1e-8 with ranges to
satellites (their rounding, 3.7e-9 m in 2e7 m, is 1e-9 of a 3 m sigma)."""

import numpy as np
import pytest

from inskit import earth
from inskit import rotations as rot
from inskit.integration import (FilterSettings, GnssPosition, GnssVelocity, InitialUncertainty, NonHolonomic,
                                SensorNoise, StateLayout, UpdateContext, ZeroVelocity, ins_blocks, rts_smooth,
                                run_filter)
from inskit.integration import _updates as U
from inskit.integration.aiding import GnssSpeedCourse, Odometer, OdometerScale
from inskit.integration.blocks import ReceiverClock, SystemTimeOffset
from inskit.integration.tight import Pseudorange, PseudorangeRate
from inskit.simulation import ideal_imu, truth_solution
from inskit.simulation.gnss import GnssErrors, simulate_gnss
from inskit.simulation.segments import SegmentTrajectory
from inskit.simulation.sensors import apply_imu_errors, preset
from inskit.types import GnssData

NOISE = SensorNoise(np.radians(0.3) / 60, 0.1 / 60, np.radians(50 / 3600), 1e-2, bias_tau_s=300.0)
FULL = StateLayout(ins_blocks(NOISE, scale_factors=True, lever_arm=True, time_offset=True)
                   + [OdometerScale(), ReceiverClock(), SystemTimeOffset("E")])
LEVER = np.array([0.9, -0.4, -1.3])
ODO_LEVER = np.array([-1.4, 0.0, 0.35])
REL = 1e-9


def full_context(layout=FULL, dt=0.004):
    """An estimate in a turn with every block carrying a non-zero estimate."""
    aux = layout.initial_aux()
    for name, val in (("lever", LEVER), ("bg", [1e-3, -2e-3, 4e-3]), ("sg", [2e-3, -1e-3, 3e-3]),
                      ("time_offset", [0.03]), ("odo_scale", [0.004]), ("clock", [1.2e5, -35.0]),
                      ("isb_E", [12.0])):
        if layout.aux_slice(name) is not None:
            aux[layout.aux_slice(name)] = val
    C = rot.dcm_from_euler([0.05, -0.08, 2.3])
    w_raw = np.array([0.05, -0.1, 0.6]) * 1.002 + 1e-3
    return UpdateContext(100.0, dt, np.array([0.7, 2e-3, 120.0]), np.array([12.0, -9.0, 0.3]), C, w_raw, layout,
                         aux)


def kinds_of(lla):
    """One measurement of every compiled kind whose innovation is non-zero."""
    g = GnssData(np.array([100.0]), (lla + [1e-7, -2e-7, 1.5])[None, :], np.array([[0.5, 0.6, 0.9]]),
                 v_n=np.array([[11.0, -8.5, 0.1]]), sigma_v_ned=np.array([[0.05, 0.06, 0.1]]))
    return [GnssPosition(g, lever_arm_b=LEVER), GnssVelocity(g, lever_arm_b=LEVER),
            ZeroVelocity([(99.0, 101.0)], 10.0, 0.02), NonHolonomic([(99.0, 101.0)], 10.0, 0.1),
            Odometer([100.0], [14.8], 0.05, lever_arm_b=ODO_LEVER),
            Odometer([100.0], [14.8], 0.05, lever_arm_b=ODO_LEVER, with_nhc=True, nhc_sigma_m_s=0.2),
            GnssSpeedCourse([100.0], [15.2], [-0.6], 0.1, 0.01, lever_arm_b=LEVER)]


def range_table(r_rx, v_rx, t, systems="GGGGGEEE", clk=(1.2e5, -35.0), isb=12.0, seed=1):
    """Corrected ranges and rates of satellites 20,000 km away in fixed
    directions (moving at 3.9 km/s) from receivers at ``r_rx``, ``v_rx``
    (ECEF, one row per epoch ``t``); zero travel time, so no Sagnac turn."""
    from types import SimpleNamespace

    rng = np.random.default_rng(seed)
    n = len(systems)
    up = r_rx[0] / np.linalg.norm(r_rx[0])
    dirs = []
    while len(dirs) < n:
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        if d @ up > 0.3:
            dirs.append(d)
    dirs = np.array(dirs)
    vel = np.cross(dirs, up) * 3.9e3
    m = len(t)
    ps = (r_rx[0] + 2.0e7 * dirs)[None] + vel[None] * (t - t[0])[:, None, None]
    d = r_rx[:, None, :] - ps
    rg = np.linalg.norm(d, axis=2)
    sys = np.array(list(systems))
    bias = clk[0] + clk[1] * (t - t[0])
    pr = rg + bias[:, None] + np.where(sys == "E", isb, 0.0)[None]
    rr = np.einsum("mij,mij->mi", d / rg[..., None], v_rx[:, None, :] - vel[None]) + clk[1]
    return SimpleNamespace(time=np.repeat(t, n), epoch=np.repeat(np.arange(m), n),
                           sat=np.tile([f"{s}{k:02d}" for k, s in enumerate(sys, 1)], m),
                           sat_pos_e=ps.reshape(-1, 3), sat_vel_e=np.tile(vel, (m, 1)), travel_s=np.zeros(m * n),
                           pseudorange_m=pr.ravel(), sigma_pr_m=np.full(m * n, 3.0), range_rate_m_s=rr.ravel(),
                           sigma_rr_m_s=np.full(m * n, 0.1))


def compiled_linearize(meas, ctx, row=0):
    sp = meas.compiled(ctx.layout)
    km = max(sp.k, U.KMAX)
    nu, H, R = np.empty(km), np.empty((km, ctx.layout.size)), np.empty((km, km))
    args = (ctx.dt, ctx.lla, ctx.v_n, np.ascontiguousarray(ctx.C_nb), ctx.omega_raw_b, ctx.aux,
            ctx.layout.kernel_index(), U.layout_index(ctx.layout), nu, H, R)
    if sp.index is None:
        k = sp.k
        ok = U.linearize(sp.kind, sp.data[row], sp.par, *args, np.empty((8, 3)), np.empty((2, 3, 3)))
    else:
        rows = sp.data[sp.index[row]:sp.index[row + 1]]
        k = len(rows)
        ok = k > 0 and U.linearize_ranges(sp.kind, rows, sp.par, *args, np.empty((k, 3)), np.empty((14, 3)),
                                          np.empty((6, 3, 3)))
    return (nu[:k], H[:k], R[:k, :k]) if ok else None


@pytest.mark.parametrize("kind", [Pseudorange, PseudorangeRate])
@pytest.mark.parametrize("lever", [LEVER, np.zeros(3)], ids=["lever", "no-lever"])
def test_range_kinds_linearize_as_their_python_plugins(kind, lever):
    """Eight satellites of two systems (time offset on the second), every
    block estimated or none besides the clock: H and R as the plug-in's to
    1e-12 of their largest entry, nu to 4e-9 m (the rounding of a 2e7 m
    range is 3.7e-9 m)."""
    for layout in (FULL, StateLayout(ins_blocks(NOISE) + [ReceiverClock()])):
        ctx = full_context(layout)
        C_en = earth.dcm_en(ctx.lla[0], ctx.lla[1])
        r = earth.lla_to_ecef(ctx.lla)
        tab = range_table(np.array([r + [30.0, -20.0, 10.0]]), np.array([C_en @ ctx.v_n + 0.3]), np.array([100.0]))
        m = kind(tab, lever_arm_b=lever)
        want, got = m.linearize(ctx, 0), compiled_linearize(m, ctx)
        for a, b, what in zip(got, want, ("nu", "H", "R")):
            assert a.shape == b.shape, what
            tol = 4e-9 if what == "nu" else 1e-12 * max(np.abs(b).max(), 1.0)
            assert np.abs(a - b).max() <= tol, f"{m.name} {what}: {np.abs(a - b).max()}"


@pytest.mark.parametrize("layout", [FULL, StateLayout(ins_blocks(NOISE)), StateLayout(ins_blocks(NOISE, scale_factors=True))],
                         ids=["full", "15-state", "21-state"])
@pytest.mark.parametrize("which", range(7))
def test_each_kind_linearizes_as_its_python_plugin(layout, which):
    """nu, H, R of the compiled kind equal the plug-in's own, to 1e-12 of
    each array's largest entry (rounding: products of a few terms)."""
    ctx = full_context(layout)
    m = kinds_of(ctx.lla)[which]
    want = m.linearize(ctx, 0)
    got = compiled_linearize(m, ctx)
    for a, b, what in zip(got, want, ("nu", "H", "R")):
        assert a.shape == b.shape, what
        assert np.abs(a - b).max() <= 1e-12 * max(np.abs(b).max(), 1.0), f"{m.name} {what}"


def test_low_speed_course_is_skipped_and_subclasses_keep_python():
    ctx = full_context()
    slow = GnssSpeedCourse([100.0], [0.2], [0.3], 0.1, 0.01)
    assert slow.linearize(ctx, 0) is None and compiled_linearize(slow, ctx) is None

    class Shifted(GnssPosition):
        name = "shifted"

        def linearize(self, ctx, row):
            nu, H, R = super().linearize(ctx, row)
            return nu + 1.0, H, R

    g = kinds_of(ctx.lla)[0].gnss
    assert Shifted(g).compiled(FULL) is None
    per_row = ZeroVelocity([(0.0, 1.0)], 10.0, 0.02)
    per_row.gating = "row"
    assert per_row.compiled(FULL) is None


@pytest.fixture(scope="module")
def drive():
    """A 150 s car run: standstill, drive with turns, a stop, drive; MEMS
    IMU; 1 Hz GNSS position and velocity with outliers and a 25 s jump of
    the fixes (rejected, then a recovery, and another when it ends)."""
    tr = SegmentTrajectory((np.radians(45), np.radians(7), 300.0), yaw0=0.3)
    tr.static(20).accelerate(12, 8).cruise(15).turn(np.radians(90), rate=np.radians(9)).cruise(10)
    tr.accelerate(0, 6).static(15).accelerate(10, 6).turn(np.radians(-60), rate=np.radians(6)).cruise(50)
    t = np.arange(0.0, tr.duration, 0.01)
    rng = np.random.default_rng(11)
    imu, _ = apply_imu_errors(ideal_imu(tr, t, nodes=3), preset("industrial-mems"), rng)
    gnss, _ = simulate_gnss(tr, t[0], t[-1], GnssErrors(rate_hz=1.0, white_h_m=0.3, white_v_m=0.5,
                                                        velocity_sigma_m_s=0.05), rng)
    lla = gnss.lla.copy()
    n_off = np.zeros((len(lla), 3))
    n_off[[30, 47, 48], 0] = 40.0                    # outliers
    jump = (gnss.time > 95.0) & (gnss.time < 120.0)  # a 25 s jump of the fixes: consistent evidence
    n_off[jump, 1] = 25.0
    rn, re = earth.principal_radii(lla[:, 0], lla[:, 2])
    lla[:, 0] += n_off[:, 0] / rn
    lla[:, 1] += n_off[:, 1] / (re * np.cos(lla[:, 0]))
    v = gnss.v_n.copy()
    v[60, 1] += 3.0
    g = GnssData(gnss.time, lla, gnss.sigma_ned, v_n=v, sigma_v_ned=gnss.sigma_v_ned)
    truth = truth_solution(tr, t)
    return imu, truth, g


def standard_measurements(imu, g):
    t0, t1 = imu.time[0], imu.time[-1]
    return [GnssPosition(g, lever_arm_b=(0.0, -0.05, 0.0)), GnssVelocity(g, lever_arm_b=(0.0, -0.05, 0.0)),
            ZeroVelocity([(t0, 19.0), (70.0, 83.0)], 10.0, 0.02), NonHolonomic([(t0, t1)], 10.0, 0.1)]


def both(imu, start, meas, smoother=False, extra_noise=None, **kw):
    out = []
    for compiled in (True, False):
        s = FilterSettings.standard(NOISE, InitialUncertainty(yaw_rad=np.radians(2.0)), compiled_updates=compiled,
                                    **kw)
        out.append(run_filter(imu, start, meas, s, smoother=smoother, extra_noise=extra_noise))
    return out


def assert_same_run(a, b, REL=REL):
    d_m = earth.lla_to_ned(a.nav.lla, b.nav.lla)
    assert np.abs(d_m).max() < REL * earth.A
    assert np.abs(a.nav.v_n - b.nav.v_n).max() < REL * max(np.abs(b.nav.v_n).max(), 1.0)
    assert np.abs(a.nav.q_nb - b.nav.q_nb).max() < REL
    assert np.all(np.abs(a.sigma - b.sigma) <= REL * b.sigma)
    assert np.all(np.abs(a.aux - b.aux) <= REL * np.abs(b.aux).max(axis=0))
    assert a.counts == b.counts
    assert [(r["measurement"], r["after_rejections"]) for r in a.recoveries] == \
        [(r["measurement"], r["after_rejections"]) for r in b.recoveries]
    assert np.allclose([r["t"] for r in a.recoveries], [r["t"] for r in b.recoveries], rtol=0, atol=1e-12)
    assert a.innovations.keys() == b.innovations.keys()
    for name, ra in a.innovations.items():
        rb = b.innovations[name]
        assert ra.keys() == rb.keys()
        assert np.array_equal(ra["accepted"], rb["accepted"]) and np.array_equal(ra["dof"], rb["dof"]), name
        assert np.array_equal(ra["t"], rb["t"]), name
        # what happened to each row, and which own row each update was
        assert np.array_equal(ra["status"], rb["status"]) and len(ra["status"]) == ra["dof"].sum(), name
        assert np.array_equal(ra["update_row"], rb["update_row"]), name
        # innovations and sigmas to REL of the sigma, the NIS to REL of its size
        sig = np.asarray(rb["sigma"], float)
        for key in ("nu", "sigma"):
            x, y = np.asarray(ra[key], float), np.asarray(rb[key], float)
            assert x.shape == y.shape, (name, key)
            assert np.all(np.abs(x - y) <= REL * sig), (name, key)
        assert np.all(np.abs(ra["nis"] - rb["nis"]) <= 4 * REL * (rb["nis"] + rb["dof"])), name


def test_compiled_and_python_paths_agree_with_rejections_and_recoveries(drive):
    imu, truth, g = drive
    a, b = both(imu, truth.state(0), standard_measurements(imu, g), scale_factors=True, recovery_after_s=5.0)
    assert_same_run(a, b)
    # the run exercises what it claims: rejections of each kind of outlier, two recoveries
    assert a.counts["gnss_pos"]["rejected"] >= 8 and a.counts["gnss_vel"]["rejected"] >= 1
    assert [r["measurement"] for r in a.recoveries].count("gnss_pos") >= 2
    assert a.counts["zupt"]["used"] > 300 and a.counts["nhc"]["used"] > 1400


def test_paths_agree_with_every_block_gap_noise_and_the_smoother_store(drive):
    """Lever arm and time offset estimated, odometer with its scale, GNSS
    speed and course, gap noise at two rows, the smoother's store."""
    imu, truth, g = drive
    kin = truth.v_n
    C = rot.dcm_from_quat(truth.q_nb)
    fwd = np.einsum("nji,nj->ni", C, kin)[:, 0]
    t_odo = imu.time[5::10]
    odo = Odometer(t_odo, 1.003 * fwd[5::10], 0.05, lever_arm_b=ODO_LEVER)
    sp = np.hypot(g.v_n[:, 0], g.v_n[:, 1])
    sc = GnssSpeedCourse(g.time, sp, np.arctan2(g.v_n[:, 1], g.v_n[:, 0]), 0.1, 0.02)
    meas = standard_measurements(imu, g)[:1] + [standard_measurements(imu, g)[3], odo, sc]
    extra = {4000: np.full(26, 1e-6), 9000: np.full(26, 1e-4)}
    a, b = both(imu, truth.state(0), meas, smoother=True, extra_noise=extra, scale_factors=True, lever_arm=True,
                time_offset=True, extra_blocks=[OdometerScale()], recovery_after_s=5.0)
    assert_same_run(a, b)
    assert a.counts["gnss_speed_course"]["skipped"] > 20  # the standstills
    sa, sb = a.store, b.store
    assert sa.k == sb.k and len(sa.P_minus) == len(sb.P_minus) > 600
    for key in ("P_minus", "P_plus", "Phi", "dx"):
        x, y = np.asarray(getattr(sa, key)), np.asarray(getattr(sb, key))
        assert np.all(np.abs(x - y) <= REL * np.abs(y).max(axis=0) + 1e-300), key
    ma, mb = rts_smooth(a), rts_smooth(b)
    assert np.abs(earth.lla_to_ned(ma.nav.lla, mb.nav.lla)).max() < REL * earth.A


def test_a_python_plugin_among_compiled_ones(drive):
    """A user's plug-in (here a GNSS position subclass, so it has no compiled
    form) is handed back to Python inside the compiled loop's nodes."""
    imu, truth, g = drive

    class MyFix(GnssPosition):
        name = "my_fix"

        def linearize(self, ctx, row):
            return super().linearize(ctx, row)

    meas = [MyFix(g)] + standard_measurements(imu, g)[2:]
    a, b = both(imu, truth.state(0), meas, scale_factors=True, recovery_after_s=5.0)
    # three recoveries multiply the navigation covariance by up to 2 * 4^k: the two paths' rounding (1e-16)
    # grows with it, to 6e-9 of a sigma in the innovations after them (the covariances still agree to 2e-12).
    # 1e-7 of a sigma still tells a fault in either path (a wrong term moves the state by a fraction of a sigma)
    assert_same_run(a, b, REL=1e-7)
    assert a.counts["my_fix"]["rejected"] >= 8 and len(a.recoveries) >= 2


def test_tight_coupling_paths_agree_with_refused_satellites_and_a_recovery(drive):
    """Pseudorange and range rate of eight satellites (two systems) at 1 Hz
    with NHC: one satellite 300 m off at three epochs (that row refused, the
    others used); for 20 s the ranges of a receiver 100 m higher (every row
    refused, then recoveries at the jump and back); per-row gating, the
    clock's estimate carried between updates."""
    imu, truth, g = drive
    t = g.time
    lla = np.array([np.interp(t, truth.time, truth.lla[:, j]) for j in range(3)]).T
    v_n = np.array([np.interp(t, truth.time, truth.v_n[:, j]) for j in range(3)]).T
    C_en = earth.dcm_en(lla[:, 0], lla[:, 1])
    r = earth.lla_to_ecef(lla)
    jump = (t > 100.0) & (t < 120.0)
    r[jump] += C_en[jump] @ np.array([0.0, 0.0, -100.0])
    tab = range_table(r, np.einsum("mij,mj->mi", C_en, v_n), t)
    pr = tab.pseudorange_m.reshape(len(t), -1)
    pr[[20, 21, 40], 2] += 300.0
    tab.pseudorange_m = pr.ravel()
    meas = [Pseudorange(tab), PseudorangeRate(tab), NonHolonomic([(imu.time[0], imu.time[-1])], 10.0, 0.1)]
    clock = [ReceiverClock(sigma0=(10.0, 1.0), estimate0=(1.2e5, -35.0)), SystemTimeOffset("E", estimate0=12.0)]
    a, b = both(imu, truth.state(0), meas, scale_factors=True, extra_blocks=clock, recovery_after_s=5.0)
    # a 2e7 m range rounds to 3.7e-9 m, 1e-9 of its 3 m sigma, and the paths round differently: 1e-8 here
    assert_same_run(a, b, REL=1e-8)
    c = a.counts["pseudorange"]
    assert c["rows_rejected"] >= 3 + 8 * 5 and c["rejected"] >= 8
    # the record says per row what the counts say in sum: the bad satellite's rows refused alone at 20, 21
    # and 40 s, its seven companions used (they were recorded as accepted with it)
    from inskit.integration.engine import ROW_ACCEPTED, ROW_REFUSED_ROW

    rec = a.innovations["pseudorange"]
    st = rec["status"].reshape(len(rec["t"]), -1)
    assert (st == ROW_REFUSED_ROW).sum() == c["rows_rejected"] and st.size == c["rows"]
    assert int((st != ROW_ACCEPTED).any(axis=1).sum()) == c["rejected"]
    assert int(rec["accepted"].sum()) == c["used"] and np.array_equal(rec["accepted"], (st == ROW_ACCEPTED).any(axis=1))
    for e in (20, 21, 40):
        k = int(np.flatnonzero(rec["update_row"] == e)[0])
        assert st[k, 2] == ROW_REFUSED_ROW and (np.delete(st[k], 2) == ROW_ACCEPTED).all(), (e, st[k])
    assert list(rec["label"][:8]) == Pseudorange(tab).satellites(0)
    assert [r["measurement"] for r in a.recoveries] == ["pseudorange", "pseudorange"]
    assert a.counts["pseudorange_rate"]["used"] > 140


def test_nhc_in_the_vehicles_axes_linearizes_as_its_python_plugin():
    """With a mounting block (non-zero pitch and yaw estimates) the compiled
    NHC rotates into the vehicle's axes as NonHolonomic.linearize does, its
    mounting columns included; the odometer keeps the Python path there."""
    from inskit.integration import Mounting

    lay = StateLayout(ins_blocks(NOISE, scale_factors=True) + [Mounting()])
    ctx = full_context(lay)
    ctx.aux[lay.aux_slice("mounting")] = [np.radians(3.5), np.radians(-1.7)]
    m = NonHolonomic([(99.0, 101.0)], 10.0, 0.1)
    want = m.linearize(ctx, 0)
    got = compiled_linearize(m, ctx)
    assert np.abs(want[1][:, lay.slice("mounting")]).max() > 1.0  # the columns are there and matter
    for a, b, what in zip(got, want, ("nu", "H", "R")):
        assert np.abs(a - b).max() <= 1e-12 * max(np.abs(b).max(), 1.0), what
    assert Odometer([100.0], [14.8], 0.05).compiled(lay) is None


@pytest.mark.parametrize("mounted", [False, True], ids=["imu-axes", "vehicle-axes"])
@pytest.mark.parametrize("layout_kind", ["15-state", "21-state"])
def test_nhc_with_a_lever_arm_linearizes_as_its_python_plugin(mounted, layout_kind):
    """The constraint at the rear axle (``lever_arm_b``): the compiled NHC adds ``omega x l_b`` and the gyro
    bias and scale-factor columns as NonHolonomic.linearize does, in the IMU's or the vehicle's axes."""
    from inskit.integration import Mounting

    blocks = ins_blocks(NOISE, scale_factors=layout_kind == "21-state") + ([Mounting()] if mounted else [])
    lay = StateLayout(blocks)
    ctx = full_context(lay)
    if mounted:
        ctx.aux[lay.aux_slice("mounting")] = [np.radians(3.5), np.radians(-1.7)]
    m = NonHolonomic([(99.0, 101.0)], 10.0, 0.1, lever_arm_b=[0.06, -0.2, 0.79])
    want = m.linearize(ctx, 0)
    got = compiled_linearize(m, ctx)
    assert np.abs(want[1][:, lay.slice("bg")]).max() > 0.1  # the lever arm's rate columns are there
    base = NonHolonomic([(99.0, 101.0)], 10.0, 0.1).linearize(ctx, 0)
    assert np.abs(want[0] - base[0]).max() > 2e-3  # and it moves the innovation (omega x l: 4 mm/s here)
    for a, b, what in zip(got, want, ("nu", "H", "R")):
        assert np.abs(a - b).max() <= 1e-12 * max(np.abs(b).max(), 1.0), what


def test_gnss_position_with_its_correlated_error_linearizes_as_its_python_plugin():
    """With a ``gnss_err`` block (GnssPositionError, a non-zero estimate) the compiled GNSS position adds the
    estimate to the prediction and its identity columns, as GnssPosition.linearize does."""
    from inskit.integration import GnssPositionError

    lay = StateLayout(ins_blocks(NOISE, scale_factors=True, lever_arm=True, time_offset=True)
                      + [GnssPositionError(0.03, 10.0)])
    ctx = full_context(lay)
    ctx.aux[lay.aux_slice("gnss_err")] = [0.02, -0.015, 0.04]
    m = kinds_of(ctx.lla)[0]
    want = m.linearize(ctx, 0)
    got = compiled_linearize(m, ctx)
    assert np.array_equal(want[1][:, lay.slice("gnss_err")], np.eye(3))
    for a, b, what in zip(got, want, ("nu", "H", "R")):
        assert np.abs(a - b).max() <= 1e-12 * max(np.abs(b).max(), 1.0), what


def test_paths_agree_with_the_nhc_lever_arm_mounting_and_the_fixes_correlated_error(drive):
    """A whole run with the constraint at a lever arm, the mounting block and the fixes' correlated-error
    states (drive_0708's layout): the compiled run is the Python run to rounding."""
    from inskit.integration import GnssPositionError, Mounting

    imu, truth, g = drive
    t0, t1 = imu.time[0], imu.time[-1]
    meas = [GnssPosition(g, lever_arm_b=(0.0, -0.05, 0.0)), ZeroVelocity([(t0, 19.0), (70.0, 83.0)], 10.0, 0.02),
            NonHolonomic([(t0, t1)], 10.0, 0.3, lever_arm_b=(0.06, 0.0, 0.79))]
    a, b = both(imu, truth.state(0), meas, scale_factors=True, recovery_after_s=5.0,
                extra_blocks=[Mounting(), GnssPositionError(0.3, 10.0)])
    assert_same_run(a, b)
    assert a.counts["nhc"]["used"] > 1400 and a.counts["gnss_pos"]["used"] > 100
