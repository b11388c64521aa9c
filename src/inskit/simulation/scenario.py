"""Scenario files (TOML) and the ``inskit simulate`` job.

A scenario names a start, an IMU (rate, grade preset, overrides), a GNSS
receiver model, optional vibration and a list of ``[[segment]]`` tables; see
``examples/*.toml``.  Units at this edge are degrees, deg/s, micro-g and the
like; everything is converted to SI here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from ..config_files import read_toml, validation_message
from ..errors import ConfigError
from ..types import GnssData, ImuData, NavSolution
from ..units import DEG
from .gnss import GnssErrors, simulate_gnss
from .imu import ideal_imu, truth_solution
from .segments import SegmentTrajectory
from .sensors import ImuErrors, apply_imu_errors, preset


class _S(BaseModel):
    model_config = ConfigDict(extra="forbid")


class StartSpec(_S):
    lat_deg: float = Field(..., ge=-90, le=90)
    lon_deg: float
    height_m: float = 0.0
    yaw_deg: float = 0.0
    speed_m_s: float = Field(0.0, ge=0)
    transition_s: float = Field(2.0, gt=0)


class ImuSpec(_S):
    rate_hz: float = Field(100.0, gt=0, le=10000)
    grade: Literal["ideal", "navigation", "tactical", "industrial-mems", "consumer-mems"] = "ideal"
    gyro: dict = Field(default_factory=dict, description="datasheet-unit overrides of the gyro preset")
    accel: dict = Field(default_factory=dict, description="datasheet-unit overrides of the accel preset")
    quadrature_nodes: int = Field(3, ge=1, le=12)
    lever_arm_b_m: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0), description="IMU position from the trajectory (truth) point, body axes")


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


class VibrationSpec(_S):
    target: Literal["roll", "pitch", "yaw", "down"]
    amplitude: float = Field(..., description="deg for attitude, m for 'down'")
    frequency_hz: float = Field(..., gt=0)
    kind: Literal["sinusoidal", "random"] = "sinusoidal"
    band_hz: tuple[float, float] | None = None


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


class Scenario(_S):
    name: str
    description: str = ""
    duration_limit_s: float | None = None
    start: StartSpec
    imu: ImuSpec = ImuSpec()
    gnss: GnssSpec = GnssSpec()
    vibration: list[VibrationSpec] = Field(default_factory=list)
    segment: list[SegmentSpec]


def load_scenario(path) -> Scenario:
    """Read and validate a scenario file."""
    data = read_toml(path, "scenario")
    try:
        return Scenario.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(validation_message(path, exc)) from None


def _need(seg, i, *names):
    for n in names:
        if getattr(seg, n) is None:
            raise ConfigError(f"segment {i} ({seg.type}) needs {n}")


def build_trajectory(sc: Scenario, rng=None) -> SegmentTrajectory:
    """The :class:`SegmentTrajectory` a scenario describes."""
    s = sc.start
    tr = SegmentTrajectory((s.lat_deg * DEG, s.lon_deg * DEG, s.height_m), s.yaw_deg * DEG, s.speed_m_s,
                           s.transition_s)
    for i, seg in enumerate(sc.segment, start=1):
        for _ in range(seg.repeat):
            t = seg.type
            if t == "static":
                _need(seg, i, "duration_s")
                tr.static(seg.duration_s)
            elif t in ("accelerate", "decelerate"):
                _need(seg, i, "speed_m_s", "duration_s")
                tr.accelerate(seg.speed_m_s, seg.duration_s)
            elif t == "cruise":
                _need(seg, i, "duration_s")
                tr.cruise(seg.duration_s)
            elif t in ("turn", "banked-turn"):
                _need(seg, i, "angle_deg")
                if seg.rate_deg_s is None and seg.radius_m is None:
                    raise ConfigError(f"segment {i} ({t}) needs rate_deg_s or radius_m")
                tr.turn(seg.angle_deg * DEG, rate=None if seg.rate_deg_s is None else seg.rate_deg_s * DEG,
                        radius=seg.radius_m, banked=(t == "banked-turn"))
            elif t in ("climb", "descend"):
                _need(seg, i, "angle_deg", "duration_s")
                a = abs(seg.angle_deg) * (1 if t == "climb" else -1)
                tr.climb(a * DEG, seg.duration_s)
            elif t in ("pitch", "roll"):
                _need(seg, i, "amplitude_deg", "duration_s")
                tr.attitude_pulse(t, seg.amplitude_deg * DEG, seg.duration_s)
            elif t == "coning":
                _need(seg, i, "amplitude_deg", "frequency_hz", "duration_s")
                tr.coning(seg.amplitude_deg * DEG, seg.frequency_hz, seg.duration_s)
            elif t == "figure-eight":
                _need(seg, i, "radius_m")
                tr.figure_eight(seg.radius_m)
    for v in sc.vibration:
        amp = v.amplitude if v.target == "down" else v.amplitude * DEG
        if v.kind == "sinusoidal":
            tr.vibration(v.target, amp, v.frequency_hz)
        else:
            if rng is None:
                raise ConfigError("random vibration needs a seed")
            band = v.band_hz or (0.5 * v.frequency_hz, 1.5 * v.frequency_hz)
            tr.random_vibration(v.target, amp, band, rng)
    return tr


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


@dataclass
class Simulation:
    scenario: Scenario
    trajectory: SegmentTrajectory
    truth: NavSolution
    imu_ideal: ImuData
    imu: ImuData
    gnss: GnssData
    draws: dict


def simulate(sc: Scenario, seed=0, *, truth_rate_hz=None, progress=None) -> Simulation:
    """Simulate a scenario: truth, ideal and measured IMU, GNSS fixes.

    One ``numpy.random.default_rng(seed)`` feeds every draw in a fixed order,
    so the same seed gives the same numbers (and byte-identical files).
    """
    rng = np.random.default_rng(seed)
    tr = build_trajectory(sc, rng)
    dt = 1.0 / sc.imu.rate_hz
    t = np.arange(0.0, tr.duration + 1e-9, dt)
    if len(t) < 2:
        raise ConfigError("the scenario is shorter than one IMU sample")
    ideal = ideal_imu(tr, t, nodes=sc.imu.quadrature_nodes, lever_arm_b=sc.imu.lever_arm_b_m)
    if progress:
        progress("ideal IMU")
    imu, draws = apply_imu_errors(ideal, imu_errors(sc), rng)
    gnss, gerr = simulate_gnss(tr, 0.0, tr.duration, gnss_errors(sc), rng)
    draws["gnss_position_errors"] = gerr
    if truth_rate_hz is not None and not truth_rate_hz > 0:
        raise ConfigError(f"the truth rate must be > 0 Hz, got {truth_rate_hz}")
    tt = t if truth_rate_hz is None else np.arange(0.0, tr.duration + 1e-9, 1.0 / truth_rate_hz)
    truth = truth_solution(tr, tt, with_rates=True)
    return Simulation(sc, tr, truth, ideal, imu, gnss, draws)
