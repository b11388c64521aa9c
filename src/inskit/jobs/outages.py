"""GNSS outage protocols and their scoring.

The rtklibexplorer protocol (data README): withhold the fixes from
``t0 + 40 + 45 k`` to ``t0 + 54.75 + 45 k`` s, ``k = 0..10`` (t0 the first GNSS
epoch): eleven 15 s outages.  Score the forward solution's antenna position at
the last withheld fix of each outage against that fix.

A withheld fix carries its own noise, so with a truth trajectory (a
simulation's) the outages are also scored against the truth, over the whole
unaided span; every key names its reference (:class:`OutageScore`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import earth
from .. import rotations as rot
from ..types import GnssData, NavSolution


def rtklibexplorer_outages(t0, count=11, first_s=40.0, length_s=14.75, period_s=45.0):
    """The eleven outage windows ``[(start, end)]`` in absolute time [s]."""
    return [(t0 + first_s + period_s * k, t0 + first_s + length_s + period_s * k) for k in range(count)]


def withheld_mask(t, windows, eps=1e-6):
    """True where ``t`` falls inside any window (inclusive)."""
    t = np.asarray(t, float)
    m = np.zeros(len(t), bool)
    for a, b in windows:
        m |= (t >= a - eps) & (t <= b + eps)
    return m


def antenna_positions(sol: NavSolution, t, lever_arm_b):
    """Antenna lla at GNSS times ``t``, predicted as the filter predicts a fix:
    from the solution row at or before ``t`` (post-update when an update was
    made there), moved by its velocity over the remaining interval, plus
    ``C_nb l_b``.  When the solution carries an estimated IMU-GNSS time offset
    (``extra["time_offset_s"]``), GNSS time ``t`` is INS time ``t + offset``.
    (Interpolating between rows would mix a pre-update row into the first fix
    after an outage.)"""
    t = np.asarray(t, float)
    i = np.clip(np.searchsorted(sol.time, t, side="right") - 1, 0, len(sol.time) - 1)
    dt = t - sol.time[i]
    if "time_offset_s" in sol.extra:
        dt = dt + sol.extra["time_offset_s"][i]
    lla = sol.lla[i]
    C_nb = rot.dcm_from_quat(sol.q_nb[i])
    d_n = sol.v_n[i] * dt[:, None] + np.einsum("nij,j->ni", C_nb, np.asarray(lever_arm_b, float))
    r = earth.lla_to_ecef(lla) + np.einsum("nij,nj->ni", earth.dcm_en(lla[:, 0], lla[:, 1]), d_n)
    return earth.ecef_to_lla(r)


#: the two references an outage is scored against (the words in the keys)
REFERENCES = ("withheld_fixes", "truth")


@dataclass(frozen=True)
class OutageScore:
    """Errors at the end of each outage, the worst inside it, and the fit to
    the fixes the filter used.

    Two references, named in the keys:

    * ``vs_withheld_fixes``: the solution's antenna position against the GNSS
      fixes withheld inside each window (what a real drive offers).  The fix
      noise is in the figure: a smoothed 0.2 m error reads as about 1 m
      against fixes of 1 m noise.  The *end* is the last withheld fix of the
      window; a window whose fixes stop earlier than :func:`end_reach_s`
      before its end (the file ends, or a gap) is not scored but listed in
      ``outages_unscored`` with the reason, as one that withholds no fix.
    * ``vs_truth`` (only when a truth is given): the solution against the
      truth at every solution epoch of the unaided span, from the last used
      fix before the window to the first used fix after it.  The *end* is the
      last epoch before the update at that next fix: the error when the
      outage ends.  A smoother's end error is pinned by the next fix a moment
      later; for a smoother only the worst point inside the outage means
      something.

    Attributes
    ----------
    table : list of dict
        Per outage: ``k``, ``start_s``, ``end_s`` (relative to the first GNSS
        epoch), ``fix_time_s`` (the last withheld fix), ``horizontal_m``,
        ``vertical_m``, ``worst_horizontal_m``, ``worst_time_s`` (the earlier
        keys, all against the withheld fixes), and their named twins
        ``outage_end_{h,v,3d}_vs_withheld_fixes_m``,
        ``outage_worst_{h,v,3d}_vs_withheld_fixes_m``, the end error split
        along and across the reference track,
        ``outage_end_along_track_vs_withheld_fixes_m`` (positive: ahead) and
        ``outage_end_cross_track_vs_withheld_fixes_m`` (positive: right), and
        ``outage_along_track_accel_fit_m_s2``, the constant along-track
        acceleration error that best fits the error's growth (a tilt of
        ``a / g`` rad or a forward accelerometer bias; see
        :func:`along_track_accel_fit`); each ``None`` when the reference
        stands still or too few fixes fall inside.  With a truth also
        ``outage_end_{h,v,3d}_vs_truth_m``, ``outage_end_time_vs_truth_s``,
        ``outage_worst_{h,v,3d}_vs_truth_m``, ``outage_worst_time_vs_truth_s``
        and ``unaided_from_s``, ``unaided_to_s`` (the used fixes that bound
        the span; ``None`` at either end of the data).  Times are relative to
        the first GNSS epoch; ``None`` where the truth does not cover the span.
    summary : dict
        ``outages``; against the withheld fixes the earlier keys
        ``outage_end_horizontal_rms_m``, ``..._median_m``, ``..._max_m``,
        ``outage_end_vertical_rms_m``, ``outage_worst_horizontal_rms_m``,
        ``..._max_m`` and their twins
        ``outage_{end,worst}_h_vs_withheld_fixes_{rms,median,max}_m``,
        ``outage_{end,worst}_{v,3d}_vs_withheld_fixes_rms_m``,
        ``outage_end_{along,cross}_track_vs_withheld_fixes_rms_m`` (over the
        outages where the reference moves).  The fit to the
        used fixes, which is not an accuracy (the filter was fed those fixes):
        ``fit_to_used_fixes_h_rms_m``, ``fit_to_used_fixes_v_rms_m``,
        ``fit_to_used_fixes_count`` and the earlier names
        ``gnss_on_horizontal_rms_m``, ``gnss_on_vertical_rms_m``,
        ``gnss_on_fixes`` (the same values); ``fixes_fused`` (False: the
        fixes are a reference the filter never saw, see :func:`score_outages`,
        and the fit keys are ``None``).  With a truth also
        ``outage_{end,worst}_h_vs_truth_{rms,median,max}_m``,
        ``outage_{end,worst}_{v,3d}_vs_truth_rms_m``, ``outages_vs_truth`` and
        the accuracy with GNSS on, over the epochs outside the unaided spans:
        ``gnss_on_h_vs_truth_rms_m``, ``gnss_on_v_vs_truth_rms_m``,
        ``gnss_on_3d_vs_truth_rms_m``, ``gnss_on_epochs_vs_truth``.
    """

    table: list
    summary: dict


#: Below this reference speed [m/s] an outage's error has no along- and cross-track parts.
TRACK_MIN_SPEED_M_S = 0.5


def track_components(gnss: GnssData, idx, d_ned):
    """Split horizontal errors at fixes into along- and cross-track parts.

    The direction of travel at each fix comes from the reference itself: the
    central difference of the neighbouring fixes (one-sided at either end of
    the file), never from the solution under test.

    Parameters
    ----------
    gnss : GnssData
        The reference fixes.
    idx : (m,) array of int
        Indices of the fixes the errors belong to.
    d_ned : (m, 3) array
        Solution minus reference, NED [m].

    Returns
    -------
    along, cross : (m,) arrays [m]
        Along-track error (positive: the solution is ahead) and cross-track
        error (positive: to the right of the direction of travel); NaN where
        the reference moves slower than :data:`TRACK_MIN_SPEED_M_S`.
    """
    idx = np.asarray(idx, dtype=int)
    n = len(gnss.time)
    lo, hi = np.maximum(idx - 1, 0), np.minimum(idx + 1, n - 1)
    along = np.full(len(idx), np.nan)
    cross = np.full(len(idx), np.nan)
    for j, (a, b) in enumerate(zip(lo, hi)):  # a handful of fixes per outage
        dt = gnss.time[b] - gnss.time[a]
        if b == a or dt <= 0:
            continue
        step = earth.lla_to_ned(gnss.lla[b], gnss.lla[a])[:2]
        speed = float(np.hypot(*step)) / dt
        if speed < TRACK_MIN_SPEED_M_S:
            continue
        u = step / np.hypot(*step)
        along[j] = d_ned[j, 0] * u[0] + d_ned[j, 1] * u[1]
        cross[j] = -d_ned[j, 0] * u[1] + d_ned[j, 1] * u[0]
    return along, cross


def along_track_accel_fit(t, along):
    """The constant along-track acceleration error that best explains an
    outage's along-track error growth.

    Least squares of ``e(t) = e0 + v0 (t - t_0) + a (t - t_0)^2 / 2`` over the
    withheld fixes; ``a`` is what a tilt error ``a / g`` [rad] or a forward
    accelerometer bias ``a`` would give.  ``None`` with fewer than four usable
    fixes or a span under 2 s (a quadratic is then not determined).
    """
    ok = np.isfinite(along)
    t, e = np.asarray(t, dtype=float)[ok], np.asarray(along, dtype=float)[ok]
    if len(t) < 4 or t[-1] - t[0] < 2.0:
        return None
    tau = t - t[0]
    A = np.stack([np.ones_like(tau), tau, 0.5 * tau ** 2], axis=1)
    coef = np.linalg.lstsq(A, e, rcond=None)[0]
    return float(coef[2])


def _rms(x):
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else None


def _aggregate(rows, key, stats=("rms",)):
    x = np.asarray([r[key] for r in rows if r.get(key) is not None], float)
    out = {}
    for st in stats:
        name = key[:-2] + f"_{st}_m"  # "..._m" -> "..._rms_m"
        out[name] = None if not len(x) else (_rms(x) if st == "rms" else float(np.median(x) if st == "median"
                                                                                  else x.max()))
    return out


def _summaries(rows, ref):
    out = {}
    for what in ("end", "worst"):
        out.update(_aggregate(rows, f"outage_{what}_h_vs_{ref}_m", ("rms", "median", "max")))
        out.update(_aggregate(rows, f"outage_{what}_v_vs_{ref}_m"))
        out.update(_aggregate(rows, f"outage_{what}_3d_vs_{ref}_m"))
    if ref == "withheld_fixes":
        out.update(_aggregate(rows, "outage_end_along_track_vs_withheld_fixes_m"))
        out.update(_aggregate(rows, "outage_end_cross_track_vs_withheld_fixes_m"))
    return out


def unaided_spans(gnss: GnssData, windows, used=None):
    """Per window ``(a, b)``: ``(t_prev, t_next)``, the last used fix before
    ``a`` and the first used fix after ``b`` [s] (``-inf`` / ``inf`` where
    there is none).  ``used`` defaults to the fixes outside every window."""
    t = np.asarray(gnss.time, float)
    used = ~withheld_mask(t, windows) if used is None else np.asarray(used, bool)
    tu = t[used]
    spans = []
    for a, b in windows:
        i = np.searchsorted(tu, a - 1e-6, side="left") - 1
        j = np.searchsorted(tu, b + 1e-6, side="right")
        spans.append((float(tu[i]) if i >= 0 else -np.inf, float(tu[j]) if j < len(tu) else np.inf))
    return spans


#: a stretch without any fix (used or withheld) longer than this many median fix intervals is a gap in the GNSS data
GNSS_GAP_FACTOR = 5.0
#: ... and at least this long [s] (a 10 Hz receiver's second without fixes is not worth a warning)
GNSS_GAP_MIN_S = 2.0


def gnss_data_gaps(fix_time, t_start, t_end):
    """Stretches of ``[t_start, t_end]`` (the IMU's span) without any GNSS
    fix, protocol outages aside (their fixes are in ``fix_time``, only
    withheld): ``[(from, to)]`` [s] longer than ``GNSS_GAP_FACTOR`` median
    fix intervals and ``GNSS_GAP_MIN_S``, including a start before the first
    fix and an end after the last.  The solution there is free-inertial
    although no outage was asked for."""
    tf = np.asarray(fix_time, float)
    tf = tf[(tf >= t_start) & (tf <= t_end)]
    if len(tf) == 0:
        return [(float(t_start), float(t_end))]
    step = float(np.median(np.diff(tf))) if len(tf) > 1 else 1.0
    limit = max(GNSS_GAP_FACTOR * step, GNSS_GAP_MIN_S)
    edges = np.concatenate([[t_start], tf, [t_end]])
    d = np.diff(edges)
    return [(float(edges[i]), float(edges[i + 1])) for i in np.nonzero(d > limit)[0]]


def _track_keys(gnss, inside, d_all):
    along, cross = track_components(gnss, inside, d_all)
    fin = lambda x: float(x) if np.isfinite(x) else None  # noqa: E731
    return {"outage_end_along_track_vs_withheld_fixes_m": fin(along[-1]),
            "outage_end_cross_track_vs_withheld_fixes_m": fin(cross[-1]),
            "outage_along_track_accel_fit_m_s2": along_track_accel_fit(gnss.time[inside], along)}


def _truth_scores(sol: NavSolution, truth: NavSolution, gnss: GnssData, windows, rows, t0):
    """Add the truth keys to ``rows`` (in place); return the summary keys.

    The unaided epochs of a window are the solution rows after the row that
    took the last used fix before it and before the row that takes the first
    used fix after it (the filter applies an update at time ``t`` at the row
    at or before ``t``: the update schedule of ``inskit.integration.engine``)."""
    from ..analysis import nav_error

    err = nav_error(sol, truth)
    h, v = err.horizontal, np.abs(err.pos_ned[:, 2])
    d3 = np.linalg.norm(err.pos_ned, axis=1)
    off = np.zeros(len(err.time), bool)

    def row_time(t):  # the time of the solution row that takes a fix at t
        if not np.isfinite(t):
            return t
        return float(sol.time[max(int(np.searchsorted(sol.time, t, side="right")) - 1, 0)])

    by_k = {r["k"]: r for r in rows}
    spans = unaided_spans(gnss, windows)
    n_scored = 0
    for k, (t_prev, t_next) in enumerate(spans):
        m = (err.time > row_time(t_prev)) & (err.time < row_time(t_next))
        off |= m
        r = by_k.get(k)
        if r is None:
            continue
        r["unaided_from_s"] = float(t_prev - t0) if np.isfinite(t_prev) else None
        r["unaided_to_s"] = float(t_next - t0) if np.isfinite(t_next) else None
        idx = np.nonzero(m)[0]
        keys = ("outage_end_h_vs_truth_m", "outage_end_v_vs_truth_m", "outage_end_3d_vs_truth_m",
                "outage_end_time_vs_truth_s", "outage_worst_h_vs_truth_m", "outage_worst_v_vs_truth_m",
                "outage_worst_3d_vs_truth_m", "outage_worst_time_vs_truth_s")
        if not len(idx):
            r.update(dict.fromkeys(keys))
            continue
        n_scored += 1
        e, w = idx[-1], idx[int(np.argmax(h[idx]))]
        r.update(zip(keys, (float(h[e]), float(v[e]), float(d3[e]), float(err.time[e] - t0),
                            float(h[w]), float(v[idx].max()), float(d3[idx].max()), float(err.time[w] - t0))))
    for a, b in gnss_data_gaps(gnss.time, float(sol.time[0]), float(sol.time[-1])):  # free-inertial, unasked
        off |= (err.time > a) & (err.time <= b) if a > sol.time[0] else (err.time < b)
    on = ~off
    out = {"outages_vs_truth": n_scored, **_summaries(rows, "truth"),
           "gnss_on_h_vs_truth_rms_m": _rms(h[on]), "gnss_on_v_vs_truth_rms_m": _rms(v[on]),
           "gnss_on_3d_vs_truth_rms_m": _rms(d3[on]), "gnss_on_epochs_vs_truth": int(on.sum())}
    return out


def end_reach_s(fix_time) -> float:
    """How far before a window's end its last withheld fix may lie and the
    window still be scored [s]: 1.5 median fix intervals (a window ending
    between two fixes ends at most one interval after its last one), at least
    1 ms.  Further, the fixes stop inside the window (the file ends, or a
    gap): its "end" error would be measured early."""
    dt = np.diff(np.asarray(fix_time, float))
    return max(1.5 * float(np.median(dt)) if len(dt) else 0.0, 1e-3)


def score_outages(sol: NavSolution, gnss: GnssData, windows, lever_arm_b, t0=None, truth: NavSolution | None = None,
                  fused=True):
    """Score a solution against the withheld fixes, against the used fixes
    (the fit, not an accuracy) and, when ``truth`` is given, against the
    truth (:class:`OutageScore` names every key).

    With ``fused=False`` the fixes were never fed to the filter (tight
    coupling scored on an RTK track): the figures with GNSS on are then an
    accuracy against an independent reference, its own error included, and
    come as ``gnss_on_h_vs_reference_fixes_rms_m``,
    ``gnss_on_v_vs_reference_fixes_rms_m``, ``gnss_on_reference_fixes``;
    ``fit_to_used_fixes_*`` are ``None`` (no fix was used) and
    ``fixes_fused`` says which case it is.

    Parameters
    ----------
    sol : NavSolution
        The solution (IMU position, on the GNSS time base).
    gnss : GnssData
        Every fix, used and withheld.
    windows : list of (float, float)
        Outage windows, absolute time [s].
    lever_arm_b : (3,) array_like
        IMU to antenna, body axes [m].
    t0 : float, optional
        Time zero of the table (default the first fix).
    truth : NavSolution, optional
        The true IMU trajectory on the same time base.
    """
    t0 = gnss.time[0] if t0 is None else t0
    rows, unscored = [], []
    reach = end_reach_s(gnss.time)
    for k, (a, b) in enumerate(windows):
        inside = np.nonzero((gnss.time >= a - 1e-6) & (gnss.time <= b + 1e-6))[0]
        in_span = inside[(gnss.time[inside] >= sol.time[0]) & (gnss.time[inside] <= sol.time[-1])]
        if len(in_span) == 0:  # nothing withheld there: said, not silently left out of the figures
            unscored.append({"k": k, "start_s": a - t0, "end_s": b - t0,
                             "reason": ("the GNSS file holds no fix inside the window" if len(inside) == 0 else
                                        "the window's fixes lie outside the solution's time span")})
            continue
        inside = in_span
        i = inside[-1]
        if b - gnss.time[i] > reach:  # the fixes stop well before the window's end: no end error to score
            after = gnss.time[gnss.time > b + 1e-6]
            nxt = (f"the unaided span runs on to the next fix at {after[0] - t0:.2f} s" if len(after)
                   else "no fix follows")
            unscored.append({"k": k, "start_s": a - t0, "end_s": b - t0,
                             "reason": f"the window's last fix is at {gnss.time[i] - t0:.2f} s, {b - gnss.time[i]:.2f} "
                                       f"s before its end (the fixes stop there; {nxt}): its end error would be "
                                       "measured that much early, and the outage is not the window's length"})
            continue
        ant = antenna_positions(sol, gnss.time[inside], lever_arm_b)
        d_all = earth.lla_to_ned(ant, gnss.lla[inside])
        h_all = np.hypot(d_all[:, 0], d_all[:, 1])
        v_all = np.abs(d_all[:, 2])
        n_all = np.linalg.norm(d_all, axis=1)
        rows.append({"k": k, "start_s": a - t0, "end_s": b - t0, "fix_time_s": gnss.time[i] - t0,
                     "horizontal_m": float(h_all[-1]), "vertical_m": float(v_all[-1]),
                     "worst_horizontal_m": float(h_all.max()),
                     "worst_time_s": float(gnss.time[inside][int(np.argmax(h_all))] - t0),
                     "outage_end_h_vs_withheld_fixes_m": float(h_all[-1]),
                     "outage_end_v_vs_withheld_fixes_m": float(v_all[-1]),
                     "outage_end_3d_vs_withheld_fixes_m": float(n_all[-1]),
                     "outage_worst_h_vs_withheld_fixes_m": float(h_all.max()),
                     "outage_worst_v_vs_withheld_fixes_m": float(v_all.max()),
                     "outage_worst_3d_vs_withheld_fixes_m": float(n_all.max()),
                     **_track_keys(gnss, inside, d_all)})
    hs = np.asarray([r["horizontal_m"] for r in rows])
    vs = np.asarray([r["vertical_m"] for r in rows])
    worst = np.asarray([r["worst_horizontal_m"] for r in rows])
    used = ~withheld_mask(gnss.time, windows)
    used &= (gnss.time >= sol.time[0]) & (gnss.time <= sol.time[-1])
    ant = antenna_positions(sol, gnss.time[used], lever_arm_b)
    d = earth.lla_to_ned(ant, gnss.lla[used])
    fit_h = float(np.sqrt(np.mean(d[:, 0] ** 2 + d[:, 1] ** 2)))
    fit_v = float(np.sqrt(np.mean(d[:, 2] ** 2)))
    summary = {
        "outages": len(rows),
        "outages_unscored": unscored,
        "outage_end_horizontal_rms_m": _rms(hs),
        "outage_end_horizontal_median_m": float(np.median(hs)) if len(hs) else None,
        "outage_end_horizontal_max_m": float(hs.max()) if len(hs) else None,
        "outage_end_vertical_rms_m": _rms(vs),
        "outage_worst_horizontal_rms_m": _rms(worst),
        "outage_worst_horizontal_max_m": float(worst.max()) if len(worst) else None,
        "gnss_on_horizontal_rms_m": fit_h,
        "gnss_on_vertical_rms_m": fit_v,
        "gnss_on_fixes": int(used.sum()),
        **_summaries(rows, "withheld_fixes"),
        "fixes_fused": bool(fused),
        "fit_to_used_fixes_h_rms_m": fit_h if fused else None,
        "fit_to_used_fixes_v_rms_m": fit_v if fused else None,
        "fit_to_used_fixes_count": int(used.sum()) if fused else None,
    }
    if not fused:
        summary.update({"gnss_on_h_vs_reference_fixes_rms_m": fit_h, "gnss_on_v_vs_reference_fixes_rms_m": fit_v,
                        "gnss_on_reference_fixes": int(used.sum())})
    if truth is not None:
        summary.update(_truth_scores(sol, truth, gnss, windows, rows, t0))
    return OutageScore(rows, summary)
