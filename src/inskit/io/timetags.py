"""Time tags of a constant-rate sensor, recovered from rounded or jittered ones.

A MEMS IMU samples on its own clock at a fixed output rate, but a logger
often stamps each reading with a coarse counter: the rtklibexplorer logs (the
bundled ``drive_0708``) carry an integer-millisecond ``counter_ms``, so a
100 Hz stream shows intervals of 8 to 11 ms around a mean of exactly
10.0 ms, and the tags sit about -0.5 or +0.5 ms off one uniform grid (the
rounding of the counter), never further than 1.5 ms.  Rates integrated over
those intervals take the rounding for motion: each sample's increment is
``w dt`` with ``dt`` off by up to 10 %, which does not telescope away when
the rate changes between samples (engine vibration and road bumps, tens of
deg/s at 30-40 Hz on a car): on ``drive_0708`` it adds a white attitude
error of about 1.6 deg/sqrt(h) on the pitch axis, bursts of tenths of a
degree in bumps.

:func:`regular_time_tags` puts each gap-free stretch of tags on its
least-squares uniform grid, and keeps a stretch as logged when some tag lies
more than ``tol`` of an interval off the grid (not a constant-rate stream:
the grid would move samples across their neighbours' intervals).  A long
stretch whose rate drifts (a sensor oscillator warming up) is split in halves
until each part fits, so the grid follows the drift piecewise.
"""

from __future__ import annotations

import numpy as np

#: intervals longer than this many median intervals break the stream (gaps, which
#: the navigation bridges on its own)
GAP_FACTOR = 1.5
#: a stretch is put on its grid only when every tag lies within this fraction of
#: one interval of it
TOLERANCE = 0.5
#: stretches shorter than this many samples keep their logged tags
MIN_SAMPLES = 50


def _grid(t):
    """Least-squares uniform grid of ``t`` over its index: ``(grid, max |t - grid| / step)``."""
    k = np.arange(len(t), dtype=float)
    km, tm = k.mean(), t.mean()
    step = float(np.dot(k - km, t - tm) / np.dot(k - km, k - km))
    g = tm + (k - km) * step
    if step <= 0:
        return g, np.inf
    return g, float(np.max(np.abs(t - g)) / step)


def _fit(t, out, a, b, tol, min_samples, parts):
    if b - a < max(min_samples, 3):
        return
    g, dev = _grid(t[a:b])
    if dev <= tol:
        out[a:b] = g
        parts.append((a, b))
        return
    m = (a + b) // 2
    _fit(t, out, a, m, tol, min_samples, parts)
    _fit(t, out, m, b, tol, min_samples, parts)


def regular_time_tags(t, *, tol=TOLERANCE, gap_factor=GAP_FACTOR, min_samples=MIN_SAMPLES):
    """Uniform time tags for a constant-rate stream whose tags are rounded or jittered.

    Parameters
    ----------
    t : (n,) ndarray
        Logged time tags [s], increasing.
    tol : float
        A stretch goes onto its grid only if no tag lies more than ``tol``
        intervals off it.
    gap_factor : float
        An interval beyond this many median intervals ends a stretch.
    min_samples : int
        Shorter stretches (and parts) keep their logged tags.

    Returns
    -------
    t_reg : (n,) ndarray
        The tags, regular within each stretch that fitted; strictly
        increasing (a part whose grid would overlap a neighbour keeps its
        logged tags).
    info : dict
        ``regular_fraction`` (of the samples put on a grid), ``parts``,
        ``max_shift_s`` (the largest tag change) and ``rms_shift_s``.
    """
    t = np.asarray(t, dtype=float)
    n = len(t)
    out = t.copy()
    parts: list = []
    if n >= 3:
        dt = np.diff(t)
        med = float(np.median(dt))
        cuts = np.nonzero(dt > gap_factor * med)[0] + 1
        edges = np.r_[0, cuts, n]
        for a, b in zip(edges[:-1], edges[1:]):
            _fit(t, out, int(a), int(b), tol, min_samples, parts)
        if np.any(np.diff(out) <= 0):  # two grids met head to head: keep the logged tags at their seams
            bad = np.nonzero(np.diff(out) <= 0)[0]
            for a, b in list(parts):
                if np.any((bad >= a - 1) & (bad < b)):
                    out[a:b] = t[a:b]
                    parts.remove((a, b))
    shift = out - t
    reg = sum(b - a for a, b in parts)
    return out, {"regular_fraction": reg / n if n else 0.0, "parts": len(parts),
                 "max_shift_s": float(np.max(np.abs(shift))) if n else 0.0,
                 "rms_shift_s": float(np.sqrt(np.mean(shift ** 2))) if n else 0.0}
