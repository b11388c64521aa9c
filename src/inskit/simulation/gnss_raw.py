"""Raw GNSS measurements: pseudorange, carrier phase, Doppler and C/N0.

The simulated receiver sees the satellites of a broadcast ephemeris
(:class:`inskit.gnss.rinex.NavData`, synthetic from
:mod:`.constellation` or from a real file) through the same algorithm any
user of the RINEX files applies (:func:`inskit.gnss.ephemeris.satellite_states`),
so the simulator and the GNSS engine can be checked against each other.

Measurement model (one row per epoch ``k`` and satellite ``s``)
--------------------------------------------------------------

**Time tags** are receiver-clock time on a regular grid: ``tag_k = t0_gps +
t_sim_k``.  The receiver clock offset ``dt_rx`` is *defined* as tag minus
true time, so the signal arrives at true (GPS) time ``t_k = tag_k -
dt_rx_k``; the trajectory is evaluated at ``t_k - t0_gps`` (scenario time).

**Geometry.** The antenna is at ``r_rx = r + C_en C_nb l_b`` (lever arm
``l_b`` in body axes from the trajectory point); its ECEF velocity is
``C_en v_n + C_eb (omega_eb_b x l_b)`` with ``omega_eb_b = omega_nb_b +
C_bn omega_en_n``.  The transmission time ``t_tx = t - tau`` solves
``|R3(omega_e tau) r_sat(t_tx) - r_rx(t)| = c tau`` (Sagnac: the satellite
position of the ECEF frame at ``t_tx`` rotated into the frame at ``t``;
fixed-point iteration, 4 passes from ``tau = 0.07 s``, converged to
< 1e-15 s); ``rho = c tau`` is the geometric range.  Its rate with respect
to the reception time is analytic: with ``u`` the unit line of sight,
``rho_dot = u.(R v_sat - v_rx) / (1 - u.(omega_e R' r_sat - R v_sat)/c)``
(the second term is the rate of the travel time itself).

**Code** ``C = rho + c (dt_rx - (dt_sv - gamma TGD)) + gamma I + T + m +
e_code``: ``dt_sv`` is ``satellite_states(...).clock_s`` at ``t_tx``
(broadcast polynomial plus the relativistic term), ``TGD`` its
``group_delay_s`` (TGD for GPS, BGD(E1,E5b) for Galileo I/NAV), ``gamma =
(f1 / f)^2`` (1 on L1/E1), so an engine that forms ``C + c (dt_sv -
TGD) - I - T`` recovers ``rho + c dt_rx`` (IS-GPS-200N 20.3.3.3.3.2).
``I`` is the Klobuchar L1 slant delay (coefficients ``iono_alpha,
iono_beta``, times ``iono_scale``: a scale other than 1 makes the
broadcast model the engine uses "wrong"), ``T`` the Saastamoinen slant
delay of the standard atmosphere, ``m`` multipath.

**Phase** ``L = (rho + c (dt_rx - (dt_sv - gamma TGD)) - gamma I + T +
e_phase) / lambda + N`` [cycles]: the ionosphere advances the phase;
*group-delay convention*: the phase carries the same satellite clock term
as the code of its band, i.e. a satellite phase bias equal to the code
group delay, so that a user who corrects phase and code alike sees them
differ only by ``2 I`` and the integer ``N``.  ``N`` is an integer drawn
per satellite pass (a pass is a run of consecutive epochs in view), uniform
in [-1000, 1000]; no cycle slips inside a pass; the first epoch of every
pass after the first epoch of the file has loss-of-lock indicator 1.

**Doppler** ``D = -(rho_dot + c (ddt_rx - ddt_sv (1 - rho_dot / c)) -
gamma dI/dt + dT/dt) / lambda + e_doppler / lambda`` [Hz] (RINEX sign:
positive when the satellite approaches): the derivative of the phase with
respect to the reception time; ``ddt_rx`` is the clock model's drift state,
``ddt_sv`` the broadcast drift (at ``t_tx``, which advances at ``1 -
rho_dot / c``), ``dI/dt`` and ``dT/dt`` by central differences over the
epochs (second order; one-sided at the ends, zero for a single epoch).
Multipath does not enter the Doppler.

**C/N0** ``S = cn0_horizon + (cn0_zenith - cn0_horizon) sin(el)`` [dB-Hz]
(3 dB lower on the second frequency).

**Noise** white, per observable, ``sigma(el) = sigma_zenith / sin(el)``
with ``sin(el)`` floored at 0.1 (5.7 deg); **multipath** on the code a
first-order Gauss-Markov process per satellite and frequency (unit
variance, correlation time ``multipath_tau_s``, stationary start) times
``multipath_sigma_m / sin(el)``.

**Receiver clock** a two-state oscillator: bias ``b`` and drift ``d``,
``b' = d + w_f``, ``d' = w_g`` with white frequency noise of PSD ``q_f =
h0 / 2`` [s] and random-walk frequency noise ``q_g = 2 pi^2 h_-2`` [1/s],
discretised exactly (``Q = [[q_f dt + q_g dt^3/3, q_g dt^2/2], [q_g dt^2/2,
q_g dt]]``), so the Allan variance is ``h0 / (2 tau) + (2 pi^2 / 3) h_-2
tau`` (flicker ``h_-1`` left out).  Defaults: a TCXO, ``h0 = 2e-19 s``,
``h_-2 = 2e-20 1/s`` (Brown & Hwang's table of oscillator coefficients),
initial bias 100 us, drift 0.1 ppm (1e-7 s/s).  No steering; with
``jumps`` the receiver keeps ``|dt_rx| <= 0.5 ms`` by stepping its clock
by whole milliseconds (code, phase and tags step together; the Doppler
does not).

**Visibility**: a valid broadcast record, elevation at or above the mask,
and outside blockage windows; inside a window only the ``keep``
highest-elevation satellites above the mask (or the named satellites)
remain.

Random draws, in this order (all over the full ``(n_ep, n_sat)`` grid, so
they do not depend on what is visible): clock (``(n_ep - 1, 2)``), then
per frequency: code noise, phase noise, Doppler noise, multipath driving
noise, ambiguities.

References
----------
IS-GPS-200N 20.3.3.3.3.1-2 (satellite clock, relativity, TGD), 20.3.3.4.3.4
(Earth rotation during signal travel), 20.3.3.5.2.5 (Klobuchar); RINEX 3.04
§5.2-5.3 (signs of phase and Doppler, LLI); Brown & Hwang, *Introduction to
Random Signals and Applied Kalman Filtering*, 4th ed. (2012) §9.3 (clock
model, ``h`` coefficients); Groves 2013 §9.3.2 (signal travel, Sagnac),
§9.4 (range rate), §9.3.3 (elevation-dependent noise); Saastamoinen (1972).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import earth
from ..errors import ConfigError
from ..gnss import constants as K
from ..gnss.atmosphere import (
    KLOBUCHAR_DEFAULT_ALPHA,
    KLOBUCHAR_DEFAULT_BETA,
    elevation_azimuth,
    klobuchar_delay,
    saastamoinen_delay,
)
from ..gnss.ephemeris import satellite_states, select_records
from ..gnss.rinex_write import iono_precision

#: Second-frequency signals written with ``dual_frequency``: GPS L2 P(Y)
#: semi-codeless, Galileo E5b (the band of the I/NAV clock and BGD).
SECOND_BAND = {"G": "2W", "E": "7Q"}
FIRST_BAND = {"G": "1C", "E": "1C"}
_LIGHT_TIME_PASSES = 4
_MIN_SIN_EL = 0.1


@dataclass(frozen=True)
class ClockModel:
    """Receiver oscillator (see the module docstring).

    Attributes
    ----------
    bias_s : float
        Initial clock offset [s].
    drift_s_s : float
        Initial frequency offset [s/s].
    h0 : float
        White frequency noise coefficient [s] (Allan variance ``h0 / (2 tau)``).
    h_2 : float
        Random-walk frequency coefficient [1/s] (Allan variance
        ``(2 pi^2 / 3) h_2 tau``).
    jumps : bool
        Keep the offset within +-0.5 ms by whole-millisecond steps.
    """

    bias_s: float = 1e-4
    drift_s_s: float = 1e-7
    h0: float = 2e-19
    h_2: float = 2e-20
    jumps: bool = False

    def __post_init__(self):
        if self.h0 < 0 or self.h_2 < 0:
            raise ConfigError(f"clock: h0 and h_2 must be >= 0, got {self.h0} and {self.h_2}")

    def allan_deviation(self, tau):
        """Model Allan deviation at averaging times ``tau`` [s]."""
        tau = np.asarray(tau, dtype=float)
        return np.sqrt(self.h0 / (2.0 * tau) + 2.0 * np.pi**2 / 3.0 * self.h_2 * tau)


@dataclass(frozen=True)
class Blockage:
    """A window of scenario time ``[start_s, end_s]`` in which only ``keep``
    satellites (the highest above the mask), or the named ``sats`` that are
    above the mask, remain visible."""

    start_s: float
    end_s: float
    keep: int = 0
    sats: tuple = ()

    def __post_init__(self):
        if not self.end_s > self.start_s:
            raise ConfigError(f"blockage window: end_s ({self.end_s}) must come after start_s ({self.start_s})")
        if self.keep < 0:
            raise ConfigError(f"blockage window: keep must be >= 0, got {self.keep}")


@dataclass(frozen=True)
class RawGnssSpec:
    """Raw-measurement error model and receiver (SI units; see module docstring).

    Attributes
    ----------
    mask_rad : float
        Elevation mask [rad].
    code_sigma_m, phase_sigma_m : float
        Zenith white noise of code and phase [m].
    doppler_sigma_m_s : float
        Zenith white noise of the Doppler, as range rate [m/s].
    multipath_sigma_m, multipath_tau_s : float
        Zenith sigma [m] and correlation time [s] of code multipath.
    clock : ClockModel
    iono_alpha, iono_beta : (4,) tuple
        Klobuchar coefficients of the simulated ionosphere, rounded to the
        5 significant digits the RINEX header holds (so the file's reader
        has the same model).
    iono_scale : float
        Factor on the Klobuchar delay (0: no ionosphere).
    troposphere : bool
    dual_frequency : bool
        Add the second band (:data:`SECOND_BAND`).
    lever_arm_b_m : (3,) tuple
        Antenna position from the trajectory point, body axes [m].
    blockage : tuple of Blockage
    cn0_zenith_dbhz, cn0_horizon_dbhz : float
    """

    mask_rad: float = np.radians(10.0)
    code_sigma_m: float = 0.5
    phase_sigma_m: float = 0.003
    doppler_sigma_m_s: float = 0.05
    multipath_sigma_m: float = 0.3
    multipath_tau_s: float = 30.0
    clock: ClockModel = field(default_factory=ClockModel)
    iono_alpha: tuple = tuple(iono_precision(KLOBUCHAR_DEFAULT_ALPHA))
    iono_beta: tuple = tuple(iono_precision(KLOBUCHAR_DEFAULT_BETA))
    iono_scale: float = 1.0
    troposphere: bool = True
    dual_frequency: bool = False
    lever_arm_b_m: tuple = (0.0, 0.0, 0.0)
    blockage: tuple = ()
    cn0_zenith_dbhz: float = 48.0
    cn0_horizon_dbhz: float = 34.0

    def __post_init__(self):
        for name in ("code_sigma_m", "phase_sigma_m", "doppler_sigma_m_s", "multipath_sigma_m", "iono_scale"):
            if getattr(self, name) < 0:
                raise ConfigError(f"raw GNSS: {name} must be >= 0, got {getattr(self, name)}")
        if not self.multipath_tau_s > 0:
            raise ConfigError(f"raw GNSS: multipath_tau_s must be > 0, got {self.multipath_tau_s}")
        if not -np.pi / 2 < self.mask_rad < np.pi / 2:
            raise ConfigError(f"raw GNSS: the elevation mask must be within (-90, 90) deg, got "
                              f"{np.degrees(self.mask_rad)}")
        for name in ("iono_alpha", "iono_beta"):
            if np.shape(getattr(self, name)) != (4,):
                raise ConfigError(f"raw GNSS: {name} must have 4 coefficients")


@dataclass(frozen=True, eq=False)
class RawSimulation:
    """Simulated raw observations and their truth.

    Attributes
    ----------
    time : (n_ep,) ndarray
        Receiver time tags [s since the GPS epoch] (the RINEX epochs).
    t_sim : (n_ep,) ndarray
        The same tags in scenario time [s] (``time - t0_gps``).
    t0_gps : float
        GPS time of scenario time 0 [s since the GPS epoch].
    sats : tuple of str, n_sat
    obs : dict
        ``'C1C' 'L1C' 'D1C' 'S1C'`` (and the second band's) -> ``(n_ep,
        n_sat)`` [m, cycles, Hz, dB-Hz], NaN where not in view.
    lli : dict
        Phase code -> ``(n_ep, n_sat)`` int8 loss-of-lock indicators.
    clock_bias_s, clock_drift_s_s : (n_ep,) ndarray
        True receiver clock offset (tag - true time) [s] and drift [s/s].
    t_true : (n_ep,) ndarray
        True reception time [s since the GPS epoch] (a float64 of 1.4e9 s
        resolves 0.24 us; ``t_sim - clock_bias_s`` is the same time in
        scenario seconds at full precision).
    r_e, v_e : (n_ep, 3) ndarray
        True antenna ECEF position [m] and velocity [m/s] at ``t_true``.
    elevation, azimuth : (n_ep, n_sat) ndarray
        [rad], NaN without a valid ephemeris.
    visible : (n_ep, n_sat) bool ndarray
        In view (has observations).
    blocked : (n_ep, n_sat) bool ndarray
        Above the mask but removed by a blockage window.
    range_m, range_rate_m_s : (n_ep, n_sat) ndarray
        Geometric range with the Sagnac rotation and its rate.
    sat_clock_s, group_delay_s : (n_ep, n_sat) ndarray
        ``dt_sv`` (with relativity) and TGD/BGD used [s].
    iono_m, tropo_m, multipath_m : (n_ep, n_sat) ndarray
        L1 ionospheric delay (scaled), tropospheric delay and L1 code
        multipath [m].
    nav : NavData
        The broadcast records the satellites follow.
    iono_alpha, iono_beta : (4,) ndarray
        Klobuchar coefficients the nav file carries (the simulated
        ionosphere is ``iono_scale`` times this model).
    """

    time: np.ndarray
    t_sim: np.ndarray
    t0_gps: float
    sats: tuple
    obs: dict
    lli: dict
    clock_bias_s: np.ndarray
    clock_drift_s_s: np.ndarray
    t_true: np.ndarray
    r_e: np.ndarray
    v_e: np.ndarray
    elevation: np.ndarray
    azimuth: np.ndarray
    visible: np.ndarray
    blocked: np.ndarray
    range_m: np.ndarray
    range_rate_m_s: np.ndarray
    sat_clock_s: np.ndarray
    group_delay_s: np.ndarray
    iono_m: np.ndarray
    tropo_m: np.ndarray
    multipath_m: np.ndarray
    nav: object
    iono_alpha: np.ndarray
    iono_beta: np.ndarray

    @property
    def n_visible(self):
        """Satellites in view per epoch, ``(n_ep,)``."""
        return self.visible.sum(axis=1)


def simulate_clock(t, clock: ClockModel, rng):
    """Receiver clock offset and drift at times ``t`` (see module docstring).

    Parameters
    ----------
    t : (n,) array_like
        Epochs [s], increasing.
    clock : ClockModel
    rng : numpy.random.Generator
        Draws ``(n - 1, 2)`` standard normals.

    Returns
    -------
    bias_s, drift_s_s : (n,) ndarray
    """
    t = np.asarray(t, dtype=float)
    n = len(t)
    dt = np.diff(t)
    z = rng.standard_normal((max(n - 1, 0), 2))
    qf, qg = clock.h0 / 2.0, 2.0 * np.pi**2 * clock.h_2
    q11 = qf * dt + qg * dt**3 / 3.0
    q12 = qg * dt**2 / 2.0
    q22 = qg * dt
    l11 = np.sqrt(q11)
    l21 = np.divide(q12, l11, out=np.zeros_like(q12), where=l11 > 0)
    l22 = np.sqrt(np.maximum(q22 - l21**2, 0.0))
    w1 = l11 * z[:, 0]
    w2 = l21 * z[:, 0] + l22 * z[:, 1]
    drift = clock.drift_s_s + np.concatenate([[0.0], np.cumsum(w2)])
    bias = clock.bias_s + np.concatenate([[0.0], np.cumsum(drift[:-1] * dt + w1)])
    if clock.jumps:
        bias = bias - 1e-3 * np.round(bias / 1e-3)
    return bias, drift


def _gauss_markov_unit(t, tau, z):
    """Unit-variance first-order Gauss-Markov sequences along axis 0 from
    standard normals ``z`` (stationary start), for any time steps."""
    out = np.empty_like(z)
    out[0] = z[0]
    phi = np.exp(-np.diff(t) / tau)
    s = np.sqrt(1.0 - phi * phi)
    if len(phi) and np.ptp(phi) < 1e-12:
        from scipy.signal import lfilter

        zi = phi[0] * z[0][None, :]
        out[1:] = lfilter([1.0], [1.0, -phi[0]], s[0] * z[1:], axis=0, zi=zi)[0]
    else:
        for k in range(1, len(t)):
            out[k] = phi[k - 1] * out[k - 1] + s[k - 1] * z[k]
    return out


def _rot_z(pos, theta):
    """``R3(theta) r`` for rows of ``pos`` (the reception-frame coordinates
    of a point fixed in inertial space while the Earth turns by theta)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([c * pos[:, 0] + s * pos[:, 1], -s * pos[:, 0] + c * pos[:, 1], pos[:, 2]], axis=-1)


def antenna_motion(trajectory, t, lever_arm_b):
    """Antenna ECEF position and velocity at scenario times ``t``.

    Returns
    -------
    r_e, v_e : (n, 3) ndarray
    lla : (n, 3) ndarray
        Antenna latitude, longitude [rad], height [m].
    """
    kin = trajectory.kinematics(np.asarray(t, dtype=float))
    lever = np.asarray(lever_arm_b, dtype=float).reshape(3)
    lat, lon, h = kin.lla[:, 0], kin.lla[:, 1], kin.lla[:, 2]
    C_en = earth.dcm_en(lat, lon)
    C_eb = C_en @ kin.C_nb
    r_e = earth.lla_to_ecef(kin.lla) + C_eb @ lever
    w_en_n = earth.rate_en_n(lat, h, kin.v_n)
    w_eb_b = kin.omega_nb_b + np.einsum("nji,nj->ni", kin.C_nb, w_en_n)
    v_e = np.einsum("nij,nj->ni", C_en, kin.v_n) + np.einsum("nij,nj->ni", C_eb, np.cross(w_eb_b, lever))
    return r_e, v_e, earth.ecef_to_lla(r_e)


def simulate_raw(trajectory, t_sim, *, t0_gps, nav, spec: RawGnssSpec, rng) -> RawSimulation:
    """Simulate raw GNSS observations of a trajectory (see module docstring).

    Parameters
    ----------
    trajectory : object
        With ``kinematics(t)`` (e.g. :class:`.segments.SegmentTrajectory`),
        ``t`` in scenario time [s].
    t_sim : (n_ep,) array_like
        Receiver time tags in scenario time [s], increasing.  The true
        reception times are earlier by the clock offset (tens to hundreds
        of microseconds): the trajectory is evaluated there.
    t0_gps : float
        GPS time of scenario time 0 [s since the GPS epoch].
    nav : NavData
        Broadcast records of the satellites (GPS and/or Galileo).
    spec : RawGnssSpec
    rng : numpy.random.Generator

    Returns
    -------
    RawSimulation
    """
    t_sim = np.ascontiguousarray(t_sim, dtype=float)
    if t_sim.ndim != 1 or len(t_sim) == 0:
        raise ConfigError(f"raw GNSS: t_sim must be a non-empty (n_ep,) array, got shape {t_sim.shape}")
    if (np.diff(t_sim) <= 0).any():
        raise ConfigError("raw GNSS: the epochs t_sim must strictly increase")
    sats = np.array(sorted({str(s) for s, sy in zip(nav.sats, nav.system) if sy in ("G", "E")}))
    if len(sats) == 0:
        raise ConfigError("raw GNSS: the navigation data have no GPS or Galileo satellite")
    n_ep, n_sat = len(t_sim), len(sats)
    system = np.array([s[0] for s in sats])
    tags = t0_gps + t_sim

    bias, drift = simulate_clock(t_sim, spec.clock, rng)
    t_true_sim = t_sim - bias
    r_rx, v_rx, lla_rx = antenna_motion(trajectory, t_true_sim, spec.lever_arm_b_m)
    t_true = tags - bias

    # --- light time with the Earth's rotation, all rows at once ---
    rows_sat = np.tile(sats, n_ep)
    rows_t = np.repeat(t_true, n_sat)
    rows_r = np.repeat(r_rx, n_sat, axis=0)
    rows_v = np.repeat(v_rx, n_sat, axis=0)
    rec = select_records(nav, rows_sat, np.repeat(tags, n_sat))
    tau = np.full(n_ep * n_sat, 0.07)
    for _ in range(_LIGHT_TIME_PASSES):
        st = satellite_states(nav, rows_sat, rows_t - tau, records=rec)
        pos = _rot_z(np.nan_to_num(st.pos_e), K.OMEGA_E_GPS * tau)
        tau = np.linalg.norm(pos - rows_r, axis=1) / K.C
    st = satellite_states(nav, rows_sat, rows_t - tau, records=rec)
    valid = st.valid.reshape(n_ep, n_sat)
    theta = K.OMEGA_E_GPS * tau
    pos = _rot_z(np.nan_to_num(st.pos_e), theta)
    vel = _rot_z(np.nan_to_num(st.vel_e), theta)
    los = pos - rows_r
    rho = np.linalg.norm(los, axis=1)
    u = los / rho[:, None]
    # d/dtheta R3(theta) r = R3(theta) [y, -x, 0]
    p0 = np.nan_to_num(st.pos_e)
    dpos = _rot_z(np.stack([p0[:, 1], -p0[:, 0], np.zeros(len(p0))], axis=-1), theta)
    a_term = np.einsum("ij,ij->i", u, vel - rows_v)
    b_term = np.einsum("ij,ij->i", u, K.OMEGA_E_GPS * dpos - vel)
    rho_dot = a_term / (1.0 - b_term / K.C)
    el, az = elevation_azimuth(rows_r, pos)

    shape = (n_ep, n_sat)
    rho, rho_dot, el, az = (x.reshape(shape) for x in (rho, rho_dot, el, az))
    el = np.where(valid, el, np.nan)
    az = np.where(valid, az, np.nan)
    dt_sv = st.clock_s.reshape(shape)
    ddt_sv = st.drift_s_s.reshape(shape)
    gd = st.group_delay_s.reshape(shape)

    # --- atmosphere: evaluated everywhere (elevation clamped) so the time derivatives exist ---
    el_c = np.clip(np.nan_to_num(el, nan=np.pi / 2), 0.02, None)
    lla_rows = np.repeat(lla_rx, n_sat, axis=0)
    alpha, beta = np.asarray(spec.iono_alpha, float), np.asarray(spec.iono_beta, float)
    az_c = np.nan_to_num(az, nan=0.0).ravel()
    iono = spec.iono_scale * klobuchar_delay(np.repeat(t_true, n_sat), lla_rows, az_c, el_c.ravel(), alpha,
                                             beta).reshape(shape)
    tropo = (saastamoinen_delay(lla_rows, el_c.ravel()).reshape(shape) if spec.troposphere
             else np.zeros(shape))
    if n_ep > 1:
        d_iono = np.gradient(iono, t_true, axis=0)
        d_tropo = np.gradient(tropo, t_true, axis=0)
    else:
        d_iono = d_tropo = np.zeros(shape)

    # --- visibility, blockage ---
    above = valid & (el >= spec.mask_rad)
    visible = above.copy()
    for w in spec.blockage:
        inside = (t_sim >= w.start_s) & (t_sim <= w.end_s)
        if not inside.any():
            continue
        sub = above[inside]
        if w.sats:
            unknown = sorted(set(w.sats) - set(sats.tolist()))
            if unknown:
                raise ConfigError(f"blockage window {w.start_s}..{w.end_s} s names satellites not in the "
                                  f"constellation: {unknown}")
            keep = sub & np.isin(sats, list(w.sats))[None, :]
        else:
            score = np.where(sub, el[inside], -np.inf)
            rank = np.argsort(np.argsort(-score, axis=1, kind="stable"), axis=1)
            keep = sub & (rank < w.keep)
        visible[inside] &= keep
    blocked = above & ~visible

    # --- passes: integer ambiguity per pass, LLI at re-acquisition ---
    k_idx = np.arange(n_ep)[:, None]
    starts = visible & np.vstack([np.ones((1, n_sat), bool), ~visible[:-1]])
    start_of_pass = np.maximum.accumulate(np.where(starts, k_idx, -1), axis=0)
    lli1 = (starts & (k_idx > 0)).astype(np.int8)

    sin_el = np.maximum(np.sin(el_c), _MIN_SIN_EL)
    clock_m = K.C * bias[:, None]
    drift_m_s = K.C * drift[:, None]
    sv_rate = K.C * ddt_sv * (1.0 - rho_dot / K.C)
    nan = np.full(shape, np.nan)
    obs, lli = {}, {}
    bands = [FIRST_BAND] + ([SECOND_BAND] if spec.dual_frequency else [])
    mp_first = None
    for band in bands:
        code_noise = rng.standard_normal(shape) * spec.code_sigma_m / sin_el
        phase_noise = rng.standard_normal(shape) * spec.phase_sigma_m / sin_el
        dopp_noise = rng.standard_normal(shape) * spec.doppler_sigma_m_s / sin_el
        mp = _gauss_markov_unit(t_true, spec.multipath_tau_s, rng.standard_normal(shape)) \
            * spec.multipath_sigma_m / sin_el
        amb = rng.integers(-1000, 1001, shape)
        n_cycles = np.take_along_axis(amb, np.maximum(start_of_pass, 0), axis=0)
        if mp_first is None:
            mp_first = mp
        freq = np.array([K.frequency(sy, "C" + band[sy]) for sy in system])
        lam = K.C / freq
        gamma = (K.FREQ_L1 / freq) ** 2
        sv_clock_m = K.C * (dt_sv - gamma * gd)
        code = rho + clock_m - sv_clock_m + gamma * iono + tropo + mp + code_noise
        phase = (rho + clock_m - sv_clock_m - gamma * iono + tropo + phase_noise) / lam + n_cycles
        dopp = -(rho_dot + drift_m_s - sv_rate - gamma * d_iono + d_tropo + dopp_noise) / lam
        cn0 = spec.cn0_horizon_dbhz + (spec.cn0_zenith_dbhz - spec.cn0_horizon_dbhz) * np.sin(el_c)
        if band is SECOND_BAND:
            cn0 = cn0 - 3.0
        # codes are per system: a satellite gets the code of its own system's band
        for sy in sorted(set(system)):
            cols = system == sy
            sig = band[sy]
            for kind, val in (("C", code), ("L", phase), ("D", dopp), ("S", cn0)):
                name = kind + sig
                arr = obs.setdefault(name, nan.copy())
                m = visible & cols[None, :]
                arr[m] = val[m]
            li = lli.setdefault("L" + sig, np.zeros(shape, np.int8))
            li[:, cols] = np.where(visible[:, cols], lli1[:, cols], 0)
    return RawSimulation(
        time=tags, t_sim=t_sim, t0_gps=float(t0_gps), sats=tuple(sats.tolist()), obs=obs, lli=lli,
        clock_bias_s=bias, clock_drift_s_s=drift, t_true=t_true, r_e=r_rx, v_e=v_rx,
        elevation=el, azimuth=az, visible=visible, blocked=blocked, range_m=np.where(valid, rho, np.nan),
        range_rate_m_s=np.where(valid, rho_dot, np.nan), sat_clock_s=dt_sv, group_delay_s=gd,
        iono_m=np.where(valid, iono, np.nan), tropo_m=np.where(valid, tropo, np.nan),
        multipath_m=np.where(valid, mp_first, np.nan), nav=nav, iono_alpha=alpha, iono_beta=beta)
