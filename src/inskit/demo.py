"""A built-in demonstration run: closed-form motion, all four mechanizations.

Used by ``inskit run`` until the integration job on real data replaces it.
"""

from __future__ import annotations

import time

import numpy as np

from . import analysis
from .simulation import HarmonicTrajectory, ideal_imu, truth_solution
from .strapdown import FRAMES, mechanize

DEMO_TRAJECTORY = HarmonicTrajectory(
    (np.radians(40.0), np.radians(-105.0), 1500.0),
    north=(0.0, 8.0, [(300.0, 0.02, 0.0), (40.0, 0.11, 1.0)]),
    east=(0.0, 5.0, [(500.0, 0.015, 0.5), (30.0, 0.09, 0.2)]),
    up=(0.0, 0.0, [(30.0, 0.01, 0.0), (5.0, 0.05, 0.3)]),
    roll=(0.0, 0.0, [(0.2, 0.1, 0.0)]),
    pitch=(0.02, 0.0, [(0.1, 0.07, 0.4)]),
    yaw=(0.5, 0.01, [(0.8, 0.03, 0.0)]),
)


def demo_run(log=print):
    t = np.arange(0.0, 600.0 + 1e-9, 0.01)
    log("demo: 10 min closed-form drive at 100 Hz, ideal IMU, free-inertial in four frames")
    imu = ideal_imu(DEMO_TRAJECTORY, t)
    truth = truth_solution(DEMO_TRAJECTORY, t)
    res = {"job": "demo-closed-form", "epochs": len(t), "frames": {}}
    lines = [f"{'frame':<10}{'horiz max m':>14}{'vert max m':>12}{'att max arcsec':>16}{'time s':>9}"]
    for frame in FRAMES:
        t0 = time.perf_counter()
        sol = mechanize(imu, truth.state(0), frame=frame)
        dt = time.perf_counter() - t0
        s = analysis.summarize(analysis.nav_error(sol, truth))
        att = max(s[k]["max"] for k in ("roll_arcmin", "pitch_arcmin", "yaw_arcmin")) * 60
        res["frames"][frame] = {"horizontal_max_m": s["horizontal_m"]["max"], "down_max_m": s["down_m"]["max"],
                                "attitude_max_arcsec": att, "elapsed_s": dt}
        lines.append(f"{frame:<10}{s['horizontal_m']['max']:>14.5f}{s['down_m']['max']:>12.5f}{att:>16.6f}{dt:>9.3f}")
    return res, "\n".join(lines)
