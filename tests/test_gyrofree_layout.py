"""Layouts, the linear measurement model and the rank test (inskit.gyrofree.layout)."""

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.gyrofree.layout import (
    PARAMETERS,
    ArrayLayout,
    builtin_layout,
    observability,
    require,
    six_layout,
    source_index,
    ten_layout,
)
from inskit.gyrofree.model import simulate_array
from inskit.gyrofree.motion import HarmonicBodyMotion


def coplanar(d=0.1):
    """Four sensors in the body xy plane, all sensing z."""
    return ArrayLayout(("a", "b", "c", "e"), [[d, 0, 0], [-d, 0, 0], [0, d, 0], [0, -d, 0]], [[0, 0, 1]] * 4,
                       "coplanar")


def random_layout(rng, m=12):
    axes = rng.standard_normal((m, 3))
    return ArrayLayout(tuple(f"s{k}" for k in range(m)), rng.uniform(-0.2, 0.2, (m, 3)),
                       axes / np.linalg.norm(axes, axis=1, keepdims=True), "random12")


def test_source_positions_match_the_notes():
    L = ten_layout(0.25)
    d = 0.25
    # SOURCES-NOTES 1.2: m7 at +d b1 sensing b3, m8 at +d b3 sensing b1, m9 at +d b2 sensing b3, m10 at +d b3 sensing b2
    assert np.allclose(L.positions_b[6:], [[d, 0, 0], [0, 0, d], [0, d, 0], [0, 0, d]])
    assert np.allclose(L.axes_b[6:], [[0, 0, 1], [1, 0, 0], [0, 0, 1], [0, 1, 0]])
    assert source_index(L) == "ten" and source_index(six_layout(2.0)) == "six"
    assert source_index(coplanar()) is None
    assert builtin_layout("six", 0.3).d == 0.3


@pytest.mark.parametrize("make", [ten_layout, six_layout, coplanar])
def test_design_matrix_reproduces_the_sensor_model(make, rng):
    """y = H x with x = [f, omega_dot, p^2, q^2, r^2, pq, pr, qr] equals the
    vector form e.(f + w_dot x r + w x (w x r)) to rounding."""
    L = make()
    mot = HarmonicBodyMotion.random(rng).motion(np.linspace(0, 5, 50))
    w = mot.omega_ib_b
    x = np.column_stack([mot.f_b, mot.omega_dot_ib_b, w[:, 0] ** 2, w[:, 1] ** 2, w[:, 2] ** 2,
                         w[:, 0] * w[:, 1], w[:, 0] * w[:, 2], w[:, 1] * w[:, 2]])
    y = simulate_array(L, mot).outputs
    assert np.abs(x @ L.H.T - y).max() < 1e-12


def test_observability_of_the_source_layouts():
    ten = observability(ten_layout())
    # no sensor senses r_dot, and pq never appears (SOURCES-NOTES 1.3)
    assert ten.unobservable() == ["r_dot", "pq"]
    assert ten.rank == 10 and ten.quadratic_rank == 3 and all(ten.sign_tracked)
    assert ten.rate_source == "quadratic" and ten.specific_force
    six = observability(six_layout())
    assert six.observable() == ["f_x", "f_y", "f_z", "p^2", "q^2", "r^2"]
    assert six.magnitudes and six.rate_source is None


def test_six_asked_for_rate_signs_is_refused_with_what_is_missing():
    with pytest.raises(InputError) as e:
        require(six_layout())
    msg = str(e.value)
    assert "layout 'six'" in msg and "sign" in msg and "p, q, r" in msg
    assert "p_dot, q_dot, r_dot unobservable" in msg and "pq, pr, qr" in msg
    assert "rate='magnitude'" in msg
    require(six_layout(), rate="magnitude")  # magnitudes are observable: no error


def test_four_coplanar_sensors_are_refused():
    with pytest.raises(InputError) as e:
        require(coplanar())
    msg = str(e.value)
    assert "f_x, f_y" in msg and "angular rates p, q, r" in msg and "rank 3 of 12" in msg
    with pytest.raises(InputError, match="f_x, f_y"):
        require(coplanar(), rate="none")


def test_ten_without_m9_m10_cannot_sign_p():
    """Dropping m9, m10 loses p_dot and qr: the sign of p can no longer be carried."""
    L = ten_layout()
    L8 = ArrayLayout(L.names[:8], L.positions_b[:8], L.axes_b[:8], "eight")
    o = observability(L8)
    assert not o.identifiable["p_dot"] and not o.identifiable["qr"]
    with pytest.raises(InputError, match="sign"):
        require(L8)


def test_a_random_redundant_layout_observes_everything(rng):
    o = observability(random_layout(rng))
    assert o.rank == 12 and o.unobservable() == [] and o.rate_source == "quadratic"


def test_rank_test_does_not_depend_on_the_unit_of_length():
    for d in (1e-3, 1.0, 30.0):
        assert observability(ten_layout(d)).unobservable() == ["r_dot", "pq"]


def test_layout_validation():
    with pytest.raises(InputError, match="repeated: a"):
        ArrayLayout(("a", "a"), np.zeros((2, 3)), [[1, 0, 0]] * 2)
    with pytest.raises(InputError, match="norm 0.5"):
        ArrayLayout(("a",), [[0, 0, 0]], [[0.5, 0, 0]])
    with pytest.raises(InputError, match="shape"):
        ArrayLayout(("a", "b"), np.zeros((3, 3)), [[1, 0, 0]] * 2)
    with pytest.raises(InputError, match="must start with a letter"):
        ArrayLayout(("1a",), [[0, 0, 0]], [[1, 0, 0]])
    with pytest.raises(InputError, match="`d`"):
        ten_layout(0.0)
    with pytest.raises(InputError, match="'ten', 'six'"):
        builtin_layout("seven")
    assert len(PARAMETERS) == 12
