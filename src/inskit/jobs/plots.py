"""Plots of an integration run: track, errors with 3-sigma envelopes,
innovations, sensor-error estimates.  PNG files, no display needed.

Long series are drawn from decimated rows: a 1100 px wide figure shows no
more, and matplotlib's time grows with the points.  Lines keep at most about
:data:`MAX_LINE_POINTS` points, the minimum and the maximum of every bin
(:func:`inskit.jobs.report.decimate`), so a spike or the worst error is
never dropped; the innovation clouds keep at most
:data:`MAX_SCATTER_POINTS` points per component, each bin's extremes plus
an even stride (:func:`inskit.jobs.report.decimate_scatter`: the extremes
alone would draw two bands and no bulk), drawn in a shuffled order so that
no component covers the others.  matplotlib is imported only inside the
plotting functions."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import earth
from ..analysis import line_breaks
from ..files import save_figure
from ..units import DEG_PER_HOUR, MILLI_G
from .outages import antenna_positions


#: most points of one line drawn over the IMU epochs (or over the fixes)
MAX_LINE_POINTS = 4000
#: most points of one component's cloud of normalised innovations, and of them the bins' extremes (two a
#: bin: 250 bins, 4 px each across the panel; more would crowd the cloud's edges into bands)
MAX_SCATTER_POINTS = 3000
SCATTER_EXTREMES = 500


def _thin(n, ys, max_points=MAX_LINE_POINTS):
    """Row indices of at most about ``max_points`` of ``n`` rows keeping the
    minimum and maximum of every bin of each series in ``ys``, the first and
    the last row (:func:`inskit.jobs.report.decimate`)."""
    from .report import decimate

    return decimate(n, ys, max_points)


def _thin_line(t, y, max_points=MAX_LINE_POINTS, **breaks):
    """``line_breaks(t, y, **breaks)`` decimated: the breaks (NaN points)
    found on every sample and all kept, the values thinned to each bin's
    extremes."""
    tb, yb = line_breaks(t, y, **breaks)
    if len(tb) <= max_points:
        return tb, yb
    k = np.union1d(_thin(len(tb), [yb], max_points), np.flatnonzero(np.isnan(yb)))
    return tb[k], yb[k]


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
    # thinned on latitude and longitude (north and east to within the Earth's curvature), then turned local
    pf = earth.lla_to_ned(fwd.lla[_thin(len(fwd.time), [fwd.lla[:, 0], fwd.lla[:, 1]], 4 * MAX_LINE_POINTS)], ref)
    ax.plot(pf[:, 1], pf[:, 0], lw=0.8, color="tab:blue", label="forward filter")
    if res.smoothed is not None:
        sl = res.smoothed.nav.lla
        ps = earth.lla_to_ned(sl[_thin(len(sl), [sl[:, 0], sl[:, 1]], 4 * MAX_LINE_POINTS)], ref)
        ax.plot(ps[:, 1], ps[:, 0], lw=0.8, color="tab:green", label="RTS smoother")
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    # equal scales by widening the data limits, not by shrinking the axes: a long, narrow track keeps
    # a full-width frame (its tick labels had no room and ran into each other)
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    # below the frame: inside it, the legend hid whichever end of the track lay under it
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=4, frameon=False)
    ax.set_title(f"{res.config.name}: track")
    fig.tight_layout()
    return save_figure(fig, path)


#: an error axis whose worst value exceeds this many times its typical one (99th percentile) turns symlog
LOG_SPAN = 10.0


def _rejected_times(res, names):
    """Times of the updates of measurements ``names`` that the gate refused."""
    out = []
    for k in names:
        v = (res.forward.innovations or {}).get(k)
        if v is not None and len(v["t"]):
            out.append(np.asarray(v["t"])[~np.asarray(v["accepted"], bool)])
    return np.concatenate(out) if out else np.empty(0)


def _nice_ceil(x):
    """The smallest of 1, 2, 5 times a power of ten at or above ``x`` > 0
    (a tick value a reader takes in at a glance)."""
    e = 10.0 ** np.floor(np.log10(x))
    return float(next(m * e for m in (1.0, 2.0, 5.0, 10.0) if m * e >= x * (1 - 1e-12)))


def _symmetric_limits(ax, values, floor, margin=1.08):
    """y limits of ``ax`` holding every finite value of ``values`` whole, at
    least ``+-floor``.  When the worst value exceeds :data:`LOG_SPAN` times
    the 99th percentile of the magnitudes (one outlier, a divergence), a
    linear axis would flatten the rest to a line at zero: the axis is then
    symmetric-logarithmic, linear within the typical magnitude.  Returns
    ``(limit, linthresh or None)``."""
    a = np.abs(np.asarray(values, float))
    a = a[np.isfinite(a)]
    worst = float(a.max()) if a.size else 0.0
    typical = float(np.percentile(a, 99)) if a.size else 0.0
    lin = _nice_ceil(max(floor, 1.0, typical))
    if worst > LOG_SPAN * lin:
        lim = 10 ** (np.log10(worst) + 0.15)  # the worst point inside, not on the frame
        ax.set_yscale("symlog", linthresh=lin, linscale=1.0)
        ax.set_ylim(-lim, lim)
        _symlog_ticks(ax, lim, lin)
        return lim, lin
    lim = max(floor, margin * worst)
    ax.set_ylim(-lim, lim)
    return lim, None


def _outage_patch(windows):
    """A legend entry for the grey outage shading (none without outages)."""
    from matplotlib.patches import Patch

    return [Patch(color="0.85", label="GNSS outage (fixes withheld)")] if len(windows) else []


def _errors(c, path, plt):
    from matplotlib.lines import Line2D

    res, fwd, g, t0, lever, inside = c.res, c.fwd, c.g, c.t0, c.lever, c.inside
    # errors against every GNSS fix, with the filter's 3-sigma envelope
    tg = g.time[inside]
    fig, axes = plt.subplots(3, 1, figsize=(10, 8), sharex=True)
    errs = [[] for _ in range(3)]  # per axis: every error, which the axis must show whole
    rejected = _rejected_times(res, ("gnss_pos",))
    rej = np.isin(tg, rejected) if len(rejected) else np.zeros(len(tg), bool)
    handles = []
    for s, label, color in ((fwd, "forward", "tab:blue"),) + (
            ((res.smoothed.solution, "smoothed", "tab:green"),) if res.smoothed is not None else ()):
        ant = antenna_positions(s, tg, lever)
        d = earth.lla_to_ned(ant, g.lla[inside])
        si = s.interpolate(tg)
        has_sigma = False
        for j, name in enumerate(("north", "east", "down")):
            ax = axes[j]
            # no line across a gap of the fixes: nothing was measured there
            ax.plot(*_thin_line(tg - t0, d[:, j]), lw=0.7, color=color)
            errs[j].append(d[:, j])
            sig = si.extra.get(("sigma_n_m", "sigma_e_m", "sigma_d_m")[j])
            if sig is not None:  # the uncoupled scheme has no covariance: no envelope
                has_sigma = True
                tb, sb = _thin_line(tg - t0, 3 * sig)
                ax.plot(tb, sb, lw=0.5, ls="--", color=color)
                ax.plot(tb, -sb, lw=0.5, ls="--", color=color)
            if rej.any() and label == "forward":
                ax.plot(tg[rej] - t0, d[rej, j], "x", ms=5, mew=1.2, color="tab:red", zorder=5)
            ax.set_ylabel(f"{name} [m]")
        handles.append(Line2D([], [], lw=0.7, color=color, label=f"{label} - GNSS"))
        if has_sigma:
            handles.append(Line2D([], [], lw=0.5, ls="--", color=color, label=f"{label} ±3σ"))
    if rej.any():
        handles.append(Line2D([], [], ls="none", marker="x", mew=1.2, color="tab:red",
                              label=f"fix rejected by the gate ({int(rej.sum())})"))
    handles += _outage_patch(res.windows)
    logs = []
    for j, ax in enumerate(axes):
        _shade(ax, res.windows, t0)
        ax.grid(alpha=0.3)
        # the worst error whole; the sigma envelope may leave the axis
        _, lin = _symmetric_limits(ax, np.concatenate(errs[j]) if errs[j] else [], 6.0)
        if lin is not None:
            logs.append(f"{('north', 'east', 'down')[j]}: log beyond ±{lin:.3g} m")
    # above the frame: inside it, the legend hid the errors and envelopes of the first outages
    axes[0].legend(handles=handles, fontsize=8, loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=len(handles),
                   frameon=False, borderaxespad=0.2)
    envelope = "sigma_n_m" in fwd.extra
    fig.suptitle("antenna position minus GNSS fix (" + (
        "dashed: ±3σ, may leave the axis" if envelope else "no sigma: no filter in this run")
        + ("; " + ", ".join(logs) if logs else "") + ")", fontsize=11)
    axes[-1].set_xlabel("time after first GNSS fix [s]")
    fig.tight_layout()
    return save_figure(fig, path)


#: the legend of the rows of a measurement with one row per satellite in view
SATELLITE_ROWS = "each row (satellite)"
#: what each row of a measurement's innovation is (its legend), where the rows are fixed
COMPONENTS = {"gnss_pos": ("north", "east", "down"), "gnss_vel": ("north", "east", "down"),
              "zupt": ("v north", "v east", "v down"), "nhc": ("lateral (body y)", "vertical (body z)")}


def _symlog_ticks(ax, lim, lin):
    """Readable ticks of a symlog axis: 0, +-lin and the decades beyond
    (matplotlib's own crowd +-1, 0 and +-10^0 into the linear band)."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator

    dec = [10.0 ** k for k in range(int(np.ceil(np.log10(lin * 2.5))), int(np.floor(np.log10(lim))) + 1)]
    ticks = sorted({0.0, lin, -lin, *dec, *(-x for x in dec)})
    ax.yaxis.set_major_locator(FixedLocator(ticks))
    ax.yaxis.set_minor_locator(NullLocator())
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))


def _innovation_rows(v, name):
    """One measurement's innovation record, one entry per row of every
    update, flat: ``(t, z = nu / sigma, component index, refused, component
    names)``; a row is refused when its own gate or its update's refused it.
    Rows that are satellites (named by the record's ``label``, or as many
    as are in view) are one component: row j is not the same satellite from
    one update to the next."""
    nu, sg = v["nu"], v["sigma"]
    acc = np.asarray(v["accepted"], bool)
    if nu.dtype == object or "label" in v:  # one row per satellite in view: all rows of an update at its time
        k = np.asarray(v["dof"], np.int64)
        z = (np.concatenate([np.ravel(a) for a in nu]) / np.concatenate([np.ravel(a) for a in sg]) if len(nu)
             else np.empty(0))
        comp = np.zeros(len(z), np.int64)
        names = [SATELLITE_ROWS]
    else:
        k = np.full(len(v["t"]), nu.shape[1], np.int64)
        z = (nu / sg).reshape(-1)
        comp = np.tile(np.arange(nu.shape[1]), len(v["t"]))
        known = COMPONENTS.get(name, ())
        names = [known[j] if j < len(known) else f"component {j}" for j in range(nu.shape[1])]
    refused = np.repeat(~acc, k)
    st = v.get("status")  # per row: one satellite refused while the others were used
    if st is not None and len(st) == len(z):
        from ..integration.engine import ROW_ACCEPTED

        refused |= np.asarray(st) != ROW_ACCEPTED
    return np.repeat(np.asarray(v["t"], float), k), z, comp, refused, names


def _innovations(c, path, plt):
    from matplotlib.lines import Line2D

    from .report import decimate_scatter

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
    # fixed, not the rcParams cycle: a library imported beside inskit (gnss_lib_py sets its own) changed them
    colours = ["tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan"]
    fig, axes = plt.subplots(len(names), 1, figsize=(11, 2.6 * len(names)), sharex=True, squeeze=False)
    thinned = False
    for ax, k in zip(axes[:, 0], names):
        v = inn[k]
        tt, z, comp, refused, labels = _innovation_rows(v, k)
        finite = np.isfinite(z)
        # each component thinned on its own (its extremes and its bulk), then all drawn in one shuffled
        # order: drawn one after the other, the last (down, the NHC's vertical) covered the others whole
        # on a long log, which then showed a green or orange band and nothing of north and east
        keep, handles = [], []
        for j, label in enumerate(labels):
            m = np.flatnonzero((comp == j) & ~refused & finite)
            sel = m[decimate_scatter(len(m), z[m], MAX_SCATTER_POINTS, SCATTER_EXTREMES)]
            thinned |= len(sel) < len(m)
            keep.append(sel)
            handles.append(Line2D([], [], ls="none", marker="o", ms=3, mew=0, color=colours[j % len(colours)],
                                  label=label))
        sel = np.concatenate(keep)
        sel = sel[np.random.default_rng(0).permutation(len(sel))]
        ax.scatter(tt[sel] - t0, z[sel], s=3, c=np.asarray(colours, dtype=object)[comp[sel] % len(colours)].tolist(),
                   linewidths=0, zorder=2)
        n_bad = int(refused.sum())
        if n_bad:
            m = np.flatnonzero(refused & finite)
            bad = m[decimate_scatter(len(m), z[m], MAX_SCATTER_POINTS)]
            thinned |= len(bad) < len(m)
            n_upd = len(np.unique(tt[refused]))
            ups = f"{n_upd} update{'s' if n_upd > 1 else ''}"
            what = f"{n_bad} row{'s' if n_bad > 1 else ''} in {ups}" if labels == [SATELLITE_ROWS] else ups
            ax.plot(tt[bad] - t0, z[bad], "x", ms=4, mew=1.0, color="tab:red", zorder=3)
            handles.append(Line2D([], [], ls="none", marker="x", ms=4, mew=1.0, color="tab:red",
                                  label=f"rejected ({what})"))
        ax.axhline(3, color="k", lw=0.5, ls="--")
        ax.axhline(-3, color="k", lw=0.5, ls="--")
        handles.append(Line2D([], [], color="k", lw=0.5, ls="--", label="±3"))
        ax.set_ylabel(f"{k}\nnu / sigma")
        zf = np.abs(z[finite])
        zmax = float(zf.max()) if zf.size else 0.0
        if zmax > 30:  # decades: a symlog axis, linear within the gate's +-3
            lim = 10 ** (np.log10(zmax) + 0.15)  # the worst point inside, not on the frame
            ax.set_yscale("symlog", linthresh=3.0, linscale=1.0)
            ax.set_ylim(-lim, lim)
            _symlog_ticks(ax, lim, 3.0)
        else:
            lim = max(8.0, 1.05 * zmax)  # the whole range, the worst case included
            ax.set_ylim(-lim, lim)
        # beside the frame: inside it, it hid points
        ax.legend(handles=handles + _outage_patch(res.windows), fontsize=7, loc="upper left",
                  bbox_to_anchor=(1.005, 1.0), frameon=False)
        ax.grid(alpha=0.3)
        _shade(ax, res.windows, t0)
    axes[0, 0].set_title("normalised innovations (dashed: ±3; x: refused by the gate)" + (
        f"\nthinned to at most {MAX_SCATTER_POINTS} points per component, each time bin's extremes kept"
        if thinned else ""))
    axes[-1, 0].set_xlabel("time after first GNSS fix [s]")
    fig.tight_layout()
    return save_figure(fig, path)


def _biases(c, path, plt):
    res, fwd, t0 = c.res, c.fwd, c.t0
    # sensor-error estimates, in the datasheet units of the report (deg/h, mg)
    fig, axes = plt.subplots(2, 1, figsize=(11, 6), sharex=True)
    bg = [fwd.extra[f"bg_{a}_rad_s"] for a in "xyz"]
    ba = [fwd.extra[f"ba_{a}_m_s2"] for a in "xyz"]
    k = _thin(len(fwd.time), bg + ba)  # a spike of an estimate is kept (an even stride could step over it)
    tt = fwd.time[k] - t0
    for a in "xyz":
        axes[0].plot(tt, fwd.extra[f"bg_{a}_rad_s"][k] / DEG_PER_HOUR, lw=0.8, label=a)
        axes[1].plot(tt, fwd.extra[f"ba_{a}_m_s2"][k] / MILLI_G, lw=0.8, label=a)
    axes[0].set_ylabel("gyro bias [deg/h]")
    axes[1].set_ylabel("accel bias [mg]")
    for ax in axes:
        ax.grid(alpha=0.3)
        h, lab = ax.get_legend_handles_labels()
        patch = _outage_patch(res.windows)
        ax.legend(h + patch, lab + [p.get_label() for p in patch], fontsize=8, loc="upper left",
                  bbox_to_anchor=(1.005, 1.0), frameon=False)  # beside the frame: inside it, it hid a line
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
