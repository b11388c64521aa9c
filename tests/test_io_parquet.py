"""Parquet and fast-CSV solution files (issue 13): lossless typed Parquet with
units, CSV at a chosen rate equal to the former ``%.15g`` files, readers that
take both, column selection, and the navigate outputs."""

import json
import re

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from inskit import io
from inskit import rotations as rot
from inskit.errors import ConfigError, InputError
from inskit.io import parquet as P
from inskit.types import NavSolution
from inskit.units import DEG
from cli_runner import in_process


def solution(n=2001, dt=0.01, t0=243261.7262, rng=None):
    """A smooth drive-like solution with sigma and estimate columns."""
    rng = rng or np.random.default_rng(13)
    t = t0 + dt * np.arange(n)
    s = np.linspace(0.0, 1.0, n)
    lla = np.column_stack([40.1 * DEG + 1e-5 * s, -105.1 * DEG + 2e-5 * np.sin(3 * s), 1600.0 + 3 * s])
    v = np.column_stack([10 * np.cos(s), 10 * np.sin(s), 0.1 * s])
    rpy = np.column_stack([0.01 * np.sin(5 * s), -0.02 * s, -3.0 + 6.0 * s])  # yaw passes through +-180 deg
    extra = {"sigma_n_m": 0.05 + s, "sigma_att_d_rad": 1e-3 * (1 + s),
             "bg_x_rad_s": 1e-4 * rng.normal(size=n), "ba_z_m_s2": 1e-3 * rng.normal(size=n), "sg_x": 1e-5 * s}
    return NavSolution.from_euler(t, lla, v, rpy, extra)


def test_parquet_round_trip_is_lossless_and_typed(tmp_path):
    sol = solution()
    p = io.write_solution(tmp_path / "s.parquet", sol, metadata={"config": "drive", "solution": "forward"})
    back = io.read_solution(p)
    # float64 on disk: only the deg <-> rad conversions round (1 ulp), nothing is lost to text
    np.testing.assert_array_equal(back.time, sol.time)
    np.testing.assert_allclose(back.lla[:, :2], sol.lla[:, :2], rtol=4e-16, atol=0)
    np.testing.assert_array_equal(back.lla[:, 2], sol.lla[:, 2])
    np.testing.assert_array_equal(back.v_n, sol.v_n)
    np.testing.assert_allclose(rot.euler_from_quat(back.q_nb), sol.euler, rtol=0, atol=1e-14)
    for k, a in sol.extra.items():
        np.testing.assert_array_equal(back.extra[k], a)
    schema = pq.read_schema(p)
    assert all(str(f.type) == "double" for f in schema)
    units = {f.name: f.metadata[b"unit"].decode() for f in schema}
    assert units["time_s"] == "s" and units["lat_deg"] == "deg" and units["vn_m_s"] == "m/s"
    assert units["bg_x_rad_s"] == "rad/s" and units["ba_z_m_s2"] == "m/s^2" and units["sg_x"] == "1"
    assert units["sigma_att_d_rad"] == "rad" and units["height_m"] == "m"
    meta = P.read_metadata(p)
    assert meta["config"] == "drive" and meta["solution"] == "forward" and meta["units"] == units
    from inskit import __version__

    assert meta["version"] == __version__


def test_fast_csv_equals_the_former_pandas_format(tmp_path):
    """The vectorised writer's values are those of ``to_csv(float_format="%.15g")`` within one unit
    of the 15th significant digit (they differ only at exact halves), and pandas' default parser
    (the one ``read_solution`` uses) reads them back within 1e-14, small values included."""
    sol = solution()
    p = io.write_solution(tmp_path / "s.csv", sol)
    cols = P.solution_columns(sol)
    pd.DataFrame(cols).to_csv(tmp_path / "old.csv", index=False, float_format="%.15g")
    new = pd.read_csv(p, float_precision="round_trip")
    old = pd.read_csv(tmp_path / "old.csv", float_precision="round_trip")
    assert list(new.columns) == list(old.columns) == list(cols)
    assert p.read_text().splitlines()[0] == ",".join(cols)  # a plain header, no quotes
    a, b = new.to_numpy(), old.to_numpy()
    assert np.all(np.abs(a - b) <= 1.0001e-14 * np.abs(b))
    assert abs(p.stat().st_size / (tmp_path / "old.csv").stat().st_size - 1) < 0.1  # the same size
    truth = np.column_stack(list(cols.values()))
    fast = pd.read_csv(p).to_numpy()  # pandas' default (fast) float parser
    assert np.all(np.abs(fast - truth) <= 1e-14 * np.abs(truth))
    back = io.read_solution(p)
    np.testing.assert_allclose(back.lla[:, 0], sol.lla[:, 0], rtol=1e-14)
    np.testing.assert_allclose(back.extra["bg_x_rad_s"], sol.extra["bg_x_rad_s"], rtol=1e-14)


def test_round_significant_digits():
    x = np.array([243261.72620000001, 40.09662684777193, -9.49153321281977e-05, 1.1146479022979544e-06, 1e-300,
                  5e-324, 0.0, 123456789012345678.0])
    r = P.round_significant(x)
    for xi, ri in zip(x, r):
        assert float(f"{xi:.15g}") == pytest.approx(ri, rel=1.0001e-14, abs=0)
        digits = repr(float(ri)).split("e")[0].replace("-", "").replace(".", "").strip("0")
        assert len(digits) <= 15


def test_gzip_csv_round_trip(tmp_path):
    sol = solution(n=300)
    p = io.write_solution(tmp_path / "s.csv.gz", sol)
    assert p.read_bytes()[:2] == b"\x1f\x8b"
    back = io.read_solution(p)
    np.testing.assert_allclose(back.v_n, sol.v_n, rtol=1e-14, atol=1e-300)


def test_decimation_keeps_one_row_per_period_on_the_absolute_grid():
    t = 243261.7262 + 0.01 * np.arange(6001)  # 100 Hz for 60 s, off the 0.1 s grid by 6.2 ms
    k = P.decimation_index(t, 10.0)
    assert k[0] == 0 and k[-1] == len(t) - 1
    inner = t[k[1:-1]]
    # each kept row is the first at or after a multiple of 0.1 s: 6.2 ms past it, 0.1 s apart
    np.testing.assert_allclose((inner * 10) % 1.0 * 0.1, 0.0062, atol=1e-6)
    np.testing.assert_allclose(np.diff(inner), 0.1, atol=1e-6)
    assert len(k) == 600 + 2
    assert len(P.decimation_index(t, 100.0)) == len(t) == len(P.decimation_index(t, 250.0))
    jitter = np.arange(1001) * 0.01 + np.r_[0.0, np.full(1000, -1e-7)]  # samples 0.1 us before the grid
    kj = P.decimation_index(jitter, 1.0)
    np.testing.assert_array_equal(kj, [0, 100, 200, 300, 400, 500, 600, 700, 800, 900, 1000])


def test_csv_at_a_rate_and_parquet_at_every_epoch(tmp_path):
    sol = solution(n=6001)
    io.write_solution(tmp_path / "s.parquet", sol)
    io.write_solution(tmp_path / "s.csv", sol, rate_hz=10.0)
    full, dec = io.read_solution(tmp_path / "s.parquet"), io.read_solution(tmp_path / "s.csv")
    assert len(full) == 6001 and len(dec) == 602
    i = np.searchsorted(full.time, dec.time)
    np.testing.assert_allclose(full.time[i], dec.time, rtol=1e-15)  # rows of the solution, not interpolated
    np.testing.assert_allclose(full.extra["sigma_n_m"][i], dec.extra["sigma_n_m"], rtol=1e-14)


def test_column_selection():
    names = ["time_s", "lat_deg", "lon_deg", "height_m", "vn_m_s", "ve_m_s", "vd_m_s", "roll_deg", "pitch_deg",
             "yaw_deg", "sigma_n_m", "bg_x_rad_s", "sg_x"]
    nav = names[:10]
    assert P.select_columns(names, "all") == names
    assert P.select_columns(names, ["navigation"]) == nav
    assert P.select_columns(names, "navigation+sigma") == nav + ["sigma_n_m"]
    assert P.select_columns(names, ["estimates"]) == nav + ["bg_x_rad_s", "sg_x"]
    assert P.select_columns(names, ["sg_x", "navigation"]) == nav + ["sg_x"]
    with pytest.raises(ConfigError, match=r"'bg_q_rad_s' is neither a group .* its columns are time_s, .*sg_x"):
        P.select_columns(names, ["bg_q_rad_s"])


def test_written_columns_follow_the_selection(tmp_path):
    sol = solution(n=200)
    io.write_solution(tmp_path / "n.parquet", sol, columns="navigation")
    io.write_solution(tmp_path / "s.csv", sol, columns=["navigation+sigma", "sg_x"])
    assert pq.read_schema(tmp_path / "n.parquet").names == list(P.NAVIGATION_COLUMNS)
    assert list(pd.read_csv(tmp_path / "s.csv").columns) == list(P.NAVIGATION_COLUMNS) + [
        "sigma_n_m", "sigma_att_d_rad", "sg_x"]


def test_reader_tells_the_format_by_content(tmp_path):
    sol = solution(n=50)
    io.write_solution(tmp_path / "s.parquet", sol)
    (tmp_path / "odd.dat").write_bytes((tmp_path / "s.parquet").read_bytes())
    assert len(io.read_solution(tmp_path / "odd.dat")) == 50
    (tmp_path / "fake.parquet").write_text("time_s,lat_deg\n1,2\n")
    with pytest.raises(InputError, match=r"fake.parquet: named .parquet but not a Parquet file"):
        io.read_solution(tmp_path / "fake.parquet")
    (tmp_path / "cut.parquet").write_bytes((tmp_path / "s.parquet").read_bytes()[:300])
    with pytest.raises(InputError, match=r"cut.parquet: not a readable Parquet file"):
        io.read_solution(tmp_path / "cut.parquet")


@pytest.mark.parametrize("kind", ["increments", "rates", "first-row", "gnss", "speed", "height", "solution-head"])
def test_every_parquet_reader_names_a_row_counted_from_0_never_a_line(tmp_path, kind):
    """The solution reader said 'row 7' of a Parquet file, the IMU, fixes, odometer and height readers
    'line 9' of the same row (a CSV's line, header = line 1): a Parquet file has rows, counted from 0."""
    import pyarrow as pa

    n = 20
    t = np.round(0.01 * np.arange(n), 2)
    one = np.ones(n)
    read = io.read_imu
    if kind in ("increments", "first-row"):
        d = 1e-5 * one
        d[0] = 0.0 if kind == "increments" else 1e-5
        cols = {"time_s": t, **{f"dtheta_{a}_rad": d for a in "xyz"}, "dv_x_m_s": d, "dv_y_m_s": d,
                "dv_z_m_s": -0.098 * one}
        if kind == "increments":
            cols["time_s"] = np.r_[t[:7], t[5], t[8:]]  # row 7 goes back to row 5's time
            want = r"row 7: time_s=0\.05 goes back in time from row 6 \(0\.06\)"
        else:
            want = r"row 0 \(the first data row\) holds increments"
    elif kind == "rates":
        gz = 0.003 * one
        gz[11] = np.nan
        cols = {"time_s": t, "gyro_x_rad_s": 0.001 * one, "gyro_y_rad_s": 0.002 * one, "gyro_z_rad_s": gz,
                "accel_x_m_s2": 0.1 * one, "accel_y_m_s2": 0.2 * one, "accel_z_m_s2": -9.8 * one}
        want = r"row 11: column 'gyro_z_rad_s' is empty \(null\) or NaN; expected a finite number"
    elif kind == "gnss":
        lat = [45.0] * n
        lat[5] = None
        cols = {"time_s": t, "lat_deg": pa.array(lat, pa.float64()), "lon_deg": 7 * one, "height_m": 300 * one,
                "sigma_n_m": one, "sigma_e_m": one, "sigma_d_m": 2 * one}
        read, want = io.read_gnss, r"row 5: column 'lat_deg' is empty \(null\) or NaN"
    elif kind == "speed":
        v = 10 * one
        v[4] = 200.0
        cols, read = {"time_s": t, "speed_m_s": v}, io.read_speed
        want = r"row 4: column 'speed_m_s' holds 200(\.0)?, above 150 m/s"
    elif kind == "height":
        sg = one.copy()
        sg[13] = 0.0
        cols, read = {"time_s": t, "height_m": 300 * one, "sigma_m": sg}, io.read_height
        want = r"row 13: column 'sigma_m' is 0\.0; sigmas must be > 0"
    else:  # the head of a solution (mechanize --init-from)
        cols = P.solution_columns(solution(n=n))
        cols["lat_deg"] = cols["lat_deg"].copy()
        cols["lat_deg"][1] = 91.0
        read = lambda p: io.read_solution(p, until_s=float(cols["time_s"][3]))  # noqa: E731
        want = r"row 1: lat_deg=91\.0 is outside \[-90, 90\] degrees"
    p = tmp_path / "f.parquet"
    pq.write_table(pa.table(cols), p)
    with pytest.raises(InputError, match=r"f\.parquet: " + want) as e:
        read(p)
    assert not re.search(r"line \d", str(e.value))


def test_parquet_reader_validates_rows(tmp_path):
    cols = P.solution_columns(solution(n=20))
    t = cols["time_s"].copy()
    t[7] = t[6]
    P.write_parquet(tmp_path / "dup.parquet", {**cols, "time_s": t})
    with pytest.raises(InputError, match=r"dup.parquet: row 7: time_s=.* does not increase from row 6"):
        io.read_solution(tmp_path / "dup.parquet")
    lat = cols["lat_deg"].copy()
    lat[3] = 91.0
    P.write_parquet(tmp_path / "lat.parquet", {**cols, "lat_deg": lat})
    with pytest.raises(InputError, match=r"lat.parquet: row 3: lat_deg=91.0 is outside \[-90, 90\]"):
        io.read_solution(tmp_path / "lat.parquet")
    P.write_parquet(tmp_path / "short.parquet", {k: v for k, v in cols.items() if k != "yaw_deg"})
    with pytest.raises(InputError, match=r"short.parquet: missing column\(s\) yaw_deg"):
        io.read_solution(tmp_path / "short.parquet")


def test_narrow_floats_for_times_and_geodetic_angles_are_refused(tmp_path):
    """lat_deg and lon_deg as float32 were read (0.21 m of 'error' in
    evaluate came from the dtype alone); a float32 height or velocity loses
    nothing that matters and is read."""
    import pyarrow as pa

    cols = P.solution_columns(solution(n=20))
    for name in ("lat_deg", "time_s"):
        table = pa.table({k: pa.array(v, type=pa.float32() if k == name else pa.float64()) for k, v in cols.items()})
        pq.write_table(table, tmp_path / f"{name}.parquet")
        with pytest.raises(InputError, match=rf"{name}\.parquet: column '{name}' holds float; expected float64"):
            io.read_solution(tmp_path / f"{name}.parquet")
    table = pa.table({k: pa.array(v, type=pa.float32() if k == "height_m" else pa.float64()) for k, v in cols.items()})
    pq.write_table(table, tmp_path / "h.parquet")
    assert len(io.read_solution(tmp_path / "h.parquet")) == 20


def test_nan_is_refused_with_column_and_row(tmp_path):
    sol = solution(n=30)
    sol.extra["sigma_n_m"][12] = np.nan
    for name in ("s.parquet", "s.csv"):
        with pytest.raises(InputError, match=rf"{name}: refusing to write nan \(column 'sigma_n_m', row 12\)"):
            io.write_solution(tmp_path / name, sol)
        assert not (tmp_path / name).exists()
    assert not list(tmp_path.iterdir())  # no temporary file left either


def test_output_config_keys():
    from inskit.jobs.config import OutputSection

    assert OutputSection().format == "both" and OutputSection().rate_hz == 10.0
    assert OutputSection(columns="navigation").columns == ["navigation"]
    with pytest.raises(Exception, match="rate_hz = 5 sets the rate of the CSV files"):
        OutputSection(format="parquet", rate_hz=5.0)
    with pytest.raises(Exception, match="greater than 0"):
        OutputSection(rate_hz=0.0)


def test_navigate_writes_parquet_and_decimated_csv_and_evaluate_reads_both(tmp_path):
    """The whole command on a simulated 100 Hz drive: Parquet at every IMU epoch, CSV at
    --output-rate, ``evaluate`` gives the same errors from either (the CSV's rows are the
    Parquet's), within what 15 digits and the coarser rows allow."""
    from click.testing import CliRunner

    from inskit.cli import cli

    scen = tmp_path / "s.toml"
    scen.write_text(
        'name = "drive"\n[start]\nlat_deg = 45\nlon_deg = 7\nheight_m = 300\n'
        '[imu]\nrate_hz = 100\ngrade = "industrial-mems"\n'
        '[gnss]\nrate_hz = 1\nwhite_h_m = 0.5\nwhite_v_m = 1.0\n'
        '[[segment]]\ntype = "static"\nduration_s = 20\n'
        '[[segment]]\ntype = "accelerate"\nspeed_m_s = 10\nduration_s = 10\n'
        '[[segment]]\ntype = "turn"\nangle_deg = 90\nradius_m = 30\n'
        '[[segment]]\ntype = "cruise"\nduration_s = 20\n')
    run = CliRunner().invoke
    r = run(cli, ["simulate", str(scen), "--out", str(tmp_path / "sim"), "--no-plot"])
    assert r.exit_code == 0, r.output
    nav = tmp_path / "nav"
    r = run(cli, ["navigate", "--imu", str(tmp_path / "sim" / "imu.csv"), "--gnss", str(tmp_path / "sim" / "gnss.csv"),
                  "--out", str(nav), "--no-plots", "--output-rate", "5", "--json"])
    assert r.exit_code == 0, r.output
    s = json.loads((nav / "summary.json").read_text())
    assert s["solution_files"] == {"format": "both", "csv_rate_hz": 5.0, "columns": ["all"]}
    full = io.read_solution(nav / "solution_forward.parquet")
    dec = io.read_solution(nav / "solution_forward.csv")
    assert len(full) == s["epochs"]
    duration = full.time[-1] - full.time[0]
    assert abs(len(dec) - 5 * duration) <= 3
    assert {"sigma_n_m", "bg_x_rad_s"} <= set(full.extra) and set(full.extra) == set(dec.extra)
    errs = {}
    for f in ("solution_forward.parquet", "solution_forward.csv"):
        r = run(cli, ["evaluate", str(nav / f), str(tmp_path / "sim" / "truth.csv"), "--json"])
        assert r.exit_code == 0, r.output
        errs[f] = json.loads(r.output[r.output.index("{"):])
    a, b = errs["solution_forward.parquet"], errs["solution_forward.csv"]
    assert a["horizontal_m"]["rms"] < 2.0  # 0.5 m white GNSS noise, filtered
    assert b["horizontal_m"]["rms"] == pytest.approx(a["horizontal_m"]["rms"], rel=0.05)
    # 15 digits of a latitude in degrees: 1e-13 deg = 1e-8 m
    assert b["horizontal_m"]["final"] == pytest.approx(a["horizontal_m"]["final"], rel=0, abs=1e-7)
    # Parquet only: no CSV is written, and a CSV rate would be ignored, so it is refused
    r = run(cli, ["navigate", "--imu", str(tmp_path / "sim" / "imu.csv"), "--gnss", str(tmp_path / "sim" / "gnss.csv"),
                  "--out", str(tmp_path / "pq"), "--no-plots", "--output-format", "parquet", "--output-rate", "5"])
    assert isinstance(r.exception, ConfigError) and "rate_hz = 5 sets the rate of the CSV files" in str(r.exception)
    assert not (tmp_path / "pq" / "summary.json").exists()


def test_damaged_inskit_metadata_is_an_input_error(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    from inskit.errors import InputError

    t = pa.table({"time_s": [0.0, 1.0]}).replace_schema_metadata({b"inskit": b"{not json"})
    pq.write_table(t, tmp_path / "m.parquet")
    with pytest.raises(InputError, match=r"m\.parquet: its inskit metadata is not readable JSON"):
        P.read_metadata(tmp_path / "m.parquet")


@pytest.mark.parametrize("name", ["s.parquet", "s.csv", "s.csv.gz"])
def test_a_solution_streamed_in_segments_is_the_file_written_whole(tmp_path, name):
    """SolutionStream: segments of any size (one of a single row) make the
    same file as write_solution of the whole, decimated on the whole run's
    grid; nothing under the final name before commit; abort leaves nothing."""
    sol = solution()
    whole = tmp_path / "whole" / name
    whole.parent.mkdir()
    rate = None if name.endswith("parquet") else 10.0
    io.write_solution(whole, sol, rate_hz=rate, columns=["navigation", "sg_x"], metadata={"solution": "forward"})
    path = tmp_path / name
    rows = None if rate is None else P.decimation_index(sol.time, rate)
    w = P.SolutionStream(path, rows=rows, columns=["navigation", "sg_x"], metadata={"solution": "forward"})
    for a, b in [(0, 1), (1, 700), (700, 701), (701, 2001)]:
        part = NavSolution._trusted(sol.time[a:b], sol.lla[a:b], sol.v_n[a:b], sol.q_nb[a:b],
                                    {k: v[a:b] for k, v in sol.extra.items()})
        w.write(part, a)
        assert not path.exists()
    w.commit()
    if name.endswith("parquet"):
        assert pq.read_table(whole).equals(pq.read_table(path))
        assert pq.read_table(whole).schema.metadata == pq.read_table(path).schema.metadata
    else:
        import gzip

        opener = gzip.open if name.endswith(".gz") else open
        assert opener(whole, "rb").read() == opener(path, "rb").read()
    w2 = P.SolutionStream(tmp_path / ("x" + name))
    w2.write(sol, 0)
    w2.abort()
    assert not list(tmp_path.glob("*x" + name + "*"))


@pytest.mark.parametrize("kind", ["increments", "rates"])
def test_a_float32_time_is_refused_by_the_imu_reader_too(tmp_path, kind):
    """The solution reader refused a float32 time_s; the IMU reader took it.  At t = 1e5 s float32 steps by
    7.8 ms, so a 100 Hz log read as 7.8 and 15.6 ms steps: allan said 'not regularly sampled', align 'static
    for only 0.0 s ... accelerometer std 1.63 m/s^2'.  The float64 file of the same log reads."""
    import pyarrow as pa

    n = 500
    t = 1e5 + 0.01 * np.arange(n)
    if kind == "increments":
        cols = {"time_s": t, **{f"dtheta_{a}_rad": np.zeros(n) for a in "xyz"},
                "dv_x_m_s": np.zeros(n), "dv_y_m_s": np.zeros(n), "dv_z_m_s": np.r_[0.0, np.full(n - 1, -0.098)]}
    else:
        cols = {"time_s": t, **{f"gyro_{a}_rad_s": np.full(n, 1e-4) for a in "xyz"},
                "accel_x_m_s2": np.zeros(n), "accel_y_m_s2": np.zeros(n), "accel_z_m_s2": np.full(n, -9.8)}
    for name, wide in (("f64.parquet", True), ("f32.parquet", False)):
        table = pa.table({k: pa.array(v, type=pa.float32() if (k == "time_s" and not wide) else pa.float64())
                          for k, v in cols.items()})
        pq.write_table(table, tmp_path / name)
    assert len(io.read_imu(tmp_path / "f64.parquet")) == n
    with pytest.raises(InputError, match=r"f32\.parquet: column 'time_s' holds float; expected float64"):
        io.read_imu(tmp_path / "f32.parquet")


def test_a_float32_truth_is_refused_when_only_its_head_is_read(tmp_path):
    """mechanize --init-from reads the head of a truth (read_solution(until_s=...)), which took the float32
    time and latitude that evaluate refuses for the same file."""
    import pyarrow as pa

    cols = P.solution_columns(solution(n=50))
    table = pa.table({k: pa.array(v, type=pa.float32() if k == "lat_deg" else pa.float64()) for k, v in cols.items()})
    pq.write_table(table, tmp_path / "truth.parquet")
    with pytest.raises(InputError, match=r"truth\.parquet: column 'lat_deg' holds float; expected float64"):
        io.read_solution(tmp_path / "truth.parquet", until_s=float(cols["time_s"][3]))


def test_a_parquet_schema_naming_a_column_twice_is_refused_by_every_reader(tmp_path):
    """pyarrow writes a schema with two 'lat_deg' fields; evaluate said 'not a readable Parquet file (Multiple
    matches for FieldRef.Name(lat_deg) in time_s: double)', mechanize --init-from (the head reader) failed
    with an internal KeyError (exit 3).  Refused as a CSV header naming a column twice is."""
    import pyarrow as pa

    cols = P.solution_columns(solution(n=50))
    names = list(cols) + ["lat_deg"]
    arrays = [pa.array(v) for v in cols.values()] + [pa.array(cols["lat_deg"] + 1.0)]
    pq.write_table(pa.table(arrays, names=names), tmp_path / "truth.parquet")
    k = names.index("lat_deg") + 1
    msg = rf"truth\.parquet: the Parquet schema names column 'lat_deg' twice \(columns {k} and {len(names)}\)"
    with pytest.raises(InputError, match=msg):
        io.read_solution(tmp_path / "truth.parquet")
    with pytest.raises(InputError, match=msg):
        io.read_solution(tmp_path / "truth.parquet", until_s=float(cols["time_s"][3]))
    n = 20
    imu = {"time_s": 0.01 * np.arange(n), **{f"dtheta_{a}_rad": np.zeros(n) for a in "xyz"},
           **{f"dv_{a}_m_s": np.zeros(n) for a in "xyz"}}
    pq.write_table(pa.table([pa.array(v) for v in imu.values()] + [pa.array(np.zeros(n))],
                            names=list(imu) + ["dv_z_m_s"]), tmp_path / "imu.parquet")
    with pytest.raises(InputError, match=r"imu\.parquet: the Parquet schema names column 'dv_z_m_s' twice"):
        io.read_imu(tmp_path / "imu.parquet")


# --- corrupt, truncated and damaged files: refused with the file and what to do, never read as other numbers ---

def _imu(n=6000):
    """A still IMU at 45 deg latitude, 100 Hz (plausible to every check of read_imu)."""
    from inskit.simulation import StationaryTrajectory, ideal_imu

    traj = StationaryTrajectory((np.radians(45), 0.1, 50.0), (0.0, 0.0, 0.5))
    return traj, ideal_imu(traj, 0.01 * np.arange(n), nodes=1)


def _flip_in_data_page(path, column):
    """Invert 4 bytes in the middle of ``column``'s data page (its column chunk in row group 0, located by
    the file's own metadata), as a disk or a copy would; the bytes it held before."""
    md = pq.ParquetFile(path).metadata
    j = md.schema.names.index(column)
    cc = md.row_group(0).column(j)
    assert cc.dictionary_page_offset is None  # inskit's writers: no dictionary, the chunk is its data pages
    mid = cc.data_page_offset + cc.total_compressed_size // 2
    raw = bytearray(path.read_bytes())
    before = bytes(raw[mid:mid + 4])
    raw[mid:mid + 4] = bytes(b ^ 0xFF for b in before)
    path.write_bytes(bytes(raw))
    return before


CORRUPT = r"corrupt Parquet file: checksum mismatch in a data page .*write it again, or copy it again from its source"


@pytest.mark.parametrize("kind", ["imu", "imu-table", "solution", "solution-head", "solution-streamed",
                                  "columns"])
def test_a_byte_changed_in_a_data_page_is_refused_by_every_reader(tmp_path, kind):
    """A byte flipped in a data page was read as other numbers, silently (the page's zstd still decoded);
    now every writer stores each page's CRC-32 and every reader checks it: an InputError naming the file."""
    from inskit.io.csv_formats import read_table

    p = tmp_path / "f.parquet"
    if kind.startswith("imu"):
        io.write_imu(p, _imu()[1])
        column = "dv_z_m_s"
        read = io.read_imu if kind == "imu" else read_table  # the streaming reader, the whole-table reader
    else:
        sol = solution()
        if kind == "solution-streamed":
            stream = P.SolutionStream(p)
            stream.write(sol.slice(0, 1000), 0)
            stream.write(sol.slice(1000), 1000)
            stream.commit()
        else:
            io.write_solution(p, sol)
        column = "lat_deg"
        read = {"solution-head": lambda q: io.read_solution(q, until_s=float(sol.time[5])),
                "columns": P.read_parquet_columns}.get(kind, io.read_solution)
    whole = pq.read_table(p)
    _flip_in_data_page(p, column)
    try:  # what a reader that does not check read: other numbers, no error
        assert not pq.read_table(p).equals(whole)
    except OSError:
        pass
    with pytest.raises(InputError, match=r"f\.parquet: " + CORRUPT) as e:
        read(p)
    assert "Traceback" not in str(e.value) and len(str(e.value).splitlines()) == 1


def test_an_imu_log_round_trips_exactly_with_its_checksums(tmp_path):
    _, imu = _imu()
    p = io.write_imu(tmp_path / "imu.parquet", imu)
    back = io.read_imu(p)
    np.testing.assert_array_equal(back.time, imu.time)
    np.testing.assert_array_equal(back.dtheta_b, imu.dtheta_b)
    np.testing.assert_array_equal(back.dv_b, imu.dv_b)
    # and the checksums are there: a reader that checks them passes the file, one flipped byte does not
    pq.read_table(p, page_checksum_verification=True)
    _flip_in_data_page(p, "time_s")
    with pytest.raises(OSError, match="CRC checksum verification failed"):
        pq.read_table(p, page_checksum_verification=True)


def test_a_file_without_checksums_is_still_read(tmp_path):
    """Other software writes no page checksums (pyarrow's default): nothing to check, the file is read."""
    sol = solution(n=300)
    cols = P.solution_columns(sol)
    import pyarrow as pa

    pq.write_table(pa.table(cols), tmp_path / "other.parquet", write_page_checksum=False)
    back = io.read_solution(tmp_path / "other.parquet")
    np.testing.assert_array_equal(back.time, sol.time)
    got, _ = P.read_parquet_columns(tmp_path / "other.parquet")
    for k, v in cols.items():
        np.testing.assert_array_equal(got[k], v)


def _cut(raw, how):
    footer = int.from_bytes(raw[-8:-4], "little")
    if how == "half":
        return raw[:len(raw) // 2]
    if how == "last-byte":
        return raw[:-1]
    b = bytearray(raw)
    if how == "footer-length":
        b[-7] ^= 0xFF
    else:  # bytes in the middle of the footer (the schema, the column metadata)
        mid = len(raw) - 8 - footer // 2
        b[mid:mid + 8] = b"\xff" * 8
    return bytes(b)


@pytest.mark.parametrize("how, want", [
    ("half", r"not a readable Parquet file: truncated \(it starts as Parquet but its end, the footer with the "
             r"schema, is missing"),
    ("last-byte", r"not a readable Parquet file: truncated"),
    ("footer-length", r"not a readable Parquet file: its footer \(the schema and column metadata\) is damaged"),
    ("footer-middle", r"not a readable Parquet file: its footer \(the schema and column metadata\) is damaged"),
])
def test_a_truncated_file_or_a_damaged_footer_says_so(tmp_path, how, want):
    p = io.write_solution(tmp_path / "s.parquet", solution(n=300))
    p.write_bytes(_cut(p.read_bytes(), how))
    for read in (io.read_solution, lambda q: io.read_solution(q, until_s=243262.0), P.read_parquet_columns,
                 P.read_metadata, io.read_imu):
        with pytest.raises(InputError, match=r"s\.parquet: " + want + r".*write it again, or copy it again"):
            read(p)


def test_a_damaged_page_header_is_refused_as_corrupt(tmp_path):
    """The checksum covers a page's data, not its header: a header that does not decode is corrupt too."""
    p = io.write_solution(tmp_path / "s.parquet", solution(n=300))
    cc = pq.ParquetFile(p).metadata.row_group(0).column(1)
    raw = bytearray(p.read_bytes())
    raw[cc.data_page_offset] ^= 0xFF
    p.write_bytes(bytes(raw))
    with pytest.raises(InputError, match=r"s\.parquet: corrupt Parquet file: a data page does not decode"):
        io.read_solution(p)


def _main(capsys, *args):
    """``inskit ARGS`` in process: (exit code, stderr)."""
    code, _, err = in_process(capsys, *args)
    return code, err


def test_the_cli_refuses_a_corrupt_parquet_input_with_one_line(tmp_path, capsys):
    """mechanize (a Parquet IMU log, read streaming) and evaluate (a Parquet solution): exit 2, one line
    naming the file and what to do, no traceback; the same files whole are read."""
    from inskit.simulation import truth_solution

    traj, imu = _imu()
    io.write_imu(tmp_path / "imu.parquet", imu)
    io.write_solution(tmp_path / "truth.parquet", truth_solution(traj, imu.time))
    code, err = _main(capsys, "mechanize", tmp_path / "imu.parquet", "--init-from", tmp_path / "truth.parquet",
                      "--out", tmp_path / "nav.parquet")
    assert code == 0, err
    code, err = _main(capsys, "evaluate", tmp_path / "nav.parquet", tmp_path / "truth.parquet", "--json")
    assert code == 0, err

    _flip_in_data_page(tmp_path / "imu.parquet", "dtheta_y_rad")
    code, err = _main(capsys, "mechanize", tmp_path / "imu.parquet", "--init-from", tmp_path / "truth.parquet",
                      "--out", tmp_path / "nav2.parquet")
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert re.search(r"imu\.parquet: " + CORRUPT, err), err
    assert not (tmp_path / "nav2.parquet").exists()

    _flip_in_data_page(tmp_path / "nav.parquet", "yaw_deg")
    code, err = _main(capsys, "evaluate", tmp_path / "nav.parquet", tmp_path / "truth.parquet")
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert re.search(r"nav\.parquet: " + CORRUPT, err), err
