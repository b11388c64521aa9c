"""RTKLIB ``.pos`` files as users hand them over: gzip whatever the name, a byte-order mark, a truncated
download (:func:`inskit.io.rtklib.read_pos`)."""

import gzip
import re
from pathlib import Path

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.io.rtklib import read_pos

DRIVE_POS = Path(__file__).resolve().parents[1] / "data" / "drive_0708" / "gnss_1934_sf.pos.gz"


def test_gzip_is_told_by_content_and_a_bom_is_dropped(tmp_path):
    ref, week = read_pos(DRIVE_POS)
    text = gzip.decompress(DRIVE_POS.read_bytes())
    cases = {"gz_named.pos": DRIVE_POS.read_bytes(),          # gzip under a plain name
             "plain_named.pos.gz": text,                      # plain text under a .gz name
             "bom.pos": b"\xef\xbb\xbf" + text,               # Windows editors
             "bom_crlf.pos.gz": gzip.compress(b"\xef\xbb\xbf" + text.replace(b"\n", b"\r\n"))}
    for name, data in cases.items():
        p = tmp_path / name
        p.write_bytes(data)
        g, w = read_pos(p)
        assert w == week and np.array_equal(g.time, ref.time) and np.array_equal(g.lla, ref.lla), name


def test_a_truncated_gzip_pos_names_the_file(tmp_path):
    """It was an EOFError, which the command line showed as 'inskit: aborted' (exit 130)."""
    data = DRIVE_POS.read_bytes()
    p = tmp_path / "cut.pos.gz"
    p.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match=r"cut\.pos\.gz: a damaged gzip file: .* \(cut short"):
        read_pos(p)


@pytest.mark.parametrize("fault, needle", [
    ("utf-16", r"is UTF-16 text \(it starts with the byte-order mark FF FE\).*save it as UTF-8"),
    ("utf-16-le", r"is UTF-16 text without a byte-order mark"),
    ("nul", r"line 4 holds NUL \(zero\) bytes, which no text holds: not a text file, or one damaged in writing"),
    ("corrupt gzip", r"a damaged gzip file: its data is corrupt"),
])
@pytest.mark.parametrize("reader", ["read_pos", "read_gnss"])
def test_a_pos_file_that_is_no_utf8_text_is_named_as_such(tmp_path, fault, needle, reader):
    """Saved as UTF-16, it was 'no '%  GPST latitude(deg) ...' column header line: not an RTKLIB .pos file'
    (read_pos) or 'not a readable CSV file ('utf-8' codec can't decode byte 0xff ...)' (read_gnss); a corrupt
    gzip file was zlib's 'Error -3 while decompressing data' (an internal error); NUL bytes in a number
    were refused with the cell's NULs shown (read_pos) or as CSV (read_gnss)."""
    from inskit.io import read_gnss

    text = gzip.decompress(DRIVE_POS.read_bytes()).decode()
    if fault == "nul":
        lines = text.splitlines(True)
        lines[3] = lines[3][:40] + "\0" * 30 + lines[3][40:]
        data = "".join(lines).encode()
    elif fault == "corrupt gzip":
        raw = DRIVE_POS.read_bytes()
        data = raw[:20] + bytes(b ^ 0xA5 for b in raw[20:2000]) + raw[2000:]
    else:
        data = text.encode(fault)
    p = tmp_path / "sol.pos"
    p.write_bytes(data)
    read = read_pos if reader == "read_pos" else read_gnss
    with pytest.raises(InputError, match=r"sol\.pos: " + needle):
        read(p)


def _as_form(line, form):
    """A blank-separated calendar row of a .pos file as RTKLIB writes it with out-timeform = tow or
    out-fieldsep = ','."""
    from inskit.io.rtklib import gps_week_seconds

    f = line.split()
    if form == "tow":
        week, sow = gps_week_seconds([f"{f[0]} {f[1]}"])
        return f"{int(week[0])} {float(sow[0]):.3f} " + " ".join(f[2:]) + "\n"
    if form == "comma":
        return f"{f[0]} {f[1]}," + ",".join(f[2:]) + "\n"
    return line


@pytest.mark.parametrize("comments, form", [(0, "calendar"), (1, "calendar"), (0, "tow"), (0, "comma")])
def test_pos_rows_without_their_column_header_are_refused_saying_what_is_missing(tmp_path, comments, form):
    """Rows without the '%  GPST  latitude(deg) ...' line: read_gnss took the file for the inskit CSV
    ('missing column(s) time_s, lat_deg, ...; found 2025/07/08 19:34:18.499 40.0966268 -105.1474483 ...'),
    read_pos said 'not an RTKLIB .pos file'.  The header names the time system (UTC is 18 s from GPST), so
    the rows are not read on a guess; the message gives RTKLIB's header line for the rows' layout, and with
    it first the file reads as the original."""
    from inskit.io import read_gnss
    from inskit.io.formats import detect_gnss_format

    ref, _ = read_pos(DRIVE_POS)
    lines = gzip.decompress(DRIVE_POS.read_bytes()).decode().splitlines(True)
    assert lines[0].startswith("%") and not lines[1].startswith("%")
    rows = "".join(_as_form(line, form) for line in lines[1:])
    p = tmp_path / "rows.pos"
    p.write_text("% program   : RTKPOST ver.demo5\n" * comments + rows)
    assert detect_gnss_format(p) == "rtklib-pos"
    for read in (read_pos, read_gnss):
        with pytest.raises(InputError, match=r"rows\.pos: holds RTKLIB \.pos solution rows \('" + re.escape(
                rows[:23]) + r"' \.\.\.\) but no '%' column header line above them, "
                                             r"which names their time system .*out-outhead = on\), or, if the times "
                                             r"are GPST, put RTKLIB's header line for these 24 fields first") as exc:
            read(p)
    header = re.search(r"fields first: '([^']*)'", str(exc.value)).group(1)
    p.write_text(header + "\n" + rows)
    g, _ = read_pos(p)
    assert np.array_equal(g.time, ref.time) and np.array_equal(g.lla, ref.lla) and np.array_equal(g.v_n, ref.v_n)


def test_ecef_rows_without_their_header_get_no_guessed_header_line(tmp_path):
    """15 fields as an llh file has, but ECEF metres, not degrees: no header line is offered."""
    p = tmp_path / "xyz.pos"
    p.write_text("2374 243258.499  -1288159.1234  -4720805.5678   4079537.9012   1  21   0.0100   0.0100   0.0100"
                 "   0.0000   0.0000   0.0000   0.00    0.0\n" * 2)
    with pytest.raises(InputError, match=r"xyz\.pos: holds RTKLIB \.pos solution rows .*out-outhead = on\) "
                                         r"\('%  GPST  latitude\(deg\)  longitude\(deg\) .* \.\.\.'\)$"):
        read_pos(p)


def test_a_pos_file_cut_mid_line_is_named_as_such(tmp_path):
    """It was 'line 406: has 12 fields, the header names 24', which did not say why."""
    text = gzip.decompress(DRIVE_POS.read_bytes()).decode()
    p = tmp_path / "cut.pos"
    p.write_text(text[:text.index("\n", 20000) + 80])
    with pytest.raises(InputError, match=r"cut\.pos: line \d+: has \d+ fields, the header names 24; it is the last "
                                         r"line and has no line end: the file seems cut short"):
        read_pos(p)


@pytest.mark.parametrize("week, shown", [("2374.5", "2374.5"), ("-1", "-1")])
def test_an_imu_log_week_that_is_no_week_number_is_refused(tmp_path, week, shown):
    """gps_week 2374.5 was truncated to 2374 without a word."""
    from inskit.io.rtklib import read_rtklibexplorer_imu

    imu = Path(__file__).resolve().parents[1] / "data" / "drive_0708" / "imu_1934_gpst.csv.gz"
    lines = gzip.decompress(imu.read_bytes()).decode().splitlines(True)[:400]
    row = lines[101].split(",")
    row[0] = week
    lines[101] = ",".join(row)
    p = tmp_path / "imu.csv"
    p.write_text("".join(lines))
    with pytest.raises(InputError, match=rf"imu\.csv: line 102: gps_week={shown}; expected a whole GPS week number"):
        read_rtklibexplorer_imu(p)


def test_rows_that_repeat_the_previous_one_are_counted_and_dropped_on_request():
    """drive_0708's IMU samples at ~97.9 Hz, its logger polls at 100 Hz: 1138 rows repeat the previous
    one in all six channels, each after a short interval (8 or 9 ms). Dropped, the next sample covers
    the whole span: the times are a subset and the total integrated time is unchanged."""
    import numpy as np

    from inskit.io.rtklib import read_rtklibexplorer_imu

    path = Path(__file__).resolve().parents[1] / "data" / "drive_0708" / "imu_1934_gpst.csv.gz"
    info_k, info_d = {}, {}
    kept, _ = read_rtklibexplorer_imu(path, info=info_k)
    dropped, _ = read_rtklibexplorer_imu(path, repeated="drop", info=info_d)
    assert info_k["repeated_rows"] == info_d["repeated_rows"] == 1138  # data/drive_0708: 54860 rows
    assert not info_k["repeated_rows_dropped"] and info_d["repeated_rows_dropped"]
    assert len(kept) - len(dropped) == 1138 and np.isin(dropped.time, kept.time).all()
    assert dropped.time[-1] == kept.time[-1] and dropped.time[0] == kept.time[0]
    gaps = np.diff(kept.time)[np.isin(kept.time[1:], dropped.time, invert=True)]
    assert gaps.max() < 0.0095  # every repeat follows a short interval (a poll before the next sample)
    # the next real sample takes over the span: its increment covers both intervals
    w_rate = dropped.dtheta_b[1:] / np.diff(dropped.time)[:, None]
    assert np.all(np.abs(w_rate) < 1.0)  # rates stay rates (rad/s), no double counting
    with pytest.raises(InputError, match="repeated_rows must be one of 'keep', 'drop'"):
        read_rtklibexplorer_imu(path, repeated="merge")


def test_an_increment_file_refuses_dropping_repeated_rows(tmp_path):
    from inskit.io.csv_formats import read_imu

    p = tmp_path / "inc.csv"
    p.write_text("time_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_m_s,dv_y_m_s,dv_z_m_s\n"
                 "0,0,0,0,0,0,0\n0.01,1e-4,0,0,0,0,-0.098\n0.02,1e-4,0,0,0,0,-0.098\n")
    with pytest.raises(InputError, match=r"inc\.csv: repeated_rows = 'drop' applies to rate files"):
        read_imu(p, repeated="drop")
    assert len(read_imu(p)) == 3


def test_a_rate_file_drops_repeated_rows_and_says_how_many(tmp_path):
    from inskit.io.csv_formats import read_imu

    p = tmp_path / "rates.csv"
    rows = ["time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2"]
    vals = [(0.011, -0.002, 0.003, 0.05, -0.02, -9.81), (0.012, -0.001, 0.003, 0.04, -0.02, -9.80)]
    seq = [0, 1, 1, 0, 1]  # row 2 repeats row 1
    for k, j in enumerate(seq):
        rows.append(f"{0.01 * k:.2f}," + ",".join(map(str, vals[j])))
    p.write_text("\n".join(rows) + "\n")
    info = {}
    imu = read_imu(p, repeated="drop", info=info)
    assert info["repeated_rows"] == 1 and len(imu) == 4
    assert list(np.round(imu.time, 3)) == [0.0, 0.01, 0.03, 0.04]


def _pos_rows(n=40):
    """The header and first ``n`` rows of the drive's .pos (GPST), split into fields."""
    lines = [ln for ln in gzip.decompress(DRIVE_POS.read_bytes()).decode().splitlines() if ln.strip()]
    return lines[0], [ln.split() for ln in lines[1:n + 1]]


def _shifted(rows, seconds):
    """The rows with their calendar stamps moved by ``seconds``."""
    out = []
    for f in rows:
        t = np.datetime64(f"{f[0].replace('/', '-')}T{f[1]}", "ms") + np.timedelta64(int(seconds * 1000), "ms")
        d, c = str(t).split("T")
        out.append([d.replace("-", "/"), c] + f[2:])
    return out


def _write_pos(path, header, rows):
    path.write_text(header + "\n" + "\n".join(" ".join(f) for f in rows) + "\n")
    return path


def test_utc_stamps_take_the_leap_seconds_of_their_date(tmp_path):
    """GPS - UTC was 17 s before 2017-01-01, 18 s from then on: a UTC file across that midnight."""
    header, rows = _pos_rows(2)
    rows[0][:2], rows[1][:2] = ["2016/12/31", "23:59:58.000"], ["2017/01/01", "00:00:01.000"]
    g, _ = read_pos(_write_pos(tmp_path / "utc.pos", header.replace("GPST", "UTC "), rows))
    assert g.time[1] - g.time[0] == pytest.approx(3.0 + 1.0, abs=1e-9)  # 3 s of the clock and the leap second


def test_an_unknown_time_system_is_refused_naming_the_header_line(tmp_path):
    header, rows = _pos_rows(3)
    p = _write_pos(tmp_path / "tai.pos", header.replace("GPST", "TAI "), rows)
    with pytest.raises(InputError, match=r"tai\.pos: line 1: the header names the time system 'TAI'; expected one "
                                         r"of GPST, UTC, JST"):
        read_pos(p)


def _week_tow(rows):
    """The rows with their calendar stamps written as GPS week and seconds of week (out-timeform tow)."""
    out = []
    for f in rows:
        ms = int((np.datetime64(f"{f[0].replace('/', '-')}T{f[1]}", "ms")
                  - np.datetime64("1980-01-06T00:00:00", "ms")).astype(np.int64))
        week, sow_ms = divmod(ms, 604800 * 1000)
        out.append([f"{week:4d}", f"{sow_ms / 1000:.3f}"] + f[2:])
    return out


@pytest.mark.parametrize("tsys, shift_s, form", [("UTC", -18.0, "calendar"), ("JST", 9 * 3600.0 - 18.0, "calendar"),
                                                 ("GPST", 0.0, "tow"), ("UTC", -18.0, "tow")])
def test_time_systems_and_forms_are_read_as_gps_time(tmp_path, tsys, shift_s, form):
    """RTKLIB writes UTC or JST stamps when out-timesys says so, and names it in the column header; they
    were read as GPS time, 18 s (JST: 9 h) off, and navigate blamed the IMU's time tags.  Its out-timeform =
    tow writes '2374   243258.499' for the date and time; such a file was refused ('line with time '2374
    243258.499': expected YYYY/MM/DD HH:MM:SS.sss')."""
    header, rows = _pos_rows()
    ref, week = read_pos(_write_pos(tmp_path / "gpst.pos", header, rows))
    rows = _shifted(rows, shift_s)
    p = _write_pos(tmp_path / f"{tsys}.pos", header.replace("GPST", tsys.ljust(4)),
                   _week_tow(rows) if form == "tow" else rows)
    g, w = read_pos(p)
    assert w == week
    np.testing.assert_allclose(g.time, ref.time, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(g.lla, ref.lla)


def test_a_stamp_of_the_other_form_is_refused_naming_its_line(tmp_path):
    header, rows = _pos_rows(5)
    tow = _week_tow(rows)
    tow[3] = rows[3]  # a calendar stamp among weeks and seconds
    with pytest.raises(InputError, match=r"line 5: time '2025/07/08 19:34:19.249': expected a GPS week and seconds "
                                         r"of week \(as on the first row"):
        read_pos(_write_pos(tmp_path / "mixed.pos", header, tow))
    tow = _week_tow(rows)
    tow[2][1] = "604800.000"
    with pytest.raises(InputError, match=r"line 4: .* seconds in \[0, 604800\)"):
        read_pos(_write_pos(tmp_path / "sow.pos", header, tow))


def _dms(x):
    sign, x = ("-" if x < 0 else ""), abs(x)
    d = int(x)
    m = int((x - d) * 60)
    return [f"{sign}{d}", f"{m:02d}", f"{(x - d - m / 60) * 3600:08.5f}"]


def test_latitude_and_longitude_in_degrees_minutes_seconds_are_read(tmp_path):
    """RTKLIB's out-degform = dms writes 'latitude(d'")' over '40 05 47.85650' (three fields): such a file was
    refused ('missing column(s) latitude(deg), longitude(deg) in the header')."""
    header, rows = _pos_rows()
    ref, _ = read_pos(_write_pos(tmp_path / "deg.pos", header, rows))
    rows[0][3] = "-0.5000000"  # west of Greenwich by less than a degree: written '-0 30 00.00000'
    dms = [f[:2] + _dms(float(f[2])) + _dms(float(f[3])) + f[4:] for f in rows]
    assert dms[0][5] == "-0"
    p = _write_pos(tmp_path / "dms.pos", header.replace("latitude(deg) longitude(deg)",
                                                        "latitude(d'\") longitude(d'\")"), dms)
    g, _ = read_pos(p)
    np.testing.assert_allclose(np.degrees(g.lla[1:, :2]), np.degrees(ref.lla[1:, :2]), rtol=0, atol=1e-9)
    assert np.degrees(g.lla[0, 1]) == pytest.approx(-0.5, abs=1e-12)
    np.testing.assert_array_equal(g.sigma_ned, ref.sigma_ned)
    dms[4][3] = "61"
    with pytest.raises(InputError, match=r"line 6: column 'latitude\(d'\"\)' has '40 61 .*'; expected whole degrees, "
                                         r"then minutes and seconds in \[0, 60\)"):
        read_pos(_write_pos(tmp_path / "bad.pos", header.replace("latitude(deg) longitude(deg)",
                                                                  "latitude(d'\") longitude(d'\")"), dms))
    with pytest.raises(InputError, match=r"missing column\(s\) longitude\(d'\"\) in the header"):
        read_pos(_write_pos(tmp_path / "half.pos", header.replace("latitude(deg) longitude(deg)",
                                                                  "latitude(d'\") longitude(D'\")"), dms))


def test_ecef_positions_and_velocities_are_read_into_lat_lon_height_and_ned(tmp_path):
    """RTKLIB's out-solformat = xyz ('x-ecef(m) y-ecef(m) z-ecef(m) ... sdx(m) ... sdzx(m)', and demo5's 'vx(m/s)
    ... sdvzx'): refused before ('no '%  GPST latitude(deg) ...' header line')."""
    from inskit import earth

    header, rows = _pos_rows()
    ref, _ = read_pos(_write_pos(tmp_path / "llh.pos", header, rows))
    rng = np.random.default_rng(1)
    sig_n = np.abs(rng.normal(0.5, 0.2, (len(rows), 3))) + 0.01
    r_e = earth.lla_to_ecef(ref.lla)
    c = earth.dcm_en(ref.lla[:, 0], ref.lla[:, 1])
    q_e = np.einsum("kij,kj,klj->kil", c, sig_n ** 2, c)
    v_e = np.einsum("kij,kj->ki", c, ref.v_n)

    def sq(x):
        return np.sign(x) * np.sqrt(np.abs(x))

    out = []
    for k, f in enumerate(rows):
        q = q_e[k]
        cols = [*r_e[k], *np.sqrt(np.diag(q)), sq(q[0, 1]), sq(q[1, 2]), sq(q[2, 0])]
        vel = [*v_e[k], *np.sqrt(np.diag(q)), sq(q[0, 1]), sq(q[1, 2]), sq(q[2, 0])]  # the same sigmas: a check
        out.append(f[:2] + [f"{x:.4f}" for x in cols[:3]] + f[5:7] + [f"{x:.9f}" for x in cols[3:]]
                   + ["0.0", "0.0"] + [f"{x:.9f}" for x in vel])
    head = ("%  GPST  x-ecef(m) y-ecef(m) z-ecef(m) Q ns sdx(m) sdy(m) sdz(m) sdxy(m) sdyz(m) sdzx(m) age(s) ratio "
            "vx(m/s) vy(m/s) vz(m/s) sdvx sdvy sdvz sdvxy sdvyz sdvzx")
    g, _ = read_pos(_write_pos(tmp_path / "xyz.pos", head, out))
    np.testing.assert_allclose(g.time, ref.time, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.degrees(g.lla[:, :2]), np.degrees(ref.lla[:, :2]), rtol=0, atol=1e-9)
    np.testing.assert_allclose(g.lla[:, 2], ref.lla[:, 2], rtol=0, atol=1e-3)
    np.testing.assert_allclose(g.sigma_ned, sig_n, rtol=1e-6)
    np.testing.assert_allclose(g.v_n, ref.v_n, rtol=0, atol=1e-8)
    np.testing.assert_allclose(g.sigma_v_ned, sig_n, rtol=1e-6)
    out[2][2:5] = [f"{x / 1000:.4f}" for x in r_e[2]]  # kilometres
    with pytest.raises(InputError, match=r"line 4: x-ecef\(m\), y-ecef\(m\), z-ecef\(m\) = .* km from the "
                                         r"ellipsoid; expected an ECEF position in metres"):
        read_pos(_write_pos(tmp_path / "km.pos", head, out))


def test_an_enu_baseline_is_refused_saying_what_to_write(tmp_path):
    header, rows = _pos_rows(3)
    head = "%  GPST  e-baseline(m) n-baseline(m) u-baseline(m) Q ns sde(m) sdn(m) sdu(m) sden(m) sdnu(m) sdue(m)"
    p = _write_pos(tmp_path / "enu.pos", head, [f[:2] + ["1.0", "2.0", "3.0"] + f[5:15] for f in rows])
    with pytest.raises(InputError, match=r"enu\.pos: line 1: the positions are an east/north/up baseline .* write the "
                                         r"solution as lat/lon/height \(llh\) or ECEF \(xyz\)"):
        read_pos(p)


@pytest.mark.parametrize("sep", [",", ";", "\t"])
def test_fields_separated_by_another_character_are_read(tmp_path, sep):
    """RTKLIB's out-fieldsep puts a character between the fields (the date and time stay one field with a blank):
    such a file was refused ('missing column(s) latitude(deg), ... in the header')."""
    header, rows = _pos_rows()
    ref, _ = read_pos(_write_pos(tmp_path / "blank.pos", header, rows))
    head = "%  " + header[1:].split()[0] + "   " + sep + sep.join(header[1:].split()[1:])
    p = tmp_path / "sep.pos"
    lines = [f"{f[0]} {f[1]}" + sep + sep.join(f" {x}" for x in f[2:]) for f in rows]
    p.write_text(head + "\n" + "\n".join(lines) + "\n")
    g, _ = read_pos(p)
    np.testing.assert_array_equal(g.time, ref.time)
    np.testing.assert_array_equal(g.lla, ref.lla)
    np.testing.assert_array_equal(g.sigma_ned, ref.sigma_ned)


def test_geodetic_heights_are_noted(tmp_path):
    """RTKLIB's out-height = geodetic writes heights above the geoid and says so in a header comment; the file was
    read as ellipsoidal without a word.  read_pos notes it (info['pos_heights']) and navigate warns (below)."""
    header, rows = _pos_rows(3)
    plain = _write_pos(tmp_path / "e.pos", header, rows)
    geo = tmp_path / "g.pos"
    geo.write_text("% (lat/lon/height=WGS84/geodetic,Q=1:fix,2:float,3:sbas,4:dgps,5:single,6:ppp,ns=# of satellites)\n"
                   + plain.read_text())
    for p, want in ((plain, "ellipsoidal"), (geo, "geodetic")):
        info = {}
        g, _ = read_pos(p, info=info)
        assert info["pos_heights"] == want and len(g.time) == 3


@pytest.mark.parametrize("line, sow", [(2, "-5"), (2, "943261"), (102, "604800"), (102, "nan")])
def test_an_imu_log_second_of_week_outside_the_week_is_refused(tmp_path, line, sow):
    """gps_sow_s = -5 or 943261 on the first row of an rtklibexplorer log was read (the .pos reader refuses
    seconds of week outside [0, 604800) naming the line): the same range, the same line numbers."""
    from inskit.io.rtklib import read_rtklibexplorer_imu

    imu = Path(__file__).resolve().parents[1] / "data" / "drive_0708" / "imu_1934_gpst.csv.gz"
    lines = gzip.decompress(imu.read_bytes()).decode().splitlines(True)[:400]
    row = lines[line - 1].split(",")
    row[1] = sow
    lines[line - 1] = ",".join(row)
    p = tmp_path / "imu.csv"
    p.write_text("".join(lines))
    if sow == "nan":  # not a number at all: the reader's cell message, naming the same line
        with pytest.raises(InputError, match=rf"imu\.csv: line {line}: column 'gps_sow_s' has 'nan'"):
            read_rtklibexplorer_imu(p)
        return
    with pytest.raises(InputError, match=rf"imu\.csv: line {line}: gps_sow_s={float(sow)!r}; expected seconds of "
                                         r"the GPS week in \[0, 604800\)"):
        read_rtklibexplorer_imu(p)


@pytest.mark.parametrize("field, value, named", [
    (4, "1601474.0", r"height\(m\)=1601474\.0 is beyond \+-100 km of the ellipsoid"),  # a height in mm
    (4, "-1e300", r"height\(m\)=-1e\+300 is beyond \+-100 km"),
    (15, "1e300", r"vn\(m/s\)=1e\+300 is beyond \+-12000 m/s"),
    (17, "-15000", r"vu\(m/s\)=-15000\.0 is beyond \+-12000 m/s"),
])
def test_a_pos_height_or_velocity_beyond_reason_is_refused(tmp_path, field, value, named):
    """A .pos row whose height or velocity is another unit or column was read (read_solution refuses them):
    the same +-100 km and +-12 km/s, naming the line and the column."""
    header, rows = _pos_rows(20)
    rows[5][field] = value
    p = _write_pos(tmp_path / "f.pos", header, rows)
    with pytest.raises(InputError, match=rf"f\.pos: line 7: {named}.*; another unit or column\?"):
        read_pos(p)
    rows[5][field] = {4: "-99000", 15: "11000", 17: "-11000"}[field]  # within the bounds: read
    g, _ = read_pos(_write_pos(p, header, rows))
    assert len(g) == 20


def test_a_pos_file_of_other_quality_names_its_quality_and_the_key_that_reads_it(tmp_path):
    """``inskit spp`` writes Q = 5 (single point); read with the default
    quality (1 fix, 2 float) the message said only "no rows with quality Q
    in [1, 2]", not what the file holds nor how to read it."""
    header, rows = _pos_rows(6)
    for f in rows:
        f[5] = "5"
    rows[0][5] = "4"
    p = _write_pos(tmp_path / "spp.pos", header, rows)
    with pytest.raises(InputError, match=r"spp\.pos: no rows with quality Q in \[1, 2\]; its rows have Q 4 "
                                         r"\(1 row, DGPS\) and 5 \(5 rows, single\): quality=\[4, 5\] "
                                         r"\(\[gnss\] quality in a navigate config\) reads them"):
        read_pos(p)
    assert len(read_pos(p, quality=(5,))[0]) == 5


@pytest.mark.parametrize("field, value, match", [
    (7, "1e30", r"line 12: column 'sdn\(m\)' is 1e\+30; a sigma beyond 100 km"),
    (19, "1e300", r"line 12: column 'sdve' is 1e\+300; a sigma beyond 12000 m/s"),
])
def test_a_pos_sigma_beyond_reason_is_refused_naming_its_line(tmp_path, field, value, match):
    """A .pos row whose sdn held 1e30 was read, and the filter squared it into 'covariance lost
    positiveness ... the filter diverged', naming neither file nor line; the CSV reader's limits now hold
    for .pos files too (line 12: the 11th row after the header line)."""
    lines = gzip.decompress(DRIVE_POS.read_bytes()).decode().splitlines(True)
    first = next(i for i, s in enumerate(lines) if not s.startswith("%"))
    k = first + 10
    cells = lines[k].split()
    cells[field] = value
    lines[k] = " ".join(cells[:2]) + " " + " ".join(cells[2:]) + "\n"
    p = tmp_path / "big.pos"
    p.write_text("".join(lines))
    with pytest.raises(InputError, match=rf"big\.pos: line {k + 1}: " + match.split(": ", 1)[1]):
        read_pos(p)


def test_a_pos_velocity_that_does_not_describe_the_positions_motion_is_refused(tmp_path):
    """read_gnss refused fixes whose velocity columns do not describe how their positions move (420c12f), but
    read_pos, whose velocity the start-up takes heading and motion from alike, read vn and ve swapped or in
    km/h without a word: the same check now runs on a .pos with velocity, naming its columns."""
    header, rows = _pos_rows(2197)  # the whole drive: it moves
    assert read_pos(_write_pos(tmp_path / "ok.pos", header, rows))[0].v_n is not None
    swapped = [f[:15] + [f[16], f[15]] + f[17:] for f in rows]
    with pytest.raises(InputError, match=r"swapped\.pos: its velocity points \d+ deg away from where its positions "
                                         r"move .*: vn\(m/s\) and ve\(m/s\) swapped, or a sign"):
        read_pos(_write_pos(tmp_path / "swapped.pos", header, swapped))
    kmh = [f[:15] + [f"{float(x) * 3.6:.4f}" for x in f[15:18]] + f[18:] for f in rows]
    with pytest.raises(InputError, match=r"kmh\.pos: its velocity columns say 3\.\d+ times the speed its positions "
                                         r"move at .*: km/h\?"):
        read_pos(_write_pos(tmp_path / "kmh.pos", header, kmh))
