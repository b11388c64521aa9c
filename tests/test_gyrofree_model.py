"""The array sensor model (inskit.gyrofree.model)."""

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.gyrofree.layout import six_layout, ten_layout
from inskit.gyrofree.model import (
    ArrayData,
    ArrayErrors,
    draw_errors,
    simulate_array,
    source_misaligned_axes,
    tilt_axes,
    true_specific_forces,
)
from inskit.gyrofree.motion import ConstantRateMotion, HarmonicBodyMotion


def test_error_free_outputs_follow_eq_7_and_8():
    """m1 (+d b1) and m2 (-d b1), both sensing b1 (SOURCES-NOTES 1.3, eq. 7-8):
    f_b1 - f_m1 = d(q^2 + r^2), f_b1 - f_m2 = -d(q^2 + r^2); eq. 10 and the
    corrected eq. 11-12: f2 - f1 = 2d(q^2+r^2), f4 - f3 = 2d(p^2+r^2),
    f6 - f5 = 2d(p^2+q^2)."""
    d = 0.2
    mot = ConstantRateMotion((1.0, 2.0, 3.0), (50.0, 10.0, 10.0)).motion(np.array([0.0, 1.0]))
    y = simulate_array(ten_layout(d), mot).outputs[0]
    p, q, r = 1.0, 2.0, 3.0
    assert np.isclose(50.0 - y[0], d * (q * q + r * r))
    assert np.isclose(50.0 - y[1], -d * (q * q + r * r))
    assert np.isclose(y[3] - y[2], 2 * d * (p * p + r * r))
    assert np.isclose(y[5] - y[4], 2 * d * (p * p + q * q))
    # eq. 15 and 18 with no angular acceleration: f7 = f_b3 + d pr, f9 = f_b3 + d qr
    assert np.isclose(y[6], 10.0 + d * p * r) and np.isclose(y[8], 10.0 + d * q * r)


def test_specific_force_at_a_point_is_rigid_body_kinematics(rng):
    mot = HarmonicBodyMotion.random(rng).motion(np.linspace(0, 3, 7))
    L = six_layout(0.3)
    fk = true_specific_forces(L, mot)
    r = L.positions_b[2]
    w, dw = mot.omega_ib_b[4], mot.omega_dot_ib_b[4]
    assert np.allclose(fk[4, 2], mot.f_b[4] + np.cross(dw, r) + np.cross(w, np.cross(w, r)))


def test_errors_enter_as_modelled(rng):
    L = ten_layout(0.1)
    mot = HarmonicBodyMotion.random(rng).motion(np.linspace(0, 2, 201))
    ideal = simulate_array(L, mot).outputs
    b = rng.normal(0, 1e-3, 10)
    s = rng.normal(0, 1e-3, 10)
    e = ArrayErrors.build(10, bias=b, scale_factor=s)
    y = simulate_array(L, mot, e).outputs
    assert np.allclose(y, ideal * (1 + s) + b, atol=1e-13)
    n = simulate_array(L, mot, ArrayErrors.build(10, noise_sigma=0.01), np.random.default_rng(1)).outputs - ideal
    assert 0.009 < n.std() < 0.011
    with pytest.raises(InputError, match="rng"):
        simulate_array(L, mot, ArrayErrors.build(10, noise_sigma=0.01))
    with pytest.raises(InputError, match="rng"):
        draw_errors(L, None, bias_sigma=1.0)


def test_source_misalignment_planes():
    """eq. 26-36: S_theta1 = [cos, 0, sin], S_theta3 = [0, cos, sin], S_theta5 = [sin, 0, cos]."""
    th = np.radians([0.1, -0.2, 0.3, -0.4, 0.5, -0.6])
    ax = source_misaligned_axes(ten_layout(), th)
    c, s = np.cos(th), np.sin(th)
    assert np.allclose(ax[0], [c[0], 0, s[0]]) and np.allclose(ax[1], [c[1], 0, s[1]])
    assert np.allclose(ax[2], [0, c[2], s[2]]) and np.allclose(ax[3], [0, c[3], s[3]])
    assert np.allclose(ax[4], [s[4], 0, c[4]]) and np.allclose(ax[5], [s[5], 0, c[5]])
    assert np.allclose(ax[6:], ten_layout().axes_b[6:])  # m7-m10 not modelled by the source
    with pytest.raises(InputError, match="six angles"):
        source_misaligned_axes(ten_layout(), th[:5])


def test_random_misalignment_angles(rng):
    L = ten_layout()
    e = draw_errors(L, rng, misalignment_sigma=1e-3)
    ang = np.arccos(np.clip(np.sum(e.axes_true_b * L.axes_b, axis=1), -1, 1))
    assert np.allclose(np.linalg.norm(e.axes_true_b, axis=1), 1)
    assert 1e-5 < np.median(ang) < 1e-2
    t = tilt_axes(np.eye(3), [[0, 1, 0], [0, 0, 1], [1, 0, 0]], [0.1, 0.2, 0.3])
    assert np.allclose(t[0], [np.cos(0.1), np.sin(0.1), 0])
    with pytest.raises(InputError, match="parallel"):
        tilt_axes(np.eye(3)[:1], [[2.0, 0, 0]], [0.1])


def test_array_data_validates():
    with pytest.raises(InputError, match=r"shape \(2, 3\)"):
        ArrayData(np.array([0.0, 1.0]), np.zeros((2, 2)), ("a", "b", "c"))
    with pytest.raises(InputError, match="accelerometer b"):
        ArrayData(np.array([0.0, 1.0]), np.array([[0, np.nan], [0, 0]]), ("a", "b"))
    d = ArrayData(np.array([0.0, 1.0]), np.zeros((2, 6)), tuple(f"m{k}" for k in range(1, 7)))
    with pytest.raises(InputError, match="no column for m7, m8, m9, m10"):
        d.check_layout(ten_layout())
    with pytest.raises(InputError, match="shape"):
        ArrayErrors.build(10, bias=np.zeros(3))
