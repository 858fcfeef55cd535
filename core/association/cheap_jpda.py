"""Cheap JPDA weights of Fitzgerald ([DH] §2, eq 16; docs/algorithms.md §3.5).

A measurement-to-track comparison baseline, not a fusion method. For the
gated pairs (track t, measurement j) with Gaussian likelihood
``G_tj = N(z_j; ẑ_t, S_t)``::

    β_tj = G_tj / (S_t + S_j − G_tj + B),   S_t = Σ_j G_tj,   S_j = Σ_t G_tj,

B the bias (clutter-density term). ``β_t0 = 1 − Σ_j β_tj`` is the weight of
"no measurement from t". The track is then updated with the weighted combined
innovation ``ν_t = Σ_j β_tj (z_j − ẑ_t)`` ([DH] eq 5–11; the update itself
belongs to the tracker).

As a registered method (:data:`SPEC`, local tracking only, ``soft``): its
result's ``scores`` are the weights β_tj of the gated pairs (G from the plain D
of the pairs, :attr:`~core.distance.CandidatePairs.plain_distance`), its pairs
each detection with its most probable track. Options ``gate_probability``
(default 0.999) and ``bias`` (default: unset, the local tracker puts the PDA's
clutter term ``λ (1 − P_D P_G) / P_D`` there, :func:`core.tracking.jpda.clutter_bias`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from core.arrays import FloatArray, IntArray
from core.association.problem import AssociationProblem
from core.association.result import AssociationResult, Diagnostics, ScoreMatrix, build_result
from core.association.spec import LOCAL_ONLY, MethodSpec, NumberOption
from core.distance import DistanceModel, Estimates, gated_pairs, threshold_from_probability
from core.errors import InvalidInput, OptionError

METHOD = "cheap_jpda"
DEFAULT_GATE_PROBABILITY = 0.999
LOG_TWO_PI = math.log(2 * math.pi)


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


def dense_weights(likelihoods: FloatArray, bias: float) -> tuple[FloatArray, FloatArray]:
    """Fitzgerald's weights ``β_tj`` and ``β_t0`` ([DH] eq 16; module docstring).

    Parameters
    ----------
    likelihoods : ndarray, shape (T, m)
        G_tj ≥ 0 (0 outside the gate).
    bias : float
        B ≥ 0.

    Returns
    -------
    weights : ndarray, shape (T, m)
    missed : ndarray, shape (T,)
        β_t0 = max(0, 1 − Σ_j β_tj).
    """
    g = np.asarray(likelihoods, dtype=np.float64)
    if g.ndim != 2 or np.any(~np.isfinite(g)) or np.any(g < 0.0):
        raise InvalidInput("cheap JPDA likelihoods must be a finite non-negative (T, m) matrix")
    if not (math.isfinite(bias) and bias >= 0.0):
        raise OptionError(f"cheap JPDA bias must be >= 0, got {bias!r}")
    per_track = g.sum(axis=1, keepdims=True)
    per_detection = g.sum(axis=0, keepdims=True)
    denominator = per_track + per_detection - g + bias
    positive = g > 0.0
    weights = np.where(positive, g / np.where(positive, denominator, 1.0), 0.0)
    missed = np.clip(1.0 - weights.sum(axis=1), 0.0, 1.0)
    return np.asarray(weights, dtype=np.float64), np.asarray(missed, dtype=np.float64)


@dataclass(frozen=True)
class CheapJpdaOptions:
    """Validated options of :func:`associate_cheap_jpda` (``bias`` None: not yet known)."""

    bias: float | None = None
    gate_probability: float = DEFAULT_GATE_PROBABILITY


def associate_cheap_jpda(
    problem: AssociationProblem, options: CheapJpdaOptions
) -> AssociationResult:
    """The weights β_tj over the gated pairs; each detection to its most probable track."""
    if options.bias is None:
        raise OptionError(f"{METHOD}: option 'bias' is needed here (no clutter density is known)")
    gate = threshold_from_probability(options.gate_probability, problem.dimension, problem.distance)
    pairs = problem.pairs(gate)
    rows, cols = pairs.rows, pairs.cols
    log_g = -0.5 * (pairs.plain_distance + pairs.log_det + problem.dimension * LOG_TWO_PI)
    likelihoods = np.zeros((problem.n_known, problem.n_incoming))
    likelihoods[rows, cols] = np.exp(log_g)
    weights, _ = dense_weights(likelihoods, options.bias)
    best_cols = np.flatnonzero(weights.max(axis=0, initial=0.0) > 0.0)
    best_rows = (
        np.argmax(weights[:, best_cols], axis=0).astype(np.int64)
        if len(best_cols)
        else np.zeros(0, dtype=np.int64)
    )
    scores = ScoreMatrix(
        kind="weight",
        rows=rows,
        cols=cols,
        values=weights[rows, cols],
        new=np.zeros(problem.n_incoming),
        shape=(problem.n_known, problem.n_incoming),
        missing=0.0,
    )
    diagnostics = Diagnostics(candidate_pairs=len(pairs), gate=gate)
    return build_result(METHOD, best_rows, best_cols, scores, diagnostics, pairs)


SPEC = MethodSpec(
    name=METHOD,
    scopes=LOCAL_ONLY,
    options=(
        NumberOption(
            "bias",
            None,
            low=0.0,
            low_open=False,
            doc="B of [DH] eq 16 (default: the PDA clutter term λ (1 − P_D P_G) / P_D)",
        ),
        NumberOption(
            "gate_probability",
            DEFAULT_GATE_PROBABILITY,
            low=0.0,
            high=1.0,
            high_open=True,
            doc="the gate, chi2.ppf(p, q)",
        ),
    ),
    build=lambda values: CheapJpdaOptions(**values),
    run=associate_cheap_jpda,
    soft=True,
    summary="Fitzgerald's cheap JPDA baseline ([DH] §2): soft weights, PDA update",
)
