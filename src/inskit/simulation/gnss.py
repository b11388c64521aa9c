"""GNSS receiver model: position (and velocity) fixes with realistic errors.

Errors per NED axis: white noise plus a first-order Gauss-Markov term
(multipath, atmosphere); antenna lever arm; latency (a fix stamped ``t``
describes the antenna at ``t - latency``); outage windows (no fixes);
occasional outliers.  The sigmas written with each fix are the model's total
``sqrt(white^2 + correlated^2)``, floored at 1 mm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import earth
from ..errors import ConfigError
from ..types import GnssData
from .sensors import _gauss_markov


@dataclass(frozen=True)
class GnssErrors:
    """GNSS receiver error model (SI units).

    Attributes
    ----------
    rate_hz : float
    white_h_m, white_v_m : float
        White position noise, horizontal (per axis) and vertical [m].
    correlated_h_m, correlated_v_m : float
        Gauss-Markov position error sigma [m].
    correlation_time_s : float
    velocity_sigma_m_s : float
        White velocity noise per axis [m/s]; 0 writes no velocity.
    lever_arm_b_m : tuple
        Antenna position in body axes relative to the trajectory point [m].
    latency_s : float
    outages : tuple of (start, end)
        Times [s] with no fixes.
    outlier_probability : float
    outlier_sigma_m : float
    """

    rate_hz: float = 1.0
    white_h_m: float = 1.0
    white_v_m: float = 2.0
    correlated_h_m: float = 0.0
    correlated_v_m: float = 0.0
    correlation_time_s: float = 60.0
    velocity_sigma_m_s: float = 0.05
    lever_arm_b_m: tuple = (0.0, 0.0, 0.0)
    latency_s: float = 0.0
    outages: tuple = ()
    outlier_probability: float = 0.0
    outlier_sigma_m: float = 30.0


def _fix_grid(t_start, t_end, errors: GnssErrors):
    """Every epoch of the receiver's ``rate_hz`` grid from ``t_start`` to
    ``t_end``, and True where no outage of ``errors`` removes it."""
    t = np.arange(t_start, t_end + 1e-9, 1.0 / errors.rate_hz)
    keep = np.ones(len(t), bool)
    for a, b in errors.outages:
        keep &= ~((t >= a) & (t <= b))
    return t, keep


def fix_times(t_start, t_end, errors: GnssErrors) -> np.ndarray:
    """The times [s] of the fixes :func:`simulate_gnss` makes between
    ``t_start`` and ``t_end`` (its ``rate_hz`` grid outside its outages),
    known before any is simulated: a window that holds none of them withholds
    nothing."""
    t, keep = _fix_grid(t_start, t_end, errors)
    return t[keep]


def simulate_gnss(trajectory, t_start, t_end, errors: GnssErrors, rng):
    """Fixes of ``trajectory`` between ``t_start`` and ``t_end``.

    Returns
    -------
    gnss : GnssData
    truth_errors : (n, 3) ndarray
        The position errors drawn (NED, before outliers) for tests.

    Raises
    ------
    ConfigError
        When the outages leave no fix between ``t_start`` and ``t_end``: an
        empty GNSS file no consumer can use (``navigate`` needs two fixes
        outside its outages), named as the scenario key the outages come
        from (``[gnss] outages_s``); when the latency is as long as the run
        (``[gnss] latency_s``).  The fixes stamped within ``latency_s`` of
        ``t_start`` describe ``t_start``: the trajectory has no earlier
        position.
    """
    if not errors.latency_s < t_end - t_start:  # every fix would describe the start (clipped there)
        raise ConfigError(f"field 'gnss.latency_s': {errors.latency_s:g} s is not shorter than the run "
                          f"({t_end - t_start:g} s): every fix, stamped t, would describe the antenna at t - latency, "
                          "before the start, and be the start's position; a latency below the run's length")
    t, keep = _fix_grid(t_start, t_end, errors)
    if not keep.any():
        shown = [[float(a), float(b)] for a, b in errors.outages]
        raise ConfigError(f"field 'gnss.outages_s': the outages {shown} remove every GNSS fix of the run "
                          f"({len(t)} at {errors.rate_hz:g} Hz over {t_start:g}..{t_end:g} s): the GNSS file would be "
                          "empty; leave fixes outside the outages (navigate needs at least two)")
    t_true = np.clip(t - errors.latency_s, t_start, t_end)
    kin = trajectory.kinematics(t_true)
    lever = np.asarray(errors.lever_arm_b_m, float)
    r = earth.lla_to_ecef(kin.lla)
    off_n = np.einsum("nij,j->ni", kin.C_nb, lever)
    C_en = earth.dcm_en(kin.lla[:, 0], kin.lla[:, 1])
    r_ant = r + np.einsum("nij,nj->ni", C_en, off_n)
    sig_w = np.array([errors.white_h_m, errors.white_h_m, errors.white_v_m])
    sig_c = np.array([errors.correlated_h_m, errors.correlated_h_m, errors.correlated_v_m])
    n = len(t)
    err = rng.standard_normal((n, 3)) * sig_w
    dt = 1.0 / errors.rate_hz
    for j in range(3):
        if sig_c[j] > 0:
            err[:, j] += _gauss_markov(n, dt, sig_c[j], errors.correlation_time_s, rng)[:, 0]
    drawn = err.copy()
    if errors.outlier_probability > 0:
        out = rng.random(n) < errors.outlier_probability
        err[out] += rng.standard_normal((int(out.sum()), 3)) * errors.outlier_sigma_m
    lla = earth.ecef_to_lla(r_ant + np.einsum("nij,nj->ni", C_en, err))
    # written sigmas: the model's total, floored at 1 mm (a filter cannot use 0)
    sigma = np.tile(np.maximum(np.sqrt(sig_w**2 + sig_c**2), 1e-3), (n, 1))
    v = sv = None
    if errors.velocity_sigma_m_s > 0:
        w_nb_b = kin.omega_nb_b  # antenna velocity: v + C_nb (omega x l), Earth rate neglected (< 1 mm/s)
        v = kin.v_n + np.einsum("nij,nj->ni", kin.C_nb, np.cross(w_nb_b, lever))
        v = v + rng.standard_normal((n, 3)) * errors.velocity_sigma_m_s
        sv = np.full((n, 3), errors.velocity_sigma_m_s)
    g = GnssData(t[keep], lla[keep], sigma[keep], None if v is None else v[keep], None if sv is None else sv[keep])
    return g, drawn[keep]
