"""Session configuration: ``POST /v1/sessions`` body and the resolved config it returns.

Everything is optional but the state layout. Unknown keys are an error at
every level. The resolved configuration (``SessionCreated.config``) is the
same model with every default filled in, so posting it back creates an
identical session.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal, Self

from pydantic import Discriminator, Field, StringConstraints, Tag, model_validator

from api_schemas.association import (
    AssociationMethod,
    AssociationOptions,
    LocalAssociationMethod,
    resolve_options,
)
from api_schemas.base import (
    MAX_CLASSES,
    FiniteFloat,
    Identifier,
    Label,
    Matrix,
    NonNegativeFloat,
    OpenUnitFloat,
    PositiveFloat,
    UnitFloat,
    WireModel,
)
from api_schemas.issues import FieldIssue, raise_issues
from api_schemas.limits import MAX_SENSORS, bounded
from api_schemas.linalg import R_DESCRIPTION, check_covariance
from core.models import TRANSITION_MODELS
from core.numerics import MAX_MAGNITUDE

MAX_STATE_DIM = 64

StateIndex = Annotated[int, Field(ge=0, lt=MAX_STATE_DIM)]
Point = Annotated[list[FiniteFloat], Field(min_length=2, max_length=2)]
Vertex = Annotated[tuple[FiniteFloat, ...], Field(min_length=2, max_length=2, strict=False)]
"""A polygon vertex: a JSON array of two numbers, a tuple once validated (a config keeps
up to 64 000 of them; tuples of floats leave the garbage collector's lists after one
pass, where lists would be walked at every full collection)."""
StateFusionMethod = Literal["covariance_intersection", "independent", "latest"]
TrackingPreset = Literal["aircraft", "pedestrian"]


class StateLayout(WireModel):
    """The state vector: its dimension and which components are positions, velocities and
    accelerations."""

    dim: Annotated[int, Field(ge=1, le=MAX_STATE_DIM)]
    position: Annotated[list[StateIndex], Field(min_length=1, max_length=3)]
    velocity: Annotated[list[StateIndex], Field(max_length=3)] = Field(default_factory=list)
    acceleration: Annotated[list[StateIndex], Field(max_length=3)] = Field(
        default_factory=list,
        description=(
            "the acceleration component of each axis, in the order of position (the singer "
            "motion model carries them); empty (the default): none"
        ),
    )

    @model_validator(mode="after")
    def _indices_consistent(self) -> Self:
        issues: list[FieldIssue] = []
        seen: set[int] = set()
        for field, indices in (
            ("position", self.position),
            ("velocity", self.velocity),
            ("acceleration", self.acceleration),
        ):
            for index, component in enumerate(indices):
                if component >= self.dim:
                    issues.append(
                        FieldIssue(
                            (field, index),
                            f"component {component} is outside the state (dim {self.dim})",
                            component,
                        )
                    )
                elif component in seen:
                    issues.append(
                        FieldIssue(
                            (field, index), f"component {component} is listed twice", component
                        )
                    )
                seen.add(component)
        if self.velocity and len(self.velocity) != len(self.position):
            issues.append(
                FieldIssue(
                    ("velocity",),
                    f"{len(self.velocity)} velocity components for {len(self.position)} position components",
                    self.velocity,
                )
            )
        if self.acceleration and len(self.acceleration) != len(self.velocity):
            issues.append(
                FieldIssue(
                    ("acceleration",),
                    f"{len(self.acceleration)} acceleration components for "
                    f"{len(self.velocity)} velocity components",
                    self.acceleration,
                )
            )
        if issues:
            raise_issues("StateLayout", issues)
        return self


class MotionModel(WireModel):
    """The fused tracks' motion model used to predict them between reports."""

    model: Literal["constant_velocity", "constant_position", "singer"] = "constant_velocity"
    q: PositiveFloat | None = Field(
        default=None,
        le=MAX_MAGNITUDE,  # q·Δt³ stays finite for every Δt of legal times (core.numerics)
        description=(
            "spectral density of the continuous white-noise acceleration (m²/s³): per axis "
            "Q = q [[Δt³/3, Δt²/2], [Δt²/2, Δt]] (constant_position: Q = q Δt), the same "
            "meaning for the fused tracks and for the local constant-velocity model of "
            "detections without a preset. null (the default): derived from "
            "tracking.preset when sensors send detections, so the fused tracks follow "
            "every manoeuvre of the preset's bank (the largest velocity change Δv of the "
            "bank in one time_interval ΔT at 3σ: q = Δv²/(9 ΔT), aircraft 342 at ΔT = 1 s, "
            "pedestrian 8), else 1"
        ),
    )
    manoeuvre_time: PositiveFloat | None = Field(
        default=None,
        le=MAX_MAGNITUDE,
        description=(
            "singer only: the manoeuvre time constant τ (s), the correlation time of the "
            "acceleration (Singer 1970: lazy turn 60 s, evasive manoeuvre 10-20 s, "
            "atmospheric turbulence 1 s). null (the default): 20 s"
        ),
    )
    acceleration_std: PositiveFloat | None = Field(
        default=None,
        le=MAX_MAGNITUDE,
        description=(
            "singer only: the acceleration's standard deviation σ_m (m/s²) per axis. null "
            "(the default): 18.9, Singer's σ_m² = A_max²/3 (1 + 4 P_max − P_0) for an "
            "aircraft's A_max = 4 g, P_max = 0.05, P_0 = 0.5"
        ),
    )

    @model_validator(mode="after")
    def _parameters_of_the_model(self) -> Self:
        """Each parameter goes with the models that have it."""
        singer = ("manoeuvre_time", "acceleration_std")
        given = self.model_fields_set
        issues = [
            FieldIssue((name,), f"{name} is a parameter of the singer model", getattr(self, name))
            for name in singer
            if name in given and getattr(self, name) is not None and self.model != "singer"
        ]
        if self.model == "singer" and self.q is not None:
            issues.append(
                FieldIssue(
                    ("q",),
                    "the singer model takes manoeuvre_time and acceleration_std, not q",
                    self.q,
                )
            )
        if issues:
            raise_issues("MotionModel", issues)
        return self


FovFrame = Literal["session", "sensor"]
"""Where a field of view's coordinates are: the session frame, or the sensor's own frame
(origin at its ``site``, y axis along its ``heading_deg``, x 90° clockwise from it: the
frame of a ``"frame": "sensor"`` track list), converted to the session frame once, when
the session is created."""

FOV_FRAME_DESCRIPTION = (
    "session (default): coordinates in the session frame; sensor: in the sensor's own frame "
    "(origin at its site, y along its heading_deg, x 90° clockwise from y), converted once "
    "when the session is created (a sensor without a site stands at the origin, heading 0)"
)


class SectorFieldOfView(WireModel):
    """A sensor's field of view as a sector: origin, heading, half-angle, range interval.

    ``heading_deg`` is the sector's axis, counter-clockwise from the frame's +x
    axis. In the sensor's frame (``frame: "sensor"``) the origin defaults to
    the site and ``heading_deg: 90`` is the sensor's own heading: a radar
    looking ±60° about its heading out to 50 km is ``{"kind": "sector",
    "frame": "sensor", "heading_deg": 90, "half_angle_deg": 60, "range": [0,
    50000]}``.
    """

    kind: Literal["sector"]
    frame: FovFrame = Field(default="session", description=FOV_FRAME_DESCRIPTION)
    origin: Point | None = Field(
        default=None,
        description="the sector's apex (required in the session frame; default: the site)",
    )
    heading_deg: FiniteFloat
    half_angle_deg: Annotated[float, Field(allow_inf_nan=False, gt=0.0, le=180.0)]
    range: Annotated[
        list[Annotated[float, Field(allow_inf_nan=False, ge=0.0)]],
        Field(min_length=2, max_length=2),
    ]

    @model_validator(mode="after")
    def _range_ordered(self) -> Self:
        issues = []
        if self.range[0] >= self.range[1]:
            issues.append(
                FieldIssue(("range",), "range must be [min, max] with min < max", self.range)
            )
        if self.origin is None and self.frame == "session":
            issues.append(
                FieldIssue(("origin",), "a sector in the session frame needs its origin", None)
            )
        if issues:
            raise_issues("SectorFieldOfView", issues)
        return self


class PolygonFieldOfView(WireModel):
    """A sensor's field of view as a simple polygon (vertices in order)."""

    kind: Literal["polygon"]
    frame: FovFrame = Field(default="session", description=FOV_FRAME_DESCRIPTION)
    vertices: Annotated[tuple[Vertex, ...], Field(min_length=3, max_length=1000, strict=False)]


FieldOfView = Annotated[SectorFieldOfView | PolygonFieldOfView, Field(discriminator="kind")]


class CartesianMeasurement(WireModel):
    """A detecting sensor that measures positions: ``r`` over the position components; its
    detections are ``{"z": [...]}`` (``kind: "cartesian"`` is the default)."""

    kind: Literal["cartesian"] = "cartesian"
    r: Matrix = Field(description=R_DESCRIPTION)

    @model_validator(mode="after")
    def _r_is_covariance(self) -> Self:
        try:
            check_covariance(self.r, name="r", noise=True)
        except ValueError as error:
            raise_issues("CartesianMeasurement", [FieldIssue(("r",), str(error), self.r)])
        return self


SIGMA_RANGE_BOUNDS_M = (1e-3, 1e5)
"""A polar sensor's ``sigma_range`` (m), bounds included: a millimetre to 100 km. No radar
measures range outside them, and inside them the converted covariances are well conditioned;
the unlikely part of the range is warned about (``app.plausibility``)."""
SIGMA_ANGLE_BOUNDS_DEG = (1e-4, 180.0)
"""``sigma_azimuth_deg`` and ``sigma_elevation_deg`` (°), bounds included: above 180° (π) a
detection's angle would be spread over more than the whole circle."""
SIGMA_RANGE_RATE_BOUNDS_MPS = (1e-3, 1e4)
"""``sigma_range_rate`` (m/s), bounds included: a millimetre per second to 10 km/s."""


def _bounded(bounds: tuple[float, float]) -> object:
    return Field(allow_inf_nan=False, ge=bounds[0], le=bounds[1])


SigmaRange = Annotated[float, _bounded(SIGMA_RANGE_BOUNDS_M)]
SigmaAngle = Annotated[float, _bounded(SIGMA_ANGLE_BOUNDS_DEG)]
SigmaRangeRate = Annotated[float, _bounded(SIGMA_RANGE_RATE_BOUNDS_MPS)]


class PolarMeasurement(WireModel):
    """A radar's range and azimuth (and elevation, in 3-D) standard deviations.

    Its detections are ``{"range", "azimuth_deg", "elevation_deg"?, "range_rate"?}`` at the
    sensor's ``site``, azimuth clockwise from north. They are tracked as converted Cartesian
    measurements with each detection's own covariance (:mod:`core.models.measurement`). With
    ``sigma_range_rate`` a detection's ``range_rate`` updates its track's velocity after the
    position (a sequential extended Kalman update, :mod:`core.tracking.range_rate`); without
    it a ``range_rate`` is accepted and not used.
    """

    kind: Literal["polar"]
    sigma_range: SigmaRange = Field(description="range standard deviation (m), 0.001 to 100 000")
    sigma_azimuth_deg: SigmaAngle = Field(
        description="azimuth standard deviation (deg), 0.0001 to 180"
    )
    sigma_elevation_deg: SigmaAngle | None = Field(
        default=None,
        description="elevation standard deviation (deg), 0.0001 to 180; required in 3-D",
    )
    sigma_range_rate: SigmaRangeRate | None = Field(
        default=None,
        description=(
            "range-rate standard deviation (m/s), 0.001 to 10 000; with it, the detections' "
            "range_rate updates the tracks' velocities (without it, range_rate is not used)"
        ),
    )

    @property
    def polar_sigmas(self) -> tuple[float, float]:
        """``(σ_range m, σ_azimuth deg)``."""
        return self.sigma_range, self.sigma_azimuth_deg


def _measurement_kind(value: object) -> str | None:
    """A measurement model's tag: its ``kind``, ``cartesian`` when it gives none."""
    if isinstance(value, dict):
        kind = value.get("kind", "cartesian")
        return kind if isinstance(kind, str) else None
    return getattr(value, "kind", None)


MeasurementModel = Annotated[
    Annotated[CartesianMeasurement, Tag("cartesian")] | Annotated[PolarMeasurement, Tag("polar")],
    Discriminator(
        _measurement_kind,
        custom_error_type="measurement_kind",
        custom_error_message="kind is 'cartesian' (the default) or 'polar'",
    ),
]
"""A detecting sensor's measurement model, tagged by ``kind`` (default ``cartesian``)."""


Latitude = Annotated[float, Field(allow_inf_nan=False, ge=-90.0, le=90.0)]
Longitude = Annotated[float, Field(allow_inf_nan=False, ge=-180.0, le=180.0)]


class GeodeticPoint(WireModel):
    """A WGS84 point: latitude and longitude (degrees), height above the ellipsoid (m)."""

    lat: Latitude
    lon: Longitude
    alt: FiniteFloat = 0.0


class SensorSite(WireModel):
    """Where a sensor stands: ``position`` in the session frame, or ``lat``/``lon``/``alt``.

    ``heading_deg`` is its reference direction, clockwise from north: a
    track list in ``"frame": "sensor"`` has its y axis along it.
    """

    position: Annotated[list[FiniteFloat], Field(min_length=2, max_length=3)] | None = None
    lat: Latitude | None = None
    lon: Longitude | None = None
    alt: FiniteFloat | None = None
    heading_deg: FiniteFloat = 0.0

    @model_validator(mode="after")
    def _one_form(self) -> Self:
        geodetic = (self.lat, self.lon, self.alt)
        if self.position is not None and any(value is not None for value in geodetic):
            raise_issues(
                "SensorSite",
                [FieldIssue(("position",), "give position or lat/lon/alt, not both", None)],
            )
        if self.position is None:
            issues = [
                FieldIssue((name,), f"{name} is required without position", None)
                for name, value in (("lat", self.lat), ("lon", self.lon))
                if value is None
            ]
            if issues:
                raise_issues("SensorSite", issues)
        return self

    @property
    def geodetic(self) -> bool:
        """Whether the site is given as lat/lon/alt (then the session needs an origin)."""
        return self.position is None


Elevation = Annotated[float, Field(allow_inf_nan=False, ge=-90.0, le=90.0)]


MAX_COVERAGE_RANGE = 1e8
"""The largest instrumented range accepted (m): beyond any radar's, and squares stay finite."""
MAX_ANTENNA_HEIGHT = 1e5
"""The largest antenna height accepted (m): above any airborne radar's; the horizon stays finite."""


class RadarCoverage(WireModel):
    """A 3-D radar's coverage volume, read off its data sheet (docs/algorithms.md §8.11).

    Where the radar could see a target: within its instrumented range, between its
    elevation limits and, with ``antenna_height``, above its radar horizon over a 4/3
    Earth, ``√(2kRh_a) + √(2kRh_t)`` of ground range (k = 4/3, R = 6371 km; h_a the
    antenna's and h_t the target's height above the horizon's surface). Its silence
    about a track counts as a miss only there; a track no sensor could see is kept as
    a phantom ([HZ] §5.1: not deleted for the misses nobody could have made, expired
    after ``phantom_max_distance / phantom_min_speed``) and ends when it leaves every
    radar's instrumented range. Every field is optional: a limit left out is no limit.
    """

    range_max: PositiveFloat | None = Field(
        default=None,
        le=MAX_COVERAGE_RANGE,
        description="instrumented range: the largest slant range seen (m, at most 10⁸)",
    )
    elevation_min_deg: Elevation = Field(
        default=-90.0, description="lowest elevation seen, above the site's horizontal (deg)"
    )
    elevation_max_deg: Elevation = Field(default=90.0, description="highest elevation seen (deg)")
    antenna_height: NonNegativeFloat | None = Field(
        default=None,
        le=MAX_ANTENNA_HEIGHT,
        description=(
            "the antenna's height (m, at most 10⁵) above the surface its radar horizon lies on (ground "
            "or sea level; at a geodetic site its alt less the surface's): with it, a "
            "target below the 4/3-Earth radar horizon is not seen (default null: no horizon)"
        ),
    )

    @model_validator(mode="after")
    def _elevations_ordered(self) -> Self:
        if self.elevation_min_deg >= self.elevation_max_deg:
            raise_issues(
                "RadarCoverage",
                [
                    FieldIssue(
                        ("elevation_min_deg",),
                        f"elevation_min_deg ({self.elevation_min_deg:g}) must be below "
                        f"elevation_max_deg ({self.elevation_max_deg:g})",
                        self.elevation_min_deg,
                    )
                ],
            )
        return self


class SensorConfig(WireModel):
    """One sensor: identity, reliability (class-evidence discounting), P_D, field of view, noise."""

    id: Identifier
    reliability: UnitFloat = 1.0
    p_detect: OpenUnitFloat = 0.9
    fov: FieldOfView | None = None
    measurement: MeasurementModel | None = None
    site: SensorSite | None = Field(
        default=None,
        description="where the sensor stands (default: the session frame's origin, heading 0)",
    )
    coverage: RadarCoverage | None = Field(
        default=None,
        description=(
            "a 3-D polar sensor's coverage volume from its data sheet (instrumented range, "
            "elevation limits, antenna height for the radar horizon); default null: it "
            "could see everywhere its fov allows"
        ),
    )
    clutter_density: PositiveFloat | None = Field(
        default=None,
        description=(
            "false detections per unit of position space (m² in 2-D, m³ in 3-D) per scan: "
            "β_FT of this sensor's track score and gate-emptiness termination (default "
            "null: estimated from the sensor's own detections, docs/algorithms.md §8.4; "
            "paper profile: one per km² or km³)"
        ),
    )
    local_tracker: bool = Field(
        default=False,
        description=(
            "true: a detecting sensor tracked on its own (its local tracker, then credal "
            "track-to-track fusion of its confirmed tracks); false (default): with two or "
            "more detecting sensors not flagged, the session tracks all their detections "
            "together in one central tracker, in time order, a report up to 5 s late put "
            "in its place (docs/algorithms.md §8.9); a session's only detecting sensor has "
            "its own tracker either way"
        ),
    )


class AssociationConfig(WireModel):
    """Track-to-track association: a method and its options (defaults filled in)."""

    method: AssociationMethod = "denoeux"
    options: AssociationOptions = Field(default_factory=AssociationOptions)

    @model_validator(mode="after")
    def _options_apply(self) -> Self:
        self.options = resolve_options(self.method, self.options, local=False)
        return self


class LocalAssociationConfig(WireModel):
    """Measurement-to-track association of local tracking (detections)."""

    method: LocalAssociationMethod = "gnn"
    options: AssociationOptions = Field(default_factory=AssociationOptions)

    @model_validator(mode="after")
    def _options_apply(self) -> Self:
        self.options = resolve_options(self.method, self.options, local=True)
        return self


class StateFusionConfig(WireModel):
    """How the latest estimates of the sensors reporting one fused track are combined."""

    state: StateFusionMethod = "covariance_intersection"


class TrackThresholds(WireModel):
    """Track life cycle of both layers (docs/algorithms.md §4, §7.3, §8): score thresholds and
    termination.

    The wire face of ``core.lifecycle.LifeCycleConfig``: same names, defaults
    and ranges (a test pins them together). ``tracking.profile: "paper"`` puts
    the unset ones at the papers' values (``min_points`` null, ``score_ceiling``
    the confirm threshold).
    """

    false_confirmation: OpenUnitFloat = Field(
        default=1e-3, description="α: probability that a false track is confirmed"
    )
    true_deletion: OpenUnitFloat = Field(
        default=1e-3,
        description=(
            "β: probability that a true track is deleted (per run of misses: with the default "
            "score_ceiling, per scan)"
        ),
    )
    termination_probability: Annotated[float, Field(allow_inf_nan=False, ge=0.0, lt=1.0)] = Field(
        default=0.5,
        description=(
            "gate-emptiness termination ([HZ] §4.2): a coasting track that has missed three "
            "scans in a row ends when the probability of its gate being empty falls below "
            "this; 0 turns it off"
        ),
    )
    min_points: Annotated[int, Field(ge=1, le=100)] | None = Field(
        default=2,
        description=(
            "confirm a tentative track after this many hits while its score is ≥ 0 "
            "(P(target) ≥ ½); null: by the score's confirm threshold only"
        ),
    )
    score_ceiling: FiniteFloat | None = Field(
        default=0.0,
        description=(
            "an established track's score is clamped at this value, so a run of misses "
            "deletes it: 0 (default) restarts the test at confirmation (3 misses at P_D 0.9); "
            "the confirm threshold ln((1−β)/α) keeps it 6; null: the raw SPRT"
        ),
    )

    @model_validator(mode="after")
    def _ceiling_above_delete(self) -> Self:
        if self.score_ceiling is None:
            return self
        delete = math.log(self.true_deletion / (1.0 - self.false_confirmation))
        if self.score_ceiling <= delete:
            message = (
                f"score_ceiling must be above the delete threshold ln(β/(1−α)) = {delete:.4g}: "
                "a track would be deleted at its confirmation"
            )
            raise_issues(
                "TrackThresholds", [FieldIssue(("score_ceiling",), message, self.score_ceiling)]
            )
        return self


class TwoPointInitiation(WireModel):
    """A leftover detection joined by one of the next scan within ``max_speed · Δt`` starts a track
    (the papers' initiation: ``tracking.profile: "paper"``)."""

    kind: Literal["two_point"]
    max_speed: PositiveFloat = Field(
        default=1000.0, description="largest target speed (m/s): the pairing gate"
    )
    velocity_std: PositiveFloat = Field(
        default=300.0,
        description="standard deviation of a new target's velocity per axis (m/s): the pair's score",
    )


class SinglePointInitiation(WireModel):
    """Every leftover detection starts a track; its second detections branch and its third
    tests them (docs/algorithms.md §8.3)."""

    kind: Literal["single_point"] = "single_point"
    velocity_std: PositiveFloat | None = Field(
        default=None,
        description=(
            "the velocity prior: standard deviation of a new target's velocity per axis (m/s); "
            "null (default): no velocity knowledge — targets from 1 to 300 m/s are confirmed, "
            "at most a scan or two later than with their true prior"
        ),
    )


def _initiation_kind(value: object) -> str:
    """The initiation's ``kind``; left out, ``single_point`` (the default)."""
    if isinstance(value, dict):
        return str(value.get("kind", "single_point"))
    return str(getattr(value, "kind", "single_point"))


Initiation = Annotated[
    Annotated[TwoPointInitiation, Tag("two_point")]
    | Annotated[SinglePointInitiation, Tag("single_point")],
    Discriminator(_initiation_kind),
]
TrackingProfile = Literal["default", "paper"]
"""``default``: for real sensors (docs/algorithms.md §8); ``paper``: the papers' experiments
(two-point starts, score-only confirmation, ceiling at the confirm threshold, one false
alarm and one birth per km^q when not given, [HZ]'s gate emptiness from the first miss)."""


class TrackingConfig(WireModel):
    """Local tracking of detecting sensors and track management.

    Sensors with a ``measurement`` model send detections, at any increasing
    times; the session tracks them with an IMM over the preset's model bank
    (or one constant-velocity model of the session's ``motion.q`` without a
    preset) in 1 to 3 dimensions (the detections' ``z`` lists the state's
    position components in order; in 3-D the presets add a vertical
    constant-velocity axis). ``time_interval`` is the nominal scan period: the
    presets' models are the papers' at that step, and their mode transitions
    are per ``time_interval``.
    """

    profile: TrackingProfile = Field(
        default="default",
        description=(
            "default: rules for real sensors, from the physics given (docs/algorithms.md §8); "
            "paper: the papers' experiments (two-point starts, score-only confirmation, "
            "densities one per km² or km³ when not given); the resolved config shows the "
            "values the profile filled in"
        ),
    )
    preset: TrackingPreset | None = None
    time_interval: PositiveFloat = Field(
        default=1.0, description="the nominal scan period ΔT (s); scans may come at any times"
    )
    association: LocalAssociationConfig = Field(default_factory=LocalAssociationConfig)
    thresholds: TrackThresholds = Field(default_factory=TrackThresholds)
    birth_density: PositiveFloat | None = Field(
        default=None,
        description=(
            "new targets per unit of position space (m² in 2-D, m³ in 3-D) per scan: β_NT of "
            "the track score and of gate-emptiness termination (default null: for a sensor "
            "with a `coverage`, one new target a minute in its coverage volume, at most its "
            "clutter density; for the others equal to each sensor's clutter density, prior "
            "odds 1; paper profile: one per km² or km³; docs/algorithms.md §8.12)"
        ),
    )
    initiation: Initiation = Field(default_factory=SinglePointInitiation)
    class_behaviours: (
        Annotated[
            dict[Label, Annotated[list[Label], Field(max_length=10)]], Field(max_length=MAX_CLASSES)
        ]
        | None
    ) = Field(
        default=None,
        description=(
            "the session's own classes with detecting sensors: each class of `classes` and the "
            "preset's behaviours it allows (aircraft: b1 no manoeuvre, b2 up to 2g, b3 up to "
            "4g; pedestrian: static, walking, running); a track showing a behaviour is then "
            "any of the classes that allow it. null (the default): the preset's own classes "
            "(aircraft: liner [b1], bomber [b1, b2], fighter [b1, b2, b3]; pedestrian: "
            "rambler [static, walking], sportsman [walking, running])"
        ),
    )

    @model_validator(mode="after")
    def _profile_fills(self) -> Self:
        """The paper profile's values where the client left a field out."""
        if self.profile != "paper":
            return self
        if "initiation" not in self.model_fields_set:
            self.initiation = TwoPointInitiation(kind="two_point")
        chosen = self.thresholds
        given = chosen.model_fields_set
        paper: dict[str, object] = {}
        if "min_points" not in given:
            paper["min_points"] = None
        if "score_ceiling" not in given:
            paper["score_ceiling"] = math.log(
                (1.0 - chosen.true_deletion) / chosen.false_confirmation
            )
        if paper:
            self.thresholds = TrackThresholds.model_validate(
                {**chosen.model_dump(include=given), **paper}
            )
        return self


class TimeConfig(WireModel):
    """The session clock."""

    unit: Literal["s"] = "s"


class SessionConfig(WireModel):
    """A fusion session's configuration."""

    name: Annotated[str, StringConstraints(min_length=1, max_length=100)] | None = None
    state: StateLayout
    motion: MotionModel = Field(default_factory=MotionModel)
    classes: Annotated[
        list[Label], Field(max_length=MAX_CLASSES), bounded("max_classes", "classes")
    ] = Field(default_factory=list)
    sensors: Annotated[
        list[SensorConfig], Field(max_length=MAX_SENSORS), bounded("max_sensors", "sensors")
    ] = Field(default_factory=list)
    region: PolygonFieldOfView | None = Field(
        default=None,
        description=(
            "the surveillance region: a track that leaves every field of view inside it "
            "becomes a phantom, outside it it is terminated (default: the union of the "
            "sensors' ranges)"
        ),
    )
    association: AssociationConfig = Field(default_factory=AssociationConfig)
    fusion: StateFusionConfig = Field(default_factory=StateFusionConfig)
    tracking: TrackingConfig = Field(default_factory=TrackingConfig)
    time: TimeConfig = Field(default_factory=TimeConfig)
    origin: GeodeticPoint | None = Field(
        default=None,
        description=(
            "WGS84 origin: the session frame is then the East-North-Up plane there (x east, "
            "y north, z up, metres); without it nothing geodetic is accepted"
        ),
    )

    @model_validator(mode="after")
    def _consistent(self) -> Self:
        issues: list[FieldIssue] = []
        for index, label in enumerate(self.classes):
            if label in self.classes[:index]:
                issues.append(
                    FieldIssue(("classes", index), f"class {label!r} is listed twice", label)
                )
        sensor_ids: set[str] = set()
        measured = len(self.state.position)
        for index, sensor in enumerate(self.sensors):
            if sensor.id in sensor_ids:
                issues.append(
                    FieldIssue(
                        ("sensors", index, "id"),
                        f"sensor id {sensor.id!r} is used twice",
                        sensor.id,
                    )
                )
            sensor_ids.add(sensor.id)
            issues.extend(self._placement_issues(index, sensor))
            if (
                isinstance(sensor.measurement, CartesianMeasurement)
                and len(sensor.measurement.r) != measured
            ):
                size = len(sensor.measurement.r)
                issues.append(
                    FieldIssue(
                        ("sensors", index, "measurement", "r"),
                        f"r must be a list of {measured} rows of {measured} to match the session's "
                        f"{measured} position components; got {size} rows of {size}",
                        sensor.measurement.r,
                    )
                )
        issues.extend(self._class_behaviour_issues())
        if self.region is not None and self.region.frame != "session":
            issues.append(
                FieldIssue(
                    ("region", "frame"),
                    "the surveillance region is in the session frame",
                    self.region.frame,
                )
            )
        issues.extend(self._motion_issues())
        if issues:
            raise_issues("SessionConfig", issues)
        return self

    def _motion_issues(self) -> list[FieldIssue]:
        """The state carries the components the motion model moves; the local trackers of
        detecting sensors have positions and velocities only."""
        model = self.motion.model
        issues = [
            FieldIssue(
                ("state", kind),
                f"the {model} motion model needs the {kind} components",
                getattr(self.state, kind),
            )
            for kind in TRANSITION_MODELS[model]().components
            if not getattr(self.state, kind)
        ]
        detecting = [
            index for index, sensor in enumerate(self.sensors) if sensor.measurement is not None
        ]
        if "acceleration" in TRANSITION_MODELS[model]().components and detecting:
            issues.append(
                FieldIssue(
                    ("sensors", detecting[0], "measurement"),
                    f"sensors that send detections are tracked with positions and velocities "
                    f"only; the {model} motion model is for sessions of track lists",
                    None,
                )
            )
        return issues

    def _class_behaviour_issues(self) -> list[FieldIssue]:
        """``tracking.class_behaviours`` names exactly the session's classes, with a preset."""
        allowed = self.tracking.class_behaviours
        if allowed is None:
            return []
        where = ("tracking", "class_behaviours")
        if self.tracking.preset is None:
            return [FieldIssue(where, "class_behaviours needs a tracking preset", None)]
        if set(allowed) != set(self.classes):
            return [
                FieldIssue(
                    where,
                    f"class_behaviours must name exactly the session's classes {self.classes}, "
                    f"got {list(allowed)}",
                    list(allowed),
                )
            ]
        return []

    def _placement_issues(self, index: int, sensor: SensorConfig) -> list[FieldIssue]:
        """A geodetic site needs the origin; a polar sensor in 3-D its elevation σ."""
        issues: list[FieldIssue] = []
        site = sensor.site
        if site is not None and site.geodetic and self.origin is None:
            issues.append(
                FieldIssue(
                    ("sensors", index, "site"),
                    "a geodetic site needs the session's 'origin'",
                    None,
                )
            )
        measured = len(self.state.position)
        if site is not None and site.position is not None and len(site.position) < measured:
            issues.append(
                FieldIssue(
                    ("sensors", index, "site", "position"),
                    f"the site has {len(site.position)} coordinates, the session {measured}",
                    site.position,
                )
            )
        polar = sensor.measurement
        if sensor.coverage is not None and (
            not isinstance(polar, PolarMeasurement) or measured != 3
        ):
            issues.append(
                FieldIssue(
                    ("sensors", index, "coverage"),
                    "a coverage volume is a 3-D polar sensor's (measurement kind 'polar' in a "
                    "session of 3 position components); give a planar sensor its fov",
                    None,
                )
            )
        if isinstance(polar, PolarMeasurement):
            if measured == 1:
                issues.append(
                    FieldIssue(
                        ("sensors", index, "measurement", "kind"),
                        "polar measurements need 2 or 3 position components",
                        "polar",
                    )
                )
            elif measured == 3 and polar.sigma_elevation_deg is None:
                issues.append(
                    FieldIssue(
                        ("sensors", index, "measurement", "sigma_elevation_deg"),
                        "a polar sensor of a 3-D session needs sigma_elevation_deg",
                        None,
                    )
                )
        return issues

    def sensor(self, sensor_id: str) -> SensorConfig | None:
        """The configured sensor with this id, if any."""
        return next((sensor for sensor in self.sensors if sensor.id == sensor_id), None)
