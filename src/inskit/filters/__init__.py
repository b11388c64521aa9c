"""Generic Kalman-filter mathematics (no navigation knowledge here).

* :mod:`.kalman`: the error-state update. SYSTEM.md §2: ``K = P H^T (H P H^T + R)^-1``,
  update in Joseph form ``P+ = (I - K H) P (I - K H)^T + K R K^T`` (symmetric
  and positive by construction, unlike ``P - K H P``), innovation gating by the
  chi-square test of the normalised innovation squared (NIS), per vector or per row;
* :mod:`.linear`: a linear discrete Kalman filter over given ``Phi_k, Q_k, H, R``
  (Van Loan discretisation, compiled loop);
* :mod:`.simple`: first-order ``1/(T p + 1)`` and second-order
  ``1/(T1^2 p^2 + 2 zeta T1 p + 1)`` filters, discretised exactly (SYSTEM.md §3).
"""

from .kalman import FilterDivergence, UpdateResult, chi2_threshold, gate_rows, joseph_update, nees

# .linear and .simple need scipy.linalg (0.3-0.5 s to import): loaded when first asked for, so the
# commands that filter with .kalman alone do not pay for it
_LAZY = {"kf_predict": "linear", "kf_update": "linear", "run_linear_kalman": "linear",
         "simulate_linear": "linear", "van_loan": "linear",
         "FirstOrderFilter": "simple", "SecondOrderFilter": "simple"}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))

__all__ = ["FilterDivergence", "FirstOrderFilter", "SecondOrderFilter", "UpdateResult", "chi2_threshold",
           "gate_rows", "joseph_update", "kf_predict", "kf_update", "nees", "run_linear_kalman", "simulate_linear",
           "van_loan"]
