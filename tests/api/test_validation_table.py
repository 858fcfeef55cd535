"""Bad bodies are rejected with 422 problem+json naming the field, by the real application.

Each row is sent to the route that takes it (``/sessions`` → ``POST /v1/sessions``,
``/tracks`` and ``/detections`` → a live session's inputs, ``/associate`` →
``POST /v1/associate``, ``/message`` → a message on the session's ``stream``
WebSocket, answered by an ``error`` message), so a check a route drops is seen.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import pytest
from fastapi.testclient import TestClient

from app.main import create_app
from tests.api.conftest import make_settings
from tests.api.examples import DETECTION_REPORT, SESSION_CONFIG, TRACK_REPORT

Body = dict[str, Any]


@dataclass(frozen=True)
class BadBody:
    """One row: the route, the body (JSON text or an edit of a valid body), the field expected in ``errors``."""

    name: str
    route: str
    loc: tuple[str | int, ...]
    edit: Callable[[Body], object] | None = None
    raw: str | None = None


def edited(template: Body, change: Callable[[Body], object]) -> Body:
    body = copy.deepcopy(template)
    change(body)
    return body


def track(body: Body) -> Body:
    first: Body = body["tracks"][0]
    return first


def set_key(key: str, value: object) -> Callable[[Body], object]:
    return lambda body: body.__setitem__(key, value)


def set_track(key: str, value: object) -> Callable[[Body], object]:
    return lambda body: track(body).__setitem__(key, value)


def set_mass(masses: list[Body]) -> Callable[[Body], object]:
    return lambda body: track(body).__setitem__("classification", {"mass": masses})


def set_state(key: str, value: object) -> Callable[[Body], object]:
    return lambda body: body["state"].__setitem__(key, value)


def set_sensor(key: str, value: object) -> Callable[[Body], object]:
    return lambda body: body["sensors"][0].__setitem__(key, value)


def add_duplicate_track(body: Body) -> None:
    body["tracks"].append(copy.deepcopy(track(body)))


def add_duplicate_sensor(body: Body) -> None:
    body["sensors"].append(copy.deepcopy(body["sensors"][0]))


REPORT_TEXT = json.dumps(TRACK_REPORT)
IDENTITY_4 = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
ASSOCIATE = {
    "known": [TRACK_REPORT["tracks"][0]],
    "incoming": [],
    "classes": ["liner", "bomber", "fighter"],
}

ROWS = [
    # --- non-finite numbers sent as raw JSON tokens
    BadBody(
        "NaN time",
        "/tracks",
        ("body", "time"),
        raw=REPORT_TEXT.replace('"time": 12.5', '"time": NaN'),
    ),
    BadBody(
        "Infinity in state",
        "/tracks",
        ("body", "tracks", 0, "state", 0),
        raw=REPORT_TEXT.replace('"state": [100.0', '"state": [Infinity'),
    ),
    BadBody(
        "-Infinity in covariance",
        "/tracks",
        ("body", "tracks", 0, "covariance", 0, 0),
        raw=REPORT_TEXT.replace('"covariance": [[4', '"covariance": [[-Infinity'),
    ),
    BadBody(
        "NaN mass",
        "/tracks",
        ("body", "tracks", 0, "classification", "mass", 0, "mass"),
        raw=REPORT_TEXT.replace('"mass": 0.6', '"mass": NaN'),
    ),
    BadBody("not JSON", "/tracks", ("body",), raw='{"sensor": "radar-1", '),
    # --- track lists: dimensions, matrices, ids, types
    BadBody(
        "covariance 3x3 for a 4-state",
        "/tracks",
        ("body", "tracks", 0, "covariance"),
        set_track("covariance", [[1, 0, 0], [0, 1, 0], [0, 0, 1]]),
    ),
    BadBody(
        "ragged covariance",
        "/tracks",
        ("body", "tracks", 0, "covariance"),
        set_track("covariance", [[1, 0], [0]]),
    ),
    BadBody(
        "non-symmetric covariance",
        "/tracks",
        ("body", "tracks", 0, "covariance"),
        set_track("covariance", [[4, 1, 0, 0], [0, 1, 0, 0], [0, 0, 4, 0], [0, 0, 0, 1]]),
    ),
    BadBody(
        "covariance not positive definite",
        "/tracks",
        ("body", "tracks", 0, "covariance"),
        set_track("covariance", [[1, 2, 0, 0], [2, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]),
    ),
    BadBody(
        "singular covariance",
        "/tracks",
        ("body", "tracks", 0, "covariance"),
        set_track("covariance", [[0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]),
    ),
    BadBody(
        "state dim differs from the session's",
        "/tracks",
        ("body", "tracks", 0, "state"),
        lambda body: track(body).update(state=[1.0, 2.0], covariance=[[1, 0], [0, 1]]),
    ),
    BadBody("duplicate track ids", "/tracks", ("body", "tracks", 1, "id"), add_duplicate_track),
    BadBody("track id is a number", "/tracks", ("body", "tracks", 0, "id"), set_track("id", 17)),
    BadBody(
        "state is a string",
        "/tracks",
        ("body", "tracks", 0, "state"),
        set_track("state", "100,3,250,-1"),
    ),
    BadBody("time is a string", "/tracks", ("body", "time"), set_key("time", "12.5")),
    BadBody(
        "unknown key in a track",
        "/tracks",
        ("body", "tracks", 0, "velocity"),
        set_track("velocity", [1, 2]),
    ),
    BadBody("unknown sensor", "/tracks", ("body", "sensor"), set_key("sensor", "sonar-9")),
    BadBody("missing tracks", "/tracks", ("body", "tracks"), lambda body: body.pop("tracks")),
    # --- class evidence
    BadBody(
        "masses sum to 0.9",
        "/tracks",
        ("body", "tracks", 0, "classification"),
        set_mass([{"set": ["bomber"], "mass": 0.5}, {"set": ["liner"], "mass": 0.4}]),
    ),
    BadBody(
        "negative mass",
        "/tracks",
        ("body", "tracks", 0, "classification", "mass", 0, "mass"),
        set_mass([{"set": ["bomber"], "mass": -0.5}, {"set": ["liner"], "mass": 1.5}]),
    ),
    BadBody(
        "unknown class in a focal set",
        "/tracks",
        ("body", "tracks", 0, "classification", "mass", 0, "set", 1),
        set_mass([{"set": ["bomber", "zeppelin"], "mass": 1.0}]),
    ),
    BadBody(
        "duplicate focal sets",
        "/tracks",
        ("body", "tracks", 0, "classification"),
        set_mass(
            [{"set": ["bomber", "liner"], "mass": 0.5}, {"set": ["liner", "bomber"], "mass": 0.5}]
        ),
    ),
    BadBody(
        "empty focal set",
        "/tracks",
        ("body", "tracks", 0, "classification", "mass", 0, "set"),
        set_mass([{"set": [], "mass": 1.0}]),
    ),
    BadBody(
        "both mass and likelihoods",
        "/tracks",
        ("body", "tracks", 0, "classification"),
        set_track(
            "classification",
            {"mass": [{"set": ["liner"], "mass": 1.0}], "likelihoods": {"liner": 0.5}},
        ),
    ),
    BadBody(
        "likelihood above 1",
        "/tracks",
        ("body", "tracks", 0, "classification", "likelihoods", "bomber"),
        set_track("classification", {"likelihoods": {"bomber": 1.5}}),
    ),
    BadBody(
        "likelihood of an unknown class",
        "/tracks",
        ("body", "tracks", 0, "classification", "likelihoods", "zeppelin"),
        set_track("classification", {"likelihoods": {"zeppelin": 0.5}}),
    ),
    # --- detections
    BadBody(
        "a polar detection without its azimuth (the union's tag is not in the path)",
        "/detections",
        ("body", "detections", 0, "azimuth_deg"),
        lambda body: body["detections"].__setitem__(0, {"range": 500.0}),
    ),
    BadBody(
        "z has 3 components for 2 positions",
        "/detections",
        ("body", "detections", 0, "z"),
        lambda body: body["detections"][0].__setitem__("z", [1.0, 2.0, 3.0]),
    ),
    BadBody(
        "detection r not positive definite",
        "/detections",
        ("body", "detections", 1, "r"),
        lambda body: body["detections"][1].__setitem__("r", [[1, 0], [0, -1]]),
    ),
    # --- session configs
    BadBody(
        "unknown top-level config key", "/sessions", ("body", "colour"), set_key("colour", "red")
    ),
    BadBody(
        "unknown sensor key", "/sessions", ("body", "sensors", 0, "gain"), set_sensor("gain", 2.0)
    ),
    BadBody("missing state layout", "/sessions", ("body", "state"), lambda body: body.pop("state")),
    BadBody("dim is a string", "/sessions", ("body", "state", "dim"), set_state("dim", "4")),
    BadBody(
        "position index outside the state",
        "/sessions",
        ("body", "state", "position", 1),
        set_state("position", [0, 7]),
    ),
    BadBody(
        "21 classes",
        "/sessions",
        ("body", "classes"),
        set_key("classes", [f"c{index}" for index in range(21)]),
    ),
    BadBody(
        "duplicate class",
        "/sessions",
        ("body", "classes", 1),
        set_key("classes", ["liner", "liner"]),
    ),
    BadBody(
        "unknown association method",
        "/sessions",
        ("body", "association", "method"),
        set_key("association", {"method": "nearest"}),
    ),
    BadBody(
        "option of another method",
        "/sessions",
        ("body", "association", "options", "gamma"),
        set_key("association", {"method": "gnn", "options": {"gamma": 0.1}}),
    ),
    BadBody(
        "unknown association option",
        "/sessions",
        ("body", "association", "options", "temperature"),
        set_key("association", {"method": "gnn", "options": {"temperature": 3}}),
    ),
    BadBody(
        "sensor r sized for 3 positions",
        "/sessions",
        ("body", "sensors", 0, "measurement", "r"),
        set_sensor("measurement", {"r": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}),
    ),
    BadBody(
        "sensor r not symmetric",
        "/sessions",
        ("body", "sensors", 0, "measurement", "r"),
        set_sensor("measurement", {"r": [[1, 0.5], [0, 1]]}),
    ),
    BadBody(
        "p_detect above 1",
        "/sessions",
        ("body", "sensors", 0, "p_detect"),
        set_sensor("p_detect", 1.5),
    ),
    BadBody(
        "unknown fov kind",
        "/sessions",
        ("body", "sensors", 0, "fov"),
        set_sensor("fov", {"kind": "cone"}),
    ),
    BadBody(
        "a polar measurement without its azimuth sigma (the union's tag is not in the path)",
        "/sessions",
        ("body", "sensors", 0, "measurement", "sigma_azimuth_deg"),
        set_sensor("measurement", {"kind": "polar", "sigma_range": 20.0}),
    ),
    BadBody(
        "a cartesian measurement (the default kind) without r",
        "/sessions",
        ("body", "sensors", 0, "measurement", "r"),
        set_sensor("measurement", {"sigma_range": 20.0}),
    ),
    BadBody(
        "polygon vertices not an array",
        "/sessions",
        ("body", "sensors", 0, "fov", "vertices"),
        set_sensor("fov", {"kind": "polygon", "vertices": "0,0 1,0 1,1"}),
    ),
    BadBody(
        "a polygon vertex of three numbers",
        "/sessions",
        ("body", "sensors", 0, "fov", "vertices", 2),
        set_sensor("fov", {"kind": "polygon", "vertices": [[0, 0], [1, 0], [1, 1, 1]]}),
    ),
    BadBody(
        "a polygon vertex as text",
        "/sessions",
        ("body", "sensors", 0, "fov", "vertices", 1, 0),
        set_sensor("fov", {"kind": "polygon", "vertices": [[0, 0], ["1", 0], [1, 1]]}),
    ),
    BadBody(
        "duplicate sensor ids", "/sessions", ("body", "sensors", 1, "id"), add_duplicate_sensor
    ),
    BadBody(
        "unknown state fusion",
        "/sessions",
        ("body", "fusion", "state"),
        set_key("fusion", {"state": "average"}),
    ),
    BadBody(
        "NaN reliability",
        "/sessions",
        ("body", "sensors", 0, "reliability"),
        raw=json.dumps(SESSION_CONFIG).replace('"reliability": 0.9', '"reliability": NaN'),
    ),
    # --- stateless association and WebSocket messages
    BadBody("unknown method", "/associate", ("body", "method"), set_key("method", "jpda")),
    BadBody(
        "mixed state dims",
        "/associate",
        ("body", "incoming", 0, "state"),
        set_key("incoming", [{"id": "x", "state": [1.0, 2.0], "covariance": [[1, 0], [0, 1]]}]),
    ),
    BadBody("message without type", "/message", ("body",), lambda body: body.pop("type")),
    BadBody("message of unknown type", "/message", ("body",), set_key("type", "hello")),
]

TEMPLATES: dict[str, Body] = {
    "/tracks": TRACK_REPORT,
    "/detections": DETECTION_REPORT,
    "/sessions": SESSION_CONFIG,
    "/associate": ASSOCIATE,
    "/message": {"type": "tracks", "ref": "r-1", **TRACK_REPORT},
}


@dataclass(frozen=True)
class RealApp:
    """The application in process, with one session whose state no bad row may change."""

    client: TestClient
    sid: str
    headers: dict[str, str]

    def path(self, route: str) -> str:
        return {
            "/sessions": "/v1/sessions",
            "/tracks": f"/v1/sessions/{self.sid}/tracks",
            "/detections": f"/v1/sessions/{self.sid}/detections",
            "/associate": "/v1/associate",
            "/message": f"/v1/sessions/{self.sid}/stream",
        }[route]

    def send(self, route: str, text: str) -> tuple[int, str, Body]:
        """(status, content type, problem) of ``text`` sent to ``route``."""
        if route == "/message":
            with self.client.websocket_connect(self.path(route), headers=self.headers) as ws:
                assert ws.receive_json()["type"] == "ack"
                ws.send_text(text)
                answer = ws.receive_json()
            assert answer["type"] == "error", answer
            problem: Body = answer["problem"]
            return int(problem["status"]), "application/problem+json", problem
        response = self.client.post(
            self.path(route),
            content=text,
            headers={"Content-Type": "application/json", **self.headers},
        )
        return response.status_code, response.headers["content-type"], response.json()


def session_of(client: TestClient) -> tuple[str, dict[str, str]]:
    created = client.post("/v1/sessions", json=SESSION_CONFIG)
    assert created.status_code == 201, created.text
    return created.json()["id"], {"Authorization": f"Bearer {created.json()['token']}"}


@pytest.fixture(scope="module")
def real_app() -> Iterator[RealApp]:
    with TestClient(create_app(make_settings()), raise_server_exceptions=False) as client:
        sid, headers = session_of(client)
        yield RealApp(client, sid, headers)


def test_the_table_is_large_enough() -> None:
    assert len(ROWS) >= 25
    assert len({row.name for row in ROWS}) == len(ROWS)


@pytest.mark.parametrize("route", sorted(set(TEMPLATES) - {"/message"}))
def test_templates_are_valid(real_app: RealApp, route: str) -> None:
    sid, headers = session_of(real_app.client)  # a fresh session: the inputs do not meet
    fresh = RealApp(real_app.client, sid, headers)
    response = real_app.client.post(fresh.path(route), json=TEMPLATES[route], headers=headers)
    assert response.status_code in (200, 201), response.text


def test_the_message_template_is_valid(real_app: RealApp) -> None:
    sid, headers = session_of(real_app.client)
    with real_app.client.websocket_connect(f"/v1/sessions/{sid}/stream", headers=headers) as ws:
        assert ws.receive_json()["type"] == "ack"
        ws.send_text(json.dumps(TEMPLATES["/message"]))
        assert ws.receive_json()["type"] == "result"


@pytest.mark.parametrize("row", ROWS, ids=[row.name for row in ROWS])
def test_bad_body_is_422_problem_naming_the_field(real_app: RealApp, row: BadBody) -> None:
    if row.raw is not None:
        text = row.raw
        assert text != json.dumps(TEMPLATES[row.route]), "the raw edit did not apply"
    else:
        assert row.edit is not None
        text = json.dumps(edited(TEMPLATES[row.route], row.edit))
    before = real_app.client.get(f"/v1/sessions/{real_app.sid}", headers=real_app.headers).json()
    status, content_type, problem = real_app.send(row.route, text)
    assert status == 422, problem
    assert content_type.startswith("application/problem+json")
    assert problem["type"] in (
        "urn:credal-fusion:problem:validation-error",
        "urn:credal-fusion:problem:limit-exceeded",
    )
    assert problem["status"] == 422
    assert problem["instance"] == real_app.path(row.route)
    locations = [tuple(error["loc"]) for error in problem["errors"]]
    expected = row.loc if row.route != "/message" else row.loc[1:]  # a message has no "body"
    assert any(location[: len(expected)] == expected for location in locations), (
        expected,
        problem["errors"],
    )
    assert all(error["pointer"].startswith("#") and error["detail"] for error in problem["errors"])
    assert not any(error["detail"].startswith("Value error") for error in problem["errors"])
    assert not any("tuple" in error["detail"].lower() for error in problem["errors"])  # wire words
    assert "invalid field" in problem["detail"]
    after = real_app.client.get(f"/v1/sessions/{real_app.sid}", headers=real_app.headers).json()
    assert after["seq"] == before["seq"] and after["counts"] == before["counts"]
