"""GNSS engine: RINEX reading, broadcast orbits and clocks, atmosphere
models and corrected range tables (layer 3; imports only the scalar cores).

Times are seconds since the GPS epoch (GPS scale); positions ECEF [m];
angles radians; satellites named ``'G05'``, ``'E11'``.
"""

from .atmosphere import (
    KLOBUCHAR_DEFAULT_ALPHA,
    KLOBUCHAR_DEFAULT_BETA,
    elevation_azimuth,
    iono_free,
    klobuchar_delay,
    saastamoinen_delay,
)
from .ephemeris import SatStates, sagnac_rotate, satellite_states, select_records, transmit_time
from .ranges import RangeTable, range_table
from .rinex import NavData, ObsData, read_nav, read_obs
from .time import GPS_EPOCH, from_week_sow, gps_seconds, week_sow

__all__ = [
    "GPS_EPOCH", "gps_seconds", "week_sow", "from_week_sow",
    "ObsData", "NavData", "read_obs", "read_nav",
    "SatStates", "select_records", "satellite_states", "transmit_time", "sagnac_rotate",
    "KLOBUCHAR_DEFAULT_ALPHA", "KLOBUCHAR_DEFAULT_BETA", "elevation_azimuth", "klobuchar_delay",
    "saastamoinen_delay", "iono_free",
    "RangeTable", "range_table",
]
