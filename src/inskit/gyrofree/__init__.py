"""Gyro-free inertial navigation from an array of accelerometers (source 003).

Accelerometer k at body position ``r_k`` with unit sensing axis ``e_k`` reads
``e_k . (f_b + omega_dot x r_k + omega x (omega x r_k)) + b_k`` (plus scale
factor, axis misalignment, noise).  Enough accelerometers, suitably placed,
give the specific force, the angular acceleration and the products
``omega_i omega_j``, hence the body rate without gyros.

Modules (frames and units as in :mod:`inskit`: body forward-right-down,
``C_ib`` body to inertial, quaternions scalar first, SI inside):

* :mod:`.layout`: layouts (the source's six and ten, any from a file), the
  linear measurement model and the rank test (:func:`require` refuses a
  layout that cannot observe what is asked, naming what it cannot observe);
* :mod:`.motion`: rigid-body motions (simulator trajectories with exact
  angular acceleration, the source's constant-rate scenario, sinusoids);
* :mod:`.model`: the array's outputs, exact or with bias, scale factor,
  misalignment and noise;
* :mod:`.solvers`: the source's closed form (eq. 13, 14, 17, 19 corrected,
  robust sign rule) and a general least-squares solver with an optional rate
  filter; both give an :class:`~inskit.types.ImuData`;
* :mod:`.navigation`: the source's inertial quaternion navigation (eq. 43-44)
  and the core NED / ECEF mechanizations;
* :mod:`.error_analysis`: analytic bias and misalignment effects (eq. 21-42,
  corrected), their propagation, Monte Carlo;
* :mod:`.files`: layout, array and inertial-solution CSV files.

Jobs (files, figures, the reproduction of the source's scenario, the
throughput figure) are in :mod:`inskit.jobs.gyrofree`,
:mod:`inskit.jobs.reproduce_gyrofree` and :mod:`inskit.jobs.bench_gyrofree`;
the command line in :mod:`inskit.cli_gyrofree`; see ``docs/gyrofree.md``.

References
----------
SYSTEM.md §5; SOURCES-NOTES §1 (the corrected reading of source 003).
"""

from .layout import (
    ArrayLayout,
    Observability,
    builtin_layout,
    design_matrix,
    observability,
    require,
    six_layout,
    ten_layout,
)
from .model import ArrayData, ArrayErrors, draw_errors, simulate_array, source_misaligned_axes, tilt_axes
from .motion import (
    ConstantRateMotion,
    HarmonicBodyMotion,
    InertialSolution,
    RigidMotion,
    angular_acceleration_ib_b,
    motion_from_trajectory,
)
from .navigation import (
    navigate_earth,
    navigate_inertial,
    navigate_solution_inertial,
    quat_from_source,
    quat_to_source,
)
from .solvers import ArraySolution, RateFilter, solve, solve_closed_form, solve_least_squares

__all__ = [
    "ArrayData", "ArrayErrors", "ArrayLayout", "ArraySolution", "ConstantRateMotion", "HarmonicBodyMotion",
    "InertialSolution", "Observability", "RateFilter", "RigidMotion", "angular_acceleration_ib_b", "builtin_layout",
    "design_matrix", "draw_errors", "motion_from_trajectory", "navigate_earth", "navigate_inertial",
    "navigate_solution_inertial", "observability", "quat_from_source", "quat_to_source", "require",
    "simulate_array", "six_layout", "solve", "solve_closed_form", "solve_least_squares", "source_misaligned_axes",
    "ten_layout", "tilt_axes",
]
