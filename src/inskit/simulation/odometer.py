"""Simulated odometer (wheel speed) of a trajectory's truth.

The sensor reads the speed of its point along the body forward axis,

``z = Q((1 + k) x_b^T (C_nb^T v_n + omega_ib_b x l_b) + n)``,

with scale-factor error ``k``, white noise ``n`` of sigma ``noise_m_s`` and
optional rounding ``Q`` to a resolution (a wheel-tick count per interval
turned into a speed).  This is the model the filter's
:class:`inskit.integration.aiding.Odometer` measures (Groves 2013 §6.3.1).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import InputError
from ..types import NavSolution


class OdometerLog(NamedTuple):
    """Simulated odometer readings (unpacks as ``time, speed, true speed``).

    Attributes
    ----------
    time : (m,) ndarray
        [s], the truth's time base.
    speed_m_s : (m,) ndarray
        Measured forward speed [m/s] (signed).
    speed_true_m_s : (m,) ndarray
        True forward speed of the odometer point [m/s] (for tests).
    """

    time: np.ndarray
    speed_m_s: np.ndarray
    speed_true_m_s: np.ndarray


def simulate_odometer(truth: NavSolution, *, rate_hz=10.0, scale_error=0.005, noise_m_s=0.05,
                      lever_arm_b=(0.0, 0.0, 0.0), resolution_m_s=0.0, rng=None) -> OdometerLog:
    """Odometer readings of a true trajectory.

    Parameters
    ----------
    truth : NavSolution
        The true solution (``time``, ``v_n``, ``q_nb``); with a non-zero
        ``lever_arm_b`` it must carry the body rate in ``extra``
        (``wx_rad_s, wy_rad_s, wz_rad_s``: ``truth_solution(...,
        with_rates=True)``, as :func:`.scenario.simulate` makes it).
    rate_hz : float
        Output rate [Hz]; readings at ``t0, t0 + 1 / rate, ...`` inside the
        truth's span, the true speed interpolated linearly between truth
        samples (exact to 1 mm/s for 2 m/s^2 at 100 Hz truth... the
        interpolation error is ``a' dt^2 / 8``, jerk times dt^2 / 8).
    scale_error : float
        ``k`` [-]: the reading is ``(1 + k)`` times the true speed.
    noise_m_s : float
        1-sigma white noise [m/s] (>= 0).
    lever_arm_b : (3,) array_like
        Odometer point from the truth point, body axes [m].
    resolution_m_s : float
        Round readings to this step [m/s] (0: no rounding).
    rng : numpy.random.Generator
        Required when ``noise_m_s > 0``.

    Returns
    -------
    OdometerLog
    """
    if not rate_hz > 0:
        raise InputError(f"`rate_hz` must be > 0, got {rate_hz}")
    if not noise_m_s >= 0 or not resolution_m_s >= 0:
        raise InputError(f"`noise_m_s` and `resolution_m_s` must be >= 0, got {noise_m_s}, {resolution_m_s}")
    if not np.isfinite(scale_error) or not abs(scale_error) < 0.5:
        raise InputError(f"`scale_error` must be a small fraction (|k| < 0.5), got {scale_error}")
    if noise_m_s > 0 and rng is None:
        raise InputError("simulate_odometer needs an `rng` (numpy.random.Generator) for its noise")
    lev = np.asarray(lever_arm_b, float)
    if lev.shape != (3,) or not np.isfinite(lev).all():
        raise InputError(f"`lever_arm_b` must be three finite numbers [m], got {lever_arm_b!r}")
    C_nb = truth.C_nb
    v_b = np.einsum("nji,nj->ni", C_nb, truth.v_n)  # C_bn v_n
    if lev.any():
        names = ("wx_rad_s", "wy_rad_s", "wz_rad_s")
        if not all(n in truth.extra for n in names):
            raise InputError("an odometer lever arm needs the true body rate in truth.extra (wx_rad_s, wy_rad_s, "
                             "wz_rad_s): make the truth with with_rates=True")
        w = np.stack([truth.extra[n] for n in names], axis=1)
        v_b = v_b + np.cross(w, lev)
    t0, t1 = float(truth.time[0]), float(truth.time[-1])
    t = t0 + np.arange(int(np.floor((t1 - t0) * rate_hz + 1e-9)) + 1) / rate_hz
    true = np.interp(t, truth.time, v_b[:, 0])
    z = (1.0 + scale_error) * true
    if noise_m_s > 0:
        z = z + noise_m_s * rng.standard_normal(len(t))
    if resolution_m_s > 0:
        z = np.round(z / resolution_m_s) * resolution_m_s
    return OdometerLog(t, z, true)
