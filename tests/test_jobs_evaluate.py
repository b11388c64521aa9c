"""The evaluate job (jobs/evaluate.py): time window, constant-offset removal,
per-epoch table, bad windows."""

import numpy as np
import pandas as pd
import pytest

from inskit import earth, io
from inskit.errors import InputError
from inskit.jobs.evaluate import evaluate, parse_interval, summary_text
from inskit.types import NavSolution

OFFSET = np.array([0.8, -1.2, 0.5])  # NED [m]
SIGMA = 0.2  # white noise per axis [m]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A 300 s drive north at 10 m/s (truth, 10 Hz) and a solution = truth +
    OFFSET + white noise, yaw 2 deg off."""
    d = tmp_path_factory.mktemp("eval")
    ref = np.array([np.radians(40), np.radians(-105), 1600.0])
    t = np.arange(3000) / 10.0
    n = len(t)
    lla = earth.ned_to_lla(np.column_stack([10.0 * t, np.zeros(n), np.zeros(n)]), ref)
    truth = NavSolution.from_euler(t, lla, np.tile([10.0, 0, 0], (n, 1)), np.tile([0, 0, np.radians(179.0)], (n, 1)))
    noise = np.random.default_rng(7).normal(0.0, SIGMA, (n, 3))
    sol = NavSolution.from_euler(t, earth.ned_to_lla(OFFSET + noise, lla), truth.v_n,
                                 np.tile([0, 0, np.radians(-179.0)], (n, 1)))
    io.write_solution(d / "truth.csv", truth)
    io.write_solution(d / "sol.csv", sol)
    return d


def test_interval_parsing():
    assert parse_interval("10:20") == (10.0, 20.0)
    assert parse_interval(" 10.5 : ") == (10.5, None)
    assert parse_interval(":1e2") == (None, 100.0)
    assert parse_interval("window") == (None, None)
    with pytest.raises(InputError, match=r"--remove-offset: 'sol\.csv' is not an interval FROM:TO"):
        parse_interval("sol.csv")


def test_window_offset_and_per_epoch_table(files, tmp_path):
    out = tmp_path / "e.csv"
    s = evaluate(files / "sol.csv", files / "truth.csv", t_from=100.0, t_to=200.0, remove_offset=(None, None),
                 per_epoch_file=out)
    assert s["epochs"] == 1001
    assert s["first_epoch_s"] == pytest.approx(100.0) and s["last_epoch_s"] == pytest.approx(200.0)
    o = s["offset_removed"]
    se = SIGMA / np.sqrt(1001)
    for k, v in zip(("north_m", "east_m", "down_m"), OFFSET):
        assert abs(o[k] - v) < 4 * se, (k, o[k])
    assert o["epochs"] == 1001 and o["from_s"] == pytest.approx(100.0)
    assert s["horizontal_m"]["rms"] == pytest.approx(np.sqrt(2) * SIGMA, rel=0.08)
    assert s["yaw_deg"]["rms"] == pytest.approx(2.0, abs=1e-6)  # -179 vs 179: 2 deg across the wrap
    tab = pd.read_csv(out)
    assert tab["time_s"].min() == pytest.approx(100.0) and tab["time_s"].max() == pytest.approx(200.0)
    assert len(tab) == 1001 and abs(tab["err_north_m"].mean()) < 1e-9  # the offset removed is the window's mean
    assert tab["err_yaw_deg"].to_numpy() == pytest.approx(2.0, abs=1e-6)
    assert s["per_epoch"] == str(out)
    assert "constant offset removed" in summary_text(s) and "yaw_deg" in summary_text(s)


def test_offset_from_an_interval_outside_the_window(files, tmp_path):
    """The offset estimated over 0..50 s is removed from the 200..300 s window."""
    s = evaluate(files / "sol.csv", files / "truth.csv", t_from=200.0, remove_offset=(0.0, 50.0),
                 per_epoch_file=tmp_path / "e.parquet")
    o = s["offset_removed"]
    assert o["epochs"] == 501 and o["to_s"] == pytest.approx(50.0)
    assert abs(o["east_m"] - OFFSET[1]) < 4 * SIGMA / np.sqrt(501)
    from inskit.io.parquet import read_parquet_columns

    cols, meta = read_parquet_columns(tmp_path / "e.parquet")
    assert cols["time_s"][0] == pytest.approx(200.0) and len(cols["time_s"]) == 1000  # 200.0 .. 299.9 s
    assert meta["offset_removed"]["epochs"] == 501
    # without removal the offset stays in the figures
    raw = evaluate(files / "sol.csv", files / "truth.csv", t_from=200.0)
    assert raw["offset_removed"] is None and raw["north_m"]["rms"] > 0.7


@pytest.mark.parametrize("kw, match", [
    ({"t_from": 50.0, "t_to": 50.0}, r"--from/--to: the window must end after it starts"),
    ({"t_from": 250.0, "t_to": 100.0}, r"must end after it starts"),
    ({"t_to": 1000.0}, r"--from/--to: the window's end 1000 s lies outside the data"),
    ({"t_from": -20.0}, r"start -20 s lies outside the data"),
    ({"remove_offset": (290.0, 400.0)}, r"--remove-offset: the window's end 400 s lies outside"),
    ({"remove_offset": (10.01, 10.05)}, r"--remove-offset: no epoch inside"),
])
def test_bad_windows_are_refused(files, kw, match):
    with pytest.raises(InputError, match=match):
        evaluate(files / "sol.csv", files / "truth.csv", **kw)


def test_per_epoch_file_refusals(files, tmp_path):
    keep = tmp_path / "keep.csv"
    keep.write_text("precious\n")
    with pytest.raises(InputError, match=r"keep\.csv: already exists; refusing to overwrite it \(use --force\)"):
        evaluate(files / "sol.csv", files / "truth.csv", per_epoch_file=keep)
    assert keep.read_text() == "precious\n"
    evaluate(files / "sol.csv", files / "truth.csv", per_epoch_file=keep, force=True)
    assert len(pd.read_csv(keep)) == 3000
    with pytest.raises(InputError, match=r"unsupported per-epoch table format"):
        evaluate(files / "sol.csv", files / "truth.csv", per_epoch_file=tmp_path / "e.txt")
    with pytest.raises(InputError, match=r"is an input of this run"):
        evaluate(files / "sol.csv", files / "truth.csv", per_epoch_file=files / "sol.csv", force=True)


def test_a_gap_in_the_truth_is_not_interpolated_across(files, tmp_path):
    """60 s of a truth removed used to be bridged by linear interpolation (a
    turn became a chord: 41 m of RMS error read as 65 m).  The epochs inside
    the gap are left unscored and said so; a truth of part of the run
    likewise."""
    from inskit import analysis

    truth = io.read_solution(files / "truth.csv")
    keep = (truth.time < 100.0) | (truth.time >= 160.0)
    cut = NavSolution(truth.time[keep], truth.lla[keep], truth.v_n[keep], truth.q_nb[keep])
    io.write_solution(tmp_path / "gap.csv", cut)
    s = evaluate(files / "sol.csv", tmp_path / "gap.csv")
    c = s["truth_coverage"]
    assert c["truth_gaps"] == [[pytest.approx(99.9), pytest.approx(160.0)]]
    assert c["epochs_in_truth_gaps"] == 600 and s["epochs"] == c["epochs_scored"] == 3000 - 600
    assert any("gap(s) of the truth" in w for w in s["warnings"]) and "warning: scored 2400 of 3000" in \
        summary_text(s)
    short = NavSolution(truth.time[:100], truth.lla[:100], truth.v_n[:100], truth.q_nb[:100])
    io.write_solution(tmp_path / "short.csv", short)
    s = evaluate(files / "sol.csv", tmp_path / "short.csv")
    assert s["epochs"] == 100 and any("2900 of 3000 solution epochs lie outside the truth's span" in w
                                      for w in s["warnings"])
    assert evaluate(files / "sol.csv", files / "truth.csv")["warnings"] == []
    # an epoch on a truth sample at the edge of a gap is still scored (nothing is interpolated there)
    assert analysis.truth_covers(np.array([99.9, 100.0, 160.0]), cut.time).tolist() == [True, False, True]
    # a streamed run hands the gaps found once to every segment: the same errors as the whole solution's
    from inskit.analysis.errors import nav_error_part

    sol = io.read_solution(files / "sol.csv")
    gaps, limit = analysis.truth_gaps(cut.time)
    assert gaps.tolist() == [[pytest.approx(99.9), pytest.approx(160.0)]] and limit == pytest.approx(0.5)
    whole = analysis.nav_error(sol, cut)
    parts = [nav_error_part(NavSolution(sol.time[a:a + 700], sol.lla[a:a + 700], sol.v_n[a:a + 700],
                                        sol.q_nb[a:a + 700]), cut, gaps) for a in range(0, 3000, 700)]
    assert np.array_equal(np.concatenate([p.time for p in parts]), whole.time)
    assert np.allclose(np.concatenate([p.pos_ned for p in parts]), whole.pos_ned)


def test_a_one_row_truth_scores_the_epoch_at_its_time(files, tmp_path):
    """A truth of one row (a surveyed point at one time) was 'inskit: error: `lla` has a NaN or infinite value
    (nan) at row 0', no file named: interpolating it divided by a zero-length interval.  It scores the one
    solution epoch at its time, and the coverage says the rest lie outside its span."""
    truth = io.read_solution(files / "truth.csv")
    io.write_solution(tmp_path / "point.csv", truth.slice(1500, 1501))
    s = evaluate(files / "sol.csv", tmp_path / "point.csv")
    assert s["epochs"] == 1 and s["first_epoch_s"] == pytest.approx(150.0)
    full = evaluate(files / "sol.csv", files / "truth.csv", t_from=150.0, t_to=150.0 + 1e-9)
    assert s["north_m"]["final"] == pytest.approx(full["north_m"]["final"], abs=1e-9)
    assert s["truth_coverage"]["epochs_outside_truth_span"] == 2999
    assert any(w.startswith("only 1 solution epoch scored") for w in s["warnings"]), s["warnings"]
    sol = io.read_solution(files / "sol.csv")  # a one-row solution against the whole truth: said too (it was not)
    io.write_solution(tmp_path / "one.csv", sol.slice(20, 21))
    w = evaluate(tmp_path / "one.csv", files / "truth.csv")["warnings"]
    assert w == ["only 1 solution epoch scored: an RMS and a maximum of so few errors say little (a solution file "
                 "cut short, or written at a low rate?)"], w
    assert not [x for x in evaluate(files / "sol.csv", files / "truth.csv")["warnings"] if "scored:" in x]
    tr = truth.slice(10, 11)
    one = tr.interpolate(tr.time)
    assert np.array_equal(one.lla, tr.lla) and np.allclose(one.q_nb, tr.q_nb)


def test_a_truth_in_milliseconds_is_refused_and_a_coarse_one_is_said(files, tmp_path):
    """A 10 Hz truth whose time column holds milliseconds reads as a sample every 100 s: it overlapped the
    solution's first 300 s with 4 samples and was scored (5.8 km RMS on a drive), later with a warning only.  Its
    positions move 1000 times slower than its velocity columns say: refused when read, naming the file.  A truth
    really sampled every 100 s is scored with the warning naming the step; the right file, and a 1 Hz truth
    (GNSS-like), say nothing."""
    truth = io.read_solution(files / "truth.csv")
    ms = NavSolution(truth.time * 1000.0, truth.lla, truth.v_n, truth.q_nb, {})
    io.write_solution(tmp_path / "truth_ms.csv", ms)
    with pytest.raises(InputError, match=r"truth_ms\.csv: its positions move 1000 times slower than its velocity "
                                         r"columns say .*the time column holds milliseconds, not seconds"):
        evaluate(files / "sol.csv", tmp_path / "truth_ms.csv")
    coarse = np.arange(0, len(truth.time), 1000)
    io.write_solution(tmp_path / "truth_100s.csv", NavSolution(truth.time[coarse], truth.lla[coarse],
                                                                truth.v_n[coarse], truth.q_nb[coarse], {}))
    s = evaluate(files / "sol.csv", tmp_path / "truth_100s.csv")
    w = [x for x in s["warnings"] if "the truth is sampled every 100 s" in x]
    assert len(w) == 1 and "against the solution's 0.1 s" in w[0] and "in ms" in w[0], s["warnings"]
    assert "warning: " + w[0] in summary_text(s)
    assert not [x for x in evaluate(files / "sol.csv", files / "truth.csv")["warnings"] if "sampled every" in x]
    keep = np.arange(0, len(truth.time), 10)
    io.write_solution(tmp_path / "truth_1hz.csv", NavSolution(truth.time[keep], truth.lla[keep], truth.v_n[keep],
                                                               truth.q_nb[keep], {}))
    assert not [x for x in evaluate(files / "sol.csv", tmp_path / "truth_1hz.csv")["warnings"]
                if "sampled every" in x]


def test_a_truth_elsewhere_from_the_start_is_said(files, tmp_path):
    """A truth whose latitude and longitude hold radians under the _deg headers (0.698 for 40 deg) was scored
    as an error of thousands of km without a word (a helper found it): now its reader refuses it (its positions
    move 57.3 times less than its velocities say); a solution that starts 10 km or more from its truth describes
    another place, and the warning says so.  The right truth says nothing."""
    truth = io.read_solution(files / "truth.csv")
    df = pd.read_csv(files / "truth.csv")
    df["lat_deg"] = np.radians(df["lat_deg"])
    df["lon_deg"] = np.radians(df["lon_deg"])
    df.to_csv(tmp_path / "truth_rad.csv", index=False)
    with pytest.raises(InputError, match=r"truth_rad\.csv: its positions move 57\.\d+ times slower than its velocity "
                                         r"columns say .*latitude and longitude hold radians under the _deg headers"):
        evaluate(files / "sol.csv", tmp_path / "truth_rad.csv")  # refused by the reader: it moves 57 times too little
    df = pd.read_csv(files / "truth.csv")
    df["lat_deg"] += 0.2  # 22 km north: another datum, another place
    df.to_csv(tmp_path / "truth_far.csv", index=False)
    s = evaluate(files / "sol.csv", tmp_path / "truth_far.csv")
    w = [x for x in s["warnings"] if "km from the truth" in x]
    assert len(w) == 1 and "radians under a _deg header" in w[0], s["warnings"]
    assert not [x for x in evaluate(files / "sol.csv", files / "truth.csv")["warnings"] if "km from" in x]
    assert len(truth.time) == len(df)


@pytest.fixture(scope="module")
def turning(tmp_path_factory):
    """A 300 s drive round a circle of 300 m at 10 m/s (it turns through 573 deg), pitch and roll swinging a
    few degrees; the solution is the truth with 0.1 deg of attitude noise."""
    d = tmp_path_factory.mktemp("turn")
    t = np.arange(3000) / 10.0
    n, w = len(t), 10.0 / 300.0
    ned = np.column_stack([300.0 * np.sin(w * t), 300.0 * (1.0 - np.cos(w * t)), np.zeros(n)])
    lla = earth.ned_to_lla(ned, np.array([np.radians(40), np.radians(-105), 1600.0]))
    v = np.column_stack([10.0 * np.cos(w * t), 10.0 * np.sin(w * t), np.zeros(n)])
    rpy = np.column_stack([np.radians(2.0) * np.cos(t / 15.0), np.radians(3.0) * np.sin(t / 20.0), w * t])
    truth = NavSolution.from_euler(t, lla, v, rpy)
    noise = np.random.default_rng(3).normal(0.0, np.radians(0.1), (n, 3))
    io.write_solution(d / "truth.csv", truth)
    io.write_solution(d / "sol.csv", NavSolution.from_euler(t, lla, v, rpy + noise))
    return d


def _in_radians(src, dst, columns):
    df = pd.read_csv(src)
    for c in columns:
        df[c] = np.radians(df[c])
    df.to_csv(dst, index=False)
    return dst


def _unit_warnings(s):
    return [w for w in s["warnings"] if "seems to hold radians" in w]


def test_attitude_in_radians_under_deg_headers_is_said(turning, tmp_path):
    """Attitude written in radians under roll_deg/pitch_deg/yaw_deg was scored without a word (a yaw error of
    107 deg RMS on a drive, a pitch that looked 57 times better than it was).  A yaw in radians follows the
    direction of travel of a track that turns; a column in radians times 180/pi matches the other file's:
    the warning names the file and the column, in either file; the right files say nothing."""
    assert _unit_warnings(evaluate(turning / "sol.csv", turning / "truth.csv")) == []
    sol_rad = _in_radians(turning / "sol.csv", tmp_path / "sol_rad.csv", ["yaw_deg"])
    s = evaluate(sol_rad, turning / "truth.csv")
    w = _unit_warnings(s)
    assert len(w) == 1 and w[0].startswith(f"{sol_rad}: column 'yaw_deg'") and "direction of travel" in w[0], w
    assert "warning: " + w[0] in summary_text(s)
    truth_rad = _in_radians(turning / "truth.csv", tmp_path / "truth_rad.csv", ["pitch_deg", "roll_deg"])
    w = _unit_warnings(evaluate(turning / "sol.csv", truth_rad))
    assert len(w) == 2 and all(x.startswith(f"{truth_rad}: column '") for x in w), w
    assert "'roll_deg'" in w[0] and "'pitch_deg'" in w[1] and "times 180/pi, they match" in w[0]
    # both files in radians agree with each other: only the yaw against the track tells, in each file
    both = _in_radians(turning / "truth.csv", tmp_path / "truth_rad_yaw.csv", ["yaw_deg"])
    w = _unit_warnings(evaluate(sol_rad, both))
    assert len(w) == 2 and "'yaw_deg'" in w[0] and "'yaw_deg'" in w[1], w


def test_attitude_unit_check_keeps_quiet_where_it_cannot_tell(files, turning, tmp_path):
    """A straight track (files: yaw 179 deg against a course of 0, the body turned from the track) cannot tell
    a yaw's unit; a poor solution in degrees (10 deg attitude errors) is no radians either."""
    assert _unit_warnings(evaluate(files / "sol.csv", files / "truth.csv")) == []
    df = pd.read_csv(turning / "sol.csv")
    rng = np.random.default_rng(5)
    for c in ("roll_deg", "pitch_deg", "yaw_deg"):
        df[c] = df[c] + rng.normal(0.0, 10.0, len(df))
    df.to_csv(tmp_path / "poor.csv", index=False)
    assert _unit_warnings(evaluate(tmp_path / "poor.csv", turning / "truth.csv")) == []


def _with_sigmas(d, name, pos_sigma_file, seed=11, offset_ned_m=(0.0, 0.0, 0.0), yaw_sigma_deg=0.5):
    """A solution = truth + white errors of 0.2 m per position axis, 0.05 m/s
    per velocity axis and 0.5 deg of yaw (and ``offset_ned_m`` [m]), written
    with its own sigma columns claiming ``pos_sigma_file`` [m] for the
    position (right: 0.2), ``yaw_sigma_deg`` for the yaw (right: 0.5) and the
    true velocity sigmas."""
    truth = io.read_solution(d / "truth.csv")
    n = len(truth.time)
    rng = np.random.default_rng(seed)
    dp, dv, dyaw = rng.normal(0, 0.2, (n, 3)), rng.normal(0, 0.05, (n, 3)), rng.normal(0, np.radians(0.5), n)
    dp = dp + np.asarray(offset_ned_m, float)
    rpy = truth.euler.copy()
    rpy[:, 2] += dyaw
    extra = {k: np.full(n, v) for k, v in (("sigma_n_m", pos_sigma_file), ("sigma_e_m", pos_sigma_file),
                                           ("sigma_d_m", pos_sigma_file), ("sigma_vn_m_s", 0.05),
                                           ("sigma_ve_m_s", 0.05), ("sigma_vd_m_s", 0.05),
                                           ("sigma_att_n_rad", np.radians(0.1)), ("sigma_att_e_rad", np.radians(0.1)),
                                           ("sigma_att_d_rad", np.radians(yaw_sigma_deg)))}
    sol = NavSolution.from_euler(truth.time, earth.ned_to_lla(dp, truth.lla), truth.v_n + dv, rpy, extra=extra)
    io.write_solution(d / name, sol)
    return d / name


def test_errors_over_the_solutions_own_sigmas(files):
    """3000 epochs of white errors whose sigmas the file states rightly: the
    RMS of error over sigma is 1 within 5 % on every channel (its standard
    error is 1/sqrt(2 n) = 1.3 %) and 0.27 % of epochs lie beyond 3 sigma
    (binomial: 8 of 3000 expected, 0.6 % allowed); no warning."""
    s = evaluate(_with_sigmas(files, "sol_sig.csv", 0.2), files / "truth.csv")
    c = s["consistency"]
    assert c["epochs"] == 3000
    assert c["normalized_rms"] == pytest.approx(dict.fromkeys(("north", "east", "down", "vn", "ve", "vd", "yaw"), 1.0),
                                                rel=0.05)
    assert max(c["beyond_3_sigma_fraction"].values()) < 0.006
    assert not [w for w in s["warnings"] if "own sigmas" in w]
    assert "error over the solution's own sigma, RMS (1 when consistent): north 1.0" in summary_text(s)


def test_a_solution_whose_sigmas_understate_its_errors_is_said(files):
    """Position sigmas of 0.05 m for errors of 0.2 m: 4 times overconfident on
    the three position axes, named with the GNSS keys that usually cause it."""
    s = evaluate(_with_sigmas(files, "sol_over.csv", 0.05), files / "truth.csv")
    z = s["consistency"]["normalized_rms"]
    assert [z[k] for k in ("north", "east", "down")] == pytest.approx([4.0] * 3, rel=0.05)
    warn = [w for w in s["warnings"] if "own sigmas" in w]
    assert len(warn) == 1 and warn[0].startswith("truth: the solution's errors are more than 2 times its own sigmas")
    assert "north 4." in warn[0] and "position: fixes whose error" in warn[0] and "velocity:" not in warn[0]


def test_a_solution_without_sigmas_has_no_consistency(files):
    s = evaluate(files / "sol.csv", files / "truth.csv")
    assert "consistency" not in s and "own sigma" not in summary_text(s)
    assert not [w for w in s["warnings"] if "sigma" in w]  # no sigma columns at all: nothing to say


def test_a_solution_with_some_of_its_sigmas_says_it_is_not_judged(files):
    """A file carrying the position and velocity sigmas but not the heading's
    (sigma_att_d_rad) was not judged, without a word."""
    import pandas as pd

    sol = pd.read_csv(_with_sigmas(files, "sol_part.csv", 0.2))
    sol.drop(columns=["sigma_att_d_rad"]).to_csv(files / "sol_part.csv", index=False)
    s = evaluate(files / "sol_part.csv", files / "truth.csv")
    assert "consistency" not in s
    w = [w for w in s["warnings"] if "not judged against the solution's own sigmas" in w]
    assert len(w) == 1 and "but not sigma_att_d_rad" in w[0] and "sigma_n_m" in w[0], s["warnings"]


def test_a_removed_offset_leaves_the_position_unjudged(files):
    """A solution 1 m off down whose sigmas claim the 0.2 m of its white
    errors: 5 sigma RMS down, said.  With --remove-offset the offset fitted
    to the errors took the overconfidence with it and the down figure read
    1.0, nothing said; the sigmas describe the error with its offset, so the
    position channels are now null, said so, and the velocity and yaw still
    judged."""
    sol = _with_sigmas(files, "sol_off.csv", 0.2, offset_ned_m=(0.0, 0.0, 1.0))
    s = evaluate(sol, files / "truth.csv")
    assert s["consistency"]["normalized_rms"]["down"] == pytest.approx(5.1, rel=0.05)
    assert [w for w in s["warnings"] if "own sigmas" in w and "down 5." in w]
    for interval in ((None, None), (0.0, 100.0)):
        s = evaluate(sol, files / "truth.csv", remove_offset=interval)
        c = s["consistency"]
        for k in ("north", "east", "down"):
            assert c["normalized_rms"][k] is None and c["beyond_3_sigma_fraction"][k] is None
        assert c["normalized_rms"]["vn"] == pytest.approx(1.0, rel=0.05) and "constant offset was removed" in c["note"]
        assert not [w for w in s["warnings"] if "own sigmas" in w]
        text = summary_text(s)
        assert "north n/a, east n/a, down n/a, vn 0.9" in text and "after a removed offset is not judged" in text


def test_a_truth_yaw_of_another_convention_is_not_blamed_on_the_gyros(files, tmp_path):
    """The truth's yaw written counter-clockwise from east (90 - yaw): the
    solution's yaw is 92 deg off, thousands of its sigmas, and the
    warning blamed gyro noise and [noise]; an error beyond the filter's
    small-angle model now names the truth's convention."""
    sol = _with_sigmas(files, "sol_sig_yaw.csv", 0.2)
    df = pd.read_csv(files / "truth.csv")
    df["yaw_deg"] = (90.0 - df["yaw_deg"] + 180.0) % 360.0 - 180.0
    df.to_csv(tmp_path / "truth_enu.csv", index=False)
    s = evaluate(sol, tmp_path / "truth_enu.csv")
    warn = [w for w in s["warnings"] if "own sigmas" in w]
    assert len(warn) == 1 and "yaw: an error of 92 deg RMS is no filter's small-angle error: a truth whose yaw_deg " \
                               "follows another convention" in warn[0] and "gyro noise" not in warn[0], warn
    s = evaluate(_with_sigmas(files, "sol_sig_yaw_over.csv", 0.2, yaw_sigma_deg=0.1), files / "truth.csv")
    warn = [w for w in s["warnings"] if "own sigmas" in w]  # a filter overconfident in yaw: the gyros are named
    assert len(warn) == 1 and "yaw: gyro noise or biases" in warn[0], warn


def test_sigma_columns_of_zero_or_below_are_said(files, tmp_path):
    """A solution file whose sigma columns hold 0 over half the epochs (or
    negative values throughout): consistency was taken over the other half
    (or dropped) without a word; now a warning names the file, the columns
    and the count."""
    df = pd.read_csv(_with_sigmas(files, "sol_sig_z.csv", 0.2))
    half = df.copy()
    half.loc[:1499, "sigma_e_m"] = 0.0
    half.to_csv(tmp_path / "half.csv", index=False)
    s = evaluate(tmp_path / "half.csv", files / "truth.csv")
    assert s["consistency"]["epochs"] == 1500
    warn = [w for w in s["warnings"] if "(a 1-sigma is > 0)" in w]
    assert warn == [f"{tmp_path / 'half.csv'}: 1500 of 3000 scored epochs hold 0 or less in sigma_e_m (a 1-sigma is "
                    "> 0): they are not judged against the solution's own sigmas"]
    neg = df.copy()
    neg["sigma_n_m"] = -neg["sigma_n_m"]
    neg.to_csv(tmp_path / "neg.csv", index=False)
    s = evaluate(tmp_path / "neg.csv", files / "truth.csv")
    assert "consistency" not in s
    assert [w for w in s["warnings"] if "3000 of 3000 scored epochs hold 0 or less in sigma_n_m" in w
            and w.endswith("no epoch is, so there is no consistency figure")]
    assert not [w for w in evaluate(files / "sol.csv", files / "truth.csv")["warnings"] if "1-sigma" in w]


def test_roll_and_yaw_errors_near_a_vertical_pitch_are_said_to_be_euler_differences(tmp_path):
    """A simulated vertical pull-up (a pitch segment of 90 deg), consumer MEMS, mechanized: evaluate gave
    roll_deg RMS 107.6, max 160 deg and yaw_deg 107.1, 160 deg, without a word, while the rotation between
    the two attitudes never passed 8.2 deg: at a pitch of 90 deg roll and yaw are ill-defined and their
    difference flips by 180 deg.  Now the summary says so, setting the rotation angle beside them; a
    level run says nothing of it."""
    n = 200
    t = np.arange(n) / 10.0
    ref = np.array([np.radians(45), np.radians(10), 100.0])
    lla = np.tile(ref, (n, 1))
    pitch = np.radians(np.minimum(89.99, 60.25 + t * 5.0))  # beyond 85 deg from 5 s, 89.99 deg from 6 s
    truth = NavSolution.from_euler(t, lla, np.zeros((n, 3)), np.column_stack([np.zeros(n), pitch, np.zeros(n)]))
    # the solution 0.5 deg off about the body's z axis: at a vertical pitch, a roll and a yaw of opposite sign
    from inskit import rotations as rot

    C = rot.dcm_from_euler(truth.euler) @ rot.dcm_from_euler([0.0, 0.0, np.radians(0.5)])
    sol = NavSolution(t, lla, np.zeros((n, 3)), rot.quat_from_dcm(C))
    io.write_solution(tmp_path / "truth.csv", truth)
    io.write_solution(tmp_path / "sol.csv", sol)
    s = evaluate(tmp_path / "sol.csv", tmp_path / "truth.csv")
    assert s["roll_deg"]["max"] > 20.0  # the Euler difference, far beyond the attitude's 0.5 deg
    w = [x for x in s["warnings"] if "gimbal lock" in x]
    assert len(w) == 1, s["warnings"]
    assert w[0].startswith(f"{int(np.sum(pitch > np.radians(85.0)))} of the {n} epochs scored (")
    assert "while the attitude is off by at most 0.5 deg (the angle of the rotation between the two attitudes)" \
        in w[0]
    steep = NavSolution.from_euler(t, lla, np.zeros((n, 3)), np.tile([0.0, np.radians(80.0), 0.0], (n, 1)))
    io.write_solution(tmp_path / "steep.csv", steep)
    io.write_solution(tmp_path / "steep_sol.csv", NavSolution(t, lla, np.zeros((n, 3)), rot.quat_from_dcm(
        rot.dcm_from_euler(steep.euler) @ rot.dcm_from_euler([0.0, 0.0, np.radians(0.5)]))))
    assert not [x for x in evaluate(tmp_path / "steep_sol.csv", tmp_path / "steep.csv")["warnings"]
                if "gimbal lock" in x]


def test_navigate_against_a_truth_says_where_its_pitch_is_vertical():
    """``navigate --truth`` scores roll and yaw as evaluate does, but said
    nothing of a truth whose pitch passes +-85 deg (found by the review of
    evaluate's gimbal-lock warning): the truth-side check, from the
    quaternions, over the run's span only."""
    from inskit.jobs.evaluate import vertical_pitch_warnings

    n = 200
    t = np.arange(n) / 10.0
    lla = np.tile([np.radians(45), np.radians(10), 100.0], (n, 1))
    pitch = np.radians(np.minimum(89.99, 60.25 + t * 5.0))  # beyond 85 deg from 5 s
    truth = NavSolution.from_euler(t, lla, np.zeros((n, 3)), np.column_stack([np.zeros(n), pitch, np.zeros(n)]))
    w = vertical_pitch_warnings(truth, 0.0, t[-1])
    assert len(w) == 1 and f"at {int(np.sum(pitch > np.radians(85.0)))} of its {n} rows (" in w[0]
    assert w[0].endswith("inskit evaluate of the solution file sets the rotation angle beside them")
    assert vertical_pitch_warnings(truth, 0.0, 4.9) == []  # the run ends before the pitch gets there
    dive = NavSolution.from_euler(t, lla, np.zeros((n, 3)), np.column_stack([np.zeros(n), -pitch, np.zeros(n)]))
    assert len(vertical_pitch_warnings(dive, 0.0, t[-1])) == 1  # nose down alike
    level = NavSolution.from_euler(t, lla, np.zeros((n, 3)), np.tile([0.0, np.radians(80.0), 0.0], (n, 1)))
    assert vertical_pitch_warnings(level, 0.0, t[-1]) == []
