"""The redis store on the real server: restart, key layout, JSON values, resends, snapshots."""

from __future__ import annotations

import json
import threading
from datetime import UTC, datetime

import pytest

from app.http.errors import SessionNotFound
from app.stores import RedisStore, SequenceConflict, SessionExists, SessionRecord, Snapshot
from tests.api.redis_support import REDIS_URL, redis_prefix, redis_store, remaining_keys


def now() -> datetime:
    return datetime.now(UTC)


def record(session_id: str = "s1") -> SessionRecord:
    return SessionRecord(
        id=session_id, config={"frame": ["car", "truck"]}, token_hash="sha256:cd", created_at=now()
    )


def test_a_new_store_object_sees_everything_and_goes_on() -> None:
    with redis_prefix("restart") as prefix:
        first = RedisStore(REDIS_URL, prefix=prefix)
        first.create_session(record("s1"))
        first.create_session(record("s2"))
        for seq in range(1, 8):
            first.append("s1", seq, {"n": seq}, now())
        first.save_snapshot("s1", Snapshot(seq=5, taken_at=now(), state={"tracks": [[1.0, 2.0]]}))
        first.delete_session("s2")
        first.close()
        with pytest.raises(RuntimeError, match="closed"):
            first.last_seq("s1")

        second = RedisStore(REDIS_URL, prefix=prefix)
        assert [session.id for session in second.list_sessions()] == ["s1"]
        restored = second.get_session("s1")
        assert restored is not None and restored.config == {"frame": ["car", "truck"]}
        assert restored.token_hash == "sha256:cd" and restored.created_at.tzinfo is not None
        loaded = second.load("s1")
        assert loaded.snapshot is not None and loaded.snapshot.seq == 5
        assert loaded.snapshot.state == {"tracks": [[1.0, 2.0]]}
        assert [entry.input["n"] for entry in loaded.entries] == [6, 7]
        assert second.last_seq("s1") == 7
        second.append("s1", 8, {"n": 8}, now())
        assert [entry.seq for entry in second.entries("s1")] == list(range(1, 9))
        second.create_session(record("s2"))  # a deleted session left nothing, its id included
        assert second.last_seq("s2") == 0 and second.entries("s2") == []
        with pytest.raises(SessionExists):
            second.create_session(record("s2"))
        second.close()


def test_keys_are_namespaced_json_and_purged() -> None:
    with redis_store("layout") as store:
        store.create_session(record())
        store.append("s1", 1, {"tracks": [{"id": "T1", "x": 0.5}]}, now())
        store.save_snapshot("s1", Snapshot(seq=1, taken_at=now(), state={"n": 1}))
        keys = set(remaining_keys(store.prefix))
        assert keys == {
            f"{store.prefix}:sessions",
            f"{store.prefix}:{{s1}}:session",
            f"{store.prefix}:{{s1}}:log",
            f"{store.prefix}:{{s1}}:snapshots",
            f"{store.prefix}:tenant-sessions",
        }
        client = store.client
        assert json.loads(client.hget(store.keys.session("s1"), "config")) == record().config
        [(entry_id, fields)] = client.xrange(store.keys.log("s1"))
        assert entry_id == "1-0"
        assert json.loads(fields["input"]) == {"tracks": [{"id": "T1", "x": 0.5}]}
        snapshot = json.loads(client.hget(store.keys.snapshots("s1"), "1"))
        assert snapshot["state"] == {"n": 1} and snapshot["seq"] == 1
        assert store.purge() == 5
        assert remaining_keys(store.prefix) == []


def test_prefixes_isolate_deployments() -> None:
    with redis_store("one") as one, redis_store("two") as two:
        one.create_session(record("shared-id"))
        assert two.get_session("shared-id") is None and two.count_sessions() == 0
        two.create_session(record("shared-id"))
        one.append("shared-id", 1, {"from": "one"}, now())
        assert two.last_seq("shared-id") == 0


def test_a_resent_append_is_accepted_once() -> None:
    with redis_store("resend") as store:
        store.create_session(record())
        received = now()
        store.append("s1", 1, {"n": 1}, received)
        store.append("s1", 1, {"n": 1}, received)  # the reply was lost, the client resends
        assert [(entry.seq, entry.input) for entry in store.entries("s1")] == [(1, {"n": 1})]
        with pytest.raises(SequenceConflict) as other:
            store.append("s1", 1, {"n": "other"}, received)
        assert other.value.expected == 2
        with pytest.raises(SequenceConflict):
            store.append("s1", 1, {"n": 1}, now())  # same input, another reception: not a resend


def test_two_latest_snapshots_are_kept() -> None:
    with redis_store("snapshots") as store:
        store.create_session(record())
        for seq in range(1, 11):
            store.append("s1", seq, {"n": seq}, now())
            if seq % 3 == 0:
                store.save_snapshot("s1", Snapshot(seq=seq, taken_at=now(), state={"at": seq}))
        assert sorted(store.client.hkeys(store.keys.snapshots("s1")), key=int) == ["6", "9"]
        loaded = store.load("s1")
        assert loaded.snapshot is not None and loaded.snapshot.state == {"at": 9}
        assert [entry.seq for entry in loaded.entries] == [10]
        store.save_snapshot("s1", Snapshot(seq=3, taken_at=now(), state={"at": "late"}))
        assert store.load("s1").snapshot.seq == 9


def test_a_snapshot_ahead_of_the_log_moves_last_seq() -> None:
    with redis_store("ahead") as store:
        store.create_session(record())
        store.save_snapshot("s1", Snapshot(seq=4, taken_at=now(), state={}))
        assert store.last_seq("s1") == 4
        with pytest.raises(SequenceConflict):
            store.append("s1", 1, {}, now())
        store.append("s1", 5, {}, now())
        assert [entry.seq for entry in store.load("s1").entries] == [5]


def test_a_deleted_session_refuses_every_access() -> None:
    with redis_store("deleted") as store:
        store.create_session(record())
        store.append("s1", 1, {}, now())
        assert store.delete_session("s1")
        for access in (
            lambda: store.append("s1", 2, {}, now()),
            lambda: store.last_seq("s1"),
            lambda: store.entries("s1"),
            lambda: store.load("s1"),
            lambda: store.save_snapshot("s1", Snapshot(seq=1, taken_at=now(), state={})),
        ):
            with pytest.raises(SessionNotFound):
                access()
        assert store.list_sessions() == [] and store.count_sessions() == 0


def test_eight_instances_appending_at_once_keep_seq_contiguous() -> None:
    """8 threads, each with its own RedisStore (its own connections), race on one session."""
    writers, per_writer = 8, 25
    with redis_prefix("race") as prefix:
        stores = [RedisStore(REDIS_URL, prefix=prefix) for _ in range(writers)]
        stores[0].create_session(record())
        start = threading.Barrier(writers)
        conflicts = [0] * writers

        def write(writer: int) -> None:
            store = stores[writer]
            start.wait()
            for index in range(per_writer):
                while True:
                    try:
                        store.append(
                            "s1", store.last_seq("s1") + 1, {"w": writer, "i": index}, now()
                        )
                        break
                    except SequenceConflict:
                        conflicts[writer] += 1

        threads = [threading.Thread(target=write, args=(writer,)) for writer in range(writers)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        entries = stores[-1].entries("s1")
        assert [entry.seq for entry in entries] == list(range(1, writers * per_writer + 1))
        logged = sorted((entry.input["w"], entry.input["i"]) for entry in entries)
        assert logged == [(w, i) for w in range(writers) for i in range(per_writer)]
        assert stores[0].client.xlen(stores[0].keys.log("s1")) == writers * per_writer
        for store in stores:
            store.close()
