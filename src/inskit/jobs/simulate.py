"""The simulate job: write a simulated scenario to files, plot it, and the
simulator's self-check (its ideal IMU mechanized against its truth)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..files import save_figure
from .. import io
from ..errors import InputError
from ..simulation.imu import ideal_imu, truth_solution
from ..simulation.scenario import Scenario, Simulation, build_trajectory


def write_simulation(sim: Simulation, out_dir, *, overwrite=False, plot=True):
    """Write ``imu.csv`` (increments), ``gnss.csv``, ``truth.csv`` and a plot."""
    out = Path(out_dir)
    files = [out / "imu.csv", out / "gnss.csv", out / "truth.csv"]
    if not overwrite:
        for f in files:
            if f.exists():
                raise InputError(f"{f}: already exists; refusing to overwrite it (use --force)")
    out.mkdir(parents=True, exist_ok=True)
    io.write_imu(files[0], sim.imu, overwrite=True)
    io.write_gnss(files[1], sim.gnss, overwrite=True)
    io.write_solution(files[2], sim.truth, overwrite=True)
    if plot:
        files.append(_plot(sim, out / "scenario.png"))
    return files


def _plot(sim, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .. import earth

    tr = sim.truth
    p = earth.lla_to_ned(tr.lla[::10], tr.lla[0])
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    ax[0, 0].plot(p[:, 1], p[:, 0], lw=0.8)
    g = earth.lla_to_ned(sim.gnss.lla, tr.lla[0])
    ax[0, 0].plot(g[:, 1], g[:, 0], ".", ms=1.5, color="0.5")
    ax[0, 0].set_aspect("equal")
    ax[0, 0].set_xlabel("east [m]")
    ax[0, 0].set_ylabel("north [m]")
    ax[0, 0].set_title(f"{sim.scenario.name}: track (dots: GNSS)")
    tt = tr.time[::10]
    ax[0, 1].plot(tt, np.linalg.norm(tr.v_n[::10], axis=1))
    ax[0, 1].set_ylabel("speed [m/s]")
    ax[1, 0].plot(tt, tr.lla[::10, 2])
    ax[1, 0].set_ylabel("height [m]")
    rpy = np.degrees(tr.euler[::10])
    for j, nme in enumerate(("roll", "pitch", "yaw")):
        ax[1, 1].plot(tt, rpy[:, j], lw=0.8, label=nme)
    ax[1, 1].legend(fontsize=8)
    ax[1, 1].set_ylabel("attitude [deg]")
    for a in (ax[0, 1], ax[1, 0], ax[1, 1]):
        a.set_xlabel("time [s]")
        a.grid(alpha=0.3)
    ax[0, 0].grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path, dpi=100)
    return path


def verify_ideal(sc: Scenario, frames=("ned",)):
    """Mechanize the scenario's ideal IMU at its rate and at twice its rate and
    report how closely each reproduces the truth (the simulator's self-check)."""
    from .. import earth
    from ..strapdown import mechanize

    tr = build_trajectory(sc, np.random.default_rng(0))
    out = {}
    for frame in frames:
        errs = []
        for mult in (1, 2):
            t = np.arange(0.0, tr.duration, 1.0 / (sc.imu.rate_hz * mult))
            imu = ideal_imu(tr, t, nodes=sc.imu.quadrature_nodes)
            truth = truth_solution(tr, t)
            sol = mechanize(imu, truth.state(0), frame=frame)
            d = earth.lla_to_ned(sol.lla, truth.lla[0]) - earth.lla_to_ned(truth.lla, truth.lla[0])
            errs.append((float(np.hypot(d[:, 0], d[:, 1]).max()), float(np.abs(d[:, 2]).max())))
        out[frame] = {"rate_hz": sc.imu.rate_hz, "horizontal_max_m": errs[0][0], "vertical_max_m": errs[0][1],
                      "double_rate_horizontal_max_m": errs[1][0],
                      "improvement_at_double_rate": errs[0][0] / max(errs[1][0], 1e-300)}
    return {"duration_s": tr.duration, "frames": out}
