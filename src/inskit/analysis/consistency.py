"""Filter consistency by axis: the shape of a vector measurement's noise.

A consistent filter's normalised innovations ``nu_i / s_i`` (``s_i`` the
innovation sigma, ``sqrt(H P H' + R)`` on the diagonal) have unit variance
on every axis.  The mean NIS judges the noise's overall size; it cannot
tell a fix whose vertical is noisier than its sigma says from one whose
horizontal is: both raise it alike.  Comparing the axes can.  A receiver's
formal sigmas (RTKLIB's ``.pos`` gives 0.99 cm on every axis of drive_0708)
often lack the shape that satellite geometry gives every GNSS fix (the
vertical worse than the horizontal: VDOP above HDOP; Misra & Enge 2011,
sec. 6.1.3; Groves 2013, sec. 9.4.3): a vertical fix noise taken too small
is then read by the filter as vertical velocity, which the non-holonomic
constraint turns into pitch (a vertical rate over the speed) and gravity
into along-track acceleration.

:func:`axis_innovation_rms` measures the RMS of the normalised innovations
on each axis over the updates a filter used, leaving out those just after
a break in the updates (the end of an outage, where the innovation measures
the INS's drift, not the fix's noise); :func:`axis_scale_step` turns it
into the factors that make the horizontal and vertical agree with their
mean kept (the mean NIS to first order unchanged).
"""

from __future__ import annotations

import numpy as np

#: updates within this long [s] after a break in the updates (or the first one) are left out
SETTLE_S = 5.0
#: a pause between updates longer than this [s] is a break (an outage, a gap in the fixes) ...
BREAK_S = 1.0
#: ... when it is also longer than this many times the updates' median interval (fixes at 1 Hz or slower, whose
#: time tags jitter by a millisecond, pause by more than 1 s between every other pair)
BREAK_INTERVALS = 1.5


def axis_innovation_rms(t, nu, sigma, accepted=None, settle_s=SETTLE_S, break_s=BREAK_S):
    """RMS of the normalised innovations ``nu / sigma`` on each axis.

    Parameters
    ----------
    t : (m,) array_like
        Update times [s], increasing.
    nu, sigma : (m, k) array_like
        Innovations and their sigmas (``sqrt(H P H' + R)``, diagonal) of
        each update's k rows (north, east, down for a GNSS position).
    accepted : (m,) bool array_like, optional
        The updates the filter used (default: all); rejected ones are left
        out.
    settle_s : float
        Updates within this long after the first update and after each
        break are left out [s].
    break_s : float
        A pause between consecutive updates (used or not) longer than this,
        and than :data:`BREAK_INTERVALS` times their median interval, is a
        break [s].

    Returns
    -------
    rms : (k,) ndarray
        The RMS of ``nu / sigma`` per axis (NaN with no update counted).
    count : int
        The updates counted.
    """
    t = np.asarray(t, dtype=float)
    nu = np.asarray(nu, dtype=float)
    sigma = np.asarray(sigma, dtype=float)
    if nu.ndim != 2 or nu.shape != sigma.shape or len(t) != len(nu):
        raise ValueError(f"nu and sigma must be (m, k) arrays of the m = {len(t)} update times, got "
                         f"{nu.shape} and {sigma.shape}")
    keep = np.ones(len(t), bool) if accepted is None else np.asarray(accepted, bool).copy()
    if len(t):
        dt = np.diff(t)
        pause = max(break_s, BREAK_INTERVALS * float(np.median(dt))) if len(dt) else break_s
        starts = np.r_[0, np.nonzero(dt > pause)[0] + 1]  # the first update after each break
        since = t - t[starts][np.searchsorted(starts, np.arange(len(t)), side="right") - 1]
        keep &= since >= settle_s
        keep &= np.all(np.isfinite(nu) & np.isfinite(sigma) & (sigma > 0), axis=1)
    n = int(keep.sum())
    if n == 0:
        return np.full(nu.shape[1] if nu.ndim == 2 else 0, np.nan), 0
    z = nu[keep] / sigma[keep]
    return np.sqrt(np.mean(z * z, axis=0)), n


def horizontal_vertical(rms_ned):
    """``(horizontal, vertical)``: the north and east RMS pooled (the
    quadratic mean of the two) and the down RMS."""
    r = np.asarray(rms_ned, dtype=float)
    return float(np.sqrt(0.5 * (r[0] ** 2 + r[1] ** 2))), float(r[2])


def axis_scale_step(rms_ned):
    """Factors ``(3,)`` for the north, east and down sigmas that bring the
    horizontal (pooled) and vertical normalised-innovation RMS
    (:func:`horizontal_vertical`) to their common mean
    ``sqrt((2 h^2 + v^2) / 3)``: an axis whose innovations are too large for
    its sigma gets a larger sigma, the other a smaller one, the mean NIS
    kept to first order.  The filter's own response (a fix trusted more
    pulls the INS more, and its innovations shrink) makes this a step of a
    fixed-point iteration, not the answer at once."""
    h, v = horizontal_vertical(rms_ned)
    if not (np.isfinite(h) and np.isfinite(v) and h > 0 and v > 0):
        raise ValueError(f"normalised-innovation RMS must be finite and > 0 on every axis, got {list(rms_ned)}")
    mean = np.sqrt((2.0 * h * h + v * v) / 3.0)
    return np.array([h / mean, h / mean, v / mean])
