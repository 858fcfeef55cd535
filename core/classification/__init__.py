"""Kinematic classification of tracks ([MTT] §5)."""

from core.classification.behaviours import BehaviourModels

__all__ = ["BehaviourModels"]
