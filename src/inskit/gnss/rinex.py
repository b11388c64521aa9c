"""RINEX 2.1x / 3.0x observation and navigation readers (GPS and Galileo).

Why our own reader
------------------
georinex 1.16.1 (the obvious third-party choice) was measured on this
machine (2 cores, numpy 2.4, xarray 2024) before this module was written:

* on the RINEX 2.11 IGS file ``abpo0080.15o`` (3.0 MB, 2727 epochs) it
  **fails** with ``numpy.exceptions.DTypePromotionError`` inside
  ``xarray.merge``;
* on the 0.9 MB RINEX 3.04 file ``gnss_1730.obs`` (536 epochs, 20
  satellites) it takes **4.9-9.5 s** (5.8 s in the first measurement; the
  spread is the load of the shared machine).

This reader, measured on the same machine (best of 5, warm cache):

* ``gnss_1730.obs`` (RINEX 3.04, 0.9 MB): **0.022 s**, values equal to
  georinex's (test_gnss_rinex.py compares them, to 1e-3);
* ``abpo0080.15o`` (RINEX 2.11, 3.0 MB, 2727 epochs, 31 satellites, 7
  types): **0.09-0.13 s** (target was < 1.5 s);
* ``abpo0080.15n`` (167 records): 0.003 s.

It returns plain numpy arrays (epochs x satellites) rather than an xarray
Dataset, and refuses bad files with the file name and line number.

How it parses
-------------
The file is read whole (gzip, ``.Z``, Hatanaka ``.crx``/``.YYd`` are
recognised by their content and expanded with :mod:`gzip` and the
``hatanaka`` package), split into lines, and one Python pass over the
*epoch* lines finds where every satellite record starts.  All the lines are
then laid into one fixed-width byte matrix and each observation field
(RINEX F14.3 plus the loss-of-lock and signal-strength digits) is cut out
for all records at once and converted by numpy's string-to-float cast.

Conventions
-----------
* Times are seconds since the GPS epoch on the GPS scale
  (:mod:`inskit.gnss.time`).  Files whose time system is GPS or GAL (and
  QZS) are taken as they are (GST is aligned with GPST to tens of ns); BDT
  is converted (+14 s).  GLONASS (UTC(SU)) and UTC time tags would need a
  leap-second table and are refused with :class:`~inskit.errors.InputError`.
* Satellites are named ``'G05'``, ``'E11'``; in RINEX 2 a blank system
  letter means GPS (RINEX 2.11 section 5.1).
* Observation codes are RINEX 3 codes.  RINEX 2 types are mapped (the
  tracking mode of RINEX 2 is implied by the type, RINEX 3.04 Table 4 /
  RINEX 2.11 section 5.1):

  ======  =====  =====================================================
  RINEX2  code   meaning
  ======  =====  =====================================================
  C1      C1C    L1 C/A code
  P1      C1W    L1 P(Y) code (semi-codeless under anti-spoofing)
  L1      L1C    L1 phase (on C/A)
  D1/S1   D1C/S1C
  P2      C2W    L2 P(Y) code
  L2      L2W    L2 phase
  D2/S2   D2W/S2W
  C2      C2X    L2C code (RINEX 2.11), tracking mode unknown
  C5 ...  C5X    band 5, 6, 7, 8 types map to ``<type><band>X``
  ======  =====  =====================================================

* Epoch flags: 0 (OK) and 1 (power failure between the previous and the
  current epoch) are kept and returned in ``epoch_flag``; flags 2-5 (moving
  antenna, new site, header information, external event) and 6 (cycle-slip
  records) are skipped together with the records that follow them (RINEX
  3.04 section 5.2.6 / Table A13).  Header changes signalled by flag 4
  are therefore not applied.
* ``SYS / SCALE FACTOR`` (RINEX 3) is applied; ``RCV CLOCK OFFS APPL`` is
  kept in ``header`` only.

References
----------
RINEX 2.11 (Gurtner & Estey, 2007), sections 5-7 and Tables A1-A4.
RINEX 3.04 (IGS/RTCM-SC104, 2018), sections 5-6 and Tables A1-A14.
Hatanaka, Y. (2008), A compression format and tools for GNSS observation
data, Bull. GSI 55.
"""

from __future__ import annotations

import gzip
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from .constants import BDT_MINUS_GPST_S, SECONDS_PER_WEEK
from .time import from_week_sow, gps_seconds

__all__ = ["ObsData", "NavData", "read_obs", "read_nav", "RINEX2_TO_RINEX3"]

#: RINEX 2 observation type -> RINEX 3 code (see the module docstring).
RINEX2_TO_RINEX3 = {
    "C1": "C1C", "P1": "C1W", "L1": "L1C", "D1": "D1C", "S1": "S1C",
    "P2": "C2W", "L2": "L2W", "D2": "D2W", "S2": "S2W", "C2": "C2X",
}
for _band in "5678":
    for _t in "CLDS":
        RINEX2_TO_RINEX3[f"{_t}{_band}"] = f"{_t}{_band}X"
del _band, _t

_SYSTEM_NAMES = {"G": "GPS", "R": "GLONASS", "E": "Galileo", "C": "BeiDou", "J": "QZSS",
                 "S": "SBAS", "I": "NavIC/IRNSS"}


# --------------------------------------------------------------------- helpers
def _read_lines(path):
    """Whole file as a list of lines (no line ends), compressed forms expanded."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    if data[:2] == b"\x1f\x8b":
        try:
            data = gzip.decompress(data)
        except (OSError, EOFError) as exc:
            raise InputError(f"{path}: damaged gzip data ({exc})") from None
    head = data[:200]
    compressed = data[:2] == b"\x1f\x9d" or data[:3] == b"BZh" or data[:4] == b"PK\x03\x04"
    if compressed or b"COMPACT RINEX FORMAT" in head or b"CRINEX VERS" in head:
        import hatanaka

        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                data = hatanaka.decompress(data)
        except Exception as exc:  # the package raises several types
            raise InputError(f"{path}: cannot be decompressed as (Hatanaka/Z/bz2/zip) RINEX ({exc})") from None
    text = data.decode("latin-1")
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return lines


def _parse_header(lines, path, fold_case=False):
    """(index of the first body line, {label: [content (columns 1-60), ...]},
    {label: [line numbers]}).

    ``fold_case`` reads labels written in lower case ('end of header', as some
    converters write a whole file) as their upper-case RINEX labels.
    """
    def label_of(line):
        label = line[60:80].strip()
        return label.upper() if fold_case else label

    if not lines or label_of(lines[0]) != "RINEX VERSION / TYPE":
        first = lines[0][:60] if lines else ""
        raise InputError(
            f"{path}: line 1: not a RINEX file: expected the label 'RINEX VERSION / TYPE' in "
            f"columns 61-80, got {first!r}"
        )
    header: dict[str, list[str]] = {}
    where: dict[str, list[int]] = {}
    for i, line in enumerate(lines):
        label = label_of(line)
        if label == "END OF HEADER":
            return i + 1, header, where
        header.setdefault(label, []).append(line[:60])
        where.setdefault(label, []).append(i + 1)
    raise InputError(f"{path}: no 'END OF HEADER' line (the file has {len(lines)} lines): truncated header?")


def _hfloat(text, path, line_no, what):
    try:
        return float(text.replace("D", "E").replace("d", "e"))
    except ValueError:
        raise InputError(f"{path}: line {line_no}: expected a number for {what}, got {text.strip()!r}") from None


def _version(header, path):
    text = header["RINEX VERSION / TYPE"][0]
    v = _hfloat(text[0:9], path, 1, "the RINEX version (columns 1-9)")
    return v, text[20:21], text[40:41]


def _fixed_matrix(lines, width):
    """All lines as an (n_lines, width) uint8 matrix, blank padded/truncated."""
    joined = "".join(line.ljust(width)[:width] for line in lines)
    return np.frombuffer(joined.encode("latin-1"), dtype=np.uint8).reshape(len(lines), width)


def _parse_fields(buf, rows, col, width, path, what, d_exponent=False):
    """Numbers in columns ``col:col+width`` of the given rows of ``buf``.

    Blank fields become NaN.  A field that is not a number raises
    :class:`InputError` naming the line (1-based ``rows + 1``) and columns.
    """
    f = buf[rows, col:col + width]
    if f.shape[1] < width:  # lines are padded to the matrix width; only a short matrix can do this
        f = np.concatenate([f, np.full((f.shape[0], width - f.shape[1]), 32, np.uint8)], axis=1)
    f = np.array(f, copy=True)
    if d_exponent:
        f[(f == 68) | (f == 100)] = 69  # 'D', 'd' -> 'E'
    blank = (f == 32).all(axis=1)
    s = np.ascontiguousarray(f).view(f"S{width}").ravel()
    s[blank] = b"nan"
    try:
        out = s.astype(np.float64)
    except ValueError:
        for j, v in enumerate(s):
            try:
                float(v)
            except ValueError:
                raise InputError(
                    f"{path}: line {int(rows[j]) + 1}: columns {col + 1}-{col + width}: expected a number "
                    f"({what}), got {v.decode('latin-1').strip()!r}"
                ) from None
        raise  # pragma: no cover - numpy and float() disagree
    # RINEX numbers are right-justified (F14.3, D19.12): one whose field ends in a blank was cut short, by a
    # truncated line ('3.115625000000D+0' read as 3.1 for 31.2) or shifted columns, and would be read wrong
    short = np.flatnonzero(~blank & (f[:, -1] == 32))
    if short.size:
        j = int(short[0])
        text = bytes(buf[int(rows[j]), col:col + width]).decode("latin-1").strip()
        raise InputError(f"{path}: line {int(rows[j]) + 1}: columns {col + 1}-{col + width}: the number "
                         f"{text!r} ({what}) does not end at column {col + width}: the line "
                         "is cut short or its columns are shifted (RINEX numbers are right-justified in fixed "
                         "columns)")
    bad = np.flatnonzero(~np.isfinite(out) & ~blank)  # 'nan', 'inf', '1E999': no field of RINEX is infinite
    if bad.size:
        j = int(bad[0])
        raise InputError(f"{path}: line {int(rows[j]) + 1}: columns {col + 1}-{col + width}: expected a finite "
                         f"number ({what}), got {s[j].decode('latin-1').strip()!r}")
    return out


def _sat_names(raw, default_system):
    """Normalise 3-character satellite fields ('G 5', ' 5', 'G05', 'g05') to 'G05'.

    A lower-case system letter ('g05', 'e11', as some converters write) is
    read as its upper-case system: RINEX writes upper case, and no system
    letter has a lower-case meaning of its own.
    """
    out = []
    cache: dict[str, str] = {}
    for r in raw:
        name = cache.get(r)
        if name is None:
            sys = r[0].upper() if r[0] != " " else default_system
            num = r[1:3].strip()
            name = f"{sys}{int(num):02d}" if num.isdigit() else ""
            cache[r] = name
        out.append(name)
    return out


def _time_offset(tsys, path, line_no):
    """Seconds to add to the file's time tags to get GPS time."""
    tsys = tsys.strip().upper()
    if tsys in ("GPS", "GAL", "QZS", "IRN", ""):
        return 0.0
    if tsys in ("BDT", "BDS"):
        return -BDT_MINUS_GPST_S
    raise InputError(
        f"{path}: line {line_no}: time system {tsys!r} is not supported: GLONASS (UTC(SU)) and UTC time "
        "tags need leap seconds; convert the file to GPS time (e.g. with RTKLIB convbin or teqc)"
    )


# --------------------------------------------------------------- observations
@dataclass(frozen=True, eq=False)
class ObsData:
    """RINEX observations as (epoch, satellite) arrays.

    Attributes
    ----------
    path : str
    version : float
        RINEX version of the file (2.11, 3.04 ...).
    time : (n_epoch,) ndarray
        Receiver time tags [s since the GPS epoch, GPS scale].
    sats : tuple of str
        Sorted satellite names (``'E11'``, ``'G01'`` ...), one column each.
    obs : dict of str -> (n_epoch, n_sat) ndarray
        RINEX 3 code -> value (m for C, cycles for L, Hz for D, dB-Hz or the
        RINEX 2 SNR digit for S), NaN where absent.  Systems that share a
        code (GPS and Galileo 'C1C') share a key; columns are per satellite.
    lli : dict of str -> (n_epoch, n_sat) int8 ndarray or None
        Loss-of-lock indicator of each phase code (bit 0: lost lock, cycle
        slip possible; 0 also where blank).
    approx_position_e : (3,) ndarray or None
        Header ``APPROX POSITION XYZ`` [m, ECEF]; None when absent or zero.
    interval_s : float or None
        Header ``INTERVAL`` [s].
    header : dict
        Header lines by label (content columns 1-60), plus parsed entries
        ``'antenna_delta_hen'`` (3,) [m], ``'receiver'``, ``'antenna'``,
        ``'marker'``, ``'time_system'``, ``'obs_types'`` ({system: codes}),
        ``'satellites_by_system'`` ({system letter: number of satellites in
        the file}, the systems not kept included).
    epoch_flag : (n_epoch,) int8 ndarray
        0 or 1 (power failure before this epoch).
    clock_offset_s : (n_epoch,) ndarray
        Receiver clock offset from the epoch line [s], NaN when absent.
    skipped_events : int
        Epochs with flags 2-6 that were skipped.
    """

    path: str
    version: float
    time: np.ndarray
    sats: tuple
    obs: dict
    lli: dict | None
    approx_position_e: np.ndarray | None
    interval_s: float | None
    header: dict
    epoch_flag: np.ndarray | None = None
    clock_offset_s: np.ndarray | None = None
    skipped_events: int = 0

    def sat_index(self, sat: str) -> int:
        """Column of satellite ``sat`` (e.g. ``'G05'``); InputError if absent."""
        try:
            return self.sats.index(sat)
        except ValueError:
            raise InputError(f"{self.path}: satellite {sat!r} is not in the observations "
                             f"(have {', '.join(self.sats)})") from None

    def systems(self) -> set:
        """System letters present (``{'G', 'E'}``)."""
        return {s[0] for s in self.sats}

    @property
    def n_epoch(self) -> int:
        return len(self.time)


def _missing_types_line(header, where, path, version, first_epoch=None):
    """The message for a header without the observation types line of its
    version: one holding the other version's line has a version line that
    disagrees with the file's layout, and is named so, with the layout of
    the first epoch line ``(line number, text)`` when one is given."""
    want, other = ("# / TYPES OF OBSERV", "SYS / # / OBS TYPES") if version < 3 else \
        ("SYS / # / OBS TYPES", "# / TYPES OF OBSERV")
    n_header = max(ln for lns in where.values() for ln in lns) + 1  # the END OF HEADER line
    if other in header:
        ln = where[other][0]
        this, that = ("RINEX 2", "RINEX 3") if version < 3 else ("RINEX 3", "RINEX 2")
        body = ""
        if first_epoch is not None:
            eln, text = first_epoch
            layout = "RINEX 3 ('>' in column 1)" if text[:1] == ">" else "RINEX 2 (no '>' in column 1)"
            body = f"; the first epoch line (line {eln}) is written as {layout}"
        return InputError(
            f"{path}: line {ln}: the version line (line 1) says RINEX {header['RINEX VERSION / TYPE'][0][0:9].strip()} "
            f"but the header holds the {that} observation types line '{other}' here, and no {this} '{want}' "
            f"line{body}: the version line and the file's layout disagree (a version edited by hand, or set by a "
            "converter that did not rewrite the file?); correct the version (columns 1-9 of line 1) to the layout "
            "the file is written in, or convert the file (e.g. with RTKLIB convbin or gfzrnx)")
    return InputError(f"{path}: lines 1-{n_header}: the header has no '{want}' line (RINEX {version:g} "
                      "observation files list their observation types there)")


def _obs_header(header, where, path, version, system_char, first_epoch=None):
    info: dict = {}
    types: dict[str, list[str]] = {}
    if version < 3:
        lines = header.get("# / TYPES OF OBSERV")
        if not lines:
            raise _missing_types_line(header, where, path, version, first_epoch)
        ln = where["# / TYPES OF OBSERV"][0]
        try:
            n = int(lines[0][0:6])
        except ValueError:
            raise InputError(f"{path}: line {ln}: expected the number of observation types in columns 1-6") from None
        codes = []
        for text in lines:
            codes.extend(text[6:60].upper().split())
        if len(codes) < n:
            raise InputError(f"{path}: line {ln}: header announces {n} observation types, lists {len(codes)}")
        types["*"] = codes[:n]
    else:
        lines = header.get("SYS / # / OBS TYPES")
        if not lines:
            raise _missing_types_line(header, where, path, version, first_epoch)
        sys = None
        for text, ln in zip(lines, where["SYS / # / OBS TYPES"]):
            if text[0] != " ":
                sys = text[0].upper()
                try:
                    n = int(text[3:6])
                except ValueError:
                    raise InputError(f"{path}: line {ln}: expected the number of types in columns 4-6") from None
                types[sys] = []
                info.setdefault("_counts", {})[sys] = (n, ln)
            elif sys is None:
                raise InputError(f"{path}: line {ln}: continuation line before any system letter")
            types[sys].extend(text[7:60].upper().split())
        for sys, (n, ln) in info.pop("_counts").items():
            if len(types[sys]) != n:
                raise InputError(f"{path}: line {ln}: system {sys} announces {n} observation types, "
                                 f"lists {len(types[sys])}")
    scale: dict[tuple[str, str], float] = {}
    for text, ln in zip(header.get("SYS / SCALE FACTOR", []), where.get("SYS / SCALE FACTOR", [])):
        try:
            sys, factor, n = text[0].upper(), int(text[2:6]), int(text[8:10] or 0)
        except ValueError:
            raise InputError(f"{path}: line {ln}: cannot read the SYS / SCALE FACTOR line") from None
        for code in (text[10:60].upper().split() if n else types.get(sys, [])):
            scale[(sys, code)] = float(factor)
    approx = None
    if "APPROX POSITION XYZ" in header:
        ln = where["APPROX POSITION XYZ"][0]
        text = header["APPROX POSITION XYZ"][0]
        xyz = np.array([_hfloat(text[14 * k:14 * k + 14], path, ln, "APPROX POSITION XYZ") for k in range(3)])
        if np.linalg.norm(xyz) > 1.0:
            approx = xyz
    interval = None
    if "INTERVAL" in header:
        interval = _hfloat(header["INTERVAL"][0][0:10], path, where["INTERVAL"][0], "INTERVAL")
    if "ANTENNA: DELTA H/E/N" in header:
        text = header["ANTENNA: DELTA H/E/N"][0]
        ln = where["ANTENNA: DELTA H/E/N"][0]
        info["antenna_delta_hen"] = np.array(
            [_hfloat(text[14 * k:14 * k + 14], path, ln, "ANTENNA: DELTA H/E/N") for k in range(3)])
    info["receiver"] = header.get("REC # / TYPE / VERS", [""])[0][20:40].strip()
    info["antenna"] = header.get("ANT # / TYPE", [""])[0][20:40].strip()
    info["marker"] = header.get("MARKER NAME", [""])[0].strip()
    tsys = header.get("TIME OF FIRST OBS", [""])[0][48:51].strip().upper()
    if not tsys:
        tsys = {"G": "GPS", " ": "GPS", "M": "GPS", "R": "GLO", "E": "GAL", "C": "BDT", "J": "QZS"}.get(
            system_char, "GPS")
    info["time_system"] = tsys
    info["obs_types"] = {k: tuple(v) for k, v in types.items()}
    tline = where.get("TIME OF FIRST OBS", [1])[0]
    offset = _time_offset(tsys, path, tline)
    return types, scale, approx, interval, info, offset


def read_obs(path, *, systems=("G", "E"), codes=None) -> ObsData:
    """Read a RINEX 2.1x or 3.0x observation file.

    Parameters
    ----------
    path : str or Path
        Plain, gzip, ``.Z`` or Hatanaka-compressed RINEX observation file.
    systems : sequence of str
        System letters to keep (``'G'`` GPS, ``'E'`` Galileo, ``'S'`` SBAS ...);
        satellites of the others are skipped and counted in one warning.
    codes : sequence of str or None
        RINEX 3 codes to keep (after mapping RINEX 2 types); None keeps all.

    Returns
    -------
    ObsData

    Raises
    ------
    InputError
        Not a RINEX observation file, an unsupported time system, a
        malformed epoch line or number, epochs that repeat with other
        content or go back in time, or a file that ends inside an epoch; the
        message names the file and the line.  An epoch that repeats the one
        before it line for line is dropped, named in one warning.

    Notes
    -----
    Epoch flags 2-6 are skipped with their records (module docstring).
    Lower case ('g05', 'c1c', 'end of header'), which RINEX does not write
    but some converters do, is read as upper case.
    """
    path = Path(path)
    lines = _read_lines(path)
    # lower case ('g05', 'observation data', 'end of header'), as some converters write, read as upper case
    body, header, where = _parse_header(lines, path, fold_case=True)
    version, ftype, fsys = _version(header, path)
    ftype, fsys = ftype.upper(), fsys.upper()
    if ftype != "O":
        raise InputError(f"{path}: line 1: RINEX file type {ftype!r} is not observation data ('O')")
    if not 2.0 <= version < 5.0:
        raise InputError(f"{path}: line 1: RINEX version {version} is not supported (2.xx, 3.xx, 4.xx obs)")
    first_epoch = next(((k + 1, lines[k]) for k in range(body, len(lines)) if lines[k].strip()), None)
    types, scale, approx, interval, info, t_offset = _obs_header(header, where, path, version, fsys, first_epoch)
    default_sys = fsys if (version < 3 and fsys not in (" ", "M")) else "G"
    keep_sys = set(systems)
    keep_codes = None if codes is None else set(codes)

    n_lines = len(lines)
    ep_fields: list[tuple] = []
    ep_flag: list[int] = []
    ep_clock: list[str] = []
    rec_line: list[int] = []     # first line (0-based) of each satellite record
    rec_epoch: list[int] = []
    rec_sat: list[str] = []
    skipped = 0
    # an epoch repeated line for line (files spliced with an overlap of whole identical epochs) carries nothing
    # new: it is dropped, named in one warning; a repeat with other content is refused below
    last_block: list = [None, None]          # (first line, lines) of the last epoch kept
    duplicates: list[tuple[int, int, tuple]] = []  # (line of the copy, line of the epoch kept, time fields)

    def keep_epoch(fields, flag, clock, record_lines):
        """An epoch read: its time fields, flag, clock field ``(line, column, text)`` and the first line of each
        satellite record (RINEX 2 and 3 alike)."""
        e = len(ep_fields)
        ep_fields.append(fields)
        ep_flag.append(flag)
        ep_clock.append(clock)
        rec_line.extend(record_lines)
        rec_epoch.extend([e] * len(record_lines))

    def is_duplicate(start, end, fields):
        block = [ln.rstrip() for ln in lines[start:end]]
        if last_block[1] == block:
            duplicates.append((start + 1, last_block[0] + 1, fields))
            return True
        last_block[:] = [start, block]
        return False

    i = body
    if version < 3:
        n_types = len(types["*"])
        per_sat = max(1, (n_types + 4) // 5)
        while i < n_lines:
            line = lines[i]
            if not line.strip():
                i += 1
                continue
            try:
                flag = int(line[26:29] or 0)
                nsat = int(line[29:32])
            except ValueError:
                raise InputError(
                    f"{path}: line {i + 1}: expected an epoch line (' yy mm dd hh mm ss.sssssss  f nnn'), "
                    f"got {line[:40]!r}"
                ) from None
            n_sat_lines = (nsat + 11) // 12 if nsat > 0 else 1
            if flag > 1:
                skipped += 1
                if flag == 6:
                    i += n_sat_lines + nsat * per_sat
                else:
                    i += 1 + nsat
                continue
            try:
                fields = (int(line[1:3]), int(line[4:6]), int(line[7:9]), int(line[10:12]),
                          int(line[13:15]), float(line[15:26]))
            except ValueError:
                raise InputError(f"{path}: line {i + 1}: cannot read the epoch time in {line[:26]!r}") from None
            if i + n_sat_lines > n_lines:
                raise InputError(f"{path}: line {i + 1}: the file ends inside the satellite list of this epoch")
            sat_text = "".join(lines[i + k][32:68].ljust(36) for k in range(n_sat_lines))
            # the count against the list: a wrong count shifted every later record and was reported lines
            # further on, as a data line where an epoch line was expected
            listed = sum(1 for k in range(len(sat_text) // 3) if sat_text[3 * k:3 * k + 3].strip())
            cont_ok = all(not lines[i + k][:32].strip() for k in range(1, n_sat_lines))
            if nsat > 0 and (listed != nsat or not cont_ok or sat_text[3 * nsat:].strip()):
                raise InputError(
                    f"{path}: line {i + 1}: the epoch announces {nsat} satellites (columns 30-32) but its "
                    f"satellite list (columns 33-68{', continued on the next line' if n_sat_lines > 1 else ''}) "
                    f"{'is not followed by a continuation line' if not cont_ok else f'holds {listed}'}: "
                    "expected as many satellite names as the count"
                )
            first = i + n_sat_lines
            end = first + nsat * per_sat
            if end > n_lines:
                raise InputError(
                    f"{path}: line {n_lines}: the file ends inside the epoch starting at line {i + 1} "
                    f"(expected {nsat} satellite records of {per_sat} line(s) each): truncated file?"
                )
            if is_duplicate(i, end, fields):
                i = end
                continue
            keep_epoch(fields, flag, (i, 68, line[68:80]), range(first, end, per_sat))
            rec_sat.extend(sat_text[3 * k:3 * k + 3] for k in range(nsat))
            i = end
        width = 80
    else:
        per_sat = 1
        while i < n_lines:
            line = lines[i]
            if not line.strip():
                i += 1
                continue
            if line[:1] != ">":
                raise InputError(
                    f"{path}: line {i + 1}: expected an epoch record starting with '>', got {line[:40]!r}"
                )
            try:
                flag = int(line[31:32] or 0)
                nsat = int(line[32:35])
            except ValueError:
                raise InputError(f"{path}: line {i + 1}: cannot read the epoch flag and satellite count "
                                 f"(columns 32-35) in {line[:40]!r}") from None
            if flag > 1:
                skipped += 1
                i += 1 + nsat
                continue
            try:
                fields = (int(line[2:6]), int(line[7:9]), int(line[10:12]), int(line[13:15]),
                          int(line[16:18]), float(line[18:29]))
            except ValueError:
                raise InputError(f"{path}: line {i + 1}: cannot read the epoch time in {line[:29]!r}") from None
            end = i + 1 + nsat
            if end > n_lines:
                raise InputError(
                    f"{path}: line {n_lines}: the file ends inside the epoch starting at line {i + 1} "
                    f"(expected {nsat} satellite lines): truncated file?"
                )
            if is_duplicate(i, end, fields):
                i = end
                continue
            keep_epoch(fields, flag, (i, 41, line[41:56]), range(i + 1, end))
            i = end
        width = 3 + 16 * max((len(v) for v in types.values()), default=0)

    if duplicates:
        def when(fl):
            year = fl[0] + ((2000 if fl[0] < 80 else 1900) if version < 3 else 0)
            return f"{year:04d}-{fl[1]:02d}-{fl[2]:02d} {fl[3]:02d}:{fl[4]:02d}:{fl[5]:06.3f}"

        n = len(duplicates)
        pairs = "; ".join(f"line {b} repeats line {a} ({when(fl)})" for b, a, fl in duplicates[:5])
        more = f"; and {n - 5} more" if n > 5 else ""
        warnings.warn(f"{path}: dropped {n} epoch{'s' if n != 1 else ''} that repeat{'s' if n == 1 else ''} the "
                      f"epoch before {'it' if n == 1 else 'them'} line for line ({pairs}{more}): files spliced "
                      "with an overlap?", stacklevel=2)
    n_epoch = len(ep_fields)
    if n_epoch:
        f = np.array(ep_fields, dtype=float)
        year = f[:, 0].astype(int)
        if version < 3:
            year = np.where(year < 80, year + 2000, year + 1900)
        time = np.asarray(gps_seconds(year, f[:, 1].astype(int), f[:, 2].astype(int), f[:, 3], f[:, 4], f[:, 5]),
                          dtype=float).reshape(-1) + t_offset
    else:
        time = np.zeros(0)
    back = np.flatnonzero(np.diff(time) <= 0)
    if back.size:  # a spliced or concatenated file: each epoch of a filter run must come after the last
        from .time import to_datetime64

        k = int(back[0])
        la, lb = ep_clock[k][0] + 1, ep_clock[k + 1][0] + 1
        ta, tb = (str(to_datetime64(time[j] - t_offset).astype("datetime64[ms]")).replace("T", " ")
                  for j in (k, k + 1))
        how = "repeats" if time[k + 1] == time[k] else "goes back from"
        other = " with other content (a copy identical line for line would be dropped)" if how == "repeats" else ""
        raise InputError(f"{path}: line {lb}: epoch {tb} {how} the epoch at line {la} ({ta}){other}; expected epochs in "
                         "increasing time order (files spliced out of order or overlapping? sort the epochs and "
                         "drop the repeated ones, e.g. with RTKLIB convbin or gfzrnx)")
    clock = np.full(n_epoch, np.nan)
    for k, (ln, col, c) in enumerate(ep_clock):
        if c.strip():
            try:
                clock[k] = float(c)
            except ValueError:
                clock[k] = np.nan
            if not np.isfinite(clock[k]):
                raise InputError(f"{path}: line {ln + 1}: columns {col + 1}-{col + len(c)}: expected the receiver "
                                 f"clock offset (a finite number) or blanks, got {c.strip()!r}")

    rec_line_a = np.asarray(rec_line, dtype=np.int64)
    rec_epoch_a = np.asarray(rec_epoch, dtype=np.int64)
    if version >= 3:
        buf = _fixed_matrix(lines, max(width, 3))
        if rec_line_a.size:
            starts = buf[rec_line_a, 0]
            bad = np.flatnonzero(starts == ord(">"))
            if bad.size:
                ln = int(rec_line_a[bad[0]]) + 1
                raise InputError(f"{path}: line {ln}: expected a satellite line, got an epoch record: "
                                 "the previous epoch has fewer satellite lines than it announces")
            raw = buf[rec_line_a, 0:3].copy().view("S3").ravel()
            rec_sat = [r.decode("latin-1").ljust(3) for r in raw]
    else:
        buf = _fixed_matrix(lines, width)
    names = np.array(_sat_names(rec_sat, default_sys), dtype="<U3") if rec_sat else np.zeros(0, "<U3")
    bad_name = np.flatnonzero(names == "")
    if bad_name.size:
        j = bad_name[0]
        raise InputError(f"{path}: line {int(rec_line_a[j]) + 1}: cannot read a satellite name from "
                         f"{rec_sat[j]!r}")
    sysch = np.array([n[0] for n in names], dtype="<U1") if names.size else np.zeros(0, "<U1")
    keep = np.isin(sysch, list(keep_sys))
    sats = tuple(sorted(set(names[keep].tolist())))
    # every system the file holds, kept or not: a consumer that finds none of its systems can say what is there
    in_file = {s: len(set(names[sysch == s].tolist())) for s in sorted(set(sysch.tolist()))}
    left = {s: n for s, n in in_file.items() if s not in keep_sys}
    if left:  # said as read_nav says it: a mixed file's GLONASS or BeiDou satellites went unmentioned
        text = ", ".join(f"{n} {_SYSTEM_NAMES.get(s, s)}" for s, n in left.items())
        kept = ", ".join(_SYSTEM_NAMES.get(s, s) for s in dict.fromkeys(systems)) or "none"
        warnings.warn(f"{path}: skipped {sum(left.values())} observed satellite{'s' if sum(left.values()) != 1 else ''}"
                      f" of other systems ({text}; systems used: {kept})", stacklevel=2)
    sat_arr = np.array(sats, dtype="<U3")
    col = np.searchsorted(sat_arr, names) if sats else np.zeros(len(names), np.int64)

    obs: dict[str, np.ndarray] = {}
    lli: dict[str, np.ndarray] = {}

    def put(code, rows, line_idx, colpos, factor):
        if keep_codes is not None and code not in keep_codes:
            return
        vals = _parse_fields(buf, line_idx, colpos, 14, path, f"observation {code}")
        if factor != 1.0:
            vals = vals / factor
        arr = obs.get(code)
        if arr is None:
            arr = obs[code] = np.full((n_epoch, len(sats)), np.nan)
        arr[rec_epoch_a[rows], col[rows]] = vals
        if code[0] == "L":
            digit = buf[line_idx, colpos + 14]
            flag = np.where((digit >= 48) & (digit <= 57), digit - 48, 0).astype(np.int8)
            la = lli.get(code)
            if la is None:
                la = lli[code] = np.zeros((n_epoch, len(sats)), np.int8)
            la[rec_epoch_a[rows], col[rows]] = flag

    if version < 3:
        rows = np.flatnonzero(keep)
        for k, t2 in enumerate(types["*"]):
            code = RINEX2_TO_RINEX3.get(t2, t2 if len(t2) == 3 else f"{t2}X")
            put(code, rows, rec_line_a[rows] + k // 5, (k % 5) * 16, 1.0)
    else:
        for sys, sys_codes in types.items():
            if sys not in keep_sys:
                continue
            rows = np.flatnonzero(keep & (sysch == sys))
            if rows.size == 0:
                continue
            for k, code in enumerate(sys_codes):
                put(code, rows, rec_line_a[rows], 3 + 16 * k, scale.get((sys, code), 1.0))

    return ObsData(
        path=str(path), version=version, time=time, sats=sats, obs=obs, lli=lli or None,
        approx_position_e=approx, interval_s=interval, header={**header, **info, "satellites_by_system": in_file},
        epoch_flag=np.asarray(ep_flag, dtype=np.int8), clock_offset_s=clock, skipped_events=skipped,
    )


# ----------------------------------------------------------------- navigation
#: Order of the 31 numbers of a GPS/Galileo record: 3 clock values on the
#: first line, then 7 "broadcast orbit" lines of 4 (RINEX 3.04 Tables A6, A8).
_NAV_SLOTS = (
    "af0", "af1", "af2",
    "iode", "crs", "dn", "m0",
    "cuc", "e", "cus", "sqrt_a",
    "toe_sow", "cic", "omega0", "cis",
    "i0", "crc", "omega", "omega_dot",
    "idot", "slot20", "week", "slot22",
    "svacc", "health", "slot25", "slot26",
    "ttm", "slot28", "slot29", "slot30",
)
#: Fields every GPS and Galileo record needs for the satellite's clock and position (IS-GPS-200 Table 20-IV).
_NAV_ORBIT_PARAMS = ("af0", "af1", "af2", "crs", "dn", "m0", "cuc", "e", "cus", "sqrt_a", "toe_sow", "cic",
                     "omega0", "cis", "i0", "crc", "omega", "omega_dot", "idot", "week")
#: System-specific meaning of the shared slots (NaN for the other system).
_NAV_SPECIFIC = {
    "G": {"slot20": "codes_l2", "slot22": "l2p_flag", "slot25": "tgd", "slot26": "iodc", "slot28": "fit_h"},
    "E": {"slot20": "data_source", "slot25": "bgd_e5a_e1", "slot26": "bgd_e5b_e1"},
}
NAV_PARAMS = tuple(k for k in _NAV_SLOTS if not k.startswith("slot")) + (
    "codes_l2", "l2p_flag", "tgd", "iodc", "fit_h", "data_source", "bgd_e5a_e1", "bgd_e5b_e1")


@dataclass(frozen=True, eq=False)
class NavData:
    """GPS and Galileo broadcast ephemeris records, one row each.

    Attributes
    ----------
    path : str
    sats : (n_rec,) ndarray of str
        ``'G05'``, ``'E11'``.
    system : (n_rec,) ndarray of str
        ``'G'`` or ``'E'``.
    toc : (n_rec,) ndarray
        Clock reference time [s since the GPS epoch].
    toe : (n_rec,) ndarray
        Ephemeris reference time [s since the GPS epoch], from the week and
        the toe seconds of week; a week that disagrees with toc by more
        than half a week (10-bit GPS weeks, raw GST weeks) is corrected to
        the week that puts toe nearest toc.
    params : dict of str -> (n_rec,) float ndarray
        Units as broadcast (s, s/s, s/s^2, m, rad, rad/s, sqrt(m), weeks):
        ``af0 af1 af2 iode crs dn m0 cuc e cus sqrt_a toe_sow cic omega0 cis
        i0 crc omega omega_dot idot week svacc health ttm``;
        GPS only (NaN for Galileo): ``codes_l2 l2p_flag tgd iodc fit_h``;
        Galileo only (NaN for GPS): ``data_source`` (bit 0 I/NAV E1-B,
        bit 1 F/NAV E5a-I, bit 2 I/NAV E5b-I, bit 8 clock for E5a/E1,
        bit 9 clock for E5b/E1), ``bgd_e5a_e1 bgd_e5b_e1``.
        ``iode`` holds Galileo's IODnav; ``svacc`` URA or SISA [m];
        ``fit_h`` the fit interval in hours (RINEX writes 0 for 4 h).
    iono_alpha, iono_beta : (4,) ndarray or None
        GPS Klobuchar coefficients from the header (s, s/sc, s/sc^2, s/sc^3;
        s, s/sc, ...), None when absent.
    skipped : dict
        Records of other systems left out, by system letter.
    header : dict
        Header lines by label.
    """

    path: str
    sats: np.ndarray
    system: np.ndarray
    toc: np.ndarray
    toe: np.ndarray
    params: dict
    iono_alpha: np.ndarray | None
    iono_beta: np.ndarray | None
    skipped: dict = field(default_factory=dict)
    header: dict = field(default_factory=dict)

    def records_for(self, sat) -> np.ndarray:
        """Indices of the records of satellite ``sat`` (``'G05'``), in file order."""
        return np.flatnonzero(self.sats == sat)

    def __len__(self) -> int:
        return len(self.sats)


def _iono_header(header, where, path, version):
    alpha = beta = None
    if version < 3:
        for label in ("ION ALPHA", "ION BETA"):
            if label in header:
                text, ln = header[label][0], where[label][0]
                v = np.array([_hfloat(text[2 + 12 * k:14 + 12 * k], path, ln, label) for k in range(4)])
                if label == "ION ALPHA":
                    alpha = v
                else:
                    beta = v
    else:
        for text, ln in zip(header.get("IONOSPHERIC CORR", []), where.get("IONOSPHERIC CORR", [])):
            kind = text[0:4].strip()
            if kind in ("GPSA", "GPSB"):
                v = np.array([_hfloat(text[5 + 12 * k:17 + 12 * k], path, ln, f"IONOSPHERIC CORR {kind}")
                              for k in range(4)])
                if kind == "GPSA":
                    alpha = v
                else:
                    beta = v
    return alpha, beta


def read_nav(path, *, systems=("G", "E")) -> NavData:
    """Read a RINEX 2.1x GPS or 3.0x (mixed) navigation file.

    Parameters
    ----------
    path : str or Path
        Plain or compressed (gzip, ``.Z``) RINEX navigation file.
    systems : sequence of str
        Systems to keep, a subset of ``('G', 'E')``.  Records of other
        systems (GLONASS, SBAS, BeiDou, QZSS, NavIC) are skipped and counted
        in one warning and in ``NavData.skipped``.

    Returns
    -------
    NavData

    Raises
    ------
    InputError
        Not a navigation file, RINEX 4, a GLONASS/SBAS-only RINEX 2 file, a
        record with too few lines or a malformed number (names file and line).

    Notes
    -----
    'D' and 'd' exponents are read as 'E'.  Layout: RINEX 2.11 Table A4 and
    RINEX 3.04 Tables A6 (GPS) and A8 (Galileo).
    """
    path = Path(path)
    lines = _read_lines(path)
    body, header, where = _parse_header(lines, path)
    version, ftype, fsys = _version(header, path)
    if version >= 4:
        raise InputError(f"{path}: line 1: RINEX {version} navigation files are not supported (2.xx, 3.xx)")
    if version < 3:
        if ftype != "N":
            what = {"G": "GLONASS", "H": "SBAS", "O": "observation", "M": "meteorological"}.get(ftype, repr(ftype))
            raise InputError(f"{path}: line 1: RINEX 2 file type {what} is not supported: expected a GPS "
                             "navigation file (type 'N')")
    elif ftype != "N":
        raise InputError(f"{path}: line 1: RINEX file type {ftype!r} is not navigation data ('N')")
    bad = set(systems) - {"G", "E"}
    if bad:
        from ..errors import ConfigError

        raise ConfigError(f"read_nav: systems {sorted(bad)} are not supported (broadcast orbits: 'G', 'E')")
    alpha, beta = _iono_header(header, where, path, version)

    body_lines = lines[body:]
    n = len(body_lines)
    if version < 3:
        starts = [k for k, line in enumerate(body_lines) if line[:2].strip()]
        sys_of = ["G"] * len(starts)
    else:
        starts = [k for k, line in enumerate(body_lines) if line[:1] not in ("", " ")]
        sys_of = [body_lines[k][0] for k in starts]
    skipped: dict[str, int] = {}
    take = []
    for j, (k, s) in enumerate(zip(starts, sys_of)):
        if s not in systems:
            skipped[s] = skipped.get(s, 0) + 1
            continue
        nxt = starts[j + 1] if j + 1 < len(starts) else n
        if nxt - k < 8:
            if nxt == n:
                raise InputError(f"{path}: line {n + body}: the file ends inside the record starting at line "
                                 f"{k + body + 1} (expected 8 lines): truncated file?")
            raise InputError(f"{path}: line {k + body + 1}: record has {nxt - k} line(s), expected 8 for system {s}")
        if nxt - k > 8:  # a repeated or stray line would shift every later field of the record
            raise InputError(f"{path}: line {k + body + 9}: the record starting at line {k + body + 1} has "
                             f"{nxt - k} lines, expected 8 for system {s} (a line repeated or inserted?)")
        take.append(j)
    if skipped:
        text = ", ".join(f"{v} {_SYSTEM_NAMES.get(s, s)}" for s, v in sorted(skipped.items()))
        warnings.warn(f"{path}: skipped {sum(skipped.values())} navigation records of other systems ({text})",
                      stacklevel=2)
    rec = np.array([starts[j] for j in take], dtype=np.int64)
    rsys = np.array([sys_of[j] for j in take], dtype="<U1")
    buf = _fixed_matrix(lines, 80)
    lineno = rec + body  # 0-based line index in the file
    if version < 3:
        clock_col, orbit_col = 22, 3
    else:
        clock_col, orbit_col = 23, 4
    values = np.full((len(rec), 31), np.nan)
    for k in range(3):
        values[:, k] = _parse_fields(buf, lineno, clock_col + 19 * k, 19, path, _NAV_SLOTS[k], True)
    for ln in range(1, 8):
        for k in range(4):
            slot = 3 + 4 * (ln - 1) + k
            name = _NAV_SLOTS[slot]
            if name.startswith("slot"):
                name = " / ".join(f"{m[name]} ({_SYSTEM_NAMES[sy]})" for sy, m in _NAV_SPECIFIC.items()
                                  if name in m) or "a spare field"
            values[:, slot] = _parse_fields(buf, lineno + ln, orbit_col + 19 * k, 19, path,
                                            f"{name}, broadcast orbit {ln} field {k + 1}", True)
    # epoch fields (a Python loop over records is cheap: a few hundred a day)
    sats, ymdhms = [], []
    for r, ln in zip(rec, lineno):
        line = body_lines[r]
        try:
            if version < 3:
                prn = int(line[0:2])
                sats.append(f"G{prn:02d}")
                yy = int(line[3:5])
                ymdhms.append((yy + (2000 if yy < 80 else 1900), int(line[6:8]), int(line[9:11]),
                               int(line[12:14]), int(line[15:17]), float(line[17:22])))
            else:
                sats.append(f"{line[0]}{int(line[1:3]):02d}")
                ymdhms.append((int(line[4:8]), int(line[9:11]), int(line[12:14]), int(line[15:17]),
                               int(line[18:20]), float(line[21:23])))
        except ValueError:
            raise InputError(f"{path}: line {ln + 1}: cannot read the satellite and epoch of a navigation "
                             f"record from {line[:23]!r}") from None
    if ymdhms:
        f = np.array(ymdhms, dtype=float)
        toc = np.asarray(gps_seconds(f[:, 0].astype(int), f[:, 1].astype(int), f[:, 2].astype(int),
                                     f[:, 3], f[:, 4], f[:, 5]), dtype=float).reshape(-1)
    else:
        toc = np.zeros(0)
    params = {k: values[:, j] for j, k in enumerate(_NAV_SLOTS) if not k.startswith("slot")}
    for name in NAV_PARAMS:
        params.setdefault(name, np.full(len(rec), np.nan))
    for s, mapping in _NAV_SPECIFIC.items():
        m = rsys == s
        for slot, name in mapping.items():
            params[name] = np.where(m, values[:, _NAV_SLOTS.index(slot)], params[name])
    toe = np.asarray(from_week_sow(params["week"], params["toe_sow"]), dtype=float).reshape(-1)
    fix = np.round((toc - toe) / SECONDS_PER_WEEK)
    toe = toe + np.where(np.isfinite(fix), fix, 0.0) * SECONDS_PER_WEEK
    bad = np.flatnonzero(~np.isfinite(toe) | ~np.isfinite(params["sqrt_a"]))
    if bad.size:
        raise InputError(f"{path}: line {int(lineno[bad[0]]) + 1}: navigation record without toe or sqrt(A)")
    # a blank orbit or clock field would give NaN satellite positions later, far from its cause
    for name in _NAV_ORBIT_PARAMS:
        bad = np.flatnonzero(~np.isfinite(params[name]))
        if bad.size:
            i = int(bad[0])
            raise InputError(f"{path}: line {int(lineno[i]) + 1}: navigation record of {sats[i]} has no value for "
                             f"{name} (a blank field); expected a number in every orbit and clock field")
    # an orbit no satellite can fly betrays a corrupted record (IS-GPS-200 Table 20-III ranges: e < 0.03
    # broadcast, sqrt(A) 2530-8192 sqrt(m)); only the impossible is refused here
    bad = np.flatnonzero(~(params["sqrt_a"] > 0) | ~((params["e"] >= 0) & (params["e"] < 1)))
    if bad.size:
        i = int(bad[0])
        raise InputError(f"{path}: line {int(lineno[i]) + 1}: navigation record of {sats[i]} has sqrt(A) = "
                         f"{float(params['sqrt_a'][i]):g} sqrt(m) and e = {float(params['e'][i]):g}; expected "
                         "sqrt(A) > 0 and 0 <= e < 1 (a corrupted record?)")
    return NavData(path=str(path), sats=np.array(sats, dtype="<U3"), system=rsys, toc=toc, toe=toe,
                   params=params, iono_alpha=alpha, iono_beta=beta, skipped=skipped, header=header)
