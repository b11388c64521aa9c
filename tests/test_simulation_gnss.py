import numpy as np
import pytest

from inskit import earth
from inskit.simulation import StationaryTrajectory
from inskit.simulation.gnss import GnssErrors, simulate_gnss

TRAJ = StationaryTrajectory((0.7, 0.1, 50.0), (0.0, 0.0, 0.8))


def test_white_and_correlated_errors_match_configuration():
    e = GnssErrors(rate_hz=1.0, white_h_m=1.0, white_v_m=2.0, correlated_h_m=0.5, correlated_v_m=1.0,
                   correlation_time_s=20.0, velocity_sigma_m_s=0.1)
    errs, verr = [], []
    truth = TRAJ.kinematics(np.array([0.0]))
    for seed in range(100):
        g, drawn = simulate_gnss(TRAJ, 0.0, 300.0, e, np.random.default_rng(seed))
        errs.append(earth.lla_to_ned(g.lla, truth.lla[0]))
        verr.append(g.v_n)
    errs = np.concatenate(errs)
    total = np.sqrt([1.0**2 + 0.5**2, 1.0**2 + 0.5**2, 2.0**2 + 1.0**2])
    assert np.allclose(errs.std(axis=0), total, rtol=0.15)
    assert np.allclose(np.concatenate(verr).std(axis=0), 0.1, rtol=0.15)
    assert np.allclose(g.sigma_ned[0], total)


def test_outages_lever_arm_latency_outliers():
    e = GnssErrors(rate_hz=2.0, white_h_m=0.0, white_v_m=0.0, lever_arm_b_m=(1.0, 0.0, -2.0),
                   outages=((10.0, 20.0),), velocity_sigma_m_s=0.0, latency_s=0.3)
    g, _ = simulate_gnss(TRAJ, 0.0, 60.0, e, np.random.default_rng(0))
    assert not ((g.time >= 10.0) & (g.time <= 20.0)).any()
    assert len(g) == 121 - 21
    truth = TRAJ.kinematics(np.array([0.0]))
    off = earth.lla_to_ned(g.lla[0], truth.lla[0])
    assert np.allclose(off, truth.C_nb[0] @ [1.0, 0.0, -2.0], atol=1e-6)
    assert g.v_n is None
    e2 = GnssErrors(rate_hz=10.0, white_h_m=0.1, outlier_probability=0.05, outlier_sigma_m=50.0)
    g2, drawn = simulate_gnss(TRAJ, 0.0, 1000.0, e2, np.random.default_rng(1))
    big = np.abs(earth.lla_to_ned(g2.lla, truth.lla[0])[:, 0]) > 2.0
    assert big.mean() == pytest.approx(0.05 * 0.97, rel=0.15)


def test_outages_that_remove_every_fix_are_refused_naming_the_key():
    """`outages_s = [[0, 100]]` on a 10 s scenario was an internal error (an array of no rows reshaped); no
    consumer can use an empty GNSS file (navigate needs two fixes), so the key is named instead."""
    from inskit.errors import ConfigError

    e = GnssErrors(outages=((0.0, 100.0),))
    with pytest.raises(ConfigError, match=r"^field 'gnss.outages_s': the outages \[\[0.0, 100.0\]\] remove every "
                                          r"GNSS fix of the run \(11 at 1 Hz over 0..10 s\)"):
        simulate_gnss(TRAJ, 0.0, 10.0, e, np.random.default_rng(0))
    g, _ = simulate_gnss(TRAJ, 0.0, 10.0, GnssErrors(outages=((0.0, 9.5),)), np.random.default_rng(0))
    assert list(g.time) == [10.0]  # one fix left: a valid file (navigate says it needs two)
