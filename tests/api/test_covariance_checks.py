"""Covariances are checked once per input, in a batch, yet every bad one is named by its field.

A track's covariance (a detection's ``r``) is checked square and of its
vector's size on its own; that it is symmetric positive definite is checked
for the whole list at once. These tests pin that the batch still names the
exact item at fault (``tracks[k].covariance``, ``detections[k].r``), lists
every bad item, and gives the per-matrix messages, over REST and WebSocket.
"""

from __future__ import annotations

import copy
import json
from typing import Any

import numpy as np
import pytest
from fastapi.testclient import TestClient
from pydantic import ValidationError

from api_schemas.associate import AssociateRequest
from api_schemas.linalg import SYMMETRY_TOLERANCE, check_covariance, covariance_problems
from api_schemas.reports import DetectionReport, SensorTrack, TrackReport
from app.inputs import client_messages
from tests.api.examples import TRACK_REPORT

NOT_DEFINITE = [[1, 2, 0, 0], [2, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
NOT_SYMMETRIC = [[4, 1, 0, 0], [0, 1, 0, 0], [0, 0, 4, 0], [0, 0, 0, 1]]
DEFINITE_MESSAGE = "covariance is not positive definite"
SYMMETRIC_MESSAGE = "covariance is not symmetric"
CONFIG = {"state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]}, "sensors": [{"id": "s"}]}


def track_list(count: int, bad: dict[int, list[list[float]]]) -> dict[str, Any]:
    """``count`` valid tracks of state dim 4, with the covariances in ``bad`` swapped in."""
    template = {key: value for key, value in TRACK_REPORT["tracks"][0].items()}
    template.pop("classification")
    tracks = []
    for index in range(count):
        track = copy.deepcopy(template) | {"id": f"t{index}"}
        if index in bad:
            track["covariance"] = bad[index]
        tracks.append(track)
    return {"sensor": "s", "time": 1.0, "tracks": tracks}


def located(error: ValidationError) -> list[tuple[tuple[str | int, ...], str]]:
    """Each error's location and message (without the numbers in parentheses)."""
    return [(tuple(entry["loc"]), str(entry["msg"]).split(" (")[0]) for entry in error.errors()]


# ------------------------------------------------------------------ the batch itself
def reference_problem(matrix: np.ndarray) -> str | None:
    """Independent verdict: symmetric within tolerance (relative to the largest entry), then
    every eigenvalue clearly positive (the generated matrices are far from the pivot tolerance)."""
    scale = float(np.abs(matrix).max())
    if float(np.abs(matrix - matrix.T).max()) > SYMMETRY_TOLERANCE * scale:
        return SYMMETRIC_MESSAGE
    if float(np.linalg.eigvalsh(matrix).min()) <= 0.0:
        return DEFINITE_MESSAGE
    return None


def test_the_batch_agrees_with_each_matrix_alone() -> None:
    rng = np.random.default_rng(7)
    matrices: list[list[list[float]]] = []
    expected: dict[int, str] = {}
    for index in range(60):
        size = int(rng.integers(1, 6))
        factor = rng.normal(size=(size, size))
        matrix = factor @ factor.T + np.eye(size)  # definite
        kind = index % 4
        if kind == 1:  # an eigenvalue of -1: symmetric, not definite
            vectors = np.linalg.qr(rng.normal(size=(size, size)))[0]
            values = np.abs(rng.normal(size=size)) + 0.5
            values[0] = -1.0
            matrix = vectors @ np.diag(values) @ vectors.T
            matrix = (matrix + matrix.T) / 2
        elif kind == 2 and size > 1:
            matrix[0, size - 1] += 0.5
        matrices.append(matrix.tolist())
        problem = reference_problem(matrix)
        if problem is not None:
            expected[index] = problem
    assert {1, 2} <= {index % 4 for index in expected}  # both kinds of problem occur
    found = covariance_problems(matrices)
    assert list(found) == sorted(expected)
    for index, problem in found.items():
        assert problem.startswith(expected[index])
        with pytest.raises(ValueError, match="covariance is not") as alone:
            check_covariance(matrices[index])
        assert str(alone.value) == problem


def test_no_matrix_no_problem() -> None:
    assert covariance_problems([]) == {}
    assert covariance_problems([[[2.0]], [[1.0, 0.0], [0.0, 1.0]]]) == {}


# ------------------------------------------------------------------ the models
@pytest.mark.parametrize("bad_index", [0, 3, 19])
def test_one_bad_covariance_is_named_by_its_index(bad_index: int) -> None:
    body = track_list(20, {bad_index: NOT_DEFINITE})
    with pytest.raises(ValidationError) as caught:
        TrackReport.model_validate_json(json.dumps(body))
    assert located(caught.value) == [(("tracks", bad_index, "covariance"), DEFINITE_MESSAGE)]


def test_every_bad_covariance_is_listed_in_order() -> None:
    body = track_list(8, {6: NOT_DEFINITE, 3: NOT_DEFINITE, 5: NOT_SYMMETRIC})
    body["tracks"][1] |= {"state": [1.0, 2.0], "covariance": [[1, 0], [0, -1]]}  # another size
    with pytest.raises(ValidationError) as caught:
        TrackReport.model_validate(body)
    locations = [loc for loc, _ in located(caught.value)]
    assert locations == [("tracks", index, "covariance") for index in (1, 3, 5, 6)]
    messages = [message for _, message in located(caught.value)]
    assert messages[0] == messages[1] == messages[3] == DEFINITE_MESSAGE
    assert messages[2].startswith(SYMMETRIC_MESSAGE)


def test_a_bad_covariance_and_a_duplicate_id_are_both_named() -> None:
    body = track_list(4, {2: NOT_DEFINITE})
    body["tracks"][3]["id"] = "t0"
    with pytest.raises(ValidationError) as caught:
        TrackReport.model_validate(body)
    assert [loc for loc, _ in located(caught.value)] == [
        ("tracks", 2, "covariance"),
        ("tracks", 3, "id"),
    ]


def test_a_track_alone_still_checks_the_covariance_size() -> None:
    with pytest.raises(ValidationError) as caught:
        SensorTrack.model_validate({"id": "x", "state": [1.0, 2.0], "covariance": [[1.0]]})
    assert located(caught.value) == [
        (
            ("covariance",),
            (
                "covariance must be a list of 2 rows of 2 to match the 2-element state; got 1 row of 1"
            ),
        )
    ]


def test_bad_detection_noise_is_named_by_its_index() -> None:
    identity = [[1, 0], [0, 1]]
    detections: list[dict[str, Any]] = [
        {"z": [1.0, 2.0], "r": identity},
        {"z": [1.0, 2.0]},
        {"z": [1.0, 2.0], "r": [[1, 0], [0, -1]]},
        {"z": [1.0, 2.0], "r": [[1, 0.5], [0, 1]]},
        {"z": [1.0], "r": [[-1]]},
    ]
    with pytest.raises(ValidationError) as caught:
        DetectionReport.model_validate({"sensor": "s", "time": 1.0, "detections": detections})
    assert [loc for loc, _ in located(caught.value)] == [
        ("detections", 2, "r"),
        ("detections", 3, "r"),
        ("detections", 4, "r"),
    ]


def test_associate_names_bad_covariances_on_each_side() -> None:
    known = track_list(3, {1: NOT_DEFINITE})["tracks"]
    incoming = track_list(2, {0: NOT_SYMMETRIC})["tracks"]
    with pytest.raises(ValidationError) as caught:
        AssociateRequest.model_validate({"known": known, "incoming": incoming})
    assert [loc for loc, _ in located(caught.value)] == [
        ("known", 1, "covariance"),
        ("incoming", 0, "covariance"),
    ]


def test_websocket_messages_are_checked_too() -> None:
    message = track_list(5, {4: NOT_DEFINITE}) | {"type": "tracks"}
    with pytest.raises(ValidationError) as caught:
        client_messages().validate_json(json.dumps(message))
    assert located(caught.value) == [(("tracks", "tracks", 4, "covariance"), DEFINITE_MESSAGE)]


# ------------------------------------------------------------------ through the service
def test_rest_and_stream_answer_with_the_field_path(client: TestClient) -> None:
    created = client.post("/v1/sessions", json=CONFIG).json()
    headers = {"Authorization": f"Bearer {created['token']}"}
    body = track_list(6, {3: NOT_DEFINITE, 5: NOT_SYMMETRIC})
    answer = client.post(f"/v1/sessions/{created['id']}/tracks", json=body, headers=headers)
    assert answer.status_code == 422
    assert answer.headers["content-type"].startswith("application/problem+json")
    errors = answer.json()["errors"]
    assert [error["loc"] for error in errors] == [
        ["body", "tracks", 3, "covariance"],
        ["body", "tracks", 5, "covariance"],
    ]
    assert [error["pointer"] for error in errors] == [
        "#/tracks/3/covariance",
        "#/tracks/5/covariance",
    ]
    with client.websocket_connect(
        f"/v1/sessions/{created['id']}/stream", headers=headers
    ) as stream:
        assert stream.receive_json()["type"] == "ack"
        stream.send_text(json.dumps(body | {"type": "tracks", "ref": "bad"}))
        refused = stream.receive_json()
        stream.send_text(json.dumps(track_list(6, {}) | {"type": "tracks", "ref": "good"}))
        accepted = stream.receive_json()
    assert refused["type"] == "error" and refused["ref"] == "bad"
    assert [error["loc"] for error in refused["problem"]["errors"]] == [
        ["tracks", 3, "covariance"],
        ["tracks", 5, "covariance"],
    ]
    assert accepted["type"] == "result" and accepted["result"]["seq"] == 1
