"""Bayesian kinematic classification, the baseline of [MTT] §5.1.

Per step with a measurement, behaviour posteriors by Bayes' rule
``P(b_i | Z_k) ∝ l_{b_i} P(b_i | Z_{k−1})`` ([MTT] eq 9) with the behaviour
likelihoods of eq 19–20; classes by ``P(C) = M P(B)`` (eq 21), where
``M[c, b] = P(c | b)`` is uniform over Γ(b) (the matrix M of [MTT] §6.1.2).
Everything is vectorised over tracks and kept in the log domain, so a
behaviour can fall to probability ~0 without NaN; tracks without a
measurement keep their posterior.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.arrays import BoolArray, FloatArray
from core.belief import Frame, Relation
from core.classification.behaviours import BehaviourModels
from core.errors import ClassificationError
from core.numerics import logsumexp, safe_log


def class_given_behaviour(relation: Relation) -> FloatArray:
    """``M[c, b] = P(c | b) = 1/|Γ(b)|`` for c ∈ Γ(b), else 0 ([MTT] eq 21)."""
    image_bits = relation.target.bits(relation.images)  # (|B|, |C|)
    return np.asarray((image_bits / image_bits.sum(axis=1, keepdims=True)).T, dtype=np.float64)


@dataclass(frozen=True)
class BayesianClassification:
    """Behaviour posteriors of T tracks.

    Attributes
    ----------
    log_behaviour_probabilities : ndarray, shape (T, |B|)
        log P(b_i | Z_k), normalised.
    """

    log_behaviour_probabilities: FloatArray

    @property
    def behaviour_probabilities(self) -> FloatArray:
        """P(b_i | Z_k), shape (T, |B|)."""
        return np.asarray(np.exp(self.log_behaviour_probabilities), dtype=np.float64)


class BayesianClassifier:
    """The Bayesian baseline of [MTT] §5.1 for many tracks.

    Parameters
    ----------
    behaviours : BehaviourModels
    relation : Relation
        Γ from the behaviours to the classes; gives M (eq 21).
    prior : ndarray, shape (|B|,), optional
        Initial behaviour probabilities; uniform by default ([MTT] §2.4).
    """

    def __init__(
        self, behaviours: BehaviourModels, relation: Relation, prior: FloatArray | None = None
    ) -> None:
        if relation.source != behaviours.frame:
            raise ClassificationError("the relation must start from the behaviour frame")
        n = len(behaviours.frame)
        initial = np.full(n, 1.0 / n) if prior is None else np.asarray(prior, dtype=np.float64)
        if initial.shape != (n,) or np.any(initial < 0.0) or abs(initial.sum() - 1.0) > 1e-9:
            raise ClassificationError(f"prior must be {n} non-negative numbers summing to 1")
        self.behaviours = behaviours
        self.relation = relation
        self.prior = initial
        self.matrix = class_given_behaviour(relation)

    @property
    def classes(self) -> Frame:
        """The class frame."""
        return self.relation.target

    def initial(self, n_tracks: int) -> BayesianClassification:
        """The prior for ``n_tracks`` tracks."""
        return BayesianClassification(np.tile(safe_log(self.prior), (n_tracks, 1)))

    def update(
        self,
        state: BayesianClassification,
        log_mode_probabilities: FloatArray,
        log_model_likelihoods: FloatArray,
        detected: BoolArray | None = None,
    ) -> BayesianClassification:
        """One Bayes step (eq 9 with eq 19–20) for every detected track."""
        log_prior = state.log_behaviour_probabilities
        tracks = log_prior.shape[0]
        hit = np.ones(tracks, dtype=bool) if detected is None else np.asarray(detected, dtype=bool)
        if hit.shape != (tracks,):
            raise ClassificationError(f"detected must have shape ({tracks},), got {hit.shape}")
        log_posterior = log_prior.copy()
        rows = np.flatnonzero(hit)
        if rows.size:
            log_l = self.behaviours.log_likelihoods(
                np.asarray(log_mode_probabilities)[rows], np.asarray(log_model_likelihoods)[rows]
            )
            joint = log_prior[rows] + log_l
            total = logsumexp(joint, axis=1)
            usable = np.isfinite(total)
            log_posterior[rows] = np.where(
                usable[:, None], joint - np.where(usable, total, 0.0)[:, None], log_prior[rows]
            )
        return BayesianClassification(log_posterior)

    def class_probabilities(self, state: BayesianClassification) -> FloatArray:
        """``P(C) = M P(B)`` for every track, shape (T, |C|) ([MTT] eq 21)."""
        return np.asarray(state.behaviour_probabilities @ self.matrix.T, dtype=np.float64)
