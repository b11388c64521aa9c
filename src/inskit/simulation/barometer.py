"""Simulated barometric altimeter of a trajectory's truth.

The sensor reads the height of its point with an offset that drifts with
the weather, and white noise:

``z = h - (C_nb l_b)_d + b0 + b_rw(t) + n``,

``b0`` a constant (the altimeter's datum: the pressure setting, the geoid),
``b_rw`` a random walk of PSD ``rw**2`` starting at 0, ``n`` white of sigma
``noise_m``; optionally rounded to a resolution.  This is the model the
filter's :class:`inskit.integration.aiding.Height` measures with a
random-walk :class:`inskit.integration.blocks.HeightBias` (Groves 2013
§6.2.1).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import InputError
from ..types import NavSolution


class BarometerLog(NamedTuple):
    """Simulated barometer readings.

    Attributes
    ----------
    time : (m,) ndarray
        [s], the truth's time base.
    height_m : (m,) ndarray
        Measured height [m].
    bias_m : (m,) ndarray
        The true offset ``b0 + b_rw(t)`` of each reading [m] (for tests).
    height_true_m : (m,) ndarray
        True height of the sensor point [m].
    """

    time: np.ndarray
    height_m: np.ndarray
    bias_m: np.ndarray
    height_true_m: np.ndarray


def simulate_barometer(truth: NavSolution, *, rate_hz=10.0, bias_m=0.0, bias_rw_m_sqrt_s=0.0, noise_m=0.5,
                       lever_arm_b=(0.0, 0.0, 0.0), resolution_m=0.0, rng=None) -> BarometerLog:
    """Barometric heights of a true trajectory.

    Parameters
    ----------
    truth : NavSolution
        The true solution (``time``, ``lla``, ``q_nb``).
    rate_hz : float
        Output rate [Hz]; readings at ``t0, t0 + 1 / rate, ...`` inside the
        truth's span, the true height interpolated linearly between truth
        samples.
    bias_m : float
        Constant offset ``b0`` [m].
    bias_rw_m_sqrt_s : float
        Random walk of the offset [m/sqrt(s)] (>= 0): its drift after ``t``
        seconds has sigma ``bias_rw_m_sqrt_s sqrt(t)``.
    noise_m : float
        1-sigma white noise [m] (>= 0).
    lever_arm_b : (3,) array_like
        Sensor point from the truth point, body axes [m].
    resolution_m : float
        Round readings to this step [m] (0: none).
    rng : numpy.random.Generator
        Required when there is noise or a random walk.

    Returns
    -------
    BarometerLog
    """
    if not rate_hz > 0:
        raise InputError(f"`rate_hz` must be > 0, got {rate_hz}")
    for name, v in (("noise_m", noise_m), ("bias_rw_m_sqrt_s", bias_rw_m_sqrt_s), ("resolution_m", resolution_m)):
        if not (np.isfinite(v) and v >= 0):
            raise InputError(f"`{name}` must be finite and >= 0, got {v}")
    if not np.isfinite(bias_m):
        raise InputError(f"`bias_m` must be finite, got {bias_m}")
    if (noise_m > 0 or bias_rw_m_sqrt_s > 0) and rng is None:
        raise InputError("simulate_barometer needs an `rng` (numpy.random.Generator) for its noise")
    lev = np.asarray(lever_arm_b, float)
    if lev.shape != (3,) or not np.isfinite(lev).all():
        raise InputError(f"`lever_arm_b` must be three finite numbers [m], got {lever_arm_b!r}")
    h = truth.lla[:, 2]
    if lev.any():
        h = h - np.einsum("nj,j->n", truth.C_nb[:, 2, :], lev)
    t0, t1 = float(truth.time[0]), float(truth.time[-1])
    t = t0 + np.arange(int(np.floor((t1 - t0) * rate_hz + 1e-9)) + 1) / rate_hz
    true = np.interp(t, truth.time, h)
    b = np.full(len(t), float(bias_m))
    if bias_rw_m_sqrt_s > 0:
        steps = bias_rw_m_sqrt_s * np.sqrt(np.diff(t)) * rng.standard_normal(len(t) - 1)
        b[1:] += np.cumsum(steps)
    z = true + b
    if noise_m > 0:
        z = z + noise_m * rng.standard_normal(len(t))
    if resolution_m > 0:
        z = np.round(z / resolution_m) * resolution_m
    return BarometerLog(t, z, b, true)
