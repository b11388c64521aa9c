"""Line-of-sight geometry and the broadcast-grade atmosphere models.

* :func:`klobuchar_delay`: GPS broadcast ionosphere model, the user
  algorithm of IS-GPS-200N 20.3.3.5.2.5 and Figure 20-4, on arrays.
* :func:`saastamoinen_delay`: zenith hydrostatic and wet delays of
  Saastamoinen (1972) with the standard atmosphere for pressure and
  temperature from height (p0 = 1013.25 hPa, T0 = 15 C at sea level,
  lapse 6.5 K/km: ``p = 1013.25 (1 - 2.2557e-5 h)^5.2568``) and the
  relative humidity given; the slant delay
  uses the mapping function of Black & Eisner (1984),
  ``m(el) = 1.001 / sqrt(0.002001 + sin(el)^2)``, the same function RTCA
  DO-229 (WAAS MOPS, A.4.2.4) prescribes: ~1/sin(el) at high elevation and
  finite down to the horizon (5.58 at 10 deg, 22.4 at 0 deg).
* :func:`iono_free`: the first-order ionosphere-free code combination.

References
----------
IS-GPS-200N (2022) 20.3.3.5.2.5, Figure 20-4.
Saastamoinen, J. (1972), Atmospheric correction for the troposphere and
stratosphere in radio ranging of satellites, Geophys. Monogr. 15, AGU.
Davis, J. L. et al. (1985), Radio Science 20(6) (gravity factor
1 - 0.00266 cos 2 phi - 0.00028 H[km]).
Black, H. D. & Eisner, A. (1984), Correcting satellite Doppler data for
tropospheric effects, J. Geophys. Res. 89(D2).
RTCA DO-229D (2006), Appendix A.4.2.4 (mapping function).
"""

from __future__ import annotations

import numpy as np

from .. import earth
from ..errors import InputError
from .constants import C

__all__ = ["KLOBUCHAR_DEFAULT_ALPHA", "KLOBUCHAR_DEFAULT_BETA", "elevation_azimuth", "klobuchar_delay",
           "saastamoinen_delay", "tropo_mapping", "iono_free"]

#: Default Klobuchar coefficients, used when a navigation header has none.
#: They are the set RTKLIB falls back to (its built-in ``ion_default``),
#: taken from a GPS broadcast of 2004/1/1.  Units: s, s/semicircle, s/sc^2, s/sc^3.
KLOBUCHAR_DEFAULT_ALPHA = np.array([0.1118e-07, -0.7451e-08, -0.5961e-07, 0.1192e-06])
#: Units: s, s/semicircle, s/sc^2, s/sc^3.
KLOBUCHAR_DEFAULT_BETA = np.array([0.1167e06, -0.2294e06, -0.1311e06, 0.1049e07])


def elevation_azimuth(rx_e, sat_e):
    """Elevation and azimuth of satellites seen from receiver positions.

    Parameters
    ----------
    rx_e : (3,) or (m, 3) array_like
        Receiver ECEF position [m].
    sat_e : (3,) or (m, 3) array_like
        Satellite ECEF position [m] (same frame, e.g. Sagnac-rotated).

    Returns
    -------
    el, az : (m,) ndarray (or floats for (3,) inputs)
        Elevation above the geodetic horizon and azimuth from north towards
        east in [0, 2 pi) [rad].
    """
    rx = np.asarray(rx_e, dtype=float)
    sat = np.asarray(sat_e, dtype=float)
    if rx.shape[-1:] != (3,) or sat.shape[-1:] != (3,):
        raise InputError(f"rx_e and sat_e must have shape (3,) or (m, 3), got {rx.shape} and {sat.shape}")
    lla = earth.ecef_to_lla(rx)
    d = sat - rx
    ned = np.einsum("...ji,...j->...i", earth.dcm_en(lla[..., 0], lla[..., 1]), d)
    horiz = np.hypot(ned[..., 0], ned[..., 1])
    el = np.arctan2(-ned[..., 2], horiz)
    az = np.mod(np.arctan2(ned[..., 1], ned[..., 0]), 2.0 * np.pi)
    return el, az


def klobuchar_delay(t_gps_s, lla_rx, az, el, alpha=None, beta=None):
    """GPS L1 ionospheric delay of the broadcast (Klobuchar) model [m].

    Parameters
    ----------
    t_gps_s : float or (m,) array_like
        GPS time [s since the GPS epoch] (only the time of day is used).
    lla_rx : (3,) or (m, 3) array_like
        Receiver latitude, longitude [rad], height [m].
    az, el : float or (m,) array_like
        Azimuth and elevation [rad].
    alpha, beta : (4,) array_like or None
        Broadcast coefficients (s, s/semicircle^k); None uses the defaults.

    Returns
    -------
    (m,) ndarray or float
        L1 group delay [m] (positive; scale by (f1/f)^2 for another
        frequency).  The model's night-time floor is 5 ns * c * F.

    References
    ----------
    IS-GPS-200N 20.3.3.5.2.5 and Figure 20-4 (angles in semicircles).
    """
    alpha = KLOBUCHAR_DEFAULT_ALPHA if alpha is None else np.asarray(alpha, dtype=float)
    beta = KLOBUCHAR_DEFAULT_BETA if beta is None else np.asarray(beta, dtype=float)
    if alpha.shape != (4,) or beta.shape != (4,):
        raise InputError(f"alpha and beta must have shape (4,), got {alpha.shape} and {beta.shape}")
    lla = np.asarray(lla_rx, dtype=float)
    phi_u = lla[..., 0] / np.pi                      # semicircles
    lam_u = lla[..., 1] / np.pi
    a = np.asarray(az, dtype=float)
    e = np.asarray(el, dtype=float) / np.pi
    psi = 0.0137 / (e + 0.11) - 0.022                # Earth-centred angle [sc]
    phi_i = np.clip(phi_u + psi * np.cos(a), -0.416, 0.416)
    lam_i = lam_u + psi * np.sin(a) / np.cos(phi_i * np.pi)
    phi_m = phi_i + 0.064 * np.cos((lam_i - 1.617) * np.pi)
    t = np.mod(4.32e4 * lam_i + np.asarray(t_gps_s, dtype=float), 86400.0)
    f = 1.0 + 16.0 * (0.53 - e) ** 3                 # obliquity factor
    amp = alpha[0] + phi_m * (alpha[1] + phi_m * (alpha[2] + phi_m * alpha[3]))
    per = beta[0] + phi_m * (beta[1] + phi_m * (beta[2] + phi_m * beta[3]))
    amp = np.maximum(amp, 0.0)
    per = np.maximum(per, 72000.0)
    x = 2.0 * np.pi * (t - 50400.0) / per
    day = f * (5e-9 + amp * (1.0 - x**2 / 2.0 + x**4 / 24.0))
    t_iono = np.where(np.abs(x) < 1.57, day, f * 5e-9)
    out = C * t_iono
    return float(out) if np.ndim(out) == 0 else out


def standard_atmosphere(h):
    """Pressure [hPa] and temperature [K] of the standard atmosphere at height h [m]
    (troposphere lapse 6.5 K/km; clamped to 0 <= h <= 11 km)."""
    h = np.clip(np.asarray(h, dtype=float), 0.0, 11000.0)
    p = 1013.25 * (1.0 - 2.2557e-5 * h) ** 5.2568
    temp = 288.15 - 6.5e-3 * h
    return p, temp


def tropo_mapping(el):
    """Black & Eisner (1984) / DO-229 tropospheric mapping function of elevation [rad]."""
    s = np.sin(np.asarray(el, dtype=float))
    return 1.001 / np.sqrt(0.002001 + s * s)


def saastamoinen_delay(lla_rx, el, *, humidity=0.7, zenith=False):
    """Tropospheric slant delay [m] (Saastamoinen zenith delays, standard atmosphere).

    Parameters
    ----------
    lla_rx : (3,) or (m, 3) array_like
        Receiver latitude, longitude [rad] and ellipsoidal height [m]
        (used as the height above sea level of the standard atmosphere).
    el : float or (m,) array_like
        Elevation [rad]; NaN returned below the horizon.
    humidity : float
        Relative humidity, 0..1.
    zenith : bool
        Return the zenith delay (el ignored).

    Returns
    -------
    (m,) ndarray or float
        Delay [m].

    Notes
    -----
    Hydrostatic zenith delay ``0.0022768 p / (1 - 0.00266 cos 2 phi - 0.00028 H)``
    (Saastamoinen 1972 with the Davis et al. 1985 gravity factor, H in km),
    wet zenith delay ``0.002277 (1255 / T + 0.05) e`` (Saastamoinen 1972),
    water vapour pressure ``e = humidity * 6.108 exp((17.15 T - 4684) / (T - 38.45))``
    hPa, a Magnus-type saturation formula with T in K (the form RTKLIB uses
    with this model; algorithm, not code).  Both are mapped by
    :func:`tropo_mapping`.  Sea level, 15 C, 70 %: 2.307 m + 0.120 m.
    """
    if not 0.0 <= humidity <= 1.0:
        from ..errors import ConfigError

        raise ConfigError(f"humidity must be in [0, 1], got {humidity}")
    lla = np.asarray(lla_rx, dtype=float)
    lat, h = lla[..., 0], lla[..., 2]
    p, temp = standard_atmosphere(h)
    e_w = humidity * 6.108 * np.exp((17.15 * temp - 4684.0) / (temp - 38.45))
    hkm = np.clip(h, 0.0, 11000.0) / 1000.0
    zhd = 0.0022768 * p / (1.0 - 0.00266 * np.cos(2.0 * lat) - 0.00028 * hkm)
    zwd = 0.002277 * (1255.0 / temp + 0.05) * e_w
    z = zhd + zwd
    if zenith:
        return float(z) if np.ndim(z) == 0 else z
    el = np.asarray(el, dtype=float)
    out = np.where(el >= 0.0, z * tropo_mapping(el), np.nan)
    return float(out) if np.ndim(out) == 0 else out


def iono_free(p1, p2, f1, f2):
    """First-order ionosphere-free combination ``(f1^2 p1 - f2^2 p2) / (f1^2 - f2^2)``.

    Parameters
    ----------
    p1, p2 : array_like
        Code (or phase in metres) observations on the two frequencies [m].
    f1, f2 : float or array_like
        Carrier frequencies [Hz].

    References
    ----------
    IS-GPS-200N 20.3.3.3.3.3 (dual-frequency correction).
    """
    f1s = np.asarray(f1, dtype=float) ** 2
    f2s = np.asarray(f2, dtype=float) ** 2
    return (f1s * np.asarray(p1, dtype=float) - f2s * np.asarray(p2, dtype=float)) / (f1s - f2s)
