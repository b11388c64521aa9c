"""Monte Carlo studies and sensor-grade / filter-setting sweeps on Dask.

A study is a TOML file (:class:`StudySpec`): a scenario, the cases (one for
``kind = "monte-carlo"``; sensor grades x filter settings for
``kind = "sweep"``), the number of runs per case, a base seed, a duration
limit and optionally a GNSS outage ``(start, length)``.  Each run is one seeded
simulation + filter pass of :mod:`.montecarlo`:

* with an outage, the closed-loop (or open-loop) filter runs forward with the
  fixes of the window withheld; the run is scored by the horizontal error at
  the end of the outage (and the worst inside it, the vertical, velocity and
  attitude errors at its end).  The simulated IMU carries the grade preset's
  full error model, the filter the 15-state matched model of its stochastic
  part (:func:`.montecarlo.matched_settings` of
  :func:`.montecarlo.consistency_errors`), as :func:`.montecarlo.compare_schemes`
  does;
* without one, the run is :func:`.montecarlo.run_once` of the consistency job
  (smoothed NEES of position, velocity, attitude and normalised final bias
  errors).

Execution (the ``map`` of :mod:`.montecarlo` made distributed and
resumable): runs are submitted to a ``distributed`` cluster (a
``LocalCluster`` of one single-threaded process per core by default, or an
existing scheduler); each batch of completed runs is written at once as a
small Parquet part file under ``DIR/runs/`` (atomically, temporary name +
rename), so a killed client loses nothing but the runs in flight.  A rerun with
the same spec and ``DIR`` reads the parts, skips every ``(case, run)`` already
there and computes the rest.  At the end the rows are sorted by
``(case, run)`` and written as ``DIR/runs.parquet``; the statistics per case as
``DIR/summary.parquet`` (one row per case, figure and statistic),
``DIR/summary.json`` (the ranking) and ``DIR/study.png``.

Sensor grades: a preset name (:data:`GRADES`), or a grade fitted to a
static log of the user's own IMU (:class:`AllanGrade`, ``{allan = "log.csv"}``):
:func:`allan_grade` runs the Allan analysis of :mod:`.allan` on the log and
puts the fitted white noise (ARW, VRW), bias instability and its correlation
time in place of a preset's; what a static log cannot show (turn-on bias, scale
factor, saturation) comes from a ``base`` preset (default none).  The study
output lists every grade's parameters and which of them came from the fit.

Seeds: run ``r`` of case ``c`` uses the 64-bit integer drawn from
``numpy.random.SeedSequence(seed, spawn_key=(c, r))`` (the same sequence as
``SeedSequence(seed).spawn(...)[c].spawn(...)[r]``), so every number depends
on the key only: not on the number of workers, the order of completion or
which runs a resumed study still had to do.

References
----------
Bar-Shalom, Li & Kirubarajan 2001, *Estimation with Applications to Tracking
and Navigation*, §5.4 (NEES consistency); NumPy ``SeedSequence`` (NEP 19,
independent streams by spawn key); Dask ``distributed`` futures API.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import (BaseModel, ConfigDict, Discriminator, Field, PrivateAttr, Tag, ValidationError,
                      field_validator)

from .. import earth
from .. import rotations as rot
from ..config_files import check_magnitude, check_scalar_type, read_toml, validation_message
from ..errors import ConfigError, InputError
from ..io.parquet import READ_OPTIONS, damage_message
from ..files import (atomic_write, check_folder_writable, check_outputs, save_figure, staged_files, write_json,
                     write_text)
from ..types import ImuData
from ..units import DEG, DEG_PER_HOUR, G0, MICRO_G, PPM
from .montecarlo import (CONSISTENCY_GNSS, ConsistencySpec, anees_band, consistency_errors,
                         grade_initial_uncertainty, matched_settings, min_consistency_duration_s, perturbed_start,
                         run_once)
from .outages import withheld_mask

#: the sensor grades a study can sweep (:data:`inskit.simulation.sensors.PRESETS` plus ``ideal``)
GRADES = ("ideal", "navigation", "tactical", "industrial-mems", "consumer-mems")
#: figures of one outage run
OUTAGE_FIGURES = ("outage_end_horizontal_m", "outage_worst_horizontal_m", "outage_end_vertical_m",
                  "outage_end_velocity_m_s", "outage_end_attitude_deg")
#: figures of one consistency run
CONSISTENCY_FIGURES = ("nees_pos_mean", "nees_vel_mean", "nees_att_mean", "bias_rms_normalized")
#: the files a study writes into its folder (besides ``study.json`` and ``runs/``)
OUTPUT_FILES = ("runs.parquet", "summary.parquet", "summary.json", "study.png")
#: statistics over the runs of a case, in the order of ``summary.parquet``
STATISTICS = ("count", "mean", "std", "min", "median", "p90", "max")


class _M(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    _magnitude = field_validator("*")(check_magnitude)
    _kinds = field_validator("*", mode="before")(classmethod(check_scalar_type))


class OutageSpec(_M):
    """A GNSS outage: the fixes inside ``[start_s, start_s + length_s]`` are withheld."""

    start_s: float = Field(..., ge=0, description="start of the outage [s of scenario time]")
    length_s: float = Field(60.0, gt=0, description="its length [s]; the run is scored at its end")


class FilterCase(_M):
    """One setting of the filter (a sweep may list several)."""

    name: str = Field("matched", min_length=1, description="label in tables and plots")
    scheme: Literal["closed", "open"] = Field("closed", description="closed- or open-loop error feedback")
    noise_scale: float = Field(1.0, gt=0, description=(
        "factor on the filter's white-noise and bias-instability terms (1: the matched model); "
        "the simulated sensor is not changed"))
    gating: bool = Field(False, description="chi-square innovation gate (probability 0.9999) on the fixes")


#: extensions stripped from a log's file name to name its Allan grade
_LOG_SUFFIXES = (".gz", ".csv", ".txt")


class AllanGrade(_M):
    """A sensor grade fitted to a static log of the user's IMU (:func:`allan_grade`).

    In ``grades`` as an inline table, beside preset names:
    ``grades = ["tactical", {allan = "logs/static.csv", base = "tactical"}]``,
    or as ``[[grades]]`` tables (then presets as ``preset = "tactical"``).
    """

    allan: str = Field(..., min_length=1, description=(
        "static IMU log, relative to the study file, in an IMU format inskit reads (see `format`); at least "
        "100 s at rest, hours to resolve a bias instability of long correlation time"))
    name: str | None = Field(None, min_length=1, description=(
        "label in tables and plots (default: the file name without .csv / .gz / .txt)"))
    format: Literal["inskit", "rtklibexplorer"] = Field("inskit", description=(
        "'inskit' (docs/formats.md) or 'rtklibexplorer' (the rtklibexplorer GNSS-IMU logs)"))
    window_s: tuple[float, float] | None = Field(None, description=(
        "[start, end] of the static part to fit [s after the log's first sample] (default: the whole log)"))
    base: Literal[GRADES] = Field("ideal", description=(
        "grade that gives what a static log cannot show: turn-on bias (run to run), scale factor, saturation, "
        "and the filter's initial attitude uncertainty; 'ideal': no turn-on bias or scale-factor error"))
    #: the log's resolved path and the spec key it came from (set by :func:`load_spec`)
    _log: Path | None = PrivateAttr(None)
    _key: str = PrivateAttr("grades")

    @field_validator("window_s")
    @classmethod
    def _window(cls, w):
        if w is not None and not 0.0 <= w[0] < w[1]:
            raise ValueError(f"must be [start, end] with 0 <= start < end, got {list(w)}")
        return w

    @property
    def label(self) -> str:
        n = Path(self.allan).name
        while any(n.lower().endswith(x) for x in _LOG_SUFFIXES) and "." in n[1:]:
            n = n[:n.rfind(".")]
        return self.name or n


class PresetGrade(_M):
    """A preset grade as a table (``[[grades]]`` form): ``preset = "tactical"``."""

    preset: Literal[GRADES] = Field(..., description="grade preset")

    @property
    def label(self) -> str:
        return self.preset


def _grade_kind(v):
    if isinstance(v, (str, PresetGrade)):
        return "preset-name" if isinstance(v, str) else "preset"
    if isinstance(v, AllanGrade):
        return "allan"
    if isinstance(v, dict):
        return "preset" if "preset" in v and "allan" not in v else "allan"
    return None


#: a grade of a study: a preset name, ``{preset = ...}`` or ``{allan = ...}``
Grade = Annotated[Annotated[Literal[GRADES], Tag("preset-name")] | Annotated[PresetGrade, Tag("preset")]
                  | Annotated[AllanGrade, Tag("allan")],
                  Discriminator(_grade_kind, custom_error_type="grade",
                                custom_error_message="a grade is a preset name, or a table with 'allan' (a static "
                                                     "log to fit) or 'preset'")]
_GRADE_TAGS = ("preset-name", "preset", "allan")


def grade_label(g) -> str:
    """The name of a grade in tables, plots and ``runs.parquet``."""
    return g if isinstance(g, str) else g.label


class StudySpec(_M):
    """A study file (TOML).  Every key:

    ``scenario``: scenario file, relative to the study file; ``kind``:
    ``"monte-carlo"`` (one case: one grade, one filter setting) or ``"sweep"``
    (every grade x every filter setting); ``grades``: IMU grades (default
    the scenario's): preset names, and tables ``{allan = "static.csv"}``
    (:class:`AllanGrade`: keys ``allan``, ``name``, ``format``,
    ``window_s``, ``base``) for grades fitted to static logs;
    ``runs``: runs per case; ``seed``: base seed;
    ``duration_s``: use only the first seconds of the scenario; ``[outage]``:
    score by the errors at the end of this GNSS outage (without it: the
    consistency figures of the ``consistency`` job); ``[[filter]]``: filter
    settings (default one matched closed-loop filter).
    """

    scenario: str = Field(..., description="scenario TOML, relative to the study file")
    kind: Literal["monte-carlo", "sweep"] = Field(..., description="one case, or grades x filter settings")
    grades: list[Grade] | None = Field(None, min_length=1, description=(
        "IMU grades (default: the scenario's): preset names and {allan = \"static.csv\", ...} tables of grades "
        "fitted to static logs"))
    runs: int = Field(..., ge=1, le=1_000_000, description="runs per case")
    seed: int = Field(0, ge=0, description="base seed of every run's SeedSequence")
    duration_s: float | None = Field(None, gt=0, description="use only the first seconds of the scenario")
    outage: OutageSpec | None = Field(None, description="GNSS outage scored at its end")
    filter: list[FilterCase] = Field(default_factory=lambda: [FilterCase()], min_length=1,
                                     description="filter settings")


def load_spec(path) -> tuple[StudySpec, Path]:
    """The validated study of ``path`` and the path of its scenario.

    Raises
    ------
    ConfigError
        Missing file, bad TOML, an unknown or invalid key (named), a
        ``monte-carlo`` study with more than one case, duplicate names.
    """
    path = Path(path)
    data = read_toml(path, "study")
    try:
        spec = StudySpec.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(_validation_message(path, exc)) from None
    if spec.kind == "monte-carlo" and (len(spec.grades or [None]) > 1 or len(spec.filter) > 1):
        raise ConfigError(f"{path}: a 'monte-carlo' study has one grade and one [[filter]]; "
                          "use kind = \"sweep\" for several")
    names = [f.name for f in spec.filter]
    if len(set(names)) != len(names):
        raise ConfigError(f"{path}: [[filter]] names must be unique, got {names}")
    labels = [grade_label(g) for g in spec.grades or []]
    if len(set(labels)) != len(labels):
        raise ConfigError(f"{path}: field 'grades': each grade once (an Allan grade is named after its file or its "
                          f"'name'), got {labels}")
    for i, g in enumerate(spec.grades or []):
        if isinstance(g, AllanGrade):
            key = f"grades.{i}.allan"
            if g.label in GRADES:
                raise ConfigError(f"{path}: field '{key}': the grade of {g.allan!r} would be named {g.label!r} like "
                                  "a preset; give it another 'name'")
            log = (path.parent / g.allan).resolve()
            if not log.is_file():
                raise ConfigError(f"{path}: field '{key}': no such file {log}")
            g._log, g._key = log, f"{path}: field '{key}' ({log.name})"
    scenario = (path.parent / spec.scenario).resolve()
    if not scenario.is_file():
        raise ConfigError(f"{path}: field 'scenario': no such file {scenario}")
    return spec, scenario


def _validation_message(path, exc):
    """:func:`validation_message`, but for an error in a grade every error of
    that grade (a misspelt key is both unknown and a missing key), without the
    grade-kind tags of the union in the field path."""
    errors = exc.errors()
    e = errors[0]
    if e["loc"][:1] != ("grades",) or len(e["loc"]) < 2:
        return validation_message(path, exc, StudySpec)

    def where(loc):
        return ".".join(str(x) for i, x in enumerate(loc) if not (i == 2 and x in _GRADE_TAGS))

    mine = [x for x in errors if x["loc"][:2] == e["loc"][:2]]
    more = f" (and {len(errors) - len(mine)} more)" if len(errors) > len(mine) else ""
    return f"{path}: " + "; ".join(f"field '{where(x['loc'])}': {x['msg'].removeprefix('Value error, ')}" for x in mine) + more


def _datasheet(errors) -> dict:
    """The grade parameters of a sensor model in datasheet units (the keys of
    the study output's ``grades[].parameters``)."""
    g, a = errors.gyro, errors.accel
    return {
        "gyro_arw_deg_sqrt_h": g.white_noise / (DEG / 60.0),
        "gyro_bias_instability_deg_h": g.bias_instability / DEG_PER_HOUR,
        "gyro_bias_tau_s": g.bias_instability_tau_s,
        "gyro_turn_on_bias_deg_h": g.turn_on_bias_sigma / DEG_PER_HOUR,
        "gyro_scale_factor_ppm": float(np.mean(g.scale_factor)) / PPM,
        "gyro_saturation_deg_s": g.saturation / DEG if np.isfinite(g.saturation) else None,
        "accel_vrw_ug_sqrt_hz": a.white_noise / MICRO_G,
        "accel_bias_instability_ug": a.bias_instability / MICRO_G,
        "accel_bias_tau_s": a.bias_instability_tau_s,
        "accel_turn_on_bias_ug": a.turn_on_bias_sigma / MICRO_G,
        "accel_scale_factor_ppm": float(np.mean(a.scale_factor)) / PPM,
        "accel_saturation_g": a.saturation / G0 if np.isfinite(a.saturation) else None,
    }


#: the parameters an Allan grade takes from the fit (the rest come from its base)
FROM_FIT = ("gyro_arw_deg_sqrt_h", "gyro_bias_instability_deg_h", "gyro_bias_tau_s", "accel_vrw_ug_sqrt_hz",
            "accel_bias_instability_ug", "accel_bias_tau_s")


def _read_log(g: AllanGrade):
    from ..io.rtklib import read_rtklibexplorer_imu
    from .allan import read_static_log

    path = g._log if g._log is not None else Path(g.allan)
    if not path.is_file():
        raise ConfigError(f"{g._key}: no such file {path}")
    imu = read_static_log(path, format="inskit") if g.format == "inskit" else read_rtklibexplorer_imu(path)[0]
    if g.window_s is not None:
        t = imu.time - imu.time[0]
        a, b = g.window_s
        if b > t[-1]:
            raise ConfigError(f"{g._key}: window_s ends at {b:g} s, after the end of the log ({t[-1]:.1f} s "
                              "after its first sample)")
        k = (t >= a) & (t <= b)
        wkey = g._key.replace(".allan'", ".window_s'", 1)  # the field at fault is the window, not the log
        if k.sum() < 2:
            raise ConfigError(f"{wkey}: window_s {list(g.window_s)} holds fewer than two samples")
        from ..analysis.allan import MIN_DURATION_S

        held = float(t[k][-1] - t[k][0])
        if held < MIN_DURATION_S:  # the Allan fit's own message said 'the log lasts 0.5 s' of a 600 s log
            raise ConfigError(f"{wkey}: window_s {list(g.window_s)} holds {held:g} s of the {t[-1]:.1f} s log; an "
                              f"Allan deviation needs at least {MIN_DURATION_S:g} s (hours to see the bias "
                              "instability)")
        imu = ImuData(imu.time[k], imu.dtheta_b[k], imu.dv_b[k])
    return path, imu


def allan_grade(g: AllanGrade):
    """The sensor model of an Allan grade and the record of where its terms came from.

    The log is read (``format``, cut to ``window_s``) and fitted per axis by
    :func:`inskit.jobs.allan.allan_report` (white noise, Gauss-Markov bias
    instability of the IEEE 952 coefficient ``B`` and correlation time
    ``tau``).  One triad of the sensor model takes the root mean square of
    its three axes' white-noise densities and ``B`` (the presets are
    isotropic; for white noise that keeps the summed noise power) and the
    geometric mean of their ``tau``.  Everything else is the ``base``
    preset's: turn-on bias, scale factor, saturation.  A constant axis (no
    measurable noise) is left out of the means, as in ``inskit allan``.  A
    fitted rate random walk is recorded but not simulated: the presets have
    none, the 15-state filter does not model it, and on a log shorter than
    hours it is often a chance upturn of the last few clusters.

    Returns
    -------
    errors : ImuErrors
        The full sensor model the study simulates.
    record : dict
        ``name``, ``source = "allan"``, ``file``, ``format``, ``window_s``,
        ``log_duration_s``, ``base``, ``parameters`` (every grade parameter,
        datasheet units), ``from_fit`` (the subset that came from the fit),
        ``rate_random_walk_not_used``, ``per_axis`` (the fit of each axis as
        ``inskit allan`` reports it), ``bias_resolved`` and ``notes``.

    Raises
    ------
    InputError
        A log that cannot be read, is too short, irregular or not static,
        named with the spec key and the file.
    """
    from .allan import allan_report

    try:
        path, imu = _read_log(g)
        fits, rep = allan_report(imu)
    except InputError as exc:
        raise InputError(f"{g._key}: {exc}") from None

    def triad(base, axes):
        axes = [f for f in axes if f is not None]  # a constant axis shows no noise (allan_report's notes)

        def rms(k):
            return float(np.sqrt(np.mean([getattr(f, k) ** 2 for f in axes])))

        tau = float(np.exp(np.mean(np.log([f.gm_tau for f in axes]))))
        return replace(base, white_noise=rms("white"), bias_instability=rms("bias_instability"),
                       bias_instability_tau_s=tau, rate_random_walk=0.0)

    base = _grade_errors(g.base)
    errors = replace(base, gyro=triad(base.gyro, fits["gyro_fit"]), accel=triad(base.accel, fits["accel_fit"]),
                     source=f"Allan fit of {path.name}; base {g.base}")
    params = _datasheet(errors)
    rrw = {"gyro_rrw_deg_h_sqrt_h": [x["rrw_deg_h_sqrt_h"] for x in rep["gyro"]],
           "accel_rrw_ug_sqrt_h": [x["rrw_ug_sqrt_h"] for x in rep["accel"]]}
    notes = list(rep["notes"])
    if any(v is not None for x in rrw.values() for v in x):
        notes.append("a rate random walk was fitted on some axes (rate_random_walk_not_used) but is not simulated: "
                     "the presets have none and the 15-state filter does not model it")
    record = {"name": g.label, "source": "allan", "file": str(path), "format": g.format,
              "window_s": None if g.window_s is None else list(g.window_s),
              "log_duration_s": float(imu.time[-1] - imu.time[0]), "base": g.base, "parameters": params,
              "from_fit": {k: params[k] for k in FROM_FIT}, "rate_random_walk_not_used": rrw,
              "per_axis": {"gyro": rep["gyro"], "accel": rep["accel"]},
              "bias_resolved": all(x["bias_instability_resolved"] for x in rep["gyro"] + rep["accel"]
                                   if not x["constant"]),
              "notes": notes}
    return errors, record


def resolve_grade(g):
    """``(label, full sensor model, grade of the initial uncertainty, record)``
    of a grade of the spec (a preset name, :class:`PresetGrade` or :class:`AllanGrade`)."""
    if isinstance(g, AllanGrade):
        errors, record = allan_grade(g)
        return g.label, errors, g.base, record
    name = grade_label(g)
    errors = _grade_errors(name)
    return name, errors, name, {"name": name, "source": "preset", "parameters": _datasheet(errors),
                                "datasheet": errors.source}


def run_seed(base, case, run) -> int:
    """The seed of run ``run`` of case ``case``: a 64-bit integer from
    ``SeedSequence(base, spawn_key=(case, run))`` (NEP 19)."""
    ss = np.random.SeedSequence(int(base), spawn_key=(int(case), int(run)))
    return int(ss.generate_state(1, np.uint64)[0])


@dataclass
class StudyCase:
    """One case of a study: what every run of it needs (picklable; the
    prepared truth and ideal IMU are rebuilt once per worker process)."""

    index: int
    grade: str
    filter: str
    spec: ConsistencySpec
    outage: tuple[float, float] | None
    lever_arm_b: tuple[float, float, float]
    #: cases with the same key share one prepared truth and ideal IMU per process
    prep_key: str = ""
    #: the grade's parameters and their origin (:func:`resolve_grade`)
    grade_info: dict | None = None

    @property
    def figures(self):
        return OUTAGE_FIGURES if self.outage is not None else CONSISTENCY_FIGURES


#: per process: prep_key -> (trajectory, (t, ideal IMU, truth)), shared by the cases of a study
_PREPARED: dict = {}


def _spec(case: StudyCase) -> ConsistencySpec:
    """The case's spec with the truth and ideal IMU prepared once per process
    for all cases of the study (they differ in sensor and filter only)."""
    hit = _PREPARED.get(case.prep_key)
    if hit is None:
        if len(_PREPARED) >= 4:  # a long-lived worker of many studies
            _PREPARED.clear()
        hit = _PREPARED[case.prep_key] = (case.spec.trajectory, case.spec.prepared())
    # the trajectory too: it integrates its position lazily, once per object
    return replace(case.spec, trajectory=hit[0], _prepared=hit[1])


def _grade_errors(grade):
    from ..simulation.sensors import ImuErrors, preset

    return ImuErrors() if grade == "ideal" else preset(grade)


def _initial(grade):
    return grade_initial_uncertainty("tactical" if grade == "ideal" else grade)


def _scaled(errors, k):
    """The filter's view of a sensor model with its white noise and bias
    instability scaled by ``k`` (filter tuning)."""
    def s(e):
        return replace(e, white_noise=e.white_noise * k, bias_instability=e.bias_instability * k)

    return replace(errors, gyro=s(errors.gyro), accel=s(errors.accel))


def build_cases(spec: StudySpec, scenario_path, key="", source=None) -> list[StudyCase]:
    """The cases of a study, in a fixed order: grades (outer) x filter settings.
    ``key`` names the shared preparation (the study's fingerprint);
    ``source``, the study file, begins the messages of its own fields."""
    def where(key):
        return f"{source}: field '{key}'" if source is not None else key

    from ..simulation.gnss import fix_times
    from ..simulation.scenario import build_trajectory, gnss_errors, load_scenario

    sc = load_scenario(scenario_path)
    if any(sc.imu.lever_arm_b_m):
        raise ConfigError(f"{scenario_path}: imu.lever_arm_b_m must be zero for a study (its truth is the IMU's "
                          f"own trajectory), got {list(sc.imu.lever_arm_b_m)}")
    if any(sc.imu.mount_rpy_deg):
        raise ConfigError(f"{scenario_path}: imu.mount_rpy_deg must be zero for a study (its IMU is simulated in "
                          f"the trajectory's axes), got {list(sc.imu.mount_rpy_deg)}")
    tr = build_trajectory(sc, np.random.default_rng(spec.seed))
    T = tr.duration if spec.duration_s is None else spec.duration_s
    if T > tr.duration:
        raise ConfigError(f"{where('duration_s')} must be within (0, {tr.duration:.0f}] s for {scenario_path.name}, "
                          f"got {spec.duration_s}")
    shortest = min_consistency_duration_s(CONSISTENCY_GNSS)
    if spec.outage is None and T < shortest:  # the consistency figures: NEES at the GNSS updates
        what = (f"{where('duration_s')} must be at least {shortest:g} s, got {spec.duration_s}"
                if spec.duration_s is not None else f"{scenario_path.name} lasts {T:g} s, less than {shortest:g} s")
        raise ConfigError(f"{what}: the consistency figures are taken at the GNSS updates "
                          f"({CONSISTENCY_GNSS.rate_hz:g} Hz), and a run needs one after its start")
    outage = None
    if spec.outage is not None:
        outage = (spec.outage.start_s, spec.outage.start_s + spec.outage.length_s)
        if outage[1] >= T:
            raise ConfigError(f"{where('outage')}: it ends at {outage[1]:g} s, after the end of the study data ({T:g} s)")
        g = gnss_errors(sc)
        if not withheld_mask(fix_times(0.0, T, g), [outage]).any():  # the runs' fixes, known before any run
            raise ConfigError(f"{where('outage')}: {outage[0]:g}..{outage[1]:g} s holds no GNSS fix of "
                              f"{scenario_path.name} (fixes at {g.rate_hz:g} Hz, outside its [gnss] outages_s): it "
                              "withholds nothing; give a longer length_s")
    lever = tuple(float(x) for x in sc.gnss.lever_arm_b_m)
    cases = []
    for grade in spec.grades or [sc.imu.grade]:
        label, full, initial, record = resolve_grade(grade)
        for f in spec.filter:
            model = consistency_errors(full)
            kw = dict(scheme=f.scheme, gate_probability=0.9999 if f.gating else None)
            if outage is not None:  # the full sensor, the scenario's GNSS, forward filter
                sim, g = full, gnss_errors(sc)
                kw["lever_arm_b"] = lever
            else:  # the consistency job's set-up: what the filter models, 1 Hz white GNSS, smoothed NEES
                sim, lever = model, (0.0, 0.0, 0.0)
                g = CONSISTENCY_GNSS
                kw["smoother_node_s"] = 0.0
            settings = matched_settings(_scaled(model, f.noise_scale), _initial(initial), **kw)
            cs = ConsistencySpec(tr, sc.imu.rate_hz, sim, g, settings, spec.duration_s)
            cases.append(StudyCase(len(cases), label, f.name, cs, outage, lever, key, record))
    return cases


def _outage_figures(case: StudyCase, seed):
    from ..integration import GnssPosition, run_filter
    from ..simulation.gnss import simulate_gnss
    from ..simulation.sensors import apply_imu_errors

    spec = _spec(case)
    t, ideal, truth = spec.prepared()
    rng = np.random.default_rng(seed)
    imu, _ = apply_imu_errors(ideal, spec.errors, rng)
    gnss, _ = simulate_gnss(spec.trajectory, t[0], t[-1], spec.gnss_errors, rng)
    use = ~withheld_mask(gnss.time, [case.outage])
    start = perturbed_start(truth.state(0), spec.settings, rng)
    sol = run_filter(imu, start, [GnssPosition(gnss, use, lever_arm_b=case.lever_arm_b)], spec.settings).nav
    k = np.nonzero((t >= case.outage[0]) & (t <= case.outage[1]))[0]
    d = earth.lla_to_ned(sol.lla[k], truth.lla[k])
    h = np.hypot(d[:, 0], d[:, 1])
    att = rot.attitude_error(sol.C_nb[k[-1]], truth.C_nb[k[-1]])
    return {"outage_end_horizontal_m": h[-1], "outage_worst_horizontal_m": h.max(),
            "outage_end_vertical_m": abs(d[-1, 2]),
            "outage_end_velocity_m_s": np.linalg.norm(sol.v_n[k[-1]] - truth.v_n[k[-1]]),
            "outage_end_attitude_deg": np.degrees(np.linalg.norm(att))}


def run_case(case: StudyCase, run: int, base_seed: int) -> dict:
    """One run of a case: its key, seed and figures (one row of ``runs.parquet``)."""
    seed = run_seed(base_seed, case.index, run)
    if case.outage is not None:
        fig = _outage_figures(case, seed)
    else:
        r = run_once(_spec(case), seed)
        fig = {f"nees_{b}_mean": np.mean(r.nees[b]) for b in ("pos", "vel", "att")}
        fig["bias_rms_normalized"] = np.sqrt(np.mean(r.bias_normalized ** 2))
    row = {"case": case.index, "run": int(run), "grade": case.grade, "filter": case.filter, "seed": seed}
    row.update({k: float(v) for k, v in fig.items()})
    return row


def fingerprint(spec: StudySpec, scenario_path) -> str:
    """SHA-256 of the validated spec, the scenario file's bytes and those of
    every Allan grade's log: a resumed study must be the same study."""
    h = hashlib.sha256(json.dumps(spec.model_dump(mode="json"), sort_keys=True).encode())
    h.update(Path(scenario_path).read_bytes())
    for g in spec.grades or []:
        if isinstance(g, AllanGrade):
            h.update(Path(g._log if g._log is not None else g.allan).read_bytes())
    return h.hexdigest()


def _frame(rows, figures):
    import pandas as pd

    df = pd.DataFrame(rows, columns=["case", "run", "grade", "filter", "seed", *figures])
    return df.astype({"case": "int32", "run": "int32", "seed": "uint64", "grade": str, "filter": str,
                      **{f: "float64" for f in figures}})


def read_parts(out_dir):
    """Every row written so far under ``DIR/runs/`` (a DataFrame, sorted by
    ``(case, run)``, duplicates dropped), or None."""
    import pandas as pd

    parts = sorted((Path(out_dir) / "runs").glob("part-*.parquet"))
    if not parts:
        return None
    frames = []
    for p in parts:
        try:
            frames.append(pd.read_parquet(p, **READ_OPTIONS))  # each page's checksum checked
        except Exception as exc:  # a part is written whole or not at all; anything else is damage
            raise InputError(damage_message(p, exc, "delete it to recompute its runs")) from None
    df = pd.concat(frames, ignore_index=True).drop_duplicates(["case", "run"])
    return df.sort_values(["case", "run"], kind="stable").reset_index(drop=True)


def _write_parquet(df, path):
    with atomic_write(path) as tmp:
        df.to_parquet(tmp, index=False, engine="pyarrow", compression="snappy", write_page_checksum=True)
    return Path(path)


def check_cluster_options(scheduler, workers):
    """Refuse, before anything is written, a ``--scheduler`` address that
    names no scheduler (no port, a port outside 1..65535) and ``--workers``
    beside it (an existing cluster has its own)."""
    if scheduler is None:
        return
    if workers is not None:
        raise ConfigError("--workers applies to the local cluster; an existing one (--scheduler) has its own")
    from distributed.comm.addressing import parse_address, parse_host_port

    expected = "expected an address such as tcp://host:8786"
    try:
        scheme, loc = parse_address(str(scheduler))
        host, port = parse_host_port(loc) if scheme in ("tcp", "tls") else (None, None)
    except ValueError as exc:
        why = "its port is not a number" if "invalid literal" in str(exc) else str(exc)
        raise InputError(f"--scheduler {scheduler}: not a scheduler address ({why}); {expected}") from None
    if scheme in ("tcp", "tls") and not (host and 1 <= int(port) <= 65535):
        raise InputError(f"--scheduler {scheduler}: not a scheduler address (" + (
            "no host" if not host else f"port {port} is outside 1..65535") + f"); {expected}")


#: the level of distributed's own logs in a study's local cluster: none.  A run's error reaches the study as its
#: exception (it fails the study, named); what distributed logs is about itself, and on Ctrl-C its workers and
#: scheduler log their lost connections as ERROR and CRITICAL with tracebacks, beside 'inskit: aborted'
_QUIET = 100


def _open_client(scheduler, workers):
    """A distributed client and the cluster it started (or None)."""
    import logging

    from distributed import Client, LocalCluster

    if scheduler is not None:
        check_cluster_options(scheduler, workers)
        try:
            return Client(scheduler, timeout="20s"), None
        except (OSError, TimeoutError, ValueError) as exc:
            raise InputError(f"--scheduler {scheduler}: could not connect ({exc})") from None
    n = (os.cpu_count() or 1) if workers is None else int(workers)
    if n < 1:
        raise ConfigError(f"--workers must be at least 1, got {workers}")
    # Ctrl-C is the study's to handle (the client stops, the parts stay): the worker processes start with SIGINT
    # ignored (a disposition they inherit, and keep: Python installs its KeyboardInterrupt handler only over the
    # default one), else each printed its traceback beside 'inskit: aborted'; and distributed's own error on the
    # interrupted wait (a NameError in its sync's cancel, logged by tornado) is not the user's message either
    import signal
    import threading

    main = threading.current_thread() is threading.main_thread()
    old = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
    try:
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0",
                               silence_logs=_QUIET)
    finally:
        if main:
            signal.signal(signal.SIGINT, old)
    logging.getLogger("tornado.application").setLevel(logging.CRITICAL)
    return Client(cluster), cluster


def statistics(df, figures):
    """One row per case, figure and statistic (``summary.parquet``)."""
    import pandas as pd

    rows = []
    for c, g in df.groupby("case", sort=True):
        for f in figures:
            x = g[f].to_numpy()
            vals = {"count": float(len(x)), "mean": x.mean(), "std": x.std(ddof=1) if len(x) > 1 else 0.0,
                    "min": x.min(), "median": np.median(x), "p90": np.percentile(x, 90), "max": x.max()}
            for s in STATISTICS:
                rows.append({"case": int(c), "grade": g["grade"].iloc[0], "filter": g["filter"].iloc[0],
                             "figure": f, "statistic": s, "value": float(vals[s])})
    out = pd.DataFrame(rows)
    return out.astype({"case": "int32", "value": "float64"})


def ranking(df, cases):
    """Cases ranked: by the median horizontal error at the end of the outage
    (outage studies), or by how far the ANEES of position, velocity and
    attitude are from their dimension 3 (``mean |ln(ANEES / 3)|``)."""
    out = []
    for c in cases:
        g = df[df["case"] == c.index]
        e = {"case": c.index, "grade": c.grade, "filter": c.filter, "runs": int(len(g))}
        if c.outage is not None:
            x = g["outage_end_horizontal_m"].to_numpy()
            e.update(metric="outage_end_horizontal_m", median=float(np.median(x)), p90=float(np.percentile(x, 90)),
                     min=float(x.min()), max=float(x.max()),
                     worst_inside_median=float(np.median(g["outage_worst_horizontal_m"])))
            e["score"] = e["median"]
        else:
            lo, hi = anees_band(len(g), 3)
            a = {b: float(g[f"nees_{b}_mean"].mean()) for b in ("pos", "vel", "att")}
            e.update(metric="anees", anees=a, band_95_per_epoch=[lo, hi],
                     bias_rms_normalized=float(np.sqrt(np.mean(g["bias_rms_normalized"] ** 2))))
            e["score"] = float(np.mean([abs(np.log(v / 3.0)) for v in a.values()]))
        out.append(e)
    out.sort(key=lambda e: (e["score"], e["case"]))
    for i, e in enumerate(out, 1):
        e["rank"] = i
    return out


def _plot(df, cases, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    outage = cases[0].outage is not None
    fig_name = "outage_end_horizontal_m" if outage else "nees_pos_mean"
    fig, ax = plt.subplots(figsize=(max(5.0, 1.3 * len(cases) + 2), 4.2))
    data = [df.loc[df["case"] == c.index, fig_name].to_numpy() for c in cases]
    pos = np.arange(1, len(cases) + 1)
    ax.boxplot(data, positions=pos, whis=(0, 100), widths=0.5, showfliers=False)  # whiskers: min to max
    rng = np.random.default_rng(0)
    for p, x in zip(pos, data):
        ax.plot(p + rng.uniform(-0.18, 0.18, len(x)), x, ".", ms=3, alpha=0.5, color="C0")
        ax.plot(p, np.percentile(x, 90), "v", color="C3", ms=7)
    ax.set_xticks(pos, [c.grade if len({k.filter for k in cases}) == 1 else f"{c.grade}\n{c.filter}"
                        for c in cases], fontsize=8)
    if outage:
        a, b = cases[0].outage
        ax.set_ylabel(f"horizontal error at the end of the {b - a:g} s outage [m]")
        if all(len(x) and x.min() > 0 for x in data) and max(x.max() for x in data) > 30 * min(x.min() for x in data):
            ax.set_yscale("log")
    else:
        ax.set_ylabel("run-mean NEES of position (3 = consistent)")
        ax.axhline(3.0, color="k", lw=0.8, ls="--")
    ax.set_title(f"{len(data[0])} runs per case; dots: runs, box: quartiles, whiskers: min-max, red: 90 %",
                 fontsize=8)
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path)


class _CtrlC:
    """Ctrl-C (SIGINT) while the study's client runs: the handler only
    notes it, and :meth:`check` raises the ``KeyboardInterrupt`` in
    :func:`run_study`'s own frame, between two requests to the scheduler; a
    second Ctrl-C raises at once, wherever the program is.  Not in the main
    thread, or with SIGINT not Python's default handler (ignored: a run
    started in the background; the caller's own), nothing changes.

    Python's own handler raises in whatever Python code the main thread
    runs, which lost a Ctrl-C two ways (each failed the Ctrl-C test now and
    then):

    * inside the client's wait for the scatter of the cases, which the
      scheduler serves in two steps: to the workers (each unpickles the
      cases, importing inskit: 1 to 4 s on a busy machine), then replicated
      to every running worker.  The study closed the cluster at once; the
      scheduler, still serving the request, found no running worker ('Can
      not use replicate to delete data', or a KeyError of the worker
      removed meanwhile) and, its client's connection closed, re-raised
      into a task nobody awaited: asyncio printed 'Task exception was never
      retrieved' and the traceback beside 'inskit: aborted';
    * inside a gc callback (distributed's GC diagnosis runs one in the main
      thread), where an exception is 'ignored': printed with a traceback and
      dropped, and the study ran on to its end.

    Noted instead, the interrupt takes effect when the scatter has returned
    or at the next poll of the runs (:data:`_POLL_S`).
    """

    def __init__(self):
        self.pressed = 0
        self._active = False

    def __enter__(self):
        import signal
        import threading

        self._active = (threading.current_thread() is threading.main_thread()
                        and signal.getsignal(signal.SIGINT) is signal.default_int_handler)
        if self._active:
            signal.signal(signal.SIGINT, self._note)
        return self

    def _note(self, signum, frame):
        self.pressed += 1
        if self.pressed > 1:  # asked twice: at once
            raise KeyboardInterrupt

    def check(self):
        """Raise ``KeyboardInterrupt`` if Ctrl-C was pressed."""
        if self.pressed:
            raise KeyboardInterrupt

    def __exit__(self, *exc):
        if self._active:
            import signal

            signal.signal(signal.SIGINT, signal.default_int_handler)
        return False


#: how often the study looks for finished runs and a noted Ctrl-C while it waits [s]: a result waits at most
#: this long to be written, so parts stay as small as when the loop blocked in ``as_completed``
_POLL_S = 0.02


def run_study(spec_path, out_dir, *, scheduler=None, workers=None, progress=None, log=None, force=False) -> dict:
    """Run (or resume) a study on a Dask cluster and write its results.

    Parameters
    ----------
    spec_path : path
        The study TOML (:class:`StudySpec`).
    out_dir : path
        Results folder: ``study.json`` (the spec's fingerprint), ``runs/part-*.parquet``
        (as runs complete), then ``runs.parquet``, ``summary.parquet``,
        ``summary.json`` and ``study.png``.  If it already holds parts of the
        same study, only the missing ``(case, run)`` are computed.
    scheduler : str, optional
        Address of an existing scheduler (``tcp://host:8786``); default a
        ``LocalCluster`` of ``workers`` single-threaded processes.
    workers : int, optional
        Local cluster size (default: every core).
    progress : callable(total, done_before) -> callable(n), optional
        Makes the progress callback, called with the number of runs just
        written (after their part file is in place).  An exception it raises
        stops the study as a killed client would (the parts stay).
    log : callable(str), optional
    force : bool, optional
        Write into a folder that is not a study's (no ``study.json``) even
        when it holds files of the study's names (:data:`OUTPUT_FILES`: the
        results of another command, or the user's); without it that is an
        :class:`~inskit.errors.InputError` before any run.  A study folder
        (the same study) is resumed and its own results rewritten either way.

    Returns
    -------
    dict
        ``ranking``, ``files``, ``runs_total``, ``runs_computed``,
        ``runs_reused``, ``seconds`` and the cluster used (also in ``summary.json``).
    """
    log = log or (lambda s: None)
    t_start = time.perf_counter()
    spec, scenario_path = load_spec(spec_path)
    check_cluster_options(scheduler, workers)
    out = check_folder_writable(out_dir)
    fp = fingerprint(spec, scenario_path)
    cases = build_cases(spec, scenario_path, fp, source=spec_path)  # every config error before anything is written
    grades = list({c.grade: c.grade_info for c in cases}.values())
    for r in grades:
        if r["source"] == "allan":
            log(f"study: grade {r['name']!r}: {_fit_line(r)}")
            for n in r["notes"]:
                log(f"study: grade {r['name']!r}: note: {n}")
    meta_path = out / "study.json"
    inputs = [spec_path, scenario_path] + [g._log for g in spec.grades or [] if isinstance(g, AllanGrade)]
    # never over an input; over another command's (or the user's) files of these names only with --force
    check_outputs([meta_path] + [out / n for n in OUTPUT_FILES], inputs, overwrite=True)
    theirs = [n for n in OUTPUT_FILES if (out / n).exists()]
    if theirs and not meta_path.is_file() and not force:
        raise InputError(f"{out}: holds {', '.join(theirs)} but no study.json: not the folder of a study (another "
                         "command's results?); refusing to overwrite them (use --force or another --out)")
    runs_dir = out / "runs"
    if runs_dir.exists() and not runs_dir.is_dir():  # before anything is written (study.json was, then Errno 17)
        raise InputError(f"{runs_dir}: is a file; a study keeps its run parts in a folder of that name (use another "
                         "--out)")
    if meta_path.is_file():
        try:
            meta = json.loads(meta_path.read_text())
        except (OSError, ValueError):
            meta = None
        if not isinstance(meta, dict):  # unreadable, or JSON of another shape ([1, 2] was an internal error)
            raise InputError(f"{meta_path}: unreadable; it is not a study folder of inskit")
        old = meta.get("fingerprint")
        if old != fp:
            raise ConfigError(f"{out}: holds the results of a different study (the spec or its scenario changed); "
                              "use another --out, or delete the folder to start over")
    elif (out / "runs").is_dir() and any((out / "runs").glob("part-*.parquet")):
        raise ConfigError(f"{out}: has run parts but no study.json; use another --out")
    else:
        write_text(meta_path, json.dumps({"fingerprint": fp, "spec": spec.model_dump(mode="json"),
                                          "scenario": str(scenario_path)}, indent=1) + "\n")
    runs_dir.mkdir(exist_ok=True)
    figures = cases[0].figures
    prev = read_parts(out)
    done = set() if prev is None else set(zip(prev["case"].tolist(), prev["run"].tolist()))
    todo = [(c.index, r) for c in cases for r in range(spec.runs) if (c.index, r) not in done]
    total = len(cases) * spec.runs
    log(f"study: {len(cases)} case(s) x {spec.runs} runs = {total}; {total - len(todo)} already in {out}, "
        f"{len(todo)} to run")
    cluster_info = {}
    t_cluster = t_runs = 0.0
    if todo:
        from distributed import as_completed

        t0 = time.perf_counter()
        client, cluster = _open_client(scheduler, workers)
        try:
            with _CtrlC() as ctrl_c:  # a Ctrl-C is raised here, between requests (_CtrlC says why)
                nworkers = len(client.scheduler_info(n_workers=-1)["workers"])
                cluster_info = {"scheduler": scheduler or "local", "workers": nworkers}
                t_cluster = time.perf_counter() - t0
                log(f"study: {'cluster at ' + scheduler if scheduler else 'local cluster'}: {nworkers} worker(s) "
                    f"({t_cluster:.1f} s to start)")
                t1 = time.perf_counter()
                shipped = client.scatter(cases, broadcast=True)
                ctrl_c.check()
                futures = [client.submit(run_case, shipped[c], r, spec.seed, key=f"inskit-study-{fp[:16]}-{c}-{r}",
                                         pure=False) for c, r in todo]
                bar = progress(total, total - len(todo)) if progress else None
                seq = 0
                try:
                    done_runs = as_completed(futures, with_results=True)
                    while not done_runs.is_empty():
                        ctrl_c.check()
                        batch = done_runs.next_batch(block=False)
                        if not batch:
                            time.sleep(_POLL_S)
                            continue
                        for future, res in batch:
                            if future.status == "error":  # a run that failed: its exception, as the run raised it
                                raise res[1].with_traceback(res[2])
                        rows = [res for _, res in batch]
                        name = f"part-{time.time_ns():020d}-{os.getpid()}-{seq:06d}.parquet"
                        seq += 1
                        _write_parquet(_frame(rows, figures), out / "runs" / name)
                        if bar:
                            bar(len(rows))
                    ctrl_c.check()
                finally:
                    client.cancel(futures)
                t_runs = time.perf_counter() - t1
        finally:
            if cluster is not None:  # its shutdown after an interrupt ('Removing worker ... lost scattered data')
                import logging       # is not the user's message: 'inskit: aborted' is

                logging.getLogger("distributed").setLevel(_QUIET)
            client.close()
            if cluster is not None:
                cluster.close()
    df = read_parts(out)
    if df is None or len(df) != total:
        raise InputError(f"{out}: expected {total} runs after the study, found {0 if df is None else len(df)}")
    df = _frame(df.to_dict("records"), figures)  # one dtype set whatever the parts held
    files = {"runs": out / "runs.parquet", "summary": out / "summary.parquet", "plot": out / "study.png"}
    rank = ranking(df, cases)
    res = {"study": str(Path(spec_path)), "kind": spec.kind, "scenario": str(scenario_path),
           "duration_s": spec.duration_s, "seed": spec.seed, "runs_per_case": spec.runs,
           "outage_s": list(cases[0].outage) if cases[0].outage else None, "ranking": rank, "grades": grades,
           "runs_total": total, "runs_computed": len(todo), "runs_reused": total - len(todo),
           "execution": {**cluster_info, "cluster_start_s": t_cluster, "runs_s": t_runs,
                         "seconds": time.perf_counter() - t_start},
           "files": {k: str(v) for k, v in files.items()}}
    files["json"] = out / "summary.json"
    res["files"]["json"] = str(files["json"])
    # and what the study wrote before its results: its fingerprint (the resume's key) and the run parts
    res["files"]["study"] = str(meta_path)
    res["files"]["run_parts"] = sorted(str(p) for p in (out / "runs").glob("part-*.parquet"))
    # the four result files whole or none, as a set: a plot that failed (or Ctrl-C) left runs.parquet and
    # summary.parquet of this run beside no summary.json, or beside the one of an earlier run
    with staged_files(out) as stage:
        _write_parquet(df, stage(files["runs"]))
        _write_parquet(statistics(df, figures), stage(files["summary"]))
        _plot(df, cases, stage(files["plot"]))
        write_json(stage(files["json"]), res)
    return res


def _fit_line(r) -> str:
    """One line of an Allan grade's fitted parameters."""
    p = r["from_fit"]
    return (f"Allan fit of {Path(r['file']).name} ({r['log_duration_s']:.0f} s): ARW {p['gyro_arw_deg_sqrt_h']:.4g} "
            f"deg/rt(h), gyro BI {p['gyro_bias_instability_deg_h']:.4g} deg/h (tau {p['gyro_bias_tau_s']:.3g} s), "
            f"VRW {p['accel_vrw_ug_sqrt_hz']:.4g} ug/rt(Hz), accel BI {p['accel_bias_instability_ug']:.4g} ug "
            f"(tau {p['accel_bias_tau_s']:.3g} s); turn-on bias, scale factor from {r['base']!r}"
            + ("" if r["bias_resolved"] else "; bias instability unresolved on some axes (upper bound)"))


def ranking_table(res) -> str:
    """The ranking as a text table."""
    rank = res["ranking"]
    if rank and rank[0]["metric"] == "outage_end_horizontal_m":
        a, b = res["outage_s"]
        lines = [f"horizontal error at the end of the {b - a:g} s outage ({a:g}-{b:g} s), over the runs of each case",
                 f"{'rank':>4}  {'grade':<16}{'filter':<12}{'runs':>6}{'median m':>11}{'90 % m':>11}{'max m':>11}"]
        for e in rank:
            lines.append(f"{e['rank']:>4}  {e['grade']:<16}{e['filter']:<12}{e['runs']:>6}{e['median']:>11.3f}"
                         f"{e['p90']:>11.3f}{e['max']:>11.3f}")
    else:
        lines = ["ANEES (3 = consistent) of position, velocity, attitude, over the runs of each case",
                 f"{'rank':>4}  {'grade':<16}{'filter':<12}{'runs':>6}{'pos':>8}{'vel':>8}{'att':>8}  band (1 epoch)"]
        for e in rank:
            a = e["anees"]
            lines.append(f"{e['rank']:>4}  {e['grade']:<16}{e['filter']:<12}{e['runs']:>6}{a['pos']:>8.2f}"
                         f"{a['vel']:>8.2f}{a['att']:>8.2f}  [{e['band_95_per_epoch'][0]:.2f}, "
                         f"{e['band_95_per_epoch'][1]:.2f}]")
    lines += [f"grade {r['name']!r}: {_fit_line(r)}" for r in res.get("grades", []) if r["source"] == "allan"]
    lines.append(f"runs: {res['runs_total']} ({res['runs_computed']} computed, {res['runs_reused']} reused); "
                 f"{res['execution']['seconds']:.1f} s; files: "
                 f"{', '.join(v for k, v in res['files'].items() if k != 'run_parts')} and "
                 f"{len(res['files'].get('run_parts', []))} run parts")
    return "\n".join(lines)
