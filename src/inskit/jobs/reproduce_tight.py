"""Tight against loose coupling (source 000, SYSTEM.md §2, SOURCES-NOTES
§3.5: tight coupling keeps aiding with fewer than four satellites).

Two experiments, each a table and a figure:

* ``walk``: the bundled handheld walk (``data/walk_0827``: consumer MEMS IMU
  and the u-blox receiver's raw log).  Single-point positioning alone, loose
  coupling of that single-point solution, and tight coupling of the same
  pseudoranges and Doppler, all started alike from the single-point
  solution (no RTK information enters any of them) and all scored against
  the RTK track (heights above sea level turned ellipsoidal by the geoid
  separation -21.4 m).
* ``blockage``: a simulated drive (``examples/tc_blockage.toml``) whose
  sky is cut to 3, then 2, then 1 satellite for 120 s each; the fixes stop
  there.  Tight coupling against loose coupling (which coasts on the INS),
  with the bound the tight filter's own covariance states.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import earth
from .config import load_config
from .navigate import load_inputs, load_raw_gnss, navigate, spp_fixes
from .outages import antenna_positions

ROOT = Path(__file__).resolve().parents[3]


def _errors_against(sol, ref, lever):
    """Horizontal and vertical error [m] of a solution's antenna at the
    reference epochs it covers."""
    m = (ref.time >= sol.time[0]) & (ref.time <= sol.time[-1])
    ant = antenna_positions(sol, ref.time[m], lever)
    d = earth.lla_to_ned(ant, ref.lla[m])
    return ref.time[m], d


def _fix_errors(fixes, ref):
    """Errors of fixes against the reference epoch nearest each (within 10 ms)."""
    k = np.clip(np.searchsorted(ref.time, fixes.time), 1, len(ref.time) - 1)
    k = np.where(np.abs(ref.time[k - 1] - fixes.time) < np.abs(ref.time[k] - fixes.time), k - 1, k)
    m = np.abs(ref.time[k] - fixes.time) < 0.01
    return fixes.time[m], earth.lla_to_ned(fixes.lla[m], ref.lla[k[m]])


def _row(name, t, d):
    h = np.hypot(d[:, 0], d[:, 1])
    return {"solution": name, "epochs": int(len(t)), "horizontal_rms_m": float(np.sqrt(np.mean(h**2))),
            "horizontal_max_m": float(h.max()), "vertical_rms_m": float(np.sqrt(np.mean(d[:, 2] ** 2))),
            "mean_north_m": float(d[:, 0].mean()), "mean_east_m": float(d[:, 1].mean())}


def walk(config=None, log=None):
    """Run the walk comparison; returns ``(result dict, curves for the plot)``."""
    cfg = load_config(config or ROOT / "examples" / "walk_0827_tight.toml")
    raw = load_raw_gnss(cfg, log)
    imu, ref = load_inputs(cfg, None, raw)
    fixes = spp_fixes(raw)
    lever = np.asarray(cfg.gnss.lever_arm_b_m, float)
    runs = {}
    tight = navigate(cfg, inputs=(imu, fixes, raw), log=log)
    loose_cfg = cfg.model_copy(update={"gnss": cfg.gnss.model_copy(update={"coupling": "loose", "file": None})})
    loose = navigate(loose_cfg, inputs=(imu, fixes, raw), log=log)
    curves = {"single-point": _fix_errors(fixes, ref)}
    curves["loose (single-point fixes)"] = _errors_against(loose.forward.solution, ref, lever)
    curves["tight (pseudorange + Doppler)"] = _errors_against(tight.forward.solution, ref, lever)
    rows = [_row(k, *v) for k, v in curves.items()]
    for name, res in (("loose", loose), ("tight", tight)):
        from .navigate import health

        runs[name] = {"measurements": res.forward.counts, "health": health(res.forward)["verdict"]}
    n_sat = np.bincount(np.asarray(raw.table.epoch), minlength=len(raw.obs.time))
    out = {"experiment": "walk", "reference": "RTK track (gnss_1730_sf.pos), heights + geoid separation "
           f"{cfg.gnss.height_offset_m} m", "satellites_with_ephemeris": sorted(set(np.asarray(raw.table.sat)
                                                                                       .tolist())),
           "satellites_per_epoch_median": float(np.median(n_sat)), "table": rows, "runs": runs,
           "t0": float(ref.time[0])}
    return out, curves


def walk_text(res):
    lines = [f"walk_0827 against the RTK track: {len(res['satellites_with_ephemeris'])} satellites with an "
             f"ephemeris ({', '.join(res['satellites_with_ephemeris'])}), median "
             f"{res['satellites_per_epoch_median']:.0f} per epoch",
             f"{'solution':<32}{'epochs':>7}{'horiz RMS [m]':>15}{'horiz max [m]':>15}{'vert RMS [m]':>14}"
             f"{'mean N, E [m]':>18}"]
    for r in res["table"]:
        lines.append(f"{r['solution']:<32}{r['epochs']:>7}{r['horizontal_rms_m']:>15.2f}{r['horizontal_max_m']:>15.2f}"
                     f"{r['vertical_rms_m']:>14.2f}{r['mean_north_m']:>9.2f},{r['mean_east_m']:>6.2f}")
    return "\n".join(lines)


def plot_walk(res, curves, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..files import save_figure

    fig, ax = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    t0 = res["t0"]
    for name, (t, d) in curves.items():
        ax[0].plot(t - t0, np.hypot(d[:, 0], d[:, 1]), lw=0.9, label=name)
        ax[1].plot(t - t0, d[:, 2], lw=0.9, label=name)
    ax[0].set_ylabel("horizontal error [m]")
    ax[1].set_ylabel("down error [m]")
    ax[1].set_xlabel("time after the first RTK epoch [s]")
    ax[0].set_title("walk_0827: errors against the RTK track (all started from the single-point solution)")
    for a in ax:
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)
    return path
