"""The ``inskit navigate`` configuration: a validated TOML file.

Units follow datasheets at this edge (deg/sqrt(h), micro-g, degrees) and are
converted to SI when the filter settings are built.  Relative paths are taken
relative to the config file.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from ..config_files import read_toml, validation_message
from ..errors import ConfigError


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class ImuSection(_Strict):
    file: Path
    format: Literal["inskit", "rtklibexplorer"] = "inskit"
    time_offset_s: float = 0.0
    mount_rpy_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)
    check_units: bool = True
    start_s: float | None = Field(None, description="ignore IMU data before this time")
    gap_factor: float = Field(5.0, gt=1.0, description="an interval longer than this many median intervals is a gap")
    gap_rate_sigma_deg_s: float = Field(5.0, gt=0, description="unknown rate change assumed over a bridged gap")
    gap_accel_sigma_m_s2: float = Field(1.0, gt=0, description="unknown acceleration change over a bridged gap")


class GnssSection(_Strict):
    coupling: Literal["loose", "tight"] = Field(
        "loose", description="loose: position (and velocity) fixes from `file` update the filter; tight: "
        "pseudoranges and Doppler from the RINEX `obs` and `nav` files do, satellite by satellite")
    file: Path | None = Field(None, description="GNSS fixes: the measurements of loose coupling (default: our "
                              "own single-point solution of `obs` and `nav`); with tight coupling the reference "
                              "for start-up and scoring (default there: the same single-point solution)")
    format: Literal["inskit", "rtklib-pos"] = "inskit"
    time_offset_s: float = 0.0
    quality: list[int] = [1, 2]
    height_offset_m: float = Field(0.0, description="added to the fixes' heights (e.g. the geoid separation, "
                                   "-21.4 m on walk_0827, turns u-blox heights above sea level into ellipsoidal)")
    lever_arm_b_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    use_velocity: bool = False
    velocity_delay_s: float = 0.0
    velocity_sigma_scale: float = Field(1.0, gt=0)
    sigma_floor_m: float = Field(0.0, ge=0)
    obs: Path | None = Field(None, description="RINEX 2/3 observation file (tight coupling)")
    nav: Path | None = Field(None, description="RINEX 2/3 navigation file with the broadcast ephemerides")
    systems: list[Literal["G", "E"]] = Field(["G", "E"], description="satellite systems used (GPS, Galileo)")
    mask_deg: float = Field(10.0, ge=0, lt=90, description="elevation mask [deg]")
    iono: Literal["klobuchar", "iono-free", "none"] = "klobuchar"
    tropo: Literal["saastamoinen", "none"] = "saastamoinen"
    use_doppler: bool = Field(True, description="pseudorange-rate (Doppler) updates beside the pseudoranges")
    pseudorange_sigma_scale: float = Field(1.0, gt=0, description="multiplies the elevation-dependent sigmas")
    doppler_sigma_scale: float = Field(1.0, gt=0)
    clock_h0: float = Field(2e-19, gt=0, description="receiver oscillator white-frequency Allan coefficient")
    clock_h_2: float = Field(2e-20, gt=0, description="receiver oscillator random-walk-frequency coefficient")

    @model_validator(mode="after")
    def _inputs(self):
        if self.coupling == "loose" and self.file is None and (self.obs is None or self.nav is None):
            raise ValueError("loose coupling needs gnss.file (the fixes to fuse), or gnss.obs and gnss.nav "
                             "(RINEX: then our own single-point solution is fused)")
        if self.coupling == "tight" and (self.obs is None or self.nav is None):
            raise ValueError("tight coupling needs gnss.obs and gnss.nav (RINEX observation and navigation "
                             "files)")
        return self


class NoiseSection(_Strict):
    gyro_arw_deg_sqrt_h: float = Field(0.3, gt=0)
    accel_vrw_m_s_sqrt_h: float = Field(0.1, gt=0)
    gyro_bias_sigma_deg_h: float = Field(50.0, gt=0)
    accel_bias_sigma_ug: float = Field(1000.0, gt=0)
    bias_tau_s: float = Field(300.0, gt=0)
    scale_factor_rw_ppm_sqrt_s: float = Field(1.0, gt=0)
    time_offset_rw_s_sqrt_s: float = Field(1e-5, gt=0, description="random walk of the estimated time offset")
    from_static: bool = Field(
        True, description="raise ARW/VRW to the white-noise density measured on the static start"
    )


class InitSection(_Strict):
    mode: Literal["static-then-track", "given"] = "static-then-track"
    lat_deg: float | None = None
    lon_deg: float | None = None
    height_m: float | None = None
    v_ned_m_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy_deg: tuple[float, float, float] | None = None
    min_static_s: float = Field(5.0, gt=0, description="static-then-track: the rest the start-up needs at the "
                                "log's start to level and find the gyro biases [s]")
    heading_speed_m_s: float = Field(3.0, gt=0, description="static-then-track: the GNSS track speed from which "
                                     "its course gives the heading (a walk needs about 1 m/s)")
    sigma_pos_m: float = Field(0.05, gt=0)
    sigma_vel_m_s: float = Field(0.05, gt=0)
    sigma_roll_pitch_deg: float = Field(1.0, gt=0)
    sigma_yaw_deg: float = Field(3.0, gt=0)
    sigma_gyro_bias_deg_s: float = Field(0.05, gt=0)
    sigma_accel_bias_m_s2: float = Field(0.05, gt=0)
    sigma_scale_factor: float = Field(0.02, gt=0)
    sigma_lever_arm_m: float = Field(0.1, gt=0)
    sigma_time_offset_s: float = Field(0.05, gt=0)

    @model_validator(mode="after")
    def _given_complete(self):
        if self.mode == "given":
            missing = [k for k in ("lat_deg", "lon_deg", "height_m", "rpy_deg") if getattr(self, k) is None]
            if missing:
                raise ValueError(f"mode 'given' needs {', '.join(missing)}")
            if abs(self.lat_deg) > 90:
                raise ValueError(f"lat_deg {self.lat_deg} is outside [-90, 90]")
        return self


class ConstraintsSection(_Strict):
    zupt: bool = True
    zupt_sigma_m_s: float = Field(0.02, gt=0)
    nhc: bool = True
    nhc_sigma_m_s: float = Field(0.1, gt=0)
    rate_hz: float = Field(10.0, gt=0, le=1000)


class FilterSection(_Strict):
    scheme: Literal["closed", "open", "uncoupled"] = "closed"
    scale_factors: bool = True
    lever_arm: bool = False
    time_offset: bool = Field(False, description="estimate the IMU-GNSS time offset as a state")
    gate_probability: float | None = Field(0.9999, gt=0.5, lt=1.0)
    gate_max_consecutive: int | None = Field(3, ge=1)
    smoother_node_s: float = Field(0.25, gt=0)


class OutagesSection(_Strict):
    protocol: Literal["none", "rtklibexplorer", "windows"] = "none"
    windows_s: list[tuple[float, float]] = Field(
        default_factory=list, description="[start, end] seconds after the first GNSS epoch"
    )
    keep_satellites: int = Field(0, ge=0, le=12, description="tight coupling: satellites kept inside each "
                                 "window (the highest ones), 0 for a full outage")

    @field_validator("windows_s")
    @classmethod
    def _ordered(cls, v):
        for a, b in v:
            if not b > a:
                raise ValueError(f"outage window [{a}, {b}] must end after it starts")
        return v


class OutputSection(_Strict):
    dir: Path | None = None
    plots: bool = True


class NavigateConfig(_Strict):
    """The whole ``inskit navigate`` configuration."""

    name: str = "run"
    imu: ImuSection
    gnss: GnssSection
    noise: NoiseSection = NoiseSection()
    init: InitSection = InitSection()
    constraints: ConstraintsSection = ConstraintsSection()
    filter: FilterSection = FilterSection()
    outages: OutagesSection = OutagesSection()
    output: OutputSection = OutputSection()
    base_dir: Path = Path(".")

    def resolve(self, p: Path) -> Path:
        p = Path(p)
        return p if p.is_absolute() else (self.base_dir / p)


def load_config(path, overrides=None) -> NavigateConfig:
    """Read and validate a navigate config; ``overrides`` is a nested dict
    applied on top (the CLI flags)."""
    data = read_toml(path, "config")
    return config_from_dict(data, base_dir=Path(path).parent, source=str(path), overrides=overrides)


def config_from_dict(data, *, base_dir=Path("."), source="config", overrides=None) -> NavigateConfig:
    data = dict(data)
    for sect, vals in (overrides or {}).items():
        if isinstance(vals, dict):
            data[sect] = {**data.get(sect, {}), **vals}
        else:
            data[sect] = vals
    data["base_dir"] = base_dir
    try:
        cfg = NavigateConfig.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(validation_message(source, exc)) from None
    if cfg.noise.bias_tau_s == math.inf:
        raise ConfigError(f"{source}: noise.bias_tau_s must be finite (use a long time constant for a random walk)")
    return cfg
