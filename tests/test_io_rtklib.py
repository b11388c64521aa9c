"""RTKLIB ``.pos`` files as users hand them over: gzip whatever the name, a byte-order mark, a truncated
download (:func:`inskit.io.rtklib.read_pos`)."""

import gzip
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
    with pytest.raises(InputError, match=r"cut\.pos\.gz: not a readable \.pos file \(.*\): truncated"):
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
