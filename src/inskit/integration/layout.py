"""The error-state layout: one object owns every index.

Error states are ``estimate - truth`` (SYSTEM.md §2; Groves 2013 §14.2):

======  ====  ==========================================================
block   size  meaning
======  ====  ==========================================================
pos     3     position error north, east, down [m]
vel     3     velocity error in NED [m/s]
att     3     attitude error phi [rad]: ``C_nb_est = (I - [phi x]) C_nb``
bg      3     gyro bias error [rad/s]
ba      3     accelerometer bias error [m/s^2]
sg      3     gyro scale-factor error [-] (optional)
sa      3     accelerometer scale-factor error [-] (optional)
lever   3     IMU-to-antenna lever arm error, body axes [m] (optional)
dt      1     IMU-GNSS time offset error [s] (optional): a GNSS time tag
              ``t`` matches the INS at ``t + offset``
======  ====  ==========================================================

Nothing else in the package hard-codes a state index.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

BLOCKS = ("pos", "vel", "att", "bg", "ba", "sg", "sa", "lever")  # the blocks the compiled kernel knows
SIZES = {"pos": 3, "vel": 3, "att": 3, "bg": 3, "ba": 3, "sg": 3, "sa": 3, "lever": 3, "dt": 1}


@dataclass(frozen=True)
class StateLayout:
    """Which optional blocks are in the filter, and where each block lives.

    Parameters
    ----------
    scale_factors : bool
        Add gyro and accelerometer scale-factor errors (15 -> 21 states).
    lever_arm : bool
        Estimate the IMU-to-antenna lever arm.
    time_offset : bool
        Estimate the IMU-GNSS time offset (one state, a random constant or
        slow random walk; the measurements carry its Jacobian).
    """

    scale_factors: bool = False
    lever_arm: bool = False
    time_offset: bool = False

    @cached_property
    def blocks(self):
        out = ["pos", "vel", "att", "bg", "ba"]
        if self.scale_factors:
            out += ["sg", "sa"]
        if self.lever_arm:
            out += ["lever"]
        if self.time_offset:
            out += ["dt"]
        return tuple(out)

    @cached_property
    def size(self):
        return sum(SIZES[b] for b in self.blocks)

    @cached_property
    def _slices(self):
        out, i = {}, 0
        for b in self.blocks:
            out[b] = slice(i, i + SIZES[b])
            i += SIZES[b]
        return out

    def slice(self, block):
        """``slice`` of a block in the state vector; ``None`` if absent."""
        return self._slices.get(block)

    def start(self, block):
        """First index of a block, or -1 if absent (for the compiled kernel)."""
        s = self.slice(block)
        return -1 if s is None else s.start

    def kernel_index(self):
        """int64 array ``[pos, vel, att, bg, ba, sg, sa, lever, size]`` of starts."""
        return np.array([self.start(b) for b in BLOCKS] + [self.size], dtype=np.int64)

    def names(self):
        """Human-readable names of every state, in order."""
        axes = {"pos": "NED", "vel": "NED", "att": "NED", "bg": "xyz", "ba": "xyz", "sg": "xyz", "sa": "xyz",
                "lever": "xyz", "dt": ["s"]}
        return [f"{b}_{a}" for b in self.blocks for a in axes[b]]

    def transition_pattern(self, gauss_markov_biases=True):
        """``(rows, cols)`` of the entries of F that can be non-zero.

        The compiled kernel multiplies only these, so the cost of the
        covariance propagation grows with them, not with ``size**2``.  Skew
        blocks have zero diagonals; of the gravity-gradient block only
        ``(vD, pD)`` is used; bias diagonals (``-1/tau``) exist only for
        Gauss-Markov biases (``gauss_markov_biases``); scale factors are random
        walks.
        """
        n = self.size
        mask = np.zeros((n, n), dtype=bool)
        p, v, a = self.slice("pos"), self.slice("vel"), self.slice("att")
        off = ~np.eye(3, dtype=bool)
        mask[p, v] = np.eye(3, dtype=bool)
        mask[v.start + 2, p.start + 2] = True  # gravity gradient, down channel
        mask[v, v] = off
        mask[v, a] = off
        mask[a, a] = off
        mask[a.start + 0, v.start + 1] = True  # transport-rate error
        mask[a.start + 1, v.start + 0] = True
        mask[a.start + 2, v.start + 1] = True
        mask[v, self.slice("ba")] = True
        mask[a, self.slice("bg")] = True
        if gauss_markov_biases:
            for b in ("bg", "ba"):
                s = self.slice(b)
                mask[s, s] = np.eye(3, dtype=bool)
        if self.scale_factors:
            mask[v, self.slice("sa")] = True
            mask[a, self.slice("sg")] = True
        rows, cols = np.nonzero(mask)
        return rows.astype(np.int64), cols.astype(np.int64)
