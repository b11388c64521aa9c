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

That trusts the jitter to be zero-mean noise about a steady clock.  Where
the sampling rate changes inside a stretch (:func:`rate_change_rows`, the
detection the job's ``imu_rate_changes`` use), the stretch is split at the
change (:func:`split_row`) and each side is smoothed on its own, so the
tags are not bent across it.  What else breaks the trust (a clock that
drifts or jumps, a window too long for the clock) is checked, not
corrected: :func:`smoothing_check` compares how far the smoothing moved the
tags with what the logged jitter explains, and names what it moved beyond.
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
#: intervals per block whose medians :func:`rate_change_rows` compares (``inskit.integration.gaps.RATE_BLOCK``)
RATE_BLOCK = 64
#: the sampling rate changes where the median interval of a block differs from the steady one by more than this
RATE_CHANGE_TOLERANCE = 0.2
#: :func:`smoothing_check`: the net move's RMS beyond this many jitter RMS is more than the jitter explains
MOVED_RMS_FACTOR = 2.0
#: :func:`smoothing_check`: one tag's net move beyond this many jitter RMS is more than the jitter explains
MOVED_MAX_FACTOR = 6.0
#: :func:`smoothing_check`: rows left out spread over the window by more than this many sampling intervals
SPREAD_MAX_INTERVALS = 0.5
#: :func:`smoothing_check`: the jitter RMS is taken as at least this [s] (tags exact to the microsecond)
JITTER_FLOOR_S = 1e-6


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


def rate_change_rows(t, tolerance=RATE_CHANGE_TOLERANCE, block=RATE_BLOCK):
    """Where the sampling rate of the tags ``t`` changes by more than
    ``tolerance`` (relative) between consecutive blocks of ``block``
    intervals and stays changed over the next block (the median of a block
    is not moved by a gap, a row left out or the jitter inside it).

    The one detection of rate changes: :func:`inskit.integration.gaps.find_rate_changes`
    (the job's ``imu_rate_changes``) is this on an IMU log's times.

    Parameters
    ----------
    t : (n,) ndarray
        Increasing time tags [s].
    tolerance : float
        Relative change of the median interval.
    block : int
        Intervals per block.

    Returns
    -------
    rows : (k,) int ndarray
        The first row of the block where each change is seen (within a
        block or so of the change: :func:`split_row` places it).
    interval_before, interval_after : (k,) ndarray
        The steady median interval before and after each change [s].
    """
    dt = np.diff(t)
    n = len(dt)
    rows, before, after = [], [], []
    if n >= 3 * block:
        nb = n // block
        med = np.median(dt[: nb * block].reshape(nb, block), axis=1)
        level = med[0]  # the interval of the current steady run of blocks
        for b in range(1, nb):  # one step per block
            c = med[b]
            if abs(c - level) <= tolerance * level:
                continue
            if b + 1 < nb and abs(med[b + 1] - c) > tolerance * c:
                continue  # a block straddling the change (or a burst): wait for the new steady rate
            rows.append(b * block + 1)
            before.append(level)
            after.append(c)
            level = c
    return np.array(rows, dtype=int), np.array(before, dtype=float), np.array(after, dtype=float)


def _segment_sse(c, a, b):
    """The residual sum of squares of the least-squares line through each
    segment ``[a, b)`` (arrays of prefix indices), from the prefix sums
    ``c = (1, x, x^2, y, x y, y^2)``, and its slope."""
    m, sx, sxx, sy, sxy, syy = (v[b] - v[a] for v in c)
    vxx = sxx - sx * sx / m
    vxy = sxy - sx * sy / m
    return syy - sy * sy / m - vxy * vxy / vxx, vxy / vxx


def split_row(t, lo, hi, tolerance=RATE_CHANGE_TOLERANCE):
    """Where in rows ``lo:hi`` the tags ``t`` change rate: the row that
    starts the second of two straight lines (tag against row) fitted by
    least squares, the row chosen to minimise the two lines' residual sum of
    squares (two-phase regression; Hinkley 1969, Biometrika 56(3), 495-504).
    Each line holds at least three rows; every candidate row is scored at
    once from prefix sums.

    Parameters
    ----------
    t : (n,) ndarray
        Increasing time tags [s].
    lo, hi : int
        The rows searched (``hi - lo >= 8``; fewer: None).
    tolerance : float
        The lines' slopes (intervals) must differ by more than this
        (relative) for a change to be taken (else None): a window that holds
        one rate only (its change at a gap, outside it) is not split.

    Returns
    -------
    (row, interval_before, interval_after) or None
        The first row at the new rate and the fitted intervals [s].
    """
    m = hi - lo
    if m < 8:
        return None
    x = np.arange(m, dtype=float)
    slope = (t[hi - 1] - t[lo]) / (m - 1)
    y = t[lo:hi] - t[lo] - slope * x  # the sums stay small
    c = [np.r_[0.0, np.cumsum(v)] for v in (np.ones(m), x, x * x, y, x * y, y * y)]
    k = np.arange(3, m - 2)
    sse_a, _ = _segment_sse(c, np.zeros_like(k), k)
    sse_b, _ = _segment_sse(c, k, np.full_like(k, m))
    best = int(k[np.argmin(sse_a + sse_b)])
    _, sa = _segment_sse(c, np.array([0]), np.array([best]))
    _, sb = _segment_sse(c, np.array([best]), np.array([m]))
    before, after = slope + float(sa[0]), slope + float(sb[0])
    if abs(after - before) <= tolerance * abs(before):
        return None
    return lo + best, before, after


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


def stretches(t):
    """The rows of ``t`` smoothed apart: ``(bounds, changes)``.

    The log is cut at its gaps (an interval longer than
    :data:`STRETCH_GAP_FACTOR` median intervals) and, inside a stretch, at
    each change of sampling rate (:func:`rate_change_rows`, placed by
    :func:`split_row` within two blocks of where it is seen).

    Returns
    -------
    bounds : (m + 1,) int ndarray
        Piece ``j`` is rows ``bounds[j]:bounds[j + 1]``.
    changes : list of dict
        Each split at a rate change: ``row`` (the first at the new rate),
        ``t_s`` (its tag as logged), ``rate_before_hz``, ``rate_after_hz``
        (from the two lines' intervals).
    """
    dt = np.diff(t)
    ends = np.flatnonzero(dt > STRETCH_GAP_FACTOR * np.median(dt)) + 1
    gaps = np.r_[0, ends, len(t)]
    rows, _, _ = rate_change_rows(t)
    splits, changes = [], []
    for i, r in enumerate(rows):  # one step per change
        s = int(np.searchsorted(gaps, r, side="right")) - 1
        lo = max(int(gaps[s]), r - 2 * RATE_BLOCK, (int(rows[i - 1]) + r) // 2 if i else 0)
        hi = min(int(gaps[s + 1]), r + 2 * RATE_BLOCK, (r + int(rows[i + 1])) // 2 if i + 1 < len(rows) else len(t))
        found = split_row(t, lo, hi)
        if found is not None:
            k, before, after = found
            splits.append(k)
            changes.append({"row": int(k), "t_s": float(t[k]), "rate_before_hz": float(1.0 / before),
                            "rate_after_hz": float(1.0 / after)})
    return np.unique(np.r_[gaps, splits].astype(int)), changes


def smoothing_check(t, out, samples, bounds):
    """How far the smoothing moved the tags against what the logged jitter
    explains.

    Tags ``t = tau + e`` of a steady clock ``tau`` that count the sensor's
    samples, white jitter ``e`` of RMS ``s``: each interval of a piece is
    one sample, or ``round(dt / T)`` of them where rows were left out (an
    interval of 1.5 or more median intervals ``T``; a sample counter
    ``k``).  The smoothing is linear, so it moves the tags by
    ``T (S(k) - k)``, the rows left out spread over the window (zero where
    none is left out; under half an interval for one in a window), plus
    ``S(e) - e``, the net move, whose RMS is ``s sqrt(1 - 1/N)`` at most.
    ``s`` is read from the intervals near the median: their variance is
    ``2 s^2`` (a millisecond counter's quantization, 1/sqrt(12) ms RMS,
    included).

    The smoothing moved the tags beyond what the jitter explains (a rate
    change it did not split, a clock that drifts or jumps, a window too long
    for the clock) when the net move's RMS exceeds :data:`MOVED_RMS_FACTOR`
    ``= 2`` times ``s`` (white jitter gives at most 1; 2 leaves room for
    jitter correlated from row to row, drive_0708: 1.6), one tag's net move
    exceeds :data:`MOVED_MAX_FACTOR` ``= 6`` times ``s`` (a white Gaussian
    jitter's largest over 10^8 rows: 6; drive_0708: 3.6), or the rows left
    out are spread by more than :data:`SPREAD_MAX_INTERVALS` ``= 0.5``
    sampling interval (several rows left out within a window, or a clock
    jump of whole intervals).  A jump of less than half an interval shows
    in the net move only beyond those factors.

    Parameters
    ----------
    t, out : (n,) ndarray
        The tags as logged and smoothed [s].
    samples : int
        The window (rows).
    bounds : (m + 1,) int ndarray
        The pieces smoothed apart (:func:`stretches`).

    Returns
    -------
    dict
        ``time_tag_jitter_s`` (``s``), ``time_tags_moved_net_rms_s``,
        ``time_tags_moved_net_max_s``, ``time_tags_left_out_spread_max_s``
        and ``time_tags_beyond_jitter``: a list, empty when the move is
        explained, else one entry per figure beyond its limit, each with
        ``key`` (the figure's name), ``value_s``, ``limit_s``, and the
        ``row`` (of ``t``) and ``t_s`` (its tag as logged) where the move
        is largest.

    References
    ----------
    Savitzky & Golay 1964, Anal. Chem. 36(8), 1627-1639 (order 1: the local
    line); the quantization noise of a counter of step q: q^2 / 12
    (Widrow & Kollar 2008, Quantization Noise, ch. 4).
    """
    n = len(t)
    k_moved = np.zeros(n)  # S(k) - k: the spread of the rows left out [intervals]
    interval = np.zeros(n)  # each row's median interval T [s]
    sq, cnt = 0.0, 0
    for a, b in zip(bounds[:-1], bounds[1:]):  # one step per piece
        if b - a < 3:
            continue
        d = np.diff(t[a:b])
        interval[a:b] = T = float(np.median(d))
        near = d[(d > 0.5 * T) & (d < 1.5 * T)]
        if near.size >= 2:
            sq += float(np.sum((near - near.mean()) ** 2))
            cnt += near.size
        if b - a >= samples:
            k = np.r_[0.0, np.cumsum(np.maximum(1.0, np.round(d / T)))]
            k_moved[a:b] = _local_line(k, samples) - k
    jitter = float(np.sqrt(sq / (2 * cnt))) if cnt else 0.0
    spread = interval * k_moved
    net = (out - t) - spread
    i, j = int(np.argmax(np.abs(net))), int(np.argmax(np.abs(k_moved)))
    figures = {"time_tags_moved_net_rms_s": float(np.sqrt(np.mean(net * net))),
               "time_tags_moved_net_max_s": float(abs(net[i])),
               "time_tags_left_out_spread_max_s": float(abs(spread[j]))}
    s = max(jitter, JITTER_FLOOR_S)
    limits = (("time_tags_moved_net_rms_s", MOVED_RMS_FACTOR * s, i),
              ("time_tags_moved_net_max_s", MOVED_MAX_FACTOR * s, i),
              ("time_tags_left_out_spread_max_s", SPREAD_MAX_INTERVALS * interval[j], j))
    beyond = [{"key": key, "value_s": figures[key], "limit_s": float(limit), "row": at, "t_s": float(t[at])}
              for key, limit, at in limits if figures[key] > limit]
    return {"time_tag_jitter_s": jitter, **figures, "time_tags_beyond_jitter": beyond}


def smooth_time_tags(path, t, samples, *, info=None):
    """The time tags ``t`` smoothed over ``samples`` consecutive rows.

    The log is cut into pieces smoothed apart (:func:`stretches`): at its
    gaps (an interval longer than :data:`STRETCH_GAP_FACTOR` median
    intervals) and where its sampling rate changes (100 Hz then 200 Hz
    with no gap between: a line through both rates would bend the tags
    across the change by up to ``dT h (h + 1) / (2 N)``, 6.8 ms for 10 to 5
    ms and ``N = 11``).  Within each piece each tag is replaced by the value
    at its row of the least-squares straight line through the ``samples``
    tags centred on it (:func:`_local_line`: the moving average inside the
    piece, a line fitted to its first and last ``samples`` rows at its
    ends).  A piece shorter than ``samples`` rows keeps its tags.

    The smoothing trusts the jitter to be zero-mean noise about a steady
    clock; :func:`smoothing_check` says where the tags moved beyond what
    the jitter explains (a drift or jump of the clock, a rate change too
    small to be split, a window too long): those are reported
    (``info["time_tags_beyond_jitter"]``), not corrected.

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
        when smoothed, how far the tags moved (``time_tags_moved_rms_s``,
        ``time_tags_moved_max_s``), the check of that move against the
        jitter (:func:`smoothing_check`: ``time_tag_jitter_s``,
        ``time_tags_moved_net_rms_s``, ``..._net_max_s``,
        ``time_tags_left_out_spread_max_s``, ``time_tags_beyond_jitter``) and
        the rate changes the tags were split at (``time_tag_rate_changes``:
        a list of dicts, :func:`stretches`).

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
    bounds, changes = stretches(t)
    out = t.copy()
    for a, b in zip(bounds[:-1], bounds[1:]):
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
                    time_tags_moved_max_s=float(np.max(np.abs(moved))), time_tag_rate_changes=changes)
        info.update(smoothing_check(t, out, samples, bounds))
    return out
