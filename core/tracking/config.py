"""The validated configuration of one sensor system's :class:`~core.tracking.tracker.LocalTracker`.

Plain frozen dataclasses, no web types (docs/algorithms.md §4). Every option the
papers leave open is a named field here; the defaults are the ones of
docs/algorithms.md §3.7 and §4.

The defaults are for real sensors (docs/algorithms.md §8): single-point
starts with no velocity knowledge (a 1 m/s walker and a 300 m/s aircraft
alike), confirmation at a second hit that leaves the score ≥ 0, deletion
after the run of misses a true target shows with probability β, each
sensor's clutter density estimated from its own data when not given
(:mod:`core.tracking.clutter`). :meth:`LocalTrackerConfig.paper` is the
tracker of the papers' experiments (the first two editions' defaults).

Readings
--------
``initiation``
    ``"single_point"`` (default) or ``"two_point"`` (the paper profile): an
    unassigned detection becomes a *seed*; a
    seed joined by an unassigned detection of the next scan within
    ``max_speed · Δt`` (plus the gate on R) starts a tentative track by
    :func:`~core.tracking.initiator.two_point_initiation`, scored from
    ``L₀ = ln(β_NT/β_FT)`` plus the second detection's hit ΔL under
    ``R₀ + R₁ + initial_velocity_std² Δt² I`` (the pair's evidence, so a pair of a
    true target starts well above the delete threshold; a pair at or below it
    starts nothing). R₀, R₁ are the two detections' own covariances (the
    bank's R for a detection without one; a seed keeps its R until the next
    scan). ``"single_point"``: every unassigned detection
    starts a tentative track at once, position from z (its covariance R), velocity
    0 with standard deviation ``initial_velocity_std`` per axis (for the
    heading convention of the pedestrian models: heading 0 with variance
    ``initial_velocity_std²``); the large velocity variance makes the first
    gate wide and the first hit increment small, and the SPRT does the rest.
``imm_distance``
    ``"gated_combined"`` (default): a (track, detection) pair is gated with the
    model j of the track's bank that gives the smallest
    ``D_j = (z − ẑ_j)ᵀ S_j⁻¹ (z − ẑ_j)``, and the association decides on the
    model-combined D of [MTT] §4, capped just under the gate (a gated pair
    stays possible); the track score takes the closest model's D_j and S_j.
    ``"closest_model"``: gated and associated on the closest model's D_j;
    ``"combined"``: gated and associated on the model-combined ẑ, S. On
    ``close-pair`` ``closest_model`` confuses two aircraft 10 m apart (the
    neighbour is where a ±2g model predicts), on ``crossing`` ``combined``
    loses the fighter at its 4g step (the detection leaves the combined
    gate); ``gated_combined`` does neither (docs/algorithms.md §4).
``distance``
    ``"plain"`` ([MTT] eq 15) or ``"modified"`` ([HZ] §4.1 with the Reading of
    :mod:`core.distance.modified`), S_ss the steady state of the bank's first
    model (the constant-velocity model of both presets) with the bank's R.
``fields_of_view``
    The fields of view of the system's sensors by name; a scan names its
    sensor. Tracks that scan's sensor should have seen (inside its field of
    view, not occluded) and that got no detection count a miss. The
    surveillance region is ``region`` or, by default, the union of the
    sensors' ranges (:mod:`core.geometry`). No fields of view: one sensor
    that sees everything.
``life_cycle``
    Score, confirmation, deletion, gate emptiness, occlusion and phantoms are
    :class:`~core.lifecycle.LifeCycleConfig`, shared with the fusion engine;
    ``p_detect`` is the tracker's P_D, ``sensor_physics`` each sensor's own P_D and
    β_FT (a scan is scored with its sensor's). β_FT left out (here and in
    the life cycle) is estimated from the sensor's detections
    (:mod:`core.tracking.clutter`); β_NT left out is the scan's β_FT. ``score_ceiling`` (there): the SPRT of
    [MTT] §4.3 as written never deletes a track that has lived a while: with
    β_FT = 1e-6 each hit adds about +11, so after 100 hits the delete
    threshold is hundreds of misses away. Blackman & Popoli delete on a fixed
    drop below the track's best score; we clamp an established track's score
    at ``score_ceiling``, so it is deleted after
    ``⌈(ceiling − delete) / |ln(1 − P_D)|⌉`` consecutive misses. The default
    ceiling 0 restarts the test once a track is established: 3 misses at
    P_D 0.9, the run a true target shows with probability β (Stone Soup's
    tutorial deletes after 3 scans without an update); the paper profile's
    ceiling is the confirm threshold (6). ``None`` keeps the raw SPRT.
    Tentative tracks are scored up to their confirm threshold.
    The gate of the gate-emptiness volume and of the hand-over is the life
    cycle's ``gate_probability``, not the association's.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from types import MappingProxyType
from typing import Any, Literal

import numpy as np

from core.arrays import FloatArray
from core.classification.behaviours import (
    LIKELIHOOD_SCALES,
    MODE_PROBABILITY_READINGS,
    LikelihoodScale,
    ModeProbabilities,
)
from core.classification.calibration import SIGNIFICANCE
from core.classification.credal import ACCUMULATIONS, DISCOUNTS, Accumulation, Discount
from core.errors import TrackingError
from core.geometry import Coverage, FieldOfView, PolygonView
from core.lifecycle import LifeCycleConfig, ScoreModel
from core.tracking.models import LinearMeasurementModel, ModelBank
from core.tracking.presets import TrackingPreset, preset, with_classes
from core.volume import RadarVolume

ImmDistance = Literal["closest_model", "combined", "gated_combined"]
DistanceKind = Literal["plain", "modified"]
Initiation = Literal["two_point", "single_point"]
UNKNOWN_VELOCITY_STD = 100.0
"""σ_v (m/s per axis) of a start without a velocity prior: a 300 m/s target's second
detection one scan later is at D ≤ 9, inside the χ² 0.999 gate (13.8 in 2-D)."""

IMM_DISTANCES: tuple[ImmDistance, ...] = ("closest_model", "combined", "gated_combined")
DEFAULT_IMM_DISTANCE: ImmDistance = "gated_combined"
"""docs/algorithms.md §4 "Assignment": neither confuses close targets nor loses a 4g turn."""
DISTANCE_KINDS: tuple[DistanceKind, ...] = ("plain", "modified")
INITIATIONS: tuple[Initiation, ...] = ("two_point", "single_point")


@dataclass(frozen=True)
class ClassificationOptions:
    """Credal kinematic classification of the tracks ([MTT] §5.2, docs/algorithms.md §5).

    Attributes
    ----------
    likelihood_scale : "max" | "clip"
    discount : "none" | "instantaneous" | "cumulative"
    reliability : λ, or None for the default of ``discount``
    accumulation : "classes" | "behaviours"
    mode_probabilities : "updated" | "predicted"
        Which μ_j weight the behaviour plausibilities ([MTT] eq 22; the
        Reading in :mod:`core.classification.behaviours`).
    significance : κ of the mode likelihoods' noise calibration
        (:mod:`core.classification.calibration`, docs/algorithms.md §5); None: the raw
        likelihoods of [MTT] eq 18
    """

    likelihood_scale: LikelihoodScale = "max"
    discount: Discount = "none"
    reliability: float | None = None
    accumulation: Accumulation = "classes"
    mode_probabilities: ModeProbabilities = "updated"
    significance: float | None = SIGNIFICANCE

    def __post_init__(self) -> None:
        if self.likelihood_scale not in LIKELIHOOD_SCALES:
            raise TrackingError(f"likelihood_scale must be one of {LIKELIHOOD_SCALES}")
        if self.discount not in DISCOUNTS:
            raise TrackingError(f"discount must be one of {DISCOUNTS}")
        if self.accumulation not in ACCUMULATIONS:
            raise TrackingError(f"accumulation must be one of {ACCUMULATIONS}")
        if self.mode_probabilities not in MODE_PROBABILITY_READINGS:
            raise TrackingError(f"mode_probabilities must be one of {MODE_PROBABILITY_READINGS}")
        if self.reliability is not None and not (0.0 <= self.reliability <= 1.0):
            raise TrackingError(f"reliability must be in [0, 1], got {self.reliability!r}")
        if self.significance is not None and not (
            math.isfinite(self.significance) and self.significance >= 0.0
        ):
            raise TrackingError(f"significance must be >= 0 or None, got {self.significance!r}")


PAPER_CLASSIFICATION = ClassificationOptions(significance=None)
"""[MTT]'s classification as printed: the raw mode likelihoods (the papers' experiments ask
for it; the default calibrates them to the sensor's noise, §8.5)."""


@dataclass(frozen=True)
class SensorPhysics:
    """What a sensor's data sheet says about its detections, for the track score.

    Attributes
    ----------
    p_detect : P_D, or None for the tracker's ``p_detect``.
    clutter_density : β_FT per unit of position space per scan, or None: the life
        cycle's, else estimated from the sensor's detections (:mod:`core.tracking.clutter`).
    measurement_noise : R of the sensor's detections that carry no covariance of their
        own, or None: the tracker's (the bank's R).
    """

    p_detect: float | None = None
    clutter_density: float | None = None
    measurement_noise: tuple[tuple[float, ...], ...] | None = None

    def __post_init__(self) -> None:
        if self.measurement_noise is not None:
            noise = np.asarray(self.measurement_noise, dtype=np.float64)
            q = len(noise)
            if noise.shape != (q, q) or not np.all(np.isfinite(noise)):
                raise TrackingError("measurement_noise must be a finite square matrix")
        if self.p_detect is not None and not (
            math.isfinite(self.p_detect) and 0.0 < self.p_detect < 1.0
        ):
            raise TrackingError(f"p_detect must be in (0, 1), got {self.p_detect!r}")
        if self.clutter_density is not None and not (
            math.isfinite(self.clutter_density) and self.clutter_density > 0.0
        ):
            raise TrackingError(
                f"clutter_density must be a positive number, got {self.clutter_density!r}"
            )


NO_PHYSICS = SensorPhysics()
"""A sensor without a data sheet of its own: the tracker's (one instance, not one per look-up)."""


@dataclass(frozen=True)
class LocalTrackerConfig:
    """Everything a :class:`~core.tracking.tracker.LocalTracker` needs (module Readings).

    Attributes
    ----------
    preset : name of a preset (``"aircraft"``, ``"pedestrian"``) giving the model
        bank, behaviours and classes.
    time_interval : the nominal scan period ΔT of the bank (s); scans come at any
        increasing times (see :mod:`core.tracking.models` for where ΔT is used).
    axes : position axes of the preset's models, 2 or 3 (3-D: see :mod:`core.tracking.presets`).
    preset_options : other keyword options of the preset (``stay``, ``noise_intensity``, ...).
    bank : an explicit model bank; replaces the preset's (and then there is no
        classification: behaviours belong to the preset's models).
    measurement_noise : R (q × q) replacing the bank's; detections may also
        carry their own covariance in :meth:`LocalTracker.step`.
    association_method : a method of the registry's ``local`` scope
        (``core.association.methods("local")``): ``gnn`` (default), ``denoeux``,
        ``hachour``, ``mercier``, ``dang_han``, ``cheap_jpda``, ``jpda``.
    association_options : the method's options (its spec's); ``cheap_jpda``'s
        ``bias`` (B of [DH] eq 16) defaults to the PDA's clutter term from the life
        cycle's ``false_target_density`` (:func:`core.tracking.jpda.clutter_bias`).
    imm_distance, distance : see the module Readings.
    modified_beta, modified_k, modified_alpha : β, k, α of the modified distance.
    p_detect : P_D of the system's sensors (the track score), unless ``sensor_physics`` says.
    sensor_physics : each sensor's own P_D and β_FT by name (:class:`SensorPhysics`); a
        sensor not named takes ``p_detect`` and the life cycle's β_FT.
    life_cycle : score thresholds and densities, confirmation, deletion, gate
        emptiness, occlusion and phantoms (:class:`~core.lifecycle.LifeCycleConfig`);
        β_FT left None is estimated per sensor (module Readings).
    initiation, max_speed : see the module Readings.
    initial_velocity_std : σ_v of a new track's velocity per axis (m/s), the velocity
        prior; None (default): no velocity knowledge (module Readings).
    fields_of_view : the system's sensors and their fields of view.
    volumes : the coverage volume of each 3-D radar that has one (:mod:`core.volume`), by
        sensor; a sensor not named has none (docs/algorithms.md §8.11).
    region : the surveillance region (default: union of the sensors' ranges).
    classification : credal options, or None for no classification; ignored
        when the bank has no classes.
    class_behaviours : the session's own classes, each with the preset's behaviours it
        allows (in the class frame's order; :func:`core.tracking.presets.with_classes`);
        None: the preset's classes.
    id_prefix : track ids are ``f"{id_prefix}{n}"``, n = 1, 2, ...
    """

    preset: str = "aircraft"
    time_interval: float = 1.0
    axes: int = 2
    preset_options: Mapping[str, float] = field(default_factory=lambda: MappingProxyType({}))
    bank: ModelBank | None = None
    measurement_noise: tuple[tuple[float, ...], ...] | None = None
    association_method: str = "gnn"
    association_options: Mapping[str, object] = field(
        default_factory=lambda: MappingProxyType({"gate_probability": 0.999})
    )
    imm_distance: ImmDistance = DEFAULT_IMM_DISTANCE
    distance: DistanceKind = "plain"
    modified_beta: float = 10.0
    modified_k: float = 1.0
    modified_alpha: float = 4.0
    p_detect: float = 0.9
    sensor_physics: Mapping[str, SensorPhysics] = field(
        default_factory=lambda: MappingProxyType({})
    )
    life_cycle: LifeCycleConfig = field(default_factory=LifeCycleConfig)
    initiation: Initiation = "single_point"
    max_speed: float = 1000.0
    initial_velocity_std: float | None = None
    fields_of_view: Mapping[str, FieldOfView | None] = field(
        default_factory=lambda: MappingProxyType({"sensor": None})
    )
    volumes: Mapping[str, RadarVolume] = field(default_factory=lambda: MappingProxyType({}))
    region: PolygonView | None = None
    classification: ClassificationOptions | None = field(default_factory=ClassificationOptions)
    class_behaviours: Mapping[str, tuple[str, ...]] | None = None
    id_prefix: str = "L"

    def __post_init__(self) -> None:
        if self.imm_distance not in IMM_DISTANCES:
            raise TrackingError(f"imm_distance must be one of {IMM_DISTANCES}")
        if self.distance not in DISTANCE_KINDS:
            raise TrackingError(f"distance must be one of {DISTANCE_KINDS}")
        if self.initiation not in INITIATIONS:
            raise TrackingError(f"initiation must be one of {INITIATIONS}")
        if not (math.isfinite(self.p_detect) and 0.0 < self.p_detect < 1.0):
            raise TrackingError(f"p_detect must be in (0, 1), got {self.p_detect!r}")
        for name in ("time_interval", "axes"):
            if name in self.preset_options:
                raise TrackingError(f"give {name} as the config field, not a preset option")
        if self.axes not in (2, 3):
            raise TrackingError(f"the presets track 2 or 3 position axes, got {self.axes!r}")
        for name in (
            "time_interval",
            "modified_beta",
            "modified_k",
            "modified_alpha",
            "max_speed",
            "initial_velocity_std",
        ):
            value = getattr(self, name)
            if value is None and name == "initial_velocity_std":
                continue
            if not (math.isfinite(value) and value > 0.0):
                raise TrackingError(f"{name} must be a positive number, got {value!r}")
        if not self.fields_of_view:
            raise TrackingError("fields_of_view needs at least one sensor")
        unknown = sorted(set(self.sensor_physics) - set(self.fields_of_view))
        if unknown:
            raise TrackingError(f"sensor_physics names {unknown}, not among fields_of_view")
        unknown = sorted(set(self.volumes) - set(self.fields_of_view))
        if unknown:
            raise TrackingError(f"volumes names {unknown}, not among fields_of_view")

    @classmethod
    def paper(cls, **options: Any) -> LocalTrackerConfig:
        """The tracker of the papers' experiments (the first two editions' defaults):
        two-point starts (σ_v 300 m/s, pairs within 1000 m/s), the paper life cycle
        (:meth:`~core.lifecycle.LifeCycleConfig.paper`: densities one per km^q, score-only
        confirmation, ceiling at the confirm threshold, [HZ]'s gate emptiness from the
        first miss); ``options`` override any field (``life_cycle`` as a whole)."""
        measured = int(options.get("axes", 2))
        bank = options.get("bank")
        if isinstance(bank, ModelBank):
            measured = bank.measurement.dim
        settings: dict[str, Any] = {
            "initiation": "two_point",
            "initial_velocity_std": 300.0,
            "life_cycle": LifeCycleConfig.paper(measured),
        }
        settings.update(options)
        return cls(**settings)

    @classmethod
    def central(
        cls, configs: Mapping[str, LocalTrackerConfig], id_prefix: str = "C"
    ) -> LocalTrackerConfig:
        """One tracker over the detections of the sensors ``configs`` (each one's own tracker
        configuration, by sensor; docs/algorithms.md §8.9).

        Each sensor keeps what is its own: its fields of view and volume, P_D, β_FT (given,
        or estimated from its own detections), and R (``sensor_physics``; its measurement
        model rides with its detections).
        Everything else (models, association, life cycle, initiation, classification)
        is the session's and must agree; the bank's R is the sensor's R of the largest
        eigenvalue (the gate of a track without a detection is never smaller than a
        detection's).
        """
        if not configs:
            raise TrackingError("a central tracker needs at least one sensor")
        names = list(configs)
        first = configs[names[0]]
        noises = {name: configs[name].model_bank().measurement.noise_covariance for name in names}
        if len({noise.shape for noise in noises.values()}) != 1:
            raise TrackingError("the sensors of a central tracker measure different dimensions")
        widest = max(names, key=lambda name: float(np.linalg.eigvalsh(noises[name])[-1]))
        reference = noises[widest]
        base = first.session_part(id_prefix)
        views: dict[str, FieldOfView | None] = {}
        volumes: dict[str, RadarVolume] = {}
        physics: dict[str, SensorPhysics] = {}
        for name in names:
            config = configs[name]
            common = config.session_part(id_prefix)
            if common != base or (config.bank is None) != (first.bank is None):
                differing = [
                    f.name
                    for f in fields(cls)
                    if f.name != "bank" and getattr(common, f.name) != getattr(base, f.name)
                ] or ["bank"]
                raise TrackingError(
                    f"sensor {name!r}: a central tracker needs the same {differing} for every "
                    "sensor"
                )
            for sensor, view in config.fields_of_view.items():
                p_detect, clutter = config.physics(sensor)
                own = noises[name]
                views[sensor] = view
                if sensor in config.volumes:
                    volumes[sensor] = config.volumes[sensor]
                physics[sensor] = SensorPhysics(
                    p_detect=p_detect,
                    clutter_density=clutter,
                    measurement_noise=(
                        None
                        if np.array_equal(own, reference)
                        else tuple(tuple(float(x) for x in row) for row in own)
                    ),
                )
        return replace(
            first,
            life_cycle=replace(first.life_cycle, false_target_density=None),
            measurement_noise=tuple(tuple(float(x) for x in row) for row in reference),
            sensor_physics=MappingProxyType(physics),
            fields_of_view=MappingProxyType(views),
            volumes=MappingProxyType(volumes),
            id_prefix=id_prefix,
        )

    def session_part(self, id_prefix: str) -> LocalTrackerConfig:
        """The configuration without what is each sensor's own (:meth:`central`): no bank, R,
        P_D, β_FT, physics, fields of view or volumes of its own."""
        return replace(
            self,
            bank=None,
            measurement_noise=None,
            p_detect=LocalTrackerConfig.p_detect,
            sensor_physics=MappingProxyType({}),
            fields_of_view=MappingProxyType({"sensor": None}),
            volumes=MappingProxyType({}),
            life_cycle=replace(self.life_cycle, false_target_density=None),
            id_prefix=id_prefix,
        )

    @property
    def velocity_std(self) -> float:
        """σ_v of a start: the velocity prior, or :data:`UNKNOWN_VELOCITY_STD` without one."""
        given = self.initial_velocity_std
        return UNKNOWN_VELOCITY_STD if given is None else given

    @property
    def measured(self) -> int:
        """The number of measured position components."""
        return self.axes if self.bank is None else self.bank.measurement.dim

    def physics(self, sensor: str) -> tuple[float, float | None]:
        """``(P_D, β_FT or None: estimate it)`` of a sensor's scans."""
        own = self.sensor_physics.get(sensor, NO_PHYSICS)
        p_detect = self.p_detect if own.p_detect is None else own.p_detect
        clutter = own.clutter_density
        return p_detect, self.life_cycle.false_target_density if clutter is None else clutter

    def noise(self, sensor: str) -> FloatArray | None:
        """R of ``sensor``'s detections without their own covariance, when it is not the
        bank's (``sensor_physics``); None: the bank's."""
        own = self.sensor_physics.get(sensor, NO_PHYSICS).measurement_noise
        return None if own is None else np.array(own, dtype=np.float64)

    def tracking_preset(self) -> TrackingPreset | None:
        """The preset (with the session's own classes, ``class_behaviours``), or None when
        an explicit bank replaces it."""
        if self.bank is not None:
            return None
        found = preset(
            self.preset,
            time_interval=self.time_interval,
            axes=self.axes,
            **dict(self.preset_options),
        )
        return (
            found if self.class_behaviours is None else with_classes(found, self.class_behaviours)
        )

    def model_bank(self, found: TrackingPreset | None = None) -> ModelBank:
        """The bank the tracker runs, with ``measurement_noise`` applied (``found``: the
        :meth:`tracking_preset` built already)."""
        chosen = self.bank
        if chosen is None:
            found = found or self.tracking_preset()
            assert found is not None
            chosen = found.bank
        if self.measurement_noise is None:
            return chosen
        noise = np.array(self.measurement_noise, dtype=np.float64)
        measurement = LinearMeasurementModel(chosen.measurement.matrix, noise)
        return ModelBank(chosen.models, measurement, chosen.mode_transition)

    @property
    def coverage(self) -> Coverage:
        """The system's coverage: one view (and volume) per sensor, in configuration order."""
        volumes = tuple(self.volumes.get(name) for name in self.fields_of_view)
        return Coverage(tuple(self.fields_of_view.values()), self.region, volumes)

    @property
    def sensors(self) -> tuple[str, ...]:
        """Sensor names, in configuration order."""
        return tuple(self.fields_of_view)

    @property
    def score(self) -> ScoreModel:
        """The SPRT score of the tracker's sensors (P_D and the life cycle's densities;
        :func:`~core.lifecycle.default_density` for a density left to the estimate)."""
        return self.life_cycle.for_dimension(self.measured).score_model(self.p_detect)
