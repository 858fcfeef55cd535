"""Bearer tokens: hashed at rest, one session's token never opens another, the admin token opens all."""

from __future__ import annotations

import base64
import hashlib
import hmac
import re
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from app.http.security import hash_token, is_admin_token, issue_token, token_matches
from app.main import create_app
from tests.api.conftest import ADMIN_TOKEN, make_settings
from tests.api.examples import SESSION_CONFIG


def bearer(token: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {token}"}


def create_session(client: TestClient) -> tuple[str, str]:
    response = client.post("/v1/sessions", json=SESSION_CONFIG)
    assert response.status_code == 201, response.text
    created = response.json()
    return created["id"], created["token"]


def test_tokens_are_random_and_hash_compare() -> None:
    first, second = issue_token(), issue_token()
    assert first != second and len(first) >= 40
    stored = hash_token(first)
    assert stored.startswith("sha256:") and first not in stored
    assert token_matches(first, stored)
    assert not token_matches(second, stored)
    assert not is_admin_token(first, None)
    assert is_admin_token(first, first)


def test_token_check_uses_constant_time_compare(monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[tuple[bytes, bytes]] = []
    real = hmac.compare_digest

    def spy(left: bytes, right: bytes) -> bool:
        calls.append((left, right))
        return real(left, right)

    monkeypatch.setattr("app.http.security.hmac.compare_digest", spy)
    token = issue_token()
    assert token_matches(token, hash_token(token))
    assert calls and all(token.encode() not in side for pair in calls for side in pair)


def test_create_returns_token_once_and_resolved_config(client: TestClient) -> None:
    response = client.post("/v1/sessions", json=SESSION_CONFIG)
    assert response.status_code == 201
    created = response.json()
    assert set(created) == {"id", "token", "config", "created_at", "sites", "warnings"}
    assert created["config"]["association"]["options"]["alpha"] == 1.0
    assert created["config"]["tracking"]["association"]["method"] == "gnn"
    listed = client.get("/v1/sessions", headers=bearer(ADMIN_TOKEN)).json()
    assert created["token"] not in str(listed)


def test_session_routes_need_the_sessions_own_token(client: TestClient) -> None:
    first, first_token = create_session(client)
    second, second_token = create_session(client)
    events = f"/v1/sessions/{first}/events"

    missing = client.get(events)
    assert missing.status_code == 401
    assert missing.headers["content-type"].startswith("application/problem+json")
    assert missing.headers["www-authenticate"].startswith("Bearer")

    assert client.get(events, headers={"Authorization": f"Basic {first_token}"}).status_code == 401
    # a token that does not open the session: 404 as for an unknown one (no existence oracle)
    forged = client.get(events, headers=bearer("not-a-token"))
    unknown = client.get("/v1/sessions/0123abcd/events", headers=bearer("not-a-token"))
    assert forged.status_code == unknown.status_code == 404
    assert forged.json()["title"] == unknown.json()["title"]
    other = client.get(events, headers=bearer(second_token))
    assert other.status_code == 404
    assert other.json()["type"] == "urn:credal-fusion:problem:session-not-found"

    assert client.get(events, headers=bearer(first_token)).status_code == 200
    assert client.get(events, headers=bearer(ADMIN_TOKEN)).status_code == 200
    assert (
        client.get(f"/v1/sessions/{second}/events", headers=bearer(second_token)).status_code == 200
    )


def test_unknown_session_is_404(client: TestClient) -> None:
    response = client.get("/v1/sessions/0123abcd/events", headers=bearer(ADMIN_TOKEN))
    assert response.status_code == 404
    assert response.json()["type"] == "urn:credal-fusion:problem:session-not-found"


def test_listing_is_admin_only(client: TestClient) -> None:
    sid, token = create_session(client)
    assert client.get("/v1/sessions").status_code == 401
    refused = client.get("/v1/sessions", headers=bearer(token))
    assert refused.status_code == 403
    assert "environment variable CREDAL_ADMIN_TOKEN" in refused.json()["detail"]
    listed = client.get("/v1/sessions", headers=bearer(ADMIN_TOKEN))
    assert listed.status_code == 200
    assert [item["id"] for item in listed.json()["sessions"]] == [sid]


def test_without_admin_token_configured_no_token_is_admin() -> None:
    with TestClient(
        create_app(make_settings(admin_token=None)), raise_server_exceptions=False
    ) as client:
        assert client.get("/v1/sessions", headers=bearer("")).status_code == 401
        refused = client.get("/v1/sessions", headers=bearer("None"))
        assert refused.status_code == 403
        assert (
            "has none: start it with the environment variable CREDAL_ADMIN_TOKEN"
            in (refused.json()["detail"])
        )


def test_delete_ends_the_session_and_its_token(client: TestClient) -> None:
    sid, token = create_session(client)
    assert client.delete(f"/v1/sessions/{sid}", headers=bearer(token)).status_code == 204
    assert client.get(f"/v1/sessions/{sid}/events", headers=bearer(token)).status_code == 404
    assert client.delete(f"/v1/sessions/{sid}", headers=bearer(ADMIN_TOKEN)).status_code == 404


def test_tokens_are_hashed_at_rest_in_sqlite(tmp_path: Path) -> None:
    database = tmp_path / "sessions.db"
    settings = make_settings(store=f"sqlite:{database}")
    with TestClient(create_app(settings), raise_server_exceptions=False) as client:
        sid, token = create_session(client)
    raw = b"".join(
        path.read_bytes() for path in tmp_path.iterdir() if path.name.startswith("sessions.db")
    )
    assert token.encode() not in raw
    assert hash_token(token).encode() in raw
    with TestClient(create_app(settings), raise_server_exceptions=False) as reopened:
        assert reopened.get(f"/v1/sessions/{sid}/events", headers=bearer(token)).status_code == 200


def test_limits_name_the_setting(client: TestClient) -> None:
    too_many = dict(
        SESSION_CONFIG, sensors=[dict(SESSION_CONFIG["sensors"][0], id=f"s{i}") for i in range(65)]
    )
    response = client.post("/v1/sessions", json=too_many)
    assert response.status_code == 422
    problem = response.json()
    assert (
        problem["limit"] == "max_sensors" and problem["maximum"] == 64 and problem["actual"] == 65
    )


def test_session_count_limit() -> None:
    with TestClient(
        create_app(make_settings(max_sessions=1)), raise_server_exceptions=False
    ) as client:
        create_session(client)
        response = client.post("/v1/sessions", json=SESSION_CONFIG)
        assert response.status_code == 429
        assert response.json()["limit"] == "max_sessions"


def test_no_token_starts_with_a_dash_that_a_command_line_would_read_as_an_option() -> None:
    # one url-safe token in 64 would (2 000 tokens: all but certain to meet one)
    assert not any(issue_token().startswith("-") for _ in range(2000))


def test_answers_are_not_sniffed_nor_cached(client: TestClient) -> None:
    """Issue 28: the answer carrying a token had no Cache-Control: no-store; nothing sent nosniff."""
    created = client.post("/v1/sessions", json=SESSION_CONFIG)
    assert created.headers["cache-control"] == "no-store"
    assert created.headers["x-content-type-options"] == "nosniff"
    refused = client.post("/v1/sessions", json={})
    assert refused.headers["cache-control"] == "no-store"
    assert client.get("/healthz").headers["x-content-type-options"] == "nosniff"


def test_pages_run_only_their_own_scripts_and_cannot_be_framed(client: TestClient) -> None:
    """Issue 28: the viewer allowed any inline script and framing."""
    for page in ("/", "/docs", "/redoc"):
        answer = client.get(page)
        policy = dict(
            part.strip().split(" ", 1)
            for part in answer.headers["content-security-policy"].split(";")
        )
        assert "'unsafe-inline'" not in policy["script-src"], page
        assert policy["frame-ancestors"] == "'none'" and answer.headers["x-frame-options"] == "DENY"
        inline = re.findall(r"<script>(.*?)</script>", answer.text, re.DOTALL)
        digests = {
            "'sha256-" + base64.b64encode(hashlib.sha256(script.encode()).digest()).decode() + "'"
            for script in inline
        }
        assert digests <= set(policy["script-src"].split()), page
