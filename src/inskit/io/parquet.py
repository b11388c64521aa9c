"""Navigation solutions as Parquet (every epoch, typed) and as fast CSV (at a
chosen rate): the column set, the decimation, both writers and the Parquet
reader.

One column grammar for both formats: the names of ``docs/formats.md``
(``time_s, lat_deg, lon_deg, height_m, vn_m_s, ..., yaw_deg`` and the named
sigma and estimate columns), the unit in the name's suffix.  A Parquet file
also carries each column's unit in its field metadata (``unit``) and, in the
schema metadata under ``inskit``, a JSON object with the units, the inskit
version and the run's own keys (config name, which solution).  Every column is
float64 (time too: float64 seconds).

Writers go through :func:`inskit.files.atomic_write`: a file is whole or
absent.  pyarrow is imported only by the functions that need it, so
``import inskit.io`` stays cheap.

References
----------
Apache Parquet format specification (file layout: magic ``PAR1`` at both
ends, footer with the schema and its key-value metadata).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from ..errors import ConfigError, InputError
from ..files import CSV_DIGITS, CSV_EXPONENT_BELOW, format_column, round_significant, write_csv_fast  # noqa: F401 (re-exported)
from ..files import arrow_array, atomic_write, require_file
from ..types import NAVIGATION_COLUMNS, NavSolution  # the navigation columns, always written (the readers need them)

#: the first four bytes (and the last four) of every Parquet file
PARQUET_MAGIC = b"PAR1"

#: column groups of ``[output] columns`` (besides column names)
COLUMN_GROUPS = ("all", "navigation", "navigation+sigma", "sigma", "estimates")

#: name suffix -> unit (longest suffix wins); a name with none of them is dimensionless ("1")
SUFFIX_UNITS = {"_m_s2": "m/s^2", "_rad_s": "rad/s", "_deg_s": "deg/s", "_m_s": "m/s", "_deg": "deg",
                "_rad": "rad", "_hz": "Hz", "_m": "m", "_s": "s"}



def column_unit(name: str) -> str:
    """Unit of a column from its name's suffix: ``"m/s"`` for ``vn_m_s``,
    ``"rad/s"`` for ``bg_x_rad_s``, ``"1"`` for ``sg_x`` (dimensionless)."""
    for suffix in sorted(SUFFIX_UNITS, key=len, reverse=True):
        if name.endswith(suffix):
            return SUFFIX_UNITS[suffix]
    return "1"


def is_parquet(path) -> bool:
    """Is ``path`` a Parquet file?  By its first bytes (``PAR1``), whatever its
    name; a missing or unreadable file is not."""
    try:
        with open(path, "rb") as fh:
            return fh.read(4) == PARQUET_MAGIC
    except OSError:
        return False


def is_checksum_error(exc) -> bool:
    """Is ``exc`` pyarrow's refusal of a page whose CRC-32 does not match
    its bytes (an ``OSError``: 'could not verify page integrity, CRC
    checksum verification failed for page_ordinal 5')?"""
    return isinstance(exc, OSError) and "checksum verification failed" in str(exc)


def damage_message(path, exc, remedy="write it again, or copy it again from its source") -> str:
    """The message of Parquet file ``path`` that pyarrow could not read
    (``exc``): a page that fails its checksum or does not decode (corrupt),
    a file that starts as Parquet but lost its end (truncated), a footer
    that does not decode (damaged), else what pyarrow said.  Each names the
    file and what to do.

    Parameters
    ----------
    path : str or Path
    exc : Exception
        What pyarrow raised (``OSError``, ``pyarrow.ArrowException`` ...).
    remedy : str, optional
        What to do about a corrupt, truncated or damaged file.

    Returns
    -------
    str
    """
    text = str(exc).strip()
    first = text.splitlines()[0] if text else type(exc).__name__
    if is_checksum_error(exc):
        return (f"{path}: corrupt Parquet file: checksum mismatch in a data page ({first}); its bytes changed "
                f"after it was written (a disk, copy or transfer fault), so its numbers cannot be trusted: {remedy}")
    if is_parquet(path) and ("magic bytes not found in footer" in first or "smaller than the minimum" in first):
        return (f"{path}: not a readable Parquet file: truncated (it starts as Parquet but its end, the footer with "
                f"the schema, is missing: the copy or the program writing it stopped early); {remedy}")
    low = first.lower()
    if is_parquet(path) and any(w in low for w in _PAGE_DAMAGE) and _footer_reads(path):
        # the footer decodes: what does not is a page (its header or its compressed bytes), which has no
        # checksum to fail in a file written without them, or in its header in any file
        return (f"{path}: corrupt Parquet file: a data page does not decode ({first}); its bytes changed after it "
                f"was written (a disk, copy or transfer fault): {remedy}")
    if is_parquet(path) and any(w in low for w in ("thrift", "base64", "footer", "metadata")):
        return (f"{path}: not a readable Parquet file: its footer (the schema and column metadata) is damaged "
                f"({first}); {remedy}")
    return f"{path}: not a readable Parquet file ({first})"


#: pyarrow's words (lower case) for a page that does not decode: its header (thrift), its sizes, its compression
_PAGE_DAMAGE = ("thrift", "page header", "page was smaller", "unexpected end of stream", "decompression failed",
                "corrupt")


def _footer_reads(path) -> bool:
    """Does the footer (metadata and schema) of Parquet file ``path`` decode?"""
    import pyarrow.parquet as pq

    try:
        pq.read_schema(str(path))
    except Exception:  # noqa: BLE001 (any failure: it does not)
        return False
    return True


def read_parquet_table(path, columns=None):
    """The whole Arrow table of Parquet file ``path`` (or ``columns`` of
    it), every page's checksum checked (:data:`READ_OPTIONS`).

    Parameters
    ----------
    path : str or Path
    columns : sequence of str, optional

    Returns
    -------
    pyarrow.Table

    Raises
    ------
    InputError
        A page that fails its checksum, a truncated file, a damaged footer
        or anything else pyarrow cannot read (:func:`damage_message`).
    """
    import pyarrow.parquet as pq

    try:
        return pq.read_table(str(path), columns=columns, **READ_OPTIONS)
    except Exception as exc:  # noqa: BLE001 (pyarrow raises several kinds for a damaged file)
        raise InputError(damage_message(path, exc)) from None


def select_columns(names, spec=("all",)) -> list:
    """The columns of ``names`` that ``spec`` asks for, in the order of ``names``.

    Parameters
    ----------
    names : sequence of str
        Every column a solution has (navigation columns first).
    spec : str or sequence of str
        Groups (``"all"``, ``"navigation"`` = time, position, velocity,
        attitude; ``"navigation+sigma"``; ``"sigma"`` = the ``sigma_*``
        columns; ``"estimates"`` = the other extra columns: biases, scale
        factors, lever arm, clock ...) and column names, combined.  The
        navigation columns are always included.

    Raises
    ------
    ConfigError
        A name that is neither a group nor a column of this solution (the
        message lists the columns there are).
    """
    spec = [spec] if isinstance(spec, str) else list(spec)
    names = list(names)
    bad = column_spec_error(names, spec)
    if bad:
        raise ConfigError(f"[output] columns: {bad}")
    nav = set(NAVIGATION_COLUMNS)
    want = set(nav)
    for s in spec:
        if s == "all":
            want.update(names)
        elif s == "navigation":
            pass
        elif s in ("navigation+sigma", "sigma"):
            want.update(n for n in names if n.startswith("sigma_"))
        elif s == "estimates":
            want.update(n for n in names if n not in nav and not n.startswith("sigma_"))
        else:
            want.add(s)
    return [n for n in names if n in want]


def column_spec_error(names, spec, of="this solution") -> str | None:
    """Why the ``[output] columns`` spec ``spec`` (groups and column names)
    does not fit a solution whose columns are ``names``: the first entry
    that is neither a group (:data:`COLUMN_GROUPS`) nor one of ``names``,
    said with the groups and the columns there are (``of`` names the
    solution); None when every entry is one.  The check of
    :func:`select_columns`, and of a navigate config before its run."""
    spec = [spec] if isinstance(spec, str) else list(spec)
    names = list(names)
    for s in spec:
        if s not in COLUMN_GROUPS and s not in names:
            return (f"{s!r} is neither a group ({', '.join(COLUMN_GROUPS)}) nor a column of {of}; its columns are "
                    f"{', '.join(names)}")
    return None


def decimation_index(time, rate_hz=None) -> np.ndarray:
    """Rows to keep for output at ``rate_hz``: the first row, the first row at
    or after each multiple of ``1 / rate_hz`` in absolute time (so runs and
    the forward and smoothed files share their epochs), and the last row.

    Parameters
    ----------
    time : (n,) array [s], increasing
    rate_hz : float or None
        None, or a rate at or above the data's median rate: every row.

    Returns
    -------
    (m,) int ndarray, increasing
    """
    t = np.asarray(time, float)
    n = len(t)
    if rate_hz is None or n <= 2:
        return np.arange(n)
    if not rate_hz > 0:
        raise ConfigError(f"output rate must be > 0 Hz, got {rate_hz!r}")
    period = 1.0 / float(rate_hz)
    dt = float(np.median(np.diff(t)))
    if period <= dt * (1.0 + 1e-6):
        return np.arange(n)
    tol = 1e-3 * dt  # timestamp jitter: a sample 1 us before the grid time still counts as on it
    k0 = np.ceil((t[0] - tol) / period)
    k1 = np.floor((t[-1] + tol) / period)
    grid = np.arange(k0, k1 + 1.0) * period
    idx = np.searchsorted(t, grid - tol, side="left")
    return np.unique(np.concatenate(([0], idx[idx < n], [n - 1])))


def solution_columns(sol: NavSolution, rows=None, path=None) -> dict:
    """The file columns of a solution (:meth:`NavSolution.columns`, whose
    names ``NavSolution.to_dataframe`` shares): navigation in degrees
    (longitude wrapped into (-180, 180]), then every ``extra`` column under
    its own name (an (n, k) extra becomes ``name_0 .. name_k-1``), after
    refusing a latitude beyond a pole.

    Parameters
    ----------
    sol : NavSolution
    rows : (m,) int array, optional
        Only these rows (e.g. from :func:`decimation_index`).
    path : str or Path, optional
        The file being written, for the messages.

    Raises
    ------
    InputError
        A latitude outside [-90, 90] deg (the solution passed a pole in a
        frame that cannot).
    """
    sl = slice(None) if rows is None else np.asarray(rows)
    where = f"{path}: " if path is not None else ""
    lat = sol.lla[sl, 0]
    bad = np.nonzero(~(np.abs(lat) <= np.pi / 2 + 1e-12))[0]
    if len(bad):
        row = int(bad[0]) if rows is None else int(np.asarray(rows)[bad[0]])
        raise InputError(f"{where}refusing to write latitude {np.degrees(lat[bad[0]]):.6f} deg at row {row} "
                         "(outside [-90, 90]: the solution passed a pole in a frame that cannot)")
    return sol.columns(rows)


def _check_finite(path, cols):
    for name, a in cols.items():
        a = np.asarray(a, float)
        if not np.isfinite(a).all():
            i = int(np.argmax(~np.isfinite(a)))
            raise InputError(f"{path}: refusing to write {float(a[i])!r} (column '{name}', row {i}); the solution is "
                             "invalid")


def prepare(sol: NavSolution, path, *, rate_hz=None, columns=("all",)) -> dict:
    """The columns to write: rows decimated to ``rate_hz``, columns selected by
    ``columns`` (:func:`select_columns`), all finite (a NaN or an infinity is
    a bug upstream and is refused with the column and row)."""
    rows = None if rate_hz is None else decimation_index(sol.time, rate_hz)
    if rows is not None and len(rows) == len(sol.time):
        rows = None
    cols = solution_columns(sol, rows, path)
    keep = select_columns(list(cols), columns)
    cols = {k: np.ascontiguousarray(cols[k], dtype=np.float64) for k in keep}
    _check_finite(path, cols)
    return cols


def write_parquet(path, cols: dict, metadata: dict | None = None, compression="zstd") -> Path:
    """Write float64 columns as one Parquet file, atomically.

    Each field carries ``{"unit": ...}`` (:func:`column_unit`); the schema's
    key-value metadata holds ``inskit``: a JSON object with ``units``, the
    inskit ``version`` and the caller's ``metadata`` (e.g. ``config``,
    ``solution``).  Built by pyarrow straight from the arrays (no DataFrame).
    """
    import pyarrow as pa
    import pyarrow.parquet as pq


    path = Path(path)
    schema = _schema(cols, metadata)
    table = pa.Table.from_arrays([arrow_array(np.asarray(v, np.float64)) for v in cols.values()], schema=schema)
    with atomic_write(path) as tmp:
        pq.write_table(table, str(tmp), compression=compression, **_PARQUET_OPTIONS)
    return path


#: float columns: no dictionary (values rarely repeat), byte-stream split (groups the exponent bytes, which zstd
#: then packs: 10 % smaller than plain encoding on drive_0708, as fast); a CRC-32 in each page's header, which
#: every inskit reader checks (:data:`READ_OPTIONS`): a byte changed in a data page after writing is refused,
#: not read as other numbers
_PARQUET_OPTIONS = {"use_dictionary": False, "use_byte_stream_split": True, "write_page_checksum": True}

#: pyarrow's reading options of every inskit Parquet reader: the CRC-32 of each page that has one is checked
#: (a page of a file written without checksums, by other software, is read as it is)
READ_OPTIONS = {"page_checksum_verification": True}


def _schema(cols, metadata):
    """The Arrow schema of :func:`write_parquet` (units per field and in the
    ``inskit`` metadata)."""
    import pyarrow as pa

    from .. import __version__

    units = {k: column_unit(k) for k in cols}
    meta = {"version": __version__, "units": units, **(metadata or {})}
    fields = [pa.field(k, pa.float64(), nullable=False, metadata={"unit": units[k]}) for k in cols]
    return pa.schema(fields, metadata={"inskit": json.dumps(meta, default=str)})


class SolutionStream:
    """A solution file written segment by segment (a streamed filter run),
    into a temporary name beside ``path`` that :meth:`commit` renames to
    ``path`` (or :meth:`abort` removes): the file appears whole or not at
    all, and a run that fails leaves none.

    The format follows the name as :func:`inskit.io.write_solution`'s:
    ``.parquet`` (one row group per segment, the same schema and metadata
    as :func:`write_parquet`), else CSV (``.gz``: gzip) with the values of
    :func:`write_csv_fast`.

    Parameters
    ----------
    path : str or Path
    rows : (m,) int array, optional
        The absolute rows to write (e.g. :func:`decimation_index` over the
        whole run's times); default every row.
    columns : sequence of str
        :func:`select_columns`.
    metadata : dict, optional
        Parquet: run keys stored in the schema metadata.
    """

    def __init__(self, path, *, rows=None, columns=("all",), metadata=None):
        self.path = Path(path)
        self.tmp = self.path.with_name(f".part-{os.getpid()}-{self.path.name}")
        self.rows = None if rows is None else np.asarray(rows, np.int64)
        self.columns, self.metadata = columns, metadata
        self.parquet = self.path.suffix == ".parquet"
        self._writer = self._fh = self._keep = None
        self.n_written = 0

    def write(self, sol: NavSolution, start: int):
        """Append a segment: ``sol`` holds absolute rows ``start ..``."""
        import pyarrow as pa

        rows = None
        if self.rows is not None:
            lo, hi = np.searchsorted(self.rows, [start, start + len(sol.time)])
            rows = self.rows[lo:hi] - start
            if not len(rows):
                return
        cols = solution_columns(sol, rows, self.path)
        if self._keep is None:
            self._keep = select_columns(list(cols), self.columns)
        cols = {k: np.ascontiguousarray(cols[k], dtype=np.float64) for k in self._keep}
        _check_finite(self.path, cols)
        try:
            if self.parquet:
                import pyarrow.parquet as pq

                if self._writer is None:
                    self._schema = _schema(cols, self.metadata)
                    self._writer = pq.ParquetWriter(str(self.tmp), self._schema, compression="zstd",
                                                    **_PARQUET_OPTIONS)
                self._writer.write_table(pa.Table.from_arrays([arrow_array(v) for v in cols.values()],
                                                              schema=self._schema))
            else:
                import pyarrow.csv as pcsv

                if self._fh is None:
                    self._fh = (pa.CompressedOutputStream(str(self.tmp), "gzip") if self.path.name.endswith(".gz")
                                else open(self.tmp, "wb"))
                    self._fh.write((",".join(cols) + "\n").encode())
                table = pa.Table.from_arrays([format_column(v) for v in cols.values()], names=list(cols))
                pcsv.write_csv(table, self._fh, pcsv.WriteOptions(include_header=False, batch_size=8192,
                                                                  quoting_style="none"))
        except OSError as exc:
            self.abort()
            raise InputError(f"{self.path}: could not be written ({exc.strerror or exc})") from None
        self.n_written += len(next(iter(cols.values())))

    def close(self):
        """Finish the temporary file (still under its temporary name)."""
        if self._writer is not None:
            self._writer.close()
            self._writer = None
        if self._fh is not None:
            self._fh.close()
            self._fh = None

    def commit(self, folder=None) -> Path:
        """Close and rename the file to its final name (with ``folder``: to
        its name in that folder, e.g. a staging folder of
        :func:`inskit.files.staged_tree` that moves a run's files into
        place as a set); returns the path it now has."""
        self.close()
        if not self.tmp.exists():
            raise InputError(f"{self.path}: the streamed run wrote no rows")
        dest = self.path if folder is None else Path(folder) / self.path.name
        try:
            os.replace(self.tmp, dest)
        except OSError as exc:
            self.abort()
            raise InputError(f"{self.path}: could not be written ({exc.strerror or exc})") from None
        return dest

    def abort(self):
        """Close and remove the temporary file."""
        try:
            self.close()
        except Exception:  # noqa: BLE001 (already failing: the removal matters, not the close)
            pass
        self.tmp.unlink(missing_ok=True)


def _column_values(col):
    """A numeric Arrow column as float64 values (nulls as NaN), without
    pyarrow's ``to_numpy`` (which imports pandas)."""
    from .csv_formats import _values

    parts = []
    for ch in col.chunks:
        v = _values(ch).astype(np.float64)
        if ch.null_count:
            valid = np.unpackbits(np.frombuffer(ch.buffers()[0], np.uint8), bitorder="little")[ch.offset:ch.offset + len(ch)]
            v = np.where(valid.astype(bool), v, np.nan)
        parts.append(v)
    return np.concatenate(parts) if parts else np.zeros(0)


def read_parquet_columns(path) -> tuple[dict, dict]:
    """The float columns of a Parquet file and its inskit metadata.

    Returns
    -------
    (columns, metadata) : dict of str -> (n,) float64 ndarray, dict
        ``metadata`` is the schema's ``inskit`` JSON object (``{}`` for a file
        written by other software; ``units`` then come from the names).

    Raises
    ------
    InputError
        Not a readable Parquet file (a page that fails its checksum, a
        truncated file, a damaged footer: :func:`damage_message`), or a
        column that is not numeric.
    """
    import pyarrow as pa

    path = require_file(path)
    parquet_column_names(path)
    table = read_parquet_table(path)
    raw = (table.schema.metadata or {}).get(b"inskit")
    try:
        meta = json.loads(raw) if raw else {}
    except ValueError:
        meta = {}
    cols = {}
    for name, col in zip(table.column_names, table.columns):
        if not (pa.types.is_floating(col.type) or pa.types.is_integer(col.type)):
            raise InputError(f"{path}: column '{name}' holds {col.type}; expected numbers (float64)")
        narrow = narrow_float_message(path, name, col.type)
        if narrow:
            raise InputError(narrow)
        cols[name] = _column_values(col)
    meta.setdefault("units", {k: column_unit(k) for k in cols})
    return cols, meta


def parquet_column_names(path) -> list:
    """The column names of Parquet file ``path`` from its schema (the data
    are not read).

    Raises
    ------
    InputError
        Not a readable Parquet file, or a schema that names a column twice
        (pyarrow writes such a file; reading a column of it by name raised
        'Multiple matches for FieldRef', or a KeyError): refused as a CSV
        header naming a column twice is.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    from .csv_formats import _refuse_repeated_names

    try:
        names = list(pq.read_schema(str(path)).names)
    except (pa.ArrowException, OSError) as exc:
        raise InputError(damage_message(path, exc)) from None
    _refuse_repeated_names(path, names, "the Parquet schema")
    return names


#: columns (by their name's first word) whose values need all of float64: times and geodetic angles
_WIDE = ("time", "lat", "lon")


def narrow_float_message(path, name, arrow_type):
    """The message that refuses column ``name`` of Parquet file ``path``
    when it holds floats narrower than float64 and needs all of float64
    (:data:`_WIDE`: a time, a latitude, a longitude), else None.  Every
    Parquet reader asks it (solutions, IMU logs, fixes, the head of a
    solution): a float32 time of 1e5 s steps by 7.8 ms, so a 100 Hz log
    read as alternating 7.8 and 15.6 ms steps (allan: 'not regularly
    sampled'; align: 'static for only 0.0 s')."""
    import pyarrow as pa

    if pa.types.is_floating(arrow_type) and arrow_type.bit_width < 64 and name.split("_")[0] in _WIDE:
        return (f"{path}: column '{name}' holds {arrow_type}; expected float64 (a {arrow_type} "
                f"{'time' if name.startswith('time') else 'latitude or longitude'} has a resolution of "
                "metres or tens of milliseconds: the file lost precision when it was written)")
    return None


def read_metadata(path) -> dict:
    """The inskit metadata of a Parquet solution (units, version, config,
    solution) without reading its data."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        schema = pq.read_schema(str(path))
    except (pa.ArrowException, OSError) as exc:
        raise InputError(damage_message(path, exc)) from None
    raw = (schema.metadata or {}).get(b"inskit")
    try:
        meta = json.loads(raw) if raw else {}
    except (ValueError, UnicodeDecodeError):
        raise InputError(f"{path}: its inskit metadata is not readable JSON (a damaged or foreign file)") from None
    meta.setdefault("units", {n: column_unit(n) for n in schema.names})
    return meta
