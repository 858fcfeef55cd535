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


API_KEY = "alpha-key-0123456789abcdefghijklmnopqrstuvwxyz"


@pytest.fixture
def keyed() -> Iterator[TestClient]:
    settings = make_settings(rate_limit=RATE, api_keys=f"alpha:{API_KEY}")
    with TestClient(create_app(settings), raise_server_exceptions=False) as client:
        yield client


def create(client: TestClient, **headers: str) -> dict[str, str]:
    answer = client.post("/v1/sessions", json=SESSION_CONFIG, headers=headers)
    assert answer.status_code == 201, answer.text
    created = answer.json()
    return {"Authorization": f"Bearer {created['token']}", "sid": created["id"]}


def test_a_tenant_beyond_its_rate_gets_429_naming_the_limit(keyed: TestClient) -> None:
    """The session's token spends its tenant's budget (the API key's that created it)."""
    owner = create(keyed, Authorization=f"Bearer {API_KEY}")  # the tenant's first request
    sid = owner.pop("sid")
    for _ in range(2):
        assert keyed.get(f"/v1/sessions/{sid}", headers=owner).status_code == 200
    refused = keyed.get(f"/v1/sessions/{sid}", headers=owner)
    assert refused.status_code == 429
    assert refused.headers["content-type"] == "application/problem+json"
    retry_after = int(refused.headers["Retry-After"])
    assert 1 <= retry_after <= 60
    problem = refused.json()
    assert problem["type"] == "urn:credal-fusion:problem:rate-limited"
    assert problem["limit"] == "rate_limit"
    assert problem["rate"] == "3 per 1 minute"
    assert problem["retry_after"] == retry_after
    assert "rate_limit" in problem["detail"] and "tenant 'key:alpha'" in problem["detail"]
    # the address without a key is another tenant, with its own budget
    assert keyed.post("/v1/sessions", json=SESSION_CONFIG).status_code == 201


def test_minting_tokens_buys_no_requests(limited: TestClient) -> None:
    """Issue 28: each session token had its own budget, and anyone could mint tokens; now every
    token of a tenant (here: of one client address) spends one budget."""
    first, second = create(limited), create(limited)  # the address's requests 1 and 2
    first_sid, second_sid = first.pop("sid"), second.pop("sid")
    assert limited.get(f"/v1/sessions/{first_sid}", headers=first).status_code == 200
    assert limited.get(f"/v1/sessions/{second_sid}", headers=second).status_code == 429
    forged = {"Authorization": "Bearer another-token"}
    refused = limited.get(f"/v1/sessions/{first_sid}", headers=forged)
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
    for _ in range(2):
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


def test_a_tenants_body_bytes_are_limited_before_the_body_is_read() -> None:
    settings = make_settings(rate_limit="none", tenant_body_bytes_per_second=2048)
    with TestClient(create_app(settings), raise_server_exceptions=False) as client:
        body = b"{" + b" " * 1400 + b"}"
        headers = {"Content-Type": "application/json"}
        assert client.post("/v1/sessions", content=body, headers=headers).status_code == 422
        refused = client.post("/v1/sessions", content=body, headers=headers)
        assert refused.status_code == 429
        assert refused.json()["limit"] == "tenant_body_bytes_per_second"
        assert int(refused.headers["Retry-After"]) >= 1
