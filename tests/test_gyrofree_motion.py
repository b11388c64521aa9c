"""Rigid-body motions, and the exact angular acceleration the simulator's
trajectories gained for the arrays (inskit.gyrofree.motion, simulation.trajectory,
simulation.segments)."""

from pathlib import Path

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.gyrofree.motion import (
    ConstantRateMotion,
    HarmonicBodyMotion,
    RigidMotion,
    angular_acceleration_ib_b,
    motion_from_trajectory,
)
from inskit.simulation import ConingTrajectory, HarmonicTrajectory, Kinematics
from inskit.simulation.imu import ideal_rates
from inskit.simulation.scenario import build_trajectory, load_scenario

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def harmonic():
    return HarmonicTrajectory((0.7, 0.1, 100.0), north=(0.0, 20.0, [(5.0, 0.5, 0.1)]),
                              east=(0.0, 10.0, [(3.0, 0.3, 0.1)]), up=(0.0, 0.0, [(2.0, 0.4, 0.0)]),
                              roll=(0.1, 0.01, [(0.3, 2.0, 0.4)]), pitch=(0.0, 0.0, [(0.2, 1.3, 0.1)]),
                              yaw=(1.0, 0.1, [(0.5, 0.7, 0.3)]))


def central(fn, t, h):
    return (fn(t + h) - fn(t - h)) / (2 * h)


# Tolerances: a central difference with step h has truncation h^2/6 |x'''| and
# rounding ~1e-16 |x| / h; the bounds below are a few times the larger of the two
# for each motion, far below any error of a wrong formula (a missing term is
# of the size of the angular acceleration itself, 1e-2..1e1 rad/s^2).
@pytest.mark.parametrize("case", ["harmonic", "coning", "car", "aircraft"])
def test_exact_angular_acceleration_of_the_trajectories(case):
    if case == "harmonic":
        tr, t, h, tol = harmonic(), np.linspace(0, 20, 801), 1e-4, 1e-8
    elif case == "coning":
        tr, t, h, tol = ConingTrajectory((0.7, 0, 0), (0.1, 0.2, 0.3), 0.1, 2.0), np.linspace(0, 5, 401), 1e-5, 1e-7
    else:
        tr = build_trajectory(load_scenario(EXAMPLES / f"{case}.toml"), np.random.default_rng(0))
        t, h, tol = np.linspace(1, min(tr.duration, 600) - 1, 4001), 1e-4, 3e-8
    k = tr.kinematics(t)
    fd = central(lambda x: tr.kinematics(x).omega_nb_b, t, h)
    assert np.abs(fd - k.omega_dot_nb_b).max() < tol
    w, dw = angular_acceleration_ib_b(k)
    fd = central(lambda x: ideal_rates(tr.kinematics(x))[0], t, h)
    assert np.abs(fd - dw).max() < tol
    assert np.allclose(w, ideal_rates(k)[0], rtol=0, atol=1e-15)


def test_earth_and_transport_rate_terms():
    """Level flight at constant velocity: omega_nb = 0, so omega_dot_ib comes
    only from the transport rate changing with latitude (about 4e-9 rad/s^2)."""
    tr = HarmonicTrajectory((0.7, 0.1, 100.0), north=(0.0, 300.0, []), east=(0.0, 200.0, []))
    t = np.linspace(0, 20, 201)
    dw = motion_from_trajectory(tr, t).omega_dot_ib_b
    fd = central(lambda x: motion_from_trajectory(tr, x).omega_ib_b, t, 1e-3)
    assert np.abs(dw).max() > 1e-9
    assert np.abs(fd - dw).max() < 1e-14


def test_kinematics_stays_backward_compatible():
    z = np.zeros((2, 3))
    k = Kinematics(np.array([0.0, 1.0]), z, z, z, np.tile(np.eye(3), (2, 1, 1)), z)
    assert k.omega_dot_nb_b is None
    with pytest.raises(InputError, match="no exact angular acceleration"):
        angular_acceleration_ib_b(k)


def test_source_scenario_closed_form():
    """SOURCES-NOTES 1.7: r(10 s) = [350.07, 815.02, 1006.63] m from rest, C(0) = I."""
    m = ConstantRateMotion()
    tr = m.truth(np.linspace(0, 10, 10001))
    assert np.allclose(tr.r_i[-1], [350.07, 815.02, 1006.63], atol=0.005)
    # consistency of the closed forms: v = dr/dt, dv/dt = C f, q is exp(t [w x])
    t = np.linspace(0.5, 9.5, 19)
    h = 1e-4
    v_fd = (m.truth(t + h).r_i - m.truth(t - h).r_i) / (2 * h)
    a_fd = (m.truth(t + h).v_i - m.truth(t - h).v_i) / (2 * h)
    s = m.truth(t)
    assert np.abs(v_fd - s.v_i).max() < 1e-5
    assert np.abs(a_fd - np.einsum("nij,j->ni", s.C_ib, m.f_b)).max() < 1e-5
    with pytest.raises(InputError, match="non-zero"):
        ConstantRateMotion((0, 0, 0))


def test_harmonic_body_motion_derivative(rng):
    hm = HarmonicBodyMotion.random(rng)
    t = np.linspace(0, 10, 101)
    fd = central(lambda x: hm.motion(x).omega_ib_b, t, 1e-5)
    assert np.abs(fd - hm.motion(t).omega_dot_ib_b).max() < 1e-8
    zc = HarmonicBodyMotion.zero_crossing().motion(np.linspace(0, 60, 6001)).omega_ib_b
    assert all((np.diff(np.sign(zc[:, j])) != 0).sum() >= 4 for j in range(3))  # each rate crosses zero


def test_rigid_motion_validates():
    with pytest.raises(InputError, match="shape"):
        RigidMotion(np.arange(3.0), np.zeros((3, 3)), np.zeros((2, 3)), np.zeros((3, 3)))
    with pytest.raises(InputError, match="strictly increase"):
        RigidMotion(np.array([0.0, 0.0]), np.zeros((2, 3)), np.zeros((2, 3)), np.zeros((2, 3)))
