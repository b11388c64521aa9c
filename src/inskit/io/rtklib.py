"""Readers for RTKLIB solution files and the rtklibexplorer GNSS/IMU logs.

Time base: GPS time as seconds of the GPS week that a file starts in
(``sow``), continued past 604800 s if a log crosses a week boundary.  Readers
that must agree take the same ``week0``.
"""

from __future__ import annotations

import io
import re
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from .. import earth
from .. import rotations as rot
from ..errors import InputError
from ..files import require_file
from ..types import GnssData, ImuData, check_euler, plain_number
from ..units import DEG, G0, MAX_HEIGHT_M
from .csv_formats import (GZIP_ERRORS, CheckedBytes, TextFault, _header_names, at_row, check_gnss_velocity,
                          check_imu_time, check_imu_units, check_ranges, check_sigmas, check_time_column,
                          cut_short_note, gzip_damage_message, lean_columns, numeric_columns, read_table,
                          repeated_rows, require_columns)
from .time_tags import smooth_time_tags

GPS_EPOCH = datetime(1980, 1, 6, tzinfo=timezone.utc)
WEEK_S = 604800.0


class _BadStamp(ValueError):
    """Row ``index`` of a column of time stamps is not one."""

    def __init__(self, index):
        super().__init__(index)
        self.index = index


def _calendar_ns(stamps):
    """Integer nanoseconds since 1980-01-06 00:00:00 of ``YYYY/MM/DD
    HH:MM:SS.sss`` strings, counted as a calendar counts them (parsed by
    NumPy's ISO 8601 reader in C); :class:`_BadStamp` names the first that
    is no such time."""
    text = np.asarray([str(x) for x in stamps], dtype=str)
    iso = np.char.replace(np.char.replace(text, "/", "-"), " ", "T")
    shaped = (np.char.count(text, "/") == 2) & (np.char.count(iso, "T") == 1)
    try:
        if not shaped.all():
            raise ValueError
        return (iso.astype("datetime64[ns]") - np.datetime64("1980-01-06T00:00:00", "ns")).astype(np.int64)
    except ValueError:
        for i in range(len(text)):
            try:
                if not shaped[i]:
                    raise ValueError
                np.datetime64(str(iso[i]), "ns")
            except ValueError:
                raise _BadStamp(i) from None
        raise _BadStamp(0) from None


def gps_week_seconds(stamps):
    """``(week, seconds of week)`` of ``YYYY/MM/DD HH:MM:SS.sss`` GPST strings
    (parsed by NumPy's ISO 8601 reader in C, counted in integer nanoseconds
    from the GPS epoch, so the seconds are exact to the nanosecond)."""
    stamps = [str(x) for x in stamps]
    try:
        ns = _calendar_ns(stamps)
    except _BadStamp as exc:
        raise InputError(f"line with time {stamps[exc.index]!r}: expected YYYY/MM/DD HH:MM:SS.sss") from None
    return _week_sow(ns)


def outside_week(sow):
    """Where seconds of week ``sow`` fall outside [0, 604800) (a NaN too): the
    range every GPS week and seconds of week stamp has (.pos files,
    the rtklibexplorer IMU log), a later time being a later week."""
    sow = np.asarray(sow, float)
    return ~((sow >= 0) & (sow < WEEK_S))


def _week_sow(ns):
    week_ns = int(WEEK_S) * 1_000_000_000
    week = ns // week_ns
    return week.astype(int), (ns - week * week_ns) / 1e9


#: the time systems of an RTKLIB .pos file, as its column header names them (``%  GPST  latitude(deg) ...``,
#: RTKLIB's out-timesys): hours ahead of UTC, or None for GPS time
POS_TIME_SYSTEMS = {"GPST": None, "UTC": 0, "JST": 9}


def _pos_times_ns(path, tsys, d0, d1, linenos):
    """GPS time of each row of a .pos file as integer nanoseconds since the
    GPS epoch: the row's stamp, a calendar date and time (``YYYY/MM/DD
    HH:MM:SS.sss``) or a week and seconds of week (``2374 243258.499``,
    RTKLIB's out-timeform tow), both as its first row writes it, read on
    the header's time system ``tsys`` (:data:`POS_TIME_SYSTEMS`): UTC and
    JST stamps are made GPS time with the leap seconds of their date
    (:func:`inskit.gnss.time.gps_minus_utc_s`)."""
    from ..gnss.time import gps_minus_utc_s

    expected = ("a GPS week and seconds of week (as on the first row, e.g. '2374 243258.499')"
                if "/" not in d0[0] and d0[0].isdigit() else "YYYY/MM/DD HH:MM:SS.sss (as on the first row)")
    if expected.startswith("YYYY"):
        try:
            ns = _calendar_ns(np.char.add(np.char.add(d0, " "), d1))
        except _BadStamp as exc:
            i = exc.index
            raise InputError(f"{path}: line {linenos[i]}: time {d0[i] + ' ' + d1[i]!r}: expected {expected}") from None
    else:
        sow = _floats(d1)
        bad = ~np.char.isdigit(d0) | outside_week(sow)
        if bad.any():
            i = int(np.argmax(bad))
            raise InputError(f"{path}: line {linenos[i]}: time {d0[i] + ' ' + d1[i]!r}: expected {expected}, "
                             "seconds in [0, 604800)")
        whole = np.floor(sow)
        ns = (d0.astype(np.int64) * int(WEEK_S) + whole.astype(np.int64)) * 1_000_000_000 \
            + np.round((sow - whole) * 1e9).astype(np.int64)
    hours = POS_TIME_SYSTEMS[tsys]
    if hours is not None:  # a UTC (JST: UTC + 9 h) stamp: GPS time is UTC plus the leap seconds of the date
        ns = ns - hours * 3_600_000_000_000
        ns = ns + gps_minus_utc_s(ns) * 1_000_000_000
    return ns


#: RTKLIB's solution quality flags (the ``Q`` column)
_Q_NAMES = {1: "fix", 2: "float", 3: "SBAS", 4: "DGPS", 5: "single", 6: "PPP"}


def read_pos(path, *, quality=(1, 2), week0=None, time_offset_s=0.0, info=None):
    """Read an RTKLIB ``.pos`` solution: latitude and longitude in degrees
    or in degrees, minutes and seconds, or ECEF x, y, z (rotated into
    latitude, longitude, height and NED sigmas and velocity).

    The time stamps are calendar dates and times or GPS weeks and seconds
    of week (RTKLIB's out-timeform), in the time system the column header
    names (``%  GPST  latitude(deg) ...``, RTKLIB's out-timesys): GPST as
    they are, UTC and JST (UTC + 9 h) made GPS time with the leap seconds
    of their date.

    Parameters
    ----------
    path : str or Path
    quality : sequence of int
        Q flags to keep (1 fix, 2 float, 5 single ...); other rows are dropped.
    week0 : int, optional
        GPS week the returned times count from (default: the first row's).
    time_offset_s : float
        Added to every time tag (the drive_0708 tags are truncated to the
        millisecond: +0.001 s).
    info : dict, optional
        Filled with ``pos_heights``: ``"geodetic"`` when a header comment
        says the heights are above the geoid (RTKLIB's out-height =
        geodetic, ``% (lat/lon/height=WGS84/geodetic, ...)``), else
        ``"ellipsoidal"``; the heights are returned as the file holds them
        (the caller adds the geoid separation: ``[gnss] height_offset_m``).

    Returns
    -------
    gnss : GnssData
        Times in GPS seconds of week ``week0``; with velocity when the file
        has ``vn ve vu`` columns (converted to NED: ``vd = -vu``) and their
        sigmas.
    week0 : int
    """
    path = require_file(path)
    header = sep = None
    rows = []
    if info is not None:
        info["pos_heights"] = "ellipsoidal"
    try:
        # a NUL byte or UTF-16 refused as read (CheckedBytes); a byte that is no UTF-8 (a comment's accent) replaced
        with io.TextIOWrapper(io.BufferedReader(CheckedBytes(path, "RTKLIB .pos solution text"), 1 << 20),
                              encoding="utf-8-sig", errors="replace") as fh:
            for lineno, line in enumerate(fh, start=1):
                if line.startswith("%"):
                    if "height=" in line and "geodetic" in line.lower() and info is not None:
                        info["pos_heights"] = "geodetic"
                    if any(c in line for c in _POS_HEADER_MARKS):
                        # RTKLIB's out-fieldsep: a separator between the fields, spaces inside the time field
                        sep = next((c for c in (",", ";", "\t") if c in line), None)
                        header = (lineno, _pos_fields(line[1:], sep))
                    continue
                if line.strip():
                    rows.append((lineno, _pos_fields(line, sep)))
    except TextFault as exc:
        raise InputError(str(exc)) from None
    except GZIP_ERRORS as exc:  # a truncated or damaged gzip file
        raise InputError(gzip_damage_message(path, exc)) from None
    if header is None:
        raise InputError(headerless_pos_message(path) or f"{path}: no '%  GPST latitude(deg) ...' (or x-ecef(m)) "
                         "column header line: not an RTKLIB .pos file")
    hline, header = header
    tsys = header[0]
    if tsys not in POS_TIME_SYSTEMS:
        raise InputError(f"{path}: line {hline}: the header names the time system {tsys!r}; expected one of "
                         f"{', '.join(POS_TIME_SYSTEMS)} (RTKLIB's out-timesys)")
    if not rows:
        raise InputError(f"{path}: no solution rows")
    # the header names the time system once for the two date and time fields
    names = ["date", "time"] + header[1:]
    if "e-baseline(m)" in names:
        raise InputError(f"{path}: line {hline}: the positions are an east/north/up baseline from the base station "
                         "(RTKLIB's out-solformat = enu), which needs the base's position; write the solution as "
                         "lat/lon/height (llh) or ECEF (xyz)")
    form = "xyz" if "x-ecef(m)" in names else "dms" if _DMS["latitude"] in names else "llh"
    for c in ("latitude", "longitude"):  # dms: degrees, minutes and seconds are three fields under one name
        if _DMS[c] in names:
            j = names.index(_DMS[c])
            names[j:j + 1] = [f"{c}(d)", f"{c}(m)", f"{c}(s)"]
    need = _POS_NEED[form]
    # a d m s field is missing as the header would name it
    missing = list(dict.fromkeys(_DMS.get(c.split("(")[0], c) if c[-3:] in ("(d)", "(m)", "(s)") else c
                                 for c in need if c not in names))
    if missing:
        raise InputError(f"{path}: missing column(s) {', '.join(missing)} in the header")
    width = len(names)
    for k, (lineno, f) in enumerate(rows):
        if len(f) < width:
            cut = cut_short_note(path) if k == len(rows) - 1 else ""
            raise InputError(f"{path}: line {lineno}: has {len(f)} fields, the header names {width}{cut}")
    # a few thousand lines of fields split above: columns by NumPy (no pandas, half a second to import)
    table = np.array([f[:width] for _, f in rows], dtype=str)
    linenos = np.array([ln for ln, _ in rows])
    week, sow = _week_sow(_pos_times_ns(path, tsys, table[:, 0], table[:, 1], linenos))
    if week0 is None:
        week0 = int(week[0])
    t = (week - week0) * WEEK_S + sow + time_offset_s
    num = {}
    for j, c in enumerate(names[2:], start=2):
        col = _floats(table[:, j])
        if (~np.isfinite(col)).any() and (c in need or c in _POS_VELOCITY["llh"] + _POS_VELOCITY["xyz"]):
            i = int(np.argmax(~np.isfinite(col)))
            cut = cut_short_note(path) if i == len(rows) - 1 else ""
            raise InputError(f"{path}: line {linenos[i]}: column '{c}' has {str(table[i, j])!r}; expected a "
                             f"finite number{cut}")
        num[c] = col
    # heights and velocities within the limits of the inskit files (an xyz position's height: _pos_from_ecef)
    check_ranges(path, {c: num[c] for c in _POS_RANGE_KINDS if c in num}, kinds=_POS_RANGE_KINDS,
                 where=lambda i: f"line {linenos[i]}")
    if form == "dms":
        for c in ("latitude", "longitude"):
            num[f"{c}(deg)"] = _dms_degrees(path, c, table, names, num, linenos)
    if form == "xyz":
        _pos_from_ecef(path, num, linenos)
    for c, limit in (("latitude(deg)", 90.0), ("longitude(deg)", 360.0)):
        bad = np.abs(num[c]) > limit
        if bad.any():
            i = int(np.argmax(bad))
            shown = (str(table[i, names.index(c)]) if c in names
                     else " ".join(table[i, names.index(f"{c[:-5]}({u})")] for u in "dms"))
            raise InputError(f"{path}: line {linenos[i]}: column '{c if c in names else _DMS[c[:-5]]}' has "
                             f"{shown!r}; expected a value in [-{limit:g}, {limit:g}] degrees")
    q_all = num["Q"].astype(int)
    keep = np.isin(q_all, list(quality))
    if not keep.any():
        found, counts = np.unique(q_all, return_counts=True)
        held = " and ".join(f"{q} ({n} row{'s' if n != 1 else ''}, {_Q_NAMES.get(int(q), 'unknown')})"
                            for q, n in zip(found, counts))
        raise InputError(f"{path}: no rows with quality Q in {list(quality)}; its rows have Q {held}: "
                         f"quality={[int(q) for q in found]} ([gnss] quality in a navigate config) reads them")
    d = np.diff(t[keep])
    if (d <= 0).any():
        i = int(np.argmax(d <= 0)) + 1
        raise InputError(f"{path}: line {linenos[keep][i]}: time does not increase (duplicate or out of order)")
    lla = np.column_stack([num["latitude(deg)"] * DEG, num["longitude(deg)"] * DEG, num["height(m)"]])[keep]
    sig = np.column_stack([num["sdn(m)"], num["sde(m)"], num["sdu(m)"]])[keep]
    bad = (sig <= 0).any(axis=1)
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"{path}: line {linenos[keep][i]}: a position sigma is {float(sig[i].min())!r}; sigmas must be > 0")
    line = lambda i: f"line {linenos[keep][i]}"  # noqa: E731 - the message's place of a kept row
    check_sigmas(path, sig, ["sdn(m)", "sde(m)", "sdu(m)"], "m", where=line)
    v = sv = None
    if all(c in num for c in _POS_VELOCITY["llh"]):  # an xyz file's made NED by _pos_from_ecef
        v = np.column_stack([num["vn(m/s)"], num["ve(m/s)"], -num["vu(m/s)"]])[keep]
        sv = np.column_stack([num["sdvn"], num["sdve"], num["sdvu"]])[keep]
        if (sv <= 0).any():
            v = sv = None  # velocity sigmas absent: treat the velocity as unusable
        else:
            check_sigmas(path, sv, ["sdvn", "sdve", "sdvu"], "m/s", where=line)
    g = GnssData(t[keep], lla, sig, v, sv)
    if v is not None:  # the velocity the start-up takes heading and motion from, against the positions' own motion
        check_gnss_velocity(path, g, names=("vn(m/s)", "ve(m/s)"))
    return g, week0


#: a data row of a .pos file: a calendar date and time (``2025/07/08 19:34:18.499``) or a GPS week and seconds of
#: week (``2374 243258.499``), then at least five numbers, separated by blanks or RTKLIB's out-fieldsep
_POS_ROW = re.compile(r"\s*(\d{4}/\d{1,2}/\d{1,2}\s+\d{1,2}:\d{2}:\d{2}(\.\d*)?|\d{1,4}\s+\d+(\.\d*)?)"
                      r"([\s,;]+[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?){5,}[\s,;]*")
#: RTKLIB's column header of an llh solution with degrees, without and with velocity (its outsolhead), by the
#: number of fields of a row
_POS_LLH_HEADER = ("%  GPST  latitude(deg)  longitude(deg)  height(m)  Q  ns  sdn(m)  sde(m)  sdu(m)  sdne(m)  "
                   "sdeu(m)  sdun(m)  age(s)  ratio")
_POS_DEFAULT_HEADERS = {15: _POS_LLH_HEADER,
                        24: _POS_LLH_HEADER + "  vn(m/s)  ve(m/s)  vu(m/s)  sdvn  sdve  sdvu  sdvne  sdveu  sdvun"}


def looks_like_pos_row(line) -> bool:
    """Is ``line`` a data row of an RTKLIB .pos file (:data:`_POS_ROW`)?"""
    return _POS_ROW.fullmatch(line.rstrip("\r\n")) is not None


def headerless_pos_message(path, also="") -> str | None:
    """The message of a .pos file whose rows come without their column
    header line (``%  GPST  latitude(deg) ...``), or None when it has one
    or its first row is no .pos row.

    The header names the time system (GPST, UTC or JST: 18 s apart since
    2017) and the columns (degrees or d m s, llh or xyz, with velocity or
    not), so rows without it are not read on a guess; the message shows
    the line RTKLIB writes for its default llh layout when the rows have
    its number of fields and degrees where it has them.  ``also`` is added
    to the advice (the format to set).
    """
    from .formats import _first_lines

    first = None
    for line in _first_lines(path):
        if line.startswith("%"):
            if any(c in line for c in _POS_HEADER_MARKS):
                return None
            continue
        if line.strip():
            first = line
            break
    if first is None or not looks_like_pos_row(first):
        return None
    sep = next((c for c in (",", ";") if c in first), None)
    fields = _pos_fields(first, sep)
    default = _POS_DEFAULT_HEADERS.get(len(fields))
    if default and sep:  # the rows' separator between the names too (RTKLIB's out-fieldsep)
        names = default[1:].split()
        default = f"%  {names[0]}{sep}{sep.join(names[1:])}"
    try:
        degrees = abs(float(fields[2])) <= 90.0 and abs(float(fields[3])) <= 360.0
    except ValueError:
        degrees = False
    fix = (f", or, if the times are GPST, put RTKLIB's header line for these {len(fields)} fields first: {default!r}"
           if default and degrees else " ('%  GPST  latitude(deg)  longitude(deg)  height(m)  Q  ns  sdn(m) ...')")
    return (f"{path}: holds RTKLIB .pos solution rows ({first.strip()[:23]!r} ...) but no '%' column header line "
            "above them, which names their time system (GPST, UTC or JST) and their columns: they are not read on a "
            f"guess; write the solution with its header (RTKLIB: out-outhead = on){fix}{also}")


#: a column header of a .pos file names one of these (RTKLIB's out-solformat llh, with degrees or d m s, or xyz)
_POS_HEADER_MARKS = ("latitude", "x-ecef", "e-baseline")
#: the header's name of a latitude or longitude written as degrees, minutes and seconds (RTKLIB's out-degform dms)
_DMS = {"latitude": "latitude(d'\")", "longitude": "longitude(d'\")"}
#: the columns each position form needs
_POS_NEED = {
    "llh": ["latitude(deg)", "longitude(deg)", "height(m)", "Q", "sdn(m)", "sde(m)", "sdu(m)"],
    "dms": ["latitude(d)", "latitude(m)", "latitude(s)", "longitude(d)", "longitude(m)", "longitude(s)", "height(m)",
            "Q", "sdn(m)", "sde(m)", "sdu(m)"],
    "xyz": ["x-ecef(m)", "y-ecef(m)", "z-ecef(m)", "Q", "sdx(m)", "sdy(m)", "sdz(m)"],
}
#: the velocity columns of each form (an xyz file's are rotated into the llh ones: :func:`_pos_from_ecef`)
_POS_VELOCITY = {"llh": ["vn(m/s)", "ve(m/s)", "vu(m/s)", "sdvn", "sdve", "sdvu"],
                 "xyz": ["vx(m/s)", "vy(m/s)", "vz(m/s)", "sdvx", "sdvy", "sdvz"]}


#: the columns of a .pos file with a plausibility limit, as the limit's column of the inskit files
#: (:data:`inskit.io.csv_formats.RANGE_LIMITS`): the height, and each velocity component (NED or ECEF)
_POS_RANGE_KINDS = {"height(m)": "height_m", "vn(m/s)": "vn_m_s", "ve(m/s)": "ve_m_s", "vu(m/s)": "vd_m_s",
                    "vx(m/s)": "vn_m_s", "vy(m/s)": "ve_m_s", "vz(m/s)": "vd_m_s"}


def _pos_fields(line, sep):
    """The fields of a .pos line: split at blanks, or at ``sep`` (RTKLIB's
    out-fieldsep) with the first field (a date and time, or a week and
    seconds) split at blanks."""
    if sep is None:
        return line.split()
    first, *rest = line.split(sep)
    return first.split() + [f.strip() for f in rest]


def _dms_degrees(path, c, table, names, num, linenos):
    """Degrees of a latitude or longitude (``c``) written as degrees,
    minutes and seconds (``-105 08 50.81388``); the sign is the degree
    field's, written as ``-0`` too.  Minutes and seconds outside [0, 60)
    are refused naming the line."""
    d, m, sec = (num[f"{c}({u})"] for u in "dms")
    bad = (m < 0) | (m >= 60) | (sec < 0) | (sec >= 60) | (d != np.round(d))
    if bad.any():
        i = int(np.argmax(bad))
        shown = " ".join(table[i, names.index(f"{c}({u})")] for u in "dms")
        raise InputError(f"{path}: line {linenos[i]}: column '{_DMS[c]}' has {shown!r}; expected whole degrees, then "
                         "minutes and seconds in [0, 60)")
    sign = np.where(np.char.startswith(table[:, names.index(f"{c}(d)")], "-"), -1.0, 1.0)
    return sign * (np.abs(d) + m / 60.0 + sec / 3600.0)


def _ecef_cov_to_ned(num, names, lat, lon):
    """Standard deviations [m or m/s] north, east, down of ECEF ones: the
    ``(x, y, z, xy, yz, zx)`` columns ``names`` of ``num`` (the cross terms,
    RTKLIB's signed square roots of the covariances, zero when absent)
    make each row's covariance, which is rotated into NED."""
    sx, sy, sz = (num[n] for n in names[:3])
    cxy, cyz, czx = (np.sign(num[n]) * num[n] ** 2 if n in num else np.zeros_like(sx) for n in names[3:])
    q = np.stack([np.stack([sx ** 2, cxy, czx], -1), np.stack([cxy, sy ** 2, cyz], -1),
                  np.stack([czx, cyz, sz ** 2], -1)], -2)
    c = earth.dcm_en(lat, lon)
    q_n = np.einsum("kji,kjl,klm->kim", c, q, c)
    return np.sqrt(np.clip(np.einsum("kii->ki", q_n), 0.0, None))


def _pos_from_ecef(path, num, linenos):
    """The columns of an llh file from those of an xyz one (RTKLIB's
    out-solformat xyz), in ``num``: latitude, longitude [deg] and height of
    the ECEF position, its sigmas and the velocity rotated into NED (the
    up sigma is the down one).  A position more than 100 km from the
    ellipsoid is refused (not metres, or not ECEF)."""
    r = np.column_stack([num["x-ecef(m)"], num["y-ecef(m)"], num["z-ecef(m)"]])
    lla = earth.ecef_to_lla(r)
    far = np.abs(lla[:, 2]) > MAX_HEIGHT_M
    if far.any():
        i = int(np.argmax(far))
        raise InputError(f"{path}: line {linenos[i]}: x-ecef(m), y-ecef(m), z-ecef(m) = {r[i].tolist()} is "
                         f"{lla[i, 2] / 1000:.0f} km from the ellipsoid; expected an ECEF position in metres")
    num["latitude(deg)"], num["longitude(deg)"], num["height(m)"] = lla[:, 0] / DEG, lla[:, 1] / DEG, lla[:, 2]
    sig = _ecef_cov_to_ned(num, ["sdx(m)", "sdy(m)", "sdz(m)", "sdxy(m)", "sdyz(m)", "sdzx(m)"], lla[:, 0], lla[:, 1])
    num["sdn(m)"], num["sde(m)"], num["sdu(m)"] = sig.T
    if all(c in num for c in _POS_VELOCITY["xyz"]):
        c = earth.dcm_en(lla[:, 0], lla[:, 1])
        v_n = np.einsum("kji,kj->ki", c, np.column_stack([num["vx(m/s)"], num["vy(m/s)"], num["vz(m/s)"]]))
        num["vn(m/s)"], num["ve(m/s)"], num["vu(m/s)"] = v_n[:, 0], v_n[:, 1], -v_n[:, 2]
        sv = _ecef_cov_to_ned(num, ["sdvx", "sdvy", "sdvz", "sdvxy", "sdvyz", "sdvzx"], lla[:, 0], lla[:, 1])
        num["sdvn"], num["sdve"], num["sdvu"] = sv.T


def _floats(text):
    """A column of number texts as floats, NaN where a text is no number
    (as pandas' ``to_numeric(errors="coerce")``), converted in C when all
    are numbers."""
    try:
        return text.astype(float)
    except ValueError:
        out = np.empty(len(text))
        for i, x in enumerate(text):
            try:
                out[i] = float(x)
            except ValueError:
                out[i] = np.nan
        return out


def mount_dcm(mount_rpy):
    """``C_bs`` (sensor to body) from the mounting Euler angles [rad].

    The angles are the ZYX Euler angles of the rotation from the body to the
    sensor axes, so ``C_bs = dcm_from_euler(mount_rpy).T`` and
    ``f_b = C_bs f_s``.  This is the convention of Groves' ``Euler_to_CTM``
    that the rtklibexplorer source uses for (180, -6.79, 185.35) deg.
    An angle beyond a full turn (those degrees given as radians) is refused
    (:func:`inskit.types.check_euler`).
    """
    return rot.dcm_from_euler(check_euler("mount_rpy", mount_rpy)).T


def rotate_to_body(mount_rpy, *vectors_s):
    """The rows of each ``(n, 3)`` array of ``vectors_s`` (sensor axes:
    increments, rates) rotated into the body axes, ``x_b = C_bs x_s``
    (:func:`mount_dcm`), in place (a reader's own arrays: an 8 h, 200 Hz log
    is 0.32 GB, not copied); nothing is done for a zero mounting.  Returns
    the arrays."""
    C_bs = mount_dcm(mount_rpy)
    if not np.array_equal(C_bs, np.eye(3)):
        for x in vectors_s:
            x[:] = x @ C_bs.T
    return vectors_s


def read_rtklibexplorer_imu(path, *, week0=None, time_offset_s=0.0, mount_rpy=(0.0, 0.0, 0.0),
                            check_units=True, repeated="keep", time_smoothing=1, info=None):
    """Read the rtklibexplorer ``imu_*_gpst.csv`` log.

    Columns ``gps_week, gps_sow_s, acc_{x,y,z}_g, gyro_{x,y,z}_dps,
    counter_ms``; rates in the sensor frame, each sample the filtered value
    over the preceding interval (integrated as ``sampled="average"``).

    Parameters
    ----------
    week0 : int, optional
        GPS week the returned times count from (default: the first row's).
    time_offset_s : float
        Added to the IMU times (the drive_0708 IMU is late: about -0.12 s
        against GNSS velocity, -0.2 s against position).
    mount_rpy : (3,) radians
        Mounting rotation, see :func:`mount_dcm`.
    repeated : {"keep", "drop"}
        A row repeating the previous one in all six sensor channels (the
        logger read one sample twice: :func:`inskit.io.csv_formats.repeated_rows`)
        kept as a sample over its short interval, or dropped (the next sample,
        averaged over the preceding interval, then covers the whole span).
    time_smoothing : int
        1, or the odd number of rows over which the time tags are smoothed
        after the repeated rows are handled (the logger's poll jitter and
        millisecond counter: :func:`inskit.io.time_tags.smooth_time_tags`).
    info : dict, optional
        Filled with the count of repeated rows (``repeated_rows``, ...) and
        how far the smoothing moved the tags, checked against their jitter
        (:func:`inskit.io.time_tags.smooth_time_tags`).

    Returns
    -------
    imu : ImuData
        In body axes (forward-right-down).
    week0 : int
    """
    cols = ["gps_week", "gps_sow_s", "acc_x_g", "acc_y_g", "acc_z_g", "gyro_x_dps", "gyro_y_dps", "gyro_z_dps"]
    names = _header_names(path)
    got = lean_columns(path, [cols]) if names is not None and set(cols) <= set(names) else None
    if got is not None:  # plain numbers: parsed by pyarrow, no pandas
        path, a = Path(path), got[0]
    else:  # anything else: the pandas path, whose messages name the line and the column
        path, df = read_table(path)
        require_columns(path, df, cols)
        a = numeric_columns(path, df, cols)
    bad = (a[:, 0] != np.floor(a[:, 0])) | (a[:, 0] < 0)
    if bad.any():  # astype(int) would truncate 2374.5 to week 2374 without a word
        i = int(np.argmax(bad))
        raise InputError(f"{path}: {at_row(path, i)}: gps_week={float(a[i, 0]):g}; expected a whole GPS week "
                         "number >= 0")
    bad = outside_week(a[:, 1])
    if bad.any():  # a later time is a later gps_week: a second of week beyond it is another column or unit
        i = int(np.argmax(bad))
        raise InputError(f"{path}: {at_row(path, i)}: gps_sow_s={plain_number(a[i, 1])}; expected seconds of the "
                         f"GPS week in [0, {WEEK_S:.0f}) (a later time counts in the next gps_week)")
    week = a[:, 0].astype(int)
    if week0 is None:
        week0 = int(week[0])
    t = (week - week0) * WEEK_S + a[:, 1] + time_offset_s
    check_time_column(path, t, "gps_sow_s")
    keep = repeated_rows(path, t, a[:, 2:8], repeated, info)
    rows = None
    if keep is not None:
        t, a = t[keep], a[keep]
        rows = np.flatnonzero(keep)  # the file's row of each sample kept, for the messages
    t = smooth_time_tags(path, t, time_smoothing, info=info)
    C_bs = mount_dcm(mount_rpy)
    f = a[:, 2:5] * G0 @ C_bs.T
    w = a[:, 5:8] * DEG @ C_bs.T
    if check_units:
        check_imu_units(path, w, f, "gyro_x_dps", "acc_x_g", "deg_s", "g", rows)
    check_imu_time(path, t, "gps_sow_s", check_units)
    return ImuData.from_rates(t, w, f, sampled="average"), week0
