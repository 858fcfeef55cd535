"""The validated configuration of a fusion session (docs/design.md "Session config").

Plain frozen dataclasses: ``app`` translates the wire model into these; the
core never sees pydantic.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

from core.association import DEFAULT_DISTANCE
from core.association.associate import resolve_method
from core.belief import Frame
from core.errors import InvalidInput
from core.fusion.detections import check_layout_for_detections
from core.fusion.motion import MotionModel
from core.fusion.state import StateFusion
from core.geometry import Coverage, FieldOfView, PolygonView
from core.lifecycle import LifeCycleConfig
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
        configuration (the session tracks them, docs/algorithms.md §4); None for a
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
class FusionConfig:
    """Everything the session engine needs, validated.

    Attributes
    ----------
    motion : the fused tracks' motion model (it carries the state layout).
    sensors : the session's sensors, in a fixed order.
    classes : the class frame, or None for a session without classification.
    association_method, association_options, distance : track-to-track association
        (defaults of docs/algorithms.md §3.7: ``denoeux``, gate probability 0.999, α = 1, ``sum``);
        ``distance=None`` takes the method's own (``core.association.DEFAULT_DISTANCE``).
    track_continuity : a report track that keeps the id under which its sensor
        last reported a live fused track stays with it while it passes a loose χ²
        gate (``sum`` distance, see ``core.fusion.associate.CONTINUITY_GATE_PROBABILITY``); only the rest
        goes to the association method. Off, every report is associated afresh.
    state_fusion : how the sensors' latest estimates are combined.
    management : the track life cycle (shared with the local trackers); its densities
        are per unit of position space (area in 2-D) per report: the score and the
        gate volume are computed on the position components (densities left None
        become :func:`~core.lifecycle.default_density` of the layout's positions).
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
    management: LifeCycleConfig = field(default_factory=LifeCycleConfig)
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
        positions = len(self.motion.layout.position)
        object.__setattr__(self, "management", self.management.for_dimension(positions))
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
                " (tracking.class_behaviours maps the session's own classes to its behaviours)"
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
            f"unknown sensor {sensor_id!r}; the session has {[s.id for s in self.sensors]}",
            loc=("sensor",),
        )

    @property
    def coverage(self) -> Coverage:
        return Coverage(tuple(sensor.fov for sensor in self.sensors), self.region)
