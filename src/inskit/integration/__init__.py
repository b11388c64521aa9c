"""INS/GNSS integration: error-state Kalman filter, schemes, smoother.

* :mod:`.layout`: the state layout (owns every index).
* :mod:`.measurements`: plug-ins (GNSS position and velocity, ZUPT, NHC).
* :mod:`.engine`: the filter loop (uncoupled, open loop, closed loop).
* :mod:`.smoother`: Rauch-Tung-Striebel smoothing of a closed-loop run.
* :mod:`.outages`: outage protocols and their scoring.
* :mod:`.navigate`: the whole job from a validated config.

References: SYSTEM.md §2 and §3; Groves 2013 ch. 14.
"""

from .engine import FilterOutput, FilterSettings, InitialUncertainty, SensorNoise, run_filter
from .layout import StateLayout
from .measurements import GnssPosition, GnssVelocity, NonHolonomic, ZeroVelocity

__all__ = [
    "FilterOutput",
    "FilterSettings",
    "GnssPosition",
    "GnssVelocity",
    "InitialUncertainty",
    "NonHolonomic",
    "SensorNoise",
    "StateLayout",
    "ZeroVelocity",
    "run_filter",
]
