"""Alignment of a static log from a file (the ``inskit align`` job)."""

from __future__ import annotations

import numpy as np

from .. import earth
from ..errors import InputError
from ..integration.blocks import SensorNoise
from ..types import ImuData, NavState
from ..units import DEG, MICRO_G
from .analytic import accel_basis, blend, gyro_basis, measured_latitude
from .coarse import detect_static_start
from .fine import fine_align
from .optimize import expected_J, ga_best_m


def read_static(path, imu_format="inskit", mount_rpy=(0.0, 0.0, 0.0), check_units=True) -> ImuData:
    from .. import io
    from ..io.rtklib import mount_dcm, read_rtklibexplorer_imu

    if imu_format == "rtklibexplorer":
        imu, _ = read_rtklibexplorer_imu(path, mount_rpy=mount_rpy, check_units=check_units)
        return imu
    raw = io.read_imu(path, check_units=check_units)
    C = mount_dcm(mount_rpy)
    return ImuData(raw.time, raw.dtheta_b @ C.T, raw.dv_b @ C.T)


def heading_usability(w_mean, f_mean, lat):
    """Whether the gyros can find north: their static mean must look like the
    Earth rate (magnitude within a factor of 2, implied latitude within 5 deg)."""
    ratio = float(np.linalg.norm(w_mean) / earth.OMEGA_IE)
    dlat = float(np.degrees(measured_latitude(f_mean, w_mean) - lat))
    if ratio > 2.0 or ratio < 0.5:
        return False, (f"the static gyro vector is {np.degrees(np.linalg.norm(w_mean)) * 3600:.1f} deg/h, "
                       f"{ratio:.1f} times the Earth rate ({np.degrees(earth.OMEGA_IE) * 3600:.2f} deg/h): the gyro "
                       "bias swamps the Earth rate, so these gyros cannot find north (use the GNSS track, a "
                       "magnetometer or two antennas)")
    if abs(dlat) > 5.0:
        return False, (f"the sensors imply a latitude {dlat:+.1f} deg off the given one: the gyro errors are a "
                       "large fraction of the Earth rate")
    return True, (f"the static gyro vector is {ratio:.2f} times the Earth rate and implies a latitude within "
                  f"{abs(dlat):.2f} deg of the given one")


def align_static(path, lat, *, method="blend", m=None, t_start=None, t_end=None, imu_format="inskit",
                 mount_rpy=(0.0, 0.0, 0.0), check_units=True, accel_bias_sigma=None, gyro_bias_sigma=None):
    """Align on the static interval of a log; returns a flat dict (JSON-ready)."""
    imu = read_static(path, imu_format, mount_rpy, check_units)
    a = imu.time[0] if t_start is None else t_start
    b = detect_static_start(imu.slice(int(np.searchsorted(imu.time, a)))) if t_end is None else t_end
    if not b > a:
        raise InputError(f"the static interval [{a}, {b}] s is empty")
    k0, k1 = int(np.searchsorted(imu.time, a)), int(np.searchsorted(imu.time, b, side="right"))
    if k1 - k0 < 10:
        raise InputError(f"{path}: fewer than 10 samples in the static interval [{a:.3f}, {b:.3f}] s")
    seg = imu.slice(k0, k1)
    w, f = seg.rates()
    w, f = w[1:], f[1:]
    f_mean, w_mean = f.mean(axis=0), w.mean(axis=0)
    n = len(f)
    dt = float(np.median(np.diff(seg.time)))
    # uncertainty of the means from white noise, or the sensor-class biases when given
    sB = accel_bias_sigma if accel_bias_sigma is not None else float(np.sqrt(np.mean(f.var(axis=0)) / n))
    sD = gyro_bias_sigma if gyro_bias_sigma is not None else float(np.sqrt(np.mean(w.var(axis=0)) / n))
    g = earth.gravity_down(lat, 0.0)
    usable, reason = heading_usability(w_mean, f_mean, lat)
    out = {"method": method, "static_start_s": float(seg.time[0]), "static_end_s": float(seg.time[-1]),
           "static_s": float(seg.time[-1] - seg.time[0]), "samples": int(n),
           "measured_latitude_deg": float(np.degrees(measured_latitude(f_mean, w_mean))),
           "gyro_norm_over_earth_rate": float(np.linalg.norm(w_mean) / earth.OMEGA_IE),
           "heading_usable": usable, "heading_reason": reason}
    tilt_sigma = sB / g
    yaw_sigma = float(np.hypot(sD / (earth.OMEGA_IE * np.cos(lat)), np.tan(lat) * sB / g))
    if method == "accel":
        C = accel_basis(f_mean, w_mean)
    elif method == "gyro":
        C = gyro_basis(f_mean, w_mean, lat)
    elif method == "blend":
        if m is None:
            C0 = accel_basis(f_mean, w_mean)
            J = expected_J(C0, lat, sB, sD, draws=100)
            m = ga_best_m(J).m
        C = blend(f_mean, w_mean, lat, m)
        out["m"] = float(m)
    else:  # fine
        C0 = accel_basis(f_mean, w_mean)
        rpy0 = np.array([np.arctan2(C0[2, 1], C0[2, 2]), np.arcsin(-C0[2, 0]), np.arctan2(C0[1, 0], C0[0, 0])])
        lla = np.array([lat, 0.0, 0.0])
        noise = SensorNoise(max(float(np.sqrt(np.mean(w.var(axis=0))) * np.sqrt(dt)), 1e-7),
                            max(float(np.sqrt(np.mean(f.var(axis=0))) * np.sqrt(dt)), 1e-6),
                            gyro_bias_sigma or 1e-7, accel_bias_sigma or 10 * MICRO_G, np.inf)
        start = NavState.from_euler(seg.time[0], lla, np.zeros(3), rpy0)
        # the static gyro mean less the Earth rate (in the coarse attitude) is the best bias start
        bg0 = w_mean - C0.T @ earth.rate_ie_n(lat)
        fa = fine_align(seg, start, noise, sigma_yaw=np.radians(10.0) if usable else np.radians(60.0),
                        gyro_bias0=bg0, gyro_bias_sigma=max(sD, 1e-6))
        out.update({"roll_deg": float(fa.rpy[0] / DEG), "pitch_deg": float(fa.rpy[1] / DEG),
                    "yaw_deg": float(fa.rpy[2] / DEG), "roll_sigma_deg": float(fa.sigma_rpy[0] / DEG),
                    "pitch_sigma_deg": float(fa.sigma_rpy[1] / DEG), "yaw_sigma_deg": float(fa.sigma_rpy[2] / DEG),
                    "converge_time_s": [None if np.isnan(v) else float(v) for v in fa.converge_time_s]})
        return out
    rpy = np.array([np.arctan2(C[2, 1], C[2, 2]), np.arcsin(np.clip(-C[2, 0], -1, 1)), np.arctan2(C[1, 0], C[0, 0])])
    out.update({"roll_deg": float(rpy[0] / DEG), "pitch_deg": float(rpy[1] / DEG), "yaw_deg": float(rpy[2] / DEG),
                "roll_sigma_deg": float(tilt_sigma / DEG), "pitch_sigma_deg": float(tilt_sigma / DEG),
                "yaw_sigma_deg": float(yaw_sigma / DEG) if usable else 180.0})
    return out
