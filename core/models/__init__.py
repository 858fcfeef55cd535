"""Motion and measurement models as interfaces (docs/algorithms.md §7.6).

- :mod:`core.models.transition` — the protocol of one axis's motion
  (:class:`TransitionModel`: components and ``matrices(dt)`` → F, Q batched
  over Δt) with constant velocity and constant position;
- :mod:`core.models.singer` — Singer's exponentially correlated acceleration;
- :mod:`core.models.layout` — a session's state layout and the motion of the
  whole state from one block per axis (:class:`MappedMotion`);
- :mod:`core.models.measurement` — the protocol of a measurement
  (:class:`MeasurementModel`: ``function``, ``jacobian``, ``covar``, ``mapping``,
  ``ndim_meas``) with a linear position mapping and a radar's polar model
  (2-D or 3-D, optionally with range-rate); :data:`MEASUREMENT_MODELS` names them
  by the wire's ``measurement.kind``.

:data:`TRANSITION_MODELS` names the models a session may choose as its
``motion.model``: a new model is its module and one line here (and its name
on the wire, ``api_schemas.config.MotionModel``). The papers' IMM banks of the
local trackers are in :mod:`core.tracking.models`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from core.models.layout import MappedMotion, StateLayout
from core.models.measurement import (
    MEASUREMENT_MODELS,
    ConvertedModel,
    LinearGaussian,
    MeasurementModel,
    Polar,
)
from core.models.singer import Singer
from core.models.transition import (
    Component,
    ConstantPosition,
    ConstantVelocity,
    TransitionModel,
)

TRANSITION_MODELS: Mapping[str, Callable[..., TransitionModel]] = {
    "constant_velocity": ConstantVelocity,
    "constant_position": ConstantPosition,
    "singer": Singer,
}
"""The session's motion models by their API names; each takes its parameters by keyword."""

__all__ = [
    "MEASUREMENT_MODELS",
    "TRANSITION_MODELS",
    "Component",
    "ConstantPosition",
    "ConstantVelocity",
    "ConvertedModel",
    "LinearGaussian",
    "MappedMotion",
    "MeasurementModel",
    "Polar",
    "Singer",
    "StateLayout",
    "TransitionModel",
]
