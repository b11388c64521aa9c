"""GPS time: seconds since the GPS epoch, weeks and seconds of week.

All GNSS times in :mod:`inskit.gnss` are float seconds since the GPS epoch
1980-01-06 00:00:00 on the GPS time scale (no leap seconds).  A float64 near
1.4e9 s resolves 0.24 microseconds, i.e. < 1 mm of satellite motion.

Galileo System Time is steered to GPS time (offset tens of ns, broadcast as
GGTO) and counts the same seconds; its week number is the GPS week minus
1024 (Galileo OS SIS ICD 5.1.2).  RINEX 3 navigation files write the Galileo
week continuous with the GPS week, which is what :func:`from_week_sow`
takes; :func:`gal_week_to_gps_week` converts a raw GST week.

References
----------
IS-GPS-200N 20.3.3.3.3 and 3.3.4 (GPS time, week number, seconds of week).
Galileo OS SIS ICD Issue 2.0, 5.1.2 (GST).
"""

from __future__ import annotations

from datetime import datetime

import numpy as np

from .constants import GAL_WEEK_OFFSET, SECONDS_PER_DAY, SECONDS_PER_WEEK

GPS_EPOCH = datetime(1980, 1, 6)
GPS_EPOCH_NP = np.datetime64("1980-01-06T00:00:00", "ns")


def _days_from_civil(y, m, d):
    """Days since 1970-01-01 of a proleptic Gregorian date (integer arrays).

    The standard era arithmetic (400-year cycles of 146097 days, with March
    as the first month so the leap day ends the year).
    """
    y = np.asarray(y, dtype=np.int64)
    m = np.asarray(m, dtype=np.int64)
    d = np.asarray(d, dtype=np.int64)
    y = y - (m <= 2)
    era = np.floor_divide(y, 400)
    yoe = y - era * 400
    mp = (m + 9) % 12
    doy = (153 * mp + 2) // 5 + d - 1
    doe = yoe * 365 + yoe // 4 - yoe // 100 + doy
    return era * 146097 + doe - 719468


_GPS_EPOCH_DAYS = int(_days_from_civil(1980, 1, 6))


def gps_seconds(year, month, day, hour=0, minute=0, second=0.0):
    """Seconds since the GPS epoch of a calendar date and time on the GPS scale.

    Parameters
    ----------
    year, month, day, hour, minute : int or array_like of int
        Calendar fields (four-digit year).
    second : float or array_like
        Seconds, fractional allowed.

    Returns
    -------
    float or ndarray
        Same shape as the broadcast inputs; a Python float for scalar input.
    """
    days = _days_from_civil(year, month, day) - _GPS_EPOCH_DAYS
    t = (days * SECONDS_PER_DAY + np.asarray(hour, dtype=float) * 3600.0
         + np.asarray(minute, dtype=float) * 60.0 + np.asarray(second, dtype=float))
    return float(t) if np.ndim(t) == 0 else t


def week_sow(t_gps_s):
    """GPS week number and seconds of week of a time since the GPS epoch.

    Parameters
    ----------
    t_gps_s : float or array_like
        Seconds since the GPS epoch.

    Returns
    -------
    week : int64 ndarray (same shape)
        Full (not modulo 1024) GPS week number.
    sow : float ndarray (same shape)
        Seconds of week in [0, 604800).
    """
    t = np.asarray(t_gps_s, dtype=float)
    week = np.floor(t / SECONDS_PER_WEEK).astype(np.int64)
    return week, t - week * SECONDS_PER_WEEK


def from_week_sow(week, sow):
    """Seconds since the GPS epoch from a full GPS week number and seconds of week."""
    t = np.asarray(week, dtype=float) * SECONDS_PER_WEEK + np.asarray(sow, dtype=float)
    return float(t) if np.ndim(t) == 0 else t


def gal_week_to_gps_week(gst_week):
    """GPS week number of a raw Galileo System Time week number (+1024)."""
    return np.asarray(gst_week) + GAL_WEEK_OFFSET


def to_datetime64(t_gps_s):
    """GPS-scale ``datetime64[ns]`` of seconds since the GPS epoch (for display)."""
    t = np.asarray(t_gps_s, dtype=float)
    return GPS_EPOCH_NP + np.round(t * 1e9).astype("timedelta64[ns]")


#: The UTC dates (00:00:00) from which GPS time - UTC grew by one second, 1 s on 1981-07-01 to 18 s on
#: 2017-01-01 (IERS Bulletin C; none announced since: Bulletin C 70, July 2025).  RTKLIB's ``leaps`` table.
LEAP_SECOND_DATES = ("1981-07-01", "1982-07-01", "1983-07-01", "1985-07-01", "1988-01-01", "1990-01-01",
                     "1991-01-01", "1992-07-01", "1993-07-01", "1994-07-01", "1996-01-01", "1997-07-01",
                     "1999-01-01", "2006-01-01", "2009-01-01", "2012-07-01", "2015-07-01", "2017-01-01")
_LEAP_NS = ((np.array(LEAP_SECOND_DATES, dtype="datetime64[ns]") - GPS_EPOCH_NP).astype(np.int64))


def gps_minus_utc_s(utc_ns):
    """GPS time - UTC [whole s] at UTC instants (:data:`LEAP_SECOND_DATES`).

    Parameters
    ----------
    utc_ns : int or (n,) array_like of int
        UTC date and time as integer nanoseconds since 1980-01-06 00:00:00,
        counted as a calendar counts them (no leap seconds), as a UTC time
        stamp parsed with ``datetime64`` is.

    Returns
    -------
    int or (n,) int ndarray
        Seconds to add to get GPS time: 0 before 1981-07-01, 18 since
        2017-01-01.
    """
    return np.searchsorted(_LEAP_NS, np.asarray(utc_ns, dtype=np.int64), side="right")
