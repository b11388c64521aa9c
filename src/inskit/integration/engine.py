"""The integration filter loop: compiled propagation and updates, plug-ins.

Schemes (SYSTEM.md §2 table 2-2 and §3, source 004 figures 1 and 2):

* ``"closed"``: loosely coupled, closed loop.  After every update the error
  estimates are fed back into the mechanization (position, velocity,
  attitude) and into every block's estimate (biases, scale factors, lever
  arm, ...: each block says how), and the error state is reset to zero.  The
  correction survives an outage.
* ``"open"``: loosely coupled, open loop.  The INS runs free on the raw
  sensors; the filter's error estimate is propagated and subtracted from the
  INS output only; nothing is fed back.

The uncoupled scheme ("GNSS resets the INS") has no filter: it is the plain
function :func:`inskit.integration.uncoupled.run_uncoupled`.

The loop knows the layout only through :class:`StateLayout` and the
measurements only through the protocol of :mod:`.measurements`.  In the
closed loop, the measurements that have a compiled form (GNSS position and
velocity, ZUPT, NHC, odometer, GNSS speed and course, pseudorange and range
rate) are updated inside the compiled loop of :mod:`._updates`, which hands
the items of every other plug-in back to :func:`run_filter`'s Python path on
the same state; the open loop, blocks with their own feedback and
``FilterSettings(compiled_updates=False)`` run every update in Python (the
same results to rounding).

Streaming: the run goes in segments of :data:`SEGMENT_ROWS` IMU rows (a node
without a measurement ends each).  Given a ``sink``, :func:`run_filter` hands
each finished segment (every row's state, estimates and sigmas) to it and
keeps only the rows asked for, so its memory grows only by the IMU log it is given;
without one it keeps every row.  Both make the same nodes, so both give the
same numbers.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .. import earth
from ..errors import InputError
from ..filters.kalman import FilterDivergence, check_covariance, chi2_threshold, gate_rows, joseph_update
from ..rotations import dcm_from_quat
from ..types import ImuData, NavSolution, NavState
from . import _kernel as K
from . import _updates as U
from .blocks import InitialUncertainty, SensorNoise, StateBlock, ins_blocks
from .layout import StateLayout
from .measurements import UpdateContext

SCHEMES = ("closed", "open")
_default_feedback = StateBlock.feedback
#: blocks whose sigmas go into the named solution columns by default
NAV_SIGMA_BLOCKS = ("pos", "vel", "att")
#: IMU rows per segment of a run (see the module text): 5.5 min at 200 Hz
SEGMENT_ROWS = 65536
#: what happened to each row of an innovation (``FilterOutput.innovations[name]["status"]``), by code:
#: used in the update; refused by its own gate (a measurement gated row by row: one satellite among
#: several); refused with its whole update by the chi-square gate of the vector
ROW_STATUS = ("accepted", "refused_row_gate", "refused_update_gate")
ROW_ACCEPTED, ROW_REFUSED_ROW, ROW_REFUSED_UPDATE = 0, 1, 2


@dataclass(frozen=True)
class Segment:
    """IMU rows ``start .. start + len(time) - 1`` of a filter run, as
    handed to a streaming run's sink (views valid only during the call:
    copy what you keep).

    Attributes
    ----------
    start : int
        Absolute IMU row of the first row.
    time : (m,) ndarray
    lla, v_n, q_nb : (m, 3), (m, 3), (m, 4) ndarray
        Navigation state (radians, metres, NED, quaternion of ``C_nb``).
    aux : (m, layout.aux_size) ndarray
        Estimates held at each row.
    sigma : (m, layout.size) ndarray
        1-sigma of every state.
    """

    start: int
    time: np.ndarray
    lla: np.ndarray
    v_n: np.ndarray
    q_nb: np.ndarray
    aux: np.ndarray
    sigma: np.ndarray


@dataclass(frozen=True)
class FilterSettings:
    """Everything the loop needs besides data and measurements.

    Attributes
    ----------
    layout : StateLayout
        The error state (its blocks carry their own noise, sigmas and
        initial estimates).
    scheme : {"closed", "open"}
    gate_probability : float or None
        Chi-square gate of the innovations (None: no gating).
    gate_max_consecutive : int or None
        Recovery from a lost filter (say after an outage with too small a
        covariance, or from a wrong initial tilt) needs consistent evidence:
        at least this many consecutive rejections of one measurement,
        spanning at least ``recovery_after_s``, whose innovations agree with
        each other (each pair within 4 sigma of their noise and of the
        velocity uncertainty over the time between them) or, for a
        measurement that fixes the position (a GNSS fix, pseudoranges),
        follow one smooth drift (a quadratic in time, as a tilt-lost
        filter's do: :func:`_drift`).  Then the navigation blocks'
        covariance is inflated just enough for the newest measurement to
        pass the gate, and it is applied; when the drift says a tilt
        beyond ``REINIT_ABOVE_TILT`` (7 deg), the filter is re-initialised
        on it instead (position and velocity reset, the navigation
        covariance decorrelated and widened).  A constraint (no position) does
        not recover while a measurement that fixes the position is being
        refused (the filter is lost against the fixes), and after a
        recovery on the fixes the other measurements' runs of rejections
        start again.  A burst of outliers shorter than
        ``recovery_after_s``, or outliers that disagree with each other,
        are never accepted.  ``None``: no recovery.
    recovery_after_s : float
        See ``gate_max_consecutive`` [s].
    coning : bool
    gravity : {"normal", "normal-simple", "j2"}
        Gravity model of the mechanization and of the error model's height
        gradient (:func:`inskit.earth.gravity_n`).
    smoother_node_s : float
        Spacing of the extra smoother nodes between updates [s].
    covariance_second_order : bool
        Keep the ``F P F^T dt^2`` term of ``Phi P Phi^T``.  Dropping it (Euler
        steps) is not positive semi-definite when uncertainties are large: a
        simulated MEMS car lost positiveness after 177 s without it.
    covariance_step_s : float
        The covariance is propagated once this much IMU time has gathered
        (and always up to an update or a node), with the rows' mean rate and
        specific force; the strapdown integrates every row whatever it is.
        Default 0.02 s (50 Hz): at 200 Hz a quarter of the propagation's
        cost of every row, for sigmas within 1 % of the every-row filter's
        where both are propagated to the same time and a 40 s outage within
        2 % (``tests/test_integration_kernel.py``); the error model's
        dynamics (Schuler, the bias couplings, the vehicle's turns) are far
        slower than 0.02 s, and the mean rate and specific force are the
        right low-pass of what lies between.  0: at every row.
    compiled_updates : bool
        Run the measurements that have a compiled form (``compiled()``: GNSS
        position and velocity, ZUPT, NHC, odometer, speed and course,
        pseudorange and range rate) in the compiled loop of :mod:`._updates`
        (closed loop; blocks with their own feedback keep the Python path).
        False: every update through the measurement's ``linearize`` in
        Python (the same results to rounding, ten times slower per update).
    """

    layout: StateLayout = field(default_factory=StateLayout)
    scheme: str = "closed"
    gate_probability: float | None = 0.9999
    gate_max_consecutive: int | None = 3
    recovery_after_s: float = 15.0
    coning: bool = True
    gravity: str = "normal"
    smoother_node_s: float = 0.25
    covariance_second_order: bool = True
    covariance_step_s: float = 0.02
    compiled_updates: bool = True

    def __post_init__(self):
        if self.scheme == "uncoupled":
            raise InputError("the uncoupled scheme has no filter: use inskit.integration.run_uncoupled")
        if self.scheme not in SCHEMES:
            raise InputError(f"filter scheme must be one of {SCHEMES}, got {self.scheme!r}")
        if not self.recovery_after_s >= 0:
            raise InputError(f"recovery_after_s must be >= 0 s, got {self.recovery_after_s}")
        if self.gate_max_consecutive is not None and not (isinstance(self.gate_max_consecutive, (int, np.integer))
                                                          and self.gate_max_consecutive >= 1):
            raise InputError(f"gate_max_consecutive must be None (no recovery) or an integer >= 1, got "
                             f"{self.gate_max_consecutive!r}")
        earth.gravity_model_code(self.gravity)  # an unknown model: InputError naming the choices
        if not (0.0 <= self.covariance_step_s <= 1.0):
            raise InputError(f"covariance_step_s must lie in 0 .. 1 s, got {self.covariance_step_s!r}")
        if not isinstance(self.layout, StateLayout):
            raise InputError(f"FilterSettings.layout must be a StateLayout, got {type(self.layout).__name__}")

    @classmethod
    def standard(cls, noise: SensorNoise = SensorNoise(1e-3, 1e-2, 1e-5, 1e-4),
                 initial: InitialUncertainty = InitialUncertainty(), *, scale_factors=False, lever_arm=False,
                 time_offset=False, lever_arm_b=(0.0, 0.0, 0.0), gyro_bias0=(0.0, 0.0, 0.0),
                 accel_bias0=(0.0, 0.0, 0.0), time_offset0=0.0, extra_blocks=(), **kw):
        """Settings with the standard INS blocks (:func:`.blocks.ins_blocks`)
        plus ``extra_blocks``."""
        blocks = ins_blocks(noise, initial, scale_factors=scale_factors, lever_arm=lever_arm,
                            time_offset=time_offset, lever_arm_b=lever_arm_b, gyro_bias0=gyro_bias0,
                            accel_bias0=accel_bias0, time_offset0=time_offset0)
        return cls(layout=StateLayout(list(blocks) + list(extra_blocks)), **kw)


@dataclass
class SmootherStore:
    """What the forward pass keeps for the RTS smoother, per node."""

    k: list = field(default_factory=list)
    P_minus: list = field(default_factory=list)
    P_plus: list = field(default_factory=list)
    Phi: list = field(default_factory=list)
    dx: list = field(default_factory=list)


class Track:
    """A navigation solution with the filter's estimates, as arrays.

    Attributes
    ----------
    nav : NavSolution
        Position, velocity, attitude at every IMU sample (no extra columns).
    aux : (N, layout.aux_size) ndarray
        Estimates of the blocks that carry one, held between updates.
    sigma : (N, layout.size) ndarray
        1-sigma of every state at every row.
    layout : StateLayout

    ``aux`` and ``sigma`` may be given as functions that make them: they are
    then made on first use (a filter run keeps the estimates per update and
    the variances, and spreads or roots them only when asked).
    """

    def __init__(self, nav: NavSolution, aux, sigma, layout: StateLayout):
        self.nav, self.layout = nav, layout
        self._aux, self._sigma = aux, sigma

    @cached_property
    def aux(self) -> np.ndarray:
        return self._aux() if callable(self._aux) else self._aux

    @cached_property
    def sigma(self) -> np.ndarray:
        return self._sigma() if callable(self._sigma) else self._sigma

    def estimate(self, name):
        """(N, size) history of block ``name``'s estimate."""
        return self.aux[:, self.layout.aux_slice(name)]

    def sigma_of(self, name):
        """(N, size) 1-sigma history of block ``name``."""
        return self.sigma[:, self.layout.slice(name)]

    @cached_property
    def solution(self) -> NavSolution:
        """The solution with named columns (navigation sigmas and every
        estimate) in ``extra``, for files, plots and tables."""
        extra = self.layout.columns(self.aux, self.sigma, sigma_blocks=NAV_SIGMA_BLOCKS)
        # a sigma no filter gave (the uncoupled scheme has no covariance) is not a column: NaN throughout,
        # it made the writers refuse the whole solution
        extra = {k: v for k, v in extra.items()
                 if not (k.startswith("sigma_") and len(v) and np.isnan(v[0]) and np.isnan(v).all())}
        return NavSolution._trusted(self.nav.time, self.nav.lla, self.nav.v_n, self.nav.q_nb, extra)


class FilterOutput(Track):
    """Result of a filter run: a :class:`Track` plus

    Attributes
    ----------
    counts : dict
        Per measurement name: ``{"used": n, "rejected": n, "skipped": n}``
        (``rejected`` counts updates with at least one rejected row); a
        measurement gated per row adds ``rows`` and ``rows_rejected``.
    innovations : dict
        Per measurement name: per update ``t``, ``nu`` (m, k), ``sigma`` (m,
        k), ``nis``, ``accepted`` (the update was applied: every row, or
        the rows that passed their own gate), ``dof`` (its rows) and
        ``update_row`` (the measurement's own row, as ``linearize`` got
        it); per row of every update, flat: ``status`` (int8, a code of
        :data:`ROW_STATUS`) and, for a measurement that names its rows
        (``row_labels``, the satellites of tight coupling), ``label``.
    settings : FilterSettings
    store : SmootherStore or None
    recoveries : list of dict
        Each recovery from a lost state: ``measurement``, ``t``,
        ``after_rejections``, ``rejected_for_s``, ``fixes_position``,
        ``reinitialised``, ``covariance_scale`` (None when re-initialised)
        and, for a measurement that fixes the position (else None), what
        the drift of its refused updates said:
        ``position_offset_m``, ``drift_velocity_m_s``, ``drift_accel_m_s2``
        (horizontal) and ``tilt_rad`` (the tilt error that acceleration
        says, ``atan(a / g)``): :func:`_recovery`.
    """

    def __init__(self, nav, aux, sigma, layout, counts=None, innovations=None, settings=None, store=None):
        super().__init__(nav, aux, sigma, layout)
        self.recoveries = []
        self.counts = {} if counts is None else counts
        self.innovations = {} if innovations is None else innovations
        self.settings, self.store = settings, store


def _nodes(imu, measurements, smoother_node_s, want_store, extra_rows=()):
    """Update items sorted by the IMU row that precedes them, then by time
    (ties keep the order: gap rows, measurements in list order, smoother
    grid).  Returns arrays ``k``, ``t``, ``m`` (index into ``measurements``;
    -1 for a node without a measurement) and ``pos`` (index into that
    measurement's kept rows), the kept rows per measurement and the skipped
    count per measurement name."""
    t = imu.time
    extra = np.asarray(list(extra_rows), dtype=np.int64)
    ks, ts, ms, ps = [extra], [t[extra].astype(float)], [np.full(len(extra), -1, np.int64)], \
        [np.full(len(extra), -1, np.int64)]
    skipped, kept = {}, []
    # a measurement inside a gap of the IMU log has no INS state near it: skipped, not extrapolated;
    # judged against the local sampling interval, so a change of rate is not taken for a gap
    from .gaps import local_interval

    loc = local_interval(np.diff(t)) if len(t) > 1 else np.full(1, np.inf)
    for j, m in enumerate(measurements):
        tm = np.asarray(m.times(), float)
        rows = np.asarray(m.rows())
        k = np.searchsorted(t, tm, side="right") - 1
        ok = (k >= 1) & (tm <= t[-1])
        ok &= (tm - t[np.clip(k, 0, len(t) - 1)]) <= 2.0 * loc[np.clip(k, 0, len(loc) - 1)]
        skipped[m.name] = int((~ok).sum())
        kept.append(rows[ok])
        n_ok = int(ok.sum())
        ks.append(k[ok].astype(np.int64))
        ts.append(tm[ok])
        ms.append(np.full(n_ok, j, np.int64))
        ps.append(np.arange(n_ok, dtype=np.int64))
    if want_store and smoother_node_s > 0:
        grid = np.arange(t[0] + smoother_node_s, t[-1], smoother_node_s)
        kg = np.searchsorted(t, grid, side="right") - 1
        kg = np.unique(kg[kg >= 1]).astype(np.int64)
        ks.append(kg)
        ts.append(t[kg].astype(float))
        ms.append(np.full(len(kg), -1, np.int64))
        ps.append(np.full(len(kg), -1, np.int64))
    k, tt, m, pos = (np.concatenate(v) for v in (ks, ts, ms, ps))
    order = np.lexsort((tt, k))  # stable: equal (k, t) keep their order
    return k[order], tt[order], m[order], pos[order], kept, skipped


def _compiled_specs(measurements, layout):
    """Each measurement's :class:`._updates.CompiledSpec` (``compiled(layout)``),
    or None for one without (a user's plug-in: the Python path)."""
    out = []
    for m in measurements:
        f = getattr(m, "compiled", None)
        sp = f(layout) if callable(f) else None
        if sp is not None and not (isinstance(sp, U.CompiledSpec) and sp.k >= 1
                                   and (sp.k <= U.KMAX or sp.index is not None)):
            sp = None
        out.append(sp)
    return out


def _check_measurements(measurements):
    names = [getattr(m, "name", None) for m in measurements]
    for m, nm in zip(measurements, names):
        for attr in ("times", "rows", "linearize"):
            if not callable(getattr(m, attr, None)):
                raise InputError(f"measurement {nm or type(m).__name__!r} lacks the method {attr}() of the "
                                 "measurement protocol (inskit.integration.measurements)")
        if not isinstance(nm, str) or not nm:
            raise InputError(f"measurement {type(m).__name__} needs a non-empty `name`")
        if getattr(m, "gating", "vector") not in ("vector", "row"):
            raise InputError(f"measurement {nm!r}: gating must be 'vector' or 'row', got {m.gating!r}")
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise InputError(f"measurement names must be unique; repeated: {sorted(dup)}")


def run_filter(imu: ImuData, initial: NavState, measurements, settings: FilterSettings, *,
               smoother=False, progress=None, extra_noise=None, sink=None, keep_rows=None,
               segment_rows=SEGMENT_ROWS, store_sink=None) -> FilterOutput:
    """Run the integration filter forward over the IMU data.

    Parameters
    ----------
    imu : ImuData
        ``imu.time[0]`` is the initial epoch.
    initial : NavState
        Initial IMU state at ``imu.time[0]``.
    measurements : list of measurement plug-ins (the protocol of :mod:`.measurements`)
    settings : FilterSettings
    smoother : bool
        Keep what the RTS smoother needs (closed loop only).
    progress : callable, optional
        Called with the number of IMU rows done since the last call.
    extra_noise : dict, optional
        ``{row: (layout.size,) variances}`` added to the covariance's
        diagonal right after propagating through that IMU row (a gap bridged
        in the IMU log, say: see :mod:`.gaps`).
    sink : callable, optional
        Stream the run: called with each finished :class:`Segment`, in order,
        rows ``0 .. N-1`` once each.  The returned output then holds only
        ``keep_rows`` (and its ``rows`` attribute says which).
    keep_rows : (m,) int array, optional
        With ``sink``: the IMU rows the returned output keeps (sorted, unique;
        row 0 and the last row are always kept).  Default: every node row.
    segment_rows : int
        Rows per segment (tests use small ones).
    store_sink : callable, optional
        With ``sink`` and ``smoother``: called with each segment's smoother
        data ``(k, P_minus, P_plus, Phi, dx)`` (arrays over its nodes, views
        valid during the call), which the returned output then does not keep
        (``store`` None): :class:`inskit.integration.smoother.DiskStore`.

    Returns
    -------
    FilterOutput
    """
    if abs(initial.time - imu.time[0]) > 1e-6:
        raise InputError(f"the initial state ({initial.time:.3f} s) must be at the first IMU sample "
                         f"({imu.time[0]:.3f} s)")
    if not abs(initial.lla[0]) < np.radians(89.9):
        raise InputError(f"the initial latitude {np.degrees(initial.lla[0]):.4f} deg is within 0.1 deg of a pole, "
                         "where the filter's NED error model is singular")
    if smoother and settings.scheme != "closed":
        raise InputError("the RTS smoother works on the closed-loop filter only")
    stream = sink is not None
    if stream and smoother and store_sink is None:
        raise InputError("a streamed run keeps no smoother data: give store_sink (a DiskStore) to smooth it")
    S = int(segment_rows)
    if S < 2:
        raise InputError(f"segment_rows must be at least 2, got {segment_rows!r}")
    _check_measurements(measurements)
    lay = settings.layout
    n = lay.size
    q_psd = lay.process_noise()
    q_body = lay.body_noise()
    if q_body is not None:  # the kernel rotates these into NED at every step (_kernel.propagate_rows)
        q_psd = np.concatenate([q_psd, q_body])
    rows_pat, cols_pat = lay.transition_pattern()
    crow, ccol, cval = lay.constant_entries()
    active = np.unique(rows_pat)
    model = (lay.kernel_index(), q_psd, rows_pat, cols_pat, active, crow, ccol, cval)
    P = lay.initial_covariance()  # updated in place throughout (the compiled loop shares it)
    x = np.zeros(n)
    aux = lay.initial_aux()
    aux_idx = lay.aux_state_index
    dyn_idx, dyn_F = lay.estimate_dynamics()
    t_aux = np.array([float(imu.time[0])])

    def predict_aux(t):
        """Carry the evolving estimates (clock bias by its drift, Gauss-Markov
        decay) from their last time to ``t`` (:func:`._updates.predict_aux`)."""
        U.predict_aux(aux, dyn_idx, dyn_F, t_aux, t)
    custom_feedback = [(lay.slice(b.name), lay.aux_slice(b.name), b) for b in lay.blocks
                       if b.has_estimate and type(b).feedback is not _default_feedback]
    default_aux = np.ones(lay.aux_size, bool)
    for _, sa, _ in custom_feedback:
        default_aux[sa] = False
    default_aux_idx = np.nonzero(default_aux)[0].astype(np.int64)
    default_x_idx = aux_idx[default_aux_idx]
    lla, v_n, q_nb = initial.lla.copy(), initial.v_n.copy(), initial.q_nb.copy()
    carry = np.zeros(11)
    carry[0] = imu.time[0]
    N = len(imu)
    cap = min(N, S + 1) if stream else N  # a segment holds at most S + 1 rows (the first one: rows 0 .. S)
    out_lla = np.empty((cap, 3))
    out_v = np.empty((cap, 3))
    out_q = np.empty((cap, 4))
    out_var = np.empty((cap, n))
    obase = np.zeros(1, np.int64)  # absolute row of the output arrays' first row
    w_raw = np.zeros(3)
    open_loop = settings.scheme == "open"
    want_store = smoother
    Phi = np.eye(n)
    nav = (lla, v_n, q_nb, carry)
    outs = (out_lla, out_v, out_q, out_var, obase)
    imu_arrays = (imu.time, imu.dtheta_b, imu.dv_b)
    eye_n = np.eye(n)
    extra_noise = {int(k): np.asarray(v, float) for k, v in (extra_noise or {}).items()}
    for k, v in extra_noise.items():
        if v.shape != (n,) or not (np.isfinite(v).all() and (v >= 0).all()):
            raise InputError(f"extra_noise at row {k} must be {n} finite variances >= 0")
        if not 1 <= k < len(imu):
            raise InputError(f"extra_noise row {k} is outside the IMU rows 1..{len(imu) - 1}")
    bounds = np.arange(S, N, S, dtype=np.int64)  # each segment ends at a node (without a measurement)
    it_k, it_t, it_m, it_pos, kept_rows, skipped = _nodes(imu, measurements, settings.smoother_node_s, want_store,
                                                          sorted(extra_noise) + bounds.tolist())
    n_items = len(it_k)
    n_nodes = len(np.unique(it_k))
    # loop state shared with the compiled loop: item, rows done, node, rows written, ...
    ctl = np.zeros(U.C_SIZE, np.int64)
    ctl[U.C_KDONE] = 1
    m_store = n_nodes if want_store else 0
    m_rows = n_nodes + 2
    if stream:  # the nodes of one segment at a time (between two flushes)
        uk = np.unique(it_k)
        edges = np.concatenate([[0], bounds, [N]])
        per_segment = int(np.diff(np.searchsorted(uk, edges, side="right")).max(initial=0))
        m_store = per_segment + 1 if want_store else 0
        # flush keeps the node that holds the next segment's first row; the end adds one for the last row
        m_rows = min(m_rows, per_segment + 3)
    node_rows = np.empty(m_rows, np.int64)
    node_aux = np.empty((m_rows, lay.aux_size))
    nbase = np.zeros(1, np.int64)  # absolute node of the store's first entry
    st_k = np.zeros(m_store, np.int64)
    st_Pm, st_Pp, st_Phi = (np.empty((m_store, n, n)) for _ in range(3))
    st_dx = np.zeros((m_store, n))

    def write_row(k):
        ko = k - int(obase[0])
        if open_loop:
            K.apply_correction(lla, v_n, q_nb, x, 1.0, out_lla[ko], out_v[ko], out_q[ko])
        else:
            out_lla[ko], out_v[ko], out_q[ko] = lla, v_n, q_nb
        out_var[ko] = P.diagonal()  # variances until the end of the run
        r = ctl[U.C_NROW]
        node_rows[r] = k
        node_aux[r] = aux - x[aux_idx] if open_loop else aux
        ctl[U.C_NROW] = r + 1

    def propagate(k0, k1, want_phi):
        filt = (x, P, aux, Phi)
        K.propagate(imu_arrays, nav, filt, model, outs, k0, k1,
                    (settings.coning, want_phi, open_loop, settings.covariance_second_order,
                     earth.gravity_model_code(settings.gravity), float(settings.covariance_step_s)))

    if stream:
        keep = (np.unique(np.concatenate([[0, N - 1], it_k])) if keep_rows is None
                else np.unique(np.concatenate([[0, N - 1], np.asarray(keep_rows, np.int64)])))
        if keep[0] < 0 or keep[-1] >= N:
            raise InputError(f"keep_rows must lie in 0 .. {N - 1}")
        nk = len(keep)  # filled segment by segment (no lists to concatenate: the peak stays the arrays)
        kept = {"lla": np.empty((nk, 3)), "v": np.empty((nk, 3)), "q": np.empty((nk, 4)),
                "aux": np.empty((nk, lay.aux_size)), "sigma": np.empty((nk, n))}

    def flush(k1):
        """Hand rows ``obase .. k1-1`` (final) to the sink, keep the rows
        asked for, and start the next segment at ``k1``."""
        a = int(obase[0])
        if k1 <= a:
            return
        m = k1 - a
        seg_lla, seg_v, seg_q = out_lla[:m], out_v[:m], out_q[:m]
        _check_rows(imu.time, a, seg_lla, seg_v, seg_q)
        nr = int(ctl[U.C_NROW])
        hold = np.searchsorted(node_rows[:nr], np.arange(a, k1), side="right") - 1
        seg_aux = node_aux[:nr][hold]
        seg_sig = np.sqrt(np.maximum(out_var[:m], 0.0))
        sink(Segment(a, imu.time[a:k1], seg_lla, seg_v, seg_q, seg_aux, seg_sig))
        if want_store:
            c = int(ctl[U.C_NODE] - nbase[0])
            store_sink(st_k[:c], st_Pm[:c], st_Pp[:c], st_Phi[:c], st_dx[:c])
            nbase[0] = ctl[U.C_NODE]
        lo, hi = np.searchsorted(keep, a), np.searchsorted(keep, k1)
        sel = keep[lo:hi] - a
        for key, arr in (("lla", seg_lla), ("v", seg_v), ("q", seg_q), ("aux", seg_aux), ("sigma", seg_sig)):
            kept[key][lo:hi] = arr[sel]
        obase[0] = k1
        # the node rows a later row may still look up: from the last at or before k1 on (memory per segment,
        # not per node of the log)
        j = int(hold[-1])
        node_rows[:nr - j] = node_rows[j:nr]
        node_aux[:nr - j] = node_aux[j:nr]
        ctl[U.C_NROW] = nr - j

    def segment_stop(k_done):
        """The last row + 1 a node of the current segment may end at."""
        return ((k_done - 1) // S + 1) * S + 1

    nav_floor = P.diagonal()[:9].copy()  # a re-initialised filter is at least as uncertain as at its start
    # per measurement: it fixes the position and its latest update was refused (both paths keep it: _recovery)
    fix_refused = np.zeros(len(measurements), np.int64)
    recovered_t = np.full(1, -np.inf)  # time of the latest recovery on a measurement that fixes the position
    write_row(0)
    counts = {m.name: {"used": 0, "rejected": 0, "skipped": skipped[m.name]} for m in measurements}
    innov = {m.name: {"t": [], "nu": [], "sigma": [], "nis": [], "accepted": [], "status": [], "update_row": []}
             for m in measurements}
    rejected_streak = {}
    rejected_recent = {}  # per measurement: (t, innovation, R) of the current run of rejections
    first_rejection = {}
    recoveries = []
    n_held = max(8, (settings.gate_max_consecutive or 0) + 1)
    t_imu = imu.time

    def python_item(idx, k_end, C_nb):
        """One update on the Python path (the measurement's own ``linearize``);
        returns the C_nb of the state after it."""
        # read off the item arrays one by one (Python lists of every item would hold 0.16 kB per item, 50 MB
        # over 8 h of updates at 10 Hz, for the few items a compiled run hands back)
        tm = float(it_t[idx])
        mi = int(it_m[idx])
        meas = measurements[mi]
        row = int(kept_rows[mi][it_pos[idx]])
        if open_loop:
            o_lla, o_v, o_q = np.empty(3), np.empty(3), np.empty(4)
            K.apply_correction(lla, v_n, q_nb, x, 1.0, o_lla, o_v, o_q)
            ctx = UpdateContext(tm, tm - t_imu[k_end], o_lla, o_v, dcm_from_quat(o_q), w_raw, lay,
                                aux - x[aux_idx])
        else:
            ctx = UpdateContext(tm, tm - t_imu[k_end], lla, v_n, C_nb, w_raw, lay, aux)
        lin = meas.linearize(ctx, row)
        if lin is None:
            counts[meas.name]["skipped"] += 1
            return C_nb
        nu, H, R = lin
        gate = settings.gate_probability
        fixes = int(gate is not None and settings.gate_max_consecutive is not None and _to_ned(H, R) is not None)
        streak = rejected_streak.get(meas.name, 0)
        rej = rejected_recent.setdefault(meas.name, [])
        if streak and first_rejection[meas.name] <= recovered_t[0]:  # refused by the state before a recovery
            streak = rejected_streak[meas.name] = 0
            rej.clear()
            fix_refused[mi] = 0
        if (gate is not None and settings.gate_max_consecutive is not None
                and streak >= settings.gate_max_consecutive
                and tm - first_rejection[meas.name] >= settings.recovery_after_s):
            held = rej[-settings.gate_max_consecutive:] + [(tm, nu, R)]
            found = _recovery(P, nu, H, R, held, gate, nav_floor, bool(fix_refused.any()))
            if found is not None:
                P[...], dx_reset, info = found
                if dx_reset is not None:  # re-initialised: position and velocity reset, the innovation left
                    if open_loop:
                        x[:] += dx_reset
                    else:
                        K.apply_correction(lla, v_n, q_nb, dx_reset, 1.0, lla, v_n, q_nb)
                        if want_store:
                            st_dx[ctl[U.C_NODE] - nbase[0]] += dx_reset
                    nu = nu - H @ dx_reset
                if info["fixes_position"]:  # the other measurements' refusals were of the state before it
                    recovered_t[0] = tm
                recoveries.append({"measurement": meas.name, "t": float(tm), "after_rejections": streak,
                                   "rejected_for_s": float(tm - first_rejection[meas.name]), **info, "_item": idx})
        rec = innov[meas.name]
        nu_all = s_all = None
        if gate is not None and getattr(meas, "gating", "vector") == "row":
            keep, s_rows = gate_rows(P, nu, H, R, gate)
            c_m = counts[meas.name]
            c_m["rows"] = c_m.get("rows", 0) + len(keep)
            c_m["rows_rejected"] = c_m.get("rows_rejected", 0) + int((~keep).sum())
            if not keep.all():  # record the whole vector; update with the rows that pass
                counts[meas.name]["rejected"] += 1
                nu_all, s_all = nu, s_rows
                if not keep.any():  # every row refused: a rejection of the measurement, as in the vector gate
                    rejected_streak[meas.name] = streak + 1
                    if not rej:
                        first_rejection[meas.name] = tm
                    rej.append((tm, nu, R))
                    del rej[:-n_held]
                    fix_refused[mi] = fixes
                    rec["t"].append(tm)
                    rec["nu"].append(nu)
                    rec["sigma"].append(np.sqrt(s_rows))
                    rec["nis"].append(float(np.sum(nu * nu / s_rows)))
                    rec["accepted"].append(False)
                    rec["status"].append(np.full(len(nu), ROW_REFUSED_ROW, np.int8))
                    rec["update_row"].append(row)
                    return C_nb
                status = np.where(keep, ROW_ACCEPTED, ROW_REFUSED_ROW).astype(np.int8)
                nu, H, R = nu[keep], H[keep], R[np.ix_(keep, keep)]
            gate = None
        res = joseph_update(P, nu, H, R, gate_probability=gate)
        rejected_streak[meas.name] = 0 if res.accepted else streak + 1
        fix_refused[mi] = 0 if res.accepted else fixes
        if res.accepted:
            rej.clear()
        else:
            if not rej:
                first_rejection[meas.name] = tm
            rej.append((tm, nu, R))
            del rej[:-n_held]  # bounded memory
        rec["t"].append(tm)
        rec["nu"].append(res.innovation if nu_all is None else nu_all)
        rec["sigma"].append(np.sqrt(np.diag(res.S)) if s_all is None else np.sqrt(s_all))
        rec["nis"].append(res.nis)
        rec["accepted"].append(res.accepted)
        rec["update_row"].append(row)
        if nu_all is not None:
            rec["status"].append(status)
        else:
            rec["status"].append(np.full(len(nu), ROW_ACCEPTED if res.accepted else ROW_REFUSED_UPDATE, np.int8))
        if not res.accepted:
            counts[meas.name]["rejected"] += 1
            return C_nb
        counts[meas.name]["used"] += 1
        P[...] = res.P
        if open_loop:
            x[...] += res.dx
            return C_nb
        dx = res.dx
        K.apply_correction(lla, v_n, q_nb, dx, 1.0, lla, v_n, q_nb)
        aux[default_aux_idx] -= dx[default_x_idx]
        for sx, sa, b in custom_feedback:
            b.feedback(aux[sa], dx[sx])
        if want_store:
            st_dx[ctl[U.C_NODE] - nbase[0]] += dx
        C_nb = np.empty((3, 3))  # a new array: an earlier context may still hold the old one
        K.dcm_into(q_nb, C_nb)
        return C_nb

    def run_compiled():
        """The compiled loop (:func:`._updates.run_nodes`) over every node,
        sharing this run's state, with the items of measurements without a
        compiled form handed to :func:`python_item`.  Returns the compiled
        measurements' records, counts and recoveries."""
        M = len(measurements)
        kinds = np.array([-1 if sp is None else sp.kind for sp in specs], np.int64)
        mk = np.array([1 if sp is None else sp.k for sp in specs], np.int64)
        d_w = np.array([1 if sp is None else sp.data.shape[1] for sp in specs], np.int64)
        per_row = np.array([sp is not None and sp.per_row for sp in specs], np.bool_)
        blocks, offs, pblocks, poffs, iblocks, ioffs, o, po, io = [], [], [], [], [], [], 0, 0, 0
        for sp in specs:
            d = np.zeros(1) if sp is None or sp.data.size == 0 else sp.data.ravel()
            p = np.zeros(1) if sp is None or sp.par.size == 0 else sp.par
            blocks.append(d)
            offs.append(o)
            o += len(d)
            pblocks.append(p)
            poffs.append(po)
            po += len(p)
            if sp is not None and sp.index is not None:
                iblocks.append(sp.index)
                ioffs.append(io)
                io += len(sp.index)
            else:
                ioffs.append(-1)
        index = np.concatenate(iblocks) if iblocks else np.zeros(1, np.int64)
        meas = (kinds, mk, np.array(offs, np.int64), d_w, np.concatenate(blocks), np.array(poffs, np.int64),
                np.concatenate(pblocks), np.array(ioffs, np.int64), index, per_row)
        compiled_m = kinds >= 0
        # own data row of each item (compiled measurements only) and the rows of its update
        it_row = np.full(n_items, -1, np.int64)
        rows_of = np.zeros(n_items, np.int64)
        for j in np.nonzero(compiled_m)[0]:
            sel = it_m == j
            it_row[sel] = np.asarray(kept_rows[j], np.int64)[it_pos[sel]]
            ix = specs[j].index
            rows_of[sel] = specs[j].k if ix is None else ix[it_row[sel] + 1] - ix[it_row[sel]]
        k_most = max(U.KMAX, int(rows_of.max(initial=0)))
        en = extra_noise
        en_k = np.array(sorted(en), np.int64)
        en_var = np.array([en[k] for k in en_k.tolist()], float).reshape(len(en_k), n)
        items = (it_k, it_t, it_m, it_row, en_k, en_var)
        gate_p, gmc = settings.gate_probability, settings.gate_max_consecutive
        gpar = np.array([0.0 if gate_p is None else 1.0, -1.0 if gmc is None else float(gmc),
                         float(settings.recovery_after_s)])
        thr = np.array([np.inf] + [0.0 if gate_p is None else chi2_threshold(k, gate_p)
                                   for k in range(1, k_most + 1)])
        thr_fit = np.array([np.inf] + [np.inf if gate_p is None else chi2_threshold(d, gate_p)
                                       for d in range(1, DRIFT_MAX_POINTS - 2)])  # a drift's residual dof
        rstate = (np.zeros(M, np.int64), np.zeros(M), np.zeros((M, n_held)), np.zeros((M, n_held), np.int64),
                  np.zeros((M, n_held, k_most)), np.zeros((M, n_held, k_most)), np.zeros(M, np.int64), fix_refused,
                  recovered_t)
        T = max(int(compiled_m[it_m[it_m >= 0]].sum()), 1)
        T_flat = max(int(rows_of.sum()), 1)
        recs = (np.zeros(T, np.int64), np.zeros(T, np.int64), np.zeros(T), np.zeros(T), np.zeros(T, np.bool_),
                np.zeros(T, np.int64), np.zeros(T, np.int64), np.zeros(T_flat), np.zeros(T_flat),
                np.zeros(T_flat, np.int8))
        recov = (np.zeros(T, np.int64), np.zeros(T, np.int64), np.zeros(T), np.zeros(T, np.int64), np.zeros(T),
                 np.zeros((T, 7)))
        counts = np.zeros((M, U.N_COUNTS), np.int64)
        store = (st_k, st_Pm, st_Pp, st_Phi, st_dx, nbase)
        nodes = (node_rows, node_aux)
        dyn = (dyn_idx, dyn_F, t_aux)
        fb = (default_aux_idx, default_x_idx)
        flags = (bool(settings.coning), bool(want_store), False, bool(settings.covariance_second_order),
                 earth.gravity_model_code(settings.gravity), float(settings.covariance_step_s))
        filt = (x, P, aux, Phi)
        lidx = U.layout_index(lay)
        C = np.empty((3, 3))
        chunk = max(N // 50, 1) if progress is not None else N + 1

        def loop():
            """Run the compiled loop to the end of the log; raise on a divergence."""
            reported = int(ctl[U.C_KDONE])
            while True:
                i = int(ctl[U.C_I])
                ctl[U.C_KSTOP] = min((int(it_k[i]) if i < n_items else N) + chunk, N + 1,
                                     segment_stop(int(ctl[U.C_KDONE])))
                code = U.run_nodes(imu_arrays, nav, filt, model, outs, flags, items, meas, lidx,
                                   (gpar, thr, thr_fit, nav_floor), rstate, recs, recov, counts, store, nodes, dyn, fb,
                                   w_raw, C, ctl)
                if progress is not None and ctl[U.C_KDONE] > reported:
                    progress(int(ctl[U.C_KDONE]) - reported)
                    reported = int(ctl[U.C_KDONE])
                if code == U.DONE:
                    break
                if code == U.CHUNK:
                    # a segment is handed on once full (its boundary node done), not at every progress chunk: a
                    # writer's cost is per segment (a short log cut into fifty pieces paid it fifty times)
                    if stream and int(ctl[U.C_KDONE]) >= segment_stop(max(int(obase[0]), 1)):
                        flush(int(ctl[U.C_KDONE]))
                    continue
                i = int(ctl[U.C_I])
                if code == U.HANDBACK:
                    k_cur = int(ctl[U.C_KCUR])
                    C_nb = np.empty((3, 3))
                    K.dcm_into(q_nb, C_nb)
                    while i < n_items and it_k[i] == k_cur and (it_m[i] < 0 or not compiled_m[it_m[i]]):
                        if it_m[i] >= 0:
                            C_nb = python_item(i, k_cur, C_nb)
                        i += 1
                    ctl[U.C_I] = i
                    continue
                if code == U.BAD_INNOVATION:
                    raise FilterDivergence("the innovation is not finite: the filter diverged")
                if code == U.NOT_PD:
                    raise FilterDivergence("innovation covariance is not positive definite: the filter diverged")
                if code == U.BAD_ROWS:
                    raise FilterDivergence("the innovation or its variance is not finite and positive: the filter "
                                           "diverged")
                check_covariance(P, f"at t = {t_imu[int(ctl[U.C_KCUR])]:.3f} s")
                raise FilterDivergence(f"covariance lost positiveness at t = {t_imu[int(ctl[U.C_KCUR])]:.3f} s")

        try:
            loop()
        except (FilterDivergence, InputError) as e:
            # the failure is where a lost filter met a numerical wall, often long after it was lost: say how
            # its measurements had fared (a ship's 8 h log with a land vehicle's constraint, lost after 6 s,
            # stopped at 2616 s 'within 0.1 deg of a pole' and said nothing more)
            nr = int(ctl[U.C_NREC])
            note = lost_note([m.name for m in measurements], recs[0][:nr], recs[2][:nr], recs[4][:nr])
            if not note:
                raise
            raise type(e)(f"{e}; {note}") from e
        nr = int(ctl[U.C_NREC])
        rec_m, rec_i, rec_t, rec_nis, rec_acc, rec_k, rec_off = (a[:nr] for a in recs[:7])
        rec_nu, rec_sig, rec_st = recs[7], recs[8], recs[9]

        def records(mi):
            sel = np.nonzero(rec_m == mi)[0]
            if not len(sel):
                return _innovation_arrays({"t": [], "nu": [], "sigma": [], "nis": [], "accepted": [], "status": [],
                                           "update_row": []})
            dof = rec_k[sel]
            out = {"t": rec_t[sel], "nis": rec_nis[sel], "accepted": rec_acc[sel], "dof": dof,
                   "update_row": it_row[rec_i[sel]]}
            at_rows = np.repeat(rec_off[sel] - (np.cumsum(dof) - dof), dof) + np.arange(int(dof.sum()))
            out["status"] = rec_st[at_rows]
            out["nis_dof"] = nis_dof(dof, out["status"])
            if (dof == dof[0]).all():
                at = rec_off[sel][:, None] + np.arange(dof[0])
                out["nu"], out["sigma"] = rec_nu[at], rec_sig[at]
            else:
                for key, flat in (("nu", rec_nu), ("sigma", rec_sig)):
                    a = np.empty(len(sel), dtype=object)
                    for q, (o, k) in enumerate(zip(rec_off[sel].tolist(), dof.tolist())):
                        a[q] = flat[o:o + k].copy()
                    out[key] = a
            return out

        nv = int(ctl[U.C_NRECOV])
        rv_m, rv_i, rv_t, rv_after, rv_for, rv_info = (a[:nv] for a in recov)
        found = [{"measurement": measurements[int(rv_m[j])].name, "t": float(rv_t[j]),
                  "after_rejections": int(rv_after[j]), "rejected_for_s": float(rv_for[j]),
                  **_recovery_info(rv_info[j]), "_item": int(rv_i[j])}
                 for j in range(nv)]
        return {"records": records, "counts": counts, "recoveries": found}

    specs = _compiled_specs(measurements, lay) if settings.compiled_updates else [None] * len(measurements)
    use_compiled = not open_loop and not custom_feedback and any(sp is not None for sp in specs)
    if use_compiled:
        rec_c = run_compiled()
    else:
        specs = [None] * len(measurements)
        k_list, m_list = it_k.tolist(), it_m.tolist()  # every item on this path: lists index faster
        i = 0
        while i < n_items:
            k_end = k_list[i]
            j = i
            while j < n_items and k_list[j] == k_end:
                j += 1
            k_done = int(ctl[U.C_KDONE])
            if k_end + 1 > k_done:
                propagate(k_done, k_end + 1, want_store)
                if progress is not None:
                    progress(k_end + 1 - k_done)
                ctl[U.C_KDONE] = k_end + 1
                w_raw[:] = (imu.dtheta_b[k_end]) / (t_imu[k_end] - t_imu[k_end - 1])
                predict_aux(float(t_imu[k_end]))
            if k_end in extra_noise:
                P[np.diag_indices(n)] += extra_noise[k_end]
            node = int(ctl[U.C_NODE])
            js = node - int(nbase[0])
            if want_store:
                st_k[js] = k_end
                st_Pm[js] = P
                st_Phi[js] = Phi
                st_dx[js] = 0.0
                Phi[:] = eye_n
            C_nb = np.empty((3, 3))
            K.dcm_into(q_nb, C_nb)
            for idx in range(i, j):
                if m_list[idx] >= 0:
                    C_nb = python_item(idx, k_end, C_nb)
            check_covariance(P, f"at t = {t_imu[k_end]:.3f} s")
            if want_store:
                st_Pp[js] = P
            write_row(k_end)
            ctl[U.C_NODE] = node + 1
            if stream and k_end % S == 0:
                flush(k_end + 1)
            i = j
        rec_c = None
    k_done = int(ctl[U.C_KDONE])
    if stream:
        flush(k_done)  # the tail below then fits in the segment
    if k_done < N:
        propagate(k_done, N, False)
        if progress is not None:
            progress(N - k_done)
    predict_aux(float(t_imu[-1]))
    check_covariance(P, "at the end of the run")
    if not stream:
        _check_rows(imu.time, 0, out_lla, out_v, out_q)
    if open_loop or len(dyn_idx):  # estimates that drift between updates: record them at the end too
        write_row_aux_only = int(ctl[U.C_NROW])
        node_rows[write_row_aux_only] = N - 1
        node_aux[write_row_aux_only] = aux - x[aux_idx] if open_loop else aux
        ctl[U.C_NROW] += 1
    n_rows = int(ctl[U.C_NROW])
    if stream:
        flush(N)

    def spread_aux():  # every row holds the estimates of the last node at or before it (they change only at updates)
        hold = np.searchsorted(node_rows[:n_rows], np.arange(N), side="right") - 1
        return node_aux[:n_rows][hold]

    def sigma():
        return np.sqrt(np.maximum(out_var, 0.0, out=out_var), out=out_var)

    innovations = {}
    for mi, m in enumerate(measurements):
        if specs[mi] is None:
            innovations[m.name] = _innovation_arrays(innov[m.name])
        else:
            innovations[m.name] = rec_c["records"](mi)
            c, cc = counts[m.name], rec_c["counts"][mi]
            c["used"] += int(cc[U.N_USED])
            c["rejected"] += int(cc[U.N_REJECTED])
            c["skipped"] += int(cc[U.N_SKIPPED])
            if cc[U.N_ROW_GATED]:
                c["rows"] = int(cc[U.N_ROWS])
                c["rows_rejected"] = int(cc[U.N_ROWS_REJECTED])
        if hasattr(m, "row_labels"):  # what each row is (a satellite), for the innovation file
            innovations[m.name]["label"] = np.asarray(m.row_labels(innovations[m.name]["update_row"]), dtype=object)
    if rec_c is not None:
        recoveries = sorted(recoveries + rec_c["recoveries"], key=lambda r: r["_item"])
    for r in recoveries:
        del r["_item"]
    store = None
    if want_store and not stream:
        store = SmootherStore(st_k.tolist(), list(st_Pm), list(st_Pp), list(st_Phi), list(st_dx))
    if stream:
        nav_sol = NavSolution._trusted(imu.time[keep], kept["lla"], kept["v"], kept["q"])
        out = FilterOutput(nav_sol, kept["aux"], kept["sigma"], lay, counts, innovations, settings, store)
        out.rows = keep
    else:
        nav_sol = NavSolution._trusted(imu.time, out_lla, out_v, out_q)
        out = FilterOutput(nav_sol, spread_aux, sigma, lay, counts, innovations, settings, store)
        out.rows = None
    out.n_rows = N
    out.recoveries = recoveries
    return out


#: a measurement refused in more than this fraction of its updates is named in a divergence's message
LOST_FRACTION = 0.5


def lost_note(names, rec_m, rec_t, rec_acc):
    """What a divergence's message adds: the measurements refused in more
    than :data:`LOST_FRACTION` of their updates before it, each with its
    counts and its last accepted update, or ``""`` when none was.

    A filter lost early (its fixes refused from the first seconds on) can run
    for hours before its covariance or its latitude meets a numerical limit;
    the limit's own words ("covariance lost positiveness at t = ...") then
    point at the wrong time and the wrong cause.  A non-holonomic constraint
    refused in most of its updates is named as the likely cause: it is a land
    vehicle's, and a vessel's heave (0.8 m/s for 1 m at 8 s), an aircraft or a
    handheld device breaks it; the filter then takes the body's vertical
    velocity for a pitch error (heave rate / speed, 5.6 deg at 8 m/s), which
    leaks gravity into the horizontal channels and drives the fixes out of the
    gate.

    Parameters
    ----------
    names : sequence of str
        The measurements' names, by index.
    rec_m : (r,) int array
        Measurement index of each update record so far.
    rec_t : (r,) float array
        Time of each record [s].
    rec_acc : (r,) bool array
        Whether each update was accepted.

    Returns
    -------
    str
    """
    parts, nhc = [], False
    for mi, name in enumerate(names):
        sel = rec_m == mi
        n = int(sel.sum())
        if not n:
            continue
        acc = rec_acc[sel]
        used = int(acc.sum())
        if n - used <= LOST_FRACTION * n:
            continue
        last = (f"the last at t = {float(rec_t[sel][acc][-1]):.1f} s" if used else "none accepted")
        parts.append(f"{name} {used} of {n} updates used ({100.0 * (n - used) / n:.0f} % refused, {last})")
        nhc = nhc or name == "nhc"
    if not parts:
        return ""
    note = "before it the filter was lost: " + "; ".join(parts)
    if nhc:
        note += (" (the non-holonomic constraint, a land vehicle's, does not hold for this vehicle: a vessel's "
                 "heave, an aircraft or a handheld device breaks it; set [constraints] nhc = false)")
    return note


def _check_rows(t, a, lla, v, q):
    """Refuse a solution that became NaN or came within 0.1 deg of a pole
    (rows ``a ..`` of the run)."""
    if not (np.isfinite(lla).all() and np.isfinite(v).all() and np.isfinite(q).all()):
        raise FilterDivergence("the navigation solution became NaN: the filter diverged")
    near = np.nonzero(~(np.abs(lla[:, 0]) < np.radians(89.9)))[0]
    if len(near):
        raise InputError(f"the solution reaches latitude {np.degrees(lla[near[0], 0]):.4f} deg at t = "
                         f"{t[a + near[0]]:.3f} s, within 0.1 deg of a pole, where the NED filter is singular")


def nis_dof(dof, status):
    """The degrees of freedom of each update's NIS: its rows (``dof``) less
    those refused by their own gate (``status`` flat, :data:`ROW_STATUS`),
    which the NIS of an update that went on with the others leaves out.  A
    mean NIS per degree of freedom divides by these: by all the rows, a
    partly refused tight-coupling epoch read as more consistent than it was."""
    dof = np.asarray(dof, np.int64)
    if not len(dof):
        return dof.copy()
    refused = np.bincount(np.repeat(np.arange(len(dof)), dof), weights=(np.asarray(status) == ROW_REFUSED_ROW),
                          minlength=len(dof))
    return dof - refused.astype(np.int64)


def _innovation_arrays(rec):
    """A measurement's innovation record as arrays: ``nu`` and ``sigma`` are
    (m, k) when every update has k rows, else object arrays of (k_i,) arrays
    (one row per satellite in view, say); ``dof`` holds each update's k,
    ``nis_dof`` the rows its NIS covers (:func:`nis_dof`), ``status`` every
    row's code (:data:`ROW_STATUS`), flat."""
    out = {kk: np.asarray(rec[kk]) for kk in ("t", "nis", "accepted")}
    out["accepted"] = out["accepted"].astype(bool)
    dof = np.array([len(v) for v in rec["nu"]], dtype=np.int64)
    out["dof"] = dof
    out["update_row"] = np.asarray(rec["update_row"], np.int64)
    out["status"] = (np.concatenate(rec["status"]).astype(np.int8) if rec["status"] else np.empty(0, np.int8))
    out["nis_dof"] = nis_dof(dof, out["status"])
    for kk in ("nu", "sigma"):
        if len(dof) and (dof == dof[0]).all():
            out[kk] = np.asarray(rec[kk])
        else:
            a = np.empty(len(rec[kk]), dtype=object)
            for i, v in enumerate(rec[kk]):
                a[i] = np.asarray(v)
            out[kk] = a
    return out


def _consistent(rejected, P):
    """Do the rejected innovations ``[(t, nu, R), ...]`` agree with each other?

    Each pair must differ by less than 4 sigma of their two noises plus the
    growth a velocity error of the filter's own sigma could cause between them
    (the innovations of a lost filter drift with its velocity error; random
    outliers, or a fix that disagrees with its neighbours, do not agree).
    """
    if len(rejected) < 2:
        return False
    sv2 = float(np.max(P.diagonal()[3:6]))
    for a in range(len(rejected)):
        ta, na, Ra = rejected[a]
        for b in range(a + 1, len(rejected)):
            tb, nb, Rb = rejected[b]
            if len(na) != len(nb):
                return False
            tol2 = 16.0 * (np.diag(Ra) + np.diag(Rb) + (tb - ta) ** 2 * sv2)
            if np.any((na - nb) ** 2 > tol2):
                return False
    return True


#: the recovery's constants, one definition for both paths (:mod:`._updates`)
DRIFT_MIN_POINTS, DRIFT_MAX_POINTS = U.DRIFT_MIN_POINTS, U.DRIFT_MAX_POINTS
POSITION_RANK_RATIO, TILT_GRAVITY = U.POSITION_RANK_RATIO, U.TILT_GRAVITY


def _drift(rejected, probability):
    """The common drift of the rejected innovations ``[(t, nu, R), ...]``
    (the current one last; the newest :data:`DRIFT_MAX_POINTS` of them):
    per row, the weighted least-squares fit
    ``c0 + c1 tau + c2 tau^2 / 2`` (``tau = t - t_now``; of degree
    ``n - 1`` below three points), its rate ``c1`` and acceleration ``c2``
    at the current time.

    A lost filter's innovations follow such a drift: its position error
    grows with its velocity error, and a tilt error leaks gravity into the
    horizontal channels (``g tan(tilt)``, 1.7 m/s^2 for 10 deg), so they
    grow with the square of time, much faster than the filter's own
    velocity sigma allows for (:func:`_consistent`).  Outliers, or fixes
    that disagree with their neighbours, do not follow one.

    Returns
    -------
    (rate, accel, g_rate, smooth) or None
        ``rate``, ``accel`` (k,); ``g_rate``: the variance of a row's rate
        per unit noise variance (``(B^T B)^-1[1, 1]``, B the fit's basis);
        ``smooth``: at least :data:`DRIFT_MIN_POINTS` rejections, and each
        row's weighted residual sum of squares within the chi-square gate
        of ``n - 3`` degrees of freedom at ``probability``.  None when the
        innovations differ in length or their times coincide.
    """
    rejected = rejected[-DRIFT_MAX_POINTS:]
    n = len(rejected)
    k = len(rejected[-1][1])
    if n < 2 or any(len(nu) != k for _, nu, _ in rejected):
        return None
    t_now = rejected[-1][0]
    tau = np.array([t - t_now for t, _, _ in rejected])
    m = min(3, n)
    B = np.stack([np.ones(n), tau, 0.5 * tau * tau], axis=1)[:, :m]
    if not np.linalg.det(B.T @ B) > 0.0:
        return None
    g_rate = float(np.linalg.inv(B.T @ B)[1, 1])
    thr = chi2_threshold(n - 3, probability) if n >= DRIFT_MIN_POINTS else np.inf
    rate, accel, smooth = np.zeros(k), np.zeros(k), n >= DRIFT_MIN_POINTS
    for r in range(k):
        y = np.array([nu[r] for _, nu, _ in rejected], float)
        w = 1.0 / np.array([R[r, r] for _, _, R in rejected], float)
        c = np.linalg.solve(B.T @ (w[:, None] * B), B.T @ (w * y))
        res = y - B @ c
        smooth = smooth and float(np.sum(w * res * res)) <= thr
        rate[r] = c[1]
        if m == 3:
            accel[r] = c[2]
    return rate, accel, g_rate, smooth


def _to_ned(H, R):
    """``(3, k)`` map of innovation rows to a NED position error (weighted
    least squares on H's position columns), or None when the measurement
    does not fix all three axes (:data:`POSITION_RANK_RATIO`)."""
    Hp = H[:, 0:3]
    w = 1.0 / np.diag(R)
    G = Hp.T @ (w[:, None] * Hp)
    d = G.diagonal()
    if not (d > 0.0).all() or not np.linalg.det(G) >= POSITION_RANK_RATIO * float(np.prod(d)):
        return None
    return np.linalg.solve(G, Hp.T * w)


#: a recovery's drift figures when it has none (a measurement that does not fix the position)
_NO_DRIFT = {"position_offset_m": None, "drift_velocity_m_s": None, "drift_accel_m_s2": None, "tilt_rad": None}
#: the recovery's constants, one definition for both paths (:mod:`._updates`)
REINIT_ABOVE_TILT, REINIT_SIGMAS = U.REINIT_ABOVE_TILT, U.REINIT_SIGMAS


def _recovery(P, nu, H, R, held, probability, nav_floor, fix_refused=False):
    """The recovery from a lost state, when the rejections ``held``
    (``[(t, nu, R), ...]``, the current one last) are evidence of it.

    * A measurement that fixes the position (a GNSS fix, pseudoranges):
      its rejections agree with each other (:func:`_consistent`) or follow
      one smooth drift (:func:`_drift`: a tilt-lost filter's fixes run away
      with the square of time, which the first test, bounded by the
      filter's own velocity sigma, never accepted).  When the drift's
      horizontal acceleration says a tilt beyond
      :data:`REINIT_ABOVE_TILT` (near the error model's small-angle limit,
      where the correlations it built no longer bring the filter back), the
      filter is re-initialised on the measurement (:func:`_reinitialise`);
      otherwise as below.
    * The navigation covariance is scaled just enough for the current
      innovation to pass the gate (:func:`_inflate_to_pass`); the update
      that follows moves position, velocity and attitude along the
      correlations the error model built.
    * A measurement that does not fix the position (a constraint, a
      velocity) recovers only when its rejections agree with each other and
      no measurement that fixes the position is being refused
      (``fix_refused``: its latest update was).  While the fixes are refused
      too, the filter is lost against them, and a constraint is no ground
      to recover on: its recoveries widened the covariance of a car
      standing still with a wrong initial tilt until its yaw wandered
      80 deg, which no later recovery on the fixes could bring back.

    Returns
    -------
    (P_new, dx, info) or None
        ``dx``: when re-initialised, the correction (position and velocity)
        to feed back into the navigation state before the update, which
        then takes ``nu - H dx`` for its innovation; else None.  ``info``:
        ``fixes_position``, ``reinitialised``, ``covariance_scale`` (the
        factor of the navigation variances; None when re-initialised) and,
        for a measurement that fixes the position (else None each), what
        its drift said: ``position_offset_m`` (the current innovation in
        NED), ``drift_velocity_m_s`` (its rate: the filter's velocity
        error), ``drift_accel_m_s2`` (its horizontal acceleration) and
        ``tilt_rad`` (the tilt error that acceleration says,
        ``atan(a / g)``).
    """
    to_ned = _to_ned(H, R)
    linear = _consistent(held, P)
    if to_ned is None:
        if not linear or fix_refused:
            return None
        Pa, alpha = _inflate_to_pass(P, nu, H, R, probability)
        return Pa, None, {"fixes_position": False, "reinitialised": False, "covariance_scale": alpha, **_NO_DRIFT}
    fit = _drift(held, probability)
    if fit is None or not (linear or fit[3]):
        return None
    rate, accel, g_rate, _ = fit
    dp, dv, da = to_ned @ nu, to_ned @ rate, to_ned @ accel
    a_h = float(np.hypot(da[0], da[1]))
    tilt = float(np.arctan2(a_h, TILT_GRAVITY))
    info = {"fixes_position": True, "reinitialised": tilt > REINIT_ABOVE_TILT,
            "position_offset_m": float(np.linalg.norm(dp)), "drift_velocity_m_s": float(np.linalg.norm(dv)),
            "drift_accel_m_s2": a_h, "tilt_rad": tilt}
    if info["reinitialised"]:
        Pn, dx = _reinitialise(P, nu, H, R, to_ned, dp, dv, tilt, g_rate, nav_floor, probability)
        return Pn, dx, {**info, "covariance_scale": None}
    Pa, alpha = _inflate_to_pass(P, nu, H, R, probability)
    return Pa, None, {**info, "covariance_scale": alpha}


def _reinitialise(P, nu, H, R, to_ned, dp, dv, tilt, g_rate, nav_floor, probability):
    """Re-initialise a lost filter on a measurement that fixes the position:
    ``(P_new, dx)``.

    The correction ``dx`` resets the position by the innovation in NED
    ``dp`` and the velocity by the drift's rate ``dv`` (:func:`_recovery`);
    the caller feeds it back and takes ``nu - H dx`` for the innovation.
    The navigation blocks (rows and columns 0..8) lose their correlations
    with each other and with every other block (which keep their own): the
    error model's correlations, built around an attitude outside its small
    angles, no longer hold.  They take the variances

    * position: ``max(P, P0)``, scaled by 4 until the innovation left
      passes the gate;
    * velocity: ``max(P, P0)`` plus :data:`REINIT_SIGMAS` squared times
      the fit variance of the rate (``g_rate`` times the measurement's NED
      variance, ``(Hp^T W Hp)^-1``);
    * attitude: ``max(P, P0) + tilt^2``.

    ``P0`` is the run's initial covariance (``nav_floor``: its first nine
    variances).  The attitude is the filter's own: the fixes that follow
    find it inside the widened covariance.
    """
    cov = np.diag(to_ned @ np.diag(np.diag(R)) @ to_ned.T)  # (Hp^T W Hp)^-1's diagonal
    add = np.concatenate([np.zeros(3), REINIT_SIGMAS ** 2 * g_rate * cov, np.full(3, tilt * tilt)])
    var = np.maximum(P.diagonal()[:9], nav_floor) + add
    Pn = P.copy()
    Pn[:9, :] = 0.0
    Pn[:, :9] = 0.0
    Pn[np.arange(9), np.arange(9)] = var
    dx = np.zeros(P.shape[0])
    dx[0:3], dx[3:6] = dp, dv
    nu_left = nu - H @ dx
    thr = chi2_threshold(len(nu), probability)
    scale = 1.0
    while scale < 1e16:
        if float(nu_left @ np.linalg.solve(H @ Pn @ H.T + R, nu_left)) <= thr:
            break
        Pn[np.arange(3), np.arange(3)] *= 4.0
        scale *= 4.0
    return Pn, dx


def _recovery_info(row):
    """A recovery's record from the compiled loop's row (:func:`._updates.recover`)."""
    keys = ("position_offset_m", "drift_velocity_m_s", "drift_accel_m_s2", "tilt_rad")
    info = {"fixes_position": bool(row[0]), "reinitialised": bool(row[6]),
            "covariance_scale": None if row[6] else float(row[5])}
    info.update({k: float(v) if row[0] else None for k, v in zip(keys, row[1:5])})
    return info


def _inflate_to_pass(P, nu, H, R, probability):
    """Scale the navigation blocks' covariance (rows and columns 0..8) by the
    smallest ``alpha`` of 2, 8, 32, ... for which the innovation passes
    the gate; sensor-error blocks keep their variances.  Returns
    ``(P_new, alpha)``."""
    from ..filters.kalman import chi2_threshold

    thr = chi2_threshold(len(nu), probability)

    def nis(alpha):
        d = np.ones(P.shape[0])
        d[:9] = np.sqrt(alpha)
        Pa = P * d[:, None] * d[None, :]
        S = H @ Pa @ H.T + R
        return float(nu @ np.linalg.solve(S, nu)), Pa

    alpha = 2.0
    v, Pa = nis(alpha)
    while v > thr and alpha < 1e16:
        alpha *= 4.0
        v, Pa = nis(alpha)
    return Pa, alpha

