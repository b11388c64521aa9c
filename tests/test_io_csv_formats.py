"""The lean IMU reader of :mod:`inskit.io.csv_formats` (issue 13): well-formed increment files (CSV and
Parquet) are read straight into their arrays, exactly (every double as Python's correctly rounded
``float()`` reads its text), and every other file still goes the pandas way, whose messages name the
line and the column."""

import re

import numpy as np
import pandas as pd
import pytest

from inskit import io
from inskit.errors import InputError
from inskit.io import csv_formats as C


def _increments(n=3001, seed=4):
    rng = np.random.default_rng(seed)
    t = 12.3 + 0.005 * np.arange(n)
    dth = rng.normal(0, 1e-4, (n, 3))
    dv = rng.normal(0, 1e-3, (n, 3)) + [0.0, 0.0, -9.8 * 0.005]
    dth[0] = dv[0] = 0.0
    return t, dth, dv


def _write(path, t, dth, dv, fmt=repr):
    head = "time_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_m_s,dv_y_m_s,dv_z_m_s\n"
    rows = (",".join(fmt(float(x)) for x in r) for r in np.column_stack([t, dth, dv]))
    path.write_text(head + "\n".join(rows) + "\n")


def test_well_formed_files_are_read_exactly_by_the_lean_path(tmp_path, monkeypatch):
    t, dth, dv = _increments()
    p = tmp_path / "imu.csv"
    _write(p, t, dth, dv)  # repr: the shortest text that reads back as the same double
    calls = []
    lean = C.lean_columns
    monkeypatch.setattr(C, "lean_columns", lambda *a: calls.append(a) or lean(*a))
    imu = C.read_imu(p)
    assert calls, "the lean path was not taken"
    assert np.array_equal(imu.time, t) and np.array_equal(imu.dtheta_b, dth) and np.array_equal(imu.dv_b, dv)
    assert imu.dtheta_b.flags["C_CONTIGUOUS"] and imu.dv_b.flags["C_CONTIGUOUS"]
    q = tmp_path / "imu.parquet"
    io.write_imu(q, imu)
    back = C.read_imu(q)
    assert np.array_equal(back.dtheta_b, dth) and np.array_equal(back.time, t) and len(calls) == 2


@pytest.mark.parametrize("whole_bytes", [0, 1 << 40])
def test_whole_and_streamed_csv_parsing_give_the_same_exact_arrays(tmp_path, monkeypatch, whole_bytes):
    # a small file parsed whole (the default below WHOLE_CSV_BYTES) or streamed block by block (above it):
    # the same doubles either way, in several blocks when streamed
    t, dth, dv = _increments(200_000)
    p = tmp_path / "imu.csv"
    _write(p, t, dth, dv)
    assert p.stat().st_size > 3 * (1 << 22)  # more than one 4 MB block of the streaming reader
    monkeypatch.setattr(C, "WHOLE_CSV_BYTES", whole_bytes)
    imu = C.read_imu(p)
    assert np.array_equal(imu.time, t) and np.array_equal(imu.dtheta_b, dth) and np.array_equal(imu.dv_b, dv)


def test_degrees_and_the_discard_rule_on_the_lean_path(tmp_path):
    t, dth, dv = _increments(500)
    p = tmp_path / "imu.csv"
    head = "time_s,dtheta_x_deg,dtheta_y_deg,dtheta_z_deg,dv_x_m_s,dv_y_m_s,dv_z_m_s\n"
    d = dth.copy()
    d[0] = 0.3  # a first packet over an unknown interval
    p.write_text(head + "\n".join(",".join(repr(float(x)) for x in r)
                                  for r in np.column_stack([t, np.degrees(d), dv])) + "\n")
    with pytest.raises(InputError, match="line 2 .*holds increments"):
        C.read_imu(p)
    imu = C.read_imu(p, first_row="discard")
    assert np.allclose(imu.dtheta_b[1:], dth[1:], rtol=1e-15, atol=0) and (imu.dtheta_b[0] == 0).all()


@pytest.mark.parametrize("fault, message", [
    (lambda rows: rows.__setitem__(7, rows[7].replace(rows[7].split(",")[2], "", 1)), r"line 9: column 'dtheta_y_rad' is empty"),
    (lambda rows: rows.__setitem__(7, rows[7].replace(rows[7].split(",")[2], "abc", 1)), r"line 9: column 'dtheta_y_rad' has 'abc'"),
    (lambda rows: rows.__setitem__(7, rows[7].replace(rows[7].split(",")[2], "nan", 1)), r"line 9: column 'dtheta_y_rad'"),
    (lambda rows: rows.__setitem__(7, rows[6]), r"line 9: duplicate timestamp"),
])
def test_faulty_files_keep_the_messages_that_name_line_and_column(tmp_path, fault, message):
    t, dth, dv = _increments(50)
    p = tmp_path / "imu.csv"
    _write(p, t, dth, dv)
    lines = p.read_text().splitlines()
    rows = lines[1:]
    fault(rows)
    p.write_text("\n".join([lines[0]] + rows) + "\n")
    with pytest.raises(InputError, match=message):
        C.read_imu(p)


def test_count_lines_with_and_without_a_final_newline(tmp_path):
    p = tmp_path / "a.txt"
    p.write_bytes(b"h\n1\n2")
    assert C._count_lines(p) == 3
    p.write_bytes(b"h\n1\n2\n")
    assert C._count_lines(p) == 3


def test_a_plain_solution_csv_is_read_by_the_lean_path_like_the_pandas_one(tmp_path, monkeypatch):
    """A well-formed solution CSV goes the pyarrow way (no pandas), with its
    extra columns, and reads the same numbers as the pandas path (which a
    file with a text cell still takes); a time going back is still named by
    its line."""
    import pandas as pd

    rng = np.random.default_rng(3)
    n = 400
    df = pd.DataFrame({"time_s": 100.0 + 0.01 * np.arange(n), "lat_deg": 45.0 + 1e-6 * rng.standard_normal(n),
                       "lon_deg": 7.0 + 1e-6 * rng.standard_normal(n), "height_m": 300.0 + rng.standard_normal(n),
                       "vn_m_s": rng.standard_normal(n), "ve_m_s": rng.standard_normal(n),
                       "vd_m_s": 0.1 * rng.standard_normal(n), "roll_deg": rng.standard_normal(n),
                       "pitch_deg": rng.standard_normal(n), "yaw_deg": 180.0 * rng.uniform(-1, 1, n),
                       "sigma_n_m": rng.uniform(0.1, 1.0, n)})
    p = tmp_path / "sol.csv"
    df.to_csv(p, index=False, float_format="%.17g")
    calls = []
    lean = C._read_solution_lean
    monkeypatch.setattr(C, "_read_solution_lean", lambda path, ranges=True: calls.append(path) or lean(path, ranges))
    fast = C.read_solution(p)
    assert calls and fast is not None and list(fast.extra) == ["sigma_n_m"]
    monkeypatch.setattr(C, "_read_solution_lean", lambda path, ranges=True: None)
    slow = C.read_solution(p)
    assert np.array_equal(fast.time, slow.time) and np.allclose(fast.lla, slow.lla, rtol=1e-15, atol=0)
    assert np.allclose(fast.q_nb, slow.q_nb, rtol=0, atol=1e-15)
    # %.17g text read back correctly rounded: the very doubles written (pandas' default parser may miss by an ulp)
    assert np.array_equal(fast.extra["sigma_n_m"], df["sigma_n_m"].to_numpy())
    assert np.allclose(slow.extra["sigma_n_m"], df["sigma_n_m"].to_numpy(), rtol=1e-15, atol=0)
    monkeypatch.setattr(C, "_read_solution_lean", lean)
    df.loc[57, "time_s"] = df.loc[55, "time_s"]
    df.to_csv(p, index=False, float_format="%.17g")
    with pytest.raises(InputError, match=r"line 59: time_s=.* goes back in time"):
        C.read_solution(p)


def test_a_gzip_csv_is_read_by_the_lean_path_and_a_large_one_left_to_pandas(tmp_path, monkeypatch):
    import gzip

    t, dth, dv = _increments(2000)
    p = tmp_path / "imu.csv"
    _write(p, t, dth, dv)
    gz = tmp_path / "imu.csv.gz"
    gz.write_bytes(gzip.compress(p.read_bytes()))
    names = C._header_names(gz)
    assert names[0] == "time_s"
    got = C.lean_columns(gz, [names[:1], names[1:4], names[4:]])
    assert got is not None and np.array_equal(got[1], dth) and np.array_equal(got[0][:, 0], t)
    monkeypatch.setattr(C, "WHOLE_CSV_BYTES", 8 * (gz.stat().st_size - 1))  # "large": its length is not known ahead
    assert C.lean_columns(gz, [names[:1]]) is None
    imu = C.read_imu(gz)  # the pandas path reads it all the same, to its parser's precision (not correctly rounded:
    assert np.allclose(imu.dtheta_b, dth, rtol=1e-11, atol=0)  # 1e-12 relative seen on 17-digit texts)


def test_a_truncated_gzip_log_is_refused_with_its_name(tmp_path):
    import gzip

    t, dth, dv = _increments(3000)
    p = tmp_path / "imu.csv"
    _write(p, t, dth, dv)
    data = gzip.compress(p.read_bytes())
    gz = tmp_path / "cut.csv.gz"
    gz.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match=r"cut\.csv\.gz: a damaged gzip file: its data ends before the compressed "
                                         r"stream does \(cut short"):
        C.read_imu(gz)


@pytest.mark.parametrize("kind", ["csv", "csv.gz", "parquet"])
def test_read_solution_until_reads_the_head_only(tmp_path, kind):
    """``read_solution(until_s=...)``: the first rows, up to the first after that time, as the whole read has
    them (CSV, gzip CSV, Parquet); a time before the file, past its end, or a fault in the head gives the
    whole read (its span, its line); a fault beyond the head is not read."""
    import gzip

    from inskit.types import NavSolution
    from inskit.rotations import quat_from_euler

    n = 200_000  # several of the head reader's blocks
    t = 50.0 + 0.01 * np.arange(n)
    rng = np.random.default_rng(1)
    lla = np.column_stack([np.radians(45.0) + 1e-8 * np.arange(n), np.full(n, np.radians(7.0)), 300.0 + 0 * t])
    v = rng.standard_normal((n, 3))
    q = quat_from_euler(np.column_stack([0 * t, 0 * t, np.radians(1e-3 * np.arange(n) % 180.0)]))
    sol = NavSolution(t, lla, v, q, {"sigma_n_m": rng.uniform(0.1, 1.0, n)})
    p = tmp_path / f"sol.{kind}"
    if kind == "csv.gz":
        plain = tmp_path / "plain.csv"
        C.write_solution(plain, sol)
        p.write_bytes(gzip.compress(plain.read_bytes()))
    else:
        C.write_solution(p, sol)
    full = C.read_solution(p)
    for u in (50.0, 50.004, 1234.567):
        head = C.read_solution(p, until_s=u)
        k = len(head.time)
        assert 2 <= k < n and head.time[-2] <= u < head.time[-1]
        assert np.array_equal(head.time, full.time[:k]) and np.array_equal(head.lla, full.lla[:k])
        assert np.array_equal(head.q_nb, full.q_nb[:k]) and np.array_equal(head.extra["sigma_n_m"],
                                                                            full.extra["sigma_n_m"][:k])
        a, b = full.interpolate(np.array([u])).state(0), head.interpolate(np.array([u])).state(0)
        assert np.array_equal(a.lla, b.lla) and np.array_equal(a.v_n, b.v_n) and np.array_equal(a.q_nb, b.q_nb)
    assert len(C.read_solution(p, until_s=1e9).time) == n
    assert len(C.read_solution(p, until_s=10.0).time) == n  # before the file: the whole read
    if kind == "csv":
        lines = p.read_text().splitlines()
        lines[150_001] = lines[150_000]  # time repeats far beyond the head
        p.write_text("\n".join(lines) + "\n")
        assert len(C.read_solution(p, until_s=60.0).time) < 10_000
        lines[5] = lines[4]  # ... and in it: named by its line, as by the whole read
        p.write_text("\n".join(lines) + "\n")
        with pytest.raises(InputError, match=r"line 6: duplicate timestamp"):
            C.read_solution(p, until_s=60.0)


def test_a_utf8_bom_before_the_header_is_no_part_of_the_first_name(tmp_path):
    """Windows editors save CSV with a byte-order mark: the lean path's header must not keep it in 'time_s'
    (the GNSS reader then refused the file, 'missing column(s) time_s; found \\ufefftime_s')."""
    gnss = ("time_s,lat_deg,lon_deg,height_m,sigma_n_m,sigma_e_m,sigma_d_m\n"
            "0,45,7,300,0.5,0.5,1\n1,45.00001,7,300,0.5,0.5,1\n")
    plain, bom = tmp_path / "plain.csv", tmp_path / "bom.csv"
    plain.write_text(gnss)
    bom.write_bytes(b"\xef\xbb\xbf" + gnss.replace("\n", "\r\n").encode())
    assert C._header_names(bom)[0] == "time_s"
    a, b = C.read_gnss(plain), C.read_gnss(bom)
    assert np.array_equal(a.time, b.time) and np.array_equal(a.lla, b.lla)
    t, dth, dv = _increments(200)
    p = tmp_path / "imu.csv"
    _write(p, t, dth, dv)
    q = tmp_path / "imu_bom.csv"
    q.write_bytes(b"\xef\xbb\xbf" + p.read_bytes())
    assert np.array_equal(C.read_imu(q).dtheta_b, C.read_imu(p).dtheta_b)


@pytest.mark.parametrize("lean", [True, False])
def test_a_column_named_twice_is_refused_not_guessed(tmp_path, lean):
    """gnss.csv with a second lat_deg (all zeros) was read silently with the first one (the lean path; pandas
    would have renamed the second 'lat_deg.1'): which one the user meant cannot be told."""
    head = "time_s,lat_deg,lon_deg,height_m,sigma_n_m,sigma_e_m,sigma_d_m,lat_deg\n"
    rows = "0,45,7,300,0.5,0.5,1,0\n1,45.00001,7,300,0.5,0.5,1,0\n" if lean else "0,45,7,300,0.5,0.5,1,0\n1,,7,300,0.5,0.5,1,0\n"
    p = tmp_path / "gnss.csv"
    p.write_text(head + rows)
    with pytest.raises(InputError, match=r"gnss\.csv: the header names column 'lat_deg' twice \(columns 2 and 8\)"):
        C.read_gnss(p)


def test_a_semicolon_file_with_decimal_commas_gets_the_separator_hint(tmp_path):
    """European spreadsheets: ';' between fields and ',' in the numbers; the parser's 'Expected 1 fields in
    line 3, saw 8' came first and hid the hint."""
    p = tmp_path / "imu.csv"
    p.write_text("time_s;dtheta_x_rad;dtheta_y_rad;dtheta_z_rad;dv_x_m_s;dv_y_m_s;dv_z_m_s\n"
                 "0;0;0;0;0;0;0\n0,01;0;0;0;0;0;-0,098\n0,02;0;0;0;0;0;-0,098\n")
    with pytest.raises(InputError, match=r"imu\.csv: the header .* is one column: the file seems separated by ';'"):
        C.read_imu(p)


def test_an_increment_file_with_time_in_milliseconds_is_not_told_to_rename_to_g(tmp_path):
    """Increments under time_s in ms make a specific force 1000 times too small; the message said 'rename
    the columns accel_*_g', which an increment file has no such column for."""
    t, dth, dv = _increments(500)
    p = tmp_path / "imu.csv"
    _write(p, 1000.0 * t, dth, dv)
    with pytest.raises(InputError, match=r"column 'dv_x_m_s': the median specific force \(dv over the time step\) "
                                         r"is .* far below gravity: is time_s in milliseconds"):
        C.read_imu(p)
    dth[1:] = 57.3 * np.abs(dth[1:]) + 0.2  # degrees under a rad header, turning
    _write(p, t, dth, dv)
    with pytest.raises(InputError, match=r"looks like values in deg/s; rename the columns dtheta_\*_deg"):
        C.read_imu(p)


def _write_rates(path, t, n=3000, seed=5):
    """A static rate log (gyro rad/s, accel m/s^2) at the times ``t``."""
    rng = np.random.default_rng(seed)
    w = rng.normal(0, 1e-3, (len(t), 3))
    f = rng.normal(0, 1e-2, (len(t), 3)) + [0.0, 0.0, -9.8]
    head = "time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n"
    path.write_text(head + "\n".join(",".join(repr(float(x)) for x in r) for r in np.column_stack([t, w, f])) + "\n")
    return path


@pytest.mark.parametrize("scale, step", [(1e3, "10 s"), (1e6, "1e\\+04 s"), (1e9, "1e\\+07 s")])
def test_a_rate_log_with_time_in_ms_us_or_ns_is_refused(tmp_path, scale, step):
    """Rates and specific forces do not depend on the time unit, so a 100 Hz rate log with time_s in
    milliseconds passed every check: allan reported an ARW sqrt(1000) times too large over a '300000 s'
    log, align a static interval of days, mechanize failed at a 'pole'.  Its steps give it away."""
    t = 0.01 * np.arange(3000)
    p = _write_rates(tmp_path / "imu.csv", scale * t)
    with pytest.raises(InputError, match=rf"imu\.csv: column 'time_s': the median time step is {step} .* is time_s "
                                         r"in milliseconds, microseconds or nanoseconds\? it must be seconds"):
        C.read_imu(p)
    assert len(C.read_imu(p, check_units=False)) == 3000  # a log truly sampled below 1 Hz: on request
    assert len(C.read_imu(_write_rates(tmp_path / "ok.csv", t))) == 3000
    assert len(C.read_imu(_write_rates(tmp_path / "one_hz.csv", np.arange(30.0)))) == 30  # 1 Hz still passes


@pytest.mark.parametrize("kind", ["increments", "increments.parquet", "rates"])
def test_a_one_row_imu_log_is_refused_in_every_reader_path(tmp_path, kind):
    """A one-row increment file (`head -2 imu.csv`) was mechanized into a zero-length 'solution' (1 epoch
    over 0 s), and align said '--start 0 s is not before the log's end' of a --start never given; the rate
    path alone refused it.  Every path (the lean and pandas increment readers, Parquet, rates) says so."""
    if kind == "rates":
        p = _write_rates(tmp_path / "imu.csv", np.array([5.0]))
    else:
        t, dth, dv = _increments(1)
        p = tmp_path / "imu.csv"
        _write(p, t, dth, dv)
        if kind.endswith(".parquet"):
            from inskit.io.parquet import write_parquet

            q = tmp_path / "imu.parquet"
            write_parquet(q, {"time_s": t, **{f"dtheta_{a}_rad": dth[:, j] for j, a in enumerate("xyz")},
                              **{f"dv_{a}_m_s": dv[:, j] for j, a in enumerate("xyz")}})
            p = q
    with pytest.raises(InputError, match=r"imu\.(csv|parquet): holds 1 data row\(s\); an IMU log needs at least two"):
        io.read_imu(p)


def test_a_null_or_infinite_parquet_solution_cell_is_named_without_numpy_repr(tmp_path):
    """A null latitude in a Parquet truth said "holds np.float64(nan)": numpy's repr, and no word that the
    cell was empty."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from inskit.io.parquet import solution_columns
    from inskit.types import NavSolution

    n = 20
    t = np.arange(n) * 0.1
    sol = NavSolution.from_euler(t, np.tile([0.7, -1.8, 100.0], (n, 1)), np.zeros((n, 3)), np.zeros((n, 3)))
    cols = solution_columns(sol)
    lat = list(cols["lat_deg"])
    lat[7] = None
    yaw = cols["yaw_deg"].copy()
    yaw[9] = np.inf
    for name, key, values in (("null.parquet", "lat_deg", pa.array(lat, pa.float64())),
                              ("inf.parquet", "yaw_deg", pa.array(yaw))):
        pq.write_table(pa.table({k: (values if k == key else pa.array(v)) for k, v in cols.items()}), tmp_path / name)
    with pytest.raises(InputError, match=r"null\.parquet: row 7: column 'lat_deg' is empty \(null\) or NaN; "
                                         r"expected a finite number$"):
        io.read_solution(tmp_path / "null.parquet")
    with pytest.raises(InputError, match=r"inf\.parquet: row 9: column 'yaw_deg' holds inf; expected a finite number$"):
        io.read_solution(tmp_path / "inf.parquet")


def test_a_trailing_comma_on_every_line_of_a_solution_is_no_column(tmp_path):
    """A spreadsheet export ends each line with a comma: the IMU reader took it, read_solution said "line 2:
    column 'Unnamed: 10' is empty", a name the file does not hold.  A column of no name and no value is
    dropped; one of no name that holds values is still read and judged."""
    from inskit.types import NavSolution

    n = 20
    sol = NavSolution.from_euler(0.1 * np.arange(n), np.tile([0.7, -1.8, 100.0], (n, 1)), np.zeros((n, 3)),
                                 np.zeros((n, 3)))
    io.write_solution(tmp_path / "sol.csv", sol)
    lines = (tmp_path / "sol.csv").read_text().splitlines()
    (tmp_path / "comma.csv").write_text("\n".join(line + "," for line in lines) + "\n")
    back = io.read_solution(tmp_path / "comma.csv")
    assert np.allclose(back.time, sol.time, rtol=0, atol=1e-12) and not back.extra
    (tmp_path / "text.csv").write_text("\n".join([lines[0] + ","] + [line + ",x" for line in lines[1:]]) + "\n")
    with pytest.raises(InputError, match=r"text\.csv: line 2: column 'Unnamed: 10' has 'x'"):
        io.read_solution(tmp_path / "text.csv")


def _with_blank_lines(rows, at=(4,)):
    """``rows`` (the header first) as file text with a blank line inserted
    before each line number in ``at`` (1-based, as the file then shows it);
    a whitespace-only line for every second one."""
    out = list(rows)
    for k, n in enumerate(sorted(at)):
        out.insert(n - 1, "" if k % 2 == 0 else "  \t")
    return "\n".join(out) + "\n"


@pytest.mark.parametrize("path_kind", ["increments", "rates", "gnss", "solution", "speed", "height", "gz"])
def test_a_blank_line_does_not_shift_the_line_numbers_of_later_messages(tmp_path, path_kind):
    """pandas and pyarrow skip a blank line, so a bad value after one was
    said to be on the line above it: the message names the line an editor
    shows (blank lines at lines 4 and 7, the bad value on line 11)."""
    import gzip

    t = [round(0.01 * i, 2) for i in range(20)]
    if path_kind in ("increments", "gz"):
        head = "time_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_m_s,dv_y_m_s,dv_z_m_s"
        rows = [f"{x!r},0,0,0,0,0,0" if i == 0 else f"{x!r},1e-5,2e-5,3e-5,1e-3,2e-3,-0.098" for i, x in enumerate(t)]
        read, bad = C.read_imu, ("time_s", "0.05")  # goes back in time
    elif path_kind == "rates":
        head = "time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2"
        rows = [f"{x!r},0.001,0.002,0.003,0.1,0.2,-9.8" for x in t]
        read, bad = C.read_imu, ("gyro_y_rad_s", "nan")
    elif path_kind == "gnss":
        head = ",".join(C.GNSS_COLUMNS)
        rows = [f"{x!r},45,7,300,1,1,2" for x in t]
        read, bad = C.read_gnss, ("lat_deg", "91")
    elif path_kind == "solution":
        head = ",".join(C.SOLUTION_COLUMNS)
        rows = [f"{x!r},45,7,300,0,0,0,0,0,0" for x in t]
        read, bad = C.read_solution, ("lon_deg", "inf")
    elif path_kind == "speed":
        head = "time_s,speed_m_s"
        rows = [f"{x!r},10" for x in t]
        read, bad = C.read_speed, ("speed_m_s", "200")
    else:
        head = "time_s,height_m,sigma_m"
        rows = [f"{x!r},300,1" for x in t]
        read, bad = C.read_height, ("sigma_m", "0")
    names = head.split(",")
    j = names.index(bad[0])
    r = 11 - 2 - 2  # data row shown on line 11 after two blank lines (header = line 1)
    cells = rows[r].split(",")
    cells[j] = bad[1]
    rows[r] = ",".join(cells)
    text = _with_blank_lines([head] + rows, at=(4, 7))
    assert text.splitlines()[10] == rows[r]  # line 11 as an editor shows it
    p = tmp_path / ("f.csv.gz" if path_kind == "gz" else "f.csv")
    p.write_bytes(gzip.compress(text.encode()) if path_kind == "gz" else text.encode())
    with pytest.raises(InputError, match=r"f\.csv(\.gz)?: line 11: ") as e:
        read(p)
    if bad[0] == "time_s":
        assert "from line 10 " in str(e.value)  # the row before it, also past the blank lines


def test_data_line_counts_blank_lines_before_the_header_and_quoted_cells_over_two_lines(tmp_path):
    p = tmp_path / "f.csv"
    p.write_text('\n\na,b\r\n1,2\r\n\r\n3,"x\ny"\n4,5\n')
    assert [C.data_line(p, i) for i in range(3)] == [4, 6, 8]
    assert C.data_line(tmp_path / "absent.csv", 5) == 7  # unreadable: the plain count


@pytest.mark.parametrize("column, value, match", [
    ("height_m", 1e300, r"height_m=1e\+300 is beyond \+-100 km of the ellipsoid"),
    ("height_m", -150_000.0, r"height_m=-150000\.0 is beyond \+-100 km"),
    ("roll_deg", 1e6, r"roll_deg=1000000\.0 is beyond \+-360 degrees"),
    ("yaw_deg", -720.0, r"yaw_deg=-720\.0 is beyond \+-360 degrees"),
    ("ve_m_s", 1e300, r"ve_m_s=1e\+300 is beyond \+-12000 m/s \(faster than the Earth's escape speed\)"),
    ("vd_m_s", -25_000.0, r"vd_m_s=-25000\.0 is beyond \+-12000 m/s"),
])
@pytest.mark.parametrize("kind", ["lean", "pandas", "parquet", "head"])
def test_a_solution_height_speed_or_angle_beyond_reason_is_refused(tmp_path, monkeypatch, column, value, match, kind):
    """A solution or truth file whose height_m held 1e300 was read, and `inskit evaluate` printed a horizontal
    RMS of inf; a roll_deg of 1e6 was wrapped into an 80 deg error; both without a word.  A height beyond
    +-100 km (the bound of every height a user gives) or an angle beyond a full turn is refused naming the
    line (or row) and the column, on every way a solution file is read."""
    import pandas as pd

    n = 50
    df = pd.DataFrame({"time_s": 0.1 * np.arange(n), "lat_deg": 45.0, "lon_deg": 7.0, "height_m": 300.0,
                       "vn_m_s": 1.0, "ve_m_s": 0.0, "vd_m_s": 0.0, "roll_deg": 1.0, "pitch_deg": -2.0,
                       "yaw_deg": 170.0})
    df.loc[7, column] = value
    if kind == "pandas":
        df["note"] = "x"  # a text column: not the lean path
        monkeypatch.setattr(C, "_read_solution_lean", lambda path, ranges=True: None)
    p = tmp_path / ("sol.parquet" if kind == "parquet" else "sol.csv")
    df.to_parquet(p) if kind == "parquet" else df.to_csv(p, index=False)
    where = "row 7" if kind == "parquet" else "line 9"
    with pytest.raises(InputError, match=rf"sol\.(csv|parquet): {where}: {match}"):
        if kind == "pandas":
            C.read_solution(p)  # the text column is refused after the solution columns are checked
        elif kind == "head":
            C.read_solution(p, until_s=2.0)
        else:
            C.read_solution(p)
    df.loc[7, column] = {"_deg": 359.0, "_m_s": -11_000.0}.get(column[-4:], -99_000.0)  # within the bounds: read
    if kind == "pandas":
        df = df.drop(columns=["note"])
    p.unlink()
    df.to_parquet(p) if kind == "parquet" else df.to_csv(p, index=False)
    assert len(C.read_solution(p).time) == n


def test_read_solution_ranges_false_reads_a_diverged_solution_but_not_a_malformed_one(tmp_path):
    """``ranges=False`` (the report of inskit's own run) skips only the
    height, velocity and attitude limits, in every reader (CSV, Parquet,
    the head of a file)."""
    import numpy as np
    import pytest

    from inskit import io
    from inskit.errors import InputError
    from inskit.types import NavSolution

    n = 5
    lla = np.column_stack([np.full(n, 0.7), np.full(n, 0.2), np.linspace(0.0, 3.0e5, n)])
    sol = NavSolution(np.arange(n, dtype=float), lla, np.zeros((n, 3)), np.tile([1.0, 0, 0, 0], (n, 1)))
    for name in ("s.csv", "s.parquet"):
        p = tmp_path / name
        io.write_solution(p, sol)
        with pytest.raises(InputError, match="beyond"):
            io.read_solution(p)
        assert io.read_solution(p, ranges=False).lla[-1, 2] == pytest.approx(3.0e5)
        assert io.read_solution(p, until_s=1.5, ranges=False).lla[-1, 2] == pytest.approx(1.5e5)
    bad = tmp_path / "bad.csv"
    bad.write_text((tmp_path / "s.csv").read_text().replace("\n1,", "\n0,", 1))
    with pytest.raises(InputError, match="duplicate timestamp"):  # the form is still checked
        io.read_solution(bad, ranges=False)


_GNSS = ("time_s,lat_deg,lon_deg,height_m,sigma_n_m,sigma_e_m,sigma_d_m\n"
         "0,45,7,300,0.5,0.5,1\n1,45.00001,7,300,0.5,0.5,1\n2,45.00002,7,300,0.5,0.5,1\n")


@pytest.mark.parametrize("encoding, needle", [
    ("utf-16", "is UTF-16 text (it starts with the byte-order mark FF FE)"),  # PowerShell 5 '>', Excel 'Unicode Text'
    ("utf-16-be", "is UTF-16 text without a byte-order mark"),
    ("utf-16-le", "is UTF-16 text without a byte-order mark"),
    ("utf-32", "is UTF-32 text (it starts with the byte-order mark FF FE 00 00)"),
])
@pytest.mark.parametrize("kind", ["imu", "gnss", "solution", "gzip"])
def test_a_file_saved_as_utf16_or_utf32_is_named_as_such(tmp_path, encoding, needle, kind):
    """A CSV saved as UTF-16 was 'not a readable CSV file ('utf-8' codec can't decode byte 0xff in position 0:
    invalid start byte)' with a byte-order mark, and 'missing column(s) time_s ...; found t, Unnamed: 1, ...'
    without one."""
    import gzip

    t, dth, dv = _increments(50)
    p = tmp_path / "f.csv"
    if kind in ("imu", "gzip"):
        _write(p, t, dth, dv)
    elif kind == "gnss":
        p.write_text(_GNSS)
    else:
        sol = C.NavSolution(t, np.tile([0.7, 0.1, 100.0], (50, 1)), np.zeros((50, 3)), np.tile([1.0, 0, 0, 0], (50, 1)))
        C.write_solution(p, sol)
    text = p.read_text().replace("\n", "\r\n").encode(encoding)
    p.write_bytes(gzip.compress(text) if kind == "gzip" else text)
    read = {"imu": C.read_imu, "gzip": C.read_imu, "gnss": io.read_gnss, "solution": C.read_solution}[kind]
    with pytest.raises(InputError, match=re.escape(f"f.csv: {needle}") + ".*save it as UTF-8"):
        read(p)


@pytest.mark.parametrize("kind", ["rates", "increments", "increments.gz", "gnss"])
def test_nul_bytes_in_a_cell_are_refused_naming_the_line_not_read_as_a_shorter_number(tmp_path, kind):
    """A block of zero bytes in a log (a logger that lost power) inside a number: pandas' parser ended the
    number at the first NUL and dropped the rest of the cell, so '1.2547<NUL x 50>6971e-3' was read as
    1.2547 (an angle increment a thousand times too large) and the run went on without a word."""
    import gzip

    if kind == "gnss":
        text = _GNSS.replace("45.00001", "45.0\0\0\0\0\0\0\0\00001")
        line = 3
    else:
        t, dth, dv = _increments(400)
        p = tmp_path / "clean.csv"
        _write(p, t, dth, dv)
        text = p.read_text()
        if kind == "rates":
            text = text.replace("dtheta_", "gyro_").replace("_rad,", "_rad_s,").replace("dv_", "accel_")
            text = text.replace("_m_s,", "_m_s2,").replace("dv_z_m_s\n", "accel_z_m_s2\n").replace("_m_s\n", "_m_s2\n")
            rows = text.splitlines(True)
            text = rows[0] + "".join(r for r in rows[2:])  # rates: a first row like the others
        rows = text.splitlines(True)
        cells = rows[300].split(",")
        cells[3] = cells[3][:5] + "\0" * 50 + cells[3][5:]
        rows[300] = ",".join(cells)
        text = "".join(rows)
        line = 301
    p = tmp_path / "f.csv"
    data = text.encode()
    p.write_bytes(gzip.compress(data) if kind.endswith(".gz") else data)
    read = io.read_gnss if kind == "gnss" else (lambda q: C.read_imu(q, check_units=False))
    with pytest.raises(InputError, match=rf"f\.csv: line {line} holds NUL \(zero\) bytes, which no text holds: not "
                                         r"a text file, or one damaged in writing"):
        read(p)


def test_a_corrupt_gzip_file_is_refused_not_an_internal_error(tmp_path):
    """A gzip file whose compressed data is damaged raised zlib's 'Error -3 while decompressing data: invalid
    code lengths set', which the command line showed as an internal error (exit 3, 'this is a bug')."""
    import gzip

    t, dth, dv = _increments(3000)
    p = tmp_path / "imu.csv"
    _write(p, t, dth, dv)
    data = gzip.compress(p.read_bytes())
    p.write_bytes(data[:20] + bytes(b ^ 0xA5 for b in data[20:2000]) + data[2000:])
    for read in (C.read_imu, io.read_imu, io.read_gnss, C.read_solution, C.read_height):
        with pytest.raises(InputError, match=r"imu\.csv: a damaged gzip file: its data is corrupt \(.*\): a "
                                             r"corrupted copy or download\?"):
            read(p)


def test_a_byte_that_is_not_utf8_is_named_by_its_line(tmp_path):
    """A Latin-1 degree sign in a cell: 'not a readable CSV file ('utf-8' codec can't decode byte 0xb0 in
    position 13: invalid start byte)', a position in a block of pandas' reader, not in the file."""
    p = tmp_path / "gnss.csv"
    p.write_bytes(_GNSS.replace("45.00002", "45.00002\xb0").encode("latin-1"))
    with pytest.raises(InputError, match=r"gnss\.csv: line 4: byte 0xb0 is not UTF-8 \(a binary file, or text saved "
                                         r"in another encoding such as Latin-1 or Windows-1252\)"):
        io.read_gnss(p)


def test_a_row_with_a_field_too_many_names_its_line_and_the_counts(tmp_path):
    """It was pandas' 'not a readable CSV file (Error tokenizing data. C error: Expected 7 fields in line 5,
    saw 8)'."""
    p = tmp_path / "gnss.csv"
    p.write_text("time_s,lat_deg,lon_deg,height_m,sigma_n_m,sigma_e_m,sigma_d_m\n"
                 "0,45,7,300,0.5,0.5,1\n1,45.00001,7,300,0.5,0.5,1\n\n"  # a blank line counts as a line
                 "2,45.00002,7,300,0,5,0.5,1\n")  # a decimal comma
    with pytest.raises(InputError, match=r"gnss\.csv: line 5: has 8 fields, the header names 7: a comma too many"):
        io.read_gnss(p)


@pytest.mark.parametrize("gz", [False, True])
def test_a_last_line_cut_short_is_named_as_such(tmp_path, gz):
    """A log copied while still being written ends mid-line: it was 'line 12: column 'dv_x_m_s' is empty'
    or 'has '3.15697030281273e-'', which read as a fault of the data rather than of the copy.  A bad last
    line that ends in a line end gets no such note."""
    import gzip

    t, dth, dv = _increments(10)
    p = tmp_path / "imu.csv"
    _write(p, t, dth, dv)
    text = p.read_text()
    for cut, note in ((text[:text.rindex(",", 0, len(text) - 40)], True),          # mid-row, no line end
                      (text[:text.rindex("e", 0, len(text) - 2) + 1], True),      # inside a number: '3.1e'
                      (text[:text.rindex(",", 0, len(text) - 40)] + "\n", False)):  # a short row, complete
        p.write_bytes(gzip.compress(cut.encode()) if gz else cut.encode())
        with pytest.raises(InputError, match=r"imu\.csv: line 11: (has \d fields, the header names 7: column '\w+' "
                                             r"is missing|column '\w+' has '[-0-9.e]+'); expected a finite number") as exc:
            C.read_imu(p)
        assert str(exc.value).endswith("; it is the last line and has no line end: the file seems cut short (still "
                                       "being written, or copied incompletely?)") == note, str(exc.value)


@pytest.mark.parametrize("above, needle", [
    ("# ", r"line 1 \('# \w+,.*'\) starts with '#', a comment mark, where the header must be: .*numpy\.savetxt"),
    ("# exported by the logger\n", r"line 1 \('# exported by the logger'\) starts with '#', a comment mark"),
    ("sep=,\n", r"line 1 is 'sep=,', a spreadsheet's separator hint, not the header: delete that line"),
])
@pytest.mark.parametrize("kind", ["imu", "gnss", "solution", "rtklibexplorer"])
def test_a_first_line_that_is_not_the_header_says_what_it_is(tmp_path, above, needle, kind):
    """numpy.savetxt's '# ' before the header, a comment above it, Excel's 'sep=,' line: the readers said
    'missing column(s) time_s ...; found # time_s, dtheta_x_rad, ...' or '... found sep=, Unnamed: 1'."""
    p = tmp_path / "f.csv"
    if kind == "imu":
        t, dth, dv = _increments(50)
        _write(p, t, dth, dv)
    elif kind == "gnss":
        p.write_text(_GNSS)
    elif kind == "rtklibexplorer":
        p.write_text("gps_week,gps_sow_s,acc_x_g,acc_y_g,acc_z_g,gyro_x_dps,gyro_y_dps,gyro_z_dps,counter_ms\n"
                     + "".join(f"2374,{243261.99 + 0.01 * i:.2f},0.1,0.0,1.0,0.1,0.2,0.3,{i}\n" for i in range(50)))
    else:
        n = 50
        C.write_solution(p, C.NavSolution(12.0 + np.arange(n), np.tile([0.7, 0.1, 100.0], (n, 1)), np.zeros((n, 3)),
                                          np.tile([1.0, 0, 0, 0], (n, 1))))
    p.write_text(above + p.read_text())
    read = {"imu": io.read_imu, "rtklibexplorer": io.read_imu, "gnss": io.read_gnss, "solution": C.read_solution}
    with pytest.raises(InputError, match=r"f\.csv: " + needle):
        read[kind](p)


def test_a_row_with_fields_missing_says_so_not_that_a_cell_is_empty(tmp_path):
    """pandas fills the fields a short row lacks with NaN: it was 'line 4: column 'sigma_d_m' is empty',
    whose cell was not empty but absent."""
    p = tmp_path / "gnss.csv"
    p.write_text(_GNSS.replace("2,45.00002,7,300,0.5,0.5,1", "2,45.00002,7,300,0.5"))
    with pytest.raises(InputError, match=r"gnss\.csv: line 4: has 5 fields, the header names 7: column 'sigma_e_m' is "
                                         r"missing; expected a finite number$"):
        io.read_gnss(p)
    p.write_text(_GNSS.replace("2,45.00002,7,300,0.5,0.5,1", "2,45.00002,7,300,0.5,,1"))
    with pytest.raises(InputError, match=r"gnss\.csv: line 4: column 'sigma_e_m' is empty; expected a finite number$"):
        io.read_gnss(p)


@pytest.mark.parametrize("kind", ["gnss", "imu"])
def test_a_header_with_a_name_missing_is_refused_not_read_shifted(tmp_path, kind):
    """Rows with one field more than the header names: pandas made the first field an index and moved every
    name one column on, so time_s held the latitudes ('line 3: time_s=44.9999998 goes back in time', or,
    for a drive northwards, no message at all)."""
    p = tmp_path / "f.csv"
    if kind == "gnss":
        rows = [f"{i},{45.0 + 1e-5 * i!r},7,300,0.5,0.5,1,0.1" for i in range(5)]  # lat rises: a valid time
        p.write_text("time_s,lat_deg,lon_deg,height_m,sigma_n_m,sigma_e_m,sigma_d_m\n" + "\n".join(rows) + "\n")
        read = io.read_gnss
    else:
        t, dth, dv = _increments(50)
        _write(p, t, dth, dv)
        lines = p.read_text().splitlines(True)
        p.write_text(lines[0].replace(",dv_z_m_s", "") + "".join(lines[1:]))
        read = C.read_imu
    with pytest.raises(InputError, match=r"f\.csv: line 2: has (8|7) fields, the header names (7|6): a name missing "
                                         r"from the header \(or a comma too many on every row\?\)"):
        read(p)


def test_seconds_of_week_restarting_at_a_week_boundary_are_named(tmp_path):
    """A logger writing GPS seconds of week as time_s across Saturday midnight: it was only 'goes back in
    time', which a user reads as a logger fault."""
    p = tmp_path / "gnss.csv"
    rows = [f"{t!r},45,7,300,0.5,0.5,1" for t in (604798.0, 604799.0, 0.0, 1.0)]
    p.write_text(_GNSS.splitlines(True)[0] + "\n".join(rows) + "\n")
    with pytest.raises(InputError, match=r"gnss\.csv: line 4: time_s=0\.0 goes back in time from line 3 \(604799\.0\); "
                                         r"timestamps must strictly increase; GPS seconds of week that restart at a "
                                         r"week boundary\? continue them past 604800 s$"):
        io.read_gnss(p)
    p.write_text(_GNSS.splitlines(True)[0] + "\n".join(rows[:2] + ["604797.0,45,7,300,0.5,0.5,1"]) + "\n")
    with pytest.raises(InputError, match=r"goes back in time from line 3 \(604799\.0\); timestamps must strictly "
                                         r"increase$"):
        io.read_gnss(p)


def _gnss_frame(n=40):
    import pandas as pd

    return pd.DataFrame({"time_s": 0.2 * np.arange(n), "lat_deg": 45.0 + 1e-6 * np.arange(n), "lon_deg": 7.0,
                         "height_m": 300.0, "sigma_n_m": 0.5, "sigma_e_m": 0.5, "sigma_d_m": 1.0, "vn_m_s": 1.0,
                         "ve_m_s": 0.0, "vd_m_s": 0.0, "sigma_vn_m_s": 0.1, "sigma_ve_m_s": 0.1,
                         "sigma_vd_m_s": 0.1})


@pytest.mark.parametrize("column, value, match", [
    ("height_m", 1e300, r"height_m=1e\+300 is beyond \+-100 km of the ellipsoid \(a height in metres\)"),
    ("height_m", "mm", r"height_m=300000\.0 is beyond \+-100 km of the ellipsoid"),
    ("vn_m_s", 1e300, r"vn_m_s=1e\+300 is beyond \+-12000 m/s \(faster than the Earth's escape speed\)"),
    ("vd_m_s", -25_000.0, r"vd_m_s=-25000\.0 is beyond \+-12000 m/s"),
])
@pytest.mark.parametrize("kind", ["lean", "pandas", "parquet"])
def test_a_gnss_height_or_speed_beyond_reason_is_refused(tmp_path, column, value, match, kind):
    """read_gnss took a fix whose height_m and vn_m_s held 1e300, and heights in millimetres, without a word
    (read_solution refuses them): the same limits, +-100 km and +-12 km/s, naming the file, the line (CSV) or
    row (Parquet) and the column, on every way a GNSS file is read."""
    df = _gnss_frame()
    if value == "mm":
        df["height_m"] *= 1000.0  # every height: the first row is named
        row = 0
    else:
        df.loc[7, column] = value
        row = 7
    if kind == "pandas":
        df["note"] = "x"  # a text column: not the lean path
    p = tmp_path / ("gnss.parquet" if kind == "parquet" else "gnss.csv")
    df.to_parquet(p) if kind == "parquet" else df.to_csv(p, index=False)
    where = f"row {row}" if kind == "parquet" else f"line {row + 2}"
    with pytest.raises(InputError, match=rf"gnss\.(csv|parquet): {where}: {match}.*; another unit or column\?"):
        io.read_gnss(p)
    ok = _gnss_frame()
    ok.loc[7, column] = {"height_m": -99_000.0}.get(column, -11_000.0)  # within the bounds: read
    p.unlink()
    ok.to_parquet(p) if kind == "parquet" else ok.to_csv(p, index=False)
    g = io.read_gnss(p)
    assert g.lla[7, 2] == ok.loc[7, "height_m"] and np.array_equal(g.v_n[:, 0], ok["vn_m_s"])


def _imu_table(n=400):
    """A turning rate log and the same motion as increments, as columns of one table."""
    t = 0.01 * np.arange(n)
    w = np.column_stack([0.1 * np.sin(t), 0.05 * np.cos(t), 0.2 + 0.0 * t])
    f = np.column_stack([0.1 + 0.0 * t, 0.0 * t, -9.8 + 0.0 * t])
    cols = {"time_s": t}
    cols.update({f"gyro_{a}_rad_s": w[:, j] for j, a in enumerate("xyz")})
    cols.update({f"accel_{a}_m_s2": f[:, j] for j, a in enumerate("xyz")})
    dth, dv = np.vstack([np.zeros((1, 3)), 0.01 * w[1:]]), np.vstack([np.zeros((1, 3)), 0.01 * f[1:]])
    cols.update({f"dtheta_{a}_rad": dth[:, j] for j, a in enumerate("xyz")})
    cols.update({f"dv_{a}_m_s": dv[:, j] for j, a in enumerate("xyz")})
    return cols


RATES = ["time_s"] + [f"gyro_{a}_rad_s" for a in "xyz"] + [f"accel_{a}_m_s2" for a in "xyz"]
INCREMENTS = ["time_s"] + [f"dtheta_{a}_rad" for a in "xyz"] + [f"dv_{a}_m_s" for a in "xyz"]


@pytest.mark.parametrize("clash, named", [
    ("units", r"the rotation is given by gyro_x_rad_s, gyro_y_rad_s, gyro_z_rad_s and by gyro_x_deg_s"),
    ("rates+increments", r"the rotation is given by gyro_x_rad_s, gyro_y_rad_s, gyro_z_rad_s and by dtheta_x_rad, "
                         r"dtheta_y_rad, dtheta_z_rad; the specific force is given by accel_x_m_s2, accel_y_m_s2, "
                         r"accel_z_m_s2 and by dv_x_m_s, dv_y_m_s, dv_z_m_s"),
    ("increments+accel_g", r"the specific force is given by accel_x_g, accel_y_g, accel_z_g and by dv_x_m_s"),
])
@pytest.mark.parametrize("kind", ["csv", "pandas", "parquet"])
def test_imu_columns_that_give_a_sensor_twice_are_refused_naming_them(tmp_path, clash, named, kind):
    """gyro_x_rad_s beside a disagreeing gyro_x_deg_s was read in rad/s, and a file of rates and increments
    was read by its increments (the lean path) or its rates (the pandas path), without a word: which one is
    meant is not guessed."""
    import pandas as pd

    cols = _imu_table()
    if clash == "units":
        df = pd.DataFrame({c: cols[c] for c in RATES})
        df["gyro_x_deg_s"] = np.degrees(df["gyro_x_rad_s"]) + 1.0  # and disagreeing
    elif clash == "rates+increments":
        df = pd.DataFrame({c: cols[c] for c in RATES + INCREMENTS[1:]})
    else:
        df = pd.DataFrame({c: cols[c] for c in INCREMENTS})
        for a in "xyz":
            df[f"accel_{a}_g"] = cols[f"accel_{a}_m_s2"] / 9.80665
    if kind == "pandas":
        df["note"] = "x"  # a text column: not the lean path
    p = tmp_path / ("imu.parquet" if kind == "parquet" else "imu.csv")
    df.to_parquet(p) if kind == "parquet" else df.to_csv(p, index=False)
    with pytest.raises(InputError, match=rf"imu\.(csv|parquet): columns that give the same measurement twice: "
                                         rf"{named}.*keep one set of columns"):
        io.read_imu(p)
    for one in (RATES, INCREMENTS):  # each set alone: read, and both give the same motion
        q = tmp_path / "one.csv"
        pd.DataFrame({c: cols[c] for c in one}).to_csv(q, index=False)
        imu = io.read_imu(q, check_units=False)
        assert np.allclose(imu.rates()[0][1:, 2], 0.2)


def test_a_solution_with_an_extra_column_named_as_a_navigation_column_is_not_written(tmp_path):
    """A solution built without checks whose extra column is named time_s: write_solution refuses it, both
    formats, and leaves no file (it wrote time_s = -5 over the times)."""
    from inskit.types import NavSolution

    t = np.arange(3.0)
    sol = NavSolution._trusted(t, np.tile([0.7, 0.1, 0.0], (3, 1)), np.zeros((3, 3)), np.tile([1.0, 0, 0, 0], (3, 1)),
                               {"time_s": np.full(3, -5.0)})
    for name in ("sol.csv", "sol.parquet"):
        with pytest.raises(InputError, match=r"extra column `time_s` would overwrite the column 'time_s'"):
            io.write_solution(tmp_path / name, sol)
        assert not (tmp_path / name).exists()
    assert C.SOLUTION_COLUMNS == list(NavSolution(t, sol.lla, sol.v_n, sol.q_nb).columns())


def test_an_unknown_sampled_mode_is_refused_for_every_file(tmp_path):
    """read_imu(path, sampled="bogus") was accepted on an increment file (which does not use it), while options
    that do not apply are refused: a value outside the modes is refused whatever the file holds."""
    p = _write_rates(tmp_path / "rates.csv", 0.01 * np.arange(50))
    imu = C.read_imu(p)
    io.write_imu(tmp_path / "inc.csv", imu)
    for f in (p, tmp_path / "inc.csv"):
        with pytest.raises(InputError, match=r"^`sampled` must be one of 'instant', 'average', got 'bogus'$"):
            io.read_imu(f, sampled="bogus")


@pytest.mark.parametrize("kind", ["increments", "increments.parquet", "increments-first-increment", "rates",
                                  "rates-drop"])
@pytest.mark.parametrize("sensor, value, match", [
    ("gyro", 1e308, r"an angular rate of over 1e30 rad/s"),
    ("gyro", 1e4, r"an angular rate of 1e\+04 rad/s"),
    ("accel", 1e5, r"a specific force of 1\.02e\+04 g"),
])
def test_one_sample_beyond_any_sensor_range_is_refused_naming_its_row(tmp_path, kind, sensor, value, match):
    """One corrupt IMU row (an increment of 100 rad or 1000 m/s over 10 ms, a 1e308; ``value`` is the rate) moved neither the
    median nor the 99th percentile of the unit checks.  navigate integrated it: 100 rad about z turned the
    heading by 5.75 rad and the run said 'health: healthy'; 1000 m/s lost the filter for 15 s; 1e308 ended in
    'the innovation is not finite: the filter diverged' or '`rpy` has a NaN or infinite value (nan)', naming
    no file and no row.  Now the reader refuses the row, by its line (row in Parquet)."""
    cols = _imu_table(400)
    row = 250
    if kind.startswith("increments"):
        names, scale = INCREMENTS, 0.01
        name = "dtheta_z_rad" if sensor == "gyro" else "dv_x_m_s"
    else:
        names, scale = RATES, 1.0
        name = "gyro_z_rad_s" if sensor == "gyro" else "accel_x_m_s2"
    frame = pd.DataFrame({c: cols[c] for c in names})
    if kind == "increments-first-increment":  # the file's first row is an increment: no initial row
        frame = frame.iloc[1:].reset_index(drop=True)
    if kind == "rates-drop":  # a repeated row dropped before the spike: the message still names the file's line
        frame.iloc[100, 1:] = frame.iloc[99, 1:].to_numpy()
    frame.loc[row, name] = value if value > 1e300 else value * scale
    p = tmp_path / ("imu.parquet" if kind.endswith("parquet") else "imu.csv")
    frame.to_parquet(p) if kind.endswith("parquet") else p.write_text(
        ",".join(names) + "\n" + "\n".join(",".join(repr(float(x)) for x in r) for r in frame.to_numpy()) + "\n")
    where = f"row {row}" if kind.endswith("parquet") else f"line {row + 2}"
    kw = {"first_row": "increment"} if kind == "increments-first-increment" else \
        {"repeated": "drop"} if kind == "rates-drop" else {}
    with pytest.raises(InputError, match=rf"imu\.(csv|parquet): {where}: .*{match}, beyond any sensor's range"):
        C.read_imu(p, **kw)
    if value < 1e300:  # on request (a spinning projectile?) the row is read
        assert len(C.read_imu(p, check_units=False, **kw)) >= 399


@pytest.mark.parametrize("kind, factor, match", [
    ("rates", 3.28084, r"column 'accel_x_m_s2': the median specific force is 32\.\d+ m/s\^2 \(3\.\d+ g\), far above "
                       r"gravity for a whole log: values in ft/s\^2, cm/s\^2 or mm/s\^2"),
    ("rates", 1000.0, r".*far above gravity for a whole log: values in ft/s\^2, cm/s\^2 or mm/s\^2"),
    ("increments", 100.0, r"column 'dv_x_m_s': .*far above gravity for a whole log: dv in cm/s, mm/s or ft/s"),
])
def test_a_specific_force_in_another_unit_under_an_m_s2_header_is_refused(tmp_path, kind, factor, match):
    """accel_*_m_s2 columns holding ft/s^2 or mm/s^2 (dv_*_m_s holding cm/s) were read: navigate lost the
    filter again and again ('recovered from a lost state ... tilt error of about 89 deg') and never said
    which column was at fault, while g under m/s^2 and m/s^2 under g were refused.  A whole log's median
    specific force above 3 g now is, as it is under a g header."""
    cols = _imu_table(400)
    names = RATES if kind == "rates" else INCREMENTS
    frame = pd.DataFrame({c: cols[c] for c in names})
    for c in names[4:]:
        frame[c] *= factor
    p = tmp_path / "imu.csv"
    frame.to_csv(p, index=False)
    with pytest.raises(InputError, match=r"imu\.csv: " + match):
        C.read_imu(p)
    assert len(C.read_imu(p, check_units=False)) == 400


@pytest.mark.parametrize("fault, match", [
    ("radians", r"its positions move 57\.\d+ times slower than its velocity columns say \(median over 39 moving "
                r"rows\): latitude and longitude hold radians under the _deg headers"),
    ("ms", r"its positions move 1000 times slower .*: the time column holds milliseconds"),
])
@pytest.mark.parametrize("kind", ["csv", "parquet"])
def test_gnss_fixes_in_radians_or_milliseconds_are_told_by_their_velocity(tmp_path, fault, match, kind):
    """Fixes with velocity whose lat_deg and lon_deg held radians (a point in the Gulf of Guinea, 57.3 times
    too little motion) were read: `inskit navigate` lost the filter five times ('recovered from a lost
    state'), searched an IMU time offset and said unhealthy without naming the file or the unit, while
    read_solution refuses the same columns by the same test.  read_gnss now applies it."""
    df = _gnss_frame()
    df["lat_deg"] = 45.0 + 10.0 / 111_132.0 * 0.2 * np.arange(len(df))  # 10 m/s north, as vn_m_s says
    df["vn_m_s"] = 10.0
    if fault == "radians":
        df["lat_deg"], df["lon_deg"] = np.radians(df["lat_deg"]), np.radians(df["lon_deg"])
    else:
        df["time_s"] *= 1000.0
    p = tmp_path / f"gnss.{kind}"
    df.to_parquet(p) if kind == "parquet" else df.to_csv(p, index=False)
    with pytest.raises(InputError, match=rf"gnss\.{kind}: {match}"):
        io.read_gnss(p)
    df.drop(columns=[c for c in df.columns if c[:2] in ("vn", "ve", "vd") or c.startswith("sigma_v")]).to_csv(
        tmp_path / "novel.csv", index=False)
    assert len(io.read_gnss(tmp_path / "novel.csv")) == len(df)  # without velocity nothing tells it


_SPEED_COURSE = "time_s,speed_m_s,course_deg,sigma_speed_m_s,sigma_course_deg\n" + "".join(
    f"{k},{10.0 + 0.1 * k},{3.0 * k},0.1,2.0\n" for k in range(10))


@pytest.mark.parametrize("reader, column, value, match", [
    ("gnss", "sigma_n_m", "1e30", r"column 'sigma_n_m' is 1e\+30; a sigma beyond 100 km"),
    ("gnss", "sigma_d_m", "2e5", r"column 'sigma_d_m' is 200000(\.0)?; a sigma beyond 100 km"),
    ("gnss", "sigma_vd_m_s", "1e300", r"column 'sigma_vd_m_s' is 1e\+300; a sigma beyond 12000 m/s"),
    ("speed_course", "sigma_speed_m_s", "1e300", r"column 'sigma_speed_m_s' is 1e\+300; a sigma beyond 12000 m/s"),
    ("speed_course", "sigma_course_deg", "400", r"column 'sigma_course_deg' is 400(\.0)?; a sigma beyond 360 deg"),
    ("speed_course", "speed_m_s", "1e300", r"column 'speed_m_s' is 1e\+300; expected a speed over ground up to "
                                           r"12000 m/s"),
    ("speed_course", "course_deg", "1e300", r"column 'course_deg' is 1e\+300; expected degrees clockwise from north, "
                                            r"within \+-360"),
    ("height", "sigma_m", "1e300", r"column 'sigma_m' is 1e\+300; a sigma beyond 100 km"),
    ("gnss", "sigma_e_m", "1e-10", r"column 'sigma_e_m' is 1e-10; a sigma below 1e-06 m is no measurement"),
    ("gnss", "sigma_ve_m_s", "1e-30", r"column 'sigma_ve_m_s' is 1e-30; a sigma below 1e-06 m/s"),
    ("speed_course", "sigma_course_deg", "1e-9", r"column 'sigma_course_deg' is 1e-09; a sigma below 1e-06 deg"),
    ("height", "sigma_m", "1e-12", r"column 'sigma_m' is 1e-12; a sigma below 1e-06 m"),
])
def test_a_sigma_speed_or_course_beyond_reason_is_refused_naming_its_line(tmp_path, reader, column, value, match):
    """A fix whose sigma_n_m held 1e30 (every fix) ended `inskit navigate` in 'covariance lost positiveness at
    t = 0.500 s: the filter diverged (check sensor noise settings and the initial state)'; a speed-and-course
    row with a speed, or a sigma, of 1e300 in 'innovation covariance is not positive definite: the filter
    diverged'; a course of 1e300 deg went in as some angle and the run said healthy.  Exact fixes with sigmas
    of 1e-10 m ended in 'covariance lost positiveness at t = 1.000 s' (1e-8 m still ran).  None named the
    file, the line or the column: the readers now refuse them."""
    if reader == "gnss":
        df = _gnss_frame()
        df[column] = df[column].astype(object)
        df.loc[5, column] = value
        p = tmp_path / "f.csv"
        df.to_csv(p, index=False)
        read = io.read_gnss
    else:
        text = _SPEED_COURSE if reader == "speed_course" else "time_s,height_m,sigma_m\n" + "".join(
            f"{k},{100.0 + k},0.5\n" for k in range(10))
        lines = text.splitlines(True)
        names = lines[0].strip().split(",")
        cells = lines[6].strip().split(",")
        cells[names.index(column)] = value
        lines[6] = ",".join(cells) + "\n"
        p = tmp_path / "f.csv"
        p.write_text("".join(lines))
        read = io.read_speed_course if reader == "speed_course" else io.read_height
    with pytest.raises(InputError, match=rf"f\.csv: line 7: {match}"):
        read(p)


def test_an_odometer_speed_beyond_the_limit_backwards_is_said_below_not_above(tmp_path):
    """A reversing speed of -400 m/s (km/h of a reversing car, a corrupt row) was refused as 'holds -400.0,
    above 150 m/s', which it is not; the message now says which side of the bound it lies."""
    p = tmp_path / "odo.csv"
    p.write_text("time_s,speed_m_s\n0.0,0.0\n0.1,-400\n0.2,1.0\n")
    with pytest.raises(InputError, match=r"odo\.csv: line 3: column 'speed_m_s' holds -400(\.0)?, below -150 m/s: "
                                         r"km/h or another unit\? expected metres per second$"):
        io.read_speed(p)
    p.write_text("time_s,speed_m_s\n0.0,0.0\n0.1,400\n0.2,1.0\n")
    with pytest.raises(InputError, match=r"line 3: column 'speed_m_s' holds 400(\.0)?, above 150 m/s"):
        io.read_speed(p)


def _moving_gnss(n=60, speed=12.0, heading_deg=10.0):
    """Fixes of a drive at ``speed`` m/s on a straight ``heading_deg`` course, 1 Hz, 0.5 m sigmas, with the
    matching north-east-down velocity."""
    import pandas as pd

    t = np.arange(n, dtype=float)
    vn, ve = speed * np.cos(np.radians(heading_deg)), speed * np.sin(np.radians(heading_deg))
    lat = 45.0 + np.degrees(vn * t / 6_367_000.0)
    lon = 7.0 + np.degrees(ve * t / (6_388_000.0 * np.cos(np.radians(45.0))))
    return pd.DataFrame({"time_s": t, "lat_deg": lat, "lon_deg": lon, "height_m": 300.0, "sigma_n_m": 0.5,
                         "sigma_e_m": 0.5, "sigma_d_m": 1.0, "vn_m_s": vn, "ve_m_s": ve, "vd_m_s": 0.0,
                         "sigma_vn_m_s": 0.1, "sigma_ve_m_s": 0.1, "sigma_vd_m_s": 0.1})


@pytest.mark.parametrize("fault, match", [
    ("zeros", r"its velocity columns say 0 times the speed its positions move at \(median over 59 pairs of "
              r"consecutive fixes whose positions move\); expected 0\.67\.\.1\.5 \(m/s, the same motion\): zeros: a "
              r"receiver that gave no velocity\? leave the six velocity columns out"),
    ("kmh", r"its velocity columns say 3\.6 times .*: km/h\?"),
    ("swapped", r"its velocity points 70 deg away from where its positions move .*: vn_m_s and ve_m_s swapped, or "
                r"a sign \(east-north-up for north-east-down\)\?"),
    ("sign", r"its velocity points 180 deg away"),
])
@pytest.mark.parametrize("kind", ["csv", "parquet"])
def test_gnss_velocity_columns_that_do_not_describe_the_positions_motion_are_refused(tmp_path, fault, match, kind):
    """The start-up takes heading and motion from the velocity of fixes coarser than 0.1 m, use_velocity or not,
    and nothing compared that velocity with the positions: velocity columns of zeros made `inskit navigate` say
    'the GNSS track never moves' of a 14 m/s drive; vn and ve swapped turned the IMU's axes by 90 deg ('the
    readings were rotated into the vehicle's axes') and lost the filter; the sign flipped lost it too, and
    km/h passed as 'healthy'.  read_gnss now refuses each, naming the file."""
    df = _moving_gnss()
    if fault == "zeros":
        df[["vn_m_s", "ve_m_s", "vd_m_s"]] = 0.0
    elif fault == "kmh":
        df[["vn_m_s", "ve_m_s", "vd_m_s"]] *= 3.6
    elif fault == "swapped":
        df[["vn_m_s", "ve_m_s"]] = df[["ve_m_s", "vn_m_s"]].to_numpy()
    else:
        df[["vn_m_s", "ve_m_s", "vd_m_s"]] *= -1.0
    p = tmp_path / f"gnss.{kind}"
    df.to_parquet(p) if kind == "parquet" else df.to_csv(p, index=False)
    with pytest.raises(InputError, match=rf"gnss\.{kind}: {match}"):
        io.read_gnss(p)
    good = _moving_gnss()
    good.to_csv(tmp_path / "good.csv", index=False)
    assert io.read_gnss(tmp_path / "good.csv").has_velocity
    slow = _moving_gnss(speed=1.0)  # a walk: its positions' noise hides their motion, nothing to judge
    slow[["vn_m_s", "ve_m_s"]] = 0.0
    slow.to_csv(tmp_path / "slow.csv", index=False)
    assert io.read_gnss(tmp_path / "slow.csv").has_velocity


def test_the_longest_run_of_repeated_rows_is_reported_with_its_line(tmp_path):
    """A rate log whose output froze for 5 s (500 rows of one sample, mid-drive) was reported as '500 rows
    repeat the previous row (the logger read one sample twice?), integrated as samples over their short
    intervals', and the run said healthy.  The reader now gives the longest run, its span and its line, from
    which navigate's verdict tells a frozen sensor from samples read twice (drive_0708, walk_0827: runs of 1)."""
    t = 0.01 * np.arange(3000)
    p = _write_rates(tmp_path / "imu.csv", t)
    lines = p.read_text().splitlines(True)
    frozen = lines[1001].split(",", 1)[1]  # data row 1000's six channels
    for k in range(1002, 1501):  # data rows 1001..1499 repeat it
        lines[k] = lines[k].split(",", 1)[0] + "," + frozen
    lines[2001] = lines[2001].split(",", 1)[0] + "," + lines[2000].split(",", 1)[1]  # and one double read
    p.write_text("".join(lines))
    info = {}
    C.read_imu(p, info=info)
    assert info["repeated_rows"] == 500 and info["repeated_rows_longest_run"] == 499
    assert info["repeated_rows_longest_run_at"] == "line 1003"
    assert info["repeated_rows_longest_run_time_s"] == pytest.approx(10.01)
    assert info["repeated_rows_longest_run_s"] == pytest.approx(4.99)
    info = {}
    C.read_imu(p, info=info, repeated="drop")  # counted on the rows as logged, dropped or not
    assert info["repeated_rows_longest_run"] == 499 and info["repeated_rows_dropped"]


@pytest.mark.parametrize("header, scale, shown", [("m_s2", 0.0, "0 m/s\\^2"), ("g", 0.0, "0 g"),
                                                  ("m_s2", 1e-4, "0\\.00\\d+ m/s\\^2"), ("g", 1e-3, "0\\.00\\d+ g")])
def test_an_accelerometer_of_zeros_is_refused_as_such_not_as_values_in_g(tmp_path, header, scale, shown):
    """accel_*_m_s2 columns of zeros (a dead or disconnected sensor) were refused as 'looks like values in g;
    rename the columns accel_*_g', and renamed so, accel_*_g zeros were read without a word (navigate then
    levelled on no gravity).  A median specific force far below 1 g in either unit is refused as what it is."""
    t = 0.01 * np.arange(400)
    rng = np.random.default_rng(3)
    cols = {"time_s": t}
    cols.update({f"gyro_{a}_rad_s": rng.normal(0, 1e-3, len(t)) for a in "xyz"})
    cols.update({f"accel_{a}_{header}": scale * rng.normal(0, 1.0, len(t)) for a in "xyz"})
    p = tmp_path / "imu.csv"
    pd.DataFrame(cols).to_csv(p, index=False)
    with pytest.raises(InputError, match=rf"imu\.csv: accel_{{x,y,z}}_{header}: the median specific force is {shown}, "
                                         r"far below gravity \(1 g, 9\.81 m/s\^2\) in any unit: the accelerometer "
                                         r"columns hold zeros or nearly"):
        C.read_imu(p)
    assert len(C.read_imu(p, check_units=False)) == 400  # free fall, on request
