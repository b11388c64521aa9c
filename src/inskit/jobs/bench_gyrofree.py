"""Throughput of the gyro-free pipeline (``inskit bench`` key
``gyrofree_epochs_per_s``).

One epoch is one sample of the ten-accelerometer array taken through the
closed-form solver (source 003 eq. 13-19, robust signs) and the inertial
quaternion navigation (eq. 43-44, fourth-order Runge-Kutta), both compiled.
The array outputs are simulated once, outside the timing; the figure is the
median of several repeats after a warm-up call (compile time excluded), one
core, with their spread beside it, as every kernel figure of ``inskit
bench`` (it was the best of them: the one figure of the bench that a lucky
run could move).
"""

from __future__ import annotations

import numpy as np

from ..gyrofree.layout import ten_layout
from ..gyrofree.model import ArrayErrors, simulate_array
from ..gyrofree.motion import ConstantRateMotion
from ..gyrofree.navigation import navigate_solution_inertial
from ..gyrofree.solvers import solve_closed_form


def gyrofree_rate(quick=False):
    """Epochs per second of solve plus navigate on the source's scenario
    (10 min at 100 Hz when ``quick``, 1 h otherwise), with sensor noise.

    Returns
    -------
    rate : float
        Median epochs per second over the repeats (rounded).
    spread : list of float
        The slowest and the fastest repeat's rates (rounded).
    """
    from .bench import _median_rate

    duration = 600.0 if quick else 3600.0
    t = np.arange(0.0, duration, 0.01)
    layout = ten_layout(0.1)
    motion = ConstantRateMotion()
    err = ArrayErrors.build(10, bias=1e-4, noise_sigma=1e-3)
    data = simulate_array(layout, motion.motion(t), err, np.random.default_rng(0))

    def job():
        sol = solve_closed_form(data, layout, omega0=motion.omega_b, noise_sigma=1e-3)
        navigate_solution_inertial(sol)

    med, spread = _median_rate(job, len(t), 3 if quick else 5)
    return float(round(med)), [float(round(v)) for v in spread]


__all__ = ["gyrofree_rate"]
