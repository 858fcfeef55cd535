"""The fused result of one input (docs/algorithms.md §6 "Fused output")."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from api_schemas.association import AnyAssociationMethod
from api_schemas.base import FiniteFloat, Identifier, Label, Matrix, UnitFloat, Vector, WireModel
from api_schemas.classification import FocalMass
from api_schemas.timing import ANSWER_TIME
from api_schemas.warnings import Warnings

STEP_WARNINGS_DESCRIPTION = (
    "implausible but legal values of this input (README 'Warnings'), pointers into its body: "
    "the step used them as given"
)

TrackStatus = Literal["tentative", "confirmed", "coasting", "phantom", "terminated"]
StatusReason = Literal[
    "initiated",
    "score_confirmed",
    "min_points",
    "second_sensor",
    "local_confirmed",
    "reacquired",
    "missed",
    "blind_zone",
    "occluded",
    "out_of_range",
    "score_deleted",
    "gate_emptiness",
    "phantom_expired",
    "merged_into_phantom",
    "duplicate",
]
"""Why a track's status last changed (``core.lifecycle.StatusReason``; a test pins them equal)."""


class TrackSource(WireModel):
    """A sensor estimate contributing to a fused track: sensor, its local track id, its time."""

    sensor: Identifier
    track: Identifier
    time: FiniteFloat


ClassificationState = Literal["defined", "total_conflict"]
DecisionState = Literal["decided", "tied", "undefined"]


class FusedClassification(WireModel):
    """The fused class belief of a track.

    ``mass`` is normalised (Dempster's rule); ``conflict`` is the mass that
    normalisation removed. ``state`` is ``total_conflict`` when the sensors'
    evidence contradicts itself totally: then ``mass``, ``pignistic``,
    ``belief``, ``plausibility`` and ``decision`` are ``null``.

    ``decision`` is the class of largest BetP, and ``decision_state`` says
    whether there is one: ``decided`` (one class leads by more than 1e-9),
    ``tied`` (two or more classes share the top BetP within 1e-9: ``decision``
    is ``null``, no class is preferred) or ``undefined`` (no BetP: total
    conflict; ``decision`` is ``null``).
    """

    state: ClassificationState
    mass: list[FocalMass] | None
    pignistic: dict[Label, UnitFloat] | None
    belief: dict[Label, UnitFloat] | None
    plausibility: dict[Label, UnitFloat] | None
    conflict: UnitFloat
    decision: Label | None
    decision_state: DecisionState
    summarized: bool = False
    """The fused mass had more focal sets than its bound (32) and was summarized: the
    largest focal sets kept, the rest of the mass on their union (a weakening: Bel
    never grows, Pl never shrinks; ``core.belief.summary``)."""


class GeodeticPosition(WireModel):
    """A fused track's position on WGS84 (degrees, metres above the ellipsoid)."""

    lat: FiniteFloat
    lon: FiniteFloat
    alt: FiniteFloat


class FusedTrack(WireModel):
    """One fused track: stable id, status, estimate, sources, class belief, score, reason.

    ``reason`` says why the status last changed (``initiated``, ``second_sensor``,
    ``score_confirmed``, ``missed``, ``blind_zone``, ``gate_emptiness``, ...):
    for a coasting, phantom or terminated track it is why it is so.
    """

    id: Identifier
    status: TrackStatus
    state: Vector
    covariance: Matrix
    sources: list[TrackSource]
    classification: FusedClassification | None
    score: FiniteFloat | None
    reason: StatusReason | None
    geodetic: GeodeticPosition | None = Field(
        default=None, description="WGS84 position of the track (only with ?frame=geodetic)"
    )


PairBasis = Literal["continuity", "association"]


class FusedPair(WireModel):
    """An association decision of a step: fused track ``fused`` takes report item ``track``.

    ``basis`` is ``continuity`` when the sensor kept reporting the object under
    the track id it gave it (no method score: ``score`` is ``null``), and
    ``association`` when the session's method decided (``score`` is its score).
    """

    fused: Identifier
    track: Identifier
    score: FiniteFloat | None
    basis: PairBasis


class ScoreMatrix(WireModel):
    """A method's score matrix: ``values[i][j]`` scores row ``rows[i]`` against column ``cols[j]``.

    ``rows`` are the known items, then one ``*:<column id>`` row per column: the
    ``*_t`` rows of [T2T] Table 1, whose only allowed cell is their own column
    (the score of declaring that item new: hachour / mercier BetP(*), gnn the
    threshold, denoeux 0). ``null`` marks a cell without a finite score: a pair
    outside the gate, or a forbidden cell of a ``*`` row.
    """

    rows: list[str]
    cols: list[str]
    values: list[list[FiniteFloat | None]]


class StepAssociation(WireModel):
    """The association decision of one step; ``matrix`` only with ``?explain=true``."""

    method: AnyAssociationMethod
    pairs: list[FusedPair]
    new: list[Identifier]
    missed: list[Identifier]
    matrix: ScoreMatrix | None


class StepResult(WireModel):
    """The fused result of one accepted input."""

    seq: int
    time: FiniteFloat = Field(description=ANSWER_TIME)
    sensor: Identifier
    tracks: list[FusedTrack]
    association: StepAssociation
    warnings: Warnings = Field(default_factory=list, description=STEP_WARNINGS_DESCRIPTION)


class TrackHistoryPoint(WireModel):
    """A past fused state of a track (one per step that showed it)."""

    time: FiniteFloat
    state: Vector
    geodetic: GeodeticPosition | None = Field(
        default=None, description="WGS84 position of the state (only with ?frame=geodetic)"
    )


class FusedTrackDetail(WireModel):
    """``GET …/tracks/{tid}``: one fused track with its recent history (oldest first)."""

    track: FusedTrack
    history: list[TrackHistoryPoint]


class FusedPicture(WireModel):
    """``GET …/tracks``: the current fused tracks, optionally predicted to ``time``."""

    seq: int
    time: FiniteFloat | None = Field(description=ANSWER_TIME)
    tracks: list[FusedTrack]


class PointGeometry(WireModel):
    """A GeoJSON Point: ``[lon°, lat°, alt m]`` on WGS84 (RFC 7946 §3.1.2)."""

    type: Literal["Point"]
    coordinates: Annotated[list[FiniteFloat], Field(min_length=2, max_length=3)]


class PositionEllipse(WireModel):
    """A fused track's horizontal position uncertainty: the ``sigma``-σ ellipse (2-σ) of its
    position covariance's east/north block, in the tangent plane at the track's point."""

    sigma: FiniteFloat = Field(description="the ellipse's size in standard deviations (2)")
    semi_major_m: FiniteFloat = Field(description="semi-major axis, metres")
    semi_minor_m: FiniteFloat = Field(description="semi-minor axis, metres")
    orientation_deg: FiniteFloat = Field(
        description="the major axis' direction, degrees clockwise from north, in [0, 180) "
        "(0 for a circle)"
    )


class TrackFeatureProperties(WireModel):
    """What a fused track's GeoJSON feature says besides its point."""

    id: Identifier
    status: TrackStatus
    sources: list[Identifier] = Field(
        description="ids of the sensors whose tracks contribute to it, each once"
    )
    decision: Label | None
    decision_state: DecisionState | None = Field(
        description="decided, tied or undefined (FusedClassification); null: no class evidence"
    )
    pignistic: dict[Label, UnitFloat] | None
    velocity_enu: list[FiniteFloat] = Field(
        description="east/north(/up) velocity (m/s) in the tangent plane at the track's point"
    )
    position_ellipse: PositionEllipse


class TrackFeature(WireModel):
    """A fused track as a GeoJSON Feature."""

    type: Literal["Feature"]
    id: Identifier
    geometry: PointGeometry
    properties: TrackFeatureProperties


class FusedFeatureCollection(WireModel):
    """``format=geojson``: fused tracks as an ``application/geo+json`` FeatureCollection
    (RFC 7946), with the answer's ``seq`` and ``time`` (and the step's ``sensor``) as foreign
    members."""

    type: Literal["FeatureCollection"]
    seq: int | None = None
    time: FiniteFloat | None = None
    sensor: Identifier | None = None
    warnings: Warnings | None = Field(
        default=None, description=f"a step's answer only: {STEP_WARNINGS_DESCRIPTION}"
    )
    features: list[TrackFeature]


__all__ = [
    "ClassificationState",
    "FusedClassification",
    "FusedFeatureCollection",
    "FusedPair",
    "FusedPicture",
    "FusedTrack",
    "FusedTrackDetail",
    "PairBasis",
    "PointGeometry",
    "PositionEllipse",
    "ScoreMatrix",
    "StepAssociation",
    "StepResult",
    "TrackFeature",
    "TrackFeatureProperties",
    "TrackHistoryPoint",
    "TrackSource",
    "TrackStatus",
]
