"""Synthetic Walker constellations as broadcast ephemerides, and real nav files as constellations."""

import warnings
from pathlib import Path

import numpy as np
import pytest

from inskit import earth
from inskit.errors import ConfigError
from inskit.gnss import read_nav, satellite_states
from inskit.gnss.constants import GM_GAL, GM_GPS, OMEGA_E_GPS
from inskit.gnss.rinex_write import write_nav
from inskit.gnss.time import from_week_sow, gps_seconds
from inskit.simulation.constellation import (
    WALKER_GALILEO,
    WALKER_GPS,
    constellation_from_nav,
    walker_constellation,
)

T0 = from_week_sow(2374, 243240.0)
DATA = Path(__file__).resolve().parent / "data" / "gnss"


def _inertial(pos_e, vel_e, t):
    """ECEF position/velocity to an Earth-centred inertial frame aligned with ECEF at T0."""
    th = OMEGA_E_GPS * (t - T0)
    c, s = np.cos(th), np.sin(th)
    x, y = c * pos_e[:, 0] - s * pos_e[:, 1], s * pos_e[:, 0] + c * pos_e[:, 1]
    vx = c * vel_e[:, 0] - s * vel_e[:, 1] - OMEGA_E_GPS * y
    vy = s * vel_e[:, 0] + c * vel_e[:, 1] + OMEGA_E_GPS * x
    return np.column_stack([x, y, pos_e[:, 2]]), np.column_stack([vx, vy, vel_e[:, 2]])


@pytest.mark.parametrize("spec,name,gm", [(WALKER_GPS, "walker-gps", GM_GPS),
                                          (WALKER_GALILEO, "walker-galileo", GM_GAL)])
def test_walker_geometry_through_the_broadcast_algorithm(spec, name, gm):
    """Radius a (to e), inclination, P equally spaced planes of T/P, Kepler speed, the F/T phasing."""
    nav = walker_constellation(name, T0, T0 + 3600.0, np.random.default_rng(7))
    sats = np.unique(nav.sats)
    assert len(sats) == spec.n_sats
    st = satellite_states(nav, sats, np.full(len(sats), T0 + 600.0))
    assert st.valid.all()
    r_i, v_i = _inertial(st.pos_e, st.vel_e, T0 + 600.0)
    r = np.linalg.norm(r_i, axis=1)
    a = spec.semi_major_axis_m
    assert np.all(np.abs(r - a) <= 5e-3 * a + 1.0)                      # e <= 5e-3
    # vis-viva speed, up to the node regression (the orbit plane turns at Omega_dot: |Omega_dot| r)
    dv = np.abs(np.linalg.norm(v_i, axis=1) - np.sqrt(gm * (2 / r - 1 / a)))
    assert np.all(dv <= abs(spec.node_rate) * r + 1e-6)
    h = np.cross(r_i, v_i)
    h /= np.linalg.norm(h, axis=1)[:, None]
    # the node regression tilts the instantaneous normal by up to |Omega_dot| r / v (5e-5 rad)
    tilt = 2 * abs(spec.node_rate) * a / np.sqrt(gm / a)
    np.testing.assert_allclose(np.arccos(h[:, 2]), spec.inclination_rad, atol=tilt)
    node = np.arctan2(h[:, 0], -h[:, 1])
    planes = np.round(np.mod(node - node[0], 2 * np.pi) / (2 * np.pi / spec.n_planes)) % spec.n_planes
    assert np.bincount(planes.astype(int)).tolist() == [spec.n_sats // spec.n_planes] * spec.n_planes
    spread = np.mod(node - node[0] - planes * 2 * np.pi / spec.n_planes + np.pi, 2 * np.pi) - np.pi
    assert np.abs(spread).max() < 2 * tilt
    # argument of latitude: slots 2 pi / S apart in a plane, planes offset by F 2 pi / T (to the e-terms)
    n_hat = np.column_stack([np.cos(node), np.sin(node), np.zeros(len(node))])
    u = np.arctan2(np.einsum("ij,ij->i", np.cross(n_hat, r_i), h), np.einsum("ij,ij->i", n_hat, r_i))
    S = spec.n_sats // spec.n_planes
    phase = np.mod(u - planes * spec.phasing * 2 * np.pi / spec.n_sats - u[0], 2 * np.pi / S)
    phase = np.minimum(phase, 2 * np.pi / S - phase)
    assert phase.max() < 4 * 5e-3   # 2 e sin(M) + the perigee term


def test_records_every_two_hours_describe_one_continuous_orbit_and_clock():
    nav = walker_constellation("walker-gps+galileo", T0, T0 + 5 * 3600.0, np.random.default_rng(2))
    toes = np.unique(nav.toe)
    np.testing.assert_array_equal(np.diff(toes), 7200.0)
    assert toes[0] <= T0 and toes[-1] <= T0 + 5 * 3600.0 < toes[-1] + 7200.0
    sats = np.unique(nav.sats)
    for t_mid in toes[:-1] + 3600.0:           # halfway: both neighbouring records are valid
        t = np.full(len(sats), t_mid)
        ra, rb = (np.array([np.flatnonzero((nav.sats == s) & (nav.toe == toe))[0] for s in sats])
                  for toe in (t_mid - 3600.0, t_mid + 3600.0))
        a = satellite_states(nav, sats, t, records=ra)
        b = satellite_states(nav, sats, t, records=rb)
        assert np.abs(a.pos_e - b.pos_e).max() < 1e-3          # rounding to 13 digits only
        assert np.abs(a.clock_s - b.clock_s).max() < 1e-15
    # small nonzero clocks and group delays, healthy
    p = nav.params
    assert np.all(np.abs(p["af0"]) <= 5e-4) and np.all(p["af0"] != 0) and np.all(np.abs(p["af1"]) <= 1e-11)
    gps = nav.system == "G"
    assert np.all(np.abs(p["tgd"][gps]) <= 1e-8) and np.all(np.isnan(p["tgd"][~gps]))
    assert np.all(p["health"] == 0) and np.all(p["data_source"][~gps] == 517)
    # the engine's group delay is TGD for GPS and, for these I/NAV records, BGD(E1,E5b)
    st = satellite_states(nav, sats, np.full(len(sats), T0))
    gal = np.array([s[0] == "E" for s in sats])
    np.testing.assert_array_equal(st.group_delay_s[~gal], p["tgd"][st.record[~gal]])
    np.testing.assert_array_equal(st.group_delay_s[gal], p["bgd_e5b_e1"][st.record[gal]])
    assert np.all(np.abs(st.group_delay_s) <= 1e-8) and np.any(st.group_delay_s != 0)


def test_written_and_read_back_the_records_are_identical(tmp_path):
    nav = walker_constellation("walker-gps+galileo", T0, T0 + 3 * 3600.0, np.random.default_rng(9),
                               iono_alpha=[1.1176e-08, 0, 0, 0], iono_beta=[9.0112e04, 0, 0, 0])
    back = read_nav(write_nav(tmp_path / "walker.rnx", nav))
    oa, ob = np.lexsort((nav.sats, nav.toe)), np.lexsort((back.sats, back.toe))
    assert list(nav.sats[oa]) == list(back.sats[ob])
    np.testing.assert_array_equal(nav.toe[oa], back.toe[ob])
    for k, v in nav.params.items():
        assert np.array_equal(v[oa], back.params[k][ob], equal_nan=True), k
    np.testing.assert_array_equal(back.iono_alpha, nav.iono_alpha)


def test_visible_satellites_at_mid_latitude():
    """Walker 24/6/1 seen from 45 deg N with a 10 deg mask over a day: 6-12 in view at least 90 %
    of the time, never fewer than 4."""
    nav = walker_constellation("walker-gps", T0, T0 + 86400.0, np.random.default_rng(0))
    sats = np.unique(nav.sats)
    t = T0 + np.arange(0.0, 86400.0, 300.0)
    rx = earth.lla_to_ecef([np.radians(45.0), np.radians(7.0), 200.0])
    st = satellite_states(nav, np.tile(sats, len(t)), np.repeat(t, len(sats)))
    d = st.pos_e - rx
    up = rx / np.linalg.norm(rx)   # geocentric up is within 0.2 deg of the geodetic one
    el = np.arcsin(d @ up / np.linalg.norm(d, axis=1)).reshape(len(t), len(sats))
    n = (el >= np.radians(10.0)).sum(axis=1)
    assert n.min() >= 4
    assert np.mean((n >= 6) & (n <= 12)) >= 0.9


def test_constellation_from_a_real_nav_file_checks_its_validity():
    src = DATA / "gnss_1730.nav"
    if not src.exists():
        pytest.skip(f"{src} is missing")
    t_walk = gps_seconds(2025, 8, 28, 17, 30, 40.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # SBAS and BeiDou records skipped
        nav = constellation_from_nav(src, t_walk, t_walk + 600.0)
        assert set(nav.system) == {"G"} and len(nav) == 4
        with pytest.raises(ConfigError, match="outside the file's validity"):
            constellation_from_nav(src, t_walk + 86400.0, t_walk + 86400.0 + 600.0)
    with pytest.raises(ConfigError, match="no such navigation file"):
        constellation_from_nav(DATA / "missing.nav", t_walk)
    with pytest.raises(ConfigError, match="unknown constellation"):
        walker_constellation("walker-glonass", T0, T0 + 1.0, np.random.default_rng(0))
