"""The simple filters' closed-loop design and the absolute-velocity slope,
shared by the integrated system (:mod:`.integrated`) and the design search
(:mod:`.design`).  SOURCES-NOTES §3.6."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import earth
from ..errors import ConfigError
from ..filters.simple import FirstOrderFilter, SecondOrderFilter

W = earth.OMEGA_IE


@dataclass(frozen=True)
class SimpleFilterDesign:
    """A first- or second-order filter with the closed-loop correction gains.

    Attributes
    ----------
    order : {1, 2}
    T : float
        Filter time constant ``T`` (order 1) or ``T1`` (order 2) [s].
    zeta : float
        Damping of the second-order filter.
    loop_frequency : float
        Natural frequency ``w_c`` of the corrected Schuler loop [rad/s]
        (default: the Schuler frequency of the 6378 km sphere).
    loop_damping : float
        ``zeta_c`` of the corrected loop.
    memory_s : float
        Closed loop: time constant [s] of the running mean of the corrective
        actions that is kept (held) while there are no fixes, so that the
        drift compensation the loop has settled into survives an outage.
    """

    order: int = 1
    T: float = 30.0
    zeta: float = 0.7071067811865476
    loop_frequency: float = math.sqrt(9.8 / earth.R_SPHERE)
    loop_damping: float = 0.7071067811865476
    memory_s: float = 3600.0

    def __post_init__(self):
        if self.order not in (1, 2):
            raise ConfigError(f"filter order must be 1 or 2, got {self.order}")
        if not self.loop_frequency > 0:
            raise ConfigError(f"`loop_frequency` must be > 0, got {self.loop_frequency}")
        if not self.loop_damping > 0:
            raise ConfigError(f"`loop_damping` must be > 0, got {self.loop_damping}")
        if not self.memory_s > 0:
            raise ConfigError(f"`memory_s` must be > 0 s, got {self.memory_s}")
        self.filter()  # validates T and zeta

    def filter(self):
        return FirstOrderFilter(self.T) if self.order == 1 else SecondOrderFilter(self.T, self.zeta)

    def gains(self, g=9.8, radius=earth.R_SPHERE):
        """``(k2, k3, ks)`` of the closed loop (module docstring)."""
        wc = self.loop_frequency
        return -2.0 * self.loop_damping * wc, -wc, wc * wc / g - 1.0 / radius


def v_west_slope(lat, h, model):
    """``c = d V_eta / d phi = U (R_E sin(phi) - R_E' cos(phi))`` [m/s/rad]:
    ``dV_eta = -dV_E + c d_phi`` (absolute against relative velocity)."""
    lat = np.asarray(lat, float)
    if model == "sphere":
        return W * (earth.R_SPHERE + np.asarray(h, float)) * np.sin(lat)
    _, re = earth.principal_radii(lat, h)
    s, co = np.sin(lat), np.cos(lat)
    rp = earth.A * earth.E2 * s * co / (1.0 - earth.E2 * s * s) ** 1.5
    return W * (re * s - rp * co)
