"""Overlapping Allan deviation of a static log and the fit of its noise terms.

For cluster times ``tau = m dt`` the overlapping Allan variance is
``AVAR(tau) = sum_k (theta_{k+2m} - 2 theta_{k+m} + theta_k)^2 / (2 tau^2 (N - 2m))``
on the integrated signal ``theta`` (IEEE Std 952-1997, annex C).  The noise
terms are read off the log-log slopes:

* white noise (ARW / VRW), slope -1/2: ``N = sigma(tau) sqrt(tau)``;
* bias instability, modelled as a first-order Gauss-Markov process of sigma
  ``s`` and correlation time ``Tc`` (what the filters take), whose Allan
  variance is ``s^2 Tc / tau^2 (2 tau - Tc (3 - 4 e^{-tau/Tc} + e^{-2 tau/Tc}))``:
  a bump peaking at ``0.6174 s`` for ``tau = 1.89 Tc``.  The IEEE coefficient
  reported is ``B = 0.6174 s / 0.664`` (the flicker floor of the same height);
* rate random walk, slope +1/2: ``K^2 tau / 3``, kept only when the curve's
  end rises above its low point by more than 3 relative sigmas of the last
  point (``1 / sqrt(2 (K - 1))`` for ``K`` clusters): the last cluster times
  rest on few clusters, and a flat or falling tail turns up by chance.

The three terms are fitted together (scipy ``least_squares`` on the log of the
deviation, started from the slope reading: white from the -1/2 region, bump
from the maximum after it).  The plain "minimum / 0.664" reading of B is
biased low for a Gauss-Markov bias (the minimum sits on the bump's rising
flank): -20 to -30 % in the tests, hence the model fit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..files import save_figure
from ..errors import InputError, is_number
from ..types import ImuData


def allan_deviation(increments, dt, taus_per_decade=10, min_clusters=9):
    """Overlapping Allan deviation of a rate signal given as increments.

    Parameters
    ----------
    increments : (n,) or (n, k) ndarray
        Angle or velocity increments per sample, finite.
    dt : float
        Sample interval [s], > 0.
    taus_per_decade : float
        Cluster times per decade, > 0.
    min_clusters : int
        Fewest clusters (``n - 2 m``) the longest cluster time rests on,
        >= 1: the curve reaches ``m = (n - 1) / (2 min_clusters)`` samples;
        the log must hold ``3 min_clusters`` increments at least.

    Returns
    -------
    tau : (m,) ndarray
        Cluster times [s].
    adev : (m,) or (m, k) ndarray
        Allan deviation in rate units (increment units per second).

    Raises
    ------
    InputError
        Increments that are not a finite (n,) or (n, k) array, a ``dt``
        that is no interval, ``taus_per_decade`` or ``min_clusters`` out of
        their ranges (``min_clusters = 0`` was a ZeroDivisionError, a
        negative one or ``dt <= 0`` a curve without a word), or a log too
        short for the clusters asked.
    """
    import numbers

    try:
        x = np.asarray(increments, float)
    except (TypeError, ValueError):
        raise InputError(f"increments must be an (n,) or (n, k) array of numbers, got "
                         f"{type(increments).__name__}") from None
    if x.ndim not in (1, 2):
        raise InputError(f"increments must have shape (n,) or (n, k), got {x.shape}")
    if not np.isfinite(x).all():
        i = int(np.argmax((~np.isfinite(x)).reshape(len(x), -1).any(axis=1)))
        raise InputError(f"increments hold a NaN or infinite value (row {i}): an Allan deviation of it is NaN")
    if not (is_number(dt) and 0 < dt < np.inf):
        raise InputError(f"dt must be the sample interval, a finite number > 0 [s], got {dt!r}")
    if not (is_number(taus_per_decade) and 0 < taus_per_decade < np.inf):
        raise InputError(f"taus_per_decade must be a finite number > 0, got {taus_per_decade!r}")
    if isinstance(min_clusters, bool) or not isinstance(min_clusters, numbers.Integral) or min_clusters < 1:
        raise InputError(f"min_clusters must be an integer >= 1 (the fewest clusters the longest cluster time "
                         f"rests on), got {min_clusters!r}")
    one = x.ndim == 1
    if one:
        x = x[:, None]
    n = len(x)
    if n < 3 * min_clusters:
        raise InputError(f"{n} samples are too few for an Allan deviation with min_clusters = {min_clusters} (at "
                         f"least 3 x {min_clusters} = {3 * min_clusters})")
    theta = np.vstack([np.zeros((1, x.shape[1])), np.cumsum(x, axis=0)])
    m_max = (n - 1) // min_clusters // 2 * 1
    ms = np.unique(np.round(np.logspace(0, np.log10(max(m_max, 1)), int(taus_per_decade * np.log10(max(m_max, 10))) + 1)).astype(int))
    ms = ms[(ms >= 1) & (2 * ms < n)]
    adev = np.empty((len(ms), x.shape[1]))
    for i, m in enumerate(ms):
        d = theta[2 * m:] - 2 * theta[m:-m] + theta[:-2 * m]
        tau = m * dt
        adev[i] = np.sqrt(np.mean(d * d, axis=0) / (2.0 * tau * tau))
    tau = ms * dt
    return tau, adev[:, 0] if one else adev


GM_PEAK = 0.6174
#: shortest log the Allan analysis accepts [s]
MIN_DURATION_S = 100.0
#: a channel whose increments spread by at most this fraction of their largest is constant: an ideal sensor
#: varies by rounding (3e-12 through a CSV's digits), a real one by its noise or its quantisation (a 16-bit
#: converter: 1.5e-5; a navigation-grade gyro at rest: 1e-1 of its increment)
CONSTANT_RELATIVE_SPREAD = 1e-9
#: fewest increments (samples after the first) the Allan analysis accepts: a curve of five cluster times
#: (:func:`allan_deviation` asks for 27 at least, which give one); 1 Hz over :data:`MIN_DURATION_S`
MIN_SAMPLES = 100


def _check_static(imu: ImuData, dt):
    """Refuse a log that moves: 1 s window means of the specific force must
    stay within 0.2 m/s^2 and of the rates within 1 deg/s of their median
    (vibration averages out, motion does not)."""
    w, f = imu.rates()
    k = max(1, int(round(1.0 / dt)))
    n = (len(imu) - 1) // k
    if n < 2:
        return
    fw = f[1:n * k + 1].reshape(n, k, 3).mean(axis=1)
    ww = w[1:n * k + 1].reshape(n, k, 3).mean(axis=1)
    df = np.abs(fw - np.median(fw, axis=0)).max()
    dw = np.abs(ww - np.median(ww, axis=0)).max()
    if df > 0.2 or dw > np.radians(1.0):
        # the channel that moves most, by its own limit, names the time (a spike in one gyro sample, too)
        dev = np.maximum(np.abs(fw - np.median(fw, axis=0)).max(axis=1) / 0.2,
                         np.abs(ww - np.median(ww, axis=0)).max(axis=1) / np.radians(1.0))
        i = int(np.argmax(dev))
        raise InputError(f"the log is not static (around t = {imu.time[1 + i * k]:.1f} s its 1 s mean specific "
                         f"force moves {df:.3g} m/s^2, its rate {np.degrees(dw):.3g} deg/s from the median; at rest "
                         "they stay within 0.2 m/s^2 and 1 deg/s): an Allan deviation needs the IMU at rest")


def gm_avar(tau, sigma, tc):
    """Allan variance of a first-order Gauss-Markov process."""
    x = np.asarray(tau, float) / tc
    return sigma**2 * tc / np.asarray(tau) ** 2 * (2 * np.asarray(tau) - tc * (3 - 4 * np.exp(-x) + np.exp(-2 * x)))


def model_adev(tau, white, sigma, tc, rrw):
    return np.sqrt(white**2 / tau + gm_avar(tau, sigma, tc) + rrw**2 * tau / 3.0)


@dataclass(frozen=True)
class AllanFit:
    """Noise terms fitted to one Allan-deviation curve (rate units: rad/s or m/s^2).

    Attributes
    ----------
    white : float
        White-noise density N [unit/sqrt(Hz)] (ARW or VRW).
    bias_instability : float
        IEEE coefficient B [unit] (``0.6174 gm_sigma / 0.664``).
    gm_sigma, gm_tau : float
        The Gauss-Markov bias model [unit], [s], ready for a filter.
    rate_random_walk : float or None
        K [unit/s/sqrt(Hz)]; None when the curve shows none.
    bias_resolved : bool
        False when the curve shows no bias-instability bump within the log
        (white noise all the way): ``bias_instability`` and ``gm_sigma`` are
        then upper bounds (the curve's floor), ``gm_tau`` the log's reach.
    """

    white: float
    bias_instability: float
    gm_sigma: float
    gm_tau: float
    rate_random_walk: float | None
    bias_resolved: bool = True


#: a rate random walk is kept only when the curve's end rises above its lowest
#: point after the white noise (or after the bias-instability bump) by more
#: than this many relative sigmas of the last point's Allan deviation
RRW_RISE_SIGMAS = 3.0


def _end_rises(a, i_from, tau_last, duration_s):
    """Does the curve rise at its end (a +1/2 slope), beyond what chance
    gives?  The relative sigma of an Allan deviation from ``K`` clusters is
    ``1 / sqrt(2 (K - 1))`` (IEEE Std 952-1997 annex C; ``K = T / tau``):
    0.17 at the end of a curve of :func:`allan_deviation` (``K = 18``), where
    a flat or falling tail turns up by chance by 20-40 %."""
    k = max(duration_s / tau_last, 2.0)
    rel = 1.0 / np.sqrt(2.0 * (k - 1.0))
    lo = float(np.min(a[i_from:]))
    return bool(a[-1] > lo * (1.0 + RRW_RISE_SIGMAS * rel))


def fit_allan(tau, adev, duration_s=None):
    """Fit white noise, Gauss-Markov bias instability and rate random walk.

    ``duration_s`` is the log's length (default: 18 times the longest
    cluster time, the reach of :func:`allan_deviation`); it sets how many
    clusters the longest cluster times rest on, hence how far the curve's
    end may wander by chance before a rise is read as a rate random walk
    (:data:`RRW_RISE_SIGMAS`).

    Raises
    ------
    InputError
        A curve that is zero (a constant signal: no noise to fit), not
        finite, or shorter than two points.
    """
    from scipy.optimize import least_squares

    tau = np.asarray(tau, float)
    a = np.asarray(adev, float)
    if tau.ndim != 1 or a.shape != tau.shape:
        raise InputError(f"tau and adev must be two (m,) arrays of the same length (one axis: adev[:, j]), got "
                         f"shapes {tau.shape} and {a.shape}")
    if not (np.isfinite(tau).all() and (tau > 0).all() and (np.diff(tau) > 0).all()):
        raise InputError("tau must be the cluster times [s]: finite, > 0 and increasing")
    if len(a) < 2 or not (np.isfinite(a).all() and (a > 0).all()):
        raise InputError("the Allan deviation must be positive and finite at two or more cluster times to fit "
                         "noise terms (a constant signal has none: its deviation is zero)")
    duration_s = 18.0 * float(tau[-1]) if duration_s is None else float(duration_s)
    lt, la = np.log(tau), np.log(a)
    slope = np.gradient(la, lt)
    i_min = int(np.argmin(a))
    pts = (np.arange(len(tau)) < max(i_min, 3)) & (np.abs(slope + 0.5) < 0.15)
    if pts.sum() < 2:
        pts = np.arange(len(tau)) < max(3, i_min)
    n0 = float(np.exp(np.mean(np.log(a[pts] * np.sqrt(tau[pts])))))
    i_pk = i_min + int(np.argmax(a[i_min:]))
    s0 = max(a[i_pk], a[i_min]) / GM_PEAK
    tc0 = max(tau[i_pk] / 1.89, tau[0])
    k0 = max(a[-1] * np.sqrt(3 / tau[-1]) * 0.1, 1e-30)

    lo = [np.log(n0) - 5, np.log(s0) - 8, np.log(tau[0]), np.log(k0) - 30]
    hi = [np.log(n0) + 5, np.log(s0) + 5, np.log(tau[-1] * 10), np.log(k0) + 20]
    p0 = np.clip([np.log(n0), np.log(s0), np.log(tc0), np.log(k0)], np.array(lo) + 1e-9, np.array(hi) - 1e-9)
    # first without rate random walk: a Gauss-Markov bias rises like one below
    # its correlation time, and a free K would trade off against it
    r3 = least_squares(lambda p: np.log(model_adev(tau, *np.exp(p), 0.0)) - la, p0[:3], bounds=(lo[:3], hi[:3]))
    # white noise alone: is the bump there at all?  It must halve the misfit
    # and peak inside the log, else it is white noise read as a bias (a
    # Gauss-Markov term with a tiny or huge tau mimics white noise or nothing)
    r1 = least_squares(lambda p: np.log(model_adev(tau, np.exp(p[0]), 0.0, 1.0, 0.0)) - la, p0[:1],
                       bounds=(lo[:1], hi[:1]))
    tc3 = float(np.exp(r3.x[2]))
    if not (2 * r3.cost < 0.5 * 2 * r1.cost and 1.89 * tc3 <= tau[-1] and tc3 >= 2 * tau[0]):
        w = float(np.exp(r1.x[0]))
        k_rep = None
        r2 = least_squares(lambda p: np.log(model_adev(tau, np.exp(p[0]), 0.0, 1.0, np.exp(p[1]))) - la,
                           [r1.x[0], p0[3]], bounds=([lo[0], lo[3]], [hi[0], hi[3]]))
        if 2 * r2.cost < 0.5 * 2 * r1.cost and _end_rises(a, 0, tau[-1], duration_s):  # RRW without a bump
            w, k_rep = float(np.exp(r2.x[0])), float(np.exp(r2.x[1]))
        floor = float(np.min(a))
        return AllanFit(w, floor / 0.664, floor / GM_PEAK, float(tau[-1] / 1.89), k_rep, bias_resolved=False)
    r4 = least_squares(lambda p: np.log(model_adev(tau, *np.exp(p))) - la, np.r_[r3.x, p0[3]], bounds=(lo, hi))
    i_peak = int(np.searchsorted(tau, 1.89 * tc3))
    if 2 * r4.cost < 0.5 * 2 * r3.cost and i_peak < len(tau) and _end_rises(a, i_peak, tau[-1], duration_s):
        # the RRW term must halve the misfit, and the curve must rise after the bump
        w, sg, tc, k = np.exp(r4.x)
        k_rep = float(k)
    else:
        w, sg, tc = np.exp(r3.x)
        k_rep = None
    return AllanFit(float(w), float(GM_PEAK * sg / 0.664), float(sg), float(tc), k_rep)


def allan_imu(imu: ImuData):
    """Allan deviations and fits of the six IMU axes.

    A channel whose increments are all the same, to within
    :data:`CONSTANT_RELATIVE_SPREAD` of their size (a stuck axis, one
    quantised coarser than its noise: a gyro reading 0 at rest, or an ideal
    simulated sensor varying only by rounding) has an
    Allan deviation of zero and no measurable noise: it is not fitted (its
    fit is None, its curve zero) and is named in ``constant``.  The other
    channels are fitted as usual.

    Returns
    -------
    dict with ``tau``, ``gyro_adev`` (m, 3) [rad/s], ``accel_adev`` (m, 3)
    [m/s^2], ``gyro_fit`` and ``accel_fit`` (lists of three AllanFit, None
    for a constant channel) and ``constant`` (the constant channels, e.g.
    ``["gyro z"]``).

    Raises
    ------
    InputError
        A log shorter than :data:`MIN_DURATION_S` or with fewer than
        :data:`MIN_SAMPLES` increments, irregularly sampled, moving, or whose
        three gyro (or three accelerometer) channels are all constant.
    """
    duration = float(imu.time[-1] - imu.time[0])
    if len(imu) > 1 and duration < MIN_DURATION_S:
        raise InputError(f"the log lasts {duration:.1f} s; an Allan deviation needs a static log of at least "
                         f"{MIN_DURATION_S:.0f} s (hours to see the bias instability)")
    if len(imu) - 1 < MIN_SAMPLES:  # before the time steps: one row has none
        raise InputError(f"the log has {len(imu)} sample(s); an Allan deviation needs a static log of at least "
                         f"{MIN_SAMPLES + 1} samples and {MIN_DURATION_S:.0f} s (hours to see the bias "
                         "instability)")
    dt = np.diff(imu.time)
    dtm = float(np.median(dt))
    if np.ptp(dt) > 0.01 * dtm:
        i = int(np.argmax(np.abs(dt - dtm)))
        raise InputError(f"the Allan deviation needs a regularly sampled log (the time steps vary by more than 1 %: "
                         f"a step of {dt[i]:.6g} s at t = {imu.time[i]:.3f} s, the median {dtm:.6g} s)")
    _check_static(imu, dtm)
    out = {"constant": []}
    for sensor, inc in (("gyro", imu.dtheta_b[1:]), ("accel", imu.dv_b[1:])):
        # every increment the same, to rounding: no noise (an ideal simulated IMU varied in its last bits and
        # reported an ARW of 4e-15 deg/sqrt(h) as if measured)
        flat = np.ptp(inc, axis=0) <= CONSTANT_RELATIVE_SPREAD * np.abs(inc).max(axis=0)
        if flat.all():
            raise InputError(f"{sensor} x, y, z are constant over the log (every increment the same, to "
                             f"rounding): no {sensor} noise is measurable (a stuck sensor, one quantised coarser than "
                             "its noise, or an ideal simulated one?)")
        tau, adev = allan_deviation(inc, dtm)
        adev[:, flat] = 0.0
        out["tau"] = tau
        out[f"{sensor}_adev"] = adev
        out[f"{sensor}_fit"] = [None if flat[j] else fit_allan(tau, adev[:, j], duration) for j in range(3)]
        out["constant"] += [f"{sensor} {'xyz'[j]}" for j in range(3) if flat[j]]
    return out


def plot_allan(res, path, title="Allan deviation"):
    """Log-log plot of the six curves with the fitted slopes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    from ..units import DEG_PER_HOUR, MICRO_G

    tau = res["tau"]
    fig, axes = plt.subplots(1, 2, figsize=(12, 5))
    for ax, key, fits, scale, unit in ((axes[0], "gyro_adev", res["gyro_fit"], DEG_PER_HOUR, "deg/h"),
                                       (axes[1], "accel_adev", res["accel_fit"], MICRO_G, "micro-g")):
        for j, axis in enumerate("xyz"):
            f = fits[j]
            if f is None:  # a constant channel: a zero curve has no place on a log axis
                ax.plot([], [], lw=0, label=f"{axis}: constant (no noise measurable)")
                continue
            (ln,) = ax.loglog(tau, res[key][:, j] / scale, lw=1.0, label=axis)
            ax.loglog(tau, f.white / np.sqrt(tau) / scale, ls=":", color=ln.get_color(), lw=0.8)
            ax.loglog(tau, np.sqrt(gm_avar(tau, f.gm_sigma, f.gm_tau)) / scale, ls="--", color=ln.get_color(),
                      lw=0.6)
            if f.rate_random_walk:
                ax.loglog(tau, f.rate_random_walk * np.sqrt(tau / 3) / scale, ls="-.", color=ln.get_color(), lw=0.8)
        ax.set_xlabel("cluster time tau [s]")
        ax.set_ylabel(f"Allan deviation [{unit}]")
        ax.grid(True, which="both", alpha=0.3)
        # the fitted terms named in each panel's legend (the gyro title alone named them, the
        # accelerometers' not at all), in black: the colour is the axis
        styles = [("-", 1.0, "measured"), (":", 0.8, "white-noise fit"), ("--", 0.6, "Gauss-Markov fit")]
        if any(f is not None and f.rate_random_walk for f in fits):
            styles.append(("-.", 0.8, "rate-random-walk fit"))
        h, lab = ax.get_legend_handles_labels()
        for ls, lw, name in styles:
            h.append(Line2D([], [], ls=ls, lw=lw, color="k"))
            lab.append(name)
        ax.legend(h, lab, fontsize=8, ncol=2, loc="best")
    axes[0].set_title(f"{title}: gyros")
    axes[1].set_title("accelerometers")
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
    return path
