"""The main job: IMU log + GNSS fixes -> navigation solution, and how good it is."""

from __future__ import annotations

import dataclasses
import json
import time
import warnings
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import io
from .. import rotations as rot
from ..alignment.coarse import Startup, gnss_speed, static_intervals
from ..errors import InputError
from ..files import write_json, write_text
from ..io.rtklib import read_pos, read_rtklibexplorer_imu
from ..io.time_tags import JITTER_HINT_FRACTION, JITTER_TOLERANCE
from ..types import GnssData, ImuData, NavState, fix_sigmas
from ..units import DEG, MILLI_G
from ..integration import (FilterOutput, FilterSettings, GnssPosition, GnssVelocity, InitialUncertainty,
                           NonHolonomic, SensorNoise, Track, ZeroVelocity, rts_smooth, run_filter, run_uncoupled)
from ..types import NavSolution
from .config import KEPT_GRID_ROWS, NavigateConfig
from .outages import OutageScore, rtklibexplorer_outages, score_outages, withheld_mask


@dataclass
class NavigateResult:
    config: NavigateConfig
    imu: ImuData
    gnss: GnssData
    windows: list
    used: np.ndarray
    startup: Startup | None
    settings: FilterSettings
    forward: FilterOutput | Track
    smoothed: Track | None
    score_forward: OutageScore
    score_smoothed: OutageScore | None
    elapsed_s: float
    measured_noise: dict
    gaps: list = None
    raw: RawGnss | None = None
    clock_start: dict | None = None
    rate_changes: list = None
    truth: NavSolution | None = None  #: the truth scored against ([truth] file / --truth)
    streams: list = None  #: solution files written during a streamed run, committed by write_outputs
    pending: object = None  #: the writer still finishing them (:func:`finish_streams`)
    truth_parts: dict = None  #: a streamed run's truth errors, segment by segment (``analysis.ErrorSummary``)
    imu_notes: dict = None  #: what the IMU reader found (repeated rows), when navigate read the files
    aiding: list = None  #: the aiding logs fused: ``(what, file, measurement)`` (:func:`aiding_warnings`)
    constraint_check: dict = None  #: the default NHC found not to hold and the run made without it (:func:`run`)


def finish_streams(res: NavigateResult) -> None:
    """Wait for a streamed run's writer and close its files (still under
    their temporary names; :func:`write_outputs` commits them)."""
    pipe, res.pending = res.pending, None
    if pipe is not None:
        try:
            pipe.close()
        except BaseException:
            abort_streams(res)
            raise
    for w in res.streams or ():
        w.close()


def abort_streams(res: NavigateResult) -> None:
    """Stop a streamed run's writer and remove its temporary files."""
    pipe, res.pending = res.pending, None
    if pipe is not None:
        pipe.close(quiet=True)
    for w in res.streams or ():
        w.abort()


def streams_run(cfg: NavigateConfig) -> bool:
    """Whether the run is streamed (``[output] stream``: "auto" and "on"
    stream every run that has a filter; the uncoupled scheme keeps its rows)."""
    return cfg.filter.scheme != "uncoupled" and cfg.output.stream != "off"


def kept_grid_rate(t, rate_hz) -> float:
    """The rate of the grid :func:`stream_keep_rows` keeps: ``rate_hz``, or
    :data:`KEPT_GRID_ROWS` over the log's span when that is lower."""
    span = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    return float(rate_hz) if span * float(rate_hz) <= KEPT_GRID_ROWS else KEPT_GRID_ROWS / span


def stream_keep_rows(t, gnss: GnssData, windows, rate_hz) -> np.ndarray:
    """The IMU rows a streamed run keeps in memory for the summary and the
    plots: the two rows around each fix (used or withheld, so the antenna
    position at a fix interpolates as in the whole run), every row of an
    outage's unaided span (from the last used fix before it to the first
    after it, :func:`.outages.unaided_spans`: where its worst point against a
    truth is looked for) and a regular grid (:func:`inskit.io.parquet.decimation_index`)
    at ``rate_hz``, coarser on a long log (:func:`kept_grid_rate`), so the
    kept rows grow with the fixes and the outages, not with the IMU rate."""
    from ..io.parquet import decimation_index
    from .outages import unaided_spans

    n = len(t)
    k = np.searchsorted(t, gnss.time, side="right") - 1
    parts = [np.clip(k, 0, n - 1), np.clip(k + 1, 0, n - 1), decimation_index(t, kept_grid_rate(t, rate_hz))]
    for (a, b), (t_prev, t_next) in zip(windows, unaided_spans(gnss, windows)):
        a, b = min(a, t_prev) if np.isfinite(t_prev) else a, max(b, t_next) if np.isfinite(t_next) else b
        lo, hi = np.searchsorted(t, [a, b])
        parts.append(np.arange(max(lo - 1, 0), min(hi + 1, n)))
    return np.unique(np.concatenate(parts).astype(np.int64))


def open_streams(cfg: NavigateConfig, out_dir: Path, t, settings, label="forward") -> list:
    """The ``label`` solution files of ``[output] format`` as
    :class:`inskit.io.parquet.SolutionStream` (temporary names in
    ``out_dir`` until :func:`write_outputs` commits them)."""
    from ..io.parquet import SolutionStream, decimation_index

    o = cfg.output
    out = []
    if o.format in ("parquet", "both"):
        out.append(SolutionStream(out_dir / f"solution_{label}.parquet", columns=o.columns,
                                  metadata={"config": cfg.name, "solution": label, "scheme": settings.scheme}))
    if o.format in ("csv", "both"):
        rows = decimation_index(t, o.rate_hz)
        out.append(SolutionStream(out_dir / f"solution_{label}.csv", rows=None if len(rows) == len(t) else rows,
                                  columns=o.columns))
    return out


class _Pipe:
    """Run ``fn(item)`` on a worker thread for each item put, in order, at
    most ``depth`` waiting (memory stays bounded): a streamed run converts
    and writes a segment while the compiled filter (which releases the GIL)
    computes the next.  An error in ``fn`` is raised by the next
    :meth:`put` or by :meth:`close`."""

    def __init__(self, fn, depth=2):
        import queue
        import threading

        self.fn, self.error = fn, None
        self.q = queue.Queue(maxsize=depth)
        self.thread = threading.Thread(target=self._run, name="inskit-writer", daemon=True)
        self.thread.start()

    def _run(self):
        while True:
            item = self.q.get()
            if item is None:
                return
            if self.error is None:
                try:
                    self.fn(item)
                except BaseException as exc:  # noqa: BLE001 (handed to the main thread)
                    self.error = exc

    def put(self, item):
        if self.error is not None:
            raise self.error
        self.q.put(item)

    def close(self, quiet=False):
        """Wait for every item; raise the worker's error, if any (``quiet``:
        the caller is already failing and only wants the thread stopped)."""
        self.q.put(None)
        self.thread.join()
        if self.error is not None and not quiet:
            raise self.error


class _ForwardScratch:
    """The forward run's every row (time, position, velocity, attitude,
    estimates) in files of a scratch folder, for the smoother's pass over
    the rows after the filter's (a streamed smoothed run)."""

    NAMES = (("lla", 3), ("v", 3), ("q", 4))

    def __init__(self, folder, aux_size):
        self.folder, self.aux_size = Path(folder), aux_size
        self._fh = {k: open(self.folder / f"fwd_{k}.bin", "wb") for k, _ in self.NAMES + (("aux", 0),)}

    def __call__(self, sg):
        for k, a in (("lla", sg.lla), ("v", sg.v_n), ("q", sg.q_nb), ("aux", sg.aux)):
            np.ascontiguousarray(a).tofile(self._fh[k])

    def close(self):
        for fh in self._fh.values():
            fh.close()

    def rows(self, a, b):
        """``lla, v, q, aux`` of rows ``a .. b-1``."""
        out = []
        for k, w in self.NAMES + (("aux", self.aux_size),):
            out.append(np.fromfile(self.folder / f"fwd_{k}.bin", count=(b - a) * w, offset=a * w * 8).reshape(b - a, w))
        return out


def _smooth_streamed(cfg, out, store, scratch, imu, settings, stream_dir, log=None, truth=None, truth_parts=None):
    """The RTS smoother of a streamed run: the backward pass over the nodes on
    disk, then the smoothed rows segment by segment into their files (and
    their truth errors into ``truth_parts["smoothed"]``); returns the
    smoothed track at the forward run's kept rows and the smoothed files'
    streams."""
    from ..analysis.errors import nav_error_part, truth_gaps
    from ..integration.engine import NAV_SIGMA_BLOCKS, SEGMENT_ROWS
    from ..integration.smoother import backward_pass, smooth_rows

    lay = settings.layout
    t0 = time.perf_counter()
    nodes = backward_pass(store.block, store.m, lay.initial_covariance())
    nodes.t = imu.time[nodes.k]
    streams = open_streams(cfg, Path(stream_dir), imu.time, settings, "smoothed")
    gaps = truth_gaps(truth.time)[0] if truth_parts is not None else None  # once, not per segment
    try:
        N = len(imu)
        for a in range(0, N, SEGMENT_ROWS):
            b = min(a + SEGMENT_ROWS, N)
            lla, v, q, aux = scratch.rows(a, b)
            tr = smooth_rows(nodes, lay, NavSolution._trusted(imu.time[a:b], lla, v, q), aux, np.arange(a, b))
            sol = NavSolution._trusted(tr.nav.time, tr.nav.lla, tr.nav.v_n, tr.nav.q_nb,
                                       lay.columns(tr.aux, tr.sigma, sigma_blocks=NAV_SIGMA_BLOCKS))
            for w in streams:
                w.write(sol, a)
            if truth_parts is not None:
                truth_parts["smoothed"].add(nav_error_part(sol, truth, gaps))
        for w in streams:
            w.close()
    except BaseException:
        for w in streams:
            w.abort()
        raise
    if log:
        log(f"smoother: {store.m} nodes, rows written in {time.perf_counter() - t0:.1f} s")
    kept = smooth_rows(nodes, lay, out.nav, out.aux, out.rows)
    kept.rows = out.rows
    return kept, streams


WEEK_S = 604800.0  #: seconds in a GPS week


@dataclass
class RawGnss:
    """What tight coupling reads: the RINEX files, our single-point solution
    of them and the corrected range table, on the IMU's seconds of week."""

    obs: object
    nav: object
    spp: object
    table: object
    week: int
    offset_s: float  #: subtracted from GPS seconds since 1980 to give seconds of week ``week``
    notes: tuple = ()  #: what reading and solving the files found (logged, ``rinex.notes`` of the summary)
    warnings: tuple = ()  #: those of the notes that are health warnings of the run
    clock_jumps: tuple = ()  #: (epoch index, step [m]) of each receiver clock jump taken out of the ranges


def load_raw_gnss(cfg: NavigateConfig, log=None) -> RawGnss:
    """Read the RINEX files, solve them epoch by epoch (start-up and the
    atmosphere corrections need a position) and build the range table."""
    from ..gnss.ranges import range_table
    from ..gnss.rinex import read_nav, read_obs
    from ..gnss.spp import clock_jump_note, receiver_clock_jumps, remove_clock_jumps, spp

    g = cfg.gnss
    systems = tuple(g.systems)
    # the readers' and the solver's warnings (systems left out, unsolved epochs ...) are the user's to read:
    # the command line silences library warnings, so they went unsaid in a tightly coupled run
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        obs = read_obs(cfg.resolve(g.obs), systems=systems)
        nav = read_nav(cfg.resolve(g.nav), systems=systems)
        sol = spp(obs, nav, mask_deg=g.mask_deg, iono=g.iono, tropo=g.tropo, systems=systems,
                  settings={"mask": "[gnss] mask_deg", "iono": "[gnss] iono = \"klobuchar\""})
    notes = []
    files = tuple(str(p) for p in (g.obs, g.nav, cfg.resolve(g.obs), cfg.resolve(g.nav)))
    for w in said:
        text = str(w.message)
        text = text if text.startswith(files) else f"single-point: {text}"
        if text not in notes:
            notes.append(text)
    health_notes = []
    solved = np.isfinite(sol.r_e).all(axis=1)
    if not solved.any():
        raise InputError(f"{g.obs}: no epoch could be solved by single-point positioning (needed for the "
                         "atmosphere corrections and the start-up); check the navigation file covers the "
                         "observations and the systems")
    table = range_table(obs, nav, rx_e=np.where(solved[:, None], sol.r_e, np.nan), mask_deg=g.mask_deg,
                        iono=g.iono, tropo=g.tropo, systems=systems)
    # a receiver clock reset (1 ms: 299.8 km on every range) is no oscillator noise: the clock state ran on by
    # its drift, rejected every later range and the covariance lost positiveness ("the filter diverged")
    jump_ep, jump_m = receiver_clock_jumps(sol)
    if len(jump_ep):
        sol, table = remove_clock_jumps(sol, table, jump_ep, jump_m)
        health_notes.append(clock_jump_note(sol, jump_ep, jump_m, g.obs) + ": taken out of the pseudoranges, the "
                            "clock state runs on continuously")
    notes += health_notes
    week = int(np.floor(obs.time[0] / WEEK_S))
    if log:
        log(f"RINEX: {len(obs.time)} epochs, {len(table.time)} usable ranges; single-point solved "
            f"{int(solved.sum())} epochs")
        for n_ in notes:
            log(f"RINEX: {n_}")
    return RawGnss(obs, nav, sol, table, week, week * WEEK_S, notes=tuple(notes), warnings=tuple(health_notes),
                   clock_jumps=tuple((int(e), float(j)) for e, j in zip(jump_ep, jump_m)))


def spp_fixes(raw: RawGnss) -> GnssData:
    """Our single-point solution as GNSS fixes (:meth:`SppSolution.to_gnss_data`:
    solved epochs, flagged ones left out) on the seconds of week of the RINEX
    file's first epoch, the IMU's time base."""
    from ..gnss.spp import EXCLUDED, SOLVED

    s = raw.spp
    try:
        g = s.to_gnss_data()
    except InputError:  # Doppler on some epochs only: positions alone
        g = s.to_gnss_data(with_velocity=False)
    t = s.time[np.isin(s.status, (SOLVED, EXCLUDED))] - raw.offset_s
    return GnssData(t, g.lla, g.sigma_ned, g.v_n, g.sigma_v_ned)


@contextmanager
def _format_hint(section, path, fmt):
    """A reader's refusal of ``path`` read as format ``fmt``, with the format
    its header shows when that is another one (``[gnss] format`` defaults to
    "inskit": an RTKLIB .pos given by --gnss was refused as 'missing
    column(s) time_s ...' with no word of the format)."""
    try:
        yield
    except InputError as exc:
        from ..io.formats import detect_gnss_format, detect_imu_format

        other = (detect_imu_format if section == "imu" else detect_gnss_format)(path)
        if other is None or other == fmt:
            raise
        setting = f"[{section}] format = \"{other}\" (or --{section}-format {other})"
        if other == "rtklib-pos":  # .pos rows without their header: what is missing, not the CSV reader's refusal
            from ..io.rtklib import headerless_pos_message

            headerless = headerless_pos_message(path, also=f"; then set {setting}")
            if headerless:
                raise InputError(headerless) from None
        raise InputError(f"{exc}; the file looks like the {other!r} format: set {setting}") from None


def load_inputs(cfg: NavigateConfig, time_offset_s=None, raw: RawGnss | None = None, notes: dict | None = None):
    """Read the IMU and GNSS files on one time base; check they overlap.

    With tight coupling the fixes (``gnss.file``, else our single-point
    solution of ``raw``) serve the start-up and the scoring only.
    ``notes`` (a dict) is filled with what the IMU reader found
    (``repeated_rows``: :func:`inskit.io.csv_formats.repeated_rows`)."""
    imu_off = cfg.imu.time_offset_s if time_offset_s is None else time_offset_s
    ipath = cfg.resolve(cfg.imu.file)
    week0 = None if raw is None else raw.week
    if cfg.gnss.file is None:
        if raw is None:
            raise InputError("no GNSS fixes: give gnss.file, or gnss.obs and gnss.nav")
        gpath = cfg.resolve(cfg.gnss.obs)
        gnss = spp_fixes(raw)
    elif cfg.gnss.format == "rtklib-pos":
        gpath = cfg.resolve(cfg.gnss.file)
        with _format_hint("gnss", gpath, cfg.gnss.format):
            gnss, week_pos = read_pos(gpath, quality=cfg.gnss.quality, time_offset_s=cfg.gnss.time_offset_s,
                                      info=notes)
        if week0 is not None and week_pos != week0:
            raise InputError(f"{gpath.name} starts in GPS week {week_pos} but {cfg.gnss.obs} in week {week0}")
        week0 = week_pos
    else:
        gpath = cfg.resolve(cfg.gnss.file)
        with _format_hint("gnss", gpath, cfg.gnss.format):
            g = io.read_gnss(gpath, format="inskit")
        gnss = GnssData(g.time + cfg.gnss.time_offset_s, g.lla, g.sigma_ned, g.v_n, g.sigma_v_ned)
    if cfg.gnss.height_offset_m:
        lla = gnss.lla.copy()
        lla[:, 2] += cfg.gnss.height_offset_m
        gnss = GnssData(gnss.time, lla, gnss.sigma_ned, gnss.v_n, gnss.sigma_v_ned)
    if cfg.imu.format == "rtklibexplorer":
        with _format_hint("imu", ipath, cfg.imu.format):
            imu, _ = read_rtklibexplorer_imu(ipath, week0=week0, time_offset_s=imu_off,
                                             mount_rpy=np.radians(cfg.imu.mount_rpy_deg),
                                             check_units=cfg.imu.check_units, repeated=cfg.imu.repeated_rows,
                                             time_smoothing=cfg.imu.time_smoothing_samples, info=notes)
    else:
        with _format_hint("imu", ipath, cfg.imu.format):
            raw_imu = io.read_imu(ipath, format="inskit", check_units=cfg.imu.check_units,
                                  first_row=cfg.imu.first_row, repeated=cfg.imu.repeated_rows,
                                  time_smoothing=cfg.imu.time_smoothing_samples, info=notes)
        from ..io.rtklib import rotate_to_body

        # the arrays are the reader's own: changed in place, not copied (an 8 h, 200 Hz log is 0.32 GB)
        t_imu, dth, dv = raw_imu.time, raw_imu.dtheta_b, raw_imu.dv_b
        del raw_imu
        if imu_off:
            t_imu += imu_off
        rotate_to_body(np.radians(cfg.imu.mount_rpy_deg), dth, dv)
        imu = ImuData(t_imu, dth, dv)
    if notes is not None:  # the offset in the times of the reader's notes (the rtklibexplorer reader applies it; the
        # inskit reader's times are the file's, the offset added above): what a message takes off for the file's time
        notes["reader_time_offset_s"] = float(imu_off) if cfg.imu.format == "rtklibexplorer" else 0.0
        if cfg.imu.check_units:
            from ..integration.gaps import imu_spikes

            notes["spikes"] = [dict(sp, t_s=sp["t_s"] - float(imu_off)) for sp in imu_spikes(imu)]  # file's times
    if gnss.time[-1] < imu.time[0] or gnss.time[0] > imu.time[-1]:
        raise InputError(
            f"GNSS ({gpath.name}: {gnss.time[0]:.3f}..{gnss.time[-1]:.3f} s) and IMU ({ipath.name}: "
            f"{imu.time[0]:.3f}..{imu.time[-1]:.3f} s) do not overlap: mismatched time bases?"
            + (" With RINEX the IMU time must be GPS seconds of week." if raw is not None else "")
            + time_unit_hint(gnss.time, imu.time)
        )
    span_g, span_i = float(gnss.time[-1] - gnss.time[0]), float(imu.time[-1] - imu.time[0])
    if (len(imu) > 1 and float(np.median(np.diff(imu.time[:1001]))) >= 1.0 and span_g > 0.0
            and span_i >= IMU_SLOW_SPAN_RATIO * span_g):  # a 1 kHz log in ms passes the reader's step check
        raise InputError(
            f"{ipath.name}: the IMU steps by {float(np.median(np.diff(imu.time[:1001]))):.4g} s (median) and spans "
            f"{span_i:.6g} s, {span_i / span_g:.4g} times the fixes' {span_g:.6g} s ({gpath.name}): is its time "
            "column in milliseconds (a 1 kHz log steps by 1 ms)? times must be seconds")
    start = max(gnss.time[0], cfg.imu.start_s if cfg.imu.start_s is not None else -np.inf)
    k0 = int(np.searchsorted(imu.time, start))
    if len(imu) - k0 < 10:
        by = ("[imu] start_s" if cfg.imu.start_s is not None and cfg.imu.start_s >= gnss.time[0]
              else f"the first GNSS fix of {gpath.name}")
        raise InputError(f"{ipath.name}: fewer than 10 IMU samples after the start time {start:.3f} s ({by}); the "
                         f"log's {len(imu)} samples span {imu.time[0]:.3f}..{imu.time[-1]:.3f} s (after "
                         "[imu] time_offset_s): the run needs at least 10 from its start on")
    return imu.slice(k0), gnss


#: GNSS fixes and an IMU log of one run whose spans differ more than this many times have a time column in
#: another unit (milliseconds: a thousand times)
TIME_SPAN_RATIO_UNIT = 200.0
#: an IMU log stepping by 1 s or more (the reader's step check lets 1 Hz through, for Allan logs) that spans this
#: many times the fixes' span is a fast log in milliseconds
IMU_SLOW_SPAN_RATIO = 20.0


def time_unit_hint(t_gnss, t_imu) -> str:
    """``"; ..."`` for a message about GNSS fixes and an IMU log that do not
    fit in time, when their spans differ by more than
    :data:`TIME_SPAN_RATIO_UNIT` times: one time column in milliseconds
    (the IMU reader refuses an IMU log in ms, not fixes: a fix every
    1000 "s" is a plausible log of sparse fixes); ``""`` otherwise."""
    span_g, span_i = float(t_gnss[-1] - t_gnss[0]), float(t_imu[-1] - t_imu[0])
    if min(span_g, span_i) <= 0.0:
        return ""
    ratio = span_g / span_i
    if max(ratio, 1.0 / ratio) < TIME_SPAN_RATIO_UNIT:
        return ""
    which = "the fixes'" if ratio > 1.0 else "the IMU log's"
    return (f"; the fixes span {span_g:.6g} s, {ratio:.4g} times the IMU log's {span_i:.6g} s: is {which} time column "
            "in milliseconds (times must be seconds)?")


#: odometer speed / GNSS track speed outside this band (median while moving) is a unit or scale mistake
ODOMETER_SPEED_RATIO = (0.8, 1.25)
#: an odometer (or speed over ground) log that says the vehicle stands still at more than this fraction of the
#: moments the GNSS track moves is refused (:func:`check_odometer_speed`): the ratio test, over the moments both
#: say it moves, never saw a log of zeros
ODOMETER_STILL_FRACTION = 0.5
#: ... and one negative (reversing) at more than this fraction of the moments it moves: a sign backwards
ODOMETER_REVERSE_FRACTION = 0.5


def check_speed_course(path, t, speed, course, gnss: GnssData, min_speed_m_s=2.0):
    """Refuse a speed-and-course log whose speed is not the GNSS track's
    (as :func:`check_odometer_speed`: km/h under an m/s header went ahead to
    1746 m of outage error, blamed on the attitude) or whose course is not
    the track's: the angle between them while moving above
    :data:`SPEED_COURSE_MAX_DEG` a quarter of the time (radians under the
    ``course_deg`` header went ahead to 13.7 km; they agree while the track
    heads north).  Silent
    when the track gives fewer than 10 moments while moving."""
    if len(gnss.time) < 3:
        return
    track = gnss_speed(gnss)
    check_odometer_speed(path, t, speed, gnss, min_speed_m_s, what="speed over ground of the speed and course log",
                         track=track)
    sp, crs = track[:2]
    inside = (t >= gnss.time[0]) & (t <= gnss.time[-1])
    if inside.sum() < 10:
        return
    k = np.clip(np.searchsorted(gnss.time, t[inside]), 0, len(gnss.time) - 1)  # the fix at or after each time
    moving = (sp[k] > min_speed_m_s) & (np.abs(np.asarray(speed, float)[inside]) > 0.5 * min_speed_m_s)
    if moving.sum() < 10:
        return
    c = np.asarray(course, float)[inside][moving]
    d = np.degrees(np.abs(np.angle(np.exp(1j * (c - crs[k][moving])))))
    med = float(np.percentile(d, 75))  # a quarter of the time off: radians agree while the car heads north
    if med > SPEED_COURSE_MAX_DEG:
        # radians read as degrees: no course beyond 2 pi "deg"
        hint = " (radians under the course_deg header?)" if np.abs(c).max() < np.radians(7.0) else ""
        raise InputError(f"{path}: the course is {med:.3g} deg or more from the GNSS track's course a quarter of "
                         f"the time ({int(moving.sum())} moments while moving){hint}; expected within "
                         f"{SPEED_COURSE_MAX_DEG:g} deg: the course column must be degrees clockwise from north")


#: a speed-and-course log whose course is further than this [deg] from the GNSS track's (75th percentile while
#: moving; a good log: 0.5 deg)
SPEED_COURSE_MAX_DEG = 20.0


def check_odometer_speed(path, t, v, gnss: GnssData, min_speed_m_s=2.0, what="odometer speed", track=None):
    """Refuse an odometer log whose speed is not the GNSS track's: the
    median ratio of odometer speed to the speed of the fixes
    (:func:`inskit.alignment.coarse.gnss_speed`, interpolated to the
    odometer times) while both say the
    vehicle moves faster than ``min_speed_m_s``, outside
    :data:`ODOMETER_SPEED_RATIO` (3.6: km/h under an m/s header; 2.24: mph;
    the filter then rejected the GNSS and blamed it).  A scale error of a
    few per cent is the scale-factor state's to estimate, not refused.
    Silent when the track gives fewer than 10 such moments.  A log that
    reads half ``min_speed_m_s`` or less at more than
    :data:`ODOMETER_STILL_FRACTION` of the moments the track moves (a log of
    zeros: a dead sensor, another column; km/s) is refused too: the ratio,
    taken where both say the vehicle moves, never saw it; so is one
    negative at more than :data:`ODOMETER_REVERSE_FRACTION` of the moments
    it moves (its sign backwards: the ratio takes magnitudes, and the filter
    lost the fixes again and again).  ``track``: the fixes'
    :func:`gnss_speed` when the caller has it already."""
    if len(gnss.time) < 3:
        return
    sp = (gnss_speed(gnss) if track is None else track)[0]
    inside = (t >= gnss.time[0]) & (t <= gnss.time[-1])
    if inside.sum() < 10:
        return
    g = np.interp(t[inside], gnss.time, sp)
    o = np.abs(np.asarray(v, float)[inside])
    lo, hi = ODOMETER_SPEED_RATIO
    track_moving = g > min_speed_m_s
    still = track_moving & (o <= 0.5 * min_speed_m_s)
    if track_moving.sum() >= 10 and still.sum() > ODOMETER_STILL_FRACTION * track_moving.sum():
        raise InputError(
            f"{path}: the {what} reads {0.5 * min_speed_m_s:g} m/s or less at {int(still.sum())} of the "
            f"{int(track_moving.sum())} moments the GNSS track moves faster than {min_speed_m_s:g} m/s (median "
            f"{float(np.median(g[track_moving])):.3g} m/s against the log's {float(np.median(o[track_moving])):.3g} "
            f"m/s); expected the track's speed (ratio {lo:g}..{hi:g}): a dead sensor, another column, or another unit "
            "(km/s?); the speed column must be m/s"
        )
    moving = track_moving & (o > 0.5 * min_speed_m_s)
    if moving.sum() < 10:
        return
    back = moving & (np.asarray(v, float)[inside] < 0.0)
    if back.sum() > ODOMETER_REVERSE_FRACTION * moving.sum():  # a vehicle drives forward most of its time
        raise InputError(f"{path}: the {what} is negative (reversing) at {int(back.sum())} of the "
                         f"{int(moving.sum())} moments the vehicle moves: its sign is backwards? expected the "
                         "speed along the forward axis, positive driving forward (negate the column)")
    r = float(np.median(o[moving] / g[moving]))
    if not lo <= r <= hi:
        hint = (" (km/h read as m/s?)" if abs(r - 3.6) < 0.4 else " (mph read as m/s?)" if abs(r - 2.237) < 0.25
                else " (m/s read as km/h?)" if abs(r - 1 / 3.6) < 0.05 else "")
        raise InputError(f"{path}: the {what} is {r:.3g} times the GNSS track's speed (median over "
                         f"{int(moving.sum())} moments while moving){hint}; expected {lo:g}..{hi:g} (a scale error "
                         "within it is estimated): the speed column must be m/s")


#: the lags [s] :func:`odometer_lag` tries: this far either side, in steps of ODOMETER_LAG_STEP_S
ODOMETER_LAG_SPAN_S = 1.0
ODOMETER_LAG_STEP_S = 0.01
#: the odometer speed at a trial time is its mean over this window [s] (or two of its sampling intervals, if
#: longer): read between two samples (interpolated) it is less noisy than at one, and the lags that put the fix
#: times between samples fitted better by that alone (10 Hz wheel speeds on 1 Hz fixes: 0.05 s "late")
ODOMETER_LAG_WINDOW_S = 0.5
#: a fix whose trial times reach into a gap of the log longer than this many median sampling intervals is left
#: out (the speed interpolated across a dropout is a straight line: during a manoeuvre its misfit follows the
#: acceleration and passes for a lag)
ODOMETER_LAG_GAP_FACTOR = 5.0
#: the summary warns of a lag at least this long [s] ...
ODOMETER_LAG_WARN_S = 0.05
#: ... when a lag is this significant: the drop of the residual sum of squares at the tagged times when the
#: track's acceleration times a lag joins the scale, over the residual variance (an F statistic of one
#: parameter; 25 is five sigma, margin for the track speed's neighbouring fixes sharing their noise)
ODOMETER_LAG_WARN_F = 25.0


def odometer_lag(t, v, gnss: GnssData, min_speed_m_s=2.0, track=None) -> dict | None:
    """How late the odometer's speeds are against the GNSS track's.

    For each trial lag ``tau`` within :data:`ODOMETER_LAG_SPAN_S`, the
    odometer's mean speed over :data:`ODOMETER_LAG_WINDOW_S` about
    ``t_fix + tau`` against the fixes' track speed
    (:func:`inskit.alignment.coarse.gnss_speed`) at the fix times while it
    says the vehicle moves faster than ``min_speed_m_s``, a scale fitted by
    least squares (the scale-factor state's share); the lag whose residual
    RMS is least (a fix whose trial times reach into a gap of the log,
    :data:`ODOMETER_LAG_GAP_FACTOR`, left out).  A positive lag: a reading
    describes the speed ``tau`` before its time tag (``[odometer]
    time_offset_s = -tau`` puts it right).  Acceleration makes a lag
    visible: at a steady speed every lag fits alike, and the least RMS falls
    on whichever lag the noise favours.
    How much the data tell is ``f_statistic``: at the tagged times, the drop
    of the residual sum of squares when the track's acceleration times a
    lag joins the scale (``o = k g - k tau dg/dt``, the lag to first
    order), over the residual variance (one parameter: above 25 it is five
    sigma; the acceleration is the track's, whose noise is not the
    odometer's, so a steady speed gives chance values); ``gain`` is the RMS
    as tagged over the RMS at the lag, ``at_search_limit`` whether the lag
    found is a limit of the search (the lag may then be longer).

    Returns ``{"lag_s", "rms_at_lag_m_s", "rms_as_given_m_s", "gain",
    "f_statistic", "fixes", "at_search_limit"}`` (``gain`` and
    ``f_statistic`` None where a residual is 0), or None with fewer than 10
    such fixes (or 3 fixes)."""
    if len(gnss.time) < 3 or len(t) < 2:
        return None
    sp = (gnss_speed(gnss) if track is None else track)[0]
    t, v = np.asarray(t, float), np.abs(np.asarray(v, float))
    taus = np.arange(-ODOMETER_LAG_SPAN_S, ODOMETER_LAG_SPAN_S + 1e-9, ODOMETER_LAG_STEP_S)
    tf = gnss.time
    half = 0.5 * max(ODOMETER_LAG_WINDOW_S, 2.0 * float(np.median(np.diff(t))))
    reach = ODOMETER_LAG_SPAN_S + half
    ok = (tf - reach >= t[0]) & (tf + reach <= t[-1]) & (sp > min_speed_m_s)
    step = np.diff(t)
    gaps = np.r_[0, np.cumsum(step > ODOMETER_LAG_GAP_FACTOR * float(np.median(step)))]  # gaps before each sample
    lo = np.clip(np.searchsorted(t, tf - reach, side="right") - 1, 0, len(t) - 1)
    hi = np.clip(np.searchsorted(t, tf + reach, side="left"), 0, len(t) - 1)
    ok &= gaps[hi] == gaps[lo]  # no gap between the samples that hold the trial times
    if ok.sum() < 10:
        return None
    g = sp[ok]
    dist = np.r_[0.0, np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))]  # the distance travelled [m]
    rms = np.empty(len(taus))
    for j, tau in enumerate(taus):  # one lag at a time: memory of one row of fixes, whatever the log's length
        tt = tf[ok] + tau
        o = (np.interp(tt + half, t, dist) - np.interp(tt - half, t, dist)) / (2.0 * half)
        rms[j] = np.sqrt(np.mean((o - (o @ g / (g @ g)) * g) ** 2))  # the scale fitted at each lag
    i = int(np.argmin(rms))
    i0 = int(np.argmin(np.abs(taus)))
    n = int(ok.sum())
    # the significance: the speeds as tagged (at the samples' own noise) against the scale alone and against
    # the scale and the lag to first order, the track's acceleration the lag's regressor
    o0 = np.interp(tf[ok], t, v)
    x = np.column_stack([g, np.gradient(sp, tf)[ok]])
    rss0 = float(np.sum((o0 - (o0 @ g / (g @ g)) * g) ** 2))
    r1 = o0 - x @ np.linalg.lstsq(x, o0, rcond=None)[0]
    var = float(r1 @ r1) / max(n - 2, 1)
    f = max(0.0, (rss0 - float(r1 @ r1)) / var) if var > 0 else None
    return {"lag_s": float(taus[i]), "rms_at_lag_m_s": float(rms[i]), "rms_as_given_m_s": float(rms[i0]),
            "gain": float(rms[i0] / rms[i]) if rms[i] > 0 else None, "f_statistic": f, "fixes": n,
            "at_search_limit": i in (0, len(taus) - 1)}


def odometer_lag_warning(lag: dict | None, path, offset_s) -> str | None:
    """The summary's warning when :func:`odometer_lag` finds the log at least
    :data:`ODOMETER_LAG_WARN_S` late or early, the better fit there
    significant (``f_statistic`` above :data:`ODOMETER_LAG_WARN_F`); a lag at
    the search's limit is said to be at least that long."""
    if (not lag or abs(lag["lag_s"]) < ODOMETER_LAG_WARN_S or lag["f_statistic"] is None
            or lag["f_statistic"] < ODOMETER_LAG_WARN_F):
        return None
    late = "late" if lag["lag_s"] > 0 else "early"
    offset = f"[odometer] time_offset_s = {offset_s - lag['lag_s']:.2f}"
    if lag.get("at_search_limit"):  # the lag may be longer: no offset found that puts it right
        where = (f"at the limit of the +-{ODOMETER_LAG_SPAN_S:g} s searched, {abs(lag['lag_s']):.2f} s {late} "
                 "or more")
        fix = (f"{offset} or {'less' if lag['lag_s'] > 0 else 'more'}, the lag perhaps longer than the search: "
               "check the log's time base")
    else:
        where, fix = f"{abs(lag['lag_s']):.2f} s {late}", f"{offset} puts them right"
    return (f"odometer: {Path(path).name}: its speeds fit the GNSS track best {where} "
            f"(residual RMS {lag['rms_at_lag_m_s']:.3f} m/s there against {lag['rms_as_given_m_s']:.3f} m/s as "
            f"tagged, over {lag['fixes']} fixes while moving): the filter takes each reading at its time tag; "
            f"{fix} (the odometer's lag against the track's: a receiver velocity that lags shifts it too)")


#: an aiding log (odometer, speed and course) whose median step is above this [s] while it spans more than
#: TIME_SPAN_RATIO_UNIT times the IMU log has a time column in milliseconds (a day-long 10 Hz log beside a short
#: IMU log steps by 0.1 s)
AIDING_STEP_MAX_S = 10.0


def refuse_no_overlap(path, what, t, imu: ImuData, offset_key):
    """Refuse an aiding log (``what``: "odometer", "speed and course")
    whose time tags ``t`` [s, after its offset] all lie outside the IMU's
    span: none of its readings could be used, and a run without them would
    pass for one with them; and one whose time column is in milliseconds
    (:data:`AIDING_STEP_MAX_S`; it overlapped, and the run warned only that
    it 'made no update').  ``offset_key`` names the config key that shifts
    its time tags."""
    if t[-1] < imu.time[0] or t[0] > imu.time[-1]:
        raise InputError(f"{Path(path).name}: {what} times {t[0]:.3f}..{t[-1]:.3f} s do not overlap the IMU's "
                         f"{imu.time[0]:.3f}..{imu.time[-1]:.3f} s: mismatched time bases? ({offset_key})")
    span, span_i = float(t[-1] - t[0]), float(imu.time[-1] - imu.time[0])
    step = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    if span_i > 0.0 and span > TIME_SPAN_RATIO_UNIT * span_i and step > AIDING_STEP_MAX_S:
        raise InputError(f"{Path(path).name}: {what} times step by {step:.4g} s (median) and span {span:.6g} s, "
                         f"{span / span_i:.4g} times the IMU log's {span_i:.6g} s: is its time column in "
                         "milliseconds (a 10 Hz log steps by 100 ms)? times must be seconds")


def odometer_measurement(cfg: NavigateConfig, imu: ImuData, gnss: GnssData | None = None):
    """The odometer plug-in over the ``[odometer]`` log, thinned to
    ``rate_hz``; refuses a log that does not overlap the IMU's, or whose
    speed is not the GNSS track's (:func:`check_odometer_speed`, with
    ``gnss`` the fixes used)."""
    from ..integration import Odometer

    o = cfg.odometer
    path = cfg.resolve(o.file)
    t, v = io.read_speed(path)
    t = t + o.time_offset_s
    refuse_no_overlap(path, "odometer", t, imu, "odometer.time_offset_s")
    if o.rate_hz is not None and len(t) > 1:
        keep = np.r_[True, np.diff(np.floor(t * o.rate_hz)) > 0]
        t, v = t[keep], v[keep]
    lag = None
    if gnss is not None:
        track = gnss_speed(gnss) if len(gnss.time) >= 3 else None
        check_odometer_speed(path.name, t, v, gnss, track=track)
        lag = odometer_lag(t, v, gnss, track=track)
    m = Odometer(t, v, o.sigma_m_s, lever_arm_b=o.lever_arm_b_m, with_nhc=o.with_nhc,
                 nhc_sigma_m_s=o.nhc_sigma_m_s)
    m.lag_check = lag  # the summary's odometer_lag (:func:`odometer_lag`)
    return m


#: the gyros' turning over the GNSS track's (median over its turns) outside which a gyro column is in another unit
#: (rad/s under a deg/s header reads 57.3 times too little; deg/s under rad/s, 57.3 times too much)
GYRO_TURN_RATIO = (0.1, 10.0)
#: turns the check of :func:`check_gyro_turns` needs before it judges
GYRO_TURN_MIN_MOMENTS = 10


def check_gyro_turns(path, imu: ImuData, gnss: GnssData, min_speed_m_s=3.0, window_s=3.0, min_turn_deg=15.0):
    """Refuse an IMU log whose gyros turn far less, or far more, than the
    GNSS track (:data:`GYRO_TURN_RATIO`): a gyro column in another unit
    that the magnitudes alone cannot tell (rad/s under the rtklibexplorer
    log's deg/s header: a drive ended unhealthy, 436 m of outage error, the
    unit never named; found by the review of navigate's inputs).

    Over windows of about ``window_s`` of fixes (one after the other) where
    the track moves above ``min_speed_m_s`` throughout and its course turns
    by more than ``min_turn_deg`` and five times the course's noise
    (:func:`inskit.alignment.coarse.gnss_speed`), the angle the gyros
    turned (the norm of the summed angle increments, whatever the mounting)
    is set against the course's change; the median of the ratios over at
    least :data:`GYRO_TURN_MIN_MOMENTS` such turns is judged.  Silent with
    fewer (a walk, a ship, a log at rest).  drive_0708 reads 1.0, the
    simulated car 1.0."""
    t = gnss.time
    if len(t) < 2 * GYRO_TURN_MIN_MOMENTS:
        return
    k = max(1, int(round(window_s / float(np.median(np.diff(t))))))
    i = np.arange(0, len(t) - k, k)
    j = i + k
    speed, course, sig_v = gnss_speed(gnss)
    low = np.minimum.reduceat(speed, np.column_stack([i, j]).ravel())[::2]  # the slowest fix of each window
    low = np.minimum(low, speed[j])
    dc = np.abs(np.angle(np.exp(1j * (course[j] - course[i]))))
    with np.errstate(divide="ignore", invalid="ignore"):
        noise = 5.0 * np.sqrt(2.0) * sig_v / np.maximum(low, 1e-9)
    turning = ((low > min_speed_m_s) & (dc > min_turn_deg * DEG) & (dc > noise) & (t[j] - t[i] <= 2.0 * window_s)
               & (t[i] >= imu.time[0]) & (t[j] < imu.time[-1]))
    a = np.searchsorted(imu.time, t[i][turning], side="right")  # the increments over (t_i, t_j]
    b = np.searchsorted(imu.time, t[j][turning], side="right")
    keep = b > a + 1
    if keep.sum() < GYRO_TURN_MIN_MOMENTS:
        return
    a, b, dc = a[keep], b[keep], dc[turning][keep]
    # rows a..b-1 of each turn (b < the last row: the turns end before the log does); reduceat's sums between
    # the turns (odd places) are dropped
    sums = np.add.reduceat(imu.dtheta_b, np.column_stack([a, b]).ravel())[::2]
    ratio = float(np.median(np.linalg.norm(sums, axis=1) / dc))
    if GYRO_TURN_RATIO[0] <= ratio <= GYRO_TURN_RATIO[1]:
        return
    guess = ("rad/s under a deg/s header reads 57.3 times too little" if ratio < 1.0
             else "deg/s under a rad/s header reads 57.3 times too much")
    raise InputError(f"{path}: while the GNSS track turns ({len(a)} turns of over {min_turn_deg:g} deg in "
                     f"{window_s:g} s at over {min_speed_m_s:g} m/s), the gyros turn a median {ratio:.3g} times as "
                     f"much as its course: a gyro column in another unit ({guess}); check the units of its header, "
                     "or set [imu] check_units = false to run it as it is")


def speed_course_measurement(cfg: NavigateConfig, windows, lever, imu: ImuData, gnss: GnssData | None = None):
    """GNSS speed and course over ground as horizontal-velocity updates,
    withheld inside the outage windows like the fixes; refuses a log that
    does not overlap the IMU's (:func:`refuse_no_overlap`), and one whose
    speed or course is not the fixes' track's (:func:`check_speed_course`)."""
    from ..integration import GnssSpeedCourse

    path = cfg.resolve(cfg.gnss.speed_course)
    t, s, c, ss, sc = io.read_speed_course(path)
    t = t + cfg.gnss.time_offset_s
    refuse_no_overlap(path, "speed and course", t, imu, "gnss.time_offset_s")
    if gnss is not None:
        check_speed_course(path, t, s, c, gnss)
    return GnssSpeedCourse(t, s, c, ss, sc, lever_arm_b=lever, use=~withheld_mask(t, windows),
                           min_speed_m_s=cfg.gnss.speed_course_min_speed_m_s)


def tight_measurements(cfg: NavigateConfig, raw: RawGnss, windows, lever):
    """Pseudorange (and Doppler) plug-ins over the range table; inside outage
    windows only the ``keep_satellites`` highest satellites stay."""
    from ..integration.tight import Pseudorange, PseudorangeRate

    tb = raw.table
    t = np.asarray(tb.time, float) - raw.offset_s
    use = np.ones(len(t), bool)
    keep = cfg.outages.keep_satellites
    for a, b in windows:
        inside = (t >= a) & (t <= b)
        use[inside] = False
        if keep:
            ep = np.asarray(tb.epoch)[inside]
            rows = np.nonzero(inside)[0]
            el = np.asarray(tb.elevation_rad)[inside]
            for e in np.unique(ep):
                m = ep == e
                best = rows[m][np.argsort(-el[m])[:keep]]
                use[best] = True
    g = cfg.gnss
    meas = [Pseudorange(tb, time_offset_s=raw.offset_s, use=use, lever_arm_b=lever,
                        sigma_scale=g.pseudorange_sigma_scale)]
    if g.use_doppler and np.isfinite(np.asarray(tb.range_rate_m_s, float)).any():
        meas.append(PseudorangeRate(tb, time_offset_s=raw.offset_s, use=use, lever_arm_b=lever,
                                    sigma_scale=g.doppler_sigma_scale))
    return meas, use


def clock_blocks(cfg: NavigateConfig, raw: RawGnss, initial: NavState, lever, use):
    """The receiver clock block, started from the first usable epoch's ranges
    at the initial position (works with a single satellite), and one
    system-offset block per further system."""
    from .. import earth
    from ..integration.blocks import ReceiverClock, SystemTimeOffset
    from ..integration.tight import clock_from_ranges

    tb = raw.table
    t = np.asarray(tb.time, float) - raw.offset_s
    ok = use & (t >= initial.time - 1.0)
    if not ok.any():
        raise InputError(f"{cfg.gnss.obs}: no pseudorange after the start of the run")
    e0 = int(np.asarray(tb.epoch)[np.argmax(ok)])
    C_nb = initial.C_nb
    C_en = earth.dcm_en(initial.lla[0], initial.lla[1])
    r_a = earth.lla_to_ecef(initial.lla) + C_en @ (C_nb @ lever)
    v_a = C_en @ initial.v_n
    sys = np.array([str(s)[:1] for s in np.asarray(tb.sat)])
    ep = np.asarray(tb.epoch)
    systems = [s for s in cfg.gnss.systems if (sys[use] == s).any()]
    if not systems:
        raise InputError(f"{cfg.gnss.obs}: no usable range of the systems {cfg.gnss.systems}")
    ref = systems[0]
    bias, drift, n = clock_from_ranges(tb, e0, r_a, v_a, system=ref)
    source = "ranges at the initial position"
    s = raw.spp
    if ref in tuple(s.systems) and np.isfinite(s.r_e[e0]).all():  # single-point's clock, when it solved that epoch
        b_spp = float(np.asarray(s.clock_m)[e0, list(s.systems).index(ref)])
        if np.isfinite(b_spp):
            bias, source = b_spp, "single-point solution"
            d_spp = float(np.asarray(s.clock_drift_m_s)[e0])
            drift = d_spp if np.isfinite(d_spp) else drift
    sigma_drift = 2.0
    drift_from = "Doppler" if np.isfinite(drift) else None
    if not np.isfinite(drift):
        # no Doppler: the drift from the single-point clock bias's slope; started at 0 with 2 m/s sigma, a
        # common TCXO's 1e-7 s/s (30 m/s) ran the bias away and every pseudorange was rejected
        from ..gnss.spp import clock_drift_from_bias

        d, pairs = clock_drift_from_bias(s, e0, system=ref)
        if np.isfinite(d):
            drift, sigma_drift, drift_from = d, 5.0, f"single-point clock bias slope ({pairs} epoch pairs)"
        else:
            drift, sigma_drift, drift_from = 0.0, 300.0, "unknown (no Doppler, no clock slope): 0 +- 300 m/s"
    if not np.isfinite(bias):
        bias, drift, source = 0.0, 0.0, "none (no range at the start)"
        sigma_drift, drift_from = 300.0, "unknown: 0 +- 300 m/s"
    # the estimate starts at the initial time, which may lie before or after that epoch: carry it by the drift
    t_e0 = float(t[np.argmax(ok)])
    bias += drift * (initial.time - t_e0)
    blocks = [ReceiverClock(sigma0=(30.0 + 3.0 * float(max(cfg.init.sigma_pos_m, 1.0)), sigma_drift),
                            h0=cfg.gnss.clock_h0, h_2=cfg.gnss.clock_h_2, estimate0=(bias, drift))]
    for s in systems[1:]:
        e_s = ep[use & (sys == s)]
        b_s = np.nan
        if len(e_s):
            b_s, _, _ = clock_from_ranges(tb, int(e_s[0]), r_a, v_a, system=s)
        blocks.append(SystemTimeOffset(s, sigma0=100.0, estimate0=0.0 if not np.isfinite(b_s) else b_s - bias))
    return blocks, {"bias_m": bias, "drift_m_s": drift, "from": source, "drift_from": drift_from,
                    "sigma_drift_m_s": sigma_drift, "satellites": n, "epoch_index": e0, "systems": systems}


def outage_windows(cfg: NavigateConfig, gnss: GnssData):
    """The outage windows of ``cfg`` in absolute time [s] (time zero: the
    first fix of ``gnss``).

    Raises
    ------
    InputError
        A window starting at or before the first fix (time zero): the
        start-up takes its initial position from that fix.
        Two windows that both withhold fixes with no used fix between them
        (touching windows, or a gap shorter than the fixes' interval): the
        first has no end, its scores would be the second's over again and
        the fix they share would be counted twice.
    """
    t0 = gnss.time[0]
    if cfg.outages.protocol == "rtklibexplorer":
        return rtklibexplorer_outages(t0)
    if cfg.outages.protocol != "windows":
        return []
    for a, b in cfg.outages.windows_s:
        if a <= 0.0:  # withholding the first fix: the INS would start from a later fix with its state at 0 unknown
            raise InputError(
                f"outages: window [{a:g}, {b:g}] s after the first GNSS fix withholds the first fix, which the start-up "
                "takes the initial position from (the run would start from the first fix after the window, at "
                f"{b:g} s or later, and score the motion before it as outage error): start the window after the "
                "first fix")
    windows = [(t0 + a, t0 + b) for a, b in cfg.outages.windows_s]
    t = gnss.time
    used = ~withheld_mask(t, windows)
    w = sorted(windows)
    for (a0, b0), (a1, b1) in zip(w, w[1:]):
        if (withheld_mask(t, [(a0, b0)]).any() and withheld_mask(t, [(a1, b1)]).any()
                and not (used & (t > b0) & (t < a1)).any()):
            step = float(np.median(np.diff(t))) if len(t) > 1 else float("nan")
            raise InputError(
                f"outages: windows [{a0 - t0:g}, {b0 - t0:g}] and [{a1 - t0:g}, {b1 - t0:g}] s after the first GNSS "
                f"epoch leave no used fix between them (the fixes come every {step:.3g} s): they are one outage, "
                f"and the first would have no end of its own; merge them into [{a0 - t0:g}, {b1 - t0:g}] or leave "
                "a fix between them")
    return windows


def _noise_used(layout, measured):
    """The white noise the filter ran with, datasheet units: one value per
    sensor, or (``*_axes``, the body axes) when it was set per axis."""
    att, vel = layout.block("att"), layout.block("vel")
    if att.body_psd is not None:
        return {"gyro_arw_axes_deg_sqrt_h": [float(v) for v in np.sqrt(att.body_psd) / DEG * 60.0],
                "accel_vrw_axes_m_s_sqrt_h": [float(v) for v in np.sqrt(vel.body_psd) * 60.0],
                "measured_on_static_start": measured}
    return {"gyro_arw_deg_sqrt_h": float(np.sqrt(att.psd[0])) / DEG * 60.0,
            "accel_vrw_m_s_sqrt_h": float(np.sqrt(vel.psd[0])) * 60.0, "measured_on_static_start": measured}


def static_noise_density(imu: ImuData, t_end, per_axis=False):
    """White-noise densities [rad/s/sqrt(Hz), m/s^2/sqrt(Hz)] measured on the
    static start (sample std times sqrt(dt), quadratic mean over the axes);
    ``per_axis``: also each body axis's, ``(arw, vrw, arw_axes (3,),
    vrw_axes (3,))``."""
    head = imu.slice(0, max(int(np.searchsorted(imu.time, t_end, side="right")), 2))  # not the whole log's rates
    w, f = head.rates()
    m = (head.time > head.time[0]) & (head.time <= t_end)
    dt = float(np.median(np.diff(head.time[m])))
    arw = float(np.sqrt(np.mean(w[m].var(axis=0))) * np.sqrt(dt))
    vrw = float(np.sqrt(np.mean(f[m].var(axis=0))) * np.sqrt(dt))
    if per_axis:
        return arw, vrw, np.sqrt(w[m].var(axis=0) * dt), np.sqrt(f[m].var(axis=0) * dt)
    return arw, vrw


def sensor_noise(n, measured=None) -> SensorNoise:
    """The filter's sensor noise (SI) from a ``[noise]`` section (datasheet
    units), the white noise raised to what the static start measured
    (:func:`.noise.sensor_noise`)."""
    from .noise import sensor_noise as noise_si

    return noise_si(n, measured)


def build_settings(cfg: NavigateConfig, startup: Startup | None, measured=None, extra_blocks=()) -> FilterSettings:
    from .noise import turn_on_sigmas

    noise = sensor_noise(cfg.noise, measured)
    i = cfg.init
    unc = InitialUncertainty((i.sigma_pos_m,) * 3, i.sigma_vel_m_s, i.sigma_roll_pitch_deg * DEG,
                             i.sigma_yaw_deg * DEG, *turn_on_sigmas(cfg),
                             i.sigma_scale_factor, i.sigma_lever_arm_m, i.sigma_time_offset_s)
    f = cfg.filter
    return FilterSettings.standard(
        noise, unc, scale_factors=f.scale_factors, lever_arm=f.lever_arm, time_offset=f.time_offset,
        lever_arm_b=tuple(cfg.gnss.lever_arm_b_m),
        gyro_bias0=tuple(startup.gyro_bias) if startup else (0.0, 0.0, 0.0),
        accel_bias0=tuple(startup.accel_bias) if startup else (0.0, 0.0, 0.0),
        scheme="closed" if f.scheme == "uncoupled" else f.scheme, gate_probability=f.gate_probability,
        gate_max_consecutive=f.gate_max_consecutive, smoother_node_s=f.smoother_node_s,
        covariance_step_s=f.covariance_step_s,
        extra_blocks=tuple(extra_blocks), gravity=cfg.earth.gravity,
    )


def solution_column_names(cfg: NavigateConfig) -> list:
    """The columns the solution files of a run of ``cfg`` can hold, known
    from the configuration alone (before any data is read): the navigation
    columns, the sigmas of position, velocity and attitude (with a filter:
    the uncoupled scheme has none), and the estimates of every state the
    configuration asks for (the blocks
    :func:`navigate` builds; tight coupling: the inter-system bias of each
    system of ``gnss.systems`` after the first, which the data may lack).
    ``[output] columns`` is checked against them when the config is loaded
    (:func:`inskit.io.parquet.column_spec_error`)."""
    from ..integration import GnssPositionError, HeightBias, Mounting, OdometerScale, ins_blocks
    from ..integration.blocks import ReceiverClock, SystemTimeOffset
    from ..integration.engine import NAV_SIGMA_BLOCKS
    from ..io.parquet import NAVIGATION_COLUMNS

    f, tight = cfg.filter, cfg.gnss.coupling == "tight"
    blocks = ins_blocks(scale_factors=f.scale_factors, lever_arm=f.lever_arm, time_offset=f.time_offset)
    if cfg.odometer is not None and cfg.odometer.estimate_scale:
        blocks.append(OdometerScale())
    if cfg.constraints.mounting:
        blocks.append(Mounting())
    if cfg.gnss.error_sigma_m is not None and not tight:
        blocks.append(GnssPositionError(cfg.gnss.error_sigma_m, cfg.gnss.error_tau_s))
    if cfg.height is not None and cfg.height.estimate_bias:
        blocks.append(HeightBias())
    if tight:
        blocks += [ReceiverClock()] + [SystemTimeOffset(sys_) for sys_ in cfg.gnss.systems[1:]]
    names = list(NAVIGATION_COLUMNS)
    if f.scheme != "uncoupled":  # no covariance: no sigma column (:attr:`Track.solution`)
        names += [nm for b in blocks if b.name in NAV_SIGMA_BLOCKS for nm in b.sigma_names()]
    names += [nm for b in blocks if b.has_estimate for nm in b.estimate_names()]
    return names


def _uncoupled_track(imu, initial, gnss, used, lever, settings):
    """The uncoupled scheme as a Track (no estimates, no sigmas)."""
    sol = run_uncoupled(imu, initial, gnss, use=used, lever_arm_b=lever, use_velocity=False,
                        gravity=settings.gravity)
    n = len(sol)
    lay = settings.layout
    aux = np.tile(lay.initial_aux(), (n, 1))
    return FilterOutput(sol, aux, np.full((n, lay.size), np.nan), lay,
                        {"gnss_pos": {"used": int(used.sum()), "rejected": 0, "skipped": 0}},
                        {"gnss_pos": {"t": np.empty(0), "nu": np.empty((0, 3)), "sigma": np.empty((0, 3)),
                                      "nis": np.empty(0), "accepted": np.empty(0, bool)}}, settings, None)


def nhc_broken(res: NavigateResult) -> str | None:
    """Why the non-holonomic constraint does not hold in this run (refused
    in more than :data:`NHC_BROKEN_FRACTION` of its updates), or None."""
    c = res.forward.counts.get("nhc")
    if not c:
        return None
    n = c["used"] + c["rejected"]
    if n and c["rejected"] > NHC_BROKEN_FRACTION * n:
        return f"{c['rejected']} of {n} of its updates refused ({c['rejected'] / n:.0%})"
    return None


def lost_fixes_hint(message, gnss: GnssData, g) -> str:
    """What a divergence's message (``message``, with the engine's
    :func:`inskit.integration.engine.lost_note`) adds when the GNSS position
    fixes were refused before it: the sigma the fixes claim, as the filter
    takes them (``g``: the ``[gnss]`` section), and the keys that put a
    claim right.  Fixes of 0.58 m noise whose file claimed 1e-6 m ended in
    'covariance lost positiveness ... check sensor noise settings', naming
    neither the fixes nor their sigmas.  ``""`` when the fixes were not
    lost."""
    lost = message.partition("before it the filter was lost:")[2]
    if "gnss_pos " not in lost:
        return ""
    return fixes_claim_hint(gnss, g)


#: a run whose GNSS position updates are refused more than this fraction of the time has the fixes' claimed
#: sigma said beside the refusals (:func:`fixes_claim_hint`)
FIXES_LOST_FRACTION = 0.5


def fixes_claim_hint(gnss: GnssData, g) -> str:
    """``"; the fixes claim ..."``: the median sigma the fixes claim, as the
    filter takes them (``g``: the ``[gnss]`` section), and the keys that
    put a claim right; said beside a divergence after the fixes were lost
    (:func:`lost_fixes_hint`) and beside a run that refused most of them."""
    sig = fix_sigmas(gnss.sigma_ned, g.sigma_floor_m, g.sigma_scale_ned)
    h = float(np.median(np.hypot(sig[:, 0], sig[:, 1]) / np.sqrt(2.0)))
    v = float(np.median(sig[:, 2]))
    return (f"; the fixes claim a median sigma of {h:.3g} m horizontally and {v:.3g} m vertically (as the filter "
            f"takes them, [gnss] sigma_floor_m = {g.sigma_floor_m:g}): fixes noisier than they claim are refused "
            "until the filter is lost; if they are, floor them ([gnss] sigma_floor_m) or scale them "
            "(sigma_scale_ned)")


def run(cfg: NavigateConfig, *, log=None, stream_dir=None, **kw) -> NavigateResult:
    """:func:`navigate`, and again without the non-holonomic constraint when
    it was on by default (not set by the user) and does not hold.

    The constraint (no lateral or vertical body velocity) is a land
    vehicle's; a vessel's heave, an aircraft's angle of attack or a
    handheld device breaks it, and the filter then takes the body's
    vertical velocity for a pitch error whose gravity leak drives the fixes
    out of the gate (an 8 h ship was lost from its sixth second and stopped
    hours later 'within 0.1 deg of a pole').  A run whose constraint was
    refused in most of its updates (:func:`nhc_broken`), or that failed
    naming it, is made again with ``[constraints] nhc = false``; the
    result's ``constraint_check`` (the summary's) says so.  A constraint the
    user set is kept as set: the health verdict names it when it fails.
    """
    from ..filters.kalman import FilterDivergence

    default = cfg.constraints.nhc and "nhc" not in cfg.constraints.model_fields_set
    try:
        res = navigate(cfg, log=log, stream_dir=stream_dir, **kw)
    except (FilterDivergence, InputError) as exc:
        if not (default and "non-holonomic constraint" in str(exc)):
            raise
        why = f"the run failed ({str(exc).split(';')[0]}) with the constraint refused before it"
    else:
        why = nhc_broken(res) if default else None
        if why is None:
            return res
        abort_streams(res)
    if log:
        log(f"warning: the non-holonomic constraint (on by default: a land vehicle's) does not hold for this "
            f"vehicle ({why}); navigating again without it ([constraints] nhc = false; set nhc = true to keep it)")
    off = cfg.model_copy(update={"constraints": cfg.constraints.model_copy(update={"nhc": False})})
    res = navigate(off, log=log, stream_dir=stream_dir, **kw)
    res.constraint_check = {"nhc": "dropped", "why": why}
    return res


def navigate(cfg: NavigateConfig, *, smooth=False, progress=None, time_offset_s=None, log=None,
             inputs=None, truth: NavSolution | None = None, stream_dir=None) -> NavigateResult:
    """Run the whole job described by ``cfg``.

    ``inputs`` is ``(imu, gnss)`` already read (by :func:`load_inputs`, with
    the time offset applied): calibration loops pass it to read the files
    once.  ``stream_dir``: the result folder, when the forward solution may
    be streamed into it (:func:`streams_run`); the result's ``forward`` then
    holds the kept rows only (:func:`stream_keep_rows`, the summary says how
    many) and :func:`write_outputs` commits the files.
    """
    from ..integration.gaps import bridge_gaps, find_gaps, find_rate_changes, gap_process_noise, refuse_long_gaps

    t_start = time.perf_counter()
    tight = cfg.gnss.coupling == "tight"
    raw = None
    imu_notes = {}
    if inputs is None:
        from .warm import warm_compiled_code

        check_input_files(cfg)  # every input there, each named by its key, before any is read
        warm_compiled_code()  # numba's own start-up, beside the reading (which pyarrow does without the GIL)
        raw = load_raw_gnss(cfg, log) if (tight or cfg.gnss.file is None) else None
        imu, gnss = load_inputs(cfg, time_offset_s, raw, notes=imu_notes)
        n_rep = imu_notes.get("repeated_rows", 0)
        if n_rep and log:
            log(f"IMU: {n_rep} rows ({imu_notes['repeated_rows_fraction']:.1%}) repeat the previous row in all six "
                "channels (a sample read twice): " + ("dropped ([imu] repeated_rows = \"drop\")"
                                                      if imu_notes["repeated_rows_dropped"] else "kept as samples"))
        if imu_notes.get("time_tags_moved_rms_s") is not None and log:
            log(f"IMU: time tags smoothed over {imu_notes['time_smoothing_samples']} rows ([imu] "
                f"time_smoothing_samples): moved {imu_notes['time_tags_moved_rms_s'] * 1e3:.2f} ms RMS, "
                f"{imu_notes['time_tags_moved_max_s'] * 1e3:.2f} ms at most; net of the rows left out "
                f"{imu_notes['time_tags_moved_net_rms_s'] * 1e3:.2f} ms RMS for a jitter of "
                f"{imu_notes['time_tag_jitter_s'] * 1e3:.2f} ms RMS")
            for c in imu_notes.get("time_tag_rate_changes", ()):
                log(f"IMU: the time tags smoothed apart on either side of the rate change from "
                    f"{c['rate_before_hz']:.4g} Hz to {c['rate_after_hz']:.4g} Hz at t = "
                    f"{c['t_s'] - imu_notes.get('reader_time_offset_s', 0.0):.3f} s (the file's time)")
    else:
        imu, gnss = inputs[:2]
        raw = inputs[2] if len(inputs) > 2 else None
        if tight and raw is None:
            raise InputError("tight coupling needs the RINEX inputs (inputs=(imu, gnss, raw))")
    if tight and (cfg.gnss.use_velocity or cfg.gnss.sigma_floor_m):
        raise InputError("gnss.use_velocity and gnss.sigma_floor_m describe fixes fused by loose coupling; with "
                         "tight coupling the fixes are only the reference (use use_doppler and the sigma scales)")
    gaps = find_gaps(imu, cfg.imu.gap_factor)
    refuse_long_gaps(gaps, str(cfg.resolve(cfg.imu.file)) if cfg.imu.file else "the IMU log",
                     time_offset_s=cfg.imu.time_offset_s)
    rate_changes = find_rate_changes(imu)
    off = cfg.imu.time_offset_s  # the messages give the file's own times (the rows here are cut and thinned)
    for c in rate_changes:
        if log:
            log(f"warning: the IMU rate changes from {c.rate_before_hz:.4g} Hz to {c.rate_after_hz:.4g} Hz near "
                f"t = {c.t_s - off:.3f} s (the file's time): gaps are judged against the local rate")
    for g in gaps:
        if log:
            log(f"warning: the IMU log has a gap of {g.length_s:.3f} s at t = {g.start_s - off:.3f} s (the file's "
                "time): bridged on the last rates, covariance inflated")
    imu, gaps = bridge_gaps(imu, gaps)
    if truth is None and cfg.truth is not None:  # a truth given in Python takes the place of [truth] file
        truth = io.read_solution(cfg.resolve(cfg.truth.file))
    windows = outage_windows(cfg, gnss)
    used = ~withheld_mask(gnss.time, windows)
    if used.sum() < 2:
        src = cfg.resolve(cfg.gnss.file if cfg.gnss.file is not None else cfg.gnss.obs)
        raise InputError(f"{src}: {len(gnss)} GNSS fix(es), {int(used.sum())} of them outside the outages"
                         "; the filter needs at least two")
    gnss_used = gnss.select(used)
    if cfg.imu.check_units:  # a gyro column in another unit, told by the track's turns
        check_gyro_turns(cfg.resolve(cfg.imu.file).name if cfg.imu.file else "the IMU data", imu, gnss_used)
    lever = np.asarray(cfg.gnss.lever_arm_b_m, float)
    startup = None
    measured = {}
    scfg, bank_on = cfg, False  # scfg: the config with the sigmas the start-up found (build_settings reads them)
    if cfg.init.mode != "given":
        from ..alignment.inmotion import STARTUP_SIGMAS, auto_startup, bank_needed
        from .noise import turn_on_sigmas

        i = cfg.init
        span = (gnss_used.time >= imu.time[0] - 1.0) & (gnss_used.time <= imu.time[-1])
        if span.sum() < 2:
            raise InputError(f"{cfg.resolve(cfg.imu.file) if cfg.imu.file else 'the IMU log'}: the IMU log "
                             f"({imu.time[0]:.3f}..{imu.time[-1]:.3f} s) overlaps {int(span.sum())} used GNSS "
                             "fix(es); the start-up needs the fixes while the IMU runs (mismatched time bases, "
                             f"or logs of different runs?){time_unit_hint(gnss_used.time, imu.time)}")
        g_start = gnss_used if span.all() else gnss_used.select(span)
        # the start-up's position is a fix's, as uncertain as the filter takes that fix (loose coupling's keys)
        fix_sigma = ({} if tight else {"sigma_floor_m": cfg.gnss.sigma_floor_m,
                                       "sigma_scale_ned": tuple(cfg.gnss.sigma_scale_ned)})

        def start(imu):
            try:  # the start-up sees only the fixes while the IMU runs (a short IMU log claimed a static start it lacked)
                return auto_startup(imu, g_start, lever, mode=i.mode,
                                    min_static_s=i.min_static_s, heading_speed_m_s=i.heading_speed_m_s,
                                    course_average_s=i.course_average_s, level_window_s=i.level_window_s,
                                    yaw_guess=None if i.yaw_deg is None else i.yaw_deg * DEG,
                                    gyro_bias_sigma=turn_on_sigmas(cfg)[0], accel_bias_sigma=turn_on_sigmas(cfg)[1],
                                    floors={k: getattr(i, k) for k in STARTUP_SIGMAS}, **fix_sigma)
            except InputError as e:
                if span.all():
                    raise
                raise InputError(f"{e} (the start-up looks only at the {int(span.sum())} fixes inside the IMU log's "
                                 f"span {imu.time[0]:.3f}..{imu.time[-1]:.3f} s; {int((~span).sum())} fixes lie "
                                 "outside it)") from None

        startup = start(imu)
        if i.yaw_deg is None and not bank_needed(startup, dict(startup.sigma or {}).get(
                "sigma_yaw_deg", i.sigma_yaw_deg) * DEG, i.yaw_hypotheses):
            # the heading comes from the track: is the IMU's x axis the direction of travel, its z axis down?
            imu, startup, cfg = _check_vehicle_axes(cfg, imu, g_start, startup, start, log)
            scfg = cfg
        initial = startup.state
        sig = dict(startup.sigma or {})
        bank_on = (cfg.filter.scheme != "uncoupled"
                   and bank_needed(startup, sig.get("sigma_yaw_deg", i.sigma_yaw_deg) * DEG, i.yaw_hypotheses))
        if bank_on:  # after the bank the yaw is within half the spacing
            sig["sigma_yaw_deg"] = 180.0 / i.yaw_hypotheses
        if sig:
            scfg = cfg.model_copy(update={"init": i.model_copy(update=sig)})
        if cfg.noise.from_static and startup.mode == "static-then-track":
            arw, vrw, arw_axes, vrw_axes = static_noise_density(imu, startup.static_end, per_axis=True)
            measured = {"gyro_arw_rad_sqrt_s": arw, "accel_vrw_m_s_sqrt_s": vrw,
                        "gyro_arw_axes_rad_sqrt_s": arw_axes, "accel_vrw_axes_m_s_sqrt_s": vrw_axes}
    else:
        i = cfg.init
        initial = NavState.from_euler(imu.time[0], [i.lat_deg * DEG, i.lon_deg * DEG, i.height_m], i.v_ned_m_s,
                                      np.radians(i.rpy_deg))
    clock_start = None
    extra_blocks, odo, aiding = [], None, []
    if cfg.odometer is not None:
        odo = odometer_measurement(cfg, imu, gnss_used)
        aiding.append(("odometer", cfg.resolve(cfg.odometer.file), odo))
        if cfg.odometer.estimate_scale:
            from ..integration import OdometerScale

            extra_blocks.append(OdometerScale(cfg.odometer.scale_sigma0, cfg.odometer.scale_rw))
    if cfg.constraints.mounting:
        from ..integration import Mounting

        extra_blocks.append(Mounting(cfg.constraints.sigma_mounting_deg * DEG,
                                     cfg.constraints.mounting_rw_deg_sqrt_h * DEG / 60.0))
    if cfg.gnss.error_sigma_m is not None and not tight:
        from ..integration import GnssPositionError

        extra_blocks.append(GnssPositionError(cfg.gnss.error_sigma_m * np.asarray(cfg.gnss.sigma_scale_ned),
                                              cfg.gnss.error_tau_s))
    height = None
    if cfg.height is not None:  # a barometer or a height profile, with its offset state
        from .height import height_aiding

        height, height_blocks = height_aiding(cfg, imu, gnss)
        extra_blocks += height_blocks
        if cfg.height.file is not None:  # a constant height_m has no log to speak of
            aiding.append(("height", cfg.resolve(cfg.height.file), height))
    if tight:
        meas_gnss, use_rows = tight_measurements(cfg, raw, windows, lever)
        clk_blocks, clock_start = clock_blocks(cfg, raw, initial, lever, use_rows)
        settings = build_settings(scfg, startup, measured, list(clk_blocks) + extra_blocks)
    else:
        settings = build_settings(scfg, startup, measured, extra_blocks)
    if cfg.filter.scheme == "uncoupled":
        if smooth:
            raise InputError("the RTS smoother needs a filter: the uncoupled scheme has none")
        out = _uncoupled_track(imu, initial, gnss, used, lever, settings)
        sm = streams = pending = truth_parts = None
    else:
        if tight:
            meas = list(meas_gnss)
        else:
            meas = [GnssPosition(gnss, used, cfg.gnss.sigma_floor_m, lever_arm_b=lever,
                                 sigma_scale_ned=cfg.gnss.sigma_scale_ned)]
        if cfg.gnss.use_velocity and not tight:
            if not gnss.has_velocity:
                raise InputError(f"{cfg.gnss.file}: use_velocity is set but the file has no velocity")
            meas.append(GnssVelocity(gnss, used, cfg.gnss.velocity_delay_s, cfg.gnss.velocity_sigma_scale,
                                     lever_arm_b=lever))
        c = cfg.constraints
        if c.zupt:  # rest found from the track against the noise of the fixes as the filter takes them (with a
            # file claiming 2 cm for 0.5 m of noise, floored at 0.5 m, no rest was ever found: no ZUPT at all)
            still = gnss_used if tight else dataclasses.replace(gnss_used, sigma_ned=fix_sigmas(
                gnss_used.sigma_ned, cfg.gnss.sigma_floor_m, cfg.gnss.sigma_scale_ned))
            meas.append(ZeroVelocity(static_intervals(still), c.rate_hz, c.zupt_sigma_m_s))
        if c.nhc:
            meas.append(NonHolonomic([(imu.time[0], imu.time[-1])], c.rate_hz, c.nhc_sigma_m_s,
                                    lever_arm_b=c.nhc_lever_arm_b_m))
        if odo is not None:
            meas.append(odo)
        if cfg.gnss.speed_course is not None:
            meas.append(speed_course_measurement(cfg, windows, lever, imu, gnss))
            aiding.append(("speed and course", cfg.resolve(cfg.gnss.speed_course), meas[-1]))
        if height is not None:
            meas.append(height)
        extra = {g.row: gap_process_noise(settings.layout, g.length_s, np.radians(cfg.imu.gap_rate_sigma_deg_s),
                                          cfg.imu.gap_accel_sigma_m_s2) for g in gaps}
        if bank_on:  # the start-up's yaw is too uncertain for the small-angle model: a bank of hypotheses
            from ..alignment.inmotion import after_bank, yaw_bank

            bank = yaw_bank(imu, startup.at_yaw, float(initial.euler[2]), meas, settings,
                            n=cfg.init.yaw_hypotheses, span_s=cfg.init.bank_s,
                            score_measurements=("pseudorange",) if tight else ("gnss_pos",),
                            keep_first_on_tie=i.yaw_deg is None)  # the track's course, not the user's guess
            startup = after_bank(startup, bank)
            initial = startup.state
            if log:
                log(bank_line(bank))
        streams = pending = truth_parts = None
        from ..filters.kalman import FilterDivergence

        try:
            if stream_dir is not None and streams_run(cfg):
                out, sm, streams, pending, truth_parts = _run_streamed(cfg, imu, gnss, windows, initial, meas,
                                                                       settings, extra, smooth, progress, stream_dir,
                                                                       log, truth)
            else:
                out = run_filter(imu, initial, meas, settings, smoother=smooth, progress=progress, extra_noise=extra)
                sm = rts_smooth(out) if smooth else None
        except FilterDivergence as exc:
            hint = "" if tight else lost_fixes_hint(str(exc), gnss, cfg.gnss)
            if not hint:
                raise
            raise FilterDivergence(f"{exc}{hint}") from None
        if log:
            for r in out.recoveries:
                if r.get("fixes_position"):
                    log(f"warning: {recovery_text(r)}")
    fused = not tight  # tight coupling fuses the raw ranges: the fixes file is only a reference
    score_f = score_outages(out.solution, gnss, windows, lever, truth=truth, fused=fused)
    score_s = score_outages(sm.solution, gnss, windows, lever, truth=truth, fused=fused) if sm is not None else None
    return NavigateResult(cfg, imu, gnss, windows, used, startup, settings, out, sm, score_f, score_s,
                          time.perf_counter() - t_start, measured, gaps, raw, clock_start, rate_changes, truth,
                          streams, pending, truth_parts, imu_notes, aiding)


def _check_vehicle_axes(cfg: NavigateConfig, imu: ImuData, gnss: GnssData, startup: Startup, start, log):
    """The start-up's check of the vehicle's axes in the IMU's
    (:mod:`inskit.alignment.vehicle_axes`): with ``[init] vehicle_axes =
    "find"`` a mismatch rotates the readings into the vehicle's axes, folds
    the rotation into the config's ``imu.mount_rpy_deg`` (so that what the
    summary suggests composes with it) and runs the start-up again
    (``start(imu)``).  Returns ``(imu, startup, cfg)``, the start-up
    carrying the check's record in ``axes``."""
    from ..alignment.vehicle_axes import axes_rotation, rotate_imu, vehicle_axes

    e = startup.state.euler
    found = vehicle_axes(imu, gnss, e[0], e[1], gyro_bias=startup.gyro_bias,
                         heading_speed_m_s=cfg.init.heading_speed_m_s)
    rec = {**found.summary(), "differ": bool(found.vehicle_axes_differ), "rotated": False}
    if found.vehicle_axes_differ:
        D = axes_rotation(found)
        m0 = list(cfg.imu.mount_rpy_deg)
        C = rot.dcm_from_euler(np.radians(m0)) @ rot.dcm_from_euler(D)
        m1 = np.degrees(rot.euler_from_dcm(C))
        m1 += 360.0 * np.round((np.asarray(m0, float) - m1) / 360.0)
        rec["rotation_rpy_deg"] = [float(v) for v in np.degrees(D)]
        rec["mount_rpy_deg_suggested"] = [round(float(v), 2) for v in m1]
        if cfg.init.vehicle_axes == "find":
            imu = rotate_imu(imu, D)
            cfg = cfg.model_copy(update={"imu": cfg.imu.model_copy(update={"mount_rpy_deg": tuple(
                float(v) for v in m1)})})
            startup = start(imu)
            rec["rotated"] = True
            rec["mount_rpy_deg_configured"] = [float(v) for v in m0]
        if log:
            log("start-up: " + vehicle_axes_message(rec))
    return imu, dataclasses.replace(startup, axes=rec), cfg


def vehicle_axes_message(rec) -> str:
    """What the vehicle-axes check found and did, in words (the log and the health verdict)."""
    from ..alignment.vehicle_axes import SNAP_SE

    what = []
    if rec["upside_down"]:
        what.append(f"the IMU's z axis points up (levelled roll {rec['roll_deg']:.1f} deg)")
    if rec["off_axis"]:
        what.append(f"the direction of travel lies {rec['travel_yaw_deg']:+.1f} deg (+-{rec['travel_yaw_se_deg']:.1f}) "
                    f"off the IMU's x axis over {rec['moving_epochs']} moving fixes"
                    + (f", taken as {rec['rotation_yaw_deg']:+.0f} deg (a right angle within "
                       f"{SNAP_SE:g} standard errors)" if rec["rotation_yaw_deg"] != rec["travel_yaw_deg"] else ""))
    m = rec["mount_rpy_deg_suggested"]
    ms = f"[{m[0]:.2f}, {m[1]:.2f}, {m[2]:.2f}]"
    if rec["rotated"]:
        return (f"vehicle axes: {'; '.join(what)}: the readings were rotated into the vehicle's axes "
                f"([init] vehicle_axes = \"find\"), as [imu] mount_rpy_deg = {ms} does; set it to say so (the lever "
                "arms are taken in the vehicle's axes: forward, right, down)")
    return (f"vehicle axes: {'; '.join(what)}, and the start-up takes the IMU's axes for the vehicle's ([init] "
            f"vehicle_axes = \"given\"): its heading from the track is off by as much; set [imu] mount_rpy_deg = "
            f"{ms}, or [init] vehicle_axes = \"find\"")


def _run_streamed(cfg, imu, gnss, windows, initial, meas, settings, extra, smooth, progress, stream_dir, log,
                  truth):
    """The filter (and with ``smooth`` the smoother) with the solution files
    written while it runs (:func:`streams_run`): the segments go through a
    worker thread into the streams of ``stream_dir``; the smoother's node
    data and the forward rows go to a scratch folder there, removed at the
    end.  Returns ``(out, sm, streams, pending, truth_parts)``: ``pending``
    is the writer still finishing a forward-only run (:func:`finish_streams`),
    ``truth_parts`` the truth errors summed segment by segment."""
    import shutil
    import tempfile

    from ..analysis.errors import ErrorSummary, nav_error_part, truth_gaps
    from ..integration.engine import NAV_SIGMA_BLOCKS, Segment
    from ..integration.smoother import DiskStore

    Path(stream_dir).mkdir(parents=True, exist_ok=True)
    streams = open_streams(cfg, Path(stream_dir), imu.time, settings)
    lay = settings.layout
    scratch_dir = Path(tempfile.mkdtemp(prefix=".smoother-", dir=stream_dir)) if smooth else None
    store = DiskStore(scratch_dir / "store", lay.size) if smooth else None
    scratch = _ForwardScratch(scratch_dir, lay.aux_size) if smooth else None
    # the truth errors of every row, summed segment by segment (the kept rows would weigh the outages'
    # full-rate rows above the rest)
    truth_parts = None if truth is None else {"forward": ErrorSummary(), "smoothed": ErrorSummary()}
    gaps = None if truth is None else truth_gaps(truth.time)[0]  # once, not per segment

    def write(sg):
        extra_cols = lay.columns(sg.aux, sg.sigma, sigma_blocks=NAV_SIGMA_BLOCKS)
        sol = NavSolution._trusted(sg.time, sg.lla, sg.v_n, sg.q_nb, extra_cols)
        for w in streams:
            w.write(sol, sg.start)
        if scratch is not None:
            scratch(sg)
        if truth_parts is not None:
            truth_parts["forward"].add(nav_error_part(sol, truth, gaps))
    pipe = _Pipe(write)

    def sink(sg):  # the views are the engine's buffers: copied, then converted and written on the worker
        pipe.put(Segment(sg.start, sg.time, sg.lla.copy(), sg.v_n.copy(), sg.q_nb.copy(), sg.aux, sg.sigma))
    sm = pending = None
    try:
        try:
            out = run_filter(imu, initial, meas, settings, progress=progress, extra_noise=extra, sink=sink,
                             keep_rows=stream_keep_rows(imu.time, gnss, windows, cfg.output.rate_hz),
                             smoother=smooth, store_sink=store)
        except BaseException:
            pipe.close(quiet=True)
            raise
        if not smooth:  # the last segments are written while the caller shows the result (finish_streams)
            pending = pipe
        else:
            pipe.close()
            for w in streams:
                w.close()
            store.close()
            scratch.close()
            sm, s_streams = _smooth_streamed(cfg, out, store, scratch, imu, settings, stream_dir, log,
                                             truth, truth_parts)
            streams += s_streams
    except BaseException:
        for w in streams:
            w.abort()
        raise
    finally:
        if scratch_dir is not None:
            shutil.rmtree(scratch_dir, ignore_errors=True)
    return out, sm, streams, pending, truth_parts


def _offset_objective(cfg: NavigateConfig, lo: float, hi: float, log=None, max_s=None):
    """``(f, evals)``: ``f(offset)`` runs the filter with the IMU time tags
    shifted by ``offset`` [s] (absolute, as ``[imu] time_offset_s``; within
    ``[lo, hi]``) and returns the mean NIS per degree of freedom of the GNSS
    updates (position fixes, or pseudoranges when tightly coupled), every
    evaluation appended to ``evals``.  Only the fixes the filter uses enter,
    never the withheld ones; the files are read once.  ``max_s``: only the
    first ``max_s`` seconds of the IMU log (from where the run starts) are
    run (a constant offset shows in any stretch with motion)."""
    cfg = cfg.model_copy(update={"truth": None})  # the search never looks at a truth
    tight = cfg.gnss.coupling == "tight"
    raw = load_raw_gnss(cfg, log) if (tight or cfg.gnss.file is None) else None
    imu0, gnss = load_inputs(cfg, hi, raw)  # read with the largest offset: it keeps every sample any offset needs
    key = "pseudorange" if tight else "gnss_pos"
    evals = []

    def f(off):
        imu = ImuData(imu0.time + (off - hi), imu0.dtheta_b, imu0.dv_b)
        k0 = int(np.searchsorted(imu.time, max(gnss.time[0], cfg.imu.start_s if cfg.imu.start_s is not None
                                                 else -np.inf)))
        k1 = None if max_s is None else int(np.searchsorted(imu.time, imu.time[min(k0, len(imu) - 1)] + max_s))
        res = navigate(cfg, inputs=(imu.slice(k0, k1), gnss, raw))
        inn = res.forward.innovations[key]
        v = float(np.sum(inn["nis"]) / max(np.sum(inn.get("nis_dof", inn["dof"])), 1))
        evals.append((float(off), v))
        if log:
            log(f"calibrate: offset {off:+.4f} s -> mean NIS {v:.3f}")
        return v

    return f, evals


def calibrate_time_offset(cfg: NavigateConfig, bounds=(-0.5, 0.2), tol=0.005, log=None):
    """IMU time offset [s] that minimises the mean NIS of the GNSS position
    updates, by a bounded scalar search (scipy).  Only the fixes the filter
    uses enter, never the withheld ones.  The files are read once; each
    evaluation shifts the IMU time tags."""
    from scipy.optimize import minimize_scalar

    f, evals = _offset_objective(cfg, bounds[0], bounds[1], log)
    r = minimize_scalar(f, bounds=bounds, method="bounded", options={"xatol": tol})
    return float(r.x), sorted(evals)


#: :func:`calibrate_gnss_axes` stops when the vertical and horizontal normalised innovations agree this well
GNSS_AXES_TOLERANCE = 0.05
#: ... or after this many runs
GNSS_AXES_MAX_RUNS = 5
#: the summary warns when the vertical and horizontal normalised innovations differ by more than this factor
GNSS_AXES_WARN_RATIO = 1.3
#: ... over at least this many updates
GNSS_AXES_MIN_UPDATES = 30


def gnss_axes(fw) -> dict | None:
    """The fixes' normalised innovations axis by axis
    (:func:`inskit.analysis.consistency.axis_innovation_rms`: the position
    updates the filter used, less those within 5 s of a break), or None
    without position updates (tight coupling, the uncoupled scheme):
    ``normalized_innovation_rms_ned``, ``horizontal``, ``vertical``,
    ``vertical_to_horizontal``, ``updates``."""
    from ..analysis.consistency import axis_innovation_rms, horizontal_vertical

    inn = fw.innovations.get("gnss_pos")
    if not inn or not len(inn.get("t", [])) or np.asarray(inn["nu"]).ndim != 2:
        return None
    rms, n = axis_innovation_rms(inn["t"], inn["nu"], inn["sigma"], inn["accepted"])
    if n == 0:
        return None
    h, v = horizontal_vertical(rms)
    return {"normalized_innovation_rms_ned": [float(x) for x in rms], "horizontal": h, "vertical": v,
            "vertical_to_horizontal": v / h if h > 0 else None, "updates": n}


def gnss_axes_warning(ax: dict | None, scale) -> str | None:
    """The summary's warning when the fixes' vertical and horizontal
    normalised innovations (:func:`gnss_axes`) differ by more than
    :data:`GNSS_AXES_WARN_RATIO`: the sigmas have the wrong shape."""
    if not ax or ax["updates"] < GNSS_AXES_MIN_UPDATES or not ax["vertical_to_horizontal"]:
        return None
    r = ax["vertical_to_horizontal"]
    if 1.0 / GNSS_AXES_WARN_RATIO <= r <= GNSS_AXES_WARN_RATIO:
        return None
    from ..analysis.consistency import axis_scale_step

    step = np.asarray(scale, float) * axis_scale_step(ax["normalized_innovation_rms_ned"])
    worse = "vertical" if r > 1 else "horizontal"
    return (f"GNSS: the fixes' {worse} innovations are {max(r, 1 / r):.2f} times the other axes' for their sigmas "
            f"(normalised RMS horizontal {ax['horizontal']:.2f}, vertical {ax['vertical']:.2f}, over "
            f"{ax['updates']} fixes): the sigmas lack the noise's shape, and the filter reads the difference as "
            f"motion. [gnss] sigma_scale_ned = [{step[0]:.3g}, {step[1]:.3g}, {step[2]:.3g}] is one step towards "
            "it; --calibrate-gnss-axes finds it")


def calibrate_gnss_axes(cfg: NavigateConfig, log=None, tol=GNSS_AXES_TOLERANCE, max_runs=GNSS_AXES_MAX_RUNS,
                        inputs=None):
    """``(scale, runs)``: ``[gnss] sigma_scale_ned`` that makes the fixes'
    horizontal and vertical normalised innovations agree (within ``tol``,
    relative), by fixed-point steps of
    :func:`inskit.analysis.consistency.axis_scale_step` from the config's
    own scale, one forward run each, at most ``max_runs``, each step
    halved (in log scale) once the ratio has crossed 1 (an oscillating
    fixed point: a 100 s ship went 0.46, 0.85, 1.11, 1.08, 0.85).  A run
    that lost the fixes (a stretch of refusals, the health verdict's
    ``lost_stretches``) is refused: what a lost filter still accepts is no
    measure of the fixes' noise.  Only the fixes
    the filter uses enter, never the withheld ones, and at least
    :data:`GNSS_AXES_MIN_UPDATES` of them (an :class:`InputError` with
    fewer); the files are read once.  ``runs`` lists each run's scale and
    what it measured."""
    from ..analysis.consistency import SETTLE_S, axis_scale_step

    cfg = cfg.model_copy(update={"truth": None})  # the calibration never looks at a truth
    if inputs is None:  # fixes from RINEX (no gnss.file): our own single-point solution, as the run makes it
        raw = load_raw_gnss(cfg, log) if cfg.gnss.file is None else None
        inputs = (*load_inputs(cfg, raw=raw), raw)
    scale = np.asarray(cfg.gnss.sigma_scale_ned, float)
    runs = []
    damping = 1.0  # a full step, halved (in log scale) once the ratio overshoots 1: the filter's own response
    for _ in range(max_runs):
        c = cfg.model_copy(update={"gnss": cfg.gnss.model_copy(update={"sigma_scale_ned": tuple(scale)})})
        fw = run(c, inputs=inputs).forward  # as the run will be (a default NHC that fails, dropped)
        lost = (health(fw)["measurements"].get("gnss_pos") or {}).get("lost_stretches") or []
        if lost:  # the fixes a lost filter still takes are those near its wrong track: their innovations are no noise
            raise InputError(f"gnss.sigma_scale_search = \"calibrate\": the filter lost the fixes over {len(lost)} "
                             f"stretch(es) (from t = {lost[0]['start_s']:.2f} s: 15 s or more of them refused in a "
                             "row); the innovations of the fixes it kept do not measure their noise. Mend the run "
                             "first (its health verdict names what fails), or set [gnss] sigma_scale_ned by hand")
        ax = gnss_axes(fw)
        n = 0 if ax is None else ax["updates"]
        if n < GNSS_AXES_MIN_UPDATES:  # a few fixes' RMS is their sampling: a shape drawn from it is noise
            used = fw.counts.get("gnss_pos", {}).get("used", 0)
            raise InputError(f"gnss.sigma_scale_search = \"calibrate\": of the {used} GNSS position updates the "
                             f"filter used, {n} are more than {SETTLE_S:g} s after the first and after each break in "
                             f"them (an outage's end measures the INS's drift, not the fixes' noise), fewer than the "
                             f"{GNSS_AXES_MIN_UPDATES} the fixes' noise shape needs; set [gnss] sigma_scale_ned by "
                             "hand (or leave it out)")
        r = ax["vertical_to_horizontal"]
        if r is None:  # every horizontal innovation exactly 0: fixes copied from the INS, say
            raise InputError("gnss.sigma_scale_search = \"calibrate\": the fixes' horizontal innovations are all "
                             "zero, so there is no shape to measure; set [gnss] sigma_scale_ned by hand")
        runs.append({"sigma_scale_ned": [float(x) for x in scale], **ax})
        if log:
            log(f"calibrate: sigma_scale_ned [{', '.join(f'{x:.3f}' for x in scale)}] -> normalised innovations "
                f"horizontal {ax['horizontal']:.3f}, vertical {ax['vertical']:.3f} (ratio {r:.3f})")
        if abs(r - 1.0) <= tol:
            return scale, runs
        if len(runs) > 1 and (runs[-2]["vertical_to_horizontal"] - 1.0) * (r - 1.0) < 0:
            damping = 0.5  # overshot: the filter trusts an axis more and its innovations shrink, beyond the step
        scale = scale * axis_scale_step(ax["normalized_innovation_rms_ned"]) ** damping
    raise InputError(f"gnss.sigma_scale_search = \"calibrate\": the fixes' vertical and horizontal innovations "
                     f"still differ by {abs(runs[-1]['vertical_to_horizontal'] - 1):.0%} after {max_runs} runs "
                     f"(the last scales [{', '.join(f'{x:.3g}' for x in runs[-1]['sigma_scale_ned'])}]); set "
                     "[gnss] sigma_scale_ned by hand")


def calibrated_config(cfg: NavigateConfig, log=None):
    """``(cfg, extra)``: the config with what its searches calibrate, and the
    summary's record of each: with ``[imu] time_offset_search =
    "calibrate"`` (``--calibrate-time-offset``) the IMU time offset that
    fits the fixes best (:func:`calibrate_time_offset`;
    ``{"time_offset_calibration": {"best_s", "evaluations"}}``), then with
    ``[gnss] sigma_scale_search = "calibrate"`` (``--calibrate-gnss-axes``)
    the fixes' noise shape (:func:`calibrate_gnss_axes`;
    ``{"gnss_axes_calibration": {"sigma_scale_ned", "runs"}}``); without
    either, ``cfg`` unchanged and an empty dict."""
    extra = {}
    if cfg.imu.time_offset_search == "calibrate":
        best, evals = calibrate_time_offset(cfg, log=log)
        if log:
            log(f"calibrate: best IMU time offset {best:+.4f} s")
        cfg = cfg.model_copy(update={"imu": cfg.imu.model_copy(update={"time_offset_s": best})})
        extra["time_offset_calibration"] = {"best_s": best, "evaluations": [list(e) for e in evals]}
    if cfg.gnss.sigma_scale_search == "calibrate":
        scale, runs = calibrate_gnss_axes(cfg, log=log)
        scale = tuple(float(x) for x in scale)
        if log:
            log(f"calibrate: [gnss] sigma_scale_ned = [{', '.join(f'{x:.3f}' for x in scale)}]")
        cfg = cfg.model_copy(update={"gnss": cfg.gnss.model_copy(update={"sigma_scale_ned": scale})})
        extra["gnss_axes_calibration"] = {"sigma_scale_ned": list(scale), "runs": runs}
    return cfg, extra


#: the IMU time offsets the check of an unhealthy run searches: this far [s] either side of the given one
TIME_OFFSET_CHECK_SPAN_S = 0.5
#: ... on a grid of this step [s] first (the mean NIS need not have one minimum over the span), then refined
TIME_OFFSET_CHECK_GRID_S = 0.1
#: an offset is named when it moves this far [s] from the given one at least
TIME_OFFSET_CHECK_MIN_S = 0.01
#: GPS time minus UTC [s] since 2017-01-01 (IERS Bulletin C): an IMU log stamped in UTC beside fixes in GPS time
#: is late or early by this much, which the check tries when nothing near the given offset fits
GPS_UTC_S = 18.0
#: the check runs the filter over this much of the log [s] at most (an hour's log: 17 runs of 10 minutes, not of
#: the hour)
TIME_OFFSET_CHECK_MAX_S = 600.0


def gnss_updates_unhealthy(h: dict, cfg: NavigateConfig) -> str | None:
    """The name of the GNSS measurement whose updates made the verdict
    unhealthy (mean NIS above :data:`HEALTH_MAX_MEAN_NIS_PER_DOF` per degree
    of freedom, or more than :data:`HEALTH_MAX_REJECTED_FRACTION` rejected),
    else None."""
    key = "pseudorange" if cfg.gnss.coupling == "tight" else "gnss_pos"
    m = (h.get("measurements") or {}).get(key)
    if not m or not m.get("updates") or not m.get("dof"):
        return None
    frac = m.get("rejected_row_fraction", m["rejected_fraction"])
    nis = m["mean_nis"] / m["dof"] if m["mean_nis"] is not None else 0.0
    return key if (frac > HEALTH_MAX_REJECTED_FRACTION or nis > HEALTH_MAX_MEAN_NIS_PER_DOF) else None


def search_time_offset(cfg: NavigateConfig, span=TIME_OFFSET_CHECK_SPAN_S, step=TIME_OFFSET_CHECK_GRID_S,
                       tol=0.005, log=None, max_s=TIME_OFFSET_CHECK_MAX_S):
    """``(best, evals)``: the IMU time offset [s] within ``span`` of the
    configured one whose run fits the GNSS updates best (least mean NIS per
    degree of freedom, :func:`_offset_objective`): a grid of ``step`` over
    the span (robust to a mean NIS with several dips), then a bounded scalar
    search (scipy) within a step of the grid's best, over the first
    ``max_s`` seconds of the log.  The fixes the filter uses only, never the
    withheld ones."""
    from scipy.optimize import minimize_scalar

    c = float(cfg.imu.time_offset_s)
    lo, hi = c - span, c + span
    f, evals = _offset_objective(cfg, lo, hi, log, max_s)
    n = int(round(2 * span / step))
    grid = [lo + i * (hi - lo) / n for i in range(n + 1)]
    vals = [f(x) for x in grid]
    j = int(np.argmin(vals))
    a, b = grid[max(j - 1, 0)], grid[min(j + 1, n)]
    minimize_scalar(f, bounds=(a, b), method="bounded", options={"xatol": tol})
    return min(evals, key=lambda e: e[1])[0], sorted(evals)


def check_time_offset(cfg: NavigateConfig, s: dict, log=None) -> dict | None:
    """``[imu] time_offset_search = "check"``: when the run's GNSS updates
    are unhealthy (:func:`gnss_updates_unhealthy`), look for an IMU time
    offset that fits the fixes (:func:`search_time_offset`) and say what was
    found in the summary's health verdict (a reason naming the offset to set
    when one brings the GNSS updates' mean NIS into the band, a warning that
    none does otherwise).  IMU time tags late or early by a fraction of a
    second (a logger's buffering, UTC against GPS time) make the filter
    reject fixes and lose its way while every file reads well; the verdict
    alone did not name the cause.

    A lost filter is no evidence of a time offset: when the updates are
    unhealthy only over the stretches where it was lost
    (:func:`timing_evidence`), nothing is searched; the verdict's first
    reason says so and names what the run shows of the cause
    (:func:`lost_reason`).  A lost filter's mean NIS (thousands) made any
    run of the search that happened to recover 'fit the fixes better': a
    car started 10 deg off in roll was told of an IMU time offset of
    -0.091 s.

    Returns the record put into ``s["time_offset_check"]`` (``searched``
    False, with ``not_searched_because``, when the filter was lost), or
    None when the GNSS updates are healthy or the check is off."""
    h = s["health"]
    key = gnss_updates_unhealthy(h, cfg)
    if key is None or cfg.imu.time_offset_search != "check" or cfg.filter.scheme == "uncoupled":
        return None
    m = h["measurements"][key]
    now = m["mean_nis"] / m["dof"]
    given = float(cfg.imu.time_offset_s)
    if not timing_evidence(m):  # unhealthy only where the filter was lost: its cause, not a search
        why = lost_reason(key, m, s)
        if log:
            log(f"health: the {key} updates are unhealthy only where the filter was lost: no IMU time offset "
                "searched (a lost filter is no evidence of one)")
        h["reasons"].insert(0, why)
        s["time_offset_check"] = {"measurement": key, "given_s": given, "searched": False, "found": False,
                                  "better": False, "not_searched_because": why}
        return s["time_offset_check"]
    if log:
        log(f"health: the {key} updates are unhealthy (mean NIS {now:.2f} per degree of freedom): searching an IMU "
            f"time offset within {given:+g} +- {TIME_OFFSET_CHECK_SPAN_S:g} s that fits them "
            "([imu] time_offset_search = \"off\" skips this)")
    try:
        best, evals = search_time_offset(cfg, log=log)
    except Exception as exc:  # a diagnosis of a finished run: its failure is said, the run's results stand
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        h["warnings"].append(f"{key}: the search for an IMU time offset that fits the fixes could not run: {msg}")
        s["time_offset_check"] = {"measurement": key, "given_s": given, "searched": True, "error": msg}
        return s["time_offset_check"]
    best_nis = min(v for _, v in evals)
    at_given = [v for o, v in evals if abs(o - given) < 1e-9]
    leap = None
    leap_tried = not best_nis <= HEALTH_MAX_MEAN_NIS_PER_DOF
    if leap_tried:  # nothing near: one log in UTC, the other in GPS time?
        for c in (given + GPS_UTC_S, given - GPS_UTC_S):
            if log:
                log(f"health: no offset near {given:+g} s fits; trying {c:+g} +- {TIME_OFFSET_CHECK_SPAN_S:g} s "
                    f"(GPS time - UTC = {GPS_UTC_S:g} s)")
            try:
                b2, e2 = search_time_offset(cfg.model_copy(update={"imu": cfg.imu.model_copy(
                    update={"time_offset_s": c})}), log=log)
            except Exception:  # noqa: BLE001 (logs that no longer overlap at that shift: no leap-second offset)
                continue
            evals = evals + e2
            n2 = min(v for _, v in e2)
            if n2 <= HEALTH_MAX_MEAN_NIS_PER_DOF and n2 < best_nis:
                best, best_nis, leap = b2, n2, c - given
                break
    rec = {"measurement": key, "given_s": given, "searched": True, "best_s": round(best, 4), "mean_nis_per_dof_given":
           at_given[0] if at_given else now, "mean_nis_per_dof_best": best_nis,
           "evaluations": [list(e) for e in sorted(evals)], "gps_utc_shift_s": leap}
    better = abs(best - given) >= TIME_OFFSET_CHECK_MIN_S and best_nis < 0.5 * rec["mean_nis_per_dof_given"]
    fits = better and best_nis <= HEALTH_MAX_MEAN_NIS_PER_DOF
    rec["found"] = bool(fits)
    rec["better"] = bool(better)
    if fits:  # the cause first, then the symptoms it explains
        h["reasons"].insert(0, (
            f"{key}: the fixes fit an IMU time offset of {best:+.3f} s (mean NIS {best_nis:.2f} per degree of "
            f"freedom against {rec['mean_nis_per_dof_given']:.2f} at the given {given:+g} s): the IMU's time tags "
            + (f"seem off by GPS time - UTC ({GPS_UTC_S:g} s: one log in UTC, the other in GPS time)"
               if leap is not None else "seem off")
            + f"; set [imu] time_offset_s = {best:.3f}" + ("" if leap is not None else
                                                          " (or run with --calibrate-time-offset)")))
    elif better:  # one cause among others, perhaps: said, not claimed
        h["warnings"].append(
            f"{key}: an IMU time offset of {best:+.3f} s fits the fixes better (mean NIS {best_nis:.2f} per degree "
            f"of freedom against {rec['mean_nis_per_dof_given']:.2f} at the given {given:+g} s) but not into the "
            f"band (at most {HEALTH_MAX_MEAN_NIS_PER_DOF:g}): another cause remains, alone or beside a time offset "
            "(the other reasons and warnings name what they can)")
    else:
        h["warnings"].append(
            f"{key}: no IMU time offset within {given:+g} +- {TIME_OFFSET_CHECK_SPAN_S:g} s"
            + (f" (nor {GPS_UTC_S:g} s either way, GPS time - UTC)" if leap_tried else "") + " fits the fixes better "
            f"(best {best:+.3f} s, mean NIS {best_nis:.2f} per degree of freedom): a time offset does not "
            "explain them (look first at what the other reasons and warnings name)")
    s["time_offset_check"] = rec
    return rec


#: the updates outside the lost stretches the time-offset check needs to judge them (fewer: no evidence)
TIME_OFFSET_EVIDENCE_MIN_UPDATES = 10


def timing_evidence(m: dict) -> bool:
    """Whether a GNSS measurement's health figures (``m``, an entry of
    :func:`health`'s ``measurements``) are evidence that may concern
    timing: unhealthy (:func:`gnss_updates_unhealthy`'s limits) outside
    the stretches where the filter was lost (``lost_stretches``,
    ``outside_lost``) over at least
    :data:`TIME_OFFSET_EVIDENCE_MIN_UPDATES` updates; any unhealthy
    measurement that never lost the filter.

    An IMU time offset displaces every fix by the vehicle's motion over it,
    lost or not: its fixes are refused or fit badly wherever the vehicle
    moves (0.3 s late on a short car: 26 % refused outside the one lost
    stretch).  A filter lost for another reason (a wrong tilt, a constraint
    that does not hold) refuses the fixes only while lost, and fits them
    outside."""
    out = m.get("outside_lost")
    if not m.get("lost_stretches") or out is None:
        return True
    if out["updates"] < TIME_OFFSET_EVIDENCE_MIN_UPDATES:
        return False
    frac = out["rejected_fraction"]
    nis = out["mean_nis_per_dof"] or 0.0
    return frac > HEALTH_MAX_REJECTED_FRACTION or nis > HEALTH_MAX_MEAN_NIS_PER_DOF


def lost_reason(key: str, m: dict, s: dict) -> str:
    """The verdict's reason for GNSS updates unhealthy only where the filter
    was lost (:func:`timing_evidence` False): how much was refused while
    lost, how the fixes fit outside, and what the run shows of the cause
    (the tilt the fixes' drift showed at its recoveries, a constraint
    refused in most of its updates, a loss that lasted to the end)."""
    lost = m["lost_stretches"]
    n_lost = sum(x["updates"] for x in lost)
    shown = ", ".join(f"{x['start_s']:.1f}..{x['end_s']:.1f} s" for x in lost[:3]) + (
        f" and {len(lost) - 3} more" if len(lost) > 3 else "")
    out = m["outside_lost"]
    if out["updates"] >= TIME_OFFSET_EVIDENCE_MIN_UPDATES:
        outside = (f"outside them {out['rejected_fraction']:.0%} of {out['updates']} were refused"
                   + (f" and the mean NIS was {out['mean_nis_per_dof']:.2f} per degree of freedom"
                      if out["mean_nis_per_dof"] is not None else "") + ", within the health limits")
    else:
        outside = f"{'only ' + str(out['updates']) if out['updates'] else 'none'} lay outside them"
    text = (f"{key}: the filter was lost: {n_lost} of {m['updates']} updates were refused over {len(lost)} "
            f"stretch{'es' if len(lost) > 1 else ''} of refusals in a row ({shown}); {outside}: a lost filter is "
            "no evidence of an IMU time offset, and none was searched")
    causes = []
    drifts = [r for r in s.get("recoveries") or () if r.get("measurement") == key and r.get("fixes_position")]
    if drifts:
        worst = max(drifts, key=lambda r: r["drift_accel_m_s2"])
        causes.append(f"at its recoveries the fixes drifted from the INS at up to {worst['drift_accel_m_s2']:.2g} "
                      f"m/s^2 horizontally, a tilt error of about {worst['tilt_deg']:.1f} deg: the attitude diverged "
                      "(a wrong initial roll or pitch, a wrong IMU axis or mounting, or a constraint that does not "
                      "hold)")
    nhc = (s.get("health") or {}).get("measurements", {}).get("nhc")
    if nhc and nhc.get("updates") and nhc["rejected_fraction"] > NHC_BROKEN_FRACTION:
        causes.append(f"the non-holonomic constraint was refused in {nhc['rejected_fraction']:.0%} of its updates "
                      "(it does not hold for this vehicle or its mounting: [constraints] nhc = false, or mounting "
                      "= true)")
    if not lost[-1]["recovered"]:
        causes.append(f"it was still lost at the end of the run (from t = {lost[-1]['start_s']:.1f} s)")
    return "; ".join([text] + causes)


#: the aiding logs the verdict names when the filter took them while refusing the fixes (name, what)
AIDING_SOURCES = (("odometer", "odometer log"), ("odometer_nhc", "odometer log"),
                  ("gnss_speed_course", "speed-and-course log"), ("height", "height log"))
#: ... below this fraction of its updates refused
AIDING_TRUSTED_FRACTION = 0.05


def aiding_suspects(per: dict) -> list[str]:
    """Reasons naming the aiding logs the filter took (fewer than
    :data:`AIDING_TRUSTED_FRACTION` of their updates refused) while it
    refused more than :data:`HEALTH_MAX_REJECTED_FRACTION` of the GNSS
    updates: an odometer 0.5 s late was taken in 99.98 % of its updates while
    72 % of the fixes were refused, and the verdict blamed the attitude."""
    g = next((per[k] for k in ("gnss_pos", "pseudorange") if per.get(k) and per[k].get("updates")), None)
    if g is None or g["rejected_fraction"] <= HEALTH_MAX_REJECTED_FRACTION:
        return []
    out = []
    for name, what in AIDING_SOURCES:
        a = per.get(name)
        if a and a.get("updates") and a["rejected_fraction"] < AIDING_TRUSTED_FRACTION:
            out.append(f"{name}: the {what} was taken in {1.0 - a['rejected_fraction']:.0%} of its {a['updates']} "
                       f"updates while {g['rejected_fraction']:.0%} of the GNSS updates were refused: a log the fixes "
                       "disagree with (its time offset, scale, lever arm or units) pulls the filter away from them; "
                       "run without it to tell")
    return out


#: fixes reaching further than this [s] beyond the IMU log's ends are worth a warning
OUTSIDE_IMU_WARN_S = 10.0


def gnss_coverage_warnings(fix_time, imu_time, raw_update_time=None) -> list[str]:
    """The stretches of the IMU's span without GNSS fixes that no outage
    protocol asked for (:func:`.outages.gnss_data_gaps`: the solution is
    free-inertial there) and the fixes outside the IMU's span (not used) when
    they reach more than :data:`OUTSIDE_IMU_WARN_S` beyond it, in words;
    empty when the logs cover each other.

    ``raw_update_time``: tight coupling, the times of the pseudorange
    updates the filter accepted; the fixes are then only its reference, and
    a stretch without them is free-inertial only where no such update
    falls (a blockage that keeps one satellite is aided, not coasting)."""
    from .outages import gnss_data_gaps

    t0, t1 = float(imu_time[0]), float(imu_time[-1])
    out = []
    raw = None if raw_update_time is None else np.unique(np.asarray(raw_update_time, float))
    for a, b in gnss_data_gaps(fix_time, t0, t1):
        where = ("before the first fix" if a == t0 else "after the last fix" if b == t1 else "between two fixes")
        if raw is None:
            out.append(f"GNSS: no fix over {a:.3f}..{b:.3f} s ({b - a:.1f} s, {where}; not an outage of the "
                       "protocol): the solution there is free-inertial")
            continue
        n = int(((raw > a) & (raw < b)).sum())
        out.append(f"GNSS: no reference fix over {a:.3f}..{b:.3f} s ({b - a:.1f} s, {where}): not scored there; "
                   + (f"the filter fused pseudoranges at {n} epochs in it" if n else
                      "no pseudorange update either: the solution there is free-inertial"))
    ft = np.asarray(fix_time, float)
    outside = int(((ft < t0 - 1e-6) | (ft > t1 + 1e-6)).sum())
    beyond = max(0.0, t0 - float(ft[0])) + max(0.0, float(ft[-1]) - t1) if len(ft) else 0.0
    if outside and beyond > OUTSIDE_IMU_WARN_S:  # a receiver started a few seconds before the IMU is no news
        out.append(f"GNSS: {outside} of {len(ft)} fixes lie outside the IMU log's span ({t0:.3f}..{t1:.3f} s) "
                   f"and are not used{time_unit_hint(ft, imu_time)}")
    return out


def aiding_warnings(logs, counts, imu_time, scheme="") -> list[str]:
    """A warning for each aiding log that made no update, naming the file
    and why: its readings withheld in the outage windows, outside the IMU's
    span (the filter's, from its second sample on), too slow for a course
    (speed and course), in a gap of the IMU log, or rejected by the
    innovation gate; or a scheme that fuses no aiding at all.  The log
    overlapped the IMU's span (:func:`refuse_no_overlap`), yet the run is as
    if it had none: without a word it would pass for one with it.

    Parameters
    ----------
    logs : sequence of (str, Path, measurement)
        What the log is ("odometer", "speed and course", "height"), its
        file and the measurement made of it (its ``name``, ``time`` and
        ``rows()``: the readings not withheld).
    counts : dict
        The filter's counts per measurement name (``used``, ``rejected``,
        ``skipped``).
    imu_time : (n,) array
        The IMU's times [s].
    scheme : str
        The filter scheme, for the message when it fused no aiding.
    """
    out = []
    t0, t1 = float(imu_time[1] if len(imu_time) > 1 else imu_time[0]), float(imu_time[-1])
    for what, path, m in logs or ():
        c = counts.get(m.name)
        if c is not None and c["used"] > 0:
            continue
        t = np.asarray(m.time, float)
        rows = np.asarray(m.rows(), int)
        if c is None:
            why = [f"the {scheme} scheme runs no filter, so it fuses nothing but the fixes"]
        else:
            why = []
            withheld = len(t) - len(rows)
            if withheld:
                why.append(f"{withheld} withheld inside the outage windows, like the fixes")
            tr = t[rows]
            inside = (tr >= t0) & (tr <= t1)
            if (~inside).any():
                why.append(f"{int((~inside).sum())} outside the span the filter runs over, {t0:.3f}..{t1:.3f} s")
            slow = 0
            min_speed = getattr(m, "min_speed", None)
            if min_speed is not None:  # speed and course: no course below walking pace
                slow = int((inside & (m.speed[rows] < min_speed[rows])).sum())
                if slow:
                    why.append(f"{slow} slower than {float(np.max(min_speed[rows])):g} m/s, below which a course "
                               "means nothing (gnss.speed_course_min_speed_m_s)")
            in_gaps = c["skipped"] - int((~inside).sum()) - slow
            if in_gaps > 0:
                why.append(f"{in_gaps} in gaps of the IMU log")
            if c["rejected"]:
                why.append(f"{c['rejected']} rejected by the innovation gate (the filter found them inconsistent "
                           "with the other measurements)")
        out.append(f"{path}: the {what} log made no update (of its {len(t)} readings: {'; '.join(why)}): the run "
                   "is as if it had none")
    return out


def truth_errors(res: NavigateResult, truth: NavSolution) -> dict:
    """Errors of the forward (and smoothed) solution against a truth file,
    summarised (:func:`inskit.analysis.summarize`) over every row (a
    streamed run: summed segment by segment as it ran)."""
    from .. import analysis

    if res.truth_parts is not None:
        finish_streams(res)  # the writer's last segments hold the last rows' errors
        return {label: res.truth_parts[label].result() for label, track in
                (("forward", res.forward), ("smoothed", res.smoothed)) if track is not None}
    out = {}
    for label, track in (("forward", res.forward), ("smoothed", res.smoothed)):
        if track is not None:  # the solution with its own sigmas: the errors' consistency with them too
            out[label] = analysis.summarize(analysis.nav_error(track.solution, truth))
    return out


def truth_errors_text(errs: dict) -> str:
    return "".join(f"\nagainst the truth ({label}): horizontal RMS {e['horizontal_m']['rms']:.3f} m, "
                   f"down RMS {e['down_m']['rms']:.3f} m, yaw RMS {e['yaw_deg']['rms']:.3f} deg"
                   for label, e in errs.items())


def summary(res: NavigateResult) -> dict:
    """The JSON summary: top-level keys describe the smoothed solution when
    there is one, else the forward solution; ``forward`` always holds the
    forward filter's figures."""
    fwd = dict(res.score_forward.summary)
    main = dict(res.score_smoothed.summary) if res.score_smoothed else fwd
    out = {
        "name": res.config.name,
        "scheme": res.settings.scheme,
        "gravity": res.settings.gravity,
        "solution": "smoothed" if res.smoothed is not None else "forward",
        "states": res.settings.layout.size,
        "epochs": len(res.imu),
        "duration_s": float(res.imu.time[-1] - res.imu.time[0]),
        "elapsed_s": res.elapsed_s,
        "imu_time_offset_s": res.config.imu.time_offset_s,
        "first_fix_time_s": float(res.gnss.time[0]),  # time zero of the outage windows and tables
        "config_dir": str(Path(res.config.base_dir).resolve()),  # where the config's relative paths start
        **main,
        "outage_table": res.score_smoothed.table if res.score_smoothed else res.score_forward.table,
        "forward": {**fwd, "outage_table": res.score_forward.table},
        "measurements": res.forward.counts,
        "noise_used": _noise_used(res.settings.layout, bool(res.measured_noise)),
    }
    if res.startup is not None:
        out["startup"] = res.startup.summary(res.imu.time[0])
    fw = res.forward
    rows = getattr(fw, "rows", None)
    out["streamed"] = rows is not None
    if rows is not None:
        out["rows_kept"] = int(len(rows))
        out["rows_kept_note"] = ("streamed run: the solution files and the truth errors cover every epoch; the plots "
                                 "use the kept rows (the rows around each fix, every row of an outage window, the "
                                 f"[output] rate_hz grid, at most {KEPT_GRID_ROWS} rows of it)")
    if "time_offset" in fw.layout:
        out["estimated_time_offset_s"] = float(fw.estimate("time_offset")[-1, 0])
    out["final_bias"] = {
        "gyro_deg_s": [float(v) for v in fw.estimate("bg")[-1] / DEG],
        "accel_m_s2": [float(v) for v in fw.estimate("ba")[-1]],
    }
    out["coupling"] = res.config.gnss.coupling
    if res.raw is not None:
        tb = res.raw.table
        ep = np.asarray(tb.epoch)
        n_per = np.bincount(ep, minlength=len(res.raw.obs.time)) if len(ep) else np.zeros(1, int)
        s = res.raw.spp
        out["rinex"] = {
            "rinex_epochs": int(len(res.raw.obs.time)),
            "ranges": int(len(ep)),
            "satellites_per_epoch_median": float(np.median(n_per)),
            "satellites_per_epoch_min": int(n_per.min()),
            "spp_epochs_solved": int(np.isfinite(s.r_e).all(axis=1).sum()),
            "clock_start": res.clock_start,
            "clock_jumps": [{"epoch_index": e, "step_m": j, "step_ms": j / 299792.458}
                            for e, j in res.raw.clock_jumps],
            "reference": "gnss.file" if res.config.gnss.file is not None else "single-point solution",
            "notes": list(res.raw.notes),
        }
    if res.truth is not None:
        out["truth_file"] = (str(res.config.resolve(res.config.truth.file)) if res.config.truth is not None
                             else "(given to navigate() in Python)")
        out["truth_errors"] = truth_errors(res, res.truth)
    out["recoveries"] = recoveries_summary(getattr(fw, "recoveries", []))
    out["health"] = health(fw, res.gaps or (), res.rate_changes or ())
    c = fw.counts.get("gnss_pos")
    if (res.config.gnss.coupling != "tight" and c
            and c["rejected"] > FIXES_LOST_FRACTION * (c["used"] + c["rejected"])):
        reasons = out["health"]["reasons"]  # the refusals' reason says what the fixes claim (it named no sigma)
        k = next((i for i, r in enumerate(reasons) if r.startswith("gnss_pos: ") and "updates rejected (" in r), None)
        if k is not None:
            reasons[k] += fixes_claim_hint(res.gnss, res.config.gnss)
    if res.startup is not None:  # what the start-up chosen by mode "auto" left unused, said (it was silent)
        from .config import unused_inmotion_keys

        unused = unused_inmotion_keys(res.config.init, res.startup.mode)
        if unused:
            out["health"]["warnings"].append(
                f"init: {', '.join(f'init.{k}' for k in unused)} (of the in-motion start-up) "
                f"{'was' if len(unused) == 1 else 'were'} not used: mode \"auto\" found rest at the start and "
                "levelled there (static-then-track: the yaw from the GNSS track once moving); set init.mode = "
                "\"in-motion\" to start from "
                + ("the yaw given" if "yaw_deg" in unused else "them") + ", or leave them out")
    if res.constraint_check:  # the default constraint did not hold: the run was made again without it
        out["constraint_check"] = dict(res.constraint_check)
        out["health"]["warnings"].append(
            f"the non-holonomic constraint (on by default) did not hold for this vehicle ({res.constraint_check['why']}): "
            "these results are of a run without it ([constraints] nhc = false)")
    raw_t = None
    if res.raw is not None:  # tight coupling: the fixes are the reference; the ranges aid
        inn = fw.innovations.get("pseudorange", {})
        t_pr, ok = np.asarray(inn.get("t", []), float), np.asarray(inn.get("accepted", []), bool)
        raw_t = t_pr[ok] if len(ok) == len(t_pr) else t_pr
    out["health"]["warnings"] += gnss_coverage_warnings(res.gnss.time, res.imu.time, raw_t)
    if res.raw is not None:
        out["health"]["warnings"] += list(res.raw.warnings)
    out["health"]["warnings"] += aiding_warnings(res.aiding, fw.counts, res.imu.time, res.settings.scheme)
    for what, path, m in res.aiding or ():
        if what == "odometer" and getattr(m, "lag_check", None) is not None:
            out["odometer_lag"] = {**m.lag_check, "time_offset_s": res.config.odometer.time_offset_s}
            warn = odometer_lag_warning(m.lag_check, path, res.config.odometer.time_offset_s)
            if warn:
                out["health"]["warnings"].append(warn)
    ax = gnss_axes(fw)
    if ax is not None:
        out["gnss_axes"] = {**ax, "sigma_scale_ned": [float(x) for x in res.config.gnss.sigma_scale_ned]}
        warn = gnss_axes_warning(ax, res.config.gnss.sigma_scale_ned)
        if warn:
            out["health"]["warnings"].append(warn)
    if res.truth is not None:  # what the truth could not score, said (not silently left out)
        from .. import analysis
        from .evaluate import (attitude_unit_warnings, coverage_warnings, truth_consistency_warnings,
                               vertical_pitch_warnings)

        cover = analysis.truth_coverage(res.imu.time, res.truth.time)
        out["truth_coverage"] = cover
        out["health"]["warnings"] += truth_consistency_warnings(out["truth_errors"])  # (from .evaluate)
        out["health"]["warnings"] += [f"truth: {w}" for w in vertical_pitch_warnings(
            res.truth, float(res.imu.time[0]), float(res.imu.time[-1]))]
        out["health"]["warnings"] += [f"truth: {w}" for w in coverage_warnings(cover, res.truth.time)]
        # a truth whose _deg columns hold radians (the solution's are this run's own: only the truth's are said)
        out["health"]["warnings"] += [f"truth: {w}" for w in attitude_unit_warnings(
            fw.solution, res.truth, "the solution", out["truth_file"]) if w.startswith(out["truth_file"])]
    notes = res.imu_notes or {}
    from ..integration.gaps import spikes_warning

    warn = spikes_warning(notes.get("spikes"), Path(str(res.config.imu.file)).name)
    if warn:
        out["health"]["warnings"].append(warn)
    if notes.get("pos_heights") == "geodetic" and not res.config.gnss.height_offset_m:
        out["health"]["warnings"].append(
            f"GNSS: {res.config.gnss.file}: its header says the heights are geodetic (above the geoid), which "
            "inskit takes as ellipsoidal: the fixes are off by the geoid separation N (tens of metres); set "
            "[gnss] height_offset_m = N, or write the .pos with ellipsoidal heights (RTKLIB out-height)")
    if notes.get("repeated_rows"):
        out["imu_repeated_rows"] = {k: notes[k] for k in ("repeated_rows", "repeated_rows_fraction",
                                                          "repeated_rows_dropped", "repeated_rows_longest_run",
                                                          "repeated_rows_longest_run_s") if k in notes}
        frozen = frozen_imu_message(notes, res.config.imu)
        if frozen:
            out["health"]["reasons"].append(frozen)
            out["health"]["verdict"] = "unhealthy"
        if not notes["repeated_rows_dropped"]:
            out["health"]["warnings"].append(
                f"IMU: {notes['repeated_rows']} rows ({notes['repeated_rows_fraction']:.1%}) repeat the previous row "
                "in all six channels (the logger read one sample twice?), integrated as samples over their short "
                "intervals; [imu] repeated_rows = \"drop\" leaves them out")
    if "time_tag_jitter_fraction" in notes:
        out["imu_time_tags"] = {k: notes[k] for k in (
            "time_smoothing_samples", "time_tag_jitter_fraction", "time_tag_interval_min_s", "time_tag_interval_max_s",
            "time_tag_interval_median_s", "time_tags_moved_rms_s", "time_tags_moved_max_s", "time_tag_jitter_s",
            "time_tags_moved_net_rms_s", "time_tags_moved_net_max_s", "time_tags_left_out_spread_max_s",
            "time_tags_beyond_jitter", "time_tag_rate_changes") if k in notes}
        out["health"]["warnings"] += time_tags_warnings(notes, notes.get("reader_time_offset_s", 0.0))
        if notes["time_smoothing_samples"] == 1 and notes["time_tag_jitter_fraction"] > JITTER_HINT_FRACTION:
            med = notes["time_tag_interval_median_s"]
            out["health"]["warnings"].append(
                f"IMU: the time tags jitter: {notes['time_tag_jitter_fraction']:.0%} of the sampling intervals "
                f"differ from the median {med * 1e3:.3g} ms by more than {JITTER_TOLERANCE:.0%} "
                f"({notes['time_tag_interval_min_s'] * 1e3:.3g}-{notes['time_tag_interval_max_s'] * 1e3:.3g} ms), "
                "and each rate sample is integrated over its own interval. If the logger stamped its read times "
                "rather than the sensor's, [imu] time_smoothing_samples = 11 takes the jitter out (choose it with "
                "`inskit tune CONFIG --grid imu.time_smoothing_samples=1,5,11,21`)")
    from ..integration.mounting import mounting_check, mounting_summary

    c, odo = res.config.constraints, res.config.odometer
    out.update(mounting_summary(fw, res.config.imu.mount_rpy_deg))
    out["mounting_check"], warn = mounting_check(
        fw, res.gnss.select(res.used), mount_rpy_deg=res.config.imu.mount_rpy_deg,
        constrained=res.config.filter.scheme != "uncoupled" and (c.nhc or (odo is not None and odo.with_nhc)))
    if warn:
        out["health"]["warnings"].append(warn)
    bank = res.startup.bank if res.startup is not None else None
    if bank and bank.get("tie"):
        out["health"]["warnings"].append(f"yaw bank: kept the start-up's own yaw {bank['chosen_yaw_deg']:.1f} deg: "
                                         + bank_tie_text(min(v for v in bank["scores"] if v is not None)))
    axes = res.startup.axes if res.startup is not None else None
    yaw_warn = unmodelled_yaw_warning(axes, fw, res.config)
    if yaw_warn:
        out["health"]["warnings"].append(yaw_warn)
    if axes and axes["differ"]:  # rotated: said; not rotated ("given"): the heading from the track is off
        if axes["rotated"]:
            out["health"]["warnings"].append(vehicle_axes_message(axes))
        else:
            out["health"]["reasons"].append(vehicle_axes_message(axes))
            out["health"]["verdict"] = "unhealthy"
    for u in out.get("outages_unscored") or ():
        out["health"]["warnings"].append(f"outage {u['k']} ({u['start_s']:.2f} .. {u['end_s']:.2f} s after the first "
                                         f"fix) not scored: {u['reason']}")
    if res.config.outages.protocol != "none" and out.get("outages_unscored") and not out.get("outages"):
        out["health"]["reasons"].append(f"the outage protocol \"{res.config.outages.protocol}\" scored no outage: "
                                        "none of its windows withholds a fix of this run, so there is no outage "
                                        "figure to trust")
        out["health"]["verdict"] = "unhealthy"
    out["imu_rate_changes"] = [{"row": c.row, "t_s": c.t_s, "rate_before_hz": c.rate_before_hz,
                                "rate_after_hz": c.rate_after_hz} for c in (res.rate_changes or ())]
    out["imu_gaps"] = [{"row": g.row, "start_s": g.start_s, "length_s": g.length_s} for g in (res.gaps or ())]
    out["final_estimates"] = {b.name: {"values": [float(v) for v in fw.estimate(b.name)[-1]],
                                       "sigma": [float(v) for v in fw.sigma_of(b.name)[-1]], "unit": b.unit}
                              for b in fw.layout.blocks if b.has_estimate}
    return out


#: a direction of travel measured off the IMU's x axis by more than this [deg] and MOUNT_YAW_SE standard errors,
#: with a vehicle constraint and no mounting states, is said (the axes check itself acts only beyond 20 deg)
MOUNT_YAW_WARN_DEG = 1.0
MOUNT_YAW_SE = 4.0


def unmodelled_yaw_warning(axes, track, cfg) -> str | None:
    """A warning when the start-up's vehicle-axes check
    (:func:`inskit.alignment.vehicle_axes.vehicle_axes`) measured the
    direction of travel off the IMU's x axis by more than
    :data:`MOUNT_YAW_WARN_DEG` and :data:`MOUNT_YAW_SE` standard errors (a
    small yaw it leaves to the filter), while the run applied the
    non-holonomic constraint without the mounting states: the constraint
    then takes the IMU's x axis for the vehicle's and bends the heading.
    The filter's own mounting check (``mounting_check``) cannot see such a
    yaw: the constraint has already turned the solution to it.  An IMU
    yawed 4 deg ran 'healthy' with 36 m of outage error against 7.5 m."""
    c, odo = cfg.constraints, cfg.odometer
    if not axes or axes.get("travel_yaw_deg") is None or axes.get("rotated") or axes.get("differ"):
        return None
    if cfg.filter.scheme == "uncoupled" or not (c.nhc or (odo is not None and odo.with_nhc)):
        return None
    if "mounting" in track.layout:
        return None
    y, se = float(axes["travel_yaw_deg"]), float(axes.get("travel_yaw_se_deg") or 0.0)
    if abs(y) <= MOUNT_YAW_WARN_DEG or abs(y) <= MOUNT_YAW_SE * se:
        return None
    return (f"the start-up measured the direction of travel {y:+.2f} deg (+-{se:.2f}) off the IMU's x axis, which "
            "the non-holonomic constraint takes for the vehicle's forward axis: a yaw mounting the filter does not "
            "model bends its heading; set [constraints] mounting = true, or add about "
            f"{y:+.1f} deg to the yaw of [imu] mount_rpy_deg")


def lost_stretches(t, accepted, min_span_s) -> list[dict]:
    """The stretches over which a measurement's updates were refused one
    after the other for at least ``min_span_s`` (the filter's recovery
    wait, ``FilterSettings.recovery_after_s``): a lost filter (or input bad
    for that long), each as ``{"start_s", "end_s", "updates", "recovered"}``
    (from the first refused update to the next accepted one, or to the last
    refused when none followed: ``recovered`` False).

    Parameters
    ----------
    t : (m,) array
        Times of the updates [s].
    accepted : (m,) bool array
    min_span_s : float
        [s].

    Returns
    -------
    list of dict
    """
    t = np.asarray(t, float)
    acc = np.asarray(accepted, bool)
    edges = np.diff(np.r_[0, (~acc).astype(np.int8), 0])
    out = []
    for a, b in zip(np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]):
        recovered = b < len(t)
        end = float(t[b] if recovered else t[b - 1])
        if end - float(t[a]) >= min_span_s:
            out.append({"start_s": float(t[a]), "end_s": end, "updates": int(b - a), "recovered": bool(recovered)})
    return out


def outside_lost(t, accepted, nis, stretches, dof) -> dict:
    """The figures of a measurement's updates outside its lost stretches
    (:func:`lost_stretches`, each from its first refused update to the
    update that ended it, exclusive): ``updates``, ``rejected_fraction``
    and ``mean_nis`` (None without updates), the figures
    :func:`gnss_updates_unhealthy` judges, without the stretches where the
    filter was lost.  ``dof``: the measurement's degrees of freedom per
    update (``mean_nis_per_dof`` divides by it)."""
    t = np.asarray(t, float)
    inside = np.zeros(len(t), bool)
    for x in stretches:
        inside |= (t >= x["start_s"]) & ((t < x["end_s"]) if x["recovered"] else (t <= x["end_s"]))
    keep = ~inside
    n = int(keep.sum())
    acc = np.asarray(accepted, bool)[keep]
    nis = np.asarray(nis, float)[keep] if len(nis) == len(t) else np.zeros(0)
    mean = float(nis.mean()) if len(nis) else None
    return {"updates": n, "rejected_fraction": float((~acc).sum() / n) if n else 0.0, "mean_nis": mean,
            "mean_nis_per_dof": None if mean is None or not dof else mean / dof}


#: the health verdict's limits (docs in :func:`health`)
HEALTH_MAX_REJECTED_FRACTION = 0.05
HEALTH_MAX_MEAN_NIS_PER_DOF = 3.0
HEALTH_MAX_PRIOR_SIGMAS = 5.0
HEALTH_BIAS_BLOCKS = ("bg", "ba")
HEALTH_MAX_REJECTION_RUN = 4


#: the non-holonomic constraint refused in more than this fraction of its updates is named as not holding
NHC_BROKEN_FRACTION = 0.5


#: a run of this many consecutive IMU rows or more repeating one sample in all six channels is the sensor's output
#: frozen, not a sample read twice (a logger polling a little faster than the sensor repeats a sample once: every
#: one of drive_0708's 1138 and walk_0827's 6958 repeats is alone)
IMU_FROZEN_RUN_ROWS = 3


def frozen_imu_message(notes: dict, imu_cfg) -> str | None:
    """The health verdict's reason when the IMU log holds a run of
    :data:`IMU_FROZEN_RUN_ROWS` or more rows repeating one sample (the
    reader's ``repeated_rows_longest_run``, ...; ``imu_cfg``: the config's
    ``[imu]``): the solution there was integrated, or bridged, on a sample
    that is not the motion; None otherwise."""
    run = notes.get("repeated_rows_longest_run", 0)
    if run < IMU_FROZEN_RUN_ROWS:
        return None
    t = notes["repeated_rows_longest_run_time_s"]  # the rtklibexplorer reader's times carry [imu] time_offset_s
    t -= notes.get("reader_time_offset_s", 0.0)
    return (f"IMU: {Path(str(imu_cfg.file)).name}: {run} rows in a row from {notes['repeated_rows_longest_run_at']} "
            f"(the file's time {t:.3f} s, {notes['repeated_rows_longest_run_s']:.3g} s of the log) repeat one sample "
            "in all six channels: the sensor's output froze (a stuck sensor, a logger that lost it), not a sample "
            "read twice; the solution there rests on no measured motion ([imu] repeated_rows = \"drop\" bridges "
            "the stretch as a gap): cut the log there, or mend the logger")


def time_tags_warnings(notes: dict, time_offset_s=0.0) -> list[str]:
    """The health warnings on the smoothed IMU time tags: one for each
    figure of the reader's check beyond its limit
    (``notes["time_tags_beyond_jitter"]``,
    :func:`inskit.io.time_tags.smoothing_check`), naming the summary key
    (under ``imu_time_tags``), the time (the file's: ``time_offset_s``, the
    offset the reader put in the notes' times, taken off) and row where the tags moved most, and what to do."""
    out = []
    n = notes.get("time_smoothing_samples")
    for b in notes.get("time_tags_beyond_jitter") or ():
        where = (f"largest at t = {b['t_s'] - time_offset_s:.3f} s (the file's time; row {b['row']} of the rows read, "
                 "after repeated_rows)")
        head = (f"IMU: the time tags smoothed over {n} rows ([imu] time_smoothing_samples) moved more than a steady "
                f"clock with their jitter ({notes['time_tag_jitter_s'] * 1e3:.3g} ms RMS) explains: "
                f"imu_time_tags.{b['key']} = "
                f"{b['value_s'] * 1e3:.3g} ms, over its limit {b['limit_s'] * 1e3:.3g} ms, {where}")
        if b["key"] == "time_tags_left_out_spread_max_s":
            why = ("rows left out (intervals of 1.5 sampling intervals or more) are spread over the window by more "
                   "than half an interval: several left out within one window, or a clock jump of whole intervals")
        else:
            why = ("the tags are no steady clock there: a drift or jump of the clock, a rate change under the "
                   "20 % the smoothing splits at, or a window too long for the clock")
        out.append(f"{head}; {why}. Use a smaller window (time_smoothing_samples = 5), or 1 to keep the tags as "
                   "logged (choose with `inskit tune CONFIG --grid imu.time_smoothing_samples=1,5,11`)")
    return out


def health(out, gaps=(), rate_changes=()) -> dict:
    """The verdict on a filter run: is the result to be trusted?

    *Unhealthy* when any of these holds (each reason is listed):

    * more than 5 % of a measurement's updates rejected (of its rows, for a
      measurement gated row by row, such as one row per satellite);
    * 4 or more consecutive updates of a measurement rejected (a burst of
      bad input: the filter survived it, the data are still suspect; or,
      over the recovery's 15 s or more, the filter lost: each such stretch
      is listed in ``measurements[name]["lost_stretches"]``
      (:func:`lost_stretches`), with the figures of the updates outside
      them in ``outside_lost``, :func:`outside_lost`);
    * a measurement's mean NIS over its accepted updates above 3 times its
      degrees of freedom (the filter is overconfident by more than sqrt(3)
      in sigma; a consistent filter averages 1 per degree of freedom; the
      rejected updates are judged by the two figures above, so that one
      refused outlier does not make the filter look overconfident);
    * a sensor-bias estimate (gyro, accelerometer) more than 5 prior sigmas
      from its initial value, the prior being its initial sigma and the
      in-run process noise accumulated over the run
      (:meth:`inskit.integration.blocks.StateBlock.prior_sigma`): the filter
      absorbs something it does not model;
    * a recovery from a lost state happened;
    * the IMU log had a gap (bridged on the last rates: the solution over it
      is an extrapolation).

    A change of the IMU's sampling rate is a warning (gaps are then judged
    against the local rate).

    *Warnings*, listed without changing the verdict: other blocks' estimates
    beyond 5 prior sigmas (a scale factor soaking up a mounting error, say),
    and a mean NIS below a third of the degrees of freedom (conservative
    noise, common for constraint pseudo-measurements).  :func:`summary` adds
    the warning of a mounting the constraints do not model
    (:func:`inskit.integration.mounting.mounting_check`) and that of an
    aiding log that made no update (:func:`aiding_warnings`).
    """
    reasons, warnings, per = [], [], {}
    settings = getattr(out, "settings", None)
    lost_span = getattr(settings, "recovery_after_s", None)
    lost_span = float(FilterSettings.recovery_after_s if lost_span is None else lost_span)
    if not any(len(v.get("nis", [])) for v in out.innovations.values()):
        warnings.append("no filter statistics to judge (the uncoupled scheme, or no measurement used): the "
                        "verdict covers only what follows")
    for name, c in out.counts.items():
        inn = out.innovations.get(name, {})
        nis = np.asarray(inn.get("nis", []), float)
        n_upd = c["used"] + c["rejected"]
        # degrees of freedom per update (the mean when the number of rows varies, e.g. satellites in view)
        dofs = np.asarray(inn.get("nis_dof", inn.get("dof", [])), float)  # the rows each NIS covers
        dof = (float(dofs.mean()) if len(dofs) else None) if len(nis) else None
        if dof is not None and dof.is_integer():
            dof = int(dof)
        frac = c["rejected"] / n_upd if n_upd else 0.0
        mean_nis = float(nis.mean()) if len(nis) else None
        # the consistency of what the filter used: a rejected update's NIS is judged by the rejection figures
        # below (one refused fix 1 km off made the mean NIS 765 for 3 dof and the run 'overconfident')
        ok = np.asarray(inn.get("accepted", []), bool)
        used_nis = nis[ok] if len(ok) == len(nis) else nis
        mean_used = float(used_nis.mean()) if len(used_nis) else None
        per[name] = {"updates": n_upd, "rejected_fraction": frac, "mean_nis": mean_nis, "mean_nis_accepted": mean_used,
                     "dof": dof}
        if c.get("rows"):  # gated row by row (one satellite each): judge the rows
            frac = c["rows_rejected"] / c["rows"]
            per[name].update(rows=c["rows"], rows_rejected=c["rows_rejected"], rejected_row_fraction=frac)
            if frac > HEALTH_MAX_REJECTED_FRACTION:
                reasons.append(f"{name}: {c['rows_rejected']} of {c['rows']} rows rejected ({frac:.0%})")
        elif frac > HEALTH_MAX_REJECTED_FRACTION:
            hint = ""
            if name == "nhc" and frac > NHC_BROKEN_FRACTION:  # the constraint itself is wrong for this vehicle
                hint = (": the non-holonomic constraint, a land vehicle's, does not hold for this vehicle (a "
                        "vessel's heave, an aircraft, a handheld device) or its mounting; set [constraints] nhc "
                        "= false")
            reasons.append(f"{name}: {c['rejected']} of {n_upd} updates rejected ({frac:.0%}){hint}")
        acc = np.asarray(inn.get("accepted", []), bool)
        t_inn = np.asarray(inn.get("t", []), float)
        lost = lost_stretches(t_inn, acc, lost_span) if len(acc) == len(t_inn) else []
        per[name]["lost_stretches"] = lost
        per[name]["outside_lost"] = outside_lost(t_inn, acc, nis, lost, dof) if lost else None
        if len(acc):  # the longest run of consecutive rejections: a burst of bad input, even when survived
            edges = np.diff(np.r_[0, (~acc).astype(np.int8), 0])
            starts, ends = np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]
            if len(starts):
                j = int(np.argmax(ends - starts))
                run = int(ends[j] - starts[j])
                per[name]["longest_rejection_run"] = run
                t0 = float(np.asarray(inn['t'])[starts[j]])
                long = [x for x in lost if x["start_s"] == t0]
                if run >= HEALTH_MAX_REJECTION_RUN:
                    reasons.append(f"{name}: {run} consecutive updates rejected from t = {t0:.2f} s " + (
                        f"(for {long[0]['end_s'] - t0:.1f} s{'' if long[0]['recovered'] else ', to the end of the run'}"
                        ": the filter lost, or the input bad for that long)" if long else "(a burst of bad input)"))
        if mean_used is not None and dof:
            of = "" if len(used_nis) == len(nis) else f" of the {len(used_nis)} accepted updates"
            if mean_used > HEALTH_MAX_MEAN_NIS_PER_DOF * dof:
                reasons.append(f"{name}: mean NIS{of} {mean_used:.2f} for {dof:.3g} degrees of freedom (filter "
                               "overconfident)")
            elif mean_used < dof / 3.0:
                warnings.append(f"{name}: mean NIS{of} {mean_used:.2f} for {dof:.3g} degrees of freedom (noise set "
                                "conservatively)")
    reasons += aiding_suspects(per)
    lay = out.layout
    for b in lay.blocks:
        if not b.has_estimate or np.all(np.isnan(out.sigma[-1, lay.slice(b.name)])):
            continue
        if b.predict_estimate:  # a clock runs away from its start by design
            continue
        elapsed = float(out.nav.time[-1] - out.nav.time[0])
        prior = b.prior_sigma(elapsed)
        dev = np.abs(out.estimate(b.name)[-1] - b.estimate0) / prior
        for axis, d, v, s0, sp in zip(b.axes, dev, out.estimate(b.name)[-1], b.sigma0, prior):
            if d > HEALTH_MAX_PRIOR_SIGMAS:
                unit = f" {b.unit}" if b.unit else ""
                grown = "" if sp <= s0 * (1 + 1e-9) else f", with its process noise over {elapsed:.0f} s"
                msg = (f"{b.name}_{axis} estimate {v:.4g}{unit} is {d:.1f} prior sigmas from its start (prior sigma "
                       f"{sp:.3g}{unit}: initial {s0:.3g}{grown})")
                (reasons if b.name in HEALTH_BIAS_BLOCKS else warnings).append(msg)
    for r in getattr(out, "recoveries", []):
        reasons.append(recovery_text(r))
    for g in gaps:
        reasons.append(f"IMU gap of {g.length_s:.3f} s at t = {g.start_s:.3f} s, bridged on the last rates")
    for c in rate_changes:
        warnings.append(f"IMU rate changes from {c.rate_before_hz:.4g} Hz to {c.rate_after_hz:.4g} Hz near "
                        f"t = {c.t_s:.3f} s")
    return {"verdict": "unhealthy" if reasons else "healthy", "reasons": reasons, "warnings": warnings,
            "measurements": per}


def recovery_text(r: dict) -> str:
    """A recovery from a lost state (:attr:`.FilterOutput.recoveries`) in
    words: when, after what, how far the filter had drifted from a
    measurement that fixes the position, and what was done."""
    text = (f"{r['measurement']}: recovered from a lost state at t = {r['t']:.2f} s after {r['after_rejections']} "
            f"consecutive rejections over {r['rejected_for_s']:.1f} s")
    if r.get("fixes_position"):
        text += (f": the filter had drifted {r['position_offset_m']:.3g} m from it with a velocity error of "
                 f"{r['drift_velocity_m_s']:.3g} m/s, growing at {r['drift_accel_m_s2']:.2g} m/s^2 horizontally (a "
                 f"tilt error of about {np.degrees(r['tilt_rad']):.1f} deg)")
        if r.get("reinitialised"):
            return text + ("; it was re-initialised on it: position and velocity reset, the navigation covariance "
                           "decorrelated and widened (the attitude's by that tilt)")
    if r.get("covariance_scale") is not None:
        text += f"; the navigation covariance was scaled by {r['covariance_scale']:.3g} for it to pass"
    return text


def recoveries_summary(recoveries) -> list[dict]:
    """The summary's ``recoveries``: each recovery's record with its tilt in
    degrees (``tilt_deg``) instead of radians."""
    out = []
    for r in recoveries:
        d = {k: v for k, v in r.items() if k != "tilt_rad"}
        if "tilt_rad" in r:
            d["tilt_deg"] = None if r["tilt_rad"] is None else float(np.degrees(r["tilt_rad"]))
        out.append(d)
    return out


def fmt_or_na(x, fmt=".3f"):
    return "n/a" if x is None else format(x, fmt)


def _mg(a_m_s2):
    """An acceleration [m/s^2] in mg (standard gravity), None kept."""
    return None if a_m_s2 is None else a_m_s2 / MILLI_G


def outage_table_text(s: dict) -> str:
    """The outage table and its figures, each named by its reference: the
    withheld fixes (their noise included), the truth when one was given, and
    the fit to the used fixes (not an accuracy).  No outage (protocol
    "none", or no window withheld a fix): no table, a line that says so."""
    rows = s["outage_table"]
    truth = "outages_vs_truth" in s
    head = (f"{'outage':>6} {'window [s after first fix]':>27} {'end horiz [m]':>14} {'end vert [m]':>13} "
            f"{'worst horiz [m]':>16} {'along [m]':>10} {'cross [m]':>10} {'accel fit [mg]':>15}")
    lines = [f"{'':>6} {'':>27} {'--- against the withheld fixes (noise included) ---':>45}"
             + (f"{'':>38}  {'--- against the truth ---':>31}" if truth else ""),
             head + (f" {'end horiz [m]':>14} {'worst horiz [m]':>16}" if truth else "")] if rows else []
    unscored = len(s.get("outages_unscored") or ())
    if not rows and not unscored:
        lines.append("outages: none (no GNSS fix withheld), so no outage table")
    elif not rows:
        lines.append(f"outages: none scored ({unscored} window(s) withheld no GNSS fix: see the health warnings), "
                     "so no outage table")
    for r in rows:
        line = (f"{r['k']:>6} {r['start_s']:>12.2f} .. {r['end_s']:>9.2f}   {r['horizontal_m']:>13.3f} "
                f"{r['vertical_m']:>13.3f} {r['worst_horizontal_m']:>16.3f} "
                f"{fmt_or_na(r.get('outage_end_along_track_vs_withheld_fixes_m'), '.2f'):>10} "
                f"{fmt_or_na(r.get('outage_end_cross_track_vs_withheld_fixes_m'), '.2f'):>10} "
                f"{fmt_or_na(_mg(r.get('outage_along_track_accel_fit_m_s2')), '.1f'):>15}")
        if truth:
            line += f" {fmt_or_na(r.get('outage_end_h_vs_truth_m')):>14} {fmt_or_na(r.get('outage_worst_h_vs_truth_m')):>16}"
        lines.append(line)
    if rows:
        lines.append(f"against the withheld fixes (their noise included), {s['solution']} solution: outage-end "
                     f"horizontal RMS {s['outage_end_horizontal_rms_m']:.3f} m, median "
                     f"{s['outage_end_horizontal_median_m']:.3f} m, max {s['outage_end_horizontal_max_m']:.3f} m; "
                     f"worst in the outage RMS {s['outage_worst_horizontal_rms_m']:.3f} m")
    if rows and s.get("outage_end_along_track_vs_withheld_fixes_rms_m") is not None:
        lines.append(f"outage-end error along the track RMS {s['outage_end_along_track_vs_withheld_fixes_rms_m']:.3f} m, "
                     f"across it {s['outage_end_cross_track_vs_withheld_fixes_rms_m']:.3f} m (along: + ahead, cross: "
                     "+ right of travel); accel fit: the constant along-track acceleration error that best fits "
                     "each outage's error growth (1 mg is a tilt of 0.057 deg or a forward accelerometer bias of 1 mg)")
    if truth and s.get("outages_vs_truth"):
        lines.append(f"against the truth, {s['solution']} solution: outage-end horizontal RMS "
                     f"{fmt_or_na(s['outage_end_h_vs_truth_rms_m'])} m, max {fmt_or_na(s['outage_end_h_vs_truth_max_m'])} m (the "
                     f"last epoch before the next used fix); worst in the outage RMS "
                     f"{fmt_or_na(s['outage_worst_h_vs_truth_rms_m'])} m, max {fmt_or_na(s['outage_worst_h_vs_truth_max_m'])} m")
    if truth:
        lines.append(f"against the truth with GNSS on: horizontal RMS {fmt_or_na(s['gnss_on_h_vs_truth_rms_m'])} m, "
                     f"vertical RMS {fmt_or_na(s['gnss_on_v_vs_truth_rms_m'])} m over {s['gnss_on_epochs_vs_truth']} "
                     "epochs")
    if s.get("fixes_fused", True):
        lines.append(f"fit to the used fixes (not an accuracy: the filter was fed them): horizontal RMS "
                     f"{s['fit_to_used_fixes_h_rms_m'] * 100:.2f} cm, vertical RMS "
                     f"{s['fit_to_used_fixes_v_rms_m'] * 100:.2f} cm over {s['fit_to_used_fixes_count']} fixes")
    else:
        lines.append(f"against the reference fixes with GNSS on (never fused: an accuracy, the reference's own "
                     f"error included): horizontal RMS {s['gnss_on_h_vs_reference_fixes_rms_m']:.3f} m, vertical "
                     f"RMS {s['gnss_on_v_vs_reference_fixes_rms_m']:.3f} m over {s['gnss_on_reference_fixes']} fixes")
    if s["solution"] == "smoothed" and rows:
        f = s["forward"]
        lines.append(f"forward filter for comparison, against the withheld fixes: outage-end RMS "
                     f"{f['outage_end_horizontal_rms_m']:.3f} m, worst in the outage RMS "
                     f"{f['outage_worst_horizontal_rms_m']:.3f} m"
                     + (f"; against the truth: outage-end RMS {fmt_or_na(f.get('outage_end_h_vs_truth_rms_m'))} m, worst "
                        f"in the outage RMS {fmt_or_na(f.get('outage_worst_h_vs_truth_rms_m'))} m" if truth else ""))
        lines.append("(the smoother's outage-end error sits next to the used fix that follows; its worst point "
                     "inside the outage is the figure that means something)")
    counts = ", ".join(f"{k} {v['used']} used/{v['rejected']} rejected" for k, v in s["measurements"].items())
    lines.append(f"updates: {counts}")
    return "\n".join(lines)


def bank_line(bank: dict) -> str:
    """The log line of a yaw bank (:func:`inskit.alignment.inmotion.yaw_bank`'s result)."""
    runner_up = bank["runner_up_score"]
    head = f"yaw bank: {len(bank['scores'])} hypotheses over {bank['span_s']:.0f} s in {bank['elapsed_s']:.1f} s; "
    if bank.get("tie"):
        best = min(v for v in bank["scores"] if v is not None)
        return head + (f"kept the start-up's own {bank['chosen_yaw_deg']:.1f} deg (mean NIS per dof "
                       f"{bank['score']:.3f}): {bank_tie_text(best)}")
    return (head + f"kept {bank['chosen_yaw_deg']:.1f} deg (mean NIS per dof {bank['score']:.3f}, next best "
            + (f"{runner_up:.3f})" if runner_up is not None else "none)"))


def bank_tie_text(best) -> str:
    """Why a yaw bank kept its first hypothesis over a best that scored no better by a margin."""
    from ..alignment.inmotion import BANK_TIE

    return (f"no other fitted the fixes more than {BANK_TIE:.0%} better (best {best:.3f}): the data of the bank's "
            "span cannot tell the yaws apart (straight driving at constant speed), so its heading rests on the "
            "start-up's")


def run_input_keys(cfg: NavigateConfig) -> list:
    """``(key, path)`` of every file a navigate run of ``cfg`` reads,
    resolved, with the config key that names it: the IMU log, the fixes,
    the RINEX observation and navigation files, the speed and course log,
    the odometer, height and truth files (those the config names)."""
    g = cfg.gnss
    keys = [("imu.file", cfg.imu.file), ("gnss.file", g.file), ("gnss.obs", g.obs), ("gnss.nav", g.nav),
            ("gnss.speed_course", g.speed_course),
            ("odometer.file", cfg.odometer.file if cfg.odometer is not None else None),
            ("truth.file", cfg.truth.file if cfg.truth is not None else None),
            ("height.file", cfg.height.file if cfg.height is not None else None)]
    return [(k, cfg.resolve(f)) for k, f in keys if f is not None]


def run_input_files(cfg: NavigateConfig) -> list:
    """The files of :func:`run_input_keys`."""
    return [p for _, p in run_input_keys(cfg)]


def check_input_files(cfg: NavigateConfig) -> None:
    """Refuse, before any reading, an input of the run that is missing or a
    folder, naming the config key that gives it (a folder given as
    ``[gnss] file`` said only '/tmp: is a folder; expected a file', and a
    missing IMU log was found only after the fixes had been read)."""
    for key, p in run_input_keys(cfg):
        if p.is_dir():
            raise InputError(f"{p}: is a folder; expected a file (field '{key}')")
        if not p.exists():
            raise InputError(f"{p}: no such file (field '{key}')")


def run_output_names() -> list:
    """The names of every file a navigate run may write into its folder
    (:func:`write_outputs`, the plots, ``report.html``)."""
    from .plots import PLOTS

    names = [f"solution_{label}.{ext}" for label in ("forward", "smoothed") for ext in ("csv", "parquet")]
    return names + ["innovations.csv", "config_used.json", "summary.json", "report.html"] + [n for n, _ in PLOTS]


def refuse_overwriting_inputs(cfg: NavigateConfig, folder, extra_inputs=(), force=False, force_word="--force",
                              other="another --out") -> None:
    """Refuse, before any work, a run whose folder ``folder`` would receive
    a file over one of the run's inputs (:func:`run_input_files`, and
    ``extra_inputs``: the config file, a truth given apart): its solution,
    innovations, summary, plots or report, or, with ``force``, a file an
    earlier run there listed (which :func:`clear_previous_run` removes).
    ``force`` (``force_word``) replaces results, never what the run reads."""
    from ..files import same_file

    folder = Path(folder)
    targets = [folder / n for n in run_output_names()] + (previous_run_files(folder) if force else [])
    inputs = run_input_files(cfg) + [Path(f) for f in extra_inputs if f is not None]
    for out in targets:
        for inp in inputs:
            if same_file(out, inp):
                raise InputError(f"{out}: would overwrite an input of this run ({inp}); {force_word} replaces "
                                 f"results, never what the run reads: choose {other}, or move the input")


def occupied_folder_message(folder, force="--force", other="--out") -> str | None:
    """Why a run may not write into ``folder`` unasked, or None (no folder,
    or an empty one): the words say what it holds, a run's results (its
    ``summary.json``) or other files, named (the first few), and what
    ``force`` does there (``--force`` on the command line,
    ``overwrite=True`` in Python; ``other`` is how to choose another
    folder): it writes the new set in, replacing files of the same names
    and the files an earlier run listed in its summary, and keeps any
    other file."""
    folder = Path(folder)
    if not folder.is_dir():
        return None
    names = sorted(p.name for p in folder.iterdir())
    if not names:
        return None
    shown = ", ".join(names[:3]) + (", ..." if len(names) > 3 else "")
    if "summary.json" in names:
        return (f"{folder}: already holds results ({shown}: an earlier run's); refusing to overwrite them: choose "
                f"another folder ({other}), or {force} to replace them (the files that run listed go, other files "
                "stay)")
    return (f"{folder}: holds other files ({shown}) and no results of a run; refusing to write among them: choose "
            f"an empty or new folder ({other}), or {force} to write the results beside them (files of the same "
            "names are replaced)")


def previous_run_files(out_dir: Path) -> list:
    """The files an earlier run in ``out_dir`` listed in its ``summary.json``
    (only those inside ``out_dir``), with the summary and the report written
    after it; ``[]`` when there is no readable summary."""
    summary_path = Path(out_dir) / "summary.json"
    if not summary_path.exists():
        return []
    try:
        listed = json.loads(summary_path.read_text()).get("files", [])
    except (OSError, ValueError, AttributeError):
        listed = []
    root = Path(out_dir).resolve()
    out = []
    for name in [str(x) for x in listed if isinstance(x, str)] + ["summary.json", "report.html"]:
        f = Path(out_dir) / Path(name).name
        if f.resolve().parent == root and f not in out:
            out.append(f)
    return out


def clear_previous_run(out_dir: Path, previous=None, keep=()) -> list:
    """Remove the files of an earlier run (``previous``, by default
    :func:`previous_run_files`) except those named in ``keep`` (the new
    run's own), so that a ``--force`` run leaves no stale result beside its
    own.  Returns the files removed."""
    previous = previous_run_files(out_dir) if previous is None else previous
    keep = set(keep)
    removed = []
    for f in previous:
        if f.name not in keep and f.exists():
            f.unlink()
            removed.append(f)
    return removed


def write_innovations(innovations: dict, path) -> Path:
    """Every innovation row of a run as one table (``measurement, t, row,
    label, nu, sigma, nis, accepted, status``): one line per component (an
    axis, a satellite), built with array operations.

    ``accepted`` (1 or 0) and ``status`` say what happened to that row:
    ``accepted`` (used in the update), ``refused_row_gate`` (a measurement
    gated row by row, the pseudoranges and Dopplers of tight coupling: this
    row failed its own gate while the update went on with the others, or
    every row of it failed) or ``refused_update_gate`` (the chi-square gate
    of the whole vector refused the update and so this row); the summary's
    ``rows_rejected`` counts the ``refused_row_gate`` lines, its
    ``rejected`` the updates with at least one refused line.  ``label`` is
    what the row is: the satellite (``G05``) of a range row, the axis of
    the fixed-row measurements, empty where unknown (a user's plug-in).
    ``nis`` is the update's (the rows used, when some were refused).
    """
    from ..files import distinct_text, write_csv, write_csv_parts
    from ..integration.engine import ROW_STATUS
    from .plots import COMPONENTS

    names = list(INNOVATION_COLUMNS)
    text = [list(innovations), ROW_STATUS] + [list(COMPONENTS.get(k, ())) for k in innovations]
    text += [distinct_text(np.asarray(v["label"], dtype=object)) for v in innovations.values()
             if v.get("label") is not None]
    if not any(c in str(x) for vals in text for x in vals for c in ',"\n\r'):  # the block writer does not quote
        return write_csv_parts(path, names, _innovation_parts(innovations), 10)
    parts = list(_innovation_parts(innovations))
    return write_csv(path, {c: np.concatenate([q[c] for q in parts]) if parts else np.empty(0) for c in names},
                     "%.10g")


#: the columns of ``innovations.csv`` (:func:`write_innovations`)
INNOVATION_COLUMNS = ("measurement", "t", "row", "label", "nu", "sigma", "nis", "accepted", "status")
#: updates per block of :func:`_innovation_parts`
INNOVATION_BLOCK_UPDATES = 1 << 16


def _innovation_parts(innovations: dict):
    """The lines of :func:`write_innovations` as consecutive column dicts, a
    block of :data:`INNOVATION_BLOCK_UPDATES` updates of one measurement at a
    time (the table of an 8 h run, 0.6 M lines, is never made whole)."""
    from ..integration.engine import ROW_ACCEPTED, ROW_STATUS
    from .plots import COMPONENTS

    status_names = np.array(ROW_STATUS, dtype=object)
    for name, v in innovations.items():
        t = np.asarray(v.get("t", []), float)
        if not len(t):
            continue
        nu, sg = v["nu"], v["sigma"]
        ragged = nu.dtype == object
        k_all = np.asarray(v["dof"], np.int64) if ragged else np.full(len(t), nu.shape[1], np.int64)
        ends = np.cumsum(k_all)  # each update's last line + 1, in this measurement's lines
        n_lines = int(ends[-1])
        status_all, label_all = v.get("status"), v.get("label")
        has_status = status_all is not None and len(status_all) == n_lines  # else: its update's verdict
        has_label = label_all is not None and len(label_all) == n_lines
        axes = COMPONENTS.get(name, ())
        axis_labels = not ragged and len(axes) == nu.shape[1]
        accepted = np.asarray(v["accepted"], bool)
        nis = np.asarray(v["nis"], float)
        for a in range(0, len(t), INNOVATION_BLOCK_UPDATES):
            b = min(a + INNOVATION_BLOCK_UPDATES, len(t))
            k = k_all[a:b]
            la, lb = int(ends[a - 1]) if a else 0, int(ends[b - 1])
            if ragged:
                nu_f, sg_f = np.concatenate(list(nu[a:b])), np.concatenate(list(sg[a:b]))
            else:
                nu_f, sg_f = nu[a:b].reshape(-1), sg[a:b].reshape(-1)
            row = np.arange(lb - la) - np.repeat(np.cumsum(k) - k, k)
            status = (np.asarray(status_all[la:lb], np.int64) if has_status
                      else np.where(np.repeat(accepted[a:b], k), 0, 2))
            if has_label:
                label = np.asarray(label_all[la:lb], dtype=object)
            else:
                label = np.array(axes, dtype=object)[row] if axis_labels else np.full(lb - la, "", dtype=object)
            yield {"measurement": np.full(lb - la, name, dtype=object), "t": np.repeat(t[a:b], k), "row": row,
                   "label": label, "nu": nu_f, "sigma": sg_f, "nis": np.repeat(nis[a:b], k),
                   "accepted": (status == ROW_ACCEPTED).astype(int), "status": status_names[status]}


def write_outputs(res: NavigateResult, out_dir: Path, s: dict, *, replace_previous=False) -> list:
    """Solution files, innovations, the configuration used, plots and
    ``summary.json`` (with the list of files) into ``out_dir``, as a set:
    written into a staging folder and moved into place together, the
    summary last, as the mark of a complete run
    (:func:`inskit.files.staged_tree`).  A failure on the way (a plot, a
    full disk, an interrupt) leaves ``out_dir`` as it was: no new file
    beside the old ones, no result without its summary.

    ``replace_previous`` (``--force``): once the new set is in place, the
    files an earlier run listed in its summary that this one did not write
    go (:func:`clear_previous_run`), so no stale result stays beside the new.

    ``[output] format``: ``solution_forward.parquet`` (and ``_smoothed``) at
    every IMU epoch, ``solution_forward.csv`` (and ``_smoothed``) at
    ``[output] rate_hz``, or both; ``[output] columns`` selects the columns of
    both (:func:`inskit.io.parquet.select_columns`).
    """
    from ..files import staged_tree

    out_dir = Path(out_dir)
    o = res.config.output
    previous = previous_run_files(out_dir) if replace_previous else []
    tracks = [("forward", res.forward)] + ([("smoothed", res.smoothed)] if res.smoothed is not None else [])
    with staged_tree(out_dir, last=("summary.json",)) as stage:
        names = []
        if res.streams:  # written while the filter ran: moved into the set now
            finish_streams(res)
            names += [w.commit(stage).name for w in res.streams]
            tracks = []
        for label, track in tracks:
            sol = track.solution
            if o.format in ("parquet", "both"):
                names.append(io.write_solution(stage / f"solution_{label}.parquet", sol, overwrite=True,
                                               columns=o.columns,
                                               metadata={"config": res.config.name, "solution": label,
                                                         "scheme": res.settings.scheme}).name)
            if o.format in ("csv", "both"):
                names.append(io.write_solution(stage / f"solution_{label}.csv", sol, overwrite=True,
                                               rate_hz=o.rate_hz, columns=o.columns).name)
        s["solution_files"] = {"format": o.format, "csv_rate_hz": o.rate_hz if o.format != "parquet" else None,
                               "columns": list(o.columns)}
        names.append(write_innovations(res.forward.innovations, stage / "innovations.csv").name)
        names.append(write_text(stage / "config_used.json",
                                res.config.model_dump_json(indent=2, exclude={"base_dir"})).name)
        if o.plots:
            from .plots import plot_all

            names += [p.name for p in plot_all(res, stage)]
        names.append("summary.json")
        files = [out_dir / n for n in names]
        s["files"] = [str(f) for f in files]
        write_json(stage / "summary.json", s, indent=2)  # strict JSON: a NaN figure is null, never NaN
    if replace_previous:
        clear_previous_run(out_dir, previous, keep=names)
    return files
