"""The simulated world of a platform run: Earth model, true motion, satellite fixes.

Earth models
------------
``"wgs84"``: the ellipsoid, Somigliana gravity with height terms
(:mod:`inskit.earth`); the truth is the trajectory's own position.

``"sphere"``: the sphere of radius ``R = 6378 km`` the sources use
(SYSTEM.md §1.1, SOURCES-NOTES §3.2), with radial gravity ``GM/(R+h)^2``.
The trajectory's velocity history (north, east, down components) and attitude
are flown over the sphere: latitude and longitude are integrated on the sphere
(RK4 at quarter steps of the run's step, far below a millimetre).  World and
navigation computer always use the same model, so that perfect sensors give a
perfect solution; the model is a choice of the run, not an error source.

The true specific force follows from the NED navigation equation solved for
``f``: ``f_n = a_n + (2 omega_ie + omega_en) x v_n - g_n`` (SYSTEM.md §1.4),
with the radii and gravity of the chosen model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import earth
from .. import rotations as rot
from ..errors import ConfigError, InputError
from ..strapdown import check_track_off_pole
from ..types import NavSolution
from . import _kernels as K

EARTH_MODELS = {"wgs84": K.WGS84, "sphere": K.SPHERE}

__all__ = ["EARTH_MODELS", "PlatformTruth", "SnsFixes", "model_code", "platform_truth", "simulate_sns"]


def model_code(name):
    if name not in EARTH_MODELS:
        raise ConfigError(f"`earth` must be one of {sorted(EARTH_MODELS)}, got {name!r}")
    return EARTH_MODELS[name]


def radii(lat, h, model):
    """``(R_N + h, R_E + h)`` [m] of the model (arrays broadcast)."""
    if model == "sphere":
        r = earth.R_SPHERE + np.asarray(h, float)
        return r, r
    return earth.principal_radii(lat, h)


def gravity_ned(lat, h, model):
    """Plumb-bob gravity ``(n, 3)`` NED of the model [m/s^2]."""
    if model == "sphere":
        h = np.asarray(h, float)
        g = earth.GM / (earth.R_SPHERE + h) ** 2
        z = np.zeros_like(g)
        return np.stack([z, z, g], -1)
    return earth.gravity_n(lat, h)


@dataclass(frozen=True)
class PlatformTruth:
    """True motion sampled at half steps of a fixed-step run.

    Index ``2k`` of every half-step array is epoch ``k`` (``time[k]``), index
    ``2k + 1`` the midpoint the RK4 stages use.

    Attributes
    ----------
    time : (n,) ndarray
        Epochs [s], uniform step ``dt``.
    dt : float
    earth : {"wgs84", "sphere"}
    lla : (2n-1, 3) ndarray
        Latitude, longitude [rad], height [m].
    v_n : (2n-1, 3) ndarray
        NED velocity [m/s].
    f_n : (2n-1, 3) ndarray
        Specific force resolved in NED [m/s^2].
    q_nb : (2n-1, 4) ndarray
        Body attitude, scalar first.
    """

    time: np.ndarray
    dt: float
    earth: str
    lla: np.ndarray
    v_n: np.ndarray
    f_n: np.ndarray
    q_nb: np.ndarray

    @property
    def f_enu(self):
        return np.ascontiguousarray(np.column_stack([self.f_n[:, 1], self.f_n[:, 0], -self.f_n[:, 2]]))

    def at_epochs(self, x):
        return x[::2]

    def solution(self) -> NavSolution:
        """The truth at the epochs as a NavSolution."""
        return NavSolution(self.time, self.lla[::2], self.v_n[::2], self.q_nb[::2])


def _specific_force(lla, v_n, a_n, model):
    lat, h = lla[:, 0], lla[:, 2]
    rn, re = radii(lat, h, model)
    w_ie = earth.rate_ie_n(lat)
    ve = v_n[:, 1]
    w_en = np.stack([ve / re, -v_n[:, 0] / rn, -ve * np.tan(lat) / re], -1)
    return a_n + np.cross(2.0 * w_ie + w_en, v_n) - gravity_ned(lat, h, model)


def platform_truth(trajectory, duration, dt, *, earth_model="wgs84", t0=0.0) -> PlatformTruth:
    """Sample a trajectory for a platform run.

    Parameters
    ----------
    trajectory : object with ``kinematics(t)``
        E.g. :class:`~inskit.simulation.segments.SegmentTrajectory` (the
        scenario simulator's) or :class:`~inskit.simulation.HarmonicTrajectory`.
    duration : float
        [s], at least one step.
    dt : float
        Step [s] of the run (platform dynamics are slow: 0.1-10 s).
    earth_model : {"wgs84", "sphere"}
    t0 : float
        Start time [s].

    Returns
    -------
    PlatformTruth

    Raises
    ------
    ConfigError
        A step or a duration that is no step.
    InputError
        A track within 0.1 deg of a pole
        (:func:`inskit.strapdown.check_track_off_pole`).
    """
    model_code(earth_model)
    if not (dt > 0 and np.isfinite(dt)):
        raise ConfigError(f"`dt` must be > 0 s, got {dt}")
    if not duration >= dt:
        raise ConfigError(f"`duration` ({duration} s) must be at least one step ({dt} s)")
    n = int(np.floor(duration / dt + 1e-9)) + 1
    time = t0 + np.arange(n) * dt
    if earth_model == "wgs84":
        th = t0 + np.arange(2 * n - 1) * (0.5 * dt)
        kin = trajectory.kinematics(th)
        lla, v_n, a_n, C_nb = kin.lla, kin.v_n, kin.a_n, kin.C_nb
    else:
        tq = t0 + np.arange(4 * n - 3) * (0.25 * dt)
        kin = trajectory.kinematics(tq)
        m = 2 * n - 1
        lat = np.empty(m)
        lon = np.empty(m)
        K.sphere_positions(float(kin.lla[0, 0]), float(kin.lla[0, 1]), np.ascontiguousarray(kin.lla[:, 2]),
                           np.ascontiguousarray(kin.v_n[:, 0]), np.ascontiguousarray(kin.v_n[:, 1]), 0.5 * dt,
                           lat, lon)
        lla = np.column_stack([lat, lon, kin.lla[::2, 2]])
        v_n, a_n, C_nb = kin.v_n[::2], kin.a_n[::2], kin.C_nb[::2]
    # the platform's axes point north, east and down: singular at a pole (a track on it was refused as
    # "`lla` holds a latitude of 1.5707964 rad ... degrees where radians are expected?")
    check_track_off_pole(t0 + np.arange(len(lla)) * (0.5 * dt), lla[:, 0], "the trajectory",
                         "a platform INS, whose axes point north, east and down, is singular")
    f_n = _specific_force(lla, v_n, a_n, earth_model)
    return PlatformTruth(time, float(dt), earth_model, np.ascontiguousarray(lla), np.ascontiguousarray(v_n),
                         np.ascontiguousarray(f_n), rot.quat_from_dcm(C_nb))


@dataclass(frozen=True)
class SnsFixes:
    """Satellite fixes on the run's epochs (NaN where there is none).

    Attributes
    ----------
    lat, lon : (n,) ndarray
        [rad].
    v_ne : (n, 2) ndarray
        North and east velocity [m/s] (relative to the Earth).
    sigma : (4,) ndarray
        1-sigma of latitude, longitude [rad] and north, east velocity [m/s].
    """

    lat: np.ndarray
    lon: np.ndarray
    v_ne: np.ndarray
    sigma: np.ndarray

    @property
    def available(self):
        return np.isfinite(self.lat)


def simulate_sns(truth: PlatformTruth, *, sigma_lat=1e-5, sigma_lon=1e-5, sigma_v=0.1, every=1,
                 outages=(), rng=None) -> SnsFixes:
    """White-noise satellite fixes of latitude, longitude and velocity.

    Parameters
    ----------
    truth : PlatformTruth
    sigma_lat, sigma_lon : float
        1-sigma angle errors [rad] (source 004: 1e-5 rad).
    sigma_v : float
        1-sigma error of each horizontal velocity component [m/s] (0.1).
    every : int
        A fix every ``every`` epochs (1: at every step).
    outages : sequence of (start, end)
        Times [s] without fixes.
    rng : numpy.random.Generator
        Required when a sigma is non-zero.

    Returns
    -------
    SnsFixes
    """
    n = len(truth.time)
    if every < 1:
        raise ConfigError(f"`every` must be >= 1, got {every}")
    sig = np.array([sigma_lat, sigma_lon, sigma_v, sigma_v], float)
    if (sig < 0).any():
        raise ConfigError("satellite sigmas must be >= 0")
    if (sig > 0).any() and rng is None:
        raise ConfigError("noisy satellite fixes need an `rng`")
    lla = truth.lla[::2]
    v = truth.v_n[::2, :2]
    e = np.zeros((n, 4)) if rng is None else rng.standard_normal((n, 4)) * sig
    lat = lla[:, 0] + e[:, 0]
    lon = lla[:, 1] + e[:, 1]
    vne = v + e[:, 2:]
    keep = np.zeros(n, bool)
    keep[::every] = True
    for a, b in outages:
        if not b > a:
            raise InputError(f"outage ({a}, {b}): the end must come after the start")
        keep &= ~((truth.time >= a) & (truth.time <= b))
    lat[~keep] = np.nan
    lon[~keep] = np.nan
    vne[~keep] = np.nan
    return SnsFixes(lat, lon, vne, np.maximum(sig, 1e-12))
