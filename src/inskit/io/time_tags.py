"""IMU time tags as the sensor sampled them: jitter of the logger taken out.

A logger that polls an IMU stamps each row with its own clock at the moment
it reads, often a millisecond counter.  The sensor samples on its own clock;
the tags then carry the poll's jitter and the counter's quantization (on
drive_0708 the intervals are 8, 9, 10 or 11 ms of a nominal 10, and after
the rows read twice are dropped, 18-20 ms now and then).  For a rate log the
tags are more than labels: each sample is integrated over its interval, so
a 10 ms interval logged as 8 or 11 ms weighs that sample 20 % short or 10 %
long.  On a smooth drive that averages out; across a bump, where the pitch
rate rings at +-50 deg/s from one sample to the next, it leaves an attitude
error of tenths of a degree that the gravity leak then turns into metres.

:func:`smooth_time_tags` replaces the tags by their moving average over a
few samples (a local straight line: a sensor clock is steady over a fraction
of a second), stretch by stretch between the log's gaps, so that every
sample covers its share of the local sampling interval.  The mean time is
kept, so the IMU-to-GNSS alignment (``[imu] time_offset_s``) is unchanged.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError

#: an interval longer than this many median intervals ends a stretch: the tags are smoothed within stretches
STRETCH_GAP_FACTOR = 5.0
#: an interval this far from the median (relative) is jitter (:func:`interval_jitter`)
JITTER_TOLERANCE = 0.05
#: the share of jittery intervals above which the job suggests smoothing the tags
JITTER_HINT_FRACTION = 0.1


def interval_jitter(t):
    """``(fraction, lo, hi, median)``: the share of the sampling intervals
    within half and one and a half median intervals that differ from the
    median by more than :data:`JITTER_TOLERANCE`, the shortest and longest of
    them, and the median [s].  The longer intervals (a row left out, a gap)
    are not jitter and are not counted."""
    dt = np.diff(t)
    if dt.size < 2:
        return 0.0, 0.0, 0.0, 0.0
    med = float(np.median(dt))
    near = dt[(dt > 0.5 * med) & (dt < 1.5 * med)]
    if near.size == 0:
        return 0.0, med, med, med
    off = np.abs(near - med) > JITTER_TOLERANCE * med
    return float(off.mean()), float(near.min()), float(near.max()), med


def check_smoothing_samples(samples) -> int:
    """``samples`` as an int: 1 (tags as logged) or an odd number >= 3."""
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)):
        raise InputError(f"time_smoothing_samples must be a whole number (1: the time tags as logged, or an odd "
                         f"number >= 3), got {samples!r}")
    n = int(samples)
    if n < 1 or (n > 1 and n % 2 == 0):
        raise InputError(f"time_smoothing_samples must be 1 (the time tags as logged) or an odd number >= 3 (a "
                         f"window centred on each sample), got {n}")
    return n


def _local_line(x, w):
    """Each of ``x`` replaced by the least-squares line through the ``w``
    values centred on it (odd ``w <= len(x)``), the first and last ``w // 2``
    by the line through the first and last ``w`` values: a Savitzky-Golay
    filter of order 1 with its ends fitted.  The moving average is taken of
    the residual from the straight line through the ends, so that the sums
    stay small however long the stretch (written here rather than imported
    from scipy.signal, whose import alone costs a quarter of a second)."""
    n, h = len(x), w // 2
    i = np.arange(n, dtype=float)
    trend = x[0] + (x[-1] - x[0]) * i / (n - 1)
    r = x - trend
    out = np.empty(n)
    out[h:n - h] = np.convolve(r, np.full(w, 1.0 / w), mode="valid")
    j = np.arange(w, dtype=float)
    for lo, hi, at in ((0, w, slice(0, h)), (n - w, n, slice(n - h, n))):
        slope, icpt = np.polyfit(j, r[lo:hi], 1)
        out[at] = icpt + slope * (np.arange(n)[at] - lo)
    return out + trend


def smooth_time_tags(path, t, samples, *, info=None):
    """The time tags ``t`` smoothed over ``samples`` consecutive rows.

    Within each stretch between gaps (an interval longer than
    :data:`STRETCH_GAP_FACTOR` median intervals), each tag is replaced by the
    value at its row of the least-squares straight line through the
    ``samples`` tags centred on it (:func:`_local_line`: the moving average
    inside the stretch, a line fitted to its first and last ``samples`` rows
    at its ends).  A stretch shorter than ``samples`` rows
    keeps its tags.

    Parameters
    ----------
    path : Path
        For the message.
    t : (n,) ndarray
        Strictly increasing time tags [s] (rows read twice already dropped).
    samples : int
        1 (returned unchanged) or an odd number >= 3.
    info : dict, optional
        Filled with ``time_smoothing_samples``, the jitter of the tags as
        logged (:func:`interval_jitter`: ``time_tag_jitter_fraction``,
        ``time_tag_interval_min_s``, ``..._max_s``, ``..._median_s``) and,
        when smoothed, how far the tags moved: ``time_tags_moved_rms_s``,
        ``time_tags_moved_max_s``.

    Returns
    -------
    (n,) ndarray
        The smoothed tags (a new array; ``t`` itself when ``samples`` is 1).

    Raises
    ------
    InputError
        When the smoothed tags would not increase (tags too irregular for a
        steady sensor clock): the message names the row.
    """
    samples = check_smoothing_samples(samples)
    if info is not None:
        frac, lo, hi, med = interval_jitter(t)
        info.update(time_tag_jitter_fraction=frac, time_tag_interval_min_s=lo, time_tag_interval_max_s=hi,
                    time_tag_interval_median_s=med, time_smoothing_samples=samples)
    if samples == 1 or len(t) < 3:
        return t
    dt = np.diff(t)
    ends = np.flatnonzero(dt > STRETCH_GAP_FACTOR * np.median(dt)) + 1
    out = t.copy()
    for a, b in zip(np.r_[0, ends], np.r_[ends, len(t)]):
        if b - a >= samples:
            out[a:b] = t[a] + _local_line(t[a:b] - t[a], samples)
    bad = np.flatnonzero(np.diff(out) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise InputError(f"{path}: the time tags smoothed over {samples} rows ([imu] time_smoothing_samples) do not "
                         f"increase after {t[i - 1]:.6f} s (as logged; the next tag {t[i]:.6f} s): the tags are too "
                         "irregular for a steady sensor clock; use fewer samples, or 1 to keep them as logged")
    if info is not None:
        moved = out - t
        info.update(time_tags_moved_rms_s=float(np.sqrt(np.mean(moved * moved))),
                    time_tags_moved_max_s=float(np.max(np.abs(moved))))
    return out
