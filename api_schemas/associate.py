"""Stateless association: ``POST /v1/associate``."""

from __future__ import annotations

from typing import Annotated, Self

from pydantic import Field, model_validator

from api_schemas.association import AssociationMethod, AssociationOptions, resolve_options
from api_schemas.base import MAX_CLASSES, FiniteFloat, Identifier, Label, WireModel
from api_schemas.issues import FieldIssue, raise_issues
from api_schemas.limits import MAX_ITEMS, bounded
from api_schemas.linalg import covariance_problems
from api_schemas.reports import SensorTrack
from api_schemas.results import ScoreMatrix

DiagnosticValue = FiniteFloat | int | str | bool | None


class AssociateRequest(WireModel):
    """Two track lists (``known`` rows, ``incoming`` columns) and a method with its options.

    Class evidence on the tracks needs ``classes``, the frame its labels belong to.
    """

    method: AssociationMethod = "denoeux"
    options: AssociationOptions = Field(default_factory=AssociationOptions)
    classes: Annotated[list[Label], Field(max_length=MAX_CLASSES)] = Field(default_factory=list)
    known: Annotated[
        list[SensorTrack],
        Field(max_length=MAX_ITEMS),
        bounded("max_tracks_per_input", "known tracks"),
    ]
    incoming: Annotated[
        list[SensorTrack],
        Field(max_length=MAX_ITEMS),
        bounded("max_tracks_per_input", "incoming tracks"),
    ]

    @model_validator(mode="after")
    def _consistent(self) -> Self:
        """Per side: covariances symmetric positive definite (one batch), distinct ids; one dim; known classes."""
        self.options = resolve_options(self.method, self.options, local=False)
        issues: list[FieldIssue] = []
        frame = set(self.classes)
        dim: int | None = None
        for side in ("known", "incoming"):
            tracks: list[SensorTrack] = getattr(self, side)
            bad_covariances = covariance_problems([track.covariance for track in tracks])
            seen: set[str] = set()
            for index, track in enumerate(tracks):
                if index in bad_covariances:
                    issues.append(
                        FieldIssue(
                            (side, index, "covariance"), bad_covariances[index], track.covariance
                        )
                    )
                if track.id in seen:
                    issues.append(
                        FieldIssue(
                            (side, index, "id"), f"track id {track.id!r} appears twice", track.id
                        )
                    )
                seen.add(track.id)
                if dim is None:
                    dim = len(track.state)
                elif len(track.state) != dim:
                    issues.append(
                        FieldIssue(
                            (side, index, "state"),
                            f"state has {len(track.state)} components, the first track has {dim}",
                            track.state,
                        )
                    )
                if track.classification is not None:
                    unknown = sorted(track.classification.labels() - frame)
                    if unknown:
                        issues.append(
                            FieldIssue(
                                (side, index, "classification"),
                                f"unknown classes {unknown} (frame 'classes': {self.classes})",
                                unknown,
                            )
                        )
        if issues:
            raise_issues("AssociateRequest", issues)
        return self


class AssociatedPair(WireModel):
    """``known`` and ``incoming`` are the same object, with the method's score."""

    known: Identifier
    incoming: Identifier
    score: FiniteFloat | None


class AssociateResponse(WireModel):
    """The assignment, the unpaired items on both sides, the score matrix and diagnostics."""

    pairs: list[AssociatedPair]
    new: list[Identifier]
    missed: list[Identifier]
    matrix: ScoreMatrix
    diagnostics: dict[str, DiagnosticValue]
