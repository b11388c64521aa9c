import numpy as np
import pytest

from inskit import earth
from inskit.simulation import HarmonicTrajectory, ideal_imu, ideal_rates

TRAJ = HarmonicTrajectory(
    (np.radians(30.0), np.radians(20.0), 200.0),
    north=(0.0, 10.0, [(100.0, 0.05, 0.0)]),
    east=(0.0, -3.0, [(80.0, 0.07, 1.0)]),
    up=(0.0, 0.5, [(10.0, 0.1, 0.0)]),
    roll=(0.0, 0.0, [(0.3, 0.2, 0.0)]),
    pitch=(0.0, 0.0, [(0.2, 0.3, 0.0)]),
    yaw=(1.0, 0.02, [(0.5, 0.1, 0.0)]),
)


def test_velocity_is_derivative_of_position_and_acceleration_of_velocity():
    t = np.linspace(10.0, 50.0, 41)
    h = 1e-4
    k0, kp, km = TRAJ.kinematics(t), TRAJ.kinematics(t + h), TRAJ.kinematics(t - h)
    dp = (earth.lla_to_ned(kp.lla, k0.lla[0]) - earth.lla_to_ned(km.lla, k0.lla[0])) / (2 * h)
    # NED displacement differences are not exactly v_n far from the reference point,
    # but within 1e-4 m/s over these few hundred metres
    assert np.abs(dp - k0.v_n).max() < 1e-3
    a = (kp.v_n - km.v_n) / (2 * h)
    assert np.abs(a - k0.a_n).max() < 1e-6


def test_body_rate_matches_attitude_derivative():
    t = np.linspace(0.0, 20.0, 21)
    h = 1e-5
    C, Cp, Cm = (TRAJ.kinematics(x).C_nb for x in (t, t + h, t - h))
    dC = (Cp - Cm) / (2 * h)
    w_skew = np.swapaxes(C, 1, 2) @ dC
    w = 0.5 * np.stack([w_skew[:, 2, 1] - w_skew[:, 1, 2], w_skew[:, 0, 2] - w_skew[:, 2, 0],
                        w_skew[:, 1, 0] - w_skew[:, 0, 1]], 1)
    assert np.abs(w - TRAJ.kinematics(t).omega_nb_b).max() < 1e-8


def test_ideal_imu_at_rest_reads_gravity_and_earth_rate():
    from inskit.simulation import StationaryTrajectory

    lat = np.radians(45.0)
    kin = StationaryTrajectory((lat, 0.0, 0.0)).kinematics(np.array([0.0]))
    w, f = ideal_rates(kin)
    assert np.allclose(f[0], [0, 0, -earth.gravity_down(lat, 0.0)])
    assert np.allclose(w[0], earth.rate_ie_n(lat))


@pytest.mark.parametrize("model", ["normal", "normal-simple", "j2"])
def test_ideal_imu_at_rest_senses_the_chosen_gravity_model(model):
    # at rest f_n = -g_n: the accelerometers of a level body at 1600 m read the model's
    # north and down components (the normal model's north part is -8.08e-9 h sin 2 lat)
    from inskit.simulation import StationaryTrajectory

    lat, h = np.radians(40.0), 1600.0
    tr = StationaryTrajectory((lat, 0.3, h))
    _, f = ideal_rates(tr.kinematics(np.array([0.0])), model)
    assert np.allclose(f[0], -earth.gravity_n(lat, h, model), rtol=0, atol=1e-15)
    imu = ideal_imu(tr, np.array([0.0, 0.01]), nodes=1, gravity=model)
    assert np.allclose(imu.dv_b[1] / 0.01, f[0], rtol=0, atol=1e-12)


def test_increments_converge_with_quadrature_order():
    t = np.arange(0.0, 10.0, 0.01)
    a = ideal_imu(TRAJ, t, nodes=4)
    b = ideal_imu(TRAJ, t, nodes=8)
    assert np.abs(a.dtheta_b - b.dtheta_b).max() < 1e-15
    assert np.abs(a.dv_b - b.dv_b).max() < 1e-13


def test_segment_trajectory_continues_smoothly_just_before_time_zero():
    """Raw GNSS receives at true times earlier than the first receiver tag by the clock offset
    (~0.1 ms): the trajectory there is the smooth continuation, position the integral of velocity."""
    from inskit.simulation.segments import SegmentTrajectory

    tr = SegmentTrajectory((np.radians(40.0), np.radians(-105.0), 1600.0), 0.3, 0.0, 2.0)
    tr.static(10.0).accelerate(10.0, 5.0).cruise(10.0)
    tr.vibration("down", 0.001, 9.0)
    t = np.array([-1e-3, -1e-4, 0.0])
    k = tr.kinematics(t)
    d = earth.lla_to_ned(k.lla, k.lla[2])
    np.testing.assert_allclose(d, k.v_n[2] * t[:, None], atol=1e-7)   # jerk term (w^3 A t^3 / 6) 3e-8 m
    assert np.isfinite(k.C_nb).all()


@pytest.mark.parametrize("nodes", [1, 2, 3])
def test_the_increment_error_of_a_sinusoid_is_the_quadratures(nodes):
    """sinusoid_increment_error is what ideal_imu's quadrature does to a vibration: the increments of a
    heave at f differ from exact ones (12 nodes) by that fraction, at every sample and phase."""
    from inskit.simulation.imu import sinusoid_increment_error
    from inskit.simulation.segments import SegmentTrajectory

    rate = 100.0
    for ratio in (0.1234, 0.3123, 0.4567):
        tr = SegmentTrajectory((np.radians(40.0), 0.0, 100.0))
        tr.static(5.0).vibration("down", 1e-4, ratio * rate)
        t = np.arange(0.0, 5.0, 1.0 / rate)
        exact = ideal_imu(tr, t, nodes=12).dv_b[1:, 2]
        got = ideal_imu(tr, t, nodes=nodes).dv_b[1:, 2]
        osc = exact - np.median(exact)  # the vibration's part (gravity is integrated exactly)
        err = sinusoid_increment_error(nodes, ratio)
        assert np.abs(got - exact).max() == pytest.approx(err * np.abs(osc).max(), rel=0.02)


def test_the_highest_frequency_an_imu_takes():
    """From 3 nodes the Nyquist frequency (exclusive) binds, below it the 0.1 % of the quadrature."""
    from inskit.simulation.imu import INCREMENT_TOLERANCE, max_oscillation_hz, sinusoid_increment_error

    for n in range(3, 13):
        assert max_oscillation_hz(100.0, n) == (50.0, False, "nyquist")
        assert sinusoid_increment_error(n, 0.5) <= INCREMENT_TOLERANCE
    for n, lim in ((1, 2.4648), (2, 22.574)):
        f, inclusive, reason = max_oscillation_hz(100.0, n)
        assert (f, inclusive, reason) == (pytest.approx(lim, abs=1e-3), True, "quadrature")
        assert sinusoid_increment_error(n, f / 100.0) <= INCREMENT_TOLERANCE * (1 + 1e-9)
        assert sinusoid_increment_error(n, f / 99.0) > INCREMENT_TOLERANCE
        assert max_oscillation_hz(400.0, n)[0] == pytest.approx(4 * f)
    r = np.linspace(1e-3, 0.5, 500)
    for n in range(1, 13):  # the bisection's premise: the error grows with the frequency below Nyquist
        e = np.array([sinusoid_increment_error(n, x) for x in r])
        assert (np.diff(e) >= -1e-15).all()
