"""Initial alignment of a strapdown IMU.

* :mod:`.coarse`: levelling on a static start and heading from the GNSS track
  (the integration filter's start-up), static-interval detection.
* :mod:`.inmotion`: start-up on a log without rest (levelling on the
  specific force less the GNSS acceleration, heading from the course) and
  the bank of yaw hypotheses for a large heading error; ``auto_startup``
  chooses between static and in-motion.
* :mod:`.analytic`: the one-step analytic alignment of source 002:
  accelerometer basis, gyro basis, their blend by m, the criterion J, eq. 29.
* :mod:`.optimize`: the blending gain by a genetic algorithm and by a scalar
  minimiser.
* :mod:`.fine`: fine alignment by a stationary Kalman filter (ZUPT,
  gyrocompassing) with convergence times.
* :mod:`.reproduce`: source 002's figures and headline case.
"""

from .analytic import accel_basis, blend, criterion, eq29, eq29_rms, general_analytic, gyro_basis, measured_latitude
from .coarse import detect_motion_start, detect_static_start, heading_from_track, level, startup_state
from .static import align_static

__all__ = [
    "accel_basis",
    "align_static",
    "blend",
    "criterion",
    "detect_motion_start",
    "detect_static_start",
    "eq29",
    "eq29_rms",
    "general_analytic",
    "gyro_basis",
    "heading_from_track",
    "level",
    "measured_latitude",
    "startup_state",
]
