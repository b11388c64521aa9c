"""Keep numba's compile cache true to the sources it was compiled from.

numba keys each cached function on the date and size of the file that
defines it, and nothing else.  A compiled function that calls compiled
functions of *other* modules carries their machine code in its own cache
entry (``integration._updates.run_nodes`` holds
``integration._kernel.propagate_rows``, the strapdown step, the gravity
model ...), so an edit of ``_kernel.py`` alone leaves the old propagation
running from the cache, silently, until ``_updates.py`` changes too (seen in
this project: a new process-noise term that changed nothing).

:func:`refresh` closes that hole for the whole package: it keeps a digest
of every source file that mentions numba beside the cache, and when the
digest changes it removes every cache entry of the package, so each
compiled function is rebuilt from the sources as they are.  The check costs
one ``stat`` per such file while nothing changed (their dates and sizes are
kept with the digest: 0.3 ms); a changed date makes it read and hash them
(25 files, 0.45 MB: milliseconds), and only a changed content clears the
cache.  Installed copies whose files never change pay the ``stat`` calls
only.  It runs once, on ``import inskit``; it never raises.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

ROOT = Path(__file__).resolve().parent
STAMP_NAME = "numba-sources.json"


def numba_sources(root: Path = ROOT) -> list[Path]:
    """The package's source files that mention numba (sorted)."""
    return [p for p in sorted(root.rglob("*.py")) if b"numba" in p.read_bytes()]


def _stats(root, files):
    out = []
    for p in files:
        st = p.stat()
        out.append([str(p.relative_to(root)), st.st_size, st.st_mtime_ns])
    return out


def _digest(root, files) -> str:
    import hashlib

    h = hashlib.sha1()
    for p in files:
        h.update(str(p.relative_to(root)).encode())
        h.update(b"\0")
        h.update(p.read_bytes())
    return h.hexdigest()


def cache_dirs(root: Path = ROOT) -> list[Path]:
    """Where numba may keep this package's cache: ``__pycache__`` beside
    the sources, and the tree under ``$NUMBA_CACHE_DIR`` or the user-wide
    numba cache that mirrors the package's path (numba's fall-backs when
    the package's folder is not writable)."""
    dirs = [root]
    rel = str(root).lstrip(os.sep)
    base = os.environ.get("NUMBA_CACHE_DIR")
    if base:
        dirs.append(Path(base) / rel)
    user = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "numba" / rel
    dirs.append(user)
    return dirs


def _stamp_path(root):
    p = root / "__pycache__" / STAMP_NAME
    if os.access(root, os.W_OK):
        return p
    import hashlib

    user = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "inskit"
    return user / f"numba-sources-{hashlib.sha1(str(root).encode()).hexdigest()[:12]}.json"


def refresh(root: Path = ROOT) -> bool:
    """Clear the package's numba cache when a numba source changed since
    the cache was made; True when entries were removed."""
    root = Path(root)
    stamp = _stamp_path(root)
    try:
        old = json.loads(stamp.read_text())
    except (OSError, ValueError):
        old = None
    try:
        if old is not None:
            try:
                files = [root / r for r, _, _ in old["files"]]
                if _stats(root, files) == old["files"]:
                    return False  # nothing touched since the last check
            except (OSError, KeyError, TypeError, ValueError):
                pass
        files = numba_sources(root)
        digest = _digest(root, files)
        removed = False
        if old is None or old.get("digest") != digest:
            for d in cache_dirs(root):
                if not d.is_dir():
                    continue
                for f in list(d.rglob("*.nbi")) + list(d.rglob("*.nbc")):
                    try:
                        f.unlink()
                        removed = True
                    except OSError:
                        pass
        stamp.parent.mkdir(parents=True, exist_ok=True)
        tmp = stamp.with_name(f"{stamp.name}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps({"digest": digest, "files": _stats(root, files)}))
        os.replace(tmp, stamp)
        return removed
    except OSError:  # a read-only tree, a vanished file: numba's own keys then stand alone
        return False
