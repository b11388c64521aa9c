"""Messages show numbers as plain floats (issue 12, item 10): never numpy's
``np.float64(inf)`` repr, whatever type the caller's numbers have."""

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.types import ImuData, check_time, plain_number


def test_plain_number():
    assert plain_number(np.float64(np.inf)) == "inf"
    assert plain_number(np.float64(-np.inf)) == "-inf"
    assert plain_number(np.float32(np.nan)) == "nan"
    assert plain_number(np.float64(0.1)) == "0.1"           # shortest text that reads back exactly
    assert plain_number(np.float64(1234567.125)) == "1234567.125"
    assert plain_number(np.float64(2.0 / 3.0), 4) == "0.6667"
    assert plain_number(np.int64(7)) == "7.0"
    assert plain_number(np.array([1.0, np.inf])) == "[1.0, inf]"
    assert plain_number("abc") == "'abc'"


def test_check_time_messages_are_plain():
    with pytest.raises(InputError, match=r"^`time` must strictly increase: row 2 \(0\.5\) goes back from row 1 "
                                         r"\(1\.0\)$"):
        check_time("time", np.array([0.0, 1.0, 0.5], dtype=np.float32))
    with pytest.raises(InputError, match=r"row 1 \(1\.0\) repeats row 0"):
        check_time("time", [np.float64(1.0), np.float64(1.0)])
    with pytest.raises(InputError, match=r"^`time` has a NaN or infinite value \(inf\) at row 1$"):
        check_time("time", [0.0, np.inf])


def test_array_messages_name_the_bad_value():
    t = np.arange(3.0)
    dv = np.zeros((3, 3))
    dv[2, 1] = -np.inf
    with pytest.raises(InputError, match=r"^`dv_b` has a NaN or infinite value \(-inf\) at row 2$") as exc:
        ImuData(t, np.zeros((3, 3)), dv)
    assert "np." not in str(exc.value)
    with pytest.raises(InputError, match=r"`dtheta_b` must have shape \(n, 3\), got \(3, 2\)"):
        ImuData(t, np.zeros((3, 2)), np.zeros((3, 3)))


def test_no_rows_are_valid_arrays():
    """An empty selection of fixes (every one outside a mask) was an internal error: numpy cannot
    reshape 0 rows to (0, -1)."""
    from inskit.types import GnssData

    g = GnssData(np.arange(3.0), np.zeros((3, 3)), np.ones((3, 3)), np.zeros((3, 3)), np.ones((3, 3)))
    none = g.select(np.zeros(3, bool))
    assert len(none) == 0 and none.lla.shape == (0, 3) and none.v_n.shape == (0, 3)
    assert len(ImuData(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)))) == 0
    with pytest.raises(InputError, match=r"`lla` must have shape \(n, 3\), got \(0, 2\)"):
        GnssData(np.zeros(0), np.zeros((0, 2)), np.ones((0, 3)))
