"""Files written whole or not at all."""

from __future__ import annotations

import os
from contextlib import contextmanager
from pathlib import Path

from ..errors import InputError


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
