"""Strapdown INS mechanizations: local-level NED, wander-azimuth, ECEF, inertial.

Every mechanization takes :class:`~inskit.types.ImuData` (angle and velocity
increments with timestamps; build it with ``ImuData.from_rates`` from rates)
and an initial :class:`~inskit.types.NavState`, and returns a
:class:`~inskit.types.NavSolution` in NED terms, whatever frame it integrates
in, so that solutions compare directly.

Two ways to call:

* whole array: ``mechanize(imu, initial, frame="ned")``;
* streaming: ``integ = NedIntegrator(initial); integ.run(chunk)`` repeatedly,
  the state (and the memory of the two-sample algorithms) carried from one
  chunk to the next, so logs larger than memory can be processed.  Chunked and
  whole-array runs give identical numbers.

The per-epoch loops are compiled (:mod:`inskit.strapdown.kernels`).

References
----------
SYSTEM.md §1.1 (wander-azimuth block diagram), §1.2 (inertial frame), §1.4
(NED, source 000 eq. 1-37..1-42); Savage, *Strapdown Analytics*, 2000;
Groves 2013 ch. 5.
"""

from __future__ import annotations

import os

import numpy as np

from .. import earth
from .. import rotations as rot
from ..errors import InputError, is_number
from ..types import ImuData, NavSolution, NavState
from . import kernels as K

__all__ = [
    "EcefIntegrator",
    "InertialIntegrator",
    "NedIntegrator",
    "WanderIntegrator",
    "mechanize",
    "check_track_off_pole",
    "FRAMES",
]

_HEIGHT_MODES = {"free": K.HEIGHT_FREE, "hold": K.HEIGHT_HOLD, "aid": K.HEIGHT_AID}


#: the NED mechanization's limit: closer than this to a pole its transport
#: rate (tan(lat)) is singular; the wander-azimuth and ECEF frames carry on
POLE_LIMIT = np.radians(89.9)


def _check_off_pole(lat, what):
    if not abs(lat) < POLE_LIMIT:
        raise InputError(f"{what} is at latitude {np.degrees(lat):.4f} deg, within 0.1 deg of a pole, where the "
                         "NED mechanization is singular: use the wander-azimuth or ECEF frame (frame='wander' or "
                         "'ecef'; --frame wander|ecef on the command line)")


def check_track_off_pole(time, lat, what, why):
    """Refuse a track that comes within 0.1 deg of a pole (:data:`POLE_LIMIT`),
    for work that has no frame to choose (a NED filter, a north-pointing
    platform): an InputError naming ``what`` (the track: ``"scenario 'x'"``),
    where and when it comes closest, and ``why`` the work is singular there.

    Parameters
    ----------
    time : (n,) array_like
        [s].
    lat : (n,) array_like
        Latitude [rad] at those times.
    what, why : str
    """
    lat = np.asarray(lat, float)
    near = ~(np.abs(lat) < POLE_LIMIT)
    if near.any():
        k = int(np.argmax(near))
        which = "north" if lat[k] > 0 else "south"
        raise InputError(f"{what} comes within 0.1 deg of the {which} pole (latitude {np.degrees(lat[k]):.4f} deg at "
                         f"t = {float(np.asarray(time)[k]):g} s), where {why}")


def _qz(angle):
    """Quaternion(s) of a rotation by ``angle`` about the z (down) axis."""
    angle = np.asarray(angle, dtype=float)
    z = np.zeros_like(angle)
    return np.stack([np.cos(0.5 * angle), z, z, np.sin(0.5 * angle)], -1)


class _Integrator:
    """Common streaming logic: carried state, chunk bookkeeping."""

    def __init__(self, initial: NavState, *, coning: bool = True, gravity="normal"):
        if not isinstance(initial, NavState):
            raise InputError("`initial` must be a NavState")
        if not isinstance(coning, (bool, np.bool_)):  # coning="no" is a non-empty string: it compensated
            raise InputError(f"`coning` must be True or False, got {type(coning).__name__} {coning!r}")
        self.initial = initial
        self.coning = bool(coning)
        #: code of the gravity model (:data:`inskit.earth.GRAVITY_MODELS`) and its name
        self._gravity = earth.gravity_model_code(gravity)
        self.gravity = earth.gravity_model_name(gravity)
        self._carry = np.zeros(11)
        self._carry[0] = initial.time
        self._started = False

    def _start_index(self, imu: ImuData):
        if not isinstance(imu, ImuData):
            raise InputError("`imu` must be an ImuData (see ImuData.from_rates)")
        if len(imu) == 0:
            raise InputError("the IMU chunk is empty")
        t_prev = self._carry[0]
        if not self._started:
            self._started = True
            tol = 1e-9 * max(1.0, abs(t_prev))
            if abs(imu.time[0] - t_prev) <= tol:
                return 1
            if imu.time[0] < t_prev:
                raise InputError(
                    f"the IMU data start at {imu.time[0]:.6f} s, before the initial state at {t_prev:.6f} s"
                )
            self._check_first_interval(imu, t_prev)
            return 0
        if imu.time[0] <= t_prev:
            raise InputError(
                f"chunk starts at {imu.time[0]:.6f} s, not after the previous chunk's end {t_prev:.6f} s"
            )
        return 0

    @staticmethod
    def _check_first_interval(imu: ImuData, t_prev):
        """Row 0 after the initial state: its increments are integrated over
        ``(t_prev, imu.time[0]]`` (a file whose row 0 is a real increment,
        docs/formats.md).  Refused when they cannot cover that interval: the
        gap is longer than the sampling interval (the motion over it was
        never measured: it was integrated as free fall, 1.8 m of height lost
        over a 100 s run for a state 10 ms early, -905 m for 5 s), or row 0
        holds six exact zeros (an initial epoch, not an interval: even at
        rest the accelerometers' increments are not zero)."""
        gap = float(imu.time[0] - t_prev)
        step = float(np.median(np.diff(imu.time[: min(len(imu), 101)]))) if len(imu) > 1 else gap
        fix = (f"give the state at the IMU's first time, {imu.time[0]:.6f} s (row 0 is then the initial epoch and "
               "its increments are not used)")
        if gap > 1.5 * step:
            raise InputError(f"the initial state at {t_prev:.6f} s is {gap:.6g} s before the IMU's first row "
                             f"({imu.time[0]:.6f} s), longer than its sampling interval ({step:.6g} s): the motion "
                             f"over that gap was never measured (it would be integrated as free fall); {fix}")
        if not (np.any(imu.dtheta_b[0] != 0.0) or np.any(imu.dv_b[0] != 0.0)):
            raise InputError(f"the initial state at {t_prev:.6f} s is before the IMU's first row ({imu.time[0]:.6f} "
                             "s), whose increments are all zero: an initial epoch, not a measured interval (it "
                             f"would be integrated as free fall); {fix}")

    def run(self, imu: ImuData, **kwargs) -> NavSolution:  # pragma: no cover - abstract
        raise NotImplementedError


class NedIntegrator(_Integrator):
    """Local-level NED mechanization (SYSTEM.md §1.4), streaming.

    Parameters
    ----------
    initial : NavState
    coning : bool
        Two-sample coning and sculling compensation (default on).
    gravity : {"normal", "normal-simple", "j2"}
        Gravity model (:func:`inskit.earth.gravity_n`); every integrator
        takes it.
    height : {"free", "hold", "aid"}
        Height channel: free inertial (unstable over long runs, SYSTEM.md
        §1.3's ``gamma_d`` gradient), held to an external height (height and
        vertical velocity taken from it), or aided by it through a
        second-order critically damped loop of time constant
        ``height_time_constant``.
    height_time_constant : float
        [s], for ``height="aid"``.
    """

    def __init__(self, initial, *, coning=True, height="free", height_time_constant=10.0, gravity="normal"):
        super().__init__(initial, coning=coning, gravity=gravity)
        if height not in _HEIGHT_MODES:
            raise InputError(f"`height` must be one of {sorted(_HEIGHT_MODES)}, got {height!r}")
        if not (is_number(height_time_constant) and 0 < height_time_constant < np.inf):
            raise InputError(f"`height_time_constant` must be a finite number > 0 [s], got {height_time_constant!r}")
        self.height_mode = _HEIGHT_MODES[height]
        tau = float(height_time_constant)
        self._gains = np.array([2.0 / tau, 1.0 / tau**2])
        self._lla = initial.lla.copy()
        self._v = initial.v_n.copy()
        self._q = initial.q_nb.copy()
        _check_off_pole(initial.lla[0], "the initial state")

    def run(self, imu: ImuData, height_ref=None) -> NavSolution:
        """Integrate one chunk; return the solution at its sample times.

        Parameters
        ----------
        imu : ImuData
        height_ref : float or (n,) array_like, optional
            External height [m] at the chunk's sample times; required when the
            height channel is held or aided.
        """
        start = self._start_index(imu)
        n = len(imu)
        if self.height_mode != K.HEIGHT_FREE:
            if height_ref is None:
                raise InputError("an external height (`height_ref`) is needed to hold or aid the height channel")
            h_ref = np.broadcast_to(np.asarray(height_ref, dtype=float), (n,)).copy()
            if not np.isfinite(h_ref).all():
                raise InputError("`height_ref` has a NaN value")
        else:
            h_ref = np.zeros(1)
        lla = np.empty((n, 3))
        v = np.empty((n, 3))
        q = np.empty((n, 4))
        K.ned_kernel(imu.time, imu.dtheta_b, imu.dv_b, start, self._lla, self._v, self._q, self._carry,
                     self.coning, self.height_mode, h_ref, self._gains, lla, v, q, self._gravity)
        near = np.nonzero(~(np.abs(lla[:, 0]) < POLE_LIMIT))[0]
        if len(near):
            _check_off_pole(lla[near[0], 0], f"the solution at t = {imu.time[near[0]]:.3f} s")
        return NavSolution._trusted(imu.time, lla, v, q)

    @property
    def state(self) -> NavState:
        return NavState(self._carry[0], self._lla, self._v, self._q)

    def reset(self, lla=None, v_n=None):
        """Overwrite the current position ``(3,)`` [rad, rad, m] and/or NED
        velocity ``(3,)`` [m/s] (an uncoupled INS/GNSS "reset"); the next
        chunk continues from them."""
        if lla is not None:
            self._lla[:] = np.asarray(lla, dtype=float)
        if v_n is not None:
            self._v[:] = np.asarray(v_n, dtype=float)


class WanderIntegrator(_Integrator):
    """Wander-azimuth mechanization (SYSTEM.md §1.1), valid over the poles.

    The solution carries the wander angle as ``extra["alpha_rad"]`` (the angle
    from north to the wander x axis, positive toward east).  At a pole the
    longitude and the wander angle are individually undefined; their
    difference, the attitude and the position stay well defined.

    Parameters
    ----------
    initial : NavState
    coning : bool
    alpha0 : float
        Initial wander angle [rad].
    """

    def __init__(self, initial, *, coning=True, alpha0=0.0, gravity="normal"):
        super().__init__(initial, coning=coning, gravity=gravity)
        if not (is_number(alpha0) and np.isfinite(alpha0)):
            raise InputError(f"`alpha0` must be a finite wander angle [rad], got {alpha0!r}")
        lat, lon, h = initial.lla
        C_ew = earth.dcm_en(lat, lon) @ rot.dcm_from_quat(_qz(alpha0))
        self._q_ew = rot.quat_from_dcm(C_ew)
        self._h = np.array([h])
        self._v = rot.dcm_from_quat(_qz(-alpha0)) @ initial.v_n
        self._q = rot.quat_multiply(_qz(-alpha0), initial.q_nb)

    def run(self, imu: ImuData) -> NavSolution:
        start = self._start_index(imu)
        n = len(imu)
        q_ew = np.empty((n, 4))
        h = np.empty(n)
        v_w = np.empty((n, 3))
        q_wb = np.empty((n, 4))
        K.wander_kernel(imu.time, imu.dtheta_b, imu.dv_b, start, self._q_ew, self._h, self._v, self._q,
                        self._carry, self.coning, q_ew, h, v_w, q_wb, self._gravity)
        return wander_to_ned(imu.time, q_ew, h, v_w, q_wb)


def wander_to_ned(time, q_ew, h, v_w, q_wb) -> NavSolution:
    """Convert wander-azimuth states to a NED NavSolution (vectorised)."""
    C = rot.dcm_from_quat(q_ew)
    lat = np.arcsin(np.clip(-C[:, 2, 2], -1.0, 1.0))
    alpha = np.arctan2(-C[:, 2, 1], C[:, 2, 0])
    lon = np.arctan2(-C[:, 1, 2], -C[:, 0, 2])
    q_nw = _qz(alpha)
    v_n = np.einsum("nij,nj->ni", rot.dcm_from_quat(q_nw), v_w)
    q_nb = rot.quat_multiply(q_nw, q_wb)
    return NavSolution._trusted(time, np.column_stack([lat, lon, h]), v_n, q_nb, {"alpha_rad": alpha})


class EcefIntegrator(_Integrator):
    """ECEF mechanization (Groves 2013 §5.2), streaming."""

    def __init__(self, initial, *, coning=True, gravity="normal"):
        super().__init__(initial, coning=coning, gravity=gravity)
        lat, lon, _ = initial.lla
        C_en = earth.dcm_en(lat, lon)
        self._r = earth.lla_to_ecef(initial.lla)
        self._v = C_en @ initial.v_n
        self._q = rot.quat_multiply(rot.quat_from_dcm(C_en), initial.q_nb)

    def run(self, imu: ImuData) -> NavSolution:
        start = self._start_index(imu)
        n = len(imu)
        r = np.empty((n, 3))
        v = np.empty((n, 3))
        q = np.empty((n, 4))
        K.ecef_kernel(imu.time, imu.dtheta_b, imu.dv_b, start, self._r, self._v, self._q, self._carry,
                      self.coning, r, v, q, self._gravity)
        return ecef_to_ned_solution(imu.time, r, v, q)


def ecef_to_ned_solution(time, r_e, v_e, q_eb) -> NavSolution:
    """Convert ECEF position, velocity and attitude to a NED NavSolution."""
    lla = earth.ecef_to_lla(r_e)
    C_ne = np.swapaxes(earth.dcm_en(lla[:, 0], lla[:, 1]), -1, -2)
    v_n = np.einsum("nij,nj->ni", C_ne, v_e)
    q_nb = rot.quat_multiply(rot.quat_from_dcm(C_ne), q_eb)
    return NavSolution._trusted(time, lla, v_n, q_nb)


class InertialIntegrator(_Integrator):
    """Inertial-frame mechanization (SYSTEM.md §1.2), streaming.

    The inertial frame coincides with ECEF at the initial epoch.  The state is
    the inertial position and velocity ``dr_i/dt``; the solution is converted
    to Earth-referenced NED terms.
    """

    def __init__(self, initial, *, coning=True, gravity="normal"):
        super().__init__(initial, coning=coning, gravity=gravity)
        lat, lon, _ = initial.lla
        C_en = earth.dcm_en(lat, lon)
        self.t0 = initial.time
        self._r = earth.lla_to_ecef(initial.lla)
        w = np.array([0.0, 0.0, earth.OMEGA_IE])
        self._v = C_en @ initial.v_n + np.cross(w, self._r)
        self._q = rot.quat_multiply(rot.quat_from_dcm(C_en), initial.q_nb)

    def run(self, imu: ImuData) -> NavSolution:
        start = self._start_index(imu)
        n = len(imu)
        r = np.empty((n, 3))
        v = np.empty((n, 3))
        q = np.empty((n, 4))
        K.inertial_kernel(imu.time, imu.dtheta_b, imu.dv_b, start, self.t0, self._r, self._v, self._q,
                          self._carry, self.coning, r, v, q, self._gravity)
        theta = earth.OMEGA_IE * (imu.time - self.t0)
        q_ei = _qz(-theta)
        C_ei = rot.dcm_from_quat(q_ei)
        w = np.array([0.0, 0.0, earth.OMEGA_IE])
        r_e = np.einsum("nij,nj->ni", C_ei, r)
        v_e = np.einsum("nij,nj->ni", C_ei, v - np.cross(w, r))
        return ecef_to_ned_solution(imu.time, r_e, v_e, rot.quat_multiply(q_ei, q))


FRAMES = {
    "ned": NedIntegrator,
    "wander": WanderIntegrator,
    "ecef": EcefIntegrator,
    "inertial": InertialIntegrator,
}


def mechanize(imu: ImuData, initial: NavState, *, frame="ned", chunk_size=1_000_000,
              progress=None, height_ref=None, **options) -> NavSolution:
    """Free-inertial navigation from IMU increments and an initial state.

    Parameters
    ----------
    imu : ImuData
        Increments; ``imu.time[0]`` is normally the initial epoch.
    initial : NavState
    frame : {"ned", "wander", "ecef", "inertial"}
        Frame the equations are integrated in; the result is always in NED
        terms.
    chunk_size : int
        Rows per compiled call (a progress bar advances per chunk).
    progress : callable, optional
        Called with the number of rows done after each chunk.
    height_ref : float or (n,) array, optional
        External height for ``frame="ned"`` with ``height="hold"`` or ``"aid"``.
    **options
        Passed to the integrator (``coning``, ``gravity``, ``height``,
        ``alpha0`` ...).

    Returns
    -------
    NavSolution

    Raises
    ------
    InputError
        ``imu`` not an ImuData (a file name: read it first with
        :func:`inskit.read_imu`), an option the frame's integrator does not
        take (``height`` outside ``frame="ned"``), a ``height_ref`` that
        would be ignored (another frame, or ``height="free"``), a
        ``chunk_size`` below 1.
    """
    import inspect

    if frame not in FRAMES:
        raise InputError(f"`frame` must be one of {sorted(FRAMES)}, got {frame!r}")
    if not isinstance(imu, ImuData):
        hint = " (a file: read it first, inskit.read_imu(path))" if isinstance(imu, (str, os.PathLike)) else ""
        raise InputError(f"`imu` must be an ImuData{hint}, got {type(imu).__name__} {imu!r}"[:300])
    takes = [k for k in inspect.signature(FRAMES[frame].__init__).parameters if k not in ("self", "initial")]
    unknown = [k for k in options if k not in takes]
    if unknown:
        note = "; height and height_time_constant are the NED frame's (frame='ned')" if (
            frame != "ned" and {"height", "height_time_constant"} & set(unknown)) else ""
        raise InputError(f"{', '.join(map(repr, unknown))}: not an option of the {frame} mechanization, which "
                         f"takes {', '.join(takes)}{note}")
    if height_ref is not None and (frame != "ned" or options.get("height", "free") == "free"):
        raise InputError("`height_ref` would be ignored: it is the external height of frame='ned' with "
                         "height='hold' or 'aid'" + (f" (the height here is {options.get('height', 'free')!r})"
                                                     if frame == "ned" else f" (the frame here is {frame!r})"))
    if isinstance(chunk_size, (bool, np.bool_)) or not isinstance(chunk_size, (int, np.integer)) or chunk_size < 1:
        raise InputError(f"`chunk_size` must be an integer >= 1 (rows per compiled call), got {chunk_size!r}")
    integ = FRAMES[frame](initial, **options)
    parts = []
    n = len(imu)
    href = None if height_ref is None else np.broadcast_to(np.asarray(height_ref, float), (n,))
    for a in range(0, n, int(chunk_size)):
        b = min(n, a + int(chunk_size))
        chunk = imu.slice(a, b)
        if frame == "ned":
            parts.append(integ.run(chunk, None if href is None else href[a:b]))
        else:
            parts.append(integ.run(chunk))
        if progress is not None:
            progress(b - a)
    return NavSolution.concat(parts)
