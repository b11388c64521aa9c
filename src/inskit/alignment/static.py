"""Alignment of a static log (the ``inskit align`` job) and the sigmas it can claim.

Error model of the one-step methods
-----------------------------------
The attitude is a function of the mean specific force ``f`` and the mean
rate ``w`` of a static interval.  At rest the sensor biases (turn-on and
in-run) are indistinguishable from the signal and do not average out, so the
errors of the means are, per body axis,

``cov_f = sigma_B^2 I + diag(s_a f)^2 + N_f``,
``cov_w = sigma_D^2 I + diag(s_g w)^2 + N_w``

with ``sigma_B``, ``sigma_D`` the bias priors, ``s_a``, ``s_g`` the
scale-factor priors and ``N`` the noise of the means (white noise
``var / n``, or the scatter of block means when larger: correlated noise).
The attitude covariance is ``J diag(cov_f, cov_w) J^T``, with ``J`` the
Jacobian of the method itself (central differences, evaluated at the
error-free inputs of the estimated attitude, where the linearisation of the
source holds), so the accelerometer basis, the gyro basis and every blend
share one model.  For the accelerometer basis it is source 002 eq. 29 in
expectation (SYSTEM.md §4): tilt ``sigma_B / g`` about north and east,
heading ``sqrt((sigma_D / (W cos phi))^2 + (tan(phi) sigma_B / g)^2)``.

Priors: the user's bias classes (1 sigma per axis), or, when none is given,
those of the grade :data:`DEFAULT_GRADE` (the worst grade inskit models, so
the sigmas are conservative for a better IMU): the preset's turn-on and
in-run bias sigmas in quadrature and its scale factor (taken per axis).  The
result says which in ``sigma_basis``.

Heading is reported unusable (yaw sigma :data:`NO_HEADING_SIGMA_DEG`, the
gyro blend gain 0) when the static gyro vector does not look like the Earth
rate or when the priors give a heading sigma above
:data:`fine.MAX_CONVERGED_SIGMA`.  A mean rate further from the Earth rate
than five sigmas of the gyro prior is refused: the IMU turned, or the gyro
is worse than assumed.

Limits: misalignment of the sensor triads and g-sensitivity are not in the
model; when the user gives the bias classes they are taken as the whole
budget (no scale-factor term).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import earth
from .. import rotations as rot
from ..errors import InputError
from ..integration.blocks import SensorNoise
from ..simulation.sensors import PRESETS, preset
from ..types import ImuData, NavState
from ..units import DEG, DEG_PER_HOUR, MICRO_G, PPM
from .analytic import accel_basis, blend, gyro_basis, ideal_static, measured_latitude
from .coarse import check_static, detect_static_start
from .fine import MAX_CONVERGED_SIGMA, fine_align
from .optimize import expected_J, ga_best_m

METHODS = ("accel", "gyro", "blend", "fine")
#: the grade whose bias priors are assumed when the user gives none
DEFAULT_GRADE = "consumer-mems"
#: the yaw sigma reported when the gyros cannot find north [deg]
NO_HEADING_SIGMA_DEG = 180.0
#: a static mean rate further than this many sigmas from the Earth rate is refused
GYRO_CONSISTENCY_SIGMAS = 5.0


def read_static(path, imu_format="inskit", mount_rpy=(0.0, 0.0, 0.0), check_units=True,
                first_row="initial") -> ImuData:
    from .. import io
    from ..io.rtklib import mount_dcm

    if imu_format == "rtklibexplorer":
        return io.read_imu(path, format=imu_format, mount_rpy=mount_rpy, check_units=check_units, first_row=first_row)
    raw = io.read_imu(path, format=imu_format, check_units=check_units, first_row=first_row)
    C = mount_dcm(mount_rpy)
    return ImuData(raw.time, raw.dtheta_b @ C.T, raw.dv_b @ C.T)


@dataclass(frozen=True)
class BiasPrior:
    """Sensor-error priors of an alignment (SI units, 1 sigma per axis).

    Attributes
    ----------
    accel, gyro : float
        Bias over the static interval (turn-on and in-run) [m/s^2], [rad/s].
    accel_scale, gyro_scale : float
        Scale-factor error [-] (0 when the user gave the bias classes).
    accel_in_run, gyro_in_run : float
        Sigma of the in-run (Gauss-Markov) part [m/s^2], [rad/s]: the fine
        filter's bias random walk.
    tau_s : float
        Its correlation time [s].
    basis : str
        Where the numbers come from, for the report.
    """

    accel: float
    gyro: float
    accel_scale: float
    gyro_scale: float
    accel_in_run: float
    gyro_in_run: float
    tau_s: float
    basis: str


def bias_prior(accel_bias_sigma=None, gyro_bias_sigma=None, grade=DEFAULT_GRADE) -> BiasPrior:
    """The priors of :func:`align_imu`: the given bias classes [m/s^2],
    [rad/s], or those of the grade preset (:mod:`inskit.simulation.sensors`)."""
    if grade not in PRESETS:
        raise InputError(f"unknown IMU grade {grade!r}; choose one of {', '.join(PRESETS)}")
    for name, v in (("accel_bias_sigma", accel_bias_sigma), ("gyro_bias_sigma", gyro_bias_sigma)):
        if v is not None and not (np.isfinite(v) and v > 0):
            raise InputError(f"`{name}` must be finite and > 0, got {float(v):g}")
    e = preset(grade)

    def total(t):
        return float(np.sqrt(t.turn_on_bias_sigma ** 2 + t.gm_sigma ** 2 + np.sum(np.square(t.fixed_bias)) / 3.0))

    ga, gg = total(e.accel), total(e.gyro)
    a = ga if accel_bias_sigma is None else float(accel_bias_sigma)
    g = gg if gyro_bias_sigma is None else float(gyro_bias_sigma)
    sa = e.accel.scale_factor[0] if accel_bias_sigma is None else 0.0
    sg = e.gyro.scale_factor[0] if gyro_bias_sigma is None else 0.0
    parts = []
    if accel_bias_sigma is not None or gyro_bias_sigma is not None:
        given = [f"accelerometer bias {a / MICRO_G:.6g} ug" if accel_bias_sigma is not None else "",
                 f"gyro bias {g / DEG_PER_HOUR:.6g} deg/h" if gyro_bias_sigma is not None else ""]
        parts.append("given: " + " and ".join(x for x in given if x) + " per axis (1 sigma)")
    if accel_bias_sigma is None or gyro_bias_sigma is None:
        assumed = [f"accelerometer bias {a / MICRO_G:.6g} ug, scale {sa / PPM:.6g} ppm"
                   if accel_bias_sigma is None else "",
                   f"gyro bias {g / DEG_PER_HOUR:.6g} deg/h, scale {sg / PPM:.6g} ppm"
                   if gyro_bias_sigma is None else ""]
        parts.append(f"assumed {grade} grade ({PRESETS[grade]['source'].split(':')[0]}): "
                     + "; ".join(x for x in assumed if x)
                     + " per axis (1 sigma, turn-on and in-run); give --accel-bias-ug and --gyro-bias-deg-h "
                       "of your IMU for sigmas that fit it")
    basis = "; ".join(parts) + "; plus the noise of the static means"
    tau = e.gyro.bias_instability_tau_s
    return BiasPrior(a, g, sa, sg, min(a, e.accel.gm_sigma), min(g, e.gyro.gm_sigma), tau, basis)


def mean_noise_cov(x, blocks=20):
    """Covariance (diagonal, ``(3, 3)``) of the mean of samples ``x``
    ``(n, 3)`` from their noise: ``var / n``, or the scatter of ``blocks``
    block means when larger (correlated noise, slow drift)."""
    x = np.asarray(x, float)
    n = len(x)
    v = x.var(axis=0, ddof=1) / n
    nb = min(blocks, n // 10)
    if nb >= 5:
        xb = x[: nb * (n // nb)].reshape(nb, n // nb, 3).mean(axis=1)
        v = np.maximum(v, xb.var(axis=0, ddof=1) / nb)
    return np.diag(v)


def method_dcm(method, f_b, w_b, lat, m=0.0):
    """``C_nb`` of a one-step method (``"accel"``, ``"gyro"``, ``"blend"``)."""
    if method == "accel":
        return accel_basis(f_b, w_b)
    if method == "gyro":
        return gyro_basis(f_b, w_b, lat)
    if method == "blend":
        return blend(f_b, w_b, lat, m)
    raise InputError(f"`method` must be one of accel, gyro, blend for a one-step alignment, got {method!r}")


def attitude_covariance(method, C_nb, lat, cov_f, cov_w, m=0.0):
    """Linear covariance of a one-step alignment's errors.

    Parameters
    ----------
    method : {"accel", "gyro", "blend"}
    C_nb : (3, 3) ndarray
        The estimated attitude (the Jacobian is taken at its error-free
        static inputs, :func:`analytic.ideal_static`).
    lat : float
        Latitude [rad].
    cov_f, cov_w : (3, 3) ndarray
        Covariance of the errors of the mean specific force [(m/s^2)^2] and
        the mean rate [(rad/s)^2], body axes.
    m : float
        Blending gain (``"blend"``).

    Returns
    -------
    cov_ned : (3, 3) ndarray
        Of the attitude error about north, east, down (:func:`rotations
        .attitude_error`) [rad^2].
    cov_rpy : (3, 3) ndarray
        Of roll, pitch, yaw [rad^2].
    """
    f0, w0 = ideal_static(C_nb, lat)
    x0 = np.concatenate([f0, w0])
    C0 = method_dcm(method, f0, w0, lat, m)
    e0 = rot.euler_from_dcm(C0)
    h = np.r_[np.full(3, 1e-6 * np.linalg.norm(f0)), np.full(3, 1e-4 * np.linalg.norm(w0))]
    dx = np.diag(h)
    Cs = np.stack([method_dcm(method, x[:3], x[3:], lat, m) for x in np.vstack([x0 + dx, x0 - dx])])
    d_ned = rot.attitude_error(Cs, np.broadcast_to(C0, Cs.shape))
    d_rpy = rot.wrap_angle(rot.euler_from_dcm(Cs) - e0)
    J_ned = ((d_ned[:6] - d_ned[6:]) / (2 * h)[:, None]).T
    J_rpy = ((d_rpy[:6] - d_rpy[6:]) / (2 * h)[:, None]).T
    S = np.zeros((6, 6))
    S[:3, :3], S[3:, 3:] = cov_f, cov_w
    return J_ned @ S @ J_ned.T, J_rpy @ S @ J_rpy.T


def heading_usability(w_mean, f_mean, lat, yaw_sigma=None, gyro_bias_sigma=None):
    """Whether the gyros can find north.

    The static mean rate must look like the Earth rate (magnitude within a
    factor of 2), and, when ``yaw_sigma`` [rad] (the heading sigma the priors
    allow) is given, it must be below :data:`fine.MAX_CONVERGED_SIGMA`.

    Returns
    -------
    usable : bool
    reason : str
    """
    ratio = float(np.linalg.norm(w_mean) / earth.OMEGA_IE)
    dlat = float(np.degrees(measured_latitude(f_mean, w_mean) - lat))
    if ratio > 2.0 or ratio < 0.5:
        return False, (f"the static gyro vector is {np.degrees(np.linalg.norm(w_mean)) * 3600:.1f} deg/h, "
                       f"{ratio:.1f} times the Earth rate ({np.degrees(earth.OMEGA_IE) * 3600:.2f} deg/h): the gyro "
                       "bias swamps the Earth rate, so these gyros cannot find north (use the GNSS track, a "
                       "magnetometer or two antennas)")
    if yaw_sigma is not None and not yaw_sigma <= MAX_CONVERGED_SIGMA:
        wh = earth.OMEGA_IE * np.cos(lat)
        bias = "" if gyro_bias_sigma is None else (
            f"the gyro bias prior ({gyro_bias_sigma / DEG_PER_HOUR:.4g} deg/h) is {gyro_bias_sigma / wh:.3g} times "
            f"the Earth rate's horizontal component ({wh / DEG_PER_HOUR:.2f} deg/h): ")
        return False, (f"{bias}the heading sigma it allows is {np.degrees(yaw_sigma):.3g} deg (more than "
                       f"{np.degrees(MAX_CONVERGED_SIGMA):.0f} deg), so the gyros cannot be trusted to find north "
                       "(give --gyro-bias-deg-h if your gyros are better; else use the GNSS track, a magnetometer "
                       "or two antennas)")
    return True, (f"the static gyro vector is {ratio:.2f} times the Earth rate and implies a latitude within "
                  f"{abs(dlat):.2f} deg of the given one")


def _euler_sigmas_from_ned(sig_ned, yaw):
    """Roll, pitch, yaw sigmas from sigmas about north, east, down (small
    pitch, correlations neglected): the tilt sigmas rotated into body axes."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([np.hypot(c * sig_ned[0], s * sig_ned[1]), np.hypot(s * sig_ned[0], c * sig_ned[1]),
                     sig_ned[2]])


def _check_gyro_consistency(name, seg, w_mean, f_mean, lat, prior, cov_w_noise):
    """Refuse a mean rate too far from the Earth rate for the gyro prior.

    Heading-free: the vertical component of the rate (along the specific
    force, which points up at rest) must be ``W sin(phi)`` and the
    magnitude of the horizontal one ``W cos(phi)``; the misfit is compared
    with the gyro prior plus the noise of the mean."""
    up = f_mean / np.linalg.norm(f_mean)
    w_up = float(w_mean @ up)
    w_h = float(np.linalg.norm(w_mean - w_up * up))

    def misfit(phi):
        return float(np.hypot(w_up - earth.OMEGA_IE * np.sin(phi), w_h - earth.OMEGA_IE * np.cos(phi)))

    r = misfit(lat)
    var = prior.gyro ** 2 + np.trace(cov_w_noise) / 3.0
    sig = float(np.sqrt(var))
    lim = GYRO_CONSISTENCY_SIGMAS * sig
    if r > lim:
        # the rate fits the Earth rate at another latitude: the latitude given is the suspect (radians, a sign)
        phi = measured_latitude(f_mean, w_mean)
        hint = ("" if misfit(phi) > lim else
                f"; it fits the Earth rate at latitude {np.degrees(phi):.1f} deg, not at the {np.degrees(lat):.4g} "
                "deg given: is the latitude (--lat) the log's, in degrees?")
        raise InputError(
            f"{name}: over [{float(seg.time[0]):.1f}, {float(seg.time[-1]):.1f}] s the mean rate differs from the "
            f"Earth rate by {r / DEG:.4g} deg/s ({r / DEG_PER_HOUR:.4g} deg/h); "
            f"a static IMU with a gyro bias of {prior.gyro / DEG_PER_HOUR:.4g} deg/h (1 sigma) stays within "
            f"{lim / DEG:.4g} deg/s ({GYRO_CONSISTENCY_SIGMAS:g} sigma): the IMU turned during the interval (give "
            f"--start/--end of a static one), or its gyro bias is larger than assumed (give --gyro-bias-deg-h){hint}"
        )


def _check_gyro_units(name, w_mean, f_mean, lat, cov_w_noise):
    """Refuse the Earth rate scaled by 57.3 (deg/s read as rad/s) or by
    1/57.3 (rad/s read as deg/s): magnitude within 15 % of it, the implied
    latitude within 5 deg of the given one, the noise of the mean below 5 %.
    A gyro bias that mimics both by chance is rare (a random MEMS bias of the
    right size points the right way in a few percent of cases); the file
    reader cannot make this test, it does not know the latitude."""
    wn = float(np.linalg.norm(w_mean))
    dlat = abs(float(np.degrees(measured_latitude(f_mean, w_mean) - lat)))
    noise = float(np.sqrt(np.trace(cov_w_noise)))
    for scale, said, held, fix in ((1.0 / DEG, "rad/s", "deg/s", "gyro_*_deg_s or dtheta_*_deg"),
                                   (DEG, "deg/s", "rad/s", "gyro_*_rad_s")):
        ref = earth.OMEGA_IE * scale
        if abs(wn / ref - 1.0) < 0.15 and dlat < 5.0 and noise < 0.05 * ref:
            raise InputError(
                f"{name}: the static mean rate is {wn:.4g} rad/s as read, {wn / earth.OMEGA_IE:.1f} times the Earth "
                f"rate, and it points where the Earth rate points at this latitude (within {dlat:.1f} deg): the "
                f"gyro columns hold {held} under a {said} header; rename them {fix} (or pass check_units=False / "
                "--no-unit-check if the gyro truly has a bias of that size)"
            )


#: the gyros measure the latitude when their static mean is the Earth rate within this fraction
LAT_MEASURE_RATE_TOL = 0.25
#: a measured latitude within this [deg] of a reading of --lat supports it; further than the next, refutes it
LAT_SUPPORT_DEG, LAT_REFUTE_DEG = 5.0, 15.0


def check_latitude_unit(name, lat, w_mean, f_mean, cov_w_noise):
    """A latitude given in radians where degrees were asked (``--lat 0.785``
    for 45 deg): refused when the gyros measure the latitude (their static
    mean within :data:`LAT_MEASURE_RATE_TOL` of the Earth rate) and it is the
    radian reading's, not the degree reading's; else, when the two readings
    differ by more than :data:`LAT_SUPPORT_DEG` and the gyros cannot tell
    them apart, a warning (returned; None when there is nothing to say).

    Parameters
    ----------
    name : str
        The log, for the message.
    lat : float
        The latitude as taken [rad] (the degrees given, converted).
    w_mean, f_mean : (3,) ndarray
        Static mean rate [rad/s] and specific force [m/s^2], body axes.
    cov_w_noise : (3, 3) ndarray
        Noise covariance of the mean rate [(rad/s)^2].
    """
    given = float(np.degrees(lat))  # the number the user wrote
    as_rad = float(np.degrees(given))  # that number read as radians [deg]
    if not (0.0 < abs(given) <= 90.0 / np.degrees(1.0)) or abs(as_rad - given) <= LAT_SUPPORT_DEG:
        return None
    ratio = float(np.linalg.norm(w_mean) / earth.OMEGA_IE)
    noise = float(np.sqrt(np.trace(cov_w_noise)))
    measured = None
    if abs(ratio - 1.0) < LAT_MEASURE_RATE_TOL and noise < 0.1 * earth.OMEGA_IE:
        measured = float(np.degrees(measured_latitude(f_mean, w_mean)))
        if abs(measured - as_rad) < LAT_SUPPORT_DEG and abs(measured - given) > LAT_REFUTE_DEG:
            raise InputError(f"{name}: --lat {given:g} looks like a latitude in radians ({as_rad:.4g} deg): the gyros "
                             f"measure a latitude of {measured:.1f} deg (their static mean is {ratio:.2f} times the "
                             "Earth rate); give --lat in degrees")
        if abs(measured - given) < LAT_SUPPORT_DEG:
            return None  # the gyros confirm the degrees: a place near the equator
    why = ("the gyros cannot tell (their static mean is "
           f"{ratio:.3g} times the Earth rate)" if measured is None else
           f"the gyros measure {measured:.1f} deg, which fits neither well")
    return (f"--lat {given:g} deg: near the equator, or {as_rad:.4g} deg written in radians? {why}; the "
            "alignment takes it as degrees")


def align_imu(imu: ImuData, lat, *, method="blend", m=None, t_start=None, t_end=None, accel_bias_sigma=None,
              gyro_bias_sigma=None, grade=DEFAULT_GRADE, name="the IMU log", check_units=True) -> dict:
    """Align on the static interval of an IMU log, with honest sigmas.

    Parameters
    ----------
    imu : ImuData
        Body-axis increments (mounting already applied).
    lat : float
        Latitude [rad].
    method : {"accel", "gyro", "blend", "fine"}
        Accelerometer basis, gyro basis, their blend by ``m`` (source 002),
        or the stationary Kalman filter (:func:`fine.fine_align`).
    m : float, optional
        Blending gain; default: the GA's choice for the priors (0 when the
        heading is unusable).
    t_start, t_end : float, optional
        The static interval [s]; default: the log start and the detected end
        of its static start.  A given end is checked to be static
        (:func:`coarse.check_static`).
    accel_bias_sigma, gyro_bias_sigma : float, optional
        Bias classes (1 sigma per axis) [m/s^2], [rad/s]; default those of
        ``grade``.
    grade : str
        Preset of :mod:`inskit.simulation.sensors` for the missing priors.
    name : str
        How messages name the log (its file).
    check_units : bool
        Refuse a static gyro mean that is the Earth rate scaled by 57.3 or
        1/57.3 (deg/s and rad/s swapped; the file reader cannot see it).

    Returns
    -------
    dict
        JSON-ready: ``roll_deg, pitch_deg, yaw_deg`` and their ``*_sigma_deg``,
        ``error_sigma_ned_deg`` (one-step methods), ``sigma_basis``,
        ``accel_bias_sigma_ug``, ``gyro_bias_sigma_deg_h``, ``heading_usable``,
        ``heading_reason``, the interval, ``m`` (blend), ``converge_time_s``
        and ``converge_note`` (fine), ``warnings`` (a latitude that may be
        radians: :func:`check_latitude_unit`).  ``yaw_sigma_deg`` is
        :data:`NO_HEADING_SIGMA_DEG` when the heading is unusable.
    """
    if method not in METHODS:
        raise InputError(f"`method` must be one of {', '.join(METHODS)}, got {method!r}")
    if not (np.isfinite(lat) and abs(lat) < np.pi / 2):
        hint = (f" (`lat` is {float(lat):g} rad here: degrees where radians are expected? np.radians)"
                if np.isfinite(lat) and abs(lat) <= 90 else "")
        raise InputError(f"--lat must be within (-90, 90) deg (at a pole north is undefined), got "
                         f"{np.degrees(float(lat)):g}{hint}")
    if m is not None:  # the command line checked these; a call did not (m = 2 gave a pitch of 8.5 deg at rest)
        if method != "blend":
            raise InputError(f"`m` {m!r} would be ignored: it is the blending gain of method 'blend', and method "
                             f"{method!r} blends nothing")
        if isinstance(m, bool) or not isinstance(m, (int, float, np.integer, np.floating)) or not 0.0 <= m <= 1.0:
            raise InputError(f"`m`, the blending gain, must be within [0, 1], got {m!r}")
    prior = bias_prior(accel_bias_sigma, gyro_bias_sigma, grade)
    t0, t1 = float(imu.time[0]), float(imu.time[-1])
    span = f"the log spans {t0:.3f}..{t1:.3f} s"
    tol = float(np.median(np.diff(imu.time))) if len(imu) > 1 else 0.0
    # a bound outside the log is refused, either side, as the window of evaluate is: clipped in silence, the
    # interval reported would not be the one asked for
    for option, v in (("--start", t_start), ("--end", t_end)):
        if v is not None and not (t0 - tol <= float(v) <= t1 + tol):
            raise InputError(f"{name}: {option} {float(v):g} s lies outside the log ({span}; times are those of "
                             "its time column)")
    a = t0 if t_start is None else float(t_start)
    if not a < t1:  # the last sample: nothing to detect the static end in
        raise InputError(f"{name}: --start {a:g} s is not before the log's end ({span})")
    if t_end is None:
        b = detect_static_start(imu.slice(int(np.searchsorted(imu.time, a))))
    else:
        b = float(t_end)
    if not b > a:
        raise InputError(f"{name}: the static interval [{a:g}, {b:g}] s is empty (--end must be after --start)")
    k0, k1 = int(np.searchsorted(imu.time, a)), int(np.searchsorted(imu.time, b, side="right"))
    if k1 - k0 < 10:
        raise InputError(f"{name}: fewer than 10 samples in the static interval [{a:.3f}, {b:.3f}] s")
    seg = imu.slice(k0, k1)
    if t_end is not None:
        try:
            check_static(seg)
        except InputError as exc:
            raise InputError(f"{name}: {exc}") from None
    w, f = seg.rates()
    w, f = w[1:], f[1:]
    T = float(seg.time[-1] - seg.time[0])
    f_mean, w_mean = seg.dv_b[1:].sum(axis=0) / T, seg.dtheta_b[1:].sum(axis=0) / T
    n = len(f)
    dt = float(np.median(np.diff(seg.time)))
    cov_f_noise, cov_w_noise = mean_noise_cov(f), mean_noise_cov(w)
    if check_units:
        _check_gyro_units(name, w_mean, f_mean, lat, cov_w_noise)
    lat_warning = check_latitude_unit(name, lat, w_mean, f_mean, cov_w_noise)
    _check_gyro_consistency(name, seg, w_mean, f_mean, lat, prior, cov_w_noise)
    C0 = accel_basis(f_mean, w_mean)
    w_earth_b = C0.T @ earth.rate_ie_n(lat)
    cov_f = prior.accel ** 2 * np.eye(3) + np.diag((prior.accel_scale * f_mean) ** 2) + cov_f_noise
    cov_w = prior.gyro ** 2 * np.eye(3) + np.diag((prior.gyro_scale * w_earth_b) ** 2) + cov_w_noise
    # the heading the priors allow (accelerometer basis: eq. 29 in expectation)
    cov_ned0, cov_rpy0 = attitude_covariance("accel", C0, lat, cov_f, cov_w)
    yaw_sigma0 = float(np.sqrt(cov_ned0[2, 2]))
    usable, reason = heading_usability(w_mean, f_mean, lat, yaw_sigma0, prior.gyro)
    out = {"method": method, "static_start_s": float(seg.time[0]), "static_end_s": float(seg.time[-1]),
           "static_s": T, "samples": int(n),
           "measured_latitude_deg": float(np.degrees(measured_latitude(f_mean, w_mean))),
           "gyro_norm_over_earth_rate": float(np.linalg.norm(w_mean) / earth.OMEGA_IE),
           "heading_usable": usable, "heading_reason": reason, "sigma_basis": prior.basis,
           "accel_bias_sigma_ug": prior.accel / MICRO_G, "gyro_bias_sigma_deg_h": prior.gyro / DEG_PER_HOUR,
           "warnings": [lat_warning] if lat_warning else []}
    if method == "fine":
        rpy0 = rot.euler_from_dcm(C0)
        lla = np.array([lat, 0.0, 0.0])
        gyro_rw = max(prior.gyro_in_run * np.sqrt(2.0 / prior.tau_s), 1e-12)
        accel_rw = max(prior.accel_in_run * np.sqrt(2.0 / prior.tau_s), 1e-12)
        noise = SensorNoise(max(float(np.sqrt(np.mean(w.var(axis=0))) * np.sqrt(dt)), 1e-7),
                            max(float(np.sqrt(np.mean(f.var(axis=0))) * np.sqrt(dt)), 1e-6), gyro_rw, accel_rw, np.inf)
        start = NavState.from_euler(seg.time[0], lla, np.zeros(3), rpy0)
        # the static gyro mean less the Earth rate (in the coarse attitude) is the best bias start
        bg0 = w_mean - w_earth_b
        if usable:
            fa = fine_align(seg, start, noise, gyro_bias0=bg0, gyro_bias_sigma=prior.gyro,
                            accel_bias_sigma=prior.accel)
        else:
            # no north: a levelling filter.  bg0 is then off by the Earth rate turned through the yaw error
            # at most, whatever the gyro grade; a large yaw prior would only feed the filter's first-order
            # reset artefacts (see fine.py), so yaw is held and reported unknown
            bg_sigma = min(prior.gyro, 2.0 * earth.OMEGA_IE + float(np.sqrt(np.trace(cov_w_noise) / 3.0)))
            fa = fine_align(seg, start, noise, sigma_yaw=np.radians(2.0), gyro_bias0=bg0, gyro_bias_sigma=bg_sigma,
                            accel_bias_sigma=prior.accel)
        # at rest the filter cannot beat the one-step means of the same data (bias and noise)
        sig_ned = np.maximum(fa.sigma_rpy, np.sqrt(np.diag(cov_ned0)))
        sig = _euler_sigmas_from_ned(sig_ned, fa.rpy[2]) / DEG
        conv = [None if np.isnan(v) else float(v) for v in fa.converge_time_s]
        notes = []
        for j, ang in enumerate(("roll", "pitch", "yaw")):
            if j == 2 and not usable:
                conv[2] = None
                notes.append("yaw not converged: the heading is unobservable with these gyros (see heading_reason)")
            elif conv[j] is None:
                notes.append(f"{ang} not converged: its sigma did not halve from its prior or stayed above "
                             f"{np.degrees(MAX_CONVERGED_SIGMA):.0f} deg (a longer static interval or better "
                             "sensors are needed)")
        out.update({"roll_deg": float(fa.rpy[0] / DEG), "pitch_deg": float(fa.rpy[1] / DEG),
                    "yaw_deg": float(fa.rpy[2] / DEG), "roll_sigma_deg": float(min(sig[0], NO_HEADING_SIGMA_DEG)),
                    "pitch_sigma_deg": float(min(sig[1], NO_HEADING_SIGMA_DEG)),
                    "yaw_sigma_deg": float(min(sig[2], NO_HEADING_SIGMA_DEG)) if usable else NO_HEADING_SIGMA_DEG,
                    "converge_time_s": conv, "converge_note": "; ".join(notes)})
        return out
    if method == "blend":
        if m is None:
            if usable:
                sB = float(np.sqrt(np.trace(cov_f) / 3.0))
                sD = float(np.sqrt(np.trace(cov_w) / 3.0))
                m = ga_best_m(expected_J(C0, lat, sB, sD, draws=100)).m
            else:
                m = 0.0  # the gyros carry no north: the accelerometer basis
        out["m"] = float(m)
    C = method_dcm(method, f_mean, w_mean, lat, 0.0 if m is None else m)
    if method == "accel":
        cov_ned, cov_rpy = cov_ned0, cov_rpy0
    else:
        cov_ned, cov_rpy = attitude_covariance(method, C, lat, cov_f, cov_w, 0.0 if m is None else m)
    rpy = rot.euler_from_dcm(C)
    sig = np.minimum(np.sqrt(np.diag(cov_rpy)) / DEG, NO_HEADING_SIGMA_DEG)
    out.update({"roll_deg": float(rpy[0] / DEG), "pitch_deg": float(rpy[1] / DEG), "yaw_deg": float(rpy[2] / DEG),
                "roll_sigma_deg": float(sig[0]), "pitch_sigma_deg": float(sig[1]),
                "yaw_sigma_deg": float(sig[2]) if usable else NO_HEADING_SIGMA_DEG,
                "error_sigma_ned_deg": [float(min(v, NO_HEADING_SIGMA_DEG))
                                        for v in np.sqrt(np.diag(cov_ned)) / DEG]})
    return out


def align_static(path, lat, *, method="blend", m=None, t_start=None, t_end=None, imu_format="inskit",
                 mount_rpy=(0.0, 0.0, 0.0), check_units=True, accel_bias_sigma=None, gyro_bias_sigma=None,
                 grade=DEFAULT_GRADE, first_row="initial"):
    """Align on the static interval of a log file (:func:`align_imu`);
    returns a flat dict (JSON-ready).  ``first_row``: that of an increment
    file (:func:`inskit.io.csv_formats.first_row_rule`)."""
    imu = read_static(path, imu_format, mount_rpy, check_units, first_row)
    return align_imu(imu, lat, method=method, m=m, t_start=t_start, t_end=t_end, accel_bias_sigma=accel_bias_sigma,
                     gyro_bias_sigma=gyro_bias_sigma, grade=grade, name=str(path), check_units=check_units)
