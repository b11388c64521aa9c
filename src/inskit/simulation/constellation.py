"""Satellite constellations for raw GNSS simulation, as broadcast ephemerides.

A synthetic constellation is written in the public format a receiver gets:
broadcast-ephemeris records (:class:`inskit.gnss.rinex.NavData`), so the
simulator and any reader of the RINEX navigation file compute the
satellites' positions and clocks on the same path
(:func:`inskit.gnss.ephemeris.satellite_states`).

* :func:`walker_constellation`: Walker delta constellations T/P/F
  (GPS-like 24/6/1 at 55 deg, a = 26,559.7 km; Galileo-like 24/3/1 at
  56 deg, a = 29,600 km): near-circular Keplerian orbits (eccentricity
  drawn in [5e-4, 5e-3], harmonic corrections zero, ``dn = 0``,
  ``idot = 0``), the node regressing at the J2 rate, small satellite clock
  offsets and drifts and group delays drawn from ``rng``; one record per
  satellite every 2 h across the span, the elements propagated from one
  record to the next so the orbit is one continuous Keplerian motion.
* :func:`constellation_from_nav`: the satellites of a real navigation file,
  checked to cover the scenario.

References
----------
Walker, J. G. (1984), Satellite constellations, *J. Br. Interplanet. Soc.*
37, 559-572 (the T/P/F pattern).  IS-GPS-200N 20.3.3.4.3 and Table 20-IV
(the broadcast orbit model the records describe: ``Omega_k = Omega_0 +
(Omega_dot - Omega_e) t_k - Omega_e t_oe``).  Vallado, *Fundamentals of
Astrodynamics*, 4th ed., eq. 9-41 (secular J2 node rate ``Omega_dot =
-3/2 n J2 (R/a)^2 cos i`` for a circular orbit).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import earth
from ..errors import ConfigError
from ..gnss import constants as K
from ..gnss.rinex_write import nav_precision

#: Interval between the broadcast records of a synthetic constellation [s] (GPS practice).
RECORD_INTERVAL_S = 7200.0


@dataclass(frozen=True)
class WalkerSpec:
    """A Walker delta constellation ``T/P/F`` (SI units).

    Attributes
    ----------
    system : str
        ``'G'`` or ``'E'``: satellite names and the GM/ephemeris conventions.
    n_sats, n_planes, phasing : int
        ``T``, ``P``, ``F``: satellites, equally spaced planes, and the
        phasing (satellites of adjacent planes are offset by ``F 2 pi / T``
        in argument of latitude).
    inclination_rad : float
    semi_major_axis_m : float
    """

    system: str
    n_sats: int
    n_planes: int
    phasing: int
    inclination_rad: float
    semi_major_axis_m: float

    def __post_init__(self):
        if self.system not in ("G", "E"):
            raise ConfigError(f"Walker constellation: system must be 'G' or 'E', got {self.system!r}")
        if self.n_sats <= 0 or self.n_planes <= 0 or self.n_sats % self.n_planes:
            raise ConfigError(f"Walker constellation: {self.n_sats} satellites cannot fill {self.n_planes} "
                              "equal planes")
        if self.n_sats > 99:
            raise ConfigError("Walker constellation: at most 99 satellites per system (RINEX names)")

    @property
    def gm(self):
        """The GM the system's ephemeris algorithm uses [m^3/s^2]."""
        return K.GM_GPS if self.system == "G" else K.GM_GAL

    @property
    def mean_motion(self):
        """[rad/s]."""
        return float(np.sqrt(self.gm / self.semi_major_axis_m**3))

    @property
    def node_rate(self):
        """Secular J2 regression of the node [rad/s] (Vallado eq. 9-41)."""
        return float(-1.5 * self.mean_motion * earth.J2 * (earth.A / self.semi_major_axis_m) ** 2
                     * np.cos(self.inclination_rad))


WALKER_GPS = WalkerSpec("G", 24, 6, 1, np.radians(55.0), 26_559_700.0)
WALKER_GALILEO = WalkerSpec("E", 24, 3, 1, np.radians(56.0), 29_600_000.0)
CONSTELLATIONS = {"walker-gps": (WALKER_GPS,), "walker-galileo": (WALKER_GALILEO,),
                  "walker-gps+galileo": (WALKER_GPS, WALKER_GALILEO)}


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi


def walker_records(spec: WalkerSpec, t_start, t_end, rng, *, record_interval_s=RECORD_INTERVAL_S):
    """Broadcast-ephemeris records of a Walker constellation over a span.

    Parameters
    ----------
    spec : WalkerSpec
    t_start, t_end : float
        Span to cover [s since the GPS epoch]; records are at multiples of
        ``record_interval_s`` from the one at or before ``t_start`` to the
        one at or before ``t_end`` (each valid +-2 h: fit interval 4 h).
    rng : numpy.random.Generator
        Draws, in this order: the constellation's orientation (node and
        argument-of-latitude offsets), per satellite the eccentricity,
        argument of perigee, clock offset ``af0`` (uniform +-0.5 ms), drift
        ``af1`` (uniform +-1e-11 s/s) and group delay (uniform +-10 ns,
        quantised to the broadcast LSB 2^-31 s for GPS, 2^-32 s for
        Galileo).

    Returns
    -------
    dict
        ``sats, system, toc, toe`` (n_rec,) and ``params`` (dict of (n_rec,)
        arrays in the :class:`inskit.gnss.rinex.NavData` keys), every value
        rounded to what a RINEX ``D19.12`` field holds
        (:func:`inskit.gnss.rinex_write.nav_precision`), so a record written
        and read back is unchanged.

    Notes
    -----
    Record ``r`` of a satellite has ``toe_r = toc_r``, ``M0_r = M0 + n
    (toe_r - toe_0)``, ``Omega0_r = Omega0 + Omega_dot (toe_r - toe_0) -
    Omega_e (w_r - w_0)`` (``w`` the start of the GPS week of each ``toe``:
    ``Omega_0`` is referred to its record's week) and ``af0_r = af0 + af1
    (toc_r - toc_0)``: consecutive records describe the same motion and
    clock.
    """
    if not t_end >= t_start:
        raise ConfigError(f"constellation span: the end ({t_end}) is before the start ({t_start})")
    toe = np.arange(np.floor(t_start / record_interval_s), np.floor(t_end / record_interval_s) + 1) \
        * record_interval_s
    T, P = spec.n_sats, spec.n_planes
    S = T // P
    plane = np.repeat(np.arange(P), S)
    slot = np.tile(np.arange(S), P)
    node_offset, u_offset = rng.uniform(0.0, 2.0 * np.pi, 2)
    ecc = rng.uniform(5e-4, 5e-3, T)
    argp = rng.uniform(-np.pi, np.pi, T)
    af0 = rng.uniform(-5e-4, 5e-4, T)
    af1 = rng.uniform(-1e-11, 1e-11, T)
    lsb = 2.0**-31 if spec.system == "G" else 2.0**-32
    tgd = np.round(rng.uniform(-1e-8, 1e-8, T) / lsb) * lsb
    raan = node_offset + plane * 2.0 * np.pi / P
    u = u_offset + slot * 2.0 * np.pi / S + plane * spec.phasing * 2.0 * np.pi / T
    # mean anomaly from the argument of latitude (nu ~ M + 2 e sin M for small e: the slot moves by < 0.6 deg)
    m_first = _wrap(u - argp)

    n_rec = len(toe)
    dt = np.repeat(toe - toe[0], T)
    week = np.floor(toe / K.SECONDS_PER_WEEK)
    dweek = np.repeat((week - week[0]) * K.SECONDS_PER_WEEK, T)

    def rep(a):
        return np.tile(np.asarray(a, dtype=float), n_rec)

    n = spec.mean_motion
    zero = np.zeros(n_rec * T)
    iod = np.repeat(np.arange(n_rec) % 256, T).astype(float)  # one issue of data per record epoch
    params = {
        "af0": af0[np.tile(np.arange(T), n_rec)] + rep(af1) * dt,
        "af1": rep(af1), "af2": zero.copy(),
        "iode": iod, "iodc": iod.copy(),
        "crs": zero.copy(), "crc": zero.copy(), "cus": zero.copy(), "cuc": zero.copy(),
        "cis": zero.copy(), "cic": zero.copy(), "dn": zero.copy(), "idot": zero.copy(),
        "m0": _wrap(rep(m_first) + n * dt),
        "e": rep(ecc),
        "sqrt_a": zero + np.sqrt(spec.semi_major_axis_m),
        "omega0": _wrap(rep(raan) + spec.node_rate * dt - K.OMEGA_E_GPS * dweek),
        "i0": zero + spec.inclination_rad,
        "omega": rep(argp),
        "omega_dot": zero + spec.node_rate,
        "week": np.repeat(week, T),
        "svacc": zero + (2.0 if spec.system == "G" else 3.12),
        "health": zero.copy(),
        "fit_h": zero + 4.0,
    }
    week_start = np.repeat(week * K.SECONDS_PER_WEEK, T)
    params["toe_sow"] = np.repeat(toe, T) - week_start
    params["ttm"] = np.maximum(params["toe_sow"] - RECORD_INTERVAL_S, 0.0)
    nan = np.full(n_rec * T, np.nan)
    if spec.system == "G":
        params.update(tgd=rep(tgd), codes_l2=zero + 1.0, l2p_flag=zero.copy(), bgd_e5a_e1=nan,
                      bgd_e5b_e1=nan.copy(), data_source=nan.copy())
    else:
        # I/NAV (E1-B and E5b-I, clock for E5b/E1: bits 0, 2, 9); both BGDs equal
        params.update(tgd=nan, iodc=nan.copy(), fit_h=nan.copy(), codes_l2=nan.copy(), l2p_flag=nan.copy(),
                      bgd_e5a_e1=rep(tgd), bgd_e5b_e1=rep(tgd), data_source=zero + 517.0)
    for k, v in params.items():
        params[k] = nav_precision(v)
    names = np.array([f"{spec.system}{i + 1:02d}" for i in range(T)])
    toe_all = np.repeat(toe, T)
    return {"sats": np.tile(names, n_rec), "system": np.full(n_rec * T, spec.system), "toc": toe_all,
            "toe": toe_all.copy(), "params": params}


def _nav_data(parts, iono_alpha, iono_beta, path):
    """One :class:`NavData` from record dicts."""
    from ..gnss.rinex import NavData

    keys = sorted(set().union(*(p["params"] for p in parts)))

    def cat(k):
        return np.concatenate([np.asarray(p[k]) for p in parts])

    params = {k: np.concatenate([np.asarray(p["params"].get(k, np.full(len(p["toe"]), np.nan)), float)
                                 for p in parts]) for k in keys}
    return NavData(path=str(path), sats=cat("sats"), system=cat("system"),
                   toc=cat("toc").astype(float), toe=cat("toe").astype(float), params=params,
                   iono_alpha=None if iono_alpha is None else np.asarray(iono_alpha, float),
                   iono_beta=None if iono_beta is None else np.asarray(iono_beta, float))


def walker_constellation(name, t_start, t_end, rng, *, iono_alpha=None, iono_beta=None):
    """The broadcast records (a ``NavData``) of a named synthetic
    constellation over ``[t_start, t_end]`` [s since the GPS epoch].

    Parameters
    ----------
    name : {"walker-gps", "walker-galileo", "walker-gps+galileo"}
    t_start, t_end : float
    rng : numpy.random.Generator
        See :func:`walker_records` (GPS drawn before Galileo).
    iono_alpha, iono_beta : (4,) array_like, optional
        Klobuchar coefficients to carry (written to the RINEX header).
    """
    if name not in CONSTELLATIONS:
        raise ConfigError(f"unknown constellation {name!r}: use one of {sorted(CONSTELLATIONS)} or 'nav:PATH'")
    parts = [walker_records(s, t_start, t_end, rng) for s in CONSTELLATIONS[name]]
    return _nav_data(parts, iono_alpha, iono_beta, path=f"synthetic:{name}")


def constellation_from_nav(nav_path, t_start=None, t_end=None, *, systems=("G", "E"), min_sats=4):
    """The GPS and Galileo satellites of a real RINEX navigation file.

    Parameters
    ----------
    nav_path : str or Path
    t_start, t_end : float, optional
        Scenario span [s since the GPS epoch].  When given, at least
        ``min_sats`` satellites must have a valid ephemeris
        (:func:`inskit.gnss.ephemeris.satellite_states`) at both ends, else
        :class:`ConfigError` says which span the file covers.
    systems : tuple of str
        Systems kept (other records, e.g. SBAS, are dropped).

    Returns
    -------
    NavData
        The file's records of ``systems`` (with its Klobuchar coefficients
        if its header has them).
    """
    from ..gnss.ephemeris import satellite_states
    from ..gnss.rinex import read_nav
    from ..gnss.time import week_sow

    nav_path = Path(nav_path)
    if nav_path.is_dir():  # 'nav:.' or 'nav:data/': it said 'no such navigation file' of a folder that exists
        raise ConfigError(f"{nav_path}: is a folder; expected a RINEX navigation file")
    if not nav_path.is_file():
        raise ConfigError(f"{nav_path}: no such navigation file")
    nav = read_nav(nav_path)
    keep = np.isin(np.asarray(nav.system).astype(str), list(systems))
    if not keep.any():
        raise ConfigError(f"{nav_path}: no {'/'.join(systems)} ephemeris records")
    nav = keep_records(nav, keep)
    if t_start is None:
        return nav
    sats = sorted(set(np.asarray(nav.sats).astype(str)))
    toe = np.asarray(nav.toe, float)
    for label, t in (("start", t_start), ("end", t_end if t_end is not None else t_start)):
        st = satellite_states(nav, np.array(sats), np.full(len(sats), float(t)))
        n_ok = int(np.count_nonzero(st.valid))
        if n_ok < min_sats:
            w0, s0 = week_sow(toe.min())
            w1, s1 = week_sow(toe.max())
            wt, st_ = week_sow(t)
            raise ConfigError(
                f"{nav_path}: the scenario {label} (GPS week {int(wt)}, {float(st_):.0f} s of week) is outside the "
                f"file's validity: only {n_ok} satellites have a valid ephemeris then (need {min_sats}); its "
                f"records have toe from week {int(w0)} {float(s0):.0f} s to week {int(w1)} {float(s1):.0f} s "
                f"(valid about +-2 h around each); set raw_gnss.start_gps_week/start_sow_s inside that span")
    return nav


def keep_records(nav, mask):
    """The records ``mask`` of a ``NavData`` as a new ``NavData``."""
    import dataclasses

    mask = np.asarray(mask, bool)
    return dataclasses.replace(nav, sats=np.asarray(nav.sats)[mask], system=np.asarray(nav.system)[mask],
                               toc=np.asarray(nav.toc, float)[mask], toe=np.asarray(nav.toe, float)[mask],
                               params={k: np.asarray(v)[mask] for k, v in nav.params.items()})
