"""First- and second-order filters of source 004, discretised exactly (ZOH)."""

import math

import numpy as np
import pytest

from inskit.errors import ConfigError, InputError
from inskit.filters.simple import FirstOrderFilter, SecondOrderFilter, zoh_discretize


def test_first_order_step_is_exact_at_samples():
    f = FirstOrderFilter(T=30.0)
    d = f.discretize(1.0)
    y = d.run(np.ones(200))
    t = np.arange(200) * 1.0
    # ZOH equivalence is exact for a held step: only rounding remains
    assert np.abs(y - f.step_response(t)).max() < 1e-13
    assert d.dc_gain() == pytest.approx(1.0, abs=1e-14)


@pytest.mark.parametrize("zeta", [0.3, 0.7071, 1.0, 1.8])
def test_second_order_step_is_exact_at_samples(zeta):
    f = SecondOrderFilter(T1=20.0, zeta=zeta)
    d = f.discretize(0.5)
    n = 600
    y = d.run(np.ones(n))
    # the closed form is written independently of the matrix exponential
    assert np.abs(y - f.step_response(np.arange(n) * 0.5)).max() < 1e-11
    assert d.dc_gain() == pytest.approx(1.0, abs=1e-12)


def test_multichannel_and_steady_start():
    d = SecondOrderFilter(10.0, 0.5).discretize(1.0)
    u = np.column_stack([np.full(50, 3.0), np.full(50, -2.0)])
    y = d.run(u, initial="first")
    assert np.allclose(y, u, atol=1e-12)  # no start-up transient
    y0 = d.run(u)
    assert y0.shape == (50, 2) and y0[0, 0] == 0.0


def test_settling_times():
    assert FirstOrderFilter(10.0).settling_time(0.05) == pytest.approx(10.0 * math.log(20.0))
    f = SecondOrderFilter(T1=10.0, zeta=0.7071)
    ts = f.settling_time(0.05)
    # independent check: simulate at 1 ms and find the last excursion beyond 5 %
    d = f.discretize(0.001)
    y = d.run(np.ones(200_000))
    last = np.nonzero(np.abs(y - 1.0) > 0.05)[0][-1] * 0.001
    assert ts == pytest.approx(last, abs=0.01)
    # a well-known landmark: zeta = 0.707 settles (5 %) in about 3 T1 (2.9-3.0)
    assert 2.5 * 10 < ts < 3.1 * 10


def test_noise_gain_and_frequency_response():
    T, dt = 20.0, 1.0
    d = FirstOrderFilter(T).discretize(dt)
    a = math.exp(-dt / T)
    assert d.noise_gain() == pytest.approx((1 - a) / (1 + a), rel=1e-10)
    # a slow sinusoid is attenuated by 1/sqrt(1 + (w T)^2); the hold adds a
    # sinc(w dt / 2) factor, below 1e-4 here, hence the 1e-3 tolerance
    w = 2 * np.pi / 600.0
    t = np.arange(0, 6000.0, dt)
    y = d.run(np.sin(w * t))
    amp = np.abs(y[len(t) // 2:]).max()
    assert amp == pytest.approx(1 / math.sqrt(1 + (w * T) ** 2), rel=1e-3)


def test_zoh_matches_integral():
    A = np.array([[0.0, 1.0], [-0.04, -0.2]])
    B = np.array([0.0, 0.04])
    Ad, Bd = zoh_discretize(A, B, 2.0)
    # B_d = A^-1 (A_d - I) B when A is invertible
    assert np.allclose(Bd, np.linalg.solve(A, (Ad - np.eye(2)) @ B), atol=1e-14)


def test_invalid_parameters():
    with pytest.raises(ConfigError, match="`T` must be > 0"):
        FirstOrderFilter(0.0)
    with pytest.raises(ConfigError, match="`zeta` must be > 0"):
        SecondOrderFilter(10.0, -1.0)
    with pytest.raises(ConfigError, match="`dt`"):
        FirstOrderFilter(5.0).discretize(0.0)
    with pytest.raises(InputError, match="NaN"):
        FirstOrderFilter(5.0).discretize(1.0).run(np.array([1.0, np.nan]))
