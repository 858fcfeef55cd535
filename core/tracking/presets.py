"""Presets that reproduce the papers' model banks, behaviours and classes (ALGORITHMS.md §4).

``aircraft`` ([MTT] §6.1)
    ΔT = 1 s, Q = 0.005 B Bᵀ, R = 0.2 I, H picks x, y; 13 acceleration inputs
    (g = 9.81 m/s²): m1 = (0, 0); m2..m5 = (±2g, 0), (0, ±2g);
    m6..m13 = (±4g, 0), (0, ±4g), (±4g, ±4g). **Reading:** [MTT] Fig 9 is not
    in the text; this set satisfies eq 25 per axis. Behaviours b1 = {m1},
    b2 = {m1..m5}, b3 = {m1..m13}; classes liner, bomber, fighter with
    Γ(b1) = {liner, bomber, fighter}, Γ(b2) = {bomber, fighter},
    Γ(b3) = {fighter}.
``pedestrian`` ([MTT] §6.3)
    Speed models (eq 26) (s_x, s_y) = (0, 0) | (2, 0), (0, 2), (2, 2) |
    (6, 2), (2, 6), (6, 6); behaviours static, walking, running; classes
    rambler, sportsman with Γ(static) = {rambler}, Γ(walking) = {rambler,
    sportsman}, Γ(running) = {sportsman}. **Reading:** the paper gives no
    ΔT, Q or R for this example; defaults ΔT = 1 s, R = 0.05 I (σ ≈ 0.22 m,
    a pedestrian detector), Q = 0.001 B Bᵀ (headings that barely wander).
    The state's second and fourth components are headings (see
    :mod:`core.tracking.models`).

Both use the mode transition matrix with ``stay`` = 0.95 on the diagonal and
the rest spread evenly (option ``stay``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

from core.belief import Frame, Relation
from core.classification.behaviours import BehaviourModels
from core.errors import ModelConfigError
from core.tracking.models import (
    LinearMeasurementModel,
    ModelBank,
    acceleration_input,
    mode_transition_matrix,
    speed_model,
)

GRAVITY = 9.81
"""g in m/s² ([MTT] §6.1.1)."""

VelocityConvention = Literal["velocity", "heading"]


@dataclass(frozen=True)
class TrackingPreset:
    """A model bank with its behaviours, classes and relation.

    Attributes
    ----------
    name : str
    bank : ModelBank
    behaviours : BehaviourModels
    relation : Relation
        Γ from the behaviours to the classes.
    velocity_convention : "velocity" | "heading"
        What the second and fourth state components mean (eq 24 vs eq 26).
    """

    name: str
    bank: ModelBank
    behaviours: BehaviourModels
    relation: Relation
    velocity_convention: VelocityConvention

    @property
    def classes(self) -> Frame:
        """The class frame."""
        return self.relation.target


AIRCRAFT_ACCELERATIONS: tuple[tuple[float, float], ...] = (
    (0.0, 0.0),
    (2.0, 0.0),
    (-2.0, 0.0),
    (0.0, 2.0),
    (0.0, -2.0),
    (4.0, 0.0),
    (-4.0, 0.0),
    (0.0, 4.0),
    (0.0, -4.0),
    (4.0, 4.0),
    (4.0, -4.0),
    (-4.0, 4.0),
    (-4.0, -4.0),
)
"""Inputs of m1..m13 in units of g."""

PEDESTRIAN_SPEEDS: tuple[tuple[float, float], ...] = (
    (0.0, 0.0),
    (2.0, 0.0),
    (0.0, 2.0),
    (2.0, 2.0),
    (6.0, 2.0),
    (2.0, 6.0),
    (6.0, 6.0),
)
"""(s_x, s_y) of m1..m7 in m/s."""


def aircraft(
    time_interval: float = 1.0,
    noise_intensity: float = 0.005,
    measurement_variance: float = 0.2,
    stay: float = 0.95,
) -> TrackingPreset:
    """The 13-model aircraft preset of [MTT] §6.1 (see the module docstring)."""
    models = tuple(
        acceleration_input(
            time_interval, (ax * GRAVITY, ay * GRAVITY), noise_intensity, f"m{i + 1}"
        )
        for i, (ax, ay) in enumerate(AIRCRAFT_ACCELERATIONS)
    )
    bank = ModelBank(
        models,
        LinearMeasurementModel.position(measurement_variance),
        mode_transition_matrix(len(models), stay),
    )
    names = bank.names
    behaviours = BehaviourModels.from_mapping(
        Frame(["b1", "b2", "b3"]),
        names,
        {"b1": names[:1], "b2": names[:5], "b3": names},
    )
    classes = Frame(["liner", "bomber", "fighter"])
    relation = Relation.from_mapping(
        behaviours.frame,
        classes,
        {"b1": ["liner", "bomber", "fighter"], "b2": ["bomber", "fighter"], "b3": ["fighter"]},
    )
    return TrackingPreset("aircraft", bank, behaviours, relation, "velocity")


def pedestrian(
    time_interval: float = 1.0,
    noise_intensity: float = 0.001,
    measurement_variance: float = 0.05,
    stay: float = 0.95,
) -> TrackingPreset:
    """The 7-model pedestrian preset of [MTT] §6.3 (see the module docstring)."""
    models = tuple(
        speed_model(time_interval, speeds, noise_intensity, f"m{i + 1}")
        for i, speeds in enumerate(PEDESTRIAN_SPEEDS)
    )
    bank = ModelBank(
        models,
        LinearMeasurementModel.position(measurement_variance),
        mode_transition_matrix(len(models), stay),
    )
    names = bank.names
    behaviours = BehaviourModels.from_mapping(
        Frame(["static", "walking", "running"]),
        names,
        {"static": names[:1], "walking": names[1:4], "running": names[4:]},
    )
    classes = Frame(["rambler", "sportsman"])
    relation = Relation.from_mapping(
        behaviours.frame,
        classes,
        {"static": ["rambler"], "walking": ["rambler", "sportsman"], "running": ["sportsman"]},
    )
    return TrackingPreset("pedestrian", bank, behaviours, relation, "heading")


PRESETS: dict[str, Callable[..., TrackingPreset]] = {
    "aircraft": aircraft,
    "pedestrian": pedestrian,
}


def preset(name: str, **options: float) -> TrackingPreset:
    """A preset by name, with its keyword options (``time_interval``, ``stay``, ...)."""
    try:
        factory = PRESETS[name]
    except KeyError:
        raise ModelConfigError(f"unknown preset {name!r}; known: {sorted(PRESETS)}") from None
    try:
        return factory(**options)
    except TypeError as exc:
        raise ModelConfigError(f"preset {name!r}: {exc}") from None
