"""The containers of :mod:`inskit.types` are valid when constructed or refuse to be: an extra column may not
take a navigation column's name (it overwrote time_s and lat_deg in tables and files), and a time held in
float32 (steps of 0.98 ms at 1e4 s) is refused, not carried into the integration."""

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.types import NAVIGATION_COLUMNS, GnssData, ImuData, NavSolution, NavState


def _solution(n=3, extra=None):
    t = np.arange(float(n))
    return NavSolution(t, np.tile([0.7, 0.1, 10.0], (n, 1)), np.zeros((n, 3)), np.tile([1.0, 0, 0, 0], (n, 1)),
                       extra)


@pytest.mark.parametrize("name", NAVIGATION_COLUMNS)
def test_an_extra_column_named_as_a_navigation_column_is_refused(name):
    """NavSolution(..., {"lat_deg": 99, "time_s": -5}) was built, and its DataFrame and written file held
    time_s = -5 and lat_deg = 99 in place of the navigation."""
    with pytest.raises(InputError, match=rf"^extra column `{name}` has the name of a navigation column \(time_s, "
                                         r"lat_deg, .*one would overwrite the other"):
        _solution(extra={"sigma_n_m": np.ones(3), name: np.full(3, 99.0)})


def test_extra_columns_that_would_be_the_same_table_column_are_refused():
    """An (n, 2) extra ``b`` is the columns b_0, b_1 of a table: an extra ``b_1`` beside it is overwritten."""
    with pytest.raises(InputError, match=r"extra columns `b` and `b_1` would both be the column 'b_1'"):
        _solution(extra={"b": np.zeros((3, 2)), "b_1": np.ones(3)})
    with pytest.raises(InputError, match=r"extra columns `b_0` and `b` would both be the column 'b_0'"):
        _solution(extra={"b_0": np.ones(3), "b": np.zeros((3, 2))})


def test_a_solution_s_table_holds_its_navigation_under_the_navigation_names():
    s = _solution(extra={"sigma_n_m": np.ones(3), "b": np.arange(6.0).reshape(3, 2)})
    df = s.to_dataframe()
    assert list(df.columns) == list(NAVIGATION_COLUMNS) + ["sigma_n_m", "b_0", "b_1"]
    assert np.array_equal(df["time_s"], s.time)
    assert np.allclose(df["lat_deg"], np.degrees(s.lla[:, 0])) and np.allclose(df["height_m"], 10.0)
    assert np.array_equal(df["b_1"], [1.0, 3.0, 5.0])
    # one built without checks (a kernel's output): its table refuses the clash rather than overwriting
    bad = NavSolution._trusted(s.time, s.lla, s.v_n, s.q_nb, {"time_s": np.full(3, -5.0)})
    with pytest.raises(InputError, match=r"extra column `time_s` would overwrite the column 'time_s'"):
        bad.to_dataframe()


def _float32_cases(dtype):
    t = (10000.0 + np.arange(0.0, 1.0, 0.01)).astype(dtype)
    n = len(t)
    z = np.zeros((n, 3))
    lla = np.tile([0.7, 0.1, 10.0], (n, 1))
    q = np.tile([1.0, 0, 0, 0], (n, 1))
    return {
        "ImuData": lambda: ImuData(t, z, z),
        "ImuData.from_rates": lambda: ImuData.from_rates(t, z, z),
        "GnssData": lambda: GnssData(t, lla, np.ones((n, 3))),
        "NavSolution": lambda: NavSolution(t, lla, z, q),
        "NavSolution.from_euler": lambda: NavSolution.from_euler(t, lla, z, z),
        "NavSolution of a list": lambda: NavSolution(list(t), lla, z, q),
        "NavState": lambda: NavState(t[0], lla[0], z[0], q[0]),
    }


@pytest.mark.parametrize("dtype", [np.float32, np.float16])
@pytest.mark.parametrize("case", list(_float32_cases(np.float32)))
def test_a_time_narrower_than_float64_is_refused_saying_why(dtype, case):
    """ImuData(float32 time near 1e4 s) took 100 Hz samples whose steps are 9.77 and 10.74 ms: a float32
    holds 24 bits, so its resolution there is 2**-10 s (the Parquet readers refuse such a column already)."""
    steps = np.diff((10000.0 + np.arange(0.0, 1.0, 0.01)).astype(np.float32).astype(float))
    assert np.ptp(steps) > 5e-4  # the loss the refusal is about: the steps are no longer 10 ms
    with pytest.raises(InputError, match=rf"^`time` holds {np.dtype(dtype).name} values; time must be float64 "
                                         r"seconds: .* is only resolved to .* s"):
        _float32_cases(dtype)[case]()


def test_integer_and_float64_times_are_taken_as_float64():
    z = np.zeros((4, 3))
    for t in (np.arange(4, dtype=np.int64), np.arange(4, dtype=np.int32), [0, 1, 2, 3], np.arange(4.0)):
        imu = ImuData(t, z, z)
        assert imu.time.dtype == np.float64 and np.array_equal(imu.time, [0.0, 1.0, 2.0, 3.0])
    assert NavState(np.int64(5), [0.7, 0.1, 0.0], np.zeros(3), [1.0, 0, 0, 0]).time == 5.0


def test_a_solution_is_interpolated_across_the_antimeridian_the_short_way():
    """A truth of a ship heading east over the antimeridian, rows at +179.9999 and -179.9999 deg: halfway
    between them ``interpolate`` gave longitude 0 (the plain average of the two), a point on the far side
    of the Earth, and ``inskit evaluate`` of a solution between those rows scored an error of 12,000 km in
    north and down for it.  The longitude now goes the short way round; rows that do not straddle the
    antimeridian are interpolated to the bit as before."""
    deg = np.pi / 180.0
    lon = np.array([179.9998, 179.9999, -179.9999, -179.9998]) * deg
    n = len(lon)
    lla = np.column_stack([np.full(n, 10.0 * deg), lon, np.zeros(n)])
    s = NavSolution(np.arange(n, dtype=float), lla, np.zeros((n, 3)), np.tile([1.0, 0, 0, 0], (n, 1)))
    got = s.interpolate(np.array([0.5, 1.25, 1.5, 1.75, 2.5]))
    np.testing.assert_allclose(got.lla[1:4, 1] / deg, [179.99995, 180.0, -179.99995], atol=1e-9)
    assert np.all(np.abs(got.lla[:, 1]) <= np.pi)
    assert got.lla[0, 1] == lon[0] * 0.5 + lon[1] * 0.5 and got.lla[4, 1] == lon[2] * 0.5 + lon[3] * 0.5
    # from west to east the same (a vehicle heading west)
    back = NavSolution(np.arange(n, dtype=float), lla[::-1].copy(), np.zeros((n, 3)), np.tile([1.0, 0, 0, 0], (n, 1)))
    np.testing.assert_allclose(np.abs(back.interpolate(np.array([1.5])).lla[0, 1]) / deg, 180.0, atol=1e-9)
