"""Broadcast orbits and clocks of GPS and Galileo satellites, vectorised.

Every function works on m rows at once (one row = one satellite at one
time); there is no per-satellite Python object.

Record selection (:func:`select_records`)
-----------------------------------------
For each row the record of that satellite with the nearest toe is taken,
among records that are

* **healthy**: GPS SV health word 0 (IS-GPS-200 20.3.3.3.1.4); Galileo
  signal health and data validity bits of the signals the clock is for
  all 0 (E1-B and E5b bits 0-2, 6-8 for I/NAV; E5a bits 3-5 for F/NAV;
  OS SIS ICD 5.1.9.3, RINEX 3.04 Table A8);
* **within the maximum age** ``|t - toe| <= max_age_s``.  Default: GPS
  2 h, half the 4 h curve-fit interval of a nominal upload (IS-GPS-200
  20.3.4.4), or half the broadcast fit interval when the record states a
  longer one (fit flag: ``fit_h`` > 4).  Galileo: also 2 h.  Galileo
  batches are uploaded far more often than GPS ones (a new IODnav every
  10 min to 3 h), so a daily file always has a record within 2 h of any
  time; a 4 h window (the nominal validity) would be allowed by the ICD but
  buys nothing in post-processing and admits older orbits.  Pass
  ``max_age_s={'E': 14400.0}`` to widen it.
* for Galileo, **I/NAV** records (E1-B/E5b, data source bits 0 or 2 with
  clock for E5b/E1, bit 9) are preferred: they carry the clock and
  BGD(E1,E5b) that apply to a single-frequency E1 user.  F/NAV (E5a)
  records are used only for rows with no valid I/NAV record.

Ties (same distance to toe) go to the later record in the file.

Orbit and clock models
----------------------
The user algorithm of IS-GPS-200N Table 20-IV (Kepler's equation solved by
6 Newton iterations on arrays from E = M: for e = 0.03 the residual is
3e-12 rad after 2 and at rounding level, 4e-16 rad, after 3), the same for
Galileo with its own GM (OS SIS ICD 5.1.1, Table 58-59).

Times are float64 seconds since 1980, resolved to 2.4e-7 s: the satellite
moves < 1 mm in that time, below the broadcast orbit error by three orders.  Velocity is the
analytic time derivative of the same expressions (ECEF, rotating frame).
The clock polynomial and the relativistic correction
``dt_r = F e sqrt(A) sin(E)`` follow IS-GPS-200 20.3.3.3.3.1 (Galileo: OS SIS
ICD 5.1.4); group delays follow 20.3.3.3.3.2 (TGD for an L1 C/A user) and
OS SIS ICD 5.1.5 (BGD).

References
----------
IS-GPS-200N (2022), Table 20-IV, 20.3.3.3.3.1-2, 20.3.4.3 (signal travel).
Galileo OS SIS ICD Issue 2.0 (2021), 5.1.1-5.1.5.
RTKLIB ephemeris.c eph2pos / seleph (algorithm, not code) for the selection
policy of nearest toe.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .constants import C, F_REL_GAL, F_REL_GPS, GM_GAL, GM_GPS, OMEGA_E_GAL, OMEGA_E_GPS
from .rinex import NavData

__all__ = ["SatStates", "select_records", "satellite_states", "transmit_time", "sagnac_rotate",
           "DEFAULT_MAX_AGE_S"]

#: Default maximum |t - toe| [s] per system (see the module docstring).
DEFAULT_MAX_AGE_S = {"G": 7200.0, "E": 7200.0}

_KEPLER_ITERATIONS = 6
_GAL_INAV_BITS = (1 << 0) | (1 << 2) | (1 << 9)
_GAL_HEALTH_INAV = 0b111000111   # E1-B (bits 0-2) and E5b (bits 6-8) DVS/HS
_GAL_HEALTH_FNAV = 0b000111000   # E5a (bits 3-5)


def _as_rows(sats, t):
    sats = np.atleast_1d(np.asarray(sats, dtype="<U3"))
    t = np.asarray(t, dtype=float)
    if t.ndim == 0:
        t = np.full(sats.shape, float(t))
    t = np.atleast_1d(t)
    if sats.shape != t.shape or sats.ndim != 1:
        raise InputError(f"sats and t must be 1-D arrays of the same length, got {sats.shape} and {t.shape}")
    return sats, t


def _is_inav(nav: NavData):
    ds = np.nan_to_num(nav.params["data_source"], nan=0.0).astype(np.int64)
    return (nav.system == "E") & ((ds & _GAL_INAV_BITS) != 0)


def _healthy(nav: NavData):
    h = np.nan_to_num(nav.params["health"], nan=1.0).astype(np.int64)
    gps = (nav.system == "G") & (h == 0)
    inav = _is_inav(nav)
    gal = (nav.system == "E") & np.where(inav, (h & _GAL_HEALTH_INAV) == 0, (h & _GAL_HEALTH_FNAV) == 0)
    return gps | gal


def select_records(nav: NavData, sats, t, *, max_age_s=None):
    """Index of the broadcast record to use for each (satellite, time) row.

    Parameters
    ----------
    nav : NavData
    sats : (m,) array_like of str
        Satellite names (``'G05'``).
    t : (m,) array_like or float
        Times [s since the GPS epoch].
    max_age_s : float, dict or None
        Maximum ``|t - toe|`` [s]: one value, a ``{system: seconds}`` dict,
        or None for :data:`DEFAULT_MAX_AGE_S` (GPS: at least half the
        record's fit interval).

    Returns
    -------
    (m,) int64 ndarray
        Record index into ``nav``, -1 where no healthy record is close enough.
    """
    sats, t = _as_rows(sats, t)
    out = np.full(sats.shape, -1, dtype=np.int64)
    if len(nav) == 0 or sats.size == 0:
        return out
    if max_age_s is None:
        ages = dict(DEFAULT_MAX_AGE_S)
    elif isinstance(max_age_s, dict):
        ages = {**DEFAULT_MAX_AGE_S, **max_age_s}
    else:
        ages = {"G": float(max_age_s), "E": float(max_age_s)}
    rec_age = np.array([ages.get(s, 0.0) for s in nav.system])
    if max_age_s is None:
        fit = nav.params["fit_h"]
        long_fit = (nav.system == "G") & np.isfinite(fit) & (fit > 4.0)
        rec_age = np.where(long_fit, np.maximum(rec_age, 0.5 * fit * 3600.0), rec_age)
    usable = _healthy(nav)
    fnav_penalty = np.where((nav.system == "E") & ~_is_inav(nav), 1e9, 0.0)
    order = np.argsort(nav.sats, kind="stable")
    sorted_sats = nav.sats[order]
    uniq, first = np.unique(sorted_sats, return_index=True)
    bounds = dict(zip(uniq.tolist(), zip(first.tolist(), list(first[1:]) + [len(order)])))
    for sat in np.unique(sats):
        b = bounds.get(str(sat))
        if b is None:
            continue
        recs = order[b[0]:b[1]]
        recs = recs[usable[recs]]
        if recs.size == 0:
            continue
        rows = np.flatnonzero(sats == sat)
        dt = np.abs(t[rows, None] - nav.toe[None, recs])
        ok = dt <= rec_age[None, recs]
        score = np.where(ok, dt + fnav_penalty[None, recs], np.inf)
        # ties to the later record: search the reversed record list
        j = score.shape[1] - 1 - np.argmin(score[:, ::-1], axis=1)
        best = recs[j]
        good = np.isfinite(score[np.arange(rows.size), j])
        out[rows[good]] = best[good]
    return out


@dataclass(frozen=True, eq=False)
class SatStates:
    """Satellite positions, velocities and clocks from broadcast records.

    Attributes
    ----------
    pos_e : (m, 3) ndarray
        ECEF position [m] at time t, in the ECEF frame of time t (no Sagnac rotation).
    vel_e : (m, 3) ndarray
        ECEF (rotating-frame) velocity [m/s].
    clock_s : (m,) ndarray
        Satellite clock offset dt_sv [s] including the relativistic term,
        excluding group delay.
    drift_s_s : (m,) ndarray
        Its rate [s/s] (including the rate of the relativistic term).
    group_delay_s : (m,) ndarray
        TGD (GPS, L1 C/A user) or BGD(E1,E5b) (Galileo I/NAV; BGD(E1,E5a)
        for F/NAV) [s]; the L1/E1 single-frequency clock is
        ``clock_s - group_delay_s``.  0 where not broadcast.
    valid : (m,) bool ndarray
        False where no usable record was found (other fields NaN).
    record : (m,) int64 ndarray
        Record index used, -1 where invalid.
    relativistic_s : (m,) ndarray
        The relativistic term included in ``clock_s`` [s].
    """

    pos_e: np.ndarray
    vel_e: np.ndarray
    clock_s: np.ndarray
    drift_s_s: np.ndarray
    group_delay_s: np.ndarray
    valid: np.ndarray
    record: np.ndarray | None = None
    relativistic_s: np.ndarray | None = None


def satellite_states(nav: NavData, sats, t, *, records=None) -> SatStates:
    """Broadcast satellite position, velocity and clock at given times.

    Parameters
    ----------
    nav : NavData
    sats : (m,) array_like of str
    t : (m,) array_like or float
        GPS-scale time at which the signal left the satellite [s since the GPS epoch].
    records : (m,) int array_like or None
        Record per row (from :func:`select_records`); None selects them at ``t``.

    Returns
    -------
    SatStates

    References
    ----------
    IS-GPS-200N Table 20-IV (orbit), 20.3.3.3.3.1 (clock, relativity);
    Galileo OS SIS ICD 5.1.1, 5.1.4.
    """
    sats, t = _as_rows(sats, t)
    m = sats.size
    rec = select_records(nav, sats, t) if records is None else np.asarray(records, dtype=np.int64).reshape(-1)
    if rec.shape != (m,):
        raise InputError(f"records must have shape ({m},), got {rec.shape}")
    valid = rec >= 0
    pos = np.full((m, 3), np.nan)
    vel = np.full((m, 3), np.nan)
    clk = np.full(m, np.nan)
    drift = np.full(m, np.nan)
    gd = np.full(m, np.nan)
    rel = np.full(m, np.nan)
    if valid.any():
        r = rec[valid]
        tv = t[valid]
        p = {k: v[r] for k, v in nav.params.items()}
        gal = nav.system[r] == "E"
        gm = np.where(gal, GM_GAL, GM_GPS)
        we = np.where(gal, OMEGA_E_GAL, OMEGA_E_GPS)
        f_rel = np.where(gal, F_REL_GAL, F_REL_GPS)

        a = p["sqrt_a"] ** 2
        e = p["e"]
        tk = tv - nav.toe[r]
        n = np.sqrt(gm / a**3) + p["dn"]
        mk = p["m0"] + n * tk
        ek = mk.copy()
        for _ in range(_KEPLER_ITERATIONS):
            ek = ek - (ek - e * np.sin(ek) - mk) / (1.0 - e * np.cos(ek))
        sin_e, cos_e = np.sin(ek), np.cos(ek)
        one_e = 1.0 - e * cos_e
        sq = np.sqrt(1.0 - e * e)
        nu = np.arctan2(sq * sin_e, cos_e - e)
        phi = nu + p["omega"]
        s2, c2 = np.sin(2.0 * phi), np.cos(2.0 * phi)
        du = p["cus"] * s2 + p["cuc"] * c2
        dr = p["crs"] * s2 + p["crc"] * c2
        di = p["cis"] * s2 + p["cic"] * c2
        u = phi + du
        rk = a * one_e + dr
        ik = p["i0"] + di + p["idot"] * tk
        xp, yp = rk * np.cos(u), rk * np.sin(u)
        om_dot = p["omega_dot"] - we
        om = p["omega0"] + om_dot * tk - we * p["toe_sow"]
        so, co = np.sin(om), np.cos(om)
        si, ci = np.sin(ik), np.cos(ik)
        x = xp * co - yp * ci * so
        y = xp * so + yp * ci * co
        z = yp * si
        # analytic rates
        e_dot = n / one_e
        nu_dot = sq * e_dot / one_e
        u_dot = nu_dot * (1.0 + 2.0 * (p["cus"] * c2 - p["cuc"] * s2))
        r_dot = a * e * sin_e * e_dot + 2.0 * nu_dot * (p["crs"] * c2 - p["crc"] * s2)
        i_dot = p["idot"] + 2.0 * nu_dot * (p["cis"] * c2 - p["cic"] * s2)
        xp_dot = r_dot * np.cos(u) - yp * u_dot
        yp_dot = r_dot * np.sin(u) + xp * u_dot
        vx = xp_dot * co - yp_dot * ci * so + yp * si * so * i_dot - om_dot * y
        vy = xp_dot * so + yp_dot * ci * co - yp * si * co * i_dot + om_dot * x
        vz = yp_dot * si + yp * ci * i_dot
        pos[valid] = np.stack([x, y, z], axis=-1)
        vel[valid] = np.stack([vx, vy, vz], axis=-1)
        # clock
        dtc = tv - nav.toc[r]
        d_rel = f_rel * e * p["sqrt_a"] * sin_e
        clk[valid] = p["af0"] + p["af1"] * dtc + p["af2"] * dtc**2 + d_rel
        drift[valid] = p["af1"] + 2.0 * p["af2"] * dtc + f_rel * e * p["sqrt_a"] * cos_e * e_dot
        rel[valid] = d_rel
        ds = np.nan_to_num(p["data_source"], nan=0.0).astype(np.int64)
        gal_gd = np.where((ds & (1 << 8)) != 0, p["bgd_e5a_e1"], p["bgd_e5b_e1"])
        gd[valid] = np.nan_to_num(np.where(gal, gal_gd, p["tgd"]), nan=0.0)
    return SatStates(pos_e=pos, vel_e=vel, clock_s=clk, drift_s_s=drift, group_delay_s=gd, valid=valid,
                     record=rec, relativistic_s=rel)


def transmit_time(nav: NavData, sats, t_rx, pseudorange_m, *, records=None):
    """Signal transmission time (GPS scale) from the reception tag and pseudorange.

    ``t_tx = t_rx - P / c - dt_sv(t_tx)``, iterated twice from
    ``t_tx = t_rx - P / c`` (IS-GPS-200 20.3.3.3.3.1: the satellite clock is
    evaluated at the transmission time).  The receiver clock offset cancels:
    ``t_rx`` and ``P`` carry the same offset.

    Parameters
    ----------
    nav : NavData
    sats : (m,) array_like of str
    t_rx : (m,) array_like or float
        Receiver time tags [s since the GPS epoch].
    pseudorange_m : (m,) array_like
        Code pseudoranges [m].
    records : (m,) int array_like or None
        Records to use; None selects them at ``t_rx``.

    Returns
    -------
    t_tx : (m,) ndarray
        Transmission time [s since the GPS epoch] (NaN where invalid).
    states : SatStates
        Satellite states at ``t_tx`` (ECEF frame of ``t_tx``).
    """
    sats, t_rx = _as_rows(sats, t_rx)
    pr = np.asarray(pseudorange_m, dtype=float).reshape(-1)
    if pr.shape != t_rx.shape:
        raise InputError(f"pseudorange_m must have shape {t_rx.shape}, got {pr.shape}")
    rec = select_records(nav, sats, t_rx) if records is None else np.asarray(records, dtype=np.int64)
    rec = np.where(np.isfinite(pr), rec, -1)
    t_tx = t_rx - pr / C
    for _ in range(2):
        st = satellite_states(nav, sats, t_tx, records=rec)
        t_tx = t_rx - pr / C - np.nan_to_num(st.clock_s, nan=0.0)
    st = satellite_states(nav, sats, t_tx, records=rec)
    return np.where(st.valid, t_tx, np.nan), st


def sagnac_rotate(pos_e, travel_s, omega_e=OMEGA_E_GPS):
    """Rotate ECEF positions of transmit time into the ECEF frame at reception.

    During the travel time tau the Earth turns by ``omega_e * tau`` about z,
    so a point fixed in inertial space has, in the reception-time frame,
    coordinates ``R3(omega_e tau) r`` (IS-GPS-200 20.3.3.4.3.4, Earth rotation
    correction).

    Parameters
    ----------
    pos_e : (3,) or (m, 3) array_like
        Positions [m] in the ECEF frame of transmission.
    travel_s : float or (m,) array_like
        Signal travel time [s].
    omega_e : float
        Earth rotation rate [rad/s] (GPS value by default).

    Returns
    -------
    ndarray, same shape as ``pos_e``.
    """
    pos = np.asarray(pos_e, dtype=float)
    th = omega_e * np.asarray(travel_s, dtype=float)
    c, s = np.cos(th), np.sin(th)
    x, y = pos[..., 0], pos[..., 1]
    return np.stack([c * x + s * y, -s * x + c * y, pos[..., 2] + 0.0 * th], axis=-1)
