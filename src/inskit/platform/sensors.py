"""Platform sensor errors and initial (alignment) errors, SI units.

Axes: the errors are given in the axes of the gyro-stabilised platform.  For
the semi-analytical platform these are the axes it realises, x east, y north,
z up (source 000, SOURCES-NOTES §3.2); for the analytical platform and for
platform 1 of the geometric system they are the inertial axes the platform
holds (ECEF axes at the start of the run); the accelerometers of the
geometric system sit on platform 2 (east, north, up).

Source 004 writes its states and inputs in xi north, eta west, zeta up
(SOURCES-NOTES §2.1); :func:`enu_to_nwu` and :func:`nwu_to_enu` convert.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError
from ..types import plain_number

__all__ = ["M_NWU_ENU", "InitialErrors", "PlatformErrors", "enu_to_nwu", "nwu_to_enu"]

#: ``x_nwu = M_NWU_ENU @ x_enu`` (north, west, up from east, north, up)
M_NWU_ENU = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def enu_to_nwu(x):
    """``(..., 3)`` east, north, up -> north, west, up."""
    x = np.asarray(x, float)
    return np.stack([x[..., 1], -x[..., 0], x[..., 2]], -1)


def nwu_to_enu(x):
    """``(..., 3)`` north, west, up -> east, north, up."""
    x = np.asarray(x, float)
    return np.stack([-x[..., 1], x[..., 0], x[..., 2]], -1)


def _vec3(name, v):
    a = np.asarray(v, float).reshape(-1)
    if a.shape != (3,) or not np.isfinite(a).all():
        raise ConfigError(f"`{name}` must be three finite numbers, got {plain_number(v)}")
    return tuple(float(x) for x in a)


@dataclass(frozen=True)
class PlatformErrors:
    """Instrument errors of a gimballed platform.

    Attributes
    ----------
    gyro_drift : (3,) tuple
        Constant drift rates [rad/s], platform axes (see module docstring).
    gyro_noise : float
        Angle random walk [rad/sqrt(s)] (white rate noise density).
    accel_bias : (3,) tuple
        [m/s^2], accelerometer axes.
    accel_noise : float
        Velocity random walk [m/s/sqrt(s)].
    accel_scale : (3,) tuple
        Scale-factor errors (dimensionless).
    torquer_scale : (3,) tuple
        Scale-factor errors of the torquer commands (semi-analytical only).
    altimeter_bias : float
        Error of the height the vertical channel is slaved to [m].
    """

    gyro_drift: tuple = (0.0, 0.0, 0.0)
    gyro_noise: float = 0.0
    accel_bias: tuple = (0.0, 0.0, 0.0)
    accel_noise: float = 0.0
    accel_scale: tuple = (0.0, 0.0, 0.0)
    torquer_scale: tuple = (0.0, 0.0, 0.0)
    altimeter_bias: float = 0.0

    def __post_init__(self):
        for name in ("gyro_drift", "accel_bias", "accel_scale", "torquer_scale"):
            object.__setattr__(self, name, _vec3(name, getattr(self, name)))
        for name in ("gyro_noise", "accel_noise"):
            v = float(getattr(self, name))
            if not (np.isfinite(v) and v >= 0):
                raise ConfigError(f"`{name}` must be >= 0, got {plain_number(getattr(self, name))}")
            object.__setattr__(self, name, v)
        if not np.isfinite(self.altimeter_bias):
            raise ConfigError("`altimeter_bias` must be finite")


@dataclass(frozen=True)
class InitialErrors:
    """Errors of the initial alignment and position/velocity setting.

    Attributes
    ----------
    tilt : (3,) tuple
        Rotation vector of the platform relative to the frame it should
        realise at the start [rad], resolved in east, north, up.
    d_lat, d_lon : float
        Indicated minus true latitude and longitude [rad].
    dv_enu : (3,) tuple
        Indicated minus true velocity, east, north, up [m/s] (the vertical
        part is ignored when the vertical channel is slaved to the altimeter).
    """

    tilt: tuple = (0.0, 0.0, 0.0)
    d_lat: float = 0.0
    d_lon: float = 0.0
    dv_enu: tuple = field(default=(0.0, 0.0, 0.0))

    def __post_init__(self):
        object.__setattr__(self, "tilt", _vec3("tilt", self.tilt))
        object.__setattr__(self, "dv_enu", _vec3("dv_enu", self.dv_enu))
        for name in ("d_lat", "d_lon"):
            if not np.isfinite(getattr(self, name)):
                raise ConfigError(f"`{name}` must be finite")
