"""Blocks of the error state: each one owns its whole meaning.

A block declares, in one place,

* its ``name``, ``axes`` and SI ``unit`` (``size = len(axes)``);
* its initial 1-sigma ``sigma0`` and process-noise PSD ``psd`` per axis
  (``Q = diag(psd) dt``), and its correlation time ``tau_s`` (first-order
  Gauss-Markov: ``d x / dt = -x / tau``; ``inf`` for a random walk or a
  random constant);
* its constant entries of the transition matrix F (:meth:`transition`:
  ``(row, column block, column, value)``, rows local to the block), for
  example a clock's ``d bias / dt = drift``;
* a ``role`` when the compiled propagation must know it: the navigation
  blocks (``"pos"``, ``"vel"``, ``"att"``) and the inertial-sensor errors
  (``"gyro_bias"``, ``"accel_bias"``, ``"gyro_scale"``, ``"accel_scale"``),
  which correct the raw increments and couple into the navigation-error rows
  through ``C_nb``, ``f_b`` and ``omega_ib_b`` at each epoch;
* its running estimate (``estimate0``; ``None`` for the navigation blocks,
  whose estimate is the navigation state itself), how an estimated error is
  fed back into it (:meth:`feedback`: closed loop ``estimate -= dx`` by
  default, since error states are ``estimate - truth``), and the names under
  which estimate and sigma are reported (:meth:`estimate_names`,
  :meth:`sigma_names`).

A new state is one new block object: nothing in the filter loop changes.

References: SYSTEM.md §2; Groves 2013 §14.2 (error states), §14.2.7 (sensor
error states), §9.4.2 (receiver clock states).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..types import plain_number

NAV_ROLES = ("pos", "vel", "att")
SENSOR_ROLES = ("gyro_bias", "accel_bias", "gyro_scale", "accel_scale")


def _per_axis(value, n, what, name):
    a = np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy() if np.ndim(value) == 0 else \
        np.asarray(value, dtype=float)
    if a.shape != (n,):
        raise InputError(f"state block {name!r}: {what} needs {n} values (one per axis), got {a.shape}")
    return a


@dataclass(frozen=True, eq=False)
class StateBlock:
    """One block of the error state (see the module text).

    Parameters
    ----------
    name : str
        Unique within a layout; measurements find the block by it.
    axes : tuple of str
        Axis names (``("n", "e", "d")``, ``("x", "y", "z")``, ``("bias",
        "drift")``...).
    unit : str
        SI unit of the error, used in reported names (``"m"``, ``"rad_s"``).
    sigma0 : float or (size,) array_like
        Initial 1-sigma [unit].
    psd : float or (size,) array_like
        Process-noise power spectral density [unit^2 / s].
    tau_s : float
        Correlation time [s]; ``inf`` for a random walk (or, with ``psd`` 0, a
        random constant).
    role : str, optional
        One of ``NAV_ROLES`` or ``SENSOR_ROLES`` when the compiled
        propagation handles this block's couplings.
    estimate0 : float or (size,) array_like, optional
        Initial value of the quantity this block estimates (bias, lever arm,
        offset...).  ``None`` for the navigation blocks.
    entries : tuple, optional
        Extra constant entries of F: ``(row, column_block, column, value)``.
    body_psd : (3,) array_like, optional
        Velocity and attitude blocks only: white-noise PSDs per *body* axis
        [unit^2 / s] (a sensor's noise differs by axis: a car's gyro shakes
        about its pitch axis), rotated into NED at every step, ``C_nb
        diag(body_psd) C_bn`` (Groves 2013 eq. 14.80 with its noise per
        axis); added to ``psd``.
    predict_estimate : bool
        Carry the estimate between updates by the block's own dynamics
        (``exp(F dt)`` over its entries), as for a receiver clock whose bias
        runs on with its drift.  Otherwise the estimate is held (see
        :meth:`StateLayout.estimate_dynamics`).
    """

    name: str
    axes: tuple
    unit: str
    sigma0: object = 1.0
    psd: object = 0.0
    tau_s: float = math.inf
    role: str | None = None
    estimate0: object = None
    entries: tuple = field(default=())
    description: str = ""
    predict_estimate: bool = False
    body_psd: object = None

    def __post_init__(self):
        if not self.name or not isinstance(self.name, str):
            raise InputError(f"state block name must be a non-empty string, got {self.name!r}")
        if len(self.axes) == 0:
            raise InputError(f"state block {self.name!r} needs at least one axis")
        n = len(self.axes)
        object.__setattr__(self, "axes", tuple(self.axes))
        object.__setattr__(self, "sigma0", _per_axis(self.sigma0, n, "sigma0", self.name))
        object.__setattr__(self, "psd", _per_axis(self.psd, n, "psd", self.name))
        if not np.all(np.isfinite(self.sigma0)) or not np.all(self.sigma0 > 0):
            raise InputError(f"state block {self.name!r}: initial sigmas must be finite and > 0, got {self.sigma0}")
        if not np.all(np.isfinite(self.psd)) or np.any(self.psd < 0):
            raise InputError(f"state block {self.name!r}: process-noise PSDs must be finite and >= 0, got {self.psd}")
        if not self.tau_s > 0:
            raise InputError(f"state block {self.name!r}: tau_s must be > 0 (inf for a random walk), got {self.tau_s}")
        if self.body_psd is not None:
            if self.role not in ("vel", "att"):
                raise InputError(f"state block {self.name!r}: body_psd applies to the velocity and attitude blocks")
            bp = _per_axis(self.body_psd, n, "body_psd", self.name)
            if not np.all(np.isfinite(bp)) or np.any(bp < 0):
                raise InputError(f"state block {self.name!r}: body-axis PSDs must be finite and >= 0, got {bp}")
            object.__setattr__(self, "body_psd", bp)
        if self.role is not None and self.role not in NAV_ROLES + SENSOR_ROLES:
            raise InputError(f"state block {self.name!r}: unknown role {self.role!r}; "
                             f"known: {NAV_ROLES + SENSOR_ROLES}")
        if self.role in NAV_ROLES and self.estimate0 is not None:
            raise InputError(f"navigation block {self.name!r} carries no separate estimate")
        if self.role in SENSOR_ROLES and self.estimate0 is None:
            object.__setattr__(self, "estimate0", np.zeros(n))
        if self.estimate0 is not None:
            object.__setattr__(self, "estimate0", _per_axis(self.estimate0, n, "estimate0", self.name))
        if self.role is not None and n != 3:
            raise InputError(f"state block {self.name!r} with role {self.role!r} must have 3 axes")

    @property
    def size(self) -> int:
        return len(self.axes)

    @property
    def has_estimate(self) -> bool:
        return self.estimate0 is not None

    def prior_sigma(self, elapsed_s):
        """How far the quantity may have moved from ``estimate0`` after
        ``elapsed_s`` without any measurement, per axis [unit]: the initial
        sigma and the process noise accumulated since,
        ``sqrt(sigma0^2 + q tau / 2 (1 - exp(-2 T / tau)))`` for a
        Gauss-Markov block (its steady-state variance ``q tau / 2`` reached
        after a few ``tau``), ``sqrt(sigma0^2 + q T)`` for a random walk.
        The initial part is not let decay: a turn-on bias is a constant, the
        model's decay describes the error of its held estimate
        (:meth:`StateLayout.estimate_dynamics`).  Health checks compare an
        estimate's excursion with this, not with ``sigma0`` alone (a bias
        fixed on a 10 s static start wanders by its in-run sigma over a walk)."""
        T = max(float(elapsed_s), 0.0)
        q = np.asarray(self.psd, float)
        if math.isfinite(self.tau_s):
            walk = q * self.tau_s / 2.0 * -np.expm1(-2.0 * T / self.tau_s)
        else:
            walk = q * T
        return np.sqrt(np.asarray(self.sigma0, float) ** 2 + walk)

    def transition(self):
        """Constant entries of F: ``[(row, column_block, column, value)]``.

        The first-order Gauss-Markov diagonal ``-1 / tau`` and the declared
        ``entries``.
        """
        out = list(self.entries)
        if math.isfinite(self.tau_s):
            out += [(i, self.name, i, -1.0 / self.tau_s) for i in range(self.size)]
        return out

    def feedback(self, estimate, dx):
        """Closed loop: remove the estimated error ``dx`` from the block's
        estimate, in place (``estimate - truth = dx``)."""
        estimate -= dx

    def estimate_names(self):
        return [f"{self.name}_{a}_{self.unit}" if self.unit else f"{self.name}_{a}" for a in self.axes]

    def sigma_names(self):
        return [f"sigma_{n}" for n in self.estimate_names()]


# --- the standard blocks of an INS error state ---------------------------------------
class _Named(StateBlock):
    """A standard block whose reported names are given explicitly."""

    _est_names: tuple = ()
    _sig_names: tuple = ()

    def estimate_names(self):
        return list(self._est_names) if self._est_names else super().estimate_names()

    def sigma_names(self):
        return list(self._sig_names) if self._sig_names else super().sigma_names()


class PositionError(_Named):
    """Position error north, east, down [m] (``estimate - truth``)."""

    _sig_names = ("sigma_n_m", "sigma_e_m", "sigma_d_m")

    def __init__(self, sigma0=(1.0, 1.0, 1.0)):
        super().__init__("pos", ("n", "e", "d"), "m", sigma0, 0.0, role="pos",
                         description="position error north, east, down")


class VelocityError(_Named):
    """NED velocity error [m/s], driven by the accelerometer white noise (VRW)."""

    _sig_names = ("sigma_vn_m_s", "sigma_ve_m_s", "sigma_vd_m_s")

    def __init__(self, sigma0=0.1, accel_vrw=1e-2, accel_vrw_axes=None):
        """``accel_vrw_axes``: (3,) VRW per body axis [m/s^2/sqrt(Hz)], in place of ``accel_vrw``."""
        body = None if accel_vrw_axes is None else np.asarray(accel_vrw_axes, float) ** 2
        super().__init__("vel", ("n", "e", "d"), "m_s", sigma0, 0.0 if body is not None else accel_vrw**2,
                         role="vel", description="velocity error in NED", body_psd=body)


class AttitudeError(_Named):
    """Attitude error ``phi`` [rad], ``C_nb_est = (I - [phi x]) C_nb``, driven
    by the gyro white noise (ARW)."""

    _sig_names = ("sigma_att_n_rad", "sigma_att_e_rad", "sigma_att_d_rad")

    def __init__(self, sigma0=(np.radians(1.0), np.radians(1.0), np.radians(5.0)), gyro_arw=1e-3,
                 gyro_arw_axes=None):
        """``gyro_arw_axes``: (3,) ARW per body axis [rad/sqrt(s)], in place of ``gyro_arw``."""
        body = None if gyro_arw_axes is None else np.asarray(gyro_arw_axes, float) ** 2
        super().__init__("att", ("n", "e", "d"), "rad", sigma0, 0.0 if body is not None else gyro_arw**2,
                         role="att", description="attitude error about north, east, down", body_psd=body)


def _bias_psd(sigma, tau_s):
    """PSD of a first-order Gauss-Markov process of steady-state ``sigma``;
    for ``tau_s = inf``, ``sigma`` is itself the random-walk PSD's root."""
    return 2.0 * sigma**2 / tau_s if math.isfinite(tau_s) else sigma**2


class GyroBias(_Named):
    """Gyro bias error [rad/s]: Gauss-Markov with ``tau_s`` (steady-state sigma
    ``instability``) or a random walk (``tau_s = inf``, ``instability`` the
    PSD root [rad/s/sqrt(s)])."""

    _est_names = ("bg_x_rad_s", "bg_y_rad_s", "bg_z_rad_s")
    _sig_names = ("sigma_bg_x_rad_s", "sigma_bg_y_rad_s", "sigma_bg_z_rad_s")

    def __init__(self, sigma0=np.radians(0.05), instability=1e-5, tau_s=math.inf, estimate0=(0.0, 0.0, 0.0)):
        super().__init__("bg", ("x", "y", "z"), "rad_s", sigma0, _bias_psd(instability, tau_s), tau_s,
                         role="gyro_bias", estimate0=estimate0, description="gyro bias")


class AccelBias(_Named):
    """Accelerometer bias error [m/s^2] (as :class:`GyroBias`)."""

    _est_names = ("ba_x_m_s2", "ba_y_m_s2", "ba_z_m_s2")
    _sig_names = ("sigma_ba_x_m_s2", "sigma_ba_y_m_s2", "sigma_ba_z_m_s2")

    def __init__(self, sigma0=0.1, instability=1e-4, tau_s=math.inf, estimate0=(0.0, 0.0, 0.0)):
        super().__init__("ba", ("x", "y", "z"), "m_s2", sigma0, _bias_psd(instability, tau_s), tau_s,
                         role="accel_bias", estimate0=estimate0, description="accelerometer bias")


class GyroScale(_Named):
    """Gyro scale-factor error [-], a random walk of PSD ``rw**2`` [1/s]."""

    _est_names = ("sg_x", "sg_y", "sg_z")
    _sig_names = ("sigma_sg_x", "sigma_sg_y", "sigma_sg_z")

    def __init__(self, sigma0=0.01, rw=1e-6):
        super().__init__("sg", ("x", "y", "z"), "", sigma0, rw**2, role="gyro_scale",
                         description="gyro scale-factor error")


class AccelScale(_Named):
    """Accelerometer scale-factor error [-], a random walk."""

    _est_names = ("sa_x", "sa_y", "sa_z")
    _sig_names = ("sigma_sa_x", "sigma_sa_y", "sigma_sa_z")

    def __init__(self, sigma0=0.01, rw=1e-6):
        super().__init__("sa", ("x", "y", "z"), "", sigma0, rw**2, role="accel_scale",
                         description="accelerometer scale-factor error")


class LeverArm(_Named):
    """IMU-to-antenna lever arm in body axes [m], a random constant.  The GNSS
    measurements use its estimate when the layout holds it."""

    _est_names = ("lever_x_m", "lever_y_m", "lever_z_m")

    def __init__(self, sigma0=0.1, estimate0=(0.0, 0.0, 0.0)):
        super().__init__("lever", ("x", "y", "z"), "m", sigma0, 0.0, estimate0=estimate0,
                         description="IMU-to-antenna lever arm, body axes")


class TimeOffset(_Named):
    """IMU-GNSS time offset [s]: a GNSS time tag ``t`` matches the INS at
    ``t + offset``; a slow random walk of PSD ``rw**2`` [s^2/s]."""

    _est_names = ("time_offset_s",)
    _sig_names = ("sigma_time_offset_s",)

    def __init__(self, sigma0=0.05, rw=1e-6, estimate0=0.0):
        super().__init__("time_offset", ("dt",), "s", sigma0, rw**2, estimate0=estimate0,
                         description="IMU-GNSS time offset")


def mounting_dcm(pitch, yaw):
    """``C_vb`` (IMU body axes to vehicle axes) of the boresight angles, and
    its derivatives by pitch and by yaw.

    ``C_vb = dcm_from_euler((0, pitch, yaw)).T``: the angles are those of
    navigate's ``[imu] mount_rpy_deg`` (:func:`inskit.io.rtklib.mount_dcm`,
    where ``C_bs = dcm_from_euler(mount).T`` rotates sensor readings into
    body axes), applied after it; for small angles ``v_v = v_b + [v_b x] m``,
    so the vehicle's vertical velocity is ``v_bz + pitch v_bx`` and its
    lateral one ``v_by - yaw v_bx``.

    Parameters
    ----------
    pitch, yaw : float
        [rad].

    Returns
    -------
    C_vb, dC_dpitch, dC_dyaw : (3, 3) ndarray
    """
    cp, sp, cy, sy = math.cos(pitch), math.sin(pitch), math.cos(yaw), math.sin(yaw)
    C = np.array([[cp * cy, cp * sy, -sp], [-sy, cy, 0.0], [sp * cy, sp * sy, cp]])
    d_p = np.array([[-sp * cy, -sp * sy, -cp], [0.0, 0.0, 0.0], [cp * cy, cp * sy, -sp]])
    d_y = np.array([[-cp * sy, cp * cy, 0.0], [-cy, -sy, 0.0], [-sp * sy, sp * cy, 0.0]])
    return C, d_p, d_y


class GnssPositionError(_Named):
    """Time-correlated error of the GNSS position fixes, north, east, down
    [m]: a first-order Gauss-Markov process of steady-state ``sigma`` and
    correlation time ``tau_s`` (PSD ``2 sigma^2 / tau``), its estimate
    carried between the fixes by its own decay ``exp(-dt / tau)``.

    A fix is ``p_antenna + e + w`` with ``w`` the white noise of its own
    sigma: carrier-phase fixes wander by centimetres over seconds
    (multipath, the residual atmosphere), which a white-noise model at 5
    fixes a second would take as information about the INS.  Modelling the
    correlated part as states is the standard remedy for time-correlated
    measurement noise (state augmentation, Brown & Hwang 2012 §8.2; Groves
    2013 §14.2.7).  :class:`.measurements.GnssPosition` finds the block by
    its name ``"gnss_err"``: ``h = ... + e``, ``H_e = I``.

    ``sigma`` is one number for the three axes or ``(3,)``, north, east,
    down (the vertical of a fix is usually the worse).
    """

    _est_names = ("gnss_err_n_m", "gnss_err_e_m", "gnss_err_d_m")
    _sig_names = ("sigma_gnss_err_n_m", "sigma_gnss_err_e_m", "sigma_gnss_err_d_m")

    def __init__(self, sigma, tau_s):
        sigma = np.asarray(sigma, dtype=float)
        super().__init__("gnss_err", ("n", "e", "d"), "m", sigma, 2.0 * sigma**2 / tau_s, tau_s,
                         estimate0=np.zeros(3), predict_estimate=True,
                         description="time-correlated error of the GNSS position fixes")


class Mounting(_Named):
    """Boresight (mounting) angles of the vehicle axes against the IMU body
    axes [rad], pitch and yaw: a random constant with a slow random walk of
    PSD ``rw**2`` [rad^2/s].

    The filter navigates the IMU's body axes; the vehicle-motion constraints
    (:class:`.measurements.NonHolonomic`, :class:`.aiding.Odometer`) hold in
    the vehicle's axes, ``v_v = C_vb v_b`` with ``C_vb`` of
    :func:`mounting_dcm`.  They find the block by its name ``"mounting"``;
    without it ``C_vb = I``.  The estimate is the residual mounting after
    ``[imu] mount_rpy_deg``, in the same convention.

    Why no roll: with ``C_vb = (R_z(yaw) R_y(pitch) R_x(roll))^T`` the body
    velocity of a vehicle moving along its forward axis, ``v_b = C_bv (V, 0,
    0)``, does not depend on the roll at all (``R_x`` leaves the forward axis
    alone), and the constraints' rows (lateral and vertical zero, forward
    speed) are the same for any roll about the forward axis.  A roll of the
    mounting is therefore exactly unobservable and exactly harmless to these
    measurements; pitch and yaw describe any mounting as they see it.

    Parameters
    ----------
    sigma0 : float or (2,) float
        Initial 1-sigma [rad].
    rw : float
        Random-walk PSD root [rad/sqrt(s)].
    estimate0 : (2,) float
        Initial pitch and yaw [rad].

    References
    ----------
    Groves 2013 §16.2.3 (non-holonomic constraints, which hold in the
    vehicle's axes, not the IMU's).
    """

    _est_names = ("mounting_pitch_rad", "mounting_yaw_rad")
    _sig_names = ("sigma_mounting_pitch_rad", "sigma_mounting_yaw_rad")

    def __init__(self, sigma0=np.radians(5.0), rw=np.radians(0.01) / 60.0, estimate0=(0.0, 0.0)):
        super().__init__("mounting", ("pitch", "yaw"), "rad", sigma0, rw**2, math.inf, estimate0=estimate0,
                         description="boresight of the vehicle axes against the IMU body axes")


#: the models of a :class:`HeightBias`
HEIGHT_BIAS_MODELS = ("constant", "random-walk", "gauss-markov")


class HeightBias(_Named):
    """Offset ``b`` of a height sensor [m]: a barometer reads ``h + b`` plus
    noise (its datum, the weather).  The :class:`.aiding.Height` measurement
    finds it by its name ``"height_bias"``; the error state is
    ``b_est - b``, fed back closed loop (``b_est -= dx``).

    Parameters
    ----------
    sigma0 : float
        Initial 1-sigma [m]; for ``"gauss-markov"`` also the steady-state sigma.
    model : {"constant", "random-walk", "gauss-markov"}
        A random constant (no process noise), a random walk of PSD ``rw**2``
        [m^2/s], or first-order Gauss-Markov with ``tau_s`` (PSD
        ``2 sigma0^2 / tau_s``, Brown & Hwang 2012 ch. 2).
    rw : float
        Random-walk PSD root [m/sqrt(s)] (``"random-walk"`` only).
    tau_s : float
        Correlation time [s] (``"gauss-markov"`` only).
    estimate0 : float
        Initial estimate [m].
    """

    _est_names = ("height_bias_m",)
    _sig_names = ("sigma_height_bias_m",)

    def __init__(self, sigma0=50.0, model="random-walk", rw=0.0, tau_s=math.inf, estimate0=0.0):
        if model not in HEIGHT_BIAS_MODELS:
            raise InputError(f"height bias model must be one of {', '.join(HEIGHT_BIAS_MODELS)}, got {model!r}")
        if model == "gauss-markov" and not (math.isfinite(tau_s) and tau_s > 0):
            raise InputError(f"a Gauss-Markov height bias needs a finite tau_s > 0, got {tau_s}")
        if model == "random-walk" and not (math.isfinite(rw) and rw >= 0):
            raise InputError(f"the height bias random walk must be finite and >= 0 m/sqrt(s), got {rw}")
        sigma0 = float(sigma0)
        if model == "gauss-markov":
            psd, tau = _bias_psd(sigma0, tau_s), float(tau_s)
        else:
            psd, tau = (rw**2 if model == "random-walk" else 0.0), math.inf
        object.__setattr__(self, "model", model)
        super().__init__("height_bias", ("b",), "m", sigma0, psd, tau, estimate0=estimate0,
                         description=f"height-sensor offset ({model})")


# --- parameter bundles for the standard layout ------------------------------------------
@dataclass(frozen=True)
class SensorNoise:
    """Continuous-time noise of the inertial sensors (SI units).

    Attributes
    ----------
    gyro_arw : float
        Angle random walk [rad/s/sqrt(Hz)] (= rad/sqrt(s)).
    accel_vrw : float
        Velocity random walk [m/s^2/sqrt(Hz)].
    gyro_bias_sigma, accel_bias_sigma : float
        Steady-state sigma of the first-order Gauss-Markov biases [rad/s],
        [m/s^2]; with ``bias_tau_s = inf`` they are the random-walk PSD roots
        [rad/s^2/sqrt(Hz)], [m/s^3/sqrt(Hz)] instead.
    bias_tau_s : float
        Correlation time of the biases [s] (both sensors unless
        ``accel_bias_tau_s`` is given); ``inf`` for random walk.
    scale_sigma : float
        Random-walk PSD root of scale-factor errors [1/sqrt(s)].
    time_offset_rw : float
        Random walk of the IMU-GNSS time offset [s/sqrt(s)].
    accel_bias_tau_s : float, optional
        Correlation time of the accelerometer biases, when it differs.
    gyro_arw_axes, accel_vrw_axes : (3,) tuple, optional
        The white noise per body axis (same units), in place of
        ``gyro_arw`` and ``accel_vrw``: the filter rotates it into NED at
        every step.
    """

    gyro_arw: float
    accel_vrw: float
    gyro_bias_sigma: float
    accel_bias_sigma: float
    bias_tau_s: float = math.inf
    scale_sigma: float = 1e-6
    time_offset_rw: float = 1e-6
    accel_bias_tau_s: float | None = None
    gyro_arw_axes: tuple | None = None
    accel_vrw_axes: tuple | None = None

    def __post_init__(self):
        for name in ("gyro_arw", "accel_vrw", "gyro_bias_sigma", "accel_bias_sigma"):
            if not getattr(self, name) > 0:
                raise InputError(f"noise.{name} must be > 0, got {getattr(self, name)}")
        for name in ("bias_tau_s", "accel_bias_tau_s"):
            v = getattr(self, name)
            if v is not None and not v > 0:
                raise InputError(f"noise.{name} must be > 0 (inf for random walk), got {v}")
        for name in ("gyro_arw_axes", "accel_vrw_axes"):
            v = getattr(self, name)
            if v is not None and not (len(v) == 3 and all(math.isfinite(x) and x > 0 for x in v)):
                raise InputError(f"noise.{name} must be three finite values > 0, got {v}")


@dataclass(frozen=True)
class InitialUncertainty:
    """1-sigma initial errors (SI units)."""

    pos_m: tuple = (1.0, 1.0, 1.0)
    vel_m_s: float = 0.1
    roll_pitch_rad: float = np.radians(1.0)
    yaw_rad: float = np.radians(5.0)
    gyro_bias: float = np.radians(0.05)
    accel_bias: float = 0.1
    scale: float = 0.01
    lever_m: float = 0.1
    time_offset_s: float = 0.05

    def __post_init__(self):
        for name in ("vel_m_s", "roll_pitch_rad", "yaw_rad", "gyro_bias", "accel_bias", "scale", "lever_m",
                     "time_offset_s"):
            if not getattr(self, name) > 0:
                raise InputError(f"initial uncertainty {name} must be > 0, got {getattr(self, name)}")
        if not all(s > 0 for s in self.pos_m):
            raise InputError(f"initial position sigmas must be > 0, got {plain_number(self.pos_m)}")


def ins_blocks(noise: SensorNoise = SensorNoise(1e-3, 1e-2, 1e-5, 1e-4),
               initial: InitialUncertainty = InitialUncertainty(), *, scale_factors=False, lever_arm=False,
               time_offset=False, lever_arm_b=(0.0, 0.0, 0.0), gyro_bias0=(0.0, 0.0, 0.0),
               accel_bias0=(0.0, 0.0, 0.0), time_offset0=0.0):
    """The standard blocks of a loosely coupled INS error state, in order:
    ``pos, vel, att, bg, ba`` (15 states), then optionally ``sg, sa`` (21),
    ``lever`` and ``time_offset``.

    ``noise`` and ``initial`` are datasheet-like bundles; each block takes
    its part of them.
    """
    n, i = noise, initial
    tau_a = n.bias_tau_s if n.accel_bias_tau_s is None else n.accel_bias_tau_s
    out = [
        PositionError(tuple(i.pos_m)),
        VelocityError(i.vel_m_s, n.accel_vrw, n.accel_vrw_axes),
        AttitudeError((i.roll_pitch_rad, i.roll_pitch_rad, i.yaw_rad), n.gyro_arw, n.gyro_arw_axes),
        GyroBias(i.gyro_bias, n.gyro_bias_sigma, n.bias_tau_s, gyro_bias0),
        AccelBias(i.accel_bias, n.accel_bias_sigma, tau_a, accel_bias0),
    ]
    if scale_factors:
        out += [GyroScale(i.scale, n.scale_sigma), AccelScale(i.scale, n.scale_sigma)]
    if lever_arm:
        out.append(LeverArm(i.lever_m, lever_arm_b))
    if time_offset:
        out.append(TimeOffset(i.time_offset_s, n.time_offset_rw, time_offset0))
    return out


# --- GNSS receiver blocks (tight coupling) ----------------------------------------------
C_LIGHT = 299792458.0  #: speed of light [m/s] (IS-GPS-200)


def oscillator_psd(h0=2e-19, h_2=2e-20):
    """Process-noise PSDs of a receiver clock's (bias, drift) in range units,
    from the oscillator's Allan-variance coefficients (white frequency
    ``h0``, random-walk frequency ``h_2``): ``S_b = c^2 h0 / 2`` [m^2/s],
    ``S_d = c^2 2 pi^2 h_2`` [m^2/s^3] (Brown & Hwang 2012 §9.3; Groves
    2013 §9.4.2).  The defaults are a typical TCXO of a low-cost receiver."""
    return C_LIGHT**2 * h0 / 2.0, C_LIGHT**2 * 2.0 * math.pi**2 * h_2


class ReceiverClock(_Named):
    """Receiver clock bias [m] and drift [m/s] (``c dt_rx`` and its rate),
    ``d bias / dt = drift``, both driven by the oscillator's noise.

    Its estimate runs on between updates (``predict_estimate``): the bias by
    the drift estimate.  Pseudorange and range-rate measurements find it by
    its name ``"clock"``.

    Parameters
    ----------
    sigma0 : (2,) float
        Initial sigma of bias [m] and drift [m/s].
    h0, h_2 : float
        Oscillator Allan coefficients (:func:`oscillator_psd`).
    estimate0 : (2,) float
        Initial bias [m] and drift [m/s] (from single-point positioning, or
        from the first epoch's ranges at the initial position).
    """

    _est_names = ("clock_bias_m", "clock_drift_m_s")
    _sig_names = ("sigma_clock_bias_m", "sigma_clock_drift_m_s")

    def __init__(self, sigma0=(100.0, 10.0), h0=2e-19, h_2=2e-20, estimate0=(0.0, 0.0)):
        super().__init__("clock", ("bias", "drift"), "", sigma0, oscillator_psd(h0, h_2), math.inf,
                         estimate0=estimate0, entries=((0, "clock", 1, 1.0),), predict_estimate=True,
                         description="receiver clock bias and drift")


class SystemTimeOffset(_Named):
    """Offset of one GNSS system's time from the receiver clock's reference
    system [m] (the inter-system bias, e.g. Galileo against GPS), a random
    walk."""

    def __init__(self, system="E", sigma0=100.0, rw=0.01, estimate0=0.0):
        object.__setattr__(self, "_est_names", (f"isb_{system}_m",))
        object.__setattr__(self, "_sig_names", (f"sigma_isb_{system}_m",))
        super().__init__(f"isb_{system}", ("bias",), "m", sigma0, rw**2, math.inf, estimate0=estimate0,
                         description=f"system time offset of {system} against the clock's system")
