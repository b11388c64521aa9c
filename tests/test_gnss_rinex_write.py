"""RINEX 3.04 writers: what is written is what readers (ours and georinex) read back."""

import time
import warnings
from pathlib import Path

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.gnss import read_nav, read_obs
from inskit.gnss.rinex_write import (
    _fixed,
    calendar,
    iono_precision,
    nav_precision,
    signal_strength_indicator,
    write_nav,
    write_obs,
)
from inskit.gnss.time import gps_seconds

DATA = Path(__file__).resolve().parent / "data" / "gnss"
T0 = gps_seconds(2025, 7, 8, 19, 34, 0.0)


def _synthetic_obs(rng, n_ep=60, dt=0.25):
    """GPS and Galileo satellites with different codes, absent values, negative Dopplers, LLI."""
    sats = ("E05", "E11", "G02", "G13", "G31")
    n = len(sats)
    obs = {
        "C1C": rng.uniform(1.9e7, 2.6e7, (n_ep, n)),
        "L1C": rng.uniform(-1e6, 1.4e8, (n_ep, n)),
        "D1C": rng.uniform(-4500.0, 4500.0, (n_ep, n)),
        "S1C": rng.uniform(30.0, 50.0, (n_ep, n)),
        "C2W": np.full((n_ep, n), np.nan),
        "C7Q": np.full((n_ep, n), np.nan),
    }
    obs["C2W"][:, 2:] = rng.uniform(1.9e7, 2.6e7, (n_ep, 3))   # GPS only
    obs["C7Q"][:, :2] = rng.uniform(1.9e7, 2.6e7, (n_ep, 2))   # Galileo only
    gone = rng.random((n_ep, n)) < 0.1
    for k in ("C1C", "L1C", "D1C", "S1C"):
        obs[k][gone] = np.nan
    obs["D1C"][3, 1] = np.nan       # one observable of a present satellite missing
    obs["C1C"][4, :] = np.nan       # an epoch where nobody has C1C but others have C2W/C7Q
    lli = {"L1C": np.where(rng.random((n_ep, n)) < 0.05, 1, 0).astype(np.int8)}
    lli["L1C"][gone] = 0
    return T0 + dt * np.arange(n_ep), sats, obs, lli


def test_obs_round_trip_through_read_obs(tmp_path):
    t, sats, obs, lli = _synthetic_obs(np.random.default_rng(3))
    pos = np.array([-1276996.5442, -4717239.8184, 4087227.6739])
    p = write_obs(tmp_path / "o.rnx", time=t, sats=sats, obs=obs, lli=lli, approx_position_e=pos,
                  header_comments=["a comment " * 8], interval_s=0.25)
    back = read_obs(p, systems=("G", "E"))
    assert back.version == pytest.approx(3.04)
    assert back.sats == sats
    np.testing.assert_allclose(back.time, t, rtol=0, atol=1e-7)     # F11.7 seconds
    np.testing.assert_allclose(back.approx_position_e, pos, atol=1e-4)
    assert back.interval_s == pytest.approx(0.25)
    for code, a in obs.items():
        b = back.obs[code]
        assert np.array_equal(np.isnan(a), np.isnan(b)), code
        # F14.3: half a millimetre (plus the float resolution of a 1e8 value)
        assert np.nanmax(np.abs(a - b)) <= 5.001e-4, code
    assert np.array_equal(back.lli["L1C"], lli["L1C"])
    assert list(back.header["obs_types"]["G"]) == ["C1C", "L1C", "D1C", "S1C", "C2W"]
    assert list(back.header["obs_types"]["E"]) == ["C1C", "L1C", "D1C", "S1C", "C7Q"]


def test_obs_georinex_reads_the_same_values(tmp_path):
    georinex = pytest.importorskip("georinex")
    t, sats, obs, _ = _synthetic_obs(np.random.default_rng(4), n_ep=12, dt=1.0)
    p = write_obs(tmp_path / "g.rnx", time=t, sats=sats, obs=obs)
    ds = georinex.load(p)
    assert [str(s) for s in ds.sv.values] == list(sats)
    t_g = (ds.time.values - np.datetime64("1980-01-06T00:00:00")) / np.timedelta64(1, "s")
    np.testing.assert_allclose(t_g, t, atol=1e-6)
    for code in ("C1C", "L1C", "D1C", "S1C", "C2W", "C7Q"):
        g = ds[code].values
        assert np.array_equal(np.isnan(g), np.isnan(obs[code])), code
        assert np.nanmax(np.abs(g - obs[code])) <= 5.0001e-4, code


def test_obs_writes_an_hour_at_1hz_in_under_a_second(tmp_path):
    rng = np.random.default_rng(0)
    n_ep, n_sat = 3600, 10
    obs = {"C1C": rng.uniform(2e7, 2.5e7, (n_ep, n_sat)), "L1C": rng.uniform(1e8, 1.3e8, (n_ep, n_sat)),
           "D1C": rng.normal(0, 2000, (n_ep, n_sat))}
    t0 = time.perf_counter()
    p = write_obs(tmp_path / "h.rnx", time=T0 + np.arange(n_ep), sats=[f"G{i:02d}" for i in range(1, 11)], obs=obs)
    assert time.perf_counter() - t0 < 1.0
    assert p.read_text().count("\n> ") == n_ep


def test_fixed_fields_match_fortran_f14_3():
    rng = np.random.default_rng(1)
    x = np.concatenate([rng.uniform(-1e9, 1e9, 2000), rng.uniform(-5, 5, 2000), [0.0, 1e-4, -1e-4, 9999999999.999]])
    x = np.round(x * 1000) / 1000 + 1e-5 * np.sign(x)   # keep away from ties, where binary rounding differs
    got = [r.tobytes().decode() for r in _fixed(x, 14, 3, "x")]
    assert got == [f"{v:14.3f}".replace("-0.000", " 0.000") for v in x]
    with pytest.raises(InputError, match="does not fit"):
        _fixed(np.array([1e10]), 14, 3, "x")
    assert _fixed(np.array([np.nan]), 14, 3, "x").tobytes() == b" " * 14


def test_calendar_rounding_carries_into_the_next_day():
    y, mo, d, h, mi, s = calendar([gps_seconds(2024, 12, 31, 23, 59, 59.99999999)])
    assert (y[0], mo[0], d[0], h[0], mi[0], s[0]) == (2025, 1, 1, 0, 0, 0.0)
    y, mo, d, h, mi, s = calendar([gps_seconds(2024, 2, 29, 12, 3, 4.25)])  # leap day
    assert (y[0], mo[0], d[0], h[0], mi[0], s[0]) == (2024, 2, 29, 12, 3, 4.25)


def test_signal_strength_indicator_steps():
    np.testing.assert_array_equal(signal_strength_indicator([5.0, 12.0, 17.9, 18.0, 35.0, 53.9, 54.0, 60.0]),
                                  [1, 2, 2, 3, 5, 8, 9, 9])


def test_obs_refuses_bad_input_and_leaves_no_file(tmp_path):
    t, sats, obs, _ = _synthetic_obs(np.random.default_rng(5), n_ep=5)
    p = tmp_path / "bad.rnx"
    with pytest.raises(InputError, match="shape"):
        write_obs(p, time=t, sats=sats, obs={"C1C": obs["C1C"][:, :2]})
    with pytest.raises(InputError, match="satellite name"):
        write_obs(p, time=t, sats=("G1",) + sats[1:], obs=obs)
    with pytest.raises(InputError, match="observation code"):
        write_obs(p, time=t, sats=sats, obs={"P1": obs["C1C"]})
    big = dict(obs, L1C=obs["L1C"] * 1e3)
    with pytest.raises(InputError, match="does not fit"):
        write_obs(p, time=t, sats=sats, obs=big)
    with pytest.raises(InputError, match="strictly increase"):
        write_obs(p, time=t[::-1], sats=sats, obs=obs)
    assert not p.exists()


@pytest.mark.parametrize("name", ["gnss_1730.nav", "BRDC00IGS_R_20201360000_01D_MN.rnx", "abpo0080.15n"])
def test_nav_round_trip_of_real_files(tmp_path, name):
    """GPS (RINEX 3 and 2) and Galileo I/NAV + F/NAV records, written and read back, are identical."""
    src = DATA / name
    if not src.exists():
        pytest.skip(f"{src} is missing")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # the walk file's SBAS and BeiDou records are skipped with a warning
        a = read_nav(src)
    b = read_nav(write_nav(tmp_path / "n.rnx", a))
    oa, ob = np.lexsort((a.sats, a.toc)), np.lexsort((b.sats, b.toc))
    assert list(a.sats[oa]) == list(b.sats[ob])
    assert np.array_equal(a.toe[oa], b.toe[ob]) and np.array_equal(a.toc[oa], b.toc[ob])
    for k in a.params:
        assert np.array_equal(a.params[k][oa], b.params[k][ob], equal_nan=True), k
    if a.iono_alpha is not None:
        np.testing.assert_array_equal(b.iono_alpha, a.iono_alpha)
        np.testing.assert_array_equal(b.iono_beta, a.iono_beta)


def test_nav_header_carries_klobuchar_and_georinex_reads_the_records(tmp_path):
    georinex = pytest.importorskip("georinex")
    src = DATA / "BRDC00IGS_R_20201360000_01D_MN.rnx"
    if not src.exists():
        pytest.skip(f"{src} is missing")
    nav = read_nav(src)
    alpha = iono_precision([1.1176e-08, 7.4506e-09, -5.9605e-08, -5.9605e-08])
    beta = iono_precision([9.0112e04, 0.0, -1.9661e05, -6.5536e04])
    p = write_nav(tmp_path / "k.rnx", nav, iono_alpha=alpha, iono_beta=beta)
    back = read_nav(p)
    np.testing.assert_array_equal(back.iono_alpha, alpha)
    np.testing.assert_array_equal(back.iono_beta, beta)
    ds = georinex.load(p)   # records of one satellite at one epoch become 'E24', 'E24_1', ...
    for ours, theirs in (("sqrt_a", "sqrtA"), ("af0", "SVclockBias"), ("m0", "M0"), ("bgd_e5b_e1", "BGDe5b")):
        v = ds[theirs].values.ravel()
        np.testing.assert_array_equal(np.sort(v[np.isfinite(v)]), np.sort(nav.params[ours]))


def test_precision_helpers_are_fixed_points_of_the_format():
    x = np.array([1.234567890123456e-4, -3.0e-12, 5153.7654321987654, 0.0])
    y = nav_precision(x)
    assert np.array_equal(nav_precision(y), y)
    assert np.abs(y / np.where(x == 0, 1, x) - np.where(x == 0, 0, 1)).max() < 1e-12
    assert iono_precision([0.11176e-7])[0] == 1.1176e-08


def test_nav_refuses_other_systems_and_incomplete_orbits(tmp_path):
    from types import SimpleNamespace

    base = {k: [v] for k, v in (("af0", 0.0), ("af1", 0.0), ("af2", 0.0), ("iode", 1.0), ("crs", 0.0), ("dn", 0.0),
                                ("m0", 0.0), ("cuc", 0.0), ("e", 0.01), ("cus", 0.0), ("sqrt_a", 5153.0),
                                ("cic", 0.0), ("omega0", 0.0), ("cis", 0.0), ("i0", 0.9), ("crc", 0.0),
                                ("omega", 0.0), ("omega_dot", 0.0), ("idot", 0.0), ("svacc", 2.0),
                                ("health", 0.0), ("tgd", 0.0), ("iodc", 1.0), ("fit_h", 4.0))}
    rec = SimpleNamespace(sats=np.array(["R05"]), system=np.array(["R"]), toc=np.array([T0]), toe=np.array([T0]),
                          params=base)
    with pytest.raises(InputError, match="only GPS"):
        write_nav(tmp_path / "r.rnx", rec)
    rec = SimpleNamespace(sats=np.array(["G05"]), system=np.array(["G"]), toc=np.array([T0]), toe=np.array([T0]),
                          params=dict(base, m0=[np.nan]))
    with pytest.raises(InputError, match="m0"):
        write_nav(tmp_path / "g.rnx", rec)
    assert not (tmp_path / "g.rnx").exists()
