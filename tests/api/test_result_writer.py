"""The one writer of results and the response models say the same thing.

:func:`app.outputs.json_results.step_json` and ``track_fields`` are the only
writers of the result shape; ``api_schemas.results`` states it for openapi.
Every registered output format (:mod:`app.outputs`) is checked the same way
against its own models, in every frame. Their outputs, over step results with every kind of content (class masses
defined, totally conflicting, tied, summarized; likelihood evidence;
tentative, confirmed, phantom and terminated tracks; continuity and
association pairs; explanation matrices; detections; geodetic positions),
must validate against the models *and* come back unchanged from them (no
field the model does not know, none it would coerce), on the engine's views
and over a live server (REST, WebSocket, the reads).
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Iterator
from dataclasses import replace
from typing import Any

import httpx
import numpy as np
import orjson
import pytest
from pydantic import BaseModel
from websockets.sync.client import connect

from api_schemas.config import SessionConfig
from api_schemas.reports import DetectionReport, TrackReport
from api_schemas.results import FusedFeatureCollection, FusedPicture, FusedTrackDetail, StepResult
from app.http.responses import dumps, itemwise
from app.inputs.detections import core_detection_report
from app.inputs.tracks import session_frame_report
from app.outputs import FRAMES, OUTPUT_FORMATS, Output, output_for
from app.outputs.json_results import step_json, wire_json
from app.routes.streams import converted_message
from app.sessions.pipeline import result_message
from app.sessions.translate import fusion_config, session_geodetic
from core.fusion.engine import SessionEngine
from core.fusion.reports import FusedTracks, FusedTrackView
from core.fusion.reports import StepResult as CoreStepResult
from tests.api.conftest import LiveServer

LABELS = [f"c{index}" for index in range(8)]
COVARIANCE = [[4.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 4.0, 0], [0, 0, 0, 1.0]]
ORIGIN = {"lat": 48.85, "lon": 2.35, "alt": 35.0}
CLASS_TARGETS = 4


def many_focal_sets(seed: int, count: int = 24) -> list[dict[str, Any]]:
    """``count`` distinct focal sets of 2 to 5 labels: two of these combine beyond 32 sets."""
    rng = np.random.default_rng(seed)
    sets: set[tuple[str, ...]] = set()
    while len(sets) < count:
        size = int(rng.integers(2, 6))
        sets.add(tuple(sorted(rng.choice(LABELS, size=size, replace=False).tolist())))
    weights = rng.random(count)
    weights /= weights.sum()
    return [
        {"set": list(labels), "mass": float(mass)}
        for labels, mass in zip(sorted(sets), weights, strict=True)
    ]


def class_evidence(sensor: str, target: int) -> dict[str, Any]:
    """Target 0: categorical and contradictory (total conflict); 1: tied BetP; 2: many focal
    sets (summarized); 3: likelihoods."""
    if target == 0:
        return {"mass": [{"set": ["c0"] if sensor == "s1" else ["c1"], "mass": 1.0}]}
    if target == 1:
        return {"mass": [{"set": ["c0", "c1"], "mass": 1.0}]}
    if target == 2:
        return {"mass": many_focal_sets(1 if sensor == "s1" else 2)}
    return {"likelihoods": {"c3": 0.9, "c4": 0.2}}


def class_config() -> dict[str, Any]:
    return {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "motion": {"model": "constant_velocity", "q": 0.5},
        "classes": LABELS,
        "origin": ORIGIN,
        "sensors": [{"id": "s1", "reliability": 1.0}, {"id": "s2", "reliability": 1.0}],
    }


def class_reports(steps: int) -> list[dict[str, Any]]:
    """Two sensors taking turns over :data:`CLASS_TARGETS` targets 3 km apart."""
    bodies = []
    for index in range(steps):
        sensor = ("s1", "s2")[index % 2]
        time = 1.0 + 0.5 * index
        tracks = [
            {
                "id": f"{sensor}/{target}",
                "state": [3000.0 * target + 10.0 * time, 10.0, 500.0, 0.0],
                "covariance": COVARIANCE,
                "classification": class_evidence(sensor, target),
            }
            for target in range(CLASS_TARGETS)
        ]
        bodies.append({"sensor": sensor, "time": time, "tracks": tracks})
    return bodies


def sector(origin: list[float], heading: float, far: float) -> dict[str, Any]:
    return {
        "kind": "sector",
        "origin": origin,
        "heading_deg": heading,
        "half_angle_deg": 89.0,
        "range": [0.0, far],
    }


def blind_zone_config() -> dict[str, Any]:
    """s1 sees x in [0, 100], s2 x >= 150 along the axis; between them a blind zone of the region."""
    return {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "motion": {"model": "constant_velocity", "q": 0.5},
        "origin": ORIGIN,
        "region": {
            "kind": "polygon",
            "vertices": [[-50.0, -200.0], [350.0, -200.0], [350.0, 200.0], [-50.0, 200.0]],
        },
        "sensors": [
            {"id": "s1", "p_detect": 0.9, "fov": sector([0.0, 0.0], 0.0, 100.0)},
            {"id": "s2", "p_detect": 0.9, "fov": sector([300.0, 0.0], 180.0, 150.0)},
        ],
    }


def blind_zone_reports() -> list[dict[str, Any]]:
    """A target at 10 m/s through s1's view, the blind zone (a phantom), then s2's view."""
    small = [[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0]]
    bodies = []
    for second in range(25):
        for sensor, time, track in (("s1", float(second), "t"), ("s2", second + 0.5, "u")):
            x = 10.0 + 10.0 * time
            seen = x <= 100.0 if sensor == "s1" else x >= 150.0
            tracks = [{"id": track, "state": [x, 10.0, 0.0, 0.0], "covariance": small}]
            bodies.append({"sensor": sensor, "time": time, "tracks": tracks if seen else []})
    return bodies


def detection_config() -> dict[str, Any]:
    return {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "classes": LABELS[:3],
        "sensors": [{"id": "radar", "measurement": {"r": [[4.0, 0.0], [0.0, 4.0]]}}],
    }


def detection_reports(steps: int) -> list[dict[str, Any]]:
    return [
        {
            "sensor": "radar",
            "time": float(scan),
            "detections": [{"z": [1000.0 * target + 10.0 * scan, 50.0]} for target in range(3)],
        }
        for scan in range(steps)
    ]


def engine_steps(
    config: dict[str, Any], bodies: list[dict[str, Any]], detections: bool = False
) -> Iterator[tuple[SessionConfig, SessionEngine, CoreStepResult]]:
    """Every step of ``bodies`` applied by an engine (an explanation on every third)."""
    session = SessionConfig.model_validate(config)
    engine = SessionEngine(fusion_config(session))
    for index, body in enumerate(bodies):
        explain = index % 3 == 0
        if detections:
            report = core_detection_report(
                DetectionReport.model_validate(body), session, engine.config
            )
            yield session, engine, engine.apply_detections(report, explain=explain)
        else:
            report_ = session_frame_report(TrackReport.model_validate(body), session)
            yield session, engine, engine.apply(report_, explain=explain)


OPTIONAL_FIELDS = {
    ("FusedTrack", "geodetic"),
    ("TrackHistoryPoint", "geodetic"),
    ("FusedFeatureCollection", "sensor"),
    ("FusedFeatureCollection", "warnings"),
}
"""Fields the writer leaves out by design (``geodetic``: only with ``frame=geodetic``; a
picture has no ``sensor`` nor ``warnings``)."""


def outputs_of(session: SessionConfig) -> list[Output]:
    """Every registered output format in every frame the session can be written in."""
    geodetic = session_geodetic(session)
    return [
        output_for(geodetic, name, frame)
        for name, output_format in OUTPUT_FORMATS.items()
        for frame in FRAMES
        if geodetic is not None or not (output_format.needs_geodetic or frame == "geodetic")
    ]


def written_in_full(parsed: object, document: object) -> None:
    """Every field of every model in ``parsed`` is in ``document`` (a default is no excuse)."""
    if isinstance(parsed, BaseModel):
        assert isinstance(document, dict)
        name = type(parsed).__name__
        required = {
            field for field in type(parsed).model_fields if (name, field) not in OPTIONAL_FIELDS
        }
        assert required <= set(document), (name, required - set(document))
        for field in document:
            written_in_full(getattr(parsed, field), document[field])
    elif isinstance(parsed, list):
        assert isinstance(document, list)
        for item, written in zip(parsed, document, strict=True):
            written_in_full(item, written)


def round_trip(model: type[BaseModel], text: str) -> dict[str, Any]:
    """``text`` validated as ``model``: it comes back unchanged from the model and writes
    every field the model has."""
    document: dict[str, Any] = json.loads(text)
    parsed = model.model_validate_json(text)
    assert parsed.model_dump(mode="json", exclude_unset=True) == document
    written_in_full(parsed, document)
    return document


class Seen:
    """What the written documents held, to check the scenes cover every kind of content."""

    def __init__(self) -> None:
        self.values: Counter[tuple[str, object]] = Counter()

    def step(self, document: dict[str, Any]) -> None:
        association = document["association"]
        self.values["matrix", association["matrix"] is not None] += 1
        for pair in association["pairs"]:
            self.values["basis", pair["basis"]] += 1
        self.tracks(document["tracks"])

    def tracks(self, tracks: list[dict[str, Any]]) -> None:
        for track in tracks:
            self.values["status", track["status"]] += 1
            self.values["geodetic", "geodetic" in track] += 1
            classification = track["classification"]
            if classification is not None:
                self.values["class state", classification["state"]] += 1
                self.values["decision", classification["decision_state"]] += 1
                self.values["summarized", classification["summarized"]] += 1

    def kinds(self, what: str) -> set[object]:
        return {value for (name, value) in self.values if name == what}


SCENES = [
    (class_config(), class_reports(10), False),
    (blind_zone_config(), blind_zone_reports(), False),
    (detection_config(), detection_reports(6), True),
]


def test_every_written_result_is_the_response_models() -> None:
    seen = Seen()
    for config, bodies, detections in SCENES:
        for seq, (session, engine, step) in enumerate(
            engine_steps(config, bodies, detections), start=1
        ):
            text = step_json(step, seq)
            # written item by item, the text is still orjson's compact text of the whole
            assert orjson.dumps(orjson.loads(text)).decode() == text
            seen.step(round_trip(StepResult, text))
            for output in outputs_of(session):
                written = round_trip(output.format.step_model, output.step(step, seq))
                picture = output.picture(seq, step.time, engine.picture())
                shown = round_trip(output.format.picture_model, picture)
                seen.values["format", output.format.name] += 1
                if output.format.name == "json":
                    seen.step(written)
                    seen.tracks(shown["tracks"])
    assert seen.kinds("status") >= {"tentative", "confirmed", "phantom", "terminated"}
    assert seen.kinds("class state") == {"defined", "total_conflict"}
    assert seen.kinds("decision") == {"decided", "tied", "undefined"}
    assert seen.kinds("summarized") == {True, False}
    assert seen.kinds("matrix") == {True, False}
    assert seen.kinds("basis") == {"continuity", "association"}
    assert seen.kinds("geodetic") == {True, False}
    assert seen.kinds("format") == set(OUTPUT_FORMATS)


def test_itemwise_is_one_call_of_its_writer_byte_for_byte() -> None:
    document = {
        "seq": 3,
        "time": 1e-7,
        "tracks": [{"id": "t0", "state": np.array([1.5, -0.0, 2e300])}, {"id": "é\u2028"}],
        "association": {"pairs": [], "matrix": {"rows": ["a"], "values": [[0.1, None]]}},
        "empty": {},
        "states": np.eye(2),
    }
    whole = orjson.dumps(document, option=orjson.OPT_SERIALIZE_NUMPY).decode()
    assert itemwise(document, wire_json) == whole
    plain = {**document, "tracks": [{"id": "é\u2028", "z": [1e-7, 2.0]}], "states": [[1, 2]]}
    assert itemwise(plain) == json.dumps(plain, allow_nan=False, separators=(",", ":"))
    assert itemwise(plain, dumps) != itemwise(plain, wire_json)  # the writers differ (1e-07)


def test_the_wire_answers_are_the_response_models(live_server: LiveServer) -> None:
    """The same over a live server: POST (with ``explain``, ``frame=geodetic``), the stream,
    the fused picture and a track's detail."""
    seen = Seen()
    with httpx.Client(base_url=live_server.url) as client:
        created = client.post("/v1/sessions", json=class_config()).json()
        sid, headers = created["id"], {"Authorization": f"Bearer {created['token']}"}
        bodies = class_reports(8)
        for index, body in enumerate(bodies[:4]):
            params = {"explain": "true", "frame": "geodetic"} if index % 2 else {}
            if index == 2:
                params = {"format": "geojson"}
            answer = client.post(
                f"/v1/sessions/{sid}/tracks", json=body, params=params, headers=headers
            )
            assert answer.status_code == 200, answer.text
            if index == 2:
                assert answer.headers["content-type"].startswith("application/geo+json")
                round_trip(FusedFeatureCollection, answer.text)
                continue
            seen.step(round_trip(StepResult, answer.text))
        url = live_server.url.replace("http://", "ws://") + f"/v1/sessions/{sid}/stream"
        parts = (
            ("", bodies[4:6]),
            ("?frame=geodetic", bodies[6:7]),
            ("?format=geojson", bodies[7:]),
        )
        for query, part in parts:
            with connect(url + query, additional_headers=headers) as stream:
                json.loads(stream.recv())  # ack
                for body in part:
                    stream.send(json.dumps(body | {"type": "tracks"}))
                    message = json.loads(stream.recv())
                    assert message["type"] == "result", message
                    if "geojson" in query:
                        round_trip(FusedFeatureCollection, json.dumps(message["result"]))
                    else:
                        seen.step(round_trip(StepResult, json.dumps(message["result"])))
        geojson = client.get(
            f"/v1/sessions/{sid}/tracks", params={"format": "geojson"}, headers=headers
        )
        assert round_trip(FusedFeatureCollection, geojson.text)["seq"] == len(bodies)
        for params in ({}, {"frame": "geodetic"}, {"time": "9.5"}):
            answer = client.get(f"/v1/sessions/{sid}/tracks", params=params, headers=headers)
            assert answer.status_code == 200, answer.text
            seen.tracks(round_trip(FusedPicture, answer.text)["tracks"])
        track = answer.json()["tracks"][0]["id"]
        for params in ({}, {"frame": "geodetic"}):
            answer = client.get(
                f"/v1/sessions/{sid}/tracks/{track}", params=params, headers=headers
            )
            assert answer.status_code == 200, answer.text
            detail = round_trip(FusedTrackDetail, answer.text)
            assert detail["track"]["id"] == track and detail["history"]
            seen.tracks([detail["track"]])
            seen.values["geodetic history", "geodetic" in detail["history"][0]] += 1
    assert seen.kinds("class state") == {"defined", "total_conflict"}
    assert seen.kinds("decision") == {"decided", "tied", "undefined"}
    assert seen.kinds("summarized") == {True, False}
    assert seen.kinds("matrix") == {True, False}
    assert seen.kinds("geodetic") == seen.kinds("geodetic history") == {True, False}


def class_steps() -> list[CoreStepResult]:
    return [step for _, _, step in engine_steps(class_config(), class_reports(4))]


def test_step_json_refuses_non_finite_numbers() -> None:
    step = class_steps()[-1]
    track = step.tracks[0]
    state = track.state.copy()
    state[0] = math.nan
    broken = replace(step, tracks=(replace(track, state=state), *step.tracks[1:]))
    with pytest.raises(ValueError, match="non-finite state"):
        step_json(broken, 1)
    last = step.tracks[-1]
    covariance = last.covariance.copy()
    covariance[1, 1] = math.inf
    broken = replace(step, tracks=(*step.tracks[:-1], replace(last, covariance=covariance)))
    with pytest.raises(ValueError, match=rf"fused track '{last.id}': non-finite covariance"):
        step_json(broken, 1)
    broken = replace(step, tracks=(replace(track, score=-math.inf), *step.tracks[1:]))
    with pytest.raises(ValueError, match="non-finite score"):
        step_json(broken, 1)
    with pytest.raises(ValueError, match="non-finite step time"):
        step_json(replace(step, time=math.nan), 1)


def test_step_json_writes_arrays_in_their_logical_order() -> None:
    """A Fortran-ordered (transposed) covariance is written row by row, as numpy reads it."""
    step = class_steps()[-1]
    track = step.tracks[0]
    skewed = track.covariance + np.triu(np.ones_like(track.covariance), 1)  # not symmetric
    transposed = replace(step, tracks=(replace(track, covariance=np.asfortranarray(skewed.T)),))
    written = json.loads(step_json(transposed, 1))["tracks"][0]["covariance"]
    assert written == skewed.T.tolist()


def view_as_read(view: FusedTrackView) -> dict[str, Any]:
    """A fused track as the contract says it, read field by field from its view (the oracle
    of the columnar writer: plain Python values, no shared code)."""
    assessment = view.classification
    classification = None
    if assessment is not None:
        labels = None if assessment.mass is None else assessment.mass.frame.labels
        classification = {
            "state": assessment.state.value,
            "mass": None
            if assessment.mass is None
            else [{"set": list(s), "mass": m} for s, m in assessment.mass.focal_sets()],
            "conflict": assessment.conflict,
            "decision": assessment.decision if labels is not None else None,
            "decision_state": assessment.decision_state.value,
            "summarized": assessment.summarized,
        }
        for name in ("pignistic", "belief", "plausibility"):
            values = getattr(assessment, name)
            classification[name] = (
                None if labels is None else dict(zip(labels, values.tolist(), strict=True))
            )
    return {
        "id": view.id,
        "status": view.status.value,
        "state": [float(x) for x in view.state],
        "covariance": [[float(x) for x in row] for row in view.covariance],
        "sources": [{"sensor": s.sensor, "track": s.track, "time": s.time} for s in view.sources],
        "classification": classification,
        "score": view.score,
        "reason": view.reason.value,
    }


def test_step_json_writes_every_track_as_its_view_says_exactly() -> None:
    """The tracks written from the step's columns are the views, value for value: every
    float bit for bit (JSON's shortest text reads back to the same double)."""
    written_tracks = Counter[str]()
    for config, bodies, detections in SCENES:
        for seq, (_, _, step) in enumerate(engine_steps(config, bodies, detections), start=1):
            assert isinstance(step.tracks, FusedTracks)
            written = json.loads(step_json(step, seq))["tracks"]
            assert written == [view_as_read(view) for view in step.tracks]
            for track in written:
                written_tracks[track["classification"] is None] += 1
    assert written_tracks[True] > 0 and written_tracks[False] > 0


def test_a_result_converted_after_the_fact_equals_the_one_written_with_it() -> None:
    """A subscriber fed through Redis converts the published JSON text to its output; one of
    this instance gets the text written beside the step: both say the same, in every output."""
    converted: Counter[str] = Counter()
    for config, bodies, detections in SCENES:
        for seq, (session, _, step) in enumerate(engine_steps(config, bodies, detections), start=1):
            for output in outputs_of(session):
                after = converted_message(result_message(step_json(step, seq), "r"), output)
                beside = result_message(output.step(step, seq), "r")
                assert json.loads(after) == json.loads(beside)
                converted[output.format.name] += bool(step.tracks)
    assert set(converted) == set(OUTPUT_FORMATS) and min(converted.values()) > 0
