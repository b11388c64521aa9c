"""The simulate job: write a simulated scenario to files, plot it, and the
simulator's self-check (its ideal IMU mechanized against its truth)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from ..files import save_figure
from .. import io
from ..errors import InputError
from ..simulation.imu import ideal_imu, truth_solution
from ..simulation.scenario import Scenario, Simulation, build_trajectory


def write_simulation(sim: Simulation, out_dir, *, overwrite=False, plot=True, file_format="csv", inputs=()):
    """Write ``imu.csv`` (increments), ``gnss.csv``, ``truth.csv`` and a plot
    (``.parquet`` instead with ``file_format="parquet"``).

    With raw GNSS observations (``sim.raw``) also ``obs.rnx`` and ``nav.rnx``
    (RINEX 3.04) and ``raw_truth.csv``, and then every time column of the
    CSV files is GPS seconds of week (the scenario's start second of week
    plus scenario time), the time scale of the RINEX epochs, as in a real
    receiver and IMU log.  Without raw GNSS the times are scenario seconds.

    ``inputs`` (the scenario file; a ``nav:`` constellation's file is added
    here) are never overwritten, ``--force`` or not.  The files are written
    whole or not at all, as a set (:func:`inskit.files.staged_files`): a
    failure leaves the folder as it was.
    """
    from ..files import staged_files

    out = Path(out_dir)
    files, stale = check_simulation_outputs(sim.scenario, out, overwrite=overwrite, plot=plot,
                                            file_format=file_format, inputs=inputs)
    imu, gnss, truth = sim.imu, sim.gnss, sim.truth
    if sim.raw is not None:
        sow0 = raw_start_sow(sim)
        imu = dataclasses.replace(imu, time=imu.time + sow0)
        gnss = dataclasses.replace(gnss, time=gnss.time + sow0)
        truth = dataclasses.replace(truth, time=truth.time + sow0)
    with staged_files(out) as stage:
        io.write_imu(stage(files[0]), imu, overwrite=True)
        io.write_gnss(stage(files[1]), gnss, overwrite=True)
        io.write_solution(stage(files[2]), truth, overwrite=True)
        if sim.raw is not None:
            _write_raw(sim, stage(files[3]), stage(files[4]), stage(files[5]))
        if plot:
            _plot(sim, stage(out / "scenario.png"))
            files.append(out / "scenario.png")
    for f in stale:  # --force: an earlier run in the other format goes, not only the files of this one
        f.unlink()
    return files


def check_simulation_outputs(sc, out_dir, *, overwrite=False, plot=True, file_format="csv", inputs=()):
    """Refuse, before the simulation runs, the outputs of
    :func:`write_simulation` that would overwrite an input (the scenario, a
    ``nav:`` constellation's file) or, without ``overwrite``, an existing
    file.  Returns ``(files, stale)``: the data files to write and those of
    the other format to remove once they are written."""
    from ..files import check_outputs

    out = Path(out_dir)
    if file_format not in ("csv", "parquet"):
        raise InputError(f"file_format must be 'csv' or 'parquet', got {file_format!r}")
    files = [out / f"{n}.{file_format}" for n in ("imu", "gnss", "truth")]
    raw_cfg = getattr(sc, "raw_gnss", None)
    raw_on = raw_cfg is not None and raw_cfg.enabled
    if raw_on:
        files += [out / "obs.rnx", out / "nav.rnx", out / "raw_truth.csv"]
    other = [out / f"{n}.{'csv' if file_format == 'parquet' else 'parquet'}" for n in ("imu", "gnss", "truth")]
    stale = [f for f in other if f.exists()]  # left beside the new files they would pass for this run's
    inputs = list(inputs)
    if raw_cfg is not None and raw_cfg.constellation.startswith("nav:"):
        inputs.append(raw_cfg.constellation[4:])
    check_outputs(files + stale + ([out / "scenario.png"] if plot else []), inputs, overwrite)
    return files, stale


def raw_start_sow(sim: Simulation) -> float:
    """GPS seconds of week of scenario time 0 of a simulation with raw GNSS."""
    from ..gnss.time import week_sow

    return float(week_sow(sim.raw.t0_gps)[1])


def _write_raw(sim, obs_path, nav_path, truth_path):
    from ..files import write_csv
    from ..gnss.rinex_write import write_nav, write_obs
    from ..gnss.time import week_sow

    raw, sc = sim.raw, sim.scenario
    week, sow0 = week_sow(raw.t0_gps)
    r = sc.raw_gnss
    comments = [f"inskit simulate: scenario {sc.name}",
                f"constellation {r.constellation}"[:60],
                f"scenario time 0 = GPS week {int(week)} {float(sow0):.3f} s",
                "time tags: receiver clock (offset in raw_truth.csv)",
                (f"iono: Klobuchar x {r.iono_scale:g}; tropo: "
                 f"{'Saastamoinen' if r.troposphere else 'none'}")]
    write_obs(obs_path, time=raw.time, sats=raw.sats, obs=raw.obs, lli=raw.lli, approx_position_e=raw.r_e[0],
              header_comments=comments, interval_s=1.0 / r.rate_hz, marker_name=sc.name[:60])
    write_nav(nav_path, raw.nav, iono_alpha=raw.iono_alpha, iono_beta=raw.iono_beta,
              header_comments=[f"inskit simulate: scenario {sc.name}"[:60], f"constellation {r.constellation}"[:60]])
    write_csv(truth_path, {
        "time_s": week_sow(raw.time)[1],
        "true_time_s": float(sow0) + (raw.t_sim - raw.clock_bias_s),   # full precision (not via 1.4e9 s floats)
        "clock_bias_s": raw.clock_bias_s,
        "clock_drift_s_s": raw.clock_drift_s_s,
        "n_visible": raw.n_visible,
        "n_blocked": raw.blocked.sum(axis=1),
        "x_e_m": raw.r_e[:, 0], "y_e_m": raw.r_e[:, 1], "z_e_m": raw.r_e[:, 2],
        "vx_e_m_s": raw.v_e[:, 0], "vy_e_m_s": raw.v_e[:, 1], "vz_e_m_s": raw.v_e[:, 2],
    }, float_format="%.15g")


#: most GNSS fixes drawn as dots on the scenario's track (an even stride beyond: an outage stays a gap)
MAX_FIX_DOTS = 2000


def _plot(sim, path):
    """``scenario.png``: the truth track over the GNSS fixes, speed, height
    and attitude, drawn from thinned rows (each bin's extremes,
    :func:`inskit.jobs.plots._thin`)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    from .. import earth
    from .plots import MAX_LINE_POINTS, _thin, _thin_line

    tr = sim.truth
    k = _thin(len(tr.time), [tr.lla[:, 0], tr.lla[:, 1]], 4 * MAX_LINE_POINTS)
    p = earth.lla_to_ned(tr.lla[k], tr.lla[0])
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    # the fixes under the track, light and thinned: drawn over it, 1843 grey dots of the car's 31 min hid the
    # whole line (and 14 400 of a 4 h drive would)
    g = earth.lla_to_ned(sim.gnss.lla, tr.lla[0])
    step = max(1, -(-len(g) // MAX_FIX_DOTS))
    ax[0, 0].plot(g[::step, 1], g[::step, 0], ".", ms=2.5, color="0.6", zorder=1)
    ax[0, 0].plot(p[:, 1], p[:, 0], lw=1.0, color="tab:blue", zorder=2)
    # equal scales by widening the data limits: a long north-south drive kept a narrow frame
    ax[0, 0].set_aspect("equal", adjustable="datalim")
    ax[0, 0].set_xlabel("east [m]")
    ax[0, 0].set_ylabel("north [m]")
    ax[0, 0].set_title(f"{sim.scenario.name}: track")
    fixes = f"GNSS fixes ({len(g)}" + (f", every {step}th drawn)" if step > 1 else ")")
    ax[0, 0].legend(handles=[Line2D([], [], color="tab:blue", lw=1.0, label="truth"),
                             Line2D([], [], ls="none", marker=".", ms=5, color="0.6", label=fixes)],
                    fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, frameon=False)
    speed = np.linalg.norm(tr.v_n, axis=1)
    k = _thin(len(tr.time), [speed, tr.lla[:, 2]])
    ax[0, 1].plot(tr.time[k], speed[k])
    ax[0, 1].set_ylabel("speed [m/s]")
    ax[1, 0].plot(tr.time[k], tr.lla[k, 2])
    ax[1, 0].set_ylabel("height [m]")
    rpy = np.degrees(tr.euler)
    for j, nme in enumerate(("roll", "pitch", "yaw")):  # broken at the +-180 deg wrap: no swing drawn there
        ax[1, 1].plot(*_thin_line(tr.time, rpy[:, j], period=360.0), lw=0.8, label=nme)
    # below the frame: inside it, the legend hid the yaw held at 180 deg
    ax[1, 1].legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=3, frameon=False)
    ax[1, 1].set_ylabel("attitude [deg]")
    for a in (ax[0, 1], ax[1, 0], ax[1, 1]):
        a.set_xlabel("time [s]")
        a.grid(alpha=0.3)
    ax[0, 0].grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path, dpi=100)
    return path


def clipping_warnings(sc: Scenario, sim: Simulation) -> list[str]:
    """What the IMU's saturation (``[imu] gyro`` / ``accel`` ``saturation``,
    or a grade's) clipped, in words: the rows with a reading at the limit
    and the largest true rate or specific force of the run.  Clipping is the
    model's (the file holds the clipped readings); a limit below the motion,
    below 1 g for an accelerometer at rest, was taken in silence."""
    from ..simulation.scenario import imu_errors
    from ..units import DEG, G0

    errors = imu_errors(sc)
    out = []
    for name, what, e, unit, k in (("gyro", "rate", errors.gyro, "deg/s", DEG),
                                   ("accel", "specific force", errors.accel, "g", G0)):
        n = int(sim.draws.get(f"{name}_clipped_rows", 0))
        if n:
            out.append(f"field 'imu.{name}' (saturation, or the grade's): the limit of {e.saturation / k:g} {unit} "
                       f"clipped the readings of {n} of {len(sim.imu) - 1} IMU rows (the run's {what} reaches "
                       f"{sim.draws[f'{name}_peak'] / k:.4g} {unit} on an axis): the IMU file holds the clipped "
                       "readings, and a navigation from it drifts while they last")
    return out


def verify_ideal(sc: Scenario, frames=None):
    """Mechanize the scenario's ideal IMU at its rate and at twice its rate and
    report how closely each reproduces the truth (the simulator's self-check),
    simulation and mechanization with the scenario's gravity model.

    ``frames`` default: ``("ned",)``, or ``("wander",)`` for a scenario that
    comes within 0.1 deg of a pole, where the NED mechanization is singular
    (``simulate --verify`` of a log at rest on the pole said 'use the
    wander-azimuth or ECEF frame (... --frame wander|ecef ...)', an option
    simulate has not)."""
    from .. import earth
    from ..strapdown import POLE_LIMIT, mechanize

    tr = build_trajectory(sc, np.random.default_rng(0))
    if frames is None:
        lat = tr.navigation(np.arange(0.0, tr.duration, 1.0))[1][:, 0]
        frames = ("ned",) if np.all(np.abs(lat) < POLE_LIMIT) else ("wander",)
    out = {}
    for frame in frames:
        errs = []
        for mult in (1, 2):
            t = np.arange(0.0, tr.duration, 1.0 / (sc.imu.rate_hz * mult))
            imu = ideal_imu(tr, t, nodes=sc.imu.quadrature_nodes, gravity=sc.earth.gravity)
            truth = truth_solution(tr, t)
            sol = mechanize(imu, truth.state(0), frame=frame, gravity=sc.earth.gravity)
            d = earth.lla_to_ned(sol.lla, truth.lla[0]) - earth.lla_to_ned(truth.lla, truth.lla[0])
            errs.append((float(np.hypot(d[:, 0], d[:, 1]).max()), float(np.abs(d[:, 2]).max())))
        out[frame] = {"rate_hz": sc.imu.rate_hz, "horizontal_max_m": errs[0][0], "vertical_max_m": errs[0][1],
                      "double_rate_horizontal_max_m": errs[1][0],
                      "improvement_at_double_rate": errs[0][0] / max(errs[1][0], 1e-300)}
    return {"duration_s": tr.duration, "gravity": sc.earth.gravity, "frames": out}
