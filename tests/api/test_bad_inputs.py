"""Bad inputs through the real routes: each the documented 4xx problem naming the field; nothing changes.

One session holds one accepted track list. Every row sends a bad request;
the answer must be the row's status with a problem+json body that names the
field (``errors[].loc``), the limit (``limit``) or the times (stale report),
and afterwards the session's ``seq``, event log and fused tracks must be
exactly what they were. No row may produce a 5xx.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import pytest
from fastapi.testclient import TestClient

from app.main import create_app
from tests.api.conftest import ADMIN_TOKEN, make_settings
from tests.api.scenario import CLASSES, track_report

Body = dict[str, Any]
MAX_TRACKS = 5
GOOD = track_report("radar-1", 12.5, seed=1)
LATER = track_report("radar-1", 13.0, seed=2)


@dataclass
class Scene:
    client: TestClient
    sid: str
    headers: dict[str, str]
    other_headers: dict[str, str]


@pytest.fixture(scope="module")
def scene() -> Iterator[Scene]:
    settings = make_settings(max_tracks_per_input=MAX_TRACKS, max_body_bytes=64 * 1024)
    with TestClient(create_app(settings), raise_server_exceptions=False) as client:
        config = {
            "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
            "classes": CLASSES,
            "sensors": [{"id": "radar-1"}, {"id": "radar-2"}],
        }
        created = client.post("/v1/sessions", json=config).json()
        other = client.post("/v1/sessions", json=config).json()
        headers = {"Authorization": f"Bearer {created['token']}"}
        accepted = client.post(f"/v1/sessions/{created['id']}/tracks", json=GOOD, headers=headers)
        assert accepted.status_code == 200, accepted.text
        yield Scene(client, created["id"], headers, {"Authorization": f"Bearer {other['token']}"})


def edited(change: Callable[[Body], object], template: Body = LATER) -> Body:
    body = copy.deepcopy(template)
    change(body)
    return body


def on_track(key: str, value: object) -> Callable[[Body], object]:
    return lambda body: body["tracks"][0].__setitem__(key, value)


def classification(evidence: object) -> Callable[[Body], object]:
    return on_track("classification", evidence)


LATER_TEXT = json.dumps(LATER)
FIRST_STATE = json.dumps(LATER["tracks"][0]["state"][0])
CONFIG = {"state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]}}


@dataclass(frozen=True)
class Row:
    """One bad request and what it must get."""

    name: str
    status: int
    loc: tuple[str | int, ...] | None = None
    body: Body | None = None
    raw: str | None = None
    path: str = "/v1/sessions/{sid}/tracks"
    method: str = "POST"
    auth: str = "own"  # own | none | wrong | other | admin
    params: dict[str, str] = field(default_factory=dict)
    limit: str | None = None
    slug: str | None = None


ROWS = [
    Row(
        "NaN time token",
        422,
        ("body", "time"),
        raw=LATER_TEXT.replace('"time": 13.0', '"time": NaN'),
    ),
    Row(
        "Infinity state token",
        422,
        ("body", "tracks", 0, "state", 0),
        raw=LATER_TEXT.replace(f'"state": [{FIRST_STATE}', '"state": [Infinity', 1),
    ),
    Row(
        "-Infinity covariance token",
        422,
        ("body", "tracks", 0, "covariance", 0, 0),
        raw=LATER_TEXT.replace('"covariance": [[4.0', '"covariance": [[-Infinity', 1),
    ),
    Row("body is not JSON", 422, ("body",), raw='{"sensor": "radar-1", '),
    Row(
        "state of 2 for a 4-state session",
        422,
        ("body", "tracks", 0, "state"),
        edited(lambda b: b["tracks"][0].update(state=[1.0, 2.0], covariance=[[1, 0], [0, 1]])),
    ),
    Row(
        "covariance 3x3 for a 4-state",
        422,
        ("body", "tracks", 0, "covariance"),
        edited(on_track("covariance", [[1, 0, 0], [0, 1, 0], [0, 0, 1]])),
    ),
    Row(
        "non-symmetric covariance",
        422,
        ("body", "tracks", 0, "covariance"),
        edited(on_track("covariance", [[4, 1, 0, 0], [0, 1, 0, 0], [0, 0, 4, 0], [0, 0, 0, 1]])),
    ),
    Row(
        "covariance not positive definite",
        422,
        ("body", "tracks", 0, "covariance"),
        edited(on_track("covariance", [[1, 2, 0, 0], [2, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])),
    ),
    Row(
        "masses sum to 0.9",
        422,
        ("body", "tracks", 0, "classification"),
        edited(classification({"mass": [{"set": ["liner"], "mass": 0.9}]})),
    ),
    Row(
        "negative mass",
        422,
        ("body", "tracks", 0, "classification", "mass", 0, "mass"),
        edited(
            classification(
                {"mass": [{"set": ["liner"], "mass": -0.5}, {"set": CLASSES, "mass": 1.5}]}
            )
        ),
    ),
    Row(
        "mass names an unknown class",
        422,
        ("body", "tracks", 0, "classification", "mass", 0, "set", 0),
        edited(classification({"mass": [{"set": ["submarine"], "mass": 1.0}]})),
    ),
    Row(
        "likelihood of an unknown class",
        422,
        ("body", "tracks", 0, "classification", "likelihoods", "submarine"),
        edited(classification({"likelihoods": {"liner": 0.5, "submarine": 0.9}})),
    ),
    Row(
        "likelihood above 1",
        422,
        ("body", "tracks", 0, "classification", "likelihoods", "liner"),
        edited(classification({"likelihoods": {"liner": 1.5}})),
    ),
    Row(
        "both mass and likelihoods",
        422,
        ("body", "tracks", 0, "classification"),
        edited(
            classification(
                {"mass": [{"set": ["liner"], "mass": 1.0}], "likelihoods": {"liner": 0.5}}
            )
        ),
    ),
    Row("unknown top-level key", 422, ("body", "priority"), edited(lambda b: b.update(priority=1))),
    Row(
        "unknown track key", 422, ("body", "tracks", 0, "velocity"), edited(on_track("velocity", 3))
    ),
    Row("time is a string", 422, ("body", "time"), edited(lambda b: b.update(time="13.0"))),
    Row("track id is a number", 422, ("body", "tracks", 0, "id"), edited(on_track("id", 17))),
    Row(
        "state is a string",
        422,
        ("body", "tracks", 0, "state"),
        edited(on_track("state", "1,2,3,4")),
    ),
    Row(
        "duplicate track ids",
        422,
        ("body", "tracks", 1, "id"),
        edited(lambda b: b["tracks"][1].update(id=b["tracks"][0]["id"])),
    ),
    Row("unknown sensor", 422, ("body", "sensor"), edited(lambda b: b.update(sensor="sonar-9"))),
    Row("missing sensor", 422, ("body", "sensor"), edited(lambda b: b.pop("sensor"))),
    Row("stale time", 409, body=edited(lambda b: b.update(time=12.0)), slug="stale-report"),
    Row("same time again", 409, body=edited(lambda b: b.update(time=12.5)), slug="stale-report"),
    Row(
        "late report whose tracks cannot be predicted to the fusion time",
        422,
        body=edited(lambda b: b.update(sensor="radar-2", time=-1e300)),
        slug="invalid-input",
    ),
    Row(
        "oversize body",
        413,
        body=edited(lambda b: b["tracks"][0].update(id="x" * 64, pad="y" * 70_000)),
        limit="max_body_bytes",
    ),
    Row(
        "too many tracks",
        422,
        body=edited(
            lambda b: b.update(tracks=track_report("radar-1", 13.0, 3, targets=6)["tracks"])
        ),
        limit="max_tracks_per_input",
    ),
    Row("missing token", 401, body=LATER, auth="none", slug="unauthorized"),
    Row("wrong token", 404, body=LATER, auth="wrong", slug="session-not-found"),
    Row("other session's token", 404, body=LATER, auth="other", slug="session-not-found"),
    Row(
        "unknown session",
        404,
        body=LATER,
        path="/v1/sessions/no-such-session/tracks",
        slug="session-not-found",
    ),
    Row("explain is not a boolean", 422, ("query", "explain"), LATER, params={"explain": "maybe"}),
    Row(
        "prediction time NaN",
        422,
        ("query", "time"),
        method="GET",
        params={"time": "nan"},
    ),
    Row(
        "prediction time too far to predict to (overflow)",
        422,
        method="GET",
        params={"time": "1e200"},
    ),
    Row(
        "report time too far from the fused tracks (overflow)",
        422,
        body={
            "sensor": "radar-2",
            "time": 1e200,
            "tracks": [
                {
                    "id": "x",
                    "state": [0, 0, 0, 0],
                    "covariance": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
                }
            ],
        },
    ),
    Row(
        "unknown fused track",
        404,
        method="GET",
        path="/v1/sessions/{sid}/tracks/F99",
        slug="track-not-found",
    ),
    Row(
        "detections from a sensor that sends track lists (no measurement model)",
        422,
        body={
            "sensor": "radar-1",
            "time": 14.0,
            "detections": [{"z": [1.0, 2.0], "r": [[1, 0], [0, 1]]}],
        },
        path="/v1/sessions/{sid}/detections",
    ),
    Row(
        "detection z of 3 in a 2-position session",
        422,
        ("body", "detections", 0, "z"),
        {"sensor": "radar-1", "time": 14.0, "detections": [{"z": [1.0, 2.0, 3.0]}]},
        path="/v1/sessions/{sid}/detections",
    ),
    Row(
        "config with an unknown key",
        422,
        ("body", "colour"),
        CONFIG | {"colour": "red"},
        path="/v1/sessions",
        auth="none",
    ),
    Row(
        "config with a self-intersecting field of view",
        422,
        ("body", "sensors", 0, "fov"),
        CONFIG
        | {
            "sensors": [
                {
                    "id": "s",
                    "fov": {"kind": "polygon", "vertices": [[0, 0], [1, 1], [1, 0], [0, 1]]},
                }
            ]
        },
        path="/v1/sessions",
        auth="none",
    ),
    Row(
        "config with mercier's unknown option",
        422,
        ("body", "association", "options", "maximise"),
        CONFIG | {"association": {"method": "mercier", "options": {"maximise": "plausibility"}}},
        path="/v1/sessions",
        auth="none",
    ),
    Row(
        "associate with mixed dimensions",
        422,
        ("body", "incoming", 0, "state"),
        {
            "known": GOOD["tracks"][:1],
            "incoming": [{"id": "x", "state": [1.0, 2.0], "covariance": [[1, 0], [0, 1]]}],
        },
        path="/v1/associate",
        auth="none",
    ),
]


def headers_for(row: Row, scene: Scene) -> dict[str, str]:
    return {
        "own": scene.headers,
        "none": {},
        "wrong": {"Authorization": "Bearer not-a-token"},
        "other": scene.other_headers,
        "admin": {"Authorization": f"Bearer {ADMIN_TOKEN}"},
    }[row.auth]


def state_of(scene: Scene) -> tuple[Any, ...]:
    """Everything a refused request must leave alone."""
    base = f"/v1/sessions/{scene.sid}"
    summary = scene.client.get(base, headers=scene.headers).json()
    summary.pop("last_input_at")
    return (
        summary,
        scene.client.get(f"{base}/tracks", headers=scene.headers).json(),
        scene.client.get(f"{base}/events", headers=scene.headers).json(),
    )


def test_the_table_is_large_enough() -> None:
    assert len(ROWS) >= 25


@pytest.mark.parametrize("row", ROWS, ids=[row.name for row in ROWS])
def test_bad_input_is_refused_and_changes_nothing(row: Row, scene: Scene) -> None:
    before = state_of(scene)
    assert before[0]["seq"] == 1
    headers = dict(headers_for(row, scene))
    content: bytes | None = None
    if row.raw is not None:
        content = row.raw.encode()
    elif row.body is not None:
        content = json.dumps(row.body).encode()
    if content is not None:
        headers["Content-Type"] = "application/json"
    answer = scene.client.request(
        row.method,
        row.path.format(sid=scene.sid),
        content=content,
        headers=headers,
        params=row.params,
    )
    assert answer.status_code == row.status, answer.text
    assert answer.headers["content-type"].startswith("application/problem+json")
    problem = answer.json()
    assert problem["status"] == row.status and problem["detail"]
    if row.loc is not None:
        locations = [tuple(error["loc"]) for error in problem["errors"]]
        assert any(location[: len(row.loc)] == row.loc for location in locations), problem
    if row.limit is not None:
        assert problem["limit"] == row.limit, problem
    if row.slug is not None:
        assert problem["type"].endswith(":" + row.slug), problem
    if row.slug == "stale-report":
        assert problem["time"] == row.body["time"] if row.body else False
        assert problem["last_time"] == 12.5
    assert state_of(scene) == before
