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
