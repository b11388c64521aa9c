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
