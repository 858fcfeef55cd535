"""The validated configuration of a fusion session (DESIGN.md "Session config").

Plain frozen dataclasses: ``app`` translates the wire model into these; the
core never sees pydantic.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from types import MappingProxyType

from core.association import DEFAULT_DISTANCE
from core.association.associate import resolve_method
from core.belief import Frame
from core.errors import InvalidInput
from core.fusion.detections import check_layout_for_detections
from core.fusion.motion import MotionModel
from core.fusion.state import StateFusion
from core.geometry import Coverage, FieldOfView, PolygonView
from core.lifecycle import ScoreModel
from core.tracking.config import LocalTrackerConfig


@dataclass(frozen=True)
class SensorSpec:
    """One sensor of the session.

    Attributes
    ----------
    id : the sensor's name in reports.
    reliability : λ for discounting its class evidence ([MTT] eq 7).
    p_detect : P_D, used by the track score.
    fov : its field of view, or None if it sees everywhere.
    tracker : for a sensor that sends raw detections, its local tracker's
        configuration (the session tracks them, ALGORITHMS.md §4); None for a
        sensor that sends track lists.
    """

    id: str
    reliability: float = 1.0
    p_detect: float = 0.9
    fov: FieldOfView | None = None
    tracker: LocalTrackerConfig | None = None

    def __post_init__(self) -> None:
        if not self.id:
            raise InvalidInput("sensor id must not be empty")
        if not (math.isfinite(self.reliability) and 0.0 <= self.reliability <= 1.0):
            raise InvalidInput(f"sensor {self.id!r}: reliability must be in [0, 1]")
        if not (math.isfinite(self.p_detect) and 0.0 < self.p_detect < 1.0):
            raise InvalidInput(f"sensor {self.id!r}: p_detect must be in (0, 1)")


@dataclass(frozen=True)
class TrackManagement:
    """Track life cycle at the fused level (ALGORITHMS.md §4, §6 step 5).

    Densities are per unit of position space (area in 2-D) per report:
    the score and the gate volume are computed on the position components.
    As in the local tracker (``core.tracking.config``, Reading ``score_margin``),
    the score is clamped at ``confirm threshold + score_margin`` so that a
    long-lived track is still deleted after a few consecutive misses where it
    should have been seen; ``None`` keeps the raw SPRT.
    """

    false_confirmation: float = 1e-3
    true_deletion: float = 1e-3
    false_target_density: float = 1e-6
    new_target_density: float = 1e-5
    termination_probability: float = 0.5
    gate_probability: float = 0.999
    min_points: int | None = None
    phantom_max_distance: float = 500.0
    phantom_min_speed: float = 1.0
    occlusion_radius: float = 0.0
    score_margin: float | None = 0.0

    def __post_init__(self) -> None:
        if self.score_margin is not None and not (
            math.isfinite(self.score_margin) and self.score_margin >= 0.0
        ):
            raise InvalidInput(f"score_margin must be >= 0 or None, got {self.score_margin!r}")
        for name in ("termination_probability", "gate_probability"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 < value < 1.0):
                raise InvalidInput(f"{name} must be in (0, 1), got {value!r}")
        for name in ("phantom_max_distance", "phantom_min_speed"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise InvalidInput(f"{name} must be a positive number, got {value!r}")
        if not (math.isfinite(self.occlusion_radius) and self.occlusion_radius >= 0.0):
            raise InvalidInput(f"occlusion_radius must be >= 0, got {self.occlusion_radius!r}")
        if self.min_points is not None and self.min_points < 1:
            raise InvalidInput(f"min_points must be >= 1, got {self.min_points}")

    def score_model(self, p_detect: float) -> ScoreModel:
        """The SPRT score of a sensor with detection probability ``p_detect`` (built once)."""
        return _score_model(self, p_detect)

    @cached_property
    def thresholds(self) -> ScoreModel:
        """The SPRT thresholds (they depend on α and β only, not on P_D)."""
        return self.score_model(p_detect=0.5)

    @cached_property
    def score_ceiling(self) -> float:
        """Largest score a fused track keeps (+inf without a margin)."""
        if self.score_margin is None:
            return math.inf
        return self.thresholds.confirm_threshold + self.score_margin

    @property
    def phantom_lifetime(self) -> float:
        """Longest time in a blind zone: the maximum distance at the minimum speed ([HZ] §5.1)."""
        return self.phantom_max_distance / self.phantom_min_speed


@lru_cache(maxsize=64)
def _score_model(management: TrackManagement, p_detect: float) -> ScoreModel:
    return ScoreModel(
        p_detect=p_detect,
        false_target_density=management.false_target_density,
        new_target_density=management.new_target_density,
        false_confirmation=management.false_confirmation,
        true_deletion=management.true_deletion,
    )


@dataclass(frozen=True)
class FusionConfig:
    """Everything the session engine needs, validated.

    Attributes
    ----------
    motion : the fused tracks' motion model (it carries the state layout).
    sensors : the session's sensors, in a fixed order.
    classes : the class frame, or None for a session without classification.
    association_method, association_options, distance : track-to-track association
        (defaults of ALGORITHMS.md §3.7: ``denoeux``, gate probability 0.999, α = 1, ``sum``);
        ``distance=None`` takes the method's own (``core.association.DEFAULT_DISTANCE``).
    track_continuity : a report track that keeps the id under which its sensor
        last reported a live fused track stays with it while it passes a loose χ²
        gate (``sum`` distance, see ``engine.CONTINUITY_GATE_PROBABILITY``); only the rest
        goes to the association method. Off, every report is associated afresh.
    state_fusion : how the sensors' latest estimates are combined.
    management : the track life cycle.
    region : the surveillance region; by default the union of the sensors'
        ranges (``core.geometry``): outside it a track is out of range.
    """

    motion: MotionModel
    sensors: tuple[SensorSpec, ...]
    classes: Frame | None = None
    association_method: str = "denoeux"
    association_options: Mapping[str, object] = field(
        default_factory=lambda: MappingProxyType({"gate_probability": 0.999, "alpha": 1.0})
    )
    distance: str | None = None
    track_continuity: bool = True
    state_fusion: StateFusion = StateFusion.COVARIANCE_INTERSECTION
    management: TrackManagement = field(default_factory=TrackManagement)
    region: PolygonView | None = None

    def __post_init__(self) -> None:
        if not self.sensors:
            raise InvalidInput("a session needs at least one sensor")
        ids = [sensor.id for sensor in self.sensors]
        repeated = sorted({sensor for sensor in ids if ids.count(sensor) > 1})
        if repeated:
            raise InvalidInput(f"sensor ids repeat: {repeated}")
        object.__setattr__(
            self, "association_options", MappingProxyType(dict(self.association_options))
        )
        for sensor in self.sensors:
            if sensor.tracker is not None:
                self._check_detecting_sensor(sensor, sensor.tracker)
        distance = self.distance or DEFAULT_DISTANCE.get(self.association_method, "sum")
        # a bad method, option or distance fails here, not at the first step that runs it
        resolve_method(self.association_method, self.association_options, distance)
        object.__setattr__(self, "distance", distance)

    def _check_detecting_sensor(self, sensor: SensorSpec, tracker: LocalTrackerConfig) -> None:
        check_layout_for_detections(self.motion.layout)
        preset = tracker.tracking_preset()
        preset_classes = (
            None if preset is None or tracker.classification is None else preset.classes
        )
        if (
            self.classes is not None
            and preset_classes is not None
            and preset_classes != self.classes
        ):
            raise InvalidInput(
                f"sensor {sensor.id!r}: its tracking preset classifies into "
                f"{list(preset_classes.labels)}, the session's classes are {list(self.classes.labels)}"
            )

    @property
    def dim(self) -> int:
        return self.motion.layout.dim

    def sensor(self, sensor_id: str) -> SensorSpec:
        """The sensor called ``sensor_id``."""
        for sensor in self.sensors:
            if sensor.id == sensor_id:
                return sensor
        raise InvalidInput(
            f"unknown sensor {sensor_id!r}; the session has {[s.id for s in self.sensors]}"
        )

    @property
    def coverage(self) -> Coverage:
        return Coverage(tuple(sensor.fov for sensor in self.sensors), self.region)
