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


def test_what_is_not_plain_numbers_is_named_not_a_numpy_error():
    """Text, None, complex numbers, ragged lists and datetimes were numpy's bare ValueError or a ComplexWarning
    (the imaginary part dropped), or, for a pandas datetime column, nanoseconds since 1970 taken as seconds."""
    import pandas as pd

    from inskit.types import NavState

    z = np.zeros((2, 3))
    cases = [
        (lambda: ImuData(["a", "b"], z, z), r"^`time` holds the text 'a'; expected numbers$"),
        (lambda: ImuData([0.0, 1.0], None, z), r"^`dtheta_b` is None; expected an array of numbers$"),
        (lambda: ImuData([0.0, 1.0], z + 1j, z), r"^`dtheta_b` holds complex numbers; expected real numbers$"),
        (lambda: ImuData([0.0, 1.0], z, [[0, 0, 0], [0, 0]]), r"^`dv_b` is not an array of numbers: a list whose"),
        (lambda: ImuData(pd.date_range("2020", periods=2, freq="s"), z, z),
         r"^`time` holds datetimes \(datetime64\[ns\]\); expected seconds as numbers"),
        (lambda: NavState(0.0, [0.7, 0.1, 100.0, 1.0], [0, 0, 0], [1, 0, 0, 0]),
         r"^`lla` must have shape \(3,\), got \(4,\)$"),
        (lambda: NavState("x", [0.7, 0.1, 100.0], [0, 0, 0], [1, 0, 0, 0]), r"^`time` holds the text 'x'"),
        (lambda: NavState(np.nan, [0.7, 0.1, 100.0], [0, 0, 0], [1, 0, 0, 0]),
         r"^`time` of the state is nan; expected a finite number \[s\]$"),
        (lambda: NavState([1.0, 2.0], [0.7, 0.1, 100.0], [0, 0, 0], [1, 0, 0, 0]),
         r"^`time` must be one number \[s\], got shape \(2,\)$"),
        (lambda: NavState(0.0, [0.7, np.inf, 100.0], [0, 0, 0], [1, 0, 0, 0]),
         r"^`lla` of the state has a NaN or infinite value \(\[0\.7, inf, 100\.0\]\)$"),
    ]
    for make, message in cases:
        with pytest.raises(InputError, match=message):
            make()
    # what converts exactly is taken: a timedelta column in seconds, integers, float32, a strided view, a DataFrame
    t = pd.Series(pd.timedelta_range(0, periods=3, freq="10ms"))
    imu = ImuData(t, pd.DataFrame(np.zeros((3, 3), np.float32)), np.zeros((3, 6), int)[:, ::2])
    np.testing.assert_array_equal(imu.time, [0.0, 0.01, 0.02])
    assert imu.dtheta_b.dtype == imu.dv_b.dtype == np.float64 and imu.dv_b.flags.c_contiguous
    s = NavState(np.array([5.0]), [[0.7, 0.1, 100.0]], np.zeros(3, int), (1, 0, 0, 0))
    assert s.time == 5.0 and s.lla.shape == (3,)


def test_degrees_for_radians_and_bad_quaternions_are_refused_by_every_type():
    """NavState refused a latitude beyond 90 deg, NavSolution and GnssData took 45 'rad' (2578 deg) without a word
    and NavSolution any quaternion (a zero row gave NaN attitude, 2 q a wrong one): one check for all."""
    from inskit.types import GnssData, NavSolution, NavState

    t = np.arange(3.0)
    lla_deg = np.tile([45.0, 10.0, 100.0], (3, 1))
    lla = np.radians(lla_deg) * [1, 1, 0] + [0, 0, 100.0]
    q = np.tile([1.0, 0, 0, 0], (3, 1))
    degrees = r"degrees where radians are expected\? \(np\.radians\)$"
    with pytest.raises(InputError, match=r"^`lla` holds a latitude of 45\.0 rad at row 0 \(2578\.31 deg\), beyond "
                                         r"\+-90 deg: " + degrees):
        NavSolution(t, lla_deg, np.zeros((3, 3)), q)
    with pytest.raises(InputError, match=r"^`lla` holds a latitude of 45\.0 rad at row 0 .*" + degrees):
        GnssData(t, lla_deg, np.ones((3, 3)))
    with pytest.raises(InputError, match=r"^`lla` holds a latitude of 45\.0 rad \(2578\.31 deg\)"):
        NavState(0.0, lla_deg[0], np.zeros(3), q[0])
    lla_lon = lla.copy()
    lla_lon[2, 1] = 10.0 * 2 * np.pi / 10 + 1.0  # a longitude beyond a full turn
    with pytest.raises(InputError, match=r"^`lla` holds a longitude of 7\.28\d* rad at row 2 .* beyond \+-360 deg"):
        GnssData(t, lla_lon, np.ones((3, 3)))
    q_bad = q.copy()
    q_bad[1] = 0.0
    with pytest.raises(InputError, match=r"^`q_nb` must hold unit quaternions \(scalar first\), its norm is 0\.0 "
                                         r"at row 1$"):
        NavSolution(t, lla, np.zeros((3, 3)), q_bad)
    with pytest.raises(InputError, match=r"^`q_nb` must hold unit quaternions \(scalar first\), its norm is 2\.0$"):
        NavState(0.0, lla[0], np.zeros(3), [2.0, 0, 0, 0])
    # float32 quaternions (a norm off 1 by 1e-7) are normalised, as NavState always did
    q32 = np.tile(np.array([0.6, 0.8, 0, 0], np.float32) * np.float32(1.0000001), (3, 1))
    sol = NavSolution(t, lla, np.zeros((3, 3)), q32)
    np.testing.assert_allclose(np.linalg.norm(sol.q_nb, axis=1), 1.0, rtol=0, atol=1e-15)


def test_euler_angles_in_degrees_are_refused():
    """NavState.from_euler(t, lla, v, [0, 0, 90]) built a yaw of 90 rad (5157 deg, i.e. 116.6 deg) without a word."""
    from inskit.types import NavSolution, NavState

    lla = [0.7, 0.1, 100.0]
    with pytest.raises(InputError, match=r"^`rpy`: yaw 90\.0 rad \(5156\.62 deg\) is beyond a full turn: degrees "
                                         r"where radians are expected\? \(np\.radians\)$"):
        NavState.from_euler(0.0, lla, np.zeros(3), [0.0, 0.0, 90.0])
    rpy = np.zeros((3, 3))
    rpy[2, 1] = 10.0
    with pytest.raises(InputError, match=r"^`rpy`: pitch 10\.0 rad at row 2 \(572\.958 deg\) is beyond \+-90 deg, "
                                         r"where every ZYX pitch lies: degrees"):
        NavSolution.from_euler(np.arange(3.0), np.tile(lla, (3, 1)), np.zeros((3, 3)), rpy)
    rpy[2] = [7.0, 0.0, 4 * np.pi + 0.1]  # a series may unwrap its roll and yaw over turns
    assert len(NavSolution.from_euler(np.arange(3.0), np.tile(lla, (3, 1)), np.zeros((3, 3)), rpy)) == 3
    with pytest.raises(InputError, match=r"^`rpy` has 2 rows but `time` has 3$"):
        NavSolution.from_euler(np.arange(3.0), np.tile(lla, (3, 1)), np.zeros((3, 3)), np.zeros((2, 3)))
    s = NavState.from_euler(0.0, lla, np.zeros(3), np.radians([10.0, -5.0, 350.0]))
    np.testing.assert_allclose(np.degrees(s.euler), [10.0, -5.0, -10.0], atol=1e-12)


def test_extra_columns_are_arrays_of_the_solution_s_rows():
    """extra=None was AttributeError ('NoneType' object has no attribute 'items'), a scalar 'object of type float
    has no len()', a text of 5 characters a column of 5 rows, and a list column an AttributeError later in
    interpolate; the caller's dict was held, so adding to it changed the solution."""
    from inskit.types import NavSolution

    t = np.arange(5.0)
    args = (t, np.tile([0.7, 0.1, 100.0], (5, 1)), np.zeros((5, 3)), np.tile([1.0, 0, 0, 0], (5, 1)))
    assert NavSolution(*args, None).extra == {}
    with pytest.raises(InputError, match=r"^extra column `s` is one value \(1\.0\); expected an array of 5 rows$"):
        NavSolution(*args, {"s": 1.0})
    with pytest.raises(InputError, match=r"^extra column `s` is one value \('hello'\)"):
        NavSolution(*args, {"s": "hello"})
    with pytest.raises(InputError, match=r"^`extra` must be a dict of column name -> array of 5 rows, got list$"):
        NavSolution(*args, [np.zeros(5)])
    columns = {"sigma_n_m": [1.0, 2.0, 3.0, 4.0, 5.0]}
    sol = NavSolution(*args, columns)
    columns["late_m"] = np.zeros(5)
    assert list(sol.extra) == ["sigma_n_m"] and isinstance(sol.extra["sigma_n_m"], np.ndarray)
    np.testing.assert_allclose(sol.interpolate([1.5]).extra["sigma_n_m"], [2.5])


def test_concat_names_what_cannot_be_joined():
    """concat([]) was numpy's 'need at least one array to concatenate', parts with different extra columns a
    KeyError (or, the other way round, the later part's column dropped without a word)."""
    from inskit.types import NavSolution

    def part(t0, extra):
        t = t0 + np.arange(3.0)
        return NavSolution(t, np.tile([0.7, 0.1, 100.0], (3, 1)), np.zeros((3, 3)), np.tile([1.0, 0, 0, 0], (3, 1)),
                           {k: np.zeros(3) for k in extra})

    with pytest.raises(InputError, match=r"^NavSolution\.concat: no solution to join \(an empty list\)$"):
        NavSolution.concat([])
    for a, b in ((["s_m"], []), ([], ["s_m"])):
        with pytest.raises(InputError, match=r"^NavSolution\.concat: the solutions hold different extra columns: "
                                             r"s_m in one of solution 0 and solution 1 only$"):
            NavSolution.concat([part(0.0, a), part(10.0, b)])
    joined = NavSolution.concat([part(0.0, ["b_m", "a_m", "c_m"]), part(10.0, ["c_m", "a_m", "b_m"])])
    assert list(joined.extra) == ["b_m", "a_m", "c_m"] and len(joined) == 6
    empty = part(0.0, [])
    empty = empty.slice(0, 0)
    assert NavSolution.concat([empty]) is empty


def test_sample_and_interpolate_name_bad_times():
    """sol.sample(2.5) and sol.interpolate(2.0) were 'len() of unsized object', a NaN time gave NaN rows without
    a word, and unsorted times to interpolate were named `time` (the solution's, not the argument)."""
    from inskit.types import NavSolution

    t = np.arange(5.0)
    sol = NavSolution(t, np.tile([0.7, 0.1, 100.0], (5, 1)), np.c_[t, t, t], np.tile([1.0, 0, 0, 0], (5, 1)))
    lla, v, q = sol.sample(2.5)
    assert lla.shape == (1, 3) and q.shape == (1, 4)
    np.testing.assert_allclose(v, [[2.5, 2.5, 2.5]])
    assert len(sol.interpolate(2.0)) == 1
    with pytest.raises(InputError, match=r"^`t` has a NaN or infinite value \(nan\) at row 1$"):
        sol.sample([1.0, np.nan])
    with pytest.raises(InputError, match=r"^`t` must strictly increase: row 1 \(1\.0\) goes back from row 0 \(3\.0\)$"):
        sol.interpolate([3.0, 1.0])
    with pytest.raises(InputError, match=r"^`t` must be one time or shape \(m,\), got \(2, 1\)$"):
        sol.sample([[1.0], [2.0]])


def test_no_samples_have_no_rates():
    """ImuData of no rows: rates(), to_dataframe(rates=True) and from_rates were 'index 0 is out of bounds'."""
    empty = ImuData(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)))
    gyro, accel = empty.rates()
    assert gyro.shape == accel.shape == (0, 3) and len(empty.to_dataframe(rates=True)) == 0
    assert len(ImuData.from_rates([], np.zeros((0, 3)), np.zeros((0, 3)))) == 0
    with pytest.raises(InputError, match=r"`sampled` must be 'instant' or 'average', got 'avg'"):
        ImuData.from_rates([], np.zeros((0, 3)), np.zeros((0, 3)), sampled="avg")


def test_a_mask_is_one_flag_per_fix():
    """GnssData.select([0, 2, 1, 0, 1]) took the row numbers as flags (rows 1, 2, 4) without a word, and a mask
    of another length was numpy's 'boolean index did not match'."""
    from inskit.types import GnssData

    g = GnssData(np.arange(5.0), np.tile([0.7, 0.1, 100.0], (5, 1)), np.ones((5, 3)))
    with pytest.raises(InputError, match=r"^`mask` must hold booleans, one per fix, got int64 values \(row numbers\?"):
        g.select([0, 2, 1, 0, 1])
    with pytest.raises(InputError, match=r"^`mask` must have shape \(5,\), one flag per fix, got \(2,\)$"):
        g.select([True, False])
    np.testing.assert_array_equal(g.select(g.time > 2.5).time, [3.0, 4.0])
