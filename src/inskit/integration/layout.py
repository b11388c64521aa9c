"""The error-state layout: built from a list of blocks, owns every index.

Error states are ``estimate - truth`` (SYSTEM.md §2; Groves 2013 §14.2).  The
layout places the blocks one after the other (the navigation blocks ``pos``,
``vel``, ``att`` first, at 0, 3, 6), and places the blocks that carry an
estimate (sensor errors, lever arm, offsets, clocks...) in one vector of
auxiliary estimates ``aux``.  It builds, from what the blocks declare, the
process noise, the initial covariance, the constant and epoch-dependent
entries of F and their sparse pattern, and the reported names.  Nothing else
in the package hard-codes a state index.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from ..errors import InputError
from .blocks import NAV_ROLES, SENSOR_ROLES, StateBlock, ins_blocks

#: order of the kernel index array: state starts of the sensor roles, their
#: starts in ``aux``, then the state size
KERNEL_ROLES = SENSOR_ROLES


class StateLayout:
    """The blocks of the error state and where each one lives.

    Parameters
    ----------
    blocks : sequence of StateBlock
        The first three must have the roles ``pos``, ``vel``, ``att``; names
        must be unique; each sensor role may appear once.

    Examples
    --------
    >>> lay = StateLayout(ins_blocks(scale_factors=True))
    >>> lay.size, lay.slice("sa")
    (21, slice(18, 21, None))
    """

    def __init__(self, blocks=None):
        blocks = tuple(ins_blocks() if blocks is None else blocks)
        for b in blocks:
            if not isinstance(b, StateBlock):
                raise InputError(f"a layout takes StateBlock objects, got {type(b).__name__}")
        if len(blocks) < 3 or tuple(b.role for b in blocks[:3]) != NAV_ROLES:
            raise InputError("a layout starts with the navigation blocks pos, vel, att (in this order)")
        names = [b.name for b in blocks]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise InputError(f"state block names must be unique; repeated: {sorted(dup)}")
        roles = [b.role for b in blocks if b.role is not None]
        dup = {r for r in roles if roles.count(r) > 1}
        if dup:
            raise InputError(f"each role may appear once in a layout; repeated: {sorted(dup)}")
        if any(b.role in NAV_ROLES for b in blocks[3:]):
            raise InputError("navigation blocks may appear only as the first three")
        self.blocks = blocks
        self._by_name = {b.name: b for b in blocks}
        self._by_role = {b.role: b for b in blocks if b.role is not None}
        self._slices, self._aux = {}, {}
        i = a = 0
        for b in blocks:
            self._slices[b.name] = slice(i, i + b.size)
            i += b.size
            if b.has_estimate:
                self._aux[b.name] = slice(a, a + b.size)
                a += b.size
        self.size = i
        self.aux_size = a
        for b in blocks:
            for (r, cb, c, _) in b.transition():
                if cb not in self._by_name:
                    raise InputError(f"state block {b.name!r} couples to block {cb!r}, which is not in the layout")
                if not (0 <= r < b.size and 0 <= c < self._by_name[cb].size):
                    raise InputError(f"state block {b.name!r}: transition entry ({r}, {cb}[{c}]) is out of range")

    def __repr__(self):
        return f"StateLayout([{', '.join(b.name for b in self.blocks)}], size={self.size})"

    # --- lookup -------------------------------------------------------------------
    def __contains__(self, name):
        return name in self._by_name

    def block(self, name) -> StateBlock:
        return self._by_name[name]

    def slice(self, name):
        """``slice`` of a block in the state vector; ``None`` if absent."""
        return self._slices.get(name)

    def aux_slice(self, name):
        """``slice`` of a block's estimate in the ``aux`` vector; ``None`` if absent."""
        return self._aux.get(name)

    def by_role(self, role):
        """The block with this role, or ``None``."""
        return self._by_role.get(role)

    @property
    def names(self):
        """Names of the blocks, in order."""
        return tuple(b.name for b in self.blocks)

    def state_names(self):
        """``block_axis`` for every state, in order."""
        return [f"{b.name}_{a}" for b in self.blocks for a in b.axes]

    # --- what the filter needs ---------------------------------------------------------
    @cached_property
    def aux_state_index(self):
        """(aux_size,) int: the state index of every aux element."""
        out = np.empty(self.aux_size, dtype=np.int64)
        for name, s in self._aux.items():
            out[s] = np.arange(self._slices[name].start, self._slices[name].stop)
        return out

    def initial_aux(self):
        """(aux_size,) the blocks' initial estimates."""
        out = np.zeros(self.aux_size)
        for name, s in self._aux.items():
            out[s] = self._by_name[name].estimate0
        return out

    def initial_covariance(self):
        """Diagonal ``P0`` from the blocks' ``sigma0``."""
        return np.diag(np.concatenate([b.sigma0 for b in self.blocks]) ** 2)

    def process_noise(self):
        """(size,) diagonal PSDs ``q`` (``Q = diag(q) dt``)."""
        return np.concatenate([b.psd for b in self.blocks])

    def body_noise(self):
        """(6,) body-axis white-noise PSDs ``[att (3), vel (3)]`` that the
        propagation rotates into NED at every step, ``C_nb diag(q_b) C_bn``
        (:attr:`.blocks.StateBlock.body_psd`; zeros for a block without),
        or ``None`` when no block has them."""
        att, vel = self.by_role("att"), self.by_role("vel")
        if all(b is None or b.body_psd is None for b in (att, vel)):
            return None
        out = np.zeros(6)
        for b, s in ((att, slice(0, 3)), (vel, slice(3, 6))):
            if b is not None and b.body_psd is not None:
                out[s] = b.body_psd
        return out

    def kernel_index(self):
        """int64 ``[x_bg, x_ba, x_sg, x_sa, a_bg, a_ba, a_sg, a_sa, size]``:
        state and aux starts of the sensor roles (-1 if absent)."""
        xs, aus = [], []
        for role in KERNEL_ROLES:
            b = self.by_role(role)
            xs.append(-1 if b is None else self._slices[b.name].start)
            aus.append(-1 if b is None else self._aux[b.name].start)
        return np.array(xs + aus + [self.size], dtype=np.int64)

    def constant_entries(self):
        """``(rows, cols, values)`` of the blocks' constant F entries."""
        r, c, v = [], [], []
        for b in self.blocks:
            s = self._slices[b.name]
            for (i, cb, j, val) in b.transition():
                r.append(s.start + i)
                c.append(self._slices[cb].start + j)
                v.append(float(val))
        return np.array(r, np.int64), np.array(c, np.int64), np.array(v, float)

    def _block_of_state(self, i):
        for k, b in enumerate(self.blocks):
            s = self._slices[b.name]
            if s.start <= i < s.stop:
                return k
        raise IndexError(i)

    def estimate_dynamics(self):
        """``(idx, F)``: the aux elements whose estimates evolve between
        updates and the constant F among them, for the blocks that ask for it
        (``predict_estimate``: a receiver clock, whose bias runs on with its
        drift).

        Such an estimate is predicted with ``exp(F dt)``, as its error state
        is.  Every other estimate is held between updates: a sensor bias's
        estimate is its turn-on part, and its Gauss-Markov model describes
        the error of that estimate (as KF-GINS and most INS filters do;
        decaying the estimate itself made the drive_0708 outage RMS 3.03 m
        instead of 2.77 m).  ``idx`` is empty when nothing evolves.
        """
        state_to_aux = {int(s): a for a, s in enumerate(self.aux_state_index)
                        if self.blocks[self._block_of_state(int(s))].predict_estimate}
        r, c, v = self.constant_entries()
        keep = [(state_to_aux[int(i)], state_to_aux[int(j)], float(x)) for i, j, x in zip(r, c, v)
                if int(i) in state_to_aux and int(j) in state_to_aux]
        idx = np.array(sorted({a for a, _, _ in keep} | {b for _, b, _ in keep}), dtype=np.int64)
        F = np.zeros((len(idx), len(idx)))
        where = {a: k for k, a in enumerate(idx.tolist())}
        for a, b, x in keep:
            F[where[a], where[b]] += x
        return idx, F

    def transition_pattern(self):
        """``(rows, cols)`` of the entries of F that can be non-zero.

        The compiled kernel multiplies only these, so the cost of the
        covariance propagation grows with them, not with ``size**2``.  Skew
        blocks have zero diagonals; of the position-to-velocity block only
        the gravity gradient ``(vD, pD)`` is used; the rest comes
        from the sensor roles and the blocks' constant entries.
        """
        n = self.size
        mask = np.zeros((n, n), dtype=bool)
        p, v, a = 0, 3, 6
        off = ~np.eye(3, dtype=bool)
        mask[p:p + 3, v:v + 3] = np.eye(3, dtype=bool)
        mask[v + 2, p + 2] = True                   # gravity with height
        mask[v:v + 3, v:v + 3] = off
        mask[v:v + 3, a:a + 3] = off
        mask[a:a + 3, a:a + 3] = off
        mask[a + 0, v + 1] = mask[a + 1, v + 0] = mask[a + 2, v + 1] = True  # transport-rate error
        for role, rows in (("gyro_bias", a), ("accel_bias", v), ("gyro_scale", a), ("accel_scale", v)):
            b = self.by_role(role)
            if b is not None:
                s = self._slices[b.name]
                mask[rows:rows + 3, s] = True
        r, c, _ = self.constant_entries()
        mask[r, c] = True
        rows, cols = np.nonzero(mask)
        return rows.astype(np.int64), cols.astype(np.int64)

    # --- reporting ----------------------------------------------------------------------
    def estimate_names(self):
        """Names of the aux elements, in order."""
        out = []
        for b in self.blocks:
            if b.has_estimate:
                out += b.estimate_names()
        return out

    def sigma_names(self):
        """Names of the sigma of every state, in order."""
        return [nm for b in self.blocks for nm in b.sigma_names()]

    def columns(self, aux=None, sigma=None, sigma_blocks=None):
        """Named columns ``{name: (N,) array}`` of estimates and sigmas (made
        only for files and tables; the filter keeps arrays).  ``sigma_blocks``
        limits the sigmas to these blocks (all by default)."""
        out = {}
        if sigma is not None:
            for b in self.blocks:
                if sigma_blocks is not None and b.name not in sigma_blocks:
                    continue
                s = self._slices[b.name]
                for j, nm in zip(range(s.start, s.stop), b.sigma_names()):
                    out[nm] = sigma[:, j]
        if aux is not None:
            for j, nm in enumerate(self.estimate_names()):
                out[nm] = aux[:, j]
        return out
