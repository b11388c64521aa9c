"""Every IMU and GNSS file format inskit reads, by name, recognised by its
header: one ``read_imu`` and one ``read_gnss`` for all of them.

IMU formats
-----------
``"inskit"``
    The project's CSV (``docs/formats.md``): ``time_s`` with rates
    ``gyro_*``/``accel_*`` or increments ``dtheta_*``/``dv_*``, units in the
    names; :func:`inskit.io.csv_formats.read_imu`.
``"rtklibexplorer"``
    The rtklibexplorer GNSS-IMU logs (``imu_*_gpst.csv``, the bundled
    ``data/drive_0708`` and ``data/walk_0827``): ``gps_week, gps_sow_s,
    acc_{x,y,z}_g, gyro_{x,y,z}_dps``; :func:`inskit.io.rtklib.read_rtklibexplorer_imu`.

GNSS formats
------------
``"inskit"``
    Our CSV of fixes; :func:`inskit.io.csv_formats.read_gnss`.
``"rtklib-pos"``
    An RTKLIB ``.pos`` solution (lat/lon/height; GPST, UTC or JST); :func:`inskit.io.rtklib.read_pos`.

The names are those of the navigate config's ``[imu] format`` and
``[gnss] format``.  Only the first line of a file (the first lines of a
``.pos``) is read to recognise it; a file that matches no signature is given
to the inskit reader, whose messages name what is missing and list the other
formats.  These functions only forward: the readers do all the checking.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..types import GnssData, ImuData, check_euler

#: IMU format -> (columns its header must hold, one line of description)
IMU_FORMATS = {
    "inskit": (("time_s",), ("inskit CSV: time_s with gyro_{x,y,z}_<unit> and accel_{x,y,z}_<unit> rates, or "
                             "dtheta_{x,y,z}_<unit> and dv_{x,y,z}_m_s increments (docs/formats.md)")),
    "rtklibexplorer": (("gps_week", "gps_sow_s", "acc_x_g", "acc_y_g", "acc_z_g", "gyro_x_dps", "gyro_y_dps",
                        "gyro_z_dps"),
                       "rtklibexplorer GNSS-IMU log: gps_week, gps_sow_s, acc_{x,y,z}_g, gyro_{x,y,z}_dps"),
}

#: GNSS format -> one line of description
GNSS_FORMATS = {
    "inskit": "inskit CSV of fixes: time_s, lat_deg, lon_deg, height_m, sigma_{n,e,d}_m (docs/formats.md)",
    "rtklib-pos": "RTKLIB .pos solution: '%' header lines, then date and time (GPST, UTC or JST), latitude(deg), ...",
}

#: lines of a file read to recognise it
_PEEK_LINES = 60


def check_path_argument(path):
    """:func:`.csv_formats.check_path_argument` (loaded on first use)."""
    from .csv_formats import check_path_argument as check

    return check(path)


def _open(path):
    """A text handle on ``path`` (:func:`.csv_formats.open_text`)."""
    from .csv_formats import open_text

    return open_text(path)


def _first_lines(path, n=_PEEK_LINES) -> list:
    """Up to ``n`` first lines of ``path`` from its first that is not blank
    (the readers skip blank lines before the header too); ``[]`` when it
    cannot be read: the reader then says why."""
    try:
        with _open(path) as fh:
            out = []
            for line in fh:
                if not out and not line.strip():
                    continue
                out.append(line.rstrip("\r\n"))
                if len(out) >= n:
                    break
            return out
    except Exception:  # noqa: BLE001 (damaged gzip data raises zlib.error too: the reader then says why)
        return []


def _header_columns(path) -> list:
    lines = _first_lines(path, 1)
    # a spreadsheet may quote every name ('"gps_week","gps_sow_s",...'), which pandas reads as the names
    return [c.strip().strip('"').strip() for c in lines[0].split(",")] if lines else []


def _format_list(formats) -> str:
    return "; ".join(f"{k!r} ({v[1] if isinstance(v, tuple) else v})" for k, v in formats.items())


def detect_imu_format(path) -> str | None:
    """The IMU format of ``path`` by its header line: ``"rtklibexplorer"``
    when the header holds that log's columns, ``"inskit"`` when it holds
    ``time_s``, else None."""
    cols = set(_header_columns(path))
    for name in ("rtklibexplorer", "inskit"):
        if set(IMU_FORMATS[name][0]) <= cols:
            return name
    return None


def detect_gnss_format(path) -> str | None:
    """The GNSS format of ``path``: ``"rtklib-pos"`` when its first line is
    an RTKLIB ``%`` comment (or a .pos data row: the file lacks its header,
    which :func:`inskit.io.rtklib.read_pos` then says), ``"inskit"`` when
    its header holds ``time_s``, else None."""
    lines = _first_lines(path, 1)
    if not lines:
        return None
    if lines[0].startswith("%"):
        return "rtklib-pos"
    if "time_s" in _header_columns(path):
        return "inskit"
    from .rtklib import looks_like_pos_row

    if looks_like_pos_row(lines[0]):  # .pos rows without their '%' header: read_pos says what is missing
        return "rtklib-pos"
    return None


def _check_format(kind, fmt, formats):
    if fmt not in formats:
        raise InputError(f"unknown {kind} format {fmt!r}; the formats are {_format_list(formats)}")


def _same_option(v, w) -> bool:
    """Is option value ``v`` the value ``w``?  Text compares as text; numbers,
    sequences and arrays by value (``np.zeros(3)`` is ``[0, 0, 0]``), never
    by ``!=``, whose answer for an array is an array (which ``if`` refuses
    with numpy's 'truth value ... is ambiguous')."""
    if isinstance(v, str) or isinstance(w, str):
        return isinstance(v, str) and isinstance(w, str) and v == w
    try:
        return bool(np.array_equal(np.asarray(v, dtype=object), np.asarray(w, dtype=object)))
    except (TypeError, ValueError):  # ragged nesting: not the value
        return False


def _refuse_options(path, fmt, given: dict, fixed=None):
    """Refuse options of another format (``fixed``: the value this format
    always has, which may be given)."""
    fixed = fixed or {}
    bad = [k for k, v in given.items() if v is not None and not (k in fixed and _same_option(v, fixed[k]))]
    if bad:
        raise InputError(f"{path}: {', '.join(bad)} {'does' if len(bad) == 1 else 'do'} not apply to the {fmt!r} "
                         "format")


def read_imu(path, format=None, *, check_units=True, sampled=None, first_row=None, week0=None,
             time_offset_s=None, mount_rpy=None, repeated="keep", time_smoothing=1, info=None) -> ImuData:
    """Read an IMU log of any format inskit knows (:data:`IMU_FORMATS`).

    Parameters
    ----------
    path : str or Path
        Plain or gzip-compressed (recognised by content).
    format : {"inskit", "rtklibexplorer"}, optional
        Default: recognised from the header (:func:`detect_imu_format`); a
        header of neither kind goes to the inskit reader, whose message
        names what is missing and the other format.
    check_units : bool
        Refuse magnitudes that betray a wrong unit (both formats).
    sampled : {"instant", "average"}, optional
        inskit rate files only: how the rates were sampled (default
        ``"instant"``; the rtklibexplorer log is always ``"average"``).
    first_row : {"initial", "increment", "discard"}, optional
        inskit increment files only: what their first row is (default
        ``"initial"``, which the rtklibexplorer log always is;
        :func:`inskit.io.csv_formats.first_row_rule`).
    week0 : int, optional
        rtklibexplorer only: the GPS week the times count from (default
        the first row's).
    time_offset_s : float, optional
        rtklibexplorer only: added to every time tag.
    mount_rpy : (3,) radians, optional
        rtklibexplorer only: mounting rotation, body to sensor (ZYX;
        :func:`inskit.io.rtklib.mount_dcm`); default the sensor axes.  An
        angle beyond a full turn (degrees) is refused.
    repeated : {"keep", "drop"}
        Rate logs (both formats): a row repeating the previous one in all six
        channels, a sample the logger read twice
        (:func:`inskit.io.csv_formats.repeated_rows`), kept or dropped.
    time_smoothing : int
        Rate logs (both formats): 1 (the time tags as logged) or the odd
        number of rows over which the tags are smoothed, taking out a
        logger's poll jitter and millisecond counter
        (:func:`inskit.io.time_tags.smooth_time_tags`).
    info : dict, optional
        Filled with the count of such rows (``repeated_rows``, ...) and how
        far the smoothing moved the tags (``time_tags_moved_rms_s``, ...),
        beyond what their jitter explains or not (``time_tags_beyond_jitter``)
        and the rate changes it smoothed apart (``time_tag_rate_changes``).

    Returns
    -------
    ImuData
        Times as in the file (rtklibexplorer: seconds of GPS week
        ``week0``), row 0 the initial epoch.

    Raises
    ------
    InputError
        From the format's reader (file, line, column, what was expected),
        an unknown format (the message lists them), or an option of another
        format.
    """
    path = check_path_argument(path)
    fmt = format if format is not None else (detect_imu_format(path) or "inskit")
    _check_format("IMU", fmt, IMU_FORMATS)
    if mount_rpy is not None:
        check_euler("mount_rpy", mount_rpy)  # radians, before the whole log is read
    if fmt == "rtklibexplorer":
        from .rtklib import read_rtklibexplorer_imu

        # the log holds rates averaged over the preceding interval; its first row is the initial epoch
        _refuse_options(path, fmt, {"sampled": sampled, "first_row": first_row},
                        fixed={"sampled": "average", "first_row": "initial"})
        imu, _ = read_rtklibexplorer_imu(path, week0=week0, time_offset_s=time_offset_s or 0.0,
                                         mount_rpy=(0.0, 0.0, 0.0) if mount_rpy is None else mount_rpy,
                                         check_units=check_units, repeated=repeated,
                                         time_smoothing=time_smoothing, info=info)
        return imu
    from .csv_formats import read_imu as read_inskit

    _refuse_options(path, fmt, {"week0": week0, "time_offset_s": time_offset_s, "mount_rpy": mount_rpy})
    return read_inskit(path, check_units=check_units, sampled=sampled or "instant", first_row=first_row or "initial",
                       repeated=repeated, time_smoothing=time_smoothing, info=info)


def read_gnss(path, format=None, *, quality=None, week0=None, time_offset_s=None) -> GnssData:
    """Read GNSS fixes of any format inskit knows (:data:`GNSS_FORMATS`).

    Parameters
    ----------
    path : str or Path
    format : {"inskit", "rtklib-pos"}, optional
        Default: recognised from the first line (:func:`detect_gnss_format`);
        anything else goes to the inskit reader.
    quality : sequence of int, optional
        rtklib-pos only: the Q flags kept (default 1 fix and 2 float).
    week0 : int, optional
        rtklib-pos only: the GPS week the times count from (default the
        first row's).
    time_offset_s : float, optional
        rtklib-pos only: added to every time tag.

    Returns
    -------
    GnssData
        Times as in the file (rtklib-pos: seconds of GPS week ``week0``).
    """
    path = check_path_argument(path)
    fmt = format if format is not None else (detect_gnss_format(path) or "inskit")
    _check_format("GNSS", fmt, GNSS_FORMATS)
    if fmt == "rtklib-pos":
        from .rtklib import read_pos

        gnss, _ = read_pos(path, quality=(1, 2) if quality is None else tuple(quality), week0=week0,
                           time_offset_s=time_offset_s or 0.0)
        return gnss
    from .csv_formats import read_gnss as read_inskit

    _refuse_options(path, fmt, {"quality": quality, "week0": week0, "time_offset_s": time_offset_s})
    return read_inskit(path)


__all__ = ["GNSS_FORMATS", "IMU_FORMATS", "detect_gnss_format", "detect_imu_format", "read_gnss", "read_imu"]
