"""Presets that reproduce the papers' model banks, behaviours and classes (docs/algorithms.md §4).

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
the rest spread evenly (option ``stay``), per nominal scan ΔT
(``time_interval``; over other steps see :mod:`core.tracking.models`).

**3-D** (option ``axes=3``, a session whose state has three positions): the
papers' banks are planar, so each model keeps its horizontal part and adds a
vertical constant-velocity axis ``[z, ż]`` with no input, speed factor 1 (ż is
a velocity, in both presets) and the preset's ``Q = q B Bᵀ`` on that axis;
H picks x, y, z with the same R variance. The behaviours and classes are
those of the horizontal motion.

:meth:`TrackingPreset.manoeuvre_density` is the white-noise acceleration
density that covers the bank's largest manoeuvre (the default ``motion.q``
of the fused layer when the session's tracks come from this preset).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

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
VELOCITY: VelocityConvention = "velocity"

MANOEUVRE_DISTANCE = 9.0
"""Mahalanobis distance (3σ) of a bank's largest manoeuvre over one scan from the fused
constant-velocity prediction, under :meth:`TrackingPreset.manoeuvre_density`."""

MIN_MANOEUVRE_DENSITY = 1.0
"""Smallest :meth:`TrackingPreset.manoeuvre_density` (m²/s³): the fused layer's default ``motion.q``."""


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
        What the second and fourth state components mean (eq 24 vs eq 26);
        a vertical axis (3-D) is always a velocity (:attr:`conventions`).
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

    @property
    def conventions(self) -> tuple[VelocityConvention, ...]:
        """What the second component of each axis means: the horizontal axes follow
        :attr:`velocity_convention`, a vertical axis is a velocity."""
        return (self.velocity_convention,) * 2 + (VELOCITY,) * (self.bank.axes - 2)

    def manoeuvre_density(self) -> float:
        """The density q of the continuous white-noise acceleration that covers the bank.

        Δv is the largest change of velocity over one nominal scan ΔT that the
        bank contains: ``|u| ΔT`` of its largest acceleration input, or the
        largest difference ``|s_j − s_k|`` of two speed models (per unit
        heading). A constant acceleration ``a`` held over Δt is at Mahalanobis
        distance ``a² Δt / q`` from the constant-velocity prediction under
        ``Q = q [[Δt³/3, Δt²/2], [Δt²/2, Δt]]``; ``q = Δv² / (ΔT d)`` with
        d = :data:`MANOEUVRE_DISTANCE` puts the bank's largest manoeuvre over
        one scan at distance d, inside every association gate of the fused
        layer (never below :data:`MIN_MANOEUVRE_DENSITY`).
        """
        bank = self.bank
        interval = bank.time_interval
        accelerations = np.array([model.acceleration for model in bank.models])
        speeds = np.array([model.speeds for model in bank.models])
        change = float(np.max(np.linalg.norm(accelerations, axis=1))) * interval
        spread = np.linalg.norm(speeds[:, None, :] - speeds[None, :, :], axis=-1)
        change = max(change, float(spread.max()))
        return max(change**2 / (interval * MANOEUVRE_DISTANCE), MIN_MANOEUVRE_DENSITY)


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


def _check_axes(axes: int) -> int:
    if axes not in (2, 3):
        raise ModelConfigError(f"presets have 2 or 3 position axes, got {axes!r}")
    return int(axes)


def aircraft(
    time_interval: float = 1.0,
    noise_intensity: float = 0.005,
    measurement_variance: float = 0.2,
    stay: float = 0.95,
    axes: int = 2,
) -> TrackingPreset:
    """The 13-model aircraft preset of [MTT] §6.1 (see the module docstring)."""
    vertical = (0.0,) * (_check_axes(axes) - 2)
    models = tuple(
        acceleration_input(
            time_interval, (ax * GRAVITY, ay * GRAVITY, *vertical), noise_intensity, f"m{i + 1}"
        )
        for i, (ax, ay) in enumerate(AIRCRAFT_ACCELERATIONS)
    )
    bank = ModelBank(
        models,
        LinearMeasurementModel.position(measurement_variance, 2 * axes),
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
    axes: int = 2,
) -> TrackingPreset:
    """The 7-model pedestrian preset of [MTT] §6.3 (see the module docstring)."""
    vertical = (1.0,) * (_check_axes(axes) - 2)
    models = tuple(
        speed_model(time_interval, (*speeds, *vertical), noise_intensity, f"m{i + 1}")
        for i, speeds in enumerate(PEDESTRIAN_SPEEDS)
    )
    bank = ModelBank(
        models,
        LinearMeasurementModel.position(measurement_variance, 2 * axes),
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


def with_classes(chosen: TrackingPreset, allowed: Mapping[str, Iterable[str]]) -> TrackingPreset:
    """The preset with a session's own classes: ``allowed`` gives each class (in the frame's
    order) the behaviours it allows, and Γ(b) is the set of classes that allow b ([MTT]
    eq 23: the preset's own Γ is liner {b1}, bomber {b1, b2}, fighter {b1, b2, b3}).

    Raises
    ------
    ModelConfigError
        A behaviour the preset does not have, or one that no class allows (a track showing
        it would contradict every class).
    """
    behaviours = chosen.behaviours.frame.labels
    unknown = sorted({b for bs in allowed.values() for b in bs} - set(behaviours))
    if unknown:
        raise ModelConfigError(
            f"behaviours {unknown} are not the {chosen.name} preset's; it has {list(behaviours)}"
        )
    images = {b: [c for c, bs in allowed.items() if b in set(bs)] for b in behaviours}
    orphans = [b for b, classes in images.items() if not classes]
    if orphans:
        raise ModelConfigError(
            f"no class allows the behaviours {orphans}: every behaviour of the "
            f"{chosen.name} preset ({list(behaviours)}) needs a class that allows it"
        )
    relation = Relation.from_mapping(chosen.behaviours.frame, Frame(list(allowed)), images)
    return replace(chosen, relation=relation)


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
