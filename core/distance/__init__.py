"""Distances between estimates, over gated pairs only (docs/algorithms.md §2).

- :class:`Estimates` — a validated list of states with covariances (or of
  measurements);
- :func:`gated_pairs` — D and log|C| for every pair with D ≤ T, found with a
  KD-tree and solved in vectorised blocks (``mean``, ``sum``, ``innovation``);
- :class:`ModifiedScale` — the modified distance of [HZ] §4.1 (see its Reading);
- :func:`steady_state_covariance` — S_ss from F, Q, H, R by the Riccati recursion.
"""

from core.distance.estimates import Estimates, check_covariances
from core.distance.modified import ModifiedScale, modified_distance, scale_factor, size_ratio
from core.distance.pairwise import (
    COVARIANCE_WEIGHTS,
    CandidatePairs,
    CovarianceKind,
    DistanceModel,
    chi2_quantile,
    distance_matrix,
    gated_pairs,
    threshold_from_probability,
)
from core.distance.steady_state import SteadyState, steady_state_covariance

__all__ = [
    "COVARIANCE_WEIGHTS",
    "CandidatePairs",
    "CovarianceKind",
    "DistanceModel",
    "Estimates",
    "ModifiedScale",
    "SteadyState",
    "check_covariances",
    "chi2_quantile",
    "distance_matrix",
    "gated_pairs",
    "modified_distance",
    "scale_factor",
    "size_ratio",
    "steady_state_covariance",
    "threshold_from_probability",
]
