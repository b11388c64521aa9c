"""The blending gain m: genetic algorithm (pygad) and a scalar cross-check.

The GA follows the source's recipe (source 002, §3): a random first
generation, fitness, the elite kept, tournament selection of parents,
two-point crossover, mutation of all but the elite, and a stop when the best
chromosome is unchanged for ``saturate`` generations or at a generation cap.
A chromosome is ``bits`` binary genes encoding ``m`` in [0, 1] (so that
two-point crossover has something to cross).  ``scipy.optimize
.minimize_scalar`` on [0, 1] (plus both ends) is the cross-check.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .analytic import blend, criterion


@dataclass(frozen=True)
class GainResult:
    m: float
    J: float
    generations: int = 0
    evaluations: int = 0


def _decode(bits):
    b = np.asarray(bits, dtype=float)
    w = 2.0 ** np.arange(len(b) - 1, -1, -1)
    return float(b @ w / (2.0 ** len(b) - 1))


def ga_best_m(J_of_m, *, bits=16, population=20, parents=10, generations=200, saturate=25, seed=0):
    """Minimise ``J_of_m`` over m in [0, 1] with pygad's GA."""
    import pygad

    count = [0]

    def fitness(ga, solution, idx):
        count[0] += 1
        return -J_of_m(_decode(solution))

    ga = pygad.GA(
        num_generations=generations, num_parents_mating=parents, fitness_func=fitness, sol_per_pop=population,
        num_genes=bits, gene_space=[0, 1], gene_type=int, parent_selection_type="tournament", K_tournament=3,
        keep_elitism=1, crossover_type="two_points", mutation_type="random", mutation_percent_genes=10,
        stop_criteria=[f"saturate_{saturate}"], random_seed=seed, suppress_warnings=True,
    )
    ga.run()
    sol, fit, _ = ga.best_solution(pop_fitness=ga.last_generation_fitness)
    return GainResult(_decode(sol), float(-fit), int(ga.generations_completed), count[0])


def scalar_best_m(J_of_m):
    """Bounded scalar minimisation on [0, 1], ends included."""
    from scipy.optimize import minimize_scalar

    r = minimize_scalar(J_of_m, bounds=(0.0, 1.0), method="bounded", options={"xatol": 1e-6})
    cands = [(float(r.fun), float(r.x)), (J_of_m(0.0), 0.0), (J_of_m(1.0), 1.0)]
    J, m = min(cands)
    return GainResult(m, J, 0, int(r.nfev) + 2)


def realization_J(f_b, w_b, lat, C_true, weights=(1.0, 1.0, 1.0)):
    """J(m) for one error realization (the source's figures)."""
    return lambda m: criterion(blend(f_b, w_b, lat, m), C_true, weights)


def expected_J(C_true, lat, sigma_accel, sigma_gyro, draws=200, seed=0, weights=(1.0, 1.0, 1.0)):
    """J(m) as the RMS over Monte Carlo draws of a sensor specification
    (independent zero-mean biases per axis): choose m for a sensor class
    before the run.  The draws are fixed (common random numbers), so J(m) is
    a smooth deterministic function of m; each evaluation is vectorised over
    the draws."""
    from .. import rotations as rot
    from .analytic import accel_basis, ideal_static, measured_latitude

    rng = np.random.default_rng(seed)
    f0, w0 = ideal_static(C_true, lat)
    fs = f0 + rng.normal(0.0, sigma_accel, (draws, 3))
    ws = w0 + rng.normal(0.0, sigma_gyro, (draws, 3))
    C_a = np.stack([accel_basis(f, w) for f, w in zip(fs, ws)])
    dphi = np.array([measured_latitude(f, w) for f, w in zip(fs, ws)]) - lat
    C_t = np.broadcast_to(C_true, C_a.shape)
    k = np.asarray(weights, float)

    def J(m):
        a = -m * dphi
        c, s = np.cos(a), np.sin(a)
        z, o = np.zeros_like(a), np.ones_like(a)
        R = np.stack([np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], -2)
        e = rot.attitude_error(R @ C_a, C_t)
        return float(np.sqrt(np.mean(e**2 @ k)))

    return J
