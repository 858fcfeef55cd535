"""Tenants and their quotas (issue 28): who may create sessions, and what one tenant can spend.

The real application in process (memory store unless said), and the stores'
tenant counts on every store (Redis: the real server).
"""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from contextlib import ExitStack
from datetime import UTC, datetime
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from app.cluster.quotas import open_quotas
from app.http.errors import LimitExceeded
from app.main import create_app
from app.stores import SessionRecord, Store
from tests.api.conftest import make_settings
from tests.api.examples import SESSION_CONFIG
from tests.api.redis_support import redis_store
from tests.api.scenario import track_report
from tests.api.test_stores import STORE_KINDS, open_kind

ALPHA = "alpha-key-0123456789abcdefghijklmnopqrstuvwxyz"
BETA = "beta-key-0123456789abcdefghijklmnopqrstuvwxyz0"
KEYS = f"alpha:{ALPHA},beta:{BETA}"


def bearer(token: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {token}"}


@pytest.fixture
def keyed() -> Iterator[TestClient]:
    """A service that needs API keys (as on any non-loopback host)."""
    settings = make_settings(access="keys", api_keys=KEYS, tenant_max_sessions=2)
    with TestClient(create_app(settings), raise_server_exceptions=False) as client:
        yield client


def test_auto_access_is_open_on_loopback_only() -> None:
    assert make_settings().open_access()
    assert make_settings(host="::1").open_access()
    assert not make_settings(host="0.0.0.0").open_access()
    assert not make_settings(host="192.0.2.7").open_access()
    assert make_settings(host="0.0.0.0", access="open").open_access()


def test_in_keys_mode_only_a_key_creates_a_session(keyed: TestClient) -> None:
    missing = keyed.post("/v1/sessions", json=SESSION_CONFIG)
    assert missing.status_code == 401
    assert "API key" in missing.json()["detail"]
    created = keyed.post("/v1/sessions", json=SESSION_CONFIG, headers=bearer(ALPHA))
    assert created.status_code == 201
    token = created.json()["token"]
    # a session's token is no key: it opens its session, it creates nothing
    assert keyed.post("/v1/sessions", json=SESSION_CONFIG, headers=bearer(token)).status_code == 401
    assert (
        keyed.get(f"/v1/sessions/{created.json()['id']}", headers=bearer(token)).status_code == 200
    )
    body = {"known": [], "incoming": []}
    assert keyed.post("/v1/associate", json=body).status_code == 401
    assert keyed.post("/v1/associate", json=body, headers=bearer(BETA)).status_code == 200


def test_a_tenant_at_its_session_quota_denies_no_other(keyed: TestClient) -> None:
    """Issue 28: one anonymous client took every session slot for an hour."""
    made = [
        keyed.post("/v1/sessions", json=SESSION_CONFIG, headers=bearer(ALPHA)) for _ in range(2)
    ]
    assert [answer.status_code for answer in made] == [201, 201]
    refused = keyed.post("/v1/sessions", json=SESSION_CONFIG, headers=bearer(ALPHA))
    assert refused.status_code == 429
    problem = refused.json()
    assert problem["limit"] == "tenant_max_sessions" and problem["maximum"] == 2
    assert int(refused.headers["Retry-After"]) == problem["retry_after"] > 0
    assert keyed.post("/v1/sessions", json=SESSION_CONFIG, headers=bearer(BETA)).status_code == 201
    first = made[0].json()
    deleted = keyed.delete(f"/v1/sessions/{first['id']}", headers=bearer(first["token"]))
    assert deleted.status_code == 204
    assert keyed.post("/v1/sessions", json=SESSION_CONFIG, headers=bearer(ALPHA)).status_code == 201


def test_the_service_wide_session_limit_says_when_to_retry() -> None:
    settings = make_settings(max_sessions=1)
    with TestClient(create_app(settings), raise_server_exceptions=False) as client:
        assert client.post("/v1/sessions", json=SESSION_CONFIG).status_code == 201
        refused = client.post("/v1/sessions", json=SESSION_CONFIG)
        assert refused.status_code == 429 and refused.json()["limit"] == "max_sessions"
        assert int(refused.headers["Retry-After"]) > 0


def test_inputs_per_second_are_the_tenants_whichever_token_sends_them() -> None:
    """Two sessions of one tenant share its input rate (3/s; inputs alternate between them until
    one is refused: faster than 3/s on any machine); a refusal applies nothing."""
    settings = make_settings(tenant_inputs_per_second=3, rate_limit="none")
    with TestClient(create_app(settings), raise_server_exceptions=False) as client:
        sessions = [client.post("/v1/sessions", json=SESSION_CONFIG).json() for _ in range(2)]
        accepted = [0, 0]
        for index in range(50):
            session = sessions[index % 2]
            answer = client.post(
                f"/v1/sessions/{session['id']}/tracks",
                json=track_report("radar-1", 10.0 + index, seed=index),
                headers=bearer(session["token"]),
            )
            if answer.status_code != 200:
                break
            accepted[index % 2] += 1
        assert answer.status_code == 429, answer.text
        assert answer.json()["limit"] == "tenant_inputs_per_second"
        assert "Retry-After" in answer.headers
        assert min(accepted) >= 1  # both tokens spent the one budget
        refused = sessions[index % 2]
        summary = client.get(f"/v1/sessions/{refused['id']}", headers=bearer(refused["token"]))
        assert summary.json()["seq"] == accepted[index % 2]  # the refused input was not applied


def test_work_per_minute_is_checked_before_the_work() -> None:
    """A 20-track list on an empty session is 20 × (0 + 1) work units, the next one 20 × (the
    live fused tracks + 1); the budget is 30."""
    settings = make_settings(tenant_work_per_minute=30, rate_limit="none")
    with TestClient(create_app(settings), raise_server_exceptions=False) as client:
        session = client.post("/v1/sessions", json=SESSION_CONFIG).json()
        path, headers = f"/v1/sessions/{session['id']}/tracks", bearer(session["token"])
        report = track_report("radar-1", 1.0, seed=1, targets=20)
        assert client.post(path, json=report, headers=headers).status_code == 200
        again = client.post(
            path, json=track_report("radar-1", 2.0, seed=2, targets=20), headers=headers
        )
        assert again.status_code == 429
        problem = again.json()
        summary = client.get(f"/v1/sessions/{session['id']}", headers=headers).json()
        live = sum(count for status, count in summary["counts"].items() if status != "terminated")
        assert problem["limit"] == "tenant_work_per_minute"
        assert problem["actual"] == 20 * (live + 1) > 30 - 20
        assert summary["seq"] == 1


def test_redis_quotas_are_shared_by_the_instances() -> None:
    """Two instances' quota counters in one Redis: their charges add up."""
    with redis_store("quotas") as store:
        first, second = (open_quotas(store, 100, 10) for _ in range(2))

        async def charges() -> None:
            await first.charge("key:alpha", 6)
            with pytest.raises(LimitExceeded) as refused:
                await second.charge("key:alpha", 5)
            assert refused.value.extensions["limit"] == "tenant_work_per_minute"
            await second.charge("key:beta", 5)  # another tenant, its own budget

        asyncio.run(charges())


@pytest.mark.parametrize("kind", STORE_KINDS)
def test_stores_count_each_tenants_sessions_in_the_creating_step(kind: str, tmp_path: Path) -> None:
    with ExitStack() as resources:
        store: Store = open_kind(kind, tmp_path, resources)

        def create(session_id: str, tenant: str) -> None:
            record = SessionRecord(
                id=session_id,
                config={"state": {"dim": 4}},
                token_hash="sha256:ab",
                created_at=datetime.now(UTC),
                tenant=tenant,
            )
            store.create_session(record, max_sessions=10, max_tenant_sessions=2)

        create("a1", "key:alpha")
        create("a2", "key:alpha")
        with pytest.raises(LimitExceeded) as refused:
            create("a3", "key:alpha")
        assert refused.value.extensions["limit"] == "tenant_max_sessions"
        create("b1", "key:beta")
        assert store.get_session("b1") is not None
        assert store.get_session("b1").tenant == "key:beta"  # type: ignore[union-attr]
        store.delete_session("a1")
        create("a3", "key:alpha")


@pytest.mark.parametrize(
    ("secret", "problem"),
    [(" " * 40, "visible ASCII"), ("é" * 40, "visible ASCII"), ("short", "at least 32")],
)
def test_secrets_are_long_visible_ascii(secret: str, problem: str) -> None:
    """Issue 28: 32 spaces passed as an admin token; a non-ASCII one never matched."""
    with pytest.raises(ValueError, match=problem):
        make_settings(admin_token=secret)
    with pytest.raises(ValueError, match=problem):
        make_settings(api_keys=f"alpha:{secret}x")
