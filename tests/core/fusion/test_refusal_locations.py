"""Every refusal of the engine says where the refused value is (``InvalidInput.loc``).

The location is a path into the engine's input (a ``TrackReport`` or a
``DetectionReport``): ``("tracks", 1, "id")``, ``("measurements", 0)``. Each
row builds a report that is wrong in exactly one place and expects that
place; the engine must also be left as it was.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest

from core.belief import Frame, MassFunction
from core.errors import CredalError, InvalidInput, Location, StaleReport
from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.engine import SessionEngine
from core.fusion.motion import MotionModel
from core.fusion.reports import DetectionReport, ReportedTrack, TrackReport
from core.tracking.config import LocalTrackerConfig

from .engine_helpers import LAYOUT

CLASSES = Frame(["liner", "bomber", "fighter"])
OTHER_CLASSES = Frame(["car", "truck"])


def engine() -> SessionEngine:
    """Sensor ``s1`` sends track lists, ``radar`` detections; one input of each at t = 1."""
    config = FusionConfig(
        motion=MotionModel(LAYOUT, q=1.0),
        sensors=(
            SensorSpec("s1"),
            SensorSpec("radar", tracker=LocalTrackerConfig(preset="aircraft")),
        ),
        classes=CLASSES,
    )
    session = SessionEngine(config)
    session.apply(TrackReport("s1", 1.0, (good("a"),)))
    session.apply_detections(DetectionReport("radar", 1.0, np.array([[500.0, 500.0]])))
    return session


def good(track_id: str, **evidence: object) -> ReportedTrack:
    return ReportedTrack(track_id, np.array([0.0, 1.0, 0.0, 1.0]), np.eye(4), **evidence)  # type: ignore[arg-type]


def tracks(*listed: ReportedTrack, time: float = 2.0, sensor: str = "s1") -> TrackReport:
    return TrackReport(sensor, time, listed)


def detections(z: list[list[float]], time: float = 2.0, **kwargs: object) -> DetectionReport:
    return DetectionReport(kwargs.pop("sensor", "radar"), time, np.array(z), **kwargs)  # type: ignore[arg-type]


@dataclass(frozen=True)
class Row:
    name: str
    send: Callable[[SessionEngine], object]
    loc: Location
    kind: type[CredalError] = InvalidInput


def apply(report: TrackReport) -> Callable[[SessionEngine], object]:
    return lambda session: session.apply(report)


def apply_detections(report: DetectionReport) -> Callable[[SessionEngine], object]:
    return lambda session: session.apply_detections(report)


ZERO = np.zeros(3)
ROWS = [
    Row("unknown sensor", apply(tracks(good("a"), sensor="s9")), ("sensor",)),
    Row("stale report", apply(tracks(good("a"), time=0.5)), ("time",), StaleReport),
    Row("same time again", apply(tracks(good("a"), time=1.0)), ("time",), StaleReport),
    Row("time not finite", apply(tracks(good("a"), time=float("nan"))), ("time",)),
    Row("time beyond the limit", apply(tracks(good("a"), time=2e12)), ("time",)),
    Row("repeated id", apply(tracks(good("a"), good("b"), good("a"))), ("tracks", 2, "id")),
    Row(
        "short state",
        apply(tracks(good("a"), ReportedTrack("b", np.zeros(3), np.eye(3)))),
        ("tracks", 1, "state"),
    ),
    Row(
        "covariance of the wrong size",
        apply(tracks(ReportedTrack("a", np.zeros(4), np.eye(3)))),
        ("tracks", 0, "covariance"),
    ),
    Row(
        "covariance not positive definite",
        apply(tracks(good("a"), ReportedTrack("b", np.zeros(4), np.diag([1.0, 1, 1, -1])))),
        ("tracks", 1, "covariance"),
    ),
    Row(
        "state beyond the magnitude limit",
        apply(tracks(good("a"), ReportedTrack("b", np.array([0, 0, 1e30, 0]), np.eye(4)))),
        ("tracks", 1, "state", 2),
    ),
    Row(
        "variance below the limit",
        apply(tracks(ReportedTrack("a", np.zeros(4), np.diag([1.0, 1e-14, 1, 1])))),
        ("tracks", 0, "covariance"),
    ),
    Row(
        "class likelihoods all zero",
        apply(tracks(good("a"), good("b", class_likelihoods=ZERO))),
        ("tracks", 1, "class_likelihoods"),
    ),
    Row(
        "class likelihoods out of [0, 1]",
        apply(tracks(good("a", class_likelihoods=np.array([0.5, 1.5, 0.5])))),
        ("tracks", 0, "class_likelihoods"),
    ),
    Row(
        "one likelihood missing",
        apply(tracks(good("a", class_likelihoods=np.array([0.5, 0.5])))),
        ("tracks", 0, "class_likelihoods"),
    ),
    Row(
        "class mass on other classes",
        apply(tracks(good("a"), good("b", class_mass=MassFunction.vacuous(OTHER_CLASSES)))),
        ("tracks", 1, "class_mass"),
    ),
    Row(
        "class mass and likelihoods",
        apply(
            tracks(
                good(
                    "a",
                    class_mass=MassFunction.vacuous(CLASSES),
                    class_likelihoods=np.ones(3),
                )
            )
        ),
        ("tracks", 0, "class_likelihoods"),
    ),
    Row(
        "detections from a track-list sensor",
        apply_detections(detections([[0.0, 0.0]], sensor="s1")),
        ("sensor",),
    ),
    Row(
        "detections of an unknown sensor",
        apply_detections(detections([[0.0, 0.0]], sensor="x")),
        ("sensor",),
    ),
    Row(
        "stale detections",
        apply_detections(detections([[0.0, 0.0]], time=1.0)),
        ("time",),
        StaleReport,
    ),
    Row(
        "detections beyond the time limit",
        apply_detections(detections([[0.0, 0.0]], time=-2e12)),
        ("time",),
    ),
    Row(
        "detection beyond the magnitude limit",
        apply_detections(detections([[0.0, 0.0], [0.0, 1e30]])),
        ("detections", 1, "z", 1),
    ),
    Row(
        "detection noise below the variance limit",
        apply_detections(
            detections([[0.0, 0.0]], covariances=np.array([[[1e-14, 0.0], [0.0, 1.0]]]))
        ),
        ("detections", 0, "r"),
    ),
    Row(
        "detection not finite",
        apply_detections(detections([[0.0, 0.0], [np.nan, 0.0]])),
        ("measurements", 1),
    ),
    Row(
        "detections of the wrong size",
        apply_detections(detections([[0.0, 0.0, 0.0]])),
        ("measurements",),
    ),
    Row(
        "detection noise of the wrong shape",
        apply_detections(detections([[0.0, 0.0]], covariances=np.eye(2)[None, None])),
        ("measurement_covariances",),
    ),
    Row(
        "detection noise not positive definite",
        apply_detections(
            detections(
                [[0.0, 0.0], [1.0, 1.0]],
                covariances=np.array([np.eye(2), [[1.0, 2.0], [2.0, 1.0]]]),
            )
        ),
        ("measurement_covariances", 1, "covariance"),
    ),
]


@pytest.mark.parametrize("row", ROWS, ids=[row.name for row in ROWS])
def test_each_refusal_names_the_refused_value(row: Row) -> None:
    session = engine()
    before = json.dumps(session.export())
    with pytest.raises(row.kind) as refused:
        row.send(session)
    assert getattr(refused.value, "loc", None) == row.loc, str(refused.value)
    assert json.dumps(session.export()) == before
