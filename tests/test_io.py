"""Every reader validation of issue 2 item 5 has a test here."""

import numpy as np
import pytest

from inskit import io
from inskit.errors import InputError
from inskit.simulation import StationaryTrajectory, ideal_imu, truth_solution
from inskit.units import DEG, G0

HEADER_RATES = "time_s,gyro_x_deg_s,gyro_y_deg_s,gyro_z_deg_s,accel_x_g,accel_y_g,accel_z_g\n"


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


def static_rows(n=5, dt=0.01, gyro=0.01, acc_z=-1.0):
    return "".join(f"{k * dt:.2f},{gyro},0,0,0,0,{acc_z}\n" for k in range(n))


def test_read_imu_rates_in_degrees_and_g(tmp_path):
    p = write(tmp_path, "imu.csv", HEADER_RATES + static_rows())
    imu = io.read_imu(p)
    assert len(imu) == 5
    gyro, acc = imu.rates()
    assert np.allclose(gyro[1:, 0], 0.01 * DEG)
    assert np.allclose(acc[1:, 2], -G0)


def test_imu_round_trip_increments(tmp_path):
    traj = StationaryTrajectory((0.7, 0.1, 10.0), (0.1, 0.2, 0.3))
    imu = ideal_imu(traj, np.arange(0, 1, 0.01), nodes=1)
    io.write_imu(tmp_path / "inc.csv", imu)
    back = io.read_imu(tmp_path / "inc.csv")
    # 17 significant digits are written; pandas' fast float parser (3x faster than its exact one) is
    # within 1e-13 relative, seven orders below any IMU's quantisation
    np.testing.assert_allclose(back.dtheta_b, imu.dtheta_b, rtol=1e-13, atol=0)
    np.testing.assert_allclose(back.dv_b, imu.dv_b, rtol=1e-13, atol=0)


def test_missing_column(tmp_path):
    p = write(tmp_path, "imu.csv", "time_s,gyro_x_deg_s,gyro_y_deg_s,accel_x_g,accel_y_g,accel_z_g\n0,0,0,0,0,1\n")
    with pytest.raises(InputError, match=r"imu\.csv: no complete set of IMU columns.*gyro_"):
        io.read_imu(p)
    p = write(tmp_path, "nt.csv", "t,gyro_x_deg_s\n0,1\n")
    with pytest.raises(InputError, match=r"nt\.csv: missing column\(s\) time_s"):
        io.read_imu(p)


def test_nan_names_line_and_column(tmp_path):
    rows = static_rows().splitlines(True)
    rows[2] = "0.02,0.01,,0,0,0,-1.0\n"
    p = write(tmp_path, "imu.csv", HEADER_RATES + "".join(rows))
    with pytest.raises(InputError, match=r"imu\.csv: line 4: column 'gyro_y_deg_s' is empty"):
        io.read_imu(p)
    rows[2] = "0.02,0.01,nan,0,0,0,-1.0\n"
    p = write(tmp_path, "imu.csv", HEADER_RATES + "".join(rows))
    with pytest.raises(InputError, match=r"line 4: column 'gyro_y_deg_s'"):
        io.read_imu(p)
    rows[2] = "0.02,0.01,abc,0,0,0,-1.0\n"
    p = write(tmp_path, "imu.csv", HEADER_RATES + "".join(rows))
    with pytest.raises(InputError, match=r"line 4: column 'gyro_y_deg_s' has 'abc'"):
        io.read_imu(p)


def test_duplicate_and_backward_timestamps(tmp_path):
    rows = static_rows().splitlines(True)
    dup = rows.copy()
    dup[3] = dup[2]
    p = write(tmp_path, "imu.csv", HEADER_RATES + "".join(dup))
    with pytest.raises(InputError, match=r"imu\.csv: line 5: duplicate timestamp"):
        io.read_imu(p)
    back = rows.copy()
    back[3] = "0.01,0.01,0,0,0,0,-1.0\n"
    p = write(tmp_path, "imu.csv", HEADER_RATES + "".join(back))
    with pytest.raises(InputError, match=r"imu\.csv: line 5: time_s=0\.01 goes back in time"):
        io.read_imu(p)


def test_wrong_units_betrayed_by_magnitude(tmp_path):
    # accelerations in g written under an m/s^2 header
    hdr = "time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n"
    p = write(tmp_path, "a.csv", hdr + static_rows(gyro=0.0))
    with pytest.raises(InputError, match=r"a\.csv: column 'accel_x_m_s2'.*looks like values in g"):
        io.read_imu(p)
    # m/s^2 under a g header
    p = write(tmp_path, "b.csv", HEADER_RATES + static_rows(acc_z=-9.81))
    with pytest.raises(InputError, match=r"looks like values in m/s\^2"):
        io.read_imu(p)
    # deg/s values under a rad/s header (a car turning at 30 deg/s)
    p = write(tmp_path, "c.csv", hdr + static_rows(gyro=30.0, acc_z=-9.81))
    with pytest.raises(InputError, match=r"c\.csv: column 'gyro_x_rad_s'.*looks like values in deg/s"):
        io.read_imu(p)
    # the check can be turned off, and correct units pass
    assert len(io.read_imu(p, check_units=False)) == 5
    p = write(tmp_path, "d.csv", hdr + static_rows(gyro=0.3, acc_z=-9.81))
    assert len(io.read_imu(p)) == 5


def test_empty_and_missing_files(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        io.read_imu(tmp_path / "nope.csv")
    with pytest.raises(InputError, match="empty"):
        io.read_imu(write(tmp_path, "e.csv", ""))
    with pytest.raises(InputError, match="no data rows"):
        io.read_imu(write(tmp_path, "h.csv", HEADER_RATES))


GNSS_HDR = "time_s,lat_deg,lon_deg,height_m,sigma_n_m,sigma_e_m,sigma_d_m\n"


def test_gnss_reader(tmp_path):
    p = write(tmp_path, "g.csv", GNSS_HDR + "0,40.1,-105.1,1600,0.01,0.01,0.02\n1,40.1,-105.1,1600,0.01,0.01,0.02\n")
    g = io.read_gnss(p)
    assert np.allclose(g.lla[0, :2], np.radians([40.1, -105.1]))
    assert not g.has_velocity
    io.write_gnss(tmp_path / "g2.csv", g)
    assert np.allclose(io.read_gnss(tmp_path / "g2.csv").lla, g.lla)


def test_gnss_bad_sigma_latitude_and_partial_velocity(tmp_path):
    p = write(tmp_path, "g.csv", GNSS_HDR + "0,40.1,-105.1,1600,0.01,0,0.02\n")
    with pytest.raises(InputError, match=r"g\.csv: line 2: column 'sigma_e_m' is 0\.0; sigmas must be > 0"):
        io.read_gnss(p)
    p = write(tmp_path, "g.csv", GNSS_HDR + "0,40.1,-105.1,1600,-1,0.1,0.02\n")
    with pytest.raises(InputError, match="sigmas must be > 0"):
        io.read_gnss(p)
    p = write(tmp_path, "g.csv", GNSS_HDR + "0,140.1,-105.1,1600,0.01,0.01,0.02\n")
    with pytest.raises(InputError, match=r"line 2: lat_deg=140\.1 is outside"):
        io.read_gnss(p)
    p = write(tmp_path, "g.csv", GNSS_HDR.strip() + ",vn_m_s\n0,40.1,-105.1,1600,0.01,0.01,0.02,1\n")
    with pytest.raises(InputError, match="velocity needs all six"):
        io.read_gnss(p)


def test_solution_round_trip_and_no_overwrite(tmp_path):
    traj = StationaryTrajectory((0.7, 0.1, 10.0), (0.1, 0.2, 0.3))
    sol = truth_solution(traj, np.arange(0, 1, 0.1))
    io.write_solution(tmp_path / "s.csv", sol)
    back = io.read_solution(tmp_path / "s.csv")
    assert np.allclose(back.lla, sol.lla, atol=1e-14)
    assert np.allclose(back.euler, sol.euler, atol=1e-13)
    with pytest.raises(InputError, match="already exists"):
        io.write_solution(tmp_path / "s.csv", sol)
    io.write_solution(tmp_path / "s.csv", sol, overwrite=True)


def test_solution_missing_columns(tmp_path):
    p = write(tmp_path, "s.csv", "time_s,lat_deg,lon_deg\n0,1,2\n")
    with pytest.raises(InputError, match=r"s\.csv: missing column\(s\) height_m, vn_m_s"):
        io.read_solution(p)


def test_gzip_data_is_read_whatever_the_name(tmp_path):
    import gzip

    from inskit.simulation import StationaryTrajectory, ideal_imu

    imu = ideal_imu(StationaryTrajectory((0.7, 0.1, 10.0)), np.arange(0.0, 1.0, 0.01), nodes=1)
    plain = tmp_path / "imu.csv"
    io.write_imu(plain, imu)
    disguised = tmp_path / "imu_gz.csv"
    disguised.write_bytes(gzip.compress(plain.read_bytes()))
    back = io.read_imu(disguised)
    assert np.allclose(back.dv_b, imu.dv_b)


def test_semicolon_separated_file_gets_a_hint(tmp_path):
    f = tmp_path / "g.csv"
    f.write_text("time_s;lat_deg;lon_deg\n0;1;2\n")
    with pytest.raises(InputError, match="separated by ';'"):
        io.read_gnss(f)


RAD_HDR = "time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2"


def _write_rates(path, t, w, f):
    np.savetxt(path, np.column_stack([t, w, f]), delimiter=",", header=RAD_HDR, comments="", fmt="%.9g")
    return path


def test_deg_s_under_rad_s_caught_by_a_short_turn(tmp_path):
    """Issue 12 item 10: 300 s at rest, then a 1.5 s turn at 30 deg/s, the gyro written in deg/s under a rad/s
    header.  The turn is 0.5 % of the samples, so neither the 99th percentile nor the median betrays it; 50
    consecutive samples at a median of 30 'rad/s' (1700 deg/s, beyond any vehicle) do."""
    t = np.arange(0.0, 301.5, 0.01)
    w_deg_s = np.tile([0.003, -0.001, 0.002], (len(t), 1))  # static: the Earth rate in deg/s
    w_deg_s[t > 300.0, 2] += 30.0
    f = np.tile([0.0, 0.0, -9.81], (len(t), 1))
    p = _write_rates(tmp_path / "turn.csv", t, w_deg_s, f)
    wn = np.linalg.norm(w_deg_s, axis=1)
    assert np.percentile(wn, 99) < 10.0 and np.median(wn) < 1.0  # the old rules see nothing
    with pytest.raises(InputError, match=r"turn\.csv: column 'gyro_x_rad_s': 50 consecutive samples \(near line "
                                         r"\d+\) turn at a median 30\.0 rad/s .*looks like values in deg/s"):
        io.read_imu(p)
    assert len(io.read_imu(p, check_units=False)) == len(t)
    # the same log in the right unit passes
    p = _write_rates(tmp_path / "turn_ok.csv", t, w_deg_s * DEG, f)
    assert len(io.read_imu(p)) == len(t)


def test_deg_s_under_rad_s_on_a_static_log_is_not_detectable_by_the_reader(tmp_path):
    """The documented limit: at rest, a tactical gyro's deg/s values read as rad/s are 57 x (Earth rate + bias)
    ~ 0.004 rad/s, the size of a calibrated MEMS bias in true rad/s; the reader accepts the file (inskit align,
    which knows the latitude, refuses it: tests/test_alignment_static.py)."""
    lat = np.radians(45.0)
    t = np.arange(0.0, 60.0, 0.01)
    ideal = ideal_imu(StationaryTrajectory((lat, 0.0, 0.0), (0.0, 0.0, 0.5)), t, nodes=1)
    w, f = ideal.rates()
    p = _write_rates(tmp_path / "static.csv", t[1:], w[1:] / DEG, f[1:])
    imu = io.read_imu(p)
    wm = imu.rates()[0][1:].mean(axis=0)
    assert np.linalg.norm(wm) / 7.292115e-5 == pytest.approx(1.0 / DEG, rel=1e-3)


def test_an_infinite_cell_is_named_without_numpy_repr(tmp_path):
    rows = static_rows().splitlines(True)
    rows[2] = "0.02,inf,0,0,0,0,-1.0\n"
    p = write(tmp_path, "imu.csv", HEADER_RATES + "".join(rows))
    with pytest.raises(InputError, match=r"line 4: column 'gyro_x_deg_s' has inf; expected a finite number") as exc:
        io.read_imu(p)
    assert "np." not in str(exc.value)


def test_read_speed_reads_and_refuses_kmh_and_time_going_back(tmp_path):
    p = write(tmp_path, "odo.csv", "time_s,speed_m_s\n0.0,0.0\n0.1,12.5\n0.2,-1.0\n")
    t, v = io.read_speed(p)
    assert t.tolist() == [0.0, 0.1, 0.2] and v.tolist() == [0.0, 12.5, -1.0]
    p = write(tmp_path, "kmh.csv", "time_s,speed_m_s\n0.0,0.0\n0.1,160.0\n")
    with pytest.raises(InputError, match=r"kmh\.csv: line 3: column 'speed_m_s' holds 160\.0, above 150 m/s"):
        io.read_speed(p)
    p = write(tmp_path, "back.csv", "time_s,speed_m_s\n0.0,0.0\n-0.1,1.0\n")
    with pytest.raises(InputError, match=r"back\.csv"):
        io.read_speed(p)
    p = write(tmp_path, "cols.csv", "time_s,v\n0.0,0.0\n")
    with pytest.raises(InputError, match=r"cols\.csv.*speed_m_s"):
        io.read_speed(p)


def test_read_height_with_and_without_sigma_and_its_bad_inputs(tmp_path):
    t, h, s = io.read_height(write(tmp_path, "baro.csv", "time_s,height_m\n0.0,301.5\n0.1,301.7\n"))
    assert t.tolist() == [0.0, 0.1] and h.tolist() == [301.5, 301.7] and s is None
    t, h, s = io.read_height(write(tmp_path, "prof.csv", "time_s,height_m,sigma_m\n0.0,-12.0,0.3\n1.0,-11.0,0.4\n"))
    assert h.tolist() == [-12.0, -11.0] and s.tolist() == [0.3, 0.4]
    with pytest.raises(InputError, match=r"pa\.csv: line 3: column 'height_m' holds 101325\.0, beyond 100 km: a "
                                         r"pressure"):
        io.read_height(write(tmp_path, "pa.csv", "time_s,height_m\n0.0,300.0\n0.1,101325.0\n"))
    with pytest.raises(InputError, match=r"sig\.csv: line 2: column 'sigma_m' is 0\.0; sigmas must be > 0"):
        io.read_height(write(tmp_path, "sig.csv", "time_s,height_m,sigma_m\n0.0,300.0,0.0\n"))
    with pytest.raises(InputError, match=r"cols\.csv: missing column\(s\) height_m \(a height log"):
        io.read_height(write(tmp_path, "cols.csv", "time_s,alt_m\n0.0,300.0\n"))
    with pytest.raises(InputError, match=r"dup\.csv: line 3: duplicate timestamp"):
        io.read_height(write(tmp_path, "dup.csv", "time_s,height_m\n0.0,300.0\n0.0,300.0\n"))
    with pytest.raises(InputError, match=r"nan\.csv: line 2: column 'height_m' has 'nan'; expected a finite number"):
        io.read_height(write(tmp_path, "nan.csv", "time_s,height_m\n0.0,nan\n"))


# --- issue 14 item 11: the first row of an increment file -------------------------------------------------------
INC_HDR = "time_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_m_s,dv_y_m_s,dv_z_m_s"


def _level_at_rest(dt=0.01, duration=1.0):
    """Ideal increments of a level IMU at rest at 45 deg (row 0 the initial epoch, zero) and the truth."""
    traj = StationaryTrajectory((np.radians(45.0), 0.1, 10.0), (0.0, 0.0, 0.3))
    t = np.arange(0.0, duration + dt / 2, dt)
    return ideal_imu(traj, t, nodes=1), truth_solution(traj, t)


def _write_increments(path, t, dth, dv):
    np.savetxt(path, np.column_stack([t, dth, dv]), delimiter=",", header=INC_HDR, comments="", fmt="%.17g")
    return path


def test_an_increment_file_without_its_initial_row_is_refused(tmp_path):
    """Row 0 of an increment file is the initial epoch and its increments are unused, so a file that starts with a
    real increment would silently lose it: refused, naming the file, the line and what to say instead."""
    imu, _ = _level_at_rest()
    p = _write_increments(tmp_path / "no_initial.csv", imu.time[1:], imu.dtheta_b[1:], imu.dv_b[1:])
    with pytest.raises(InputError, match=r"no_initial\.csv: line 2 \(the first data row\) holds increments "
                                         r"\(.*dv_z_m_s=-0\.098.*\).*lack that row.*first_row=\"increment\".*"
                                         r"first_row=\"discard\".*\[imu\] first_row.*--first-row"):
        io.read_imu(p)
    # the file with its initial row (zeros, as write_imu writes it) is read as before
    io.write_imu(tmp_path / "with_initial.csv", imu)
    back = io.read_imu(tmp_path / "with_initial.csv")
    assert len(back) == len(imu) and not back.dtheta_b[0].any() and not back.dv_b[0].any()


def test_first_row_increment_keeps_every_interval_and_discard_loses_one(tmp_path):
    """A file of real increments from the start of its first interval, t0, whose time is not in the file.
    first_row="increment" puts the initial epoch one median interval before the first row, at t0: free-inertial
    navigation from the truth at t0 stays at rest (the ideal increments leave only integration error).
    "discard" drops the first increment: its first row (at t0 + dt) becomes the initial epoch, and a state at t0
    is refused (the interval before that row would be integrated with no specific force, free fall: the velocity
    was off by the lost gravity compensation, g * dt = 0.098 m/s at 100 Hz); the state must be the row's own."""
    from inskit.strapdown import mechanize

    dt = 0.01
    imu, truth = _level_at_rest(dt)
    p = _write_increments(tmp_path / "no_initial.csv", imu.time[1:], imu.dtheta_b[1:], imu.dv_b[1:])
    inc = io.read_imu(p, first_row="increment")
    assert len(inc) == len(imu)
    assert inc.time[0] == pytest.approx(imu.time[0], abs=1e-12)  # one median interval before the first row
    assert not inc.dtheta_b[0].any() and not inc.dv_b[0].any()
    np.testing.assert_allclose(inc.dv_b[1:], imu.dv_b[1:], rtol=1e-13)  # pandas' fast parser: 1e-13
    start = truth.state(0)
    assert np.abs(mechanize(inc, start).v_n[-1]).max() < 1e-6
    dis = io.read_imu(p, first_row="discard")
    assert len(dis) == len(imu) - 1 and dis.time[0] == imu.time[1] and not dis.dv_b[0].any()
    with pytest.raises(InputError, match=r"whose increments are all zero: an initial epoch"):
        mechanize(dis, start)
    assert np.abs(mechanize(dis, truth.state(1)).v_n[-1]).max() < 1e-6


def test_first_row_increment_refuses_an_initial_row_and_a_single_row(tmp_path):
    imu, _ = _level_at_rest()
    io.write_imu(tmp_path / "with_initial.csv", imu)
    with pytest.raises(InputError, match=r"with_initial\.csv: line 2 \(the first data row\) holds zero increments: "
                                         r"it is the initial epoch.*first_row=\"initial\""):
        io.read_imu(tmp_path / "with_initial.csv", first_row="increment")
    one = _write_increments(tmp_path / "one.csv", imu.time[1:2], imu.dtheta_b[1:2], imu.dv_b[1:2])
    with pytest.raises(InputError, match=r"one\.csv: first_row=\"increment\" needs at least two rows"):
        io.read_imu(one, first_row="increment")
    with pytest.raises(InputError, match=r"`first_row` must be one of 'initial', 'increment', 'discard'"):
        io.read_imu(tmp_path / "with_initial.csv", first_row="first")


def test_first_row_empty_tolerance_and_rate_files(tmp_path):
    """A first row a billionth of the typical increment is empty (a writer's rounding), one a millionth of it is
    not; first_row describes increment files, not rates."""
    imu, _ = _level_at_rest()
    d = imu.dv_b.copy()
    d[0] = imu.dv_b[1] * 1e-10
    assert len(io.read_imu(_write_increments(tmp_path / "tiny.csv", imu.time, imu.dtheta_b, d))) == len(imu)
    d[0] = imu.dv_b[1] * 1e-6
    with pytest.raises(InputError, match=r"small\.csv: line 2"):
        io.read_imu(_write_increments(tmp_path / "small.csv", imu.time, imu.dtheta_b, d))
    p = write(tmp_path, "rates.csv", HEADER_RATES + static_rows())
    with pytest.raises(InputError, match=r"rates\.csv: first_row='increment' applies to increment files"):
        io.read_imu(p, first_row="increment")


def test_write_imu_writes_the_initial_epoch(tmp_path):
    """ImuData.from_rates puts rate x step in row 0; the file format's row 0 is the initial epoch, so write_imu
    writes zeros there and the file reads back under the default rule, every later row unchanged."""
    from inskit.types import ImuData

    t = np.arange(0.0, 1.0, 0.01)
    imu = ImuData.from_rates(t, np.tile([0.01, 0.0, 0.0], (len(t), 1)), np.tile([0.0, 0.0, -G0], (len(t), 1)))
    assert imu.dv_b[0].any()
    io.write_imu(tmp_path / "r.csv", imu)
    back = io.read_imu(tmp_path / "r.csv")
    assert not back.dv_b[0].any()
    np.testing.assert_allclose(back.dv_b[1:], imu.dv_b[1:], rtol=1e-13)


def test_a_parquet_column_that_is_not_a_number_is_refused(tmp_path):
    """A timestamp time column would otherwise be read as microseconds."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    n = 5
    cols = {"time_s": pa.array(np.arange(n) * 10_000, pa.timestamp("us"))}
    for c in ("dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad", "dv_x_m_s", "dv_y_m_s", "dv_z_m_s"):
        cols[c] = pa.array(np.zeros(n))
    p = tmp_path / "imu.parquet"
    pq.write_table(pa.table(cols), p)
    with pytest.raises(InputError, match=r"imu\.parquet: column 'time_s' is of type timestamp\[us\]; expected numbers"):
        io.read_imu(p)
