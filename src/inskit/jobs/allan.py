"""The allan job: Allan deviation of a static log, and the ``[noise]``
section of an ``inskit navigate`` config that it implies.

The section holds exactly keys of :class:`~inskit.jobs.config.NoiseSection`
(a test parses the emitted TOML into it):

* ``gyro_arw_deg_sqrt_h``, ``accel_vrw_m_s_sqrt_h``: the white noise, RMS
  over the three axes;
* per sensor a bias model.  When the fit finds no rate random walk (+1/2
  slope) on any axis: ``*_bias_model = "gauss-markov"`` with
  ``*_bias_sigma_*`` (RMS of the axes' Gauss-Markov sigmas, the bias
  instability bump) and ``*_bias_tau_s`` (geometric mean of the axes'
  correlation times, from where the bump sits).  When it finds one:
  ``*_bias_model = "random-walk"`` with ``*_bias_rrw_*`` the root of the
  mean over the axes of ``K^2 + s^2 / T`` (one filter state holds one
  process: the rate random walk ``K``, plus, on an axis whose bump is
  resolved, the random walk that gathers the bump's variance ``s^2`` over
  its correlation time ``T``; it grows past the bump at longer times, the
  safe side).

Turn-on biases are not in it: a static log cannot tell them from the
mounting and gravity (they need a multi-position calibration or a
datasheet).

A constant channel (every increment the same: a stuck axis, or one
quantised coarser than its noise) shows no noise: it is left out of the
RMS and means above (the section holds the other two axes of its sensor),
its row has ``constant = true`` and None for every figure, and a note names
it.  Three constant axes of one sensor are refused
(:func:`inskit.analysis.allan.allan_imu`).
"""

from __future__ import annotations

import math

import numpy as np

from ..analysis.allan import AllanFit, allan_imu
from ..units import DEG, DEG_PER_HOUR, MICRO_G


def _bias_section(sensor, fits, sigma_unit, rrw_unit, sigma_key, rrw_key):
    """The bias keys of one sensor from its AllanFit (SI inside; constant axes left out)."""
    fits = [f for f in fits if f is not None]
    if any(f.rate_random_walk is not None for f in fits):
        q = [(f.rate_random_walk or 0.0) ** 2 + (f.gm_sigma**2 / f.gm_tau if f.bias_resolved else 0.0)
             for f in fits]
        return {f"{sensor}_bias_model": "random-walk", rrw_key: float(np.sqrt(np.mean(q))) / rrw_unit}
    return {f"{sensor}_bias_model": "gauss-markov",
            sigma_key: float(np.sqrt(np.mean([f.gm_sigma**2 for f in fits]))) / sigma_unit,
            f"{sensor}_bias_tau_s": float(np.exp(np.mean(np.log([f.gm_tau for f in fits]))))}


def noise_section(r) -> dict:
    """The ``[noise]`` keys (datasheet units) of :func:`allan_imu` fits ``r``
    (see the module text)."""
    g, a = ([f for f in r[k] if f is not None] for k in ("gyro_fit", "accel_fit"))  # constant axes left out
    out = {"gyro_arw_deg_sqrt_h": float(np.sqrt(np.mean([f.white**2 for f in g]))) / DEG * 60.0,
           "accel_vrw_m_s_sqrt_h": float(np.sqrt(np.mean([f.white**2 for f in a]))) * 60.0}
    out.update(_bias_section("gyro", g, DEG_PER_HOUR, DEG_PER_HOUR / 60.0, "gyro_bias_sigma_deg_h",
                             "gyro_bias_rrw_deg_h_sqrt_h"))
    out.update(_bias_section("accel", a, MICRO_G, MICRO_G / 60.0, "accel_bias_sigma_ug", "accel_bias_rrw_ug_sqrt_h"))
    return out


def _toml_value(v) -> str:
    if isinstance(v, str):
        return f'"{v}"'
    if not math.isfinite(v):  # pragma: no cover - fits are finite
        raise ValueError(f"no TOML for {v}")
    s = f"{v:.5g}"
    return s if any(c in s for c in ".e") else s + ".0"


def noise_toml(section: dict, comments=()) -> str:
    """The ``[noise]`` section as TOML text, ``comments`` as ``#`` lines above it."""
    lines = [f"# {c}" for c in comments] + ["[noise]"]
    lines += [f"{k} = {_toml_value(v)}" for k, v in section.items()]
    return "\n".join(lines) + "\n"


def _axis_row(axis, fit, figures):
    """One axis of the report: ``figures(fit)`` (datasheet units), or None
    for each of them on a constant axis (``fit`` None)."""
    if fit is None:
        row = dict.fromkeys(figures(AllanFit(1.0, 1.0, 1.0, 1.0, None)))  # the keys (of any fit), all None
        return {"axis": axis, **row, "bias_instability_resolved": None, "constant": True}
    return {"axis": axis, **figures(fit), "bias_instability_resolved": fit.bias_resolved, "constant": False}


def read_static_log(path, **kw):
    """An IMU log for the Allan deviation: :func:`inskit.io.read_imu` with
    ``kw``, rate samples taken as they are (``sampled="average"``: each one
    the increment over its interval).  The Allan deviation is that of the
    samples the sensor gave; read as point samples, the trapezoid rule would
    average each with its neighbour and hide part of the white noise (4-5 %
    of the ARW and VRW of a tactical log, the shortest cluster times by a
    factor of up to sqrt(2)).  Increment files are read as they are."""
    from .. import io

    return io.read_imu(path, sampled="average", **kw)


def allan_report(imu):
    """Per-axis fits in datasheet units and the navigate ``[noise]`` keys.

    Returns
    -------
    fits : dict
        ``allan_imu`` output (for the plot).
    report : dict
        ``gyro`` and ``accel`` lists of per-axis dicts, ``noise_section``
        (the ``[noise]`` keys, :func:`noise_section`; also under its older
        name ``navigate_noise_section``), ``noise_toml`` (the same as TOML
        text) and ``notes``.  A row has ``constant`` (true for a constant
        channel, whose figures are then None: module text).
    """
    r = allan_imu(imu)
    gyro = [_axis_row(a, f, lambda f: {
                "arw_deg_sqrt_h": f.white / DEG * 60, "bias_instability_deg_h": f.bias_instability / DEG_PER_HOUR,
                "gm_sigma_deg_h": f.gm_sigma / DEG_PER_HOUR, "gm_tau_s": f.gm_tau,
                "rrw_deg_h_sqrt_h": None if f.rate_random_walk is None else f.rate_random_walk / DEG_PER_HOUR * 60})
            for a, f in zip("xyz", r["gyro_fit"])]
    acc = [_axis_row(a, f, lambda f: {
               "vrw_ug_sqrt_hz": f.white / MICRO_G, "vrw_m_s_sqrt_h": f.white * 60,
               "bias_instability_ug": f.bias_instability / MICRO_G, "gm_sigma_ug": f.gm_sigma / MICRO_G,
               "gm_tau_s": f.gm_tau,
               "rrw_ug_sqrt_h": None if f.rate_random_walk is None else f.rate_random_walk / MICRO_G * 60})
           for a, f in zip("xyz", r["accel_fit"])]
    noise = noise_section(r)
    notes = []
    for sensor, rows in (("gyro", gyro), ("accel", acc)):
        stuck = [x["axis"] for x in rows if x["constant"]]
        if stuck:
            notes.append(f"{sensor} {', '.join(stuck)}: constant over the log (every increment the same: a stuck "
                         "axis, or one quantised coarser than its noise), so no noise is measurable there; the "
                         f"{sensor} keys of the [noise] section come from the other axes")
        flat = [x["axis"] for x in rows if x["bias_instability_resolved"] is False]
        if noise[f"{sensor}_bias_model"] == "gauss-markov" and flat:
            notes.append(f"{sensor} {', '.join(flat)}: no bias-instability bump within the log, so the bias sigma "
                         "is an upper bound (the curve's floor) and the correlation time the log's reach; record "
                         "a longer static log")
        if noise[f"{sensor}_bias_model"] == "random-walk" and len(flat) < len(rows) - len(stuck):
            notes.append(f"{sensor}: the random walk also carries the bias-instability bump of the axes that show "
                         "one (its variance over its correlation time)")
    duration_h = float(imu.time[-1] - imu.time[0]) / 3600.0
    text = noise_toml(noise, [f"inskit allan: {duration_h:.2f} h static log, {len(imu)} samples"]
                      + [f"note: {n}" for n in notes])
    return r, {"gyro": gyro, "accel": acc, "noise_section": noise, "navigate_noise_section": noise,
               "noise_toml": text, "notes": notes}
