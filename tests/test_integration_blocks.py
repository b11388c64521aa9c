"""State blocks: a user-defined block runs in the filter without editing any
inskit file, and its covariance follows the closed form; the standard
blocks say what they mean."""

import math

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.integration import (AccelBias, FilterSettings, GnssPosition, GyroBias, HeightBias, LeverArm, SensorNoise,
                                StateBlock, TimeOffset, ins_blocks, run_filter)
from inskit.simulation import StationaryTrajectory, ideal_imu, truth_solution
from inskit.types import GnssData, ImuData

SB, SD = 30.0, 0.5         # initial sigmas: clock bias [m], drift [m/s]
QB, QD = 0.04, 1e-3        # random-walk PSDs [m^2/s], [m^2/s^3]


class ReceiverClock(StateBlock):
    """A two-state clock written outside the package: bias and drift, each
    driven by white noise, ``d bias / dt = drift``."""

    def __init__(self, bias0=0.0):
        super().__init__("clock", ("bias", "drift"), "m", (SB, SD), (QB, QD), math.inf,
                         estimate0=(bias0, 0.0), entries=((0, "clock", 1, 1.0),),
                         description="receiver clock bias and drift, in metres")


class ClockFix:
    """A user measurement plug-in that observes the clock bias directly."""

    name = "clock_fix"
    gating = "vector"

    def __init__(self, t, z, sigma):
        self.t, self.z, self.sigma = np.asarray(t), np.asarray(z), sigma

    def times(self):
        return self.t

    def rows(self):
        return np.arange(len(self.t))

    def linearize(self, ctx, row):
        H = np.zeros((1, ctx.layout.size))
        H[0, ctx.layout.slice("clock").start] = 1.0
        return ctx.estimate("clock")[:1] - self.z[row], H, np.array([[self.sigma**2]])


def static_log(duration=600.0, rate=100.0, seed=3):
    tr = StationaryTrajectory((np.radians(45.0), np.radians(7.0), 200.0), (0.01, -0.02, 1.0))
    t = np.arange(0.0, duration + 1e-9, 1.0 / rate)
    ideal = ideal_imu(tr, t, nodes=1)
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate
    imu = ImuData(t, ideal.dtheta_b + rng.normal(0, 1e-4 * np.sqrt(dt), ideal.dtheta_b.shape),
                  ideal.dv_b + rng.normal(0, 1e-3 * np.sqrt(dt), ideal.dv_b.shape))
    start = truth_solution(tr, t[:1]).state(0)
    tg = t[100::100]
    gnss = GnssData(tg, np.tile(start.lla, (len(tg), 1)), np.full((len(tg), 3), 0.5))
    return imu, start, gnss


def test_user_clock_block_covariance_follows_the_random_walk_closed_form():
    """Static log, GNSS position updates at 1 Hz (which do not see the clock):
    ``P_bb(t) = sb^2 + qb t + sd^2 t^2 + qd t^3 / 3`` and ``P_dd = sd^2 + qd t``
    within 1 % at every IMU epoch."""
    imu, start, gnss = static_log()
    settings = FilterSettings.standard(SensorNoise(1e-4, 1e-3, 1e-6, 1e-5), extra_blocks=[ReceiverClock()])
    out = run_filter(imu, start, [GnssPosition(gnss)], settings)
    assert out.counts["gnss_pos"]["used"] == len(gnss)
    t = imu.time - imu.time[0]
    sig = out.sigma_of("clock")
    p_bb = SB**2 + QB * t + SD**2 * t**2 + QD * t**3 / 3.0
    p_dd = SD**2 + QD * t
    assert np.max(np.abs(sig[:, 0] ** 2 / p_bb - 1)) < 0.01
    assert np.max(np.abs(sig[:, 1] ** 2 / p_dd - 1)) < 0.01
    # and the named columns carry it, made from the block's own names
    assert "clock_bias_m" in out.solution.extra


def test_user_block_and_measurement_estimate_a_clock():
    """The user measurement observes the user block; feedback goes into the
    block's estimate; the truth (a constant 40 m bias) ends within 3 sigma."""
    imu, start, gnss = static_log(120.0)
    rng = np.random.default_rng(5)
    tc = imu.time[50::50]
    z = 40.0 + rng.normal(0, 2.0, len(tc))
    settings = FilterSettings.standard(SensorNoise(1e-4, 1e-3, 1e-6, 1e-5), extra_blocks=[ReceiverClock()])
    out = run_filter(imu, start, [GnssPosition(gnss), ClockFix(tc, z, 2.0)], settings)
    est, sig = out.estimate("clock")[-1], out.sigma_of("clock")[-1]
    assert abs(est[0] - 40.0) < 3 * sig[0]
    assert sig[0] < 1.0  # far below the 30 m prior and the 2 m noise of one fix
    assert out.counts["clock_fix"]["used"] == len(tc)


def test_blocks_refuse_what_they_cannot_mean():
    with pytest.raises(InputError, match="sigma"):
        StateBlock("x", ("a",), "m", sigma0=0.0)
    with pytest.raises(InputError, match="one per axis"):
        StateBlock("x", ("a", "b"), "m", sigma0=(1.0, 2.0, 3.0))
    with pytest.raises(InputError, match="tau_s"):
        StateBlock("x", ("a",), "m", tau_s=-1.0)
    with pytest.raises(InputError, match="role"):
        StateBlock("x", ("a",), "m", role="odometer")
    with pytest.raises(InputError, match="3 axes"):
        StateBlock("x", ("a",), "m", role="gyro_bias")


def test_standard_blocks_own_their_noise_and_transition():
    g = GyroBias(sigma0=1e-3, instability=2e-5, tau_s=100.0)
    assert g.psd == pytest.approx(2 * (2e-5) ** 2 / 100.0)     # Gauss-Markov: 2 sigma^2 / tau
    assert g.transition() == [(i, "bg", i, -0.01) for i in range(3)]
    rw = AccelBias(sigma0=0.1, instability=1e-4)                 # random walk
    assert rw.psd == pytest.approx(1e-8) and rw.transition() == []
    assert LeverArm().estimate_names() == ["lever_x_m", "lever_y_m", "lever_z_m"]
    assert TimeOffset().estimate_names() == ["time_offset_s"]
    names = [b.name for b in ins_blocks(scale_factors=True, lever_arm=True, time_offset=True)]
    assert names == ["pos", "vel", "att", "bg", "ba", "sg", "sa", "lever", "time_offset"]


def test_separate_correlation_times_per_sensor():
    blocks = ins_blocks(SensorNoise(1e-3, 1e-2, 1e-5, 1e-4, bias_tau_s=300.0, accel_bias_tau_s=60.0))
    assert blocks[3].tau_s == 300.0 and blocks[4].tau_s == 60.0


def test_custom_feedback_is_used():
    """A block may feed its estimate back its own way (here: a logarithmic
    scale, fed back multiplicatively)."""

    class LogScale(StateBlock):
        def feedback(self, estimate, dx):
            estimate *= np.exp(-dx)

    imu, start, gnss = static_log(30.0)
    blk = LogScale("k", ("k",), "", 0.1, 0.0, estimate0=2.0)
    settings = FilterSettings.standard(extra_blocks=[blk])
    out = run_filter(imu, start, [GnssPosition(gnss)], settings)
    assert out.estimate("k")[-1, 0] == pytest.approx(2.0)  # unobserved: no correction at all


def test_mounting_dcm_is_the_mount_rotation_and_its_derivatives():
    """``C_vb = dcm_from_euler((0, pitch, yaw)).T`` (navigate's mount
    convention) and its two derivatives against central differences (step
    1e-6 rad: truncation 1e-13)."""
    from inskit import rotations as rot
    from inskit.integration.blocks import mounting_dcm

    p, y, h = 0.07, -0.035, 1e-6
    C, d_p, d_y = mounting_dcm(p, y)
    assert np.allclose(C, rot.dcm_from_euler([0.0, p, y]).T, atol=1e-15)
    assert np.allclose(d_p, (mounting_dcm(p + h, y)[0] - mounting_dcm(p - h, y)[0]) / (2 * h), atol=1e-9)
    assert np.allclose(d_y, (mounting_dcm(p, y + h)[0] - mounting_dcm(p, y - h)[0]) / (2 * h), atol=1e-9)


def test_mounting_roll_is_invisible_to_the_vehicle_constraints():
    """Why the block has no roll: the body velocity of a vehicle moving along
    its forward axis, ``C_bv (V, 0, 0)``, is the same for any mounting roll,
    and the vehicle-axes velocity rows the constraints use (forward speed;
    lateral and vertical both zero) are unchanged by any roll about the
    forward axis."""
    from inskit import rotations as rot
    from inskit.integration import Mounting
    from inskit.integration.blocks import mounting_dcm

    p, y = np.radians(4.0), np.radians(2.0)
    v_b = [rot.dcm_from_euler([r, p, y]) @ [15.0, 0.0, 0.0] for r in np.radians([-30.0, 0.0, 10.0, 90.0])]
    assert np.allclose(v_b, v_b[1], atol=1e-12)
    C = mounting_dcm(p, y)[0]
    assert np.allclose(C @ v_b[0], [15.0, 0.0, 0.0], atol=1e-12)
    b = Mounting(sigma0=np.radians(3.0), rw=1e-5)
    assert b.axes == ("pitch", "yaw") and b.size == 2 and b.unit == "rad"
    assert b.estimate_names() == ["mounting_pitch_rad", "mounting_yaw_rad"]
    assert np.allclose(b.sigma0, np.radians(3.0)) and np.allclose(b.psd, 1e-10) and b.transition() == []


def test_height_bias_block_models():
    rw = HeightBias(10.0, "random-walk", rw=0.05)
    assert rw.name == "height_bias" and rw.psd[0] == pytest.approx(0.0025) and rw.transition() == []
    assert rw.estimate_names() == ["height_bias_m"] and rw.sigma_names() == ["sigma_height_bias_m"]
    gm = HeightBias(4.0, "gauss-markov", tau_s=200.0)
    assert gm.psd[0] * gm.tau_s / 2.0 == pytest.approx(16.0)  # steady state = sigma0
    assert gm.transition() == [(0, "height_bias", 0, -1.0 / 200.0)]
    const = HeightBias(3.0, "constant", rw=0.05)
    assert const.psd[0] == 0.0 and math.isinf(const.tau_s)
    est = np.array([2.0])
    const.feedback(est, np.array([0.5]))
    assert est[0] == 1.5  # closed loop: estimate -= dx
    with pytest.raises(InputError, match="tau_s"):
        HeightBias(4.0, "gauss-markov")
    with pytest.raises(InputError, match="one of"):
        HeightBias(4.0, "flicker")
