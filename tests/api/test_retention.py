"""Bounded stores: a deleted session frees everything, logs are compacted behind snapshots,
a compacted history still replays, and a backend error is an outage, not a bug.

Every store kind runs on its real backend (a sqlite file, the real Redis).
Sizes are the store's own measure (:meth:`Store.usage`), checked against
counts and JSON lengths computed here with the json module.
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Iterator
from contextlib import ExitStack
from pathlib import Path

import httpx
import pytest

from app.http.errors import SessionNotFound, StoreUnavailable
from app.stores import MemoryStore, Snapshot, SqliteStore, Store
from app.stores.base import history
from tests.api.conftest import make_settings, serving
from tests.api.redis_support import remaining_keys
from tests.api.scenario import reports, session_config
from tests.api.test_stores import STORE_KINDS, now, open_kind, record

CYCLES = 20
INPUT = {"type": "tracks", "report": {"sensor": "radar-1", "tracks": [[1.5, 2.25]] * 20}}


@pytest.fixture(params=STORE_KINDS)
def store(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[Store]:
    with ExitStack() as resources:
        yield open_kind(request.param, tmp_path, resources)


def fill(store: Store, session_id: str, inputs: int, snapshot_at: int | None = None) -> None:
    store.create_session(record(session_id))
    for seq in range(1, inputs + 1):
        store.append(session_id, seq, INPUT | {"n": seq}, now())
        if seq == snapshot_at:
            store.save_snapshot(session_id, Snapshot(seq=seq, taken_at=now(), state={"n": seq}))


def test_a_deleted_session_leaves_nothing_in_the_store(store: Store) -> None:
    fill(store, "kept", 3)
    baseline = store.usage()
    assert (baseline.sessions, baseline.inputs, baseline.snapshots) == (1, 3, 0)
    for cycle in range(CYCLES):
        fill(store, f"gone-{cycle}", 10, snapshot_at=5)
        assert store.usage().inputs == 13 and store.usage().snapshots == 1
        assert store.delete_session(f"gone-{cycle}")
        with pytest.raises(SessionNotFound):
            store.load(f"gone-{cycle}")
    after = store.usage()
    assert (after.sessions, after.inputs, after.snapshots) == (1, 3, 0)
    assert after.bytes <= baseline.bytes  # sqlite: freed pages are reused, the rest identical


def test_memory_store_counts_exactly_the_json_it_keeps() -> None:
    store = MemoryStore()
    assert store.usage().bytes == 0
    fill(store, "s1", 4, snapshot_at=2)
    config = json.dumps(record().config, separators=(",", ":"), sort_keys=True)
    inputs = [
        json.dumps(INPUT | {"n": n}, separators=(",", ":"), sort_keys=True) for n in range(1, 5)
    ]
    assert store.usage().bytes == len(config) + sum(map(len, inputs)) + len('{"n":2}')
    store.compact("s1", 2)
    assert store.usage().bytes == len(config) + sum(map(len, inputs[2:])) + len('{"n":2}')
    store.delete_session("s1")
    assert store.usage().bytes == 0 and store.usage().sessions == 0


def test_redis_delete_unlinks_every_key_of_the_session(tmp_path: Path) -> None:
    with ExitStack() as resources:
        store = open_kind("redis", tmp_path, resources)
        prefix = store.keys.prefix  # type: ignore[attr-defined]
        fill(store, "s1", 5, snapshot_at=3)
        # index, tenants' counts, record, log, snapshots
        assert len(remaining_keys(prefix)) == 5
        store.delete_session("s1")
        assert remaining_keys(prefix) == []


def test_compaction_stops_at_the_latest_snapshot(store: Store) -> None:
    fill(store, "s1", 10)
    assert store.compact("s1", 8) == 0  # no snapshot: nothing may go
    store.save_snapshot("s1", Snapshot(seq=6, taken_at=now(), state={"n": 6}))
    assert store.compact("s1", 100) == 6
    assert [entry.seq for entry in store.entries("s1")] == [7, 8, 9, 10]
    assert store.usage().inputs == 4
    loaded = store.load("s1")
    assert loaded.snapshot is not None and loaded.snapshot.seq == 6
    assert [entry.seq for entry in loaded.entries] == [7, 8, 9, 10]
    store.append("s1", 11, INPUT, now())
    assert store.last_seq("s1") == 11
    with pytest.raises(SessionNotFound):
        store.compact("missing", 1)


def test_history_is_the_log_while_retained_then_the_snapshot_and_the_log_after_it(
    store: Store,
) -> None:
    fill(store, "s1", 10, snapshot_at=6)
    full = history(store, "s1", 0, 1000)
    assert full.snapshot is None and [entry.seq for entry in full.entries] == list(range(1, 11))
    store.compact("s1", 3)  # the log keeps 4..10
    kept = history(store, "s1", 3, 1000)
    assert kept.snapshot is None and [entry.seq for entry in kept.entries] == list(range(4, 11))
    paged = history(store, "s1", 4, 2)
    assert paged.snapshot is None and [entry.seq for entry in paged.entries] == [5, 6]
    for after in (0, 2):  # inputs 1..3 are gone: start from the snapshot
        compacted = history(store, "s1", after, 1000)
        assert compacted.snapshot is not None and compacted.snapshot.seq == 6
        assert compacted.snapshot.state == {"n": 6}
        assert [entry.seq for entry in compacted.entries] == [7, 8, 9, 10]
    assert history(store, "s1", 0, 2).entries[-1].seq == 8  # the page limit holds
    end = history(store, "s1", 10, 1000)
    assert end.snapshot is None and end.entries == []


def test_a_sqlite_error_is_an_outage_and_changes_nothing(tmp_path: Path) -> None:
    store = SqliteStore(tmp_path / "store.db")
    try:
        fill(store, "s1", 2)
        store._writer().execute("PRAGMA query_only = ON")  # writes fail as on a bad disk
        with pytest.raises(StoreUnavailable) as refused:
            store.append("s1", 3, INPUT, now())
        assert refused.value.status_code == 503 and refused.value.headers()["Retry-After"]
        assert isinstance(refused.value.__cause__, sqlite3.OperationalError)
        store._writer().execute("PRAGMA query_only = OFF")  # the disk is back
        assert store.last_seq("s1") == 2
        store.append("s1", 3, INPUT, now())
        assert [entry.seq for entry in store.entries("s1")] == [1, 2, 3]
    finally:
        store.close()


def gauge(metrics: str, name: str) -> float:
    line = next(line for line in metrics.splitlines() if line.startswith(f"{name} "))
    return float(line.split()[1])


def test_deleted_sessions_free_the_servers_store(tmp_path: Path) -> None:
    settings = make_settings(session_idle_seconds=3600, snapshot_every=4)
    with serving(settings) as server, httpx.Client(base_url=server.url, timeout=30) as client:
        empty = client.get("/metrics").text
        assert gauge(empty, "credal_store_bytes") == 0 and gauge(empty, "credal_store_inputs") == 0
        for _ in range(5):
            created = client.post("/v1/sessions", json=session_config()).json()
            headers = {"Authorization": f"Bearer {created['token']}"}
            for body in reports(6):
                answer = client.post(
                    f"/v1/sessions/{created['id']}/tracks", json=body, headers=headers
                )
                assert answer.status_code == 200, answer.text
            full = client.get("/metrics").text
            assert gauge(full, "credal_store_inputs") == 6 and gauge(full, "credal_store_bytes") > 0
            deleted = client.delete(f"/v1/sessions/{created['id']}", headers=headers)
            assert deleted.status_code == 204
            after = client.get("/metrics").text
            assert gauge(after, "credal_store_bytes") == 0
            assert gauge(after, "credal_store_inputs") == 0
