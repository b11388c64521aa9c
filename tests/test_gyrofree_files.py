"""Layout, array and inertial-solution files (inskit.gyrofree.files)."""

import numpy as np
import pytest

from inskit import io
from inskit.errors import InputError
from inskit.gyrofree.files import (
    read_array,
    read_inertial,
    read_layout,
    write_array,
    write_inertial,
    write_layout,
    write_rates,
)
from inskit.gyrofree.layout import six_layout, source_index, ten_layout
from inskit.gyrofree.model import simulate_array
from inskit.gyrofree.motion import ConstantRateMotion
from inskit.gyrofree.solvers import solve_closed_form

HEADER = "name,x_m,y_m,z_m,axis_x,axis_y,axis_z\n"


def test_layout_round_trip(tmp_path):
    p = write_layout(tmp_path / "ten.csv", ten_layout(0.07))
    L = read_layout(p)
    assert L.names == ten_layout().names
    assert np.array_equal(L.positions_b, ten_layout(0.07).positions_b)
    assert source_index(L) == "ten"  # a file with the source's geometry can use the closed form
    with pytest.raises(InputError, match="already exists"):
        write_layout(p, six_layout())


BAD_LAYOUTS = {
    "missing": ("name,x_m,y_m,z_m,axis_x,axis_y\n", "line 1: missing column(s) axis_z"),
    "unknown": (HEADER.strip() + ",bias\n", "unknown column(s) bias"),
    "empty_field": (HEADER + "a,0.1,0,0,1,0,0\nb,,0,0,1,0,0\n", "line 3: field 'x_m' is empty"),
    "text": (HEADER + "a,0.1,0,0,1,0,zero\n", "line 2: field 'axis_z' has 'zero'"),
    "norm": (HEADER + "# a comment\na,0.1,0,0,1,1,0\n", "line 3: fields axis_x, axis_y, axis_z of a have norm 1.41421"),
    "repeat": (HEADER + "a,0.1,0,0,1,0,0\na,0.2,0,0,1,0,0\n", "line 3: accelerometer name 'a' repeats line 2"),
    "millimetres": (HEADER + "a,100,0,250,1,0,0\n", "line 2: fields x_m, y_m, z_m put a 269.3 m"),
    "fields": (HEADER + "a,0.1,0,0,1,0\n", "line 2: 6 fields, expected 7"),
    "name": (HEADER + "7up,0.1,0,0,1,0,0\n", "line 2: field 'name'"),
    "no_rows": (HEADER, "no accelerometers"),
}


@pytest.mark.parametrize("case", sorted(BAD_LAYOUTS))
def test_bad_layout_files_name_file_line_and_field(case, tmp_path):
    text, expected = BAD_LAYOUTS[case]
    p = tmp_path / "lay.csv"
    p.write_text(text)
    with pytest.raises(InputError) as e:
        read_layout(p)
    assert "lay.csv" in str(e.value) and expected in str(e.value)


def test_array_round_trip_and_validation(tmp_path):
    L = ten_layout()
    t = np.arange(0, 0.1, 0.01)
    data = simulate_array(L, ConstantRateMotion().motion(t))
    p = write_array(tmp_path / "a.csv", data)
    back = read_array(p, L)
    assert np.array_equal(back.outputs, data.outputs) and back.names == L.names
    with pytest.raises(InputError, match="does not match layout 'six'.*columns for m7, m8, m9, m10"):
        read_array(p, six_layout())
    # columns in g, in another order
    g = tmp_path / "g.csv"
    g.write_text("time_s,m2_g,m1_g\n0,1,2\n0.1,1,2\n")
    two = read_array(g)
    assert two.names == ("m2", "m1") and np.isclose(two.outputs[0, 1], 2 * 9.80665)
    bad = tmp_path / "b.csv"
    bad.write_text("time_s,m1_m_s2,gyro_x\n0,1,2\n")
    with pytest.raises(InputError, match="column 'gyro_x' is not an accelerometer output"):
        read_array(bad)
    bad.write_text("time_s,m1_m_s2\n0,1\n0,2\n")
    with pytest.raises(InputError, match="line 3: duplicate timestamp"):
        read_array(bad)
    bad.write_text("time_s,m1_m_s2\n0,1\n1,x\n")
    with pytest.raises(InputError, match="line 3: column 'm1_m_s2'"):
        read_array(bad)


def test_inertial_solution_and_rates_files(tmp_path):
    t = np.arange(0, 1.0, 0.01)
    m = ConstantRateMotion()
    tr = m.truth(t)
    p = write_inertial(tmp_path / "tr.csv", tr, extra={"wx_rad_s": np.ones(len(t))})
    back, extra = read_inertial(p)
    assert np.allclose(back.r_i, tr.r_i) and np.allclose(back.q_ib, tr.q_ib) and "wx_rad_s" in extra
    L = ten_layout()
    sol = solve_closed_form(simulate_array(L, m.motion(t)), L, omega0=[1, 2, 3])
    r = write_rates(tmp_path / "rates.csv", sol)
    imu = io.read_imu(r, check_units=False)  # the core IMU reader takes the estimates
    w, f = imu.rates()
    assert np.allclose(w[1:], [1, 2, 3]) and np.allclose(f[1:], [50, 10, 10])
    with pytest.raises(InputError, match="deg/s"):
        io.read_imu(r)  # 3.7 rad/s looks like deg/s to the unit check, as documented
