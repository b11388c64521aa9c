"""From accelerometer-array outputs to specific force and body rate.

Two solvers, both compiled per sample (numba), both returning an
:class:`ArraySolution` whose :meth:`~ArraySolution.imu` is an
:class:`~inskit.types.ImuData` the strapdown mechanizations take unchanged.

**Closed form** (:func:`solve_closed_form`), source 003 for its six- and
ten-accelerometer layouts, with the slips corrected (SOURCES-NOTES §1.3):

* ``f_b = [(f1+f2)/2, (f3+f4)/2, (f5+f6)/2]`` (eq. 13);
* ``p^2 = (+f1-f2-f3+f4-f5+f6)/(4d)``, ``q^2 = (-f1+f2+f3-f4-f5+f6)/(4d)``,
  ``r^2 = (-f1+f2-f3+f4+f5-f6)/(4d)`` (eq. 14, correct as printed; eq. 11-12's
  pair differences are sign-flipped in the print: ``f4-f3 = 2d(p^2+r^2)``,
  ``f6-f5 = 2d(p^2+q^2)``);
* ``q_dot = (-f1-f2+f5+f6-2f7+2f8)/(4d)`` (eq. 17),
  ``p_dot = (f3+f4-f5-f6+2f9-2f10)/(4d)`` (eq. 19); ``r_dot`` is not sensed;
* signs: p and q take the sign of their integrated angular accelerations
  (eq. 17, 19); for r the source uses ``r = (f7 - f_b3 + d q_dot)/(d p)``
  (eq. 15, first line), which divides by ``p ~ 0``.  The robust rule
  (default) uses the products ``pr = (f7+f8-f_b1-f_b3)/(2d)`` and
  ``qr = (f9+f10-f_b2-f_b3)/(2d)``: ``sign(r) = sign(pr p + qr q)``, the
  least-squares choice that weights the larger of ``|p|, |q|`` most (the
  notes' "whichever of |p| and |q| is larger"), keeping the previous sign
  when both products are below the noise.  The sign of p (q) is carried by a
  complementary tracker: the previous value plus the integrated ``p_dot``,
  pulled toward the measured signed rate with time constant ``tau`` (pure
  integration, the source's reading, drifts with the accelerometer biases;
  re-anchoring every sample locks a wrong sign in when the noise on ``|p|``
  near a zero crossing exceeds ``|p_dot| dt``).  Magnitudes always come from
  eq. 14, as in the source, so the error analysis of eq. 21-42 applies.

**Least squares** (:func:`solve_least_squares`), any layout: each sample gives
``x_hat = G y`` (weighted pseudo-inverse of the design matrix; exact for every
identifiable parameter), then the rate is the maximum a-posteriori solution of
the identifiable centripetal terms ``W_ij = omega_i omega_j`` and a prior from
the previous rate plus the integrated angular acceleration (Gauss-Newton, with
backtracking; since ``W`` is even in ``omega``, the solution and its mirror
``-omega`` are then compared on the prior alone).  Without a
:class:`RateFilter` the prior is only a weak tie breaker (components whose
angular acceleration is not sensed are held from the previous sample with a
million times less weight) (the rate comes from ``W`` wherever ``W`` determines it, to rounding
error); with one, it is a small Kalman filter carrying the rate and its 3x3
covariance between samples (process noise from the angular-acceleration noise
and an angular-jerk density), which averages the sensor noise.  Layouts that
cannot observe what is asked are refused first (:func:`.layout.require`).

The global sign of the rate is unobservable at any instant (``W`` is even in
``omega``): both solvers need the initial rate's signs, ``omega0``, unless
the body starts at rest.

References
----------
SYSTEM.md §5; SOURCES-NOTES §1.3 (corrected eq. 11-19, pr/qr products), §1.2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..errors import InputError
from ..types import ImuData
from .layout import PARAMETERS, W_PAIRS, ArrayLayout, observability, require, source_index
from .model import ArrayData
from ..types import plain_number

SIGN_RULES = ("robust", "source")


@dataclass(frozen=True)
class ArraySolution:
    """Specific force and rate estimated from an array, per sample.

    Attributes
    ----------
    time : (n,) ndarray
    f_b : (n, 3) ndarray
        Specific force at the reference point [m/s^2].
    omega_ib_b : (n, 3) ndarray
        Body rate [rad/s]; magnitudes only when ``signed`` is false.
    omega_dot_ib_b : (n, 3) ndarray
        Angular acceleration [rad/s^2]; NaN for unobservable components.
    quadratic : (n, 6) ndarray
        Estimated ``p^2, q^2, r^2, pq, pr, qr`` [(rad/s)^2]; NaN where
        unobservable.
    rate_sigma : (n, 3) ndarray or None
        1-sigma of the rate from the rate filter [rad/s].
    method : str
        ``"closed-form/robust"``, ``"closed-form/source"``,
        ``"least-squares"`` or ``"least-squares+filter"``.
    layout : str
        The layout's label.
    signed : bool
        False when only rate magnitudes were asked for.
    """

    time: np.ndarray
    f_b: np.ndarray
    omega_ib_b: np.ndarray
    omega_dot_ib_b: np.ndarray
    quadratic: np.ndarray
    rate_sigma: np.ndarray | None
    method: str
    layout: str
    signed: bool = True

    def __len__(self):
        return len(self.time)

    def imu(self, integration="cubic") -> ImuData:
        """The estimates as strapdown increments, for :func:`inskit.strapdown.mechanize`.

        The estimates are point samples; each increment integrates them over
        ``(t[k-1], t[k]]``:

        * ``"cubic"`` (default): the cubic through the four samples around the
          interval, ``h (-y[k-2] + 13 y[k-1] + 13 y[k] - y[k+1]) / 24``
          (fourth order; quadratic at the two ends; trapezoid when the steps
          are irregular);
        * ``"trapezoid"``: :meth:`ImuData.from_rates` (second order).
        """
        if integration not in ("cubic", "trapezoid"):
            raise InputError(f"`integration` must be 'cubic' or 'trapezoid', got {integration!r}")
        if not self.signed:
            raise InputError("this solution holds rate magnitudes only (the layout cannot observe the signs); "
                             "no strapdown input can be made from it")
        if not np.isfinite(self.omega_ib_b).all():
            k = int(np.argmax(~np.isfinite(self.omega_ib_b).all(axis=1)))
            raise InputError(f"the rate estimate is undefined at sample {k} (t = {self.time[k]:.6f} s); "
                             "the source's sign rule divides by p there (use sign_rule='robust')")
        if integration == "trapezoid":
            return ImuData.from_rates(self.time, self.omega_ib_b, self.f_b, sampled="instant")
        return ImuData(self.time, point_increments(self.time, self.omega_ib_b),
                       point_increments(self.time, self.f_b))



class InitialRateNeeded(InputError):
    """The array alone cannot start the rates: an initial body rate
    (``omega0``) is needed.  ``reason`` is the why without the Python hint
    (the command line adds its own options')."""

    def __init__(self, reason):
        self.reason = reason
        super().__init__(f"{reason}; pass `omega0`, an approximate initial rate p, q, r [rad/s] (only its signs "
                         "are used)")


def point_increments(t, y):
    """Integrals of point samples ``y`` (``(n, 3)``) over each interval
    ``(t[k-1], t[k]]`` (row 0: zero), fourth order on uniform steps (see
    :meth:`ArraySolution.imu`)."""
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    n = len(t)
    inc = np.zeros_like(y)
    if n < 2:
        return inc
    h = np.diff(t)
    inc[1:] = 0.5 * (y[1:] + y[:-1]) * h[:, None]
    if n >= 4 and np.abs(np.diff(h)).max() <= 1e-9 * h.max():
        k = np.arange(2, n - 1)
        inc[k] = h[k - 1, None] * (-y[k - 2] + 13.0 * y[k - 1] + 13.0 * y[k] - y[k + 1]) / 24.0
        inc[1] = h[0] * (5.0 * y[0] + 8.0 * y[1] - y[2]) / 12.0
        inc[n - 1] = h[-1] * (5.0 * y[n - 1] + 8.0 * y[n - 2] - y[n - 3]) / 12.0
    return inc


@dataclass(frozen=True)
class RateFilter:
    """Settings of the small filter that carries the rate between samples.

    Attributes
    ----------
    sensor_noise : float or (m,) array_like
        White-noise sigma of one accelerometer sample [m/s^2], > 0.
    angular_jerk_psd : float
        Density of the change of angular acceleration between samples
        [(rad/s^3)^2/Hz]: covers the trapezoid's truncation and unmodelled
        motion (prediction variance ``q dt^3 / 3``).
    unobserved_accel_psd : float
        Density of an angular acceleration the layout does not sense (``r_dot``
        for the ten-accelerometer layout) [(rad/s^2)^2/Hz] (variance ``q dt``).
    initial_sigma : float
        1-sigma of ``omega0`` [rad/s].
    """

    sensor_noise: float = 1e-3
    angular_jerk_psd: float = 1.0
    unobserved_accel_psd: float = 10.0
    initial_sigma: float = 1.0

    def __post_init__(self):
        s = np.asarray(self.sensor_noise, float)
        if not (np.isfinite(s).all() and (s > 0).all()):
            raise InputError(f"`sensor_noise` must be > 0 m/s^2 (the filter weighs the sensors by it), got {s}")
        for name in ("angular_jerk_psd", "unobserved_accel_psd", "initial_sigma"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"`{name}` must be a finite number > 0, got {v}")


# --- closed form ---------------------------------------------------------------------
@njit(cache=True)
def _closed_form_kernel(t, y, d, w0, ten, robust, floor, tau, f_out, w_out, wd_out, quad_out):
    """Source 003 eq. 13, 14, 17, 19 and the sign rules, one pass (see module
    docstring).  ``ten`` false: six accelerometers, magnitudes only."""
    n = t.shape[0]
    inv4d = 1.0 / (4.0 * d)
    inv2d = 1.0 / (2.0 * d)
    nan = math.nan
    pt, qt, r_prev = w0[0], w0[1], w0[2]
    pd_prev, qd_prev = 0.0, 0.0
    for k in range(n):
        f1, f2, f3, f4, f5, f6 = y[k, 0], y[k, 1], y[k, 2], y[k, 3], y[k, 4], y[k, 5]
        fb1 = 0.5 * (f1 + f2)
        fb2 = 0.5 * (f3 + f4)
        fb3 = 0.5 * (f5 + f6)
        P2 = (f1 - f2 - f3 + f4 - f5 + f6) * inv4d
        Q2 = (-f1 + f2 + f3 - f4 - f5 + f6) * inv4d
        R2 = (-f1 + f2 - f3 + f4 + f5 - f6) * inv4d
        f_out[k, 0] = fb1
        f_out[k, 1] = fb2
        f_out[k, 2] = fb3
        quad_out[k, 0] = P2
        quad_out[k, 1] = Q2
        quad_out[k, 2] = R2
        quad_out[k, 3] = nan
        ap = math.sqrt(P2) if P2 > 0.0 else 0.0
        aq = math.sqrt(Q2) if Q2 > 0.0 else 0.0
        ar = math.sqrt(R2) if R2 > 0.0 else 0.0
        if not ten:
            w_out[k, 0] = ap
            w_out[k, 1] = aq
            w_out[k, 2] = ar
            wd_out[k, 0] = nan
            wd_out[k, 1] = nan
            wd_out[k, 2] = nan
            quad_out[k, 4] = nan
            quad_out[k, 5] = nan
            continue
        f7, f8, f9, f10 = y[k, 6], y[k, 7], y[k, 8], y[k, 9]
        qd = (-f1 - f2 + f5 + f6 - 2.0 * f7 + 2.0 * f8) * inv4d
        pd = (f3 + f4 - f5 - f6 + 2.0 * f9 - 2.0 * f10) * inv4d
        PR = (f7 + f8 - fb1 - fb3) * inv2d
        QR = (f9 + f10 - fb2 - fb3) * inv2d
        wd_out[k, 0] = pd
        wd_out[k, 1] = qd
        wd_out[k, 2] = nan
        quad_out[k, 4] = PR
        quad_out[k, 5] = QR
        if k == 0:
            pp, qp = pt, qt
            gain = 1.0
        else:
            h = t[k] - t[k - 1]
            pp = pt + 0.5 * (pd_prev + pd) * h
            qp = qt + 0.5 * (qd_prev + qd) * h
            gain = h / tau if tau > h else 1.0
        p = ap if pp >= 0.0 else -ap
        q = aq if qp >= 0.0 else -aq
        if robust:
            s = PR * p + QR * q
            if abs(s) > floor * math.sqrt(p * p + q * q) and s != 0.0:
                sr = 1.0 if s > 0.0 else -1.0
            else:
                sr = -1.0 if r_prev < 0.0 else 1.0
            pt = pp + gain * (p - pp)
            qt = qp + gain * (q - qp)
        else:
            x = (f7 - fb3 + d * qd) / (d * p) if p != 0.0 else nan  # eq. 15, first line
            sr = 1.0 if x >= 0.0 else (-1.0 if x < 0.0 else nan)
            pt, qt = pp, qp  # the source: signs from the running integral of p_dot, q_dot
        r = sr * ar
        w_out[k, 0] = p
        w_out[k, 1] = q
        w_out[k, 2] = r
        r_prev = r
        pd_prev, qd_prev = pd, qd


def _initial_rate(omega0, W0, rest_tolerance, what):
    """``omega0`` as an array, or zero after checking that the body starts at
    rest (the rate's global sign is unobservable)."""
    if omega0 is not None:
        w = np.asarray(omega0, float).reshape(-1)
        if w.shape != (3,) or not np.isfinite(w).all():
            raise InputError(f"`omega0` must be three finite numbers p, q, r [rad/s], got {plain_number(omega0)}")
        return w
    if W0 is None:
        raise InitialRateNeeded(f"{what} gets the rates by integrating angular accelerations only")
    mag = math.sqrt(max(float(W0), 0.0))
    if mag > rest_tolerance:
        raise InitialRateNeeded(f"the initial rate magnitude is {mag:.4g} rad/s: the sign of the rate vector is not "
                                "observable from accelerometers (omega and -omega give the same outputs)")
    return np.zeros(3)


def solve_closed_form(data: ArrayData, layout: ArrayLayout, *, omega0=None, sign_rule="robust", rate="signed",
                      noise_sigma=0.0, tau=0.5, rest_tolerance=0.01) -> ArraySolution:
    """Source 003's closed-form solution (eq. 13, 14, 17, 19, corrected).

    Parameters
    ----------
    data : ArrayData
        Outputs of the ten- (or, for ``rate="magnitude"``, six-) accelerometer
        layout, columns in the layout's order.
    layout : ArrayLayout
        :func:`~inskit.gyrofree.layout.ten_layout` or ``six_layout`` geometry
        (any ``d``).
    omega0 : (3,) array_like, optional
        Approximate initial rate [rad/s]; only its signs matter.  Omitted: the
        body must start at rest (``|omega| < rest_tolerance``).
    sign_rule : {"robust", "source"}
        See the module docstring.
    rate : {"signed", "magnitude"}
        ``"magnitude"`` gives ``|p|, |q|, |r|`` (all the six-accelerometer
        layout can).
    noise_sigma : float
        Per-sample accelerometer noise [m/s^2]: below three sigmas of the
        ``pr``/``qr`` products the robust rule keeps r's previous sign.
    tau : float
        Time constant [s] of the sign tracker of p and q (robust rule).
    rest_tolerance : float
        [rad/s], see ``omega0``.

    Returns
    -------
    ArraySolution

    References
    ----------
    SOURCES-NOTES §1.3, source 003 eq. 13, 14, 15, 17, 19.
    """
    if sign_rule not in SIGN_RULES:
        raise InputError(f"`sign_rule` must be one of {SIGN_RULES}, got {sign_rule!r}")
    if rate not in ("signed", "magnitude"):
        raise InputError(f"`rate` must be 'signed' or 'magnitude', got {rate!r}")
    kind = source_index(layout)
    if kind is None:
        raise InputError(f"the closed form needs the source's six- or ten-accelerometer geometry (see ten_layout); "
                         f"layout '{layout.label}' is not: use solve_least_squares")
    require(layout, rate=rate)
    data.check_layout(layout)
    if not (tau > 0 and np.isfinite(tau)):
        raise InputError(f"`tau` must be a finite number > 0 s, got {tau}")
    d = float(np.linalg.norm(layout.positions_b[0]))
    y = data.outputs
    n = len(data)
    if rate == "signed":
        f1, f2, f3, f4, f5, f6 = y[0, :6]
        W0 = (f4 - f3 + f6 - f5 + f2 - f1) / (4 * d)  # p^2 + q^2 + r^2
        w0 = _initial_rate(omega0, W0, rest_tolerance, "the closed form")
    else:
        w0 = np.zeros(3)
    f = np.empty((n, 3))
    w = np.empty((n, 3))
    wd = np.empty((n, 3))
    quad = np.empty((n, 6))
    floor = 3.0 * float(noise_sigma) * math.sqrt(3.0) / (2.0 * d)
    _closed_form_kernel(data.time, y, d, w0, kind == "ten" and rate == "signed", sign_rule == "robust", floor,
                        float(tau), f, w, wd, quad)
    return ArraySolution(data.time, f, w, wd, quad, None, f"closed-form/{sign_rule}", layout.label,
                         rate == "signed")


# --- least squares --------------------------------------------------------------------
@njit(cache=True, inline="always")
def _inv3(A, out):
    a, b, c = A[0, 0], A[0, 1], A[0, 2]
    d, e, f = A[1, 0], A[1, 1], A[1, 2]
    g, h, i = A[2, 0], A[2, 1], A[2, 2]
    c00 = e * i - f * h
    c01 = -(d * i - f * g)
    c02 = d * h - e * g
    det = a * c00 + b * c01 + c * c02
    inv = 1.0 / det
    out[0, 0] = c00 * inv
    out[1, 0] = c01 * inv
    out[2, 0] = c02 * inv
    out[0, 1] = -(b * i - c * h) * inv
    out[1, 1] = (a * i - c * g) * inv
    out[2, 1] = -(a * h - b * g) * inv
    out[0, 2] = (b * f - c * e) * inv
    out[1, 2] = -(a * f - c * d) * inv
    out[2, 2] = (a * e - b * d) * inv


@njit(cache=True, inline="always")
def _h_and_jac(w, pa, pb, res_z, wmask, r, J):
    """Residuals ``z - w_a w_b`` of the identifiable W entries and their Jacobian."""
    for j in range(6):
        a, b = pa[j], pb[j]
        if wmask[j]:
            r[j] = res_z[j] - w[a] * w[b]
        else:
            r[j] = 0.0
        J[j, 0] = 0.0
        J[j, 1] = 0.0
        J[j, 2] = 0.0
        if wmask[j]:
            J[j, a] += w[b]
            J[j, b] += w[a]


@njit(cache=True, inline="always")
def _cost(w, wp, Pinv, z, wmask, pa, pb, Rinv, r):
    c = 0.0
    for i in range(3):
        for j in range(3):
            c += (w[i] - wp[i]) * Pinv[i, j] * (w[j] - wp[j])
    for j in range(6):
        r[j] = z[j] - w[pa[j]] * w[pb[j]] if wmask[j] else 0.0
    for i in range(6):
        if wmask[i]:
            for j in range(6):
                c += r[i] * Rinv[i, j] * r[j]
    return c


@njit(cache=True)
def _lsq_kernel(t, Y, G, amask, wmask, Rinv, w0, P0, lam, filt, qa, qj, qu, tau, pa, pb,
                f_out, w_out, wd_out, quad_out, sig_out):
    """Per sample: ``x = G y``, prediction, Gauss-Newton MAP of the rate (see
    module docstring)."""
    n, m = Y.shape
    x = np.empty(12)
    z = np.empty(6)
    a = np.zeros(3)
    a_prev = np.zeros(3)
    wt = w0.copy()
    wp = np.empty(3)
    w = np.empty(3)
    wn = np.empty(3)
    step = np.empty(3)
    g = np.empty(3)
    P = P0.copy()
    Pm = np.empty((3, 3))
    Pinv = np.empty((3, 3))
    A = np.empty((3, 3))
    Ainv = np.empty((3, 3))
    r = np.empty(6)
    J = np.empty((6, 3))
    RJ = np.empty((6, 3))
    nan = math.nan
    for k in range(n):
        for i in range(12):
            s = 0.0
            for j in range(m):
                s += G[i, j] * Y[k, j]
            x[i] = s
        for i in range(3):
            f_out[k, i] = x[i]
            a[i] = x[3 + i] if amask[i] else 0.0
            wd_out[k, i] = x[3 + i] if amask[i] else nan
        for j in range(6):
            z[j] = x[6 + j]
            quad_out[k, j] = x[6 + j] if wmask[j] else nan
        h = t[k] - t[k - 1] if k > 0 else 0.0
        for i in range(3):
            wp[i] = wt[i] + (0.5 * (a_prev[i] + a[i]) * h if amask[i] else 0.0)
        # prior information
        if filt:
            for i in range(3):
                for j in range(3):
                    Pm[i, j] = P[i, j]
                if k > 0:
                    Pm[i, i] += (0.5 * qa[i] * h * h + qj * h * h * h / 3.0) if amask[i] else qu * h
            _inv3(Pm, Pinv)
        else:
            for i in range(3):
                for j in range(3):
                    Pinv[i, j] = 0.0
                Pinv[i, i] = lam if amask[i] else lam * 1e-6
        # Gauss-Newton with backtracking
        for i in range(3):
            w[i] = wp[i]
        cost = _cost(w, wp, Pinv, z, wmask, pa, pb, Rinv, r)
        for it in range(30):
            _h_and_jac(w, pa, pb, z, wmask, r, J)
            for i in range(6):
                for c in range(3):
                    s = 0.0
                    for j in range(6):
                        s += Rinv[i, j] * J[j, c]
                    RJ[i, c] = s
            for i in range(3):
                gi = 0.0
                for j in range(6):
                    gi += RJ[j, i] * r[j]
                for j in range(3):
                    gi -= Pinv[i, j] * (w[j] - wp[j])
                    s = Pinv[i, j]
                    for l in range(6):
                        s += J[l, i] * RJ[l, j]
                    A[i, j] = s
                g[i] = gi
            _inv3(A, Ainv)
            smax = 0.0
            for i in range(3):
                s = 0.0
                for j in range(3):
                    s += Ainv[i, j] * g[j]
                step[i] = s
                smax = max(smax, abs(s))
            alpha = 1.0
            accepted = False
            for _ in range(30):
                for i in range(3):
                    wn[i] = w[i] + alpha * step[i]
                cn = _cost(wn, wp, Pinv, z, wmask, pa, pb, Rinv, r)
                if cn <= cost:
                    accepted = True
                    break
                alpha *= 0.5
            if not accepted:
                break
            for i in range(3):
                w[i] = wn[i]
            cost = cn
            wmag = abs(w[0]) + abs(w[1]) + abs(w[2])
            if alpha * smax <= 1e-15 * (1.0 + wmag):
                break
        # W is even in omega: the global sign is the prior's decision alone
        for i in range(3):
            wn[i] = -w[i]
        if _cost(wn, wp, Pinv, z, wmask, pa, pb, Rinv, r) < _cost(w, wp, Pinv, z, wmask, pa, pb, Rinv, r):
            for i in range(3):
                w[i] = wn[i]
        # posterior covariance (Laplace) at the solution
        _h_and_jac(w, pa, pb, z, wmask, r, J)
        for i in range(3):
            for j in range(3):
                s = Pinv[i, j]
                for l in range(6):
                    for q in range(6):
                        s += J[l, i] * Rinv[l, q] * J[q, j]
                A[i, j] = s
        _inv3(A, Ainv)
        for i in range(3):
            w_out[k, i] = w[i]
            sig_out[k, i] = math.sqrt(Ainv[i, i]) if filt else nan
        if filt:
            for i in range(3):
                wt[i] = w[i]
                for j in range(3):
                    P[i, j] = Ainv[i, j]
        else:
            gain = 1.0 if (k == 0 or h >= tau) else h / tau
            for i in range(3):
                wt[i] = wp[i] + gain * (w[i] - wp[i])
        for i in range(3):
            a_prev[i] = a[i]


def estimator_matrix(layout: ArrayLayout, sensor_sigma=None):
    """Weighted pseudo-inverse ``G`` (``(12, m)``) with ``x_hat = G y`` and the
    covariance ``G diag(sigma^2) G^T`` of ``x_hat`` for per-sample noise
    ``sensor_sigma`` [m/s^2] (default 1: relative weights only).

    Identifiable parameters are reproduced exactly from error-free outputs;
    the others get the minimum-norm value and must not be used.
    """
    m = len(layout)
    s = np.ones(m) if sensor_sigma is None else np.broadcast_to(np.asarray(sensor_sigma, float), (m,)).copy()
    if not (np.isfinite(s).all() and (s > 0).all()):
        raise InputError("`sensor_noise` must be > 0 for every accelerometer")
    scale = np.ones(12)
    scale[3:] = layout.size
    Hs = layout.H * scale / s[:, None]
    G = (np.linalg.pinv(Hs, rcond=1e-10) * scale[:, None]) / s[None, :]
    C = (G * s[None, :] ** 2) @ G.T
    return G, C


def solve_least_squares(data: ArrayData, layout: ArrayLayout, *, omega0=None, rate_filter: RateFilter | None = None,
                        tau=0.5, rest_tolerance=0.01) -> ArraySolution:
    """General least-squares solution for any layout that observes the rate.

    Parameters
    ----------
    data : ArrayData
    layout : ArrayLayout
    omega0 : (3,) array_like, optional
        Initial rate [rad/s] (its signs fix the branch; with a filter, its
        value is the prior mean).  Omitted: the body must start at rest.
    rate_filter : RateFilter, optional
        Carry the rate with a small Kalman filter (noisy data); without it the
        prior is only a tie breaker.
    tau : float
        Time constant [s] of the tie-breaking tracker (no filter).
    rest_tolerance : float
        [rad/s], see ``omega0``.

    Returns
    -------
    ArraySolution

    Raises
    ------
    InputError
        When the layout cannot observe the specific force and the signed rate
        (the message names what it cannot observe).
    """
    obs = require(layout, rate="signed")
    data.check_layout(layout)
    if not (tau > 0 and np.isfinite(tau)):
        raise InputError(f"`tau` must be a finite number > 0 s, got {tau}")
    sigma = None if rate_filter is None else rate_filter.sensor_noise
    G, C = estimator_matrix(layout, sigma)
    amask = obs.omega_dot_mask
    wmask = obs.quadratic_mask
    idx = np.nonzero(wmask)[0]
    Rinv = np.zeros((6, 6))
    if len(idx):
        Cw = C[6:, 6:][np.ix_(idx, idx)]
        Rinv[np.ix_(idx, idx)] = np.linalg.inv(Cw)
    x0 = G @ data.outputs[0]
    W0 = x0[6] + x0[7] + x0[8] if wmask[:3].all() else None
    w0 = _initial_rate(omega0, W0, rest_tolerance, f"layout '{layout.label}'")
    # prior weight without a filter: far below the information in W at any rate above ~1e-4 rad/s
    lam = 1e-12 * max(float(np.max(np.diag(Rinv))), 1e-300) if len(idx) else 1.0
    if rate_filter is not None:
        P0 = np.eye(3) * rate_filter.initial_sigma**2
        qa = np.diag(C)[3:6].copy()
        qj, qu = rate_filter.angular_jerk_psd, rate_filter.unobserved_accel_psd
    else:
        P0 = np.eye(3)
        qa, qj, qu = np.zeros(3), 0.0, 0.0
    pa = np.array([p[0] for p in W_PAIRS], dtype=np.int64)
    pb = np.array([p[1] for p in W_PAIRS], dtype=np.int64)
    n = len(data)
    f = np.empty((n, 3))
    w = np.empty((n, 3))
    wd = np.empty((n, 3))
    quad = np.empty((n, 6))
    sig = np.empty((n, 3))
    _lsq_kernel(data.time, data.outputs, np.ascontiguousarray(G), amask, wmask, Rinv, w0, P0, lam,
                rate_filter is not None, qa, qj, qu, float(tau), pa, pb, f, w, wd, quad, sig)
    return ArraySolution(data.time, f, w, wd, quad, sig if rate_filter is not None else None,
                         "least-squares+filter" if rate_filter is not None else "least-squares", layout.label)


def solve(data: ArrayData, layout: ArrayLayout, *, method="auto", **options) -> ArraySolution:
    """Dispatch: ``method="closed-form"``, ``"least-squares"`` or ``"auto"``
    (closed form for the source's ten-accelerometer geometry, least squares
    otherwise)."""
    if method == "auto":
        method = "closed-form" if source_index(layout) == "ten" else "least-squares"
    if method == "closed-form":
        return solve_closed_form(data, layout, **options)
    if method == "least-squares":
        return solve_least_squares(data, layout, **options)
    raise InputError(f"`method` must be 'auto', 'closed-form' or 'least-squares', got {method!r}")


__all__ = [
    "PARAMETERS",
    "SIGN_RULES",
    "ArraySolution",
    "RateFilter",
    "estimator_matrix",
    "observability",
    "point_increments",
    "solve",
    "solve_closed_form",
    "solve_least_squares",
]
