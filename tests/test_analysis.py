import numpy as np
import pytest

from inskit import analysis, earth
from inskit.errors import InputError
from inskit.types import NavSolution
from inskit.units import ARCMIN


def make(t, lla, yaw=0.0):
    n = len(t)
    return NavSolution.from_euler(t, np.tile(lla, (n, 1)), np.zeros((n, 3)), np.tile([0, 0, yaw], (n, 1)))


def test_known_offsets():
    ref = np.array([np.radians(40), np.radians(-105), 1600.0])
    t = np.arange(0.0, 10.0, 1.0)
    truth = make(t, ref)
    moved = earth.ned_to_lla([3.0, 4.0, -1.0], ref)
    sol = make(t, moved, yaw=np.radians(0.5))
    err = analysis.nav_error(sol, truth)
    assert np.allclose(err.pos_ned, [3.0, 4.0, -1.0], atol=1e-6)
    s = analysis.summarize(err)
    assert s["horizontal_m"]["rms"] == pytest.approx(5.0, abs=1e-6)
    assert s["yaw_arcmin"]["final"] == pytest.approx(30.0, rel=1e-9)
    assert s["roll_arcmin"]["max"] == pytest.approx(0.0, abs=1e-9)


def test_yaw_wraps():
    t = np.arange(3.0)
    ref = np.array([0.5, 0.5, 0.0])
    err = analysis.nav_error(make(t, ref, np.radians(179.9)), make(t, ref, np.radians(-179.9)))
    assert err.att_rpy[0, 2] / ARCMIN == pytest.approx(-12.0, abs=1e-6)


def test_no_overlap_is_an_error():
    ref = np.array([0.5, 0.5, 0.0])
    with pytest.raises(InputError, match="do not overlap"):
        analysis.nav_error(make(np.arange(3.0), ref), make(np.arange(3.0) + 100, ref))


def test_plot_writes_png(tmp_path):
    ref = np.array([0.5, 0.5, 0.0])
    t = np.arange(0.0, 5.0, 0.5)
    err = analysis.nav_error(make(t, ref), make(t, ref))
    p = analysis.plot_errors(err, tmp_path / "e.png")
    assert (tmp_path / "e.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert p == tmp_path / "e.png"


def test_attitude_in_degrees_beside_arcmin_and_yaw_wrapped():
    t = np.arange(3.0)
    ref = np.array([0.5, 0.5, 0.0])
    s = analysis.summarize(analysis.nav_error(make(t, ref, np.radians(179.9)), make(t, ref, np.radians(-179.9))))
    assert s["yaw_deg"]["final"] == pytest.approx(-0.2, abs=1e-9)  # across +-180: 0.2 deg, not 359.8
    assert s["yaw_arcmin"]["final"] == pytest.approx(-12.0, abs=1e-6)
    cols = analysis.per_epoch_columns(analysis.nav_error(make(t, ref, np.radians(179.9)),
                                                         make(t, ref, np.radians(-179.9))))
    assert cols["err_yaw_deg"] == pytest.approx([-0.2] * 3, abs=1e-9)


def _moving(t, ref):
    """2 km north at 10 m/s: NED frames along it differ by 0.3 mrad."""
    n = len(t)
    lla = earth.ned_to_lla(np.column_stack([10.0 * t, np.zeros(n), np.zeros(n)]), ref)
    return NavSolution.from_euler(t, lla, np.tile([10.0, 0, 0], (n, 1)), np.zeros((n, 3)))


def test_window_limits_are_respected_and_bad_windows_refused():
    ref = np.array([np.radians(40), np.radians(-105), 1600.0])
    t = np.arange(0.0, 200.0, 0.1)
    err = analysis.nav_error(_moving(t, ref), _moving(t, ref))
    w = analysis.restrict(err, 50.0, 60.0)
    assert w.time[0] == pytest.approx(50.0) and w.time[-1] == pytest.approx(60.0) and len(w.time) == 101
    assert analysis.restrict(err, None, 10.0).time[0] == 0.0  # one side open
    with pytest.raises(InputError, match=r"--from/--to: the window must end after it starts"):
        analysis.restrict(err, 60.0, 60.0)
    with pytest.raises(InputError, match=r"end 500 s lies outside the data .*0\.000\.\.199\.900 s"):
        analysis.restrict(err, 10.0, 500.0)
    with pytest.raises(InputError, match=r"--remove-offset: the window's start -50 s lies outside"):
        analysis.constant_offset(err, -50.0, 10.0)
    with pytest.raises(InputError, match="no epoch inside"):
        analysis.restrict(err, 50.01, 50.05)


def test_constant_offset_recovered_within_its_noise():
    """Solution = truth + a constant NED offset + white noise of 0.3 m per
    axis over 2000 epochs: the mean recovers the offset within 4 standard
    errors (0.3 / sqrt(2000) = 6.7 mm), the spread is the noise, and after
    the removal the horizontal RMS is the noise's sqrt(2) * 0.3 m."""
    ref = np.array([np.radians(40), np.radians(-105), 1600.0])
    t = np.arange(0.0, 200.0, 0.1)
    truth = _moving(t, ref)
    offset = np.array([1.5, -2.0, 0.7])
    rng = np.random.default_rng(11)
    noise = rng.normal(0.0, 0.3, (len(t), 3))
    sol = NavSolution(t, earth.ned_to_lla(offset + noise, truth.lla), truth.v_n, truth.q_nb)
    err = analysis.nav_error(sol, truth)
    o = analysis.constant_offset(err)
    se = 0.3 / np.sqrt(len(t))
    assert np.all(np.abs(o.ned_m - offset) < 4 * se), o.ned_m - offset
    assert o.spread_ned_m == pytest.approx([0.3] * 3, rel=0.05)
    assert o.epochs == 2000 and (o.from_s, o.to_s) == (0.0, pytest.approx(199.9))
    s = analysis.summarize(analysis.remove_offset(err, o.ned_m))
    assert s["horizontal_m"]["rms"] == pytest.approx(np.sqrt(2) * 0.3, rel=0.05)
    assert s["north_m"]["rms"] == pytest.approx(0.3, rel=0.05)  # the 1.5 m are gone
    # over a sub-interval: 300 epochs, a wider bound
    o2 = analysis.constant_offset(err, 20.0, 49.95)
    assert o2.epochs == 300 and np.all(np.abs(o2.ned_m - offset) < 4 * 0.3 / np.sqrt(300))


def test_per_epoch_columns():
    ref = np.array([np.radians(40), np.radians(-105), 1600.0])
    t = np.arange(0.0, 5.0, 0.5)
    truth = _moving(t, ref)
    sol = NavSolution(t, earth.ned_to_lla(np.array([3.0, 4.0, -1.0]), truth.lla), truth.v_n, truth.q_nb)
    cols = analysis.per_epoch_columns(analysis.nav_error(sol, truth))
    assert tuple(cols) == analysis.PER_EPOCH_COLUMNS
    assert cols["time_s"] == pytest.approx(t)
    assert cols["err_horizontal_m"] == pytest.approx([5.0] * len(t), abs=1e-6)
    assert cols["err_vertical_m"] == pytest.approx([1.0] * len(t), abs=1e-6)  # |down|
    assert cols["err_down_m"] == pytest.approx([-1.0] * len(t), abs=1e-6)
    assert cols["err_3d_m"] == pytest.approx([np.sqrt(26.0)] * len(t), abs=1e-6)


def _kept_figure(monkeypatch, module):
    """Capture the figure ``module.save_figure`` would write (and close)."""
    figs = []

    def keep(fig, path, dpi=110):
        figs.append(fig)
        return path

    monkeypatch.setattr(module, "save_figure", keep)
    return figs


def test_line_breaks_at_time_gaps_and_angle_wraps():
    t = np.array([0.0, 1.0, 2.0, 3.0, 10.0, 11.0])
    y = np.array([170.0, 178.0, -178.0, -170.0, -160.0, -150.0])
    tb, yb = analysis.line_breaks(t, y, period=360.0)
    # one break at the wrap (between 1 s and 2 s: 178 -> -178), one at the 7 s gap
    assert len(tb) == len(t) + 2 and np.isnan(yb).sum() == 2
    assert np.isnan(yb[2]) and tb[2] == 1.5 and np.isnan(yb[5]) and tb[5] == 6.5
    # not an angle: the jump stays joined, the gap does not
    tb, yb = analysis.line_breaks(t, y)
    assert np.isnan(yb).sum() == 1 and tb[4] == 6.5
    # nothing to break: the arrays as given
    tb, yb = analysis.line_breaks(t[:4], np.arange(4.0))
    assert np.array_equal(tb, t[:4]) and not np.isnan(yb).any()


def test_plot_draws_no_line_across_a_truth_gap_or_a_yaw_wrap(monkeypatch, tmp_path):
    """A truth with a 20 s hole leaves those epochs unscored, and a yaw error
    near 180 deg wraps: neither is joined by a line (it would draw errors
    nobody computed, and a swing through the whole circle)."""
    import inskit.analysis.errors as E

    ref = np.array([0.5, 0.5, 0.0])
    t = np.arange(0.0, 60.0, 1.0)
    yaw = np.radians(170.0 + t)  # crosses 180 deg at 10 s
    sol = NavSolution.from_euler(t, np.tile(ref, (len(t), 1)), np.zeros((len(t), 3)),
                                 np.column_stack([0 * t, 0 * t, yaw]))
    keep = (t < 20) | (t > 40)
    truth = NavSolution(t[keep], np.tile(ref, (keep.sum(), 1)), np.zeros((keep.sum(), 3)),
                        np.tile([1.0, 0, 0, 0], (keep.sum(), 1)))
    err = analysis.nav_error(sol, truth)
    assert err.time.max() - err.time.min() == 59.0 and len(err.time) == keep.sum()
    figs = _kept_figure(monkeypatch, E)
    analysis.plot_errors(err, tmp_path / "e.png")
    pos, _, att = figs[0].axes
    x, y = pos.get_lines()[0].get_data()
    gap = (x > 19) & (x < 41)
    assert np.isnan(y[gap]).all() and gap.any()           # the hole: undrawn
    yaw_line = att.get_lines()[2]
    _, yy = yaw_line.get_data()
    ok = ~np.isnan(yy)
    assert (np.abs(np.diff(yy))[ok[1:] & ok[:-1]] < 180).all()  # no segment jumps across the wrap
    assert ok.sum() == len(err.time)                       # every epoch still drawn
    assert np.nanmax(yy) > 175 and np.nanmin(yy) < -175   # the wrap is there, undrawn


def test_error_summary_judges_errors_against_the_solutions_own_sigmas():
    """Errors of 2 m north on a solution claiming 1 m: the ratio's RMS is 2
    there, 0 elsewhere; summed in parts it is the whole's; one part without
    sigmas (a solution file without them) drops the figure rather than
    judging half the run."""
    from inskit.analysis.errors import SIGMA_COLUMNS, ErrorSummary

    ref = np.array([np.radians(40), np.radians(-105), 1600.0])
    t = np.arange(0.0, 100.0, 1.0)
    n = len(t)
    truth = make(t, ref)
    extra = {k: np.ones(n) for k in SIGMA_COLUMNS}
    sol = NavSolution.from_euler(t, np.tile(earth.ned_to_lla([2.0, 0.0, 0.0], ref), (n, 1)), np.zeros((n, 3)),
                                 np.zeros((n, 3)), extra=extra)
    whole = analysis.summarize(analysis.nav_error(sol, truth))["consistency"]
    assert whole["normalized_rms"]["north"] == pytest.approx(2.0, rel=1e-6)
    assert whole["normalized_rms"]["east"] == pytest.approx(0.0, abs=1e-6)
    assert whole["beyond_3_sigma_fraction"] == dict.fromkeys(whole["beyond_3_sigma_fraction"], 0.0)
    err = analysis.nav_error(sol, truth)
    parts = ErrorSummary().add(err.select(t < 40)).add(err.select(t >= 40)).result()["consistency"]
    assert parts["normalized_rms"] == pytest.approx(whole["normalized_rms"], rel=1e-12, abs=1e-15)
    bare = analysis.nav_error(make(t, ref), truth)
    assert bare.sigma is None
    assert "consistency" not in ErrorSummary().add(err.select(t < 40)).add(bare.select(t >= 40)).result()
