"""The validated configuration of a fusion session (docs/design.md "Session config").

Plain frozen dataclasses: ``app`` translates the wire model into these; the
core never sees pydantic.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

from core.association import DEFAULT_DISTANCE
from core.association.associate import resolve_method
from core.belief import Frame
from core.errors import InvalidInput, TrackingError
from core.fusion.detections import check_layout_for_detections
from core.fusion.state import StateFusion
from core.geometry import Coverage, FieldOfView, PolygonView
from core.lifecycle import LifeCycleConfig
from core.models import MappedMotion
from core.models.measurement import MeasurementModel
from core.tracking.config import LocalTrackerConfig
from core.tracking.range_rate import require_velocities
from core.volume import RadarVolume

CENTRAL_MIN_SENSORS = 2
"""Detecting sensors (not flagged ``local_tracker``) from which a session tracks centrally
(a single detecting sensor keeps its own tracker: there is nothing to fuse centrally)."""
CENTRAL_SOURCE = "central"
"""The fused layer's source id of the central tracker (:attr:`FusionConfig.central_source`)."""
CENTRAL_P_DETECT = 1.0 - 1e-9
"""P_D of the central tracker's source in the fused layer: it reports every track it keeps
at every step, so a track missing from its report is one it ended (one miss deletes)."""


@dataclass(frozen=True)
class SensorSpec:
    """One sensor of the session.

    Attributes
    ----------
    id : the sensor's name in reports.
    reliability : λ for discounting its class evidence ([MTT] eq 7).
    p_detect : P_D, used by the track score.
    fov : its field of view, or None if it sees everywhere.
    volume : a 3-D radar's coverage volume (:mod:`core.volume`), or None: none.
    tracker : for a sensor that sends raw detections, its own tracker
        configuration (the session tracks them, docs/algorithms.md §4, §8.9); None for a
        sensor that sends track lists.
    local_tracker : a detecting sensor tracked on its own (its local tracker, then
        track-to-track fusion, docs/algorithms.md §8.9); False (default): its detections go
        to the central tracker (:attr:`FusionConfig.central_tracker`) with the other
        detecting sensors' not flagged, when there are two or more.
    model : the measurement model of its detections (:mod:`core.models.measurement`), built
        once with the session's configuration; every detection report of the sensor
        carries it (:attr:`~core.fusion.reports.DetectionReport.model`). None for a sensor
        that sends track lists.
    """

    id: str
    reliability: float = 1.0
    p_detect: float = 0.9
    fov: FieldOfView | None = None
    volume: RadarVolume | None = None
    tracker: LocalTrackerConfig | None = None
    local_tracker: bool = False
    model: MeasurementModel | None = field(default=None, compare=False)

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
    central_tracker : derived, not given: with two or more detecting sensors not flagged
        ``local_tracker``, one tracker over all their detections in time order
        (:meth:`LocalTrackerConfig.central`, docs/algorithms.md §8.9); its tracks enter the
        fusion step as the track list of the source :attr:`central_source`. None: every
        detecting sensor has its own local tracker.
    """

    motion: MappedMotion
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
    central_tracker: LocalTrackerConfig | None = field(init=False, default=None)

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
        central = {
            sensor.id: sensor.tracker
            for sensor in self.sensors
            if sensor.tracker is not None and not sensor.local_tracker
        }
        if len(central) >= CENTRAL_MIN_SENSORS:
            try:
                tracker = LocalTrackerConfig.central(central, id_prefix=f"{self.central_source}:")
            except TrackingError as error:
                raise InvalidInput(str(error), loc=("sensors",)) from None
            # the session's surveillance region: a target between two sensors' views (and
            # inside it) is in a blind zone, a phantom that hands over, not out of range (§8.9)
            tracker = dataclasses.replace(tracker, region=self.region)
            object.__setattr__(self, "central_tracker", tracker)
        distance = self.distance or DEFAULT_DISTANCE.get(self.association_method, "sum")
        # a bad method, option or distance fails here, not at the first step that runs it
        resolve_method(self.association_method, self.association_options, distance)
        object.__setattr__(self, "distance", distance)

    def _check_detecting_sensor(self, sensor: SensorSpec, tracker: LocalTrackerConfig) -> None:
        check_layout_for_detections(self.motion.layout)
        preset = tracker.tracking_preset()
        rates = getattr(sensor.model, "velocity_mapping", None) is not None
        if rates:
            try:
                require_velocities(preset)
            except TrackingError as error:
                raise InvalidInput(f"sensor {sensor.id!r}: {error}") from None
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

    @property
    def central_source(self) -> str:
        """The source id of the central tracker's tracks in the fused layer: ``central``,
        with ``~`` appended while a sensor has that id."""
        ids = {sensor.id for sensor in self.sensors}
        name = CENTRAL_SOURCE
        while name in ids:
            name += "~"
        return name

    def tracked_centrally(self, sensor_id: str) -> bool:
        """Whether ``sensor_id``'s detections go to the central tracker."""
        return self.central_tracker is not None and sensor_id in self.central_tracker.sensors

    def source(self, source_id: str) -> SensorSpec:
        """A sensor, or the central tracker's source (:data:`CENTRAL_SPEC` under its id)."""
        if self.central_tracker is not None and source_id == self.central_source:
            return dataclasses.replace(CENTRAL_SPEC, id=source_id)
        return self.sensor(source_id)

    @property
    def sources(self) -> tuple[str, ...]:
        """The fused layer's sources: the sensors, then the central tracker's."""
        ids = tuple(sensor.id for sensor in self.sensors)
        return ids if self.central_tracker is None else (*ids, self.central_source)

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
        return Coverage(
            tuple(sensor.fov for sensor in self.sensors),
            self.region,
            tuple(sensor.volume for sensor in self.sensors),
        )


CENTRAL_SPEC = SensorSpec(id=CENTRAL_SOURCE, p_detect=CENTRAL_P_DETECT)
"""The central tracker's source in the fused layer (sees everywhere: module constants)."""
