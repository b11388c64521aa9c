"""Geometry and atmosphere models (inskit.gnss.atmosphere).

Truths: a Klobuchar value worked by hand through IS-GPS-200 Figure 20-4,
the model's night-time floor, the standard-atmosphere zenith delay at sea
level (~2.3 m hydrostatic), the mapping function's 1/sin(el) limit, and
geometric landmarks (a satellite straight overhead, due north, due east).
"""

from __future__ import annotations

import numpy as np
import pytest

from inskit import earth
from inskit.errors import ConfigError, InputError
from inskit.gnss import (
    KLOBUCHAR_DEFAULT_ALPHA,
    KLOBUCHAR_DEFAULT_BETA,
    elevation_azimuth,
    iono_free,
    klobuchar_delay,
    saastamoinen_delay,
)
from inskit.gnss.atmosphere import tropo_mapping
from inskit.gnss.constants import C, FREQ_L1, FREQ_L2
from inskit.units import DEG

LLA_40N = np.array([40.0 * DEG, -100.0 * DEG, 0.0])


def test_klobuchar_hand_worked_point():
    # Stated point: lat 40 N, lon 100 W, az 210 deg, el 20 deg, GPS seconds of week 593100,
    # default coefficients.  By hand through IS-GPS-200 Figure 20-4 (semicircles):
    #   E = 0.11111, psi = 0.0137/(E+0.11) - 0.022 = 0.0399598
    #   phi_i = 0.222222 + psi cos(210) = 0.187616; lam_i = -0.555556 + psi sin(210)/cos(pi phi_i) = -0.579591
    #   phi_m = phi_i + 0.064 cos(pi (lam_i - 1.617)) = 0.239793
    #   t = 43200 lam_i + 593100 mod 86400 = 49661.67 s (local afternoon)
    #   F = 1 + 16 (0.53 - E)^3 = 2.176025
    #   AMP = sum alpha_n phi_m^n = 7.60925e-9 s; PER = sum beta_n phi_m^n = 68617 s -> floor 72000 s
    #   x = 2 pi (t - 50400)/PER = -0.0644317
    #   T = F (5e-9 + AMP (1 - x^2/2 + x^4/24)) = 2.740368e-8 s -> 8.21542 m
    t = 1826 * 604800.0 + 593100.0
    d = klobuchar_delay(t, LLA_40N, 210.0 * DEG, 20.0 * DEG, KLOBUCHAR_DEFAULT_ALPHA, KLOBUCHAR_DEFAULT_BETA)
    assert d == pytest.approx(8.21542, abs=1e-4)
    assert isinstance(d, float)


def test_klobuchar_night_floor_and_shapes():
    # local midnight at the receiver (lon 0): only the 5 ns constant remains, times F
    t_night = 1826 * 604800.0 + 0.0
    zen = klobuchar_delay(t_night, [0.3, 0.0, 0.0], 0.0, 90.0 * DEG)
    f_zenith = 1.0 + 16.0 * (0.53 - 0.5) ** 3
    assert zen == pytest.approx(C * 5e-9 * f_zenith, rel=1e-12)   # 1.4996 m
    low = klobuchar_delay(t_night, [0.3, 0.0, 0.0], 0.0, 5.0 * DEG)
    assert low == pytest.approx(C * 5e-9 * (1 + 16 * (0.53 - 5 / 180) ** 3), rel=1e-12)
    # vectorised over m rows and (m, 3) positions; daytime larger than night
    m = 5
    t = t_night + np.linspace(0.0, 86400.0, m)
    lla = np.tile([0.3, 0.0, 0.0], (m, 1))
    out = klobuchar_delay(t, lla, np.zeros(m), np.full(m, 45 * DEG))
    assert out.shape == (m,)
    assert out[2] > 2 * out[0]  # t = 12 h local: near the 14 h peak
    with pytest.raises(InputError, match=r"shape \(4,\)"):
        klobuchar_delay(t, lla, 0.0, 0.5, alpha=[1e-8, 0.0], beta=KLOBUCHAR_DEFAULT_BETA)


def test_saastamoinen_zenith_and_mapping():
    sea = np.array([45.0 * DEG, 0.0, 0.0])
    z = saastamoinen_delay(sea, 90.0 * DEG)
    # standard atmosphere at sea level: hydrostatic 0.0022768 * 1013.25 / (1 - 0.00028*0) = 2.307 m,
    # wet (15 C, 70 %: e = 12.0 hPa) 0.120 m
    assert 2.30 < z < 2.50
    assert saastamoinen_delay(sea, 0.0, humidity=0.0, zenith=True) == pytest.approx(2.307, abs=0.002)
    # height: 1.81 m hydrostatic at 2 km (standard pressure 795 hPa)
    assert saastamoinen_delay([45 * DEG, 0.0, 2000.0], 0.0, humidity=0.0, zenith=True) == pytest.approx(
        1.81, abs=0.01)
    # mapping ~ 1/sin(el) at high elevation, flatter than 1/sin near the horizon, finite at 0
    for el_deg in (90.0, 60.0, 45.0):
        el = el_deg * DEG
        ratio = saastamoinen_delay(sea, el) / z
        assert ratio * np.sin(el) == pytest.approx(1.0, abs=2e-3)
    assert tropo_mapping(10 * DEG) == pytest.approx(5.58, abs=0.01)
    assert tropo_mapping(10 * DEG) < 1 / np.sin(10 * DEG)
    assert np.isfinite(tropo_mapping(0.0)) and tropo_mapping(0.0) == pytest.approx(22.4, abs=0.1)
    assert np.isnan(saastamoinen_delay(sea, -1 * DEG))
    out = saastamoinen_delay(np.tile(sea, (3, 1)), np.array([10, 30, 90]) * DEG)
    assert out.shape == (3,) and np.all(np.diff(out) < 0)
    with pytest.raises(ConfigError):
        saastamoinen_delay(sea, 1.0, humidity=70.0)


def test_elevation_azimuth_landmarks():
    lla = np.array([30.0 * DEG, 60.0 * DEG, 100.0])
    rx = earth.lla_to_ecef(lla)
    c_en = earth.dcm_en(lla[0], lla[1])
    north, east, down = c_en[:, 0], c_en[:, 1], c_en[:, 2]
    overhead = rx - 2.0e7 * down
    el, az = elevation_azimuth(rx, overhead)
    assert el == pytest.approx(90.0 * DEG, abs=1e-9)
    sats = np.stack([rx + 2e7 * north, rx + 2e7 * east, rx + 1e7 * (north + east) - 1e7 * down,
                     rx - 2e7 * north + 1e3 * down])
    el, az = elevation_azimuth(np.tile(rx, (4, 1)), sats)
    np.testing.assert_allclose(el[:3], [0.0, 0.0, np.arctan(1 / np.sqrt(2))], atol=1e-9)
    np.testing.assert_allclose(az[:3], [0.0, 90 * DEG, 45 * DEG], atol=1e-9)
    assert az[3] == pytest.approx(180 * DEG) and el[3] < 0
    # (3,) receiver with (m, 3) satellites
    el2, _ = elevation_azimuth(rx, sats)
    np.testing.assert_allclose(el2, el)
    with pytest.raises(InputError):
        elevation_azimuth(rx[:2], sats)


def test_iono_free_removes_first_order_delay():
    rho = np.array([2.0e7, 2.3e7])
    i1 = np.array([5.0, 12.0])                  # L1 delay [m]; L2 delay is (f1/f2)^2 larger
    p1 = rho + i1
    p2 = rho + i1 * (FREQ_L1 / FREQ_L2) ** 2
    np.testing.assert_allclose(iono_free(p1, p2, FREQ_L1, FREQ_L2), rho, rtol=0, atol=1e-6)
