"""The allan job: Allan deviation of a static log, and the ``[noise]``
section of an ``inskit navigate`` config that it implies."""

from __future__ import annotations

import numpy as np

from ..analysis.allan import allan_imu
from ..units import DEG, DEG_PER_HOUR, MICRO_G


def allan_report(imu):
    """Per-axis fits in datasheet units and the navigate ``[noise]`` keys.

    Returns
    -------
    fits : dict
        ``allan_imu`` output (for the plot).
    report : dict
        ``gyro`` and ``accel`` lists of per-axis dicts, ``navigate_noise_section``.
    """
    r = allan_imu(imu)
    gyro = [{"axis": a, "arw_deg_sqrt_h": f.white / DEG * 60, "bias_instability_deg_h": f.bias_instability / DEG_PER_HOUR,
             "gm_sigma_deg_h": f.gm_sigma / DEG_PER_HOUR, "gm_tau_s": f.gm_tau,
             "rrw_deg_h_sqrt_h": None if f.rate_random_walk is None else f.rate_random_walk / DEG_PER_HOUR * 60,
             "bias_instability_resolved": f.bias_resolved}
            for a, f in zip("xyz", r["gyro_fit"])]
    acc = [{"axis": a, "vrw_ug_sqrt_hz": f.white / MICRO_G, "vrw_m_s_sqrt_h": f.white * 60,
            "bias_instability_ug": f.bias_instability / MICRO_G, "gm_sigma_ug": f.gm_sigma / MICRO_G,
            "gm_tau_s": f.gm_tau,
            "rrw_ug_sqrt_h": None if f.rate_random_walk is None else f.rate_random_walk / MICRO_G * 60,
            "bias_instability_resolved": f.bias_resolved}
           for a, f in zip("xyz", r["accel_fit"])]

    def rms(rows, k):
        return float(np.sqrt(np.mean([x[k] ** 2 for x in rows])))

    noise = {  # the [noise] section of an `inskit navigate` config
        "gyro_arw_deg_sqrt_h": rms(gyro, "arw_deg_sqrt_h"),
        "accel_vrw_m_s_sqrt_h": rms(acc, "vrw_m_s_sqrt_h"),
        "gyro_bias_sigma_deg_h": rms(gyro, "gm_sigma_deg_h"),
        "accel_bias_sigma_ug": rms(acc, "gm_sigma_ug"),
        "bias_tau_s": float(np.exp(np.mean(np.log([x["gm_tau_s"] for x in gyro + acc])))),
    }
    notes = []
    if not all(x["bias_instability_resolved"] for x in gyro + acc):
        notes.append("no bias-instability bump within the log on some axes: their bias sigma is an upper bound "
                     "(the curve's floor) and their correlation time the log's reach; record a longer static log")
    return r, {"gyro": gyro, "accel": acc, "navigate_noise_section": noise, "notes": notes}
