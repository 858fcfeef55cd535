"""The fused result of one input (ALGORITHMS.md §6 "Fused output")."""

from __future__ import annotations

from typing import Literal

from api_schemas.association import AssociationMethod
from api_schemas.base import FiniteFloat, Identifier, Label, Matrix, UnitFloat, Vector, WireModel
from api_schemas.classification import FocalMass

TrackStatus = Literal["tentative", "confirmed", "coasting", "phantom", "terminated"]


class TrackSource(WireModel):
    """A sensor estimate contributing to a fused track: sensor, its local track id, its time."""

    sensor: Identifier
    track: Identifier
    time: FiniteFloat


class FusedClassification(WireModel):
    """The fused class belief of a track.

    ``mass`` is normalised (Dempster's rule); ``conflict`` is the mass that
    normalisation removed. ``pignistic`` is ``null`` (and ``decision`` too)
    when the conflict is total.
    """

    mass: list[FocalMass]
    pignistic: dict[Label, UnitFloat] | None
    belief: dict[Label, UnitFloat]
    plausibility: dict[Label, UnitFloat]
    conflict: UnitFloat
    decision: Label | None


class FusedTrack(WireModel):
    """One fused track: stable id, status, estimate, sources, class belief, score, reason."""

    id: Identifier
    status: TrackStatus
    state: Vector
    covariance: Matrix
    sources: list[TrackSource]
    classification: FusedClassification | None
    score: FiniteFloat | None
    reason: str | None


class FusedPair(WireModel):
    """An association decision of a step: fused track ``fused`` takes report item ``track``."""

    fused: Identifier
    track: Identifier
    score: FiniteFloat | None


class ScoreMatrix(WireModel):
    """A method's score matrix: ``values[i][j]`` scores row ``rows[i]`` against column ``cols[j]``.

    ``null`` marks a forbidden cell (e.g. the ``*`` rows of [T2T] Table 1).
    """

    rows: list[str]
    cols: list[str]
    values: list[list[FiniteFloat | None]]


class StepAssociation(WireModel):
    """The association decision of one step; ``matrix`` only with ``?explain=true``."""

    method: AssociationMethod | Literal["cheap_jpda"]
    pairs: list[FusedPair]
    new: list[Identifier]
    missed: list[Identifier]
    matrix: ScoreMatrix | None


class StepResult(WireModel):
    """The fused result of one accepted input."""

    seq: int
    time: FiniteFloat
    sensor: Identifier
    tracks: list[FusedTrack]
    association: StepAssociation


class TrackHistoryPoint(WireModel):
    """A past estimate of a fused track."""

    seq: int
    time: FiniteFloat
    status: TrackStatus
    state: Vector
    covariance: Matrix


class FusedTrackDetail(WireModel):
    """``GET …/tracks/{tid}``: one fused track with its recent history (oldest first)."""

    track: FusedTrack
    history: list[TrackHistoryPoint]


class FusedPicture(WireModel):
    """``GET …/tracks``: the current fused tracks, optionally predicted to ``time``."""

    seq: int
    time: FiniteFloat | None
    tracks: list[FusedTrack]


__all__ = [
    "FusedClassification",
    "FusedPair",
    "FusedPicture",
    "FusedTrack",
    "FusedTrackDetail",
    "ScoreMatrix",
    "StepAssociation",
    "StepResult",
    "TrackHistoryPoint",
    "TrackSource",
    "TrackStatus",
]
