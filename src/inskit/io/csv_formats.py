"""The project's CSV formats for IMU data, GNSS fixes and navigation solutions.

Every file has one header line; units are part of the column names
(``gyro_x_deg_s``, ``accel_z_g``, ``lat_deg``).  Degrees and g appear only
here: what the readers return is SI and radians.

Line numbers in messages are those a text editor shows: the header is line
1 when nothing is above it, so data row ``i`` (0-based) is line ``i + 2``
unless blank lines, which the parsers skip, come before it
(:func:`data_line`).  A Parquet file has rows, not lines: its messages say
``row i``, counted from 0 (:func:`at_row`).
"""

from __future__ import annotations

import io
import zlib
from pathlib import Path

import numpy as np

from .. import rotations as rot
from ..errors import InputError
from ..files import require_file, write_csv
from ..types import NAVIGATION_COLUMNS, GnssData, ImuData, NavSolution
from ..units import DEG, DEG_PER_HOUR, G0, MAX_HEIGHT_M, MAX_SPEED_M_S
from ..types import plain_number

AXES = ("x", "y", "z")
GYRO_UNITS = {"rad_s": 1.0, "deg_s": DEG, "deg_h": DEG_PER_HOUR}
ACCEL_UNITS = {"m_s2": 1.0, "g": G0}
DTHETA_UNITS = {"rad": 1.0, "deg": DEG}
DV_UNITS = {"m_s": 1.0}

#: the columns every solution file holds: :data:`inskit.types.NAVIGATION_COLUMNS`, which no extra column may take
SOLUTION_COLUMNS = list(NAVIGATION_COLUMNS)
GNSS_COLUMNS = ["time_s", "lat_deg", "lon_deg", "height_m", "sigma_n_m", "sigma_e_m", "sigma_d_m"]
GNSS_VEL_COLUMNS = ["vn_m_s", "ve_m_s", "vd_m_s", "sigma_vn_m_s", "sigma_ve_m_s", "sigma_vd_m_s"]

# unit plausibility thresholds (see read_imu)
_ACCEL_G_LIKE = 2.0       # median |f| in m/s^2 below this looks like g
_ACCEL_MS2_LIKE = 3.0     # median |f| in g above this looks like m/s^2
_ACCEL_DEAD_M_S2 = 0.3    # median |f| below this under an m_s2 header is neither m/s^2 nor g (which reads ~1)
_ACCEL_DEAD_G = 0.2       # median |f| below this many g under a g header (m/s^2 there reads 9.8) is no accelerometer
_GYRO_RAD_MAX = 10.0      # 99th percentile |w| in rad/s above this looks like deg/s
_GYRO_RAD_MEDIAN = 1.0    # median |w| in rad/s above this looks like deg/s
_IMU_STEP_MAX_S = 1.0     # a median IMU time step above this [s] (below 1 Hz) looks like ms, us or ns
_GYRO_SAMPLE_MAX = 1000.0  # one sample's |w| above this [rad/s] (57,000 deg/s) is beyond any gyro's range
_ACCEL_SAMPLE_MAX_G = 1000.0  # one sample's |f| above this [g] is beyond any navigation accelerometer's range


def read_table(path) -> tuple:
    """Read a comma-separated table with one header line, or a Parquet file;
    gzip and Parquet data are recognised by their content whatever the file
    is called.  (Messages name a CSV file's line, a Parquet file's row:
    :func:`at_row`.)"""
    path = require_file(path)
    from .parquet import is_parquet

    if is_parquet(path):
        from .parquet import parquet_column_names, read_parquet_table

        parquet_column_names(path)  # a column named twice: said so, before pyarrow's 'Multiple matches'
        table = read_parquet_table(path)  # every page's checksum checked: a corrupt file is refused, not misread
        import pyarrow as pa

        from .parquet import narrow_float_message

        for name, col in zip(table.column_names, table.columns):  # a timestamp or text column is no number
            if not (pa.types.is_floating(col.type) or pa.types.is_integer(col.type)):
                raise InputError(f"{path}: column '{name}' is of type {col.type}; expected numbers "
                                 "(float or integer columns, times in seconds)")
            narrow = narrow_float_message(path, name, col.type)
            if narrow:
                raise InputError(narrow)
        df = table.to_pandas()
        if len(df) == 0:
            raise InputError(f"{path}: has columns but no data rows")
        return path, df
    with open(path, "rb") as fh:
        gz = fh.read(2) == b"\x1f\x8b"
    head = _first_line(path)
    if head is not None and head.replace("\t", " ").isprintable():  # a text header (not binary garbage)
        _refuse_header_in_disguise(path, head)
        if "," not in head and any(sep in head for sep in (";", "\t")):  # before pandas' 'Expected 1 fields'
            _refuse_separator(path, head)
        _refuse_repeated_names(path, head.split(","))
    import pandas as pd  # here, not at import: the lean readers and the writers need no pandas

    # only an empty cell is missing: 'nan', 'NA', 'null' stay text, so a message can show what the cell holds
    options = {"skipinitialspace": True, "keep_default_na": False, "na_values": [""]}
    try:
        if not gz and path.suffix.lower() in _PANDAS_COMPRESSIONS:  # another compression, which pandas infers
            df = pd.read_csv(path, compression="infer", **options)
        else:  # plain or gzip: its bytes checked as pandas reads them (a NUL byte, UTF-16)
            with CheckedBytes(path) as stream:
                df = pd.read_csv(stream, compression=None, **options)
    except TextFault as exc:
        raise InputError(str(exc)) from None
    except pd.errors.EmptyDataError:
        raise InputError(f"{path}: the file is empty; expected a header line and data rows") from None
    except pd.errors.ParserError as exc:
        raise InputError(_parser_error_message(path, exc)) from None
    except UnicodeDecodeError:
        raise InputError(undecodable_message(path)) from None
    except GZIP_ERRORS as exc:
        if gz:
            raise InputError(gzip_damage_message(path, exc)) from None
        raise InputError(f"{path}: not a readable CSV file ({str(exc).splitlines()[0]})") from None
    if not isinstance(df.index, pd.RangeIndex):  # rows with more fields than the header names: pandas made the
        # first ones an index and shifted every name onto the next column (time_s held the latitudes)
        fields = len(df.columns) + df.index.nlevels
        raise InputError(f"{path}: {at_row(path, 0)}: has {fields} fields, the header names {len(df.columns)}: a "
                         "name missing from the header (or a comma too many on every row?); each column needs its "
                         "name")
    df.columns = [str(c).strip() for c in df.columns]
    if len(df.columns) == 1 and any(sep in df.columns[0] for sep in (";", "\t")):
        _refuse_separator(path, df.columns[0])
    if len(df) == 0:
        raise InputError(f"{path}: has a header but no data rows")
    # a trailing comma on every line (spreadsheet exports) makes a column of no name and no value: no column
    # of the file, which pandas named 'Unnamed: 19' and a reader of every column then refused as empty
    raw = head.split(",") if head is not None else []
    blank = [c for j, c in enumerate(df.columns) if j < len(raw) and not raw[j].strip() and df[c].isna().all()]
    if blank:
        df = df.drop(columns=blank)
    return path, df


#: file name suffixes of the compressions other than gzip that pandas infers from the name (gzip is told by content)
_PANDAS_COMPRESSIONS = (".bz2", ".xz", ".zip", ".zst", ".tar")


def _parser_error_message(path, exc) -> str:
    """pandas' tokenizer error ('Error tokenizing data. C error: Expected 7
    fields in line 9, saw 8') as a message of ours: the line (pandas counts
    a text editor's lines) and its count of fields against the header's."""
    import re

    text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    m = re.search(r"Expected (\d+) fields in line (\d+), saw (\d+)", text)
    if m:
        want, line, saw = (int(g) for g in m.groups())
        return (f"{path}: line {line}: has {saw} fields, the header names {want}: a comma too many (a decimal "
                "comma, a text with a comma in it, rows of another table?)")
    return f"{path}: not a readable CSV file ({text})"


def data_line(path, row) -> int:
    """The line of data row ``row`` (0-based, as the parsers number the rows)
    of CSV file ``path``, as a text editor numbers it (from 1).

    pandas and pyarrow skip a blank (or whitespace-only) line, before the
    header or between rows, so ``row + 2`` names the line above the right
    one once for every blank line before it.  The file (plain or gzip) is
    read up to that row, for a message only; a quoted cell that spans
    lines (an odd count of ``"`` on a line) continues its row.  A file that
    cannot be read as text gives ``row + 2``.
    """
    row = int(row)
    try:
        with open_text(path) as fh:
            seen = -2  # the header is row -1
            open_quote = False
            for lineno, line in enumerate(fh, start=1):
                if not open_quote:
                    if not line.strip():
                        continue
                    seen += 1
                    if seen == row:
                        return lineno
                if line.count('"') % 2:
                    open_quote = not open_quote
    except Exception:  # noqa: BLE001 (a damaged file: the message keeps the row's plain count)
        pass
    return row + 2


def at_row(path, row) -> str:
    """Where data row ``row`` (0-based) of table file ``path`` is, for a
    message: ``"line N"`` in a CSV file, the line a text editor shows
    (:func:`data_line`), ``"row N"`` in a Parquet file, which has rows, not
    lines, counted from 0 as pyarrow and pandas count them."""
    from .parquet import is_parquet

    return f"row {int(row)}" if is_parquet(path) else f"line {data_line(path, row)}"


def _refuse_header_in_disguise(path, head):
    """A first line that is not the header but looks like one, or stands
    above it, refused saying what it is: a spreadsheet's separator hint
    (``sep=,``, which Excel writes and reads), or a line starting with
    ``#`` (a comment above the header, or the header behind numpy.savetxt's
    comment mark, which it writes unless ``comments=""``): the readers
    found 'missing column(s) time_s; found # time_s, ...' or '... found
    sep=, Unnamed: 1'."""
    shown = head.strip()
    if shown.lower().startswith("sep=") and len(shown) <= 6:
        raise InputError(f"{path}: line 1 is {shown!r}, a spreadsheet's separator hint, not the header: delete that "
                         "line (the column names must be the first line)")
    if shown.startswith("#"):
        raise InputError(f"{path}: line 1 ({shown[:60]!r}) starts with '#', a comment mark, where the header must "
                         "be: the column names alone on the first line (numpy.savetxt writes '# ' before its header "
                         "unless comments=''); delete the '#' (or the comment lines above the header)")


def _refuse_separator(path, header):
    sep = ";" if ";" in header else "tab"
    raise InputError(f"{path}: the header {header!r} is one column: the file seems separated by "
                     f"{sep!r}, not by commas; convert it to comma-separated values")


def _refuse_repeated_names(path, names, where="the header"):
    """A header (``where``: or a Parquet schema) that names a column twice
    is refused: which of the two a reader took would be a guess (pandas
    renamed the second 'name.1', the lean path took the first, pyarrow
    raised 'Multiple matches for FieldRef')."""
    seen = {}
    for j, n in enumerate(n.strip() for n in names):
        if n and n in seen:
            raise InputError(f"{path}: {where} names column '{n}' twice (columns {seen[n] + 1} and {j + 1}); "
                             "each column needs a name of its own")
        seen.setdefault(n, j)


def _first_line_bytes(path):
    """The first line of a file (plain or gzip), its line end kept, at most
    64 KB; None when it cannot be read (the parser then says what is
    wrong)."""
    try:
        with open_bytes(path) as fh:
            return fh.readline(1 << 16)
    except Exception:  # noqa: BLE001 (a damaged file: the parser says what is wrong)
        return None


def _first_line(path):
    """The header line of a CSV file (plain or gzip), decoded, without its
    line end and byte-order mark; None when it cannot be read as text (the
    parser then says what is wrong)."""
    head = _first_line_bytes(path)
    try:
        return None if head is None else head.decode("utf-8-sig").rstrip("\r\n")
    except UnicodeDecodeError:
        return None


def _is_gzip(path) -> bool:
    with open(path, "rb") as fh:
        return fh.read(2) == b"\x1f\x8b"


#: what damaged gzip data raises while it is decompressed: zlib's error (corrupt data), EOFError (cut short),
#: gzip.BadGzipFile (an OSError: a bad header or check sum)
GZIP_ERRORS = (zlib.error, EOFError, OSError)


def gzip_damage_message(path, exc) -> str:
    """The message of a gzip file whose data cannot be decompressed
    (``exc``, one of :data:`GZIP_ERRORS`): cut short, or corrupted."""
    detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    if isinstance(exc, EOFError):
        return (f"{path}: a damaged gzip file: its data ends before the compressed stream does (cut short: copied "
                "or downloaded incompletely, or still being written?)")
    return f"{path}: a damaged gzip file: its data is corrupt ({detail}): a corrupted copy or download?"


class TextFault(Exception):
    """A fault in a text file's bytes (:func:`text_fault`): its message
    is the user's (the caller raises it as an InputError)."""


#: byte-order marks of the text encodings a spreadsheet or a shell may save instead of UTF-8 (UTF-32 before
#: UTF-16: FF FE 00 00 starts with FF FE)
_BOMS = ((b"\xff\xfe\x00\x00", "UTF-32", "FF FE 00 00"), (b"\x00\x00\xfe\xff", "UTF-32", "00 00 FE FF"),
         (b"\xff\xfe", "UTF-16", "FF FE"), (b"\xfe\xff", "UTF-16", "FE FF"))
_SAVE_AS_UTF8 = ("inskit reads UTF-8: save it as UTF-8 (Excel: 'CSV UTF-8'; PowerShell: '| Out-File -Encoding utf8' "
                 "rather than '>')")


def text_fault(path, head: bytes, offset=None, what="comma-separated text") -> str | None:
    """Why a file is no UTF-8 text, from its bytes, or None.

    Parameters
    ----------
    path : Path
        The file (plain or gzip: its decompressed bytes), for the message and
        for the line of a NUL byte.
    head : bytes
        Its first bytes (decompressed), at least its first line when it has
        one.
    offset : int, optional
        Where a NUL byte was found (decompressed bytes from the start), when
        the caller has seen one beyond ``head``.
    what : str
        What the file should hold, for the message.

    Returns
    -------
    str or None
        * UTF-16 or UTF-32 text, told by its byte-order mark (Excel's 'Unicode
          Text', Windows PowerShell's ``>``), or UTF-16 without one (every
          other byte of the first line zero);
        * a NUL byte, which no text holds: not a text file, or one damaged in
          writing (a logger that lost power, a full disk: blocks of zeros).
    """
    for bom, enc, shown in _BOMS:
        if head.startswith(bom):
            return (f"{path}: is {enc} text (it starts with the byte-order mark {shown}), as Excel's 'Unicode Text' "
                    f"and Windows PowerShell's '>' save it; {_SAVE_AS_UTF8}")
    if offset is None:
        offset = head.find(b"\x00")
        if offset < 0:
            return None
    first = head.split(b"\n", 1)[0][:200]
    if len(first) >= 4 and offset < len(first) and any(
            not any(first[k::2]) and all(first[1 - k::2]) for k in (0, 1)):
        return (f"{path}: is UTF-16 text without a byte-order mark (every other byte of its first line is zero); "
                f"{_SAVE_AS_UTF8}")
    return (f"{path}: line {_line_of_offset(path, offset)} holds NUL (zero) bytes, which no text holds: not a text "
            "file, or one damaged in writing (a logger that lost power or a full disk leaves blocks of zeros); "
            f"expected {what}")


def _line_of_offset(path, offset) -> int:
    """The line (from 1) of byte ``offset`` of a file (plain or gzip:
    decompressed bytes), for a message: the line ends before it, plus 1."""
    n, seen = 1, 0
    try:
        with open_bytes(path) as fh:
            while seen < offset:
                block = fh.read(min(1 << 24, offset - seen))
                if not block:
                    break
                n += block.count(b"\n")
                seen += len(block)
    except Exception:  # noqa: BLE001 (a damaged file: the count so far)
        pass
    return n


def undecodable_message(path, what="comma-separated text") -> str:
    """The message of a file with a byte that is no UTF-8 (after a
    UnicodeDecodeError): the line and the byte, found by decoding the file
    (plain or gzip) again, in blocks; a message only."""
    import codecs
    dec = codecs.getincrementaldecoder("utf-8-sig")()
    line = 1
    try:
        with open_bytes(path) as fh:
            while True:
                block = fh.read(1 << 22)
                try:
                    text = dec.decode(block, final=not block)
                except UnicodeDecodeError as exc:
                    line += exc.object[:exc.start].count(b"\n")
                    return (f"{path}: line {line}: byte 0x{exc.object[exc.start]:02x} is not UTF-8 (a binary file, "
                            "or text saved in another encoding such as Latin-1 or Windows-1252); expected UTF-8 "
                            f"{what}: save it as UTF-8")
                line += text.count("\n")
                if not block:
                    break
    except GZIP_ERRORS as exc:
        return gzip_damage_message(path, exc)
    return f"{path}: not UTF-8 text; expected UTF-8 {what} (save it as UTF-8)"


class CheckedBytes(io.RawIOBase):
    """A binary stream over a file (plain or gzip, decompressed) that
    refuses, as it is read, what :func:`text_fault` refuses (a byte-order
    mark of UTF-16 or UTF-32 at its start, a NUL byte anywhere), raising
    :class:`TextFault`.  For a parser that reads the file once anyway
    (pandas): the check costs a ``find`` per block, no second pass.

    pandas' C parser ends a number at a NUL byte and drops the rest of the
    cell: a cell ``1.2547<NUL x 50>6971e-3`` was read as 1.2547 (rad, an
    angle increment a thousand times too large) without a word.
    """

    def __init__(self, path, what="comma-separated text"):
        super().__init__()
        self.path, self.what = Path(path), what
        self._raw = open_bytes(path)
        self._seen = 0
        self._head = b""

    def readable(self):
        return True

    def read(self, size=-1):
        data = self._raw.read(size)
        self._check(data)
        return data

    def readinto(self, b):
        data = self.read(len(b))
        b[:len(data)] = data
        return len(data)

    def _check(self, data):
        if not self._seen:
            self._head = data[:4096]
            fault = text_fault(self.path, data, what=self.what)
        else:
            k = data.find(b"\x00")
            fault = None if k < 0 else text_fault(self.path, self._head, self._seen + k, self.what)
        if fault:
            raise TextFault(fault)
        self._seen += len(data)

    def close(self):
        self._raw.close()
        super().close()


def check_path_argument(path, name="path"):
    """``path`` as a Path when it is a str or path-like, else an InputError
    naming the argument (pathlib's 'expected str, bytes or os.PathLike
    object, not int' names none)."""
    import os

    if not isinstance(path, (str, os.PathLike)):
        raise InputError(f"`{name}` must be a file path (str or Path), got {type(path).__name__} {path!r:.80}")
    return Path(path)


def open_bytes(path):
    """A binary handle on ``path``'s bytes, decompressed when it is gzip
    (recognised by its first bytes, not its name)."""
    if _is_gzip(path):
        import gzip

        return gzip.open(path, "rb")
    return open(path, "rb")


def open_text(path):
    """A text handle on ``path``: gzip recognised by its first bytes (not
    its name), a byte-order mark (Windows editors) dropped, an undecodable
    byte replaced."""
    if _is_gzip(path):
        import gzip

        return gzip.open(path, "rt", encoding="utf-8-sig", errors="replace")
    return open(path, encoding="utf-8-sig", errors="replace")


def _header_names(path):
    """The column names of a CSV file's header line (plain or gzip), or of
    a Parquet file's schema; None for anything else (the caller then reads
    through :func:`read_table`, whose messages name what is wrong)."""
    from .parquet import is_parquet

    path = Path(path)
    if is_parquet(path):
        import pyarrow.parquet as pq

        try:
            names = list(pq.ParquetFile(str(path)).schema_arrow.names)
        except Exception:  # noqa: BLE001 (a damaged file: read_table says what is wrong)
            return None
        _refuse_repeated_names(path, names, "the Parquet schema")  # as a CSV header naming a column twice
        return names
    head = _first_line_bytes(path)
    if head is None or not head.endswith(b"\n"):
        return None
    try:
        names = head.decode("utf-8-sig").rstrip("\r\n").split(",")  # a BOM (Windows editors) is no part of a name
    except UnicodeDecodeError:
        return None
    if ",".join(names).replace("\t", " ").isprintable():  # a text header (not binary garbage)
        _refuse_header_in_disguise(path, ",".join(names))
        _refuse_repeated_names(path, names)
    return names if len(names) > 1 and all(n and n == n.strip() for n in names) else None


#: a CSV up to this size is parsed whole by :func:`lean_columns` (in parallel), a larger one streamed in blocks
WHOLE_CSV_BYTES = 256 << 20


def lean_columns(path, groups):
    """Read float columns with bounded memory, or return None.

    ``groups`` is a list of lists of column names; each group is read into
    one C-contiguous ``(n, len(group))`` float64 array, filled in blocks
    straight from pyarrow's readers (its CSV reader parses on every core
    and rounds correctly; a CSV above :data:`WHOLE_CSV_BYTES` is streamed
    block by block, a Parquet file row group by row group), so the peak is
    the arrays themselves, not a DataFrame and its copies (an 8 h, 200 Hz
    log: 0.32 GB instead of 1.5 GB).

    Returns None when the file is not plain well-formed numbers (an empty
    or text cell, a NaN, a ragged row, a gzip file above an eighth of
    :data:`WHOLE_CSV_BYTES` ...): the caller then reads it
    through :func:`read_table` and :func:`numeric_columns`, whose messages
    name the line and the column.
    """
    import pyarrow as pa

    from .parquet import is_parquet

    path = Path(path)
    want = [c for g in groups for c in g]
    try:
        if is_parquet(path):
            import pyarrow.parquet as pq

            from .parquet import READ_OPTIONS, narrow_float_message

            pf = pq.ParquetFile(str(path), **READ_OPTIONS)
            if any(narrow_float_message(path, c, pf.schema_arrow.field(c).type) for c in want):
                return None  # a float32 time: read_table's message
            n = pf.metadata.num_rows
            batches = pf.iter_batches(batch_size=1 << 18, columns=want)
        else:
            import pyarrow.csv as pcsv

            co = pcsv.ConvertOptions(include_columns=want, column_types={c: pa.float64() for c in want})
            gz = _is_gzip(path)
            if gz and path.stat().st_size > WHOLE_CSV_BYTES // 8:
                return None  # a large gzip file: the pandas path streams it (its length is not known ahead)
            if gz or path.stat().st_size <= WHOLE_CSV_BYTES:
                # parsed whole, on every core: twice as fast as the streaming reader, and the table (about
                # half the file's size) is the only extra memory
                src = pa.input_stream(str(path), compression="gzip") if gz else str(path)
                table = pcsv.read_csv(src, convert_options=co)
                n = table.num_rows
                batches = table.to_batches()
            else:
                n = _count_lines(path) - 1
                ro = pcsv.ReadOptions(block_size=1 << 22)  # 4 MB blocks: ~0.2 GB in flight on two cores
                batches = pcsv.open_csv(str(path), read_options=ro, convert_options=co)
        outs = [np.empty((max(n, 0), len(g))) for g in groups]
        i = 0
        for b in batches:
            m = b.num_rows
            if i + m > n:
                return None
            for g, out in zip(groups, outs):
                for j, c in enumerate(g):
                    col = b.column(c)
                    if col.null_count or not (pa.types.is_floating(col.type) or pa.types.is_integer(col.type)):
                        return None
                    out[i:i + m, j] = _values(col)
            i += m
    except (pa.ArrowException, OSError, KeyError, ValueError) as exc:
        _refuse_corrupt_parquet(path, exc)
        return None
    finally:
        pa.default_memory_pool().release_unused()  # the reader's blocks: back to the system, not held
    if i == 0:
        return None
    outs = [o[:i] for o in outs]
    if not all(np.isfinite(o).all() for o in outs):
        return None
    return outs


def _refuse_corrupt_parquet(path, exc):
    """Raise the :class:`InputError` of a Parquet page that failed its
    checksum (``exc``), which a streaming reader's fallback to the whole
    read would only meet again; anything else is left to that read."""
    from .parquet import damage_message, is_checksum_error

    if is_checksum_error(exc):
        raise InputError(damage_message(path, exc)) from None


def _values(col):
    """A null-free numeric Arrow array's values as a NumPy view of its
    buffer (``to_numpy`` would import pandas, half a second)."""
    import pyarrow as pa

    t = col.type
    kind = "f" if pa.types.is_floating(t) else ("u" if pa.types.is_unsigned_integer(t) else "i")
    size = t.bit_width // 8
    return np.frombuffer(col.buffers()[1], dtype=np.dtype(f"{kind}{size}"), count=len(col), offset=col.offset * size)


def _count_lines(path) -> int:
    """Lines of a file (a last line without its newline counts), in 16 MB
    blocks."""
    n, last = 0, b"\n"
    with open(path, "rb") as fh:
        while True:
            block = fh.read(1 << 24)
            if not block:
                break
            n += block.count(b"\n")
            last = block[-1:]
    return n + (last != b"\n")


class LeanFrame:
    """The columns of a table read by :func:`lean_columns` (all finite
    numbers), with the little of a DataFrame's face the readers use:
    ``columns`` (every name of the header) and ``len``."""

    def __init__(self, names, data: dict):
        self.columns, self.data = list(names), data

    def __len__(self):
        return len(next(iter(self.data.values())))


def read_numeric_table(path, wanted):
    """:func:`read_table` for readers of number columns: the ``wanted``
    columns the header holds, read by :func:`lean_columns` into a
    :class:`LeanFrame` when the file is plain well-formed numbers (no
    pandas), else the DataFrame of :func:`read_table` (whose faults
    :func:`numeric_columns` then names)."""
    names = _header_names(path)
    if names is not None:
        have = [c for c in wanted if c in names]
        got = lean_columns(path, [[c] for c in have]) if have else None
        if got is not None:
            return Path(path), LeanFrame(names, {c: a[:, 0] for c, a in zip(have, got)})
    return read_table(path)


def numeric_columns(path, df, columns):
    """The named columns as a float array; names the line (CSV) or the row
    (Parquet) of a bad value (:func:`at_row`)."""
    if isinstance(df, LeanFrame):
        return np.column_stack([df.data[c] for c in columns])
    import pandas as pd

    out = np.empty((len(df), len(columns)))
    for j, c in enumerate(columns):
        col = pd.to_numeric(df[c], errors="coerce").to_numpy(dtype=float)
        bad = ~np.isfinite(col)
        if bad.any():
            i = int(np.argmax(bad))
            raw = df[c].iloc[i]
            shown = plain_number(raw) if isinstance(raw, (int, float, np.number)) else repr(raw)
            what = f"has {shown}"
            where = at_row(path, i)
            if isinstance(raw, float) and np.isnan(raw):  # an empty CSV cell; a null or a NaN in Parquet
                from .parquet import is_parquet

                what = "is empty (null) or NaN" if is_parquet(path) else "is empty"
                short = None if is_parquet(path) else _short_row(path, int(where.split()[1]))
                if short:  # pandas fills the fields a short row lacks with NaN: not an empty cell
                    where += f": has {short[0]} fields, the header names {short[1]}"
                    what = "is missing"
            cut = cut_short_note(path) if i == len(df) - 1 else ""
            raise InputError(f"{path}: {where}: column '{c}' {what}; expected a finite number{cut}")
        out[:, j] = col
    return out


def _short_row(path, line):
    """``(fields, header fields)`` when line ``line`` of CSV file ``path``
    holds fewer fields than its header line, else None: for a message only
    (the file is read again up to that line)."""
    import csv

    try:
        with open_text(path) as fh:
            header = None
            for k, text in enumerate(fh, start=1):
                if header is None and text.strip():
                    header = len(next(csv.reader([text])))
                if k == line:
                    n = len(next(csv.reader([text]))) if text.strip() else 0
                    return (n, header) if header and n < header else None
    except Exception:  # noqa: BLE001 (a damaged file: the plain message)
        pass
    return None


def cut_short_note(path) -> str:
    """``"; ..."`` saying the file seems cut short when its last line has
    no line end (a file still being written, or copied incompletely),
    for the message of a fault in its last line; ``""`` otherwise (a
    Parquet file, a file ending in a line end).  Reads to the end of a
    gzip file: for a message only."""
    from .parquet import is_parquet

    try:
        if is_parquet(path):
            return ""
        if _is_gzip(path):
            last = b""
            with open_bytes(path) as fh:
                while block := fh.read(1 << 24):
                    last = block[-1:]
        else:
            with open(path, "rb") as fh:
                fh.seek(0, 2)
                if fh.tell() == 0:
                    return ""
                fh.seek(-1, 2)
                last = fh.read(1)
    except Exception:  # noqa: BLE001 (a damaged file: its message says so)
        return ""
    if not last or last in b"\r\n":
        return ""
    return ("; it is the last line and has no line end: the file seems cut short (still being written, or copied "
            "incompletely?)")


def require_columns(path, df, columns, hint=""):
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise InputError(
            f"{path}: missing column(s) {', '.join(missing)}{hint}; found {', '.join(df.columns)}"
        )


#: seconds in a GPS week: a time column of seconds of week that falls from its last hour to the first hour
#: of the next week is said to restart there (:func:`check_time_column`)
WEEK_ROLLOVER_S = 604800.0


def check_time_column(path, t, column="time_s"):
    d = np.diff(t)
    bad = d <= 0
    if bad.any():
        i = int(np.argmax(bad)) + 1
        if d[i - 1] == 0:
            raise InputError(f"{path}: {at_row(path, i)}: duplicate timestamp {column}={float(t[i])!r} (same as "
                             f"{at_row(path, i - 1)})")
        week = WEEK_ROLLOVER_S
        rollover = (t[i - 1] > week - 3600.0) and (t[i - 1] <= week) and (0.0 <= t[i] < 3600.0)
        raise InputError(
            f"{path}: {at_row(path, i)}: {column}={float(t[i])!r} goes back in time from "
            f"{at_row(path, i - 1)} ({float(t[i - 1])!r}); "
            "timestamps must strictly increase"
            + ("; GPS seconds of week that restart at a week boundary? continue them past 604800 s" if rollover
               else "")
        )


def check_imu_time(path, t, column="time_s", check_units=True):
    """The time column of an IMU log, after its rows are final: at least two
    rows (the initial epoch and one interval: a single row holds no motion
    to integrate), and with ``check_units`` a median step of at most
    :data:`_IMU_STEP_MAX_S` (1 s).

    A rate log whose times are in milliseconds, microseconds or nanoseconds
    has plausible rates and specific forces (they do not depend on the time
    unit), so only its steps give it away: 10 ms written as ms is a "10 s"
    step, an IMU at 0.1 Hz.  Read as seconds such a log is 1000 times
    longer: an Allan deviation sqrt(1000) times too noisy, a static interval
    of days, a mechanization that leaves the Earth.

    Parameters
    ----------
    path : Path
        For the message.
    t : (n,) ndarray
        Times [s as read], strictly increasing (:func:`check_time_column`).
    column : str
        The time column's name, for the message.
    check_units : bool
        Also the step test (``check_units=False`` / ``--no-unit-check``
        keeps a log sampled slower than 1 Hz).
    """
    if len(t) < 2:
        raise InputError(f"{path}: holds {len(t)} data row(s); an IMU log needs at least two (the initial epoch and "
                         "one interval to integrate)")
    dt = float(np.median(np.diff(t)))
    if check_units and dt > _IMU_STEP_MAX_S:
        raise InputError(
            f"{path}: column '{column}': the median time step is {dt:.4g} s (an IMU sampled at {1.0 / dt:.3g} Hz): "
            f"is {column} in milliseconds, microseconds or nanoseconds? it must be seconds (or pass "
            "check_units=False / --no-unit-check for a log sampled slower than 1 Hz)"
        )


#: the IMU column families of each sensor: (prefix, units) of its rates and of its increments
_IMU_FAMILIES = {"rotation": (("gyro", GYRO_UNITS), ("dtheta", DTHETA_UNITS)),
                 "specific force": (("accel", ACCEL_UNITS), ("dv", DV_UNITS))}


def refuse_imu_column_clash(path, names):
    """Refuse a header (``names``) that gives one sensor's motion twice: in
    two units (``gyro_x_rad_s`` and ``gyro_x_deg_s``), or as rates and as
    increments (``gyro_*`` and ``dtheta_*``, ``accel_*`` and ``dv_*``).
    The reader would read one and ignore the other without a word (which
    one depended on the path it took), though they may disagree; the
    message names the clashing columns, and the user says which one is
    meant by removing the others."""
    names = set(names)
    clashes = []
    for sensor, families in _IMU_FAMILIES.items():
        found = []  # the columns of each (prefix, unit) family the header holds
        for prefix, units in families:
            for u in units:
                cols = [f"{prefix}_{a}_{u}" for a in AXES if f"{prefix}_{a}_{u}" in names]
                if cols:
                    found.append(cols)
        if len(found) > 1:
            clashes.append(f"the {sensor} is given by " + " and by ".join(", ".join(c) for c in found))
    if clashes:
        raise InputError(f"{path}: columns that give the same measurement twice: {'; '.join(clashes)}; which one "
                         "is meant is not guessed (they may disagree): keep one set of columns, one unit, rates "
                         "(gyro_*, accel_*) or increments (dtheta_*, dv_*) (docs/formats.md)")


def _find_triplet(df, prefix, units):
    """Unit of the first complete x/y/z column triplet ``prefix_<axis>_<unit>``."""
    for u in units:
        if all(f"{prefix}_{a}_{u}" in df.columns for a in AXES):
            return u
    return None


#: what to do with a row of a rate log that repeats the previous row exactly (:func:`repeated_rows`)
REPEATED_ROWS_MODES = ("keep", "drop")


def repeated_rows(path, t, values, mode="keep", info=None):
    """The rows of a rate log that repeat the previous row in every sensor
    channel, kept or dropped.

    A MEMS sensor's noise makes two consecutive samples that agree in all
    six channels to the last digit practically impossible; such a row is
    the logger reading one sample twice (on drive_0708 every one of its
    1138 repeats follows a short interval, 8 or 9 ms of a nominal 10).
    Kept, the repeat is integrated as a new sample over its short interval;
    dropped, the next real sample covers the whole span, which is what a
    sample averaged over the preceding interval means.

    Parameters
    ----------
    path : Path
        For the message.
    t : (n,) ndarray
        Times.
    values : (n, k) ndarray
        The sensor channels as read (before any unit or axis change).
    mode : {"keep", "drop"}
    info : dict, optional
        Filled with ``repeated_rows`` (the count), ``repeated_rows_fraction``
        and ``repeated_rows_dropped``.

    Returns
    -------
    keep : (n,) bool ndarray or None
        The rows to keep (None: all of them).
    """
    _check_repeated_mode(mode)
    rep = np.zeros(len(t), bool)
    if len(t) > 1:
        rep[1:] = np.all(values[1:] == values[:-1], axis=1)
    n = int(rep.sum())
    if info is not None:
        info.update(repeated_rows=n, repeated_rows_fraction=n / max(len(t) - 1, 1),
                    repeated_rows_dropped=bool(mode == "drop" and n))
        if n:
            info.update(_longest_repeat_run(path, t, rep))
    if mode == "drop" and n:
        if len(t) - n < 2:
            raise InputError(f"{path}: {n} of {len(t)} rows repeat the previous one: fewer than two samples remain")
        return ~rep
    return None


def _longest_repeat_run(path, t, rep) -> dict:
    """The longest run of consecutive repeated rows (``rep``: the row
    repeats the one before it): ``repeated_rows_longest_run`` (rows),
    ``..._s`` (from the sample repeated to the last repeat [s], on the
    file's times), ``..._at`` (the place of its first repeat:
    :func:`at_row`) and ``..._time_s`` (that row's time).  A logger that
    reads one sample twice repeats it once (drive_0708, walk_0827: every run
    is one row); a longer run is the sensor's output frozen."""
    edges = np.flatnonzero(np.diff(np.r_[0, rep.astype(np.int8), 0]))
    starts, ends = edges[::2], edges[1::2]  # each run: rows starts[i] .. ends[i] - 1
    i = int(np.argmax(ends - starts))
    a, b = int(starts[i]), int(ends[i])
    return {"repeated_rows_longest_run": b - a, "repeated_rows_longest_run_s": float(t[b - 1] - t[a - 1]),
            "repeated_rows_longest_run_at": at_row(path, a), "repeated_rows_longest_run_time_s": float(t[a])}


def _check_repeated_mode(mode):
    if mode not in REPEATED_ROWS_MODES:
        raise InputError(f"repeated_rows must be one of {', '.join(map(repr, REPEATED_ROWS_MODES))}, got {mode!r}")


def _increments_keep_repeated_rows(path, mode, time_smoothing=1):
    """Increment files take only ``repeated_rows = "keep"`` and their time
    tags as logged."""
    if mode != "keep":
        raise InputError(f"{path}: repeated_rows = {mode!r} applies to rate files; this one holds increments "
                         "(a repeated increment is not a re-read sample of a rate)")
    if time_smoothing != 1:
        raise InputError(f"{path}: time_smoothing_samples = {time_smoothing} applies to rate files, whose time tags "
                         "set each sample's interval; this one holds increments, already integrated over the "
                         "sensor's own intervals: use 1")


def read_imu(path, *, check_units=True, sampled="instant", first_row="initial", repeated="keep",
             time_smoothing=1, info=None) -> ImuData:
    """Read an IMU CSV file of the inskit format (``docs/formats.md``).

    Columns: ``time_s`` and either rates ``gyro_{x,y,z}_{rad_s|deg_s|deg_h}``
    with ``accel_{x,y,z}_{m_s2|g}``, or increments
    ``dtheta_{x,y,z}_{rad|deg}`` with ``dv_{x,y,z}_m_s`` (over the interval
    that ends at the row's time).  Body axes forward-right-down.

    :func:`inskit.io.read_imu` reads this format and the others inskit
    knows, recognised by their header.

    Parameters
    ----------
    path : str or Path
    check_units : bool
        Refuse magnitudes that betray a wrong unit: a median specific force
        below 2 m/s^2 in a column said to be m/s^2 (it looks like g), above 3
        g in one said to be g or m/s^2; a gyro said to be in rad/s whose 99th
        percentile exceeds 10 rad/s or median exceeds 1 rad/s (it looks like
        deg/s); one sample beyond any sensor's range (1000 rad/s, 1000 g: a
        corrupt row), naming its line.
        Turn off for unusual data (free fall, spinning bodies).
    sampled : {"instant", "average"}
        How rates were sampled (see :meth:`ImuData.from_rates`).
    first_row : {"initial", "increment", "discard"}
        Increment files only: what their first row is (:func:`first_row_rule`).
        ``"initial"``: the initial epoch, whose increments must be zero (a
        first row holding increments is refused: the file seems to lack its
        initial row and would lose its first increment); ``"increment"``: a
        real increment, and an initial epoch one median interval earlier is
        prepended; ``"discard"``: the initial epoch, whatever it holds is
        dropped (set to zero).
    repeated : {"keep", "drop"}
        Rate files only: a row repeating the previous one in all six
        channels (:func:`repeated_rows`) kept as a sample or dropped.
    time_smoothing : int
        Rate files only: 1, or the odd number of rows over which the time
        tags are smoothed after the repeated rows are handled (a logger's
        poll jitter and millisecond counter:
        :func:`inskit.io.time_tags.smooth_time_tags`).
    info : dict, optional
        Filled by :func:`repeated_rows` and the smoothing (rate files:
        :func:`inskit.io.time_tags.smooth_time_tags`, its check against the
        jitter included).

    Returns
    -------
    ImuData
        Row 0 is the initial epoch (zero increments).
    """
    if first_row not in FIRST_ROW_MODES:
        raise InputError(f"`first_row` must be one of {', '.join(map(repr, FIRST_ROW_MODES))}, got {first_row!r}")
    if sampled not in SAMPLED_MODES:  # checked whatever the file holds (increment files do not use it)
        raise InputError(f"`sampled` must be one of {', '.join(map(repr, SAMPLED_MODES))}, got {sampled!r}")
    _check_repeated_mode(repeated)
    from .time_tags import check_smoothing_samples, smooth_time_tags

    time_smoothing = check_smoothing_samples(time_smoothing)
    lean = _read_imu_lean(path, check_units, first_row)
    if lean is not None:
        _increments_keep_repeated_rows(path, repeated, time_smoothing)
        return lean
    path, df = read_table(path)
    require_columns(path, df, ["time_s"], f" (the inskit IMU format; {OTHER_IMU_FORMATS_HINT})")
    refuse_imu_column_clash(path, df.columns)
    t = numeric_columns(path, df, ["time_s"])[:, 0]
    check_time_column(path, t)
    gu, au = _find_triplet(df, "gyro", GYRO_UNITS), _find_triplet(df, "accel", ACCEL_UNITS)
    du, vu = _find_triplet(df, "dtheta", DTHETA_UNITS), _find_triplet(df, "dv", DV_UNITS)
    if gu and au:
        gcols = [f"gyro_{a}_{gu}" for a in AXES]
        acols = [f"accel_{a}_{au}" for a in AXES]
        w = numeric_columns(path, df, gcols)
        f = numeric_columns(path, df, acols)
        keep = repeated_rows(path, t, np.hstack([w, f]), repeated, info)
        rows = None
        if keep is not None:
            t, w, f = t[keep], w[keep], f[keep]
            rows = np.flatnonzero(keep)  # the file's row of each sample kept, for the messages
        t = smooth_time_tags(path, t, time_smoothing, info=info)
        w = w * GYRO_UNITS[gu]
        f = f * ACCEL_UNITS[au]
        if check_units:
            check_imu_units(path, w, f, gcols[0], acols[0], gu, au, rows)
        check_imu_time(path, t, check_units=check_units)
        if first_row != "initial":
            raise InputError(f"{path}: first_row={first_row!r} applies to increment files (dtheta/dv columns); this "
                             "file holds rates, which have no first increment to lose")
        return ImuData.from_rates(t, w, f, sampled=sampled)
    if du and vu:
        _increments_keep_repeated_rows(path, repeated, time_smoothing)
        tcols = [f"dtheta_{a}_{du}" for a in AXES]
        vcols = [f"dv_{a}_{vu}" for a in AXES]
        raw = numeric_columns(path, df, tcols + vcols)
        t, raw = first_row_rule(path, t, raw, tcols + vcols, first_row)
        dth = raw[:, :3] * DTHETA_UNITS[du]
        dv = raw[:, 3:] * DV_UNITS[vu]
        if check_units and len(t) > 1:
            dt = np.diff(t)
            with np.errstate(over="ignore"):  # a corrupt row's inf is refused by name (_check_imu_samples)
                w, f = dth[1:] / dt[:, None], dv[1:] / dt[:, None]
            check_imu_units(path, w, f, tcols[0], vcols[0],
                            "rad_s" if du == "rad" else "deg_s", "m_s2", rows=1 if first_row != "increment" else 0)
        check_imu_time(path, t, check_units=check_units)
        return ImuData(t, dth, dv)
    raise InputError(
        f"{path}: no complete set of IMU columns: expected gyro_{{x,y,z}}_{{rad_s|deg_s|deg_h}} with "
        f"accel_{{x,y,z}}_{{m_s2|g}}, or dtheta_{{x,y,z}}_{{rad|deg}} with dv_{{x,y,z}}_m_s "
        f"({OTHER_IMU_FORMATS_HINT}); found {', '.join(df.columns)}"
    )


#: what the first row of an increment file is (:func:`first_row_rule`)
FIRST_ROW_MODES = ("initial", "increment", "discard")
#: how a rate file's rates were sampled (:meth:`inskit.types.ImuData.from_rates`)
SAMPLED_MODES = ("instant", "average")
#: a first row whose increments are all at most this fraction of the median increment of the other rows is
#: empty (the initial epoch); exactly zero when there are no other rows or they are all zero
FIRST_ROW_EMPTY = 1e-9
#: the IMU formats besides this one, for the messages of a file this reader cannot read
OTHER_IMU_FORMATS_HINT = ("the other IMU format inskit reads is the rtklibexplorer log: gps_week, gps_sow_s, "
                          "acc_{x,y,z}_g, gyro_{x,y,z}_dps, read by inskit.io.read_imu or format = "
                          "\"rtklibexplorer\"")


def first_row_empty(inc) -> bool:
    """Does the first row of an increment table hold nothing?

    ``inc`` is ``(n, 6)``: three angle then three velocity increments (any
    unit).  Empty when every angle component is at most
    :data:`FIRST_ROW_EMPTY` times the median angle-increment norm of the
    other rows, and likewise the velocity components: a real increment is
    of the size of its neighbours, never a billionth of it.
    """
    inc = np.asarray(inc, float)
    return _first_row_empty_parts(inc[:, :3], inc[:, 3:])


def _first_row_empty_parts(dth, dv, norms=None) -> bool:
    """:func:`first_row_empty` of the angle and the velocity increments
    given apart (no (n, 6) copy of a long log); ``norms``: their rows'
    norms from row 1 on, when the caller has them already."""
    if len(dth) < 2:
        return not (np.any(dth[0]) or np.any(dv[0]))
    for j, part in enumerate((dth, dv)):
        typical = float(np.median(_norm(part[1:]) if norms is None else norms[j]))
        if np.max(np.abs(part[0])) > FIRST_ROW_EMPTY * typical:
            return False
    return True


def _read_imu_lean(path, check_units, first_row):
    """:func:`read_imu` of a well-formed increment file (plain CSV or
    Parquet, first row the initial epoch or discarded) by
    :func:`lean_columns`, the increments read straight into their arrays;
    None for anything else (rates, another first-row rule, a file with a
    fault), which :func:`read_imu` then reads and judges itself."""
    names = _header_names(path)
    if names is None or "time_s" not in names or first_row == "increment":
        return None
    refuse_imu_column_clash(path, names)
    header = LeanFrame(names, {})
    du, vu = _find_triplet(header, "dtheta", DTHETA_UNITS), _find_triplet(header, "dv", DV_UNITS)
    if not (du and vu):
        return None
    tcols = [f"dtheta_{a}_{du}" for a in AXES]
    vcols = [f"dv_{a}_{vu}" for a in AXES]
    got = lean_columns(path, [["time_s"], tcols, vcols])
    if got is None:
        return None
    path = Path(path)
    t, dth, dv = got[0][:, 0], got[1], got[2]
    check_time_column(path, t)
    # the rows' norms from row 1 on (file units; the unit factors are positive): made once for both rules
    norms = [_norm_rows32(dth[1:]), _norm_rows32(dv[1:])] if len(t) > 1 else None
    # the first-row rule (these two rules change row 0 only): its message when row 0 holds increments
    if first_row == "initial" and not _first_row_empty_parts(dth, dv, norms):
        first_row_rule(path, t[:1], np.hstack([dth[:1], dv[:1]]), tcols + vcols, "initial")
    if first_row == "discard":
        dth[0], dv[0] = 0.0, 0.0
    if DTHETA_UNITS[du] != 1.0:
        dth *= DTHETA_UNITS[du]
    if DV_UNITS[vu] != 1.0:
        dv *= DV_UNITS[vu]
    if check_units and norms is not None:
        for a in range(0, len(t) - 1, NORM_BLOCK_ROWS):  # the rates' norms, block by block (no (n,) temporaries)
            inv_dt = 1.0 / np.diff(t[a:a + NORM_BLOCK_ROWS + 1])
            with np.errstate(over="ignore"):  # a corrupt row's inf is refused by name (_check_imu_samples)
                norms[0][a:a + NORM_BLOCK_ROWS] *= DTHETA_UNITS[du] * inv_dt
                norms[1][a:a + NORM_BLOCK_ROWS] *= DV_UNITS[vu] * inv_dt
        check_units_norms(path, norms[0], norms[1], tcols[0], vcols[0], "rad_s" if du == "rad" else "deg_s",
                          "m_s2", rows=1)
    check_imu_time(path, t, check_units=check_units)
    return ImuData(t, dth, dv)


def first_row_rule(path, t, inc, columns, first_row="initial"):
    """Apply the first-row convention of increment files (``docs/formats.md``).

    Row ``k`` holds the increments over ``(t[k-1], t[k]]``; the first row
    has no earlier time, so it is the initial epoch of the file and its
    increments are not used.  A file written without that row would silently
    lose its first increment, so what the first row is must be known:

    * ``"initial"``: it is the initial epoch and holds zeros
      (:func:`first_row_empty`); increments there are refused with the file,
      the line and the values.
    * ``"increment"``: it is a real increment; an initial epoch one median
      interval earlier, with zero increments, is prepended.  A zero first
      row is refused (it is an initial epoch, and reading it as an interval
      of zero specific force would be free fall).
    * ``"discard"``: it is the initial epoch, whatever it holds (the first
      packet of many sensors covers an unknown interval); its increments are
      set to zero.

    Parameters
    ----------
    path : Path
        The file, for the messages.
    t : (n,) ndarray
        Times [s], strictly increasing.
    inc : (n, 6) ndarray
        Angle and velocity increments as the file holds them (file units).
    columns : sequence of str
        The six column names, for the messages.
    first_row : {"initial", "increment", "discard"}

    Returns
    -------
    (t, inc) : the times and increments, row 0 the initial epoch (zeros)
    """
    empty = first_row_empty(inc)
    if first_row == "initial":
        if not empty:
            held = ", ".join(f"{c}={plain_number(v)}" for c, v in zip(columns, inc[0]) if v != 0)
            raise InputError(
                f"{path}: {at_row(path, 0)} (the first data row) holds increments ({held}); in an increment "
                "file the first row is the initial epoch and its increments are not used (docs/formats.md), so this "
                "file seems to lack that row and would lose its first increment.  Say what the row is: "
                "first_row=\"increment\" (its increments are real: an initial epoch one median interval earlier is "
                "prepended) or first_row=\"discard\" (it is the initial epoch: its increments are dropped); [imu] "
                "first_row in a navigate config, --first-row on the command line"
            )
        return t, inc
    if first_row == "discard":
        inc = inc.copy()
        inc[0] = 0.0
        return t, inc
    if empty:
        raise InputError(
            f"{path}: {at_row(path, 0)} (the first data row) holds zero increments: it is the initial "
            "epoch, not an increment; read the file with first_row=\"initial\" (the default) rather than \"increment\""
        )
    if len(t) < 2:
        raise InputError(f"{path}: first_row=\"increment\" needs at least two rows (the initial epoch is put one "
                         "median interval before the first)")
    dt = float(np.median(np.diff(t)))
    return np.r_[t[0] - dt, t], np.vstack([np.zeros((1, inc.shape[1])), inc])


def _norm(x):
    """Row norms of an (n, 3) array that do not overflow below 1.8e308 and
    stay finite above it: an inf norm would make NaN percentiles, which pass
    every rule of :func:`check_imu_units`."""
    with np.errstate(over="ignore", invalid="ignore"):
        n = np.hypot(np.hypot(x[:, 0], x[:, 1]), x[:, 2])
    return np.minimum(n, np.finfo(float).max)


#: rows per block of :func:`_norm_rows32` and the rates' norms of :func:`_read_imu_lean`
NORM_BLOCK_ROWS = 1 << 18


def _norm_rows32(x) -> np.ndarray:
    """:func:`_norm` of an (n, 3) array as float32, made block by block: the
    unit checks compare medians and percentiles with thresholds a factor of
    two or more apart, which single precision holds to 1e-7, and a long log's
    norms then take 4 bytes per row with no (n,) float64 temporaries (8 h at
    200 Hz: 46 MB for both instead of 0.2 GB)."""
    out = np.empty(len(x), np.float32)
    for a in range(0, len(x), NORM_BLOCK_ROWS):
        out[a:a + NORM_BLOCK_ROWS] = np.minimum(_norm(x[a:a + NORM_BLOCK_ROWS]), _F32_MAX)  # finite, as _norm's
    return out


_F32_MAX = float(np.finfo(np.float32).max)


def check_imu_units(path, w, f, gcol, acol, gunit, aunit, rows=None):
    """Refuse magnitudes that betray a wrong unit (see :func:`read_imu`).

    ``w`` [rad/s] and ``f`` [m/s^2] are the rates as converted from the
    header's units ``gunit`` and ``aunit``.

    What can be told, and what cannot
    ---------------------------------
    * Accelerometers: a median ``|f|`` below 2 m/s^2 under an m/s^2 header
      (g read as m/s^2), above 3 g under a g header.
    * deg/s under a rad/s header, when the log moves: turn rates of more than
      10 rad/s (570 deg/s) are beyond vehicles and people, so a 99th
      percentile above 10 rad/s, a median above 1 rad/s, or a block of 50
      consecutive samples whose median exceeds 10 rad/s (a turn faster
      than 10 deg/s held for 75 samples or more, written in deg/s) give the
      unit away.
    * Accelerometers: a median ``|f|`` above 3 g under an m/s^2 header
      (ft/s^2, cm/s^2 or mm/s^2 read as m/s^2; under an increment header,
      dv in cm/s, mm/s or ft/s).
    * One sample beyond any sensor's range: ``|w|`` above 1000 rad/s
      (57,000 deg/s) or ``|f|`` above 1000 g, whatever the unit: a corrupt
      row (a spike, a shifted or merged field).  A lone such row moves
      neither the median nor the 99th percentile, and integrated it turned
      the attitude by whole radians, or overflowed to a non-finite state
      ('the innovation is not finite'), naming no row.  ``rows`` gives the
      file row of each sample (``None``: the index; an int: the index plus
      it; an array: looked up), for the message.
    * deg/s under a rad/s header on a *static* log cannot be told here: the
      values are 57.3 times the true rates, i.e. 57.3 times the Earth rate
      plus bias, about 0.004 rad/s for a good gyro.  That is also the bias of
      many a calibrated MEMS gyro in true rad/s (0.1 to 0.5 deg/s), and the
      reader knows neither the gyro grade nor the latitude.  Only a MEMS gyro
      whose bias exceeds 1 deg/s trips the median rule.  ``inskit align``,
      which knows the latitude, recognises the Earth rate scaled by 57.3 in
      a static log of a gyro good enough to see it.
    """
    check_units_norms(path, _norm(w), _norm(f), gcol, acol, gunit, aunit, rows)


def check_units_norms(path, wn, f_norm, gcol, acol, gunit, aunit, rows=None):
    """:func:`check_imu_units` from the rows' norms (``|w|`` [rad/s] and
    ``|f|`` [m/s^2]): a reader that has the increments need not make the
    rates.  The rules of the whole log first (they name the unit), then
    the samples one by one."""
    _check_units_of_log(path, wn, f_norm, gcol, acol, gunit, aunit, rows)
    _check_accel_above_gravity(path, f_norm, acol, aunit)
    _check_imu_samples(path, wn, f_norm, gcol, acol, rows)


def _check_accel_above_gravity(path, f_norm, acol, aunit):
    """A whole log's median specific force above 3 g under an m/s^2 header
    (ft/s^2, cm/s^2, mm/s^2; dv in cm/s, mm/s or ft/s), judged after the
    other rules of the log, whose messages (deg/s ...) it does not take
    over."""
    fn = float(np.median(f_norm))
    if aunit == "m_s2" and fn / G0 > _ACCEL_MS2_LIKE:
        other = "dv in cm/s, mm/s or ft/s (it must be m/s)" if acol.startswith("dv_") else \
            "values in ft/s^2, cm/s^2 or mm/s^2 (they must be m/s^2)"
        raise InputError(
            f"{path}: column '{acol}': the median specific force is {fn:.4g} m/s^2 ({fn / G0:.3g} g), far above "
            f"gravity for a whole log: {other}? (or pass check_units=False / --no-unit-check)"
        )


def _check_units_of_log(path, wn, f_norm, gcol, acol, gunit, aunit, rows=None):
    """The rules of :func:`check_units_norms` over the whole log."""
    fn = float(np.median(f_norm))
    dead = fn == 0.0 or (not acol.startswith("dv_") and (aunit == "m_s2" and fn < _ACCEL_DEAD_M_S2
                                                          or aunit == "g" and fn < _ACCEL_DEAD_G * G0))
    if dead:  # neither g nor m/s^2: 'looks like values in g' (or nothing, under a g header) misled
        cols = acol.replace("_x_", "_{x,y,z}_", 1)
        raise InputError(
            f"{path}: {cols}: the median specific force is {(fn if aunit == 'm_s2' else fn / G0):.4g} "
            f"{'m/s^2' if aunit == 'm_s2' else 'g'}, far below gravity (1 g, 9.81 m/s^2) in any unit: the "
            "accelerometer columns hold zeros or nearly (a dead or disconnected sensor, another column?) (or pass "
            "check_units=False / --no-unit-check for a log in free fall)"
        )
    if aunit in ("m_s2",) and fn < _ACCEL_G_LIKE:
        if acol.startswith("dv_"):  # increments have no g unit: the step they are divided by is the suspect
            raise InputError(
                f"{path}: column '{acol}': the median specific force (dv over the time step) is {fn:.4g} m/s^2, "
                "far below gravity: is time_s in milliseconds (it must be seconds), or dv not in m/s? (or pass "
                "check_units=False / --no-unit-check)"
            )
        raise InputError(
            f"{path}: column '{acol}': the median specific force is {fn:.4g} m/s^2, which looks like "
            "values in g; rename the columns accel_*_g (or pass check_units=False / --no-unit-check)"
        )
    if aunit == "g" and fn / G0 > _ACCEL_MS2_LIKE:
        raise InputError(
            f"{path}: column '{acol}': the median specific force is {fn / G0:.4g} g, which looks like "
            "values in m/s^2; rename the columns accel_*_m_s2 (or pass check_units=False / --no-unit-check)"
        )
    if gunit != "rad_s":
        return
    hint = (f"rename the columns {'dtheta_*_deg' if gcol.startswith('dtheta_') else 'gyro_*_deg_s'} (or pass "
            "check_units=False / --no-unit-check); note that deg/s under "
            "a rad/s header is caught only when the log turns: a static log cannot show it")
    if np.percentile(wn, 99) > _GYRO_RAD_MAX or np.median(wn) > _GYRO_RAD_MEDIAN:
        raise InputError(
            f"{path}: column '{gcol}': angular rates reach {np.percentile(wn, 99):.4g} rad/s "
            f"(median {np.median(wn):.3g}), which looks like values in deg/s; {hint}"
        )
    k = 50  # samples per block of the sustained-turn test
    nb = len(wn) // k
    if nb:
        med = np.median(wn[: nb * k].reshape(nb, k), axis=1)
        if (med > _GYRO_RAD_MAX).any():
            i = int(np.argmax(med > _GYRO_RAD_MAX))
            raise InputError(
                f"{path}: column '{gcol}': {k} consecutive samples (near {at_row(path, _file_row(rows, i * k))}) "
                f"turn at a median {float(med[i]):.1f} rad/s ({float(med[i]) / DEG:.0f} deg/s), more than a vehicle or "
                f"a person can; it looks like values in deg/s; {hint}"
            )


def _file_row(rows, i) -> int:
    """The file row of sample ``i`` (``rows``: see :func:`check_imu_units`)."""
    if rows is None:
        return int(i)
    if isinstance(rows, (int, np.integer)):
        return int(i) + int(rows)
    return int(rows[i])


def _check_imu_samples(path, wn, f_norm, gcol, acol, rows=None):
    """Refuse the first sample whose rate norm ``wn`` [rad/s] or specific
    force norm ``f_norm`` [m/s^2] is beyond any sensor's range
    (:data:`_GYRO_SAMPLE_MAX`, :data:`_ACCEL_SAMPLE_MAX_G`), naming its
    line or row (``rows``: see :func:`check_imu_units`)."""
    for norms, lim, col, what, unit, scale in (
            (wn, _GYRO_SAMPLE_MAX, gcol, "an angular rate", "rad/s", 1.0),
            (f_norm, _ACCEL_SAMPLE_MAX_G * G0, acol, "a specific force", "g", G0)):
        bad = np.flatnonzero(np.asarray(norms) > lim)
        if not len(bad):
            continue
        i = int(bad[0])
        v = float(norms[i]) / scale
        size = f"{v:.4g} {unit}" if np.isfinite(v) and v < 1e30 else f"over 1e30 {unit}"
        more = f" ({len(bad) - 1} more row(s) do)" if len(bad) > 1 else ""
        cols = col.replace("_x_", "_{x,y,z}_", 1)
        raise InputError(
            f"{path}: {at_row(path, _file_row(rows, i))}: {cols} give {what} of {size}{more}, beyond any "
            f"sensor's range ({lim / scale:g} {unit}); expected a sample of the log: a corrupt row, or another "
            "unit? (or pass check_units=False / --no-unit-check)"
        )


def write_imu(path, imu: ImuData, *, overwrite=False):
    """Write increments in the IMU format (``dtheta_*_rad``, ``dv_*_m_s``):
    Parquet when ``path`` ends in ``.parquet`` (float64, exact), else CSV with
    17 significant digits.

    Row 0 is written as the format's initial epoch, with zero increments
    (:func:`first_row_rule`): whatever ``imu`` holds there is over an
    interval before its first time, which no reader or integrator uses
    (``ImuData.from_rates`` puts a rate times an assumed step there).
    """
    path = check_writable(path, overwrite)
    data = {"time_s": imu.time}
    for i, a in enumerate(AXES):
        data[f"dtheta_{a}_rad"] = np.r_[0.0, imu.dtheta_b[1:, i]]
    for i, a in enumerate(AXES):
        data[f"dv_{a}_m_s"] = np.r_[0.0, imu.dv_b[1:, i]]
    if path.suffix == ".parquet":
        from .parquet import write_parquet

        return write_parquet(path, data)
    return write_csv(path, data, "%.17g")


def check_writable(path, overwrite):
    path = Path(path)
    if path.exists() and not overwrite:
        raise InputError(f"{path}: already exists; refusing to overwrite it (use --force / overwrite=True)")
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


def read_gnss(path) -> GnssData:
    """Read GNSS fixes.

    Columns: ``time_s, lat_deg, lon_deg, height_m, sigma_n_m, sigma_e_m,
    sigma_d_m`` and optionally ``vn_m_s, ve_m_s, vd_m_s, sigma_vn_m_s,
    sigma_ve_m_s, sigma_vd_m_s``.  Sigmas are 1-sigma and must be > 0.
    Fixes with velocity whose positions move far more slowly than it says
    (latitude and longitude in radians under the ``_deg`` headers, a time
    column in milliseconds) are refused (:func:`check_solution_time_unit`).
    """
    path, df = read_numeric_table(path, GNSS_COLUMNS + GNSS_VEL_COLUMNS)
    require_columns(path, df, GNSS_COLUMNS)
    a = numeric_columns(path, df, GNSS_COLUMNS)
    check_time_column(path, a[:, 0])
    _check_latlon(path, a[:, 1], a[:, 2])
    check_ranges(path, {"height_m": a[:, 3]})
    check_sigmas(path, a[:, 4:7], GNSS_COLUMNS[4:7])
    v = sv = None
    have = [c in df.columns for c in GNSS_VEL_COLUMNS]
    if any(have):
        require_columns(path, df, GNSS_VEL_COLUMNS, " (velocity needs all six velocity columns)")
        b = numeric_columns(path, df, GNSS_VEL_COLUMNS)
        check_ranges(path, dict(zip(GNSS_VEL_COLUMNS[:3], b[:, :3].T)))
        check_sigmas(path, b[:, 3:], GNSS_VEL_COLUMNS[3:], "m/s")
        v, sv = b[:, :3], b[:, 3:]
    lla = np.column_stack([a[:, 1] * DEG, a[:, 2] * DEG, a[:, 3]])
    gnss = GnssData(a[:, 0], lla, a[:, 4:7], v, sv)
    if v is not None:  # the fixes' own motion against their velocity: radians under _deg, time in ms
        check_solution_time_unit(path, gnss)
        check_gnss_velocity(path, gnss)
    return gnss


#: :func:`check_gnss_velocity` judges pairs of consecutive fixes at most this far apart [s] whose positions move
#: faster than this [m/s] and than this many times their own noise (sqrt(2) sigma_h / dt), and needs this many
GNSS_VELOCITY_CHECK_MAX_DT_S = 2.0
GNSS_VELOCITY_CHECK_MIN_SPEED_M_S = 2.0
GNSS_VELOCITY_CHECK_NOISE_FACTOR = 5.0
GNSS_VELOCITY_CHECK_MIN_PAIRS = 20
#: the median ratio of the velocity columns' horizontal speed to the positions' own must lie within this band
#: (1.00 on simulated fixes and drive_0708's .pos), the median angle between them within this [deg] (2 deg and 0.3)
GNSS_VELOCITY_RATIO_BAND = (0.67, 1.5)
GNSS_VELOCITY_MAX_ANGLE_DEG = 30.0


def check_gnss_velocity(path, gnss: GnssData, names=("vn_m_s", "ve_m_s")) -> None:
    """Refuse fixes whose velocity columns do not describe how their
    positions move: over pairs of consecutive fixes whose positions clearly
    move (:data:`GNSS_VELOCITY_CHECK_MIN_SPEED_M_S`, well above their
    noise), the median ratio of the velocity's horizontal speed to the
    positions' outside :data:`GNSS_VELOCITY_RATIO_BAND` (zeros written by a
    receiver that had none, km/h, knots) or the median angle between the two
    beyond :data:`GNSS_VELOCITY_MAX_ANGLE_DEG` (vn and ve swapped, a sign:
    east-north-up for north-east-down).  The start-up takes heading and
    motion from the velocity of fixes coarser than 0.1 m, ``use_velocity``
    or not: zeros said 'the GNSS track never moves' of a drive, a swap or
    a sign turned the IMU's axes by 90 or 180 deg.  Silent with fewer than
    :data:`GNSS_VELOCITY_CHECK_MIN_PAIRS` such pairs (fixes too sparse,
    too noisy, or at rest).  ``names``: the file's north and east velocity
    columns, for the message (an RTKLIB ``.pos``: ``vn(m/s)``, ``ve(m/s)``)."""
    t = gnss.time
    if len(t) < 3 or gnss.v_n is None:
        return
    k, dt, dn, de = _row_pairs(t, gnss.lla)
    pn, pe = dn / dt, de / dt
    ps = np.hypot(pn, pe)
    sig = gnss.sigma_ned
    sig_h = np.maximum(np.hypot(sig[k, 0], sig[k, 1]), np.hypot(sig[k + 1, 0], sig[k + 1, 1])) / np.sqrt(2.0)
    m = ((dt <= GNSS_VELOCITY_CHECK_MAX_DT_S) & (ps > GNSS_VELOCITY_CHECK_MIN_SPEED_M_S)
         & (ps > GNSS_VELOCITY_CHECK_NOISE_FACTOR * np.sqrt(2.0) * sig_h / dt) & np.isfinite(ps))
    if m.sum() < GNSS_VELOCITY_CHECK_MIN_PAIRS:
        return
    v = 0.5 * (gnss.v_n[k, :2] + gnss.v_n[k + 1, :2])[m]
    vs = np.hypot(v[:, 0], v[:, 1])
    pn, pe, ps = pn[m], pe[m], ps[m]
    ratio = float(np.median(vs / ps))
    lo, hi = GNSS_VELOCITY_RATIO_BAND
    what = f"(median over {int(m.sum())} pairs of consecutive fixes whose positions move)"
    if not lo <= ratio <= hi:
        hint = ("zeros: a receiver that gave no velocity? leave the six velocity columns out" if ratio < 0.05 else
                "km/h?" if abs(ratio - 3.6) < 0.4 else "knots?" if abs(ratio - 1.944) < 0.2 else
                "mph?" if abs(ratio - 2.237) < 0.2 else "another unit or column?")
        raise InputError(f"{path}: its velocity columns say {ratio:.3g} times the speed its positions move at "
                         f"{what}; expected {lo:g}..{hi:g} (m/s, the same motion): {hint}")
    ok = vs > 0
    cos = (v[ok, 0] * pn[ok] + v[ok, 1] * pe[ok]) / (vs[ok] * ps[ok])
    angle = float(np.degrees(np.median(np.arccos(np.clip(cos, -1.0, 1.0)))))
    if angle > GNSS_VELOCITY_MAX_ANGLE_DEG:
        raise InputError(f"{path}: its velocity points {angle:.0f} deg away from where its positions move {what}; "
                         f"expected within {GNSS_VELOCITY_MAX_ANGLE_DEG:g} deg: {names[0]} and {names[1]} swapped, or a sign "
                         "(east-north-up for north-east-down)?")


def _row_pairs(t, lla):
    """``(k, dt, dn, de)``: at most :data:`TIME_UNIT_MAX_PAIRS` pairs of
    consecutive rows ``k, k + 1`` spread over a file, their time step [s]
    and the north and east displacement between them [m] (the chord on the
    WGS84 radii of curvature at the mid-point; the longitude the short way
    round)."""
    from ..earth import principal_radii

    n = len(t)
    k = np.unique(np.linspace(0, n - 2, min(n - 1, TIME_UNIT_MAX_PAIRS)).astype(np.int64))
    lat = lla[:, 0]
    mid = 0.5 * (lat[k] + lat[k + 1])
    rn, re = principal_radii(mid, 0.5 * (lla[k, 2] + lla[k + 1, 2]))
    dn = (lat[k + 1] - lat[k]) * rn
    de = np.angle(np.exp(1j * (lla[k + 1, 1] - lla[k, 1]))) * np.cos(mid) * re
    return k, t[k + 1] - t[k], dn, de


def _check_latlon(path, lat, lon):
    bad = np.abs(lat) > 90
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"{path}: {at_row(path, i)}: lat_deg={float(lat[i])!r} is outside [-90, 90] degrees")
    bad = (lon < -180) | (lon > 360)
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"{path}: {at_row(path, i)}: lon_deg={float(lon[i])!r} is outside [-180, 360] degrees")


#: the largest attitude angle [deg] a solution file may hold: a full turn (config_files.ANGLE_LIMIT_DEG)
SOLUTION_ANGLE_LIMIT_DEG = 360.0


#: the plausibility limit of each height, velocity and attitude column of a solution or GNSS file:
#: column -> (largest magnitude, what it is) (:func:`check_ranges`)
RANGE_LIMITS = {"height_m": (MAX_HEIGHT_M, f"+-{MAX_HEIGHT_M / 1000:g} km of the ellipsoid (a height in metres)")}
RANGE_LIMITS.update({c: (MAX_SPEED_M_S, f"+-{MAX_SPEED_M_S:g} m/s (faster than the Earth's escape speed)")
                     for c in ("vn_m_s", "ve_m_s", "vd_m_s")})
RANGE_LIMITS.update({c: (SOLUTION_ANGLE_LIMIT_DEG, f"+-{SOLUTION_ANGLE_LIMIT_DEG:g} degrees (no attitude needs more "
                                                   "than a full turn)") for c in ("roll_deg", "pitch_deg", "yaw_deg")})


def check_ranges(path, cols, *, kinds=None, where=None):
    """Refuse a value of a height, velocity or attitude column beyond its
    :data:`RANGE_LIMITS`, naming the file, the line (CSV) or row (Parquet)
    and the column: beyond them the number is another unit or column (a
    height in mm, a pressure; a yaw of 1e6), which the scoring would wrap
    or square into nonsense (a height of 1e300: an RMS of inf).

    Parameters
    ----------
    path : Path
        For the message.
    cols : dict of str -> (n,) ndarray
        Columns by name; those with no limit (time, latitude, sigmas ...)
        are not looked at, and a limited column the file lacks is not
        asked for.
    kinds : dict of str -> str, optional
        The :data:`RANGE_LIMITS` name of a column named otherwise (a .pos
        file's ``"height(m)"`` is ``"height_m"``; its ``"vu(m/s)"``,
        the negative of a down velocity, ``"vd_m_s"``).
    where : callable, optional
        Row index -> the place a message names (default :func:`at_row`:
        ``line k`` of a CSV, ``row i`` of a Parquet file).
    """
    kinds = kinds or {}
    for c, v in cols.items():
        limit = RANGE_LIMITS.get(kinds.get(c, c))
        if limit is None:
            continue
        lim, what = limit
        bad = np.abs(v) > lim
        if bad.any():
            i = int(np.argmax(bad))
            at = where(i) if where is not None else at_row(path, i)
            raise InputError(f"{path}: {at}: {c}={plain_number(v[i])} is beyond {what}; another unit or column?")


def _check_height_attitude(path, cols):
    """:func:`check_ranges` of a solution's columns: height, velocity and
    attitude (checked in that order)."""
    check_ranges(path, {c: cols[c] for c in RANGE_LIMITS})


#: the largest 1-sigma a reader takes, by the kind of quantity [m, m/s, deg]: beyond these a number says no
#: measurement and is another unit or column; squared in the filter, 1e300 overflowed to inf and 1e30 left the
#: covariance without its positiveness ('the filter diverged'), naming neither the file nor the column
SIGMA_LIMITS = {"m": (MAX_HEIGHT_M, "100 km (no fix nor height is known that loosely)"),
                "m/s": (MAX_SPEED_M_S, f"{MAX_SPEED_M_S:g} m/s (faster than the Earth's escape speed)"),
                "deg": (360.0, "360 degrees (a full turn)")}
#: the smallest 1-sigma a reader takes (any kind): below it no sensor measures, and the filter's covariance
#: cannot follow (fixes of sigma 1e-10 m, exact as they were, ended 'covariance lost positiveness at t = 1.000 s:
#: the filter diverged'; 1e-8 m still ran); ``inskit simulate`` writes 1 mm at least
SIGMA_MIN = 1e-6


def check_sigmas(path, a, columns, kind="m", where=None):
    """Refuse a sigma that is not > 0, below :data:`SIGMA_MIN`, or beyond
    :data:`SIGMA_LIMITS` of its ``kind`` (``"m"``, ``"m/s"``, ``"deg"``),
    naming the file, the line (``where``: row index -> the place, default
    :func:`at_row`) and the column."""
    at = where if where is not None else (lambda i: at_row(path, i))
    bad = a <= 0
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise InputError(f"{path}: {at(i)}: column '{columns[j]}' is {float(a[i, j])!r}; "
                         "sigmas must be > 0")
    bad = a < SIGMA_MIN
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise InputError(f"{path}: {at(i)}: column '{columns[j]}' is {plain_number(a[i, j])}; a sigma below "
                         f"{SIGMA_MIN:g} {kind} is no measurement (no sensor is that exact, and the filter's covariance "
                         "cannot follow it): another unit or column?")
    lim, what = SIGMA_LIMITS[kind]
    bad = ~(a <= lim)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise InputError(f"{path}: {at(i)}: column '{columns[j]}' is {plain_number(a[i, j])}; a sigma beyond {what} "
                         "is no measurement: another unit or column?")


def write_gnss(path, gnss: GnssData, *, overwrite=False):
    path = check_writable(path, overwrite)
    cols = {
        "time_s": gnss.time,
        "lat_deg": gnss.lla[:, 0] / DEG,
        "lon_deg": -((-gnss.lla[:, 1] + np.pi) % (2.0 * np.pi) - np.pi) / DEG,  # wrapped into (-180, 180]
        "height_m": gnss.lla[:, 2],
        "sigma_n_m": gnss.sigma_ned[:, 0],
        "sigma_e_m": gnss.sigma_ned[:, 1],
        "sigma_d_m": gnss.sigma_ned[:, 2],
    }
    if gnss.has_velocity:
        for i, c in enumerate(GNSS_VEL_COLUMNS[:3]):
            cols[c] = gnss.v_n[:, i]
        for i, c in enumerate(GNSS_VEL_COLUMNS[3:]):
            cols[c] = gnss.sigma_v_ned[:, i]
    if path.suffix == ".parquet":
        from .parquet import write_parquet

        return write_parquet(path, cols)
    return write_csv(path, cols, "%.15g")


def read_solution(path, *, until_s=None, ranges=True) -> NavSolution:
    """Read a navigation solution or truth file (:func:`_read_solution`),
    its time column checked against its own motion
    (:func:`check_solution_time_unit`)."""
    sol = _read_solution(path, until_s=until_s, ranges=ranges)
    check_solution_time_unit(path, sol)
    return sol


#: moving rows (horizontal speed above TIME_UNIT_MIN_SPEED_M_S) the time-unit check of a solution file needs, and
#: the most consecutive pairs it looks at (evenly spread)
TIME_UNIT_MIN_ROWS = 20
TIME_UNIT_MAX_PAIRS = 2000
TIME_UNIT_MIN_SPEED_M_S = 1.0
#: a median ratio of the velocity columns' speed to the positions' own speed above this is refused: 1 in a
#: consistent file (a few per cent more on coarse rows through turns); 1000 for a time column in ms.  The other
#: way (positions faster) is not judged: hand-made files often pair a track with any velocity
TIME_UNIT_RATIO_MAX = 20.0


def check_solution_time_unit(path, sol: NavSolution | GnssData) -> None:
    """Refuse a solution, truth or GNSS file (with velocity) whose positions move more slowly than
    its velocity columns say, by more than :data:`TIME_UNIT_RATIO_MAX`
    (median over up to :data:`TIME_UNIT_MAX_PAIRS` consecutive
    rows where the file moves faster than :data:`TIME_UNIT_MIN_SPEED_M_S`):
    a time column in milliseconds reads 1000 times too long (a truth in ms
    scored 2181 m of 'outage error' against a solution fitting its fixes to
    0.5 m, with no warning), and radians under the ``_deg`` headers move
    57.3 times too little.  A file that stands still, or has fewer than
    :data:`TIME_UNIT_MIN_ROWS` moving rows, is not checked.  The distance
    between rows: the chord on the WGS84 radii of curvature."""
    t = sol.time
    if len(t) < 3:
        return
    k, dt, dn, de = _row_pairs(t, sol.lla)
    pos_speed = np.hypot(dn, de) / dt
    v = 0.5 * (np.hypot(sol.v_n[k, 0], sol.v_n[k, 1]) + np.hypot(sol.v_n[k + 1, 0], sol.v_n[k + 1, 1]))
    m = (v > TIME_UNIT_MIN_SPEED_M_S) & (dt > 0) & np.isfinite(pos_speed)
    if m.sum() < TIME_UNIT_MIN_ROWS or not np.median(pos_speed[m]) > 0.0:  # positions held: no time to judge
        return
    ratio = float(np.median(v[m] / np.maximum(pos_speed[m], 1e-300)))
    if ratio > TIME_UNIT_RATIO_MAX:
        if abs(ratio / np.degrees(1.0) - 1.0) < 0.1:
            why = "latitude and longitude hold radians under the _deg headers (57.3 times too small)"
        elif abs(ratio / 1000.0 - 1.0) < 0.1:
            why = "the time column holds milliseconds, not seconds (1000 times too long)"
        else:
            why = "time_s is not in seconds, or lat_deg and lon_deg are not in degrees"
        raise InputError(f"{path}: its positions move {ratio:.4g} times slower than its velocity columns say (median "
                         f"over {int(m.sum())} moving rows): {why}")


def _read_solution(path, *, until_s=None, ranges=True) -> NavSolution:
    """Read a navigation solution or truth file: CSV (``.csv``, gzip-compressed
    ``.csv.gz``) or Parquet (``.parquet``, as ``inskit navigate`` writes at
    full rate), told apart by content (Parquet's ``PAR1`` magic), not name.

    Columns: ``time_s, lat_deg, lon_deg, height_m, vn_m_s, ve_m_s, vd_m_s,
    roll_deg, pitch_deg, yaw_deg``; any further numeric columns are kept in
    ``NavSolution.extra`` under their own names.  A bad value is named by its
    line (CSV, header = line 1) or its row (Parquet, first data row = row 0).

    With ``until_s`` [s] the file is read only up to its first row after
    that time, two rows at least (in blocks of about a megabyte; the whole file when no
    row reaches it, or when the head is not plain numbers, so that the
    messages are those of a whole read): the initial state of a run
    (``mechanize --init-from``) needs the rows around its start, not an
    hour of truth.

    ``ranges=False`` skips the plausibility limits of height, velocity and
    attitude (:func:`_check_height_attitude`), not the checks of the file's
    form, time or latitude: for a solution inskit wrote itself, whose
    filter may have diverged beyond them (the report of such a run must
    still show it), never for a file whose units are in doubt.
    """
    from .parquet import is_parquet

    p = check_path_argument(path)
    if until_s is not None:
        head = _read_solution_head(p, float(until_s), ranges)
        if head is not None:
            return head
    if is_parquet(p):
        return _read_solution_parquet(p, ranges)
    if p.suffix == ".parquet" and p.is_file():
        raise InputError(f"{p}: named .parquet but not a Parquet file (no PAR1 magic at its start)")
    lean = _read_solution_lean(p, ranges)
    if lean is not None:
        return lean
    path, df = read_table(path)
    require_columns(path, df, SOLUTION_COLUMNS)
    a = numeric_columns(path, df, SOLUTION_COLUMNS)
    check_time_column(path, a[:, 0])
    _check_latlon(path, a[:, 1], a[:, 2])
    if ranges:
        _check_height_attitude(path, dict(zip(SOLUTION_COLUMNS, a.T)))
    extra = {}
    for c in df.columns:
        if c not in SOLUTION_COLUMNS:
            extra[c] = numeric_columns(path, df, [c])[:, 0]
    lla = np.column_stack([a[:, 1] * DEG, a[:, 2] * DEG, a[:, 3]])
    rpy = a[:, 7:10] * DEG
    return NavSolution(a[:, 0], lla, a[:, 4:7], rot.quat_from_euler(rpy), extra)


def _read_solution_lean(path, ranges=True) -> NavSolution | None:
    """:func:`read_solution` of a plain, well-formed CSV (every cell a
    finite number) by :func:`lean_columns`, the columns parsed by pyarrow on
    every core straight into one array; None for anything else, which the
    pandas path then reads and judges (its messages name the line)."""
    names = _header_names(path)
    if names is None or not set(SOLUTION_COLUMNS) <= set(names) or len(set(names)) != len(names):
        return None
    got = lean_columns(path, [names])
    if got is None:
        return None
    a = got[0]
    cols = {c: a[:, j] for j, c in enumerate(names)}
    check_time_column(path, cols["time_s"])
    _check_latlon(path, cols["lat_deg"], cols["lon_deg"])
    if ranges:
        _check_height_attitude(path, cols)
    return _solution_of_columns({c: np.ascontiguousarray(v) for c, v in cols.items()})


def _read_solution_head(path, until_s, ranges=True) -> NavSolution | None:
    """The rows of a solution file up to the first after ``until_s`` (two at
    least) (:func:`read_solution`), by pyarrow's streaming readers; None
    when the head is not plain finite numbers with the solution columns, or
    no row passes ``until_s`` (the caller then reads the whole file)."""
    import pyarrow as pa

    from .parquet import is_parquet

    try:
        if is_parquet(path):
            import pyarrow.parquet as pq

            from .parquet import READ_OPTIONS, narrow_float_message, parquet_column_names

            parquet_column_names(path)  # a column named twice: refused, not a KeyError below
            pf = pq.ParquetFile(str(path), **READ_OPTIONS)
            if any(narrow_float_message(path, f.name, f.type) for f in pf.schema_arrow):
                return None  # a float32 time or latitude: the whole read's message
            batches = pf.iter_batches(batch_size=1 << 14)
        else:
            import pyarrow.csv as pcsv

            names = _header_names(path)
            if names is None or not set(SOLUTION_COLUMNS) <= set(names) or len(set(names)) != len(names):
                return None
            co = pcsv.ConvertOptions(column_types={c: pa.float64() for c in names})
            src = pa.input_stream(str(path), compression="gzip") if _is_gzip(path) else str(path)
            batches = pcsv.open_csv(src, read_options=pcsv.ReadOptions(block_size=1 << 20), convert_options=co)
        got, reached = [], False
        for b in batches:
            got.append(b)
            tcol = b.column("time_s")
            if len(tcol) and (pa.types.is_floating(tcol.type) or pa.types.is_integer(tcol.type)) \
                    and tcol.null_count == 0 and float(_values(tcol).max()) > until_s \
                    and sum(len(x) for x in got) >= 2:
                reached = True
                break
    except (pa.ArrowException, OSError, KeyError, ValueError) as exc:
        _refuse_corrupt_parquet(path, exc)
        return None
    if not reached:
        return None
    cols = {}
    for c in got[0].schema.names:
        parts = [b.column(c) for b in got]
        if any(x.null_count or not (pa.types.is_floating(x.type) or pa.types.is_integer(x.type)) for x in parts):
            return None
        cols[c] = np.concatenate([_values(x).astype(float) for x in parts])
    if not set(SOLUTION_COLUMNS) <= set(cols) or not all(np.isfinite(v).all() for v in cols.values()):
        return None
    # the rows up to the first after until_s (two at least: an interpolation's pair), checked as a whole file is
    t = cols["time_s"]
    if t[0] > until_s:
        return None  # before the file: the whole read, whose span the caller's message then names
    stop = max(int(np.argmax(t > until_s)) + 1, 2)
    cols = {c: np.ascontiguousarray(v[:stop]) for c, v in cols.items()}
    check_time_column(path, cols["time_s"])
    _check_latlon(path, cols["lat_deg"], cols["lon_deg"])
    if ranges:
        _check_height_attitude(path, cols)
    return _solution_of_columns(cols)


def _solution_of_columns(cols) -> NavSolution:
    """The :class:`NavSolution` of checked solution columns (file units:
    degrees), the columns beyond :data:`SOLUTION_COLUMNS` in ``extra``."""
    lla = np.column_stack([cols["lat_deg"] * DEG, cols["lon_deg"] * DEG, cols["height_m"]])
    v_n = np.column_stack([cols["vn_m_s"], cols["ve_m_s"], cols["vd_m_s"]])
    rpy = np.column_stack([cols["roll_deg"], cols["pitch_deg"], cols["yaw_deg"]]) * DEG
    extra = {c: v for c, v in cols.items() if c not in SOLUTION_COLUMNS}
    return NavSolution(cols["time_s"], lla, v_n, rot.quat_from_euler(rpy), extra)


def _read_solution_parquet(path, ranges=True) -> NavSolution:
    """:func:`read_solution` of a Parquet file (the same checks, by row)."""
    from .parquet import read_parquet_columns

    cols, _ = read_parquet_columns(path)
    missing = [c for c in SOLUTION_COLUMNS if c not in cols]
    if missing:
        raise InputError(f"{path}: missing column(s) {', '.join(missing)}; found {', '.join(cols)}")
    n = len(cols["time_s"])
    if n == 0:
        raise InputError(f"{path}: has columns but no rows")
    for c, v in cols.items():
        bad = ~np.isfinite(v)
        if bad.any():
            i = int(np.argmax(bad))
            what = "is empty (null) or NaN" if np.isnan(v[i]) else f"holds {plain_number(v[i])}"
            raise InputError(f"{path}: row {i}: column '{c}' {what}; expected a finite number")
    t = cols["time_s"]
    d = np.diff(t)
    if (d <= 0).any():
        i = int(np.argmax(d <= 0)) + 1
        raise InputError(f"{path}: row {i}: time_s={float(t[i])!r} does not increase from row {i - 1} "
                         f"({float(t[i - 1])!r}); timestamps must strictly increase")
    for c, lim in (("lat_deg", (-90.0, 90.0)), ("lon_deg", (-180.0, 360.0))):
        bad = (cols[c] < lim[0]) | (cols[c] > lim[1])
        if bad.any():
            i = int(np.argmax(bad))
            raise InputError(f"{path}: row {i}: {c}={float(cols[c][i])!r} is outside [{lim[0]:g}, {lim[1]:g}] "
                             "degrees")
    if ranges:
        _check_height_attitude(path, cols)
    return _solution_of_columns(cols)


def write_solution(path, sol: NavSolution, *, overwrite=False, rate_hz=None, columns=("all",), metadata=None):
    """Write a navigation solution; ``extra`` columns follow the standard ones.

    The format follows the name: ``.parquet`` (typed float64 columns, units in
    the schema metadata, :func:`inskit.io.parquet.write_parquet`), else CSV
    (``.csv``, gzip for ``.csv.gz``), written by a vectorised writer with 15
    significant digits (:func:`inskit.io.parquet.write_csv_fast`).

    Parameters
    ----------
    path : str or Path
    sol : NavSolution
    overwrite : bool
    rate_hz : float, optional
        Keep one row per ``1 / rate_hz`` seconds (plus the first and the last
        row, :func:`inskit.io.parquet.decimation_index`); default every row.
    columns : str or sequence of str
        ``"all"``, ``"navigation"``, ``"navigation+sigma"``, ``"sigma"``,
        ``"estimates"`` and column names (:func:`inskit.io.parquet.select_columns`).
    metadata : dict, optional
        Parquet only: run keys stored in the schema metadata.

    Refuses to write a NaN (a solution with NaN is a bug upstream).

    Returns
    -------
    Path
    """
    from .parquet import prepare, write_csv_fast, write_parquet

    if not isinstance(sol, NavSolution):
        raise InputError(f"`sol` must be a NavSolution, got {type(sol).__name__}")
    path = check_writable(check_path_argument(path), overwrite)
    cols = prepare(sol, path, rate_hz=rate_hz, columns=columns)
    if path.suffix == ".parquet":
        return write_parquet(path, cols, metadata)
    return write_csv_fast(path, cols)


def read_speed(path):
    """Read an odometer / wheel-speed log: columns ``time_s, speed_m_s``
    (speed along the vehicle's forward axis, >= 0 when driving forward;
    negative values mean reversing and are allowed).

    Returns
    -------
    (time, speed) : two (n,) float arrays
    """
    path, df = read_table(path)
    require_columns(path, df, ["time_s", "speed_m_s"], " (an odometer log: time_s, speed_m_s)")
    a = numeric_columns(path, df, ["time_s", "speed_m_s"])
    check_time_column(path, a[:, 0])
    if (np.abs(a[:, 1]) > 150.0).any():
        i = int(np.argmax(np.abs(a[:, 1]) > 150.0))
        raise InputError(f"{path}: {at_row(path, i)}: column 'speed_m_s' holds {plain_number(a[i, 1])}, "
                         f"{'above' if a[i, 1] > 0 else 'below'} {'' if a[i, 1] > 0 else '-'}150 m/s: km/h or "
                         "another unit? expected metres per second")
    return a[:, 0].copy(), a[:, 1].copy()


SPEED_COURSE_COLUMNS = ["time_s", "speed_m_s", "course_deg", "sigma_speed_m_s", "sigma_course_deg"]


def read_speed_course(path):
    """Read GNSS speed over ground and course over ground (NMEA RMC/VTG,
    phone logs): columns ``time_s, speed_m_s, course_deg, sigma_speed_m_s,
    sigma_course_deg`` (course clockwise from true north).

    Returns
    -------
    (time, speed, course_rad, sigma_speed, sigma_course_rad) : five (n,) arrays
    """
    path, df = read_table(path)
    require_columns(path, df, SPEED_COURSE_COLUMNS, " (GNSS speed and course)")
    a = numeric_columns(path, df, SPEED_COURSE_COLUMNS)
    check_time_column(path, a[:, 0])
    if (a[:, 1] < 0).any():
        i = int(np.argmax(a[:, 1] < 0))
        raise InputError(f"{path}: {at_row(path, i)}: column 'speed_m_s' is {plain_number(a[i, 1])}; a "
                         "speed over ground is >= 0 (the direction is in course_deg)")
    big = ~(a[:, 1] <= MAX_SPEED_M_S)
    if big.any():
        i = int(np.argmax(big))
        raise InputError(f"{path}: {at_row(path, i)}: column 'speed_m_s' is {plain_number(a[i, 1])}; expected a "
                         f"speed over ground up to {MAX_SPEED_M_S:g} m/s (faster than the Earth's escape speed): "
                         "another unit or column?")
    big = np.abs(a[:, 2]) > 360.0
    if big.any():
        i = int(np.argmax(big))
        raise InputError(f"{path}: {at_row(path, i)}: column 'course_deg' is {plain_number(a[i, 2])}; expected "
                         "degrees clockwise from north, within +-360: another unit or column?")
    check_sigmas(path, a[:, 3:4], SPEED_COURSE_COLUMNS[3:4], "m/s")
    check_sigmas(path, a[:, 4:5], SPEED_COURSE_COLUMNS[4:5], "deg")
    return a[:, 0].copy(), a[:, 1].copy(), np.radians(a[:, 2]), a[:, 3].copy(), np.radians(a[:, 4])


#: heights beyond this many metres from the ellipsoid are taken as a wrong unit or column [m]
HEIGHT_LIMIT_M = MAX_HEIGHT_M


def read_height(path):
    """Read a height log (a barometer's altitude, a known height profile):
    columns ``time_s, height_m`` and optionally ``sigma_m`` (the 1-sigma of
    each reading, > 0).

    Returns
    -------
    (time, height, sigma) : two (n,) float arrays and an (n,) array or
    ``None`` when the file has no ``sigma_m`` column.

    Raises
    ------
    InputError
        Missing columns, a cell that is not a finite number, time not
        strictly increasing, a height beyond 100 km (a pressure in Pa or
        another column?), a sigma not > 0; naming the file and line.
    """
    path, df = read_table(path)
    require_columns(path, df, ["time_s", "height_m"], " (a height log: time_s, height_m and optionally sigma_m)")
    cols = ["time_s", "height_m"] + (["sigma_m"] if "sigma_m" in df.columns else [])
    a = numeric_columns(path, df, cols)
    check_time_column(path, a[:, 0])
    big = np.abs(a[:, 1]) > HEIGHT_LIMIT_M
    if big.any():
        i = int(np.argmax(big))
        raise InputError(f"{path}: {at_row(path, i)}: column 'height_m' holds {plain_number(a[i, 1])}, "
                         "beyond 100 km: a pressure or another unit? expected a height in metres")
    sigma = None
    if len(cols) == 3:
        check_sigmas(path, a[:, 2:3], ["sigma_m"])
        sigma = a[:, 2].copy()
    return a[:, 0].copy(), a[:, 1].copy(), sigma
