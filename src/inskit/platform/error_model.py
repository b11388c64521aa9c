"""Source 004's platform-INS error model, completed; observability; stability.

State and inputs in source 004's variables (SOURCES-NOTES §2.1-2.2): xi north,
eta west, zeta up (right-handed), platform azimuth ``chi = 0`` (north
pointing)::

    x = [alpha_x, alpha_y, alpha_z, d_phi, d_lambda, dV_xi, dV_eta]
    u = [eps_xi, eps_eta, eps_zeta, da_xi, da_eta]
    x' = F x + B u   (+ corrections)

``alpha`` is the rotation of the platform from the true geographic frame
(``C_true,p = I + [alpha x]``); ``dV_xi``, ``dV_eta`` are errors of the
*absolute* velocity components, ``V_eta = -(V_E + U (R_E+h) cos(phi))``.

How the coefficients were obtained
----------------------------------
The printed equations (eq. 1-3) are incomplete (SOURCES-NOTES §2.2, §2.5): the
``dV_eta`` equation lacks ``-omega_zeta dV_xi``, A, B and the ``d`` in C and
D are undefined, "d_phi0" must be read as the current ``d_phi``.  Rather than
patch term by term, :func:`error_matrix` linearises the semi-analytical
mechanization of :mod:`.mechanization` (the north-pointing platform of
SOURCES-NOTES §3.2, vertical channel slaved) in the relative variables
``[alpha_E, alpha_N, alpha_U, dV_E, dV_N, d_phi, d_lambda]``::

    alpha' = -omega x alpha + d_omega + eps
    d_omega = [-dV_N/R_N, dV_E/R_E - U sin(phi) d_phi,
               tan(phi) dV_E/R_E + (U cos(phi) + V_E/(R_E cos^2 phi)) d_phi]
    dV_E' = -f_U alpha_N + f_N alpha_U + a dV_N + (V_N tan(phi) - V_U)/R_E dV_E
            + (V_N (2U cos(phi) + V_E/(R_E cos^2 phi)) + 2U sin(phi) V_U) d_phi + da_E
    dV_N' = f_U alpha_E - f_E alpha_U - (a + V_E tan(phi)/R_E) dV_E - V_U/R_N dV_N
            - V_E (2U cos(phi) + V_E/(R_E cos^2 phi)) d_phi + da_N
    d_phi' = dV_N/R_N,  d_lambda' = dV_E/(R_E cos(phi)) + V_E sin(phi)/(R_E cos^2 phi) d_phi

plus, on the ellipsoid, the terms from the latitude dependence of the radii
(``-V_N R_N'/R_N^2 d_phi`` in ``d_phi'`` and the like; zero on the sphere)

with ``a = 2U sin(phi) + V_E tan(phi)/R_E`` and ``omega`` the platform's
absolute rate, and transforms it exactly to source 004's variables,
``F = T F_rel T^-1 + T' T^-1`` with ``dV_eta = -dV_E + c(phi) d_phi``,
``c = U (R_E sin(phi) - R_E' cos(phi))``.  The result has the printed
structure (every printed term appears, with ``R_eta = R_E + h``,
``R_xi = R_N + h``, ``1/R_o = 0`` for ``chi = 0``, ``B = [I3 0; 0 0; 0 I2]``)
and these differences from the printed eq. 1-3, each checked against the
mechanization (finite-difference Jacobian and 8 h runs, tests):

* the restored ``-omega_zeta dV_xi`` (SOURCES-NOTES §2.5 flag 1), and in both
  velocity equations the factor of the ``dV`` cross terms is
  ``2 omega_zeta``-like, not ``omega_zeta``: the printed form drops the
  velocity dependence of ``omega_zeta`` (a Coriolis-size term);
* ``alpha_z' = ... + (U + lambda')/cos(phi) d_phi - tan(phi) dV_eta/R_eta``
  instead of ``U cos(phi) d_phi`` (the printed coefficient belongs to a
  platform whose azimuth command omits the transport rate);
* A = 0 and B = -V_E,abs sin(phi)/(R_E cos^2 phi) (about ``-U tan phi`` at
  rest; SOURCES-NOTES §2.2 reconstruction);
* C and D come out as the notes reconstruct them plus the terms above.

:func:`printed_error_matrix` keeps the printed form with the notes' repairs
only, for comparison (the reproduction reports how far it drifts from the
mechanization).

References
----------
SOURCES-NOTES §2.1-2.2, §2.5 (source 004 eq. 1-3); SYSTEM.md §3;
Britting, *Inertial Navigation Systems Analysis*, 1971, ch. 8 (phi- and
psi-angle error equations of a local-level system).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from .. import earth
from ..errors import ConfigError
from . import _kernels as K
from .sensors import InitialErrors, PlatformErrors, enu_to_nwu
from .world import PlatformTruth, model_code

W = earth.OMEGA_IE
NX = 7
NU = 5
STATE_NAMES = ("alpha_x", "alpha_y", "alpha_z", "d_phi", "d_lambda", "dV_xi", "dV_eta")
INPUT_NAMES = ("eps_xi", "eps_eta", "eps_zeta", "da_xi", "da_eta")

__all__ = [
    "INPUT_NAMES",
    "STATE_NAMES",
    "ObservabilityResult",
    "augmented",
    "correction_matrix",
    "error_matrix",
    "input_matrix",
    "observability",
    "printed_error_matrix",
    "simulate_error_model",
    "source_initial_state",
    "source_inputs",
    "stability_margin",
    "stability_region",
    "stationary_closed_form",
]


@njit(cache=True)
def _re_prime(lat, model):
    if model == K.SPHERE:
        return 0.0
    s, c = math.sin(lat), math.cos(lat)
    w2 = 1.0 - earth.E2 * s * s
    return earth.A * earth.E2 * s * c / w2 ** 1.5


@njit(cache=True)
def _rn_prime(lat, model):
    if model == K.SPHERE:
        return 0.0
    s, c = math.sin(lat), math.cos(lat)
    w2 = 1.0 - earth.E2 * s * s
    return 3.0 * earth.A * (1.0 - earth.E2) * earth.E2 * s * c / w2 ** 2.5


@njit(cache=True)
def f_relative(lat, h, vE, vN, vU, fE, fN, fU, model):
    """``F_rel`` over ``[alpha_E, alpha_N, alpha_U, dV_E, dV_N, d_phi, d_lambda]``
    (module docstring); coefficients at the given point."""
    RN, RE = K.radii(lat, h, model)
    sl, cl = math.sin(lat), math.cos(lat)
    tl = sl / cl
    w0, w1, w2 = -vN / RN, W * cl + vE / RE, W * sl + vE * tl / RE
    F = np.zeros((7, 7))
    # alpha' = -omega x alpha + d_omega
    F[0, 1], F[0, 2] = w2, -w1
    F[1, 0], F[1, 2] = -w2, w0
    F[2, 0], F[2, 1] = w1, -w0
    F[0, 4] = -1.0 / RN
    F[1, 3] = 1.0 / RE
    F[1, 5] = -W * sl
    F[2, 3] = tl / RE
    F[2, 5] = W * cl + vE / (RE * cl * cl)
    a = 2.0 * W * sl + vE * tl / RE
    da = 2.0 * W * cl + vE / (RE * cl * cl)
    # dV_E'
    F[3, 1], F[3, 2] = -fU, fN
    F[3, 4] = a
    F[3, 3] = (vN * tl - vU) / RE
    F[3, 5] = vN * da + 2.0 * W * sl * vU
    # dV_N'
    F[4, 0], F[4, 2] = fU, -fE
    F[4, 3] = -(a + vE * tl / RE)
    F[4, 4] = -vU / RN
    F[4, 5] = -vE * da
    # position
    F[5, 4] = 1.0 / RN
    F[6, 3] = 1.0 / (RE * cl)
    F[6, 5] = vE * sl / (RE * cl * cl)
    # latitude dependence of the ellipsoid's radii (zero on the sphere)
    rn_p, re_p = _rn_prime(lat, model), _re_prime(lat, model)
    F[0, 5] += vN * rn_p / (RN * RN)
    F[1, 5] -= vE * re_p / (RE * RE)
    F[2, 5] -= vE * tl * re_p / (RE * RE)
    F[5, 5] -= vN * rn_p / (RN * RN)
    F[6, 5] -= vE * re_p / (RE * RE * cl)
    return F


@njit(cache=True)
def _transform(lat, h, vN, model):
    """``T``, ``T^-1`` and ``T'`` from relative to source variables."""
    RN, RE = K.radii(lat, h, model)
    sl, cl = math.sin(lat), math.cos(lat)
    rp = _re_prime(lat, model)
    c = W * (RE * sl - rp * cl)
    cdot = W * (RE * cl + 2.0 * rp * sl) * vN / RN
    T = np.zeros((7, 7))
    T[0, 1] = 1.0   # alpha_x = alpha_N
    T[1, 0] = -1.0  # alpha_y = -alpha_E
    T[2, 2] = 1.0
    T[3, 5] = 1.0   # d_phi
    T[4, 6] = 1.0   # d_lambda
    T[5, 4] = 1.0   # dV_xi = dV_N
    T[6, 3] = -1.0  # dV_eta = -dV_E + c d_phi
    T[6, 5] = c
    Ti = np.zeros((7, 7))
    Ti[1, 0] = 1.0
    Ti[0, 1] = -1.0
    Ti[2, 2] = 1.0
    Ti[5, 3] = 1.0
    Ti[6, 4] = 1.0
    Ti[4, 5] = 1.0
    Ti[3, 6] = -1.0
    Ti[3, 3] = c
    Td = np.zeros((7, 7))
    Td[6, 5] = cdot
    return T, Ti, Td


@njit(cache=True)
def f_source(lat, h, vE, vN, vU, fE, fN, fU, model):
    """Source-variable ``F`` (7, 7) at one point (compiled)."""
    Fr = f_relative(lat, h, vE, vN, vU, fE, fN, fU, model)
    T, Ti, Td = _transform(lat, h, vN, model)
    return T @ Fr @ Ti + Td @ Ti


def input_matrix():
    """``B`` (7, 5): ``[I3 0; 0 0; 0 I2]`` (SOURCES-NOTES §2.2)."""
    B = np.zeros((NX, NU))
    B[0, 0] = B[1, 1] = B[2, 2] = 1.0
    B[5, 3] = B[6, 4] = 1.0
    return B


def error_matrix(lat, h=0.0, v_enu=(0.0, 0.0, 0.0), f_enu=None, earth_model="wgs84"):
    """Continuous ``F`` (7, 7) of the completed source-004 model at one point.

    Parameters
    ----------
    lat : float
        [rad].
    h : float
        [m].
    v_enu : (3,) array_like
        Earth-relative velocity east, north, up [m/s].
    f_enu : (3,) array_like, optional
        Specific force east, north, up [m/s^2]; default ``[0, 0, g]``.
    earth_model : {"wgs84", "sphere"}

    Returns
    -------
    (7, 7) ndarray
    """
    m = model_code(earth_model)
    if f_enu is None:
        f_enu = (0.0, 0.0, float(K.gravity(lat, h, m)[1]))
    v = np.asarray(v_enu, float)
    f = np.asarray(f_enu, float)
    return f_source(float(lat), float(h), v[0], v[1], v[2], f[0], f[1], f[2], m)


def printed_error_matrix(lat, h=0.0, v_enu=(0.0, 0.0, 0.0), f_enu=None, earth_model="wgs84"):
    """Eq. 1-3 of source 004 as printed, with only the repairs of
    SOURCES-NOTES §2.2/§2.5: ``-omega_zeta dV_xi`` restored, ``d_phi0`` read
    as ``d_phi``, ``C = U^2 R1 cos(2 phi) + V_eta U cos(phi)``,
    ``D = V_xi U cos(phi)`` (printed sign), A = 0,
    ``B = -V_E,abs sin(phi)/(R1 cos^2 phi)``; ``chi = 0``."""
    m = model_code(earth_model)
    RN, RE = K.radii(lat, h, m)
    if f_enu is None:
        f_enu = (0.0, 0.0, float(K.gravity(lat, h, m)[1]))
    vE, vN, vU = (float(x) for x in v_enu)
    fE, fN, fU = (float(x) for x in f_enu)
    sl, cl = np.sin(lat), np.cos(lat)
    w_xi = W * cl + vE / RE
    w_eta = vN / RN
    w_zeta = W * sl + vE * sl / cl / RE
    a_xi, a_eta, a_zeta = fN, -fE, fU
    V_xi, V_eta, V_zeta = vN, -(vE + W * RE * cl), vU
    F = np.zeros((7, 7))
    F[0, 2], F[0, 1], F[0, 6] = -w_eta, w_zeta, -1.0 / RE
    F[1, 2], F[1, 0], F[1, 5] = w_xi, -w_zeta, 1.0 / RN
    F[2, 1], F[2, 0], F[2, 3] = -w_xi, w_eta, W * cl
    C = W * W * RE * np.cos(2 * lat) + V_eta * W * cl
    D = V_xi * W * cl
    F[5, 2], F[5, 1], F[5, 5], F[5, 6], F[5, 3] = a_eta, -a_zeta, -V_zeta / RN, w_zeta, C
    F[6, 2], F[6, 0], F[6, 5], F[6, 6], F[6, 3] = -a_xi, a_zeta, -w_zeta, -V_zeta / RE, D
    F[3, 5] = 1.0 / RN
    Bc = -(vE + W * RE * cl) * sl / (RE * cl * cl)
    F[4, 6], F[4, 3] = -1.0 / (RE * cl), -Bc
    return F


def source_initial_state(initial: InitialErrors, truth: PlatformTruth):
    """``x0`` (7,) in source variables from :class:`InitialErrors`."""
    lat, h = truth.lla[0, 0], truth.lla[0, 2]
    a = enu_to_nwu(np.asarray(initial.tilt))
    _, re = K.radii(lat, h, model_code(truth.earth))
    rp = float(_re_prime(lat, model_code(truth.earth)))
    c = W * (re * np.sin(lat) - rp * np.cos(lat))
    dv = np.asarray(initial.dv_enu)
    return np.array([a[0], a[1], a[2], initial.d_lat, initial.d_lon, dv[1], -dv[0] + c * initial.d_lat])


def source_inputs(errors: PlatformErrors):
    """``u`` (5,) in source variables from semi-analytical platform errors
    (platform axes east, north, up)."""
    e = enu_to_nwu(np.asarray(errors.gyro_drift))
    b = np.asarray(errors.accel_bias)
    return np.array([e[0], e[1], e[2], b[1], -b[0]])


@njit(cache=True)
def _sim_kernel(t, lat, h, v_enu, f_enu, model, x0, u, Kc, out):
    n = t.shape[0]
    x = x0.copy()
    out[0] = x
    B = np.zeros((7, 5))
    B[0, 0] = B[1, 1] = B[2, 2] = 1.0
    B[5, 3] = B[6, 4] = 1.0
    Bu = B @ u
    for k in range(n - 1):
        dt = t[k + 1] - t[k]
        ks = np.empty((4, 7))
        idx = (2 * k, 2 * k + 1, 2 * k + 1, 2 * k + 2)
        for s in range(4):
            j = idx[s]
            F = f_source(lat[j], h[j], v_enu[j, 0], v_enu[j, 1], v_enu[j, 2], f_enu[j, 0], f_enu[j, 1],
                         f_enu[j, 2], model) + Kc
            if s == 0:
                xs = x
            elif s < 3:
                xs = x + 0.5 * dt * ks[s - 1]
            else:
                xs = x + dt * ks[2]
            ks[s] = F @ xs + Bu
        x = x + dt / 6.0 * (ks[0] + 2.0 * ks[1] + 2.0 * ks[2] + ks[3])
        out[k + 1] = x


def simulate_error_model(truth: PlatformTruth, x0, u, *, corrections=None, form="complete"):
    """Integrate ``x' = (F(t) + K_c) x + B u`` along a trajectory (RK4, the
    run's step, coefficients from the truth at half steps).

    Parameters
    ----------
    truth : PlatformTruth
    x0 : (7,) array_like
        Initial errors (source variables).
    u : (5,) array_like
        Constant instrument errors (source variables).
    corrections : (7, 7) array_like, optional
        Closed-loop correction matrix for ideal estimates (see
        :func:`correction_matrix`).
    form : {"complete", "printed"}
        The completed model, or the printed one with the notes' repairs
        (coefficients frozen along the truth in Python, slower).

    Returns
    -------
    (n, 7) ndarray
    """
    model = model_code(truth.earth)
    Kc = np.zeros((7, 7)) if corrections is None else np.asarray(corrections, float)
    x0 = np.asarray(x0, float)
    u = np.asarray(u, float)
    lat = np.ascontiguousarray(truth.lla[:, 0])
    h = np.ascontiguousarray(truth.lla[:, 2])
    v_enu = np.ascontiguousarray(np.column_stack([truth.v_n[:, 1], truth.v_n[:, 0], -truth.v_n[:, 2]]))
    f = truth.f_enu
    n = len(truth.time)
    out = np.empty((n, 7))
    if form == "complete":
        _sim_kernel(truth.time, lat, h, v_enu, f, model, x0, u, Kc, out)
        return out
    if form != "printed":
        raise ConfigError(f"`form` must be 'complete' or 'printed', got {form!r}")
    Bu = input_matrix() @ u
    Fs = [printed_error_matrix(lat[j], h[j], v_enu[j], f[j], truth.earth) + Kc for j in range(2 * n - 1)]
    x = x0.copy()
    out[0] = x
    t = truth.time
    for k in range(n - 1):
        dt = t[k + 1] - t[k]
        k1 = Fs[2 * k] @ x + Bu
        k2 = Fs[2 * k + 1] @ (x + 0.5 * dt * k1) + Bu
        k3 = Fs[2 * k + 1] @ (x + 0.5 * dt * k2) + Bu
        k4 = Fs[2 * k + 2] @ (x + dt * k3) + Bu
        x = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        out[k + 1] = x
    return out


# --- closed form at rest ---------------------------------------------------------------
def stationary_closed_form(t, lat, eps_enu=(0.0, 0.0, 0.0), accel_enu=(0.0, 0.0), g=None, radius=None):
    """Closed-form errors of a stationary local-level platform INS.

    The psi-angle equation ``psi' = -Omega x psi + eps`` (Omega = Earth rate)
    is solved exactly: ``psi = eps_par t + sin(Ut)/U eps_perp - (1 - cos Ut)/U
    (k x eps_perp)`` (the 24 h Earth-rate oscillation); the horizontal
    position error ``z = dr_E + i dr_N`` obeys the Foucault pendulum
    ``z'' + 2 i U sin(phi) z' + w_s^2 z = F``, ``F = (-g psi_N + da_E) +
    i (g psi_E + da_N)``, solved exactly for that forcing with ``z(0) =
    z'(0) = 0`` (Schuler oscillation ``w_s^2 = g/R``, modulated at the
    Foucault rate).  The tilt against the true frame is
    ``alpha = psi + [-d_phi, d_lambda cos(phi), d_lambda sin(phi)]``.

    Parameters
    ----------
    t : (n,) array_like
        [s] from the start.
    lat : float
        [rad].
    eps_enu : (3,) array_like
        Gyro drift, platform axes east, north, up [rad/s].
    accel_enu : (2,) array_like
        Horizontal accelerometer errors east, north [m/s^2].
    g, radius : float, optional
        Gravity [m/s^2] and Earth radius [m] (default: the sphere of
        SYSTEM.md §1.1, ``GM/R^2`` and ``R = 6378 km``).

    Returns
    -------
    dict
        ``tilt_enu`` (n, 3) [rad], ``d_lat``, ``d_lon`` (n,) [rad],
        ``dv_en`` (n, 2) [m/s], ``psi`` (n, 3) [rad].

    References
    ----------
    Britting 1971, §8.3 (stationary solutions); Titterton & Weston,
    *Strapdown Inertial Navigation Technology*, 2nd ed., 2004, §12.3.
    """
    t = np.asarray(t, float)
    R = earth.R_SPHERE if radius is None else float(radius)
    g = earth.GM / R**2 if g is None else float(g)
    U = W
    k = np.array([0.0, np.cos(lat), np.sin(lat)])
    eps = np.asarray(eps_enu, float)
    e_par = (eps @ k) * k
    e_perp = eps - e_par
    kxe = np.cross(k, e_perp)
    s, c = np.sin(U * t), np.cos(U * t)
    psi = np.outer(t, e_par) + np.outer(s / U, e_perp) - np.outer((1 - c) / U, kxe)
    ws2 = g / R
    wz = U * np.sin(lat)
    # forcing F(t) = F0 + F1 t + A e^{iUt} + B e^{-iUt}, from psi's components
    da = np.asarray(accel_enu, float)

    def cplx(v):  # complex forcing of a constant psi-like vector v: -g v_N + i g v_E
        return -g * v[1] + 1j * g * v[0]

    F0 = cplx(-kxe / U) + (da[0] + 1j * da[1])
    F1 = cplx(e_par)
    # sin(Ut)/U e_perp + cos(Ut)/U kxe = Re/Im of exponentials
    P = cplx(e_perp / U)  # multiplies sin(Ut)
    Q = cplx(kxe / U)     # multiplies cos(Ut)
    A = (P / 2j) + Q / 2  # coefficient of e^{iUt}
    Bm = -(P / 2j) + Q / 2  # coefficient of e^{-iUt}

    def zp(tt):
        z = F0 / ws2 + F1 * tt / ws2 - 2j * wz * F1 / ws2**2
        z = z + A * np.exp(1j * U * tt) / (ws2 - U * U - 2 * wz * U)
        z = z + Bm * np.exp(-1j * U * tt) / (ws2 - U * U + 2 * wz * U)
        return z

    def zpd(tt):
        z = F1 / ws2 + 0j * tt
        z = z + 1j * U * A * np.exp(1j * U * tt) / (ws2 - U * U - 2 * wz * U)
        z = z - 1j * U * Bm * np.exp(-1j * U * tt) / (ws2 - U * U + 2 * wz * U)
        return z

    wn = np.sqrt(ws2 + wz * wz)
    s1, s2 = 1j * (wn - wz), -1j * (wn + wz)
    z0, v0 = -zp(np.zeros(1))[0], -zpd(np.zeros(1))[0]
    C2 = (v0 - s1 * z0) / (s2 - s1)
    C1 = z0 - C2
    z = zp(t) + C1 * np.exp(s1 * t) + C2 * np.exp(s2 * t)
    zd = zpd(t) + s1 * C1 * np.exp(s1 * t) + s2 * C2 * np.exp(s2 * t)
    d_lat = z.imag / R
    d_lon = z.real / (R * np.cos(lat))
    tilt = psi + np.column_stack([-d_lat, d_lon * np.cos(lat), d_lon * np.sin(lat)])
    return {"tilt_enu": tilt, "d_lat": d_lat, "d_lon": d_lon, "dv_en": np.column_stack([zd.real, zd.imag]),
            "psi": psi}


# --- observability -------------------------------------------------------------------
@dataclass(frozen=True)
class ObservabilityResult:
    """Rank test of ``(F, H)``.

    Attributes
    ----------
    rank : int
    n : int
        Number of states.
    singular_values : (n,) ndarray
        Of the scaled observability matrix, descending.
    gap : float
        Ratio of the smallest singular value counted in the rank to the
        largest one left out (a wide gap makes the rank unambiguous).
    unobservable : (n, n - rank) ndarray
        Basis of the unobservable subspace, in unscaled state units.
    """

    rank: int
    n: int
    singular_values: np.ndarray
    gap: float
    unobservable: np.ndarray


def augmented(F, B=None):
    """12-state model with the five constant instrument errors as states:
    ``[[F, B], [0, 0]]``."""
    B = input_matrix() if B is None else np.asarray(B, float)
    n, m = B.shape
    A = np.zeros((n + m, n + m))
    A[:n, :n] = F
    A[:n, n:] = B
    return A


def measurement_matrix(n=NX):
    """``H = [0_(4x3) | I4 | 0]``: differences of latitude, longitude and the
    two absolute velocities (SOURCES-NOTES §2.3)."""
    H = np.zeros((4, n))
    H[:, 3:7] = np.eye(4)
    return H


def default_scales(n):
    """Typical magnitudes used to scale states before the rank test: tilt
    1e-4 rad, angles 1e-5 rad, velocity 0.1 m/s, drift 1e-7 rad/s, accel
    1e-4 m/s^2 (the orders of source 004's experiment)."""
    s = np.array([1e-4, 1e-4, 1e-4, 1e-5, 1e-5, 0.1, 0.1, 1e-7, 1e-7, 1e-7, 1e-4, 1e-4])
    return s[:n]


def observability(F, H, *, scales=None, time_scale=None, tol=1e-8):
    """Rank test of the observability matrix ``[H; H F; ...; H F^(n-1)]``.

    States are scaled by typical magnitudes and time by ``time_scale``
    (default: the Schuler time ``1/w_s = sqrt(R/g)``), so that the
    singular values measure observability in physical terms instead of
    unit choices; the rank counts singular values above ``tol`` times the
    largest.

    Parameters
    ----------
    F : (n, n) array_like
    H : (m, n) array_like
    scales : (n,) array_like, optional
    time_scale : float, optional
        [s].
    tol : float

    Returns
    -------
    ObservabilityResult
    """
    F = np.asarray(F, float)
    H = np.asarray(H, float)
    n = F.shape[0]
    s = default_scales(n) if scales is None else np.asarray(scales, float)
    ts = np.sqrt(earth.R_SPHERE / 9.8) if time_scale is None else float(time_scale)
    D = np.diag(s)
    Fs = np.linalg.solve(D, F @ D) * ts
    Hs = H @ D
    Hs = Hs / np.abs(Hs).max(axis=1, keepdims=True)
    blocks = [Hs]
    for _ in range(n - 1):
        blocks.append(blocks[-1] @ Fs)
    O = np.vstack(blocks)
    _, sv, Vt = np.linalg.svd(O)
    rank = int((sv > tol * sv[0]).sum())
    gap = float(sv[rank - 1] / sv[rank]) if rank < n and sv[rank] > 0 else np.inf
    null = D @ Vt[rank:].T
    return ObservabilityResult(rank, n, sv, gap, null)


# --- correction gains and stability ----------------------------------------------------
def correction_matrix(k1=0.0, k2=0.0, k3=0.0, k_tilt_velocity=(0.0, 0.0)):
    """Closed-loop corrections of eq. 1-3 with ideal estimates (``x_hat = x``).

    ``k1`` on the three tilts, ``k2`` on both velocity errors, ``k3`` on
    latitude and longitude (the printed "+k x_hat" terms; damping needs
    negative gains, SOURCES-NOTES §2.5 flag 3), and the alternative tilt
    correction from velocity estimates: ``alpha_x' += kx dV_eta``,
    ``alpha_y' += ky dV_xi`` with ``k_tilt_velocity = (kx, ky)`` (the source's
    second ``k3`` and ``k4``).

    Returns
    -------
    (7, 7) ndarray
        Added to ``F``.
    """
    Kc = np.zeros((7, 7))
    Kc[0, 0] = Kc[1, 1] = Kc[2, 2] = k1
    Kc[5, 5] = Kc[6, 6] = k2
    Kc[3, 3] = Kc[4, 4] = k3
    Kc[0, 6] = k_tilt_velocity[0]
    Kc[1, 5] = k_tilt_velocity[1]
    return Kc


def stability_margin(F, Kc):
    """Largest real part of the eigenvalues of ``F + K_c`` [1/s] (< 0: stable)."""
    return float(np.linalg.eigvals(np.asarray(F) + np.asarray(Kc)).real.max())


def stability_region(F, k1_values, k2_values, k3=None):
    """Largest eigenvalue real part over a grid of ``k1`` (rows) and ``k2``
    (columns); ``k3`` fixed (default: equal to ``k2``).

    Returns
    -------
    (len(k1_values), len(k2_values)) ndarray
        [1/s]; negative where the corrected error model is asymptotically
        stable.
    """
    out = np.empty((len(k1_values), len(k2_values)))
    for i, a in enumerate(k1_values):
        for j, b in enumerate(k2_values):
            out[i, j] = stability_margin(F, correction_matrix(a, b, b if k3 is None else k3))
    return out
