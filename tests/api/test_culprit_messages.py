"""Refusals that name the real culprit, through a live server: a state and a covariance of
different lengths say which shape is expected and why; a flat covariance is one error that
says rows are expected (not one "not a list" per number). Nothing is applied."""

from __future__ import annotations

from typing import Any

import httpx

from tests.api.conftest import LiveServer

STATE = {"dim": 4, "position": [0, 2], "velocity": [1, 3]}


def identity(size: int) -> list[list[float]]:
    return [[1.0 if row == col else 0.0 for col in range(size)] for row in range(size)]


def refused(server: LiveServer, track: dict[str, Any]) -> dict[str, Any]:
    with httpx.Client(base_url=server.url) as client:
        created = client.post("/v1/sessions", json={"state": STATE}).json()
        headers = {"Authorization": f"Bearer {created['token']}"}
        body = {"sensor": "a", "time": 1.0, "tracks": [{"id": "t1", **track}]}
        answer = client.post(f"/v1/sessions/{created['id']}/tracks", json=body, headers=headers)
        assert answer.status_code == 422, answer.text
        assert answer.headers["content-type"] == "application/problem+json"
        summary = client.get(f"/v1/sessions/{created['id']}", headers=headers).json()
        assert summary["seq"] == 0  # nothing applied
        problem: dict[str, Any] = answer.json()
        return problem


def test_a_6_element_state_with_a_4x4_covariance_names_the_shape_mismatch(
    live_server: LiveServer,
) -> None:
    problem = refused(live_server, {"state": [0.0] * 6, "covariance": identity(4)})
    assert [(e["pointer"], e["detail"]) for e in problem["errors"]] == [
        (
            "#/tracks/0/covariance",
            "covariance must be a list of 6 rows of 6 to match the 6-element state; "
            "got 4 rows of 4 (or the state must have 4 elements)",
        )
    ]


def test_a_flat_covariance_is_one_error_asking_for_rows(live_server: LiveServer) -> None:
    flat = [value for row in identity(4) for value in row]
    problem = refused(live_server, {"state": [0.0] * 4, "covariance": flat})
    assert [(e["pointer"], e["detail"]) for e in problem["errors"]] == [
        (
            "#/tracks/0/covariance",
            "must be a list of 4 rows of 4 (each row a list); got a flat list of 16 entries",
        )
    ]
    assert "error_count" not in problem


def test_a_ragged_covariance_names_its_short_row(live_server: LiveServer) -> None:
    ragged: list[list[float]] = identity(4)
    ragged[2] = ragged[2][:3]
    problem = refused(live_server, {"state": [0.0] * 4, "covariance": ragged})
    assert [e["detail"] for e in problem["errors"]] == [
        "covariance must be a list of 4 rows of 4 to match the 4-element state; row 2 has 3 entries"
    ]
