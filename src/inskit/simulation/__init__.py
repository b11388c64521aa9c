"""Simulation: reference trajectories and ideal (and, later, erroneous) sensors.

* :mod:`.trajectory`: closed-form reference motions that give position,
  velocity, acceleration, attitude and body rate at any time.
* :mod:`.imu`: the exact IMU output of a trajectory, as rates or as
  increments integrated by Gauss-Legendre quadrature (exact to numerical
  precision for smooth motion).
"""

from .imu import ideal_imu, ideal_rates, truth_solution
from .trajectory import ConingTrajectory, HarmonicTrajectory, Kinematics, StationaryTrajectory

__all__ = [
    "ConingTrajectory",
    "HarmonicTrajectory",
    "Kinematics",
    "StationaryTrajectory",
    "ideal_imu",
    "ideal_rates",
    "truth_solution",
]
