"""numba's own set-up, started early in a background thread.

The first compiled function a process calls, even one loaded from the
compile cache, pays for numba's set-up: its typing and lowering registries,
its BLAS check (without scipy.linalg: :mod:`inskit._numba_blas`), the
cache's first load (about a quarter of a second, once per process).  A command that reads its inputs first starts
that set-up here, in a thread, before reading: pyarrow parses CSV and
Parquet without holding the GIL, so the two overlap and the compiled code
is ready when the data are (``inskit navigate`` and ``inskit mechanize``).
"""

from __future__ import annotations

import threading

import numpy as np

_WARMING: threading.Thread | None = None


def warm_compiled_code() -> None:
    """Start numba's set-up in a daemon thread (nothing is compiled); a
    process that has started it already returns at once."""
    global _WARMING
    if _WARMING is not None:
        return

    def warm():
        try:
            from ..rotations import quat_from_rotvec

            quat_from_rotvec(np.zeros((2, 3)))  # a cached kernel: loading it sets numba up
        except Exception:  # noqa: BLE001 (a warm-up only: the command itself then says what is wrong)
            pass

    _WARMING = threading.Thread(target=warm, name="inskit-warm", daemon=True)
    _WARMING.start()
