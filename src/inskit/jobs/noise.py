"""The filter's sensor noise from a ``[noise]`` section (datasheet units to SI).

Each sensor's bias is a first-order Gauss-Markov process (steady-state sigma
``s``, correlation time ``T``: process-noise PSD ``2 s^2 / T``) or a random
walk (rate random walk ``K``: PSD ``K^2``), Groves 2013 §14.2.7 and Brown &
Hwang 2012 ch. 2.  Datasheet units convert as (IEEE Std 952-1997 annex C):

* ARW [deg/sqrt(h)] / 60 -> rad/sqrt(s); VRW [m/s/sqrt(h)] / 60 -> m/s^2/sqrt(Hz);
* gyro RRW [deg/h/sqrt(h)]: ``K = value * (deg/h) / 60`` [rad/s/sqrt(s)]
  (a drift of ``K sqrt(t)``: ``value`` after one hour);
* accelerometer RRW [micro-g/sqrt(h)]: ``K = value * micro-g / 60`` [m/s^2/sqrt(s)];
* turn-on bias sigmas: deg/h and milli-g.
"""

from __future__ import annotations

from ..integration import SensorNoise
from ..units import DEG, DEG_PER_HOUR, MICRO_G, MILLI_G


def sensor_noise(n, measured=None) -> SensorNoise:
    """The filter's sensor noise (SI) from a ``[noise]`` section
    (:class:`~inskit.jobs.config.NoiseSection`), the white noise raised to
    what the static start measured (``measured``: ``gyro_arw_rad_sqrt_s``,
    ``accel_vrw_m_s_sqrt_s``; with ``from_static_per_axis`` the per-axis
    ``gyro_arw_axes_rad_sqrt_s`` and ``accel_vrw_axes_m_s_sqrt_s``, each
    raised to the configured floor).

    For a random-walk bias the bias "sigma" of :class:`SensorNoise` is the
    rate random walk ``K`` and its correlation time ``inf``.
    """
    arw = n.gyro_arw_deg_sqrt_h * DEG / 60.0
    vrw = n.accel_vrw_m_s_sqrt_h / 60.0
    arw_axes = vrw_axes = None
    if measured:
        if getattr(n, "from_static_per_axis", False) and "gyro_arw_axes_rad_sqrt_s" in measured:
            arw_axes = tuple(max(arw, float(v)) for v in measured["gyro_arw_axes_rad_sqrt_s"])
            vrw_axes = tuple(max(vrw, float(v)) for v in measured["accel_vrw_axes_m_s_sqrt_s"])
        arw = max(arw, measured["gyro_arw_rad_sqrt_s"])
        vrw = max(vrw, measured["accel_vrw_m_s_sqrt_s"])
    if n.gyro_bias_model == "random-walk":
        g = n.gyro_bias_rrw_deg_h_sqrt_h * DEG_PER_HOUR / 60.0
    else:
        g = n.gyro_bias_sigma_deg_h * DEG_PER_HOUR
    if n.accel_bias_model == "random-walk":
        a = n.accel_bias_rrw_ug_sqrt_h * MICRO_G / 60.0
    else:
        a = n.accel_bias_sigma_ug * MICRO_G
    return SensorNoise(arw, vrw, g, a, n.gyro_tau_s(), n.scale_factor_rw_ppm_sqrt_s * 1e-6,
                       n.time_offset_rw_s_sqrt_s, accel_bias_tau_s=n.accel_tau_s(), gyro_arw_axes=arw_axes,
                       accel_vrw_axes=vrw_axes)


def turn_on_sigmas(cfg) -> tuple[float, float]:
    """The turn-on bias sigmas per axis, ``(gyro [rad/s], accel [m/s^2])``:
    ``[noise] gyro_turn_on_bias_deg_h`` and ``accel_turn_on_bias_mg`` when
    given, else the ``[init]`` keys ``sigma_gyro_bias_deg_s`` and
    ``sigma_accel_bias_m_s2`` (the configuration refuses both spellings of
    one)."""
    n, i = cfg.noise, cfg.init
    g = i.sigma_gyro_bias_deg_s * DEG if n.gyro_turn_on_bias_deg_h is None else n.gyro_turn_on_bias_deg_h * DEG_PER_HOUR
    a = i.sigma_accel_bias_m_s2 if n.accel_turn_on_bias_mg is None else n.accel_turn_on_bias_mg * MILLI_G
    return float(g), float(a)
