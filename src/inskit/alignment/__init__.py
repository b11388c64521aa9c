"""Initial alignment.

:mod:`.coarse`: levelling from a static accelerometer average and heading
from the GNSS track, the start-up that the integration filter uses.
"""

from .coarse import detect_motion_start, heading_from_track, level, startup_state

__all__ = ["detect_motion_start", "heading_from_track", "level", "startup_state"]
