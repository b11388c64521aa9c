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
            "horizontal_std_m": float(np.sqrt(d[:, 0].var() + d[:, 1].var())),
            "horizontal_jitter_m": float(np.sqrt(np.mean(np.sum(np.diff(d[:, :2], axis=0) ** 2, axis=1)) / 2.0)),
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
    lines = ["jitter: epoch-to-epoch change of the N, E error per axis over sqrt(2), the white part of the error",
             f"walk_0827 against the RTK track: {len(res['satellites_with_ephemeris'])} satellites with an "
             f"ephemeris ({', '.join(res['satellites_with_ephemeris'])}), median "
             f"{res['satellites_per_epoch_median']:.0f} per epoch",
             f"{'solution':<32}{'epochs':>7}{'horiz RMS [m]':>15}{'horiz std [m]':>15}{'jitter [m]':>12}"
             f"{'horiz max [m]':>15}{'vert RMS [m]':>14}{'mean N, E [m]':>18}"]
    for r in res["table"]:
        lines.append(f"{r['solution']:<32}{r['epochs']:>7}{r['horizontal_rms_m']:>15.2f}{r['horizontal_std_m']:>15.2f}"
                     f"{r['horizontal_jitter_m']:>12.3f}{r['horizontal_max_m']:>15.2f}"
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


# --- simulated blockage ----------------------------------------------------------------
#: the navigate settings of the blockage drive, matched to the scenario's industrial-MEMS preset
#: (ADIS16495-1: ARW 0.09 deg/sqrt(h), VRW 13.6 ug/sqrt(Hz) = 0.008 m/s/sqrt(h), in-run 0.8 deg/h and
#: 3.2 ug; turn-on 200 deg/h and 1 mg)
BLOCKAGE_NAVIGATE = {
    "name": "tc_blockage",
    "imu": {"file": "imu.csv"},
    "gnss": {"file": "gnss.csv", "lever_arm_b_m": [0.0, 0.0, -1.2]},
    "noise": {"gyro_arw_deg_sqrt_h": 0.09, "accel_vrw_m_s_sqrt_h": 0.008, "gyro_bias_sigma_deg_h": 1.0,
              "accel_bias_sigma_ug": 10.0, "bias_tau_s": 600.0, "from_static": False},
    "init": {"sigma_gyro_bias_deg_s": 200.0 / 3600.0, "sigma_accel_bias_m_s2": 0.01, "sigma_scale_factor": 0.002},
    "constraints": {"zupt": True, "nhc": True},
    "filter": {"scheme": "closed", "scale_factors": True},
    "output": {"plots": False},
}


def blockage(out_dir, seed=1, log=None, scenario=None):
    """Simulate the blockage drive into ``out_dir`` (IMU, fixes, RINEX 3 obs
    and nav, truth), then run loose and tight coupling on those files and
    score both against the truth file."""
    from .. import analysis, io
    from ..simulation.scenario import load_scenario, simulate
    from .config import config_from_dict
    from .simulate import write_simulation

    out_dir = Path(out_dir)
    sc = load_scenario(scenario or ROOT / "examples" / "tc_blockage.toml")
    sim = simulate(sc, seed)
    write_simulation(sim, out_dir, overwrite=True, plot=False)
    truth = io.read_solution(out_dir / "truth.csv")
    t_sow0 = float(truth.time[0])
    windows = [(b.start_s, b.end_s, b.keep) for b in sc.raw_gnss.blockage]
    base = {k: (dict(v) if isinstance(v, dict) else v) for k, v in BLOCKAGE_NAVIGATE.items()}
    base["earth"] = {"gravity": sc.earth.gravity}  # navigate with the simulation's gravity model
    loose = config_from_dict(base, base_dir=out_dir, source="blockage (loose)")
    tdict = dict(base)
    tdict["gnss"] = {**base["gnss"], "coupling": "tight", "obs": "obs.rnx", "nav": "nav.rnx", "systems": ["G"]}
    tight = config_from_dict(tdict, base_dir=out_dir, source="blockage (tight)")
    res = {"loose": navigate(loose, log=log), "tight": navigate(tight, log=log)}
    curves, rows = {}, []
    for name, r in res.items():
        err = analysis.nav_error(r.forward.nav, truth)
        h = np.hypot(err.pos_ned[:, 0], err.pos_ned[:, 1])
        sig = r.forward.sigma_of("pos")
        k = np.searchsorted(r.forward.nav.time, err.time)
        sig_h = np.hypot(sig[k, 0], sig[k, 1])
        curves[name] = (err.time - t_sow0, h, sig_h)
        for a, b, keep in windows:
            m = (err.time - t_sow0 >= a) & (err.time - t_sow0 <= b)
            rows.append({"solution": name, "window_s": [a, b], "satellites": keep,
                         "max_horizontal_m": float(h[m].max()), "end_horizontal_m": float(h[m][-1]),
                         "bound_3sigma_m": float(3.0 * sig_h[m].max()),
                         "within_bound": bool((h[m] <= 3.0 * sig_h[m]).all())})
    counts = {name: r.forward.counts for name, r in res.items()}
    from .navigate import health

    out = {"experiment": "blockage", "seed": seed, "scenario": sc.name, "windows": [list(w) for w in windows],
           "table": rows, "measurements": counts,
           "health": {name: health(r.forward)["verdict"] for name, r in res.items()},
           "bound": "3 sigma of the tight filter's own horizontal position covariance, its maximum over the window"}
    return out, curves


def blockage_text(res):
    lines = [f"{res['scenario']} (seed {res['seed']}): horizontal error against the truth in each blockage",
             f"{'window [s]':<14}{'sats':>5}{'loose max [m]':>15}{'tight max [m]':>15}{'tight 3-sigma bound [m]':>25}"
             f"{'tight within':>14}"]
    by = {}
    for r in res["table"]:
        by.setdefault(tuple(r["window_s"]), {})[r["solution"]] = r
    for w, d in by.items():
        lo, ti = d["loose"], d["tight"]
        lines.append(f"{w[0]:>5.0f}..{w[1]:<6.0f}{ti['satellites']:>5}{lo['max_horizontal_m']:>15.2f}"
                     f"{ti['max_horizontal_m']:>15.2f}{ti['bound_3sigma_m']:>25.2f}"
                     f"{'yes' if ti['within_bound'] else 'NO':>14}")
    return "\n".join(lines)


def plot_blockage(res, curves, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..files import save_figure

    fig, ax = plt.subplots(figsize=(10, 5))
    colors = {"loose": "tab:red", "tight": "tab:blue"}
    for name, (t, h, s) in curves.items():
        ax.plot(t, h, lw=1.0, color=colors.get(name), label=f"{name}: horizontal error")
    t, _, s = curves["tight"]
    ax.plot(t, 3 * s, lw=0.8, ls="--", color="tab:blue", label="tight: 3-sigma (its own covariance)")
    ymax = max(max(float(np.max(c[1])) for c in curves.values()), 3.0 * float(np.max(s))) * 1.05
    for a, b, keep in res["windows"]:
        ax.axvspan(a, b, color="0.85", zorder=0)
        ax.text((a + b) / 2, ymax * 0.97, f"{keep} sat", ha="center", va="top", fontsize=9)
    ax.set_yscale("symlog", linthresh=1.0)
    ax.set_ylim(0, ymax)
    ax.set_xlabel("scenario time [s]")
    ax.set_ylabel("horizontal error [m]")
    ax.set_title("blockages keeping 3, 2, 1 satellites (shaded): tight coupling keeps ranging, loose coasts")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    save_figure(fig, path)
    return path


def run(out_dir, experiments=("walk", "blockage"), seed=1, log=None):
    """Run the experiments, write their figures (and the blockage drive's
    simulated files under ``out_dir/blockage_sim``); returns the JSON-ready
    results and the text tables."""
    from ..files import check_folder_writable

    out_dir = Path(out_dir)
    check_folder_writable(out_dir)
    results, texts, files = {}, [], []
    if "walk" in experiments:
        r, curves = walk(log=log)
        files.append(str(plot_walk(r, curves, out_dir / "tight_walk.png")))
        results["walk"] = r
        texts.append(walk_text(r))
    if "blockage" in experiments:
        r, curves = blockage(out_dir / "blockage_sim", seed=seed, log=log)
        files.append(str(plot_blockage(r, curves, out_dir / "tight_blockage.png")))
        results["blockage"] = r
        texts.append(blockage_text(r))
    results["files"] = files
    return results, "\n\n".join(texts)
