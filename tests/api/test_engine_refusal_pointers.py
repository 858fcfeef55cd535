"""Inputs the schema lets through and the engine refuses: each answer points at the field.

A live uvicorn server holds one session (sensor ``radar-1`` sends track lists,
``radar-9`` detections) that accepted one input of each. Every row is wrong
in one place the engine checks (times against the sensor's previous input,
magnitude bounds, class evidence that rules out every class, detections from
a track-list sensor); its answer must be the row's status with a
problem+json ``errors[].pointer`` naming that place, and the session must be
unchanged afterwards.
"""

from __future__ import annotations

import copy
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import httpx
import pytest

from .conftest import make_settings, serving
from .scenario import CLASSES, track_report

Body = dict[str, Any]
GOOD_TRACKS = track_report("radar-1", 10.0, seed=1)
LATER_TRACKS = track_report("radar-1", 11.0, seed=2)
GOOD_DETECTIONS: Body = {"sensor": "radar-9", "time": 10.0, "detections": [{"z": [50.0, 60.0]}]}
LATER_DETECTIONS: Body = {
    "sensor": "radar-9",
    "time": 11.0,
    "detections": [{"z": [50.0, 60.0]}, {"z": [900.0, 100.0]}],
}


@dataclass(frozen=True)
class Row:
    name: str
    body: Body
    pointer: str
    status: int = 422
    route: str = "tracks"


def tracks(change: Any) -> Body:
    body = copy.deepcopy(LATER_TRACKS)
    change(body)
    return body


def detections(change: Any) -> Body:
    body = copy.deepcopy(LATER_DETECTIONS)
    change(body)
    return body


ZERO = {label: 0.0 for label in CLASSES}
ROWS = [
    Row("stale track list", tracks(lambda b: b.update(time=9.0)), "#/time", 409),
    Row("track list at the same time", tracks(lambda b: b.update(time=10.0)), "#/time", 409),
    Row("time beyond the limit", tracks(lambda b: b.update(time=1e300)), "#/time"),
    Row(
        "class likelihoods all zero",
        tracks(lambda b: b["tracks"][2].update(classification={"likelihoods": ZERO})),
        "#/tracks/2/classification/likelihoods",
    ),
    Row(
        "state beyond the magnitude limit",
        tracks(lambda b: b["tracks"][1].update(state=[0.0, 0.0, 1e30, 0.0])),
        "#/tracks/1/state/2",
    ),
    Row(
        "detections from a track-list sensor",
        detections(
            lambda b: b.update(
                sensor="radar-1", detections=[{"z": [1.0, 2.0], "r": [[1.0, 0.0], [0.0, 1.0]]}]
            )
        ),
        "#/sensor",
        route="detections",
    ),
    Row(
        "stale detections",
        detections(lambda b: b.update(time=10.0)),
        "#/time",
        409,
        route="detections",
    ),
    Row(
        "detections beyond the time limit",
        detections(lambda b: b.update(time=-1e13)),
        "#/time",
        route="detections",
    ),
    Row(
        "detection beyond the magnitude limit",
        detections(lambda b: b["detections"][1].update(z=[1e30, 0.0])),
        "#/detections/1/z/0",
        route="detections",
    ),
    Row(
        "detection noise below the variance limit",
        detections(lambda b: b["detections"][0].update(r=[[1e-14, 0.0], [0.0, 1.0]])),
        "#/detections/0/r",
        route="detections",
    ),
]


@dataclass
class Scene:
    client: httpx.Client
    base: str
    headers: dict[str, str]


@pytest.fixture(scope="module")
def scene() -> Iterator[Scene]:
    config = {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "classes": CLASSES,
        "sensors": [
            {"id": "radar-1"},
            {"id": "radar-9", "measurement": {"r": [[25.0, 0.0], [0.0, 25.0]]}},
        ],
    }
    with serving(make_settings()) as server, httpx.Client(base_url=server.url) as client:
        created = client.post("/v1/sessions", json=config).json()
        base = f"/v1/sessions/{created['id']}"
        headers = {"Authorization": f"Bearer {created['token']}"}
        assert client.post(f"{base}/tracks", json=GOOD_TRACKS, headers=headers).status_code == 200
        accepted = client.post(f"{base}/detections", json=GOOD_DETECTIONS, headers=headers)
        assert accepted.status_code == 200, accepted.text
        yield Scene(client, base, headers)


def state_of(scene: Scene) -> tuple[Any, ...]:
    summary = scene.client.get(scene.base, headers=scene.headers).json()
    summary.pop("last_input_at")
    return (
        summary,
        scene.client.get(f"{scene.base}/tracks", headers=scene.headers).json(),
        scene.client.get(f"{scene.base}/events", headers=scene.headers).json()["last_seq"],
    )


@pytest.mark.parametrize("row", ROWS, ids=[row.name for row in ROWS])
def test_an_engine_refusal_points_at_the_refused_field(row: Row, scene: Scene) -> None:
    before = state_of(scene)
    answer = scene.client.post(f"{scene.base}/{row.route}", json=row.body, headers=scene.headers)
    assert answer.status_code == row.status, answer.text
    assert answer.headers["content-type"].startswith("application/problem+json")
    problem = answer.json()
    assert [error["pointer"] for error in problem["errors"]] == [row.pointer], problem
    assert all(error["detail"] for error in problem["errors"])
    assert state_of(scene) == before
