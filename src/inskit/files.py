"""Files written whole or not at all: the one place every writer goes through
(CSV tables, text, figures), below every package that writes."""

from __future__ import annotations

import json
import math
import os
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from .errors import InputError


@contextmanager
def atomic_write(path):
    """Yield a temporary path beside ``path`` (same suffixes, so formats and
    compression are inferred alike); when the block completes it is renamed
    to ``path`` in one step, on any error or interrupt it is removed.

    A failed write (disk full, no permission) raises :class:`InputError`
    naming the file; nothing is left under the final name.
    """
    path = Path(path)
    tmp = path.with_name(f".part-{os.getpid()}-{path.name}")
    try:
        yield tmp
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise InputError(f"{path}: could not be written ({exc.strerror or exc})") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextmanager
def staged_files(folder):
    """Write a set of files whole or not at all: yield ``stage(path)``, which
    maps each final path (in ``folder``) to its place in a hidden staging
    folder beside them; when the block completes every staged file is moved
    to its final name (``os.replace``, same file system), on any error or
    interrupt the staging folder goes and the files already in ``folder``
    are left as they were (a failed ``--force`` run does not leave new files
    beside old ones of another run).  The moves are undone too when one of
    them fails (:func:`_commit`): the set lands whole or the old one stays."""
    import shutil
    import tempfile

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".staging-", dir=folder))
    staged = {}

    def stage(path):
        path = Path(path)
        staged[path] = tmp / path.name
        return staged[path]

    try:
        yield stage
        _commit(staged, tmp / "previous")
    except InputError as exc:  # a writer's message names the file by its final name, not the staging one
        shutil.rmtree(tmp, ignore_errors=True)
        raise InputError(str(exc).replace(f"{tmp}{os.sep}", f"{folder}{os.sep}")) from None
    except OSError as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        raise InputError(f"{folder}: the results could not be written ({exc.strerror or exc})") from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    shutil.rmtree(tmp, ignore_errors=True)


def _move_set(pairs, aside):
    """Move each staged file to its final name, ``pairs`` of ``(part,
    final)`` in order (a part that was never written is passed over), the
    file a final name held moved to ``aside(k, final)`` first and the
    folders a final name needs made; should any move fail (or be
    interrupted), undo the ones made: the files they replaced come back,
    the new ones and the folders made for them go, and the error is raised.
    Returns ``(final, the file it replaced or None)`` of each move, for the
    caller to drop the replaced files once the set is in place.  The one
    commit of :func:`staged_files`, :func:`staged_paths` and
    :func:`staged_tree`."""
    moved, made = [], []
    try:
        for k, (part, final) in enumerate(pairs):
            if not part.exists():
                continue
            for d in reversed(final.parents):
                if not d.exists():
                    d.mkdir()
                    made.append(d)
            old = None
            if final.exists():
                old = aside(k, final)
                os.replace(final, old)
            moved.append((final, old))
            os.replace(part, final)
    except BaseException:
        for final, old in reversed(moved):
            try:
                if old is not None:
                    os.replace(old, final)
                else:
                    final.unlink(missing_ok=True)
            except OSError:
                pass
        for d in reversed(made):
            try:
                d.rmdir()
            except OSError:
                pass
        raise
    return moved


def _commit(staged, previous):
    """Move each staged file (``{final: part}``) to its final name, the
    files they replace into the folder ``previous`` (:func:`_move_set`:
    undone should a move fail)."""
    previous.mkdir()
    _move_set([(part, final) for final, part in staged.items()], lambda k, final: previous / final.name)


@contextmanager
def staged_paths():
    """Write a set of files that may lie in different folders (``--plot``
    and ``--toml`` of one command) whole or not at all, as
    :func:`staged_files` does for one folder: yield ``stage(path)``, a
    temporary path beside ``path`` (:func:`atomic_write`'s name, same
    suffixes); when the block completes each is renamed to its final name,
    and should a rename fail (or be interrupted) the ones made are undone:
    the files they replaced come back.  On any error or interrupt in the
    block the temporary files go and every final file is left as it was.
    A failed write raises :class:`InputError` naming the file."""
    staged = {}

    def stage(path):
        path = Path(path)
        staged[path] = path.with_name(f".part-{os.getpid()}-{path.name}")
        return staged[path]

    def drop_parts():
        for part in staged.values():
            part.unlink(missing_ok=True)

    def finals(msg):  # a message names the file the user gave, not its temporary name
        for final, part in staged.items():
            msg = msg.replace(str(part), str(final))
        return msg

    try:
        yield stage
    except OSError as exc:
        drop_parts()
        raise InputError(finals(f"{exc.filename or 'an output'}: could not be written ({exc.strerror or exc})")) \
            from None
    except InputError as exc:
        drop_parts()
        raise InputError(finals(str(exc))) from None
    except BaseException:
        drop_parts()
        raise
    current = []  # the final name being moved, for the message

    def aside(k, final):
        return final.with_name(f".previous-{os.getpid()}-{final.name}")

    def pairs():
        for final, part in staged.items():
            current[:] = [final]
            yield part, final

    try:
        moved = _move_set(pairs(), aside)
    except BaseException as exc:
        drop_parts()
        if isinstance(exc, OSError):
            raise InputError(f"{current[0] if current else 'an output'}: could not be written "
                             f"({exc.strerror or exc})") from None
        raise
    for _, old in moved:
        if old is not None:
            old.unlink(missing_ok=True)


def check_results_folder(folder, overwrite=False, option="--force"):
    """Refuse, before the work, a results folder that already holds files
    unless ``overwrite`` (``inskit navigate``'s rule, for a command whose
    file names are known only once it has run: every figure of a
    reproduction); make it and prove it writable
    (:func:`check_folder_writable`)."""
    folder = Path(folder)
    if folder.is_dir() and any(folder.iterdir()) and not overwrite:
        raise InputError(f"{folder}: already holds files; refusing to overwrite them (use {option} or another "
                         "--out)")
    return check_folder_writable(folder)


@contextmanager
def staged_tree(folder, last=()):
    """Write a whole tree of results whole or not at all: yield a hidden
    staging folder inside ``folder`` for the job to write into (subfolders
    too, under the names they will have in ``folder``); when the block
    completes every file is moved to its place in ``folder`` (the files
    named in ``last`` after the others: a run's summary lands last, as the
    mark of a complete set), undone should a move fail (the files replaced come back, the new ones go); on
    any error or interrupt the staging folder goes and ``folder`` is left
    as it was.  A file that would replace a folder is refused
    (:func:`check_outputs`).  Paths the job returns name the staging folder:
    :func:`relocated` maps them to ``folder``."""
    import shutil
    import tempfile

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".staging-", dir=folder))
    previous = None
    try:
        yield tmp
        parts = sorted((p for p in tmp.rglob("*") if p.is_file()), key=lambda p: (p.name in last, p))
        finals = [folder / p.relative_to(tmp) for p in parts]
        check_outputs(finals, (), overwrite=True)  # a folder of the user's in a file's place is not replaced
        previous = Path(tempfile.mkdtemp(prefix=".previous-", dir=folder))
        _move_set(list(zip(parts, finals)), lambda k, final: previous / str(k))
    except OSError as exc:
        raise InputError(f"{folder}: the results could not be written ({exc.strerror or exc})") from None
    except InputError as exc:  # a writer's message names the file as it will be, not in the staging folder
        raise InputError(str(exc).replace(str(tmp), str(folder))) from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
        if previous is not None:
            shutil.rmtree(previous, ignore_errors=True)


def relocated(obj, old, new):
    """``obj`` (a JSON-like result) with every text that is the path
    ``old`` or lies under it rewritten to lie under ``new`` (the paths a job
    wrote into :func:`staged_tree`'s staging folder, as they are once moved)."""
    old, new = str(old), str(new)
    if isinstance(obj, dict):
        return {k: relocated(v, old, new) for k, v in obj.items()}
    if isinstance(obj, list):
        return [relocated(v, old, new) for v in obj]
    if isinstance(obj, tuple):
        return tuple(relocated(v, old, new) for v in obj)
    if isinstance(obj, Path):
        obj = str(obj)
    if isinstance(obj, str) and (obj == old or obj.startswith(old + os.sep)):
        return new + obj[len(old):]
    return obj


#: the output folders :func:`check_folder_writable` made in this command (the deepest first)
_MADE: list = []


def forget_made_folders():
    """Start a command afresh: no folder of an earlier one (in the same process) is removed for it."""
    _MADE.clear()


def remove_made_folders():
    """Remove the folders :func:`check_folder_writable` made that are still
    empty (the CLI calls it when a command fails: a refused input leaves no
    empty output folder behind); forget them all."""
    for p in list(_MADE):
        try:
            p.rmdir()  # only an empty folder goes
        except OSError:
            pass
    _MADE.clear()


def check_folder_writable(folder):
    """Create ``folder`` if needed and prove it writable with a probe file
    (before any long computation, not after it).  The folders it makes are
    remembered for :func:`remove_made_folders`."""
    folder = Path(folder)
    _nearest_folder(folder, folder, "made")  # the nearest existing one must be a folder ('File exists' misled)
    full = folder.resolve()  # 'x/../E/new' with no x: E exists, and must not be taken for a folder made here
    missing = [p for p in (full, *full.parents) if not p.exists()]  # the deepest first
    try:
        folder.mkdir(parents=True, exist_ok=True)
        _MADE.extend(p for p in missing if p not in _MADE)
        probe = folder / f".write-probe-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        raise InputError(f"{folder}: the output folder is not writable ({exc.strerror or exc})") from None
    return folder


def _nearest_folder(folder, target, verb):
    """The nearest existing one of ``folder`` and its parents; an InputError
    when it is a file (``target`` cannot be ``verb`` under it: 'File exists'
    or 'Not a directory' from the write misled)."""
    for p in (folder, *folder.parents):
        if p.exists():
            if not p.is_dir():
                where = "" if p == target else f" (so {target} cannot be {verb})"
                raise InputError(f"{p}: is a file; expected an output folder{where}")
            return p
    return Path(".")


def check_output_place(path):
    """Refuse, before any work, an output file whose folder cannot hold it:
    one under a file, or in a folder that is not writable (the write, after
    the work, said '[Errno 20] Not a directory: .../.part-...').  Makes
    nothing."""
    path = Path(path)
    near = _nearest_folder(path.parent, path, "written")
    if not os.access(near, os.W_OK | os.X_OK):
        raise InputError(f"{path}: cannot be written ({near} is not a writable folder)")


def require_file(path) -> Path:
    """``path`` as a Path when it names a file; else an InputError that says
    what it is instead (missing, or a folder: 'no such file' misled)."""
    path = Path(path)
    if not path.is_file():
        if path.is_dir():
            raise InputError(f"{path}: is a folder; expected a file")
        raise InputError(f"{path}: no such file")
    return path


def check_outputs(outputs, inputs=(), overwrite=False, option="--force"):
    """Refuse, before any work, to write where it would destroy something:
    an output that is one of the command's ``inputs`` (never, whatever
    ``overwrite`` says: the run would replace what it reads), or one that
    exists when ``overwrite`` is false (the user's file: ``option`` lifts
    that), or one that is a folder (never: ``option`` overwrites files,
    it does not delete a folder and what it holds), or one whose folder
    cannot hold it (:func:`check_output_place`).
    ``None`` entries of either list are skipped.  Every command that
    writes files calls this on the whole list of what it will write."""
    ins = [Path(i) for i in inputs if i is not None]
    for out in outputs:
        if out is None:
            continue
        for inp in ins:
            if same_file(out, inp):
                raise InputError(f"{out}: is an input of this command; refusing to overwrite it (choose another "
                                 "output)")
        if Path(out).is_dir():  # never replaced, --force or not: the set's commit took it, and all it held, away
            raise InputError(f"{out}: is a folder; refusing to replace it by a file (move it, or choose another "
                             "output)")
        if Path(out).exists() and not overwrite:
            raise InputError(f"{out}: already exists; refusing to overwrite it (use {option})")
        check_output_place(out)


def same_file(a, b) -> bool:
    """Do two paths name the same file (or would they, once written)?"""
    try:
        return Path(a).resolve() == Path(b).resolve()
    except OSError:
        return False


def distinct_text(v) -> list:
    """The distinct values of a text column as ``str``: a set of an object
    column's values (its ``astype(str)`` would be a fixed-width copy four
    bytes per character of its longest value, and ``unique`` sort it)."""
    if v.dtype.kind == "O":
        try:
            return [str(x) for x in set(v.tolist())]
        except TypeError:  # unhashable values (arrays, lists): their text
            pass
    return np.unique(v.astype(str)).tolist()


def write_csv(path, columns, float_format="%.15g"):
    """Write a table (a dict of columns or a DataFrame) as CSV, atomically.

    A table of numeric (and text) columns, with a ``%.Ng`` format, goes through
    :func:`write_csv_fast` (pyarrow's vectorised writer, ``N`` significant
    digits; pandas' ``to_csv`` with a float format calls Python per value,
    10 s for a 30-minute 100 Hz IMU log); anything else through pandas.
    """
    import re

    m = re.fullmatch(r"%\.(\d+)g", float_format or "")
    if m and isinstance(columns, dict):
        cols = {k: np.asarray(v) for k, v in columns.items()}
        plain_text = all(not any(c in x for x in distinct_text(v) for c in ',"\n\r')
                         for v in cols.values() if v.dtype.kind in "OU")  # the writer does not quote
        if cols and plain_text and all(v.ndim == 1 and v.dtype.kind in "fiubOU" for v in cols.values()) \
                and len({len(v) for v in cols.values()}) == 1:
            return write_csv_fast(path, {k: v if v.dtype.kind in "OUiub" else np.asarray(v, np.float64)
                                         for k, v in cols.items()}, int(m.group(1)))
    import pandas as pd  # only for what the fast writer does not take

    df = columns if isinstance(columns, pd.DataFrame) else pd.DataFrame(columns)
    with atomic_write(path) as tmp:
        df.to_csv(tmp, index=False, float_format=float_format)
    return Path(path)


#: significant digits of the CSV values (those of the earlier ``%.15g`` files)
CSV_DIGITS = 15
#: rows formatted at a time by :func:`write_csv_fast`
CSV_BLOCK_ROWS = 1 << 17


def round_significant(x, digits=CSV_DIGITS) -> np.ndarray:
    """``x`` rounded to ``digits`` significant decimal digits, vectorised.

    The result is the double nearest to a ``digits``-digit decimal, so its
    shortest round-trip decimal form (what pyarrow writes) has at most
    ``digits`` digits, as ``%.15g`` gave; it may differ from C's correctly
    rounded ``%.15g`` by one unit in the last digit at exact halves.
    """
    x = np.asarray(x, np.float64)
    ax = np.abs(x)
    ok = (ax > 0) & np.isfinite(ax)
    e = np.zeros_like(x)
    np.floor(np.log10(ax, where=ok, out=np.zeros_like(x)), where=ok, out=e)
    p = digits - 1 - e
    with np.errstate(over="ignore", invalid="ignore"):  # subnormals: 10^p overflows, x is kept as it is
        s = np.power(10.0, np.abs(p))
        r = np.where(p >= 0, np.round(x * s) / s, np.round(x / s) * s)
    return np.where(ok & np.isfinite(r), r, x)


#: below this magnitude CSV values are written as ``m.mmme-N``: a fixed-point ``0.00123...`` has leading
#: zeros that pandas' default float parser counts among its 17 digits (it would lose the last ones)
CSV_EXPONENT_BELOW = 1e-2


def arrow_array(v):
    """A 1-D NumPy array as an Arrow array, built on its buffer (no copy for
    float64 and int64).  ``pyarrow.array`` would do the same after
    importing pandas (a quarter of a second) to check whether ``v`` is a
    pandas object.  Floats become float64, integers int64, booleans bool,
    anything else UTF-8 strings."""
    import pyarrow as pa

    v = np.asarray(v)
    n = len(v)
    if v.dtype.kind == "f":
        return pa.Array.from_buffers(pa.float64(), n, [None, pa.py_buffer(np.ascontiguousarray(v, np.float64))])
    if v.dtype.kind in "iu":
        return pa.Array.from_buffers(pa.int64(), n, [None, pa.py_buffer(np.ascontiguousarray(v, np.int64))])
    if v.dtype.kind == "b":
        return pa.Array.from_buffers(pa.bool_(), n, [None, pa.py_buffer(np.packbits(v, bitorder="little"))])
    # each distinct text encoded once (a column of measurement names has a handful), then gathered row by row
    uniq, inv = np.unique(v.astype(str), return_inverse=True)
    b = np.char.encode(uniq, "utf-8")
    ulen = np.char.str_len(b).astype(np.int64)
    width = b.dtype.itemsize
    m = len(uniq)
    raw_u = np.frombuffer(b.tobytes(), np.uint8).reshape(m, width) if m and width else np.zeros((m, width), np.uint8)
    inv = inv.reshape(-1)
    lengths = ulen[inv]
    data = raw_u[inv][np.arange(width) < lengths[:, None]]
    offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int32)
    return pa.Array.from_buffers(pa.string(), n, [None, pa.py_buffer(offsets), pa.py_buffer(data)])


def format_column(x, digits=CSV_DIGITS):
    """A float column as an Arrow column for the CSV writer: rounded to
    ``digits`` significant digits (:func:`round_significant`), numbers below
    :data:`CSV_EXPONENT_BELOW` in magnitude as mantissa and exponent strings,
    built by Arrow's vectorised kernels (no Python per value)."""
    import pyarrow as pa
    import pyarrow.compute as pc

    r = round_significant(x, digits)
    ar = np.abs(r)
    small = (ar >= 1e-290) & (ar < CSV_EXPONENT_BELOW)  # pyarrow writes smaller ones with an exponent itself
    if not small.any():
        return arrow_array(r)
    rs = r[small]
    e = np.floor(np.log10(np.abs(rs)))
    m = round_significant(rs * np.power(10.0, -e), digits)  # in [1, 10), or 10 after rounding 9.99..: still exact
    # call_function with arrays only: the keyword wrappers of pyarrow.compute import pandas to inspect arguments
    sep = arrow_array(np.full(len(m), "e"))
    text = pc.call_function("binary_join_element_wise", [pc.cast(arrow_array(m), pa.string()),
                                                         pc.cast(arrow_array(e.astype(np.int64)), pa.string()), sep])
    # one float-to-text conversion per value: Arrow's (shortest round trip) for the rest
    return pc.call_function("replace_with_mask", [pc.cast(arrow_array(r), pa.string()), arrow_array(small), text])


def write_csv_fast(path, cols: dict, digits=CSV_DIGITS) -> Path:
    """Write float columns as CSV (one plain header line), atomically, by
    pyarrow's vectorised CSV writer; gzip when ``path`` ends in ``.gz``.

    Values have ``digits`` significant digits (:func:`format_column`), so
    files stay the size of the former ``%.15g`` ones and read back within one
    unit of the last digit, by pandas' default parser too.
    """
    return write_csv_parts(path, list(cols), [cols], digits)


def write_csv_parts(path, names, parts, digits=CSV_DIGITS) -> Path:
    """:func:`write_csv_fast` of a table given as consecutive ``parts``
    (an iterable of dicts of equally long columns, keyed by ``names``), each
    made only when the writer reaches it: a long table (every innovation of
    an 8 h run) never exists whole.  Text must need no quoting (no comma,
    quote or line break: the writer does not quote)."""
    import pyarrow as pa
    import pyarrow.csv as pcsv

    path = Path(path)
    names = list(names)
    header = (",".join(names) + "\n").encode()

    def column(v):  # text and integers as they are (an integer is exact: no rounding to digits), floats formatted
        v = np.asarray(v)
        if v.dtype.kind in "OU":
            return arrow_array(v.astype(str))
        if v.dtype.kind in "iub":
            return arrow_array(v)
        return format_column(v, digits)

    opts = pcsv.WriteOptions(include_header=False, batch_size=8192, quoting_style="none")
    step = CSV_BLOCK_ROWS  # formatted text in blocks: the memory of one block, whatever the table's length

    def write(out):
        out.write(header)
        for cols in parts:
            n = len(cols[names[0]]) if names else 0
            for a in range(0, n, step):
                pcsv.write_csv(pa.Table.from_arrays([column(np.asarray(cols[k])[a:a + step]) for k in names],
                                                    names=names), out, opts)

    with atomic_write(path) as tmp:
        if path.name.endswith(".gz"):
            with pa.CompressedOutputStream(str(tmp), "gzip") as out:
                write(out)
        else:
            with open(tmp, "wb") as fh:
                write(fh)
    return path


def write_text(path, text):
    """Write text atomically."""
    with atomic_write(path) as tmp:
        Path(tmp).write_text(text)
    return Path(path)


def plain_json(x):
    """Plain JSON values for numpy scalars and arrays, paths, and non-finite
    floats (``null``: NaN and infinity are not JSON, and a strict reader
    refuses the file); dict keys as text."""
    if isinstance(x, dict):
        return {str(k): plain_json(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [plain_json(v) for v in x]
    if isinstance(x, np.ndarray):
        return plain_json(x.tolist())
    if isinstance(x, (np.floating, float)):
        x = float(x)
        return x if math.isfinite(x) else None
    if isinstance(x, (np.integer, np.bool_)):
        return x.item()
    if isinstance(x, Path):
        return str(x)
    return x


def write_json(path, obj, indent=1):
    """Write ``obj`` as one JSON document, atomically (:func:`write_text`),
    through :func:`plain_json` (a NaN is ``null``) and strict: never the
    ``NaN`` or ``Infinity`` of Python's default; anything else JSON has no
    type for as its text."""
    return write_text(path, json.dumps(plain_json(obj), indent=indent, allow_nan=False, default=str) + "\n")


def save_figure(fig, path, dpi=110):
    """Save a matplotlib figure atomically and close it."""
    import matplotlib.pyplot as plt

    with atomic_write(path) as tmp:
        fig.savefig(tmp, dpi=dpi)
    plt.close(fig)
    return Path(path)
