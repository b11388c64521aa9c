"""Gimballed-platform INS mechanizations: semi-analytical, analytical, geometric.

All three simulate the real (imperfect) platform and the navigation computer
together, in continuous time (fixed-step RK4, truth sampled at half steps):

* **semi-analytical** (local level, north pointing; SOURCES-NOTES §3.2): the
  torquers turn the platform at the commanded rate computed from the
  indicated velocity and latitude,
  ``w_X = -V_N/(R_N+h)``, ``w_Y = V_E/(R_E+h) + U cos(phi)``,
  ``w_Z = V_E tan(phi)/(R_E+h) + U sin(phi)`` (source 000 §1.1; the platform
  really turns at ``(1 + torquer scale) w + gyro drift``); the accelerometers
  on it measure east, north, up; the computer integrates
  ``a_E = f_E + (2U sin(phi) + V_E tan(phi)/R_E) V_N - (2U cos(phi) + V_E/R_E) V_U``,
  ``a_N = f_N - (2U sin(phi) + V_E tan(phi)/R_E) V_E - V_N V_U/R_N``,
  ``a_H = f_U - g + (2U cos(phi) + V_E/R_E) V_E + V_N^2/R_N`` (the Coriolis
  and gravity terms the source omits; SOURCES-NOTES §3.2 [fix]) and
  ``phi' = V_N/(R_N+h)`` (the source's minus sign is a slip),
  ``lambda' = V_E/((R_E+h) cos(phi))``.  Euler angles are read from the
  gimbal pick-offs, i.e. they are the ZYX angles of ``C_pb``, so the attitude
  error equals the platform tilt.
* **analytical** (space-stabilised; §3.3): the platform holds inertial axes
  (it turns only by gyro drift); the computer integrates
  ``r_i'' = f_i + G(r_i)`` (source 000 eq. 1-2) with gravitation
  ``G = g - w_ie x (w_ie x r)`` consistent with the plumb-bob gravity, then
  converts ``r_e = C_ei r_i``, ``v_e = C_ei (v_i - w_ie x r_i)`` to latitude,
  longitude, height and NED velocity.  Attitude
  ``C_nb = C_ne C_ei C_ip C_pb`` with ``C_ip = I`` as far as the computer
  knows.
* **geometric** (§3.4): platform 1 (gyros) holds inertial axes; platform 2
  (accelerometers) is servo-driven relative to platform 1 to the computed
  geographic frame ``C_p1p2 = C_ie(t) C_e,enu(phi, lambda)``; navigation as in
  the semi-analytical case.  The angles between the platforms are the
  computed latitude and hour angle ``lambda + U t``; body attitude
  ``C_nb = C_n,i C_p1b`` (§3.4).

The vertical channel of a platform INS is unstable (time constant
``sqrt(R/2g)``, about 9.5 min); by default (``vertical="altimeter"``) it is
slaved to an external height and vertical rate (true values plus
``PlatformErrors.altimeter_bias``), as platform systems on ships and aircraft
are.  ``vertical="free"`` integrates it.

Outputs: a :class:`~inskit.types.NavSolution` (NED terms, so
:func:`inskit.analysis.nav_error` and the plots apply unchanged) whose
``extra`` columns carry the platform tilt against the true geographic frame
(``tilt_e_rad, tilt_n_rad, tilt_u_rad``), the gimbal pick-off angles
(``gimbal_roll_rad, gimbal_pitch_rad, gimbal_yaw_rad``) and, for the
analytical and geometric kinds, the platform's drift angle from inertial axes
(``drift_x_rad, ..``) and, for the geometric kind, the angles between the two
platforms (``p2_lat_rad, p2_hour_angle_rad``).

References
----------
SYSTEM.md §1.1-1.2; SOURCES-NOTES §3.2-3.4 (source 000 fig. 5, eq. 1-2..1-12).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import earth
from .. import rotations as rot
from ..errors import ConfigError
from ..types import NavSolution
from . import _kernels as K
from .sensors import InitialErrors, PlatformErrors
from .world import PlatformTruth, model_code, radii

KINDS = {"semi-analytical": K.SEMI, "analytical": K.ANALYTIC, "geometric": K.GEOMETRIC}
VERTICAL = ("altimeter", "free")
#: NED <-> ENU axis swap (its own inverse)
T_NED_ENU = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])

__all__ = ["KINDS", "T_NED_ENU", "PlatformRun", "mechanize_platform", "source_errors"]


@dataclass(frozen=True)
class PlatformRun:
    """Result of a platform simulation.

    Attributes
    ----------
    kind : str
    earth : str
    solution : NavSolution
        Indicated navigation solution at the epochs, with the extra columns
        listed in the module docstring.
    truth : PlatformTruth
    state : (n, 10) ndarray
        Raw state of the compiled integrator (layout: :mod:`._kernels`).
    """

    kind: str
    earth: str
    solution: NavSolution
    truth: PlatformTruth
    state: np.ndarray

    @property
    def tilt_enu(self):
        """``(n, 3)`` platform (reference-frame) tilt, east, north, up [rad]."""
        x = self.solution.extra
        return np.column_stack([x["tilt_e_rad"], x["tilt_n_rad"], x["tilt_u_rad"]])

    @property
    def gimbal_rpy(self):
        x = self.solution.extra
        return np.column_stack([x["gimbal_roll_rad"], x["gimbal_pitch_rad"], x["gimbal_yaw_rad"]])


def _c_e_enu(lat, lon):
    return earth.dcm_en(lat, lon) @ T_NED_ENU


def _c_i_e(tau):
    s, c = np.sin(earth.OMEGA_IE * tau), np.cos(earth.OMEGA_IE * tau)
    z, o = np.zeros_like(s), np.ones_like(s)
    return np.stack([np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2)


def _lla_from_ecef(r, model):
    if model == "sphere":
        p = np.hypot(r[:, 0], r[:, 1])
        return np.column_stack([np.arctan2(r[:, 2], p), np.arctan2(r[:, 1], r[:, 0]),
                                np.sqrt(p * p + r[:, 2] ** 2) - earth.R_SPHERE])
    return earth.ecef_to_lla(r)


def _ecef_from_lla(lla, model):
    if model == "sphere":
        rr = earth.R_SPHERE + lla[..., 2]
        cl = np.cos(lla[..., 0])
        return np.stack([rr * cl * np.cos(lla[..., 1]), rr * cl * np.sin(lla[..., 1]), rr * np.sin(lla[..., 0])], -1)
    return earth.lla_to_ecef(lla)


def initial_state(kind, truth: PlatformTruth, initial: InitialErrors):
    """The 10-element initial state of the compiled integrator."""
    lla0 = truth.lla[0]
    v_enu = T_NED_ENU @ truth.v_n[0]
    C_i_enu = _c_e_enu(lla0[0], lla0[1])  # i = e at the start
    R0 = rot.dcm_from_rotvec(np.asarray(initial.tilt))
    y = np.zeros(10)
    lat_c, lon_c, h = lla0[0] + initial.d_lat, lla0[1] + initial.d_lon, lla0[2]
    v_c = v_enu + np.asarray(initial.dv_enu)
    if kind == K.SEMI:
        C_ip = C_i_enu @ R0
    else:
        C_ip = C_i_enu @ R0 @ C_i_enu.T
    y[0:4] = rot.quat_from_dcm(C_ip)
    if kind == K.ANALYTIC:
        r = _ecef_from_lla(np.array([lat_c, lon_c, h]), truth.earth)
        v_e = _c_e_enu(lat_c, lon_c) @ v_c
        y[4:7] = r
        y[7:10] = v_e + np.cross([0.0, 0.0, earth.OMEGA_IE], r)
    else:
        y[4:7] = lat_c, lon_c, h
        y[7:10] = v_c
    return y


def _noise(n, density, dt, rng):
    if density == 0.0:
        return np.zeros((n, 3))
    if rng is None:
        raise ConfigError("sensor noise needs an `rng`")
    return rng.standard_normal((n, 3)) * (density / np.sqrt(dt))


def mechanize_platform(truth: PlatformTruth, kind="semi-analytical", *, errors: PlatformErrors | None = None,
                       initial: InitialErrors | None = None, vertical="altimeter", rng=None) -> PlatformRun:
    """Simulate a platform INS over a sampled trajectory.

    Parameters
    ----------
    truth : PlatformTruth
        From :func:`~inskit.platform.world.platform_truth`.
    kind : {"semi-analytical", "analytical", "geometric"}
    errors : PlatformErrors, optional
        Instrument errors (perfect instruments by default).
    initial : InitialErrors, optional
        Alignment and initial-condition errors (none by default).
    vertical : {"altimeter", "free"}
        Vertical channel slaved to the external height, or free inertial.
    rng : numpy.random.Generator, optional
        Needed only when the errors include noise.

    Returns
    -------
    PlatformRun
    """
    if kind not in KINDS:
        raise ConfigError(f"`kind` must be one of {', '.join(KINDS)}, got {kind!r}")
    if vertical not in VERTICAL:
        raise ConfigError(f"`vertical` must be one of {', '.join(VERTICAL)}, got {vertical!r}")
    errors = errors or PlatformErrors()
    initial = initial or InitialErrors()
    k = KINDS[kind]
    model = model_code(truth.earth)
    n = len(truth.time)
    y0 = initial_state(k, truth, initial)
    href, vuref = vertical_reference(truth, errors)
    ng = _noise(n, errors.gyro_noise, truth.dt, rng)
    na = _noise(n, errors.accel_noise, truth.dt, rng)
    out = np.empty((n, 10))
    K.run_free(k, model, vertical == "altimeter", truth.time, np.ascontiguousarray(truth.lla[:, 0]),
               np.ascontiguousarray(truth.lla[:, 1]), truth.f_enu, href, vuref, y0,
               np.array(errors.gyro_drift), np.array(errors.accel_bias), np.array(errors.accel_scale),
               np.array(errors.torquer_scale), ng, na, out)
    sol = solution_from_state(kind, truth, out)
    return PlatformRun(kind, truth.earth, sol, truth, out)


def vertical_reference(truth, errors):
    href = np.ascontiguousarray(truth.lla[:, 2] + errors.altimeter_bias)
    vuref = np.ascontiguousarray(-truth.v_n[:, 2])
    return href, vuref


def solution_from_state(kind, truth: PlatformTruth, y) -> NavSolution:
    """Indicated NavSolution (with platform columns) from integrator states."""
    k = KINDS[kind]
    t = truth.time
    lla_t = truth.lla[::2]
    C_nb_t = rot.dcm_from_quat(truth.q_nb[::2])
    tau = t - t[0]
    Cie = _c_i_e(tau)
    C_i_ned_t = Cie @ earth.dcm_en(lla_t[:, 0], lla_t[:, 1])
    C_ip = rot.dcm_from_quat(y[:, 0:4])
    extra = {}
    if k == K.ANALYTIC:
        r_i, v_i = y[:, 4:7], y[:, 7:10]
        r_e = np.einsum("nji,nj->ni", Cie, r_i)
        w = np.array([0.0, 0.0, earth.OMEGA_IE])
        v_e = np.einsum("nji,nj->ni", Cie, v_i - np.cross(w, r_i))
        lla = _lla_from_ecef(r_e, truth.earth)
        C_ne = np.swapaxes(earth.dcm_en(lla[:, 0], lla[:, 1]), -1, -2)
        v_n = np.einsum("nij,nj->ni", C_ne, v_e)
        C_pb = np.swapaxes(C_ip, -1, -2) @ C_i_ned_t @ C_nb_t
        C_nb = C_ne @ np.swapaxes(Cie, -1, -2) @ C_pb
        extra.update(_vec_cols("drift", rot.rotvec_from_dcm(C_ip @ np.swapaxes(C_ip[:1], -1, -2)), "xyz"))
    else:
        lla = y[:, 4:7].copy()
        v_n = np.column_stack([y[:, 8], y[:, 7], -y[:, 9]])
        C_ni = np.swapaxes(Cie @ earth.dcm_en(lla[:, 0], lla[:, 1]), -1, -2)  # computed NED from inertial
        if k == K.SEMI:
            C_enu_t_p = np.swapaxes(C_i_ned_t @ T_NED_ENU, -1, -2) @ C_ip
            C_pb = np.swapaxes(C_enu_t_p, -1, -2) @ T_NED_ENU @ C_nb_t
            C_nb = T_NED_ENU @ C_pb  # the computer takes the platform for its geographic frame
        else:
            C_p1b = np.swapaxes(C_ip, -1, -2) @ C_i_ned_t @ C_nb_t
            C_nb = C_ni @ C_p1b
            C_pb = C_p1b
            extra.update(_vec_cols("drift", rot.rotvec_from_dcm(C_ip @ np.swapaxes(C_ip[:1], -1, -2)), "xyz"))
            extra["p2_lat_rad"] = lla[:, 0].copy()
            extra["p2_hour_angle_rad"] = rot.wrap_angle(lla[:, 1] + earth.OMEGA_IE * tau)
    tilt_ned = rot.attitude_error(C_nb, C_nb_t)  # rotvec of C_nb_true C_nb^T
    tilt_enu = tilt_ned @ T_NED_ENU.T
    extra.update(_vec_cols("tilt", tilt_enu, "enu"))
    g = rot.euler_from_dcm(T_NED_ENU @ C_pb) if k == K.SEMI else rot.euler_from_dcm(C_pb)
    extra.update({"gimbal_roll_rad": g[:, 0], "gimbal_pitch_rad": g[:, 1], "gimbal_yaw_rad": g[:, 2]})
    return NavSolution(t, lla, v_n, rot.quat_from_dcm(C_nb), extra)


def _vec_cols(prefix, v, axes):
    return {f"{prefix}_{a}_rad": np.ascontiguousarray(v[:, j]) for j, a in enumerate(axes)}


def v_west_absolute(lat, h, v_east, model):
    """West component of the absolute velocity ``V_eta = -(V_E + U (R_E+h) cos(phi))``
    (SOURCES-NOTES §2.1: source 004 uses absolute velocities)."""
    _, re = radii(lat, h, model)
    return -(v_east + earth.OMEGA_IE * re * np.cos(lat))


def source_errors(solution: NavSolution, truth: PlatformTruth):
    """Errors in source 004's state variables (SOURCES-NOTES §2.1).

    Returns
    -------
    (n, 7) ndarray
        ``[alpha_x, alpha_y, alpha_z, d_phi, d_lambda, dV_xi, dV_eta]``:
        tilts about north, west, up [rad] (from the ``tilt_*`` columns),
        indicated minus true latitude and longitude [rad], north and west
        absolute-velocity errors [m/s].
    """
    x = solution.extra
    lla_t = truth.lla[::2]
    v_t = truth.v_n[::2]
    out = np.empty((len(solution), 7))
    out[:, 0] = x["tilt_n_rad"]
    out[:, 1] = -x["tilt_e_rad"]
    out[:, 2] = x["tilt_u_rad"]
    out[:, 3] = solution.lla[:, 0] - lla_t[:, 0]
    out[:, 4] = rot.wrap_angle(solution.lla[:, 1] - lla_t[:, 1])
    out[:, 5] = solution.v_n[:, 0] - v_t[:, 0]
    out[:, 6] = (v_west_absolute(solution.lla[:, 0], solution.lla[:, 2], solution.v_n[:, 1], truth.earth)
                 - v_west_absolute(lla_t[:, 0], lla_t[:, 2], v_t[:, 1], truth.earth))
    return out
