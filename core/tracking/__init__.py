"""Local tracking from detections (docs/algorithms.md §4): models, presets, the batched IMM, the tracker."""

from core.tracking.imm import IMMPrediction, IMMPredictor, IMMState, IMMUpdate, IMMUpdater
from core.tracking.initiator import pair_seeds, single_point_initiation, two_point_initiation
from core.tracking.models import (
    LinearMeasurementModel,
    ModelBank,
    MotionModel,
    acceleration_input,
    constant_velocity,
    input_matrix,
    mode_transition_matrix,
    speed_model,
)

__all__ = [
    "IMMPrediction",
    "IMMPredictor",
    "IMMState",
    "IMMUpdate",
    "IMMUpdater",
    "LinearMeasurementModel",
    "ModelBank",
    "MotionModel",
    "acceleration_input",
    "constant_velocity",
    "input_matrix",
    "mode_transition_matrix",
    "pair_seeds",
    "single_point_initiation",
    "speed_model",
    "two_point_initiation",
]
