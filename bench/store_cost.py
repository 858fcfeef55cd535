"""What durability costs: the service's CPU per input on the memory store and on sqlite.

Run with ``make bench`` (or ``python bench/store_cost.py [--inputs N]``).
First the store calls alone, in this process: :data:`SESSIONS` sessions' inputs
(:func:`scan`, as logged) appended to a :class:`~app.stores.memory.MemoryStore`
and to a :class:`~app.stores.sqlite.SqliteStore` on a fresh file (WAL,
``synchronous=FULL``: an fsync per commit, group commit), by one writer thread
and by one thread per session; this process's CPU (every thread, user +
system) per input; then the same on ``synchronous=NORMAL``, a labelled extra
row (no fsync at commit: what the fsync costs). Then through the service: three service
processes run on loopback with the default settings, one on the memory store, one on sqlite
(``synchronous=FULL``, the default) and a labelled extra on sqlite with
``CREDAL_SQLITE_SYNCHRONOUS=NORMAL``, but the overload guards
(off: a refusal's CPU would be charged to the inputs applied). The load is
:data:`SESSIONS` sessions of one detecting sensor each (:func:`scan`: 20
targets and some clutter a scan), every one fed by its own client over REST,
one request at a time (closed loop: the next input is sent when the previous
one is acknowledged, i.e. durable). The servers are loaded at once, in
:data:`ROUNDS` rounds of :data:`INPUTS` inputs per session on each, so that
whatever the shared machine does falls on all, and every server applies the
same scans (the same engine work); each server's CPU (user + system, every
thread) is read from ``/proc/<pid>/stat`` around each round, and its event
loop thread's apart (the other threads' part is sqlite's committer: resolved
even when the loop's CPU per input drifts by more than the difference). Prints
CPU per input for each store and sqlite's extra, over all rounds and as the
median (and quartiles) over the rounds of the difference.

Then overload (issue 29, "refused, not spread"): :data:`OVERLOAD_SESSIONS` sensors
on ``stream`` connections, each sending at a steady rate whatever the answers,
:data:`OVERLOAD_FACTOR` times the rate just measured in all, first to a server
with the default ``overload_delay_ms`` and then to one with the guard off:
answered and refused inputs per second, and the latency (send to answer) of
the answered ones. Never asserts a time.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import os
import resource
import statistics
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import orjson
from websockets.asyncio.client import connect
from websockets.typing import Subprotocol

sys.path.insert(0, str(Path(__file__).resolve().parent))

from machine import describe_machine
from service import free_port, process_cpu_s, running, service_command

from app.stores.base import SessionRecord, Store
from app.stores.memory import MemoryStore
from app.stores.sqlite import SqliteStore, Synchronous

SESSIONS = 16
"""Sessions (sensors), each with its own client sending one input at a time."""
TRACKS = 20
ROUNDS = 12
INPUTS = 8
"""Inputs per session and round, on every server at once: each server applies the same scans
in every round (the engine's work is the same: what differs is the store)."""
WARMUP_INPUTS = 5
"""Inputs per session sent before any window (the engine's first tracks, connections)."""
CLUTTER = 4
"""False detections per scan, spread over the surveyed area."""


def config(sensor: str) -> dict[str, Any]:
    """A session of one detecting sensor (2-D positions, 10 m noise), default preset."""
    return {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "sensors": [{"id": sensor, "measurement": {"r": [[100.0, 0.0], [0.0, 100.0]]}}],
    }


def scan(sensor: str, index: int) -> bytes:
    """Scan ``index`` (one a second) of :data:`TRACKS` targets on a grid moving at 10 m/s,
    each seen with 10 m noise, and :data:`CLUTTER` false detections (seeded by the index)."""
    rng = np.random.default_rng(index)
    targets = np.array([[500.0 * (t % 5), 500.0 * (t // 5)] for t in range(TRACKS)])
    moved = targets + np.array([10.0 * index, 5.0 * index])
    points = moved + rng.normal(0.0, 10.0, targets.shape)
    clutter = rng.uniform(-500.0, 3000.0, (CLUTTER, 2))
    detections = [{"z": [round(float(v), 3) for v in point]} for point in [*points, *clutter]]
    return orjson.dumps({"sensor": sensor, "time": float(index), "detections": detections})


STORE_INPUTS = 200
"""Inputs per session appended in the store-calls-alone part."""


def _process_cpu_s() -> float:
    """This process's CPU seconds so far (every thread, user + system)."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def store_calls(store: Store, writers: int) -> tuple[float, float]:
    """CPU ms per input and inputs/s of :data:`SESSIONS` sessions' :data:`STORE_INPUTS` inputs
    each appended to ``store`` by ``writers`` threads (each writing whole sessions, in order)."""
    for index in range(SESSIONS):
        record = SessionRecord(
            id=f"s{index}",
            config=config(f"s{index}"),
            token_hash=f"h{index}",
            created_at=datetime.now(UTC),
        )
        store.create_session(record)
    logged = [{"report": orjson.loads(scan("s", number))} for number in range(STORE_INPUTS)]

    def write(sessions: range) -> None:
        for number in range(STORE_INPUTS):
            for index in sessions:
                store.append(f"s{index}", number + 1, logged[number], datetime.now(UTC))

    threads = [
        threading.Thread(target=write, args=(range(first, SESSIONS, writers),))
        for first in range(writers)
    ]
    cpu, started = _process_cpu_s(), time.perf_counter()
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    count = SESSIONS * STORE_INPUTS
    return 1e3 * (_process_cpu_s() - cpu) / count, count / (time.perf_counter() - started)


def store_calls_alone() -> None:
    """The store calls alone, sqlite as configured (``synchronous=FULL``), then a labelled
    extra row: ``synchronous=NORMAL`` (no fsync at commit: an acknowledged input survives the
    process's death, SIGKILL included, but not the machine's), what the fsync costs."""
    print(
        f"store calls alone (this process): {SESSIONS} sessions × {STORE_INPUTS} inputs"
        f" ({len(orjson.dumps({'report': orjson.loads(scan('s', 0))}))} bytes each, as logged)"
    )
    print(
        f"{'sqlite':<26} {'writers':>7} {'memory ms/input':>15} {'sqlite ms/input':>15}"
        f" {'extra':>6} {'sqlite inputs/s':>15}"
    )
    rows: list[tuple[str, Synchronous]] = [
        ("synchronous=FULL (default)", "FULL"),
        ("NORMAL (extra row)", "NORMAL"),
    ]
    for label, synchronous in rows:
        for writers in (1, SESSIONS):
            memory, _ = store_calls(MemoryStore(), writers)
            with tempfile.TemporaryDirectory() as directory:
                sqlite = SqliteStore(Path(directory) / "alone.db", synchronous)
                durable, rate = store_calls(sqlite, writers)
                sqlite.close()
            print(
                f"{label:<26} {writers:>7} {memory:15.3f} {durable:15.3f}"
                f" {durable - memory:6.3f} {rate:15.0f}"
            )


class Load:
    """:data:`SESSIONS` sessions on one server and a client for each."""

    def __init__(self, url: str) -> None:
        self.url = url
        self.clients: list[httpx.AsyncClient] = []
        self.paths: list[str] = []
        self.sent = [0] * SESSIONS
        self.refused = 0
        """Inputs refused 503 ``overloaded`` (not counted as processed; sent again)."""

    async def open(self) -> None:
        async with httpx.AsyncClient(base_url=self.url) as admin:
            for index in range(SESSIONS):
                created = (await admin.post("/v1/sessions", json=config(f"s{index}"))).json()
                self.paths.append(f"/v1/sessions/{created['id']}/detections")
                self.clients.append(
                    httpx.AsyncClient(
                        base_url=self.url,
                        headers={
                            "Authorization": f"Bearer {created['token']}",
                            "Content-Type": "application/json",
                        },
                        timeout=60,
                        # idle while the other server is measured: reconnect rather than
                        # race uvicorn's keep-alive timeout (5 s)
                        limits=httpx.Limits(keepalive_expiry=1.0),
                    )
                )

    async def close(self) -> None:
        for client in self.clients:
            await client.aclose()

    async def window(self, inputs: int) -> tuple[int, float]:
        """``inputs`` more inputs of every session acknowledged by the server (every client
        sending in turn): how many, and the seconds it took."""
        started = time.perf_counter()
        done = 0

        async def client(index: int) -> None:
            nonlocal done
            for _ in range(inputs):
                body = scan(f"s{index}", self.sent[index])
                answer = await self.clients[index].post(self.paths[index], content=body)
                while answer.status_code == 503 and "overloaded" in answer.text:
                    self.refused += 1
                    answer = await self.clients[index].post(self.paths[index], content=body)
                assert answer.status_code == 200, answer.text
                self.sent[index] += 1
                done += 1

        await asyncio.gather(*(client(index) for index in range(SESSIONS)))
        return done, time.perf_counter() - started

    async def warm_up(self) -> None:
        for _ in range(WARMUP_INPUTS):
            await asyncio.gather(
                *(
                    self.clients[index].post(
                        self.paths[index],
                        content=scan(f"s{index}", self.sent[index]),
                    )
                    for index in range(SESSIONS)
                )
            )
            for index in range(SESSIONS):
                self.sent[index] += 1


async def measure(
    servers: dict[str, tuple[str, int]], inputs_per_round: int
) -> tuple[dict[str, list[float]], int]:
    """Per store: CPU ms per input over all rounds, inputs/s, the event loop thread's CPU ms
    per input, then CPU ms per input in every round; and how many inputs were refused as
    overload (sent again, none expected: the guards are off). In each round every server
    is sent ``inputs_per_round`` inputs per session at once: whatever the shared machine
    does meanwhile falls on all, and each applies the same scans."""
    loads = {store: Load(url) for store, (url, _) in servers.items()}
    for load in loads.values():
        await load.open()
    await asyncio.gather(*(load.warm_up() for load in loads.values()))
    cpu = dict.fromkeys(servers, 0.0)
    loop_cpu = dict.fromkeys(servers, 0.0)
    inputs = dict.fromkeys(servers, 0)
    per_round: dict[str, list[float]] = {store: [] for store in servers}
    elapsed = dict.fromkeys(servers, 0.0)
    for _ in range(ROUNDS):
        before = {
            store: (process_cpu_s(pid), main_thread_cpu_s(pid))
            for store, (_, pid) in servers.items()
        }
        done = await asyncio.gather(*(load.window(inputs_per_round) for load in loads.values()))
        for store, (count, seconds) in zip(servers, done, strict=True):
            elapsed[store] += seconds
            pid = servers[store][1]
            used = process_cpu_s(pid) - before[store][0]
            cpu[store] += used
            loop_cpu[store] += main_thread_cpu_s(pid) - before[store][1]
            inputs[store] += count
            per_round[store].append(1e3 * used / max(count, 1))
    for load in loads.values():
        await load.close()
    per_store = {
        store: [
            1e3 * cpu[store] / max(inputs[store], 1),
            inputs[store] / elapsed[store],
            1e3 * loop_cpu[store] / max(inputs[store], 1),
        ]
        + per_round[store]
        for store in servers
    }
    return per_store, sum(load.refused for load in loads.values())


def main_thread_cpu_s(pid: int) -> float:
    """CPU seconds (user + system) of process ``pid``'s main thread, the event loop's, so far
    (Linux ``/proc/<pid>/task/<pid>/stat``); the rest of :func:`process_cpu_s` is the other
    threads' (sqlite's committer, worker threads)."""
    fields = Path(f"/proc/{pid}/task/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


OVERLOAD_SESSIONS = 40
"""Stream sessions of the overload run, each a sensor sending at its own steady rate."""
OVERLOAD_FACTOR = 2.0
"""Offered load of the overload run, in multiples of the closed-loop capacity just measured."""
OVERLOAD_SECONDS = 8.0
GUARD_OFF = {"CREDAL_OVERLOAD_DELAY_MS": "0", "CREDAL_MAX_QUEUE_MS": "0"}
"""Both overload guards off: the store comparison measures the CPU of inputs applied, all of
them (a refusal's CPU would be charged to the inputs accepted)."""
QUOTAS_OFF = {
    "CREDAL_TENANT_INPUTS_PER_SECOND": "1000000",
    "CREDAL_TENANT_WORK_PER_MINUTE": "1000000000000",
}
"""Every sensor of the bench is one tenant (one loopback address): its quotas are lifted, so
that what refuses inputs is the overload guard, not the tenant's fair share."""
NORMAL_LABEL = "sqlite NORMAL"
"""The labelled extra server: ``CREDAL_SQLITE_SYNCHRONOUS=NORMAL`` (no fsync at commit: an
acknowledged input survives the process's death, SIGKILL included, not the machine's)."""
DRAIN_SECONDS = 30.0
"""How long answers are awaited after the last input was sent."""


@dataclass
class Stream:
    """What one sensor of the overload run saw."""

    latencies_ms: list[float] = field(default_factory=list)
    refused: int = 0
    unanswered: int = 0


async def sensor(url: str, index: int, rate: float, seconds: float) -> Stream:
    """A detecting sensor on its own session and ``stream``: one scan every ``1 / rate`` s
    whatever the answers (a sensor does not wait), answers read as they come."""
    async with httpx.AsyncClient(base_url=url) as admin:
        created = (await admin.post("/v1/sessions", json=config(f"s{index}"))).json()
    address = url.replace("http://", "ws://") + f"/v1/sessions/{created['id']}/stream"
    seen = Stream()
    sent_at: dict[str, float] = {}
    async with connect(
        address, subprotocols=[Subprotocol("bearer"), Subprotocol(created["token"])], max_size=None
    ) as socket:
        await socket.recv()  # ack

        async def send() -> None:
            start = time.perf_counter() + index / (rate * OVERLOAD_SESSIONS)  # spread the phases
            for number in range(round(seconds * rate)):
                await asyncio.sleep(max(0.0, start + number / rate - time.perf_counter()))
                body = orjson.loads(scan(f"s{index}", number))
                sent_at[str(number)] = time.perf_counter()
                await socket.send(orjson.dumps({"type": "detections", "ref": str(number), **body}))

        async def read() -> None:
            while len(seen.latencies_ms) + seen.refused < round(seconds * rate):
                answer = orjson.loads(await socket.recv())
                started = sent_at.pop(answer["ref"])
                if answer["type"] == "result":
                    seen.latencies_ms.append(1e3 * (time.perf_counter() - started))
                else:
                    assert answer["problem"]["status"] == 503, answer
                    seen.refused += 1

        reading = asyncio.create_task(read())
        await send()
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(asyncio.shield(reading), DRAIN_SECONDS)
        reading.cancel()
        seen.unanswered = round(seconds * rate) - len(seen.latencies_ms) - seen.refused
    return seen


async def overload(url: str, offered: float) -> list[Stream]:
    rate = offered / OVERLOAD_SESSIONS
    return await asyncio.gather(
        *(sensor(url, index, rate, OVERLOAD_SECONDS) for index in range(OVERLOAD_SESSIONS))
    )


def overload_run(offered: float, why: str) -> None:
    """The same steady load, above capacity, on a server with the default overload guards and
    on one without (:data:`GUARD_OFF`); the latency of the answered inputs."""
    print(
        f"\noverload: {OVERLOAD_SESSIONS} stream sessions (memory store), each a detecting sensor"
        f" at a steady {offered / OVERLOAD_SESSIONS:.2f} Hz, {offered:.0f} scans/s in all"
        f" ({why}) for {OVERLOAD_SECONDS:g} s;"
        " defaults but the tenant quotas (lifted: every sensor here is one tenant)"
    )
    print(
        f"{'overload guards':<18} {'answered/s':>10} {'refused/s':>9} {'p50 ms':>8}"
        f" {'p99 ms':>8} {'unanswered':>10}"
    )
    for label, environment in (
        ("default", QUOTAS_OFF),
        ("off", QUOTAS_OFF | GUARD_OFF),
    ):
        port = free_port()
        with running(service_command(port, "memory"), port, environment):
            streams = asyncio.run(overload(f"http://127.0.0.1:{port}", offered))
        latencies = sorted(value for stream in streams for value in stream.latencies_ms)
        refused = sum(stream.refused for stream in streams)
        unanswered = sum(stream.unanswered for stream in streams)
        p50 = latencies[len(latencies) // 2] if latencies else float("nan")
        p99 = (
            latencies[min(len(latencies) - 1, round(0.99 * (len(latencies) - 1)))]
            if latencies
            else float("nan")
        )
        print(
            f"{label:<18} {len(latencies) / OVERLOAD_SECONDS:10.0f} {refused / OVERLOAD_SECONDS:9.0f}"
            f" {p50:8.0f} {p99:8.0f} {unanswered:10d}"
        )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--inputs", type=int, default=INPUTS, help="per session and round, on every server"
    )
    parser.add_argument(
        "--overload-rate",
        type=float,
        help="scans/s of the overload run alone (without it: the stores first, then overload)",
    )
    parser.add_argument("--no-overload", action="store_true", help="the stores only")
    arguments = parser.parse_args()
    print(describe_machine())
    if arguments.overload_rate is not None:
        overload_run(arguments.overload_rate, "--overload-rate")
        return 0
    store_calls_alone()
    print(
        f"\nthrough the service: {SESSIONS} sessions × 1 client each, closed loop, {TRACKS} targets"
        f" + {CLUTTER} clutter a scan (REST /detections), default settings but the overload"
        f" guards (off: a refusal's CPU would be charged to the inputs applied); {ROUNDS}"
        f" rounds of {arguments.inputs} inputs a session, the same on the three servers loaded"
        f" at once (memory,"
        f" sqlite as configured by default: FULL, and a labelled extra: {NORMAL_LABEL})"
    )
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as directory:
        memory_port, sqlite_port, normal_port = free_port(), free_port(), free_port()
        with (
            running(service_command(memory_port, "memory"), memory_port, GUARD_OFF) as memory,
            running(
                service_command(sqlite_port, f"sqlite:{Path(directory) / 'full.db'}"),
                sqlite_port,
                GUARD_OFF,
            ) as sqlite,
            running(
                service_command(normal_port, f"sqlite:{Path(directory) / 'normal.db'}"),
                normal_port,
                GUARD_OFF | {"CREDAL_SQLITE_SYNCHRONOUS": "NORMAL"},
            ) as normal,
        ):
            servers = {
                "memory": (f"http://127.0.0.1:{memory_port}", memory.pid),
                "sqlite": (f"http://127.0.0.1:{sqlite_port}", sqlite.pid),
                NORMAL_LABEL: (f"http://127.0.0.1:{normal_port}", normal.pid),
            }
            results, refused = asyncio.run(measure(servers, arguments.inputs))
    print(
        f"{'store':<14} {'CPU ms/input':>12} {'loop thread':>11} {'other threads':>13}"
        f" {'inputs/s':>8}   per round"
    )
    for store, (cpu_ms, rate, loop_ms, *rounds) in results.items():
        shown = " ".join(f"{value:.2f}" for value in rounds)
        print(
            f"{store:<14} {cpu_ms:12.2f} {loop_ms:11.2f} {cpu_ms - loop_ms:13.2f}"
            f" {rate:8.0f}   {shown}"
        )
    for store, label in (("sqlite", "sqlite's (FULL, default)"), (NORMAL_LABEL, "NORMAL's")):
        extra = results[store][0] - results["memory"][0]
        differences = [
            durable - memory
            for memory, durable in zip(results["memory"][3:], results[store][3:], strict=True)
        ]
        low, middle, high = statistics.quantiles(differences, n=4)
        print(
            f"{label} extra CPU per input: {extra:.2f} ms over all rounds; per round median"
            f" {middle:.2f} ms (quartiles {low:.2f} … {high:.2f}); other threads"
            f" {results[store][0] - results[store][2]:.2f} ms; goal ≤ 0.5 ms (issue 29)"
        )
    print(
        f"machine load (1-minute average, {os.cpu_count()} cores): {load_before:.1f} at start,"
        f" {os.getloadavg()[0]:.1f} at end"
    )
    if refused:
        print(f"({refused} inputs were refused as overload and sent again)")
    if not arguments.no_overload:
        capacity = min(results["memory"][1], results["sqlite"][1])
        overload_run(OVERLOAD_FACTOR * capacity, f"{OVERLOAD_FACTOR:g}× the closed-loop rate above")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
