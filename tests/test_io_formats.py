"""inskit.io.read_imu / read_gnss read every format inskit knows, recognised by the header (issue 14 item 10):
the bundled drive among them; a header of no known kind gets a message that names the formats."""

from pathlib import Path

import numpy as np
import pytest

from inskit import io
from inskit.errors import InputError
from inskit.io.formats import detect_gnss_format, detect_imu_format
from inskit.io.rtklib import read_pos, read_rtklibexplorer_imu
from inskit.units import G0

ROOT = Path(__file__).resolve().parents[1]
DRIVE_IMU = ROOT / "data" / "drive_0708" / "imu_1934_gpst.csv.gz"
DRIVE_POS = ROOT / "data" / "drive_0708" / "gnss_1934_sf.pos.gz"


def test_the_bundled_drive_is_read_by_read_imu():
    """data/drive_0708: 54 860 rows of a 100 Hz consumer MEMS IMU, standing still for its first 38 s, where the
    specific force is gravity, 9.80 m/s^2 at 40 deg N and 1600 m, to the percent of an uncalibrated MEMS scale."""
    assert detect_imu_format(DRIVE_IMU) == "rtklibexplorer"
    imu = io.read_imu(DRIVE_IMU)
    assert len(imu) == 54860
    assert np.median(np.diff(imu.time)) == pytest.approx(0.01, abs=2e-4)
    _, f = imu.rates()
    still = (imu.time > imu.time[0]) & (imu.time < imu.time[0] + 30.0)
    assert np.median(np.linalg.norm(f[still], axis=1)) == pytest.approx(9.80, rel=0.02)
    ref, week0 = read_rtklibexplorer_imu(DRIVE_IMU)
    np.testing.assert_array_equal(imu.time, ref.time)
    np.testing.assert_array_equal(imu.dv_b, ref.dv_b)
    # the format's own options pass through: the mounting rotation keeps |f|, the offset shifts every tag
    m = io.read_imu(DRIVE_IMU, mount_rpy=np.radians([180.0, -6.79, 185.35]), time_offset_s=-0.26, week0=week0)
    np.testing.assert_allclose(np.linalg.norm(m.dv_b, axis=1), np.linalg.norm(imu.dv_b, axis=1), rtol=1e-12)
    np.testing.assert_allclose(m.time, imu.time - 0.26, rtol=0, atol=1e-9)
    # the body z axis points down: specific force at rest is up, about -1 g along it
    assert np.median(m.rates()[1][still, 2]) == pytest.approx(-G0, rel=0.02)


def test_the_bundled_fixes_are_read_by_read_gnss():
    assert detect_gnss_format(DRIVE_POS) == "rtklib-pos"
    g = io.read_gnss(DRIVE_POS)
    ref, _ = read_pos(DRIVE_POS)
    assert len(g) == len(ref) == 2197  # data/drive_0708/README.md: 2197 epochs, fixed or float (Q 1, 2)
    np.testing.assert_array_equal(g.lla, ref.lla)
    assert len(io.read_gnss(DRIVE_POS, quality=[1])) == 2189  # of which 2189 fixed


def test_inskit_files_are_recognised_and_an_explicit_format_is_obeyed(tmp_path):
    p = tmp_path / "imu.csv"
    p.write_text("time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n"
                 "0,0,0,0,0,0,-9.8\n0.01,0,0,0,0,0,-9.8\n")
    assert detect_imu_format(p) == "inskit"
    assert len(io.read_imu(p)) == 2
    # the drive read as inskit: the message names what is missing and the other format
    with pytest.raises(InputError, match=r"imu_1934_gpst\.csv\.gz: missing column\(s\) time_s \(the inskit IMU "
                                         r"format; the other IMU format inskit reads is the rtklibexplorer log"):
        io.read_imu(DRIVE_IMU, format="inskit")
    with pytest.raises(InputError, match=r"unknown IMU format 'xsens'; the formats are 'inskit' \(.*\); "
                                         r"'rtklibexplorer' \(rtklibexplorer GNSS-IMU log: gps_week"):
        io.read_imu(p, format="xsens")
    with pytest.raises(InputError, match=r"imu\.csv: mount_rpy does not apply to the 'inskit' format"):
        io.read_imu(p, mount_rpy=(0.0, 0.0, 0.0))
    with pytest.raises(InputError, match=r"first_row does not apply to the 'rtklibexplorer' format"):
        io.read_imu(DRIVE_IMU, first_row="increment")
    with pytest.raises(InputError, match=r"quality does not apply to the 'inskit' format"):
        io.read_gnss(p, quality=[1])


def test_a_header_of_no_known_format_names_them(tmp_path):
    p = tmp_path / "x.csv"
    p.write_text("t,wx,wy,wz\n0,1,2,3\n")
    assert detect_imu_format(p) is None
    with pytest.raises(InputError, match=r"x\.csv: missing column\(s\) time_s .*rtklibexplorer log: gps_week, "
                                         r"gps_sow_s, acc_\{x,y,z\}_g, gyro_\{x,y,z\}_dps.*; found t, wx, wy, wz"):
        io.read_imu(p)
    q = tmp_path / "g.csv"
    q.write_text("time_s,lat_deg\n0,1\n")
    assert detect_gnss_format(q) == "inskit"
    with pytest.raises(InputError, match=r"g\.csv: missing column\(s\) lon_deg"):
        io.read_gnss(q)
    # a missing or empty file: the reader says so (detection reads nothing)
    with pytest.raises(InputError, match=r"nope\.csv: no such file"):
        io.read_imu(tmp_path / "nope.csv")
    (tmp_path / "e.csv").write_text("")
    with pytest.raises(InputError, match=r"e\.csv: the file is empty"):
        io.read_imu(tmp_path / "e.csv")


def test_the_lean_readers_of_the_real_logs_agree_with_the_pandas_way(monkeypatch):
    """The bundled gzip IMU log parsed by pyarrow reads the same numbers as
    the pandas path it replaced (which any irregular file still takes), and
    the .pos times, parsed by NumPy, are the GPS seconds of week that
    Python's datetime gives for the same stamps."""
    from datetime import datetime, timezone

    import gzip

    from inskit.io import csv_formats, rtklib

    lean, _ = read_rtklibexplorer_imu(DRIVE_IMU)
    monkeypatch.setattr(rtklib, "lean_columns", lambda *a: None)
    slow, _ = read_rtklibexplorer_imu(DRIVE_IMU)
    np.testing.assert_allclose(lean.time, slow.time, rtol=0, atol=1e-9)
    np.testing.assert_allclose(lean.dv_b, slow.dv_b, rtol=1e-14, atol=1e-18)
    np.testing.assert_allclose(lean.dtheta_b, slow.dtheta_b, rtol=1e-14, atol=1e-18)
    assert csv_formats._header_names(DRIVE_IMU)[:2] == ["gps_week", "gps_sow_s"]
    stamps = []
    with gzip.open(DRIVE_POS, "rt") as fh:
        for line in fh:
            if not line.startswith("%") and line.strip():
                f = line.split()
                stamps.append(f"{f[0]} {f[1]}")
    week, sow = rtklib.gps_week_seconds(stamps)
    epoch = datetime(1980, 1, 6, tzinfo=timezone.utc)
    for i in (0, len(stamps) // 2, len(stamps) - 1):
        d = datetime.strptime(stamps[i], "%Y/%m/%d %H:%M:%S.%f").replace(tzinfo=timezone.utc) - epoch
        whole = d.days * 86400 + d.seconds
        assert week[i] == whole // 604800
        assert sow[i] == pytest.approx(whole % 604800 + d.microseconds * 1e-6, abs=1e-9)
    with pytest.raises(InputError, match="expected YYYY/MM/DD HH:MM:SS.sss"):
        rtklib.gps_week_seconds(["2025/07/08 19:34:24.5", "2025/07/32 01:00:00.0"])


def test_a_byte_order_mark_does_not_hide_the_format(tmp_path):
    """A log saved by a Windows editor starts with a BOM: its header is still recognised."""
    import gzip

    p = tmp_path / "imu.csv"
    p.write_bytes(b"\xef\xbb\xbf" + gzip.decompress(DRIVE_IMU.read_bytes())[:4000].rsplit(b"\n", 1)[0] + b"\n")
    assert detect_imu_format(p) == "rtklibexplorer"
    q = tmp_path / "gnss.pos"
    q.write_bytes(b"\xef\xbb\xbf" + gzip.decompress(DRIVE_POS.read_bytes()))
    assert detect_gnss_format(q) == "rtklib-pos"
    assert len(io.read_gnss(q)) == 2197


def test_a_header_with_quoted_names_keeps_its_format(tmp_path):
    """A spreadsheet that quotes every cell: '"gps_week","gps_sow_s",...' was taken for the inskit format and
    refused ('missing column(s) time_s ...; found gps_week, gps_sow_s, ...', the names it had just read)."""
    import gzip

    lines = gzip.decompress(DRIVE_IMU.read_bytes())[:40000].decode().splitlines()[:-1]
    plain, quoted = tmp_path / "plain.csv", tmp_path / "quoted.csv"
    plain.write_text("\n".join(lines) + "\n")
    quoted.write_text("\n".join(",".join(f'"{c}"' for c in line.split(",")) for line in lines) + "\n")
    assert detect_imu_format(quoted) == "rtklibexplorer"
    a, b = io.read_imu(plain), io.read_imu(quoted)
    assert np.array_equal(a.time, b.time) and np.array_equal(a.dv_b, b.dv_b) and np.array_equal(a.dtheta_b, b.dtheta_b)
    g = tmp_path / "gnss.csv"
    g.write_text('"time_s","lat_deg","lon_deg","height_m","sigma_n_m","sigma_e_m","sigma_d_m"\n'
                 "0,45,7,300,0.5,0.5,1\n1,45.00001,7,300,0.5,0.5,1\n")
    assert detect_gnss_format(g) == "inskit" and len(io.read_gnss(g)) == 2


def test_a_one_row_rtklibexplorer_log_is_refused(tmp_path):
    """`head -2` of the bundled log: one sample, which read_imu turned into a one-epoch log (mechanize then
    'navigated' 0 s)."""
    import gzip

    with gzip.open(DRIVE_IMU, "rt") as fh:
        head = [next(fh) for _ in range(2)]
    p = tmp_path / "imu_gpst.csv"
    p.write_text("".join(head))
    with pytest.raises(InputError, match=r"imu_gpst\.csv: holds 1 data row\(s\); an IMU log needs at least two"):
        io.read_imu(p)


def test_blank_lines_before_the_header_or_between_rows_keep_the_format_and_the_line_numbers(tmp_path):
    """The readers skip a blank line; the header recognition read the first line only (a log with a blank
    first line was given to the inskit reader, which asked for time_s), and the messages counted the rows,
    so every line after a blank one was named as the line above it."""
    import gzip

    lines = gzip.decompress(DRIVE_IMU.read_bytes()).decode().splitlines()[:400]
    p = tmp_path / "imu.csv"
    p.write_text("\n" + "\n".join(lines[:100] + [""] + lines[100:]) + "\n")
    assert detect_imu_format(p) == "rtklibexplorer"
    assert len(io.read_imu(p)) == 399
    shown = p.read_text().splitlines()
    k = 250  # the week of the row an editor shows on line 251: half a week
    cells = shown[k - 1].split(",")
    cells[0] += ".5"
    shown[k - 1] = ",".join(cells)
    p.write_text("\n".join(shown) + "\n")
    with pytest.raises(InputError, match=rf"imu\.csv: line {k}: gps_week=\d+\.5; expected a whole GPS week"):
        io.read_imu(p)
    q = tmp_path / "gnss.pos"
    q.write_bytes(b"\n\n" + gzip.decompress(DRIVE_POS.read_bytes()))
    assert detect_gnss_format(q) == "rtklib-pos"
    assert len(io.read_gnss(q)) == 2197


def test_a_mounting_rotation_in_degrees_is_refused_before_the_log_is_read(tmp_path, monkeypatch):
    """read_imu(path, mount_rpy=[180, -6.79, 185.35]) (the config's degrees given to the radians argument) read
    the drive rotated by 180 rad about x and 185 rad about z without a word; a pair of angles was an IndexError
    from rotations.dcm_from_euler.  The check runs before the log is read (no reader is reached)."""
    import inskit.io.rtklib as R
    from inskit.io.rtklib import mount_dcm

    def no_read(*a, **k):
        raise AssertionError("the log was read")

    monkeypatch.setattr(R, "read_rtklibexplorer_imu", no_read)
    with pytest.raises(InputError, match=r"^`mount_rpy`: roll 180\.0 rad \(10313\.2 deg\) is beyond a full turn: "
                                         r"degrees where radians are expected\? \(np\.radians\)$"):
        io.read_imu(DRIVE_IMU, mount_rpy=[180.0, -6.79, 185.35])
    with pytest.raises(InputError, match=r"^`mount_rpy` must be roll, pitch, yaw: shape \(3,\), got \(2,\)$"):
        io.read_imu(DRIVE_IMU, mount_rpy=[1.0, 2.0])
    with pytest.raises(InputError, match=r"`mount_rpy`: yaw 185\.35 rad"):  # the shared mechanism: every caller
        mount_dcm([0.0, 0.0, 185.35])


def test_a_path_argument_that_is_no_path_is_named(tmp_path):
    """read_imu(3), read_gnss(3), read_solution(3) were pathlib's 'expected str, bytes or os.PathLike object, not
    int' (no argument named); write_solution(path, dataframe) an AttributeError inside the writer."""
    import inskit

    for read in (inskit.read_imu, inskit.read_gnss, inskit.read_solution):
        with pytest.raises(InputError, match=r"^`path` must be a file path \(str or Path\), got int 3$"):
            read(3)
    with pytest.raises(InputError, match=r"^`sol` must be a NavSolution, got dict$"):
        inskit.write_solution(tmp_path / "sol.csv", {"time_s": [0.0]})
    assert not (tmp_path / "sol.csv").exists()
    assert len(inskit.read_gnss(DRIVE_POS)) == len(inskit.read_gnss(str(DRIVE_POS)))


def test_an_array_option_of_another_format_is_refused_by_name_not_a_numpy_error(tmp_path):
    """read_imu("imu.csv", mount_rpy=np.zeros(3)) on an inskit file raised numpy's 'The truth value of an
    array with more than one element is ambiguous' (the option compared with `!=`); a list gave the message."""
    from inskit.io.formats import _refuse_options

    p = tmp_path / "imu.csv"
    p.write_text("time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n"
                 "0,0,0,0,0,0,-9.8\n0.01,0,0,0,0,0,-9.8\n")
    for rpy in (np.zeros(3), np.zeros((1, 3)), [0.0, 0.0, 0.0]):
        with pytest.raises(InputError, match=r"imu\.csv: mount_rpy does not apply to the 'inskit' format"):
            io.read_imu(p, mount_rpy=rpy)
    g = tmp_path / "gnss.csv"
    g.write_text("time_s,lat_deg,lon_deg,height_m,sigma_n_m,sigma_e_m,sigma_d_m\n0,45,7,300,0.5,0.5,1\n")
    with pytest.raises(InputError, match=r"gnss\.csv: quality, week0 do not apply to the 'inskit' format"):
        io.read_gnss(g, quality=np.array([1, 2]), week0=np.int64(2374))
    # a value this format always has may be given, as text or as an array equal to it; another is refused
    _refuse_options(p, "x", {"sampled": "average", "rpy": np.zeros(3)}, fixed={"sampled": "average", "rpy": [0, 0, 0]})
    with pytest.raises(InputError, match=r"imu\.csv: rpy does not apply to the 'x' format"):
        _refuse_options(p, "x", {"rpy": np.ones(3)}, fixed={"rpy": [0, 0, 0]})
    with pytest.raises(InputError, match=r"imu\.csv: sampled does not apply to the 'x' format"):
        _refuse_options(p, "x", {"sampled": np.array(["average", "average"])}, fixed={"sampled": "average"})
