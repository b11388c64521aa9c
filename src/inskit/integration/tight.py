"""Tightly coupled measurements: pseudorange and pseudorange rate, one row
per satellite, as plug-ins of the measurement protocol.

Source 000 (SYSTEM.md §2, SOURCES-NOTES §3.5) names tight coupling the level
that keeps aiding with fewer than four satellites: every satellite's range
updates the INS error state and the receiver clock block
(:class:`~inskit.integration.blocks.ReceiverClock`) directly, with no
position fix in between.  The filter loop does not know these are GNSS: they
are rows gated one by one (``gating = "row"``) like any other plug-in.

Input is a table of corrected ranges (:class:`inskit.gnss.ranges.RangeTable`
or any object with its attributes), one row per (epoch, satellite):

``time`` (receiver time tags), ``epoch`` (int), ``sat`` (str), ``sat_pos_e``
(m, 3) at transmit time in the ECEF frame of that time, ``sat_vel_e``,
``travel_s``, ``pseudorange_m`` (corrected: ``|r_sat - r_rx| + c dt_rx``),
``sigma_pr_m``, ``range_rate_m_s`` (``d|r_sat - r_rx|/dt + c ddt_rx``, NaN
without Doppler), ``sigma_rr_m_s``.

Models (Groves 2013 §14.3.3 and §8.5.3; IS-GPS-200 §20.3.3.4.3.3.2 for the
Earth-rotation correction):

* the antenna at the measurement time, ``tau = dt`` after the IMU sample:
  ``r_a = r_imu + C_en (C_nb l_b + v_a tau)``, ``v_a = v_n + C_nb (omega x l_b)``;
* the satellite rotated into the ECEF frame of reception (Sagnac):
  ``r_s' = R3(omega_e tau_s) r_s``, ``v_s' = R3(omega_e tau_s) v_s``;
* ``rho = |r_s' - r_a| + b + d tau (+ isb for another system)``, with the
  line of sight ``u = (r_a - r_s') / |r_a - r_s'|`` (satellite to antenna):
  ``H_pos = u_n^T``, ``H_vel = tau u_n^T``, ``H_att = u_n^T [(C_nb l) x]``,
  ``H_bias = 1``, ``H_drift = tau``;
* ``rho_dot = u . (v_a,e - v_s') + d``:
  ``H_vel = u_n^T``, ``H_pos = ((v_a - v_s')^T (I - u u^T) / r)`` in NED,
  ``H_att = u_n^T [(C_nb (omega x l)) x]``, gyro terms through the lever
  arm, ``H_drift = 1``.

Each H is checked against central finite differences of its own innovation
(``tests/test_integration_tight.py``).
"""

from __future__ import annotations

import math

import numpy as np

from .. import earth
from ..errors import InputError
from ..gnss.constants import OMEGA_E_GPS as OMEGA_E_GNSS
from ..gnss.ephemeris import sagnac_rotate
from ..rotations import skew
from . import _updates as U
from .measurements import UpdateContext, _sensor_rate_columns, compiled_form_applies


def _frame_rotation(lla, C_en, w_n):
    """``d (C_en w_n) / d p_n`` (3, 3): how a vector held in NED turns in
    ECEF when the position moves by ``p_n`` metres (the NED frame rotates
    with latitude and longitude)."""
    lat = float(lla[0])
    rn, re = earth.principal_radii(lat, float(lla[2]))
    s, cl = math.sin(lat), math.cos(lat)
    so, co = math.sin(float(lla[1])), math.cos(float(lla[1]))
    north, down = C_en[:, 0], C_en[:, 2]
    d_lat = np.stack([down, np.zeros(3), -north], axis=1)
    d_lon = np.array([[s * so, -co, cl * so], [-s * co, -so, -cl * co], [0.0, 0.0, 0.0]])
    out = np.zeros((3, 3))
    out[:, 0] = d_lat @ w_n / rn
    out[:, 1] = d_lon @ w_n / (re * cl)
    return out


class _RangeRows:
    """Shared bookkeeping: the table's epochs, rotated satellite states and
    the receiver-side geometry of one epoch."""

    gating = "row"

    def __init__(self, table, *, time_offset_s=0.0, use=None, lever_arm_b=(0.0, 0.0, 0.0), sigma_scale=1.0,
                 values="pseudorange_m", sigmas="sigma_pr_m"):
        t = np.asarray(table.time, float) - float(time_offset_s)
        ep = np.asarray(table.epoch, np.int64)
        z = np.asarray(getattr(table, values), float)
        s = np.asarray(getattr(table, sigmas), float) * float(sigma_scale)
        ok = np.isfinite(z) & np.isfinite(s) & (s > 0)
        if use is not None:
            ok &= np.asarray(use, bool)
        if len(ep) > 1 and (np.diff(ep) < 0).any():
            raise InputError("the range table must be sorted by epoch")
        self.lever_arm_b = np.asarray(lever_arm_b, float)
        sel = np.nonzero(ok)[0]
        self._z, self._s = z[sel], s[sel]
        tau = np.asarray(table.travel_s, float)[sel]  # into the frame of reception (Sagnac)
        self._rs = sagnac_rotate(np.asarray(table.sat_pos_e, float)[sel], tau, OMEGA_E_GNSS)
        self._vs = sagnac_rotate(np.asarray(table.sat_vel_e, float)[sel], tau, OMEGA_E_GNSS)
        sats = np.asarray(table.sat).astype(str)[sel]
        self._system = np.array([x[:1] for x in sats])
        self._sats = sats
        ep = ep[sel]
        # one update per epoch: rows [start[i], start[i+1])
        if len(ep):
            first = np.r_[True, ep[1:] != ep[:-1]]
            self._start = np.r_[np.nonzero(first)[0], len(ep)]
            self._t = t[sel][first]
        else:
            self._start = np.zeros(1, np.int64)
            self._t = np.empty(0)
        self.systems = sorted(set(self._system.tolist()))

    def times(self):
        return self._t

    def rows(self):
        return np.arange(len(self._t))

    def satellites(self, row):
        """Names of the satellites of update ``row`` (in the order of its rows)."""
        return self._sats[self._start[row]:self._start[row + 1]].tolist()

    def row_labels(self, rows):
        """The satellite of every row of the updates ``rows`` ((m,) int), flat
        and in order: what each innovation row is (the innovation file's
        ``label``)."""
        rows = np.asarray(rows, np.int64)
        a, b = self._start[rows], self._start[rows + 1]
        n = b - a
        return self._sats[np.repeat(a - (np.cumsum(n) - n), n) + np.arange(int(n.sum()))]

    def _compiled(self, layout, kind, cls):
        """The compiled form (:mod:`._updates`): per table row the rotated
        satellite state, value, sigma and the state and aux index of its
        system's time offset (pseudoranges only), the epochs' row ranges."""
        if not compiled_form_applies(self, cls, "row") or layout.aux_slice("clock") is None:
            return None  # without a clock the Python path says what is missing
        n = len(self._z)
        data = np.empty((n, U.RANGE_WIDTH))
        data[:, 0:3], data[:, 3:6], data[:, 6], data[:, 7] = self._rs, self._vs, self._z, self._s
        data[:, 8:10] = -1.0
        if kind == U.KIND_PSEUDORANGE:
            for system in set(self._system.tolist()):
                b = f"isb_{system}"
                if b in layout and layout.aux_slice(b) is not None:
                    m = self._system == system
                    data[m, 8], data[m, 9] = layout.slice(b).start, layout.aux_slice(b).start
        k = int(np.diff(self._start).max(initial=1))
        return U.spec(kind, max(k, 1), data, self.lever_arm_b, index=self._start, per_row=True)

    def _antenna(self, ctx: UpdateContext, tau):
        """Antenna ECEF position, ECEF velocity, C_en and the lever-arm pieces."""
        C_en = earth.dcm_en(float(ctx.lla[0]), float(ctx.lla[1]))
        lev = ctx.estimate("lever", self.lever_arm_b)
        C = ctx.C_nb
        w = ctx.omega_ib_b
        wl = np.cross(w, lev)
        v_a = ctx.v_n + C @ wl
        cl = C @ lev
        arm = cl + v_a * tau
        r_a = earth.lla_to_ecef(ctx.lla) + C_en @ arm
        # d r_a / d p_n: the NED axes, plus the turn of the lever arm's NED vector with position
        self._dr_dp = C_en + _frame_rotation(ctx.lla, C_en, arm)
        self._dv_dp = _frame_rotation(ctx.lla, C_en, v_a)
        return r_a, C_en @ v_a, C_en, lev, cl, C @ wl

    def _clock_columns(self, ctx, H, sys, tau, rate):
        lay = ctx.layout
        clk = ctx.estimate("clock")
        if clk is None:
            raise InputError(f"measurement {self.name!r} needs a 'clock' block (ReceiverClock) in the state layout")
        s = lay.slice("clock")
        if rate:
            H[:, s.start + 1] = 1.0
            extra = clk[1]
        else:
            H[:, s.start] = 1.0
            H[:, s.start + 1] = tau
            extra = clk[0] + clk[1] * tau
        extra = np.full(len(sys), extra)
        if not rate:
            for system in set(sys.tolist()):
                b = f"isb_{system}"
                if b in lay:
                    m = sys == system
                    extra[m] += ctx.estimate(b)[0]
                    H[m, lay.slice(b).start] = 1.0
        return extra


class Pseudorange(_RangeRows):
    """Pseudorange of each satellite (see the module text), gated per row.

    Parameters
    ----------
    table : RangeTable-like
    time_offset_s : float
        Subtracted from the table's times to put them on the IMU time base
        (for example ``week * 604800`` when the IMU time is seconds of week).
    use : (m,) bool, optional
        Rows of the table to use (the rest are withheld).
    lever_arm_b : (3,)
        IMU-to-antenna lever arm [m], body axes, when not estimated.
    sigma_scale : float
        Multiplies the table's sigmas.
    """

    name = "pseudorange"

    def __init__(self, table, **kw):
        super().__init__(table, values="pseudorange_m", sigmas="sigma_pr_m", **kw)

    def linearize(self, ctx: UpdateContext, row):
        a, b = self._start[row], self._start[row + 1]
        if b <= a:
            return None
        lay = ctx.layout
        tau = ctx.dt
        r_a, _, C_en, lev, cl, c_wl = self._antenna(ctx, tau)
        d = r_a[None, :] - self._rs[a:b]
        rng = np.sqrt(np.einsum("ij,ij->i", d, d))
        u_e = d / rng[:, None]
        u_n = u_e @ C_en
        H = np.zeros((b - a, lay.size))
        H[:, 0:3] = u_e @ self._dr_dp
        H[:, 3:6] = u_n * tau
        H[:, 6:9] = u_n @ skew(cl + c_wl * tau)
        if lev.any() or "lever" in lay:
            # the velocity extrapolation's lever term, v_a = v + C (omega x l): tau-small, kept for exactness
            M = -ctx.C_nb @ skew(lev) * tau
            _sensor_rate_columns(H, ctx, u_n @ M)
            if "lever" in lay:
                H[:, lay.slice("lever")] = u_n @ ctx.C_nb @ (np.eye(3) + skew(ctx.omega_ib_b) * tau)
        clock = self._clock_columns(ctx, H, self._system[a:b], tau, rate=False)
        nu = rng + clock - self._z[a:b]
        return nu, H, np.diag(self._s[a:b] ** 2)

    def compiled(self, layout):
        """:meth:`linearize` in compiled form (:mod:`._updates`)."""
        return self._compiled(layout, U.KIND_PSEUDORANGE, Pseudorange)


class PseudorangeRate(_RangeRows):
    """Pseudorange rate (Doppler) of each satellite, gated per row (see the
    module text; parameters as :class:`Pseudorange`)."""

    name = "pseudorange_rate"

    def __init__(self, table, **kw):
        super().__init__(table, values="range_rate_m_s", sigmas="sigma_rr_m_s", **kw)

    def linearize(self, ctx: UpdateContext, row):
        a, b = self._start[row], self._start[row + 1]
        if b <= a:
            return None
        lay = ctx.layout
        tau = ctx.dt
        r_a, v_a_e, C_en, lev, cl, c_wl = self._antenna(ctx, tau)
        d = r_a[None, :] - self._rs[a:b]
        rng = np.sqrt(np.einsum("ij,ij->i", d, d))
        u_e = d / rng[:, None]
        dv = v_a_e[None, :] - self._vs[a:b]
        rr = np.einsum("ij,ij->i", u_e, dv)
        u_n = u_e @ C_en
        H = np.zeros((b - a, lay.size))
        # the line of sight turns with the antenna position: d rr / d r_a = (dv - u (u . dv)) / rng
        G = (dv - u_e * rr[:, None]) / rng[:, None]
        g_n = G @ C_en
        H[:, 0:3] = G @ self._dr_dp + u_e @ self._dv_dp
        H[:, 3:6] = u_n + g_n * tau
        H[:, 6:9] = u_n @ skew(c_wl) + g_n @ skew(cl + c_wl * tau)
        if lev.any() or "lever" in lay:
            C = ctx.C_nb
            _sensor_rate_columns(H, ctx, (u_n + g_n * tau) @ (-C @ skew(lev)))
            if "lever" in lay:
                W = skew(ctx.omega_ib_b)
                H[:, lay.slice("lever")] = u_n @ C @ W + g_n @ C @ (np.eye(3) + W * tau)
        clock = self._clock_columns(ctx, H, self._system[a:b], tau, rate=True)
        nu = rr + clock - self._z[a:b]
        return nu, H, np.diag(self._s[a:b] ** 2)

    def compiled(self, layout):
        """:meth:`linearize` in compiled form (:mod:`._updates`)."""
        return self._compiled(layout, U.KIND_RANGE_RATE, PseudorangeRate)


def clock_from_ranges(table, row_epoch, r_e, v_e=None, system=None):
    """Receiver clock bias [m] and drift [m/s] at one epoch from its ranges
    and a known antenna position (and velocity): the median over satellites
    (of ``system`` only, when given) of ``P - |r_s' - r|`` and of
    ``rr - u . (v - v_s')``.  Works with a single satellite (a tightly coupled
    start needs no four-satellite fix when the INS position is known).
    Returns ``(bias, drift, n_used)``; drift is NaN without Doppler or
    velocity.
    """
    m = np.asarray(table.epoch) == row_epoch
    if system is not None:
        m &= np.char.startswith(np.asarray(table.sat).astype(str), system)
    if not m.any():
        return math.nan, math.nan, 0
    tau = np.asarray(table.travel_s, float)[m]
    rs = sagnac_rotate(np.asarray(table.sat_pos_e, float)[m], tau, OMEGA_E_GNSS)
    vr = sagnac_rotate(np.asarray(table.sat_vel_e, float)[m], tau, OMEGA_E_GNSS)
    d = np.asarray(r_e, float)[None, :] - rs
    rng = np.linalg.norm(d, axis=1)
    pr = np.asarray(table.pseudorange_m, float)[m]
    ok = np.isfinite(pr)
    bias = float(np.median(pr[ok] - rng[ok])) if ok.any() else math.nan
    drift = math.nan
    if v_e is not None:
        rr = np.asarray(table.range_rate_m_s, float)[m]
        u = d / rng[:, None]
        pred = np.einsum("ij,ij->i", u, np.asarray(v_e, float)[None, :] - vr)
        okr = np.isfinite(rr)
        if okr.any():
            drift = float(np.median(rr[okr] - pred[okr]))
    return bias, drift, int(ok.sum())
