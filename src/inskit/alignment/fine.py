"""Fine alignment: a stationary Kalman filter with zero-velocity updates.

The closed-loop error-state filter of :mod:`inskit.integration` runs over the
static interval from a coarse attitude, with ZUPTs only.  Roll and pitch
converge in seconds (velocity errors from tilt); heading converges by
gyrocompassing (the east gyro sees the Earth rate's north component), at a
speed set by the gyro noise and bias: ``sigma_yaw ~ D_east / (W cos(phi))``
at best.  The report carries the time each angle took to converge, so the
one-step (analytic) and two-step (analytic + fine) alignments can be
compared in accuracy and in time.

At rest the biases are not separable from the attitude: the filter observes
``tilt + B/g`` and ``W cos(phi) yaw + D_east``, so its final sigmas are only
as good as the bias priors it is given (SYSTEM.md §4, source 002 eq. 29).
The coarse attitude a caller starts from is made of the same data, so its
error *is* ``-B/g`` (and ``-D_east/(W cos(phi))``); a prior of the coarse
error's own size, taken as independent of the bias, would shrink the final
sigma by up to ``sqrt(2)``.  The default initial sigmas are therefore ten
times the bias-implied ones (capped), which leaves the final sigmas at the
bias limit, and an angle whose sigma does not shrink (heading with gyros
whose bias swamps the Earth rate) is never reported as converged.

The reported sigmas are never below that bias limit (:func:`bias_floor`).
The filter alone can fall below it: its closed-loop reset moves the attitude
to first order only, so a heading correction ``eps`` turns the body-axis
accelerometer bias in the navigation frame without turning the tilt error
with it, and the zero innovations that follow look like information that
separates tilt from bias (a consumer-grade 20 s log: tilt sigma 0.2 deg
against the 2.3 deg the 40 mg bias allows).  No data at rest carry that
information.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import earth
from ..integration import FilterSettings, InitialUncertainty, SensorNoise, ZeroVelocity, run_filter
from ..types import ImuData, NavState

#: an angle is "converged" only when its final sigma is below this (a 90 deg
#: prior shrunk to 40 deg is not an alignment)
MAX_CONVERGED_SIGMA = np.radians(30.0)
#: caps of the default initial sigmas (tilt, yaw) [rad]
MAX_SIGMA_TILT0 = np.radians(30.0)
MAX_SIGMA_YAW0 = np.radians(90.0)


@dataclass(frozen=True)
class FineAlignment:
    """Result of :func:`fine_align`.

    Attributes
    ----------
    rpy : (3,) ndarray
        Final roll, pitch, yaw [rad].
    sigma_rpy : (3,) ndarray
        Final 1-sigma of the attitude errors about north, east, down [rad]:
        the filter's, but not below ``sigma_floor``.
    converge_time_s : (3,) ndarray
        Time after the start when each sigma came (and stayed) within 10 % of
        its final value; NaN when it did not shrink by half at all or ended
        above :data:`MAX_CONVERGED_SIGMA` (not observable with these sensors).
    time : (n,) ndarray
    sigma_history : (n, 3) ndarray
        The filter's sigmas about north, east, down at every IMU sample
        [rad]; row 0 holds the initial (prior) sigmas.
    sigma_floor : (3,) ndarray
        :func:`bias_floor` of the priors [rad].
    """

    rpy: np.ndarray
    sigma_rpy: np.ndarray
    converge_time_s: np.ndarray
    time: np.ndarray
    sigma_history: np.ndarray
    sigma_floor: np.ndarray


def bias_floor(lat, accel_bias_sigma, gyro_bias_sigma):
    """The attitude sigmas about north, east, down [rad] that the biases
    alone allow at rest (source 002 eq. 29 in expectation, SYSTEM.md §4):
    ``B/g``, ``B/g``, ``sqrt((D/(W cos phi))^2 + (tan(phi) B/g)^2)``."""
    g = earth.gravity_down(lat, 0.0)
    tilt = accel_bias_sigma / g
    yaw = np.hypot(gyro_bias_sigma / (earth.OMEGA_IE * max(np.cos(lat), 1e-3)), np.tan(lat) * tilt)
    return np.array([tilt, tilt, yaw])


def default_initial_sigmas(lat, accel_bias_sigma, gyro_bias_sigma):
    """Initial tilt and yaw sigmas [rad] for a coarse start made of the same
    static data: ten times the bias-implied errors ``B/g`` and
    ``D/(W cos(phi)) + tan(phi) B/g`` (source 002 eq. 29), at least 0.5 and
    2 deg, at most :data:`MAX_SIGMA_TILT0` and :data:`MAX_SIGMA_YAW0`."""
    tilt, _, yaw = bias_floor(lat, accel_bias_sigma, gyro_bias_sigma)
    return (float(np.clip(10.0 * tilt, np.radians(0.5), MAX_SIGMA_TILT0)),
            float(np.clip(10.0 * yaw, np.radians(2.0), MAX_SIGMA_YAW0)))


def fine_align(imu: ImuData, coarse: NavState, noise: SensorNoise, *, sigma_tilt=None, sigma_yaw=None,
               gyro_bias_sigma=np.radians(0.01), accel_bias_sigma=0.01, zupt_sigma=0.01, rate_hz=10.0,
               gyro_bias0=(0.0, 0.0, 0.0)) -> FineAlignment:
    """Stationary Kalman-filter alignment over the whole of ``imu``.

    Parameters
    ----------
    imu : ImuData
        The static interval; ``imu.time[0]`` is the start.
    coarse : NavState
        The coarse attitude (and position) at ``imu.time[0]``.
    noise : SensorNoise
        White noise and bias random walk of the sensors.
    sigma_tilt, sigma_yaw : float, optional
        Initial attitude sigmas [rad]; default :func:`default_initial_sigmas`
        (for a coarse start from the same data).
    gyro_bias_sigma, accel_bias_sigma : float
        Prior 1-sigma of the turn-on biases [rad/s], [m/s^2] (about
        ``gyro_bias0``): they bound the final sigmas.
    zupt_sigma : float
        Zero-velocity measurement sigma [m/s].
    rate_hz : float
        Rate of the zero-velocity updates.
    gyro_bias0 : (3,) array_like
        Initial gyro-bias estimate [rad/s].

    Returns
    -------
    FineAlignment
    """
    lat = float(coarse.lla[0])
    t0_, y0_ = default_initial_sigmas(lat, accel_bias_sigma, gyro_bias_sigma)
    sigma_tilt = t0_ if sigma_tilt is None else sigma_tilt
    sigma_yaw = y0_ if sigma_yaw is None else sigma_yaw
    init = InitialUncertainty(pos_m=(0.1, 0.1, 0.1), vel_m_s=0.01, roll_pitch_rad=sigma_tilt, yaw_rad=sigma_yaw,
                              gyro_bias=gyro_bias_sigma, accel_bias=accel_bias_sigma)
    settings = FilterSettings.standard(noise, init, gate_probability=None, gyro_bias0=tuple(gyro_bias0))
    z = ZeroVelocity([(imu.time[0], imu.time[-1])], rate_hz, zupt_sigma)
    out = run_filter(imu, coarse, [z], settings)
    sol = out.nav
    sig = out.sigma_of("att")
    floor = bias_floor(lat, accel_bias_sigma, gyro_bias_sigma)
    final = np.maximum(sig[-1], floor)
    conv = np.full(3, np.nan)
    t0 = sol.time[0]
    for j in range(3):
        if final[j] < 0.5 * sig[0, j] and final[j] < MAX_CONVERGED_SIGMA:
            above = np.nonzero(sig[:, j] > 1.1 * final[j])[0]
            conv[j] = sol.time[above[-1] + 1] - t0 if len(above) else 0.0
    return FineAlignment(sol.euler[-1], final, conv, sol.time, sig, floor)
