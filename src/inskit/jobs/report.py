"""A self-contained HTML report of one navigate run folder.

:func:`build_report` reads what ``inskit navigate`` wrote (``summary.json``,
``solution_forward.csv`` and ``solution_smoothed.csv``, and when present
``innovations.csv`` and ``config_used.json``) and writes ONE HTML page: the
health verdict with its reasons and warnings, a table of the key figures, the
track on a plain local east/north map, the position/velocity/attitude sigmas,
the innovations normalised by their sigma with the +-3 gate, the sensor-error
estimates with their sigmas, the outage table and the configuration used.

Why plotly rather than bokeh
----------------------------
* plotly ships its whole JavaScript library as one bundle that can be
  **inlined** into the page, so the report opens with networking off: no
  CDN, no tile server, nothing fetched.  Bokeh's inline resources work too but
  come as several bundles and extensions (tables, widgets) to keep in step.
* Its ``scatter`` traces are SVG, not WebGL (``scattergl``), so they draw in
  headless and GPU-less browsers and print as vectors.
* Hover, box zoom and pan come with every figure, and subplots share one time
  axis through ``matches``; across figures a few lines of inline script pass
  the time range on (one linked time axis for the whole page).

Long series are decimated to at most :data:`MAX_POINTS` points per trace by
keeping the minimum and the maximum of every bin (:func:`decimate`), so the
worst case is never clipped.

The page's weight is plotly.js (4.56 MB of plotly 5.24's bundle; the
figures' data of the smoothed drive_0708 run is 0.5 MB).  It is inlined
gzip-compressed and base64-encoded (1.77 MB) and unpacked by the browser's
``DecompressionStream`` (Chrome and Edge 80, Firefox 113, Safari 16.4 on)
before the figures are drawn from their JSON (:data:`_LOADER`); a browser
without it says so in place of the figures, and the tables stay readable.
The smoothed drive_0708 report went from 5.04 MB to about 2.2 MB.
"""

from __future__ import annotations

import base64
import functools
import gzip
import html
import json
import time
from pathlib import Path

import numpy as np

from .. import earth
from ..errors import InputError
from ..files import write_text
from ..units import DEG

#: most points drawn per trace (min/max decimation above this)
MAX_POINTS = 5000

#: bins of the min/max envelope of a long time series (two points a bin)
TIME_SERIES_BINS = 600

#: points per track trace and per innovation trace
TRACK_POINTS = 3000
INNOVATION_POINTS = 2000

#: reasons and warnings listed open at the top of the page; the rest folded under one line
HEADER_ITEMS = 12

#: a sigma panel spanning more than this ratio (largest / smallest) has a log axis
SIGMA_LOG_SPAN = 100.0

#: measurement names that carry GNSS (their update times mark the fixes)
GNSS_MEASUREMENTS = ("gnss_pos", "gnss_vel", "pseudorange", "pseudorange_rate")

_VERDICT_COLOURS = {"healthy": ("#1b5e20", "#e8f5e9"), "suspect": ("#8a5a00", "#fff4d6"),
                    "unhealthy": ("#b71c1c", "#fdecea")}


# --- data ------------------------------------------------------------------------
def decimate(n, ys, max_points=MAX_POINTS):
    """Indices that keep at most ``max_points`` of ``n`` samples and, for every
    series in ``ys``, the minimum and maximum of each bin (the extremes of the
    whole series included), plus the first and last sample.

    Parameters
    ----------
    n : int
        Number of samples.
    ys : sequence of (n,) ndarray
        Series whose extremes must survive (NaN ignored).
    max_points : int
        Upper bound on the number of indices returned.

    Returns
    -------
    (m,) ndarray of int
        Sorted unique indices, ``m <= max_points``.
    """
    if n <= max_points:
        return np.arange(n)
    ys = [np.asarray(y, float) for y in ys] or [np.arange(n, dtype=float)]
    nbins = max(1, (max_points - 2) // (2 * len(ys)))
    size = -(-n // nbins)
    pad = nbins * size - n
    keep = [np.array([0, n - 1])]
    starts = np.arange(nbins) * size
    for y in ys:
        yp = np.concatenate([y, np.full(pad, np.nan)]).reshape(nbins, size)
        ok = ~np.all(np.isnan(yp), axis=1)
        if not ok.any():
            continue
        lo = np.where(np.isnan(yp), np.inf, yp).argmin(axis=1)
        hi = np.where(np.isnan(yp), -np.inf, yp).argmax(axis=1)
        keep += [(starts + lo)[ok], (starts + hi)[ok]]
    idx = np.unique(np.concatenate(keep))
    return idx[idx < n]


def decimate_scatter(n, y, max_points=MAX_POINTS, extremes=None):
    """Indices of at most ``max_points`` of ``n`` scattered samples ``y``
    that show both their extremes and their bulk: ``extremes`` points
    (default half) are the minimum and maximum of each bin
    (:func:`decimate`), the rest an even stride over all samples.  The
    extremes alone draw a cloud of innovations as two bands at its edges,
    none near zero where most lie (the 8 h drive's 26 000 fixes looked
    bimodal at +-2 sigma)."""
    if n <= max_points:
        return np.arange(n)
    ext = decimate(n, [y], max_points // 2 if extremes is None else min(int(extremes), max_points))
    rest = np.linspace(0, n - 1, max(0, max_points - len(ext))).astype(np.int64)
    return np.unique(np.concatenate([ext, rest]))


def envelope(t, y, nbins):
    """Min/max envelope of ``y(t)`` on ``nbins`` equal time bins: two values a
    bin (its minimum, then its maximum), drawn at the quarter and three-quarter
    points of the bin, so a trace needs only ``x0, dx`` and the values.  An
    empty bin gives NaN (a gap, as in the data).

    Parameters
    ----------
    t : (n,) ndarray
        Increasing times [s].
    y : (n,) ndarray
        Values (NaN ignored).
    nbins : int
        Number of bins; the result has ``2 * nbins`` values.

    Returns
    -------
    x0, dx : float
        Time of the first value and the spacing [s].
    v : (2 * nbins,) ndarray
        Minimum and maximum of each bin, interleaved.
    """
    t, y = np.asarray(t, float), np.asarray(y, float)
    w = (t[-1] - t[0]) / nbins if t[-1] > t[0] else 1.0
    k = np.minimum(((t - t[0]) / w).astype(np.int64), nbins - 1)
    lo = np.full(nbins, np.inf)
    hi = np.full(nbins, -np.inf)
    ok = ~np.isnan(y)
    np.minimum.at(lo, k[ok], y[ok])
    np.maximum.at(hi, k[ok], y[ok])
    v = np.column_stack([lo, hi]).reshape(-1)
    v[~np.isfinite(v)] = np.nan
    return t[0] + 0.25 * w, 0.5 * w, v


def _round(x, digits=5):
    """Round to ``digits`` significant figures of the series' largest value
    (short JSON; NaN kept)."""
    x = np.asarray(x, float)
    finite = np.isfinite(x)
    if not finite.any():
        return x
    m = np.max(np.abs(x[finite]))
    d = digits - 1 - (int(np.floor(np.log10(m))) if m > 0 else 0)
    return np.round(x, max(d, 0) if d > 0 else d)


def _read_json(path, what):
    try:
        text = Path(path).read_text()
    except OSError as exc:
        raise InputError(f"{path}: cannot read {what} ({exc.strerror or exc})") from None
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: line {exc.lineno}: not valid JSON ({exc.msg}); expected the complete {what} "
                         f"(truncated or damaged file?)") from None
    if not isinstance(obj, dict):
        raise InputError(f"{path}: expected a JSON object ({what}), got {type(obj).__name__}")
    return obj


def _is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def check_summary(s: dict, path) -> None:
    """Refuse a run summary whose parts the report reads are not of the
    shape navigate writes (a summary.json edited by hand, or damaged into
    other valid JSON): every key ending in ``_m`` or ``_s``, at the top, in
    ``forward``, in each ``outage_table`` row and each measurement's
    figures, a number or null; ``outage_table`` a list of objects with
    numeric ``start_s`` and ``end_s``; ``health``, ``measurements``,
    ``final_estimates`` and ``forward`` objects (each measurement and
    estimate an object, an estimate's ``values`` and ``sigma`` lists of
    numbers), ``health``'s ``reasons`` and ``warnings`` lists.  Such a file
    was an internal error (``health: "x"``: 'str' object has no attribute
    'get'), or a page without the outages (``outage_table: {}``)."""
    def kind(v):
        return ("null" if v is None else "true/false" if isinstance(v, bool) else "a number" if _is_number(v)
                else "text" if isinstance(v, str) else "a list" if isinstance(v, list) else "an object")

    def refuse(key, v, expected):
        shown = json.dumps(v)
        shown = shown if len(shown) <= 40 else shown[:37] + "..."
        raise InputError(f"{path}: {key} is {kind(v)} ({shown}) where navigate writes {expected}: a damaged or "
                         "hand-edited summary.json? (run navigate again to write it)")

    def numbers(obj, where):
        for k, v in obj.items():
            if (k.endswith("_m") or k.endswith("_s")) and v is not None and not _is_number(v):
                refuse(f"{where}{k}", v, "a number or null")

    def objects(key, v, inner=False):
        if v is None:
            return {}
        if not isinstance(v, dict):
            refuse(key, v, "an object")
        for name, x in v.items():
            if inner and not isinstance(x, dict):
                refuse(f"{key}.{name}", x, "an object")
        return v

    numbers(s, "")
    numbers(objects("forward", s.get("forward")), "forward.")
    for name, m in objects("measurements", s.get("measurements"), inner=True).items():
        numbers(m, f"measurements.{name}.")
        if m.get("used") is not None and not _is_number(m["used"]):
            refuse(f"measurements.{name}.used", m["used"], "a count")
    h = objects("health", s.get("health"))
    for k in ("reasons", "warnings"):
        if h.get(k) is not None and not isinstance(h[k], list):
            refuse(f"health.{k}", h[k], "a list")
    for name, m in objects("health.measurements", h.get("measurements"), inner=True).items():
        for k in ("mean_nis", "dof"):
            if m.get(k) is not None and not _is_number(m[k]):
                refuse(f"health.measurements.{name}.{k}", m[k], "a number or null")
    for name, e in objects("final_estimates", s.get("final_estimates"), inner=True).items():
        for k in ("values", "sigma"):
            x = e.get(k)
            if x is not None and not (isinstance(x, list) and all(v is None or _is_number(v) for v in x)):
                refuse(f"final_estimates.{name}.{k}", x, "a list of numbers")
    rows = s.get("outage_table")
    if rows is not None and not isinstance(rows, list):
        refuse("outage_table", rows, "a list of outages")
    for i, r in enumerate(rows or []):
        if not isinstance(r, dict):
            refuse(f"outage_table[{i}]", r, "an object")
        for k in ("start_s", "end_s"):
            if not _is_number(r.get(k)):
                refuse(f"outage_table[{i}].{k}", r.get(k), "a number")
        numbers(r, f"outage_table[{i}].")


def read_innovations(path, counts=None):
    """``innovations.csv`` as a dict of name -> dict of arrays (``t, row, nu,
    sigma, accepted``), or None if the file is absent.

    A file cut short is refused, not plotted as if whole: one whose last
    line has no line end (cut mid-row: its fields may still parse), or, with
    ``counts`` (the run summary's ``measurements``: per name ``used``), one
    holding fewer used updates of a measurement (distinct times of accepted
    rows) than the run made."""
    import pandas as pd

    path = Path(path)
    if not path.exists():
        return None
    try:
        df = pd.read_csv(path)
    except Exception as exc:  # pandas raises several types for a damaged CSV
        raise InputError(f"{path}: not a readable CSV table ({exc})") from None
    need = ["measurement", "t", "row", "nu", "sigma", "accepted"]
    missing = [c for c in need if c not in df.columns]
    if missing:
        raise InputError(f"{path}: line 1: missing column(s) {', '.join(missing)}; expected {', '.join(need)}")
    blank = df[need].isna().any(axis=1).to_numpy()
    if blank.any():  # a file cut short (a copy interrupted, a disk filled) or edited: not plotted as if whole
        i = int(np.argmax(blank))
        from ..io.csv_formats import data_line

        raise InputError(f"{path}: line {data_line(path, i)}: empty field(s) in {', '.join(c for c in need if pd.isna(df[c].iloc[i]))}"
                         f"{' (the file ends mid-row: cut short?)' if i == len(df) - 1 else ''}")
    with open(path, "rb") as fh:
        fh.seek(0, 2)
        if fh.tell() > 0:
            fh.seek(-1, 2)
            if fh.read(1) != b"\n":
                raise InputError(f"{path}: the last line has no line end: the file seems cut short (a copy "
                                 "interrupted, a disk filled); run navigate again or copy the folder again")
    for name, c in (counts or {}).items():
        want = int((c or {}).get("used", 0) or 0)  # updates used: each at its own time (tight coupling's rejected
        if not want:                               # satellites share their epoch's time)
            continue
        have = int(df.loc[(df["measurement"] == name) & (df["accepted"] == 1), "t"].nunique())
        if have < want:
            raise InputError(f"{path}: holds {have} used update(s) of {name} where the run's summary.json counts "
                             f"{want}: the file seems cut short; run navigate again or copy the folder again")
    out = {}
    for name, g in df.groupby("measurement", sort=False):
        out[str(name)] = {c: g[c].to_numpy(float) for c in ("t", "row", "nu", "sigma", "accepted")}
        # what each row is (a satellite, an axis), in files that say it
        out[str(name)]["label"] = (g["label"].fillna("").astype(str).to_numpy() if "label" in df.columns
                                   else g["row"].astype(int).astype(str).to_numpy())
    return out


def _find_fix_file(run_dir, cfg, config_dir=None):
    """The GNSS fix file named in ``config_used.json`` if it can be found (its
    path is relative to the config file, which the run folder does not record:
    try the folder the default ``output.dir`` implies, the run folder, its
    parent and the working directory)."""
    g = (cfg or {}).get("gnss") or {}
    f = g.get("file")
    if not f:
        return None
    p = Path(f)
    if p.is_absolute():
        return p if p.exists() else None
    bases = [Path(config_dir)] if config_dir else []  # recorded by navigate in summary.json
    out = Path(str(((cfg or {}).get("output") or {}).get("dir") or ""))
    rd = Path(run_dir).resolve()
    if out.parts and rd.parts[-len(out.parts):] == out.parts:
        bases.append(Path(*rd.parts[:-len(out.parts)]))
    bases += [rd, rd.parent, Path.cwd()]
    for b in bases:
        if (b / p).exists():
            return b / p
    return None


def _read_fixes(path, cfg):
    """``(fixes, error)``: fix times and lla from the GNSS file (rtklib .pos
    or our CSV) and None, or None and the reader's message."""
    from .. import io
    from ..io.rtklib import read_pos

    g = cfg.get("gnss") or {}
    try:
        if g.get("format") == "rtklib-pos":
            gnss, _ = read_pos(path, quality=tuple(g.get("quality") or (1, 2)),
                                  time_offset_s=float(g.get("time_offset_s") or 0.0))
            return (gnss.time, gnss.lla), None
        d = io.read_gnss(path)
        return (d.time + float(g.get("time_offset_s") or 0.0), d.lla), None
    except InputError as exc:
        return None, str(exc)


def _infer_t0(summary, innov, t_sol):
    """Time of the first GNSS fix (the zero of the outage table), inferred
    from the GNSS update times when the fix file is not at hand: the shift
    that puts each outage-table end fix on an update and no update inside the
    windows.  Returns (t0, how)."""
    tg = np.unique(np.concatenate([innov[m]["t"] for m in GNSS_MEASUREMENTS if innov and m in innov] or [[]]))
    rows = summary.get("outage_table") or []
    if len(tg) and rows:
        fix = np.array([r["fix_time_s"] for r in rows], float)
        a = np.array([r["start_s"] for r in rows], float)
        b = np.array([r["end_s"] for r in rows], float)
        cand = tg - fix[0]
        best, score = None, -1
        for c in cand[:2000]:
            hit = np.abs(tg[np.clip(np.searchsorted(tg, c + fix), 0, len(tg) - 1)] - (c + fix)) < 0.02
            lo, hi = np.searchsorted(tg, c + a + 0.02), np.searchsorted(tg, c + b - 0.02)
            s = int(np.sum(hit & (hi <= lo)))
            if s > score:
                best, score = c, s
        if score == len(rows):
            return float(best), "first GNSS fix (inferred from the GNSS update times and the outage table)"
    if len(tg):
        return float(tg[0]), "first GNSS update"
    return float(t_sol[0]), "start of the solution"


class _Run:
    """Everything the report needs from one run folder."""

    def __init__(self, run_dir):
        from .. import io

        d = Path(run_dir)
        if not d.is_dir():
            raise InputError(f"{d}: not a folder (expected a navigate run folder holding summary.json)")
        if not (d / "summary.json").exists():
            raise InputError(f"{d}: not a navigate run folder: summary.json is missing (run `inskit navigate "
                             f"CONFIG --out {d}` first)")
        self.dir = d
        self.summary = _read_json(d / "summary.json", "run summary (summary.json)")
        check_summary(self.summary, d / "summary.json")

        def solution(stem):  # the full-rate Parquet when there is one, else the CSV
            for ext in (".parquet", ".csv"):
                if (d / f"{stem}{ext}").exists():
                    # navigate's own file: a filter that diverged beyond 100 km of height or the escape
                    # speed wrote it so, and the report is where that is to be seen (the form is checked)
                    return io.read_solution(d / f"{stem}{ext}", ranges=False)
            return None

        self.forward = solution("solution_forward")
        if self.forward is None:
            raise InputError(f"{d}: solution_forward.parquet or .csv is missing (expected beside summary.json)")
        self.smoothed = solution("solution_smoothed")
        if self.smoothed is None and self.summary.get("solution") == "smoothed":
            # the key figures and the outage table are the smoother's: a page of the forward filter alone
            # under them passed the folder for whole
            raise InputError(f"{d}: solution_smoothed.parquet or .csv is missing, and summary.json says the run "
                             "was smoothed (its figures are the smoother's); copy the folder again, or run "
                             "navigate --smooth again")
        self.innov = read_innovations(d / "innovations.csv", self.summary.get("measurements"))
        self.config = _read_json(d / "config_used.json", "configuration (config_used.json)") \
            if (d / "config_used.json").exists() else None
        self.fixes, self.fix_file, self.fix_error = None, None, None
        #: the files the report reads: never its output, --force or not (the fix file lies outside the folder)
        self.inputs = [p for p in d.iterdir() if p.is_file() and p.suffix.lower() != ".html"]
        if self.config:
            p = _find_fix_file(d, self.config, self.summary.get("config_dir"))
            if p is not None:
                self.inputs.append(p)
                self.fixes, self.fix_error = _read_fixes(p, self.config)
                self.fix_file = p if self.fixes is not None else None
        if self.summary.get("first_fix_time_s") is not None:  # recorded by navigate
            self.t0, self.t0_how = float(self.summary["first_fix_time_s"]), "first GNSS fix (summary.json)"
        elif self.fixes is not None and len(self.fixes[0]):
            self.t0, self.t0_how = float(self.fixes[0][0]), f"first GNSS fix (from {self.fix_file.name})"
        else:
            self.t0, self.t0_how = _infer_t0(self.summary, self.innov, self.forward.time)
        self.windows = [(self.t0 + r["start_s"], self.t0 + r["end_s"]) for r in self.summary.get("outage_table") or []]
        self.name = str(self.summary.get("name") or d.name)


# --- figures ---------------------------------------------------------------------
def _layout(fig, height, title):
    fig.update_layout(template="plotly_white", height=height, title=dict(text=title, x=0.01, font=dict(size=15)),
                      margin=dict(l=70, r=20, t=50, b=45), legend=dict(orientation="h", y=-0.12),
                      hovermode="closest", font=dict(size=12))
    return fig


def _shade(fig, run, rows):
    for a, b in run.windows:
        for r in range(1, rows + 1):
            fig.add_vrect(x0=a - run.t0, x1=b - run.t0, fillcolor="#9e9e9e", opacity=0.18, line_width=0,
                          layer="below", row=r, col=1)


def _line(go, t, y, name, color, dash=None, legendgroup=None, showlegend=True, nbins=None):
    """A time-series trace: exact up to ``2 * nbins`` samples, else the min/max
    envelope of :func:`envelope` (extremes kept, time to half a bin)."""
    nbins = nbins or TIME_SERIES_BINS
    style = dict(name=name, mode="lines", line=dict(color=color, width=1.2, dash=dash), legendgroup=legendgroup,
                 showlegend=showlegend)
    if len(t) <= 2 * nbins:
        return go.Scatter(x=_round(t, 6), y=_round(y, 4), **style), False
    x0, dx, v = envelope(t, y, nbins)
    return go.Scatter(x0=float(np.round(x0, 4)), dx=float(dx), y=_round(v, 4), **style), True


def _fig_track(run, go):
    fig = go.Figure()
    ref = run.forward.lla[0]
    dec = False
    for sol, label, colour in ((run.forward, "forward filter", "#1f77b4"),
                               (run.smoothed, "RTS smoother", "#2ca02c")):
        if sol is None:
            continue
        ned = earth.lla_to_ned(sol.lla, ref)
        idx = decimate(len(sol.time), [ned[:, 0], ned[:, 1]], TRACK_POINTS)
        dec |= len(idx) < len(sol.time)
        fig.add_trace(go.Scatter(x=_round(ned[idx, 1], 6), y=_round(ned[idx, 0], 6), mode="lines", name=label,
                                 line=dict(color=colour, width=1.3),
                                 hovertemplate="E %{x:.2f} m, N %{y:.2f} m"))
        if run.windows and label == "forward filter":
            t = sol.time[idx]
            xs, ys = [], []
            for a, b in run.windows:
                m = (t >= a) & (t <= b)
                xs += list(_round(ned[idx, 1])[m]) + [None]
                ys += list(_round(ned[idx, 0])[m]) + [None]
            fig.add_trace(go.Scatter(x=xs, y=ys, mode="lines", name="forward, in GNSS outage",
                                     line=dict(color="#d62728", width=2.4)))
    if run.fixes is not None:
        tf, lla = run.fixes
        ned = earth.lla_to_ned(lla, ref)
        out = np.zeros(len(tf), bool)
        for a, b in run.windows:
            out |= (tf >= a) & (tf <= b)
        for m, label, colour in ((~out, f"GNSS fixes ({run.fix_file.name})", "#7f7f7f"),
                                 (out, "GNSS fixes withheld (outages)", "#ff7f0e")):
            if m.any():
                k = np.flatnonzero(m)
                k = k[decimate(len(k), [ned[k, 0], ned[k, 1]], TRACK_POINTS)]
                fig.add_trace(go.Scatter(x=_round(ned[k, 1]), y=_round(ned[k, 0]), mode="markers", name=label,
                                         marker=dict(size=3, color=colour)))
    elif run.innov:
        for name in GNSS_MEASUREMENTS[:1] + GNSS_MEASUREMENTS[2:3]:
            if name not in run.innov:
                continue
            v = run.innov[name]
            tu, inv = np.unique(v["t"], return_inverse=True)
            acc = np.zeros(len(tu), bool)  # an update is used when any of its rows is (one satellite may be refused)
            np.logical_or.at(acc, inv, v["accepted"] > 0.5)
            s = run.forward.interpolate(tu)
            ned = earth.lla_to_ned(s.lla, ref)
            for m, label, colour in ((acc, f"{name} updates (solution at the update)", "#7f7f7f"),
                                     (~acc, f"{name} rejected", "#ff7f0e")):
                if m.any():
                    k = np.flatnonzero(m)
                    k = k[decimate(len(k), [ned[k, 0], ned[k, 1]], TRACK_POINTS)]
                    fig.add_trace(go.Scatter(x=_round(ned[k, 1]), y=_round(ned[k, 0]), mode="markers", name=label,
                                             marker=dict(size=3, color=colour)))
            break
    # the fixes under the solution's lines (drawn first), the lines first in the legend: drawn after
    # them, the grey and orange dots of a long drive covered the forward line and its red outage stretches
    # (the smoother, close to the fixes, under the forward filter and its outage stretches, which it hid)
    lines = [t for t in fig.data if t.mode == "lines"]
    marks = [t for t in fig.data if t.mode != "lines"]
    for i, t in enumerate(lines + marks):
        t.legendrank = 1000 + i
    fig.data = tuple(marks + sorted(lines, key=lambda t: t.name != "RTS smoother"))
    _layout(fig, 640, "Track: east/north from the first point [m]")
    fig.update_xaxes(title_text="east [m]")
    fig.update_yaxes(title_text="north [m]", scaleanchor="x", scaleratio=1)
    return fig, dec


def _fig_sigmas(run, go, make_subplots):
    blocks = (("position", ("sigma_n_m", "sigma_e_m", "sigma_d_m"), 1.0, "m"),
              ("velocity", ("sigma_vn_m_s", "sigma_ve_m_s", "sigma_vd_m_s"), 1.0, "m/s"),
              ("attitude", ("sigma_att_n_rad", "sigma_att_e_rad", "sigma_att_d_rad"), 1 / DEG, "deg"))
    blocks = [b for b in blocks if all(c in run.forward.extra for c in b[1])]
    if not blocks:
        return None, False
    fig = make_subplots(rows=len(blocks), cols=1, shared_xaxes=True, vertical_spacing=0.05)
    colours = ("#1f77b4", "#ff7f0e", "#2ca02c")
    dec = False
    for r, (what, cols, k, unit) in enumerate(blocks, start=1):
        for sol, label, dash in ((run.forward, "forward", None), (run.smoothed, "smoothed", "dot")):
            if sol is None:
                continue
            for c, axis, colour in zip(cols, ("N", "E", "D"), colours):
                tr, d = _line(go, sol.time - run.t0, sol.extra[c] * k, f"{label} {axis}", colour, dash,
                              legendgroup=f"{label}{axis}", showlegend=r == 1)
                dec |= d
                fig.add_trace(tr, row=r, col=1)
        v = np.concatenate([sol.extra[c] for sol in (run.forward, run.smoothed) if sol is not None for c in cols]) * k
        v = v[np.isfinite(v) & (v > 0)]
        if len(v) and v.max() > SIGMA_LOG_SPAN * v.min():
            # decades (centimetres aided, metres at an outage's end): a linear axis showed the aided
            # sigmas as a line on zero, the figure a filter is judged by
            fig.update_yaxes(title_text=f"{what} 1σ [{unit}] (log)", type="log", row=r, col=1)
        else:
            fig.update_yaxes(title_text=f"{what} 1σ [{unit}]", rangemode="tozero", row=r, col=1)
    _shade(fig, run, len(blocks))
    _layout(fig, 250 * len(blocks) + 80, "Filter sigmas (1σ, N/E/D; grey: GNSS outages)")
    fig.update_xaxes(title_text=f"time after {run.t0_how.split(' (')[0]} [s]", row=len(blocks), col=1)
    return fig, dec


def _fig_innovations(run, go, make_subplots):
    if not run.innov:
        return None, False
    names = list(run.innov)
    fig = make_subplots(rows=len(names), cols=1, shared_xaxes=True, vertical_spacing=0.2 / max(1, len(names) - 1)
                        if len(names) > 1 else 0.0, subplot_titles=names)
    dec = False
    for r, name in enumerate(names, start=1):
        v = run.innov[name]
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.where(v["sigma"] > 0, v["nu"] / v["sigma"], np.nan)
        # rows that are satellites (row j is another satellite from one update to the next) hover by name
        lab, rows = v["label"], v["row"].astype(np.int64)
        _, first, inv = np.unique(rows, return_index=True, return_inverse=True)
        by_label = bool(len(lab)) and bool((lab != "").all()) and bool((lab != lab[first][inv]).any())
        for m, label, colour in ((v["accepted"] > 0.5, "accepted", "#1f77b4"),
                                 (v["accepted"] <= 0.5, "rejected", "#d62728")):
            k = np.flatnonzero(m & np.isfinite(z))
            if not len(k):
                continue
            kk = k[decimate_scatter(len(k), z[k], INNOVATION_POINTS)]
            dec |= len(kk) < len(k)
            fig.add_trace(go.Scatter(x=_round(v["t"][kk] - run.t0, 6), y=_round(z[kk], 3), mode="markers",
                                     name=label, legendgroup=label, showlegend=r == 1,
                                     marker=dict(size=3, color=colour),
                                     customdata=(v["label"][kk] if by_label else v["row"][kk].astype(int)),
                                     hovertemplate="t %{x:.2f} s, ν/σ %{y:.2f}, "
                                                   + ("%{customdata}" if by_label else "row %{customdata}")),
                          row=r, col=1)
        for g in (-3, 3):
            fig.add_hline(y=g, line=dict(color="#555", width=1, dash="dash"), row=r, col=1)
        # the gate lines inside the frame with room above: on the frame's edge, the next panel's
        # title was written over the dashed line
        fig.update_yaxes(title_text="ν/σ", autorangeoptions=dict(include=[-4.5, 4.5]), row=r, col=1)
    _shade(fig, run, len(names))
    _layout(fig, 200 * len(names) + 100, "Innovations normalised by their sigma (dashed: ±3 gate)")
    fig.update_xaxes(title_text=f"time after {run.t0_how.split(' (')[0]} [s]", row=len(names), col=1)
    return fig, dec


#: estimate blocks: column prefix, title, factor from the file's unit to the shown one, shown unit
_ESTIMATES = (("bg", "gyro bias", 1 / DEG * 3600, "deg/h"), ("ba", "accel bias", 1e3 / 9.80665, "mg"),
              ("sg", "gyro scale factor", 1e2, "%"), ("sa", "accel scale factor", 1e2, "%"))


def _estimate_series(run):
    ex = run.forward.extra
    fin = run.summary.get("final_estimates") or {}
    out = []
    for key, title, k, unit in _ESTIMATES:
        cols = [c for c in ex if c.startswith(key + "_") and c[len(key) + 1:len(key) + 2] in "xyz"]
        if cols:
            out.append((key, title, k, unit, cols, (fin.get(key) or {}).get("sigma")))
    if "clock_bias_m" in ex:
        sig = (fin.get("clock") or {}).get("sigma")
        out.append(("clock_b", "receiver clock bias", 1.0, "m", ["clock_bias_m"], sig[:1] if sig else None))
    if "clock_drift_m_s" in ex:
        sig = (fin.get("clock") or {}).get("sigma")
        out.append(("clock_d", "receiver clock drift", 1.0, "m/s", ["clock_drift_m_s"],
                    sig[1:2] if sig and len(sig) > 1 else None))
    return out


def _fig_estimates(run, go, make_subplots):
    series = _estimate_series(run)
    if not series:
        return None, False
    fig = make_subplots(rows=len(series), cols=1, shared_xaxes=True, vertical_spacing=0.04,
                        subplot_titles=[f"{s[1]} [{s[3]}]" for s in series])
    colours = ("#1f77b4", "#ff7f0e", "#2ca02c")
    t = run.forward.time - run.t0
    dec = False
    for r, (key, title, k, unit, cols, sig) in enumerate(series, start=1):
        for j, c in enumerate(cols):
            # named as shown (the file's column, e.g. bg_x_rad_s, named the unit it is not drawn in)
            name = f"{title} {c[len(key) + 1]}" if len(cols) > 1 else title
            tr, d = _line(go, t, run.forward.extra[c] * k, name, colours[j % 3], showlegend=True)
            dec |= d
            fig.add_trace(tr, row=r, col=1)
            if sig is not None and j < len(sig) and sig[j] is not None:
                fig.add_trace(go.Scatter(x=[float(t[-1])], y=[float(run.forward.extra[c][-1] * k)], mode="markers",
                                         marker=dict(color=colours[j % 3], size=7, symbol="diamond"),
                                         error_y=dict(type="data", array=[float(sig[j]) * k], thickness=2,
                                                      width=6),
                                         name=f"{name} final ±1σ", showlegend=False,
                                         hovertemplate=f"final {name}: %{{y:.4g}} ± {float(sig[j]) * k:.3g} {unit}"),
                              row=r, col=1)
        fig.update_yaxes(title_text=unit, row=r, col=1)
    _shade(fig, run, len(series))
    _layout(fig, 200 * len(series) + 100, "Sensor-error estimates (final value ±1σ at the right end)")
    fig.update_xaxes(title_text=f"time after {run.t0_how.split(' (')[0]} [s]", row=len(series), col=1)
    return fig, dec


# --- page ------------------------------------------------------------------------
_CSS = """
*{box-sizing:border-box}
body{margin:0;background:#fff;color:#212121;font:14px/1.45 system-ui,-apple-system,"Segoe UI",Roboto,sans-serif}
main{max-width:1200px;margin:0 auto;padding:16px 20px 40px}
h1{font-size:24px;margin:8px 0 4px}
h2{font-size:18px;margin:28px 0 8px;border-bottom:1px solid #ddd;padding-bottom:4px}
.verdict{display:inline-block;padding:3px 12px;border-radius:4px;font-weight:600;border:1px solid}
.meta{color:#555}
table{border-collapse:collapse;margin:6px 0;font-variant-numeric:tabular-nums}
th,td{border:1px solid #ddd;padding:3px 8px;text-align:right}
th{background:#f5f5f5}
td.l,th.l{text-align:left}
.figure{margin:12px 0;break-inside:avoid;page-break-inside:avoid}
.note{color:#555;font-size:12px}
pre{background:#f8f8f8;border:1px solid #ddd;padding:8px;overflow:auto;font-size:12px;max-height:480px}
.cols{display:flex;flex-wrap:wrap;gap:24px}
@media print{
  body{font-size:11px}
  main{max-width:none;padding:0}
  .modebar-container{display:none!important}
  pre{max-height:none;overflow:visible;white-space:pre-wrap}
  h2{break-after:avoid;page-break-after:avoid}
  .verdict,th{-webkit-print-color-adjust:exact;print-color-adjust:exact}
}
"""

# unpack plotly.js (inlined gzip + base64), draw every figure from its JSON, then link the time
# axes across the time figures and record where each figure was drawn (data-* attributes, for checks
# of the rendered page)
_LOADER = """
(function(){
  function say(text){
    document.querySelectorAll('.plotly-graph-div').forEach(function(d){
      d.innerHTML = '<p class=note>' + text + '</p>'; d.style.height = 'auto'; });
  }
  function mark(){
    var ok = 0;
    document.querySelectorAll('.figure').forEach(function(f){
      var r = f.getBoundingClientRect();
      f.setAttribute('data-top', Math.round(r.top + window.scrollY));
      f.setAttribute('data-height', Math.round(r.height));
      if (f.querySelector('.main-svg')) ok += 1;
    });
    document.body.setAttribute('data-figures-drawn', ok);
  }
  function link(){
    var figs = Array.prototype.slice.call(document.querySelectorAll('.tplot .plotly-graph-div'));
    var busy = false;
    figs.forEach(function(src){
      src.on('plotly_relayout', function(ev){
        if (busy) return;
        var upd = null;
        Object.keys(ev).forEach(function(k){
          var m = k.match(/^xaxis\\d*\\.range\\[([01])\\]$/);
          if (m) { upd = upd || {}; upd['xaxis.range[' + m[1] + ']'] = ev[k]; }
          if (/^xaxis\\d*\\.autorange$/.test(k)) { upd = {'xaxis.autorange': true}; }
        });
        if (!upd) return;
        busy = true;
        var p = figs.filter(function(f){ return f !== src; }).map(function(f){ return Plotly.relayout(f, upd); });
        Promise.all(p).then(function(){ busy = false; }, function(){ busy = false; });
      });
    });
  }
  if (typeof DecompressionStream === 'undefined') {
    say('This browser cannot unpack the figures (it has no DecompressionStream: Chrome or Edge 80, '
        + 'Firefox 113, Safari 16.4 or later can). The tables below are complete.');
    mark();
    return;
  }
  var packed = document.getElementById('plotly-js-gzip');
  var bytes = Uint8Array.from(atob(packed.textContent.trim()), function(c){ return c.charCodeAt(0); });
  var stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('gzip'));
  new Response(stream).text().then(function(src){
    window.PlotlyConfig = {MathJaxConfig: 'local'};
    var s = document.createElement('script');
    s.text = src;
    document.head.appendChild(s);
    var template = JSON.parse(document.getElementById('plotly-template').textContent);
    var config = JSON.parse(document.getElementById('plotly-config').textContent);
    var divs = Array.prototype.slice.call(document.querySelectorAll('.plotly-graph-div'));
    return divs.reduce(function(done, div){
      return done.then(function(){
        var spec = JSON.parse(document.getElementById('spec-' + div.id).textContent);
        spec.layout.template = template;
        return Plotly.newPlot(div, spec.data, spec.layout, config);
      });
    }, Promise.resolve());
  }).then(function(){ link(); mark(); }, function(err){
    say('The figures could not be drawn: ' + err);
    mark();
    throw err;
  });
  window.addEventListener('load', function(){ setTimeout(mark, 0); });
})();
"""

#: the plotly figures' configuration (the same for every figure)
_PLOT_CONFIG = {"displaylogo": False, "responsive": True, "modeBarButtonsToRemove": ["toImage"]}


@functools.lru_cache(maxsize=1)
def _packed_plotly_js():
    """plotly.js of the installed plotly, gzip-compressed (mtime 0: the same
    bytes each time) and base64-encoded: 1.77 MB for its 4.56 MB."""
    from plotly.offline import get_plotlyjs

    return base64.b64encode(gzip.compress(get_plotlyjs().encode(), 9, mtime=0)).decode("ascii")


def _script_json(obj):
    """JSON for a ``<script type="application/json">`` block (no ``</``
    can close it early)."""
    return json.dumps(obj, separators=(",", ":"), allow_nan=False).replace("</", "<\\/").replace("<!--", "<\\!--")


def _e(x):
    return html.escape(str(x))


def _num(x, fmt=".3f", scale=1.0):
    return "n/a" if x is None else format(float(x) * scale, fmt)


def _length(x):
    """A length [m] as (text, unit): centimetres below a metre (an RTK fit), metres above (a lost filter's
    632 km was '63240570.38 cm')."""
    if x is None:
        return "n/a", "m"
    return (format(float(x) * 100, ".2f"), "cm") if abs(float(x)) < 1.0 else (format(float(x), ".3f"), "m")


def _fit_rows(s):
    """The GNSS-on rows of the summary table: the fit to the fixes the filter
    was fed (not an accuracy), or, when the fixes were only a reference
    (tight coupling), the accuracy against them."""
    if s.get("fixes_fused", True):
        return [("fit to the used fixes, horizontal RMS (not an accuracy)", *_length(s.get("gnss_on_horizontal_rms_m"))),
                ("fit to the used fixes, vertical RMS (not an accuracy)", *_length(s.get("gnss_on_vertical_rms_m"))),
                ("used fixes in the fit", _e(s.get("gnss_on_fixes", "n/a")), "")]
    return [("GNSS on, horizontal RMS against the reference fixes (never fused)",
             _num(s.get("gnss_on_h_vs_reference_fixes_rms_m")), "m"),
            ("GNSS on, vertical RMS against the reference fixes (never fused)",
             _num(s.get("gnss_on_v_vs_reference_fixes_rms_m")), "m"),
            ("reference fixes", _e(s.get("gnss_on_reference_fixes", "n/a")), "")]


def _key_table(s):
    rows = [("outage-end horizontal RMS, against the withheld fixes", _num(s.get("outage_end_horizontal_rms_m")), "m"),
            ("outage-end horizontal median, against the withheld fixes",
             _num(s.get("outage_end_horizontal_median_m")), "m"),
            ("outage-end horizontal max, against the withheld fixes", _num(s.get("outage_end_horizontal_max_m")), "m"),
            ("outage-end vertical RMS, against the withheld fixes", _num(s.get("outage_end_vertical_rms_m")), "m"),
            ("worst-in-outage horizontal RMS, against the withheld fixes",
             _num(s.get("outage_worst_horizontal_rms_m")), "m"),
            *(_fit_rows(s)),
            ("outages", _e(s.get("outages", "n/a")), ""),
            ("IMU epochs", _e(s.get("epochs", "n/a")), ""),
            ("duration", _num(s.get("duration_s"), ".1f"), "s"),
            ("filter states", _e(s.get("states", "n/a")), ""),
            ("run time", _num(s.get("elapsed_s"), ".2f"), "s")]
    if "outages_vs_truth" in s:  # scored against a truth as well
        rows[5:5] = [("outage-end horizontal RMS, against the truth", _num(s.get("outage_end_h_vs_truth_rms_m")), "m"),
                     ("worst-in-outage horizontal RMS, against the truth",
                      _num(s.get("outage_worst_h_vs_truth_rms_m")), "m"),
                     ("GNSS-on horizontal RMS, against the truth", _num(s.get("gnss_on_h_vs_truth_rms_m")), "m")]
    fw = s.get("forward")
    if s.get("solution") == "smoothed" and isinstance(fw, dict):
        rows.insert(5, ("forward filter: outage-end horizontal RMS", _num(fw.get("outage_end_horizontal_rms_m")),
                        "m"))
    body = "".join(f"<tr><td class=l>{a}</td><td>{b}</td><td class=l>{c}</td></tr>" for a, b, c in rows)
    return f"<table><tr><th class=l>figure</th><th>value</th><th class=l>unit</th></tr>{body}</table>"


def _counts_table(s):
    meas = s.get("measurements") or {}
    hm = (s.get("health") or {}).get("measurements") or {}
    if not meas and not hm:
        return ""
    rows = []
    for name in list(meas) + [n for n in hm if n not in meas]:
        m, h = meas.get(name) or {}, hm.get(name) or {}
        rows.append(f"<tr><td class=l>{_e(name)}</td><td>{_e(m.get('used', ''))}</td>"
                    f"<td>{_e(m.get('rejected', ''))}</td><td>{_e(m.get('skipped', ''))}</td>"
                    f"<td>{_e(m.get('rows', ''))}</td><td>{_e(m.get('rows_rejected', ''))}</td>"
                    f"<td>{_num(h.get('mean_nis'), '.2f')}</td><td>{_num(h.get('dof'), '.2f')}</td></tr>")
    return ("<table><tr><th class=l>measurement</th><th>used</th><th>rejected</th><th>skipped</th><th>rows</th>"
            "<th>rows rejected</th><th>mean NIS</th><th>dof</th></tr>" + "".join(rows) + "</table>")


def _outage_table(s, solution):
    rows = s.get("outage_table") or []
    if not rows:
        return "<p>No GNSS outages in this run.</p>"
    truth = "outages_vs_truth" in s
    body = "".join(
        f"<tr><td>{r['k']}</td><td>{r['start_s']:.2f}</td><td>{r['end_s']:.2f}</td>"
        f"<td>{_num(r.get('horizontal_m'))}</td><td>{_num(r.get('vertical_m'))}</td>"
        f"<td>{_num(r.get('worst_horizontal_m'))}</td><td>{_num(r.get('worst_time_s'), '.2f')}</td>"
        f"<td>{_num(r.get('outage_end_along_track_vs_withheld_fixes_m'), '.2f')}</td>"
        f"<td>{_num(r.get('outage_end_cross_track_vs_withheld_fixes_m'), '.2f')}</td>"
        + (f"<td>{_num(r.get('outage_end_h_vs_truth_m'))}</td><td>{_num(r.get('outage_worst_h_vs_truth_m'))}</td>"
           if truth else "") + "</tr>"
        for r in rows)
    note = (f"<p class=note>Errors of the {_e(solution)} solution against the withheld fixes (their noise "
            "included; the end error split along the reference track, + ahead, and across it, + right)"
            + ("; the last two columns against the truth, from the last used fix before the window to the next"
               if truth else "") + "; windows in seconds after the first GNSS fix.</p>")
    return (note + "<table><tr><th>outage</th><th>start [s]</th><th>end [s]</th>"
            "<th>end horiz [m]</th><th>end vert [m]</th><th>worst horiz [m]</th><th>worst at [s]</th>"
            "<th>end along-track [m]</th><th>end cross-track [m]</th>"
            + ("<th>end horiz vs truth [m]</th><th>worst horiz vs truth [m]</th>" if truth else "") + "</tr>"
            + body + "</table>")


#: final estimates shown in datasheet units: key -> (name, factor from the file's unit, shown unit, row names)
_TABLE_UNITS = {"bg": ("gyro bias", 1 / DEG * 3600, "deg/h", "xyz"), "ba": ("accel bias", 1e3 / 9.80665, "mg", "xyz"),
                "sg": ("gyro scale factor", 1e2, "%", "xyz"), "sa": ("accel scale factor", 1e2, "%", "xyz"),
                "mounting": ("mounting", 1 / DEG, "deg", ("pitch", "yaw")), "gnss_err": ("GNSS error", 1.0, "m", "NED"),
                "clock": ("receiver clock", 1.0, ("m", "m/s"), ("bias", "drift"))}


def _estimates_table(s):
    """The final estimates in the units of the plots and of a datasheet
    (deg/h, mg, %, deg): they were in the file's rad/s, m/s^2 and bare
    fractions, 0.000506388 rad_s beside a plot of 104 deg/h."""
    fin = s.get("final_estimates") or {}
    if not fin:
        return ""
    rows = []
    for key, v in fin.items():
        vals, sig = v.get("values") or [], v.get("sigma") or []
        file_unit = v.get("unit", "")
        title, k, unit, names = _TABLE_UNITS.get(key, (key, 1.0, file_unit, None))
        for j, x in enumerate(vals):
            sj = sig[j] if j < len(sig) else None
            u = unit[j] if isinstance(unit, tuple) and j < len(unit) else unit if not isinstance(unit, tuple) else ""
            label = f"{title} {names[j]}" if names and j < len(names) else f"{title} [{j}]"
            rows.append(f"<tr><td class=l>{_e(label)}</td><td class=l>{_e(key)}[{j}]</td><td>{_num(x, '.4g', k)}</td>"
                        f"<td>{_num(sj, '.3g', k)}</td><td class=l>{_e(u)}</td></tr>")
    return ("<table><tr><th class=l>state</th><th class=l>in summary.json</th><th>final value</th><th>1σ</th>"
            "<th class=l>unit</th></tr>" + "".join(rows) + "</table>")


def _config_section(run):
    if run.config is not None:
        return ("<p class=note>From config_used.json (the validated configuration; relative paths are relative to "
                "the configuration file).</p><pre>" + _e(json.dumps(run.config, indent=2)) + "</pre>")
    s = run.summary
    keep = {k: s[k] for k in ("scheme", "solution", "coupling", "states", "imu_time_offset_s", "noise_used",
                              "startup", "rinex", "imu_gaps") if k in s}
    return ("<p class=note>config_used.json is not in the run folder; what summary.json records about the set-up:"
            "</p><pre>" + _e(json.dumps(keep, indent=2)) + "</pre>")


def _header(run):
    s = run.summary
    h = s.get("health") or {}
    verdict = str(h.get("verdict", "unknown"))
    fg, bg = _VERDICT_COLOURS.get(verdict, ("#333", "#eee"))
    lines = [f"<li><b>reason:</b> {_e(r)}</li>" for r in h.get("reasons") or []]
    lines += [f"<li>warning: {_e(w)}</li>" for w in h.get("warnings") or []]
    items = "".join(lines[:HEADER_ITEMS])
    if len(lines) > HEADER_ITEMS:  # a lost filter's dozens of recoveries: folded, the figures still in view
        items += (f"<li><details><summary>{len(lines) - HEADER_ITEMS} more reasons and warnings</summary><ul>"
                  + "".join(lines[HEADER_ITEMS:]) + "</ul></details></li>")
    meta = (f"{_e(s.get('coupling', ''))} coupling, {_e(s.get('scheme', ''))} scheme, "
            f"{_e(s.get('solution', 'forward'))} solution scored; run folder {_e(run.dir.resolve())}")
    return (f"<header><h1>inskit run report: {_e(run.name)}</h1><p class=meta>{meta}</p>"
            f"<p>Health: <span class=verdict id=verdict style=\"color:{fg};background:{bg};border-color:{fg}\">"
            f"{_e(verdict)}</span></p>" + (f"<ul>{items}</ul>" if items else "<p>No reasons or warnings.</p>")
            + "</header>")


def build_report(run_dir, out=None, overwrite=False):
    """Write the HTML report of a navigate run folder.

    Parameters
    ----------
    run_dir : path
        A folder written by ``inskit navigate`` (must hold ``summary.json`` and
        ``solution_forward.csv``).
    out : path, optional
        The HTML file (default ``run_dir/report.html``), written atomically;
        its name ends in ``.html`` or ``.htm``.  Never a file the report reads (the run's own: ``summary.json``, the
        solutions ...; the GNSS fix file its configuration names); an
        existing file only with ``overwrite``.
    overwrite : bool
        Replace an existing ``out`` (``--force``).

    Returns
    -------
    dict
        ``report`` (path), ``bytes``, ``plots`` (figure names, in page order),
        ``seconds``.

    Raises
    ------
    InputError
        Not a run folder, or a damaged ``summary.json`` / CSV.
    """
    t_start = time.perf_counter()
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    from ..files import check_folder_writable, check_outputs

    run = _Run(run_dir)
    out = Path(out) if out is not None else run.dir / "report.html"
    check_outputs([out], run.inputs, overwrite)  # an input named first: that is what matters most
    if out.suffix.lower() not in (".html", ".htm"):  # an HTML page under x.txt or x.csv: refused, as evaluate's plot
        raise InputError(f"{out}: the report is an HTML page: its name must end in .html (or .htm), got "
                         f"{out.suffix or 'no extension'!r}")
    check_folder_writable(out.resolve().parent)  # a folder not there yet: made (the page was built, then lost)
    figs = [("track", "Track", *_fig_track(run, go), False),
            ("sigmas", "Position, velocity and attitude sigmas", *_fig_sigmas(run, go, make_subplots), True),
            ("innovations", "Innovations", *_fig_innovations(run, go, make_subplots), True),
            ("estimates", "Sensor-error estimates", *_fig_estimates(run, go, make_subplots), True)]
    parts, names, any_dec, template = [], [], False, None
    for name, title, fig, dec, timed in figs:
        if fig is None:
            continue
        any_dec |= dec
        spec = json.loads(fig.to_json())  # plotly's encoder (numpy arrays, NaN as null)
        template = spec["layout"].pop("template", None)  # the same for every figure: written once
        height = int(fig.layout.height or 450)
        parts.append(f"<section class=\"figure{' tplot' if timed else ''}\" id=\"sec-{name}\">"
                     f"<h2>{_e(title)}</h2><div id=\"fig-{name}\" class=\"plotly-graph-div\" "
                     f"style=\"height:{height}px; width:100%;\"></div>"
                     f"<script type=\"application/json\" id=\"spec-fig-{name}\">{_script_json(spec)}</script>"
                     "</section>")
        names.append(name)
    s = run.summary
    notes = [f"Time axes start at the {_e(run.t0_how)} (t = {run.t0:.3f} s); the time plots share one linked axis "
             "(zoom one, the others follow)."]
    notes.append(f"Series longer than {MAX_POINTS:,} points are decimated to at most {MAX_POINTS:,} per trace by "
                 "keeping each bin's minimum and maximum, so peaks and worst cases are shown"
                 + (" (decimation applied in this report)." if any_dec else " (none needed here)."))
    if run.fixes is None:
        where = (f"the fix file named in the configuration could not be read ({run.fix_error})" if run.fix_error
                 else "the fix file named in the configuration was not found from the run folder" if run.config
                 else "no configuration (config_used.json) names a fix file")
        notes.append(f"GNSS fixes: {where}; the track marks the solution at the GNSS update times from "
                     "innovations.csv instead." if run.innov else
                     f"GNSS fixes: not available in this run folder ({where}).")
    if run.innov is None:
        notes.append("innovations.csv is not in the run folder: no innovation plot.")
    page = [
        "<!DOCTYPE html><html lang=en><head><meta charset=utf-8>",
        "<meta name=viewport content=\"width=device-width, initial-scale=1\">",
        f"<title>inskit report: {_e(run.name)}</title><style>{_CSS}</style></head><body><main>",
        _header(run),
        "<h2>Key figures</h2><div class=cols><div>", _key_table(s), "</div><div>", _counts_table(s),
        "</div></div>",
        "<p class=note>" + "<br>".join(notes) + "</p>",
        *parts,
        "<h2>Final estimates</h2>", _estimates_table(s),
        "<h2>Outages</h2>", _outage_table(s, s.get("solution", "forward")),
        "<h2>Configuration used</h2>", _config_section(run),
        f"<p class=note>Written by inskit report from {_e(run.dir.name)}/summary.json.</p>",
        "</main>",
        *([f"<script type=\"application/json\" id=\"plotly-template\">{_script_json(template or {})}</script>",
           f"<script type=\"application/json\" id=\"plotly-config\">{_script_json(_PLOT_CONFIG)}</script>",
           f"<script type=\"text/plain\" id=\"plotly-js-gzip\">{_packed_plotly_js()}</script>",
           f"<script>{_LOADER}</script>"] if names else []),
        "</body></html>",
    ]
    text = "\n".join(page)
    write_text(out, text)
    return {"report": str(out), "bytes": out.stat().st_size, "plots": names,
            "seconds": time.perf_counter() - t_start}
