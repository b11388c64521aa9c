"""Gaps in an IMU log: found, bridged, and paid for in covariance.

A logger that drops rows leaves one interval ``t[k] - t[k-1]`` much longer
than the others, with the increments of a single sample in it: the INS would
stop turning for the length of the gap (a 10 s gap in a 90 deg turn left an
85 deg heading error).  Bridging coasts on the last rates: rows at the usual
interval fill the gap with the previous sample's rate and specific force.  What the
vehicle really did meanwhile is unknown, so the filter's covariance grows by
what an unknown change of rate and acceleration over the gap could do
(:func:`gap_process_noise`), and the next GNSS fixes pass the gate and
recover the state.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..types import ImuData
from .layout import StateLayout


@dataclass(frozen=True)
class ImuGap:
    """One gap: the IMU row after it, when it started and how long it is [s]."""

    row: int
    start_s: float
    length_s: float


@dataclass(frozen=True)
class RateChange:
    """The log's sampling rate changes near ``row`` (time ``t_s``)."""

    row: int
    t_s: float
    rate_before_hz: float
    rate_after_hz: float


#: samples per block of the local sampling interval
RATE_BLOCK = 64


def local_interval(dt, block=RATE_BLOCK):
    """The local sampling interval at each of ``dt``: the median of its block
    of ``block`` intervals (a gap inside a block does not move a median), so
    a log whose rate changes is judged against its own rate at each time."""
    dt = np.asarray(dt, float)
    n = len(dt)
    if n < 2 * block:
        return np.full(n, float(np.median(dt)) if n else np.nan)
    nb = n // block
    med = np.median(dt[: nb * block].reshape(nb, block), axis=1)
    return med[np.minimum(np.arange(n) // block, nb - 1)]


def find_rate_changes(imu: ImuData, tolerance=0.2, block=RATE_BLOCK):
    """Where the sampling rate changes by more than ``tolerance`` (relative)
    between consecutive blocks and stays changed over the next block
    (:func:`inskit.io.time_tags.rate_change_rows` on the log's times: the
    reader's time-tag smoothing splits its stretches at the same changes)."""
    from ..io.time_tags import rate_change_rows

    rows, before, after = rate_change_rows(imu.time, tolerance, block)
    return [RateChange(int(k), float(imu.time[k]), float(1.0 / a), float(1.0 / b))
            for k, a, b in zip(rows, before, after)]


def find_gaps(imu: ImuData, factor=5.0):
    """Intervals longer than ``factor`` times the local sampling interval
    (:func:`local_interval`: a change of rate is not a gap)."""
    dt = np.diff(imu.time)
    loc = local_interval(dt)
    rows = np.nonzero(dt > factor * loc)[0] + 1
    return [ImuGap(int(k), float(imu.time[k - 1]), float(dt[k - 1])) for k in rows]


#: the longest IMU gap a run goes across [s]: beyond it the log is broken (a week rollover, two logs in one file)
MAX_GAP_S = 60.0


def refuse_long_gaps(gaps, name="the IMU log", limit=MAX_GAP_S, time_offset_s=0.0):
    """Raise an InputError naming the first gap longer than ``limit`` [s] by
    the times on either side of it as the file's time column holds them
    (``time_offset_s``: what the reader added to them, taken off again): a
    row number would count the rows as the job holds them (cut to the
    fixes' span, repeated rows dropped), not the lines of the file.
    Coasting (or bridging) on one sample's rates over minutes is no
    navigation, and a gap of a GPS week (a rollover the time column missed)
    would be bridged by tens of millions of rows."""
    from ..errors import InputError

    for g in gaps:
        if g.length_s > limit:
            a = g.start_s - time_offset_s
            raise InputError(f"{name}: a gap of {g.length_s:.3f} s in the time column, from {a:.4f} s to "
                             f"{a + g.length_s:.4f} s (the file's times); at most {limit:g} s is gone across: "
                             "split the log there, or fix its time column (a GPS week rollover?)")


def bridge_gaps(imu: ImuData, gaps):
    """Fill each gap with rows at the local interval that carry the previous
    sample's rate and specific force (the last row keeps its own sample).

    Returns
    -------
    ImuData
        The bridged log.
    list of ImuGap
        The gaps with ``row`` now the first inserted row of the bridged log.
    """
    if not gaps:
        return imu, []
    dt = np.diff(imu.time)
    loc = local_interval(dt)
    t_parts, th_parts, v_parts, out = [], [], [], []
    prev, n_new = 0, 0
    for g in gaps:
        k = g.row
        med = float(loc[k - 1])  # the log's own interval around the gap
        t_parts.append(imu.time[prev:k])
        th_parts.append(imu.dtheta_b[prev:k])
        v_parts.append(imu.dv_b[prev:k])
        n_new += k - prev
        m = int(np.floor(g.length_s / med + 0.5)) - 1  # rows to insert
        if m >= 1 and k >= 2:
            w = imu.dtheta_b[k - 1] / dt[k - 2]
            f = imu.dv_b[k - 1] / dt[k - 2]
            tt = imu.time[k - 1] + med * np.arange(1, m + 1)
            tt = tt[tt < imu.time[k] - 0.5 * med]
            steps = np.diff(np.concatenate([[imu.time[k - 1]], tt]))
            t_parts.append(tt)
            th_parts.append(w[None, :] * steps[:, None])
            v_parts.append(f[None, :] * steps[:, None])
            out.append(ImuGap(n_new, g.start_s, g.length_s))
            n_new += len(tt)
        else:
            out.append(ImuGap(n_new, g.start_s, g.length_s))
        prev = k
    t_parts.append(imu.time[prev:])
    th_parts.append(imu.dtheta_b[prev:])
    v_parts.append(imu.dv_b[prev:])
    return ImuData(np.concatenate(t_parts), np.concatenate(th_parts), np.concatenate(v_parts)), out


#: a lone IMU sample whose angular rate [rad/s] or specific force [m/s^2] exceeds these, and ten times both its
#: neighbours', is a spike (a corrupt row): no vehicle's or person's motion jumps so for one sample (drive_0708's
#: pitch rate rings at +-50 deg/s, 0.9 rad/s, from one sample to the next at a bump)
SPIKE_RATE_RAD_S, SPIKE_FORCE_M_S2, SPIKE_FACTOR = 20.0, 30.0 * 9.80665, 10.0
#: rows per block of :func:`imu_spikes` (its temporaries stay a few megabytes on logs of any length)
SPIKE_BLOCK_ROWS = 1 << 18


def imu_spikes(imu: ImuData) -> list[dict]:
    """The IMU's lone spikes: rows whose mean angular rate above
    :data:`SPIKE_RATE_RAD_S` (or specific force above
    :data:`SPIKE_FORCE_M_S2`) exceeds :data:`SPIKE_FACTOR` times both
    neighbours' (row 0, the initial epoch, and a missing neighbour count
    zero), sorted by row: ``{"row", "t_s", "sensor", "value", "neighbour"}``
    (``value``, ``neighbour`` [rad/s] or [m/s^2]).  Below the readers'
    limits (1000 rad/s, 1000 g, refused), such a row was integrated without
    a word: a 5000 deg/s sample in drive_0708 left the run unhealthy, no row
    named (found by the review of navigate's inputs); ``inskit mechanize`` integrates such
    a row alike.  Block by block."""
    t, n = imu.time, len(imu.time)
    out = []
    for sensor, x, lim in (("gyro", imu.dtheta_b, SPIKE_RATE_RAD_S), ("accel", imu.dv_b, SPIKE_FORCE_M_S2)):
        for a in range(1, n, SPIKE_BLOCK_ROWS):
            b = min(n, a + SPIKE_BLOCK_ROWS)
            lo, hi = max(1, a - 1), min(n, b + 1)  # one neighbour row either side
            r = np.sqrt(np.einsum("ij,ij->i", x[lo:hi], x[lo:hi])) / (t[lo:hi] - t[lo - 1:hi - 1])
            if not (r[a - lo:b - lo] > lim).any():
                continue
            prev, nxt = np.zeros_like(r), np.zeros_like(r)
            prev[1:], nxt[:-1] = r[:-1], r[1:]
            near = np.maximum(prev, nxt)
            idx = np.flatnonzero((r > lim) & (r > SPIKE_FACTOR * near))
            idx = idx[(idx >= a - lo) & (idx < b - lo)]
            out += [{"row": int(lo + i), "t_s": float(t[lo + i]), "sensor": sensor, "value": float(r[i]),
                     "neighbour": float(near[i])} for i in idx]
    return sorted(out, key=lambda sp: sp["row"])


def spikes_warning(spikes, imu_file) -> str | None:
    """The health warning of :func:`imu_spikes` (None without spikes): how
    many, the first three with their times (the file's) and values."""
    if not spikes:
        return None
    unit = {"gyro": ("rad/s", 1.0), "accel": ("g", 9.80665)}
    shown = "; ".join(f"t = {sp['t_s']:.3f} s, {sp['sensor']} {sp['value'] / unit[sp['sensor']][1]:.3g} "
                      f"{unit[sp['sensor']][0]} beside {sp['neighbour'] / unit[sp['sensor']][1]:.3g}"
                      for sp in spikes[:3])
    more = f" (and {len(spikes) - 3} more)" if len(spikes) > 3 else ""
    return (f"IMU: {imu_file}: {len(spikes)} lone sample{'s' if len(spikes) > 1 else ''} far beyond "
            f"{'their' if len(spikes) > 1 else 'its'} neighbours ({shown}{more}; the file's times): "
            + ("corrupt rows? each was" if len(spikes) > 1 else "a corrupt row? it was")
            + " integrated as it is, a jump in attitude or velocity there")


def gap_process_noise(layout: StateLayout, length_s, rate_sigma=np.radians(5.0), accel_sigma=1.0):
    """(layout.size,) variances a gap of ``length_s`` adds: an unknown rate
    change of ``rate_sigma`` [rad/s] and acceleration change ``accel_sigma``
    [m/s^2] held over the gap give attitude ``rate_sigma T`` (at most pi),
    velocity ``accel_sigma T`` and position ``accel_sigma T^2 / 2``."""
    q = np.zeros(layout.size)
    T = float(length_s)
    q[0:3] = (0.5 * accel_sigma * T * T) ** 2
    q[3:6] = (accel_sigma * T) ** 2
    q[6:9] = min(np.pi, rate_sigma * T) ** 2
    return q
