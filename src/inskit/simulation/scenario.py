"""Scenario files (TOML) and the ``inskit simulate`` job.

A scenario names a start, an IMU (rate, grade preset, overrides), a GNSS
receiver model, optional vibration and a list of ``[[segment]]`` tables; see
``examples/*.toml``.  Units at this edge are degrees, deg/s, micro-g and the
like; everything is converted to SI here.

An optional ``[raw_gnss]`` table adds raw GNSS observations (pseudorange,
carrier phase, Doppler, C/N0 of a synthetic or real constellation,
:mod:`.gnss_raw`) on a GPS time scale; the simulate job then writes them as
RINEX 3 files and puts every CSV time column on GPS seconds of week.
"""

from __future__ import annotations

import typing
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, ValidationError, field_validator, model_validator

from ..config_files import (ANGLE_LIMIT_DEG, MASK_RANGE_DEG, check_angles, check_height, check_longitude, check_magnitude,
                            check_mask, check_scalar_type, read_toml, validation_message)
from ..errors import ConfigError
from ..types import GnssData, ImuData, NavSolution
from ..units import DEG, MAX_RATE_HZ, MAX_SAMPLES
from .gnss import GnssErrors, simulate_gnss
from .imu import INCREMENT_TOLERANCE, ideal_imu, max_oscillation_hz, truth_solution
from .segments import SegmentTrajectory
from .sensors import ImuErrors, apply_imu_errors, preset, triad_terms_problem


class _S(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    _magnitude = field_validator("*")(check_magnitude)
    _kinds = field_validator("*", mode="before")(classmethod(check_scalar_type))


class StartSpec(_S):
    lat_deg: float = Field(..., ge=-90, le=90)
    lon_deg: float
    height_m: float = 0.0
    yaw_deg: float = 0.0
    speed_m_s: float = Field(0.0, ge=0)
    transition_s: float = Field(2.0, gt=0)
    _angles = field_validator("yaw_deg")(check_angles)
    _longitude = field_validator("lon_deg")(check_longitude)
    _height = field_validator("height_m")(check_height)


class ImuSpec(_S):
    rate_hz: float = Field(100.0, gt=0, le=MAX_RATE_HZ)
    grade: Literal["ideal", "navigation", "tactical", "industrial-mems", "consumer-mems"] = "ideal"
    gyro: dict = Field(default_factory=dict, description="datasheet-unit overrides of the gyro preset (keys and "
                       "units: the rules above)")
    accel: dict = Field(default_factory=dict, description="datasheet-unit overrides of the accel preset (keys and "
                        "units: the rules above)")
    quadrature_nodes: int = Field(3, ge=1, le=12)
    lever_arm_b_m: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0), description="IMU position from the trajectory (truth) point, body axes")
    mount_rpy_deg: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0), description="mounting of the IMU in the vehicle, in the convention of navigate's "
        "[imu] mount_rpy_deg (the same numbers there rotate the readings back into vehicle axes); the truth file "
        "keeps the vehicle's attitude")
    _angles = field_validator("mount_rpy_deg")(check_angles)

    @field_validator("gyro", "accel")
    @classmethod
    def _terms(cls, v, info):
        """Each override a term of the sensor with a value it takes (:data:`.sensors.TRIAD_TERMS`): a
        negative sigma, ``bias_instability_tau_s = 0`` (a ZeroDivisionError), ``fixed_bias = [1, 2]``
        (numpy's broadcast error) and an accelerometer's ``g_sensitivity`` (ignored) were let through."""
        problem = triad_terms_problem(info.field_name, v)
        if problem:
            raise ValueError(problem)
        return v

    @model_validator(mode="after")
    def _overrides_need_a_grade(self):
        if self.grade == "ideal" and (self.gyro or self.accel):
            raise ValueError("gyro and accel override the terms of a grade preset; an 'ideal' IMU has none: give a "
                             "grade (e.g. grade = \"tactical\") or drop the overrides")
        return self


class GnssSpec(_S):
    rate_hz: float = Field(1.0, gt=0, le=100)
    white_h_m: float = Field(1.0, ge=0)
    white_v_m: float = Field(2.0, ge=0)
    correlated_h_m: float = Field(0.0, ge=0)
    correlated_v_m: float = Field(0.0, ge=0)
    correlation_time_s: float = Field(60.0, gt=0)
    velocity_sigma_m_s: float = Field(0.05, ge=0)
    lever_arm_b_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    latency_s: float = Field(0.0, ge=0)
    outages_s: list[tuple[float, float]] = Field(default_factory=list)
    outlier_probability: float = Field(0.0, ge=0, le=1)
    outlier_sigma_m: float = Field(30.0, ge=0)

    @field_validator("outages_s")
    @classmethod
    def _windows(cls, v):
        for k, (a, b) in enumerate(v, start=1):
            if not b > a:
                what = "is empty (it ends where it starts)" if b == a else "ends before it starts"
                raise ValueError(f"window {k} [{a:g}, {b:g}] {what}; give [start, end] with end > start")
            if a < 0:
                raise ValueError(f"window {k} [{a:g}, {b:g}] starts before the scenario (time 0)")
        return v


class VibrationSpec(_S):
    target: Literal["roll", "pitch", "yaw", "down"]
    amplitude: float = Field(..., description="deg for attitude, m for 'down'")
    frequency_hz: float | None = Field(None, gt=0)
    kind: Literal["sinusoidal", "random"] = "sinusoidal"
    band_hz: tuple[float, float] | None = None

    def top_hz(self):
        """``(the highest frequency of the vibration [Hz], the key that sets it)``."""
        if self.kind == "random" and self.band_hz is not None:
            return self.band_hz[1], "band_hz"
        return (1.5 if self.kind == "random" else 1.0) * self.frequency_hz, "frequency_hz"


class SegmentSpec(_S):
    type: Literal["static", "accelerate", "decelerate", "cruise", "turn", "banked-turn", "climb", "descend",
                  "pitch", "roll", "coning", "figure-eight"]
    duration_s: float | None = Field(None, gt=0)
    speed_m_s: float | None = Field(None, ge=0)
    angle_deg: float | None = None
    rate_deg_s: float | None = Field(None, gt=0)
    radius_m: float | None = Field(None, gt=0)
    amplitude_deg: float | None = None
    frequency_hz: float | None = Field(None, gt=0)
    repeat: int = Field(1, ge=1)
    _angles = field_validator("amplitude_deg")(check_angles)  # angle_deg of a turn may be more than a turn


@dataclass(frozen=True)
class SegmentRule:
    """The keys one segment type takes: all of ``needs`` and exactly one of
    ``one_of`` (besides ``type`` and ``repeat``, which every segment takes)."""

    needs: tuple[str, ...]
    one_of: tuple[str, ...] = ()
    note: str = ""

    @property
    def keys(self) -> tuple[str, ...]:
        return self.needs + self.one_of

    def takes(self) -> str:
        """The keys in words: ``angle_deg and one of rate_deg_s, radius_m``."""
        parts = [", ".join(self.needs)] if self.needs else []
        if self.one_of:
            parts.append("one of " + ", ".join(self.one_of))
        return " and ".join(parts)


_TURN = SegmentRule(("angle_deg",), ("rate_deg_s", "radius_m"),
                    note="its length follows from the angle and the rate, or the radius and the speed")
_CLIMB = SegmentRule(("angle_deg", "duration_s"), note="|angle_deg| < 90")

#: The keys of each segment type: the one table that :func:`check_segment` and the
#: generated docs/config.md read.  A key outside its type's rule would be ignored, so it is
#: refused; ``type`` and ``repeat`` (:data:`SEGMENT_COMMON_KEYS`) go with every type.
SEGMENT_RULES: dict[str, SegmentRule] = {
    "static": SegmentRule(("duration_s",)),
    "accelerate": SegmentRule(("speed_m_s", "duration_s"), note="to a speed above the current one"),
    "decelerate": SegmentRule(("speed_m_s", "duration_s"), note="to a speed below the current one"),
    "cruise": SegmentRule(("duration_s",)),
    "turn": _TURN,
    "banked-turn": _TURN,
    "climb": _CLIMB,
    "descend": _CLIMB,
    "pitch": SegmentRule(("amplitude_deg", "duration_s")),
    "roll": SegmentRule(("amplitude_deg", "duration_s")),
    "coning": SegmentRule(("amplitude_deg", "frequency_hz", "duration_s"),
                          note="frequency_hz below the IMU's Nyquist frequency"),
    "figure-eight": SegmentRule(("radius_m",), note="two full turns: its length follows from the radius and the "
                                "speed"),
}
SEGMENT_COMMON_KEYS = ("type", "repeat")


def segment_keys_text() -> str:
    """The types and their keys in words (types with the same keys together), for docs/config.md."""
    groups: dict[SegmentRule, list[str]] = {}
    for t, rule in SEGMENT_RULES.items():
        groups.setdefault(SegmentRule(rule.needs, rule.one_of), []).append(t)
    return "; ".join(f"{', '.join(ts)} ({rule.takes()})" for rule, ts in groups.items())


#: Default start of raw GNSS scenarios: GPS week 2374, 243240 s of week = Tuesday
#: 2025-07-08 19:34:00 GPS time (the day of the rtklibexplorer drive_0708 log).
RAW_GNSS_DEFAULT_WEEK = 2374
RAW_GNSS_DEFAULT_SOW_S = 243240.0
#: GPS - UTC [s] since 2017-01-01 (IERS Bulletin C 52; no leap second announced since).
_GPS_MINUS_UTC_S = 18.0
_GPS_MINUS_UTC_SINCE = datetime(2017, 1, 1)


class BlockageSpec(_S):
    start_s: float = Field(..., ge=0, description="window start [s of scenario time]")
    end_s: float = Field(..., gt=0, description="window end [s of scenario time]")
    keep: int = Field(0, ge=0, le=99, description="satellites left in view: the highest above the mask")
    sats: list[str] = Field(default_factory=list,
                            description="satellites left in view (those above the mask), instead of `keep`")

    @model_validator(mode="after")
    def _order(self):
        if not self.end_s > self.start_s:
            raise ValueError(f"end_s ({self.end_s}) must come after start_s ({self.start_s})")
        if self.sats and "keep" in self.model_fields_set:  # the named satellites won: keep was ignored
            raise ValueError(f"give keep or sats, not both (keep = {self.keep} would be ignored: sats names the "
                             "satellites left in view)")
        return self


class RawGnssSection(_S):
    enabled: bool = Field(True, description="simulate raw observations")
    start_utc: str | None = Field(None, description="ISO date-time (UTC) of scenario time 0, from 2017-01-01")
    start_gps_week: int | None = Field(None, ge=0, description="GPS week of scenario time 0 (with start_sow_s)")
    start_sow_s: float | None = Field(None, ge=0, lt=604800, description="GPS seconds of week of scenario time 0")
    rate_hz: float = Field(1.0, gt=0, le=100, description="observation rate [Hz]")
    constellation: str = Field("walker-gps", description="'walker-gps', 'walker-galileo', 'walker-gps+galileo' "
                               "or 'nav:PATH' (a RINEX navigation file, relative to the scenario file)")
    mask_deg: float = Field(10.0, ge=MASK_RANGE_DEG[0], lt=MASK_RANGE_DEG[1], description="elevation mask [deg]")
    code_sigma_m: float = Field(0.5, ge=0, description="zenith white code noise [m] (/ sin el)")
    phase_sigma_m: float = Field(0.003, ge=0, description="zenith white phase noise [m] (/ sin el)")
    doppler_sigma_m_s: float = Field(0.05, ge=0, description="zenith white Doppler noise [m/s] (/ sin el)")
    multipath_sigma_m: float = Field(0.3, ge=0, description="zenith code multipath sigma [m] (/ sin el)")
    multipath_tau_s: float = Field(30.0, gt=0, description="multipath correlation time [s]")
    clock_bias_us: float = Field(100.0, description="initial receiver clock offset [us]")
    clock_drift_ppm: float = Field(0.1, description="initial receiver clock drift [ppm = 1e-6 s/s]")
    clock_h0: float = Field(2e-19, ge=0, description="white frequency noise h0 [s] (TCXO default)")
    clock_h_2: float = Field(2e-20, ge=0, description="random-walk frequency noise h_-2 [1/s] (TCXO default)")
    clock_jumps: bool = Field(False, description="keep |offset| <= 0.5 ms by whole-millisecond clock steps")
    iono_scale: float = Field(1.0, ge=0, description="factor on the Klobuchar delay (1: the broadcast model)")
    iono_alpha: tuple[float, float, float, float] | None = Field(
        None, description="Klobuchar alpha [s, s/sc, s/sc^2, s/sc^3]; default the nav file's or RTKLIB's")
    iono_beta: tuple[float, float, float, float] | None = Field(
        None, description="Klobuchar beta [s, s/sc, s/sc^2, s/sc^3]; default the nav file's or RTKLIB's")
    troposphere: bool = Field(True, description="Saastamoinen tropospheric delay")
    dual_frequency: bool = Field(False, description="add GPS L2 P(Y) (C2W...) and Galileo E5b (C7Q...)")
    cn0_zenith_dbhz: float = Field(48.0, gt=0, description="C/N0 at zenith [dB-Hz]")
    cn0_horizon_dbhz: float = Field(34.0, gt=0, description="C/N0 at the horizon [dB-Hz]")
    blockage: list[BlockageSpec] = Field(default_factory=list, description="blockage windows")
    _mask = field_validator("mask_deg", mode="before")(check_mask)

    @model_validator(mode="after")
    def _start(self):
        if self.start_utc is not None and (self.start_gps_week is not None or self.start_sow_s is not None):
            raise ValueError("give start_utc or start_gps_week + start_sow_s, not both")
        if (self.start_gps_week is None) != (self.start_sow_s is None):
            raise ValueError("start_gps_week and start_sow_s go together")
        if self.cn0_horizon_dbhz > self.cn0_zenith_dbhz:
            raise ValueError(f"cn0_horizon_dbhz ({self.cn0_horizon_dbhz:g}) is above cn0_zenith_dbhz "
                             f"({self.cn0_zenith_dbhz:g}): a signal is strongest at the zenith (swapped?)")
        if not (self.constellation in ("walker-gps", "walker-galileo", "walker-gps+galileo")
                or self.constellation.startswith("nav:")):
            raise ValueError(f"constellation {self.constellation!r}: use 'walker-gps', 'walker-galileo', "
                             "'walker-gps+galileo' or 'nav:PATH'")
        return self


class EarthSpec(_S):
    """The Earth model of the simulated specific force."""

    gravity: Literal["normal", "normal-simple", "j2"] = Field(
        "normal", description="gravity model of the simulated specific force (the truth): normal (WGS84 "
        "Somigliana with the first- and second-order height terms and the north component), normal-simple "
        "(Somigliana with the first-order height term, no north component) or j2 (GM + J2 gravitation plus "
        "centrifugal); navigate and mechanize the data with the same model to reproduce the truth")


class Scenario(_S):
    name: str
    description: str = ""
    duration_limit_s: float | None = Field(None, gt=0)
    start: StartSpec
    imu: ImuSpec = ImuSpec()
    gnss: GnssSpec = GnssSpec()
    raw_gnss: RawGnssSection | None = None
    vibration: list[VibrationSpec] = Field(default_factory=list)
    segment: list[SegmentSpec]
    earth: EarthSpec = Field(EarthSpec(), description="Earth model (gravity) of the simulation")
    #: the file the scenario was read from (:func:`load_scenario`): the start of its error messages
    _source: str | None = PrivateAttr(None)


_SEGMENT_TYPES = typing.get_args(SegmentSpec.model_fields["type"].annotation)
assert set(SEGMENT_RULES) == set(_SEGMENT_TYPES), "SEGMENT_RULES must cover every segment type"
assert all(k in SegmentSpec.model_fields for r in SEGMENT_RULES.values() for k in r.keys + SEGMENT_COMMON_KEYS)


def load_scenario(path, *, imu_rate_hz=None) -> Scenario:
    """Read and validate a scenario file (a ``nav:PATH`` constellation is
    resolved relative to the file's folder).  ``imu_rate_hz`` replaces the
    file's ``[imu] rate_hz`` before the checks that depend on it (a
    vibration above the Nyquist frequency): a command that samples the
    scenario at its own rate (``inskit gyrofree simulate --rate``)."""
    data = read_toml(path, "scenario")
    if imu_rate_hz is not None and isinstance(data.get("imu", {}), dict):  # an [imu] of another shape: refused below
        data["imu"] = {**data.get("imu", {}), "rate_hz": float(imu_rate_hz)}
    try:
        sc = Scenario.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(validation_message(path, exc, Scenario)) from None
    sc._source = str(path)
    check_scenario(sc)
    raw = sc.raw_gnss
    if raw is not None and raw.constellation.startswith("nav:"):
        nav = Path(raw.constellation[4:]).expanduser()
        if not nav.is_absolute():
            nav = Path(path).resolve().parent / nav
        raw.constellation = f"nav:{nav}"
    return sc


def _where(sc: Scenario) -> str:
    return f"{sc._source}: " if sc._source else ""


def check_segment(seg: SegmentSpec, i: int, imu: ImuSpec, where: str = "") -> None:
    """Refuse a ``[[segment]]`` (number ``i``, from 1) that gives a key its
    type would ignore, lacks one it needs, gives both of a pair it takes one
    of (:data:`SEGMENT_RULES`), or asks what its type cannot do: a climb or
    descent at ``|angle_deg| >= 90`` (straight up, then backwards and upside
    down), coning faster than the IMU samples (:func:`check_frequency`).
    ``where`` begins the messages (the file)."""
    t = seg.type
    rule = SEGMENT_RULES[t]
    name = f"{where}segment {i} ({t})"
    takes = f"a {t} segment takes {rule.takes()} and repeat" + (f" ({rule.note})" if rule.note else "")
    given = [k for k in SegmentSpec.model_fields if k in seg.model_fields_set and getattr(seg, k) is not None]
    extra = [k for k in given if k not in rule.keys + SEGMENT_COMMON_KEYS]
    if extra:
        keys = ", ".join(extra)
        verb = "is not a key" if len(extra) == 1 else "are not keys"
        it = "it" if len(extra) == 1 else "they"
        raise ConfigError(f"{name}: {keys} {verb} of a {t} segment ({it} would be ignored); {takes}")
    for k in rule.needs:
        if getattr(seg, k) is None:
            raise ConfigError(f"{name} needs {k}; {takes}")
    if rule.one_of:
        chosen = [k for k in rule.one_of if getattr(seg, k) is not None]
        if not chosen:
            raise ConfigError(f"{name} needs {' or '.join(rule.one_of)}; {takes}")
        if len(chosen) > 1:
            got = " and ".join(f"{k} {getattr(seg, k):g}" for k in chosen)
            raise ConfigError(f"{name}: give {' or '.join(chosen)}, not both (got {got}); one of them sets the "
                              "other, so the second would be ignored")
    if t in ("climb", "descend") and not abs(seg.angle_deg) < 90.0:
        raise ConfigError(f"{name}: angle_deg {seg.angle_deg:g} is no flight-path angle: |angle_deg| must be "
                          f"below 90 (at 90 the vehicle flies straight up, beyond it backwards and upside down); "
                          f"{t} goes {'up' if t == 'climb' else 'down'} by the angle's size")
    if t == "coning":
        check_frequency(seg.frequency_hz, imu, name, f"frequency_hz {seg.frequency_hz:g} Hz")


def check_frequency(f_hz: float, imu: ImuSpec, name: str, what: str) -> None:
    """Refuse a motion at ``f_hz`` (``what`` of ``name``, in words) that the IMU of
    ``[imu]`` cannot sample: at or above its Nyquist frequency ``rate_hz /
    2``, or above the frequency its quadrature integrates to
    :data:`.imu.INCREMENT_TOLERANCE` (with fewer than 3 nodes); see
    :func:`.imu.max_oscillation_hz` for why the limit sits there."""
    limit, inclusive, reason = max_oscillation_hz(imu.rate_hz, imu.quadrature_nodes)
    if f_hz < limit or (inclusive and f_hz <= limit):
        return
    if reason == "nyquist":
        raise ConfigError(f"{name}: {what} is at or above the Nyquist frequency of the IMU ({limit:g} Hz "
                          f"at imu.rate_hz {imu.rate_hz:g}): its increments would alias and not reproduce the "
                          f"motion; keep it below {limit:g} Hz or raise imu.rate_hz")
    raise ConfigError(f"{name}: {what} is above the {limit:.3g} Hz up to which imu.quadrature_nodes "
                      f"{imu.quadrature_nodes} integrate the increments at imu.rate_hz {imu.rate_hz:g} to "
                      f"{INCREMENT_TOLERANCE:.1%}; raise imu.quadrature_nodes (from 3 they reach the Nyquist "
                      f"frequency, {0.5 * imu.rate_hz:g} Hz) or imu.rate_hz")


def check_vibration(v: VibrationSpec, i: int, imu: ImuSpec, where: str = "") -> None:
    """Refuse a ``[[vibration]]`` (number ``i``, from 1) with a key its kind
    would ignore (``band_hz`` of a sinusoid; ``frequency_hz`` of a random
    vibration given ``band_hz``), a band that is no band, or a frequency the
    IMU cannot sample (:func:`check_frequency`)."""
    name = f"{where}vibration {i} ({v.target}, {v.kind})"
    if v.target != "down" and not abs(v.amplitude) <= ANGLE_LIMIT_DEG:
        raise ConfigError(f"{name}: amplitude {v.amplitude:g} is outside [-{ANGLE_LIMIT_DEG:g}, {ANGLE_LIMIT_DEG:g}] "
                          f"degrees: no angle needs more than a full turn either way (a typo, or another unit?)")
    if v.kind == "sinusoidal":
        if v.band_hz is not None:
            raise ConfigError(f"{name}: band_hz is for kind = \"random\" (a sinusoidal vibration would ignore it); "
                              "a sinusoidal vibration takes frequency_hz")
        if v.frequency_hz is None:
            raise ConfigError(f"{name} needs frequency_hz")
    else:
        if (v.frequency_hz is None) == (v.band_hz is None):
            raise ConfigError(f"{name}: give frequency_hz (the band 0.5-1.5 x it) or band_hz, "
                              + ("not both (frequency_hz would be ignored)" if v.band_hz is not None else
                                 "one of them"))
        if v.band_hz is not None:
            lo, hi = v.band_hz
            if not 0 < lo < hi:
                raise ConfigError(f"{name}: band_hz [{lo:g}, {hi:g}] is no band: give [low, high] with "
                                  "0 < low < high")
    top, key = v.top_hz()
    if v.kind == "sinusoidal":
        what = f"frequency_hz {top:g} Hz"
    elif key == "band_hz":
        what = f"the top of band_hz, {top:g} Hz,"
    else:
        what = f"the top of the band of frequency_hz {v.frequency_hz:g} (1.5 x), {top:g} Hz,"
    check_frequency(top, imu, name, what)


def check_scenario(sc: Scenario) -> None:
    """The rules of a scenario beyond its fields' own bounds: every
    segment's keys and values (:func:`check_segment`) and every vibration's
    (:func:`check_vibration`).  Run by :func:`load_scenario` and by
    :func:`build_trajectory` (a scenario made in code)."""
    where = _where(sc)
    for i, seg in enumerate(sc.segment, start=1):
        check_segment(seg, i, sc.imu, where)
    for i, v in enumerate(sc.vibration, start=1):
        check_vibration(v, i, sc.imu, where)


#: The most segments one trajectory builds (each repetition of a ``[[segment]]`` is one, a figure eight
#: two): about 0.65 kB and 5 us each, so 65 MB and half a second at most.  ``repeat = 1000000000`` (a
#: slip of the keyboard) built repetitions for minutes and gigabytes before any limit on the run's
#: length could see it.
MAX_SEGMENTS = 100_000


def build_trajectory(sc: Scenario, rng=None) -> SegmentTrajectory:
    """The :class:`SegmentTrajectory` a scenario describes (checked first:
    :func:`check_scenario`).  An accelerate segment must speed up and a
    decelerate one slow down (from the speed the segments before leave)."""
    check_scenario(sc)
    where = _where(sc)
    s = sc.start
    tr = SegmentTrajectory((s.lat_deg * DEG, s.lon_deg * DEG, s.height_m), s.yaw_deg * DEG, s.speed_m_s,
                           s.transition_s)
    tr.source = sc._source
    limit = sc.duration_limit_s
    cut = False  # the segments were cut at duration_limit_s: those after it are not built
    for i, seg in enumerate(sc.segment, start=1):
        t = seg.type
        for r in range(1, seg.repeat + 1):
            if limit is not None and tr.t >= limit:  # a segment starting at or after the limit adds nothing but
                cut = True                           # its cost (a segment repeated a million times, 3.6 GB)
                break
            tr.label = f"{where}segment {i} ({t})" + (f", repetition {r} of {seg.repeat}" if seg.repeat > 1 else "")
            if len(tr.segments) >= MAX_SEGMENTS:
                raise ConfigError(f"{tr.label}: the scenario would build more than {MAX_SEGMENTS:,} segments "
                                  f"(each repetition counts, a figure-eight twice; field 'segment.{i - 1}.repeat' = "
                                  f"{seg.repeat:,}): lower repeat, or cut the run with duration_limit_s")
            if t == "static":
                tr.static(seg.duration_s)
            elif t in ("accelerate", "decelerate"):
                v0, v1 = tr.end_speed, seg.speed_m_s
                if t == "accelerate" and not v1 > v0 + 1e-9:
                    raise ConfigError(f"{tr.label}: speed_m_s {v1:g} is not above the current speed {v0:g} m/s; "
                                      "accelerate speeds up (decelerate slows down)")
                if t == "decelerate" and not v1 < v0 - 1e-9:
                    raise ConfigError(f"{tr.label}: speed_m_s {v1:g} is not below the current speed {v0:g} m/s; "
                                      "decelerate slows down (accelerate speeds up)")
                tr.accelerate(v1, seg.duration_s)
            elif t == "cruise":
                tr.cruise(seg.duration_s)
            elif t in ("turn", "banked-turn"):
                tr.turn(seg.angle_deg * DEG, rate=None if seg.rate_deg_s is None else seg.rate_deg_s * DEG,
                        radius=seg.radius_m, banked=(t == "banked-turn"))
            elif t in ("climb", "descend"):
                a = abs(seg.angle_deg) * (1 if t == "climb" else -1)
                tr.climb(a * DEG, seg.duration_s)
            elif t in ("pitch", "roll"):
                tr.attitude_pulse(t, seg.amplitude_deg * DEG, seg.duration_s)
            elif t == "coning":
                tr.coning(seg.amplitude_deg * DEG, seg.frequency_hz, seg.duration_s)
            elif t == "figure-eight":
                tr.figure_eight(seg.radius_m)
    tr.label = None
    for v in sc.vibration:
        amp = v.amplitude if v.target == "down" else v.amplitude * DEG
        if v.kind == "sinusoidal":
            tr.vibration(v.target, amp, v.frequency_hz)
        else:
            if rng is None:
                raise ConfigError(f"{where}random vibration needs a seed")
            band = v.band_hz or (0.5 * v.frequency_hz, 1.5 * v.frequency_hz)
            tr.random_vibration(v.target, amp, band, rng)
    if limit is not None:
        tr.duration_limit = float(limit)
    _check_windows_inside(sc, np.inf if cut else tr.t, where)
    return tr


def _check_windows_inside(sc: Scenario, total_s, where=""):
    """Refuse a GNSS outage or raw-GNSS blockage window that starts after the
    segments end (``total_s``): it would withhold nothing, silently.  A
    window beyond ``duration_limit_s`` but inside the segments is kept (the
    limit cuts a scenario short on purpose); ``total_s`` is infinite when the
    segments were built only up to the limit (their end then unknown)."""
    lists = [("gnss.outages_s", [tuple(w) for w in sc.gnss.outages_s])]
    if sc.raw_gnss is not None:
        lists.append(("raw_gnss.blockage", [(b.start_s, b.end_s) for b in sc.raw_gnss.blockage]))
    for key, wins in lists:
        for k, (a, b) in enumerate(wins, start=1):
            if a >= total_s:
                raise ConfigError(f"{where}field '{key}': window {k} [{a:g}, {b:g}] starts after the scenario's "
                                  f"segments end ({total_s:g} s): it would withhold nothing")


def imu_errors(sc: Scenario) -> ImuErrors:
    if sc.imu.grade == "ideal":
        if sc.imu.gyro or sc.imu.accel:
            raise ConfigError("imu.gyro/imu.accel overrides need a grade other than 'ideal'")
        return ImuErrors()
    return preset(sc.imu.grade, gyro=sc.imu.gyro, accel=sc.imu.accel)


def gnss_errors(sc: Scenario) -> GnssErrors:
    g = sc.gnss
    return GnssErrors(g.rate_hz, g.white_h_m, g.white_v_m, g.correlated_h_m, g.correlated_v_m,
                      g.correlation_time_s, g.velocity_sigma_m_s, tuple(g.lever_arm_b_m), g.latency_s,
                      tuple(tuple(o) for o in g.outages_s), g.outlier_probability, g.outlier_sigma_m)


def raw_gnss_spec(sc: Scenario):
    """The :class:`.gnss_raw.RawGnssSpec` of a scenario's ``[raw_gnss]``
    table (SI units; Klobuchar coefficients still to be chosen: see
    :func:`simulate_raw_gnss`)."""
    from .gnss_raw import Blockage, ClockModel, RawGnssSpec

    r = sc.raw_gnss
    clock = ClockModel(r.clock_bias_us * 1e-6, r.clock_drift_ppm * 1e-6, r.clock_h0, r.clock_h_2, r.clock_jumps)
    blockage = tuple(Blockage(b.start_s, b.end_s, b.keep, tuple(b.sats)) for b in r.blockage)
    return RawGnssSpec(mask_rad=r.mask_deg * DEG, code_sigma_m=r.code_sigma_m, phase_sigma_m=r.phase_sigma_m,
                       doppler_sigma_m_s=r.doppler_sigma_m_s, multipath_sigma_m=r.multipath_sigma_m,
                       multipath_tau_s=r.multipath_tau_s, clock=clock, iono_scale=r.iono_scale,
                       troposphere=r.troposphere, dual_frequency=r.dual_frequency,
                       lever_arm_b_m=tuple(sc.gnss.lever_arm_b_m), blockage=blockage,
                       cn0_zenith_dbhz=r.cn0_zenith_dbhz, cn0_horizon_dbhz=r.cn0_horizon_dbhz)


def raw_gnss_start(sc: Scenario, duration_s):
    """GPS week and seconds of week of scenario time 0, checked so that the
    scenario (plus 1 s of clock offset margin) ends inside the same GPS week:
    then GPS seconds of week are one continuous time scale for every file."""
    from ..gnss.time import from_week_sow, gps_seconds, week_sow

    r = sc.raw_gnss
    if r.start_utc is not None:
        try:
            d = datetime.fromisoformat(r.start_utc)
        except ValueError:
            raise ConfigError(f"raw_gnss.start_utc: {r.start_utc!r} is not an ISO date-time such as "
                              "'2025-07-08T19:33:42'") from None
        if d.tzinfo is not None:
            if d.utcoffset().total_seconds() != 0:
                raise ConfigError(f"raw_gnss.start_utc: {r.start_utc!r} must be UTC")
            d = datetime(d.year, d.month, d.day, d.hour, d.minute, d.second, d.microsecond)
        if d < _GPS_MINUS_UTC_SINCE:
            raise ConfigError(f"raw_gnss.start_utc: {r.start_utc} is before 2017-01-01, when GPS - UTC was not "
                              f"{_GPS_MINUS_UTC_S:.0f} s; give start_gps_week and start_sow_s instead")
        week, sow = week_sow(gps_seconds(d.year, d.month, d.day, d.hour, d.minute,
                                         d.second + d.microsecond * 1e-6 + _GPS_MINUS_UTC_S))
        week, sow = int(week), float(sow)
    elif r.start_gps_week is not None:
        week, sow = int(r.start_gps_week), float(r.start_sow_s)
    else:
        week, sow = RAW_GNSS_DEFAULT_WEEK, RAW_GNSS_DEFAULT_SOW_S
    if sow + duration_s + 1.0 >= 604800.0:
        raise ConfigError(f"raw_gnss: the scenario ({duration_s:.0f} s) starting at GPS week {week}, {sow:.0f} s of "
                          "week would run past the end of the week (seconds of week would jump back to 0); start "
                          f"at start_sow_s <= {604800.0 - duration_s - 1.0:.0f}")
    return week, sow, from_week_sow(week, sow)


def child_rng(seed) -> np.random.Generator:
    """The generator of the draws kept apart from the main stream (raw GNSS):
    the first child of ``SeedSequence(seed)`` for an integer seed (or None:
    fresh entropy); for a ``numpy.random.Generator``, a child spawned from it
    (``Generator.spawn``: the first spawned child of ``default_rng(s)`` is
    the first child of ``SeedSequence(s)``, so a fresh ``default_rng(s)``
    gives the numbers of the seed ``s``); a generator that cannot spawn (its
    bit generator has no ``SeedSequence``) seeds the child with four draws."""
    if isinstance(seed, np.random.Generator):
        try:
            return seed.spawn(1)[0]
        except TypeError:  # a bit generator without a SeedSequence to spawn from
            return np.random.default_rng(seed.integers(0, 2**63, size=4))
    return np.random.default_rng(np.random.SeedSequence(seed).spawn(1)[0])


def simulate_raw_gnss(sc: Scenario, trajectory, seed):
    """Raw GNSS observations of a scenario (:func:`.gnss_raw.simulate_raw`).

    The draws come from a child of ``numpy.random.SeedSequence(seed)``, not
    from the generator of the other draws: adding ``[raw_gnss]`` changes no
    IMU or GNSS-fix number, and the raw observations do not depend on the
    IMU settings.  ``seed`` may be a ``numpy.random.Generator``: the child
    is then spawned from it (:func:`child_rng`).  Epochs are the receiver tags ``0, 1/rate, ...`` up to
    the scenario's end.  Klobuchar coefficients: ``iono_alpha/beta`` if
    given, else the navigation file's (``nav:PATH``), else RTKLIB's
    default set (:data:`inskit.gnss.atmosphere.KLOBUCHAR_DEFAULT_ALPHA`),
    rounded to the 5 digits of the RINEX header.
    """
    import dataclasses

    from ..gnss.atmosphere import KLOBUCHAR_DEFAULT_ALPHA, KLOBUCHAR_DEFAULT_BETA
    from ..gnss.rinex_write import iono_precision
    from .constellation import constellation_from_nav, walker_constellation
    from .gnss_raw import simulate_raw

    r = sc.raw_gnss
    rng = child_rng(seed)
    duration = trajectory.duration
    _, _, t0 = raw_gnss_start(sc, duration)
    t_sim = np.arange(0.0, duration + 1e-9, 1.0 / r.rate_hz)
    if r.constellation.startswith("nav:"):
        nav = constellation_from_nav(r.constellation[4:], t0, t0 + duration)
    else:
        nav = walker_constellation(r.constellation, t0 - 1.0, t0 + duration + 1.0, rng)
    alpha = r.iono_alpha if r.iono_alpha is not None else (
        nav.iono_alpha if nav.iono_alpha is not None else KLOBUCHAR_DEFAULT_ALPHA)
    beta = r.iono_beta if r.iono_beta is not None else (
        nav.iono_beta if nav.iono_beta is not None else KLOBUCHAR_DEFAULT_BETA)
    spec = dataclasses.replace(raw_gnss_spec(sc), iono_alpha=tuple(iono_precision(alpha)),
                               iono_beta=tuple(iono_precision(beta)))
    raw = simulate_raw(trajectory, t_sim, t0_gps=t0, nav=nav, spec=spec, rng=rng)
    if not np.any(raw.n_visible > 0):  # it was '`obs` holds no observation at all: nothing to write'
        raise ConfigError(f"field 'raw_gnss.mask_deg': no satellite is in view at any epoch (above the "
                          f"{r.mask_deg:g} deg mask, outside the blockage windows): the observation file would be "
                          "empty; lower the mask")
    worst = int(np.argmax(np.abs(raw.clock_bias_s)))
    if abs(raw.clock_bias_s[worst]) > MAX_CLOCK_OFFSET_S:  # it was 'obs['L1C']: ... does not fit the RINEX field'
        raise ConfigError(f"field 'raw_gnss.clock_bias_us': the receiver clock offset reaches "
                          f"{raw.clock_bias_s[worst]:.3g} s at t = {t_sim[worst]:g} s (clock_bias_us, "
                          f"clock_drift_ppm and the clock's noise over the run), beyond +-{MAX_CLOCK_OFFSET_S:g} s: "
                          "carrier phases that far off do not fit RINEX's fields (a receiver keeps its clock within "
                          "a millisecond: clock_jumps = true steps it back)")
    return raw


#: the largest receiver clock offset [s] a simulation keeps: RINEX's F14.3 carrier-phase field holds down to about
#: -0.7 s of offset (L1 cycles of a range of 20,000 km less 0.7 light-seconds)
MAX_CLOCK_OFFSET_S = 0.5


@dataclass
class Simulation:
    scenario: Scenario
    trajectory: SegmentTrajectory
    truth: NavSolution
    imu_ideal: ImuData
    imu: ImuData
    gnss: GnssData
    draws: dict
    #: raw GNSS observations (:class:`.gnss_raw.RawSimulation`) when the scenario has ``[raw_gnss]``
    raw: object = None


def mounted_imu(imu: ImuData, mount_rpy_deg) -> ImuData:
    """The readings of an IMU mounted at ``mount_rpy_deg`` in the vehicle,
    from the vehicle-axes increments ``imu``.

    The angles follow navigate's ``[imu] mount_rpy_deg``
    (:func:`inskit.io.rtklib.mount_dcm`): navigate rotates sensor readings
    into vehicle (body) axes by ``C_bs = dcm_from_euler(mount).T``, so the
    sensor reads ``x_s = dcm_from_euler(mount) x_b``, and the same numbers in
    a navigate config undo the mounting exactly.  ``(0, p, 0)`` with ``p >
    0`` is an IMU pitched nose-down by ``p`` against the vehicle; ``(0, 0,
    y)`` one yawed to the left by ``y``.  A rigid mounting: the gyros sense
    the vehicle's rate and the accelerometers its specific force, rotated.
    """
    from ..rotations import dcm_from_euler

    m = np.asarray(mount_rpy_deg, float)
    if not m.any():
        return imu
    C_sb = dcm_from_euler(np.radians(m))
    return ImuData(imu.time, imu.dtheta_b @ C_sb.T, imu.dv_b @ C_sb.T)


def simulate(sc: Scenario, seed=0, *, truth_rate_hz=None, progress=None) -> Simulation:
    """Simulate a scenario: truth, ideal and measured IMU, GNSS fixes.

    The specific force follows the gravity model of ``[earth] gravity``.

    The truth is the vehicle's: position of the trajectory point, velocity,
    and the attitude (and, with rates, body rate and specific force) of the
    vehicle axes.  With ``[imu] mount_rpy_deg`` the IMU's own axes differ
    from them (:func:`mounted_imu`): its attitude is
    ``C_nb = C_nv dcm_from_euler(mount)^T``, and the ideal and measured IMU
    are in its axes (the sensor errors act there).

    One ``numpy.random.default_rng(seed)`` feeds every draw in a fixed order,
    so the same seed gives the same numbers (and byte-identical files).
    Raw GNSS observations (``[raw_gnss]``) draw from their own child
    generator (:func:`simulate_raw_gnss`).

    ``seed`` is an integer >= 0, None (fresh entropy) or a
    ``numpy.random.Generator``, which is then drawn from (it advances: a
    second call with the same generator gives other numbers) and spawns the
    raw-GNSS child (:func:`child_rng`); a fresh ``default_rng(s)`` gives the
    numbers of the seed ``s``.
    """
    if truth_rate_hz is not None and not 0 < truth_rate_hz <= MAX_RATE_HZ:
        raise ConfigError(f"the truth rate must be within (0, {MAX_RATE_HZ:g}] Hz, got {truth_rate_hz}")
    rng = np.random.default_rng(seed)
    tr = build_trajectory(sc, rng)
    for what, rate in (("IMU samples at field 'imu.rate_hz' =", sc.imu.rate_hz),
                       ("truth rows at the truth rate (simulate --truth-rate)", truth_rate_hz)):
        if rate is not None and tr.duration * rate > MAX_SAMPLES:  # refused before any array is made
            raise ConfigError(f"{_where(sc)}the scenario lasts {tr.duration:g} s: {tr.duration * rate:,.0f} {what} "
                              f"{rate:g} Hz, more than the {MAX_SAMPLES:,} one simulation holds; lower the rate or "
                              "shorten the scenario (duration_limit_s)")
    if truth_rate_hz is not None and not 1.0 / truth_rate_hz <= tr.duration + 1e-9:  # the grid's second row
        step = 10.0 ** (np.floor(np.log10(1.0 / tr.duration)) - 3)
        least = np.ceil(1.0 / tr.duration / step) * step  # 4 digits, rounded up: a rate that gives two rows
        raise ConfigError(f"{_where(sc)}the truth rate (simulate --truth-rate) {truth_rate_hz:g} Hz puts a truth row "
                          f"every {1.0 / truth_rate_hz:g} s, longer than the scenario ({tr.duration:g} s): the truth "
                          f"file would hold the start alone; give at least {least:.4g} Hz")
    dt = 1.0 / sc.imu.rate_hz
    t = np.arange(0.0, tr.duration + 1e-9, dt)
    if len(t) < 2:
        raise ConfigError(f"{_where(sc)}the scenario lasts {tr.duration:g} s, shorter than one IMU sample at field "
                          f"'imu.rate_hz' = {sc.imu.rate_hz:g} Hz ({dt:g} s)"
                          + (" (cut by field 'duration_limit_s')" if sc.duration_limit_s is not None
                             and sc.duration_limit_s < tr.t else ""))
    ideal = mounted_imu(ideal_imu(tr, t, nodes=sc.imu.quadrature_nodes, lever_arm_b=sc.imu.lever_arm_b_m,
                                  gravity=sc.earth.gravity),
                        sc.imu.mount_rpy_deg)
    if progress:
        progress("ideal IMU")
    imu, draws = apply_imu_errors(ideal, imu_errors(sc), rng)
    try:
        gnss, gerr = simulate_gnss(tr, 0.0, tr.duration, gnss_errors(sc), rng)
    except ConfigError as exc:  # a [gnss] key (outages_s, latency_s): said of the file
        raise ConfigError(f"{_where(sc)}{exc}") from None
    draws["gnss_position_errors"] = gerr
    tt = t if truth_rate_hz is None else np.arange(0.0, tr.duration + 1e-9, 1.0 / truth_rate_hz)
    truth = truth_solution(tr, tt, with_rates=True, gravity=sc.earth.gravity)
    raw = None
    if sc.raw_gnss is not None and sc.raw_gnss.enabled:
        try:
            raw = simulate_raw_gnss(sc, tr, seed)
        except ConfigError as exc:  # a [raw_gnss] key, its nav file, a blockage's satellites: said of the file
            raise ConfigError(f"{_where(sc)}{exc}") from None
    return Simulation(sc, tr, truth, ideal, imu, gnss, draws, raw)
