"""Files written whole or not at all: the one place every writer goes through
(CSV tables, text, figures), below every package that writes."""

from __future__ import annotations

import os
from contextlib import contextmanager
from pathlib import Path

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


def check_folder_writable(folder):
    """Create ``folder`` if needed and prove it writable with a probe file
    (before any long computation, not after it)."""
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / f".write-probe-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        raise InputError(f"{folder}: the output folder is not writable ({exc.strerror or exc})") from None
    return folder


def same_file(a, b) -> bool:
    """Do two paths name the same file (or would they, once written)?"""
    try:
        return Path(a).resolve() == Path(b).resolve()
    except OSError:
        return False


def write_csv(path, columns, float_format="%.15g"):
    """Write a table (a dict of columns or a DataFrame) as CSV, atomically
    (pandas' vectorised writer)."""
    import pandas as pd

    df = columns if isinstance(columns, pd.DataFrame) else pd.DataFrame(columns)
    with atomic_write(path) as tmp:
        df.to_csv(tmp, index=False, float_format=float_format)
    return Path(path)


def write_text(path, text):
    """Write text atomically."""
    with atomic_write(path) as tmp:
        Path(tmp).write_text(text)
    return Path(path)


def save_figure(fig, path, dpi=110):
    """Save a matplotlib figure atomically and close it."""
    import matplotlib.pyplot as plt

    with atomic_write(path) as tmp:
        fig.savefig(tmp, dpi=dpi)
    plt.close(fig)
    return Path(path)
