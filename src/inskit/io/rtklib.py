"""Readers for RTKLIB solution files and the rtklibexplorer GNSS/IMU logs.

Time base: GPS time as seconds of the GPS week that a file starts in
(``sow``), continued past 604800 s if a log crosses a week boundary.  Readers
that must agree take the same ``week0``.
"""

from __future__ import annotations

from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from .. import rotations as rot
from ..errors import InputError
from ..types import GnssData, ImuData
from ..units import DEG, G0
from .csv_formats import check_imu_units, check_time_column, numeric_columns, read_table, require_columns

GPS_EPOCH = datetime(1980, 1, 6, tzinfo=timezone.utc)
WEEK_S = 604800.0


def gps_week_seconds(stamps):
    """``(week, seconds of week)`` of ``YYYY/MM/DD HH:MM:SS.sss`` GPST strings."""
    import pandas as pd  # here, not at import: the IMU path of navigate needs no pandas

    ts = pd.to_datetime(pd.Series(stamps), format="%Y/%m/%d %H:%M:%S.%f", utc=True, errors="coerce")
    if ts.isna().any():
        i = int(np.argmax(ts.isna().to_numpy()))
        raise InputError(f"line with time {stamps[i]!r}: expected YYYY/MM/DD HH:MM:SS.sss")
    sec = (ts - pd.Timestamp(GPS_EPOCH)).dt.total_seconds().to_numpy()
    week = np.floor(sec / WEEK_S).astype(int)
    return week, sec - week * WEEK_S


def read_pos(path, *, quality=(1, 2), week0=None, time_offset_s=0.0):
    """Read an RTKLIB ``.pos`` solution (lat/lon/height format, GPST).

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

    Returns
    -------
    gnss : GnssData
        With velocity when the file has ``vn ve vu`` columns (converted to
        NED: ``vd = -vu``) and their sigmas.
    week0 : int
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file")
    header = None
    rows = []
    opener = _open_text(path)
    with opener as fh:
        for lineno, line in enumerate(fh, start=1):
            if line.startswith("%"):
                if "latitude" in line:
                    header = line[1:].split()
                continue
            if line.strip():
                rows.append((lineno, line.split()))
    if header is None:
        raise InputError(f"{path}: no '%  GPST latitude(deg) ...' header line: not an RTKLIB lat/lon .pos file")
    if not rows:
        raise InputError(f"{path}: no solution rows")
    # the header names 'GPST' once for the two date and time fields
    names = ["date", "time"] + header[1:]
    need = ["latitude(deg)", "longitude(deg)", "height(m)", "Q", "sdn(m)", "sde(m)", "sdu(m)"]
    missing = [c for c in need if c not in names]
    if missing:
        raise InputError(f"{path}: missing column(s) {', '.join(missing)} in the header")
    width = len(names)
    for lineno, f in rows:
        if len(f) < width:
            raise InputError(f"{path}: line {lineno}: has {len(f)} fields, the header names {width}")
    import pandas as pd

    df = pd.DataFrame([f[:width] for _, f in rows], columns=names)
    linenos = np.array([ln for ln, _ in rows])
    try:
        week, sow = gps_week_seconds(list(df["date"] + " " + df["time"]))
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    if week0 is None:
        week0 = int(week[0])
    t = (week - week0) * WEEK_S + sow + time_offset_s
    num = {}
    for c in names[2:]:
        col = pd.to_numeric(df[c], errors="coerce").to_numpy(float)
        if (~np.isfinite(col)).any() and c in need + ["vn(m/s)", "ve(m/s)", "vu(m/s)", "sdvn", "sdve", "sdvu"]:
            i = int(np.argmax(~np.isfinite(col)))
            raise InputError(f"{path}: line {linenos[i]}: column '{c}' has {df[c].iloc[i]!r}; expected a finite "
                             "number")
        num[c] = col
    for c, limit in (("latitude(deg)", 90.0), ("longitude(deg)", 360.0)):
        bad = np.abs(num[c]) > limit
        if bad.any():
            i = int(np.argmax(bad))
            raise InputError(f"{path}: line {linenos[i]}: column '{c}' has {df[c].iloc[i]!r}; expected a value in "
                             f"[-{limit:g}, {limit:g}] degrees")
    keep = np.isin(num["Q"].astype(int), list(quality))
    if not keep.any():
        raise InputError(f"{path}: no rows with quality Q in {list(quality)}")
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
    v = sv = None
    if all(c in num for c in ("vn(m/s)", "ve(m/s)", "vu(m/s)", "sdvn", "sdve", "sdvu")):
        v = np.column_stack([num["vn(m/s)"], num["ve(m/s)"], -num["vu(m/s)"]])[keep]
        sv = np.column_stack([num["sdvn"], num["sdve"], num["sdvu"]])[keep]
        if (sv <= 0).any():
            v = sv = None  # velocity sigmas absent: treat the velocity as unusable
    return GnssData(t[keep], lla, sig, v, sv), week0


def _open_text(path):
    if str(path).endswith(".gz"):
        import gzip

        return gzip.open(path, "rt")
    return open(path, encoding="utf-8", errors="replace")


def mount_dcm(mount_rpy):
    """``C_bs`` (sensor to body) from the mounting Euler angles [rad].

    The angles are the ZYX Euler angles of the rotation from the body to the
    sensor axes, so ``C_bs = dcm_from_euler(mount_rpy).T`` and
    ``f_b = C_bs f_s``.  This is the convention of Groves' ``Euler_to_CTM``
    that the rtklibexplorer source uses for (180, -6.79, 185.35) deg.
    """
    return rot.dcm_from_euler(np.asarray(mount_rpy, float)).T


def read_rtklibexplorer_imu(path, *, week0=None, time_offset_s=0.0, mount_rpy=(0.0, 0.0, 0.0),
                            check_units=True):
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

    Returns
    -------
    imu : ImuData
        In body axes (forward-right-down).
    week0 : int
    """
    path, df = read_table(path)
    cols = ["gps_week", "gps_sow_s", "acc_x_g", "acc_y_g", "acc_z_g", "gyro_x_dps", "gyro_y_dps", "gyro_z_dps"]
    require_columns(path, df, cols)
    a = numeric_columns(path, df, cols)
    week = a[:, 0].astype(int)
    if week0 is None:
        week0 = int(week[0])
    t = (week - week0) * WEEK_S + a[:, 1] + time_offset_s
    check_time_column(path, t, "gps_sow_s")
    C_bs = mount_dcm(mount_rpy)
    f = a[:, 2:5] * G0 @ C_bs.T
    w = a[:, 5:8] * DEG @ C_bs.T
    if check_units:
        check_imu_units(path, w, f, "gyro_x_dps", "acc_x_g", "deg_s", "g")
    return ImuData.from_rates(t, w, f, sampled="average"), week0
