"""The lean IMU reader of :mod:`inskit.io.csv_formats` (issue 13): well-formed increment files (CSV and
Parquet) are read straight into their arrays, exactly (every double as Python's correctly rounded
``float()`` reads its text), and every other file still goes the pandas way, whose messages name the
line and the column."""

import numpy as np
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
