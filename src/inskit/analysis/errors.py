"""Navigation error against a reference: errors, statistics, time windows,
a constant-offset removal, per-epoch tables, plots.

Position errors are NED metres (solution minus truth, resolved at the truth
position), velocity errors m/s, attitude errors the wrapped differences of
roll, pitch and yaw [rad] inside, reported in degrees (and, for the earlier
keys, arcmin) at the edge.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..files import save_figure
from .. import earth
from .. import rotations as rot
from ..errors import InputError
from ..types import NavSolution
from ..units import ARCMIN, DEG


@dataclass(frozen=True)
class NavError:
    """Solution minus truth at common times.

    Attributes
    ----------
    time : (n,) ndarray
    pos_ned : (n, 3) ndarray
        [m].
    vel_ned : (n, 3) ndarray
        [m/s].
    att_rpy : (n, 3) ndarray
        Roll, pitch, yaw differences [rad], wrapped to (-pi, pi].
    sigma : (n, 7) ndarray or None
        The solution's own 1-sigma of the same epochs, when it carries them
        (a filter's solution: its ``sigma_*`` columns, :data:`SIGMA_COLUMNS`):
        north, east, down [m], vn, ve, vd [m/s], the heading error about
        down [rad].  None otherwise.
    """

    time: np.ndarray
    pos_ned: np.ndarray
    vel_ned: np.ndarray
    att_rpy: np.ndarray
    sigma: np.ndarray | None = None

    @property
    def horizontal(self):
        return np.hypot(self.pos_ned[:, 0], self.pos_ned[:, 1])

    def select(self, mask) -> "NavError":
        """The epochs where ``mask`` (n,) is true."""
        m = np.asarray(mask, bool)
        return NavError(self.time[m], self.pos_ned[m], self.vel_ned[m], self.att_rpy[m],
                        None if self.sigma is None else self.sigma[m])


#: a truth is interpolated only across intervals up to this many times its median sampling interval
TRUTH_GAP_FACTOR = 5.0


def truth_gaps(truth_time, factor=TRUTH_GAP_FACTOR):
    """``(gaps, limit)``: the ``(k, 2)`` array of the ``[start, end]`` [s]
    of every interval of the truth longer than ``factor`` median sampling
    intervals, and that limit [s].  One pass over the truth: a streamed
    run computes it once and hands it to :func:`nav_error_part` for every
    segment."""
    tt = np.asarray(truth_time, float)
    steps = np.diff(tt)
    limit = factor * float(np.median(steps)) if len(steps) else 0.0
    big = np.nonzero(steps > limit)[0]
    return np.column_stack([tt[big], tt[big + 1]]) if len(big) else np.zeros((0, 2)), limit


def line_breaks(t, y, *, gap_factor=TRUTH_GAP_FACTOR, period=None):
    """``(t, y)`` with a NaN point inserted wherever a plotted line must not
    join two neighbouring samples.

    Two samples are not joined when the time step between them exceeds
    ``gap_factor`` median steps (no data there: a line across the gap
    would draw values nobody computed) or, with ``period``, when ``y``
    jumps by more than half a period (an angle wrapped to one period: the
    jump is the wrap, not motion, and a line would draw a swing through
    the whole circle).

    Parameters
    ----------
    t : (n,) array_like
        Increasing times [s] (any unit: only ratios of steps count).
    y : (n,) array_like
        Values.
    gap_factor : float or None
        Steps longer than this many median steps break the line; ``None``:
        never on time.
    period : float, optional
        The period ``y`` is wrapped to (360 for degrees, ``2 pi`` for
        radians); ``None``: ``y`` is not an angle.

    Returns
    -------
    t, y : (m,) ndarray
        ``m >= n``; each break adds one point at the midpoint time with a
        NaN value, which matplotlib leaves undrawn.
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if len(t) < 2:
        return t, y
    dt = np.diff(t)
    cut = np.zeros(len(dt), dtype=bool)
    if gap_factor is not None:
        cut |= dt > gap_factor * float(np.median(dt))
    if period is not None:
        with np.errstate(invalid="ignore"):
            cut |= np.abs(np.diff(y)) > 0.5 * period
    if not cut.any():
        return t, y
    k = np.nonzero(cut)[0] + 1
    return np.insert(t, k, 0.5 * (t[k - 1] + t[k])), np.insert(y, k, np.nan)


def truth_covers(t, truth_time, factor=TRUTH_GAP_FACTOR, gaps=None):
    """Which times ``t`` a truth sampled at ``truth_time`` can score: inside
    its span and not strictly inside one of its gaps (:func:`truth_gaps`,
    or the ``gaps`` array given; linear interpolation across a longer gap
    invents the motion: 60 s of a turn removed from a truth turned a 41 m
    RMS error into 65 m).  Returns a boolean mask."""
    tt = np.asarray(truth_time, float)
    t = np.asarray(t, float)
    inside = (t >= tt[0]) & (t <= tt[-1])
    if gaps is None:
        gaps = truth_gaps(tt, factor)[0]
    if not len(gaps):
        return inside
    i = np.clip(np.searchsorted(gaps[:, 0], t, side="right") - 1, 0, len(gaps) - 1)
    return inside & ~((t > gaps[i, 0]) & (t < gaps[i, 1]))


def truth_coverage(t, truth_time, factor=TRUTH_GAP_FACTOR) -> dict:
    """How much of a solution at times ``t`` a truth scores
    (:func:`truth_covers`): ``epochs``, ``epochs_scored``,
    ``epochs_outside_truth_span``, ``epochs_in_truth_gaps``,
    ``truth_gaps`` (``[start, end]`` [s] of every gap longer than the
    limit) and ``truth_gap_limit_s``."""
    tt = np.asarray(truth_time, float)
    t = np.asarray(t, float)
    gaps, limit = truth_gaps(tt, factor)
    inside = (t >= tt[0]) & (t <= tt[-1])
    ok = truth_covers(t, tt, gaps=gaps)
    return {"epochs": int(len(t)), "epochs_scored": int(ok.sum()), "epochs_outside_truth_span": int((~inside).sum()),
            "epochs_in_truth_gaps": int((inside & ~ok).sum()), "truth_gaps": gaps.tolist(),
            "truth_gap_limit_s": limit}


def nav_error(sol: NavSolution, truth: NavSolution, gaps=None) -> NavError:
    """Errors of ``sol`` against ``truth``, evaluated at the solution times
    the truth covers (:func:`truth_covers`: inside its span, not inside a
    gap of the truth, ``gaps`` as :func:`truth_gaps` gives them; truth
    interpolated linearly)."""
    inside = truth_covers(sol.time, truth.time, gaps=gaps)
    if not inside.any():
        raise InputError(
            f"the solution ({sol.time[0]:.3f}..{sol.time[-1]:.3f} s) and the truth "
            f"({truth.time[0]:.3f}..{truth.time[-1]:.3f} s) do not overlap in time: mismatched time bases?"
        )
    return _errors_at(sol, truth, inside)


#: the solution columns of its own 1-sigma that :class:`NavError` carries, in its ``sigma`` order
SIGMA_COLUMNS = ("sigma_n_m", "sigma_e_m", "sigma_d_m", "sigma_vn_m_s", "sigma_ve_m_s", "sigma_vd_m_s",
                 "sigma_att_d_rad")
#: the names of those channels in :class:`ErrorSummary`'s ``consistency``
SIGMA_NAMES = ("north", "east", "down", "vn", "ve", "vd", "yaw")


def _own_sigma(sol, inside):
    """``(m, 7)`` of the solution's :data:`SIGMA_COLUMNS` at the rows
    ``inside``, or None when it lacks one of them."""
    ex = getattr(sol, "extra", None) or {}
    if not all(k in ex for k in SIGMA_COLUMNS):
        return None
    return np.column_stack([np.asarray(ex[k], dtype=float)[inside] for k in SIGMA_COLUMNS])


def _errors_at(sol, truth, inside):
    """:func:`nav_error` at the rows ``inside`` (a non-empty mask)."""
    s = sol if inside.all() else NavSolution(sol.time[inside], sol.lla[inside], sol.v_n[inside], sol.q_nb[inside])
    tr = truth.interpolate(s.time)
    r_s = earth.lla_to_ecef(s.lla)
    r_t = earth.lla_to_ecef(tr.lla)
    C_ne = np.swapaxes(earth.dcm_en(tr.lla[:, 0], tr.lla[:, 1]), -1, -2)
    dpos = np.einsum("nij,nj->ni", C_ne, r_s - r_t)
    datt = rot.wrap_angle(s.euler - tr.euler)
    return NavError(s.time, dpos, s.v_n - tr.v_n, datt, _own_sigma(sol, inside))


def _components(err: NavError) -> dict:
    """The error components :func:`summarize` reports, by key."""
    p, v = err.pos_ned, err.vel_ned
    a, a_deg = err.att_rpy / ARCMIN, err.att_rpy / DEG
    return {
        "north_m": p[:, 0], "east_m": p[:, 1], "down_m": p[:, 2],
        "horizontal_m": err.horizontal, "3d_m": np.linalg.norm(p, axis=1),
        "vn_m_s": v[:, 0], "ve_m_s": v[:, 1], "vd_m_s": v[:, 2],
        "roll_arcmin": a[:, 0], "pitch_arcmin": a[:, 1], "yaw_arcmin": a[:, 2],
        "roll_deg": a_deg[:, 0], "pitch_deg": a_deg[:, 1], "yaw_deg": a_deg[:, 2],
    }


class ErrorSummary:
    """:func:`summarize` of errors handed over in time order, part by part
    (a streamed run's segments): sums of squares, largest magnitudes and last
    values per component, so the figures are those of the whole without
    keeping it."""

    def __init__(self):
        self.n, self.t0, self.t1 = 0, None, None
        self.sq, self.max, self.final = {}, {}, {}
        # the errors over the solution's own sigmas: sums of squares and counts beyond 3 sigma per channel,
        # while every part carried its sigmas (one part without them and the figure is dropped)
        self.z_sq, self.z_out, self.z_n, self.z_ok = np.zeros(len(SIGMA_NAMES)), np.zeros(len(SIGMA_NAMES)), 0, True

    def add(self, err: NavError) -> "ErrorSummary":
        if not len(err.time):
            return self
        for k, x in _components(err).items():
            x = np.asarray(x, dtype=float)
            self.sq[k] = self.sq.get(k, 0.0) + float(np.sum(x * x))
            self.max[k] = max(self.max.get(k, 0.0), float(np.max(np.abs(x))))
            self.final[k] = float(x[-1])
        if err.sigma is None:
            self.z_ok = False
        elif self.z_ok:
            e = np.column_stack([err.pos_ned, err.vel_ned, err.att_rpy[:, 2]])
            sig = err.sigma
            good = np.all(np.isfinite(sig) & (sig > 0), axis=1)
            z = e[good] / sig[good]
            self.z_sq += np.sum(z * z, axis=0)
            self.z_out += np.sum(np.abs(z) > 3.0, axis=0)
            self.z_n += int(good.sum())
        self.n += len(err.time)
        self.t0 = float(err.time[0]) if self.t0 is None else self.t0
        self.t1 = float(err.time[-1])
        return self

    def result(self) -> dict:
        if not self.n:
            raise InputError("no epoch of the solution lies inside the truth's span")
        out = {k: {"rms": float(np.sqrt(self.sq[k] / self.n)), "max": self.max[k], "final": self.final[k]}
               for k in self.sq}
        out["epochs"] = self.n
        out["duration_s"] = self.t1 - self.t0
        out["first_epoch_s"] = self.t0
        out["last_epoch_s"] = self.t1
        if self.z_ok and self.z_n:
            out["consistency"] = {
                "normalized_rms": dict(zip(SIGMA_NAMES, (float(x) for x in np.sqrt(self.z_sq / self.z_n)))),
                "beyond_3_sigma_fraction": dict(zip(SIGMA_NAMES, (float(x) for x in self.z_out / self.z_n))),
                "epochs": self.z_n,
                "note": "the errors over the solution's own 1-sigma (1 for a consistent filter; yaw against the "
                        "heading sigma about down); 0.27 % of epochs beyond 3 sigma for Gaussian errors"}
        return out


def summarize(err: NavError) -> dict:
    """RMS, maximum absolute and final values of every error component.

    Keys: ``north_m``, ``east_m``, ``down_m``, ``horizontal_m``, ``3d_m``,
    ``vn_m_s``, ``ve_m_s``, ``vd_m_s``, ``roll_deg``, ``pitch_deg``,
    ``yaw_deg`` (degrees, as every other angle the package reports) and the
    same attitude figures in arcmin (``roll_arcmin``, ``pitch_arcmin``,
    ``yaw_arcmin``, kept for earlier readers); each maps to ``{"rms", "max",
    "final"}``.  Also ``epochs``, ``duration_s``, ``first_epoch_s`` and
    ``last_epoch_s`` (the time span scored).  :class:`ErrorSummary` makes
    the same from parts.
    """
    return ErrorSummary().add(err).result()


def nav_error_part(sol: NavSolution, truth: NavSolution, gaps=None) -> NavError:
    """:func:`nav_error` of a part of a solution (a segment of a streamed
    run), empty where the part lies outside the truth's span (no error: the
    whole run's check of the overlap is :meth:`ErrorSummary.result`).
    ``gaps``: the truth's (:func:`truth_gaps`), computed once per run rather
    than once per segment."""
    inside = truth_covers(sol.time, truth.time, gaps=gaps)
    if not inside.any():
        e = np.zeros((0, 3))
        return NavError(np.zeros(0), e, e, e)
    return _errors_at(sol, truth, inside)


def _epoch_tolerance(t):
    """One median epoch interval [s]: a window bound this close to the span
    scored is taken as its edge."""
    return float(np.median(np.diff(t))) if len(t) > 1 else 0.0


def restrict(err: NavError, t_from=None, t_to=None, *, name="--from/--to") -> NavError:
    """The epochs of ``err`` with ``t_from <= t <= t_to`` [s] (the time scale
    of the files' time column; ``None`` leaves that side open).

    Raises
    ------
    InputError
        ``t_from >= t_to``; a bound outside the span that the solution and the
        truth share (by more than one epoch interval); no epoch inside.  The
        message names ``name`` (the option) and the span.
    """
    t = err.time
    span = f"the solution and the truth share {t[0]:.3f}..{t[-1]:.3f} s"
    if t_from is not None and t_to is not None and not t_from < t_to:
        raise InputError(f"{name}: the window must end after it starts, got {t_from:g}..{t_to:g} s")
    tol = _epoch_tolerance(t)
    for label, b in (("start", t_from), ("end", t_to)):
        if b is not None and not (t[0] - tol <= b <= t[-1] + tol):
            raise InputError(f"{name}: the window's {label} {b:g} s lies outside the data ({span}; times are "
                             "those of the files' time column)")
    lo = -np.inf if t_from is None else t_from
    hi = np.inf if t_to is None else t_to
    m = (t >= lo) & (t <= hi)
    if not m.any():
        raise InputError(f"{name}: no epoch inside {lo:g}..{hi:g} s ({span})")
    return err.select(m)


@dataclass(frozen=True)
class ConstantOffset:
    """A constant NED position offset of a solution against its truth.

    Attributes
    ----------
    ned_m : (3,) ndarray
        Mean north, east, down error over the interval [m] (solution minus
        truth).
    spread_ned_m : (3,) ndarray
        Standard deviation of each component about that mean [m].
    epochs : int
        Epochs averaged.
    from_s, to_s : float
        First and last epoch averaged [s].
    """

    ned_m: np.ndarray
    spread_ned_m: np.ndarray
    epochs: int
    from_s: float
    to_s: float

    def summary(self) -> dict:
        n, e, d = (float(x) for x in self.ned_m)
        sn, se, sd = (float(x) for x in self.spread_ned_m)
        return {"north_m": n, "east_m": e, "down_m": d, "spread_north_m": sn, "spread_east_m": se,
                "spread_down_m": sd, "epochs": self.epochs, "from_s": self.from_s, "to_s": self.to_s}


def constant_offset(err: NavError, t_from=None, t_to=None, *, name="--remove-offset") -> ConstantOffset:
    """The constant NED offset of ``err`` over ``t_from..t_to`` [s]: the mean
    of each position-error component (the least-squares constant).

    A constant in NED is one vector over a drive of a few kilometres: the
    local frames of two points ``L`` apart differ by ``L / R`` rad (1.6 mrad
    over 10 km), which turns a 1 m offset by under 2 mm.  On correlated
    errors the mean is uncertain by more than ``spread / sqrt(epochs)``.
    """
    w = restrict(err, t_from, t_to, name=name)
    p = w.pos_ned
    return ConstantOffset(p.mean(axis=0), p.std(axis=0), int(len(w.time)), float(w.time[0]), float(w.time[-1]))


def remove_offset(err: NavError, offset_ned_m) -> NavError:
    """``err`` with the constant NED offset (3,) [m] subtracted from the
    position errors (velocity and attitude unchanged)."""
    o = np.asarray(offset_ned_m, float).reshape(3)
    return NavError(err.time, err.pos_ned - o, err.vel_ned, err.att_rpy, err.sigma)


#: the columns of :func:`per_epoch_columns`, in order
PER_EPOCH_COLUMNS = ("time_s", "err_north_m", "err_east_m", "err_down_m", "err_horizontal_m", "err_vertical_m",
                     "err_3d_m", "err_vn_m_s", "err_ve_m_s", "err_vd_m_s", "err_roll_deg", "err_pitch_deg",
                     "err_yaw_deg")


def per_epoch_columns(err: NavError) -> dict:
    """The error at every epoch as named float columns
    (:data:`PER_EPOCH_COLUMNS`): NED position error, horizontal
    ``hypot(north, east)``, vertical ``|down|`` and 3-D norm [m], NED
    velocity error [m/s], roll, pitch, yaw differences [deg], each wrapped
    to (-180, 180]."""
    p, v, a = err.pos_ned, err.vel_ned, err.att_rpy / DEG
    cols = [err.time, p[:, 0], p[:, 1], p[:, 2], err.horizontal, np.abs(p[:, 2]), np.linalg.norm(p, axis=1),
            v[:, 0], v[:, 1], v[:, 2], a[:, 0], a[:, 1], a[:, 2]]
    return {k: np.ascontiguousarray(c, dtype=np.float64) for k, c in zip(PER_EPOCH_COLUMNS, cols)}


def plot_errors(err: NavError, path, *, title="Navigation error", sigma=None):
    """Plot position, velocity and attitude errors against time to a PNG.

    The lines break across gaps of the epochs (those a truth gap left
    unscored) and across the wrap of an attitude error at +-180 deg
    (:func:`line_breaks`).

    Parameters
    ----------
    err : NavError
    path : str or Path
    sigma : dict, optional
        ``{"pos": (n, 3), "vel": (n, 3), "att": (n, 3)}`` 1-sigma arrays
        [m, m/s, rad]; drawn as +-3 sigma envelopes.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = err.time - err.time[0]
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    groups = [
        (err.pos_ned, "position error [m]", ("north", "east", "down"), 1.0, "pos"),
        (err.vel_ned, "velocity error [m/s]", ("north", "east", "down"), 1.0, "vel"),
        (err.att_rpy / DEG, "attitude error [deg]", ("roll", "pitch", "yaw"), 1.0 / DEG, "att"),
    ]
    for ax, (data, label, names, scale, key) in zip(axes, groups):
        for j, name in enumerate(names):
            # no line across a gap of the epochs scored (a truth gap, say) nor across an angle's wrap
            (line,) = ax.plot(*line_breaks(t, data[:, j], period=360.0 if key == "att" else None), lw=0.8,
                              label=name)
            if sigma is not None and key in sigma:
                s = 3.0 * np.asarray(sigma[key])[:, j] * scale
                ax.plot(*line_breaks(t, s), lw=0.6, ls="--", color=line.get_color())
                ax.plot(*line_breaks(t, -s), lw=0.6, ls="--", color=line.get_color())
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper left", fontsize=8)
    axes[-1].set_xlabel("time since start [s]")
    axes[0].set_title(title)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
    return path
