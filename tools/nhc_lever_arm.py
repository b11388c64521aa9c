"""Estimate the non-holonomic constraint's lever arm from a drive's own data.

The lateral velocity of a car is zero at the centre of its unsteered rear
axle, not at the IMU: at the IMU it is ``v_y = -(omega x l)_y = -(omega_z
l_x - omega_x l_z)`` (``l``: IMU to that point, body axes).  This runs the
config with the constraint and the mounting states off (the velocity and
attitude then come from the GNSS fixes alone), RTS-smoothed, with the
config's own outages withheld, and fits over the moving samples outside
those outages (never the withheld fixes)

    v_y = a + psi v_x - omega_z l_x + omega_x l_z

(``psi``: the residual boresight yaw) by least squares, on 0.1 s means of
the body rate and velocity.  The vertical row's ``(omega x l)_z = omega_x l_y
- omega_y l_x`` is fitted the same way and printed for comparison (the pitch
of the body over bumps turns about the middle of the wheelbase instead).

Usage: ``PYTHONPATH=src python tools/nhc_lever_arm.py examples/drive_0708.toml``
"""

from __future__ import annotations

import sys

import numpy as np

from inskit import api
from inskit.rotations import dcm_from_quat


def _mean(x, k=10):
    ker = np.ones(k) / k
    return np.stack([np.convolve(x[:, i], ker, "same") for i in range(x.shape[1])], axis=1)


def main(config, min_speed=3.0, margin_s=1.0):
    from inskit.jobs.config import ConstraintsSection

    # the constraint's own keys back at their defaults: with nhc = false they would be ignored (and are refused)
    off = {k: ConstraintsSection.model_fields[k].default for k in ("nhc_sigma_m_s", "nhc_lever_arm_b_m")}
    run = api.navigate(config, smooth=True, constraints={"nhc": False, "mounting": False, **off},
                       output={"stream": "off"})
    sol, imu, windows = run.smoothed, run.details.imu, run.details.windows
    dt = np.diff(imu.time, prepend=imu.time[0] - np.median(np.diff(imu.time)))
    w = _mean(imu.dtheta_b / dt[:, None])
    C = np.array([dcm_from_quat(q) for q in sol.q_nb])
    v_b = _mean(np.einsum("nji,nj->ni", C, sol.v_n))
    m = np.linalg.norm(sol.v_n, axis=1) > min_speed
    for a, b in windows:  # the withheld stretches, and the smoother's reach back into them
        m &= (sol.time < a - margin_s) | (sol.time > b + margin_s)
    one, vx = np.ones(m.sum()), v_b[m, 0]
    A = np.column_stack([one, vx, -w[m, 2], w[m, 0]])
    x = np.linalg.lstsq(A, v_b[m, 1], rcond=None)[0]
    _, psi, lx, lz = x
    r = v_b[m, 1] - A @ x
    print(f"lateral row: l_x = {lx:.3f} m, l_z = {lz:.3f} m (boresight yaw {np.degrees(psi):.2f} deg); "
          f"residual {r.std():.3f} m/s against {v_b[m, 1].std():.3f} m/s at l = 0, over {m.sum()} samples")
    A = np.column_stack([one, vx, w[m, 0], -w[m, 1]])
    _, _, ly, lx_v = np.linalg.lstsq(A, v_b[m, 2], rcond=None)[0]
    print(f"vertical row: l_x = {-lx_v:.3f} m, l_y = {-ly:.3f} m")
    print(f"[constraints]\nnhc_lever_arm_b_m = [{lx:.2f}, 0.0, {lz:.2f}]")


if __name__ == "__main__":
    main(sys.argv[1])
