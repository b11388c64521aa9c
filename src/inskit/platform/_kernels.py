"""Compiled right-hand sides and RK4 steps of the platform mechanizations.

State vector (10 numbers for every kind):

* semi-analytical and geometric: ``[q_ip (4), lat, lon, h, V_E, V_N, V_U]``
  where ``q_ip`` is the real (gyro-stabilised) platform's attitude in the
  inertial frame and the rest is what the navigation computer indicates;
* analytical: ``[q_ip (4), r_i (3), v_i (3)]`` (inertial position and
  velocity as integrated by the computer).

Truth comes in as arrays sampled at half steps (index ``2k`` is epoch ``k``,
``2k+1`` the midpoint used by the RK4 stages): latitude, longitude and the
true specific force resolved in ENU.  The real platform's accelerometers
measure that force resolved in the platform axes; the computer does not know
the platform's error and treats its axes as the frame they are meant to
realise.  Equations: SOURCES-NOTES §3.2 (semi-analytical, with the restored
Coriolis and gravity terms), §3.3 (analytical), §3.4 (geometric).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import earth
from ..earth import gravity_down as _gd
from ..earth import gravity_north as _gn
from ..earth import principal_radii as _radii_wgs
from ..rotations import qmul as _qmul
from ..rotations import quat_dcm as _quat_dcm
from ..rotations import rotvec_quat as _rotvec_quat

W = earth.OMEGA_IE
GM = earth.GM
R_SPHERE = earth.R_SPHERE
WGS84 = 0
SPHERE = 1
SEMI = 0
ANALYTIC = 1
GEOMETRIC = 2
#: layout of the correction vector fed to the right-hand side
#: torque rate about E, N, U [rad/s]; latitude, longitude rate [rad/s];
#: V_E, V_N rate [m/s^2]; accelerometer compensation E, N, U [m/s^2]
NCORR = 10


@njit(cache=True)
def radii(lat, h, model):
    """``(R_N + h, R_E + h)`` of the model (the sphere has one radius)."""
    if model == SPHERE:
        r = R_SPHERE + h
        return r, r
    return _radii_wgs(lat, h)


@njit(cache=True)
def gravity(lat, h, model):
    """Plumb-bob gravity ``(g_north, g_down)`` [m/s^2] of the model.

    The sphere's gravity is radial, ``GM / (R + h)^2`` (no horizontal part:
    the sphere is taken as an equipotential surface)."""
    if model == SPHERE:
        r = R_SPHERE + h
        return 0.0, GM / (r * r)
    return _gn(lat, h), _gd(lat, h)


@njit(cache=True)
def qmul(a, b):
    """Hamilton product of two (4,) arrays (the package's scalar core)."""
    out = np.empty(4)
    out[0], out[1], out[2], out[3] = _qmul(a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3])
    return out


@njit(cache=True)
def qdcm(q):
    """DCM of a (4,) unit quaternion (the package's scalar core)."""
    c = _quat_dcm(q[0], q[1], q[2], q[3])
    C = np.empty((3, 3))
    C[0, 0], C[0, 1], C[0, 2] = c[0], c[1], c[2]
    C[1, 0], C[1, 1], C[1, 2] = c[3], c[4], c[5]
    C[2, 0], C[2, 1], C[2, 2] = c[6], c[7], c[8]
    return C


@njit(cache=True)
def qrotvec(x, y, z):
    """Quaternion of a rotation vector (exact; the package's scalar core)."""
    q = np.empty(4)
    q[0], q[1], q[2], q[3] = _rotvec_quat(x, y, z)
    return q


@njit(cache=True)
def c_e_enu(lat, lon):
    """``C_e,enu``: columns are east, north, up resolved in ECEF."""
    sl, cl, so, co = math.sin(lat), math.cos(lat), math.sin(lon), math.cos(lon)
    C = np.empty((3, 3))
    C[0, 0], C[0, 1], C[0, 2] = -so, -sl * co, cl * co
    C[1, 0], C[1, 1], C[1, 2] = co, -sl * so, cl * so
    C[2, 0], C[2, 1], C[2, 2] = 0.0, cl, sl
    return C


@njit(cache=True)
def c_i_e(tau):
    """``C_ie`` after ``tau`` seconds (i coincides with e at tau = 0)."""
    s, c = math.sin(W * tau), math.cos(W * tau)
    C = np.zeros((3, 3))
    C[0, 0], C[0, 1], C[1, 0], C[1, 1], C[2, 2] = c, -s, s, c, 1.0
    return C


@njit(cache=True)
def lla_from_ecef(x, y, z, model):
    if model == SPHERE:
        p = math.hypot(x, y)
        return math.atan2(z, p), math.atan2(y, x), math.sqrt(p * p + z * z) - R_SPHERE
    lat, h = earth.geodetic_from_ecef(x, y, z)
    return lat, math.atan2(y, x), h


@njit(cache=True)
def ecef_from_lla(lat, lon, h, model):
    r = np.empty(3)
    cl, sl = math.cos(lat), math.sin(lat)
    if model == SPHERE:
        rr = R_SPHERE + h
        r[0], r[1], r[2] = rr * cl * math.cos(lon), rr * cl * math.sin(lon), rr * sl
        return r
    re = earth.A / math.sqrt(1.0 - earth.E2 * sl * sl)
    r[0] = (re + h) * cl * math.cos(lon)
    r[1] = (re + h) * cl * math.sin(lon)
    r[2] = (re * (1.0 - earth.E2) + h) * sl
    return r


@njit(cache=True)
def project_inertial(y, tau, href, vuref, model):
    """Analytical platform with the vertical channel slaved to the
    altimeter: replace height and vertical velocity in ``(r_i, v_i)``."""
    Cie = c_i_e(tau)
    r_i = y[4:7].copy()
    v_i = y[7:10].copy()
    r_e = Cie.T @ r_i
    lat, lon, _ = lla_from_ecef(r_e[0], r_e[1], r_e[2], model)
    wr = np.array([-W * r_i[1], W * r_i[0], 0.0])
    v_e = Cie.T @ (v_i - wr)
    Cen = c_e_enu(lat, lon)
    v_enu = Cen.T @ v_e
    v_enu[2] = vuref
    r_e2 = ecef_from_lla(lat, lon, href, model)
    r_i2 = Cie @ r_e2
    v_i2 = Cie @ (Cen @ v_enu) + np.array([-W * r_i2[1], W * r_i2[0], 0.0])
    out = y.copy()
    out[4:7] = r_i2
    out[7:10] = v_i2
    return out


@njit(cache=True)
def accel_output(kind, tau, y, lat_t, lon_t, f_t, ba, sa, na, corr):
    """What the accelerometers on the real platform output (after the
    compensation ``corr[7:10]``): the true specific force resolved in the
    platform axes, with scale-factor error, bias and noise."""
    C_ip = qdcm(y[0:4])
    Cie = c_i_e(tau)
    f_i_t = Cie @ (c_e_enu(lat_t, lon_t) @ f_t)
    if kind == GEOMETRIC:
        # platform 2 servo-driven from platform 1 to the computed geographic frame
        C_ip2 = C_ip @ (Cie @ c_e_enu(y[4], y[5]))
        f_p = C_ip2.T @ f_i_t
    else:
        f_p = C_ip.T @ f_i_t
    fm = np.empty(3)
    for j in range(3):
        fm[j] = f_p[j] * (1.0 + sa[j]) + ba[j] + na[j] + corr[7 + j]
    return fm


@njit(cache=True)
def rhs(kind, model, hold, tau, y, lat_t, lon_t, f_t, href, vuref, eps, ba, sa, st, ng, na, corr):
    """Time derivative of the 10-element state (see module docstring).

    ``f_t`` is the true specific force in ENU; ``eps``/``ng`` gyro drift and
    noise, ``ba``/``na`` accelerometer bias and noise, ``sa``/``st``
    accelerometer and torquer scale-factor errors (all in platform axes);
    ``corr`` the closed-loop corrections (layout: :data:`NCORR`)."""
    dy = np.zeros(10)
    q = y[0:4]
    Cie = c_i_e(tau)
    fm = accel_output(kind, tau, y, lat_t, lon_t, f_t, ba, sa, na, corr)

    if kind == ANALYTIC:
        w = np.empty(4)
        w[0] = 0.0
        for j in range(3):
            w[1 + j] = eps[j] + ng[j] + corr[j]
        dq = qmul(q, w)
        for j in range(4):
            dy[j] = 0.5 * dq[j]
        r_i = y[4:7]
        r_e = Cie.T @ r_i
        lat, lon, h = lla_from_ecef(r_e[0], r_e[1], r_e[2], model)
        gN, gD = gravity(lat, h, model)
        g_e = c_e_enu(lat, lon) @ np.array([0.0, gN, -gD])
        # gravitation = plumb-bob gravity minus the centrifugal term W^2 (x, y, 0)
        G_e = np.array([g_e[0] - W * W * r_e[0], g_e[1] - W * W * r_e[1], g_e[2]])
        G_i = Cie @ G_e
        for j in range(3):
            dy[4 + j] = y[7 + j]
            dy[7 + j] = fm[j] + G_i[j]  # the computer takes platform axes as inertial axes
        return dy

    lat, lon = y[4], y[5]
    h = href if hold else y[6]
    vE, vN = y[7], y[8]
    vU = vuref if hold else y[9]
    RN, RE = radii(lat, h, model)
    gN, gD = gravity(lat, h, model)
    sl, cl = math.sin(lat), math.cos(lat)
    tl = sl / cl
    w = np.empty(4)
    w[0] = 0.0
    if kind == SEMI:
        # torquer commands of SOURCES-NOTES §3.2 from the indicated state
        wc0 = -vN / RN
        wc1 = vE / RE + W * cl
        wc2 = vE * tl / RE + W * sl
        w[1] = wc0 * (1.0 + st[0]) + eps[0] + ng[0] + corr[0]
        w[2] = wc1 * (1.0 + st[1]) + eps[1] + ng[1] + corr[1]
        w[3] = wc2 * (1.0 + st[2]) + eps[2] + ng[2] + corr[2]
    else:  # geometric: platform 1 is never torqued
        for j in range(3):
            w[1 + j] = eps[j] + ng[j] + corr[j]
    dq = qmul(q, w)
    for j in range(4):
        dy[j] = 0.5 * dq[j]
    dy[4] = vN / RN + corr[3]
    dy[5] = vE / (RE * cl) + corr[4]
    a = 2.0 * W * sl + vE * tl / RE
    b = 2.0 * W * cl + vE / RE
    dy[7] = fm[0] + a * vN - b * vU + corr[5]
    dy[8] = fm[1] - a * vE - vN * vU / RN + gN + corr[6]
    if not hold:
        dy[6] = vU
        dy[9] = fm[2] - gD + b * vE + vN * vN / RN
    return dy


@njit(cache=True)
def rk4_step(kind, model, hold, t0, tk, dt, y, j, lat_t, lon_t, f_t, href, vuref, eps, ba, sa, st, ng, na, corr):
    """One RK4 step from epoch ``k`` (truth index ``j = 2k``) to ``k + 1``.

    Sensor noise and corrections are held over the step."""
    tau = tk - t0
    ya = y
    if kind == ANALYTIC and hold:
        ya = project_inertial(y, tau, href[j], vuref[j], model)
    k1 = rhs(kind, model, hold, tau, ya, lat_t[j], lon_t[j], f_t[j], href[j], vuref[j],
             eps, ba, sa, st, ng, na, corr)
    y2 = ya + 0.5 * dt * k1
    if kind == ANALYTIC and hold:
        y2 = project_inertial(y2, tau + 0.5 * dt, href[j + 1], vuref[j + 1], model)
    k2 = rhs(kind, model, hold, tau + 0.5 * dt, y2, lat_t[j + 1], lon_t[j + 1], f_t[j + 1], href[j + 1],
             vuref[j + 1], eps, ba, sa, st, ng, na, corr)
    y3 = ya + 0.5 * dt * k2
    if kind == ANALYTIC and hold:
        y3 = project_inertial(y3, tau + 0.5 * dt, href[j + 1], vuref[j + 1], model)
    k3 = rhs(kind, model, hold, tau + 0.5 * dt, y3, lat_t[j + 1], lon_t[j + 1], f_t[j + 1], href[j + 1],
             vuref[j + 1], eps, ba, sa, st, ng, na, corr)
    y4 = ya + dt * k3
    if kind == ANALYTIC and hold:
        y4 = project_inertial(y4, tau + dt, href[j + 2], vuref[j + 2], model)
    k4 = rhs(kind, model, hold, tau + dt, y4, lat_t[j + 2], lon_t[j + 2], f_t[j + 2], href[j + 2],
             vuref[j + 2], eps, ba, sa, st, ng, na, corr)
    yn = ya + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    nq = math.sqrt(yn[0] ** 2 + yn[1] ** 2 + yn[2] ** 2 + yn[3] ** 2)
    for i in range(4):
        yn[i] /= nq
    if hold:
        if kind == ANALYTIC:
            yn = project_inertial(yn, tau + dt, href[j + 2], vuref[j + 2], model)
        else:
            yn[6] = href[j + 2]
            yn[9] = vuref[j + 2]
    return yn


@njit(cache=True)
def run_free(kind, model, hold, t, lat_t, lon_t, f_t, href, vuref, y0, eps, ba, sa, st, ng, na, out):
    """Free (unaided) run over all epochs; ``out[k]`` is the state at ``t[k]``."""
    n = t.shape[0]
    corr = np.zeros(NCORR)
    y = y0.copy()
    out[0] = y
    for k in range(n - 1):
        y = rk4_step(kind, model, hold, t[0], t[k], t[k + 1] - t[k], y, 2 * k, lat_t, lon_t, f_t, href, vuref,
                     eps, ba, sa, st, ng[k], na[k], corr)
        out[k + 1] = y


@njit(cache=True)
def sphere_positions(lat0, lon0, h, vn, ve, dt_half, lat, lon):
    """RK4 of latitude and longitude on the sphere over a grid of step
    ``dt_half`` whose velocity samples are given at quarter steps (index
    ``2 i`` on the grid point ``i``)."""
    m = lat.shape[0]
    lat[0], lon[0] = lat0, lon0
    for i in range(m - 1):
        a = 2 * i
        y0, y1 = lat[i], lon[i]
        k = np.empty((4, 2))
        idx = (a, a + 1, a + 1, a + 2)
        for s in range(4):
            c = 0.0 if s == 0 else (0.5 if s < 3 else 1.0)
            la = y0 + c * dt_half * (k[s - 1, 0] if s > 0 else 0.0)
            r = R_SPHERE + h[idx[s]]
            k[s, 0] = vn[idx[s]] / r
            k[s, 1] = ve[idx[s]] / (r * math.cos(la))
        lat[i + 1] = y0 + dt_half / 6.0 * (k[0, 0] + 2 * k[1, 0] + 2 * k[2, 0] + k[3, 0])
        lon[i + 1] = y1 + dt_half / 6.0 * (k[0, 1] + 2 * k[1, 1] + 2 * k[2, 1] + k[3, 1])
