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

WebSocket round trips are measured the same way: :data:`WS_ROUNDS` windows of
:data:`WS_PER_ROUND` sequential messages alternate between the bare echo and
the service (after :data:`WS_WARMUP` messages on each connection); the floor
is checked on the p50 of every service sample. On a loaded machine a round
trip is mostly waiting for a CPU, so each server's event-loop thread is also
measured from the kernel's scheduler statistics: the CPU time it used per
message, and how long it was runnable but waiting for a CPU. The engine's
part is shown next to it twice: the apply step inside the server
(``credal_fusion_step_seconds`` from ``/metrics``: wall time of translating,
stepping and serialising) and the engine step alone, in this process, as CPU
time over the same inputs — what is left of the server's CPU per message is
the application's own cost (WebSocket, parsing, validation, logging).
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
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx
import numpy as np
from fastapi import FastAPI, WebSocket
from starlette.websockets import WebSocketDisconnect
from websockets.asyncio.client import ClientConnection, connect

from api_schemas.reports import TrackReport
from app.inputs import client_messages

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
WS_ROUNDS = 5
WS_PER_ROUND = 200
"""Sequential messages per endpoint and round of the WebSocket latency measurement."""
WS_WARMUP = 50
"""Messages sent on each WebSocket before any is timed (caches, the engine's first tracks)."""
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
                message = client_messages().validate_json(await websocket.receive_text())
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
    start_timeout_s: float = START_TIMEOUT_S,
) -> Iterator[subprocess.Popen[bytes]]:
    """``command`` serving on ``port`` once ``ready`` answers 200 (within ``start_timeout_s``);
    terminated on exit."""
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
        deadline = time.monotonic() + start_timeout_s
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
        process.wait(timeout=start_timeout_s)


@contextmanager
def server(command: list[str], port: int) -> Iterator[str]:
    """The URL of ``command`` serving on ``port`` (see :func:`running`)."""
    with running(command, port):
        yield f"http://127.0.0.1:{port}"


@contextmanager
def server_process(command: list[str], port: int) -> Iterator[tuple[str, int]]:
    """:func:`server`, and the server's process id."""
    with running(command, port) as process:
        yield f"http://127.0.0.1:{port}", process.pid


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


def process_cpu_s(pid: int) -> float:
    """CPU seconds (user + system, every thread, ended ones too) of process ``pid`` so far
    (Linux ``/proc/<pid>/stat``, in clock ticks; NaN where there is none)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return float("nan")
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@dataclass(frozen=True)
class StepTotals:
    """What the service's ``/metrics`` says of the inputs applied so far (every kind)."""

    apply_s: float
    """Wall time of the apply steps (``credal_fusion_step_seconds``: translate, step, serialise)."""
    engine_cpu_s: float
    """CPU time of the engine steps alone (``credal_fusion_engine_cpu_seconds``)."""
    count: int

    def since(self, before: StepTotals) -> StepTotals:
        return StepTotals(
            self.apply_s - before.apply_s,
            self.engine_cpu_s - before.engine_cpu_s,
            self.count - before.count,
        )

    def mean_ms(self, seconds: float) -> float:
        """``seconds`` (one of the sums) per input, in ms."""
        return 1e3 * seconds / self.count if self.count > 0 else float("nan")


def step_totals(url: str) -> StepTotals:
    """The apply-step and engine-step totals of the service at ``url`` so far."""
    sums = {"credal_fusion_step_seconds": 0.0, "credal_fusion_engine_cpu_seconds": 0.0}
    count = 0
    for line in httpx.get(f"{url}/metrics").text.splitlines():
        name, value = line.split("{", 1)[0].split(" ", 1)[0], line.rsplit(" ", 1)[-1]
        if name.endswith("_sum") and name.removesuffix("_sum") in sums:
            sums[name.removesuffix("_sum")] += float(value)
        elif name == "credal_fusion_step_seconds_count":
            count += int(float(value))
    return StepTotals(
        sums["credal_fusion_step_seconds"], sums["credal_fusion_engine_cpu_seconds"], count
    )


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
) -> tuple[float, float, list[float], tuple[int, int]]:
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
    answered = (sum(sent[0]), sum(sent[1]))
    return statistics.median(rates[0]), statistics.median(rates[1]), ratios, answered


def loop_thread_times(pid: int) -> tuple[float, float]:
    """Seconds the main (event-loop) thread of process ``pid`` has run on a CPU, and has
    waited runnable for one (Linux ``/proc/<pid>/schedstat``; NaN where there is none)."""
    try:
        on_cpu, waiting, _ = Path(f"/proc/{pid}/schedstat").read_text().split()
    except (OSError, ValueError):
        return float("nan"), float("nan")
    return int(on_cpu) / 1e9, int(waiting) / 1e9


@dataclass
class RoundTrips:
    """Sequential WebSocket round trips of one endpoint, over every latency round."""

    samples_ms: list[float] = field(default_factory=list)
    round_p50_ms: list[float] = field(default_factory=list)
    cpu_s: float = 0.0
    """The server's event-loop thread: CPU time while its rounds ran."""
    waited_s: float = 0.0
    """The same thread: time runnable but waiting for a CPU."""
    steps: StepTotals = StepTotals(0.0, 0.0, 0)
    """The service's apply and engine steps during its rounds (from ``/metrics``)."""

    def per_message_ms(self, seconds: float) -> float:
        return 1e3 * seconds / len(self.samples_ms)


@dataclass
class Stream:
    """An open WebSocket under test: its server process and the messages it is sent."""

    websocket: ClientConnection
    pid: int
    message: Callable[[int], str]
    metrics_url: str | None = None
    """The service's base URL (its ``/metrics`` are read around each round); None: bare."""
    sent: int = 0

    async def round_trip(self) -> float:
        text = self.message(self.sent)  # built before the clock starts, as for REST
        self.sent += 1
        started = time.perf_counter()
        await self.websocket.send(text)
        answer = json.loads(await self.websocket.recv())
        elapsed = (time.perf_counter() - started) * 1e3
        assert answer.get("type") != "error", answer
        return elapsed

    async def timed_round(self, trips: RoundTrips) -> None:
        steps = step_totals(self.metrics_url) if self.metrics_url else None
        cpu, waited = loop_thread_times(self.pid)
        samples = [await self.round_trip() for _ in range(WS_PER_ROUND)]
        cpu_after, waited_after = loop_thread_times(self.pid)
        if self.metrics_url and steps:
            applied = step_totals(self.metrics_url).since(steps)
            trips.steps = StepTotals(
                trips.steps.apply_s + applied.apply_s,
                trips.steps.engine_cpu_s + applied.engine_cpu_s,
                trips.steps.count + applied.count,
            )
        trips.samples_ms.extend(samples)
        trips.round_p50_ms.append(statistics.median(samples))
        trips.cpu_s += cpu_after - cpu
        trips.waited_s += waited_after - waited

    async def throughput(self) -> float:
        """Messages per second with :data:`WS_WINDOW` in flight for :data:`WS_SECONDS`."""
        window = asyncio.Semaphore(WS_WINDOW)
        base, sent = self.sent, 0
        stop = time.perf_counter() + WS_SECONDS
        started = time.perf_counter()

        async def sender() -> None:
            nonlocal sent
            while time.perf_counter() < stop:
                await window.acquire()
                await self.websocket.send(self.message(base + sent))
                sent += 1

        send_task = asyncio.create_task(sender())
        received = 0
        while not (send_task.done() and received >= sent):
            await self.websocket.recv()
            received += 1
            window.release()
        await send_task
        self.sent += sent
        return received / (time.perf_counter() - started)


async def ws_measure(
    bare: tuple[str, int, Callable[[int], str]],
    service: tuple[str, int, dict[str, str], Callable[[int], str]],
) -> tuple[tuple[RoundTrips, RoundTrips], tuple[float, float]]:
    """Round trips of the bare echo and the service in alternating rounds (one message at
    a time, after :data:`WS_WARMUP`), then each one's throughput with ``WS_WINDOW`` in flight."""
    bare_url, bare_pid, bare_message = bare
    service_url, service_pid, headers, service_message = service
    service_http = service_url.replace("ws://", "http://").split("/v1/", 1)[0]
    trips = (RoundTrips(), RoundTrips())
    async with (
        connect(bare_url, max_size=None) as bare_socket,
        connect(service_url, additional_headers=headers, max_size=None) as service_socket,
    ):
        await service_socket.recv()  # ack
        streams = (
            Stream(bare_socket, bare_pid, bare_message),
            Stream(service_socket, service_pid, service_message, service_http),
        )
        for stream in streams:
            for _ in range(WS_WARMUP):
                await stream.round_trip()
        for round_number in range(WS_ROUNDS):
            for which in (1, 0) if round_number % 2 else (0, 1):
                await streams[which].timed_round(trips[which])
        rates = (await streams[0].throughput(), await streams[1].throughput())
    return trips, rates


def main() -> int:
    print(describe_machine())
    print(f"loopback; {TRACKS}-track report; {LATENCY_REQUESTS} sequential requests for latency,")
    print(
        f"{WORKERS} concurrent clients for {THROUGHPUT_SECONDS:.0f} s per REST endpoint, in "
        f"{THROUGHPUT_ROUNDS} windows alternating bare / service,"
    )
    print(
        f"WebSocket: {WS_ROUNDS} rounds of {WS_PER_ROUND} sequential messages alternating bare / "
        f"service (after {WS_WARMUP}), then {WS_WINDOW} in flight for {WS_SECONDS:.0f} s each; "
        "service on the memory store"
    )
    load_before = os.getloadavg()
    sensors = [f"s{index}" for index in range(WORKERS)]
    service_port, bare_port = free_port(), free_port()
    rows: list[tuple[str, float, float, float]] = []
    with (
        server_process(service_command(service_port), service_port) as (service_url, service_pid),
        server_process(bare_command(bare_port), bare_port) as (bare_url, bare_pid),
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
        cpu_before = (process_cpu_s(bare_pid), process_cpu_s(service_pid))
        bare_rate, service_rate, ratios, answered = asyncio.run(
            interleaved_throughput(
                (bare_url, "/echo", {}, lambda w, i: echo[i % 2]),
                (service_url, path, headers, service_body),
            )
        )
        rest_cpu_ms = (
            1e3 * (process_cpu_s(bare_pid) - cpu_before[0]) / answered[0],
            1e3 * (process_cpu_s(service_pid) - cpu_before[1]) / answered[1],
        )
        rows.append(("REST bare validate+echo", bare_p50, bare_p99, bare_rate))
        rows.append(("REST service /tracks", service_p50, service_p99, service_rate))
        rest_steps = step_totals(service_url).since(before)

        ws_bare = bare_url.replace("http://", "ws://") + "/echo"
        bare_message = json.dumps(track_list("s0", 1.0, TRACKS) | {"type": "tracks"})
        created = httpx.post(f"{service_url}/v1/sessions", json=config(sensors)).json()
        ws_url = service_url.replace("http://", "ws://") + f"/v1/sessions/{created['id']}/stream"
        ws_headers = {"Authorization": f"Bearer {created['token']}"}

        def ws_message(index: int) -> str:
            return json.dumps(track_list("s0", 1.0 + index, TRACKS) | {"type": "tracks"})

        (bare_trips, service_trips), (bare_ws_rate, service_ws_rate) = asyncio.run(
            ws_measure(
                (ws_bare, bare_pid, lambda index: bare_message),
                (ws_url, service_pid, ws_headers, ws_message),
            )
        )
        for name, trips, rate in (
            ("WS bare validate+echo", bare_trips, bare_ws_rate),
            ("WS service stream", service_trips, service_ws_rate),
        ):
            rows.append((name, *percentiles(trips.samples_ms), rate))

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
    load_after = os.getloadavg()

    print(f"{'':26} {'p50 ms':>8} {'p99 ms':>8} {'per s':>8}")
    for name, p50, p99, rate in rows:
        print(f"{name:26} {p50:8.2f} {p99:8.2f} {rate:8.0f}")
    print(
        f"{BIG_TRACKS}-track report against {BIG_TRACKS} fused tracks (REST): "
        f"median {statistics.median(big):.0f} ms, max {max(big):.0f} ms over {BIG_REPEATS}"
    )
    print(
        "REST throughput service / bare, by round (neighbouring windows): "
        + ", ".join(f"{ratio:.0%}" for ratio in ratios)
    )
    print(
        f"REST server CPU per request (all threads): bare {rest_cpu_ms[0]:.2f} ms, service "
        f"{rest_cpu_ms[1]:.2f} ms (bare / service {rest_cpu_ms[0] / rest_cpu_ms[1]:.0%}); "
        f"service apply step {rest_steps.mean_ms(rest_steps.apply_s):.2f} ms wall, "
        f"engine step {rest_steps.mean_ms(rest_steps.engine_cpu_s):.2f} ms CPU (8 sensors)"
    )
    print(
        f"{'WS round trips':26} {'p50 ms':>8} {'p90 ms':>8} {'CPU/msg':>8} {'waited':>8}  p50 by round"
    )
    for name, trips in (("bare validate+echo", bare_trips), ("service stream", service_trips)):
        ordered = sorted(trips.samples_ms)
        print(
            f"{name:26} {statistics.median(ordered):8.2f} {ordered[int(0.9 * len(ordered))]:8.2f} "
            f"{trips.per_message_ms(trips.cpu_s):8.2f} {trips.per_message_ms(trips.waited_s):8.2f}  "
            + " ".join(f"{p50:.2f}" for p50 in trips.round_p50_ms)
        )
    ws_p50 = statistics.median(service_trips.samples_ms)
    service_cpu_ms = service_trips.per_message_ms(service_trips.cpu_s)
    ws_steps = service_trips.steps
    apply_ms, engine_ms = (
        ws_steps.mean_ms(ws_steps.apply_s),
        ws_steps.mean_ms(ws_steps.engine_cpu_s),
    )
    print(
        "  (CPU/msg, waited: the server's event-loop thread per message, on a CPU and "
        "runnable but waiting for one)\n"
        f"WS service per message: apply step {apply_ms:.2f} ms wall ({apply_ms / ws_p50:.0%} "
        f"of the p50); engine step {engine_ms:.2f} ms CPU = {engine_ms / service_cpu_ms:.0%} "
        f"of the server's {service_cpu_ms:.2f} ms CPU; the application's own: "
        f"{service_cpu_ms - engine_ms:.2f} ms CPU (bare echo: "
        f"{bare_trips.per_message_ms(bare_trips.cpu_s):.2f} ms)"
    )
    print(
        f"machine load (1-minute average, {os.cpu_count()} cores): {load_before[0]:.1f} at start, "
        f"{load_after[0]:.1f} at end"
    )
    ratio = statistics.median(ratios)
    print(
        f"floor: REST throughput >= {FLOOR_REST_RATIO:.0%} of bare (median round) -> "
        f"{'met' if ratio >= FLOOR_REST_RATIO else 'NOT met'} ({ratio:.0%}); "
        f"WS p50 <= {FLOOR_WS_P50_MS:.0f} ms -> "
        f"{'met' if ws_p50 <= FLOOR_WS_P50_MS else 'NOT met'} ({ws_p50:.2f} ms)"
    )
    return 0


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--serve-bare":
        import uvicorn

        uvicorn.run(bare_app(), host="127.0.0.1", port=int(sys.argv[2]), log_level="warning")
        raise SystemExit(0)
    raise SystemExit(main())
