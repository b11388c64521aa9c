"""WGS84 Earth model: radii, normal gravity, gravitation, rates, coordinates.

All functions broadcast over numpy arrays (latitude ``(n,)``, positions
``(n, 3)``) and accept scalars.  Angles are radians, lengths metres.

The scalar formulas are written with numpy ufuncs only and marked
``register_jitable``: called from Python they are ordinary numpy functions,
called from the compiled mechanization kernels (:mod:`inskit.strapdown`) they
are compiled in.  One implementation serves both.

Gravity models (:data:`GRAVITY_MODELS`, chosen by name at the edges and by
integer code inside the compiled kernels, :func:`gravity_nd`):

* ``"normal"`` (default): Somigliana normal gravity with the first- and
  second-order height terms and the north component (:func:`gravity_down`,
  :func:`gravity_north`);
* ``"normal-simple"``: Somigliana with the first-order height term only and
  no north component (:func:`gravity_down_simple`), the model of most other
  strapdown codes;
* ``"j2"``: gravitation of a GM + J2 Earth plus centrifugal, in NED with its
  north component (:func:`gravity_nd_j2`).

References
----------
SYSTEM.md §1.2-1.4 (source 000 eq. 1-21..1-42); NIMA TR8350.2 (WGS84);
Groves, *Principles of GNSS, Inertial, and Multisensor Integrated Navigation
Systems*, 2nd ed., 2013, ch. 2.
"""

from __future__ import annotations

import numpy as np
from numba.extending import register_jitable

# --- WGS84 defining and derived constants (SYSTEM.md §1.3) -----------------
A = 6378137.0                      #: semi-major axis [m]
B = 6356752.3142                   #: semi-minor axis [m]
F = 1.0 / 298.257223563            #: flattening
E2 = 6.69437999014e-3              #: first eccentricity squared
EP2 = E2 / (1.0 - E2)              #: second eccentricity squared
GM = 3.986004418e14                #: Earth's gravitational constant [m^3/s^2]
OMEGA_IE = 7.292115e-5             #: Earth rotation rate [rad/s]
J2 = 1.082627e-3                   #: second zonal harmonic (unnormalised)
GAMMA_E = 9.7803253359             #: normal gravity at the equator [m/s^2]
GAMMA_P = 9.8321849378             #: normal gravity at the poles [m/s^2]
K_SOMIGLIANA = B * GAMMA_P / (A * GAMMA_E) - 1.0
M_RATIO = 0.00344978650684         #: omega^2 a^2 b / GM
#: Radius of the spherical Earth that source 000 uses for platform systems (§1.1)
R_SPHERE = 6378000.0
#: Horizontal (north) normal-gravity gradient with height [1/s^2]; see gravity_n
GAMMA_N_PER_M = -8.08e-9


# --- radii and gravity -------------------------------------------------------
@register_jitable
def principal_radii(lat, h=0.0):
    """Meridian and transverse radii of curvature plus height.

    Parameters
    ----------
    lat : float or ndarray
        Geodetic latitude [rad].
    h : float or ndarray
        Ellipsoidal height [m].

    Returns
    -------
    rn_h, re_h : float or ndarray
        ``R_N + h`` (meridian, north-south) and ``R_E + h`` (transverse,
        east-west) [m].

    References
    ----------
    SYSTEM.md §1.3: ``R_N = a(1-e^2)/(1-e^2 sin^2 phi)^1.5``,
    ``R_E = a/(1-e^2 sin^2 phi)^0.5``.
    """
    s2 = np.sin(lat) ** 2
    w = np.sqrt(1.0 - E2 * s2)
    return A * (1.0 - E2) / (w * w * w) + h, A / w + h


def somigliana(lat):
    """Normal gravity magnitude on the ellipsoid [m/s^2] (SYSTEM.md §1.3).

    ``gamma = gamma_e (1 + k sin^2 phi) / sqrt(1 - e^2 sin^2 phi)``.
    """
    s2 = np.sin(lat) ** 2
    return GAMMA_E * (1.0 + K_SOMIGLIANA * s2) / np.sqrt(1.0 - E2 * s2)


@register_jitable
def gravity_down(lat, h):
    """Down component of normal (plumb-bob) gravity at height ``h`` [m/s^2].

    ``gamma_d = gamma [1 - (2/a)(1 + f + m - 2 f sin^2 phi) h + 3 h^2/a^2]``
    (SYSTEM.md §1.3; the quadratic term is NIMA TR8350.2 eq. 4-3 / Groves
    eq. 2.140, which the source drops).
    """
    s2 = np.sin(lat) ** 2
    gamma = GAMMA_E * (1.0 + K_SOMIGLIANA * s2) / np.sqrt(1.0 - E2 * s2)
    return gamma * (1.0 - 2.0 / A * (1.0 + F + M_RATIO - 2.0 * F * s2) * h + 3.0 * h * h / (A * A))


@register_jitable
def gravity_down_dh(lat, h):
    """``d gamma_d / d h`` [1/s^2] of :func:`gravity_down` (exact derivative of
    the same formula; about ``-2 g / a``).  Used by the filter's error model."""
    s2 = np.sin(lat) ** 2
    gamma = GAMMA_E * (1.0 + K_SOMIGLIANA * s2) / np.sqrt(1.0 - E2 * s2)
    return gamma * (-2.0 / A * (1.0 + F + M_RATIO - 2.0 * F * s2) + 6.0 * h / (A * A))


@register_jitable
def gravity_north_dh(lat, h):
    """``d gamma_n / d h`` [1/s^2] of :func:`gravity_north`."""
    return GAMMA_N_PER_M * np.sin(2.0 * lat)


@register_jitable
def radii_and_gravity_gradient(sin_lat, h):
    """``R_N + h``, ``R_E + h`` (:func:`principal_radii`) and ``d gamma_d / d h``
    (:func:`gravity_down_dh`) [1/s^2] from the sine of the latitude, with one
    square root (the error model needs all three at every epoch)."""
    s2 = sin_lat * sin_lat
    w = np.sqrt(1.0 - E2 * s2)
    rn = A * (1.0 - E2) / (w * w * w) + h
    re = A / w + h
    gamma = GAMMA_E * (1.0 + K_SOMIGLIANA * s2) / w
    return rn, re, gamma * (-2.0 / A * (1.0 + F + M_RATIO - 2.0 * F * s2) + 6.0 * h / (A * A))


@register_jitable
def gravity_north(lat, h):
    """North component of normal gravity at height ``h`` [m/s^2].

    ``gamma_n = -8.08e-9 h sin(2 phi)`` with ``h`` in metres.  SYSTEM.md §1.3
    prints the coefficient as 8.08e-6, which is the value for ``h`` in
    kilometres (Titterton & Weston 2004, eq. 3.90, give 8.08e-9 per metre);
    the SI value is used here.
    """
    return GAMMA_N_PER_M * h * np.sin(2.0 * lat)


# --- selectable gravity models -------------------------------------------------
#: integer codes of the gravity models, as the compiled kernels take them
GRAVITY_NORMAL = 0
GRAVITY_NORMAL_SIMPLE = 1
GRAVITY_J2 = 2
#: the models by the names of the configuration files and the command line
GRAVITY_MODELS = {"normal": GRAVITY_NORMAL, "normal-simple": GRAVITY_NORMAL_SIMPLE, "j2": GRAVITY_J2}


def gravity_model_code(model) -> int:
    """The integer code of a gravity model given by name (or already a code).

    ``"normal"`` (default): Somigliana normal gravity with the first- and
    second-order height terms and the north component (:func:`gravity_down`,
    :func:`gravity_north`); ``"normal-simple"``: Somigliana with the
    first-order height term only and no north component
    (:func:`gravity_down_simple`); ``"j2"``: the gravitation of a GM + J2
    Earth plus the centrifugal acceleration (:func:`gravity_nd_j2`).

    Raises
    ------
    InputError
        An unknown name or code, naming the choices.
    """
    from .errors import InputError

    if isinstance(model, (int, np.integer)) and not isinstance(model, bool):
        if int(model) in GRAVITY_MODELS.values():
            return int(model)
    elif isinstance(model, str) and model in GRAVITY_MODELS:
        return GRAVITY_MODELS[model]
    raise InputError(f"gravity model {model!r} is not one of {', '.join(repr(k) for k in GRAVITY_MODELS)}")


def gravity_model_name(model) -> str:
    """The name (``"normal"``, ``"normal-simple"``, ``"j2"``) of a model given by name or code."""
    code = gravity_model_code(model)
    return next(k for k, v in GRAVITY_MODELS.items() if v == code)


@register_jitable
def gravity_down_simple(lat, h):
    """Down component of the simple normal gravity [m/s^2]: Somigliana with
    the first-order (free-air) height term only.

    ``gamma_d = gamma [1 - (2/a)(1 + f + m - 2 f sin^2 phi) h]``: NIMA
    TR8350.2 eq. 4-3 (Groves 2013 eq. 2.140) without its ``3 h^2/a^2`` term,
    and no north component.  This is the model of most strapdown codes: the
    height coefficient is the free-air gradient, ``3.0864e-6 1/s^2`` at
    37 deg (PSINS writes ``g0(phi) - 3.086e-6 h``, the same to 3e-10 1/s^2 at
    mid latitudes; KF-GINS keeps the quadratic term, also without the north
    component).  Against the full model it leaves out ``3 g h^2/a^2``
    (1.9e-6 m/s^2 at 1600 m) vertically and ``8.08e-9 h sin(2 phi)``
    (1.3e-5 m/s^2 at 1600 m, 45 deg) northward.
    """
    s2 = np.sin(lat) ** 2
    gamma = GAMMA_E * (1.0 + K_SOMIGLIANA * s2) / np.sqrt(1.0 - E2 * s2)
    return gamma * (1.0 - 2.0 / A * (1.0 + F + M_RATIO - 2.0 * F * s2) * h)


@register_jitable
def gravity_down_simple_dh(lat, h):
    """``d gamma_d / d h`` [1/s^2] of :func:`gravity_down_simple` (independent of ``h``)."""
    s2 = np.sin(lat) ** 2
    gamma = GAMMA_E * (1.0 + K_SOMIGLIANA * s2) / np.sqrt(1.0 - E2 * s2)
    return gamma * (-2.0 / A * (1.0 + F + M_RATIO - 2.0 * F * s2)) + 0.0 * h


@register_jitable
def gravity_ecef_j2_xyz(x, y, z):
    """Plumb-bob gravity of the GM + J2 field in e from ECEF coordinates,
    ``(gx, gy, gz)`` [m/s^2]: gravitation (Groves 2013 eq. 2.142) plus the
    centrifugal ``omega_ie^2 (x, y, 0)``.  Component form of
    :func:`gravity_ecef_j2`, for scalars or arrays and the compiled kernels."""
    r2 = x * x + y * y + z * z
    r = np.sqrt(r2)
    zr2 = 5.0 * z * z / r2
    c = 1.5 * J2 * A * A / r2
    k = -GM / (r2 * r)
    w2 = OMEGA_IE * OMEGA_IE
    return (k * x * (1.0 + c * (1.0 - zr2)) + w2 * x, k * y * (1.0 + c * (1.0 - zr2)) + w2 * y,
            k * z * (1.0 + c * (3.0 - zr2)))


@register_jitable
def gravity_nd_j2(lat, h):
    """North and down components [m/s^2] of the GM + J2 plumb-bob gravity at
    geodetic latitude ``lat`` and height ``h`` (the east component is zero:
    the field is symmetric about the polar axis).

    The field is evaluated at the ECEF point of ``(lat, 0, h)`` (SYSTEM.md
    §1.3 coordinates), :func:`gravity_ecef_j2_xyz`, and resolved on the north
    ``(-sin phi, 0, cos phi)`` and down ``(-cos phi, 0, -sin phi)`` axes.
    The J2 field is not exactly normal to the ellipsoid (it leaves out J4 and
    higher zonal terms, about 1e-5 of g), so its north component is not zero
    even on the ellipsoid; its growth with height is the plumb-line
    curvature of the normal field, about ``-8.08e-9 h sin(2 phi)``.
    """
    sl, cl = np.sin(lat), np.cos(lat)
    n = A / np.sqrt(1.0 - E2 * sl * sl)
    x = (n + h) * cl
    z = (n * (1.0 - E2) + h) * sl
    gx, _, gz = gravity_ecef_j2_xyz(x, 0.0 * x, z)
    return -sl * gx + cl * gz, -cl * gx - sl * gz


#: height step [m] of the central difference in :func:`gravity_down_dh_model` (j2)
_J2_DH_STEP = 8.0


@register_jitable
def gravity_nd(lat, h, model):
    """North and down plumb-bob gravity [m/s^2] of the model ``model`` (an
    integer code, :data:`GRAVITY_MODELS`) at scalar ``lat`` [rad], ``h`` [m]:
    the selector the compiled mechanizations call.

    ``GRAVITY_NORMAL``: :func:`gravity_north`, :func:`gravity_down` (the very
    operations of the unselected kernels, so results are bit-identical);
    ``GRAVITY_NORMAL_SIMPLE``: ``0``, :func:`gravity_down_simple`;
    ``GRAVITY_J2``: :func:`gravity_nd_j2`.
    """
    if model == GRAVITY_J2:
        return gravity_nd_j2(lat, h)
    if model == GRAVITY_NORMAL_SIMPLE:
        return 0.0, gravity_down_simple(lat, h)
    return gravity_north(lat, h), gravity_down(lat, h)


@register_jitable
def gravity_down_dh_model(lat, h, model):
    """``d gamma_d / d h`` [1/s^2] of the model ``model`` (scalar): exact for
    the two normal models; for J2 a central difference over +-8 m (truncation
    ~(8 m / a)^2 = 2e-12 relative, rounding ~1e-10 relative)."""
    if model == GRAVITY_J2:
        _, gp = gravity_nd_j2(lat, h + _J2_DH_STEP)
        _, gm = gravity_nd_j2(lat, h - _J2_DH_STEP)
        return (gp - gm) / (2.0 * _J2_DH_STEP)
    if model == GRAVITY_NORMAL_SIMPLE:
        return gravity_down_simple_dh(lat, h)
    return gravity_down_dh(lat, h)


@register_jitable
def gravity_ecef_model(x, y, z, model):
    """Plumb-bob gravity ``(gx, gy, gz)`` in e [m/s^2] of the model ``model``
    from scalar ECEF coordinates (the ECEF and inertial mechanizations):
    J2 directly in e; the normal models from their north and down
    components at the point's geodetic latitude and height."""
    if model == GRAVITY_J2:
        return gravity_ecef_j2_xyz(x, y, z)
    if model == GRAVITY_NORMAL_SIMPLE:
        lat, h = geodetic_from_ecef(x, y, z)
        gd = gravity_down_simple(lat, h)
        sl, cl = np.sin(lat), np.cos(lat)
        lon = np.arctan2(y, x)
        co, so = np.cos(lon), np.sin(lon)
        return -cl * co * gd, -cl * so * gd, -sl * gd
    return gravity_ecef_xyz(x, y, z)


def gravity_n(lat, h, model="normal"):
    """Plumb-bob gravity resolved in NED, shape ``(..., 3)`` [m/s^2].

    This is gravitation plus centrifugal acceleration (the ``g_l`` of
    SYSTEM.md §1.2), i.e. what a plumb bob feels at rest on the Earth.

    Parameters
    ----------
    lat, h : float or ndarray
        Geodetic latitude [rad] and ellipsoidal height [m] (broadcast).
    model : {"normal", "normal-simple", "j2"} or int
        ``"normal"`` (default): Somigliana normal gravity with the first- and
        second-order height terms and the north component; ``"normal-simple"``:
        Somigliana with the first-order height term, no north component;
        ``"j2"``: the GM + J2 field plus centrifugal (see
        :func:`gravity_model_code`).
    """
    code = gravity_model_code(model)
    lat = np.asarray(lat, dtype=float)
    h = np.asarray(h, dtype=float)
    if code == GRAVITY_J2:
        gn, gd = gravity_nd_j2(lat, h)
    elif code == GRAVITY_NORMAL_SIMPLE:
        gd = gravity_down_simple(lat, h)
        gn = np.zeros_like(gd)
    else:
        gn, gd = gravity_north(lat, h), gravity_down(lat, h)
    return np.stack(np.broadcast_arrays(gn, np.zeros_like(gn), gd), axis=-1)


def gravity_spherical(h):
    """Gravity of the spherical Earth of §1.1: ``GM / (R + h)^2`` [m/s^2]."""
    return GM / (R_SPHERE + np.asarray(h, dtype=float)) ** 2


def gravitation_ecef_j2(r_e):
    """Gravitational acceleration (no centrifugal) with GM and J2, ECEF.

    Parameters
    ----------
    r_e : (3,) or (n, 3) array_like
        ECEF position [m].

    Returns
    -------
    (3,) or (n, 3) ndarray
        Gravitational acceleration resolved in e [m/s^2].

    References
    ----------
    SYSTEM.md §1.2 (``g_0 = -GM r/|r|^3``) extended with J2 as in Groves
    eq. 2.142.
    """
    r_e = np.asarray(r_e, dtype=float)
    x, y, z = r_e[..., 0], r_e[..., 1], r_e[..., 2]
    r2 = x * x + y * y + z * z
    r = np.sqrt(r2)
    zr2 = 5.0 * z * z / r2
    c = 1.5 * J2 * A * A / r2
    k = -GM / (r2 * r)
    return np.stack(
        [k * x * (1.0 + c * (1.0 - zr2)), k * y * (1.0 + c * (1.0 - zr2)), k * z * (1.0 + c * (3.0 - zr2))],
        axis=-1,
    )


def centrifugal_ecef(r_e):
    """Centrifugal acceleration ``-omega_ie x (omega_ie x r)`` in e [m/s^2]."""
    r_e = np.asarray(r_e, dtype=float)
    w2 = OMEGA_IE * OMEGA_IE
    return np.stack([w2 * r_e[..., 0], w2 * r_e[..., 1], np.zeros_like(r_e[..., 2])], axis=-1)


def gravity_ecef_j2(r_e):
    """Plumb-bob gravity from the GM+J2 field: gravitation plus centrifugal."""
    return gravitation_ecef_j2(r_e) + centrifugal_ecef(r_e)


@register_jitable
def gravity_ecef_xyz(x, y, z):
    """Normal plumb-bob gravity in e from ECEF coordinates; returns (gx, gy, gz).

    The component form of :func:`gravity_ecef`, for scalars or arrays; the
    compiled kernels use it directly.
    """
    lat, h = geodetic_from_ecef(x, y, z)
    gd = gravity_down(lat, h)
    gn = gravity_north(lat, h)
    sl, cl = np.sin(lat), np.cos(lat)
    lon = np.arctan2(y, x)
    co, so = np.cos(lon), np.sin(lon)
    # north column of C_en: (-sl co, -sl so, cl); down column: (-cl co, -cl so, -sl)
    return (-sl * co * gn - cl * co * gd, -sl * so * gn - cl * so * gd, cl * gn - sl * gd)


def gravity_ecef(r_e):
    """Normal plumb-bob gravity (Somigliana with height terms) resolved in e.

    The mechanizations in every frame use this field, so that NED, ECEF,
    wander-azimuth and inertial solutions of the same data agree; the J2 model
    (:func:`gravity_ecef_j2`) differs from it by up to 1.2e-4 m/s^2 (at the
    poles), the size of the zonal terms beyond J2 that it leaves out.

    Parameters
    ----------
    r_e : (3,) or (n, 3) array_like
        ECEF position [m].
    """
    r_e = np.asarray(r_e, dtype=float)
    return np.stack(gravity_ecef_xyz(r_e[..., 0], r_e[..., 1], r_e[..., 2]), axis=-1)


# --- rates ------------------------------------------------------------------
def rate_ie_n(lat):
    """Earth rate resolved in NED: ``[W cos phi, 0, -W sin phi]`` [rad/s]."""
    lat = np.asarray(lat, dtype=float)
    return np.stack([OMEGA_IE * np.cos(lat), np.zeros_like(lat), -OMEGA_IE * np.sin(lat)], axis=-1)


def rate_en_n(lat, h, v_n):
    """Transport rate resolved in NED (SYSTEM.md §1.4) [rad/s].

    ``omega_en_n = [vE/(R_E+h), -vN/(R_N+h), -vE tan(phi)/(R_E+h)]``.
    """
    v_n = np.asarray(v_n, dtype=float)
    rn, re = principal_radii(lat, h)
    ve = v_n[..., 1]
    return np.stack([ve / re, -v_n[..., 0] / rn, -ve * np.tan(lat) / re], axis=-1)


# --- coordinates -------------------------------------------------------------
def lla_to_ecef(lla):
    """Geodetic latitude, longitude [rad], height [m] to ECEF [m].

    Parameters
    ----------
    lla : (3,) or (n, 3) array_like
    """
    lla = np.asarray(lla, dtype=float)
    lat, lon, h = lla[..., 0], lla[..., 1], lla[..., 2]
    _, re = principal_radii(lat, 0.0)
    cl = np.cos(lat)
    return np.stack(
        [(re + h) * cl * np.cos(lon), (re + h) * cl * np.sin(lon), (re * (1.0 - E2) + h) * np.sin(lat)],
        axis=-1,
    )


@register_jitable
def geodetic_from_ecef(x, y, z):
    """Latitude [rad] and height [m] from ECEF coordinates (scalars or arrays).

    Bowring's iteration on the reduced latitude, three passes (sub-micrometre
    from near the Earth's centre out to orbit heights), with the height formula
    that stays well conditioned at the poles.  Written with ufuncs only, so the
    compiled kernels use this same function.
    """
    p = np.hypot(x, y)
    beta = np.arctan2(z, (1.0 - F) * p)
    lat = beta
    for _ in range(3):
        sb, cb = np.sin(beta), np.cos(beta)
        lat = np.arctan2(z + EP2 * B * sb**3, p - E2 * A * cb**3)
        beta = np.arctan2((1.0 - F) * np.sin(lat), np.cos(lat))
    sl, cl = np.sin(lat), np.cos(lat)
    n = A / np.sqrt(1.0 - E2 * sl * sl)
    return lat, p * cl + (z + E2 * n * sl) * sl - n


def ecef_to_lla(r_e):
    """ECEF [m] to geodetic latitude, longitude [rad] and height [m].

    Parameters
    ----------
    r_e : (3,) or (n, 3) array_like

    Returns
    -------
    (3,) or (n, 3) ndarray
        ``[lat, lon, h]``.
    """
    r_e = np.asarray(r_e, dtype=float)
    x, y, z = r_e[..., 0], r_e[..., 1], r_e[..., 2]
    lat, h = geodetic_from_ecef(x, y, z)
    return np.stack([lat, np.arctan2(y, x), h], axis=-1)


def dcm_en(lat, lon):
    """``C_en``: maps NED vectors at (lat, lon) into ECEF; shape ``(..., 3, 3)``.

    Its columns are the north, east and down unit vectors resolved in e.
    """
    lat = np.asarray(lat, dtype=float)
    lon = np.asarray(lon, dtype=float)
    sl, cl, so, co = np.sin(lat), np.cos(lat), np.sin(lon), np.cos(lon)
    zero = np.zeros_like(sl * so)
    rows = [
        [-sl * co, -so + zero, -cl * co],
        [-sl * so, co + zero, -cl * so],
        [cl + zero, zero, -sl + zero],
    ]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def ecef_to_ned(r_e, lla_ref):
    """ECEF positions to NED offsets [m] from a reference (lat, lon, h)."""
    lla_ref = np.asarray(lla_ref, dtype=float)
    d = np.asarray(r_e, dtype=float) - lla_to_ecef(lla_ref)
    return np.einsum("...ji,...j->...i", dcm_en(lla_ref[..., 0], lla_ref[..., 1]), d)


def ned_to_ecef(p_n, lla_ref):
    """NED offsets [m] from a reference (lat, lon, h) to ECEF positions [m]."""
    lla_ref = np.asarray(lla_ref, dtype=float)
    c = dcm_en(lla_ref[..., 0], lla_ref[..., 1])
    return lla_to_ecef(lla_ref) + np.einsum("...ij,...j->...i", c, np.asarray(p_n, dtype=float))


def lla_to_ned(lla, lla_ref):
    """Geodetic positions to NED offsets [m] from a reference position."""
    return ecef_to_ned(lla_to_ecef(lla), lla_ref)


def ned_to_lla(p_n, lla_ref):
    """NED offsets [m] from a reference position to geodetic positions."""
    return ecef_to_lla(ned_to_ecef(p_n, lla_ref))


def ned_to_enu(x):
    """Swap NED to ENU (or back): ``[N, E, D] -> [E, N, -D]`` on the last axis."""
    x = np.asarray(x, dtype=float)
    return np.stack([x[..., 1], x[..., 0], -x[..., 2]], axis=-1)


enu_to_ned = ned_to_enu


def ecef_to_enu(r_e, lla_ref):
    """ECEF positions to ENU offsets [m] (a thin adapter over NED)."""
    return ned_to_enu(ecef_to_ned(r_e, lla_ref))
