"""The evaluate job: a solution file against a truth file, over a time
window, optionally after removing a constant NED offset, with a per-epoch
error table.

The figures are :func:`inskit.analysis.summarize`'s (attitude in degrees,
yaw wrapped to +-180 deg); times are those of the files' time column.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .. import analysis, io
from .. import rotations as rot
from ..errors import InputError
from ..files import check_output_place, same_file
from ..units import DEG

#: file names the per-epoch table may have (the format follows the name)
PER_EPOCH_SUFFIXES = (".csv", ".csv.gz", ".parquet")

#: the value ``--remove-offset`` takes when given without an interval
WHOLE_WINDOW = "window"

_NUM = r"[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?"
_INTERVAL = re.compile(rf"^\s*({_NUM})?\s*:\s*({_NUM})?\s*$")


def parse_interval(text, option="--remove-offset"):
    """``(from_s, to_s)`` of ``FROM:TO`` (either side may be empty: open);
    ``(None, None)`` for :data:`WHOLE_WINDOW`.

    Raises
    ------
    InputError
        Anything else, with an example.
    """
    if text == WHOLE_WINDOW:
        return None, None
    m = _INTERVAL.match(str(text))
    if not m:
        raise InputError(f"{option}: {text!r} is not an interval FROM:TO in seconds (e.g. 100:160, 100: or :160; "
                         f"give {option} after the two files, or alone for the whole window)")
    a, b = (None if g is None else float(g) for g in m.groups())
    return a, b


def per_epoch_format(path) -> str:
    """``"parquet"`` or ``"csv"`` from the name; anything else is refused."""
    name = Path(path).name.lower()
    if name.endswith(".parquet"):
        return "parquet"
    if name.endswith(".csv") or name.endswith(".csv.gz"):
        return "csv"
    raise InputError(f"{path}: unsupported per-epoch table format; use a name ending in "
                     f"{', '.join(PER_EPOCH_SUFFIXES)}")


def check_per_epoch_file(path, force, inputs=()):
    """Refuse, before the work, a per-epoch path of unknown format, one that
    exists (without ``force``), one that names an input or one whose folder
    cannot hold it."""
    if path is None:
        return
    per_epoch_format(path)
    for inp in inputs:
        if same_file(path, inp):
            raise InputError(f"{path}: is an input of this run; choose another --per-epoch file")
    if Path(path).exists() and not force:
        raise InputError(f"{path}: already exists; refusing to overwrite it (use --force)")
    check_output_place(path)


def write_per_epoch(path, err: analysis.NavError, metadata=None) -> Path:
    """The per-epoch errors (:data:`inskit.analysis.PER_EPOCH_COLUMNS`) as CSV
    or Parquet by the name, written whole or not at all."""
    from ..io.parquet import write_csv_fast, write_parquet

    cols = analysis.per_epoch_columns(err)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    if per_epoch_format(path) == "parquet":
        return write_parquet(path, cols, metadata)
    return write_csv_fast(path, cols)


def evaluate(solution_file, truth_file, *, t_from=None, t_to=None, remove_offset=None, per_epoch_file=None,
             force=False, plot_file=None) -> dict:
    """Errors of a solution file against a truth file.

    Parameters
    ----------
    solution_file, truth_file : str or Path
        Solution files (CSV or Parquet, told by content), one time base.
    t_from, t_to : float, optional
        The window scored [s] (the files' time column); default the whole
        span they share.
    remove_offset : tuple of (float or None, float or None), optional
        Estimate the constant NED position offset (mean solution minus truth)
        over this interval (``(None, None)``: the window) and subtract it
        before scoring; the interval may lie outside the window (a static
        start, say) but inside the shared span.
    per_epoch_file : str or Path, optional
        Write the per-epoch errors of the window (after the offset removal)
        here.
    force : bool
        Overwrite ``per_epoch_file`` (and ``plot_file``) if it exists.
    plot_file : str or Path, optional
        An error plot (the caller checks its format first).

    Returns
    -------
    dict
        :func:`inskit.analysis.summarize`'s keys, ``solution_file``,
        ``truth_file``, ``window`` (``from_s``, ``to_s`` as asked, ``None``
        for open), ``offset_removed`` (:meth:`~inskit.analysis.ConstantOffset.summary`,
        or ``None``) and, when written, ``per_epoch`` and ``plot``.

    Raises
    ------
    InputError
        A bad window or interval (empty, reversed, outside the shared span),
        no overlap, an unwritable or existing output.
    """
    check_per_epoch_file(per_epoch_file, force, (solution_file, truth_file))
    if plot_file is not None and per_epoch_file is not None and same_file(plot_file, per_epoch_file):
        raise InputError(f"{per_epoch_file}: given as both --plot and --per-epoch")
    sol = io.read_solution(solution_file)
    truth = io.read_solution(truth_file)
    full = analysis.nav_error(sol, truth)
    cover = analysis.truth_coverage(sol.time, truth.time)
    err = analysis.restrict(full, t_from, t_to, name="--from/--to")
    offset = None
    if remove_offset is not None:
        a, b = remove_offset
        offset = (analysis.constant_offset(err) if a is None and b is None
                  else analysis.constant_offset(full, a, b, name="--remove-offset"))
        err = analysis.remove_offset(err, offset.ned_m)
    s = analysis.summarize(err)
    if offset is not None and "consistency" in s:
        # the solution's sigmas describe its error with any offset in it; what is left once an offset fitted to
        # the errors is gone passed an overconfident solution (a correlated error is much of the offset)
        c = s["consistency"]
        for f in ("normalized_rms", "beyond_3_sigma_fraction"):
            c[f].update(dict.fromkeys(OFFSET_CHANNELS, None))
        c["note"] += (f"; {', '.join(OFFSET_CHANNELS)} not judged (null): a constant offset was removed, and the "
                      "solution's sigmas describe its error with the offset in it")
    s["solution_file"] = str(solution_file)
    s["truth_file"] = str(truth_file)
    s["window"] = {"from_s": t_from, "to_s": t_to}
    s["offset_removed"] = offset.summary() if offset is not None else None
    s["truth_coverage"] = cover
    s["warnings"] = (coverage_warnings(cover, truth.time) + sampling_warnings(sol.time, truth.time, truth_file)
                     + start_warnings(full, truth_file)
                     + attitude_unit_warnings(sol, truth, solution_file, truth_file)
                     + gimbal_lock_warnings(err, sol, truth)
                     + sigma_column_warnings(err, solution_file, sol) + truth_consistency_warnings({"": s}))
    if per_epoch_file is not None:
        meta = {"solution": str(solution_file), "truth": str(truth_file), "window": s["window"],
                "offset_removed": s["offset_removed"]}
        s["per_epoch"] = str(write_per_epoch(per_epoch_file, err, meta))
    if plot_file is not None:
        title = f"{Path(solution_file).name} vs {Path(truth_file).name}"
        if offset is not None:
            title += " (constant offset removed)"
        analysis.plot_errors(err, plot_file, title=title)
        s["plot"] = str(plot_file)
    return s


#: the channels of ``consistency`` that a removed offset leaves unjudged (the position's)
OFFSET_CHANNELS = ("north", "east", "down")

#: a truth sampled more coarsely than this [s] (median step), and than this many solution steps, is said
TRUTH_STEP_WARN_S = 2.0
TRUTH_STEP_WARN_RATIO = 50.0


#: a solution whose errors against the truth exceed its own sigmas by this factor (RMS) on a channel is
#: overconfident there: the summary warns
TRUTH_OVERCONFIDENT_FACTOR = 2.0
#: what each channel's overconfidence most often comes from
TRUTH_OVERCONFIDENT_HINTS = {
    "position": "fixes whose error is time-correlated or larger than their sigmas ([gnss] error_sigma_m, "
                "sigma_scale_ned, sigma_floor_m)",
    "velocity": "accelerometer noise or biases larger than configured, or vibration ([noise])",
    "yaw": "gyro noise or biases larger than configured, or a mounting the constraints do not model ([noise], "
           "[constraints] mounting)"}
#: a yaw error of more than this RMS [deg] is beyond the filter's small-angle model: rather a truth whose yaw
#: follows another convention (or a heading never found) than gyro noise
TRUTH_YAW_CONVENTION_DEG = 20.0


def sigma_column_warnings(err: analysis.NavError, solution_file="solution", sol=None) -> list[str]:
    """Scored epochs whose ``sigma_*`` columns
    (:data:`inskit.analysis.errors.SIGMA_COLUMNS`) hold a value of 0 or
    below, in words: ``consistency`` leaves them out (all of them: no
    ``consistency``), which would otherwise go unsaid; and, given the
    solution ``sol``, a file that carries some of those columns but not all
    (no ``consistency`` at all)."""
    from ..analysis.errors import SIGMA_COLUMNS

    if err.sigma is None:
        have = [c for c in SIGMA_COLUMNS if c in (getattr(sol, "extra", None) or {})]
        if have:  # some of its own sigmas, not all: nothing judged, said
            missing = [c for c in SIGMA_COLUMNS if c not in have]
            return [f"{solution_file}: it carries {', '.join(have)} but not {', '.join(missing)}: the errors are "
                    "not judged against the solution's own sigmas (no consistency figure; all of "
                    f"{', '.join(SIGMA_COLUMNS)} are needed)"]
        return []
    if not len(err.time):
        return []
    bad = ~np.all(err.sigma > 0, axis=1)
    if not bad.any():
        return []
    cols = [c for c, b in zip(SIGMA_COLUMNS, (err.sigma <= 0).any(axis=0)) if b]
    return [f"{solution_file}: {int(bad.sum())} of {len(bad)} scored epochs hold 0 or less in "
            f"{', '.join(cols)} (a 1-sigma is > 0): they are not judged against the solution's own sigmas"
            + ("; no epoch is, so there is no consistency figure" if bad.all() else "")]


def truth_consistency_warnings(errs: dict) -> list[str]:
    """Warnings for the solutions (``truth_errors``' ``forward``,
    ``smoothed``) whose errors against the truth are, on some channel, more
    than :data:`TRUTH_OVERCONFIDENT_FACTOR` times their own 1-sigma (RMS of
    the ratio, :class:`inskit.analysis.errors.ErrorSummary`'s
    ``consistency``): the sigmas the run reports understate its errors
    there.  A consistent filter's ratio has an RMS of 1; over a run whose
    errors are correlated for a minute, half an hour holds some 30
    independent samples, whose RMS scatters by about 13 %: twice is no
    chance."""
    out = []
    for label, e in errs.items():
        c = e.get("consistency")
        if not c:
            continue
        bad = {k: v for k, v in c["normalized_rms"].items() if v is not None and v > TRUTH_OVERCONFIDENT_FACTOR}
        if bad:
            worst = sorted(bad, key=bad.get, reverse=True)
            what = ", ".join(f"{k} {bad[k]:.1f} ({c['beyond_3_sigma_fraction'][k]:.0%} of epochs beyond 3 sigma)"
                             for k in worst)
            kinds = [kind for kind, names in (("position", ("north", "east", "down")),
                                              ("velocity", ("vn", "ve", "vd")), ("yaw", ("yaw",)))
                     if any(k in bad for k in names)]
            hints = dict(TRUTH_OVERCONFIDENT_HINTS)
            yaw_rms = (e.get("yaw_deg") or {}).get("rms")
            if yaw_rms is not None and yaw_rms > TRUTH_YAW_CONVENTION_DEG:
                hints["yaw"] = (f"an error of {yaw_rms:.0f} deg RMS is no filter's small-angle error: a truth whose "
                                "yaw_deg follows another convention (clockwise from north expected: not from east, "
                                "not counter-clockwise, the body's x axis forward), or a heading the start-up never "
                                "found")
            hint = "; ".join(f"{kind}: {hints[kind]}" for kind in kinds)
            whose = f"the {label} solution's" if label else "the solution's"
            out.append(f"truth: {whose} errors are more than {TRUTH_OVERCONFIDENT_FACTOR:g} times its "
                       f"own sigmas (RMS of error over sigma, 1 when consistent: {what}): the filter is "
                       f"overconfident there and its sigma columns understate the error. Likely causes, {hint}")
    return out


def sampling_warnings(t, truth_time, truth_file="truth") -> list[str]:
    """A truth sampled far more coarsely than the solution (median step
    above :data:`TRUTH_STEP_WARN_S` and :data:`TRUTH_STEP_WARN_RATIO` times
    the solution's), in words: the errors between its samples are those of
    a linear interpolation over that step, not the solution's; and a truth
    whose time column is in milliseconds (a 100 Hz truth read as a sample
    every 10 s) looks the same and is scored without another word."""
    tt, ts = np.asarray(truth_time, float), np.asarray(t, float)
    if len(tt) < 2 or len(ts) < 2:
        return []
    dt_truth, dt_sol = float(np.median(np.diff(tt))), float(np.median(np.diff(ts)))
    if dt_truth > TRUTH_STEP_WARN_S and dt_truth > TRUTH_STEP_WARN_RATIO * dt_sol:
        return [f"{truth_file}: the truth is sampled every {dt_truth:.4g} s (median) against the solution's "
                f"{dt_sol:.4g} s: between its samples the errors are those of a linear interpolation over "
                f"{dt_truth:.4g} s, not the solution's own (a time column in ms, 1000 times its seconds, looks "
                "the same)"]
    return []


#: a solution further than this [m] from the truth at the first epoch they share is said
START_APART_WARN_M = 10_000.0


def start_warnings(err, truth_file="truth") -> list[str]:
    """A solution that is already far from the truth at the first epoch they
    share (above :data:`START_APART_WARN_M` horizontally), in words: a
    solution starts from the truth or from the fixes, so two files kilometres
    apart from the start describe different places (another datum, or
    radians under a ``_deg`` header: a latitude of 0.7 for 40 deg) rather
    than a navigation error, and their scores would read as one."""
    if not len(err.time):
        return []
    h0 = float(np.hypot(err.pos_ned[0, 0], err.pos_ned[0, 1]))
    if h0 > START_APART_WARN_M:
        return [f"{truth_file}: at the first epoch they share ({float(err.time[0]):.3f} s) the solution is "
                f"{h0 / 1000.0:.4g} km from the truth: the two files seem to describe different places (a datum, "
                "or angles in radians under a _deg header?) rather than a navigation error"]
    return []


#: a pitch [deg] beyond which (in size) roll and yaw are ill-defined: their errors are amplified about
#: 1 / cos(pitch) times (11 at 85 deg) and flip by 180 deg across +-90
GIMBAL_LOCK_PITCH_DEG = 85.0


def gimbal_lock_warnings(err: analysis.NavError, sol, truth) -> list[str]:
    """Scored epochs where the solution's or the truth's pitch lies beyond
    :data:`GIMBAL_LOCK_PITCH_DEG` (a vertical climb, a loop), in words.
    There roll and yaw are ill-defined, and the roll and yaw errors (Euler
    differences) read tens of degrees, up to 180, for an attitude off by a
    fraction of one: the warning sets beside them the angle of the rotation
    between the two attitudes over the same epochs."""
    if not len(err.time):
        return []
    i = np.searchsorted(sol.time, err.time)  # the scored epochs are solution epochs
    tr = truth.interpolate(err.time)
    near = np.maximum(np.abs(sol.euler[i, 1]), np.abs(tr.euler[:, 1])) > GIMBAL_LOCK_PITCH_DEG * DEG
    if not near.any():
        return []
    cos_half = np.abs(np.einsum("ij,ij->i", sol.q_nb[i[near]], tr.q_nb[near]))
    angle = 2.0 * np.arccos(np.clip(cos_half, 0.0, 1.0)) / DEG
    euler = np.abs(err.att_rpy[near][:, [0, 2]]).max() / DEG
    t = err.time[near]
    return [f"{int(near.sum())} of the {len(err.time)} epochs scored ({t[0]:.3f}..{t[-1]:.3f} s) have a pitch beyond "
            f"+-{GIMBAL_LOCK_PITCH_DEG:g} deg, where roll and yaw are ill-defined (gimbal lock): the roll and yaw "
            f"errors there (up to {euler:.3g} deg) are differences of Euler angles, while the attitude is off by at "
            f"most {angle.max():.3g} deg (the angle of the rotation between the two attitudes); read roll_deg and "
            "yaw_deg with that in mind"]


def vertical_pitch_warnings(truth, t0, t1) -> list[str]:
    """:func:`gimbal_lock_warnings` from the truth alone, for a run that
    scores its solution against a truth as it goes (``navigate --truth``:
    the per-epoch errors of a streamed run are not kept): the truth's rows
    within ``[t0, t1]`` whose pitch lies beyond
    :data:`GIMBAL_LOCK_PITCH_DEG`, where the roll and yaw errors are
    differences of Euler angles.  The sine of the pitch straight from the
    quaternions (``-C_nb[2, 0]``): no Euler angles of the whole truth."""
    k0, k1 = int(np.searchsorted(truth.time, t0, side="left")), int(np.searchsorted(truth.time, t1, side="right"))
    q = truth.q_nb[k0:k1]
    if not len(q):
        return []
    sin_p = 2.0 * (q[:, 0] * q[:, 2] - q[:, 1] * q[:, 3])
    near = np.abs(sin_p) > np.sin(GIMBAL_LOCK_PITCH_DEG * DEG)
    if not near.any():
        return []
    t = truth.time[k0:k1][near]
    return [f"the truth's pitch passes beyond +-{GIMBAL_LOCK_PITCH_DEG:g} deg at {int(near.sum())} of its "
            f"{len(q)} rows ({t[0]:.3f}..{t[-1]:.3f} s), where roll and yaw are ill-defined (gimbal lock): the "
            "roll and yaw errors there are differences of Euler angles (up to 180 deg for an attitude off by a "
            "fraction of one); inskit evaluate of the solution file sets the rotation angle beside them"]


#: attitude columns of a solution file, in the order of :attr:`NavSolution.euler`
ATTITUDE_COLUMNS = ("roll_deg", "pitch_deg", "yaw_deg")
#: a horizontal speed [m/s] above which the direction of travel is taken as a heading reference
COURSE_MIN_SPEED_M_S = 2.0
#: fewest moving epochs (and fewest shared epochs) the attitude-unit checks need
UNIT_CHECK_MIN_EPOCHS = 20
#: the checks look at this many epochs at most (evenly spread): a verdict, not a score
UNIT_CHECK_MAX_EPOCHS = 20_000
#: a track whose courses have a mean resultant length above this does not turn enough to tell units apart
COURSE_MAX_RESULTANT = 0.9
#: yaw read as radians within this [deg] (median) of the course, and read as degrees beyond the next, is radians
COURSE_FIT_DEG, COURSE_MISFIT_DEG = 20.0, 45.0
#: a column whose values times 180/pi fit the other file this many times better (RMS) is radians, when as
#: written they differ by more than the next [deg] (RMS): a column in degrees times 57.3 fits far worse
SCALED_FIT_RATIO, SCALED_MIN_MISFIT_DEG = 4.0, 0.5
_RADIAN_RANGE = 2.0 * np.pi + 1e-6


def _wrapped_deg(x):
    """Angles [deg] wrapped into [-180, 180)."""
    return (np.asarray(x, float) + 180.0) % 360.0 - 180.0


def _rms(x):
    return float(np.sqrt(np.mean(np.square(x))))


def _spread(idx, limit=UNIT_CHECK_MAX_EPOCHS):
    """At most ``limit`` of the indices ``idx``, evenly spread."""
    return idx if len(idx) <= limit else idx[np.linspace(0, len(idx) - 1, limit).astype(int)]


def _yaw_radians_evidence(nav) -> str | None:
    """Why the ``yaw_deg`` column of ``nav`` holds radians, or None: on a
    moving track that turns, its values stay within +-2 pi and, read as
    radians, follow the direction of travel (``atan2(ve, vn)``) where read
    as degrees they do not.  A vehicle's yaw follows its course up to the
    side-slip and crab (tens of degrees at most), and a track that turns
    rules out a chance fit of the radian reading; a track that does not turn
    (or a body turned from its direction of travel) says nothing."""
    speed = np.hypot(nav.v_n[:, 0], nav.v_n[:, 1])
    idx = _spread(np.nonzero(speed > COURSE_MIN_SPEED_M_S)[0])
    if len(idx) < UNIT_CHECK_MIN_EPOCHS:
        return None
    course = np.arctan2(nav.v_n[idx, 1], nav.v_n[idx, 0])
    if abs(np.mean(np.exp(1j * course))) > COURSE_MAX_RESULTANT:
        return None
    y = rot.euler_from_quat(nav.q_nb[idx])[:, 2] / DEG  # the numbers as the file holds them
    if np.abs(y).max() > _RADIAN_RANGE:
        return None
    as_deg = float(np.median(np.abs(_wrapped_deg(y - np.degrees(course)))))
    as_rad = float(np.median(np.abs(_wrapped_deg(np.degrees(y) - np.degrees(course)))))
    if as_rad < COURSE_FIT_DEG and as_deg > COURSE_MISFIT_DEG:
        return (f"column 'yaw_deg' seems to hold radians, not degrees: its values stay within "
                f"{y.min():.4g}..{y.max():.4g} and, read as radians, follow the direction of travel (median "
                f"difference {as_rad:.3g} deg over {len(idx)} moving epochs of a track that turns) where read as "
                f"degrees they differ from it by {as_deg:.3g} deg: the yaw errors are meaningless (write the "
                "attitude in degrees)")
    return None


def attitude_unit_warnings(sol, truth, solution_file="solution", truth_file="truth") -> list[str]:
    """Attitude columns (``roll_deg``, ``pitch_deg``, ``yaw_deg``) that seem
    to hold radians under their degree headers, in words naming the file and
    the column: their errors would be scored as nonsense (a yaw in radians
    is off by up to 180 deg, a roll in radians looks 57 times better than it
    is).

    Two tests, each of which tells radians with confidence where it speaks:

    * a file's yaw against its own direction of travel
      (:func:`_yaw_radians_evidence`), on a moving track that turns;
    * a column of one file against the same column of the other, at the
      epochs the truth scores: its values lie within +-2 pi and, times
      180/pi, fit the other file's :data:`SCALED_FIT_RATIO` times better
      (RMS) than as written, which differ by more than
      :data:`SCALED_MIN_MISFIT_DEG`.  Angles near zero (a level drive's
      roll) fit either way and are not judged: their errors are small
      either way.

    Two files that both hold radians fit each other as written: only the
    first test can see them (a yaw on a turning track).
    """
    files = (("solution", sol, str(solution_file)), ("truth", truth, str(truth_file)))
    out, said = [], set()
    for key, nav, name in files:
        why = _yaw_radians_evidence(nav)
        if why:
            out.append(f"{name}: {why}")
            said.add((key, 2))
    idx = _spread(np.nonzero(analysis.truth_covers(sol.time, truth.time))[0])
    if len(idx) < UNIT_CHECK_MIN_EPOCHS:
        return out
    values = {"solution": rot.euler_from_quat(sol.q_nb[idx]) / DEG,
              "truth": rot.euler_from_quat(truth.interpolate(sol.time[idx]).q_nb) / DEG}
    for j, column in enumerate(ATTITUDE_COLUMNS):
        as_written = _rms(_wrapped_deg(values["solution"][:, j] - values["truth"][:, j]))
        if as_written <= SCALED_MIN_MISFIT_DEG:
            continue
        for key, nav, name in files:
            other = "truth" if key == "solution" else "solution"
            mine = values[key][:, j]
            if (key, j) in said or np.abs(mine).max() > _RADIAN_RANGE:
                continue
            scaled = _rms(_wrapped_deg(np.degrees(mine) - values[other][:, j]))
            if scaled * SCALED_FIT_RATIO <= as_written:
                other_name = dict((k, n) for k, _, n in files)[other]
                out.append(f"{name}: column '{column}' seems to hold radians, not degrees: its values stay within "
                           f"{mine.min():.4g}..{mine.max():.4g} and, times 180/pi, they match {other_name}'s "
                           f"'{column}' to {scaled:.3g} deg (RMS over {len(idx)} epochs) where as written they "
                           f"differ by {as_written:.3g} deg: the {column[:-4]} errors are meaningless (write the "
                           "attitude in degrees)")
                said.add((key, j))
                break
    return out


def coverage_warnings(cover: dict, truth_time) -> list[str]:
    """What a truth left unscored (:func:`inskit.analysis.truth_coverage`),
    in words: epochs outside its span, epochs inside its gaps."""
    out = []
    n, done = cover["epochs"], cover["epochs_scored"]
    if cover["epochs_outside_truth_span"]:
        out.append(f"{cover['epochs_outside_truth_span']} of {n} solution epochs lie outside the truth's span "
                   f"({float(truth_time[0]):.3f}..{float(truth_time[-1]):.3f} s) and are not scored")
    gaps = cover["truth_gaps"]
    if cover["epochs_in_truth_gaps"]:
        longest = max(gaps, key=lambda g: g[1] - g[0])
        out.append(f"{cover['epochs_in_truth_gaps']} solution epochs fall in {len(gaps)} gap(s) of the truth longer "
                   f"than {cover['truth_gap_limit_s']:.3g} s (5 of its sampling intervals; the longest "
                   f"{longest[0]:.3f}..{longest[1]:.3f} s) and are not scored: the truth is not interpolated "
                   "across them")
    if out:
        out.append(f"scored {done} of {n} solution epochs")
    if 0 < done < FEW_EPOCHS:
        out.append(f"only {done} solution epoch{'s' if done > 1 else ''} scored: an RMS and a maximum of so few "
                   "errors say little (a solution file cut short, or written at a low rate?)")
    return out


#: fewer scored epochs than this is a warning: the statistics of a handful of errors are no accuracy figure
FEW_EPOCHS = 10

SUMMARY_ROWS = (("north_m", "m"), ("east_m", "m"), ("down_m", "m"), ("horizontal_m", "m"), ("3d_m", "m"),
                ("vn_m_s", "m/s"), ("ve_m_s", "m/s"), ("vd_m_s", "m/s"),
                ("roll_deg", "deg"), ("pitch_deg", "deg"), ("yaw_deg", "deg"))


def summary_text(s: dict) -> str:
    """The table form of :func:`evaluate`'s summary."""
    lines = [f"{'error':<14}{'rms':>12}{'max':>12}{'final':>12}  unit"]
    for k, u in SUMMARY_ROWS:
        v = s[k]
        lines.append(f"{k:<14}{v['rms']:>12.4g}{v['max']:>12.4g}{v['final']:>12.4g}  {u}")
    lines.append(f"{s['epochs']} epochs over {s['duration_s']:.1f} s "
                 f"({s['first_epoch_s']:.3f}..{s['last_epoch_s']:.3f} s)")
    c = s.get("consistency")
    if c:  # the solution carried its own sigmas
        lines.append("error over the solution's own sigma, RMS (1 when consistent): " + ", ".join(
            f"{k} {'n/a' if v is None else format(v, '.2f')}" for k, v in c["normalized_rms"].items())
            + (" (n/a: the position after a removed offset is not judged)" if None in c["normalized_rms"].values()
               else ""))
    for w in s.get("warnings", []):
        lines.append(f"warning: {w}")
    o = s.get("offset_removed")
    if o:
        lines.append(f"constant offset removed (mean over {o['from_s']:.3f}..{o['to_s']:.3f} s, {o['epochs']} epochs): "
                     f"north {o['north_m']:.4f} m, east {o['east_m']:.4f} m, down {o['down_m']:.4f} m")
    return "\n".join(lines)
