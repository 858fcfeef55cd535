"""The ``json`` output format: results, pictures and tracks in the contract's shape.

:mod:`api_schemas.results` documents it (``StepResult``, ``FusedPicture``,
``FusedTrack``) and ``tests/api/test_result_writer.py`` validates the
writers' output against those models: :func:`step_json` for a step result
(the per-input hot path), :func:`picture_json` for fused tracks, both written
by orjson in C from the step's columns (:class:`~core.fusion.reports.FusedTracks`: all
states and all covariances turned into floats in one call each, ``Source`` dataclasses
as they are); every non-finite score of a matrix is
``null``, any other non-finite number refused. ``frame=geodetic`` adds each
track's ``geodetic`` position.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence

import numpy as np
import orjson

from api_schemas.results import FusedPicture
from api_schemas.results import StepResult as StepResultModel
from api_schemas.warnings import FieldWarning
from app.geo.geojson import GeodeticOutput, with_geodetic
from app.outputs.base import OutputFormat, PlainObject
from app.outputs.text import itemwise
from core.fusion.classes import ClassAssessment
from core.fusion.reports import AssociationView, FusedTracks, FusedTrackView, StepResult

ONE_CALL_TRACKS = 200
"""A step result of at most this many tracks (~100 KB) is written in one orjson call: one C
call of that size holds the GIL ~0.1 ms; larger ones are written an item at a time."""


class JsonFormat(OutputFormat):
    """``application/json``: the contract's result and picture."""

    name = "json"
    media_type = "application/json"
    step_model = StepResultModel
    picture_model = FusedPicture
    needs_geodetic = False
    description = "the contract's JSON (frame=geodetic adds each track's geodetic position)"

    def step(
        self,
        step: StepResult,
        seq: int,
        geodetic: GeodeticOutput | None,
        warnings: Sequence[FieldWarning] = (),
    ) -> str:
        return step_json(step, seq, geodetic, warnings)

    def picture(
        self,
        seq: int,
        time: float | None,
        views: Sequence[FusedTrackView],
        geodetic: GeodeticOutput | None,
    ) -> str:
        return picture_json(seq, time, views, geodetic)

    def from_plain(self, result: PlainObject, geodetic: GeodeticOutput | None) -> str:
        if geodetic is not None:
            result = {**result, "tracks": with_geodetic(result["tracks"], geodetic)}
        return itemwise(result)


def finite_or_none(value: float | None) -> float | None:
    """``value`` if it is a finite number, else ``None``."""
    return value if value is not None and math.isfinite(value) else None


def check_finite(views: Sequence[FusedTrackView]) -> None:
    """Raise ``ValueError`` naming the first track with a non-finite state or covariance.

    One test over every track's columns (:class:`~core.fusion.reports.FusedTracks`); the
    culprit is looked for only then.
    """
    tracks = FusedTracks.of(views)
    if np.isfinite(tracks.states).all() and np.isfinite(tracks.covariances).all():
        return
    for index, track_id in enumerate(tracks.ids):
        for what, values in (("state", tracks.states), ("covariance", tracks.covariances)):
            if not np.isfinite(values[index]).all():
                raise ValueError(f"fused track {track_id!r}: non-finite {what}")


def _class_fast(assessment: ClassAssessment | None) -> PlainObject | None:
    """A track's classification in the contract's shape; a non-finite conflict raises.

    Under total conflict every distribution is ``None`` (only the state and the
    conflict are known).
    """
    if assessment is None:
        return None
    conflict = float(assessment.conflict)
    if not math.isfinite(conflict):
        raise ValueError("non-finite class conflict")
    mass = assessment.mass
    if mass is None:
        return {
            "state": assessment.state.value,
            "mass": None,
            "pignistic": None,
            "belief": None,
            "plausibility": None,
            "conflict": assessment.conflict,
            "decision": None,
            "decision_state": assessment.decision_state.value,
            "summarized": assessment.summarized,
        }
    labels = mass.frame.labels
    return {
        "state": assessment.state.value,
        "mass": [{"set": list(subset), "mass": value} for subset, value in mass.focal_sets()],
        "pignistic": dict(zip(labels, assessment.pignistic.tolist(), strict=True)),
        "belief": dict(zip(labels, assessment.belief.tolist(), strict=True)),
        "plausibility": dict(zip(labels, assessment.plausibility.tolist(), strict=True)),
        "conflict": assessment.conflict,
        "decision": assessment.decision,
        "decision_state": assessment.decision_state.value,
        "summarized": assessment.summarized,
    }


def _association_plain(association: AssociationView) -> PlainObject:
    matrix = association.matrix
    return {
        "method": association.method,
        "pairs": [
            {"fused": fused, "track": track, "score": finite_or_none(score), "basis": basis}
            for fused, track, score, basis in association.pairs
        ],
        "new": list(association.new),
        "missed": list(association.missed),
        "matrix": None
        if matrix is None
        else {
            "rows": list(matrix[0]),
            "cols": list(matrix[1]),
            "values": [[finite_or_none(value) for value in row] for row in matrix[2].tolist()],
        },
    }


def step_json(
    step: StepResult,
    seq: int,
    geodetic: GeodeticOutput | None = None,
    warnings: Sequence[FieldWarning] = (),
) -> str:
    """A step result in the contract's shape (``StepResult``), numbered ``seq`` (the
    session's input number), as compact JSON text (hot path); ``geodetic``: with each
    track's ``geodetic`` position (``?frame=geodetic``); ``warnings``: its input's.

    Refuses (``ValueError``) a non-finite time, state, covariance or score instead
    of writing ``null``; a pair's or a matrix cell's non-finite score is ``null``.
    """
    if not math.isfinite(step.time):
        raise ValueError("non-finite step time")
    tracks = track_items(step.tracks, geodetic)
    small = len(step.tracks) <= ONE_CALL_TRACKS
    document = {
        "seq": seq,
        "time": step.time,
        "sensor": step.sensor,
        "tracks": list(tracks) if small else tracks,
        "association": _association_plain(step.association),
        "warnings": [entry.model_dump() for entry in warnings],
    }
    if small:  # the same text (itemwise is byte for byte), in one C call
        return wire_json(document)
    return itemwise(document, wire_json)  # no single C call for a 10 MB answer


def picture_json(
    seq: int,
    time: float | None,
    views: Sequence[FusedTrackView],
    geodetic: GeodeticOutput | None = None,
) -> str:
    """The live fused tracks at ``time`` (a ``FusedPicture``) as compact JSON text."""
    document = {"seq": seq, "time": time, "tracks": track_items(views, geodetic)}
    return itemwise(document, wire_json)


def track_items(
    views: Sequence[FusedTrackView], geodetic: GeodeticOutput | None = None
) -> Iterator[PlainObject]:
    """Fused tracks in the contract's shape (``FusedTrack``), for :func:`wire_json`, made one
    at a time as they are written (:func:`~app.outputs.text.itemwise`) from the step's columns
    (:class:`~core.fusion.reports.FusedTracks`: every state and covariance turned into floats
    in one call each; sources ``Source`` dataclasses, which orjson writes in C). Refuses
    (``ValueError``, before the first) a non-finite state, covariance or score."""
    tracks = FusedTracks.of(views)
    check_finite(tracks)
    for track_id, score in zip(tracks.ids, tracks.scores, strict=True):
        if not math.isfinite(score):
            raise ValueError(f"fused track {track_id!r}: non-finite score")
    columns = zip(
        tracks.ids,
        tracks.statuses,
        tracks.states.tolist(),
        tracks.covariances.tolist(),
        tracks.sources,
        tracks.classifications,
        tracks.scores,
        tracks.reasons,
        strict=True,
    )
    items = (
        {
            "id": track_id,
            "status": status.value,
            "state": state,
            "covariance": covariance,
            "sources": sources,  # frozen dataclasses (sensor, track, time): the wire names
            "classification": None if classification is None else _class_fast(classification),
            "score": score,
            "reason": reason.value,
        }
        for track_id, status, state, covariance, sources, classification, score, reason in columns
    )
    if geodetic is None:
        return items
    points = geodetic.points(list(tracks.states))
    return ({**item, "geodetic": point} for item, point in zip(items, points, strict=True))


def track_fields(views: Sequence[FusedTrackView]) -> list[PlainObject]:
    """:func:`track_items` as a list."""
    return list(track_items(views))


def wire_json(document: object) -> str:
    """Compact JSON text of a document holding :func:`track_fields` output."""
    return orjson.dumps(document, option=orjson.OPT_SERIALIZE_NUMPY).decode()
