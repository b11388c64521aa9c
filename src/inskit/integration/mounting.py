"""Is the IMU mounted as the filter assumes?  Evidence and reporting.

The vehicle-motion constraints (non-holonomic, odometer) hold in the
vehicle's axes.  Without the ``mounting`` block (:class:`.blocks.Mounting`)
the filter takes the IMU's body axes (after ``[imu] mount_rpy_deg``) for the
vehicle's, and a residual mounting of a few degrees then bends the solution:
either the constraint wins and the attitude follows the vehicle, with the
accelerometer bias soaking up the gravity the wrong pitch lets in
(``ba_x = -g pitch``), or the attitude holds and the constraint drags the
velocity off the track until the GNSS fixes are rejected.

:func:`mounting_evidence` measures the residual mounting from what the run
itself shows, with two pieces of evidence independent of the constraint's
own innovations (which a bent filter keeps small):

* the direction of travel in the IMU's axes: the velocity of the GNSS fixes
  (central differences of the positions the filter used) resolved with the
  filter's attitude, ``v_b = C_bn v_gnss``.  A vehicle moves along its
  forward axis, so ``v_b = V (cos p cos y, cos p sin y, -sin p)`` with ``(p,
  y)`` the residual pitch and yaw of the mounting (the convention of
  :func:`.blocks.mounting_dcm`).  Epochs below ``min_speed_m_s`` and in
  turns (where the antenna's lever arm adds ``omega x l``) are left out;
  the mean is weighted by ``V^2`` (the angle's noise falls as ``1 / V``),
  and its standard error comes from the scatter of consecutive batch means
  (which keeps the slow correlation of GNSS errors and filter attitude; the
  white noise of the fixes mostly cancels, as the central differences of a
  batch telescope to the difference of its end fixes);
* the forward accelerometer bias: a pitch the filter was bent by shows as
  ``ba_x = -g sin(pitch)``; counted when the estimate moved more than
  ``BIAS_PRIOR_SIGMAS`` initial sigmas (a true bias within its prior is not
  evidence).

:func:`mounting_warning` turns the evidence into a health warning when the
implied pitch or yaw exceeds ``WARN_DEG`` and ``WARN_SE`` standard errors.
References: Groves 2013 §16.2.3 (non-holonomic constraints hold in the
vehicle's axes); SYSTEM.md §2 (error states ``estimate - truth``).
"""

from __future__ import annotations

import math

import numpy as np

from .. import earth
from ..rotations import dcm_from_euler, dcm_from_quat, euler_from_dcm, euler_from_quat
from ..types import GnssData

#: a warning needs an implied pitch or yaw of at least this [deg]: at 15 m/s a
#: 1 deg mounting error is a 0.26 m/s side or vertical velocity, 2.6 sigma of
#: the default non-holonomic noise (0.1 m/s)
WARN_DEG = 1.0
#: ... and this many standard errors
WARN_SE = 4.0
#: the forward accelerometer bias counts as evidence beyond this many initial sigmas
BIAS_PRIOR_SIGMAS = 3.0
#: standard gravity [m/s^2] (only to turn a bias into an angle)
G0 = 9.80665


def gnss_velocity(gnss: GnssData, max_gap_factor=1.5):
    """Velocity of the fixes by central differences [m/s], NED at each fix.

    ``v_k = C_ne(k) (r_e[k+1] - r_e[k-1]) / (t[k+1] - t[k-1])``, exact for
    any distance (no flat-earth step); defined where both neighbours exist
    within ``max_gap_factor`` median intervals.

    Returns
    -------
    rows : (m,) int ndarray
        The fixes with a velocity.
    v_n : (m, 3) ndarray
    """
    t = np.asarray(gnss.time, float)
    if len(t) < 3:
        return np.empty(0, np.int64), np.empty((0, 3))
    dt = np.diff(t)
    med = float(np.median(dt))
    ok = (dt[:-1] <= max_gap_factor * med) & (dt[1:] <= max_gap_factor * med)
    k = np.nonzero(ok)[0] + 1
    r = earth.lla_to_ecef(gnss.lla)
    dr = (r[k + 1] - r[k - 1]) / (t[k + 1] - t[k - 1])[:, None]
    C_en = earth.dcm_en(gnss.lla[k, 0], gnss.lla[k, 1])
    return k, np.einsum("nji,nj->ni", C_en, dr)


def _batch_se(x, w, batches):
    """Standard error of the weighted mean of ``x`` from the scatter of
    ``batches`` consecutive batch means."""
    parts = [(x[i], w[i]) for i in np.array_split(np.arange(len(x)), batches) if len(i)]
    means = np.array([np.sum(a * b) / np.sum(b) for a, b in parts])
    return float(means.std(ddof=1) / math.sqrt(len(means))) if len(means) > 1 else math.inf


def mounting_evidence(track, gnss: GnssData, *, min_speed_m_s=5.0, max_turn_rate_deg_s=3.0, batches=10,
                      min_epochs=30):
    """The residual mounting a run implies (see the module text).

    Parameters
    ----------
    track : Track or FilterOutput
        The forward solution (``nav``; ``layout`` and the ``ba`` estimate for
        the bias evidence).
    gnss : GnssData
        The fixes the filter used (not the withheld ones).
    min_speed_m_s : float
        Epochs slower than this are left out (the direction of a slow track
        is noise).
    max_turn_rate_deg_s : float
        Epochs turning faster than this are left out.
    batches : int
        Number of consecutive batches for the standard error.
    min_epochs : int
        Fewer usable epochs give no evidence (``None``).

    Returns
    -------
    dict or None
        ``pitch_deg``, ``yaw_deg`` (implied residual mounting, the
        convention of ``mounting_rpy_deg``), ``pitch_se_deg``,
        ``yaw_se_deg``, ``epochs``, and the parts: ``travel_pitch_deg``,
        ``travel_yaw_deg`` (direction of travel in the IMU's axes),
        ``accel_bias_pitch_deg`` (``asin(-d ba_x / g)`` when counted, else 0) with
        ``accel_bias_x_m_s2`` and ``accel_bias_prior_sigmas``.
    """
    nav = track.nav
    rows, v_g = gnss_velocity(gnss)
    t = np.asarray(gnss.time, float)[rows]
    inside = (t >= nav.time[0] + 0.5) & (t <= nav.time[-1] - 0.5)
    v_g, t = v_g[inside], t[inside]
    if len(t) < min_epochs:
        return None
    k = np.clip(np.searchsorted(nav.time, t), 0, len(nav.time) - 1)
    v_b = np.einsum("nji,nj->ni", dcm_from_quat(nav.q_nb[k]), v_g)  # C_bn v_n
    ka = np.clip(np.searchsorted(nav.time, t - 0.5), 0, len(nav.time) - 1)
    kb = np.clip(np.searchsorted(nav.time, t + 0.5), 0, len(nav.time) - 1)
    span = np.maximum(nav.time[kb] - nav.time[ka], 1e-9)
    d_yaw = euler_from_quat(nav.q_nb[kb])[:, 2] - euler_from_quat(nav.q_nb[ka])[:, 2]
    turn = np.abs((d_yaw + math.pi) % (2 * math.pi) - math.pi) / span
    speed = np.linalg.norm(v_b, axis=1)
    use = (v_b[:, 0] >= min_speed_m_s) & (turn <= math.radians(max_turn_rate_deg_s))
    if use.sum() < min_epochs:
        return None
    vb, w = v_b[use], speed[use] ** 2
    pitch = np.arctan2(-vb[:, 2], np.hypot(vb[:, 0], vb[:, 1]))
    yaw_m = np.arctan2(vb[:, 1], vb[:, 0])
    p_travel = float(np.sum(w * pitch) / np.sum(w))
    y_travel = float(np.sum(w * yaw_m) / np.sum(w))
    se_p, se_y = _batch_se(pitch, w, batches), _batch_se(yaw_m, w, batches)
    out = {"epochs": int(use.sum()), "travel_pitch_deg": math.degrees(p_travel),
           "travel_yaw_deg": math.degrees(y_travel), "accel_bias_pitch_deg": 0.0,
           "accel_bias_x_m_s2": None, "accel_bias_prior_sigmas": None}
    p_bias = 0.0
    lay = getattr(track, "layout", None)
    b = None if lay is None else lay.by_role("accel_bias")
    if b is not None:
        d = float(track.estimate(b.name)[-1, 0] - b.estimate0[0])
        n_sig = abs(d) / float(b.sigma0[0])
        out["accel_bias_x_m_s2"] = float(track.estimate(b.name)[-1, 0])
        out["accel_bias_prior_sigmas"] = n_sig
        if n_sig > BIAS_PRIOR_SIGMAS:
            p_bias = math.asin(min(1.0, max(-1.0, -d / G0)))
            out["accel_bias_pitch_deg"] = math.degrees(p_bias)
    out.update(pitch_deg=math.degrees(p_travel + p_bias), yaw_deg=math.degrees(y_travel),
               pitch_se_deg=math.degrees(se_p), yaw_se_deg=math.degrees(se_y))
    return out


def corrected_mount_rpy_deg(mount_rpy_deg, pitch_deg, yaw_deg):
    """The ``[imu] mount_rpy_deg`` that takes a residual mounting (pitch,
    yaw) [deg] into account: ``dcm(M1) = dcm(M0) dcm((0, pitch, yaw))``
    (navigate rotates the readings by ``dcm(M)^T``, the mounting block's
    ``C_vb = dcm((0, pitch, yaw))^T`` follows it).  Each angle is given on
    the turn nearest the configured one (185 deg stays 185, not -175)."""
    m0 = np.asarray(mount_rpy_deg, float)
    C = dcm_from_euler(np.radians(m0)) @ dcm_from_euler(np.radians([0.0, pitch_deg, yaw_deg]))
    m1 = np.degrees(euler_from_dcm(C))
    m1 += 360.0 * np.round((m0 - m1) / 360.0)
    return [float(v) for v in m1]


def mounting_warning(evidence, mount_rpy_deg=(0.0, 0.0, 0.0), *, warn_deg=WARN_DEG, warn_se=WARN_SE):
    """A health warning when the evidence betrays a mounting the filter does
    not model (the implied pitch or yaw beyond ``warn_deg`` and ``warn_se``
    standard errors), else ``None``.  It names the implied angles (an axis
    short of the test marked as such, and left out of the suggested
    ``[imu] mount_rpy_deg``) and how to fix it."""
    if not evidence:
        return None
    found, parts = {}, []
    for axis in ("pitch", "yaw"):
        v, se = evidence[f"{axis}_deg"], evidence[f"{axis}_se_deg"]
        hit = abs(v) > warn_deg and abs(v) > warn_se * se
        found[axis] = v if hit else 0.0
        parts.append(f"{axis} {v:+.2f} deg (+-{se:.2f}{'' if hit else ', not significant'})")
    if not any(found.values()):
        return None
    why = (f"the direction of travel lies at pitch {evidence['travel_pitch_deg']:+.2f} deg, yaw "
           f"{evidence['travel_yaw_deg']:+.2f} deg in the IMU's axes over {evidence['epochs']} GNSS epochs")
    if evidence["accel_bias_pitch_deg"]:
        why += (f"; the forward accelerometer bias estimate {evidence['accel_bias_x_m_s2']:+.3f} m/s^2 "
                f"({evidence['accel_bias_prior_sigmas']:.1f} initial sigmas) would be a pitch of "
                f"{evidence['accel_bias_pitch_deg']:+.2f} deg")
    m1 = corrected_mount_rpy_deg(mount_rpy_deg, found["pitch"], found["yaw"])
    return (f"mounting: the IMU seems mounted off the vehicle's axes, which the non-holonomic constraint and "
            f"odometer take for the IMU's: {', '.join(parts)} ({why}); set [constraints] mounting = true to "
            f"estimate it, or correct [imu] mount_rpy_deg (about [{m1[0]:.2f}, {m1[1]:.2f}, {m1[2]:.2f}])")


def mounting_summary(track, mount_rpy_deg=(0.0, 0.0, 0.0)):
    """The summary keys of an estimated mounting (``{}`` without the block):
    ``mounting_rpy_deg`` (roll 0: not estimated, see
    :class:`.blocks.Mounting`), ``mounting_sigma_deg`` (roll ``None``) and
    ``mount_rpy_deg_corrected``, the ``[imu] mount_rpy_deg`` that takes the
    estimate in."""
    if "mounting" not in track.layout:
        return {}
    m = np.degrees(track.estimate("mounting")[-1])
    s = np.degrees(track.sigma_of("mounting")[-1])
    return {"mounting_rpy_deg": [0.0, float(m[0]), float(m[1])],
            "mounting_sigma_deg": [None, float(s[0]), float(s[1])],
            "mount_rpy_deg_corrected": corrected_mount_rpy_deg(mount_rpy_deg, float(m[0]), float(m[1]))}


def mounting_check(track, gnss: GnssData, *, constrained, mount_rpy_deg=(0.0, 0.0, 0.0)):
    """``(evidence, warning)`` of a run: :func:`mounting_evidence` and
    :func:`mounting_warning` when the run applied a lateral or vertical
    vehicle constraint (``constrained``) without the ``mounting`` block;
    ``(None, None)`` otherwise (a modelled mounting reports its estimate
    instead, :func:`mounting_summary`)."""
    if not constrained or "mounting" in track.layout:
        return None, None
    ev = mounting_evidence(track, gnss)
    return ev, mounting_warning(ev, mount_rpy_deg)
