"""Simulated odometer: the forward speed of its point, scaled, with noise of
the stated sigma; the lever-arm term of a turn; the filter's model reads it
back with zero innovation."""

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.integration import StateLayout, UpdateContext, ins_blocks
from inskit.integration.aiding import Odometer, OdometerScale
from inskit.simulation.imu import truth_solution
from inskit.simulation.odometer import simulate_odometer
from inskit.simulation.segments import SegmentTrajectory

LLA0 = (np.radians(40.0), np.radians(-105.0), 1600.0)


def drive():
    """Static, accelerate to 12 m/s, cruise, a 90 deg turn of radius 20 m, cruise."""
    tr = SegmentTrajectory(LLA0, np.radians(30.0), 0.0, 2.0)
    tr.static(5.0)
    tr.accelerate(12.0, 6.0)
    tr.cruise(10.0)
    tr.turn(np.radians(90.0), radius=20.0)
    tr.cruise(10.0)
    return tr


@pytest.fixture(scope="module")
def truth():
    tr = drive()
    return truth_solution(tr, np.arange(0.0, tr.duration, 0.01), with_rates=True)


def test_noise_free_reading_is_the_scaled_speed(truth):
    """A car drives along its forward axis: with no lever arm the true
    reading is |v_n| (to the 1e-9 of the trajectory's own rounding), scaled
    by 1 + k; readings at 10 Hz inside the truth's span."""
    log = simulate_odometer(truth, rate_hz=10.0, scale_error=0.005, noise_m_s=0.0)
    t, z, _ = log  # unpacks as (time, speed, true speed)
    assert np.allclose(np.diff(t), 0.1) and t[0] == truth.time[0] and t[-1] <= truth.time[-1]
    speed = np.interp(t, truth.time, np.linalg.norm(truth.v_n, axis=1))
    assert np.abs(log.speed_true_m_s - speed).max() < 1e-6
    assert np.abs(z - 1.005 * speed).max() < 1e-6
    assert abs(z.max() - 1.005 * 12.0) < 1e-3 and abs(z[:40]).max() < 1e-9  # 12 m/s cruise, static start


def test_noise_has_the_stated_sigma_and_zero_mean(truth):
    """Residuals of 10 Hz readings: sample sigma within 3 sqrt(1/(2 n)) of
    0.05 m/s, mean within 3 sigma / sqrt(n) of zero (n = 320 readings)."""
    log = simulate_odometer(truth, rate_hz=10.0, scale_error=0.0, noise_m_s=0.05, rng=np.random.default_rng(7))
    r = log.speed_m_s - log.speed_true_m_s
    n = len(r)
    assert abs(r.std() / 0.05 - 1) < 3 / np.sqrt(2 * n)
    assert abs(r.mean()) < 3 * 0.05 / np.sqrt(n)


def test_lever_arm_adds_omega_cross_l_in_the_turn(truth):
    """In the 12 m/s, 20 m turn (yaw rate 0.6 rad/s) a point 1 m to the right
    of the truth point (l = (0, 1, 0)) has the forward speed
    v + (w x l)_x = v - w_z * 1 m: 0.6 m/s slower on the inside of the right
    turn (positive yaw rate turns right)."""
    base = simulate_odometer(truth, noise_m_s=0.0, scale_error=0.0)
    side = simulate_odometer(truth, noise_m_s=0.0, scale_error=0.0, lever_arm_b=(0.0, 1.0, 0.0))
    wz = np.interp(base.time, truth.time, truth.extra["wz_rad_s"])
    assert np.allclose(side.speed_m_s - base.speed_m_s, -wz * 1.0, atol=1e-9)
    assert abs(wz).max() == pytest.approx(0.6, rel=0.02)


def test_resolution_rounds_and_invalid_inputs_raise(truth):
    log = simulate_odometer(truth, noise_m_s=0.0, resolution_m_s=0.1)
    assert np.allclose(log.speed_m_s / 0.1, np.round(log.speed_m_s / 0.1), atol=1e-9)
    assert np.abs(log.speed_m_s - 1.005 * log.speed_true_m_s).max() <= 0.05 + 1e-9
    with pytest.raises(InputError, match="rng"):
        simulate_odometer(truth, noise_m_s=0.1)
    with pytest.raises(InputError, match="with_rates"):
        simulate_odometer(truth_solution(drive(), np.arange(0.0, 5.0, 0.01)), noise_m_s=0.0,
                          lever_arm_b=(1.0, 0.0, 0.0))
    with pytest.raises(InputError, match="rate_hz"):
        simulate_odometer(truth, rate_hz=0.0)


def test_the_filter_model_reads_the_simulation_back(truth):
    """The Odometer plug-in at the true state, with the scale estimate equal
    to the simulated k and the same lever arm, predicts the simulated
    noise-free reading (innovation below 1e-6 m/s) at every reading of the
    turn: simulator and filter share one model and one sign of k."""
    lever = np.array([-1.2, 0.3, 0.4])
    log = simulate_odometer(truth, noise_m_s=0.0, scale_error=-0.01, lever_arm_b=lever)
    lay = StateLayout(ins_blocks() + [OdometerScale()])
    aux = lay.initial_aux()
    aux[lay.aux_slice("odo_scale")] = -0.01
    m = Odometer(log.time, log.speed_m_s, 0.05, lever_arm_b=lever)
    C = truth.C_nb
    w = np.stack([truth.extra[f"w{a}_rad_s"] for a in "xyz"], axis=1)
    worst = 0.0
    for row in range(0, len(log.time), 7):
        k = int(np.argmin(np.abs(truth.time - log.time[row])))
        assert abs(truth.time[k] - log.time[row]) < 1e-9
        ctx = UpdateContext(log.time[row], 0.0, truth.lla[k], truth.v_n[k], C[k], w[k], lay, aux)
        nu, _, _ = m.linearize(ctx, row)
        worst = max(worst, abs(nu[0]))
    assert worst < 1e-6
