"""A built-in demonstration run: closed-form motion, all four mechanizations.

Used by ``inskit run`` until the integration job on real data replaces it.
"""

from __future__ import annotations

import time

import numpy as np

from .. import analysis
from ..simulation import HarmonicTrajectory, ideal_imu, truth_solution
from ..strapdown import FRAMES, mechanize

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


def closed_form_checks(log=print):
    """The closed-form checks of the mechanizations, measured (issue 2):
    stationary 1 h, Schuler 3 h, coning 10 min at two rates."""
    from .. import earth
    from .. import rotations as rot
    from ..simulation import ConingTrajectory, StationaryTrajectory
    from ..types import ImuData
    from ..units import ARCSEC, MICRO_G

    out = {}
    lat = np.radians(45.0)
    log("checks: stationary 1 h at 45 deg N, ideal sensors, 100 Hz, height held")
    traj = StationaryTrajectory((lat, np.radians(10.0), 100.0), (0.02, -0.01, 1.0))
    t = np.arange(0.0, 3600.0 + 1e-9, 0.01)
    imu = ideal_imu(traj, t, nodes=1)
    truth = truth_solution(traj, t[:1])
    sol = mechanize(imu, truth.state(0), height="hold", height_ref=100.0)
    d = earth.lla_to_ned(sol.lla, truth.lla[0])
    att = rot.attitude_error(sol.C_nb, np.broadcast_to(truth.C_nb[0], sol.C_nb.shape))
    out["stationary"] = {"horizontal_max_m": float(np.hypot(d[:, 0], d[:, 1]).max()),
                         "attitude_max_arcsec": float(np.linalg.norm(att, axis=1).max() / ARCSEC)}
    log("checks: Schuler, 100 micro-g north accelerometer bias, 3 h")
    traj = StationaryTrajectory((lat, 0.0, 0.0))
    t = np.arange(0.0, 3 * 3600.0 + 1e-9, 0.01)
    imu = ideal_imu(traj, t, nodes=1)
    dv = imu.dv_b.copy()
    b = 100 * MICRO_G
    dv[1:, 0] += b * np.diff(t)
    sol = mechanize(ImuData(t, imu.dtheta_b, dv), truth_solution(traj, t[:1]).state(0), height="hold",
                    height_ref=0.0)
    north = earth.lla_to_ned(sol.lla, np.array([lat, 0.0, 0.0]))[:, 0]
    rn, _ = earth.principal_radii(lat, 0.0)
    ws = np.sqrt(earth.gravity_down(lat, 0.0) / rn)
    vn = sol.v_n[:, 0]
    k = np.where((vn[1:-1] > 0) != (vn[2:] > 0))[0] + 1
    cross = t[k] - vn[k] * (t[k + 1] - t[k]) / (vn[k + 1] - vn[k])
    period = 2.0 * np.mean(np.diff(np.concatenate([[0.0], cross])))
    first = t < 2 * np.pi / ws
    out["schuler"] = {"period_s": float(period), "closed_form_period_s": float(2 * np.pi / ws),
                      "first_peak_m": float(north[first].max()), "closed_form_peak_m": float(2 * b / ws**2)}
    log("checks: coning 1 deg half-angle at 1 Hz, 10 min")
    cone = ConingTrajectory((lat, 0.0, 0.0), (0.0, 0.0, 0.0), np.radians(1.0), 1.0)
    res = {}
    for step, coning in ((0.01, False), (0.01, True), (0.005, True)):
        t = np.arange(0.0, 600.0 + 1e-9, step)
        imu = ideal_imu(cone, t, nodes=8)
        tr = truth_solution(cone, t[[0, -1]])
        s = mechanize(imu, tr.state(0), coning=coning, height="hold", height_ref=0.0)
        res[f"{'two' if coning else 'single'}_sample_{int(round(1 / step))}hz_rad"] = float(
            np.linalg.norm(rot.attitude_error(s.C_nb[-1], tr.C_nb[-1])))
    out["coning_attitude_drift"] = res
    return out
