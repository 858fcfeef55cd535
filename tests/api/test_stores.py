"""Stores: the protocol on every implementation (redis: the real server), sqlite on a real file."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import textwrap
import threading
from collections.abc import Callable, Iterator
from contextlib import ExitStack
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import pytest

from app.errors import StoreUnavailable
from app.http.errors import SessionNotFound
from app.settings import Settings
from app.stores import (
    MemoryStore,
    RedisStore,
    SequenceConflict,
    SessionExists,
    SessionRecord,
    Snapshot,
    SqliteStore,
    Store,
    StoreSpec,
    open_store,
    parse_store_url,
    to_plain,
)
from app.stores.base import decode, dumps, encode, loads
from tests.api.redis_support import REDIS_URL, redis_prefix, redis_store

ROOT = Path(__file__).resolve().parents[2]


def now() -> datetime:
    return datetime.now(UTC)


def record(session_id: str = "s1") -> SessionRecord:
    return SessionRecord(
        id=session_id, config={"state": {"dim": 4}}, token_hash="sha256:ab", created_at=now()
    )


STORE_KINDS = ["memory", "sqlite", "redis"]


def open_kind(kind: str, tmp_path: Path, resources: ExitStack) -> Store:
    """A fresh, empty store of this kind, cleaned up by ``resources``."""
    if kind == "memory":
        opened: Store = MemoryStore()
    elif kind == "sqlite":
        opened = SqliteStore(tmp_path / "store.db")
    else:
        return resources.enter_context(redis_store(kind))
    resources.callback(opened.close)
    return opened


@pytest.fixture(params=STORE_KINDS)
def store(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[Store]:
    with ExitStack() as resources:
        yield open_kind(request.param, tmp_path, resources)


def test_append_then_load(store: Store) -> None:
    store.create_session(record())
    for seq in range(1, 6):
        store.append("s1", seq, {"type": "tracks", "n": seq}, now())
    loaded = store.load("s1")
    assert loaded.snapshot is None
    assert [entry.seq for entry in loaded.entries] == [1, 2, 3, 4, 5]
    assert loaded.entries[2].input == {"type": "tracks", "n": 3}
    assert loaded.last_seq == store.last_seq("s1") == 5
    assert [entry.seq for entry in store.entries("s1", after=3)] == [4, 5]
    assert [entry.seq for entry in store.entries("s1", after=0, limit=2)] == [1, 2]


def test_snapshot_then_log_after_it(store: Store) -> None:
    store.create_session(record())
    for seq in range(1, 4):
        store.append("s1", seq, {"n": seq}, now())
    state = {"tracks": np.arange(6.0).reshape(2, 3), "count": np.int64(3), "ids": ("F1", "F2")}
    store.save_snapshot("s1", Snapshot(seq=3, taken_at=now(), state=state))
    store.append("s1", 4, {"n": 4}, now())
    loaded = store.load("s1")
    assert loaded.snapshot is not None and loaded.snapshot.seq == 3
    assert loaded.snapshot.state == {
        "tracks": [[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]],
        "count": 3,
        "ids": ["F1", "F2"],
    }
    assert [entry.seq for entry in loaded.entries] == [4]
    assert loaded.last_seq == 4


def test_sequence_must_be_contiguous(store: Store) -> None:
    store.create_session(record())
    store.append("s1", 1, {"n": 1}, now())
    with pytest.raises(SequenceConflict) as duplicate:
        store.append("s1", 1, {"n": "again"}, now())
    assert duplicate.value.expected == 2
    with pytest.raises(SequenceConflict):
        store.append("s1", 3, {"n": 3}, now())
    assert [entry.input for entry in store.entries("s1")] == [{"n": 1}]


def test_sessions_list_delete_and_errors(store: Store) -> None:
    store.create_session(record("a"))
    store.create_session(record("b"))
    with pytest.raises(SessionExists):
        store.create_session(record("a"))
    assert [entry.id for entry in store.list_sessions()] == ["a", "b"]
    assert store.delete_session("a") and not store.delete_session("a")
    assert store.get_session("a") is None and store.count_sessions() == 1
    with pytest.raises(SessionNotFound):
        store.append("a", 1, {}, now())
    with pytest.raises(SessionNotFound):
        store.load("missing")


def test_stored_inputs_are_copies(store: Store) -> None:
    store.create_session(record())
    payload = {"tracks": [1, 2]}
    store.append("s1", 1, payload, now())
    payload["tracks"].append(3)
    assert store.entries("s1")[0].input == {"tracks": [1, 2]}


COPIED_AS_JSON_READS_IT = [
    {"tracks": [{"id": "t0", "state": [0.1, -0.0, 1e-320, 1.7976931348623157e308]}]},
    {"nested": ("tuple", [1, 2**63 - 1, -(2**63)]), "text": 'é\u2028\\"', "flag": True},
    {"big": 2**70, "keys": {1: "int key"}},
    {"numpy": np.arange(3.0), "scalar": np.float64(2.5)},
    {"none": None, "lone": "\ud800"},
    {"likelihoods": {"truck": 0.2, "car": 0.9, "Ärzte": 0.1, "bus": {"z": 1, "a": 2}}},
]


def json_module_round_trip(value: object) -> object:
    """The reference: the json module alone (numpy through to_plain), keys sorted."""
    text = json.dumps(
        value, default=to_plain, sort_keys=True, separators=(",", ":"), allow_nan=True
    )
    return json.loads(text)


@pytest.mark.parametrize("value", COPIED_AS_JSON_READS_IT)
def test_what_stores_keep_reads_back_as_the_json_round_trip(value: dict[str, object]) -> None:
    expected = json_module_round_trip(value)
    for copied in (decode(encode(value)), loads(dumps(value))):
        assert copied == expected
        # the same keys in the same order: json.dumps keeps dict order
        assert json.dumps(copied) == json.dumps(expected)


@pytest.mark.parametrize(
    "value",
    [
        {"a": [1.0, float("nan")], "b": None},  # NaN would become null in orjson
        {"a": (1, 2), "b": None},  # a tuple reads back as a list
        {"when": None, "values": [0.1, 2.5e-300, -0.0], "id": "x"},
    ],
)
def test_dumps_writes_what_the_json_module_reads_back(value: dict[str, object]) -> None:
    text = dumps(value)
    assert json.dumps(json.loads(text), allow_nan=True) == json.dumps(
        json_module_round_trip(value), allow_nan=True
    )
    assert json.dumps(loads(text), allow_nan=True) == json.dumps(json.loads(text), allow_nan=True)


def test_stores_keep_non_finite_numbers() -> None:
    copied = decode(encode({"values": [float("nan"), float("inf"), -float("inf")]}))
    assert dumps(copied) == '{"values":[NaN,Infinity,-Infinity]}'


@dataclass
class Reading:
    value: float


@pytest.mark.parametrize("value", [object(), Reading(1.0), datetime(2026, 1, 1, tzinfo=UTC)])
def test_encode_refuses_what_the_json_module_refuses(value: object) -> None:
    with pytest.raises(TypeError) as by_json:
        json.dumps({"engine": value}, default=to_plain)
    for writer in (encode, dumps):
        with pytest.raises(TypeError) as refused:
            writer({"engine": value})
        assert str(refused.value) == str(by_json.value)
        assert str(refused.value).endswith("is not plain data")


def test_to_plain_refuses_objects() -> None:
    with pytest.raises(TypeError, match=r"\$\.engine"):
        to_plain({"engine": object()})
    assert to_plain({"x": np.float32(0.5), "flag": np.bool_(True)}) == {"x": 0.5, "flag": True}


def test_to_plain_names_the_path_of_a_nested_refusal() -> None:
    state = {"tracks": [{"history": [[0.0, 1.0]]}, {"history": [[2.0, (3.0, object())]]}]}
    with pytest.raises(TypeError, match=r"^\$\.tracks\[1\]\.history\[0\]\[1\]\[1\]: object is"):
        to_plain(state)
    with pytest.raises(TypeError, match=r"^\$\.tracks\[0\]: key 3 is not a string"):
        to_plain({"tracks": [{3: "x"}]})


def test_to_plain_converts_nested_numpy_tuples_and_subclasses() -> None:
    class Label(str):
        pass

    state = {
        "rows": [(1.0, 2), [np.float64(0.5), np.int64(7)], np.eye(2)],
        "flags": (np.bool_(False), True, None),
        "names": {Label("a"): Label("b")},
        "objects": np.array([1.5, "x"], dtype=object),
    }
    plain = to_plain(state)
    assert plain == {
        "rows": [[1.0, 2], [0.5, 7], [[1.0, 0.0], [0.0, 1.0]]],
        "flags": [False, True, None],
        "names": {"a": "b"},
        "objects": [1.5, "x"],
    }
    assert type(plain["rows"][0]) is list and type(plain["flags"][0]) is bool


def test_store_urls(tmp_path: Path) -> None:
    assert parse_store_url("memory") == StoreSpec("memory")
    assert parse_store_url("sqlite") == StoreSpec("sqlite", Path("data/credal-fusion.db"))
    assert parse_store_url("sqlite:run/x.db") == StoreSpec("sqlite", Path("run/x.db"))
    assert parse_store_url("sqlite:///tmp/x.db") == StoreSpec("sqlite", Path("/tmp/x.db"))
    assert parse_store_url("redis://localhost") == StoreSpec("redis", url="redis://localhost")
    assert parse_store_url("rediss://:pw@cache:6380/2").url == "rediss://:pw@cache:6380/2"
    assert parse_store_url("redis") == StoreSpec("redis", url="redis://127.0.0.1:6379/0")
    for bad in (
        "postgres://x",
        "sqlite:",
        "redis://",
        "redis://host:port/0",
        "redis://host:6379/zero",
        "redis:host",
    ):
        with pytest.raises(ValueError):
            parse_store_url(bad)
    opened = open_store(f"sqlite:{tmp_path / 'nested' / 'dir' / 'x.db'}")
    assert isinstance(opened, SqliteStore) and opened.path.exists()
    opened.close()
    with redis_prefix("url") as prefix:
        shared = open_store(REDIS_URL, redis_prefix=prefix)
        assert isinstance(shared, RedisStore) and shared.prefix == prefix
        shared.close()


def test_sqlite_restores_after_reopen(tmp_path: Path) -> None:
    path = tmp_path / "reopen.db"
    first = SqliteStore(path)
    first.create_session(record())
    for seq in range(1, 11):
        first.append("s1", seq, {"n": seq}, now())
    first.save_snapshot("s1", Snapshot(seq=6, taken_at=now(), state={"x": [1.5, 2.5]}))
    first.close()
    second = SqliteStore(path)
    loaded = second.load("s1")
    assert loaded.snapshot is not None and loaded.snapshot.state == {"x": [1.5, 2.5]}
    assert [entry.input["n"] for entry in loaded.entries] == [7, 8, 9, 10]
    assert [entry.seq for entry in second.entries("s1")] == list(range(1, 11))
    second.close()


def test_sqlite_uses_wal_and_full_sync(tmp_path: Path) -> None:
    store = SqliteStore(tmp_path / "pragmas.db")
    for connection in (store._connection(), store._writer()):  # a reader, the writer
        assert connection.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        assert connection.execute("PRAGMA synchronous").fetchone()[0] == 2  # FULL
    store.close()


class _CommitFailsOnce:
    """The store's write connection, whose next COMMIT fails as SQLITE_BUSY does: with an
    error and the transaction left open (sqlite's documented behaviour)."""

    def __init__(self, connection: sqlite3.Connection) -> None:
        self._connection = connection
        self.failed = False

    def execute(self, sql: str, *args: object) -> sqlite3.Cursor:
        if sql == "COMMIT" and not self.failed:
            self.failed = True
            raise sqlite3.OperationalError("database is locked")
        return self._connection.execute(sql, *args)

    def __getattr__(self, name: str) -> object:
        return getattr(self._connection, name)


def test_sqlite_acknowledges_no_append_after_a_failed_commit(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A write whose COMMIT fails must not leave the shared write connection inside a
    transaction: the next lone append is acknowledged only once it is on disk, as another
    connection to the file reads it."""
    path = tmp_path / "commit.db"
    store = SqliteStore(path)
    store.create_session(record())
    store.append("s1", 1, {"n": 1}, now())
    failing = _CommitFailsOnce(store._writer())
    monkeypatch.setattr(store, "_writer", lambda: failing)
    with pytest.raises(StoreUnavailable):
        store.save_snapshot("s1", Snapshot(seq=1, taken_at=now(), state={"x": 1}))
    assert failing.failed
    store.append("s1", 2, {"n": 2}, now())
    other = sqlite3.connect(path)
    seqs = [row[0] for row in other.execute("SELECT seq FROM inputs ORDER BY seq")]
    snapshots = other.execute("SELECT COUNT(*) FROM snapshots").fetchone()[0]
    other.close()
    store.close()
    assert seqs == [1, 2]
    assert snapshots == 0  # the failed write was rolled back, not committed later


WRITER = textwrap.dedent(
    """
    import sys
    from datetime import UTC, datetime
    from app.stores import SessionRecord, SqliteStore

    store = SqliteStore(sys.argv[1])
    store.create_session(SessionRecord("s1", {}, "sha256:00", datetime.now(UTC)))
    for seq in range(1, 100_001):
        store.append("s1", seq, {"n": seq, "pad": "x" * 200}, datetime.now(UTC))
        print(seq, flush=True)
    """
)


def test_sqlite_keeps_every_acknowledged_input_after_sigkill(tmp_path: Path) -> None:
    path = tmp_path / "killed.db"
    child = subprocess.Popen(
        [sys.executable, "-c", WRITER, str(path)],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert child.stdout is not None
    acknowledged = 0
    try:
        for line in child.stdout:
            acknowledged = int(line)
            if acknowledged >= 150:
                break
    finally:
        os.kill(child.pid, signal.SIGKILL)
        child.wait()
        child.stdout.close()
    assert child.returncode == -signal.SIGKILL
    assert acknowledged >= 150
    reopened = SqliteStore(path)
    entries = reopened.entries("s1")
    seqs = [entry.seq for entry in entries]
    assert seqs == list(range(1, len(seqs) + 1))
    assert len(seqs) >= acknowledged
    assert all(entry.input["n"] == entry.seq for entry in entries)
    reopened.append("s1", len(seqs) + 1, {"n": "after restart"}, now())
    reopened.close()


@pytest.mark.parametrize("kind", STORE_KINDS)
def test_concurrent_appends_keep_seq_contiguous(kind: str, tmp_path: Path) -> None:
    with ExitStack() as resources:
        concurrent_appends(open_kind(kind, tmp_path, resources))


def concurrent_appends(store: Store) -> None:
    """8 threads append to one session, each retrying on SequenceConflict."""
    store.create_session(record())
    writers, per_writer = 8, 20
    conflicts: list[int] = []
    start = threading.Barrier(writers)

    def write(writer: int) -> None:
        start.wait()
        for index in range(per_writer):
            while True:
                seq = store.last_seq("s1") + 1
                try:
                    store.append("s1", seq, {"writer": writer, "index": index}, now())
                    break
                except SequenceConflict:
                    conflicts.append(writer)

    threads = [threading.Thread(target=write, args=(writer,)) for writer in range(writers)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    entries = store.entries("s1")
    assert [entry.seq for entry in entries] == list(range(1, writers * per_writer + 1))
    written = sorted((entry.input["writer"], entry.input["index"]) for entry in entries)
    assert written == [(writer, index) for writer in range(writers) for index in range(per_writer)]


GROUP_WRITERS = textwrap.dedent(
    """
    import sys, threading
    from datetime import UTC, datetime
    from app.stores import SessionRecord, SqliteStore

    store = SqliteStore(sys.argv[1])
    writers = int(sys.argv[2])
    for writer in range(writers):
        store.create_session(SessionRecord(f"s{writer}", {}, f"sha256:{writer}", datetime.now(UTC)))
    print("ready", flush=True)
    lock = threading.Lock()

    def write(writer):
        for seq in range(1, 100_001):
            store.append(f"s{writer}", seq, {"n": seq, "w": writer}, datetime.now(UTC))
            with lock:
                print(writer, seq, flush=True)

    for writer in range(writers):
        threading.Thread(target=write, args=(writer,)).start()
    """
)


def test_sqlite_group_commits_lose_no_acknowledged_input_after_sigkill(tmp_path: Path) -> None:
    """Many writers share commits (group commit); a SIGKILL loses none of what they were told
    is logged: every acknowledged input is there after reopening, each session contiguous."""
    path, writers = tmp_path / "group.db", 8
    child = subprocess.Popen(
        [sys.executable, "-c", GROUP_WRITERS, str(path), str(writers)],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert child.stdout is not None
    acknowledged = dict.fromkeys(range(writers), 0)
    try:
        assert child.stdout.readline().strip() == "ready"
        for line in child.stdout:
            writer, seq = map(int, line.split())
            acknowledged[writer] = seq
            if sum(acknowledged.values()) >= 400:
                break
    finally:
        os.kill(child.pid, signal.SIGKILL)
        child.wait()
        child.stdout.close()
    assert child.returncode == -signal.SIGKILL
    reopened = SqliteStore(path)
    for writer in range(writers):
        entries = reopened.entries(f"s{writer}")
        seqs = [entry.seq for entry in entries]
        assert seqs == list(range(1, len(seqs) + 1))
        assert len(seqs) >= acknowledged[writer]
        assert all(entry.input == {"n": entry.seq, "w": writer} for entry in entries)
    reopened.close()


QUEUED_WRITERS = textwrap.dedent(
    """
    import asyncio, os, re, sys, threading
    from datetime import UTC, datetime
    from app.stores import SessionRecord, SqliteStore

    store = SqliteStore(sys.argv[1], sys.argv[4])
    sessions, hold_after = int(sys.argv[2]), int(sys.argv[3])
    for index in range(sessions):
        store.create_session(SessionRecord(f"s{index}", {}, f"sha256:{index}", datetime.now(UTC)))
    acknowledged = 0
    batch = []

    def say(line):  # one write(2) a line: the two threads' lines never interleave
        os.write(1, (line + "\\n").encode())

    def trace(sql):  # the committer's thread, expanded statements of the batch's transaction
        if sql.startswith("BEGIN"):
            batch.clear()
        elif "INSERT INTO inputs" in sql:
            batch.append("%s:%s" % re.search(r"SELECT '(s[0-9]+)', ([0-9]+),", sql).groups())
        elif sql == "COMMIT" and acknowledged >= hold_after:
            say("held " + " ".join(batch))  # inserted, not committed
            threading.Event().wait()  # until the SIGKILL

    store._writer().set_trace_callback(trace)

    async def write(index):
        global acknowledged
        loop = asyncio.get_running_loop()
        for seq in range(1, 100_001):
            logged = loop.create_future()
            store.append_queued(
                f"s{index}", seq, {"n": seq, "w": index}, datetime.now(UTC),
                lambda listened, error, logged=logged: loop.call_soon_threadsafe(
                    logged.set_result, error
                ),
            )
            error = await logged
            if error is not None:
                raise error
            acknowledged += 1
            say(f"{index} {seq}")

    async def main():
        await asyncio.gather(*(write(index) for index in range(sessions)))

    asyncio.run(main())
    """
)


@pytest.mark.parametrize("synchronous", ["FULL", "NORMAL"])
def test_sqlite_queued_batch_killed_before_its_commit_loses_no_acknowledged_input(
    tmp_path: Path, synchronous: str
) -> None:
    """Several sessions' inputs queued from one event loop (``append_queued``, as the service
    logs them) share the committer's transactions; the process is SIGKILLed while a batch of
    several is inserted but not committed. Reopened, each session's log holds every input the
    client was told is logged (its own record of acks), as sent and in order, and none of the
    killed batch (never acknowledged: rolled back). ``NORMAL`` (no fsync at commit) keeps
    this guarantee too: a process's death leaves its writes in the kernel's cache (a power
    loss does not, which no test here can show)."""
    path, sessions = tmp_path / "queued.db", 6
    child = subprocess.Popen(
        [sys.executable, "-c", QUEUED_WRITERS, str(path), str(sessions), "300", synchronous],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert child.stdout is not None
    acknowledged = dict.fromkeys(range(sessions), 0)
    held: list[tuple[int, int]] = []
    try:
        for line in child.stdout:
            if line.startswith("held"):
                held = [
                    (int(name[1:]), int(seq))
                    for name, seq in (item.split(":") for item in line.split()[1:])
                ]
                break
            index, seq = map(int, line.split())
            assert seq == acknowledged[index] + 1  # each session's acks in order
            acknowledged[index] = seq
    finally:
        os.kill(child.pid, signal.SIGKILL)
        child.wait()
        child.stdout.close()
    assert len(held) >= 2, "no batch of several inputs was held"
    assert child.returncode == -signal.SIGKILL
    assert sum(acknowledged.values()) >= 300
    reopened = SqliteStore(path)
    logged = {}
    for index in range(sessions):
        entries = reopened.entries(f"s{index}")
        logged[index] = len(entries)
        assert [entry.seq for entry in entries] == list(range(1, len(entries) + 1))
        assert [entry.input for entry in entries] == [
            {"n": seq, "w": index} for seq in range(1, len(entries) + 1)
        ]
        assert len(entries) >= acknowledged[index]
    for index, seq in held:
        assert logged[index] == seq - 1  # the batch killed before its COMMIT: none of it
    reopened.append("s0", logged[0] + 1, {"n": "after restart"}, now())
    reopened.close()


def test_sqlite_queued_appends_are_settled_as_append_answers(tmp_path: Path) -> None:
    """``append_queued`` settles each input with what ``append`` would answer: logged (False:
    not shared), its own refusal (a wrong seq, a deleted session, data that is not plain)
    without the others of its batch; after ``close`` nothing more is logged."""
    store = SqliteStore(tmp_path / "queued.db")
    for session_id in ("a", "gone"):
        store.create_session(record(session_id))
    store.delete_session("gone")
    answers: dict[str, tuple[bool, Exception | None]] = {}
    settled = threading.Event()
    calls = [
        ("a", 1, {"n": 1}),
        ("a", 5, {"n": 5}),
        ("gone", 1, {"n": 1}),
        ("a", 2, {"n": object()}),
    ]

    def answer(name: str) -> Callable[[bool, Exception | None], None]:
        def settle(listened: bool, error: Exception | None) -> None:
            answers[name] = (listened, error)
            if len(answers) == len(calls):
                settled.set()

        return settle

    with store._write_lock:  # a commit under way: all four share the committer's next batch
        for session_id, seq, entry in calls:
            store.append_queued(session_id, seq, entry, now(), answer(f"{session_id}{seq}"))
    assert settled.wait(30)
    assert answers["a1"] == (False, None)
    assert isinstance(answers["a5"][1], SequenceConflict)
    assert isinstance(answers["gone1"][1], SessionNotFound)
    assert isinstance(answers["a2"][1], TypeError)
    assert [entry.input for entry in store.entries("a")] == [{"n": 1}]
    store.close()
    late: list[Exception | None] = []
    store.append_queued("a", 2, {"n": 2}, now(), lambda _, error: late.append(error))
    assert len(late) == 1 and late[0] is not None
    reopened = SqliteStore(tmp_path / "queued.db")
    assert [entry.seq for entry in reopened.entries("a")] == [1]
    reopened.close()


@pytest.mark.parametrize(("setting", "pragma"), [(None, 2), ("FULL", 2), ("NORMAL", 1)])
def test_the_sqlite_synchronous_setting_reaches_the_write_connection(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, setting: str | None, pragma: int
) -> None:
    """``CREDAL_SQLITE_SYNCHRONOUS`` (default FULL) is the synchronous mode of the connection
    that commits (sqlite's numbers: FULL 2, NORMAL 1); anything else is refused."""
    if setting is not None:
        monkeypatch.setenv("CREDAL_SQLITE_SYNCHRONOUS", setting)
    settings = Settings()
    store = open_store(
        f"sqlite:{tmp_path / 'sync.db'}", sqlite_synchronous=settings.sqlite_synchronous
    )
    assert isinstance(store, SqliteStore)
    assert store._writer().execute("PRAGMA synchronous").fetchone()[0] == pragma
    store.close()
    monkeypatch.setenv("CREDAL_SQLITE_SYNCHRONOUS", "OFF")
    with pytest.raises(ValueError, match="sqlite_synchronous"):
        Settings()


def test_sqlite_appends_waiting_for_a_commit_share_the_next_one(tmp_path: Path) -> None:
    """Appends queued while the write lock is held are logged by one transaction; one whose seq
    is wrong, or whose session is deleted, is refused alone, the others of its batch are logged."""
    store = SqliteStore(tmp_path / "batch.db")
    for session_id in ("a", "b", "c", "gone"):
        store.create_session(record(session_id))
    store.delete_session("gone")
    commits: list[int] = []
    commit = store._commit_queued

    def counted() -> None:
        commits.append(len(store._queue))
        commit()

    store._commit_queued = counted  # type: ignore[method-assign]
    outcomes: dict[tuple[str, int], str] = {}

    def append(session_id: str, seq: int) -> None:
        try:
            store.append(session_id, seq, {"session": session_id, "seq": seq}, now())
            outcomes[session_id, seq] = "logged"
        except SequenceConflict:
            outcomes[session_id, seq] = "conflict"
        except SessionNotFound:
            outcomes[session_id, seq] = "not found"

    calls = [("a", 1), ("b", 1), ("c", 1), ("c", 5), ("gone", 1)]
    threads = [threading.Thread(target=append, args=call) for call in calls]
    with store._write_lock:  # a commit under way: every append queues behind it
        for thread in threads:
            thread.start()
        while len(store._queue) < len(calls):
            threading.Event().wait(0.001)
    for thread in threads:
        thread.join()
    assert commits == [len(calls)]  # the first thread to get the lock committed all of them
    assert outcomes == {
        ("a", 1): "logged",
        ("b", 1): "logged",
        ("c", 1): "logged",
        ("c", 5): "conflict",
        ("gone", 1): "not found",
    }
    for session_id in ("a", "b", "c"):
        assert [entry.input for entry in store.entries(session_id)] == [
            {"session": session_id, "seq": 1}
        ]
    store.close()


def test_sqlite_load_reads_one_snapshot_while_a_writer_compacts(tmp_path: Path) -> None:
    """``load`` reads the record, the newest snapshot and the inputs after it in one read
    transaction. A writer thread that snapshots at 5 and compacts through 5 between the
    snapshot's read and the inputs' read (held there by the reader's trace callback, so the
    interleaving is certain) must not show through: the load is the store either before
    (snapshot 2, inputs 3..6) or after (snapshot 5, input 6) that commit. Read without one
    transaction it was snapshot 2 with input 6 alone: inputs 3..5 lost, a replay missing
    three steps."""
    path = tmp_path / "store.db"
    store = SqliteStore(path)
    try:
        store.create_session(record())
        for seq in range(1, 7):
            store.append("s1", seq, {"n": seq}, now())
            if seq == 2:
                store.save_snapshot("s1", Snapshot(seq=2, taken_at=now(), state={"n": 2}))
        reading_inputs, written = threading.Event(), threading.Event()

        def writer() -> None:
            reading_inputs.wait(timeout=30)
            store.save_snapshot("s1", Snapshot(seq=5, taken_at=now(), state={"n": 5}))
            assert store.compact("s1", 5) == 5  # inputs 1..5 deleted, committed
            written.set()

        def hold(statement: str) -> None:
            if "FROM inputs" in statement and not reading_inputs.is_set():
                reading_inputs.set()
                assert written.wait(timeout=30), "the writer did not commit"

        thread = threading.Thread(target=writer)
        thread.start()
        store._connection().set_trace_callback(hold)  # this thread's reading connection
        try:
            loaded = store.load("s1")
        finally:
            store._connection().set_trace_callback(None)
            thread.join()
        assert written.is_set()
        assert loaded.snapshot is not None
        seqs = [entry.seq for entry in loaded.entries]
        # by hand: the two committed states of the store
        assert (loaded.snapshot.seq, seqs) in [(2, [3, 4, 5, 6]), (5, [6])]
        again = store.load("s1")  # and after the writer: its state
        assert again.snapshot is not None
        assert (again.snapshot.seq, [entry.seq for entry in again.entries]) == (5, [6])
    finally:
        store.close()
