"""Height aiding for ``inskit navigate`` (the ``[height]`` section): a
barometer's log, a known height profile or a constant height, as a
:class:`~inskit.integration.aiding.Height` measurement with, optionally, the
sensor's offset as a :class:`~inskit.integration.blocks.HeightBias` state."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .. import io
from ..errors import InputError
from ..types import ImuData


def height_series(cfg, imu: ImuData):
    """The heights to fuse, ``(time, height, sigma)`` [s, m, m]: the
    ``[height]`` file's readings shifted by ``time_offset_s`` and thinned to
    ``rate_hz`` (the first reading of each ``1 / rate_hz`` slot), or the
    constant ``height_m`` on a ``rate_hz`` grid over the IMU's span; both
    plus ``offset_m``.

    Raises
    ------
    InputError
        A log that does not overlap the IMU's, or ``sigma_m`` set beside a
        file that has its own sigma_m column (it would be ignored).
    """
    h = cfg.height
    if h.file is None:
        t = np.arange(imu.time[0], imu.time[-1], 1.0 / h.rate_hz)
        z = np.full(len(t), float(h.height_m))
        s = np.full(len(t), h.sigma_m)
    else:
        path = cfg.resolve(h.file)
        t, z, s = io.read_height(path)
        if s is None:
            s = np.full(len(t), h.sigma_m)
        elif "sigma_m" in h.model_fields_set:
            raise InputError(f"{path.name}: the file has a sigma_m column, so height.sigma_m = {h.sigma_m:g} would "
                             "be ignored; remove one of them")
        t = t + h.time_offset_s
        if t[-1] < imu.time[0] or t[0] > imu.time[-1]:
            raise InputError(f"{path.name}: height times {t[0]:.3f}..{t[-1]:.3f} s do not overlap the IMU's "
                             f"{imu.time[0]:.3f}..{imu.time[-1]:.3f} s: mismatched time bases? "
                             "(height.time_offset_s)")
        if len(t) > 1:
            keep = np.r_[True, np.diff(np.floor(t * h.rate_hz)) > 0]
            t, z, s = t[keep], z[keep], s[keep]
    return t, z + h.offset_m, s


def height_aiding(cfg, imu: ImuData):
    """The ``[height]`` measurement and its state blocks: ``(Height, [HeightBias])``
    (no block without ``estimate_bias``)."""
    from ..integration import Height, HeightBias

    h = cfg.height
    t, z, s = height_series(cfg, imu)
    meas = Height(t, z, s, lever_arm_b=h.lever_arm_b_m)
    if not h.estimate_bias:
        return meas, []
    rw = h.bias_rw_m_sqrt_h / 60.0  # m/sqrt(h) -> m/sqrt(s)
    tau = math.inf if h.bias_tau_s is None else h.bias_tau_s
    return meas, [HeightBias(h.bias_sigma0_m, h.bias_model, rw=rw, tau_s=tau)]


def height_profile_at(path, t, log=None):
    """A height log (:func:`inskit.io.read_height`) interpolated linearly
    onto the times ``t`` [s] (for the height channel of a free-inertial
    mechanization, ``inskit mechanize --height aid --height-ref FILE``).
    Outside the log's span its first or last height is held, and ``log``
    is told how long.

    Raises
    ------
    InputError
        A log that does not overlap ``t``.
    """
    path = Path(path)
    th, z, _ = io.read_height(path)
    t = np.asarray(t, float)
    if th[-1] < t[0] or th[0] > t[-1]:
        raise InputError(f"{path.name}: height times {th[0]:.3f}..{th[-1]:.3f} s do not overlap the IMU's "
                         f"{t[0]:.3f}..{t[-1]:.3f} s: mismatched time bases?")
    held = float(max(th[0] - t[0], 0.0) + max(t[-1] - th[-1], 0.0))
    if held > 0 and log:
        log(f"warning: {path.name} covers {th[0]:.3f}..{th[-1]:.3f} s of the IMU's {t[0]:.3f}..{t[-1]:.3f} s: its "
            f"end heights are held over {held:.3f} s")
    return np.interp(t, th, z)
