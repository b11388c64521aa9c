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
        A log that does not overlap the IMU's or whose time column is in
        milliseconds (:func:`inskit.jobs.navigate.refuse_no_overlap`), or ``sigma_m`` set beside a
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
        from .navigate import refuse_no_overlap  # the odometer's rule: no overlap, or a time column in ms

        refuse_no_overlap(path, "height", t, imu, "height.time_offset_s")
        if len(t) > 1:
            keep = np.r_[True, np.diff(np.floor(t * h.rate_hz)) > 0]
            t, z, s = t[keep], z[keep], s[keep]
    return t, z + h.offset_m, s


#: a height log whose changes are not the fixes' (the slope of one against the other) outside this band is refused
HEIGHT_SCALE_BAND = (0.8, 1.25)
#: the fixes must climb or descend this much [m] (5th to 95th percentile) for the scale to be judged
HEIGHT_SCALE_MIN_RANGE_M = 5.0


def check_height_scale(path, t, z, gnss):
    """Refuse a height log whose changes are not the GNSS fixes' heights'
    changes: the least-squares slope of its heights against the fixes'
    (interpolated to its times) outside :data:`HEIGHT_SCALE_BAND` (a
    barometer in feet, 3.28, went ahead: the filter refused its NHC as
    'not holding' and ended 253 km off).  A constant offset is the bias
    state's; silent when the fixes vary by less than
    :data:`HEIGHT_SCALE_MIN_RANGE_M` or overlap fewer than 10 readings."""
    if gnss is None or len(gnss.time) < 3:
        return
    inside = (t >= gnss.time[0]) & (t <= gnss.time[-1])
    if inside.sum() < 10:
        return
    hg = np.interp(t[inside], gnss.time, gnss.lla[:, 2])
    lo5, hi95 = np.percentile(hg, [5, 95])
    if hi95 - lo5 < HEIGHT_SCALE_MIN_RANGE_M:
        return
    zz = np.asarray(z, float)[inside]
    dg = hg - hg.mean()
    slope = float(np.dot(dg, zz - zz.mean()) / np.dot(dg, dg))
    lo, hi = HEIGHT_SCALE_BAND
    if not lo <= slope <= hi:
        hint = (" (feet read as metres?)" if abs(slope - 3.2808) < 0.3 else
                " (metres read as feet?)" if abs(slope - 0.3048) < 0.03 else "")
        raise InputError(f"{path}: its heights change {slope:.3g} times as much as the GNSS fixes' heights (slope "
                         f"over {int(inside.sum())} readings, the fixes spanning {hi95 - lo5:.1f} m){hint}; expected "
                         f"{lo:g}..{hi:g}: heights must be metres (a constant offset is the bias state's)")


def height_aiding(cfg, imu: ImuData, gnss=None):
    """The ``[height]`` measurement and its state blocks: ``(Height, [HeightBias])``
    (no block without ``estimate_bias``); a height log is checked against the
    fixes' heights ``gnss`` (:func:`check_height_scale`)."""
    from ..integration import Height, HeightBias

    h = cfg.height
    t, z, s = height_series(cfg, imu)
    if h.file is not None:
        check_height_scale(cfg.resolve(h.file).name, t, z, gnss)
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
