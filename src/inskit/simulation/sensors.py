"""Inertial sensor error models and grade presets.

Each triad (gyro, accelerometer) has, in SI units inside
(:class:`TriadErrors`): fixed bias, turn-on bias (random per run), bias
instability (first-order Gauss-Markov), rate random walk, white noise (angle /
velocity random walk), scale factor, misalignment / non-orthogonality,
g-sensitivity (gyros), quantization and saturation.  Parameters are given in
datasheet units at the edge (:func:`triad_from_datasheet`) and converted there.

The measured output of a triad for the true mean rate ``x`` over an interval
of length ``dt`` is

``x_m = (I + diag(s) + M) x + b_fixed + b_on + b_gm(t) + b_rrw(t) + G f + n``

with ``n`` white of density ``N`` (so the increment noise has sigma
``N sqrt(dt)``), then saturated and quantized (increments rounded to the LSB
with the remainder carried).  Every random draw comes from the ``rng`` passed
in (Groves 2013 §4.4; IEEE Std 952-1997 for the Allan terms).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numba import njit

from ..errors import ConfigError
from ..types import ImuData
from ..units import DEG, DEG_PER_HOUR, G0, MICRO_G, PPM

#: ratio of the Allan-deviation floor (0.664 B) to the peak Allan deviation of
#: a first-order Gauss-Markov process of sigma s (0.6174 s at T = 1.89 tau)
GM_ALLAN_PEAK = 0.6174
BIAS_INSTABILITY_FACTOR = 0.664


@dataclass(frozen=True)
class TriadErrors:
    """Error parameters of one sensor triad, SI units.

    ``bias_instability`` is the IEEE 952 bias-instability coefficient B: the
    Gauss-Markov process gets ``sigma = 0.664 B / 0.6174`` so that its Allan
    deviation peaks at ``0.664 B``, where a flicker floor of B would sit.
    """

    fixed_bias: tuple = (0.0, 0.0, 0.0)
    turn_on_bias_sigma: float = 0.0
    bias_instability: float = 0.0
    bias_instability_tau_s: float = 300.0
    rate_random_walk: float = 0.0     # [unit/s per sqrt(s)]
    white_noise: float = 0.0           # density [unit per sqrt(Hz)]
    scale_factor: tuple = (0.0, 0.0, 0.0)
    misalignment: tuple = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))  # off-diagonal used
    g_sensitivity: float = 0.0         # gyros: [rad/s per m/s^2], isotropic
    quantization: float = 0.0          # LSB of the increment [rad or m/s]; 0 = none
    saturation: float = np.inf         # [rad/s or m/s^2]

    @property
    def gm_sigma(self):
        return BIAS_INSTABILITY_FACTOR * self.bias_instability / GM_ALLAN_PEAK


def triad_from_datasheet(kind, *, fixed_bias=(0, 0, 0), turn_on_bias=0.0, bias_instability=0.0,
                         bias_instability_tau_s=300.0, rate_random_walk=0.0, noise=0.0, scale_factor_ppm=0.0,
                         misalignment_mrad=0.0, g_sensitivity=0.0, quantization=0.0, saturation=np.inf, rng=None):
    """Triad errors from datasheet units.

    Gyros (``kind="gyro"``): biases in deg/h, ``noise`` (ARW) in deg/sqrt(h),
    ``rate_random_walk`` in deg/h/sqrt(h), ``g_sensitivity`` in deg/h/g,
    ``quantization`` in rad, ``saturation`` in deg/s.
    Accelerometers (``kind="accel"``): biases in micro-g, ``noise`` (VRW) in
    micro-g/sqrt(Hz), ``rate_random_walk`` in micro-g/sqrt(h), quantization in
    m/s, saturation in g.  Both: scale factor in ppm (the same for all axes),
    misalignment in mrad: a fixed, seeded draw of the six off-diagonal terms
    with that sigma (``rng`` required when it is non-zero).
    """
    if kind == "gyro":
        b, arw, rrw = DEG_PER_HOUR, DEG / 60.0, DEG_PER_HOUR / 60.0
        gs = g_sensitivity * DEG_PER_HOUR / G0
        sat = saturation * DEG
    elif kind == "accel":
        b, arw, rrw = MICRO_G, MICRO_G, MICRO_G / 60.0
        gs = 0.0
        sat = saturation * G0
    else:
        raise ConfigError(f"sensor kind must be 'gyro' or 'accel', got {kind!r}")
    mis = ((0.0,) * 3,) * 3
    if misalignment_mrad:
        if rng is None:
            raise ConfigError("a misalignment needs an rng to draw its fixed terms")
        m = rng.normal(0.0, misalignment_mrad * 1e-3, (3, 3))
        np.fill_diagonal(m, 0.0)
        mis = tuple(map(tuple, m))
    return TriadErrors(
        fixed_bias=tuple(np.asarray(fixed_bias, float) * b),
        turn_on_bias_sigma=turn_on_bias * b,
        bias_instability=bias_instability * b,
        bias_instability_tau_s=bias_instability_tau_s,
        rate_random_walk=rate_random_walk * rrw,
        white_noise=noise * arw,
        scale_factor=(scale_factor_ppm * PPM,) * 3,
        misalignment=mis,
        g_sensitivity=gs,
        quantization=quantization,
        saturation=sat,
    )


@dataclass(frozen=True)
class ImuErrors:
    """Gyro and accelerometer triads (``None`` parts are ideal)."""

    gyro: TriadErrors = field(default_factory=TriadErrors)
    accel: TriadErrors = field(default_factory=TriadErrors)
    source: str = "ideal"


#: Grade presets.  The figures quoted in ``source`` are the named datasheets'
#: typical values (in-run bias stability used as B); the others (turn-on bias
#: where the sheet gives only a bound, scale factors, VRW where not listed) are
#: assumptions typical of the class and are marked as such.
PRESETS = {
    "navigation": {
        "source": "Honeywell HG9900 datasheet: gyro bias <0.003 deg/h, ARW <0.002 deg/sqrt(h), accel bias "
                  "<25 ug; assumed: accel in-run 10 ug, VRW 5 ug/sqrt(Hz)",
        "gyro": dict(turn_on_bias=0.003, bias_instability=0.003, noise=0.002, scale_factor_ppm=5),
        "accel": dict(turn_on_bias=25.0, bias_instability=10.0, noise=5.0, scale_factor_ppm=100),
    },
    "tactical": {
        "source": "Honeywell HG1700-AG58 datasheet: gyro bias 1 deg/h, ARW 0.125 deg/sqrt(h), accel bias 1 mg; "
                  "assumed: in-run 0.35 deg/h and 50 ug, VRW 50 ug/sqrt(Hz)",
        "gyro": dict(turn_on_bias=1.0, bias_instability=0.35, noise=0.125, scale_factor_ppm=150),
        "accel": dict(turn_on_bias=1000.0, bias_instability=50.0, noise=50.0, scale_factor_ppm=300),
    },
    "industrial-mems": {
        "source": "Analog Devices ADIS16495-1 datasheet: gyro in-run 0.8 deg/h, ARW 0.09 deg/sqrt(h), accel "
                  "in-run 3.2 ug, VRW 0.008 m/s/sqrt(h); assumed: turn-on 200 deg/h and 1 mg, scale 500 ppm",
        "gyro": dict(turn_on_bias=200.0, bias_instability=0.8, noise=0.09, scale_factor_ppm=500),
        "accel": dict(turn_on_bias=1000.0, bias_instability=3.2, noise=13.6, scale_factor_ppm=500),
    },
    "consumer-mems": {
        "source": "Bosch BMI160 datasheet: gyro noise 0.007 deg/s/sqrt(Hz), zero-rate offset +-3 deg/s "
                  "(sigma 1 deg/s used), accel noise 180 ug/sqrt(Hz), zero-g offset +-40 mg; assumed: in-run "
                  "20 deg/h and 100 ug, scale 1 %",
        "gyro": dict(turn_on_bias=3600.0, bias_instability=20.0, noise=0.42, scale_factor_ppm=10000,
                     saturation=2000.0),
        "accel": dict(turn_on_bias=40000.0, bias_instability=100.0, noise=180.0, scale_factor_ppm=10000,
                      saturation=16.0),
    },
}


@dataclass(frozen=True)
class TermRule:
    """A datasheet term of a triad that a preset's overrides may set: its
    units (gyro, accelerometer; None: the term does not exist for that
    sensor) and the values it takes."""

    gyro_unit: str
    accel_unit: str | None
    takes: str   # "3 numbers" (any sign), ">= 0", "> 0", "> -1e6" (ppm: above -100 %), "any"
    meaning: str

    def problem(self, value) -> str | None:
        """What is wrong with ``value`` (datasheet units), in words; None: nothing."""
        import math

        def number(x):
            return not isinstance(x, bool) and isinstance(x, (int, float, np.integer, np.floating)) and math.isfinite(x)

        if self.takes == "3 numbers":
            if not (isinstance(value, (list, tuple, np.ndarray)) and len(value) == 3 and all(map(number, value))):
                return "expected three finite numbers [x, y, z]"
            return None
        if not number(value):
            return "expected one finite number"
        v = float(value)
        ok = {">= 0": v >= 0, "> 0": v > 0, "> -1e6": v > -1e6, "any": True}[self.takes]
        return None if ok else f"must be {self.takes}"


#: the datasheet terms a preset's triads take as overrides (``[imu] gyro = {...}`` and ``accel = {...}`` of a
#: scenario, :func:`preset`): one table for the checks and the documentation (docs/config.md)
TRIAD_TERMS = {
    "fixed_bias": TermRule("deg/h", "micro-g", "3 numbers", "constant bias per axis [x, y, z]"),
    "turn_on_bias": TermRule("deg/h", "micro-g", ">= 0", "turn-on bias, 1 sigma per axis, drawn per run"),
    "bias_instability": TermRule("deg/h", "micro-g", ">= 0", "bias instability B: a Gauss-Markov bias whose "
                                 "Allan deviation peaks at 0.664 B"),
    "bias_instability_tau_s": TermRule("s", "s", "> 0", "correlation time of that Gauss-Markov bias"),
    "rate_random_walk": TermRule("deg/h/sqrt(h)", "micro-g/sqrt(h)", ">= 0", "rate random walk of the bias"),
    "noise": TermRule("deg/sqrt(h)", "micro-g/sqrt(Hz)", ">= 0", "white noise: angle / velocity random walk"),
    "scale_factor_ppm": TermRule("ppm", "ppm", "> -1e6", "scale-factor error, the same on every axis"),
    "g_sensitivity": TermRule("deg/h/g", None, "any", "bias per g of specific force"),
    "quantization": TermRule("rad", "m/s", ">= 0", "LSB of the increments, 0: none"),
    "saturation": TermRule("deg/s", "g", "> 0", "output limit: larger readings clip"),
}


def triad_terms_problem(kind, terms) -> str | None:
    """What is wrong with the overrides ``terms`` (a dict) of the ``kind``
    (``"gyro"`` or ``"accel"``) triad, in words naming the key (None:
    nothing): an unknown key, a term the sensor has not
    (``g_sensitivity`` of an accelerometer), or a value outside
    :data:`TRIAD_TERMS`' rule (a negative sigma, a correlation time of 0,
    a bias of two axes)."""
    if not isinstance(terms, dict):
        return f"expected a table of error terms, got {type(terms).__name__} {terms!r}"
    for key, value in terms.items():
        rule = TRIAD_TERMS.get(key)
        unit = None if rule is None else (rule.gyro_unit if kind == "gyro" else rule.accel_unit)
        if unit is None:
            known = [k for k, r in TRIAD_TERMS.items() if (r.gyro_unit if kind == "gyro" else r.accel_unit)]
            what = "an accelerometer has no g-sensitivity" if key in TRIAD_TERMS else "unknown error term"
            sensor = "a gyro" if kind == "gyro" else "an accelerometer"
            return f"{key}: {what}; the terms of {sensor} are {', '.join(known)}"
        problem = rule.problem(value)
        if problem:
            return f"{key} = {value!r}: {problem} [{unit}] ({rule.meaning})"
    return None


def preset(name, **overrides) -> ImuErrors:
    """The :class:`ImuErrors` of a grade preset; ``overrides`` replace
    datasheet-unit fields: ``gyro={"noise": 0.1}``, ``accel={...}``
    (:data:`TRIAD_TERMS`: their units and values; anything else is a
    ConfigError naming the key)."""
    if name not in PRESETS:
        raise ConfigError(f"unknown IMU grade {name!r}; choose one of {', '.join(PRESETS)}")
    for kind in overrides:
        if kind not in ("gyro", "accel"):
            raise ConfigError(f"preset: unknown sensor {kind!r}; give gyro={{...}} and/or accel={{...}}")
    for kind in ("gyro", "accel"):
        problem = triad_terms_problem(kind, overrides.get(kind, {}))
        if problem:
            raise ConfigError(f"imu.{kind}: {problem}")
    p = PRESETS[name]
    g = {**p["gyro"], **overrides.get("gyro", {})}
    a = {**p["accel"], **overrides.get("accel", {})}
    if g.get("misalignment_mrad") or a.get("misalignment_mrad"):
        raise ConfigError("misalignment needs a seeded draw: use triad_from_datasheet with rng")
    return ImuErrors(triad_from_datasheet("gyro", **g), triad_from_datasheet("accel", **a), p["source"])


def _gauss_markov(n, dt, sigma, tau, rng):
    """Stationary first-order Gauss-Markov sequence, ``(n, 3)``."""
    if sigma <= 0:
        return np.zeros((n, 3))
    phi = np.exp(-dt / tau)
    w = rng.standard_normal((n, 3)) * sigma * np.sqrt(1.0 - phi * phi)
    w[0] = rng.standard_normal(3) * sigma
    return _ar1(w, phi)


def _ar1(w, phi):
    """``y[k] = w[k] + phi y[k-1]``, ``y[0] = w[0]``, along axis 0 (what
    ``scipy.signal.lfilter([1], [1, -phi], w, axis=0)`` gives, compiled:
    importing scipy.signal alone took 1.7 s of every ``inskit simulate``),
    ``w`` of shape ``(n, m)``."""
    w = np.ascontiguousarray(w, dtype=float)
    y = np.empty_like(w)
    _ar1_into(w, phi, y)
    return y


@njit(cache=True)
def _ar1_into(w, phi, y):
    """:func:`_ar1` into ``y`` (no array made inside: a compiled function
    that allocates has numba import its array module, 40 ms, when it is
    loaded from the cache)."""
    for j in range(w.shape[1]):
        y[0, j] = w[0, j]
    for k in range(1, w.shape[0]):
        for j in range(w.shape[1]):
            y[k, j] = w[k, j] + phi * y[k - 1, j]


def _quantize(inc, lsb):
    """Round increments to ``lsb`` carrying the remainder (no drift)."""
    if lsb <= 0:
        return inc
    c = np.round(np.cumsum(inc, axis=0) / lsb) * lsb
    out = np.empty_like(inc)
    out[0] = c[0]
    out[1:] = np.diff(c, axis=0)
    return out


def _rows_times(x, M):
    """``x @ M.T`` for ``x`` of shape ``(n, 3)`` and ``M`` of ``(3, 3)``: each
    row of ``x`` times the matrix, as three column products (not BLAS: its
    threads took 130 ms for the 360 001 rows of an hour at 100 Hz on a busy
    two-core machine, where these take 5 ms).  For a diagonal ``M`` (scale
    factors without misalignment: the presets) one product per element, the
    very numbers of ``x @ M.T`` (but for the sign of a zero)."""
    d = np.diag(M)
    if not np.any(M - np.diag(d)):
        return x * d
    return x[:, 0:1] * M[:, 0] + x[:, 1:2] * M[:, 1] + x[:, 2:3] * M[:, 2]


def _triad(x, dt, t, e: TriadErrors, rng, f=None):
    """Measured mean rates of one triad (see module docstring)."""
    n = len(x)
    M = np.eye(3) + np.diag(e.scale_factor) + np.asarray(e.misalignment, float) * (1 - np.eye(3))
    y = _rows_times(x, M)
    bias = np.asarray(e.fixed_bias, float) + rng.standard_normal(3) * e.turn_on_bias_sigma
    series = np.tile(bias, (n, 1))
    if e.bias_instability > 0:
        dtm = float(np.median(dt))
        series += _gauss_markov(n, dtm, e.gm_sigma, e.bias_instability_tau_s, rng)
    if e.rate_random_walk > 0:
        series += np.cumsum(rng.standard_normal((n, 3)) * e.rate_random_walk * np.sqrt(dt)[:, None], axis=0)
    y += series
    if f is not None and e.g_sensitivity:
        y += e.g_sensitivity * f
    if e.white_noise > 0:
        y += rng.standard_normal((n, 3)) * (e.white_noise / np.sqrt(dt))[:, None]
    if np.isfinite(e.saturation):
        y = np.clip(y, -e.saturation, e.saturation)
    return y, bias, series


def apply_imu_errors(imu: ImuData, errors: ImuErrors, rng) -> tuple[ImuData, dict]:
    """Corrupt ideal increments with an error model.

    Returns
    -------
    imu : ImuData
        Measured increments (row 0 stays zero: the initial epoch).
    draws : dict
        The per-run random draws for tests and reports: ``gyro_turn_on_bias``,
        ``accel_turn_on_bias`` (3,) and the true additive bias over time,
        ``gyro_bias``, ``accel_bias`` (n, 3) (fixed + turn-on + Gauss-Markov +
        rate random walk, applied over the interval ending at each row);
        ``gyro_clipped_rows``, ``accel_clipped_rows``: rows (past the
        initial epoch) with a reading clipped at the triad's saturation, and
        ``gyro_peak``, ``accel_peak``: the largest true rate [rad/s] and
        specific force [m/s^2] component of the run.
    """
    t = imu.time
    dt = np.empty_like(t)
    dt[1:] = np.diff(t)
    dt[0] = dt[1] if len(t) > 1 else 1.0
    w, f = imu.dtheta_b / dt[:, None], imu.dv_b / dt[:, None]
    wm, bg, bg_series = _triad(w, dt, t, errors.gyro, rng, f=f)
    fm, ba, ba_series = _triad(f, dt, t, errors.accel, rng)
    dth = _quantize(wm * dt[:, None], errors.gyro.quantization)
    dv = _quantize(fm * dt[:, None], errors.accel.quantization)
    dth[0] = 0.0
    dv[0] = 0.0
    clipped = {f"{name}_clipped_rows": int((np.abs(y[1:]) >= e.saturation).any(axis=1).sum())
               if np.isfinite(e.saturation) else 0
               for name, y, e in (("gyro", wm, errors.gyro), ("accel", fm, errors.accel))}
    return ImuData(t, dth, dv), {"gyro_turn_on_bias": bg, "accel_turn_on_bias": ba,
                                 "gyro_bias": bg_series, "accel_bias": ba_series, **clipped,
                                 "gyro_peak": float(np.abs(w[1:]).max(initial=0.0)),
                                 "accel_peak": float(np.abs(f[1:]).max(initial=0.0))}


__all__ = ["ImuErrors", "PRESETS", "TRIAD_TERMS", "TriadErrors", "apply_imu_errors", "preset", "replace",
           "triad_from_datasheet", "triad_terms_problem"]
