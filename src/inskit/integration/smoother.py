"""Rauch-Tung-Striebel smoothing of a closed-loop error-state filter run.

The forward pass keeps, at every node ``j`` (update epochs plus a regular
grid), the prior and posterior covariances ``P-_j``, ``P+_j``, the transition
``Phi_j`` from node ``j-1`` to ``j`` and the correction ``dx_j`` that the
update fed back.  After the feedback the filter's error estimate is zero, so
the RTS recursion (Rauch, Tung & Striebel 1965; Groves 2013 eq. 3.80-3.81)
reads, for the error ``e = nominal - truth`` of the post-update nominal state:

``A_j = P+_j Phi_{j+1}^T (P-_{j+1})^-1``
``e_j = A_j (e_{j+1} + dx_{j+1})``  (the prior nominal at ``j+1`` is off by
``dx_{j+1}`` more than the posterior)
``Ps_j = P+_j + A_j (Ps_{j+1} - P-_{j+1}) A_j^T``.

Between nodes the nominal trajectory is continuous, and the smoothed error is
interpolated linearly from ``e_j`` to ``e_{j+1} + dx_{j+1}``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import earth
from .. import rotations as rot
from ..errors import InputError
from ..types import NavSolution
from .engine import FilterOutput, Track


def rts_smooth(out: FilterOutput) -> Track:
    """Smoothed track (navigation solution, estimates of every block and
    sigmas of every state) of a run made with ``run_filter(..., smoother=True)``."""
    st = out.store
    if st is None or not st.k:
        raise InputError("the filter run kept no smoother data: run it with smoother=True")
    lay = out.layout
    nodes = backward_pass(lambda j0, j1: (np.asarray(st.k[j0:j1]), st.P_minus[j0:j1], st.P_plus[j0:j1],
                                          st.Phi[j0:j1], st.dx[j0:j1]), len(st.k), lay.initial_covariance())
    sol = out.nav
    nodes.t = sol.time[nodes.k]
    return smooth_rows(nodes, lay, sol, out.aux, np.arange(len(sol)))


def smooth_rows(nodes, lay, sol: NavSolution, aux, rows) -> Track:
    """The smoothed track at IMU rows ``rows`` (sorted) of the forward
    solution ``sol`` and estimates ``aux`` given at those rows only (a
    segment of a streamed run, or its kept rows)."""
    e_rows = nodes.errors_at(rows, sol.time)
    lla, v, q = _correct(sol, e_rows)
    return Track(NavSolution._trusted(sol.time, lla, v, q), aux - e_rows[:, lay.aux_state_index],
                 nodes.sigma_at(rows, sol.time), lay)


@dataclass
class SmoothedNodes:
    """The RTS recursion's result per anchor (row 0, then every node):
    the smoothed error just after the anchor (``e_start``) and just before
    the next one (``e_end``), and the smoothed sigmas at the anchor.  Any row
    of the run is then found from these alone (:meth:`errors_at`,
    :meth:`sigma_at`), so a streamed run smooths segment by segment."""

    k: np.ndarray          #: (m + 1,) IMU row of each anchor (0 first)
    t: np.ndarray          #: (m + 1,) its time (set by the caller, who has the rows' times)
    e_start: np.ndarray    #: (m + 1, n)
    e_end: np.ndarray      #: (m + 1, n)
    sigma: np.ndarray      #: (m + 1, n)

    def errors_at(self, rows, t_rows):
        """Smoothed errors at IMU rows ``rows`` (sorted, at times
        ``t_rows``): piecewise linear in time between anchors, as the
        nominal trajectory is continuous between nodes."""
        rows, t = np.asarray(rows), np.asarray(t_rows)
        a = np.searchsorted(self.k, rows, side="right") - 1
        last = len(self.k) - 1
        inner = (rows != self.k[a]) & (a < last)
        e = self.e_start[a].copy()
        if inner.any():
            ai = a[inner]
            k0t, k1t = self.t[ai], self.t[ai + 1]
            w = ((t[inner] - k0t) / (k1t - k0t))[:, None]
            e[inner] = self.e_start[ai] * (1 - w) + self.e_end[ai] * w
        return e

    def sigma_at(self, rows, t_rows):
        """Smoothed sigmas, interpolated in time between anchors."""
        return np.column_stack([np.interp(t_rows, self.t, self.sigma[:, i]) for i in range(self.sigma.shape[1])])


def backward_pass(block, m, P0, block_nodes=4096) -> SmoothedNodes:
    """The RTS recursion over ``m`` nodes (module text), reading the
    forward pass's node data in blocks from the last node back.

    Parameters
    ----------
    block : callable
        ``block(j0, j1) -> (k, P_minus, P_plus, Phi, dx)`` of nodes
        ``j0 .. j1-1`` (arrays, or lists of arrays).
    m : int
        Number of nodes.
    P0 : (n, n) ndarray
        Initial covariance (row 0).

    Returns
    -------
    SmoothedNodes
        ``t`` unset (NaN): the caller knows the times of the rows.
    """
    n = P0.shape[0]
    ks = np.empty(m, np.int64)
    e_post = np.zeros((m, n))
    e_end = np.zeros((m + 1, n))
    sig = np.empty((m + 1, n))
    k_l, Pm_l, Pp_l, Phi_l, dx_l = block(m - 1, m)
    ks[m - 1] = k_l[0]
    Ps_next = np.asarray(Pp_l[0])
    sig[m] = np.sqrt(np.maximum(np.diag(Ps_next), 0.0))
    nxt = (np.asarray(Pm_l[0]), np.asarray(Phi_l[0]), np.asarray(dx_l[0]))
    e_end[m - 1] = e_post[m - 1] + nxt[2]
    for j1 in range(m - 1, 0, -block_nodes):
        j0 = max(0, j1 - block_nodes)
        k_b, Pm_b, Pp_b, Phi_b, dx_b = block(j0, j1)
        for j in range(j1 - 1, j0 - 1, -1):
            Pm, Phi1, dx1 = nxt
            Pp = np.asarray(Pp_b[j - j0])
            A = np.linalg.solve(Pm, Phi1 @ Pp).T
            e_post[j] = A @ (e_post[j + 1] + dx1)
            D = Ps_next - Pm
            Ps = Pp + A @ D @ A.T
            Ps_next = 0.5 * (Ps + Ps.T)
            sig[j + 1] = np.sqrt(np.maximum(np.diag(Ps_next), 0.0))
            nxt = (np.asarray(Pm_b[j - j0]), np.asarray(Phi_b[j - j0]), np.asarray(dx_b[j - j0]))
            e_end[j] = e_post[j] + nxt[2]
            ks[j] = k_b[j - j0]
    # the initial epoch (row 0)
    Pm0, Phi0, dx0 = nxt
    A0 = np.linalg.solve(Pm0, Phi0 @ P0).T
    e0 = A0 @ (e_post[0] + dx0)
    Ps0 = P0 + A0 @ (Ps_next - Pm0) @ A0.T
    sig[0] = np.sqrt(np.maximum(np.diag(Ps0), 0.0))
    # anchors: row 0 then every node; the error just after each, and just before the next (the prior nominal at
    # node j+1 is off by dx_{j+1} more than the posterior); the last anchor holds its value to the end
    e_start = np.vstack([e0[None, :], e_post])
    e_end = np.vstack([e_end[:m], np.zeros((1, n))])
    return SmoothedNodes(np.concatenate([[0], ks]), np.full(m + 1, np.nan), e_start, e_end, sig)


class DiskStore:
    """The smoother's node data of a streamed run, in files (one per array,
    appended segment by segment; the page cache, not the process, holds
    them), read back in blocks by :meth:`block`.

    Parameters
    ----------
    folder : Path
        Where the files go (removed by :meth:`remove`).
    n : int
        States.
    """

    NAMES = ("k", "Pm", "Pp", "Phi", "dx")

    def __init__(self, folder, n):
        from pathlib import Path

        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.n = n
        self.m = 0
        self._fh = {k: open(self.folder / f"{k}.bin", "wb") for k in self.NAMES}

    def __call__(self, k, Pm, Pp, Phi, dx):
        """Append a segment's nodes (the engine's ``store_sink``)."""
        for name, a in zip(self.NAMES, (k, Pm, Pp, Phi, dx)):
            np.ascontiguousarray(a, np.int64 if name == "k" else np.float64).tofile(self._fh[name])
        self.m += len(k)

    def close(self):
        for fh in self._fh.values():
            fh.close()

    def block(self, j0, j1):
        """Nodes ``j0 .. j1-1``: ``(k, P_minus, P_plus, Phi, dx)``."""
        n, c = self.n, j1 - j0
        out = []
        for name in self.NAMES:
            per = 1 if name == "k" else (n if name == "dx" else n * n)
            a = np.fromfile(self.folder / f"{name}.bin", dtype=np.int64 if name == "k" else np.float64,
                            count=c * per, offset=j0 * per * 8)
            out.append(a if name == "k" else a.reshape((c, n) if name == "dx" else (c, n, n)))
        return tuple(out)

    def remove(self):
        import shutil

        self.close()
        shutil.rmtree(self.folder, ignore_errors=True)


def _correct(sol, e):
    """Remove error estimates ``e`` (rows; navigation blocks at 0, 3, 6) from
    a solution, vectorised."""
    lla = sol.lla.copy()
    rn, re = earth.principal_radii(lla[:, 0], lla[:, 2])
    lla[:, 0] -= e[:, 0] / rn
    lla[:, 1] -= e[:, 1] / (re * np.cos(sol.lla[:, 0]))
    lla[:, 2] += e[:, 2]
    vel = sol.v_n - e[:, 3:6]
    q = rot.quat_multiply(rot.quat_from_rotvec(e[:, 6:9]), sol.q_nb)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return lla, vel, q
