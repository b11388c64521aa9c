"""RTS smoothing of a closed-loop run: better than the forward filter inside
an outage, smaller sigmas, every block smoothed, consistent with the truth."""

import numpy as np
import pytest

from inskit import earth
from inskit.errors import InputError
from inskit.integration import GnssPosition, rts_smooth, run_filter
from inskit.jobs.montecarlo import consistency_errors, matched_settings, perturbed_start
from inskit.integration import InitialUncertainty
from inskit.simulation import ideal_imu, truth_solution
from inskit.simulation.gnss import GnssErrors, simulate_gnss
from inskit.simulation.segments import SegmentTrajectory
from inskit.simulation.sensors import apply_imu_errors, preset


@pytest.fixture(scope="module")
def run():
    tr = SegmentTrajectory((np.radians(45), np.radians(7), 300.0), yaw0=0.3)
    tr.static(20).accelerate(12, 8).cruise(20).turn(np.radians(90), rate=np.radians(9)).cruise(30)
    tr.turn(np.radians(-60), rate=np.radians(6)).cruise(30)
    t = np.arange(0.0, tr.duration, 0.01)
    rng = np.random.default_rng(7)
    errs = consistency_errors(preset("industrial-mems"))
    imu, _ = apply_imu_errors(ideal_imu(tr, t, nodes=3), errs, rng)
    gnss, _ = simulate_gnss(tr, t[0], t[-1], GnssErrors(rate_hz=1.0, white_h_m=0.3, white_v_m=0.5,
                                                        velocity_sigma_m_s=0.0), rng)
    truth = truth_solution(tr, t)
    init = InitialUncertainty(pos_m=(1.0, 1.0, 2.0), vel_m_s=0.1, roll_pitch_rad=np.radians(1.0),
                              yaw_rad=np.radians(3.0))
    settings = matched_settings(errs, init, gate_probability=None)
    outage = (gnss.time > 75.0) & (gnss.time < 95.0)
    start = perturbed_start(truth.state(0), settings, rng)
    out = run_filter(imu, start, [GnssPosition(gnss, ~outage)], settings, smoother=True)
    return out, rts_smooth(out), truth


def _horizontal(nav, truth, m):
    d = earth.lla_to_ned(nav.lla[m], truth.lla[m])
    return np.hypot(d[:, 0], d[:, 1])


def test_smoother_beats_the_forward_filter_in_the_outage(run):
    out, sm, truth = run
    m = (truth.time > 75.0) & (truth.time < 95.0)
    f, s = _horizontal(out.nav, truth, m), _horizontal(sm.nav, truth, m)
    assert s.max() < 0.5 * f.max()
    k = np.asarray(out.store.k)  # at the nodes the smoothed covariance is below the filtered one
    assert np.all(sm.sigma[k] <= out.sigma[k] * (1 + 1e-6) + 1e-12)


def test_smoothed_errors_are_within_their_sigmas(run):
    """Horizontal error over its sigma: RMS near 1 (0.3..1.5 allows for one run
    and correlated errors along it)."""
    _, sm, truth = run
    d = earth.lla_to_ned(sm.nav.lla[::50], truth.lla[::50])
    z = d[:, :2] / sm.sigma[::50, :2]
    assert 0.3 < np.sqrt(np.mean(z**2)) < 1.5


def test_every_block_is_smoothed_and_named(run):
    out, sm, _ = run
    assert sm.aux.shape == out.aux.shape and sm.sigma.shape == out.sigma.shape
    assert not np.allclose(sm.estimate("bg"), out.estimate("bg"))
    assert "bg_x_rad_s" in sm.solution.extra and "sigma_n_m" in sm.solution.extra


def test_smoother_needs_the_store():
    class NoStore:
        store = None

    with pytest.raises(InputError, match="smoother=True"):
        rts_smooth(NoStore())
