"""Cheap JPDA weights of Fitzgerald ([DH] §2, eq 16; docs/algorithms.md §3.5).

A measurement-to-track comparison baseline, not a fusion method. For the
gated pairs (track t, measurement j) with Gaussian likelihood
``G_tj = N(z_j; ẑ_t, S_t)``::

    β_tj = G_tj / (S_t + S_j − G_tj + B),   S_t = Σ_j G_tj,   S_j = Σ_t G_tj,

B the bias (clutter-density term). ``β_t0 = 1 − Σ_j β_tj`` is the weight of
"no measurement from t". The track is then updated with the weighted combined
innovation ``ν_t = Σ_j β_tj (z_j − ẑ_t)`` ([DH] eq 5–11; the update itself
belongs to the tracker).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from core.arrays import FloatArray, IntArray
from core.distance import DistanceModel, Estimates, gated_pairs, threshold_from_probability
from core.errors import OptionError


@dataclass(frozen=True, eq=False)
class JpdaWeights:
    """Sparse association weights.

    Attributes
    ----------
    rows, cols : ndarray of int64
        Track t and measurement j of each gated pair.
    weights : ndarray
        β_tj.
    none : ndarray, shape (n_tracks,)
        β_t0 = 1 − Σ_j β_tj.
    innovation : ndarray, shape (n_tracks, m)
        Combined innovation ν_t = Σ_j β_tj (z_j − ẑ_t).
    spread : ndarray, shape (n_tracks, m, m)
        Σ_j β_tj ν_tj ν_tjᵀ − ν_t ν_tᵀ (the spread-of-innovations term of the
        covariance update).
    """

    rows: IntArray
    cols: IntArray
    weights: FloatArray
    none: FloatArray
    innovation: FloatArray
    spread: FloatArray


def cheap_jpda_weights(
    predicted_measurements: ArrayLike,
    innovation_covariances: ArrayLike,
    measurements: ArrayLike,
    *,
    bias: float,
    gate_probability: float = 0.999,
) -> JpdaWeights:
    """Fitzgerald's cheap JPDA weights over the measurements in each track's gate."""
    if not (math.isfinite(bias) and bias >= 0.0):
        raise OptionError(f"cheap_jpda: option 'bias' must be finite and ≥ 0, got {bias!r}")
    if not 0.0 < gate_probability < 1.0:
        raise OptionError(
            f"cheap_jpda: option 'gate_probability' must lie in (0, 1), got {gate_probability!r}"
        )
    tracks = Estimates.of(predicted_measurements, innovation_covariances, name="tracks")
    found = Estimates.of(
        measurements, None, name="measurements", dimension=tracks.dimension if len(tracks) else None
    )
    model = DistanceModel(covariance="innovation")
    q = tracks.dimension
    gate = threshold_from_probability(gate_probability, q, model) if len(tracks) else 0.0
    pairs = gated_pairs(tracks, found, gate, model)
    n, m = len(tracks), len(found)
    likelihood = np.exp(-0.5 * (pairs.distance + q * math.log(2 * math.pi) + pairs.log_det))
    per_track = np.bincount(pairs.rows, weights=likelihood, minlength=n)
    per_measurement = np.bincount(pairs.cols, weights=likelihood, minlength=m)
    denominator = per_track[pairs.rows] + per_measurement[pairs.cols] - likelihood + bias
    weights = np.where(
        denominator > 0.0, likelihood / np.where(denominator > 0, denominator, 1.0), 0.0
    )
    none = np.asarray(1.0 - np.bincount(pairs.rows, weights=weights, minlength=n), dtype=np.float64)
    residual = found.states[pairs.cols] - tracks.states[pairs.rows]
    innovation = np.zeros((n, q))
    np.add.at(innovation, pairs.rows, weights[:, None] * residual)
    spread = np.zeros((n, q, q))
    np.add.at(
        spread, pairs.rows, weights[:, None, None] * residual[:, :, None] * residual[:, None, :]
    )
    spread -= innovation[:, :, None] * innovation[:, None, :]
    return JpdaWeights(pairs.rows, pairs.cols, weights, none, innovation, spread)
