"""Reading TOML files (:mod:`inskit.config_files`): what editors put in them."""

import pytest

from inskit.config_files import read_toml
from inskit.errors import ConfigError


def test_a_byte_order_mark_is_dropped(tmp_path):
    p = tmp_path / "c.toml"
    p.write_bytes(b"\xef\xbb\xbfname = \"x\"\r\n[imu]\r\nfile = \"a.csv\"\r\n")
    assert read_toml(p) == {"name": "x", "imu": {"file": "a.csv"}}


def test_a_file_that_is_not_utf8_names_its_line(tmp_path):
    """It was 'internal error: UnicodeDecodeError ...', exit 3."""
    p = tmp_path / "c.toml"
    p.write_bytes(b"name = \"x\"\n# caf\xe9 (latin-1)\n")
    with pytest.raises(ConfigError, match=r"c\.toml: line 2: byte 0xe9 is not UTF-8; a config file is UTF-8"):
        read_toml(p)
