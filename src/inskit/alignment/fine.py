"""Fine alignment: a stationary Kalman filter with zero-velocity updates.

The closed-loop error-state filter of :mod:`inskit.integration` runs over the
static interval from a coarse attitude, with ZUPTs only.  Roll and pitch
converge in seconds (velocity errors from tilt); heading converges by
gyrocompassing (the east gyro sees the Earth rate's north component), at a
speed set by the gyro noise and bias: ``sigma_yaw ~ D_east / (W cos(phi))``
at best.  The report carries the time each angle took to converge, so the
one-step (analytic) and two-step (analytic + fine) alignments can be
compared in accuracy and in time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..integration import FilterSettings, InitialUncertainty, SensorNoise, ZeroVelocity, run_filter
from ..types import ImuData, NavState


@dataclass(frozen=True)
class FineAlignment:
    """Result of :func:`fine_align`.

    Attributes
    ----------
    rpy : (3,) ndarray
        Final roll, pitch, yaw [rad].
    sigma_rpy : (3,) ndarray
        Final 1-sigma of the attitude errors about north, east, down [rad].
    converge_time_s : (3,) ndarray
        Time after the start when each sigma came (and stayed) within 10 % of
        its final value; NaN when it did not shrink by half at all.
    time : (n,) ndarray
    sigma_history : (n, 3) ndarray
    """

    rpy: np.ndarray
    sigma_rpy: np.ndarray
    converge_time_s: np.ndarray
    time: np.ndarray
    sigma_history: np.ndarray


def fine_align(imu: ImuData, coarse: NavState, noise: SensorNoise, *, sigma_tilt=np.radians(1.0),
               sigma_yaw=np.radians(5.0), gyro_bias_sigma=np.radians(0.01), accel_bias_sigma=0.01,
               zupt_sigma=0.01, rate_hz=10.0, gyro_bias0=(0.0, 0.0, 0.0)) -> FineAlignment:
    """Stationary Kalman-filter alignment over the whole of ``imu``."""
    init = InitialUncertainty(pos_m=(0.1, 0.1, 0.1), vel_m_s=0.01, roll_pitch_rad=sigma_tilt, yaw_rad=sigma_yaw,
                              gyro_bias=gyro_bias_sigma, accel_bias=accel_bias_sigma)
    settings = FilterSettings.standard(noise, init, gate_probability=None, gyro_bias0=tuple(gyro_bias0))
    z = ZeroVelocity([(imu.time[0], imu.time[-1])], rate_hz, zupt_sigma)
    out = run_filter(imu, coarse, [z], settings)
    sol = out.nav
    sig = out.sigma_of("att")
    final = sig[-1]
    conv = np.full(3, np.nan)
    t0 = sol.time[0]
    for j in range(3):
        if final[j] < 0.5 * sig[0, j]:
            above = np.nonzero(sig[:, j] > 1.1 * final[j])[0]
            conv[j] = sol.time[above[-1] + 1] - t0 if len(above) else 0.0
    return FineAlignment(sol.euler[-1], final, conv, sol.time, sig)
