"""What durability costs: the service's CPU per input on the memory store and on sqlite.

Run with ``make bench`` (or ``python bench/store_cost.py [--seconds S]``). Two
service processes run on loopback with the default settings, one per store
(``memory``, and ``sqlite`` on a fresh file: WAL, ``synchronous=FULL``, an
fsync per commit, group commit). The load is :data:`SESSIONS` sessions of one
detecting sensor each (:func:`scan`: 20 targets and some clutter a scan),
every one fed by its own client over REST, one request at a time (closed
loop: the next input is sent when the previous one is acknowledged, i.e.
durable). Windows alternate between the two servers (:data:`ROUNDS` each, the
order flipping every round) so a drift of the shared machine's speed falls on
both; each server's CPU (user + system, every thread) is read from
``/proc/<pid>/stat`` around its windows. Prints CPU per input for each store
and sqlite's extra, over all windows and as the median over rounds of the
difference between neighbouring windows; never asserts a time.
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import orjson

sys.path.insert(0, str(Path(__file__).resolve().parent))

from machine import describe_machine
from service import free_port, process_cpu_s, running, service_command

SESSIONS = 16
"""Sessions (sensors), each with its own client sending one input at a time."""
TRACKS = 20
ROUNDS = 8
SECONDS = 1.5
"""Per window (one server, one round)."""
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


class Load:
    """:data:`SESSIONS` sessions on one server and a client for each."""

    def __init__(self, url: str) -> None:
        self.url = url
        self.clients: list[httpx.AsyncClient] = []
        self.paths: list[str] = []
        self.sent = [0] * SESSIONS

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

    async def window(self, seconds: float) -> int:
        """Inputs acknowledged by the server in ``seconds`` (every client sending in turn)."""
        stop = time.perf_counter() + seconds
        done = 0

        async def client(index: int) -> None:
            nonlocal done
            while time.perf_counter() < stop:
                body = scan(f"s{index}", self.sent[index])
                answer = await self.clients[index].post(self.paths[index], content=body)
                assert answer.status_code == 200, answer.text
                self.sent[index] += 1
                done += 1

        await asyncio.gather(*(client(index) for index in range(SESSIONS)))
        return done

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


async def measure(servers: dict[str, tuple[str, int]], seconds: float) -> dict[str, list[float]]:
    """Per store: CPU ms per input in every round, and inputs/s (the last entry)."""
    loads = {store: Load(url) for store, (url, _) in servers.items()}
    for load in loads.values():
        await load.open()
        await load.warm_up()
    cpu = {store: 0.0 for store in servers}
    inputs = {store: 0 for store in servers}
    per_round: dict[str, list[float]] = {store: [] for store in servers}
    elapsed = {store: 0.0 for store in servers}
    order = list(servers)
    for round_ in range(ROUNDS):
        for store in order if round_ % 2 == 0 else reversed(order):
            pid = servers[store][1]
            before, started = process_cpu_s(pid), time.perf_counter()
            done = await loads[store].window(seconds)
            used = process_cpu_s(pid) - before
            elapsed[store] += time.perf_counter() - started
            cpu[store] += used
            inputs[store] += done
            per_round[store].append(1e3 * used / max(done, 1))
    for load in loads.values():
        await load.close()
    return {
        store: [1e3 * cpu[store] / max(inputs[store], 1), inputs[store] / elapsed[store]]
        + per_round[store]
        for store in servers
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=SECONDS, help="per window")
    arguments = parser.parse_args()
    print(describe_machine())
    print(
        f"load: {SESSIONS} sessions × 1 client each, closed loop, {TRACKS} targets + {CLUTTER} clutter a scan"
        " (REST /detections),"
        f" default settings; {ROUNDS} alternating windows of {arguments.seconds:.1f} s per store"
    )
    with tempfile.TemporaryDirectory() as directory:
        memory_port, sqlite_port = free_port(), free_port()
        database = Path(directory) / "bench.db"
        with (
            running(service_command(memory_port, "memory"), memory_port) as memory,
            running(service_command(sqlite_port, f"sqlite:{database}"), sqlite_port) as sqlite,
        ):
            servers = {
                "memory": (f"http://127.0.0.1:{memory_port}", memory.pid),
                "sqlite": (f"http://127.0.0.1:{sqlite_port}", sqlite.pid),
            }
            results = asyncio.run(measure(servers, arguments.seconds))
    print(f"{'store':<8} {'CPU ms/input':>13} {'inputs/s':>9}   per round")
    for store, (cpu_ms, rate, *rounds) in results.items():
        shown = " ".join(f"{value:.2f}" for value in rounds)
        print(f"{store:<8} {cpu_ms:13.2f} {rate:9.0f}   {shown}")
    extra = results["sqlite"][0] - results["memory"][0]
    paired = statistics.median(
        sqlite - memory
        for memory, sqlite in zip(results["memory"][2:], results["sqlite"][2:], strict=True)
    )
    print(
        f"sqlite's extra CPU per input: {extra:.2f} ms over all windows, {paired:.2f} ms median"
        " of the rounds (neighbouring windows); goal ≤ 0.5 ms (issue 29)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
