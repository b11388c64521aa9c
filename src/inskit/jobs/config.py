"""The ``inskit navigate`` configuration: a validated TOML file.

Units follow datasheets at this edge (deg/sqrt(h), micro-g, degrees) and are
converted to SI when the filter settings are built.  Relative paths (the
input files and ``[output] dir``) are taken relative to the config file.

A key that would be ignored in the configuration it sits in is an error,
not a silent no-op (:class:`~inskit.errors.ConfigError` naming the key):
``[outages] windows_s`` without ``protocol = "windows"``, ``keep_satellites``
without windows or without tight coupling, ``[gnss]`` RINEX and tight-coupling
keys changed from their defaults where no RINEX is read or no pseudorange is
fused, loose-coupling keys with tight coupling, ``[init]`` keys of the other
start-up mode, the velocity keys without ``use_velocity``, ``quality``
without a .pos file, the keys of an optional state (scale factors, lever
arm, time offset) with the state off, a constraint's keys with the
constraint off.  Only a key changed from its default counts (:func:`_changed`).
``[output] columns`` are checked against the columns the configuration's
solution has.  The reference of every key is ``docs/config.md``, generated
from these models by ``python -m inskit.jobs.config_doc --write``.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator
from pydantic_core import PydanticCustomError

from ..config_files import (MASK_RANGE_DEG, check_angles, check_height, check_lever_arm, check_longitude,
                            check_magnitude, check_mask, check_scalar_type, read_toml, validation_message)
from ..errors import ConfigError, InputError
from ..units import MAX_RATE_HZ

#: error type of a consistency rule that names its key (see :func:`_key_error`)
_KEY_ERROR = "inskit_key"


def _key_error(key, text):
    """A validation error naming ``key`` (relative to the model raising it);
    :func:`config_from_dict` turns it into ``source: field 'section.key': text``."""
    return PydanticCustomError(_KEY_ERROR, "{text}", {"key": key, "text": text})


def _changed(model, keys):
    """The keys of ``keys`` whose value differs from the field's default."""
    fields = type(model).model_fields
    out = []
    for k in keys:
        d = fields[k].get_default(call_default_factory=True)
        v = getattr(model, k)
        if isinstance(d, (tuple, list)) and isinstance(v, (tuple, list)):
            same = list(d) == list(v)
        else:
            same = v == d
        if not same:
            out.append(k)
    return out


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    _magnitude = field_validator("*")(check_magnitude)
    _kinds = field_validator("*", mode="before")(classmethod(check_scalar_type))


class ImuSection(_Strict):
    """The IMU log and how to read it.

    Rules: first_row other than "initial" needs format = "inskit" (the
    rtklibexplorer log holds rates).
    """

    file: Path = Field(..., description="IMU log, relative to this config file (plain or .gz)")
    format: Literal["inskit", "rtklibexplorer"] = Field(
        "inskit", description="file layout: 'inskit' (our CSV of rates or increments, docs/formats.md) or "
        "'rtklibexplorer' (the rtklibexplorer GNSS-IMU logs, GPS time tags)")
    time_offset_s: float = Field(0.0, description="added to every IMU time tag (late tags need a negative "
                                 "offset; `inskit navigate --calibrate-time-offset` finds it)")
    time_offset_search: Literal["check", "calibrate", "off"] = Field(
        "check", description="'check': when the run's GNSS updates are unhealthy (mean NIS above 3 per degree of "
        "freedom or more than 5 % rejected) outside the stretches where the filter was lost (15 s or more of "
        "refusals in a row: a lost filter is no evidence of a time offset, and the verdict then says it was lost), "
        "search the IMU time offset within time_offset_s +- 0.5 s that fits the "
        "fixes best (when none fits, also 18 s either way: GPS time - UTC, one log in UTC) and name it in the health "
        "verdict (late or early IMU time tags are a common cause that the "
        "files do not show); 'calibrate': search it before the run (within -0.5 .. 0.2 s) and use it, as "
        "`inskit navigate --calibrate-time-offset`; 'off': neither. Only the fixes the filter uses enter the search")
    mount_rpy_deg: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0), description="roll, pitch, yaw (ZYX) of the rotation from the body axes (forward, right, "
        "down) to the sensor axes; the readings are rotated into body axes")
    check_units: bool = Field(True, description="refuse a log whose magnitudes betray a wrong unit (e.g. deg/s "
                              "under a rad/s header), or whose gyros turn far less or more than the GNSS track "
                              "(rad/s under a deg/s header); name its lone spikes (docs/formats.md)")
    first_row: Literal["initial", "increment", "discard"] = Field(
        "initial", description="what the first row of an increment file (dtheta/dv columns) is: 'initial' (the "
        "initial epoch, zero increments; a first row that holds increments is refused, the file seems to lack its "
        "initial row), 'increment' (a real increment: an initial epoch one median interval earlier is prepended) "
        "or 'discard' (the initial epoch: its increments are dropped); docs/formats.md")
    repeated_rows: Literal["keep", "drop"] = Field(
        "keep", description="rate logs: a row that repeats the previous one in all six channels (the logger read "
        "one sample twice; a noisy MEMS sensor never repeats itself to the last digit): 'keep' integrates it as a "
        "sample over its short interval (the health verdict then warns when there are any), 'drop' leaves it out "
        "so that the next sample covers the whole span (docs/formats.md)")
    time_smoothing_samples: int = Field(
        1, ge=1, description="rate logs: 1 keeps the time tags as logged; an odd number >= 3 replaces each tag by the "
        "moving average of that many (after repeated_rows), stretch by stretch between gaps, each side of a change "
        "of sampling rate apart. A logger that polls the IMU stamps its own jittery read times (often a millisecond "
        "counter: 8-11 ms intervals of a nominal 10), and each rate sample is integrated over its interval: the "
        "jitter misweighs samples, which a bump turns into attitude error. The mean time is kept (time_offset_s "
        "unchanged). Where the tags move more than their jitter explains (a clock that drifts or jumps, a window "
        "too long for it, rows left out piling up in one window) the health verdict warns "
        "(imu_time_tags.time_tags_beyond_jitter); docs/formats.md")
    start_s: float | None = Field(None, description="ignore IMU data before this time (IMU time scale, after "
                                  "time_offset_s; default: the first GNSS epoch)")
    gap_factor: float = Field(5.0, gt=1.0, description="an interval longer than this many median intervals is a gap")
    gap_rate_sigma_deg_s: float = Field(5.0, gt=0, description="unknown rate change assumed over a bridged gap")
    gap_accel_sigma_m_s2: float = Field(1.0, gt=0, description="unknown acceleration change over a bridged gap")
    _angles = field_validator("mount_rpy_deg")(check_angles)

    @field_validator("time_smoothing_samples")
    @classmethod
    def _odd(cls, v):
        if v > 1 and v % 2 == 0:
            raise ValueError(f"must be 1 (the time tags as logged) or odd (a window centred on each row), got {v}")
        return v

    @model_validator(mode="after")
    def _first_row_needs_increments(self):
        if self.format == "rtklibexplorer" and self.first_row != "initial":
            raise _key_error("first_row", "applies to increment files (format \"inskit\" with dtheta/dv columns); "
                             "the rtklibexplorer log holds rates: remove it")
        return self


#: the most rows of the ``[output] rate_hz`` grid a streamed run keeps in memory for its plots (a longer log
#: keeps a coarser grid: 8 h at 10 Hz would hold 0.29 M rows, 0.1 GB): :func:`inskit.jobs.navigate.kept_grid_rate`
KEPT_GRID_ROWS = 50_000
#: [gnss] keys that configure the reading and single-point solution of the RINEX files
GNSS_RINEX_KEYS = ("obs", "nav", "systems", "mask_deg", "iono", "tropo")
#: [gnss] keys used only when pseudoranges are fused (tight coupling)
GNSS_TIGHT_KEYS = ("use_doppler", "pseudorange_sigma_scale", "doppler_sigma_scale", "clock_h0", "clock_h_2")
#: [gnss] keys that describe fixes fused by loose coupling
GNSS_LOOSE_KEYS = ("use_velocity", "velocity_delay_s", "velocity_sigma_scale", "sigma_floor_m", "sigma_scale_ned",
                   "sigma_scale_search", "error_sigma_m", "error_tau_s")
#: [gnss] keys that describe how ``file`` is read
GNSS_FILE_KEYS = ("format", "quality", "time_offset_s")
#: [gnss] formats of ``file`` with a quality column (``quality`` selects its rows)
GNSS_QUALITY_FORMATS = ("rtklib-pos",)
#: [gnss] keys of the fixes' velocity updates (they need use_velocity)
GNSS_VELOCITY_KEYS = ("velocity_delay_s", "velocity_sigma_scale")
#: [constraints] switches and their own keys (ignored, so refused changed, with the switch off)
CONSTRAINT_SWITCH_KEYS = {"zupt": ("zupt_sigma_m_s",), "nhc": ("nhc_sigma_m_s", "nhc_lever_arm_b_m")}


def _names(keys, section="gnss"):
    return ", ".join(f"{section}.{k}" for k in keys)


def _they(keys, singular, plural):
    """``singular`` for one key, ``plural`` for several."""
    return singular if len(keys) == 1 else plural


class GnssSection(_Strict):
    """GNSS input: fixes (loose coupling) or RINEX observations (tight).

    Rules: loose coupling needs ``file`` or ``obs`` + ``nav``; tight coupling
    needs ``obs`` + ``nav``.  Keys that would be ignored are refused when
    changed from their defaults: the RINEX keys (obs, nav, systems, mask_deg,
    iono, tropo) and the tight-coupling keys (use_doppler, the sigma scales,
    clock_h0, clock_h_2) with loose coupling and a ``file``; the
    tight-coupling keys with loose coupling from RINEX; the loose-coupling keys
    (use_velocity, velocity_delay_s, velocity_sigma_scale, sigma_floor_m,
    sigma_scale_ned, sigma_scale_search, error_sigma_m, error_tau_s) with
    tight coupling; format, quality and
    time_offset_s without a ``file``; quality with a format other than
    "rtklib-pos" (only a .pos file has a quality column); velocity_delay_s
    and velocity_sigma_scale without use_velocity; error_tau_s without
    error_sigma_m.
    """

    coupling: Literal["loose", "tight"] = Field(
        "loose", description="loose: position (and velocity) fixes from `file` update the filter; tight: "
        "pseudoranges and Doppler from the RINEX `obs` and `nav` files do, satellite by satellite")
    file: Path | None = Field(None, description="GNSS fixes: the measurements of loose coupling (default: our "
                              "own single-point solution of `obs` and `nav`); with tight coupling the reference "
                              "for start-up and scoring (default there: the same single-point solution)")
    format: Literal["inskit", "rtklib-pos"] = Field(
        "inskit", description="layout of `file`: 'inskit' (our CSV of fixes, docs/formats.md) or 'rtklib-pos' "
        "(an RTKLIB .pos solution, GPS time)")
    time_offset_s: float = Field(0.0, description="added to every time tag of `file`")
    quality: list[int] = Field([1, 2], description="format 'rtklib-pos' only (the one with a quality column), one "
                               "or more of 1..6: "
                               "the Q flags kept (1 fix, 2 float, 5 single, ...); other rows are dropped")
    height_offset_m: float = Field(0.0, description="added to the fixes' heights (e.g. the geoid separation, "
                                   "-21.4 m on walk_0827, turns u-blox heights above sea level into ellipsoidal)")
    lever_arm_b_m: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0), description="antenna position relative to the IMU in body axes (forward, right, down), "
        "each within +-1 km")
    _lever_arm = field_validator("lever_arm_b_m")(check_lever_arm)
    use_velocity: bool = Field(False, description="loose coupling: fuse the fixes' velocity as well as their "
                               "position")
    velocity_delay_s: float = Field(0.0, description="loose coupling with use_velocity: a fix's velocity "
                                    "describes the antenna this long before its time tag (a lagging receiver "
                                    "velocity)")
    velocity_sigma_scale: float = Field(1.0, gt=0, description="loose coupling with use_velocity: multiplies "
                                        "the fixes' velocity sigmas")
    sigma_floor_m: float = Field(0.0, ge=0, description="loose coupling: lower bound on the fixes' position sigmas "
                                 "(0: as the file gives them)")
    sigma_scale_ned: tuple[float, float, float] = Field(
        (1.0, 1.0, 1.0), description="loose coupling: multiplies the fixes' north, east and down position sigmas "
        "(after sigma_floor_m) and error_sigma_m: the shape of the fixes' noise where the file's sigmas lack it (a "
        "receiver's formal sigmas, alike on every axis, where the vertical is really the worse). Measured from the "
        "innovations of the fixes the filter uses: the summary's gnss_axes, sigma_scale_search = \"calibrate\" "
        "(--calibrate-gnss-axes); docs/guide.md")
    sigma_scale_search: Literal["off", "calibrate"] = Field(
        "off", description="loose coupling: \"calibrate\" (--calibrate-gnss-axes) runs the filter first to "
        "measure the fixes' normalised innovations on each axis (the fixes it uses, never the withheld ones) and "
        "sets sigma_scale_ned so that the horizontal and the vertical agree, their mean kept (a few runs, until "
        "they agree within 5 %); the summary's gnss_axes_calibration says what each run measured")
    error_sigma_m: float | None = Field(None, gt=0, description="loose coupling: steady-state sigma of a "
                                        "time-correlated (Gauss-Markov) error of the fixes, north, east, down, "
                                        "estimated as 3 states (default: none, the fixes' errors are white)")
    error_tau_s: float = Field(10.0, gt=0, description="loose coupling: correlation time of that error [s] "
                               "(with error_sigma_m)")
    obs: Path | None = Field(None, description="RINEX 2/3 observation file (tight coupling, or loose coupling "
                             "on our own single-point fixes)")
    nav: Path | None = Field(None, description="RINEX 2/3 navigation file with the broadcast ephemerides")
    systems: list[Literal["G", "E"]] = Field(["G", "E"], min_length=1, description="satellite systems used "
                                             "(GPS, Galileo), each once")
    mask_deg: float = Field(10.0, ge=MASK_RANGE_DEG[0], lt=MASK_RANGE_DEG[1], description="elevation mask")
    _mask = field_validator("mask_deg", mode="before")(check_mask)
    iono: Literal["klobuchar", "iono-free", "none"] = Field(
        "klobuchar", description="ionospheric correction: the broadcast Klobuchar model, the dual-frequency "
        "ionosphere-free code combination, or none")
    tropo: Literal["saastamoinen", "none"] = Field(
        "saastamoinen", description="tropospheric correction: the Saastamoinen model of a standard atmosphere, "
        "or none")
    use_doppler: bool = Field(True, description="pseudorange-rate (Doppler) updates beside the pseudoranges")
    pseudorange_sigma_scale: float = Field(1.0, gt=0, description="multiplies the elevation-dependent sigmas")
    doppler_sigma_scale: float = Field(1.0, gt=0, description="multiplies the elevation-dependent Doppler "
                                       "(pseudorange-rate) sigmas")
    clock_h0: float = Field(2e-19, gt=0, description="receiver oscillator white-frequency Allan coefficient [s]")
    clock_h_2: float = Field(2e-20, gt=0, description="receiver oscillator random-walk-frequency coefficient [1/s]")

    speed_course: Path | None = Field(None, description="GNSS speed and course over ground (CSV: time_s, speed_m_s, "
                                      "course_deg, sigma_speed_m_s, sigma_course_deg), fused as horizontal "
                                      "velocity; withheld in outage windows like the fixes")
    speed_course_min_speed_m_s: float = Field(0.5, ge=0, description="below this speed (or 3 sigma of it) the "
                                              "course is meaningless and the reading is skipped [m/s]")
    @field_validator("quality")
    @classmethod
    def _quality_flags(cls, v):
        bad = [q for q in v if not 1 <= q <= 6]
        if not v or bad:
            raise ValueError(f"expected one or more of RTKLIB's quality flags Q, 1 to 6 (1 fix, 2 float, 3 SBAS, "
                             f"4 DGPS, 5 single, 6 PPP), got {list(v)}: " + ("an empty list keeps no fix" if not v else
                                                                              f"no .pos row has Q = {bad[0]}"))
        return v

    @field_validator("sigma_scale_ned")
    @classmethod
    def _positive_scales(cls, v):
        if not all(math.isfinite(x) and x > 0 for x in v):
            raise ValueError(f"each scale must be a finite number > 0 (north, east, down), got {list(v)}")
        return v

    @field_validator("systems")
    @classmethod
    def _once(cls, v):
        if len(set(v)) != len(v):
            raise ValueError(f"each system once: {v} lists {sorted({s for s in v if v.count(s) > 1})} twice")
        return v

    @model_validator(mode="after")
    def _inputs(self):
        if self.coupling == "loose" and self.file is None and (self.obs is None or self.nav is None):
            raise ValueError("loose coupling needs gnss.file (the fixes to fuse), or gnss.obs and gnss.nav "
                             "(RINEX: then our own single-point solution is fused)")
        if self.coupling == "tight" and (self.obs is None or self.nav is None):
            raise ValueError("tight coupling needs gnss.obs and gnss.nav (RINEX observation and navigation "
                             "files)")
        return self

    @model_validator(mode="after")
    def _ignored(self):
        if self.coupling == "loose" and self.file is not None:
            bad = _changed(self, GNSS_RINEX_KEYS + GNSS_TIGHT_KEYS)
            if bad:
                raise _key_error(bad[0], f"{_names(bad)} would be ignored: with coupling = \"loose\" and "
                                 "gnss.file given, the fixes of `file` are fused and no RINEX file is read "
                                 "(obs, nav, systems, mask_deg, iono and tropo serve tight coupling, or our own "
                                 "single-point fixes when `file` is absent); remove "
                                 f"{_they(bad, 'it', 'them')}, or set coupling = \"tight\"")
        if self.coupling == "loose" and self.file is None:
            bad = _changed(self, GNSS_TIGHT_KEYS)
            if bad:
                raise _key_error(bad[0], f"{_names(bad)} would be ignored: "
                                 f"{_they(bad, 'it configures', 'they configure')} the pseudorange and Doppler "
                                 "updates of tight coupling, and coupling = \"loose\" fuses our single-point "
                                 "fixes instead; remove "
                                 f"{_they(bad, 'it', 'them')}, or set coupling = \"tight\"")
        if self.coupling == "tight":
            bad = _changed(self, GNSS_LOOSE_KEYS)
            if bad:
                raise _key_error(bad[0], f"{_names(bad)} would be ignored: "
                                 f"{_they(bad, 'it describes', 'they describe')} fixes fused by loose coupling; "
                                 "with coupling = \"tight\" the fixes are only the reference for start-up and "
                                 "scoring (tune use_doppler and the sigma scales instead)")
        if self.error_sigma_m is None and _changed(self, ("error_tau_s",)):
            raise _key_error("error_tau_s", "gnss.error_tau_s would be ignored: the fixes' correlated error is "
                             "modelled only with gnss.error_sigma_m")
        if self.file is None:
            bad = _changed(self, GNSS_FILE_KEYS)
            if bad:
                raise _key_error(bad[0], f"{_names(bad)} would be ignored: "
                                 f"{_they(bad, 'it describes', 'they describe')} how gnss.file is read, and no "
                                 "`file` is given (the fixes are our single-point solution of obs and nav)")
        elif self.format not in GNSS_QUALITY_FORMATS and _changed(self, ("quality",)):
            raise _key_error("quality", f"gnss.quality would be ignored: it selects rows by the quality flag Q of "
                             f"an RTKLIB .pos file (format = \"rtklib-pos\"), and format = \"{self.format}\" has "
                             "no quality column; remove it, or set format = \"rtklib-pos\" if gnss.file is a .pos "
                             "solution")
        if self.coupling == "loose" and not self.use_velocity:
            bad = _changed(self, GNSS_VELOCITY_KEYS)
            if bad:
                raise _key_error(bad[0], f"{_names(bad)} would be ignored: "
                                 f"{_they(bad, 'it describes', 'they describe')} the fixes' velocity, and "
                                 "use_velocity = false fuses only their position; set gnss.use_velocity = true, or "
                                 f"remove {_they(bad, 'it', 'them')}")
        return self


class NoiseSection(_Strict):
    """Sensor noise of the filter, in datasheet units (``inskit allan``
    prints this section from a static log: ``--toml FILE``).

    Each sensor's bias is a first-order Gauss-Markov process (its
    steady-state sigma and correlation time) or a random walk (its rate
    random walk, the +1/2 slope of an Allan curve).

    Rules: ``bias_tau_s`` is a shorthand that sets ``gyro_bias_tau_s`` and
    ``accel_bias_tau_s`` where they are not given; giving a specific key
    and the shorthand with different values is an error.  A random-walk
    bias needs its ``*_rrw_*`` key and refuses its ``*_sigma_*`` and
    ``*_tau_s`` keys changed from their defaults (they would be ignored); a
    Gauss-Markov bias refuses its ``*_rrw_*`` key.  The turn-on bias sigmas
    (the initial bias uncertainty) are ``gyro_turn_on_bias_deg_h`` and
    ``accel_turn_on_bias_mg``; the older ``[init]`` keys
    ``sigma_gyro_bias_deg_s`` and ``sigma_accel_bias_m_s2`` still work
    (their defaults apply when neither spelling is given), and giving both
    spellings of one is an error.  ``from_static_per_axis = true`` needs
    ``from_static`` and a start-up that can measure on a static start
    (init.mode "static-then-track" or "auto"; "in-motion" and "given" have
    none).
    """

    gyro_arw_deg_sqrt_h: float = Field(0.3, gt=0, description="gyro angle random walk (white rate noise)")
    accel_vrw_m_s_sqrt_h: float = Field(0.1, gt=0, description="accelerometer velocity random walk (white "
                                        "specific-force noise)")
    gyro_bias_model: Literal["gauss-markov", "random-walk"] = Field(
        "gauss-markov", description="gyro in-run bias: first-order Gauss-Markov (gyro_bias_sigma_deg_h, "
        "gyro_bias_tau_s) or random walk (gyro_bias_rrw_deg_h_sqrt_h)")
    gyro_bias_sigma_deg_h: float = Field(50.0, gt=0, description="gauss-markov: steady-state sigma of the gyro "
                                         "bias (in-run variation)")
    gyro_bias_tau_s: float | None = Field(None, gt=0, description="gauss-markov: correlation time of the gyro "
                                          "bias (default: bias_tau_s)")
    gyro_bias_rrw_deg_h_sqrt_h: float | None = Field(None, gt=0, description="random-walk: gyro rate random "
                                                     "walk (the bias drifts by this much in 1 h, 1 sigma)")
    accel_bias_model: Literal["gauss-markov", "random-walk"] = Field(
        "gauss-markov", description="accelerometer in-run bias: first-order Gauss-Markov (accel_bias_sigma_ug, "
        "accel_bias_tau_s) or random walk (accel_bias_rrw_ug_sqrt_h)")
    accel_bias_sigma_ug: float = Field(1000.0, gt=0, description="gauss-markov: steady-state sigma of the "
                                       "accelerometer bias (in-run variation)")
    accel_bias_tau_s: float | None = Field(None, gt=0, description="gauss-markov: correlation time of the "
                                           "accelerometer bias (default: bias_tau_s)")
    accel_bias_rrw_ug_sqrt_h: float | None = Field(None, gt=0, description="random-walk: accelerometer rate "
                                                   "random walk (the bias drifts by this much in 1 h, 1 sigma)")
    bias_tau_s: float = Field(300.0, gt=0, description="shorthand: the correlation time of both Gauss-Markov "
                              "biases, where gyro_bias_tau_s or accel_bias_tau_s is not given (finite; a random "
                              "walk is a *_bias_model)")
    gyro_turn_on_bias_deg_h: float | None = Field(None, gt=0, description="sigma of the gyro turn-on bias per "
                                                  "axis: the initial bias uncertainty (default: "
                                                  "init.sigma_gyro_bias_deg_s, 0.05 deg/s = 180 deg/h)")
    accel_turn_on_bias_mg: float | None = Field(None, gt=0, description="sigma of the accelerometer turn-on "
                                                "bias per axis: the initial bias uncertainty (default: "
                                                "init.sigma_accel_bias_m_s2, 0.05 m/s^2 = 5.1 mg)")
    scale_factor_rw_ppm_sqrt_s: float = Field(1.0, gt=0, description="random walk of the gyro and accelerometer "
                                              "scale-factor errors (with filter.scale_factors)")
    time_offset_rw_s_sqrt_s: float = Field(1e-5, gt=0, description="random walk of the estimated time offset "
                                           "(with filter.time_offset)")
    from_static: bool = Field(
        True, description="raise ARW/VRW to the white-noise density measured on the static start "
        "(init.mode = \"static-then-track\")"
    )
    from_static_per_axis: bool = Field(
        False, description="with from_static (init.mode \"static-then-track\" or \"auto\"): measure the white "
        "noise of each body axis on its own (each raised "
        "to gyro_arw_deg_sqrt_h / accel_vrw_m_s_sqrt_h) and rotate it into NED at every step, instead of one "
        "quadratic mean over the three axes for every axis (a car's gyro shakes about its pitch axis: 14 against "
        "0.7 deg/sqrt(h) about yaw on drive_0708)")

    @model_validator(mode="after")
    def _bias_models(self):
        given = self.model_fields_set
        for sensor, rrw, sigma in (("gyro", "gyro_bias_rrw_deg_h_sqrt_h", "gyro_bias_sigma_deg_h"),
                                   ("accel", "accel_bias_rrw_ug_sqrt_h", "accel_bias_sigma_ug")):
            model, tau = getattr(self, f"{sensor}_bias_model"), f"{sensor}_bias_tau_s"
            if model == "random-walk":
                if getattr(self, rrw) is None:
                    raise _key_error(rrw, f"{sensor}_bias_model = \"random-walk\" needs noise.{rrw}, the rate "
                                     "random walk (inskit allan reports it)")
                for k in _changed(self, (tau, sigma)):
                    raise _key_error(k, f"noise.{k} would be ignored: it describes a Gauss-Markov bias and "
                                     f"{sensor}_bias_model = \"random-walk\" (a random walk has no correlation "
                                     f"time or steady-state sigma; its strength is noise.{rrw})")
            else:
                if getattr(self, rrw) is not None:
                    raise _key_error(rrw, f"noise.{rrw} would be ignored: it is the strength of a random-walk "
                                     f"bias and {sensor}_bias_model = \"gauss-markov\"; set {sensor}_bias_model = "
                                     "\"random-walk\" to use it")
                v = getattr(self, tau)
                if v is not None and "bias_tau_s" in given and v != self.bias_tau_s:
                    raise _key_error(tau, f"noise.{tau} = {v:g} contradicts the shorthand noise.bias_tau_s = "
                                     f"{self.bias_tau_s:g} (which sets both correlation times); give one of them")
        if self.from_static_per_axis and not self.from_static:
            raise _key_error("from_static_per_axis", "noise.from_static_per_axis = true measures the white noise "
                             "per axis on the static start, and from_static = false measures none: set "
                             "from_static = true, or remove it")
        if _changed(self, ["bias_tau_s"]) and self.gyro_bias_model == self.accel_bias_model == "random-walk":
            raise _key_error("bias_tau_s", "noise.bias_tau_s would be ignored: both biases are random walks "
                             "(gyro_bias_model and accel_bias_model), which have no correlation time")
        return self

    def gyro_tau_s(self) -> float:
        """Correlation time of the gyro bias [s]; ``inf`` for a random walk."""
        if self.gyro_bias_model == "random-walk":
            return math.inf
        return self.bias_tau_s if self.gyro_bias_tau_s is None else self.gyro_bias_tau_s

    def accel_tau_s(self) -> float:
        """Correlation time of the accelerometer bias [s]; ``inf`` for a random walk."""
        if self.accel_bias_model == "random-walk":
            return math.inf
        return self.bias_tau_s if self.accel_bias_tau_s is None else self.accel_bias_tau_s


#: [init] keys of mode "given" (the initial state itself)
INIT_GIVEN_KEYS = ("lat_deg", "lon_deg", "height_m", "v_ned_m_s", "rpy_deg")
#: [init] keys of mode "static-then-track"
INIT_STATIC_KEYS = ("min_static_s", "heading_speed_m_s")
#: [init] keys of the in-motion start-up only
INIT_INMOTION_KEYS = ("course_average_s", "level_window_s", "yaw_deg")


def unused_inmotion_keys(init, startup_mode) -> list[str]:
    """The in-motion start-up's keys (:data:`INIT_INMOTION_KEYS`) that
    ``init`` sets but a run started ``startup_mode`` did not use: mode
    "auto" that found rest at the start and levelled there
    (static-then-track, which takes the yaw from the track)."""
    if init.mode != "auto" or startup_mode != "static-then-track":
        return []
    return _changed(init, INIT_INMOTION_KEYS)


class InitSection(_Strict):
    """The initial state and its uncertainty.

    Rules: mode "given" needs lat_deg, lon_deg, height_m and rpy_deg; the
    keys of one mode changed from their defaults under another mode are
    refused (they would be ignored).  The data-driven modes ("auto",
    "static-then-track", "in-motion") run a bank of yaw hypotheses when the
    initial yaw sigma exceeds 10 deg (the filter's small-angle limit).
    """

    mode: Literal["auto", "static-then-track", "in-motion", "given"] = Field(
        "auto", description="auto: static-then-track when the log starts with min_static_s of rest, else "
        "in-motion (the summary's startup entry says which and why); static-then-track: level and gyro biases "
        "from the static start, heading from the GNSS track once moving; in-motion: level on the specific force "
        "less the GNSS-derived acceleration, heading from the GNSS course, position and velocity from the fixes, "
        "sigmas from the data (the sigma_* keys then act as floors); given: the state of lat_deg ... rpy_deg")
    lat_deg: float | None = Field(None, description="given: initial latitude")
    lon_deg: float | None = Field(None, description="given: initial longitude")
    height_m: float | None = Field(None, description="given: initial ellipsoidal height")
    v_ned_m_s: tuple[float, float, float] = Field((0.0, 0.0, 0.0), description="given: initial velocity north, "
                                                  "east, down")
    rpy_deg: tuple[float, float, float] | None = Field(None, description="given: initial roll, pitch, yaw of the "
                                                       "body axes")
    min_static_s: float = Field(5.0, gt=0, description="static-then-track, auto: the rest the start-up needs at "
                                "the log's start to level and find the gyro biases [s]")
    heading_speed_m_s: float = Field(3.0, gt=0, description="static-then-track, in-motion, auto: the GNSS track "
                                     "speed from which its course gives the heading (a car: 3; a walk: 0.8)")
    course_average_s: float = Field(3.0, gt=0, description="in-motion, auto: span of fixes over which the course "
                                    "is averaged once above heading_speed_m_s [s]")
    level_window_s: float = Field(2.0, gt=0, description="in-motion, auto: span of IMU data from the start over "
                                  "which the acceleration-corrected specific force is levelled [s]")
    yaw_deg: float | None = Field(None, description="in-motion, auto: a first yaw guess instead of the track's "
                                  "course (a handheld device not pointing along its track, a magnetometer); taken "
                                  "as unknown on the circle, so the yaw bank searches around it")
    yaw_hypotheses: int = Field(12, ge=1, le=72, description="number of yaw hypotheses of the bank, spread evenly "
                                "over 360 deg (1: no bank); after it the yaw sigma is half their spacing")
    bank_s: float = Field(40.0, gt=0, description="data each yaw hypothesis is run over before the best (smallest "
                          "mean NIS of the GNSS updates) is kept [s]")
    vehicle_axes: Literal["find", "given"] = Field(
        "find", description="static-then-track, in-motion, auto (heading from the track): where the vehicle's "
        "forward and down axes lie in the IMU's (after imu.mount_rpy_deg) is measured at start-up from the GNSS "
        "acceleration against the specific force (the summary's startup.vehicle_axes); find: when the direction "
        "of travel lies more than 20 deg off the IMU's x axis, or its z axis points up, the readings are rotated "
        "into the vehicle's axes (reported, with the imu.mount_rpy_deg that says so; lever arms are taken in the "
        "vehicle's axes); given: the IMU's axes are taken for the vehicle's, and a mismatch makes the run "
        "unhealthy")
    sigma_pos_m: float = Field(0.05, gt=0, description="initial position sigma per axis; a start-up that takes "
                               "the position from a fix (static-then-track, in-motion, auto) uses that fix's "
                               "largest axis sigma, this the floor")
    sigma_vel_m_s: float = Field(0.05, gt=0, description="initial velocity sigma per axis")
    sigma_roll_pitch_deg: float = Field(1.0, gt=0, description="initial roll and pitch sigma")
    sigma_yaw_deg: float = Field(3.0, gt=0, description="initial yaw sigma (above 10 deg the yaw bank runs)")
    sigma_gyro_bias_deg_s: float = Field(0.05, gt=0, description="initial gyro-bias sigma per axis (turn-on "
                                         "bias class; the older spelling of noise.gyro_turn_on_bias_deg_h: give "
                                         "one)")
    sigma_accel_bias_m_s2: float = Field(0.05, gt=0, description="initial accelerometer-bias sigma per axis "
                                         "(turn-on bias class; the older spelling of noise.accel_turn_on_bias_mg: "
                                         "give one)")
    sigma_scale_factor: float = Field(0.02, gt=0, description="initial scale-factor sigma, a fraction (0.02 = "
                                      "2 %; with filter.scale_factors)")
    sigma_lever_arm_m: float = Field(0.1, gt=0, description="initial sigma of the estimated lever arm per axis "
                                     "(with filter.lever_arm)")
    sigma_time_offset_s: float = Field(0.05, gt=0, description="initial sigma of the estimated IMU-GNSS time "
                                       "offset (with filter.time_offset)")
    _angles = field_validator("rpy_deg", "yaw_deg")(check_angles)
    _longitude = field_validator("lon_deg")(check_longitude)
    _height = field_validator("height_m")(check_height)

    @model_validator(mode="after")
    def _given_complete(self):
        inmotion_keys = INIT_INMOTION_KEYS
        if self.mode == "given":
            missing = [k for k in ("lat_deg", "lon_deg", "height_m", "rpy_deg") if getattr(self, k) is None]
            if missing:
                raise ValueError(f"mode 'given' needs {', '.join(missing)}")
            if abs(self.lat_deg) > 90:
                raise ValueError(f"lat_deg {self.lat_deg} is outside [-90, 90]")
            bad = _changed(self, INIT_STATIC_KEYS + inmotion_keys + ("yaw_hypotheses", "bank_s", "vehicle_axes"))
            if bad:
                raise _key_error(bad[0], f"{_names(bad, 'init')} would be ignored: "
                                 f"{_they(bad, 'it tunes', 'they tune')} mode \"static-then-track\", "
                                 "\"in-motion\" or \"auto\", and mode is \"given\"")
        else:
            bad = _changed(self, INIT_GIVEN_KEYS)
            if bad:
                raise _key_error(bad[0], f"{_names(bad, 'init')} would be ignored: mode "
                                 "\"static-then-track\", \"in-motion\" and \"auto\" find the initial state "
                                 f"themselves; set mode = \"given\" to start from {_they(bad, 'it', 'them')}")
            if self.mode == "static-then-track":
                bad = _changed(self, inmotion_keys)
                if bad:
                    raise _key_error(bad[0], f"{_names(bad, 'init')} would be ignored: "
                                     f"{_they(bad, 'it tunes', 'they tune')} the in-motion start-up, and mode is "
                                     "\"static-then-track\" (use mode = \"in-motion\" or \"auto\")")
            if self.mode == "in-motion" and _changed(self, ("min_static_s",)):
                raise _key_error("min_static_s", "init.min_static_s would be ignored: mode \"in-motion\" uses no "
                                 "static start (use mode = \"auto\" to choose by the rest at the start)")
        return self


class ConstraintsSection(_Strict):
    """Pseudo-measurements of a vehicle's motion.

    Rules: sigma_mounting_deg and mounting_rw_deg_sqrt_h need mounting =
    true; mounting = true needs nhc = true or odometer.with_nhc = true, and a
    filter (not the uncoupled scheme); zupt_sigma_m_s needs zupt = true,
    nhc_sigma_m_s and nhc_lever_arm_b_m need nhc = true, rate_hz needs one
    of them (changed from their defaults, they would be ignored).
    """

    zupt: bool = Field(True, description="zero-velocity updates while the GNSS fixes show the vehicle at rest")
    zupt_sigma_m_s: float = Field(0.02, gt=0, description="sigma of a zero-velocity update per axis")
    nhc: bool = Field(True, description="non-holonomic constraint: no lateral or vertical velocity in body axes "
                      "(a land vehicle; off for a handheld device, a vessel, an aircraft). Left at its default, a "
                      "constraint refused in more than half its updates is dropped and the run made again "
                      "without it (the summary's constraint_check says so); set true or false, it is kept as set")
    nhc_sigma_m_s: float = Field(0.1, gt=0, description="sigma of the lateral and vertical body velocity")
    nhc_lever_arm_b_m: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0), description="IMU to the point where the non-holonomic constraint holds (the centre "
        "of the unsteered rear axle), body axes [m], each within +-1 km; 0: at the IMU")
    _lever_arm = field_validator("nhc_lever_arm_b_m")(check_lever_arm)
    rate_hz: float = Field(10.0, gt=0, le=1000, description="rate of the zero-velocity and non-holonomic updates")
    mounting: bool = Field(False, description="estimate the IMU's mounting in the vehicle (pitch and yaw of the "
                           "vehicle axes against the IMU's, after imu.mount_rpy_deg; 2 states) for the "
                           "non-holonomic constraint and the odometer")
    sigma_mounting_deg: float = Field(5.0, gt=0, le=30, description="initial sigma of the mounting angles")
    mounting_rw_deg_sqrt_h: float = Field(0.01, ge=0, description="random walk of the mounting angles")

    @model_validator(mode="after")
    def _mounting_keys(self):
        bad = [] if self.mounting else _changed(self, ("sigma_mounting_deg", "mounting_rw_deg_sqrt_h"))
        if bad:
            raise _key_error(bad[0], f"{_names(bad, 'constraints')} would be ignored: the mounting is estimated "
                             "only with constraints.mounting = true")
        return self

    @model_validator(mode="after")
    def _constraint_keys(self):
        if not self.zupt and _changed(self, CONSTRAINT_SWITCH_KEYS["zupt"]):
            raise _key_error("zupt_sigma_m_s", "constraints.zupt_sigma_m_s would be ignored: it is the sigma of the "
                             "zero-velocity updates, and zupt = false applies none; set constraints.zupt = true, or "
                             "remove it")
        bad = [] if self.nhc else _changed(self, CONSTRAINT_SWITCH_KEYS["nhc"])
        if bad:
            raise _key_error(bad[0], f"{_names(bad, 'constraints')} would be ignored: "
                             f"{_they(bad, 'it tunes', 'they tune')} the non-holonomic constraint, and nhc = false "
                             "applies none (odometer.with_nhc has its own nhc_sigma_m_s and takes the wheel point "
                             "odometer.lever_arm_b_m); set constraints.nhc = true, or remove "
                             f"{_they(bad, 'it', 'them')}")
        if not self.zupt and not self.nhc and _changed(self, ("rate_hz",)):
            raise _key_error("rate_hz", "constraints.rate_hz would be ignored: it is the rate of the zero-velocity "
                             "and non-holonomic updates, and zupt = false and nhc = false apply neither; remove it")
        return self


class FilterSection(_Strict):
    """The integration scheme and the error state.

    Rules: the keys of other sections that describe an optional state are
    refused, changed from their defaults, when the state is off (they would
    be ignored): init.sigma_scale_factor and
    noise.scale_factor_rw_ppm_sqrt_s need scale_factors = true,
    init.sigma_lever_arm_m needs lever_arm = true, init.sigma_time_offset_s
    and noise.time_offset_rw_s_sqrt_s need time_offset = true.  The
    uncoupled scheme (no filter) refuses what only a filter fuses or
    estimates: gnss.use_velocity, gnss.error_sigma_m, gnss.speed_course,
    [odometer], [height], lever_arm, time_offset and the constraints'
    sigmas, lever arm and rate changed from their defaults.
    """

    scheme: Literal["closed", "open", "uncoupled"] = Field(
        "closed", description="closed: estimated errors fed back into the INS; open: the INS runs free and its "
        "errors are estimated beside it; uncoupled: the INS is reset to each fix (no filter, loose coupling only)")
    scale_factors: bool = Field(True, description="estimate gyro and accelerometer scale-factor errors (6 states)")
    lever_arm: bool = Field(False, description="estimate the antenna lever arm (3 states), from gnss.lever_arm_b_m")
    time_offset: bool = Field(False, description="estimate the IMU-GNSS time offset as a state")
    gate_probability: float | None = Field(0.9999, gt=0.5, lt=1.0, description="chi-square gate of the "
                                           "innovations: the probability that a consistent measurement passes")
    gate_max_consecutive: int | None = Field(3, ge=1, description="recovery of a lost filter: after this many "
                                             "mutually consistent rejections of one measurement (over at least "
                                             "15 s; for the fixes, also a smooth drift away from the INS, as a "
                                             "wrong tilt makes) the covariance is inflated and the measurement "
                                             "applied, or, when the fixes' drift says a tilt beyond 7 deg, the "
                                             "filter re-initialised on them (a constraint not while the fixes are "
                                             "refused too)")
    smoother_node_s: float = Field(0.25, gt=0, description="spacing of the extra RTS smoother nodes between "
                                   "updates (with --smooth)")
    covariance_step_s: float = Field(0.02, ge=0, le=1, description="interval of the covariance propagation [s]: "
                                     "stepped at the IMU row nearest this much gathered time (and always up to "
                                     "an update), with the rows' mean rate and specific force; the strapdown "
                                     "integrates every IMU row whatever it is; 0: at every IMU row")


_WINDOWS_EXAMPLE = "windows_s = [[100, 110], [130, 145]]"


def _shown_window(v):
    return "a table" if isinstance(v, dict) else repr(v)


def windows_conflict(windows):
    """Why the outage windows ``windows`` (``[start, end]`` pairs) cannot be
    taken as they are, or None: two that overlap (their fixes would be
    scored twice) or touch (one outage, the first without an end of its
    own); the words name no source (the caller says where they came from)."""
    w = sorted((float(a), float(b)) for a, b in windows)
    for (a0, b0), (a1, b1) in zip(w, w[1:]):
        if a1 < b0:
            return (f"outage windows [{a0:g}, {b0:g}] and [{a1:g}, {b1:g}] overlap (their fixes would be scored "
                    f"twice); merge them into [{a0:g}, {max(b0, b1):g}]")
        if a1 == b0:
            return (f"outage windows [{a0:g}, {b0:g}] and [{a1:g}, {b1:g}] touch: they are one outage, and the first "
                    f"would have no end of its own; merge them into [{a0:g}, {b1:g}] or leave a gap with a fix "
                    "between them")
    return None


class OutagesSection(_Strict):
    """GNSS outages: fixes (or satellites) withheld to score the coasting INS.

    Rules: windows_s needs protocol = "windows", and protocol = "windows"
    needs windows_s; its windows may neither overlap nor touch (merge them);
    keep_satellites needs windows (protocol "windows" or "rtklibexplorer")
    and tight coupling.
    """

    protocol: Literal["none", "rtklibexplorer", "windows"] = Field(
        "none", description="none; rtklibexplorer: the dataset's eleven outages, 40 + 45 k to 54.75 + 45 k s "
        "after the first GNSS epoch (k = 0..10); windows: the windows of windows_s")
    windows_s: list[tuple[float, float]] = Field(
        default_factory=list, description="[start, end] seconds after the first GNSS epoch (protocol = \"windows\"); "
        "the outage table numbers them k = 0, 1, ... in time order, whatever the order given"
    )
    keep_satellites: int = Field(0, ge=0, le=12, description="tight coupling: satellites kept inside each "
                                 "window (the highest ones), 0 for a full outage")

    @field_validator("windows_s", mode="before")
    @classmethod
    def _pairs(cls, v):
        if isinstance(v, (list, tuple)):
            for w in v:
                if not isinstance(w, (list, tuple)) or len(w) != 2:
                    raise ValueError(f"{_shown_window(w)} is not a window: windows_s is a list of [start, end] pairs "
                                     f"in seconds after the first GNSS epoch, e.g. {_WINDOWS_EXAMPLE}")
        else:
            raise ValueError(f"{_shown_window(v)} is not a list of windows: windows_s is a list of [start, end] "
                             f"pairs in seconds after the first GNSS epoch, e.g. {_WINDOWS_EXAMPLE}")
        return v

    @field_validator("windows_s")
    @classmethod
    def _ordered(cls, v):
        for a, b in v:
            if not b > a:
                raise ValueError(f"outage window [{a:g}, {b:g}] must end after it starts")
            if a < 0:
                raise ValueError(f"outage window [{a:g}, {b:g}] starts before the first GNSS epoch (times are "
                                 "seconds after it, >= 0)")
        clash = windows_conflict(v)
        if clash:
            raise ValueError(clash)
        # numbered in time order (the outage table's k), whatever the order given: windows 900-960, 300-330 made
        # k = 0 the later one
        return sorted((float(a), float(b)) for a, b in v)

    @model_validator(mode="after")
    def _consistent(self):
        if self.windows_s and self.protocol != "windows":
            raise _key_error("windows_s", f"windows_s is given but protocol = \"{self.protocol}\", which would "
                             "ignore it; set protocol = \"windows\" to withhold GNSS in these windows")
        if self.protocol == "windows" and not self.windows_s:
            raise _key_error("windows_s", "protocol = \"windows\" needs windows_s, [start, end] pairs in seconds "
                             "after the first GNSS epoch, e.g. windows_s = [[15, 25], [30, 40]]")
        if self.keep_satellites and self.protocol == "none":
            raise _key_error("keep_satellites", f"keep_satellites = {self.keep_satellites} needs outage windows "
                             "(protocol = \"windows\" or \"rtklibexplorer\"); with protocol = \"none\" it would "
                             "be ignored")
        return self


class OutputSection(_Strict):
    """Where the results go."""

    dir: Path | None = Field(None, description="result folder, relative to this config file (default: out/<name> "
                             "in the working directory; --out overrides it)")
    plots: bool = Field(True, description="write the PNG plots (--no-plots turns them off)")
    format: Literal["parquet", "csv", "both"] = Field(
        "both", description="solution files: parquet (solution_forward.parquet, and _smoothed, every IMU epoch, "
        "float64 columns with their units in the schema metadata), csv (solution_forward.csv at rate_hz), or both "
        "(the CSV keeps `inskit report` and scripts that read CSV working); --output-format overrides it")
    rate_hz: float = Field(
        10.0, gt=0, le=MAX_RATE_HZ, description="rows per second of the CSV solution files (the first row at or after each "
        "multiple of 1/rate_hz, plus the first and last rows); a rate at or above the IMU rate writes every "
        "epoch. 10 Hz matches the ZUPT/NHC update rate and makes 1 h of 31 columns 21 MB instead of 211 MB "
        "at 100 Hz; Parquet files always hold every epoch; --output-rate overrides it")
    stream: Literal["auto", "on", "off"] = Field(
        "auto", description="write the solution files while the filter runs, keeping in memory only the rows "
        "the summary and plots use (the rows around each fix, every row of an outage window, the rate_hz grid, "
        f"at most {KEPT_GRID_ROWS} rows of it), so memory grows by the IMU log itself (56 bytes per epoch) and little else, "
        "and the files are "
        "written on a second core while the filter computes: auto and on (the same: every run with a filter), or off (every row kept, as "
        "navigate() in Python does). The numbers are the same either way. A streamed smoother keeps its node "
        "data (about 11 KB per update node) in a scratch folder of the result folder until the run ends")
    columns: list[str] = Field(
        ["all"], description="columns of the solution files: groups \"all\", \"navigation\" (time, position, "
        "velocity, attitude), \"navigation+sigma\", \"sigma\", \"estimates\" (biases, scale factors, lever arm, "
        "clock ...) and column names, combined (a single string is a one-element list); the navigation columns "
        "are always written. A name that is neither a group nor a column the solution of this configuration has "
        "(its states: filter.scale_factors, gnss.coupling ...) is refused when the config is loaded")

    @field_validator("columns", mode="before")
    @classmethod
    def _one_string(cls, v):
        return [v] if isinstance(v, str) else v

    @field_validator("columns")
    @classmethod
    def _known_groups(cls, v):
        if not v:
            raise ValueError("give at least one group or column name (e.g. \"navigation\")")
        for s in v:
            if not s or not re.fullmatch(r"[A-Za-z0-9_+]+", s):
                raise ValueError(f"{s!r} is not a group or a column name (letters, digits, _ and +)")
        return v

    @model_validator(mode="after")
    def _rate_needs_csv(self):
        if self.format == "parquet" and "rate_hz" in _changed(self, ["rate_hz"]):
            raise _key_error("rate_hz", f"rate_hz = {self.rate_hz:g} sets the rate of the CSV files, but format = "
                             "\"parquet\" writes none (Parquet holds every epoch); use format = \"both\" or "
                             "\"csv\", or drop rate_hz")
        return self


class OdometerSection(_Strict):
    """Wheel speed (odometer) aiding: the speed along the vehicle's forward
    axis at the wheel point, with an estimated scale-factor error."""

    file: Path = Field(..., description="odometer log: CSV with time_s (IMU time base) and speed_m_s")
    time_offset_s: float = Field(0.0, description="added to the log's time tags [s]")
    sigma_m_s: float = Field(0.05, gt=0, description="white noise of one speed reading [m/s]")
    rate_hz: float | None = Field(None, gt=0, description="use at most this many readings per second "
                                  "(default: every reading)")
    lever_arm_b_m: tuple[float, float, float] = Field((0.0, 0.0, 0.0), description="IMU to the wheel point, "
                                                      "body axes [m], each within +-1 km")
    _lever_arm = field_validator("lever_arm_b_m")(check_lever_arm)
    estimate_scale: bool = Field(True, description="estimate the odometer scale-factor error as a state")
    scale_sigma0: float = Field(0.01, gt=0, description="initial sigma of the scale-factor error [-]")
    scale_rw: float = Field(1e-6, ge=0, description="random walk of the scale-factor error [1/sqrt(s)]")
    with_nhc: bool = Field(False, description="apply the non-holonomic constraint at the wheel with each "
                           "reading (then leave constraints.nhc off)")
    nhc_sigma_m_s: float = Field(0.1, gt=0, description="sigma of the lateral and vertical rows with with_nhc "
                                 "[m/s]")


class TruthSection(_Strict):
    """A truth trajectory to score the run against (a simulation's): the
    outages are then scored against it as well as against the withheld fixes
    (`--truth` on the command line sets `file`)."""

    file: Path = Field(..., description="truth trajectory: a solution file (CSV or Parquet, told by content, as "
                       "`inskit simulate` writes truth.csv) on the solution's time base, relative to this config "
                       "file")


class EarthSection(_Strict):
    """The Earth model of the mechanization and the filter."""

    gravity: Literal["normal", "normal-simple", "j2"] = Field(
        "normal", description="gravity model: normal (WGS84 Somigliana normal gravity with the first- and "
        "second-order height terms and the north component), normal-simple (Somigliana with the first-order "
        "height term only, no north component: what many other tools use), or j2 (gravitation of a GM + J2 Earth "
        "plus centrifugal, with its north component); choose the model of the tool that made a truth you compare "
        "with (at 1600 m and 40 deg the north component alone, 1.3e-5 m/s^2, is 2.2 m over 600 s free-inertial)")


#: [height] keys of the bias state (they need estimate_bias)
HEIGHT_BIAS_KEYS = ("bias_model", "bias_sigma0_m", "bias_rw_m_sqrt_h", "bias_tau_s")


class HeightSection(_Strict):
    """Height aiding: a barometer's altitude or a known height profile (a
    road's, a ship's sea level), fused as a measurement of the height of the
    sensor point with its own sigma and, optionally, an estimated offset
    ``b`` (the barometer's bias: the reading is ``h + b`` plus noise).

    Rules: give ``file`` or ``height_m`` (a constant height), not both;
    ``time_offset_s`` needs a ``file``; the bias keys need ``estimate_bias``;
    ``bias_rw_m_sqrt_h`` belongs to bias_model "random-walk" and
    ``bias_tau_s`` to (and is needed by) "gauss-markov"; ``sigma_m`` is
    refused when the file has its own sigma_m column.  Heights are
    ellipsoidal, like the filter's: heights above mean sea level need the
    geoid separation in ``offset_m`` (or ``estimate_bias``, whose offset
    then absorbs it).
    """

    file: Path | None = Field(None, description="height log: CSV with time_s (IMU time base), height_m and "
                              "optionally sigma_m (docs/formats.md), relative to this config file")
    height_m: float | None = Field(None, description="a constant height instead of a file (a vehicle on a level "
                                   "site, a ship at sea level): the same measurement at rate_hz")
    time_offset_s: float = Field(0.0, description="added to the log's time tags [s]")
    offset_m: float = Field(0.0, description="added to every height, e.g. the geoid separation N for heights "
                            "above mean sea level (ellipsoidal = sea-level height + N)")
    sigma_m: float = Field(1.0, gt=0, description="white noise of one height reading (for a file without a "
                           "sigma_m column, and for height_m)")
    rate_hz: float = Field(1.0, gt=0, le=1000, description="use at most this many readings per second (the "
                           "readings are taken as independent); the rate of a constant height_m")
    lever_arm_b_m: tuple[float, float, float] = Field((0.0, 0.0, 0.0), description="IMU to the height sensor, "
                                                      "body axes (forward, right, down) [m], each within +-1 km")
    _lever_arm = field_validator("lever_arm_b_m")(check_lever_arm)
    estimate_bias: bool = Field(True, description="estimate the sensor's offset b as a state (a barometer: "
                                "its datum and the weather); off: the heights are taken as unbiased")
    bias_model: Literal["constant", "random-walk", "gauss-markov"] = Field(
        "random-walk", description="how the offset changes: a random constant, a random walk "
        "(bias_rw_m_sqrt_h) or first-order Gauss-Markov (bias_tau_s, steady-state sigma bias_sigma0_m)")
    bias_sigma0_m: float = Field(50.0, gt=0, description="initial sigma of the offset (gauss-markov: also its "
                                 "steady-state sigma); GNSS heights make it observable, so a loose value is "
                                 "harmless")
    bias_rw_m_sqrt_h: float = Field(2.0, gt=0, description="random-walk: the offset's drift in 1 h, 1 sigma (a "
                                    "barometer: 2 m is 0.25 hPa of weather per sqrt(h))")
    bias_tau_s: float | None = Field(None, gt=0, description="gauss-markov: correlation time of the offset")
    _height = field_validator("height_m")(check_height)

    @model_validator(mode="after")
    def _consistent(self):
        if (self.file is None) == (self.height_m is None):
            raise ValueError("[height] needs file (a height log) or height_m (a constant height), exactly one")
        if self.file is None and _changed(self, ["time_offset_s"]):
            raise _key_error("time_offset_s", "height.time_offset_s would be ignored: it shifts the time tags of "
                             "height.file, and a constant height_m has none")
        if not self.estimate_bias:
            bad = _changed(self, HEIGHT_BIAS_KEYS)
            if bad:
                raise _key_error(bad[0], f"{_names(bad, 'height')} would be ignored: "
                                 f"{_they(bad, 'it describes', 'they describe')} the estimated offset, and "
                                 "estimate_bias = false")
            return self
        if self.bias_model != "random-walk" and _changed(self, ["bias_rw_m_sqrt_h"]):
            raise _key_error("bias_rw_m_sqrt_h", f"height.bias_rw_m_sqrt_h would be ignored: bias_model = "
                             f"\"{self.bias_model}\" (it is the strength of a random-walk offset)")
        if self.bias_model == "gauss-markov" and self.bias_tau_s is None:
            raise _key_error("bias_tau_s", "bias_model = \"gauss-markov\" needs height.bias_tau_s, the offset's "
                             "correlation time [s]")
        if self.bias_model != "gauss-markov" and self.bias_tau_s is not None:
            raise _key_error("bias_tau_s", f"height.bias_tau_s would be ignored: bias_model = \"{self.bias_model}\" "
                             "has no correlation time (use bias_model = \"gauss-markov\")")
        return self


#: the [filter] switches of optional states, the keys of other sections that describe each state (they would be
#: ignored without it) and what the state is
FILTER_STATE_KEYS = (
    ("scale_factors", (("init", ("sigma_scale_factor",)), ("noise", ("scale_factor_rw_ppm_sqrt_s",))),
     "scale-factor errors"),
    ("lever_arm", (("init", ("sigma_lever_arm_m",)),), "lever arm"),
    ("time_offset", (("init", ("sigma_time_offset_s",)), ("noise", ("time_offset_rw_s_sqrt_s",))),
     "IMU-GNSS time offset"),
)


#: switches and the keys that only count with the switch on ("section.key" -> keys): a config that sets one of
#: those keys with its switch off is refused (the key would be ignored); ``inskit tune`` resets them to their
#: defaults in a candidate that turns the switch off (:func:`switched_off_overrides`)
SWITCH_KEYS = {
    "constraints.zupt": tuple(f"constraints.{k}" for k in CONSTRAINT_SWITCH_KEYS["zupt"]),
    # the mounting is estimated through the NHC (odometer.with_nhc aside): off with it, and its own keys with it
    "constraints.nhc": tuple(f"constraints.{k}" for k in CONSTRAINT_SWITCH_KEYS["nhc"]) + ("constraints.mounting",),
    "constraints.mounting": ("constraints.sigma_mounting_deg", "constraints.mounting_rw_deg_sqrt_h"),
    "gnss.use_velocity": tuple(f"gnss.{k}" for k in GNSS_VELOCITY_KEYS),
    **{f"filter.{switch}": tuple(f"{sect}.{k}" for sect, ks in keys for k in ks)
       for switch, keys, _ in FILTER_STATE_KEYS},
}


#: the keys the uncoupled scheme (no filter) refuses changed from their defaults (NavigateConfig._turn_on_once;
#: mounting and error_tau_s by their own rules first) and an uncoupled candidate of ``inskit tune`` resets to them;
#: the switches among them reset their own keys too
UNCOUPLED_OFF = ("gnss.use_velocity", "gnss.error_sigma_m", "gnss.error_tau_s", "gnss.speed_course",
                 "gnss.sigma_scale_ned", "gnss.sigma_scale_search",
                 "filter.lever_arm", "filter.time_offset", "constraints.mounting", "constraints.zupt_sigma_m_s",
                 "constraints.nhc_sigma_m_s", "constraints.nhc_lever_arm_b_m", "constraints.rate_hz")


def switched_off_overrides(params: dict) -> dict:
    """``{"section.key": default}`` for the keys of :data:`SWITCH_KEYS` whose
    switch ``params`` (``{"section.key": value}``, a tune candidate) turns
    off, unless ``params`` sets them itself: the candidate then runs without
    the feature instead of being refused for the keys the config sets for it
    (``--grid constraints.nhc=true,false`` on drive_0708, whose
    ``nhc_sigma_m_s`` serves the ``true`` candidate); a candidate of the
    uncoupled scheme also resets :data:`UNCOUPLED_OFF`."""
    out = {}
    todo = [k for k, v in params.items() if k in SWITCH_KEYS and v is False]

    def reset(k):  # to its default; a switch whose default is off resets its own keys too (nhc -> mounting -> ...)
        if k in params or k in out:
            return
        sect, key = k.split(".")
        out[k] = NavigateConfig.model_fields[sect].annotation.model_fields[key].default
        if k in SWITCH_KEYS and out[k] is False:
            todo.append(k)

    if params.get("filter.scheme") == "uncoupled":  # no filter: what only a filter fuses or estimates goes too
        for k in UNCOUPLED_OFF:
            reset(k)
    while todo:
        for k in SWITCH_KEYS[todo.pop()]:
            reset(k)
    return out


class NavigateConfig(_Strict):
    """The whole ``inskit navigate`` configuration."""

    name: str = Field("run", description="name of the run (the default output folder is out/<name>): one folder "
                      "name, without '/', '\\' or ':', not starting with '.'", max_length=100)
    imu: ImuSection = Field(..., description="the IMU log")
    gnss: GnssSection = Field(..., description="the GNSS input")
    noise: NoiseSection = Field(NoiseSection(), description="sensor noise of the filter")
    init: InitSection = Field(InitSection(), description="initial state and uncertainty")
    constraints: ConstraintsSection = Field(ConstraintsSection(), description="motion constraints")
    filter: FilterSection = Field(FilterSection(), description="integration scheme and error state")
    outages: OutagesSection = Field(OutagesSection(), description="GNSS outage protocol")
    output: OutputSection = Field(OutputSection(), description="results")
    odometer: OdometerSection | None = Field(None, description="wheel-speed aiding (optional)")
    truth: TruthSection | None = Field(None, description="truth trajectory to score against (optional)")
    earth: EarthSection = Field(EarthSection(), description="Earth model (gravity)")
    height: HeightSection | None = Field(None, description="height aiding: a barometer or a height profile "
                                         "(optional)")
    base_dir: Path = Field(Path("."), description="(set by the loader, not a key of the file) the folder "
                           "relative paths are taken from: the config file's")

    @field_validator("name")
    @classmethod
    def _name_is_a_folder_name(cls, v):
        import re

        if not v.strip() or v != v.strip() or v.startswith(".") or re.search(r"[/\\:\x00-\x1f]", v):
            raise ValueError(f"{v!r} is not a plain folder name (the default output folder is out/<name>): no path "
                             "separators ('/', '\\', ':'), not empty, not starting with '.' or a space")
        return v

    @model_validator(mode="after")
    def _mounting_needs_a_vehicle_constraint(self):
        c = self.constraints
        if c.mounting and not c.nhc and not (self.odometer is not None and self.odometer.with_nhc):
            raise _key_error("constraints.mounting", "mounting = true estimates the mounting through the "
                             "lateral and vertical zero velocity of the vehicle, and neither constraints.nhc nor "
                             "odometer.with_nhc applies it (the forward speed alone sees the mounting only to "
                             "second order)")
        if c.mounting and self.filter.scheme == "uncoupled":
            raise _key_error("constraints.mounting", "mounting = true needs a filter: the uncoupled scheme has "
                             "none")
        if self.odometer is not None and self.odometer.with_nhc and c.nhc:
            raise _key_error("odometer.with_nhc", "odometer.with_nhc applies the non-holonomic constraint at the "
                             "wheel: turn constraints.nhc off (it would be applied twice)")
        if self.gnss.coupling == "tight" and self.filter.scheme == "uncoupled":
            raise _key_error("filter.scheme", "the uncoupled scheme resets the INS to position fixes: it has no "
                             "tight form (use filter.scheme = \"closed\" or \"open\")")
        return self

    @model_validator(mode="after")
    def _keep_needs_tight(self):
        if self.outages.keep_satellites and self.gnss.coupling != "tight":
            raise _key_error("outages.keep_satellites", f"keep_satellites = {self.outages.keep_satellites} "
                             "keeps satellites inside the outage windows, which only tight coupling fuses; with "
                             "coupling = \"loose\" a fix is withheld whole and it would be ignored")
        return self

    @model_validator(mode="after")
    def _turn_on_once(self):
        for new, old in (("gyro_turn_on_bias_deg_h", "sigma_gyro_bias_deg_s"),
                         ("accel_turn_on_bias_mg", "sigma_accel_bias_m_s2")):
            if getattr(self.noise, new) is not None and old in self.init.model_fields_set:
                raise _key_error(f"noise.{new}", f"noise.{new} and init.{old} both give the turn-on bias sigma; "
                                 f"keep one (noise.{new} is the datasheet spelling, init.{old} the older one)")
        if self.height is not None and self.filter.scheme == "uncoupled":
            raise _key_error("height", "[height] would be ignored: the uncoupled scheme has no filter to fuse "
                             "heights into (use filter.scheme = \"closed\" or \"open\")")
        if self.filter.scheme == "uncoupled" and self.imu.time_offset_search == "calibrate":
            raise _key_error("imu.time_offset_search", "imu.time_offset_search = \"calibrate\" "
                             "(--calibrate-time-offset) fits the offset to the filter's GNSS innovations, and the "
                             "uncoupled scheme has no filter: use filter.scheme = \"closed\" or \"open\" to "
                             "calibrate, or give imu.time_offset_s")
        if self.filter.scheme == "uncoupled":  # the INS reset to each fix: no filter, so none of these is applied
            bad = [k for k in UNCOUPLED_OFF if _changed(getattr(self, k.split(".")[0]), (k.split(".")[1],))]
            bad += ["odometer"] if self.odometer is not None else []
            if bad:
                raise _key_error(bad[0], f"{', '.join(bad)} would be ignored: the uncoupled scheme resets the INS to "
                                 "each position fix and has no filter to fuse velocities, wheel speed or "
                                 "constraints into, nor states to estimate; use filter.scheme = \"closed\" or "
                                 f"\"open\", or remove {_they(bad, 'it', 'them')}")
        return self

    @model_validator(mode="after")
    def _state_keys_need_their_state(self):
        for switch, keys, what in FILTER_STATE_KEYS:
            if getattr(self.filter, switch):
                continue
            bad = [f"{sect}.{k}" for sect, ks in keys for k in _changed(getattr(self, sect), ks)]
            if bad:
                raise _key_error(bad[0], f"{', '.join(bad)} would be ignored: "
                                 f"{_they(bad, 'it describes', 'they describe')} "
                                 f"the estimated {what}, and filter.{switch} = false estimates none; set "
                                 f"filter.{switch} = true, or remove {_they(bad, 'it', 'them')}")
        if self.noise.from_static_per_axis and self.init.mode in ("in-motion", "given"):
            raise _key_error("noise.from_static_per_axis", "noise.from_static_per_axis = true would be ignored: it "
                             "measures the white noise per axis on the static start, and init.mode = "
                             f"\"{self.init.mode}\" has none (only \"static-then-track\", or \"auto\" when the log "
                             "starts at rest, measures it); use init.mode = \"static-then-track\" or \"auto\", or "
                             "remove it")
        return self

    @model_validator(mode="after")
    def _columns_of_this_run(self):
        if not _changed(self.output, ["columns"]):  # every column: nothing to look up (nor the writers to import)
            return self
        from ..io.parquet import column_spec_error
        from .navigate import solution_column_names

        bad = column_spec_error(solution_column_names(self), self.output.columns,
                                of="the solution of this configuration")
        if bad:
            raise _key_error("output.columns", bad)
        return self

    def resolve(self, p: Path) -> Path:
        """``p`` relative to the config file's folder (absolute paths unchanged)."""
        p = Path(p)
        return p if p.is_absolute() else (self.base_dir / p)


#: keys of the models that are not keys of a config file
INTERNAL_KEYS = ("base_dir",)

_NUM = r"(\d+(?:\.\d*)?|\.\d+)"
_WINDOW = re.compile(rf"^\s*{_NUM}\s*-\s*{_NUM}\s*$")
_OUTAGES_EXAMPLE = ("none, rtklibexplorer, or windows:START-END[,START-END...] in seconds after the first GNSS "
                    "epoch, e.g. windows:15-25,30-40")


def outages_from_spec(spec: str, option: str = "--outages") -> dict:
    """The ``[outages]`` keys of a command-line outage spec.

    ``none`` (no outages: also clears ``keep_satellites``),
    ``rtklibexplorer`` (the dataset's protocol) or ``windows:15-25,30-40``
    (windows in seconds after the first GNSS epoch).  The windows of the
    config file are replaced, never merged.

    Raises
    ------
    InputError
        A malformed spec, with an example.
    """
    s = str(spec).strip()
    if s == "none":
        return {"protocol": "none", "windows_s": [], "keep_satellites": 0}
    if s == "rtklibexplorer":
        return {"protocol": "rtklibexplorer", "windows_s": []}
    if not s.startswith("windows:"):
        raise InputError(f"{option}: {spec!r} is not an outage protocol; use {_OUTAGES_EXAMPLE}")
    windows = []
    for item in s[len("windows:"):].split(","):
        m = _WINDOW.match(item)
        if not m:
            raise InputError(f"{option}: {item.strip()!r} in {spec!r} is not a window START-END of two numbers >= 0; "
                             f"use {_OUTAGES_EXAMPLE}")
        a, b = float(m.group(1)), float(m.group(2))
        if not b > a:
            raise InputError(f"{option}: the window {item.strip()!r} must end after it starts; use {_OUTAGES_EXAMPLE}")
        windows.append([a, b])
    clash = windows_conflict(windows)
    if clash:
        raise InputError(f"{option} {spec}: {clash}")
    return {"protocol": "windows", "windows_s": windows}


def load_config(path, overrides=None) -> NavigateConfig:
    """Read and validate a navigate config; ``overrides`` is a nested dict
    applied on top (the CLI flags)."""
    data = read_toml(path, "config")
    return config_from_dict(data, base_dir=Path(path).parent, source=str(path), overrides=overrides)


def _message(source, exc: ValidationError):
    """One line naming the field; a consistency rule names its own key."""
    errors = exc.errors()
    e = errors[0]
    if e["type"] != _KEY_ERROR:
        return validation_message(source, exc, NavigateConfig)
    where = ".".join([str(x) for x in e["loc"]] + [e["ctx"]["key"]])
    more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
    return f"{source}: field '{where}': {e['ctx']['text']}{more}"


def config_from_dict(data, *, base_dir=Path("."), source="config", overrides=None) -> NavigateConfig:
    """Validate a config given as a nested dict (``overrides`` merged per section)."""
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: a configuration is a dict of sections (or a TOML file), got "
                          f"{type(data).__name__}")
    data = dict(data)
    for sect, vals in (overrides or {}).items():
        if isinstance(vals, dict):
            have = data.get(sect, {})
            if not isinstance(have, dict):  # '{"imu": 3}' beside an override of [imu]: said of the section
                raise ConfigError(f"{source}: section '{sect}' is {type(have).__name__} {have!r}; expected a table "
                                  "of keys (a dict)")
            data[sect] = {**have, **vals}
        else:
            data[sect] = vals
    data["base_dir"] = base_dir
    try:
        cfg = NavigateConfig.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(_message(source, exc)) from None
    return cfg
