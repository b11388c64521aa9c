"""Corrected code and Doppler measurements, one row per (epoch, satellite).

:func:`range_table` turns RINEX observations and broadcast records into
what a positioning filter needs: the satellite state at transmission, and
the pseudorange and range rate with every modelled term but the receiver's
own removed,

``P_corr = P + c (dt_sv - k TGD) - I - T  = |r_sat - r_rx| + c dt_rx + noise``
``rr_corr = -lambda D + c d(dt_sv)/dt     = d|r_sat - r_rx|/dt + c d(dt_rx)/dt + noise``

where ``|r_sat - r_rx|`` is the range with the satellite position rotated
into the reception-time ECEF frame by :func:`~inskit.gnss.ephemeris.sagnac_rotate`
(the user applies it: the table keeps the transmit-frame position and the
travel time).  ``k`` is ``(f_L1 / f)^2``: TGD (GPS) and BGD (Galileo) are
defined for the L1/E1 user and scale with the inverse square of the
frequency for the second one (IS-GPS-200N 20.3.3.3.3.2; OS SIS ICD 5.1.5).

Ionosphere-free rows (``iono="iono-free"``) combine the chosen code with the
first second-frequency code present on that satellite: GPS ``C2W, C2L,
C2S, C2X, C5Q, C5X, C5I``; Galileo ``C7Q, C7X, C7I, C5Q, C5X, C5I``.  The
broadcast clock of GPS refers to the L1/L2 P(Y) ionosphere-free
combination, so no group delay is applied (IS-GPS-200 20.3.3.3.3.3);
with C1C instead of P1 the C1-P1 bias (a few dm) and with L2C the ISC
(not in the legacy message) remain and are not modelled.  Galileo I/NAV
clocks refer to E1/E5b, so E1+E5b needs no BGD; E1+E5a with an I/NAV clock
leaves the E5a-E5b bias (also not modelled).

Error model (stated, not estimated)
-----------------------------------
``sigma_pr^2 = (f_sys k_if)^2 (a^2 + b^2 / sin^2 el) + sigma_iono^2 + sigma_tropo^2``
with ``a = b = 0.3 m`` (the elevation model RTKLIB uses for code, algorithm),
``f_sys`` 1 for GPS and Galileo, 3 for SBAS, ``k_if`` the noise gain of the
ionosphere-free combination (2.98 for L1/L2), ``sigma_iono`` half the
Klobuchar delay (the model removes about half the delay RMS, IS-GPS-200
20.3.3.5.2.5) or the whole estimated delay when no model is applied (0 for
iono-free), ``sigma_tropo = 0.1 m * m(el)`` after Saastamoinen or the whole
delay when none is applied.  Range rate: ``sigma_rr^2 = f_sys^2 (0.05^2 +
0.05^2 / sin^2 el)`` (m/s), typical of the Doppler of a consumer receiver
at 1-10 Hz.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import earth
from ..errors import ConfigError, InputError
from ..units import DEG
from .atmosphere import (
    KLOBUCHAR_DEFAULT_ALPHA,
    KLOBUCHAR_DEFAULT_BETA,
    elevation_azimuth,
    klobuchar_delay,
    saastamoinen_delay,
    tropo_mapping,
)
from .constants import C, FREQ_L1, frequency
from .ephemeris import sagnac_rotate, select_records, transmit_time
from .rinex import NavData, ObsData

__all__ = ["RangeTable", "range_table", "require_systems", "CODE_FALLBACK", "SECOND_CODES", "SIGMA_FACTOR"]

#: Second-frequency codes tried, in order, for ionosphere-free rows.
SECOND_CODES = {
    "G": ("C2W", "C2L", "C2S", "C2X", "C5Q", "C5X", "C5I"),
    "E": ("C7Q", "C7X", "C7I", "C5Q", "C5X", "C5I"),
}
#: Codes of the same band taken, in order, where the requested code is absent on a satellite at an epoch
#: (RTKLIB's per-band priority, the same idea): a RINEX 2 file with P1 and P2 but no C1 (read as C1W and
#: C2W), or a receiver that logs L1 P(Y) or L1C beside C/A on some satellites only.  The inter-code biases
#: (P1-C1 a few dm) are not modelled, as the C1-P1 bias of iono-free rows is not.
CODE_FALLBACK = {
    "C1C": {"G": ("C1W", "C1P", "C1X", "C1L", "C1S"), "E": ("C1X", "C1B"), "J": ("C1X", "C1L", "C1S")},
}
#: Per-system factor on the code and Doppler sigma.
SIGMA_FACTOR = {"G": 1.0, "E": 1.0, "S": 3.0, "J": 1.0}
_CODE_A_M = 0.3
_CODE_B_M = 0.3
_DOPPLER_A_M_S = 0.05
_DOPPLER_B_M_S = 0.05
_TROPO_ZENITH_SIGMA_M = 0.1


@dataclass(frozen=True, eq=False)
class RangeTable:
    """Corrected raw measurements, one row per (epoch, satellite) with a usable code,
    sorted by epoch then satellite.

    Attributes
    ----------
    time : (m,) ndarray
        Receiver time tag [s since the GPS epoch].
    epoch : (m,) int64 ndarray
        Index into the ObsData epochs.
    sat : (m,) ndarray of str
        Satellite name.
    sat_pos_e, sat_vel_e : (m, 3) ndarray
        Satellite position [m] and velocity [m/s] at transmit time, in the
        ECEF frame of transmit time (Sagnac NOT applied).
    travel_s : (m,) ndarray
        ``t_rx - t_tx`` [s]: the travel time plus the receiver clock offset
        (both tags are receiver-clock based); subtract ``dt_rx`` if known
        before :func:`~inskit.gnss.ephemeris.sagnac_rotate`.
    pseudorange_m : (m,) ndarray
        ``|r_sat - r_rx| + c dt_rx + noise`` [m] (module docstring).
    sigma_pr_m : (m,) ndarray
    range_rate_m_s : (m,) ndarray
        ``d|r_sat - r_rx|/dt + c ddt_rx`` [m/s]; NaN without Doppler.
    sigma_rr_m_s : (m,) ndarray
    elevation_rad, azimuth_rad : (m,) ndarray
        Seen from ``rx_e`` (Sagnac-rotated satellite).
    iono_m, tropo_m : (m,) ndarray
        What was removed [m]; for iono-free rows ``iono_m`` is ``P1 - P_IF``
        (the first-frequency delay the combination took out, noisy).
    system : (m,) ndarray of str
    clock_s, drift_s_s, group_delay_s : (m,) ndarray
        Satellite clock terms that were applied.
    rx_e : (m, 3) ndarray
        Approximate receiver position used for geometry and models.
    dropped : dict
        Rows dropped, by reason: ``'system'``, ``'no_ephemeris'``,
        ``'below_mask'``, ``'no_second_code'``.
    no_ephemeris : dict
        Satellite -> rows dropped for want of a usable broadcast record
        (none of that satellite, none healthy, or none within the maximum
        age of :func:`~inskit.gnss.ephemeris.select_records`).
    settings : dict
        code, doppler, iono, tropo, mask_deg, systems, iono coefficients
        and their source ('argument', 'header' or 'default').
    """

    time: np.ndarray
    epoch: np.ndarray
    sat: np.ndarray
    sat_pos_e: np.ndarray
    sat_vel_e: np.ndarray
    travel_s: np.ndarray
    pseudorange_m: np.ndarray
    sigma_pr_m: np.ndarray
    range_rate_m_s: np.ndarray
    sigma_rr_m_s: np.ndarray
    elevation_rad: np.ndarray
    azimuth_rad: np.ndarray
    iono_m: np.ndarray
    tropo_m: np.ndarray
    system: np.ndarray
    clock_s: np.ndarray
    drift_s_s: np.ndarray
    group_delay_s: np.ndarray
    rx_e: np.ndarray
    dropped: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    no_ephemeris: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.time)


def _receiver_positions(obs: ObsData, rx_e):
    """(n_epoch, 3) approximate receiver positions."""
    n = obs.n_epoch
    if rx_e is None:
        if obs.approx_position_e is None:
            raise ConfigError(
                f"{obs.path}: the header has no APPROX POSITION XYZ: give an approximate receiver position "
                "as rx_e=(x, y, z) in ECEF metres (or per epoch, shape (n_epoch, 3), e.g. from an SPP run)"
            )
        return np.broadcast_to(obs.approx_position_e, (n, 3)).astype(float)
    rx = np.asarray(rx_e, dtype=float)
    if rx.shape == (3,):
        if not np.all(np.isfinite(rx)) or np.linalg.norm(rx) < 1e3:
            raise ConfigError(f"rx_e must be a finite ECEF position [m], got {rx.tolist()}")
        return np.broadcast_to(rx, (n, 3)).astype(float)
    if rx.shape != (n, 3):
        raise ConfigError(f"rx_e must have shape (3,) or (n_epoch, 3) = ({n}, 3), got {rx.shape}")
    good = np.all(np.isfinite(rx), axis=1) & (np.linalg.norm(np.nan_to_num(rx), axis=1) > 1e3)
    if not good.any():
        raise ConfigError("rx_e has no finite row: give at least one approximate receiver position")
    if good.all():
        return rx.copy()
    known = np.flatnonzero(good)
    t = obs.time
    k = np.clip(np.searchsorted(t[known], t), 1, max(len(known) - 1, 1))
    lo = known[np.clip(k - 1, 0, len(known) - 1)]
    hi = known[np.clip(k, 0, len(known) - 1)]
    nearest = np.where(np.abs(t - t[lo]) <= np.abs(t[hi] - t), lo, hi)
    return np.where(good[:, None], rx, rx[nearest])


def require_systems(obs: ObsData, systems):
    """Refuse observations without a single satellite of ``systems``.

    Without this check a GLONASS-only file, or ``systems=('E',)`` on a
    GPS-only one, ended in "no code 'C1C' in the observations (have )" or in
    "no epoch could be solved ... does the navigation file cover ...".

    Parameters
    ----------
    obs : ObsData
    systems : sequence of str
        System letters asked for (``'G'``, ``'E'``).

    Raises
    ------
    InputError
        Naming the file, the systems asked for and those the file holds
        (``obs.header['satellites_by_system']``).
    """
    from .rinex import _SYSTEM_NAMES

    systems = tuple(systems)
    if any(s[0] in systems for s in obs.sats):
        return
    asked = ", ".join(f"{_SYSTEM_NAMES.get(s, s)} ({s})" for s in systems) or "none"
    held = (getattr(obs, "header", None) or {}).get("satellites_by_system") or {}
    if held:
        have = ", ".join(f"{_SYSTEM_NAMES.get(s, s)} ({s}): {n} satellite{'s' if n != 1 else ''}"
                         for s, n in held.items())
        usable = [s for s in held if s in ("G", "E")]
        hint = (f"; use the system(s) {', '.join(usable)} (spp --systems, or [gnss] systems)" if usable else
                "; only GPS (G) and Galileo (E) broadcast orbits are supported")
        raise InputError(f"{obs.path}: no satellite of the systems asked for ({asked}) in the observations; the "
                         f"file holds {have}{hint}")
    raise InputError(f"{obs.path}: no satellite observations in the file (systems asked for: {asked}): an empty "
                     "observation file?")


def _code(obs: ObsData, code, what):
    arr = obs.obs.get(code)
    if arr is None:
        raise ConfigError(f"{obs.path}: no {what} {code!r} in the observations (have {', '.join(sorted(obs.obs))})")
    return arr


def _code_with_fallback(obs: ObsData, code, sat_sys):
    """(n_epoch, n_sat) pseudoranges of ``code``, each gap filled from the
    :data:`CODE_FALLBACK` codes of the satellite's system in order, and the
    number of values taken from each code."""
    fall = CODE_FALLBACK.get(code, {})
    tried = [code] + [c for c in dict.fromkeys(c for v in fall.values() for c in v)]
    if not any(c in obs.obs for c in tried):
        have = ", ".join(c for c in sorted(obs.obs) if c[0] == "C") or "none"
        raise ConfigError(f"{obs.path}: no code {code!r} in the observations"
                          + (f", nor any code of its band taken in its place ({', '.join(tried[1:])})"
                             if len(tried) > 1 else "")
                          + f" (codes in the file: {have})")
    n_ep, n_sat = len(obs.time), len(sat_sys)
    out = np.array(obs.obs[code], dtype=float, copy=True) if code in obs.obs else np.full((n_ep, n_sat), np.nan)
    used = {code: int(np.isfinite(out).sum())}
    for s in sorted(set(sat_sys.tolist())):
        cols = np.flatnonzero(sat_sys == s)
        for c in fall.get(s, ()):
            if c not in obs.obs:
                continue
            sub = out[:, cols]
            gap = np.isnan(sub) & np.isfinite(obs.obs[c][:, cols])
            if gap.any():
                sub[gap] = obs.obs[c][:, cols][gap]
                out[:, cols] = sub
                used[c] = used.get(c, 0) + int(gap.sum())
    return out, {k: v for k, v in used.items() if v}


def range_table(obs: ObsData, nav: NavData, *, rx_e=None, mask_deg=10.0, code="C1C", doppler="D1C",
                iono="klobuchar", tropo="saastamoinen", systems=("G", "E"), alpha=None, beta=None,
                code_fallback=True) -> RangeTable:
    """Corrected pseudoranges and range rates with satellite states, per (epoch, satellite).

    Parameters
    ----------
    obs : ObsData
    nav : NavData
    rx_e : None, (3,) or (n_epoch, 3) array_like
        Approximate receiver ECEF position [m]; NaN rows take the nearest
        known epoch; None uses the header's APPROX POSITION XYZ.
    mask_deg : float
        Elevation mask [deg] (from ``rx_e``).
    code : str
        RINEX 3 code to use (``'C1C'``; ``'C1W'`` for P1 ...).
    code_fallback : bool
        Where ``code`` is absent, take the :data:`CODE_FALLBACK` codes of the
        same band (``settings['codes_used']`` counts the values of each).
    doppler : str or None
        Doppler code (``'D1C'``); None or absent gives NaN range rates.
    iono : {'klobuchar', 'iono-free', 'none'}
    tropo : {'saastamoinen', 'none'}
    systems : sequence of str
        Systems to use.
    alpha, beta : (4,) array_like or None
        Klobuchar coefficients; default the navigation header's, else
        :data:`~inskit.gnss.atmosphere.KLOBUCHAR_DEFAULT_ALPHA`/``BETA``.

    Returns
    -------
    RangeTable

    Raises
    ------
    ConfigError
        Unknown model name, missing code, or no receiver position.
    InputError
        No satellite of ``systems`` in ``obs`` (:func:`require_systems`).
    """
    if iono not in ("klobuchar", "iono-free", "none"):
        raise ConfigError(f"iono must be 'klobuchar', 'iono-free' or 'none', got {iono!r}")
    if tropo not in ("saastamoinen", "none"):
        raise ConfigError(f"tropo must be 'saastamoinen' or 'none', got {tropo!r}")
    if not np.isfinite(mask_deg) or not -90.0 <= mask_deg <= 90.0:
        raise ConfigError(f"mask_deg must be an angle in degrees, got {mask_deg}")
    if alpha is not None or beta is not None:
        if alpha is None or beta is None:
            raise ConfigError("give both alpha and beta Klobuchar coefficients, or neither")
        iono_src = "argument"
        alpha, beta = np.asarray(alpha, float), np.asarray(beta, float)
    elif nav.iono_alpha is not None and nav.iono_beta is not None:
        iono_src, alpha, beta = "header", nav.iono_alpha, nav.iono_beta
    else:
        iono_src, alpha, beta = "default", KLOBUCHAR_DEFAULT_ALPHA, KLOBUCHAR_DEFAULT_BETA

    require_systems(obs, systems)
    rx_ep = _receiver_positions(obs, rx_e)
    sats = np.array(obs.sats, dtype="<U3")
    sat_sys = np.array([s[0] for s in obs.sats], dtype="<U1")
    in_sys = np.isin(sat_sys, list(systems))
    if code_fallback:
        p1, codes_used = _code_with_fallback(obs, code, np.where(in_sys, sat_sys, ""))
    else:
        p1 = _code(obs, code, "code")
        codes_used = {code: int(np.isfinite(p1).sum())}
    present = np.isfinite(p1)
    dropped = {"system": int(present[:, ~in_sys].sum()), "no_ephemeris": 0, "below_mask": 0, "no_second_code": 0}
    present &= in_sys[None, :]
    ep, col = np.nonzero(present)
    sat = sats[col]
    sysr = sat_sys[col]
    pr = p1[ep, col]
    t_rx = obs.time[ep]
    sat_f = np.array([frequency(s, code) if s in systems else np.nan for s in sat_sys])
    band_f = sat_f[col]

    keep = np.ones(ep.size, bool)
    p2 = f2 = None
    if iono == "iono-free":
        p2 = np.full(ep.size, np.nan)
        f2 = np.full(ep.size, np.nan)
        for s, cands in SECOND_CODES.items():
            rows = np.flatnonzero((sysr == s) & np.isnan(p2))
            for c2 in cands:
                if c2 not in obs.obs or rows.size == 0:
                    continue
                v = obs.obs[c2][ep[rows], col[rows]]
                ok = np.isfinite(v)
                p2[rows[ok]] = v[ok]
                f2[rows[ok]] = frequency(s, c2)
                rows = rows[~ok]
        no2 = ~np.isfinite(p2)
        dropped["no_second_code"] = int(no2.sum())
        keep &= ~no2

    rec = select_records(nav, sat, t_rx)
    noeph = rec < 0
    dropped["no_ephemeris"] = int((noeph & keep).sum())
    names, counts = np.unique(sat[noeph & keep], return_counts=True)
    no_eph = {str(n): int(c) for n, c in zip(names, counts)}
    keep &= ~noeph
    idx = np.flatnonzero(keep)
    ep, col, sat, sysr, pr, t_rx, band_f, rec = (a[idx] for a in (ep, col, sat, sysr, pr, t_rx, band_f, rec))
    if p2 is not None:
        p2, f2 = p2[idx], f2[idx]

    t_tx, st = transmit_time(nav, sat, t_rx, pr, records=rec)
    travel = t_rx - t_tx
    rx = rx_ep[ep]
    sat_rx = sagnac_rotate(st.pos_e, travel)
    el, az = elevation_azimuth(rx, sat_rx)
    above = el >= mask_deg * DEG
    dropped["below_mask"] = int((~above).sum())
    idx = np.flatnonzero(above)
    ep, col, sat, sysr, pr, t_rx, band_f, t_tx, travel, rx, el, az = (
        a[idx] for a in (ep, col, sat, sysr, pr, t_rx, band_f, t_tx, travel, rx, el, az))
    if p2 is not None:
        p2, f2 = p2[idx], f2[idx]
    pos, vel = st.pos_e[idx], st.vel_e[idx]
    clk, drift, gd = st.clock_s[idx], st.drift_s_s[idx], st.group_delay_s[idx]

    lla = earth.ecef_to_lla(rx)
    klob = klobuchar_delay(t_rx, lla, az, el, alpha, beta) * (FREQ_L1 / band_f) ** 2 if idx.size else np.zeros(0)
    saas = saastamoinen_delay(lla, el) if idx.size else np.zeros(0)
    fac = np.array([SIGMA_FACTOR.get(s, 1.0) for s in sysr]) if idx.size else np.zeros(0)
    sin_el = np.sin(el)
    if iono == "iono-free":
        f1s, f2s = band_f**2, f2**2
        p_if = (f1s * pr - f2s * p2) / (f1s - f2s)
        iono_m = pr - p_if
        corrected = p_if + C * clk
        k_if = np.sqrt(f1s**2 + f2s**2) / (f1s - f2s)
        sig_iono = np.zeros_like(pr)
        gd_used = np.zeros_like(pr)
    else:
        iono_m = klob if iono == "klobuchar" else np.zeros_like(pr)
        gd_used = gd * (FREQ_L1 / band_f) ** 2
        corrected = pr + C * (clk - gd_used) - iono_m
        k_if = 1.0
        sig_iono = 0.5 * klob if iono == "klobuchar" else klob
    tropo_m = saas if tropo == "saastamoinen" else np.zeros_like(pr)
    corrected = corrected - tropo_m
    sig_tropo = _TROPO_ZENITH_SIGMA_M * tropo_mapping(el) if tropo == "saastamoinen" else saas
    sigma_pr = np.sqrt((fac * k_if) ** 2 * (_CODE_A_M**2 + _CODE_B_M**2 / sin_el**2) + sig_iono**2 + sig_tropo**2)

    rr = np.full(pr.shape, np.nan)
    if doppler is not None and doppler in obs.obs:
        lam = C / np.array([frequency(s, doppler) for s in sysr]) if idx.size else np.zeros(0)
        d = obs.obs[doppler][ep, col]
        rr = -lam * d + C * drift
    elif doppler is not None and doppler[0] != "D":
        raise ConfigError(f"doppler must be a RINEX 3 Doppler code such as 'D1C', got {doppler!r}")
    sigma_rr = fac * np.sqrt(_DOPPLER_A_M_S**2 + _DOPPLER_B_M_S**2 / sin_el**2)
    sigma_rr = np.where(np.isfinite(rr), sigma_rr, np.nan)

    settings = dict(code=code, codes_used=codes_used, doppler=doppler, iono=iono, tropo=tropo, mask_deg=float(mask_deg),
                    systems=tuple(systems), alpha=np.asarray(alpha), beta=np.asarray(beta), iono_source=iono_src)
    if not np.all(np.isfinite(corrected)):  # pragma: no cover - every term is finite by construction
        raise InputError(f"{obs.path}: non-finite corrected pseudorange (a bug: please report)")
    return RangeTable(
        time=t_rx, epoch=ep.astype(np.int64), sat=sat, sat_pos_e=pos, sat_vel_e=vel, travel_s=travel,
        pseudorange_m=corrected, sigma_pr_m=sigma_pr, range_rate_m_s=rr, sigma_rr_m_s=sigma_rr,
        elevation_rad=el, azimuth_rad=az, iono_m=iono_m, tropo_m=tropo_m, system=sysr, clock_s=clk,
        drift_s_s=drift, group_delay_s=gd_used, rx_e=rx, dropped=dropped, settings=settings, no_ephemeris=no_eph,
    )
