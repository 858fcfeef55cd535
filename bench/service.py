"""The service under load on loopback: REST and WebSocket latency and throughput.

Run with ``make bench`` (or ``python bench/service.py``). Two servers run as
subprocesses on 127.0.0.1, each on uvicorn: the service (memory store, so the
numbers are the service's own cost, not the disk's fsync) and a bare FastAPI
app that validates the same 20-track body with the same wire model and echoes
it. The load generator is this process. Prints a table; never asserts a time.
Bounded: each measurement runs for a fixed number of requests or seconds.

REST throughput is measured in short windows that alternate between the bare
endpoint and the service (the order flips each round): the speed of a shared
2-core VM drifts by tens of percent within seconds, so each round's ratio
compares neighbouring windows and the floor is checked on the median round.
Both servers run without an access log (uvicorn's, one line per request).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import socket
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import httpx
import numpy as np
from fastapi import FastAPI, WebSocket
from starlette.websockets import WebSocketDisconnect
from websockets.asyncio.client import connect

from api_schemas.reports import TrackReport
from api_schemas.ws import client_message_adapter

sys.path.insert(0, str(Path(__file__).resolve().parent))

from machine import describe_machine

ROOT = Path(__file__).resolve().parents[1]
TRACKS = 20
LATENCY_REQUESTS = 300
THROUGHPUT_SECONDS = 6.0
"""Per endpoint, in :data:`THROUGHPUT_ROUNDS` windows alternating with the other endpoint's."""
THROUGHPUT_ROUNDS = 6
WORKERS = 8
WS_WINDOW = 16
"""Messages in flight on one WebSocket during the throughput run (pipelining, bounded)."""
WS_SECONDS = 3.0
PREPARED_PER_WORKER = 3000
"""Service bodies built per client before the throughput run (more than 6 s can use here)."""
BIG_TRACKS = 1000
BIG_REPEATS = 5
START_TIMEOUT_S = 30.0
FLOOR_REST_RATIO = 0.5
FLOOR_WS_P50_MS = 3.0


# ---------------------------------------------------------------- payloads
def track_list(sensor: str, time_s: float, count: int) -> dict[str, Any]:
    """``count`` targets on a grid, each reported by ``sensor`` at ``time_s``."""
    rng = np.random.default_rng(int(time_s * 1000) % 2**31)
    tracks = []
    for index in range(count):
        x0, y0 = 300.0 * (index % 40), 300.0 * (index // 40)
        state = np.array([x0 + 5.0 * time_s, 5.0, y0 - 2.0 * time_s, -2.0]) + rng.normal(0, 1, 4)
        tracks.append(
            {
                "id": f"t{index}",
                "state": [round(float(v), 4) for v in state],
                "covariance": [[4, 0, 0, 0], [0, 1, 0, 0], [0, 0, 4, 0], [0, 0, 0, 1]],
            }
        )
    return {"sensor": sensor, "time": time_s, "tracks": tracks}


def config(sensors: list[str]) -> dict[str, Any]:
    return {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "sensors": [{"id": sensor} for sensor in sensors],
    }


# ---------------------------------------------------------------- servers
def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def bare_app() -> Any:
    """FastAPI that validates a track list with the service's model and echoes it."""
    app = FastAPI()

    @app.post("/echo")
    def echo(report: TrackReport) -> TrackReport:
        return report

    @app.websocket("/echo")
    async def echo_ws(websocket: WebSocket) -> None:
        await websocket.accept()
        try:
            while True:
                message = client_message_adapter.validate_json(await websocket.receive_text())
                await websocket.send_text(message.model_dump_json())
        except WebSocketDisconnect:
            return

    return app


@contextmanager
def running(
    command: list[str],
    port: int,
    environment: Mapping[str, str] | None = None,
    ready: str = "/openapi.json",
) -> Iterator[subprocess.Popen[bytes]]:
    """``command`` serving on ``port`` once ``ready`` answers 200; terminated on exit."""
    process = subprocess.Popen(
        command,
        cwd=ROOT,
        env=os.environ
        | {"CREDAL_ADMIN_TOKEN": "bench-admin-token-0123456789abcdef"}
        | dict(environment or {}),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + START_TIMEOUT_S
        while True:
            try:
                if httpx.get(f"http://127.0.0.1:{port}{ready}", timeout=1).status_code == 200:
                    break
            except httpx.TransportError:
                pass
            if process.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"server {command} did not start")
            time.sleep(0.05)
        yield process
    finally:
        process.terminate()
        process.wait(timeout=START_TIMEOUT_S)


@contextmanager
def server(command: list[str], port: int) -> Iterator[str]:
    """The URL of ``command`` serving on ``port`` (see :func:`running`)."""
    with running(command, port):
        yield f"http://127.0.0.1:{port}"


def service_command(port: int, store: str = "memory") -> list[str]:
    return [
        sys.executable,
        "-m",
        "app.cli",
        "serve",
        "--host",
        "127.0.0.1",
        "--port",
        str(port),
        "--store",
        store,
        "--no-access-log",  # as the bare endpoint (log level warning): no line per request
    ]


def bare_command(port: int) -> list[str]:
    return [sys.executable, str(Path(__file__).resolve()), "--serve-bare", str(port)]


def step_totals(url: str) -> tuple[float, int]:
    """Seconds spent in engine steps so far (``credal_fusion_step_seconds``, all kinds), and how many."""
    total, count = 0.0, 0
    for line in httpx.get(f"{url}/metrics").text.splitlines():
        if line.startswith("credal_fusion_step_seconds_sum"):
            total += float(line.rsplit(" ", 1)[1])
        elif line.startswith("credal_fusion_step_seconds_count"):
            count += int(float(line.rsplit(" ", 1)[1]))
    return total, count


def mean_step_ms(url: str, before: tuple[float, int]) -> float:
    """Mean engine step (ms) of the inputs applied since ``before`` (a :func:`step_totals`)."""
    total, count = step_totals(url)
    applied = count - before[1]
    return 1e3 * (total - before[0]) / applied if applied > 0 else float("nan")


# ---------------------------------------------------------------- load
def percentiles(samples_ms: list[float]) -> tuple[float, float]:
    ordered = sorted(samples_ms)
    p99 = ordered[min(len(ordered) - 1, round(0.99 * (len(ordered) - 1)))]
    return statistics.median(ordered), p99


def rest_latency(
    url: str, path: str, headers: dict[str, str], bodies: Callable[[int], bytes]
) -> tuple[float, float]:
    samples = []
    with httpx.Client(
        base_url=url, headers=headers | {"Content-Type": "application/json"}
    ) as client:
        for index in range(LATENCY_REQUESTS + 20):
            body = bodies(index)
            started = time.perf_counter()
            answer = client.post(path, content=body)
            elapsed = (time.perf_counter() - started) * 1e3
            assert answer.status_code == 200, answer.text
            if index >= 20:
                samples.append(elapsed)
    return percentiles(samples)


async def rest_window(
    clients: list[httpx.AsyncClient],
    path: str,
    bodies: Callable[[int, int], bytes],
    seconds: float,
    sent: list[int],
) -> float:
    """Requests per second of ``clients`` (one per worker) posting for ``seconds``;
    ``sent[w]``: worker ``w``'s next body index (kept from one window to the next)."""
    done = 0
    stop = time.perf_counter() + seconds

    async def worker(number: int) -> None:
        nonlocal done
        while time.perf_counter() < stop:
            answer = await clients[number].post(path, content=bodies(number, sent[number]))
            assert answer.status_code == 200, answer.text
            sent[number] += 1
            done += 1

    started = time.perf_counter()
    await asyncio.gather(*(worker(number) for number in range(len(clients))))
    return done / (time.perf_counter() - started)


Endpoint = tuple[str, str, dict[str, str], Callable[[int, int], bytes]]
"""Base URL, path, headers, and the body of worker ``w``'s ``i``-th request."""


async def interleaved_throughput(
    bare: Endpoint, service: Endpoint
) -> tuple[float, float, list[float]]:
    """REST throughput of both endpoints over :data:`THROUGHPUT_ROUNDS` alternating windows.

    Each endpoint has its own :data:`WORKERS` clients, kept from window to
    window. This machine's speed drifts by tens of percent within seconds, so
    each round's ratio compares neighbouring windows (the order flips each
    round). Returns the median rate of each and every round's ratio service / bare.
    """
    window = THROUGHPUT_SECONDS / THROUGHPUT_ROUNDS
    endpoints = (bare, service)
    rates: tuple[list[float], list[float]] = ([], [])
    sent = ([0] * WORKERS, [0] * WORKERS)
    async with contextlib.AsyncExitStack() as stack:
        clients = [
            [
                await stack.enter_async_context(
                    httpx.AsyncClient(
                        base_url=url, headers=headers | {"Content-Type": "application/json"}
                    )
                )
                for _ in range(WORKERS)
            ]
            for url, _, headers, _ in endpoints
        ]
        for round_number in range(THROUGHPUT_ROUNDS):
            for which in (1, 0) if round_number % 2 else (0, 1):
                _, path, _, bodies = endpoints[which]
                rates[which].append(
                    await rest_window(clients[which], path, bodies, window, sent[which])
                )
    ratios = [s / b for s, b in zip(rates[1], rates[0], strict=True)]
    return statistics.median(rates[0]), statistics.median(rates[1]), ratios


async def ws_measure(
    url: str, headers: dict[str, str], messages: Callable[[int], str]
) -> tuple[float, float, float]:
    """Round-trip p50/p99 (one message at a time), then throughput with ``WS_WINDOW`` in flight."""
    samples = []
    async with connect(url, additional_headers=headers, max_size=None) as websocket:
        if "echo" not in url:
            await websocket.recv()  # ack
        for index in range(LATENCY_REQUESTS + 20):
            message = messages(index)  # built before the clock starts, as for REST
            started = time.perf_counter()
            await websocket.send(message)
            answer = json.loads(await websocket.recv())
            elapsed = (time.perf_counter() - started) * 1e3
            assert answer.get("type") != "error", answer
            if index >= 20:
                samples.append(elapsed)
        base = LATENCY_REQUESTS + 20
        window = asyncio.Semaphore(WS_WINDOW)
        sent = 0
        stop = time.perf_counter() + WS_SECONDS
        started = time.perf_counter()

        async def sender() -> None:
            nonlocal sent
            while time.perf_counter() < stop:
                await window.acquire()
                await websocket.send(messages(base + sent))
                sent += 1

        send_task = asyncio.create_task(sender())
        received = 0
        while not (send_task.done() and received >= sent):
            await websocket.recv()
            received += 1
            window.release()
        await send_task
        rate = received / (time.perf_counter() - started)
    p50, p99 = percentiles(samples)
    return p50, p99, rate


def main() -> int:
    print(describe_machine())
    print(f"loopback; {TRACKS}-track report; {LATENCY_REQUESTS} sequential requests for latency,")
    print(
        f"{WORKERS} concurrent clients for {THROUGHPUT_SECONDS:.0f} s per REST endpoint, in "
        f"{THROUGHPUT_ROUNDS} windows alternating bare / service,"
    )
    print(
        f"one client, {WS_WINDOW} messages in flight for {WS_SECONDS:.0f} s per WebSocket; "
        "service on the memory store"
    )
    sensors = [f"s{index}" for index in range(WORKERS)]
    service_port, bare_port = free_port(), free_port()
    rows: list[tuple[str, float, float, float]] = []
    steps: dict[str, float] = {}  # mean engine step inside the server during a run (/metrics)
    with (
        server(service_command(service_port), service_port) as service_url,
        server(bare_command(bare_port), bare_port) as bare_url,
    ):
        echo = {i: json.dumps(track_list("s0", 1.0 + i, TRACKS)).encode() for i in range(2)}
        bare_p50, bare_p99 = rest_latency(bare_url, "/echo", {}, lambda i: echo[i % 2])

        created = httpx.post(f"{service_url}/v1/sessions", json=config(sensors)).json()
        headers = {"Authorization": f"Bearer {created['token']}"}
        path = f"/v1/sessions/{created['id']}/tracks"
        service_p50, service_p99 = rest_latency(
            service_url,
            path,
            headers,
            lambda i: json.dumps(track_list("s0", 1.0 + i, TRACKS)).encode(),
        )
        offset = LATENCY_REQUESTS + 100.0
        prepared = [
            [
                json.dumps(track_list(sensors[w], offset + i + w / WORKERS, TRACKS)).encode()
                for i in range(PREPARED_PER_WORKER)
            ]
            for w in range(WORKERS)
        ]

        def service_body(w: int, i: int) -> bytes:
            """Bodies built before the clock starts (the bare endpoint's are too)."""
            if i < PREPARED_PER_WORKER:
                return prepared[w][i]
            return json.dumps(track_list(sensors[w], offset + i + w / WORKERS, TRACKS)).encode()

        before = step_totals(service_url)
        bare_rate, service_rate, ratios = asyncio.run(
            interleaved_throughput(
                (bare_url, "/echo", {}, lambda w, i: echo[i % 2]),
                (service_url, path, headers, service_body),
            )
        )
        rows.append(("REST bare validate+echo", bare_p50, bare_p99, bare_rate))
        rows.append(("REST service /tracks", service_p50, service_p99, service_rate))
        steps["REST throughput (8 sensors)"] = mean_step_ms(service_url, before)

        ws_bare = bare_url.replace("http://", "ws://") + "/echo"
        bare_messages = [json.dumps(track_list("s0", 1.0, TRACKS) | {"type": "tracks"})]
        rows.append(
            (
                "WS bare validate+echo",
                *asyncio.run(ws_measure(ws_bare, {}, lambda i: bare_messages[0])),
            )
        )

        created = httpx.post(f"{service_url}/v1/sessions", json=config(sensors)).json()
        ws_url = service_url.replace("http://", "ws://") + f"/v1/sessions/{created['id']}/stream"
        ws_headers = {"Authorization": f"Bearer {created['token']}"}
        before = step_totals(service_url)
        rows.append(
            (
                "WS service stream",
                *asyncio.run(
                    ws_measure(
                        ws_url,
                        ws_headers,
                        lambda i: json.dumps(
                            track_list("s0", 1.0 + i, TRACKS) | {"type": "tracks"}
                        ),
                    )
                ),
            )
        )

        steps["WS stream (1 sensor)"] = mean_step_ms(service_url, before)

        created = httpx.post(f"{service_url}/v1/sessions", json=config(["a", "b"])).json()
        headers = {"Authorization": f"Bearer {created['token']}"}
        big = []
        with httpx.Client(base_url=service_url, headers=headers, timeout=120) as client:
            for index in range(BIG_REPEATS + 1):
                body = json.dumps(track_list("ab"[index % 2], 1.0 + index / 2, BIG_TRACKS)).encode()
                started = time.perf_counter()
                answer = client.post(
                    f"/v1/sessions/{created['id']}/tracks",
                    content=body,
                    headers={"Content-Type": "application/json"},
                )
                assert answer.status_code == 200, answer.text[:300]
                if index:
                    big.append((time.perf_counter() - started) * 1e3)

    print(f"{'':26} {'p50 ms':>8} {'p99 ms':>8} {'per s':>8}")
    for name, p50, p99, rate in rows:
        print(f"{name:26} {p50:8.2f} {p99:8.2f} {rate:8.0f}")
    print(
        f"{BIG_TRACKS}-track report against {BIG_TRACKS} fused tracks (REST): "
        f"median {statistics.median(big):.0f} ms, max {max(big):.0f} ms over {BIG_REPEATS}"
    )
    for name, step_ms in steps.items():
        print(f"engine step inside the server, {name}: mean {step_ms:.2f} ms")
    print(
        "REST throughput service / bare, by round (neighbouring windows): "
        + ", ".join(f"{ratio:.0%}" for ratio in ratios)
    )
    ratio = statistics.median(ratios)
    print(
        f"floor: REST throughput >= {FLOOR_REST_RATIO:.0%} of bare (median round) -> "
        f"{'met' if ratio >= FLOOR_REST_RATIO else 'NOT met'} ({ratio:.0%}); "
        f"WS p50 <= {FLOOR_WS_P50_MS:.0f} ms -> "
        f"{'met' if rows[3][1] <= FLOOR_WS_P50_MS else 'NOT met'} ({rows[3][1]:.2f} ms)"
    )
    return 0


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--serve-bare":
        import uvicorn

        uvicorn.run(bare_app(), host="127.0.0.1", port=int(sys.argv[2]), log_level="warning")
        raise SystemExit(0)
    raise SystemExit(main())
