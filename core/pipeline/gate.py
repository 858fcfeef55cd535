"""Distances of the pairs a step scores: D = Δᵀ S⁻¹ Δ and log|S| (docs/algorithms.md §2, §4).

The SPRT hit increment ΔL ([MTT] §4.3, eq 16) and the gate volume A_G
([HZ] §4.2) read the same two numbers of a (track, observation) pair: the
squared Mahalanobis distance D of the innovation Δ and the log-determinant
of its covariance S. The local tracker gets them from its gating
(:mod:`core.tracking.gating`, in measurement space); the fusion engine
computes them on the position components of the state.
"""

from __future__ import annotations

import numpy as np

from core.arrays import FloatArray, IntArray
from core.distance.cholesky import quadratic_form_and_log_det


def mahalanobis(differences: FloatArray, covariances: FloatArray) -> tuple[FloatArray, FloatArray]:
    """D = Δᵀ C⁻¹ Δ and log|C| of every row (n, q), (n, q, q) (batched Cholesky, §2)."""
    return quadratic_form_and_log_det(differences.T, np.moveaxis(covariances, 0, -1))


def position_distances(
    states: FloatArray,
    covariances: FloatArray,
    observed: FloatArray,
    observed_covariances: FloatArray,
    position: IntArray,
) -> tuple[FloatArray, FloatArray]:
    """D and log|S| of each pair on the ``position`` components, S = P + P_obs (§6.5)."""
    combined = (covariances + observed_covariances)[:, position][:, :, position]
    return mahalanobis(observed[:, position] - states[:, position], combined)


def pair_positions(
    gated_rows: IntArray, gated_cols: IntArray, columns: int, rows: IntArray, cols: IntArray
) -> IntArray:
    """Where each pair (rows[k], cols[k]) sits among gated pairs sorted by (row, col)."""
    keys = gated_rows * columns + gated_cols
    return np.asarray(np.searchsorted(keys, rows * columns + cols), dtype=np.int64)
