"""The input kinds are one registry (app/inputs): a kind added there is served everywhere.

A toy decoded kind (``xy``: text lines ``x y``, a blank line between scans)
registered here, and nowhere else, gets its ``POST …/xy`` route (in
openapi.json), its WebSocket binary message, and its inputs applied and
logged as the ``detections`` they decode into: the results equal those of
the same detections posted as JSON. No ``isinstance`` on an input kind
remains outside ``app/inputs``.
"""

from __future__ import annotations

import ast
import contextlib
import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any, ClassVar

from fastapi.testclient import TestClient

from api_schemas.base import Identifier, WireModel
from app.inputs import DECODED_KINDS, Decoded, DecodedKind, Input, SessionView, input_kind
from app.main import create_app
from tests.api.conftest import make_settings

ROOT = Path(__file__).resolve().parents[2]
CONFIG = {
    "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
    "sensors": [{"id": "cam", "measurement": {"r": [[4.0, 0.0], [0.0, 4.0]]}}],
}
SCANS = [[(100.0 + 10.0 * k, 50.0 - 5.0 * k), (900.0, 400.0 + 3.0 * k)] for k in range(6)]


class XYParameters(WireModel):
    sensor: Identifier


class XYAnswer(WireModel):
    lines: int
    results: list[dict[str, Any]]


class XY(DecodedKind[XYParameters]):
    """Text lines ``x y``; a line ``t=<time>`` starts a scan."""

    tag = "xy"
    media_type = "text/plain"
    parameters = XYParameters
    answer_model = XYAnswer
    summary = "x y lines"
    description: ClassVar[str] = "Lines of x y → detections."

    def decode(self, data: bytes, parameters: XYParameters, session: SessionView) -> Decoded:
        scans: list[dict[str, Any]] = []
        lines = data.decode().splitlines()
        for line in lines:
            if line.startswith("t="):
                scans.append(
                    {"sensor": parameters.sensor, "time": float(line[2:]), "detections": []}
                )
            elif line.strip():
                scans[-1]["detections"].append({"z": [float(value) for value in line.split()]})
        detections = input_kind("detections")
        inputs = tuple(Input(detections, detections.parse(scan)) for scan in scans)
        for made in inputs:
            made.check(session.config)
        return Decoded(inputs, {"lines": len(lines)})


@contextlib.contextmanager
def registered(kind: DecodedKind[Any]) -> Iterator[None]:
    DECODED_KINDS[kind.tag] = kind
    try:
        yield
    finally:
        del DECODED_KINDS[kind.tag]


def xy_text(scans: list[list[tuple[float, float]]], first: int = 0) -> bytes:
    lines = []
    for index, scan in enumerate(scans, start=first):
        lines.append(f"t={float(index)}")
        lines += [f"{x} {y}" for x, y in scan]
    return "\n".join(lines).encode()


def test_a_decoded_kind_registered_once_is_served_by_rest_websocket_log_and_openapi() -> None:
    with registered(XY()), TestClient(create_app(make_settings())) as client:
        assert "/v1/sessions/{sid}/xy" in client.get("/openapi.json").json()["paths"]
        posted, twin = (client.post("/v1/sessions", json=CONFIG).json() for _ in range(2))
        auth = {"Authorization": f"Bearer {posted['token']}"}
        answer = client.post(
            f"/v1/sessions/{posted['id']}/xy",
            params={"sensor": "cam"},
            content=xy_text(SCANS[:4]),
            headers={**auth, "content-type": "text/plain"},
        )
        assert answer.status_code == 200, answer.text
        assert answer.json()["lines"] == 4 * 3
        results = answer.json()["results"]
        with client.websocket_connect(
            f"/v1/sessions/{posted['id']}/stream?sensor=cam&decode=xy", headers=auth
        ) as socket:
            socket.receive_json()  # ack
            socket.send_bytes(xy_text(SCANS[4:], first=4))
            message = socket.receive_json()
        assert message["type"] == "xy_result"
        results += message["result"]["results"]

        twin_auth = {"Authorization": f"Bearer {twin['token']}"}
        expected = []
        for time, scan in enumerate(SCANS):
            body = {
                "sensor": "cam",
                "time": float(time),
                "detections": [{"z": [x, y]} for x, y in scan],
            }
            response = client.post(
                f"/v1/sessions/{twin['id']}/detections", json=body, headers=twin_auth
            )
            expected.append(response.json())
        assert json.dumps(results) == json.dumps(expected)
        events = client.get(f"/v1/sessions/{posted['id']}/events", headers=auth).json()["events"]
        assert [event["type"] for event in events] == ["detections"] * len(SCANS)


def test_a_bad_decoded_input_is_refused_whole() -> None:
    with registered(XY()), TestClient(create_app(make_settings())) as client:
        created = client.post("/v1/sessions", json=CONFIG).json()
        auth = {"Authorization": f"Bearer {created['token']}", "content-type": "text/plain"}
        body = xy_text(SCANS[:2]) + b"\n1 2 3"  # the second scan: a 3-D point in a 2-D session
        answer = client.post(
            f"/v1/sessions/{created['id']}/xy", params={"sensor": "cam"}, content=body, headers=auth
        )
        assert answer.status_code == 422
        assert answer.json()["errors"][0]["loc"] == ["body", "detections", 2, "z"]
        summary = client.get(f"/v1/sessions/{created['id']}", headers=auth).json()
        assert summary["seq"] == 0


INPUT_MODELS = {"TrackReport", "DetectionReport", "TracksMessage", "DetectionsMessage"}


def test_no_isinstance_on_an_input_kind_outside_app_inputs() -> None:
    for path in sorted((ROOT / "app").rglob("*.py")):
        if path.parent.name == "inputs":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "isinstance":
                named = {name.id for name in ast.walk(node.args[1]) if isinstance(name, ast.Name)}
                assert not named & INPUT_MODELS, f"{path.relative_to(ROOT)}:{node.lineno}"
