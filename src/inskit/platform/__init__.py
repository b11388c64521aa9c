"""Gimballed-platform INS: mechanizations, source 004's error model, integration.

Modules
-------
:mod:`.world`
    Earth model (``"wgs84"`` or the 6378 km ``"sphere"``), the sampled true
    motion (:func:`platform_truth`) and satellite fixes (:func:`simulate_sns`).
:mod:`.sensors`
    :class:`PlatformErrors` (drifts, biases, noise, scale factors) and
    :class:`InitialErrors`.
:mod:`.mechanization`
    :func:`mechanize_platform`: semi-analytical, analytical and geometric
    platforms simulated with the navigation computer (SOURCES-NOTES §3.2-3.4).
:mod:`.error_model`
    Source 004's error model completed and checked against the mechanization,
    the closed-form stationary solution, observability, correction gains and
    stability (SOURCES-NOTES §2).
:mod:`.integrated`
    :func:`integrate_platform`: open and closed loop with a Kalman filter or a
    first-/second-order filter (SYSTEM.md §3).
:mod:`.design`
    Search of the simple filters' constants for a given transient time.

Conventions are the package's (see :mod:`inskit`); platform axes are east,
north, up (source 000), source 004's variables north, west, up.  The job
layer (files, plots, the reproduction) is :mod:`inskit.jobs.platform`.
"""

from .error_model import (
                          error_matrix,
                          observability,
                          printed_error_matrix,
                          simulate_error_model,
                          stationary_closed_form,
)
from .integrated import (
                          IntegratedRun,
                          KalmanTuning,
                          SimpleFilterDesign,
                          integrate_platform,
)
from .mechanization import KINDS, PlatformRun, mechanize_platform, source_errors
from .sensors import InitialErrors, PlatformErrors
from .world import PlatformTruth, SnsFixes, platform_truth, simulate_sns

__all__ = [
    "KINDS", "InitialErrors", "IntegratedRun", "KalmanTuning", "PlatformErrors", "PlatformRun", "PlatformTruth",
    "SimpleFilterDesign", "SnsFixes", "error_matrix", "integrate_platform", "mechanize_platform", "observability",
    "platform_truth", "printed_error_matrix", "simulate_error_model", "simulate_sns", "source_errors",
    "stationary_closed_form",
]
