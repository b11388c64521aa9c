"""INS/GNSS integration: error-state Kalman filter, schemes, smoother.

* :mod:`.blocks`: the blocks of the error state, each owning its meaning.
* :mod:`.layout`: the state layout built from blocks (owns every index).
* :mod:`.measurements`: the measurement protocol and its plug-ins (GNSS
  position and velocity, ZUPT, NHC); :mod:`.tight` (pseudorange and
  pseudorange rate per satellite) and :mod:`.aiding` (odometer, GNSS speed
  and course, height) add more.
* :mod:`.engine`: the filter loop (open and closed loop).
* :mod:`.uncoupled`: the uncoupled scheme (GNSS resets the INS).
* :mod:`.smoother`: Rauch-Tung-Striebel smoothing of a closed-loop run.

Jobs built on it (the navigate job, outage scoring, plots, Monte Carlo) live
in :mod:`inskit.jobs`.

References: SYSTEM.md §2 and §3; Groves 2013 ch. 14.
"""

from .aiding import GnssSpeedCourse, Height, Odometer, OdometerScale
from .blocks import (AccelBias, AccelScale, AttitudeError, GnssPositionError, GyroBias, GyroScale, HeightBias,
                     InitialUncertainty, LeverArm, Mounting, PositionError, SensorNoise, StateBlock, TimeOffset,
                     VelocityError, ins_blocks)
from .engine import FilterOutput, FilterSettings, Track, run_filter
from .layout import StateLayout
from .measurements import (GnssPosition, GnssVelocity, Measurement, NonHolonomic, UpdateContext, ZeroVelocity,
                           perturbed_context)
from .smoother import rts_smooth
from .uncoupled import run_uncoupled

__all__ = [
    "GnssSpeedCourse", "Height", "HeightBias", "Odometer", "OdometerScale",
    "AccelBias", "AccelScale", "AttitudeError", "FilterOutput", "FilterSettings", "GnssPosition", "GnssVelocity",
    "GnssPositionError", "GyroBias", "GyroScale", "InitialUncertainty", "LeverArm", "Measurement", "Mounting",
    "NonHolonomic", "PositionError",
    "SensorNoise", "StateBlock", "StateLayout", "TimeOffset", "Track", "UpdateContext", "VelocityError",
    "ZeroVelocity", "ins_blocks", "perturbed_context", "rts_smooth", "run_filter", "run_uncoupled",
]
