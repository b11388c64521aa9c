"""Raw GNSS simulation: the physics of each observable, the clock, noise, visibility, and the
simulator checked against the GNSS engine through the RINEX files."""

import dataclasses

import numpy as np
import pytest

from inskit import earth
from inskit.gnss import range_table, read_nav, read_obs, sagnac_rotate, transmit_time
from inskit.gnss.constants import FREQ_L1, FREQ_L2, OMEGA_E_GPS, C
from inskit.gnss.rinex_write import write_nav, write_obs
from inskit.gnss.time import from_week_sow
from inskit.simulation import HarmonicTrajectory, StationaryTrajectory
from inskit.simulation.constellation import walker_constellation
from inskit.simulation.gnss_raw import (
    Blockage,
    ClockModel,
    RawGnssSpec,
    antenna_motion,
    simulate_clock,
    simulate_raw,
)

T0 = from_week_sow(2374, 243240.0)
LLA0 = (np.radians(40.0966), np.radians(-105.1474), 1600.0)
LAM1 = C / FREQ_L1
#: a vehicle at constant velocity (no jerk, so numerical derivatives are exact to rounding)
STRAIGHT = HarmonicTrajectory(LLA0, north=(0.0, 12.0, ()), east=(0.0, -5.0, ()), up=(0.0, 0.3, ()),
                              yaw=(np.arctan2(-5.0, 12.0), 0.0, ()))
QUIET = RawGnssSpec(code_sigma_m=0.0, phase_sigma_m=0.0, doppler_sigma_m_s=0.0, multipath_sigma_m=0.0,
                    clock=ClockModel(bias_s=2.5e-4, drift_s_s=3e-7, h0=0.0, h_2=0.0))


@pytest.fixture(scope="module")
def nav():
    return walker_constellation("walker-gps+galileo", T0 - 10.0, T0 + 4000.0, np.random.default_rng(11))


def _run(nav, spec, t=None, traj=STRAIGHT, seed=3):
    t = np.arange(0.0, 600.0, 1.0) if t is None else t
    return simulate_raw(traj, t, t0_gps=T0, nav=nav, spec=spec, rng=np.random.default_rng(seed))


def test_code_minus_clocks_is_the_sagnac_range(nav):
    """With every error off but the clocks, C1C - c dt_rx + c (dt_sv - TGD) is the geometric range
    |R3(w tau) r_sat(t_tx) - r_rx(t)|, computed here the engine's way from the code itself."""
    r = _run(nav, dataclasses.replace(QUIET, iono_scale=0.0, troposphere=False))
    P = r.obs["C1C"]
    k, j = np.nonzero(np.isfinite(P))
    sats = np.array(r.sats)[j]
    t_tx, st = transmit_time(r.nav, sats, r.time[k], P[k, j])
    travel = (r.time[k] - r.clock_bias_s[k]) - t_tx
    geo = np.linalg.norm(sagnac_rotate(st.pos_e, travel) - r.r_e[k], axis=1)
    corrected = P[k, j] - C * r.clock_bias_s[k] + C * (st.clock_s - st.group_delay_s)
    assert np.abs(corrected - geo).max() < 1e-3
    # and the Sagnac term is really in: without it the ranges differ by up to ~ w r_sat r_rx / c
    flat = np.linalg.norm(st.pos_e - r.r_e[k], axis=1)
    assert np.abs(corrected - flat).max() > 10.0


def test_doppler_is_minus_the_rate_of_the_phase_and_code(nav):
    """D1C = -dL1C/dt exactly as a derivative of the simulated phase, and = -dC1C/dt / lambda to
    the ionospheric divergence 2 dI/dt (mm/s); central differences on the 1 s grid."""
    r = _run(nav, QUIET)
    ok = np.isfinite(r.obs["D1C"])
    ok[[0, -1]] = False
    ok[1:-1] &= np.isfinite(r.obs["C1C"][2:]) & np.isfinite(r.obs["C1C"][:-2])
    dP = np.gradient(r.obs["C1C"], r.t_sim, axis=0)   # GPS L1 and Galileo E1 share the wavelength
    dL = np.gradient(r.obs["L1C"], r.t_sim, axis=0)
    assert np.abs(r.obs["D1C"] * LAM1 + dP)[ok].max() < 0.01           # 1 cm/s
    assert np.abs(r.obs["D1C"] + dL)[ok].max() * LAM1 < 2e-3
    # the receiver clock drift is in: c * 3e-7 = 90 m/s on every satellite
    v_geo = -r.range_rate_m_s[ok]
    assert np.median(r.obs["D1C"][ok] * LAM1 - v_geo) == pytest.approx(-C * 3e-7, abs=1.0)


def test_phase_carries_minus_the_ionosphere_and_an_integer_per_pass(nav):
    r = _run(nav, QUIET, t=np.arange(0.0, 3000.0, 10.0))
    P, L = r.obs["C1C"], r.obs["L1C"]
    n = (L * LAM1 - P + 2 * r.iono_m) / LAM1          # = N, integer, constant in a pass
    ok = np.isfinite(n)
    assert np.abs(n[ok] - np.round(n[ok])).max() < 0.01
    lli = r.lli["L1C"]
    for j in range(len(r.sats)):
        vis = np.flatnonzero(ok[:, j])
        if len(vis) < 2:
            continue
        runs = np.split(vis, np.flatnonzero(np.diff(vis) > 1) + 1)
        for run in runs:
            assert np.ptp(np.round(n[run, j])) == 0
            assert lli[run[0], j] == (0 if run[0] == 0 else 1) and not lli[run[1:], j].any()
    assert 2 * np.nanmax(r.iono_m) > 1.0   # the test sees a real ionosphere


def test_clock_allan_deviation_matches_h0_and_h_minus2():
    """Overlapping Allan deviation of 2e5 s of simulated clock against h0/(2 tau) + (2 pi^2/3) h_-2 tau;
    tolerances about four times the estimator's spread over seeds (0.2 % at 1 s, 1.5 % at 100 s,
    3 % at 1000 s)."""
    clock = ClockModel(bias_s=1e-4, drift_s_s=1e-7, h0=2e-19, h_2=2e-20)
    t = np.arange(200_000.0)
    bias, drift = simulate_clock(t, clock, np.random.default_rng(1))
    for tau, tol in ((1, 0.01), (10, 0.015), (100, 0.06), (1000, 0.15)):
        x = bias
        d2 = x[2 * tau:] - 2 * x[tau:-tau] + x[:-2 * tau]
        adev = np.sqrt(np.mean(d2**2) / (2.0 * tau**2))
        assert adev == pytest.approx(float(clock.allan_deviation(tau)), rel=tol), tau
    # the drift state is the random walk: its increments have variance 2 pi^2 h_-2 dt
    assert np.std(np.diff(drift)) == pytest.approx(np.sqrt(2 * np.pi**2 * 2e-20), rel=0.01)
    # white frequency only: ADEV(1 s) = sqrt(h0 / 2)
    b, _ = simulate_clock(t[:50_000], ClockModel(h0=8e-20, h_2=0.0), np.random.default_rng(2))
    assert np.std(np.diff(b) - 1e-7) == pytest.approx(np.sqrt(4e-20), rel=0.02)
    # deterministic without noise, and ms jumps keep |bias| <= 0.5 ms
    b, d = simulate_clock(t[:10], ClockModel(bias_s=1e-3 - 2e-6, drift_s_s=1e-6, h0=0, h_2=0, jumps=True),
                          np.random.default_rng(0))
    np.testing.assert_allclose(d, 1e-6)
    assert np.abs(b).max() <= 5e-4 and b[0] == pytest.approx(-2e-6) and b[3] == pytest.approx(1e-6)


def test_code_phase_doppler_noise_scale_as_one_over_sin_elevation(nav):
    spec = RawGnssSpec(code_sigma_m=0.8, phase_sigma_m=0.004, doppler_sigma_m_s=0.1, multipath_sigma_m=0.0,
                       mask_rad=np.radians(5.0))
    noisy = _run(nav, spec, t=np.arange(0.0, 3600.0, 2.0), traj=StationaryTrajectory(LLA0))
    clean = _run(nav, dataclasses.replace(spec, code_sigma_m=0.0, phase_sigma_m=0.0, doppler_sigma_m_s=0.0),
                 t=np.arange(0.0, 3600.0, 2.0), traj=StationaryTrajectory(LLA0))
    s = np.sin(noisy.elevation)
    for code, sigma, unit in (("C1C", 0.8, 1.0), ("L1C", 0.004, LAM1), ("D1C", 0.1, LAM1)):
        z = (noisy.obs[code] - clean.obs[code]) * unit * s / sigma
        for lo, hi in ((5, 25), (25, 50), (50, 90)):
            m = np.isfinite(z) & (noisy.elevation >= np.radians(lo)) & (noisy.elevation < np.radians(hi))
            assert m.sum() > 2000
            assert np.std(z[m]) == pytest.approx(1.0, abs=0.06), (code, lo)
            assert abs(np.mean(z[m])) < 0.06


def test_multipath_is_gauss_markov_scaled_by_elevation(nav):
    spec = dataclasses.replace(QUIET, multipath_sigma_m=0.4, multipath_tau_s=20.0, mask_rad=np.radians(-5.0))
    r = _run(nav, spec, t=np.arange(0.0, 3600.0, 1.0), traj=StationaryTrajectory(LLA0))
    u = r.multipath_m * np.maximum(np.sin(np.clip(r.elevation, 0.02, None)), 0.1) / 0.4
    u = u[:, np.isfinite(u).all(axis=0)]
    assert u.shape[1] >= 10
    assert np.std(u) == pytest.approx(1.0, abs=0.15)
    lag = np.mean(u[20:] * u[:-20]) / np.mean(u * u)
    assert lag == pytest.approx(np.exp(-1.0), abs=0.1)
    # the multipath is on the code only
    base = _run(nav, QUIET, t=np.arange(0.0, 3600.0, 1.0), traj=StationaryTrajectory(LLA0))
    vis = np.isfinite(base.obs["C1C"])
    np.testing.assert_allclose((r.obs["C1C"] - base.obs["C1C"])[vis], r.multipath_m[vis], atol=1e-6)
    dn = (r.obs["L1C"] - base.obs["L1C"])[vis]     # passes start elsewhere with a -5 deg mask: other N
    np.testing.assert_allclose(dn, np.round(dn), atol=1e-6)


def test_blockage_windows_leave_exactly_keep_satellites(nav):
    spec = dataclasses.replace(QUIET, blockage=(Blockage(100.0, 219.0, 3), Blockage(300.0, 419.0, 1),
                                                Blockage(450.0, 470.0, 0), Blockage(500.0, 520.0, sats=("G01",
                                                                                                       "E05"))))
    r = _run(nav, spec)
    free = _run(nav, QUIET)
    t = r.t_sim
    above = free.visible
    for a, b, keep in ((100, 219, 3), (300, 419, 1), (450, 470, 0)):
        m = (t >= a) & (t <= b)
        np.testing.assert_array_equal(r.n_visible[m], np.minimum(keep, above[m].sum(axis=1)))
        # the ones kept are the highest
        el = np.where(above[m], r.elevation[m], -np.inf)
        top = np.sort(el, axis=1)[:, ::-1][:, :max(keep, 1)]
        if keep:
            kept = np.where(r.visible[m], r.elevation[m], np.inf).min(axis=1)
            np.testing.assert_array_equal(kept, top[:, keep - 1])
        assert (r.blocked[m] == (above[m] & ~r.visible[m])).all()
    m = (t >= 500) & (t <= 520)
    named = np.isin(r.sats, ["G01", "E05"])
    np.testing.assert_array_equal(r.visible[m], above[m] & named[None, :])
    out = ~((t >= 100) & (t <= 219) | (t >= 300) & (t <= 419) | (t >= 450) & (t <= 470) | (t >= 500) & (t <= 520))
    np.testing.assert_array_equal(r.visible[out], above[out])
    assert not r.blocked[out].any()
    # satellites reacquired after a window start a new pass: LLI set
    back = np.flatnonzero(t == 220)[0]
    re = r.visible[back] & ~r.visible[back - 1]
    assert re.any() and (r.lli["L1C"][back, re] == 1).all()


def test_mask_and_validity(nav):
    r = _run(nav, dataclasses.replace(QUIET, mask_rad=np.radians(15.0)))
    assert np.all(r.elevation[r.visible] >= np.radians(15.0))
    assert np.any((r.elevation > np.radians(5.0)) & (r.elevation < np.radians(15.0)) & ~r.visible)
    for code, a in r.obs.items():
        assert np.array_equal(np.isfinite(a) & (np.array([s[0] for s in r.sats]) == "G")[None, :],
                              r.visible & (np.array([s[0] for s in r.sats]) == "G")[None, :]), code
    s = r.obs["S1C"][r.visible]
    assert s.min() >= 34.0 and s.max() <= 48.0


def test_lever_arm_and_antenna_velocity():
    """Antenna = trajectory point + C_en C_nb l_b; its ECEF velocity is the time derivative."""
    traj = HarmonicTrajectory(LLA0, north=(0.0, 8.0, [(30.0, 0.2, 0.0)]), yaw=(0.3, 0.1, ()),
                              pitch=(0.0, 0.0, [(0.05, 0.5, 0.0)]))
    lever = (0.7, -0.3, -1.2)
    t = np.linspace(1.0, 20.0, 20)
    r, v, lla = antenna_motion(traj, t, lever)
    kin = traj.kinematics(t)
    off = r - earth.lla_to_ecef(kin.lla)
    np.testing.assert_allclose(np.linalg.norm(off, axis=1), np.linalg.norm(lever), atol=1e-9)
    off_n = np.einsum("nji,nj->ni", earth.dcm_en(kin.lla[:, 0], kin.lla[:, 1]), off)
    np.testing.assert_allclose(off_n, np.einsum("nij,j->ni", kin.C_nb, lever), atol=1e-9)
    h = 1e-4
    rp, _, _ = antenna_motion(traj, t + h, lever)
    rm, _, _ = antenna_motion(traj, t - h, lever)
    np.testing.assert_allclose(v, (rp - rm) / (2 * h), atol=2e-4)
    np.testing.assert_allclose(lla, earth.ecef_to_lla(r))


def test_dual_frequency_group_delay_and_ionosphere(nav):
    r = _run(nav, dataclasses.replace(QUIET, dual_frequency=True), t=np.arange(0.0, 120.0, 1.0))
    g = np.array([s[0] == "G" for s in r.sats])
    e = ~g
    gamma = (FREQ_L1 / FREQ_L2) ** 2
    d = (r.obs["C2W"] - r.obs["C1C"])[:, g]
    expect = ((gamma - 1) * (r.iono_m + C * r.group_delay_s))[:, g]
    ok = np.isfinite(d)
    assert ok.sum() > 100 and np.abs(d - expect)[ok].max() < 1e-6
    # ionosphere-free code: no ionosphere and the broadcast clock without any group delay
    p_if = (gamma * r.obs["C1C"] - r.obs["C2W"]) / (gamma - 1)
    ref = r.range_m + C * (r.clock_bias_s[:, None] - r.sat_clock_s) + r.tropo_m
    assert np.abs((p_if - ref)[:, g][ok]).max() < 1e-5
    assert np.isfinite(r.obs["C7Q"][:, e]).any() and not np.isfinite(r.obs["C7Q"][:, g]).any()
    assert not np.isfinite(r.obs["C2W"][:, e]).any()


def test_same_rng_same_observations_and_draws_independent_of_visibility(nav):
    a = _run(nav, RawGnssSpec(), seed=5)
    b = _run(nav, RawGnssSpec(), seed=5)
    for k in a.obs:
        assert np.array_equal(a.obs[k], b.obs[k], equal_nan=True)
    c = _run(nav, RawGnssSpec(mask_rad=np.radians(30.0)), seed=5)
    both = c.visible
    np.testing.assert_array_equal(c.obs["C1C"][both], a.obs["C1C"][both])


def _write_and_read(r, tmp_path):
    obs_path = write_obs(tmp_path / "sim.rnx", time=r.time, sats=r.sats, obs=r.obs, lli=r.lli,
                         approx_position_e=r.r_e[0])
    nav_path = write_nav(tmp_path / "sim_nav.rnx", r.nav, iono_alpha=r.iono_alpha, iono_beta=r.iono_beta)
    return read_obs(obs_path), read_nav(nav_path)


def test_rinex_round_trip_of_a_simulation(nav, tmp_path):
    r = _run(nav, dataclasses.replace(RawGnssSpec(), dual_frequency=True,
                                      blockage=(Blockage(30.0, 40.0, 0),)), t=np.arange(0.0, 60.0, 0.5))
    obs, _ = _write_and_read(r, tmp_path)
    seen = r.visible.any(axis=0)
    assert obs.sats == tuple(np.array(r.sats)[seen])
    rows = r.visible.any(axis=1)                     # the empty epochs (keep = 0) are not written
    np.testing.assert_allclose(obs.time, r.time[rows], atol=1e-7)
    for k, a in r.obs.items():
        a = a[rows][:, seen]
        assert np.array_equal(np.isnan(a), np.isnan(obs.obs[k])), k
        assert np.nanmax(np.abs(obs.obs[k] - a)) <= 5.001e-4, k
    np.testing.assert_array_equal(obs.lli["L1C"], r.lli["L1C"][rows][:, seen])


@pytest.mark.parametrize("iono_scale", [1.0, 2.0])
def test_engine_corrections_on_simulated_files_leave_the_simulated_noise(nav, tmp_path, iono_scale):
    """Through the RINEX files: the engine's corrected pseudorange minus the true range minus
    c dt_rx is the simulated noise (mean 0, sigma 0.6 m / sin el) when the ionosphere is the broadcast
    model, and is biased by (scale - 1) I when the simulated ionosphere is scaled."""
    spec = RawGnssSpec(code_sigma_m=0.6, multipath_sigma_m=0.0, doppler_sigma_m_s=0.05, iono_scale=iono_scale)
    r = _run(nav, spec, t=np.arange(0.0, 1800.0, 2.0), seed=21)
    obs, nav_back = _write_and_read(r, tmp_path)
    ep = np.round((obs.time - r.time[0]) / 2.0).astype(int)      # the epochs written (2 s grid)
    rt = range_table(obs, nav_back, rx_e=r.r_e[ep], mask_deg=10.0)
    k = ep[rt.epoch]
    dt = r.clock_bias_s[k]
    truth = np.linalg.norm(sagnac_rotate(rt.sat_pos_e, rt.travel_s - dt) - r.r_e[k], axis=1)
    res = rt.pseudorange_m - truth - C * dt
    z = res * np.sin(rt.elevation_rad) / 0.6
    j = np.searchsorted(np.array(r.sats), rt.sat)
    if iono_scale == 1.0:
        assert len(z) > 5000
        assert abs(np.mean(z)) < 0.05 and np.std(z) == pytest.approx(1.0, abs=0.05)
    else:
        bias = (1.0 - 1.0 / iono_scale) * r.iono_m[k, j]     # iono_m is the scaled (simulated) delay
        assert np.mean(bias) > 1.0
        zb = (res - bias) * np.sin(rt.elevation_rad) / 0.6
        assert abs(np.mean(zb)) < 0.05 and np.std(zb) == pytest.approx(1.0, abs=0.05)
    # range rates: the engine's -lambda D + c ddt_sv is the geometric rate plus c ddt_rx (plus the
    # phase divergence of the atmosphere, -dI/dt + dT/dt, a few mm/s, taken out here)
    atm = -np.gradient(r.iono_m, r.t_sim, axis=0) + np.gradient(r.tropo_m, r.t_sim, axis=0)
    rr = rt.range_rate_m_s - r.range_rate_m_s[k, j] - C * r.clock_drift_s_s[k] - atm[k, j]
    zr = rr * np.sin(rt.elevation_rad) / 0.05
    assert abs(np.mean(zr)) < 0.05 and np.std(zr) == pytest.approx(1.0, abs=0.05)


def test_simulator_refuses_bad_input(nav):
    from inskit.errors import ConfigError

    with pytest.raises(ConfigError, match="increase"):
        _run(nav, QUIET, t=np.array([0.0, 2.0, 1.0]))
    with pytest.raises(ConfigError, match="not in the constellation"):
        _run(nav, dataclasses.replace(QUIET, blockage=(Blockage(0.0, 5.0, sats=("G77",)),)),
             t=np.arange(0.0, 10.0))
    with pytest.raises(ConfigError, match="end_s"):
        Blockage(5.0, 5.0, 1)
    with pytest.raises(ConfigError, match="h0"):
        ClockModel(h0=-1.0)
    assert OMEGA_E_GPS > 0


def test_simulated_walk_matches_the_real_receiver_between_satellites():
    """The real walk log (u-blox, first 10 s, standing) against a simulation of a static receiver at
    its header position with the same broadcast records: real - simulated code is one receiver
    clock term common to all satellites, to a few metres (the real atmosphere and multipath), and
    so is the Doppler, to a fraction of a hertz."""
    import warnings
    from pathlib import Path

    from inskit.simulation.constellation import constellation_from_nav

    data = Path(__file__).resolve().parent / "data" / "gnss"
    if not (data / "gnss_1730_first40.obs").exists():
        pytest.skip("walk excerpt missing")
    real = read_obs(data / "gnss_1730_first40.obs")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # SBAS/BeiDou records skipped
        nav_w = constellation_from_nav(data / "gnss_1730.nav", real.time[0], real.time[-1])
    spec = dataclasses.replace(QUIET, clock=ClockModel(0.0, 0.0, 0.0, 0.0))
    sim = simulate_raw(StationaryTrajectory(earth.ecef_to_lla(real.approx_position_e)), real.time - real.time[0],
                       t0_gps=real.time[0], nav=nav_w, spec=spec, rng=np.random.default_rng(0))
    assert len(sim.sats) == 4 and sim.visible.all()
    cols = [real.sats.index(s) for s in sim.sats]
    d_code = real.obs["C1C"][:, cols] - sim.obs["C1C"]
    d_dopp = real.obs["D1C"][:, cols] - sim.obs["D1C"]
    spread = d_code - d_code.mean(axis=1, keepdims=True)
    assert np.abs(np.nanmean(spread, axis=0)).max() < 5.0
    assert np.abs(d_dopp - d_dopp.mean(axis=1, keepdims=True)).max() < 1.0
    assert abs(np.nanmean(d_code)) > 1e5                  # the receiver's clock offset is really there
