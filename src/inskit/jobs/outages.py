"""GNSS outage protocols and their scoring.

The rtklibexplorer protocol (data README): withhold the fixes from
``t0 + 40 + 45 k`` to ``t0 + 54.75 + 45 k`` s, ``k = 0..10`` (t0 the first GNSS
epoch): eleven 15 s outages.  Score the forward solution's antenna position at
the last withheld fix of each outage against that fix.
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


@dataclass(frozen=True)
class OutageScore:
    """Errors at the end of each outage and with GNSS on.

    Attributes
    ----------
    table : list of dict
        Per outage: ``k``, ``start_s``, ``end_s`` (relative to the first GNSS
        epoch), ``horizontal_m``, ``vertical_m``.
    summary : dict
        ``outage_end_horizontal_rms_m``, ``..._median_m``, ``..._max_m``,
        ``outage_end_vertical_rms_m``, ``outage_worst_horizontal_rms_m`` and
        ``..._max_m`` (the largest error at any withheld fix of each outage:
        for a smoother, whose error peaks mid-outage, the meaningful figure), ``gnss_on_horizontal_rms_m``,
        ``gnss_on_vertical_rms_m``, ``outages``.
    """

    table: list
    summary: dict


def score_outages(sol: NavSolution, gnss: GnssData, windows, lever_arm_b, t0=None):
    """Score a solution against withheld fixes and against the used fixes."""
    t0 = gnss.time[0] if t0 is None else t0
    rows = []
    hs, vs, worst = [], [], []
    for k, (a, b) in enumerate(windows):
        inside = np.nonzero((gnss.time >= a - 1e-6) & (gnss.time <= b + 1e-6))[0]
        inside = inside[(gnss.time[inside] >= sol.time[0]) & (gnss.time[inside] <= sol.time[-1])]
        if len(inside) == 0:
            continue
        i = inside[-1]
        ant = antenna_positions(sol, gnss.time[inside], lever_arm_b)
        d_all = earth.lla_to_ned(ant, gnss.lla[inside])
        h_all = np.hypot(d_all[:, 0], d_all[:, 1])
        d = d_all[-1]
        rows.append({"k": k, "start_s": a - t0, "end_s": b - t0, "fix_time_s": gnss.time[i] - t0,
                     "horizontal_m": float(np.hypot(d[0], d[1])), "vertical_m": float(abs(d[2])),
                     "worst_horizontal_m": float(h_all.max()),
                     "worst_time_s": float(gnss.time[inside][int(np.argmax(h_all))] - t0)})
        hs.append(np.hypot(d[0], d[1]))
        vs.append(abs(d[2]))
        worst.append(h_all.max())
    used = ~withheld_mask(gnss.time, windows)
    used &= (gnss.time >= sol.time[0]) & (gnss.time <= sol.time[-1])
    ant = antenna_positions(sol, gnss.time[used], lever_arm_b)
    d = earth.lla_to_ned(ant, gnss.lla[used])
    hs, vs = np.asarray(hs), np.asarray(vs)
    summary = {
        "outages": len(rows),
        "outage_end_horizontal_rms_m": float(np.sqrt(np.mean(hs**2))) if len(hs) else None,
        "outage_end_horizontal_median_m": float(np.median(hs)) if len(hs) else None,
        "outage_end_horizontal_max_m": float(hs.max()) if len(hs) else None,
        "outage_end_vertical_rms_m": float(np.sqrt(np.mean(vs**2))) if len(vs) else None,
        "outage_worst_horizontal_rms_m": float(np.sqrt(np.mean(np.square(worst)))) if worst else None,
        "outage_worst_horizontal_max_m": float(np.max(worst)) if worst else None,
        "gnss_on_horizontal_rms_m": float(np.sqrt(np.mean(d[:, 0] ** 2 + d[:, 1] ** 2))),
        "gnss_on_vertical_rms_m": float(np.sqrt(np.mean(d[:, 2] ** 2))),
        "gnss_on_fixes": int(used.sum()),
    }
    return OutageScore(rows, summary)
