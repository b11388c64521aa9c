"""Plots of an integration run: track, errors with 3-sigma envelopes,
innovations, sensor-error estimates.  PNG files, no display needed.

Lines over the IMU epochs are drawn from decimated rows (at most
:data:`MAX_LINE_POINTS` per line, an even stride): a 1100 px wide figure shows
no more, and matplotlib's time grows with the points.  matplotlib is imported
only inside the plotting functions."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import earth
from ..analysis import line_breaks
from ..files import save_figure
from ..units import DEG
from .outages import antenna_positions


#: most points of one line drawn over the IMU epochs
MAX_LINE_POINTS = 4000


def _every(n, max_points=MAX_LINE_POINTS):
    """Row indices: an even stride over ``n`` rows keeping at most about
    ``max_points`` of them, and always the last row."""
    step = max(1, -(-n // max_points))
    idx = np.arange(0, n, step)
    return idx if (n == 0 or idx[-1] == n - 1) else np.append(idx, n - 1)


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _shade(ax, windows, t0):
    for a, b in windows:
        ax.axvspan(a - t0, b - t0, color="0.85", zorder=0)


class _Context:
    """What every plot of a run shares."""

    def __init__(self, res):
        fwd = res.forward.solution
        g = res.gnss
        self.res, self.fwd, self.g = res, fwd, g
        self.t0 = g.time[0]
        self.ref = g.lla[0]
        self.lever = np.asarray(res.config.gnss.lever_arm_b_m, float)
        self.inside = (g.time >= fwd.time[0]) & (g.time <= fwd.time[-1])


def _track(c, path, plt):
    res, fwd, g, ref = c.res, c.fwd, c.g, c.ref
    fig, ax = plt.subplots(figsize=(8, 7))
    pg = earth.lla_to_ned(g.lla, ref)
    ax.plot(pg[res.used, 1], pg[res.used, 0], ".", ms=2, color="0.6", label="GNSS fixes used")
    if (~res.used).any():
        ax.plot(pg[~res.used, 1], pg[~res.used, 0], ".", ms=3, color="tab:red", label="GNSS withheld (outages)")
    pf = earth.lla_to_ned(fwd.lla[_every(len(fwd.time), 4 * MAX_LINE_POINTS)], ref)
    ax.plot(pf[:, 1], pf[:, 0], lw=0.8, color="tab:blue", label="forward filter")
    if res.smoothed is not None:
        ps = earth.lla_to_ned(res.smoothed.nav.lla[_every(len(res.smoothed.nav.time), 4 * MAX_LINE_POINTS)], ref)
        ax.plot(ps[:, 1], ps[:, 0], lw=0.8, color="tab:green", label="RTS smoother")
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"{res.config.name}: track")
    fig.tight_layout()
    return save_figure(fig, path)


def _errors(c, path, plt):
    res, fwd, g, t0, lever, inside = c.res, c.fwd, c.g, c.t0, c.lever, c.inside
    # errors against every GNSS fix, with the filter's 3-sigma envelope
    tg = g.time[inside]
    fig, axes = plt.subplots(3, 1, figsize=(10, 8), sharex=True)
    worst = np.zeros(3)  # per axis: the largest error, which the axis must show whole
    for s, label, color in ((fwd, "forward", "tab:blue"),) + (
            ((res.smoothed.solution, "smoothed", "tab:green"),) if res.smoothed is not None else ()):
        ant = antenna_positions(s, tg, lever)
        d = earth.lla_to_ned(ant, g.lla[inside])
        si = s.interpolate(tg)
        for j, name in enumerate(("north", "east", "down")):
            ax = axes[j]
            # no line across a gap of the fixes: nothing was measured there
            ax.plot(*line_breaks(tg - t0, d[:, j]), lw=0.7, color=color, label=f"{label} - GNSS")
            if len(d):
                worst[j] = max(worst[j], float(np.nanmax(np.abs(d[:, j]))))
            sig = si.extra.get(("sigma_n_m", "sigma_e_m", "sigma_d_m")[j])
            if sig is not None:  # the uncoupled scheme has no covariance: no envelope
                ax.plot(*line_breaks(tg - t0, 3 * sig), lw=0.5, ls="--", color=color)
                ax.plot(*line_breaks(tg - t0, -3 * sig), lw=0.5, ls="--", color=color)
            ax.set_ylabel(f"{name} [m]")
    for j, ax in enumerate(axes):
        _shade(ax, res.windows, t0)
        ax.grid(alpha=0.3)
        lim = max(6.0, 1.08 * worst[j])  # the worst error whole; the sigma envelope may leave the axis
        ax.set_ylim(-lim, lim)
    axes[0].legend(fontsize=8, loc="upper left")
    envelope = "sigma_n_m" in fwd.extra
    axes[0].set_title("antenna position minus GNSS fix (grey: outages; " + (
        "dashed: +-3 sigma, may leave the axis)" if envelope else "no sigma: no filter in this run)"))
    axes[-1].set_xlabel("time after first GNSS fix [s]")
    fig.tight_layout()
    return save_figure(fig, path)


def _innovations(c, path, plt):
    res, t0 = c.res, c.t0
    # innovations
    inn = res.forward.innovations
    names = [k for k, v in inn.items() if len(v["t"])]
    if not names:  # the uncoupled scheme: the fixes reset the solution, no filter weighs them
        fig, ax = plt.subplots(figsize=(10, 2.6))
        ax.text(0.5, 0.5, "no filter innovations: no measurement was fused by a filter in this run "
                f"({res.settings.scheme} scheme)", ha="center", va="center", transform=ax.transAxes)
        ax.set_axis_off()
        return save_figure(fig, path)
    fig, axes = plt.subplots(len(names), 1, figsize=(10, 2.6 * len(names)), sharex=True, squeeze=False)
    for ax, k in zip(axes[:, 0], names):
        v = inn[k]
        nu, sg = v["nu"], v["sigma"]
        if nu.dtype == object:  # one row per satellite in view: all rows of an update at its time
            tt = np.repeat(v["t"], v["dof"])
            z = np.concatenate(list(nu)) / np.concatenate(list(sg)) if len(nu) else np.empty(0)
            ax.plot(tt - t0, z, ".", ms=1.5, label="each row (satellite)")
            zmax = float(np.abs(z).max()) if len(z) else 0.0
        else:
            z = nu / sg
            for j in range(nu.shape[1]):
                ax.plot(v["t"] - t0, z[:, j], ".", ms=1.5, label=f"component {j}")
            zmax = float(np.abs(z).max()) if z.size else 0.0
        ax.axhline(3, color="k", lw=0.5, ls="--")
        ax.axhline(-3, color="k", lw=0.5, ls="--")
        ax.set_ylabel(f"{k}\nnu / sigma")
        lim = max(8.0, 1.05 * zmax)  # the whole range, the worst case included
        ax.set_ylim(-lim, lim)
        if lim > 30:
            ax.set_yscale("symlog", linthresh=3.0)
        ax.legend(fontsize=7, loc="upper right")
        ax.grid(alpha=0.3)
        _shade(ax, res.windows, t0)
    axes[0, 0].set_title("normalised innovations (dashed: +-3)")
    axes[-1, 0].set_xlabel("time after first GNSS fix [s]")
    fig.tight_layout()
    return save_figure(fig, path)


def _biases(c, path, plt):
    res, fwd, t0 = c.res, c.fwd, c.t0
    # sensor-error estimates
    fig, axes = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    k = _every(len(fwd.time))
    tt = fwd.time[k] - t0
    for a in "xyz":
        axes[0].plot(tt, fwd.extra[f"bg_{a}_rad_s"][k] / DEG, lw=0.8, label=a)
        axes[1].plot(tt, fwd.extra[f"ba_{a}_m_s2"][k], lw=0.8, label=a)
    axes[0].set_ylabel("gyro bias [deg/s]")
    axes[1].set_ylabel("accel bias [m/s^2]")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        _shade(ax, res.windows, t0)
    axes[-1].set_xlabel("time after first GNSS fix [s]")
    axes[0].set_title("sensor bias estimates (forward filter)")
    fig.tight_layout()
    return save_figure(fig, path)


#: the plots of a run: (file name, function drawing it into a path and returning the path)
PLOTS = (("track.png", _track), ("errors.png", _errors), ("innovations.png", _innovations),
         ("biases.png", _biases))


def plot_all(res, out_dir, parallel=True):
    """The run's PNG plots (track, errors, innovations, biases) into
    ``out_dir``; returns their paths.

    ``parallel`` (Linux, two cores or more, from the main thread): every
    second plot is drawn by a forked child while this process draws the
    others (matplotlib holds the GIL: threads would not overlap); the child
    writes its files whole (:func:`inskit.files.save_figure`) and only
    exits; if it fails, its plots are drawn here, so a plot is never missing
    silently and its error reaches the caller.
    """
    import os
    import sys
    import threading

    c = _Context(res)
    out_dir = Path(out_dir)
    theirs = PLOTS[1::2]
    pid = -1
    if (parallel and sys.platform.startswith("linux") and (os.cpu_count() or 1) > 1
            and threading.current_thread() is threading.main_thread()):
        try:
            pid = os.fork()
        except OSError:
            pid = -1
        if pid == 0:  # the child: its plots, then gone (no atexit, no stream flush: the parent owns those)
            code = 1
            try:
                plt = _plt()
                for name, f in theirs:
                    f(c, out_dir / name, plt)
                code = 0
            finally:
                os._exit(code)
    plt = _plt()
    try:
        for name, f in (PLOTS[0::2] if pid > 0 else PLOTS):
            f(c, out_dir / name, plt)
    finally:
        child_failed = pid > 0 and os.waitpid(pid, 0)[1] != 0
    if child_failed:  # its plots drawn here: their error, if any, reaches the caller
        for name, f in theirs:
            f(c, out_dir / name, plt)
    return [out_dir / name for name, _ in PLOTS]
