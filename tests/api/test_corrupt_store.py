"""One policy for a corrupt store (issue 28), on a real sqlite file and the real Redis.

Two sessions are stored through the service; one of them is damaged in the
store (each kind of corruption in turn) and the service restarted on it. It
must start, set the damaged session aside (quarantined: ``/readyz`` and
``/metrics`` say so), answer it with a 500 ``session-unreadable`` that names
it, says the fault is permanent (no ``Retry-After``) and quotes nothing
stored, serve the other session as before, and let the admin delete the
damaged one. A store whose file itself is damaged starts too, not ready and
saying why, never "retry in 2 s".
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any

import pytest
import redis
from fastapi.testclient import TestClient

from app.main import create_app
from app.settings import Settings
from tests.api.conftest import ADMIN_TOKEN, make_settings
from tests.api.examples import SESSION_CONFIG
from tests.api.redis_support import REDIS_URL, unique_prefix
from tests.api.scenario import track_report

MARKER = "STORED-TEXT-7f3a"
"""Put into every damaged value: no answer may quote it."""
ADMIN = {"Authorization": f"Bearer {ADMIN_TOKEN}"}


def bearer(session: dict[str, Any]) -> dict[str, str]:
    return {"Authorization": f"Bearer {session['token']}"}


@contextmanager
def service(settings: Settings) -> Iterator[TestClient]:
    with TestClient(create_app(settings), raise_server_exceptions=False) as client:
        yield client


def stored_sessions(settings: Settings, count: int = 2) -> list[dict[str, Any]]:
    """``count`` sessions with three inputs each (a snapshot after the second)."""
    with service(settings) as client:
        sessions = [client.post("/v1/sessions", json=SESSION_CONFIG).json() for _ in range(count)]
        for session in sessions:
            for index in range(3):
                answer = client.post(
                    f"/v1/sessions/{session['id']}/tracks",
                    json=track_report("radar-1", 10.0 + index, seed=index),
                    headers=bearer(session),
                )
                assert answer.status_code == 200, answer.text
    return sessions


def sqlite_kinds(path: Path) -> dict[str, Callable[[str], None]]:
    import sqlite3

    def execute(sql: str, *args: object) -> None:
        with sqlite3.connect(path) as connection:
            connection.execute(sql, args)

    return {
        "config": lambda sid: execute(
            "UPDATE sessions SET config = ? WHERE id = ?", '{"state": ' + MARKER, sid
        ),
        "input after the snapshot": lambda sid: execute(
            "UPDATE inputs SET input = ? WHERE session_id = ? AND seq = 3", MARKER + "{", sid
        ),
        "snapshot": lambda sid: execute(
            "UPDATE snapshots SET state = ? WHERE session_id = ?", "[" + MARKER, sid
        ),
        "engine state": lambda sid: execute(
            "UPDATE snapshots SET state = ? WHERE session_id = ?",
            f'{{"format": 1, "x": "{MARKER}"}}',
            sid,
        ),
        "creation time": lambda sid: execute(
            "UPDATE sessions SET created_at = ? WHERE id = ?", MARKER, sid
        ),
    }


def redis_kinds(client: redis.Redis, prefix: str) -> dict[str, Callable[[str], None]]:
    def key(sid: str, kind: str) -> str:
        return f"{prefix}:{{{sid}}}:{kind}"

    def bad_input(sid: str) -> None:
        entries = client.xrange(key(sid, "log"))
        client.delete(key(sid, "log"))  # the log written again, input 3 damaged
        for entry_id, fields in entries:
            damaged = {"received_at": MARKER, "input": MARKER}
            client.xadd(key(sid, "log"), damaged if entry_id == "3-0" else fields, id=entry_id)

    return {
        "config": lambda sid: client.hset(key(sid, "session"), "config", "{" + MARKER),
        "input after the snapshot": bad_input,
        "snapshot": lambda sid: client.hset(key(sid, "snapshots"), "2", MARKER),
        "missing token hash": lambda sid: client.hdel(key(sid, "session"), "token_hash"),
    }


@contextmanager
def store_settings(
    kind: str, tmp_path: Path
) -> Iterator[tuple[Settings, Callable[[str, str], None]]]:
    """Settings of a fresh store of ``kind``, and ``damage(session id, corruption kind)``."""
    if kind == "sqlite":
        path = tmp_path / "store.db"
        settings = make_settings(store=f"sqlite:{path}", snapshot_every=2, rate_limit="none")
        yield settings, lambda sid, corruption: sqlite_kinds(path)[corruption](sid)
        return
    prefix = unique_prefix("corrupt")
    client = redis.Redis.from_url(REDIS_URL, decode_responses=True)
    settings = make_settings(
        store=REDIS_URL, redis_prefix=prefix, snapshot_every=2, rate_limit="none"
    )
    try:
        yield settings, lambda sid, corruption: redis_kinds(client, prefix)[corruption](sid)
    finally:
        keys = list(client.scan_iter(match=f"{prefix}:*"))
        if keys:
            client.delete(*keys)
        client.close()


CORRUPTIONS = {
    "sqlite": list(sqlite_kinds(Path("unused"))),
    "redis": ["config", "input after the snapshot", "snapshot", "missing token hash"],
}


def assert_unreadable(answer: Any, sid: str) -> None:
    assert answer.status_code == 500, answer.text
    problem = answer.json()
    assert problem["type"] == "urn:credal-fusion:problem:session-unreadable"
    assert problem["session"] == sid and sid in problem["detail"]
    assert "Retry-After" not in answer.headers and "retry" not in problem
    assert MARKER not in answer.text


@pytest.mark.parametrize("kind", ["sqlite", "redis"])
def test_damaged_sessions_are_quarantined_and_the_rest_served(kind: str, tmp_path: Path) -> None:
    """One session damaged per kind of corruption, one intact, one restart."""
    corruptions = CORRUPTIONS[kind]
    with store_settings(kind, tmp_path) as (settings, damage):
        good, *bad = stored_sessions(settings, 1 + len(corruptions))
        for session, corruption in zip(bad, corruptions, strict=True):
            damage(session["id"], corruption)
        with service(settings) as client:
            ready = client.get("/readyz")
            assert ready.status_code == 200
            assert ready.json()["quarantined"] == sorted(session["id"] for session in bad)
            assert f"credal_sessions_quarantined {len(bad)}.0" in client.get("/metrics").text
            for session in bad:
                path = f"/v1/sessions/{session['id']}"
                assert_unreadable(client.get(path, headers=bearer(session)), session["id"])
                assert_unreadable(
                    client.post(
                        path + "/tracks",
                        json=track_report("radar-1", 20.0, seed=9),
                        headers=bearer(session),
                    ),
                    session["id"],
                )
            assert client.get(f"/v1/sessions/{good['id']}", headers=bearer(good)).json()["seq"] == 3
            later = client.post(
                f"/v1/sessions/{good['id']}/tracks",
                json=track_report("radar-1", 20.0, seed=9),
                headers=bearer(good),
            )
            assert later.status_code == 200 and later.json()["seq"] == 4
            listed = client.get("/v1/sessions", headers=ADMIN)
            assert listed.status_code == 200 and MARKER not in listed.text
            for session in bad:
                deleted = client.delete(f"/v1/sessions/{session['id']}", headers=ADMIN)
                assert deleted.status_code == 204
            assert client.get("/readyz").json()["quarantined"] == []


@pytest.mark.parametrize("kind", ["sqlite", "redis"])
def test_an_unreadable_old_input_quarantines_its_session_when_read(
    kind: str, tmp_path: Path
) -> None:
    """Input 1 is behind the snapshot: the session restores, and is set aside when its events
    page reads the damaged input (before: ``GET …/events`` answered 500 for ever)."""
    with store_settings(kind, tmp_path) as (settings, _):
        good, bad = stored_sessions(settings)
        if kind == "sqlite":
            import sqlite3

            path = settings.store.removeprefix("sqlite:")
            with sqlite3.connect(path) as connection:
                connection.execute(
                    "UPDATE inputs SET input = ? WHERE session_id = ? AND seq = 1",
                    (MARKER + "{", bad["id"]),
                )
        else:
            client = redis.Redis.from_url(REDIS_URL, decode_responses=True)
            log = f"{settings.redis_prefix}:{{{bad['id']}}}:log"
            entries = client.xrange(log)
            client.delete(log)
            client.xadd(
                log, {"received_at": entries[0][1]["received_at"], "input": MARKER}, id="1-0"
            )
            for entry_id, fields in entries[1:]:
                client.xadd(log, fields, id=entry_id)
            client.close()
        with service(settings) as client:
            assert client.get("/readyz").json()["quarantined"] == []
            events = client.get(f"/v1/sessions/{bad['id']}/events", headers=bearer(bad))
            assert_unreadable(events, bad["id"])
            assert client.get("/readyz").json()["quarantined"] == [bad["id"]]
            assert (
                client.get(f"/v1/sessions/{good['id']}/events", headers=bearer(good)).status_code
                == 200
            )


def test_a_damaged_sqlite_file_starts_not_ready_and_says_it_is_permanent(tmp_path: Path) -> None:
    """The file truncated to a third, its write-ahead log kept (before: 'ready', restoring
    nothing, 500 on /v1/sessions and /metrics; a damaged page: 503 'retry in 2 s')."""
    path = tmp_path / "store.db"
    settings = make_settings(store=f"sqlite:{path}", snapshot_every=2, rate_limit="none")
    with ExitStack():
        stored_sessions(settings)
        size = path.stat().st_size
        with path.open("r+b") as file:
            file.seek(size // 3)
            file.write(b"\xff" * 4096 + MARKER.encode())
            file.truncate()
        with service(settings) as client:
            ready = client.get("/readyz")
            assert ready.status_code == 503 and "Retry-After" not in ready.headers
            assert "damaged" in ready.json()["components"][0]["detail"]
            assert client.get("/metrics").status_code == 200
            listed = client.get("/v1/sessions", headers=ADMIN)
            assert listed.status_code == 500
            assert listed.json()["type"] == "urn:credal-fusion:problem:store-corrupt"
            assert "Retry-After" not in listed.headers and MARKER not in listed.text
            assert client.get("/healthz").status_code == 200
