"""Accelerometer-array layouts and what they can observe.

A layout is a set of single-axis accelerometers, each at a body position
``r_k`` (from the reference point b, body axes forward-right-down) with a unit
sensing axis ``e_k``.  Accelerometer k reads (SOURCES-NOTES §1.1, the
force-rebalance form of source 003 eq. 4-6)

``y_k = e_k . (f_b + omega_dot x r_k + omega x (omega x r_k))``

with ``omega = omega_ib_b = [p, q, r]``.  The reading is linear in twelve
parameters: the specific force ``f_b`` (3), the angular acceleration
``omega_dot`` (3, since ``e . (a x r) = a . (r x e)``) and the six distinct
entries of ``W = omega omega^T`` (since ``omega x (omega x r) = W r - tr(W) r``):

``y = H x``,  ``x = [f_x, f_y, f_z, p_dot, q_dot, r_dot, p^2, q^2, r^2, pq, pr, qr]``.

:func:`design_matrix` builds ``H``; :func:`observability` decides which
parameters a layout identifies (a parameter is identifiable when its unit
vector lies in the row space of ``H``) and whether the rate, with its signs,
can be recovered; :func:`require` refuses a layout that cannot deliver what is
asked, naming what it cannot observe.

The global sign of the rate is never observable from one epoch: ``W`` is the
same for ``omega`` and ``-omega``.  Signs come from integrating the observable
angular accelerations from a known start (source 003 §4) and, for components
whose angular acceleration is not sensed, from the observable products
``pr``, ``qr`` (SOURCES-NOTES §1.3).

References
----------
SYSTEM.md §5; SOURCES-NOTES §1.1 (sensor model), §1.2 (the ten-accelerometer
layout, positions of m5-m10 inferred from eq. 14, 15, 18, 35, 36), §1.3.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError

#: Names of the twelve parameters of the linear model, in the order of ``x``.
PARAMETERS = ("f_x", "f_y", "f_z", "p_dot", "q_dot", "r_dot", "p^2", "q^2", "r^2", "pq", "pr", "qr")
#: Index pairs ``(i, j)`` of the six entries of ``W = omega omega^T`` in ``x[6:12]``.
W_PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
RATE_NAMES = ("p", "q", "r")

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
#: a direction no layout is tuned to, for the generic-rank test of the rate
_GENERIC_RATE = np.array([0.3719, -0.6143, 0.8327])


@dataclass(frozen=True, eq=False)
class ArrayLayout:
    """Positions and sensing axes of an accelerometer array.

    Attributes
    ----------
    names : tuple of str
        One name per accelerometer (letters, digits, underscores; used as CSV
        column names).
    positions_b : (m, 3) ndarray
        Positions from the reference point b, body axes [m].
    axes_b : (m, 3) ndarray
        Unit sensing axes, body axes (normalised on construction; a norm off
        1 by more than 1e-3 is refused).
    label : str
        What the layout is (``"ten"``, ``"six"``, a file name).
    d : float or None
        The common lever arm of the source's layouts [m]; ``None`` otherwise.
    """

    names: tuple
    positions_b: np.ndarray
    axes_b: np.ndarray
    label: str = "custom"
    d: float | None = None
    _H: np.ndarray = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        names = tuple(str(n) for n in self.names)
        m = len(names)
        if m == 0:
            raise InputError("a layout needs at least one accelerometer")
        for n in names:
            if not _NAME.match(n):
                raise InputError(f"accelerometer name {n!r} must start with a letter and hold only letters, "
                                 "digits and underscores")
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise InputError(f"accelerometer names must be unique; repeated: {', '.join(dup)}")
        pos = np.array(self.positions_b, dtype=float)
        ax = np.array(self.axes_b, dtype=float)
        for nm, a in (("positions_b", pos), ("axes_b", ax)):
            if a.shape != (m, 3):
                raise InputError(f"`{nm}` must have shape ({m}, 3) for {m} accelerometers, got {a.shape}")
            if not np.isfinite(a).all():
                raise InputError(f"`{nm}` has a NaN or infinite value (accelerometer "
                                 f"{names[int(np.argmax(~np.isfinite(a).all(axis=1)))]})")
        norm = np.linalg.norm(ax, axis=1)
        bad = np.abs(norm - 1.0) > 1e-3
        if bad.any():
            k = int(np.argmax(bad))
            raise InputError(f"sensing axis of accelerometer {names[k]} has norm {norm[k]:.6g}; expected a unit "
                             "vector")
        ax = ax / norm[:, None]
        pos.setflags(write=False)
        ax.setflags(write=False)
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "positions_b", pos)
        object.__setattr__(self, "axes_b", ax)
        if self.d is not None:
            object.__setattr__(self, "d", float(self.d))
        object.__setattr__(self, "_H", design_matrix_from(pos, ax))

    def __len__(self):
        return len(self.names)

    @property
    def H(self):
        """``(m, 12)`` design matrix (see module docstring)."""
        return self._H

    @property
    def size(self):
        """Largest distance of an accelerometer from b [m] (1 when all sit at b)."""
        s = float(np.linalg.norm(self.positions_b, axis=1).max())
        return s if s > 0 else 1.0

    def with_axes(self, axes_b, label=None):
        """The same positions with other sensing axes (e.g. misaligned ones)."""
        return ArrayLayout(self.names, self.positions_b, axes_b, label or self.label, self.d)


def design_matrix_from(positions_b, axes_b):
    """``(m, 12)`` matrix ``H`` of ``y = H x`` for positions and unit axes.

    Row k: ``[e_k, r_k x e_k, e_i r_i - e.r (i = x, y, z), e_i r_j + e_j r_i
    ((i, j) = xy, xz, yz)]``.
    """
    r = np.asarray(positions_b, float)
    e = np.asarray(axes_b, float)
    er = np.sum(e * r, axis=1)
    H = np.empty((len(r), 12))
    H[:, 0:3] = e
    H[:, 3:6] = np.cross(r, e)
    for j, (a, b) in enumerate(W_PAIRS):
        H[:, 6 + j] = e[:, a] * r[:, a] - er if a == b else e[:, a] * r[:, b] + e[:, b] * r[:, a]
    return H


def design_matrix(layout: ArrayLayout):
    """The layout's ``(m, 12)`` design matrix (parameters :data:`PARAMETERS`)."""
    return layout.H


# --- the source's layouts ---------------------------------------------------------
def six_layout(d=0.1):
    """The six-accelerometer layout of source 003 §3 (a cube's face centres):
    pairs at ``+-d`` on each body axis sensing along that axis.

    Gives the specific force (eq. 13) and the rate magnitudes (eq. 14), not the
    rate signs.

    Parameters
    ----------
    d : float
        Lever arm [m] (unstated in the source; 0.1 m by default).
    """
    d = _check_d(d)
    pos = np.array([[d, 0, 0], [-d, 0, 0], [0, d, 0], [0, -d, 0], [0, 0, d], [0, 0, -d]], float)
    ax = np.array([[1, 0, 0], [1, 0, 0], [0, 1, 0], [0, 1, 0], [0, 0, 1], [0, 0, 1]], float)
    return ArrayLayout(tuple(f"m{k}" for k in range(1, 7)), pos, ax, "six", d)


def ten_layout(d=0.1):
    """The ten-accelerometer layout of source 003 §4 (SOURCES-NOTES §1.2).

    m1-m6 as :func:`six_layout`; m7 at ``+d b1`` sensing b3, m8 at ``+d b3``
    sensing b1 (they give ``q_dot`` and ``pr``, eq. 15-17), m9 at ``+d b2``
    sensing b3, m10 at ``+d b3`` sensing b2 (``p_dot`` and ``qr``, eq. 18-19).
    The positions of m5-m10 are not printed; they are the unique ones that
    make eq. 14, 15, 18, 35 and 36 hold.

    Parameters
    ----------
    d : float
        Lever arm [m] (unstated in the source; 0.1 m by default).
    """
    d = _check_d(d)
    six = six_layout(d)
    pos = np.vstack([six.positions_b, [[d, 0, 0], [0, 0, d], [0, d, 0], [0, 0, d]]])
    ax = np.vstack([six.axes_b, [[0, 0, 1], [1, 0, 0], [0, 0, 1], [0, 1, 0]]])
    return ArrayLayout(tuple(f"m{k}" for k in range(1, 11)), pos, ax, "ten", d)


def _check_d(d):
    d = float(d)
    if not (np.isfinite(d) and d > 0):
        raise InputError(f"the lever arm `d` must be a finite number > 0 m, got {d}")
    return d


def builtin_layout(name, d=0.1):
    """``"ten"`` or ``"six"`` with lever arm ``d`` [m]."""
    if name == "ten":
        return ten_layout(d)
    if name == "six":
        return six_layout(d)
    raise InputError(f"unknown built-in layout {name!r}; expected 'ten', 'six' or a layout file")


def source_index(layout: ArrayLayout):
    """``"ten"`` or ``"six"`` when the layout has the geometry of the source's
    layout of that size (same order, any ``d``), else ``None``."""
    m = len(layout)
    if m not in (6, 10):
        return None
    d = float(np.linalg.norm(layout.positions_b[0]))
    if d <= 0:
        return None
    ref = ten_layout(d) if m == 10 else six_layout(d)
    ok = (np.abs(layout.positions_b - ref.positions_b).max() <= 1e-9 * d
          and np.abs(layout.axes_b - ref.axes_b).max() <= 1e-9)
    return ref.label if ok else None


# --- observability -------------------------------------------------------------------
@dataclass(frozen=True)
class Observability:
    """What a layout observes.

    Attributes
    ----------
    label : str
        The layout's label.
    rank : int
        Rank of the design matrix (at most 12).
    identifiable : dict of str -> bool
        For each of :data:`PARAMETERS`, whether one epoch determines it.
    quadratic_rank : int
        Rank, at a generic rate, of the Jacobian of the identifiable ``W``
        entries with respect to ``omega`` (3: the rate is determined up to
        the global sign by the centripetal terms).
    sign_tracked : tuple of 3 bool
        Whether the sign of p, q, r can be carried from the start: its angular
        acceleration is identifiable, or an identifiable product links it to a
        component that is sign-tracked.
    rate_source : str or None
        ``"quadratic"`` (rates from ``W``, signs from integrated angular
        accelerations and the products), ``"integrated"`` (angular
        accelerations only, rates by integration from a known start: drift),
        or ``None`` (no signed rate).
    magnitudes : bool
        Whether ``|p|, |q|, |r|`` are determined (from ``W``'s diagonal or by
        integration).
    """

    label: str
    rank: int
    identifiable: dict
    quadratic_rank: int
    sign_tracked: tuple
    rate_source: str | None
    magnitudes: bool

    def observable(self):
        """Names of the identifiable parameters."""
        return [k for k in PARAMETERS if self.identifiable[k]]

    def unobservable(self):
        """Names of the parameters one epoch does not determine."""
        return [k for k in PARAMETERS if not self.identifiable[k]]

    @property
    def specific_force(self):
        return all(self.identifiable[k] for k in PARAMETERS[:3])

    @property
    def signed_rate(self):
        return self.rate_source is not None

    @property
    def omega_dot_mask(self):
        return np.array([self.identifiable[k] for k in PARAMETERS[3:6]])

    @property
    def quadratic_mask(self):
        return np.array([self.identifiable[k] for k in PARAMETERS[6:12]])


def observability(layout: ArrayLayout, *, rtol=1e-9) -> Observability:
    """Decide what the layout observes (see :class:`Observability`).

    The columns of ``H`` that multiply lever arms are scaled by the array's
    size before the singular-value decomposition, so the rank test does not
    depend on the unit of length; singular values below ``rtol`` times the
    largest count as zero.
    """
    H = layout.H
    scale = np.ones(12)
    scale[3:] = layout.size
    Hs = H * scale
    _, s, vt = np.linalg.svd(Hs)
    rank = int(np.sum(s > rtol * s[0])) if s.size and s[0] > 0 else 0
    null = vt[rank:]  # rows span the null space (scaled coordinates)
    ident = {}
    for j, name in enumerate(PARAMETERS):
        ident[name] = bool(np.linalg.norm(null[:, j]) < 1e-7) if len(null) else True
    wmask = [ident[k] for k in PARAMETERS[6:12]]
    amask = [ident[k] for k in PARAMETERS[3:6]]
    w = _GENERIC_RATE
    rows = [_w_jacobian_row(j, w) for j in range(6) if wmask[j]]
    qrank = int(np.linalg.matrix_rank(np.array(rows), tol=1e-9)) if rows else 0
    tracked = list(amask)
    changed = True
    while changed:
        changed = False
        for j, (a, b) in enumerate(W_PAIRS):
            if a != b and wmask[j] and (tracked[a] != tracked[b]):
                tracked[a] = tracked[b] = True
                changed = True
    if all(amask):
        source = "integrated" if qrank < 3 else "quadratic"
    elif qrank == 3 and all(tracked):
        source = "quadratic"
    else:
        source = None
    magnitudes = all(wmask[:3]) or qrank == 3 or all(amask)
    return Observability(layout.label, rank, ident, qrank, tuple(tracked), source, magnitudes)


def _w_jacobian_row(j, w):
    a, b = W_PAIRS[j]
    row = np.zeros(3)
    row[a] += w[b]
    row[b] += w[a]
    return row


def require(layout: ArrayLayout, *, rate="signed", obs: Observability | None = None) -> Observability:
    """Refuse a layout that cannot observe what is asked.

    Parameters
    ----------
    layout : ArrayLayout
    rate : {"signed", "magnitude", "none"}
        ``"signed"``: the specific force and the full rate vector (what an
        :class:`~inskit.types.ImuData` needs); ``"magnitude"``: the specific
        force and ``|p|, |q|, |r|``; ``"none"``: the specific force only.

    Returns
    -------
    Observability

    Raises
    ------
    InputError
        Naming what cannot be observed, e.g. "layout 'six' cannot observe the
        signs of the angular rates p, q, r: ...".
    """
    if rate not in ("signed", "magnitude", "none"):
        raise InputError(f"`rate` must be 'signed', 'magnitude' or 'none', got {rate!r}")
    o = obs or observability(layout)
    problems = []
    missing_f = [k for k in PARAMETERS[:3] if not o.identifiable[k]]
    if missing_f:
        problems.append(f"the specific force component(s) {', '.join(missing_f)}")
    miss_a = [k for k in PARAMETERS[3:6] if not o.identifiable[k]]
    miss_w = [k for k in PARAMETERS[6:12] if not o.identifiable[k]]
    if rate == "signed" and o.rate_source is None:
        why = []
        if len(miss_a) == 3:
            why.append("no accelerometer senses angular acceleration (p_dot, q_dot, r_dot unobservable)")
        elif miss_a:
            why.append(f"the angular acceleration(s) {', '.join(miss_a)} are unobservable")
        if miss_w:
            why.append(f"the rate-quadratic term(s) {', '.join(miss_w)} are unobservable")
        untracked = [RATE_NAMES[i] for i in range(3) if not o.sign_tracked[i]]
        if o.quadratic_rank < 3:
            what = "the angular rates p, q, r"
            why.append(f"the centripetal terms fix only {o.quadratic_rank} of the 3 rate components")
        else:
            what = f"the sign(s) of the angular rate(s) {', '.join(untracked or RATE_NAMES)}"
        problems.append(f"{what} ({'; '.join(why)})")
    elif rate == "magnitude" and not o.magnitudes:
        problems.append(f"the rate magnitudes |p|, |q|, |r| (unobservable: {', '.join(miss_a + miss_w)})")
    if problems:
        hint = ""
        if rate == "signed" and o.magnitudes and not missing_f and o.rate_source is None:
            hint = "; it gives |p|, |q|, |r| only (rate='magnitude')"
        raise InputError(f"layout '{o.label}' ({len(layout)} accelerometers, rank {o.rank} of 12) cannot observe "
                         f"{' and '.join(problems)}. Observable: {', '.join(o.observable()) or 'nothing'}{hint}")
    return o


__all__ = [
    "PARAMETERS",
    "RATE_NAMES",
    "W_PAIRS",
    "ArrayLayout",
    "Observability",
    "builtin_layout",
    "design_matrix",
    "design_matrix_from",
    "observability",
    "require",
    "six_layout",
    "source_index",
    "ten_layout",
]
