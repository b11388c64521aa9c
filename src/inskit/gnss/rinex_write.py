"""Writing RINEX 3.04 observation and navigation files.

The observation writer formats every field of the body with numpy (no
per-value Python formatting): values are turned into fixed-width byte
matrices by integer arithmetic, so an hour of 1 Hz data from ten
satellites with three observables each is written in a few tens of
milliseconds.  Files go through :func:`inskit.files.atomic_write`: whole or
absent.

Times are seconds since the GPS epoch (1980-01-06 00:00:00) on the GPS scale,
as everywhere in :mod:`inskit.gnss`; the calendar epochs written are GPS
time (``TIME OF FIRST OBS ... GPS``).  Galileo navigation epochs are written
on the same calendar (GST is steered to GPS time to within tens of
nanoseconds, and RINEX 3 numbers Galileo weeks continuously with GPS weeks).

References
----------
IGS/RTCM, *RINEX: The Receiver Independent Exchange Format, Version 3.04*
(2018): §5.1 and Table A2-A3 (observation header and records), Table A6,
A8 and A10 (GPS and Galileo navigation header and records), §5.7 (signal
strength indicator).
"""

from __future__ import annotations

import datetime as _dt
import os
import re
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..files import atomic_write

SECONDS_PER_WEEK = 604800.0
_GPS_EPOCH = np.datetime64("1980-01-06", "D")
_SAT_RE = re.compile(r"^[GRECJSI][0-9]{2}$")
_CODE_RE = re.compile(r"^[CLDS][1-9][A-Z]$")
#: order of the observation types of one band in the header (code, phase, Doppler, strength)
_TYPE_ORDER = "CLDS"
#: order of the systems in the header
_SYSTEM_ORDER = "GERCJIS"
_SYSTEM_NAMES = {"G": "GPS", "E": "GALILEO", "R": "GLONASS", "C": "BEIDOU", "J": "QZSS", "I": "IRNSS",
                 "S": "SBAS"}


# --- small helpers --------------------------------------------------------------------------------
def _hline(content, label):
    """One header line: 60 columns of content and the label in columns 61-80."""
    if len(content) > 60:
        raise InputError(f"RINEX header field {label!r} is longer than 60 characters: {content!r}")
    return f"{content:<60}{label:<20}\n"


def _run_date():
    """``PGM / RUN BY / DATE`` date: now (UTC), or the reproducible-builds
    ``SOURCE_DATE_EPOCH`` when set, so that a rerun can give identical bytes."""
    sde = os.environ.get("SOURCE_DATE_EPOCH")
    if sde:
        try:
            now = _dt.datetime.fromtimestamp(int(sde), _dt.UTC)
        except ValueError:
            raise InputError(f"SOURCE_DATE_EPOCH must be an integer number of seconds, got {sde!r}") from None
    else:
        now = _dt.datetime.now(_dt.UTC)
    return now.strftime("%Y%m%d %H%M%S UTC")


def calendar(t, decimals=7):
    """GPS-time calendar fields of times ``t`` [s since the GPS epoch].

    Parameters
    ----------
    t : (n,) array_like
    decimals : int
        Decimal places of the seconds; the rounding carries into minutes,
        hours and days (59.99999999 s becomes the next minute).

    Returns
    -------
    year, month, day, hour, minute : (n,) int ndarray
    second : (n,) float ndarray
        Rounded to ``decimals``.
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    whole = np.floor(t)
    scale = 10 ** decimals
    ticks = np.round((t - whole) * scale).astype(np.int64)  # the fraction alone keeps full precision
    whole = whole.astype(np.int64) + ticks // scale
    ticks = ticks % scale
    days = whole // 86400
    sod = whole - days * 86400
    date = _GPS_EPOCH + days.astype("timedelta64[D]")
    year = date.astype("datetime64[Y]").astype(np.int64) + 1970
    month = date.astype("datetime64[M]").astype(np.int64) % 12 + 1
    day = (date - date.astype("datetime64[M]")).astype(np.int64) + 1
    return year, month, day, sod // 3600, (sod // 60) % 60, (sod % 60) + ticks / scale


def _fixed(x, width, decimals, what):
    """Right-aligned fixed-point fields (Fortran ``F{width}.{decimals}``) of
    the values ``x`` as a ``(n, width)`` uint8 matrix; NaN gives blanks.

    Integer arithmetic on the value in units of the last decimal (rounded
    half away from zero), so the digits are exact and nothing is formatted
    value by value.
    """
    x = np.asarray(x, dtype=float).ravel()
    out = np.full((x.size, width), ord(" "), np.uint8)
    ok = np.isfinite(x)
    if not ok.any():
        return out
    v = np.floor(np.abs(x[ok]) * 10 ** decimals + 0.5).astype(np.int64)
    neg = (x[ok] < 0) & (v > 0)
    int_part = v // 10 ** decimals
    n_int = width - decimals - 1  # columns left of the decimal point, sign included
    limit = 10 ** (n_int - neg.astype(np.int64))
    if (int_part >= limit).any():
        bad = x[ok][np.argmax(int_part >= limit)]
        raise InputError(f"{what}: {bad!r} does not fit the RINEX field F{width}.{decimals}")
    sub = np.full((v.size, width), ord(" "), np.uint8)
    frac = v % 10 ** decimals
    for k in range(decimals):
        sub[:, width - 1 - k] = ord("0") + (frac // 10 ** k) % 10
    sub[:, n_int] = ord(".")
    # integer digits from the right; the units digit always, the others while the number has them
    n_digits = np.ones(v.size, np.int64)
    for k in range(n_int):
        col = n_int - 1 - k
        has = (k == 0) | (int_part >= 10 ** k)
        sub[has, col] = ord("0") + (int_part[has] // 10 ** k) % 10
        n_digits[has] = k + 1
    rows = np.nonzero(neg)[0]
    sub[rows, n_int - 1 - n_digits[rows]] = ord("-")
    out[ok] = sub
    return out


def _digit_column(x, n):
    """One column of single digits 1..9 (0 or NaN blank) for LLI and SSI flags, ``(n, 1)``."""
    out = np.full((n, 1), ord(" "), np.uint8)
    if x is None:
        return out
    a = np.asarray(x, dtype=float).ravel()
    ok = np.isfinite(a) & (a > 0)
    out[ok, 0] = ord("0") + np.clip(a[ok], 0, 9).astype(np.uint8)
    return out


def signal_strength_indicator(cn0_dbhz):
    """RINEX signal strength indicator 1..9 from C/N0 [dB-Hz] (§5.7: 1 below
    12 dB-Hz, then one step per 6 dB, 9 from 54 dB-Hz); NaN stays NaN."""
    s = np.asarray(cn0_dbhz, dtype=float)
    return np.where(np.isfinite(s), np.clip(np.floor((s - 12.0) / 6.0) + 2.0, 1.0, 9.0), np.nan)


def _code_key(code):
    return (code[1], _TYPE_ORDER.index(code[0]), code[2])


# --- observation file -----------------------------------------------------------------------------
def write_obs(path, *, time, sats, obs, lli=None, approx_position_e=None, header_comments=(), interval_s=None,
              marker_name="INSKIT", marker_type="NON_PHYSICAL", observer="inskit", agency="inskit",
              receiver=("SIMULATED", "INSKIT SIMULATOR", "1"), antenna=("SIMULATED", "ISOTROPIC NONE"),
              antenna_delta_hen=(0.0, 0.0, 0.0), ssi="auto"):
    """Write a RINEX 3.04 observation file.

    Parameters
    ----------
    path : str or Path
    time : (n_ep,) array_like
        Epochs (receiver time tags) [s since the GPS epoch, GPS scale],
        strictly increasing.
    sats : sequence of str, length n_sat
        Satellite names, e.g. ``"G05"``, ``"E11"``.
    obs : dict
        RINEX 3 observation code (``"C1C"``, ``"L1C"``, ``"D1C"``,
        ``"S1C"`` ...) -> ``(n_ep, n_sat)`` array [m, cycles, Hz, dB-Hz];
        NaN means absent.  A system's header lists the codes that have at
        least one value for one of its satellites (band, then C L D S).
    lli : dict or ndarray, optional
        Loss-of-lock indicators (0..7): a dict code -> ``(n_ep, n_sat)``
        ints, or one ``(n_ep, n_sat)`` array applied to every phase (``L``)
        code.  0 is written blank.
    approx_position_e : (3,) array_like, optional
        ``APPROX POSITION XYZ`` [m, ECEF]; zeros if not given (a moving
        receiver may leave it so).
    header_comments : sequence of str
        ``COMMENT`` lines (each cut into 60-column lines).
    interval_s : float, optional
        ``INTERVAL``; if not given it is written when the epochs are
        regular.
    marker_name, marker_type, observer, agency, receiver, antenna,
    antenna_delta_hen
        The corresponding header fields (``antenna_delta_hen`` [m]).
    ssi : {"auto", None}
        ``"auto"``: the signal strength indicator of every observation of a
        band is derived from that band's ``S`` code (same band and
        attribute, e.g. ``S1C`` for ``C1C``) when it is present
        (:func:`signal_strength_indicator`); ``None``: blank.

    Returns
    -------
    Path

    Notes
    -----
    Epochs at which no satellite has any observation are left out (an
    empty epoch record says nothing).  The epoch flag is 0 throughout; the
    receiver clock offset field is left blank (the clock is in the
    observations, as a receiver that does not steer its clock reports it).

    References
    ----------
    RINEX 3.04 Tables A2 (header: RINEX VERSION / TYPE, PGM / RUN BY /
    DATE, MARKER NAME, MARKER TYPE, OBSERVER / AGENCY, REC # / TYPE /
    VERS, ANT # / TYPE, APPROX POSITION XYZ, ANTENNA: DELTA H/E/N, SYS / #
    / OBS TYPES, INTERVAL, TIME OF FIRST OBS, TIME OF LAST OBS, SYS /
    PHASE SHIFT, GLONASS SLOT / FRQ #, GLONASS COD/PHS/BIS, END OF HEADER)
    and A3 (epoch record ``> yyyy mm dd hh mm ss.sssssss  f nnn``; per
    observation F14.3, LLI I1, SSI I1).
    """
    t = np.ascontiguousarray(time, dtype=float)
    if t.ndim != 1 or len(t) == 0:
        raise InputError(f"`time` must have shape (n_ep,) with n_ep >= 1, got {t.shape}")
    if not np.isfinite(t).all():
        raise InputError(f"`time` has a NaN or infinite value at row {int(np.argmax(~np.isfinite(t)))}")
    if (np.diff(t) <= 0).any():
        raise InputError(f"`time` must strictly increase (row {int(np.argmax(np.diff(t) <= 0)) + 1})")
    sats = tuple(str(s) for s in sats)
    for s in sats:
        if not _SAT_RE.match(s):
            raise InputError(f"`sats`: {s!r} is not a RINEX 3 satellite name such as 'G05'")
    if len(set(sats)) != len(sats):
        raise InputError("`sats` has a satellite twice")
    n_ep, n_sat = len(t), len(sats)
    arrays = {}
    for code, a in obs.items():
        if not _CODE_RE.match(str(code)):
            raise InputError(f"`obs`: {code!r} is not a RINEX 3 observation code such as 'C1C'")
        a = np.asarray(a, dtype=float)
        if a.shape != (n_ep, n_sat):
            raise InputError(f"`obs[{code!r}]` must have shape (n_ep, n_sat) = {(n_ep, n_sat)}, got {a.shape}")
        if np.isinf(a).any():
            raise InputError(f"`obs[{code!r}]` has an infinite value (use NaN for an absent observation)")
        arrays[str(code)] = a
    lli_arrays = {}
    if lli is not None:
        if isinstance(lli, dict):
            items = lli.items()
        else:
            items = [(c, lli) for c in arrays if c[0] == "L"]
        for code, a in items:
            a = np.asarray(a)
            if a.shape != (n_ep, n_sat):
                raise InputError(f"`lli` for {code!r} must have shape {(n_ep, n_sat)}, got {a.shape}")
            if ((a < 0) | (a > 7)).any():
                raise InputError(f"`lli` for {code!r}: loss-of-lock indicators are 0..7")
            lli_arrays[code] = a
    if ssi not in ("auto", None):
        raise InputError(f"`ssi` must be 'auto' or None, got {ssi!r}")

    systems = np.array([s[0] for s in sats])
    # codes per system: those with at least one value for one of its satellites
    sys_codes = {}
    for sy in sorted(set(systems), key=_SYSTEM_ORDER.index):
        cols = systems == sy
        codes = sorted((c for c, a in arrays.items() if np.isfinite(a[:, cols]).any()), key=_code_key)
        if codes:
            sys_codes[sy] = codes
    if not sys_codes:
        raise InputError("`obs` holds no observation at all: nothing to write")
    present = np.zeros((n_ep, n_sat), bool)
    for sy, codes in sys_codes.items():
        cols = systems == sy
        for c in codes:
            present[:, cols] |= np.isfinite(arrays[c][:, cols])
    epochs = np.nonzero(present.any(axis=1))[0]
    if present.sum(axis=1).max() > 999:
        raise InputError("more than 999 satellites in one epoch")

    # --- body: one byte matrix per system, one row per (epoch, satellite) ---
    row_bytes = np.empty((n_ep, n_sat), dtype=object)
    for sy, codes in sys_codes.items():
        cols = np.nonzero(systems == sy)[0]
        m = n_ep * len(cols)
        parts = [np.frombuffer("".join(sats[j] for j in cols).encode(), np.uint8).reshape(len(cols), 3)
                 [np.tile(np.arange(len(cols)), n_ep)]]
        for c in codes:
            vals = arrays[c][:, cols]
            parts.append(_fixed(vals, 14, 3, f"obs[{c!r}]"))
            flag = lli_arrays.get(c)
            parts.append(_digit_column(None if flag is None else flag[:, cols], m))
            s_code = "S" + c[1:]
            strength = None
            if ssi == "auto" and s_code in arrays:
                strength = np.where(np.isfinite(vals), signal_strength_indicator(arrays[s_code][:, cols]), np.nan)
            parts.append(_digit_column(strength, m))
        parts.append(np.full((m, 1), ord("\n"), np.uint8))
        mat = np.ascontiguousarray(np.hstack(parts))
        width = mat.shape[1]
        row_bytes[:, cols] = mat.view(f"S{width}").reshape(n_ep, len(cols))

    y, mo, d, h, mi, s = calendar(t)
    body = []
    for k in epochs:
        sel = present[k]
        body.append(f"> {y[k]:4d} {mo[k]:02d} {d[k]:02d} {h[k]:02d} {mi[k]:02d}{s[k]:11.7f}  0{int(sel.sum()):3d}\n"
                    .encode())
        body.append(b"".join(row_bytes[k, sel]))

    # --- header ---
    hdr = [_hline(f"{3.04:9.2f}{'':11}{'OBSERVATION DATA':<20}{'M: Mixed':<20}", "RINEX VERSION / TYPE"),
           _hline(f"{'inskit':<20}{'inskit':<20}{_run_date():<20}", "PGM / RUN BY / DATE")]
    for c in header_comments:
        c = str(c)
        for i in range(0, max(len(c), 1), 60):
            hdr.append(_hline(c[i:i + 60], "COMMENT"))
    hdr.append(_hline(str(marker_name)[:60], "MARKER NAME"))
    hdr.append(_hline(str(marker_type)[:20], "MARKER TYPE"))
    hdr.append(_hline(f"{str(observer)[:20]:<20}{str(agency)[:40]:<40}", "OBSERVER / AGENCY"))
    hdr.append(_hline("".join(f"{str(x)[:20]:<20}" for x in receiver), "REC # / TYPE / VERS"))
    hdr.append(_hline("".join(f"{str(x)[:20]:<20}" for x in antenna), "ANT # / TYPE"))
    xyz = np.zeros(3) if approx_position_e is None else np.asarray(approx_position_e, dtype=float).reshape(3)
    hdr.append(_hline("".join(f"{v:14.4f}" for v in xyz), "APPROX POSITION XYZ"))
    hdr.append(_hline("".join(f"{v:14.4f}" for v in np.asarray(antenna_delta_hen, float).reshape(3)),
                      "ANTENNA: DELTA H/E/N"))
    for sy, codes in sys_codes.items():
        for i in range(0, len(codes), 13):
            chunk = "".join(f" {c}" for c in codes[i:i + 13])
            head = f"{sy}  {len(codes):3d}" if i == 0 else " " * 6
            hdr.append(_hline(head + chunk, "SYS / # / OBS TYPES"))
    if any("S" == c[0] for codes in sys_codes.values() for c in codes):
        hdr.append(_hline("DBHZ", "SIGNAL STRENGTH UNIT"))
    if interval_s is None and len(t) > 1:
        dts = np.diff(t)
        if np.ptp(dts) < 1e-6:
            interval_s = float(np.mean(dts))
    if interval_s is not None:
        hdr.append(_hline(f"{float(interval_s):10.3f}", "INTERVAL"))
    for k, label in ((epochs[0], "TIME OF FIRST OBS"), (epochs[-1], "TIME OF LAST OBS")):
        hdr.append(_hline(f"{y[k]:6d}{mo[k]:6d}{d[k]:6d}{h[k]:6d}{mi[k]:6d}{s[k]:13.7f}{'':5}GPS", label))
    for sy, codes in sys_codes.items():
        for c in codes:
            if c[0] == "L":
                hdr.append(_hline(f"{sy} {c} {0.0:8.5f}", "SYS / PHASE SHIFT"))
    hdr.append(_hline(f"{0:3d}", "GLONASS SLOT / FRQ #"))
    hdr.append(_hline(" C1C    0.000 C1P    0.000 C2C    0.000 C2P    0.000", "GLONASS COD/PHS/BIS"))
    hdr.append(_hline("", "END OF HEADER"))

    path = Path(path)
    with atomic_write(path) as tmp, open(tmp, "wb") as f:
        f.write("".join(hdr).encode())
        f.write(b"".join(body))
    return path


# --- navigation file ------------------------------------------------------------------------------
def _d19(x):
    """Fortran ``D19.12`` fields of the values ``x`` (13 significant digits,
    ``D`` exponent): one string of ``19 * len(x)`` characters; NaN is
    written blank (a spare field)."""
    out = []
    for v in np.asarray(x, dtype=float).ravel():
        if not np.isfinite(v):
            out.append(" " * 19)
            continue
        if v != 0.0 and abs(v) < 1e-99:
            v = 0.0
        out.append(f"{v:19.12E}".replace("E", "D"))
    return "".join(out)


def nav_precision(x):
    """``x`` rounded to what a ``D19.12`` field holds (13 significant
    digits), so that a value written and read back is the same float."""
    a = np.asarray(x, dtype=float)
    flat = [float(f"{v:.12E}") if np.isfinite(v) else v for v in a.ravel()]
    return np.array(flat).reshape(a.shape) if a.ndim else flat[0]


def iono_precision(x):
    """Klobuchar coefficients rounded to what the header's ``D12.4``
    fields hold (5 significant digits): simulate with these and the
    reader of the file uses the same model."""
    a = np.asarray(x, dtype=float)
    return np.array([float(f"{v:.4E}") for v in a.ravel()]).reshape(a.shape)


def _d12(x):
    return "".join(f"{v:12.4E}".replace("E", "D") for v in np.asarray(x, dtype=float).ravel())


def write_nav(path, nav_like, *, iono_alpha=None, iono_beta=None, header_comments=()):
    """Write a RINEX 3.04 navigation file of GPS and Galileo broadcast
    ephemerides.

    Parameters
    ----------
    path : str or Path
    nav_like : object
        With attributes ``sats`` (n_rec,) str, ``system`` (n_rec,) ``'G'`` or
        ``'E'``, ``toc``, ``toe`` (n_rec,) [s since the GPS epoch] and
        ``params``: a dict of (n_rec,) arrays with the keys ``af0 af1 af2
        iode crs dn m0 cuc e cus sqrt_a cic omega0 cis i0 crc omega
        omega_dot idot svacc health tgd iodc fit_h`` (SI units and radians
        as broadcast: s, s/s, s/s^2, m, rad, rad/s, m^0.5, m, hours) and,
        for Galileo records, ``bgd_e5a_e1 bgd_e5b_e1 data_source``;
        optional keys ``ttm`` (transmission time, s of week; default
        ``toe - 2 h`` floored at 0), ``codes_l2`` and ``l2p_flag``.  The
        orbit and clock parameters (and Galileo's ``data_source``) must be
        finite; a NaN elsewhere (``iode``, ``iodc``, ``svacc``, ``tgd``,
        ``fit_h``, ``ttm`` ...) is written as a blank field.  The
        optional ``iono_alpha``/``iono_beta`` attributes (4,) are used when
        the keyword arguments are not given.  (:class:`inskit.gnss.rinex.NavData`
        is such an object.)
    iono_alpha, iono_beta : (4,) array_like, optional
        Klobuchar coefficients [s, s/semicircle, s/semicircle^2,
        s/semicircle^3] and [s, ...], written as ``IONOSPHERIC CORR GPSA``
        and ``GPSB``.  Written with 5 significant digits (``D12.4``): see
        :func:`iono_precision`.
    header_comments : sequence of str

    Returns
    -------
    Path

    Notes
    -----
    The week written with each record (``GPS Week`` / ``GAL Week``) is the
    week of its ``toe`` and ``Toe`` is that week's second, so the record
    fixes the absolute time of ``toe``.  Orbit values are written with 13
    significant digits (:func:`nav_precision`).

    References
    ----------
    RINEX 3.04 Table A5-A6 (GPS: SV / EPOCH / SV CLK, BROADCAST ORBIT 1-7)
    and A8 (Galileo), header Table A5 (IONOSPHERIC CORR ``A4,1X,4D12.4``).
    """
    sats = np.asarray(nav_like.sats).astype(str)
    system = np.asarray(nav_like.system).astype(str)
    toc = np.asarray(nav_like.toc, dtype=float)
    toe = np.asarray(nav_like.toe, dtype=float)
    n = len(sats)
    if not (len(system) == len(toc) == len(toe) == n):
        raise InputError("nav records: `sats`, `system`, `toc` and `toe` must have the same length")
    other = sorted(set(system) - {"G", "E"})
    if other:
        raise InputError(f"nav records: only GPS ('G') and Galileo ('E') can be written, got {other}")
    p = {k: np.asarray(v, dtype=float) for k, v in nav_like.params.items()}
    need = ["af0", "af1", "af2", "iode", "crs", "dn", "m0", "cuc", "e", "cus", "sqrt_a", "cic", "omega0", "cis",
            "i0", "crc", "omega", "omega_dot", "idot", "svacc", "health", "tgd", "iodc", "fit_h"]
    if (system == "E").any():
        need += ["bgd_e5a_e1", "bgd_e5b_e1", "data_source"]
    missing = [k for k in need if k not in p]
    if missing:
        raise InputError(f"nav records: missing parameters {missing}")
    # the orbit and clock must be complete; informational fields (IODE/IODC, accuracy, fit interval,
    # group delays) may be NaN and are then written blank, as a receiver that did not decode them would
    core = ["af0", "af1", "af2", "crs", "dn", "m0", "cuc", "e", "cus", "sqrt_a", "cic", "omega0", "cis", "i0",
            "crc", "omega", "omega_dot", "idot", "health"]
    for k in need:
        if p[k].shape != (n,):
            raise InputError(f"nav records: parameter {k!r} must have shape ({n},), got {p[k].shape}")
    for k in core + ["data_source"]:
        if k not in p:
            continue
        applies = system == "E" if k == "data_source" else np.ones(n, bool)
        bad = applies & ~np.isfinite(p[k])
        if bad.any():
            i = int(np.argmax(bad))
            raise InputError(f"nav records: parameter {k!r} is not finite in record {i} ({sats[i]})")
    alpha = getattr(nav_like, "iono_alpha", None) if iono_alpha is None else iono_alpha
    beta = getattr(nav_like, "iono_beta", None) if iono_beta is None else iono_beta

    week = np.floor(toe / SECONDS_PER_WEEK)
    toe_sow = toe - week * SECONDS_PER_WEEK
    ttm = p["ttm"] if "ttm" in p else np.maximum(toe_sow - 7200.0, 0.0)
    y, mo, d, h, mi, s = calendar(toc, decimals=0)
    if (np.abs(toc - np.round(toc)) > 1e-6).any():
        raise InputError("nav records: `toc` must be whole seconds (the record epoch is written to 1 s)")
    zero = np.zeros(n)
    codes_l2 = np.nan_to_num(p.get("codes_l2", zero + 1.0), nan=1.0)
    l2p = np.nan_to_num(p.get("l2p_flag", zero), nan=0.0)
    lines = []
    order = np.lexsort((sats, toc, [_SYSTEM_ORDER.index(x) for x in system]))
    for i in order:
        gal = system[i] == "E"
        head = f"{sats[i]} {y[i]:4d} {mo[i]:02d} {d[i]:02d} {h[i]:02d} {mi[i]:02d} {round(s[i]):02d}"
        rows = [
            [p["iode"][i], p["crs"][i], p["dn"][i], p["m0"][i]],
            [p["cuc"][i], p["e"][i], p["cus"][i], p["sqrt_a"][i]],
            [toe_sow[i], p["cic"][i], p["omega0"][i], p["cis"][i]],
            [p["i0"][i], p["crc"][i], p["omega"][i], p["omega_dot"][i]],
        ]
        if gal:
            rows += [[p["idot"][i], p["data_source"][i], week[i], 0.0],
                     [p["svacc"][i], p["health"][i], p["bgd_e5a_e1"][i], p["bgd_e5b_e1"][i]],
                     [ttm[i]]]
        else:
            rows += [[p["idot"][i], codes_l2[i], week[i], l2p[i]],
                     [p["svacc"][i], p["health"][i], p["tgd"][i], p["iodc"][i]],
                     [ttm[i], p["fit_h"][i]]]
        lines.append(head + _d19([p["af0"][i], p["af1"][i], p["af2"][i]]) + "\n")
        lines.extend("    " + _d19(r) + "\n" for r in rows)

    hdr = [_hline(f"{3.04:9.2f}{'':11}{'N: GNSS NAV DATA':<20}{'M: Mixed':<20}", "RINEX VERSION / TYPE"),
           _hline(f"{'inskit':<20}{'inskit':<20}{_run_date():<20}", "PGM / RUN BY / DATE")]
    for c in header_comments:
        c = str(c)
        for i in range(0, max(len(c), 1), 60):
            hdr.append(_hline(c[i:i + 60], "COMMENT"))
    for name, coef in (("GPSA", alpha), ("GPSB", beta)):
        if coef is not None:
            coef = np.asarray(coef, dtype=float).reshape(4)
            hdr.append(_hline(f"{name} {_d12(coef)}", "IONOSPHERIC CORR"))
    hdr.append(_hline("", "END OF HEADER"))
    path = Path(path)
    with atomic_write(path) as tmp:
        Path(tmp).write_text("".join(hdr) + "".join(lines))
    return path
