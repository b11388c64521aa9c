"""In-motion start-up: attitude from the GNSS track while moving, and a bank
of yaw hypotheses for a start with a large heading error.

Levelling in motion.  The accelerometers measure ``f_b = C_bn (a_n - g_n)``
(Groves 2013 eq. 5.54 with the Coriolis and transport terms, below 1e-3
m/s^2 at road speed, left out), so the specific force corrected for the
GNSS-derived acceleration, ``f_b - C_bn a_n = -C_bn g_n``, levels as at rest
(Groves 2013 eq. 5.101).  ``a_n`` is the GNSS velocity differenced over about
a second; ``C_bn`` needs roll, pitch and yaw, so levelling and heading are
iterated (two passes: the correction depends on the attitude only through the
small acceleration).

Heading from the track.  A land vehicle moves along its forward axis, so its
yaw equals the GNSS course once the speed makes the course well defined
(speed well above the velocity noise).  The offset between the course and the
yaw integrated by the gyros from the start (yaw 0 at the first sample) is
averaged over a few seconds of fixes (a circular mean weighted by speed
squared, i.e. by the inverse course variance), which carries the heading back
to the first sample and lets the average run through a turn.

Large heading errors.  The error-state filter linearises the attitude error
(small angles); beyond 10-20 deg of yaw error its covariance no longer
describes the error and it may lock onto a wrong heading.  :func:`yaw_bank`
runs the filter from several yaw hypotheses spread over the circle on the
first tens of seconds of data and keeps the one whose GNSS updates are most
consistent (smallest mean NIS per degree of freedom: a Gaussian sum filter's
hypothesis weights (Alspach and Sorenson 1972) reduce to this ranking when
every hypothesis has the same prior weight and comparable innovation
covariances).  The kept hypothesis is within half the spacing of the truth,
inside the small-angle model.
"""

from __future__ import annotations

import dataclasses
import time as _time

import numpy as np

from .. import earth
from .. import rotations as rot
from ..errors import InputError, InskitError
from ..types import GnssData, ImuData, NavState, fix_sigmas
from ..units import DEG
from .coarse import Startup, _chain_rotations, detect_motion_start, fix_sigma_m, level, startup_state

#: a yaw sigma above this [rad] is outside the filter's small-angle model: the start-up runs the yaw bank
BANK_ABOVE_YAW_SIGMA = 10.0 * DEG
#: the sigma [rad] of a yaw known only to lie on the circle (uniform over 360 deg: 180 / sqrt(3) deg)
UNKNOWN_YAW_SIGMA = np.pi / np.sqrt(3.0)
#: the config sigmas a data-driven start-up finds for itself (config units)
STARTUP_SIGMAS = ("sigma_pos_m", "sigma_vel_m_s", "sigma_roll_pitch_deg", "sigma_yaw_deg")


def gnss_velocity(gnss: GnssData, span_s=1.0):
    """NED velocity of the fixes and its noise.

    Precise fixes (median horizontal sigma below 0.1 m: RTK) give their
    velocity by central differences of position over about ``span_s``; coarser
    fixes use the receiver's velocity when there is one, else position
    differences over a span long enough to average the noise (as
    :func:`inskit.alignment.coarse.gnss_speed`).

    Parameters
    ----------
    gnss : GnssData
        ``n >= 2`` fixes.
    span_s : float
        Differencing span [s].

    Returns
    -------
    v_n : (n, 3) ndarray
        Velocity north, east, down [m/s].
    sigma_h, sigma_d : float
        Noise sigma of one horizontal component and of the down component [m/s].
    """
    t = gnss.time
    if len(t) < 2:
        raise InputError("in-motion start-up needs at least two GNSS fixes")
    sig = np.asarray(gnss.sigma_ned, float)
    sig_h = float(np.median(np.hypot(sig[:, 0], sig[:, 1]) / np.sqrt(2)))
    sig_d = float(np.median(sig[:, 2]))
    if sig_h >= 0.1 and gnss.has_velocity:
        sv = np.asarray(gnss.sigma_v_ned, float)
        return (np.asarray(gnss.v_n, float), float(np.median(np.hypot(sv[:, 0], sv[:, 1]) / np.sqrt(2))),
                float(np.median(sv[:, 2])))
    if sig_h >= 0.1:
        span_s = max(span_s, 10.0 * sig_h)
    p = earth.lla_to_ned(gnss.lla, gnss.lla[0])
    h = max(1, int(round(span_s / max(float(np.median(np.diff(t))), 1e-3) / 2)))
    i0 = np.clip(np.arange(len(t)) - h, 0, len(t) - 1)
    i1 = np.clip(np.arange(len(t)) + h, 0, len(t) - 1)
    dt = np.maximum(t[i1] - t[i0], 1e-9)
    v = (p[i1] - p[i0]) / dt[:, None]
    span = float(np.median(dt))
    return v, float(np.sqrt(2.0) * sig_h / span), float(np.sqrt(2.0) * sig_d / span)


def gnss_acceleration(t, v_n, span_s=1.0):
    """NED acceleration [m/s^2] by central differences of ``v_n`` ``(n, 3)``
    over about ``span_s`` (at least one fix either side), and the span used [s]."""
    t = np.asarray(t, float)
    h = max(1, int(round(span_s / max(float(np.median(np.diff(t))), 1e-3) / 2)))
    i0 = np.clip(np.arange(len(t)) - h, 0, len(t) - 1)
    i1 = np.clip(np.arange(len(t)) + h, 0, len(t) - 1)
    dt = np.maximum(t[i1] - t[i0], 1e-9)
    return (v_n[i1] - v_n[i0]) / dt[:, None], float(np.median(dt))


def _interp_rows(t_new, t, x):
    """Linear interpolation of the columns of ``x`` ``(n, m)`` (held at the ends)."""
    return np.stack([np.interp(t_new, t, x[:, j]) for j in range(x.shape[1])], axis=-1)


def _yaw_offsets(imu, roll, pitch, t_fix):
    """Yaw [rad] the gyros integrate from the first IMU sample (roll, pitch as
    given, yaw 0, biases unknown: 0) to each time of ``t_fix`` (ascending)."""
    q = rot.quat_from_euler([roll, pitch, 0.0])
    out = np.empty(len(t_fix))
    k_prev = 0
    for j, tf in enumerate(t_fix):
        k = int(np.clip(np.searchsorted(imu.time, tf), 0, len(imu) - 1))
        if k > k_prev:
            q = _chain_rotations(q, np.ascontiguousarray(imu.dtheta_b[k_prev + 1:k + 1]))
            k_prev = k
        out[j] = rot.euler_from_quat(q)[2]
    return out


class _Levelling:
    """What in-motion levelling needs, computed once (the bank re-levels for each yaw)."""

    def __init__(self, imu: ImuData, gnss: GnssData, window_s, accel_span_s, velocity_span_s):
        self.imu, self.gnss = imu, gnss
        self.t0 = float(imu.time[0])
        self.v_fix, self.sig_vh, self.sig_vd = gnss_velocity(gnss, velocity_span_s)
        a_fix, self.accel_span = gnss_acceleration(gnss.time, self.v_fix, accel_span_s)
        w, f = imu.rates()
        m = (imu.time > self.t0) & (imu.time <= self.t0 + window_s)
        if m.sum() < 3:
            raise InputError(f"in-motion levelling needs IMU samples over its {window_s:g} s window from "
                             f"t = {self.t0:.3f} s; found {int(m.sum())}")
        self.window = float(imu.time[m][-1] - self.t0)
        self.f_b = f[m]
        self.a_n = _interp_rows(imu.time[m], gnss.time, a_fix)
        # yaw change over the window from the z gyro (small tilt): enough for the acceleration's projection
        self.dyaw = np.cumsum(imu.dtheta_b[1:][m[1:], 2])
        self.lla0 = _interp_lla(self.t0, gnss)
        self.v0 = _interp_rows(np.array([self.t0]), gnss.time, self.v_fix)[0]
        k = int(np.clip(np.searchsorted(gnss.time, self.t0), 0, len(gnss.time) - 1))
        self.fix0 = k  # the fix the position is taken at
        self.a_mean = self.a_n.mean(axis=0)

    def roll_pitch(self, yaw):
        """Roll and pitch [rad] levelled on the acceleration-corrected specific force, for initial ``yaw``."""
        roll, pitch = level(self.f_b.mean(axis=0))  # first pass: as if unaccelerated
        for _ in range(3):
            rpy = np.column_stack([np.full(len(self.dyaw), roll), np.full(len(self.dyaw), pitch),
                                   yaw + self.dyaw])
            a_b = np.einsum("nji,nj->ni", rot.dcm_from_euler(rpy), self.a_n)  # C_bn a_n
            roll, pitch = level((self.f_b - a_b).mean(axis=0))
        return float(roll), float(pitch)

    def state(self, yaw, lever_arm_b):
        roll, pitch = self.roll_pitch(yaw)
        rpy = np.array([roll, pitch, float(rot.wrap_angle(yaw))])
        p_imu = earth.ned_to_lla(-(rot.dcm_from_euler(rpy) @ np.asarray(lever_arm_b, float)), self.lla0)
        return NavState.from_euler(self.t0, p_imu, self.v0, rpy)


def _interp_lla(t, gnss: GnssData):
    """The fixes' position at ``t`` [s], linearly interpolated in NED."""
    p = earth.lla_to_ned(gnss.lla, gnss.lla[0])
    return earth.ned_to_lla(_interp_rows(np.array([t]), gnss.time, p)[0], gnss.lla[0])


def floored_sigmas(sigma: dict, floors: dict | None) -> dict:
    """The start-up's sigmas (config units, :data:`STARTUP_SIGMAS`) each no
    smaller than its floor in ``floors`` (the config's ``[init]`` sigmas)."""
    return {k: max(v, float((floors or {}).get(k, 0.0))) for k, v in sigma.items()}


def inmotion_startup(imu: ImuData, gnss: GnssData, lever_arm_b=(0.0, 0.0, 0.0), *, heading_speed_m_s=3.0,
                     course_average_s=3.0, level_window_s=2.0, accel_span_s=1.0, yaw_guess=None,
                     gyro_bias_sigma=0.05 * DEG, accel_bias_sigma=0.05, floors=None, reason="",
                     sigma_floor_m=0.0, sigma_scale_ned=(1.0, 1.0, 1.0)) -> Startup:
    """Initial state of a log that starts in motion.

    Roll and pitch from the specific force corrected for the GNSS-derived
    acceleration (mean over ``level_window_s`` from the first IMU sample),
    yaw from the GNSS course averaged over ``course_average_s`` from the first
    fix above ``heading_speed_m_s`` (carried back to the first sample by the
    gyros), position and velocity from the fixes interpolated to the first
    IMU sample.

    Parameters
    ----------
    imu : ImuData
        Starts at or after the first fix.
    gnss : GnssData
        The fixes the filter uses.
    lever_arm_b : (3,) array_like
        Antenna position in body axes [m].
    heading_speed_m_s : float
        Speed from which the course gives the heading [m/s] (a car: 3; a walk: 0.8).
    course_average_s : float
        Span of fixes the course is averaged over [s].
    level_window_s : float
        Span of IMU data the specific force is averaged over [s].
    accel_span_s : float
        Differencing span of the GNSS acceleration [s] (about 1 s smooths the noise).
    yaw_guess : float, optional
        A first yaw [rad] instead of the course (a handheld device that does
        not point along its track; a magnetometer): its sigma is that of a
        yaw anywhere on the circle, so the job's yaw bank runs.
    gyro_bias_sigma, accel_bias_sigma : float
        Turn-on bias sigmas [rad/s], [m/s^2]: they enter the yaw carried back
        by the gyros and the tilt.
    floors : dict, optional
        Lower bounds of the sigmas found (:data:`STARTUP_SIGMAS`, config units).
    sigma_floor_m, sigma_scale_ned : float, (3,) array_like
        How the filter takes the fixes' position sigmas (``[gnss]``): the
        position's sigma is the fix's so taken
        (:func:`~inskit.alignment.coarse.fix_sigma_m`).

    Returns
    -------
    Startup
        ``mode = "in-motion"``, zero initial biases, and ``sigma``: position
        from the fix sigma, velocity from the GNSS velocity noise, tilt from the
        acceleration noise and the accelerometer-bias sigma
        (``sqrt(sigma_a^2 + sigma_ba^2 + (a sigma_yaw)^2) / g``), yaw from the
        course noise at the speed reached, averaged over the fixes, and the gyro
        bias over the time carried back (``sigma_bg (t_course - t0)``).

    References
    ----------
    Groves 2013 eq. 5.54 (specific force), 5.101 (levelling); the course as
    heading of a land vehicle, Groves 2013 §6.1.4.
    """
    lv = _Levelling(imu, gnss, level_window_s, accel_span_s, 1.0)
    g = float(earth.gravity_down(lv.lla0[0], lv.lla0[2]))
    speed = np.hypot(lv.v_fix[:, 0], lv.v_fix[:, 1])
    course = np.arctan2(lv.v_fix[:, 1], lv.v_fix[:, 0])
    limit = max(heading_speed_m_s, 5.0 * lv.sig_vh)
    if yaw_guess is not None:
        yaw0, sig_yaw, t_head = float(yaw_guess), UNKNOWN_YAW_SIGMA, lv.t0
        how = "yaw from init.yaw_deg (unknown quality: the bank searches the circle)"
    else:
        ok = (gnss.time >= lv.t0 - 0.5) & (speed > limit)
        if not ok.any():
            raise InputError(
                f"the GNSS track never exceeds {limit:.2f} m/s (fastest {float(speed.max()):.2f} m/s): no heading "
                f"from the track; lower init.heading_speed_m_s (a walk: 0.8) or give a first guess in init.yaw_deg")
        i = int(np.argmax(ok))
        t_head = float(gnss.time[i])
        sel = ok & (gnss.time >= t_head) & (gnss.time <= t_head + course_average_s)
        t_sel, c_sel, w_sel = gnss.time[sel], course[sel], speed[sel] ** 2
        yaw0 = float(c_sel[0])
        for _ in range(2):  # roll/pitch for the gyro integration need a yaw (small effect): iterate
            roll, pitch = lv.roll_pitch(yaw0)
            off = c_sel - _yaw_offsets(imu, roll, pitch, t_sel)
            yaw0 = float(np.arctan2(np.sum(w_sel * np.sin(off)), np.sum(w_sel * np.cos(off))))
        # course noise per fix sig_v / speed; neighbouring fixes share the velocity differences: count fixes
        # one differencing span apart as independent
        n_eff = max(1.0, (t_sel[-1] - t_sel[0]) / max(lv.accel_span, 1e-3) + 1.0) if len(t_sel) > 1 else 1.0
        sig_c = lv.sig_vh / float(np.sqrt(np.mean(w_sel))) / np.sqrt(n_eff)
        sig_yaw = float(np.hypot(sig_c, gyro_bias_sigma * (float(np.mean(t_sel)) - lv.t0)))
        how = (f"yaw from the course averaged over {len(t_sel)} fixes from t0 + {t_head - lv.t0:.1f} s "
               f"(speed {float(np.sqrt(np.mean(w_sel))):.2f} m/s, above {limit:.2f} m/s)")
    state = lv.state(yaw0, lever_arm_b)
    sig_a = np.sqrt(2.0) * lv.sig_vh / lv.accel_span / np.sqrt(max(1.0, lv.window / lv.accel_span))
    a_h = float(np.hypot(lv.a_mean[0], lv.a_mean[1]))
    sig_tilt = float(np.sqrt(sig_a ** 2 + accel_bias_sigma ** 2 + (a_h * min(sig_yaw, 1.0)) ** 2) / g)
    sigma = {"sigma_pos_m": fix_sigma_m(gnss, lv.fix0, sigma_floor_m, sigma_scale_ned),
             "sigma_vel_m_s": max(lv.sig_vh, lv.sig_vd),
             "sigma_roll_pitch_deg": sig_tilt / DEG, "sigma_yaw_deg": sig_yaw / DEG}
    sigma = floored_sigmas(sigma, floors)
    return Startup(state, np.zeros(3), np.zeros(3), lv.t0, t_head, mode="in-motion",
                   reason=(reason + "; " if reason else "") + how, sigma=sigma,
                   at_yaw=lambda yaw: lv.state(yaw, lever_arm_b))


def static_start_s(imu: ImuData, gnss: GnssData, motion_threshold_m_s=0.3):
    """Rest at the start of the log that :func:`~inskit.alignment.coarse.startup_state`
    would level on [s]: from the first IMU sample to one second before the
    GNSS track first moves (0 when the IMU starts more than a second before
    the fixes, whose speed then says nothing about it)."""
    if imu.time[0] < gnss.time[0] - 1.0:
        return 0.0
    try:
        t_move = detect_motion_start(gnss, motion_threshold_m_s)
    except InputError:  # never moves: all of it is rest
        return float(gnss.time[-1] - imu.time[0])
    return max(0.0, float(t_move - 1.0 - imu.time[0]))


def auto_startup(imu: ImuData, gnss: GnssData, lever_arm_b=(0.0, 0.0, 0.0), *, mode="auto", min_static_s=5.0,
                 heading_speed_m_s=3.0, **inmotion) -> Startup:
    """The start-up of ``mode``: ``"static-then-track"``
    (:func:`~inskit.alignment.coarse.startup_state`), ``"in-motion"``
    (:func:`inmotion_startup`), or ``"auto"``: static-then-track when the log
    starts with at least ``min_static_s`` of rest (by the GNSS track), else
    in-motion.  The result's ``reason`` says which and why.

    ``inmotion`` are the keyword arguments of :func:`inmotion_startup`.
    """
    if mode not in ("auto", "static-then-track", "in-motion"):
        raise InputError(f"start-up mode must be auto, static-then-track or in-motion, got {mode!r}")
    shape = {k: inmotion.pop(k) for k in ("sigma_floor_m", "sigma_scale_ned") if k in inmotion}
    if shape:  # the fixes as the filter takes them (types.fix_sigmas) for every use of their sigmas below: the
        # rest and motion found from the track's speed against its noise, the velocity, course and tilt sigmas, the
        # position's sigma (a file claiming 2 cm for 0.5 m of noise, floored at 0.5 m, was read as moving from its
        # first second: 'the log starts with 0.0 s of rest' of 20, an in-motion start with a 1.4 cm/s velocity sigma)
        gnss = dataclasses.replace(gnss, sigma_ned=fix_sigmas(gnss.sigma_ned, **shape))

    def floored(s):  # the static start-up's sigmas (the first fix's position sigma) no smaller than the floors
        if s.sigma is None:
            return s
        return dataclasses.replace(s, sigma=floored_sigmas(s.sigma, inmotion.get("floors")))

    if mode == "static-then-track":
        return floored(startup_state(imu, gnss, lever_arm_b, min_static_s=min_static_s,
                                     heading_speed_m_s=heading_speed_m_s))
    if mode == "in-motion":
        return inmotion_startup(imu, gnss, lever_arm_b, heading_speed_m_s=heading_speed_m_s,
                                reason="init.mode = \"in-motion\"", **inmotion)
    rest = static_start_s(imu, gnss)
    if rest >= min_static_s:
        s = floored(startup_state(imu, gnss, lever_arm_b, min_static_s=min_static_s,
                                  heading_speed_m_s=heading_speed_m_s))
        return Startup(s.state, s.gyro_bias, s.accel_bias, s.static_end, s.heading_time, mode=s.mode,
                       reason=f"auto: {s.reason}", sigma=s.sigma, at_yaw=s.at_yaw)
    why = (f"auto: the log starts with {rest:.1f} s of rest (static-then-track needs init.min_static_s = "
           f"{min_static_s:g} s)")
    return inmotion_startup(imu, gnss, lever_arm_b, heading_speed_m_s=heading_speed_m_s, reason=why, **inmotion)


#: a hypothesis must score more than this fraction below the start-up's own yaw (hypothesis 0) to replace it: on
#: 40 s of straight driving at constant speed every yaw fits the fixes alike (0.738 against 0.741), and the bank
#: kept one 150 deg from a course the track gave to a degree
BANK_TIE = 0.05


def yaw_bank(imu: ImuData, at_yaw, yaw0, measurements, settings, *, n=12, span_s=40.0,
             score_measurements=("gnss_pos",), run=None, keep_first_on_tie=False) -> dict:
    """Run the filter from ``n`` yaw hypotheses and rank them.

    Each hypothesis ``yaw0 + 2 pi k / n`` (k = 0 .. n-1) starts the filter
    from ``at_yaw(yaw)`` over the first ``span_s`` of ``imu``; its score is
    the mean NIS per degree of freedom of the updates of
    ``score_measurements`` (accepted and rejected: a hypothesis whose updates
    the gate refuses scores them all the same).  A run that diverges scores
    infinity.  With ``keep_first_on_tie`` (the start-up's yaw is a measured
    one, the GNSS track's course, not a guess) hypothesis 0 is kept unless
    another scores more than :data:`BANK_TIE` below it (``tie``: the data
    could not tell them apart).

    Parameters
    ----------
    imu : ImuData
    at_yaw : callable
        ``at_yaw(yaw [rad]) -> NavState`` at ``imu.time[0]``.
    yaw0 : float
        First hypothesis [rad].
    measurements : list
        Measurement plug-ins (those of the full run).
    settings : FilterSettings
        With the initial yaw sigma of one hypothesis (about half the spacing).
    n : int
        Number of hypotheses.
    span_s : float
        Data each hypothesis runs over [s].
    score_measurements : tuple of str
        Names of the measurements whose NIS ranks the hypotheses.
    run : callable, optional
        The filter (default :func:`inskit.integration.run_filter`).

    Returns
    -------
    dict
        ``hypotheses_deg``, ``scores`` (mean NIS per dof, None for a
        divergence), ``chosen`` (index), ``chosen_yaw_deg``, ``score``,
        ``tie`` (hypothesis 0 kept over a best within :data:`BANK_TIE`),
        ``runner_up_score``, ``span_s``, ``elapsed_s``; ``yaw_rad``, the
        chosen yaw.

    References
    ----------
    Hypothesis weighting by innovation likelihood: Alspach and Sorenson
    1972 (Gaussian sum filter), Magill 1965 (multiple-model adaptive estimation).
    """
    if run is None:
        from ..integration import run_filter as run
    if n < 1:
        raise InputError(f"the yaw bank needs at least one hypothesis, got {n}")
    t_start = _time.perf_counter()
    k1 = int(np.searchsorted(imu.time, imu.time[0] + span_s)) + 1
    short = imu.slice(0, min(k1, len(imu)))
    yaws = rot.wrap_angle(yaw0 + 2.0 * np.pi * np.arange(n) / n)
    scores = np.full(n, np.inf)
    for j, y in enumerate(yaws):
        try:
            out = run(short, at_yaw(float(y)), measurements, settings)
        except InskitError:
            continue
        nis = dof = 0.0
        for name in score_measurements:
            inn = out.innovations.get(name)
            if inn is not None and len(inn["nis"]):
                nis += float(np.sum(inn["nis"]))
                dof += float(np.sum(inn.get("nis_dof", inn["dof"])))  # the rows each NIS covers
        if dof > 0 and np.isfinite(nis):
            scores[j] = nis / dof
    if not np.isfinite(scores).any():
        raise InputError(f"the yaw bank: no hypothesis gave a {'/'.join(score_measurements)} update in the first "
                         f"{span_s:g} s (or every run diverged); give init.yaw_deg, or mode = \"given\"")
    best = int(np.argmin(scores))
    tie = bool(keep_first_on_tie and best != 0 and np.isfinite(scores[0])
               and scores[0] <= (1.0 + BANK_TIE) * scores[best])
    if tie:  # the data cannot tell them apart: the start-up's own yaw (hypothesis 0: the track's course) stands
        best = 0
    ranked = np.sort(scores)
    return {"hypotheses_deg": [float(v) for v in yaws / DEG],
            "scores": [float(v) if np.isfinite(v) else None for v in scores],
            "chosen": best, "chosen_yaw_deg": float(yaws[best] / DEG), "score": float(scores[best]),
            "tie": tie,
            "runner_up_score": float(ranked[1]) if n > 1 and np.isfinite(ranked[1]) else None,
            "span_s": float(short.time[-1] - short.time[0]), "elapsed_s": time_since(t_start),
            "yaw_rad": float(yaws[best])}


def time_since(t0):
    """Seconds of wall time since ``t0`` (``time.perf_counter``)."""
    return float(_time.perf_counter() - t0)


def bank_needed(startup: Startup, sigma_yaw_rad, n_hypotheses) -> bool:
    """Whether the start-up's yaw sigma [rad] lies outside the small-angle model
    (:data:`BANK_ABOVE_YAW_SIGMA`) and the bank may run (``n_hypotheses > 1``)."""
    return n_hypotheses > 1 and startup.at_yaw is not None and sigma_yaw_rad > BANK_ABOVE_YAW_SIGMA


def after_bank(startup: Startup, bank: dict) -> Startup:
    """The start-up from the bank's chosen yaw, with the bank's record; its yaw
    sigma is half the hypotheses' spacing (the chosen one is the nearest)."""
    info = {k: v for k, v in bank.items() if k != "yaw_rad"}
    sigma = {**(startup.sigma or {}), "sigma_yaw_deg": 180.0 / len(bank["hypotheses_deg"])}
    return Startup(startup.at_yaw(bank["yaw_rad"]), startup.gyro_bias, startup.accel_bias, startup.static_end,
                   startup.heading_time, mode=startup.mode,
                   reason=startup.reason + f"; yaw bank: hypothesis {bank['chosen']} of "
                   f"{len(bank['hypotheses_deg'])} ({bank['chosen_yaw_deg']:.1f} deg)",
                   sigma=sigma, bank=info, at_yaw=startup.at_yaw)
