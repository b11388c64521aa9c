"""Generic Kalman-filter mathematics (no navigation knowledge here).

SYSTEM.md §2: ``K = P H^T (H P H^T + R)^-1``, update in Joseph form
``P+ = (I - K H) P (I - K H)^T + K R K^T`` (symmetric and positive by
construction, unlike ``P - K H P``), innovation gating by the chi-square test
of the normalised innovation squared (NIS).
"""

from .kalman import FilterDivergence, UpdateResult, chi2_threshold, gate_rows, joseph_update, nees

__all__ = ["FilterDivergence", "UpdateResult", "chi2_threshold", "gate_rows", "joseph_update", "nees"]
