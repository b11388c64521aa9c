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
    m = len(st.k)
    n = lay.size
    e_post = np.zeros((m, n))
    Ps = np.empty((m, n, n))
    Ps[-1] = st.P_plus[-1]
    for j in range(m - 2, -1, -1):
        Pm = st.P_minus[j + 1]
        A = np.linalg.solve(Pm, st.Phi[j + 1] @ st.P_plus[j]).T
        e_post[j] = A @ (e_post[j + 1] + st.dx[j + 1])
        D = Ps[j + 1] - Pm
        Ps[j] = st.P_plus[j] + A @ D @ A.T
        Ps[j] = 0.5 * (Ps[j] + Ps[j].T)
    # the initial epoch (row 0)
    P0 = lay.initial_covariance()
    A0 = np.linalg.solve(st.P_minus[0], st.Phi[0] @ P0).T
    e0 = A0 @ (e_post[0] + st.dx[0])
    Ps0 = P0 + A0 @ (Ps[0] - st.P_minus[0]) @ A0.T

    sol = out.nav
    N = len(sol)
    t = sol.time
    ks = np.asarray(st.k)
    # smoothed error at every row: piecewise linear between node anchors
    e_rows = np.zeros((N, n))
    anchors_k = np.concatenate([[0], ks])
    e_start = np.vstack([e0, e_post])               # value just after each anchor
    e_end = np.vstack([e_post + np.asarray(st.dx), np.zeros((1, n))])  # value just before the next anchor
    for a in range(len(anchors_k)):
        k0 = anchors_k[a]
        k1 = anchors_k[a + 1] if a + 1 < len(anchors_k) else N
        e_rows[k0] = e_start[a]
        if k1 - k0 > 1:
            if a + 1 < len(anchors_k):
                w = ((t[k0 + 1:k1] - t[k0]) / (t[k1] - t[k0]))[:, None]
                e_rows[k0 + 1:k1] = e_start[a] * (1 - w) + e_end[a] * w
            else:
                e_rows[k0 + 1:k1] = e_start[a]
    lla, v, q = _correct(sol, e_rows)
    # sigmas at the anchors, interpolated in time
    sig_nodes = np.sqrt(np.maximum(np.vstack([np.diag(Ps0)[None, :], np.einsum("jii->ji", Ps)]), 0.0))
    t_nodes = t[anchors_k]
    sigma = np.column_stack([np.interp(t, t_nodes, sig_nodes[:, i]) for i in range(n)])
    aux = out.aux - e_rows[:, lay.aux_state_index]
    return Track(NavSolution._trusted(t, lla, v, q), aux, sigma, lay)


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
