"""Trajectories built from manoeuvre segments.

A trajectory is a list of segments (static, accelerate, cruise, turn, banked
turn, climb, pitch and roll manoeuvres, coning, figure eight) with vibration on
top.  Each kinematic channel (speed, heading rate, flight-path angle, roll,
pitch) is a constant plus a sum of quintic smooth steps
``S(x) = 10 x^3 - 15 x^4 + 6 x^5``: acceleration is continuous and jerk
finite, and every derivative and integral is in closed form.  Heading is the
integral of the heading rate; the velocity follows the heading and the
flight-path angle; position is integrated on the ellipsoid (RK4 on a fine
grid, cubic Hermite in between: millimetre-exact at any time).  The angular
acceleration ``omega_dot_nb_b`` comes from the channels' exact second
derivatives.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from .. import earth
from ..errors import ConfigError
from ..rotations import euler_quat
from .imu import rates_at
from .trajectory import Kinematics, kinematics_from_curvilinear


G_COORD = 9.80665  # gravity used only to set the bank angle of coordinated turns

#: how close to a pole [rad of latitude, about 6 m] a moving trajectory may come: nearer, the integration of
#: latitude and longitude is singular (:meth:`SegmentTrajectory._check_position`); at rest it may sit on the pole
POLE_MARGIN_RAD = 1e-6


def smoothstep(x):
    """Quintic smooth step and its first two derivatives and its integral."""
    x = np.clip(x, 0.0, 1.0)
    s = x**3 * (10 - 15 * x + 6 * x * x)
    ds = 30 * x * x * (1 - x) ** 2
    dds = 60 * x * (1 - x) * (1 - 2 * x)
    return s, ds, dds


def smoothstep_integral(x):
    """``int_0^x S(u) du`` for any x (0 before the step, x - 1/2 after it)."""
    xc = np.clip(x, 0.0, 1.0)
    inner = xc**6 - 3 * xc**5 + 2.5 * xc**4
    return np.where(x > 1.0, x - 0.5, np.where(x < 0.0, 0.0, inner))


@dataclass
class Channel:
    """``c0 + sum_i A_i S((t - t_i) / T_i)`` with closed-form calculus."""

    c0: float = 0.0
    steps: list = field(default_factory=list)  # (t_i, T_i, A_i)

    def add_step(self, t0, T, A):
        if A != 0.0:
            self.steps.append((float(t0), float(max(T, 1e-9)), float(A)))

    def add_pulse(self, t0, ramp, hold, A):
        """Rise by A over ``ramp``, hold ``hold``, fall back over ``ramp``."""
        self.add_step(t0, ramp, A)
        self.add_step(t0 + ramp + hold, ramp, -A)

    def value_at_end(self, t):
        return self.c0 + sum(A for t0, T, A in self.steps if t0 + T <= t + 1e-9)

    def eval(self, t):
        """Value and first two derivatives at (sorted or unsorted) times ``t``.

        Each step is evaluated only inside its window; after it the step adds
        a constant, accumulated with one cumulative sum (cost O(n + steps)
        instead of O(n * steps) on sorted times).
        """
        order = None
        if len(t) > 1 and np.any(t[1:] < t[:-1]):
            order = np.argsort(t, kind="stable")
            t = t[order]
        v = np.zeros_like(t)
        d = np.zeros_like(t)
        dd = np.zeros_like(t)
        after = np.zeros(len(t) + 1)
        for t0, T, A in self.steps:
            i0, i1 = np.searchsorted(t, (t0, t0 + T))
            if i1 > i0:
                s, ds, dds = smoothstep((t[i0:i1] - t0) / T)
                v[i0:i1] += A * s
                d[i0:i1] += A * ds / T
                dd[i0:i1] += A * dds / T**2
            after[i1] += A
        v += self.c0 + np.cumsum(after)[:-1]
        if order is not None:
            out = [np.empty_like(v) for _ in range(3)]
            for o, x in zip(out, (v, d, dd)):
                o[order] = x
            return tuple(out)
        return v, d, dd

    def integral(self, t, t_start):
        """``int_{t_start}^t`` of the channel (``t_start`` before every step)."""
        order = None
        if len(t) > 1 and np.any(t[1:] < t[:-1]):
            order = np.argsort(t, kind="stable")
            t = t[order]
        out = self.c0 * (t - t_start)
        slope = np.zeros(len(t) + 1)
        icpt = np.zeros(len(t) + 1)
        for t0, T, A in self.steps:
            i0, i1 = np.searchsorted(t, (t0, t0 + T))
            if i1 > i0:
                out[i0:i1] += A * T * smoothstep_integral((t[i0:i1] - t0) / T)
            # after the step: A T ((t - t0)/T - 1/2) = A t - A (t0 + T/2)
            slope[i1] += A
            icpt[i1] -= A * (t0 + 0.5 * T)
        out += np.cumsum(slope)[:-1] * t + np.cumsum(icpt)[:-1]
        if order is not None:
            res = np.empty_like(out)
            res[order] = out
            return res
        return out


@dataclass
class Window:
    """Smooth on/off window of an oscillation (for coning and vibration)."""

    t0: float
    t1: float
    ramp: float

    def eval(self, t):
        a, da, dda = smoothstep((t - self.t0) / self.ramp)
        b, db, ddb = smoothstep((t - self.t1 + self.ramp) / self.ramp)
        return a - b, (da - db) / self.ramp, (dda - ddb) / self.ramp**2


@dataclass
class Oscillation:
    """``w(t) A sin(2 pi f t + p)`` added to a channel (attitude or down position)."""

    target: str  # "roll", "pitch", "yaw", "down"
    amplitude: float
    frequency: float
    phase: float
    window: Window | None = None

    def eval(self, t):
        w = 2 * np.pi * self.frequency
        s, c = np.sin(w * t + self.phase), np.cos(w * t + self.phase)
        x, dx, ddx = self.amplitude * s, self.amplitude * w * c, -self.amplitude * w * w * s
        if self.window is None:
            return x, dx, ddx
        g, dg, ddg = self.window.eval(t)
        return g * x, dg * x + g * dx, ddg * x + 2 * dg * dx + g * ddx


@njit(cache=True)
def _lla_rate(lat, hgt, vn, ve, vd):
    """``d(lat, lon, h)/dt = (v_N/(R_N+h), v_E/((R_E+h) cos lat), -v_D)``
    (radii as :func:`inskit.earth.principal_radii`, WGS84)."""
    rn, re = earth.principal_radii(lat, hgt)
    return vn / rn, ve / (re * np.cos(lat)), -vd


@njit(cache=True)
def _rk4_lla(y, v_grid, v_half, h):
    """RK4 of d(lat, lon, h)/dt = (v_N/(R_N+h), v_E/((R_E+h) cos lat), -v_D)
    on a uniform grid, in place (``y[0]`` given), with the velocity known at
    the grid points and half-steps (it does not depend on position).
    Compiled: a Python loop here was half of ``simulate()`` (issue 13).
    Radii as :func:`inskit.earth.principal_radii` (WGS84).  No array is
    made inside (the stages are scalars): a compiled function that
    allocates has numba import its array module (``numba.np.arrayobj``,
    40 ms) when it is loaded from the cache."""
    n = y.shape[0]
    hh = 0.5 * h
    for i in range(n - 1):
        y0, y1, y2 = y[i, 0], y[i, 1], y[i, 2]
        a0, a1, a2 = _lla_rate(y0, y2, v_grid[i, 0], v_grid[i, 1], v_grid[i, 2])
        b0, b1, b2 = _lla_rate(y0 + hh * a0, y2 + hh * a2, v_half[i, 0], v_half[i, 1], v_half[i, 2])
        c0, c1, c2 = _lla_rate(y0 + hh * b0, y2 + hh * b2, v_half[i, 0], v_half[i, 1], v_half[i, 2])
        d0, d1, d2 = _lla_rate(y0 + h * c0, y2 + h * c2, v_grid[i + 1, 0], v_grid[i + 1, 1], v_grid[i + 1, 2])
        y[i + 1, 0] = y0 + h / 6.0 * (a0 + 2.0 * b0 + 2.0 * c0 + d0)
        y[i + 1, 1] = y1 + h / 6.0 * (a1 + 2.0 * b1 + 2.0 * c1 + d1)
        y[i + 1, 2] = y2 + h / 6.0 * (a2 + 2.0 * b2 + 2.0 * c2 + d2)


#: the channels of :class:`SegmentTrajectory`, in the order of the fused kernel's tables
_CHANNELS = ("speed", "rate_flat", "rate_bank", "gamma", "roll", "pitch")
_TARGETS = ("roll", "pitch", "yaw", "down")


@njit(cache=True)
def _smooth3(x):
    """:func:`smoothstep` of one value (clipped to [0, 1])."""
    x = min(max(x, 0.0), 1.0)
    return (x**3 * (10 - 15 * x + 6 * x * x), 30 * x * x * (1 - x) ** 2, 60 * x * (1 - x) * (1 - 2 * x))


@njit(cache=True, nogil=True)  # nogil: two threads share a long run (SegmentTrajectory._fused)
def _state_kernel(t, c0, off, t0, T, A, end, osc, h, y, dy, yaw0, gravity, lo, acc, lla_o, v_o, a_o, q_o, w_o,
                  f_o):
    """:meth:`SegmentTrajectory._state` (and, with ``rates``, :func:`.imu.rates_at`
    on it) at the sorted times ``t`` in one pass, no temporaries: the
    channels' quintic steps swept with one pointer per channel (steps sorted
    by start; ``t0 <= t < t0 + T`` inside a step, after it the step's full
    amplitude, as :meth:`Channel.eval`), the heading as
    :meth:`Channel.integral`, the position by the Hermite spline
    ``(h, y, dy)`` (:func:`_hermite_rows`), the oscillations ``osc`` (rows
    ``target, amplitude, frequency, phase, windowed, w_t0, w_t1, w_ramp``).

    Writes position ``(lat, lon, h)``, NED velocity and acceleration, the
    attitude quaternion ``q_nb`` of the Euler angles (scalar part >= 0, as
    :func:`inskit.rotations.quat_from_euler`), ``omega_ib_b`` and ``f_b``
    (gravity model coded ``gravity``) into those of ``lla_o, v_o, a_o, q_o,
    w_o, f_o`` that have rows (the others have none).  Without a spline
    (``y`` of fewer than two rows: the velocity for the position's own
    integration, :meth:`SegmentTrajectory._integrate_position`) neither the
    position (zero) nor the oscillations are evaluated: the velocity is the
    segments' alone, as the position integrates it (a ``down`` oscillation
    is added to the height afterwards), and the rates may not be asked
    for.

    The caller gives the sweep's state, as nothing is allocated inside (a
    compiled function that allocates has numba import its array module,
    ``numba.np.arrayobj``, 40 ms, when it is loaded from the cache): ``lo``
    (int64, one per channel) ``off[:-1]``, per channel the first step not
    yet ended; ``acc`` (float64, ``(6, channels)``) zeros, per channel the
    sum of the ended steps' amplitudes, the heading integral's slope and
    intercept of them (``A``, ``-A (t0 + T/2)``), the value, derivative and
    (heading rates, channels 1 and 2) integral at the time."""
    nch = c0.shape[0]
    AFTER, SLOPE, ICPT, VAL, DER, INTEG = 0, 1, 2, 3, 4, 5
    npos = y.shape[0]
    for k in range(t.shape[0]):
        tk = t[k]
        for c in range(nch):
            hi = off[c + 1]
            while lo[c] < hi and end[lo[c]] <= tk:
                j = lo[c]
                acc[AFTER, c] += A[j]
                acc[SLOPE, c] += A[j]
                acc[ICPT, c] -= A[j] * (t0[j] + 0.5 * T[j])
                lo[c] += 1
            v = 0.0
            d = 0.0
            ii = 0.0
            late = 0.0
            lslope = 0.0
            licpt = 0.0
            j = lo[c]
            while j < hi and t0[j] <= tk:
                if end[j] <= tk:    # ended out of order (steps overlapping)
                    late += A[j]
                    lslope += A[j]
                    licpt -= A[j] * (t0[j] + 0.5 * T[j])
                else:
                    x = (tk - t0[j]) / T[j]
                    s, ds, _ = _smooth3(x)
                    v += A[j] * s
                    d += A[j] * ds / T[j]
                    if c == 1 or c == 2:
                        xc = min(max(x, 0.0), 1.0)
                        ii += A[j] * T[j] * (xc**6 - 3 * xc**5 + 2.5 * xc**4)
                j += 1
            acc[VAL, c] = v + (c0[c] + (acc[AFTER, c] + late))
            acc[DER, c] = d
            if c == 1 or c == 2:
                acc[INTEG, c] = c0[c] * tk + ii + ((acc[SLOPE, c] + lslope) * tk + (acc[ICPT, c] + licpt))
        sp_, dsp = acc[VAL, 0], acc[DER, 0]
        rf, rb, drb = acc[VAL, 1], acc[VAL, 2], acc[DER, 2]
        g, dg = acc[VAL, 3], acc[DER, 3]
        psi = yaw0 + acc[INTEG, 1] + acc[INTEG, 2]
        r = rf + rb
        cg, sg, cp, spsi = np.cos(g), np.sin(g), np.cos(psi), np.sin(psi)
        vn, ve, vd = sp_ * cg * cp, sp_ * cg * spsi, -sp_ * sg
        an = dsp * cg * cp - sp_ * sg * dg * cp - sp_ * cg * spsi * r
        ae = dsp * cg * spsi - sp_ * sg * dg * spsi + sp_ * cg * cp * r
        ad = -dsp * sg - sp_ * cg * dg
        # position: the Hermite spline of the integrated (lat, lon, h)
        lat = lon = hgt = 0.0
        if npos >= 2:
            i = int(np.floor(tk / h))
            i = min(max(i, 0), npos - 2)
            u = (tk - i * h) / h
            u2 = u * u
            u3 = u2 * u
            h00, h10 = 2.0 * u3 - 3.0 * u2 + 1.0, (u3 - 2.0 * u2 + u) * h
            h01, h11 = -2.0 * u3 + 3.0 * u2, (u3 - u2) * h
            lat = h00 * y[i, 0] + h10 * dy[i, 0] + h01 * y[i + 1, 0] + h11 * dy[i + 1, 0]
            lon = h00 * y[i, 1] + h10 * dy[i, 1] + h01 * y[i + 1, 1] + h11 * dy[i + 1, 1]
            hgt = h00 * y[i, 2] + h10 * dy[i, 2] + h01 * y[i + 1, 2] + h11 * dy[i + 1, 2]
        q = sp_ * rb / G_COORD
        bank = np.arctan(q)
        dbank = (dsp * rb + sp_ * drb) / G_COORD / (1 + q**2)
        e0, e1, e2 = acc[VAL, 4] + bank, g + acc[VAL, 5], psi
        de0, de1, de2 = acc[DER, 4] + dbank, dg + acc[DER, 5], r
        for o in range(osc.shape[0] if npos >= 2 else 0):  # no spline: the segments' velocity alone
            w = 2 * np.pi * osc[o, 2]
            ph = w * tk + osc[o, 3]
            sn, cs = np.sin(ph), np.cos(ph)
            amp = osc[o, 1]
            x, dx, ddx = amp * sn, amp * w * cs, -amp * w * w * sn
            if osc[o, 4] != 0.0:
                ramp = osc[o, 7]
                a, da, dda = _smooth3((tk - osc[o, 5]) / ramp)
                b, db, ddb = _smooth3((tk - osc[o, 6] + ramp) / ramp)
                gw, dgw, ddgw = a - b, (da - db) / ramp, (dda - ddb) / ramp**2
                x, dx, ddx = gw * x, dgw * x + gw * dx, ddgw * x + 2 * dgw * dx + gw * ddx
            tg = int(osc[o, 0])
            if tg == 3:
                hgt -= x
                vd += dx
                ad += ddx
            elif tg == 0:
                e0 += x
                de0 += dx
            elif tg == 1:
                e1 += x
                de1 += dx
            else:
                e2 += x
                de2 += dx
        if w_o.shape[0] > 0:
            w_o[k, 0], w_o[k, 1], w_o[k, 2], f_o[k, 0], f_o[k, 1], f_o[k, 2] = rates_at(
                lat, hgt, vn, ve, vd, an, ae, ad, e0, e1, e2, de0, de1, de2, gravity)
        if lla_o.shape[0] > 0:
            lla_o[k, 0], lla_o[k, 1], lla_o[k, 2] = lat, lon, hgt
        if v_o.shape[0] > 0:
            v_o[k, 0], v_o[k, 1], v_o[k, 2] = vn, ve, vd
        if q_o.shape[0] > 0:
            q_o[k, 0], q_o[k, 1], q_o[k, 2], q_o[k, 3] = euler_quat(e0, e1, e2)
        if a_o.shape[0] > 0:
            a_o[k, 0], a_o[k, 1], a_o[k, 2] = an, ae, ad


class SegmentTrajectory:
    """A trajectory assembled segment by segment (see module docstring).

    Parameters
    ----------
    lla0 : (3,) latitude, longitude [rad], height [m]
    yaw0 : float
        Initial heading [rad].
    speed0 : float
        Initial speed [m/s].
    transition_s : float
        Default length of the smooth transitions [s].

    Attributes
    ----------
    label : str or None
        What the error messages call the segment being added; by default
        ``"segment N (kind)"``, N counting the segments added so far.  A
        scenario sets it to its own ``"FILE: segment N (type)"`` before each
        ``[[segment]]`` (a figure eight adds two turns, a repeated segment
        several), so that a refusal names the table of the file.
    source : str or None
        What the messages call the whole trajectory's description (a
        scenario sets its file): the start of a refusal that is no one
        segment's (a vibration's).
    """

    def __init__(self, lla0, yaw0=0.0, speed0=0.0, transition_s=2.0):
        self.lla0 = np.asarray(lla0, float)
        self.yaw0 = float(yaw0)
        self.transition = float(transition_s)
        self.speed = Channel(float(speed0))
        self.rate_flat = Channel()   # heading rate of flat (unbanked) turns
        self.rate_bank = Channel()   # heading rate of coordinated banked turns
        self.gamma = Channel()       # flight-path angle
        self.roll = Channel()
        self.pitch = Channel()
        self.osc: list[Oscillation] = []
        self.t = 0.0
        self.segments: list[dict] = []
        self.label: str | None = None
        self.source: str | None = None
        self._labels: list[str] = []  # what the messages call each entry of ``segments``
        self._pos = None

    # --- segments -------------------------------------------------------------
    def _v(self):
        return self.speed.value_at_end(self.t)

    @property
    def end_speed(self):
        """The speed [m/s] at the end of the segments added so far (where the next one starts)."""
        return self._v()

    def _where(self, kind):
        return self.label or f"segment {len(self.segments) + 1} ({kind})"

    def static(self, duration):
        if abs(self._v()) > 1e-9:
            raise ConfigError(f"{self._where('static')}: the vehicle still moves at "
                              f"{self._v():.2f} m/s; decelerate to 0 first")
        return self._advance("static", duration)

    def accelerate(self, to_speed, duration):
        if to_speed < 0:
            raise ConfigError(f"{self._where('accelerate')}: speed must be >= 0, got {to_speed}")
        self.speed.add_step(self.t, duration, to_speed - self._v())
        return self._advance("accelerate", duration)

    def cruise(self, duration):
        return self._advance("cruise", duration)

    def turn(self, angle, rate=None, radius=None, banked=False, transition=None):
        """Turn by ``angle`` [rad] at ``rate`` [rad/s] or on ``radius`` [m]."""
        tr = self.transition if transition is None else transition
        kind = "banked-turn" if banked else "turn"
        v = self._v()
        if radius is not None:
            if v <= 0:
                raise ConfigError(f"{self._where(kind)}: a turn by radius needs speed > 0")
            rate = v / radius
        if rate is None or rate <= 0:
            raise ConfigError(f"{self._where(kind)}: give rate_deg_s > 0 or radius_m > 0")
        hold = abs(angle) / rate - tr
        if hold < 0:
            raise ConfigError(f"{self._where(kind)}: {np.degrees(abs(angle)):.1f} deg at "
                              f"{np.degrees(rate):.2f} deg/s is shorter than the {tr} s transitions")
        ch = self.rate_bank if banked else self.rate_flat
        ch.add_pulse(self.t, tr, hold, np.sign(angle) * rate)
        return self._advance(kind, 2 * tr + hold)

    def climb(self, angle, duration, transition=None):
        """Climb (or descend, angle < 0) at flight-path ``angle`` [rad],
        ``|angle| < pi/2``: at 90 deg the vehicle would fly straight up, and
        beyond it backwards and upside down (and down: the height follows
        ``sin(angle)``), which no climb means."""
        tr = self.transition if transition is None else transition
        if abs(self._v()) <= 1e-9:  # as a turn by radius: at rest a flight path moves nothing (it was a silent no-op)
            raise ConfigError(f"{self._where('climb')}: the vehicle is at rest (speed 0 m/s): a climb or descent at "
                              "rest changes neither height nor attitude; accelerate first")
        if not abs(angle) < 0.5 * np.pi:
            raise ConfigError(f"{self._where('climb')}: the flight-path angle must be within (-90, 90) deg "
                              f"(negative: descend), got {np.degrees(angle):g} deg")
        hold = duration - 2 * tr
        if hold < 0:
            raise ConfigError(f"{self._where('climb')}: duration_s {duration:g} must exceed two transitions "
                              f"(2 x {tr:g} s)")
        self.gamma.add_pulse(self.t, tr, hold, angle)
        return self._advance("climb", duration)

    def attitude_pulse(self, axis, amplitude, duration):
        """Roll or pitch away by ``amplitude`` and back over ``duration``."""
        ramp = duration / 3.0
        getattr(self, axis).add_pulse(self.t, ramp, duration - 2 * ramp, amplitude)
        return self._advance(f"{axis}-manoeuvre", duration)

    def coning(self, half_angle, frequency, duration):
        win = Window(self.t, self.t + duration, min(self.transition, duration / 4))
        self.osc.append(Oscillation("roll", half_angle, frequency, np.pi / 2, win))
        self.osc.append(Oscillation("pitch", half_angle, frequency, 0.0, win))
        return self._advance("coning", duration)

    def figure_eight(self, radius):
        self.turn(2 * np.pi, radius=radius)
        self.turn(-2 * np.pi, radius=radius)
        return self

    def vibration(self, target, amplitude, frequency, phase=0.0):
        """Sinusoidal vibration over the whole run (attitude [rad] or down [m])."""
        self.osc.append(Oscillation(target, amplitude, frequency, phase, None))
        return self

    def random_vibration(self, target, rms, band_hz, rng, components=24):
        """Band-limited random vibration: a seeded sum of sinusoids whose
        amplitudes give the requested RMS (an analytic, differentiable signal)."""
        f = rng.uniform(band_hz[0], band_hz[1], components)
        ph = rng.uniform(0, 2 * np.pi, components)
        amp = rms * np.sqrt(2.0 / components)
        for fi, pi in zip(f, ph):
            self.osc.append(Oscillation(target, amp, fi, pi, None))
        return self

    def _advance(self, kind, duration):
        if duration <= 0:
            raise ConfigError(f"{self._where(kind)}: duration must be > 0")
        self.segments.append({"type": kind, "start_s": self.t, "end_s": self.t + duration})
        self._labels.append(self._where(kind))
        self.t += duration
        self._pos = None
        return self

    @property
    def duration(self):
        """Length of the simulated run [s]: the segments' total, or the
        scenario's ``duration_limit_s`` when that is shorter."""
        limit = getattr(self, "duration_limit", None)
        return self.t if limit is None else min(self.t, limit)

    # --- evaluation --------------------------------------------------------------
    def _heading(self, t):
        return self.yaw0 + self.rate_flat.integral(t, 0.0) + self.rate_bank.integral(t, 0.0)

    def _velocity(self, t):
        v, dv, _ = self.speed.eval(t)
        rf, drf, _ = self.rate_flat.eval(t)
        rb, drb, _ = self.rate_bank.eval(t)
        g, dg, _ = self.gamma.eval(t)
        psi = self._heading(t)
        r = rf + rb
        cg, sg, cp, sp = np.cos(g), np.sin(g), np.cos(psi), np.sin(psi)
        v_n = np.column_stack([v * cg * cp, v * cg * sp, -v * sg])
        a_n = np.column_stack([
            dv * cg * cp - v * sg * dg * cp - v * cg * sp * r,
            dv * cg * sp - v * sg * dg * sp + v * cg * cp * r,
            -dv * sg - v * cg * dg,
        ])
        return v_n, a_n, (v, dv, rb, drb, psi, r, g, dg)

    def _integrate_position(self):
        """RK4 of (lat, lon, h) on a 0.05 s grid, kept as Hermite splines,
        over the run's :attr:`duration` (a ``duration_limit_s`` of 20 s on
        segments of 1e7 s integrated all of them: minutes and gigabytes)."""
        h = 0.05
        n = int(np.ceil(self.duration / h)) + 2
        tg = np.arange(n) * h
        y = np.empty((n, 3))
        y[0] = self.lla0

        # the velocity does not depend on position: evaluate it for all stages at once, by the fused kernel
        # (sorted: grid points and half-steps interleaved; the NumPy channels took two thirds of this)
        t_all = np.empty(2 * n)
        t_all[0::2] = tg
        t_all[1::2] = tg + h / 2
        _, o = self._fused(t_all, ("v_n",), pos=_NO_POSITION)
        v_grid, v_half = o["v_n"][0::2], o["v_n"][1::2]

        _rk4_lla(y, v_grid, v_half, h)
        self._check_position(tg, y, v_grid)
        rn, re = earth.principal_radii(y[:, 0], y[:, 2])
        dy = np.column_stack([v_grid[:, 0] / rn, v_grid[:, 1] / (re * np.cos(y[:, 0])), -v_grid[:, 2]])
        self._pos = _UniformHermite(h, y, dy)

    def segment_at(self, t) -> str:
        """What the messages call the segment under way at time ``t`` [s]."""
        for seg, label in zip(self.segments, self._labels):
            if t <= seg["end_s"]:
                return label
        return self._labels[-1] if self._labels else "the trajectory"

    def _check_position(self, tg, y, v_grid):
        """Refuse a trajectory whose integrated position (``y``: latitude,
        longitude, height on the grid ``tg``) is no position inskit can use:
        over a pole, or moving within :data:`POLE_MARGIN_RAD` of one (the
        latitude-longitude integration is singular there: the latitude went
        past 90 deg, the longitude to 1e10 rad, and the truth was refused as
        'degrees where radians are expected?'), or a height beyond
        +-:data:`inskit.units.MAX_HEIGHT_M` (a descent into the Earth wrote a
        truth file that inskit's readers refuse), or a velocity component
        beyond +-:data:`inskit.units.MAX_SPEED_M_S` (the same)."""
        from ..units import MAX_HEIGHT_M, MAX_SPEED_M_S

        inside = tg <= self.duration + 1e-9
        lat, hgt = y[inside, 0], y[inside, 2]
        moving = np.hypot(v_grid[inside, 0], v_grid[inside, 1]) > 0.0
        pole = ~(np.abs(lat) < 0.5 * np.pi - POLE_MARGIN_RAD) & moving
        if pole.any():
            k = int(np.argmax(pole))
            which = "north" if lat[k] > 0 else "south"
            raise ConfigError(f"{self.segment_at(tg[k])}: the trajectory reaches the {which} pole at t = {tg[k]:.2f} s "
                              "while moving; the simulation integrates latitude and longitude, which cannot pass "
                              "over a pole: start further from it or head away from it")
        far = ~(np.abs(hgt) <= MAX_HEIGHT_M)
        if far.any():
            k = int(np.argmax(far))
            raise ConfigError(f"{self.segment_at(tg[k])}: the trajectory's height reaches {hgt[k]:,.0f} m at t = "
                              f"{tg[k]:.2f} s, beyond +-{MAX_HEIGHT_M / 1000:g} km of the ellipsoid (where inskit's "
                              "readers stop: the truth file would be refused); a shallower or shorter climb or "
                              "descent")
        fast = ~(np.abs(v_grid[inside]).max(axis=1) <= MAX_SPEED_M_S) if inside.any() else np.zeros(0, bool)
        if fast.any():
            k = int(np.argmax(fast))
            raise ConfigError(f"{self.segment_at(tg[k])}: a velocity component reaches "
                              f"{np.abs(v_grid[k]).max():,.0f} m/s at t = {tg[k]:.2f} s, beyond "
                              f"+-{MAX_SPEED_M_S:g} m/s (faster than the Earth's escape speed, where inskit's readers "
                              "stop: the truth file would be refused); a lower speed_m_s")
        heave = sum(abs(o.amplitude) for o in self.osc if o.target == "down")  # on top of the segments' height
        if heave and not np.abs(hgt).max() + heave <= MAX_HEIGHT_M:
            where = f"{self.source}: " if self.source else ""
            raise ConfigError(f"{where}[[vibration]]: the 'down' vibration ({heave:,.0f} m of amplitude) takes the "
                              f"height beyond +-{MAX_HEIGHT_M / 1000:g} km of the ellipsoid (the segments reach "
                              f"{np.abs(hgt).max():,.0f} m), where inskit's readers stop: the truth file would be "
                              "refused; its amplitude is in metres")

    def _state(self, t, second=False):
        """Position, NED velocity and acceleration, Euler angles and rates
        (and, with ``second``, the Euler angles' second derivatives as a
        seventh item)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if self._pos is None:
            self._integrate_position()
        v_n, a_n, (v, dv, rb, drb, psi, r, g, dg) = self._velocity(t)
        lla = self._pos(t)
        # attitude: yaw = heading, pitch = flight path + pitch channel,
        # roll = roll channel + coordinated bank angle atan(v r_bank / g)
        rl, drl, _ = self.roll.eval(t)
        pt, dpt, _ = self.pitch.eval(t)
        bank = np.arctan(v * rb / G_COORD)
        dbank = (dv * rb + v * drb) / G_COORD / (1 + (v * rb / G_COORD) ** 2)
        rpy = np.column_stack([rl + bank, g + pt, psi])
        drpy = np.column_stack([drl + dbank, dg + dpt, r])
        ddrpy = self._euler_second_derivatives(t, v, dv, rb, drb) if second else None
        for o in self.osc:
            x, dx, ddx = o.eval(t)
            if o.target == "down":
                lla[:, 2] -= x
                v_n = v_n.copy()
                v_n[:, 2] += dx
                a_n[:, 2] += ddx
            else:
                j = ("roll", "pitch", "yaw").index(o.target)
                rpy[:, j] += x
                drpy[:, j] += dx
                if second:
                    ddrpy[:, j] += ddx
        _wrap_longitude(lla)
        if second:
            return t, lla, v_n, a_n, rpy, drpy, ddrpy
        return t, lla, v_n, a_n, rpy, drpy

    def _euler_second_derivatives(self, t, v, dv, rb, drb):
        """Second time derivatives of roll, pitch, yaw before the oscillations
        (exact: every channel is a sum of quintic steps).

        Roll holds the coordinated bank ``atan(u)``, ``u = v r_bank / g``:
        ``d2/dt2 atan(u) = u'' / (1 + u^2) - 2 u u'^2 / (1 + u^2)^2``; yaw is the
        integral of the heading rates, so its second derivative is their
        first."""
        _, _, ddv = self.speed.eval(t)
        _, drf, _ = self.rate_flat.eval(t)
        _, _, ddrb = self.rate_bank.eval(t)
        _, _, ddg = self.gamma.eval(t)
        _, _, ddrl = self.roll.eval(t)
        _, _, ddpt = self.pitch.eval(t)
        u = v * rb / G_COORD
        du = (dv * rb + v * drb) / G_COORD
        ddu = (ddv * rb + 2.0 * dv * drb + v * ddrb) / G_COORD
        k = 1.0 + u * u
        ddbank = ddu / k - 2.0 * u * du * du / (k * k)
        return np.column_stack([ddrl + ddbank, ddg + ddpt, drf + drb])

    def kinematics(self, t):
        """:class:`Kinematics` at times ``t`` (any rate, any order), with the
        exact angular acceleration ``omega_dot_nb_b``."""
        return _kinematics_from_ned(*self._state(t, second=True))

    def navigation(self, t):
        """``(t, lla, v_n, q_nb)`` at times ``t``: the true navigation
        solution without the kinematics' rates (what a truth file holds;
        :func:`.imu.truth_solution` takes it when it needs no rates), the
        attitude straight from the Euler angles (scalar part >= 0); by the
        fused kernel (:func:`_state_kernel`, the formulas of :meth:`_state`)."""
        t, o = self._fused(t, ("lla", "v_n", "q_nb"))
        return t, o["lla"], o["v_n"], o["q_nb"]

    def navigation_and_rates(self, t, gravity="normal"):
        """``(t, lla, v_n, q_nb, a_n, omega_ib_b, f_b)`` at times ``t``:
        :meth:`navigation` with the NED acceleration and the true rates of
        :func:`.imu.ideal_rates` (gravity model ``gravity``), in one pass of
        the fused kernel (a truth file with rates)."""
        t, o = self._fused(t, ("lla", "v_n", "q_nb", "a_n", "w_ib", "f_b"), gravity)
        return t, o["lla"], o["v_n"], o["q_nb"], o["a_n"], o["w_ib"], o["f_b"]

    def rates(self, t, gravity="normal"):
        """True ``(omega_ib_b, f_b)`` at times ``t``: the compiled equivalent of
        ``ideal_rates(self.kinematics(t), gravity)`` (:func:`_state_kernel`:
        the trajectory and the rates in one pass; the NumPy form made some
        thirty temporaries of the two million quadrature times of an hour
        at 100 Hz, two thirds of ``inskit simulate``)."""
        _, o = self._fused(t, ("w_ib", "f_b"), gravity)
        return o["w_ib"], o["f_b"]

    def _tables(self):
        """The channels' steps and the oscillations as the arrays of
        :func:`_state_kernel`: per channel its constant, and its steps
        ``(t0, T, A, t0 + T)`` sorted by start, the channel ``c`` being rows
        ``off[c]:off[c + 1]``; one row per oscillation."""
        c0 = np.array([getattr(self, c).c0 for c in _CHANNELS], float)
        steps = [sorted(getattr(self, c).steps, key=lambda st: st[0]) for c in _CHANNELS]
        off = np.zeros(len(steps) + 1, np.int64)
        off[1:] = np.cumsum([len(st) for st in steps])
        flat = np.array([st for ch in steps for st in ch], float).reshape(-1, 3)
        t0, T, A = (np.ascontiguousarray(flat[:, j]) for j in range(3))
        osc = np.zeros((len(self.osc), 8))
        for i, o in enumerate(self.osc):
            osc[i, :4] = _TARGETS.index(o.target), o.amplitude, o.frequency, o.phase
            if o.window is not None:
                osc[i, 4:] = 1.0, o.window.t0, o.window.t1, o.window.ramp
        return c0, off, t0, T, A, t0 + T, osc

    def _fused(self, t, want, gravity="normal", pos=None):
        """:func:`_state_kernel` at times ``t`` (any order: sorted for the
        sweep, results in the order given): ``t`` and a dict of the arrays
        named in ``want`` (a subset of ``lla, v_n, a_n, q_nb, w_ib, f_b``;
        the two rates come together).  ``pos``: the position's spline,
        by default the trajectory's (integrated on first use);
        ``_NO_POSITION`` for the velocity alone."""
        from ..earth import gravity_model_code

        t = np.atleast_1d(np.asarray(t, dtype=float))
        code = gravity_model_code(gravity)
        if pos is None:
            if self._pos is None:
                self._integrate_position()
            pos = self._pos
        order = None
        ts = t
        if len(t) > 1 and np.any(t[1:] < t[:-1]):
            order = np.argsort(t, kind="stable")
            ts = t[order]
        names = ("lla", "v_n", "a_n", "q_nb", "w_ib", "f_b")
        on = set(want) | ({"w_ib", "f_b"} if {"w_ib", "f_b"} & set(want) else set())
        outs = {k: np.empty((len(ts) if k in on else 0, 4 if k == "q_nb" else 3)) for k in names}
        ts = np.ascontiguousarray(ts)
        args = (*self._tables(), pos.h, np.ascontiguousarray(pos.y), np.ascontiguousarray(pos.dy), self.yaw0, code)

        off = args[1]

        def run(a, b):  # rows a:b (each chunk sweeps the steps from the start: exact, whatever the split)
            lo, acc = off[:-1].copy(), np.zeros((6, len(off) - 1))  # the sweep's state, its own per chunk
            _state_kernel(ts[a:b], *args, lo, acc, *(o[a:b] for o in (outs[k] for k in names)))

        parts = _chunks(len(ts))
        if len(parts) == 1:
            run(*parts[0])
        else:
            from concurrent.futures import ThreadPoolExecutor

            with ThreadPoolExecutor(max_workers=len(parts) - 1, thread_name_prefix="inskit-trajectory") as pool:
                pending = [pool.submit(run, a, b) for a, b in parts[1:]]
                run(*parts[0])
                for f in pending:
                    f.result()
        res = {k: outs[k] for k in want}
        if "lla" in res:
            _wrap_longitude(res["lla"])
        if order is not None:
            for o in res.values():
                o[order] = o.copy()
        return t, res


def _wrap_longitude(lla):
    """Wrap, in place, the longitudes of ``lla`` (n, 3) that lie outside
    (-pi, pi] into it (a vehicle circling a pole, or the globe, went past a
    full turn and was refused as 'degrees where radians are expected?');
    those inside are left to the bit.  Latitudes past +-pi/2 by rounding
    (the interpolation of a trajectory at rest on a pole gave pi/2 + 2 ulp at
    some times, refused the same way) are set to +-pi/2: the trajectory
    itself never passes a pole (:meth:`SegmentTrajectory._check_position`)."""
    np.clip(lla[:, 0], -0.5 * np.pi, 0.5 * np.pi, out=lla[:, 0])
    lon = lla[:, 1]
    out = ~((lon > -np.pi) & (lon <= np.pi))
    if out.any():
        from ..rotations import wrap_angle

        lon[out] = wrap_angle(lon[out])


#: below this many times one thread evaluates the trajectory (a thread's start costs more than it saves)
_PARALLEL_MIN = 200_000


def _chunks(n):
    """Row ranges of :meth:`SegmentTrajectory._fused`: one per core (at most
    four) for ``n >= _PARALLEL_MIN``, else one."""
    import os

    k = min(4, os.cpu_count() or 1) if n >= _PARALLEL_MIN else 1
    edges = np.linspace(0, n, k + 1).astype(int)
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]


def _kinematics_from_ned(t, lla, v_n, a_n, rpy, drpy, ddrpy=None):
    """Kinematics from position, NED velocity/acceleration and Euler angles
    (with ``ddrpy``, their second derivatives, also the angular acceleration)."""
    z = np.zeros(len(t))
    kin = kinematics_from_curvilinear(t, lla[:, 0], lla[:, 1], lla[:, 2], z, z, z, z, z, z, rpy, drpy, ddrpy)
    return Kinematics(t, lla, v_n, a_n, kin.C_nb, kin.omega_nb_b, kin.omega_dot_nb_b)


class _UniformHermite:
    """Cubic Hermite interpolation of rows ``y`` with derivatives ``dy`` on
    the grid ``0, h, 2h, ...`` (what ``scipy.interpolate.CubicHermiteSpline``
    does, written out for the uniform grid: importing scipy.interpolate costs
    ``inskit simulate`` 0.7 s, a fifth of an hour's simulation).  Times
    outside the grid extrapolate the end intervals' cubics, as scipy's does."""

    def __init__(self, h, y, dy):
        self.h, self.y, self.dy = float(h), np.asarray(y, float), np.asarray(dy, float)

    def __call__(self, t):
        t = np.asarray(t, float)
        flat = np.ascontiguousarray(t.reshape(-1))
        if flat.shape[0] < _HERMITE_COMPILED_MIN:
            out = _hermite_numpy(self.h, self.y, self.dy, flat)
        else:
            out = np.empty((flat.shape[0], self.y.shape[1]))
            _hermite_rows(self.h, np.ascontiguousarray(self.y), np.ascontiguousarray(self.dy), flat, out)
        return out.reshape(t.shape + (self.y.shape[1],))


#: from this many times :class:`_UniformHermite` runs compiled (:func:`_hermite_rows`); below, NumPy, whose few
#: temporaries cost less than loading the compiled function from the cache (3-9 ms: the GNSS fixes of a
#: simulation, 3601 for an hour at 1 Hz, were its only use in ``inskit simulate``)
_HERMITE_COMPILED_MIN = 20_000


def _hermite_numpy(h, y, dy, t):
    """:func:`_hermite_rows` in NumPy: the same operations in the same order
    (the same numbers to the bit)."""
    n = y.shape[0]
    i = np.minimum(np.maximum(np.floor(t / h).astype(np.int64), 0), n - 2)
    s = (t - i * h) / h
    s2 = s * s
    s3 = s2 * s
    h00 = (2.0 * s3 - 3.0 * s2 + 1.0)[:, None]
    h10 = ((s3 - 2.0 * s2 + s) * h)[:, None]
    h01 = (-2.0 * s3 + 3.0 * s2)[:, None]
    h11 = ((s3 - s2) * h)[:, None]
    return h00 * y[i] + h10 * dy[i] + h01 * y[i + 1] + h11 * dy[i + 1]


@njit(cache=True)
def _hermite_rows(h, y, dy, t, out):
    """:class:`_UniformHermite` at every time of ``t`` into ``out``, one
    pass (the NumPy form made eight temporaries of the million quadrature
    times of an hour at 100 Hz)."""
    n = y.shape[0]
    m = y.shape[1]
    for k in range(t.shape[0]):
        i = int(np.floor(t[k] / h))
        i = min(max(i, 0), n - 2)
        s = (t[k] - i * h) / h
        s2 = s * s
        s3 = s2 * s
        h00 = 2.0 * s3 - 3.0 * s2 + 1.0
        h10 = (s3 - 2.0 * s2 + s) * h
        h01 = -2.0 * s3 + 3.0 * s2
        h11 = (s3 - s2) * h
        for j in range(m):
            out[k, j] = h00 * y[i, j] + h10 * dy[i, j] + h01 * y[i + 1, j] + h11 * dy[i + 1, j]


#: no position (:meth:`SegmentTrajectory._fused` of the velocity alone: the position's own integration)
_NO_POSITION = _UniformHermite(1.0, np.zeros((0, 3)), np.zeros((0, 3)))
