"""Throughput of the gyro-free pipeline (``inskit bench`` key
``gyrofree_epochs_per_s``).

One epoch is one sample of the ten-accelerometer array taken through the
closed-form solver (source 003 eq. 13-19, robust signs) and the inertial
quaternion navigation (eq. 43-44, fourth-order Runge-Kutta), both compiled.
The array outputs are simulated once, outside the timing; the figure is the
best of several repeats after a warm-up call (compile time excluded), one
core.
"""

from __future__ import annotations

import time

import numpy as np

from ..gyrofree.layout import ten_layout
from ..gyrofree.model import ArrayErrors, simulate_array
from ..gyrofree.motion import ConstantRateMotion
from ..gyrofree.navigation import navigate_solution_inertial
from ..gyrofree.solvers import solve_closed_form


def _best(fn, repeats):
    fn()
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def gyrofree_rate(quick=False):
    """Epochs per second of solve plus navigate on the source's scenario
    (10 min at 100 Hz when ``quick``, 1 h otherwise), with sensor noise.

    Returns
    -------
    float
        Epochs per second (rounded).
    """
    duration = 600.0 if quick else 3600.0
    t = np.arange(0.0, duration, 0.01)
    layout = ten_layout(0.1)
    motion = ConstantRateMotion()
    err = ArrayErrors.build(10, bias=1e-4, noise_sigma=1e-3)
    data = simulate_array(layout, motion.motion(t), err, np.random.default_rng(0))

    def job():
        sol = solve_closed_form(data, layout, omega0=motion.omega_b, noise_sigma=1e-3)
        navigate_solution_inertial(sol)

    return float(round(len(t) / _best(job, 2 if quick else 5)))


__all__ = ["gyrofree_rate"]
