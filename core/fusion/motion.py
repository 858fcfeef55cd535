"""The fused tracks' motion: a registered transition model on the session's state layout.

The model of one axis comes from :data:`core.models.TRANSITION_MODELS` by its
API name, and :class:`~core.models.layout.MappedMotion` places it on the
session's layout (docs/algorithms.md §7.6). ``constant_velocity`` is the
discretised continuous white-noise acceleration model of spectral density
``q`` (Bar-Shalom, Li & Kirubarajan §6.2.2), the one meaning of the session's
``motion.q``, the meaning too of the local constant-velocity model of a
session that tracks detections without a preset (:mod:`core.tracking.models`,
``noise="continuous"``, with its own arithmetic, §7.6); ``singer`` is Singer's model
(:mod:`core.models.singer`). Every Δt is one closed-form step; components of
no axis block are kept constant.

Prediction backwards in time (a late report, docs/algorithms.md §6.4) uses
``F(Δt)`` with Δt < 0 and adds ``Q(|Δt|)``: the uncertainty grows in both
directions.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from core.models import TRANSITION_MODELS, MappedMotion, StateLayout

__all__ = ["MotionKind", "MotionModel", "StateLayout"]


class MotionKind(enum.StrEnum):
    """Motion models by their API names (the keys of :data:`core.models.TRANSITION_MODELS`)."""

    CONSTANT_VELOCITY = "constant_velocity"
    CONSTANT_POSITION = "constant_position"
    SINGER = "singer"


@dataclass(frozen=True, init=False)
class MotionModel(MappedMotion):
    """The session's motion model by name, with its parameters, on its state layout.

    ``MotionModel(layout, "singer", manoeuvre_time=20.0)``; ``q`` is the
    parameter of ``constant_velocity`` and ``constant_position``.
    """

    kind: MotionKind

    def __init__(
        self,
        layout: StateLayout,
        kind: MotionKind | str = MotionKind.CONSTANT_VELOCITY,
        **parameters: float,
    ) -> None:
        chosen = MotionKind(kind)
        object.__setattr__(self, "kind", chosen)
        super().__init__(layout, TRANSITION_MODELS[chosen](**parameters))

    @property
    def q(self) -> float:
        """The spectral density of the model's driving white noise (``motion.q``)."""
        return self.model.q
