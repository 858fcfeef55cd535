"""Rate limits: per token (or client address), 429 problem+json naming the limit, Retry-After."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient
from starlette.testclient import WebSocketDenialResponse

from app.main import create_app
from app.settings import parse_rates
from tests.api.conftest import make_settings
from tests.api.examples import SESSION_CONFIG

RATE = "3/minute"


@pytest.fixture
def limited() -> Iterator[TestClient]:
    settings = make_settings(rate_limit=RATE)
    with TestClient(create_app(settings), raise_server_exceptions=False) as client:
        yield client


def create(client: TestClient) -> dict[str, str]:
    answer = client.post("/v1/sessions", json=SESSION_CONFIG)
    assert answer.status_code == 201, answer.text
    created = answer.json()
    return {"Authorization": f"Bearer {created['token']}", "sid": created["id"]}


def test_a_token_beyond_its_rate_gets_429_naming_the_limit(limited: TestClient) -> None:
    owner = create(limited)
    sid = owner.pop("sid")
    for _ in range(3):
        assert limited.get(f"/v1/sessions/{sid}", headers=owner).status_code == 200
    refused = limited.get(f"/v1/sessions/{sid}", headers=owner)
    assert refused.status_code == 429
    assert refused.headers["content-type"] == "application/problem+json"
    retry_after = int(refused.headers["Retry-After"])
    assert 1 <= retry_after <= 60
    problem = refused.json()
    assert problem["type"] == "urn:credal-fusion:problem:rate-limited"
    assert problem["limit"] == "rate_limit"
    assert problem["rate"] == "3 per 1 minute"
    assert problem["retry_after"] == retry_after
    assert "rate_limit" in problem["detail"] and "this token" in problem["detail"]


def test_verified_tokens_are_counted_apart_forged_ones_count_against_the_address(
    limited: TestClient,
) -> None:
    owner = create(limited)  # the address's first request
    sid = owner.pop("sid")
    for _ in range(3):
        assert limited.get(f"/v1/sessions/{sid}", headers=owner).status_code == 200
    assert limited.get(f"/v1/sessions/{sid}", headers=owner).status_code == 429
    forged = {"Authorization": "Bearer another-token"}
    assert (
        limited.get(f"/v1/sessions/{sid}", headers=forged).status_code == 403
    )  # the address's 2nd
    create(limited)  # the address's third request
    refused = limited.post("/v1/sessions", json=SESSION_CONFIG)
    assert refused.status_code == 429
    assert "this client address" in refused.json()["detail"]


def test_inventing_tokens_buys_no_requests(limited: TestClient) -> None:
    """Issue 14: ``Bearer fake<i>`` never saw a 429; each forged token had its own budget."""
    answers = [
        limited.get("/v1/sessions/x", headers={"Authorization": f"Bearer fake{index}"}).status_code
        for index in range(5)
    ]
    assert answers[:3] == [404, 404, 404]
    assert answers[3:] == [429, 429]


def test_liveness_is_never_limited(limited: TestClient) -> None:
    for _ in range(10):
        assert limited.get("/healthz").status_code == 200


def test_a_websocket_upgrade_counts_and_is_refused_beyond_the_rate(limited: TestClient) -> None:
    owner = create(limited)
    sid = owner.pop("sid")
    for _ in range(3):
        with limited.websocket_connect(f"/v1/sessions/{sid}/subscribe", headers=owner) as ws:
            assert ws.receive_json()["type"] == "ack"
    with (
        pytest.raises(WebSocketDenialResponse) as refused,
        limited.websocket_connect(f"/v1/sessions/{sid}/subscribe", headers=owner),
    ):
        pass
    assert refused.value.status_code == 429
    assert refused.value.json()["limit"] == "rate_limit"
    assert "Retry-After" in refused.value.headers


def test_rate_settings() -> None:
    assert [str(rate) for rate in parse_rates("50/second;2000/minute")] == [
        "50 per 1 second",
        "2000 per 1 minute",
    ]
    assert parse_rates("none") == []
    with pytest.raises(ValueError, match="rate_limit"):
        make_settings(rate_limit="as many as you like")
    assert make_settings().rate_limit == "1000/second"
