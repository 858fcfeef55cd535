"""Kinematic classification of tracks: credal ([MTT] §5.2) and Bayesian baseline (§5.1)."""

from core.classification.batched import BatchedCredalClassifier, CredalBatch
from core.classification.bayesian import (
    BayesianClassification,
    BayesianClassifier,
    class_given_behaviour,
)
from core.classification.behaviours import BehaviourModels
from core.classification.credal import CredalClassification, CredalClassifier

__all__ = [
    "BatchedCredalClassifier",
    "BayesianClassification",
    "BayesianClassifier",
    "BehaviourModels",
    "CredalBatch",
    "CredalClassification",
    "CredalClassifier",
    "class_given_behaviour",
]
