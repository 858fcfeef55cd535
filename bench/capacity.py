"""Capacity: how many detecting sensors one machine serves, per core, per store (issue 29).

Measured as an engineer sizing a deployment would: K WebSocket ``stream``
sessions, each one detecting sensor sending a scan of 20 targets with clutter
(P_D 0.9, σ 5 m, 2 false detections a scan on average, uniform over its 40 km
square field of view) at r Hz, paced as a sensor is (a scan is sent when it is
due, whether or not the previous one was answered). The load generator is a
process of its own (this script with ``--load``); the server's CPU is read
from ``/proc`` (the ``serve`` process and its workers), its RSS too. The same
payload goes to a bare FastAPI WebSocket echo (``bench/service.py``'s: it
validates each message with the service's wire model and echoes it) in the
same run: the transport's own cost.

Grid: K × r in :data:`GRID` (the issue's), then a ladder of 50 sensors at rising rates
(:data:`LADDER`) up to the first rate over capacity, for each store (memory; sqlite on a fresh file;
redis under a prefix of its own on ``CREDAL_CAPACITY_REDIS_URL``, default the
local server) with 1 worker, and sqlite and redis with 2 (``serve --workers``;
the memory store is one process's). Each cell: the K sessions are created and
their streams opened, :data:`WARMUP_S` of scans (at least 5: their tracks confirm), then
:data:`WINDOW_S` measured: scans answered per second, the p50 and p99 of a
scan's round trip (sent → answered), the server's CPU per scan. A cell whose
answers do not keep up (fewer than 95 % of the scans sent in the window
answered within it, or p99 ≥ 50 ms) is over capacity. Per configuration the
summary gives the highest rate answered at p99 < 50 ms, per worker process
(a core each), and 2 workers against 1. Then 2 workers against 1 once more, at
saturation and drift-proof (:func:`scaling`): both servers up, windows alternating,
each round followed by a window on the bare echo (the machine's speed then);
``--scaling`` runs that part alone.

Sessions run with the defaults and the sensor's physics only (R, P_D, clutter
density, field of view, the scan period). The service's protective limits are
those of a deployment sized for the load (stated in :data:`SIZED`): no rate
limit, tenant quotas and connections per client above the load (one load
generator speaks for every sensor). Never asserts a time; ``--quick`` (one
small cell on memory, one round of sqlite's scaling, 1 s windows) is the smoke test's.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import redis
from websockets.asyncio.client import ClientConnection, connect

sys.path.insert(0, str(Path(__file__).resolve().parent))

from machine import describe_machine
from service import bare_command, free_port, process_cpu_s, running, service_command
from soak import rss_of

GRID: list[tuple[int, float]] = [(10, 10.0), (100, 1.0), (100, 5.0), (500, 1.0)]
"""(K sessions, r Hz): the issue's grid."""
QUICK_GRID: list[tuple[int, float]] = [(4, 2.0)]
LADDER = [50, 75, 100, 130, 170, 220, 280, 360, 460, 600, 780, 1000, 1300]
"""Total scans/s of :data:`LADDER_SENSORS` sensors, climbed until a step is over capacity:
the grid's four rates alone cannot tell 1 worker's capacity from 2's."""
LADDER_SENSORS = 50
SATURATING_SENSORS = 32
SCALING_ROUNDS = 4
WARMUP_S = 3.0
WARMUP_SCANS = 5
"""Scans of each sensor before the window at least (four confirm a track: steady state)."""
WINDOW_S = 6.0
DRAIN_S = 5.0
MAX_BEHIND_S = 2.0
"""A sensor whose scans of the last 2 s are all unanswered skips the next (counted lost)."""
"""After the window: how long the scans sent in it may still be answered (later: lost)."""
P99_LIMIT_MS = 50.0
START_TIMEOUT_S = 180.0
"""A serve of two workers on a busy 2-core machine may take a minute to start."""
KEPT_UP = 0.95
REDIS_URL = os.environ.get("CREDAL_CAPACITY_REDIS_URL", "redis://127.0.0.1:6379/0")
TARGETS = 20
P_DETECT = 0.9
SIGMA_M = 5.0
CLUTTER_PER_SCAN = 2.0
HALF_SIDE_M = 20_000.0
SCAN_PERIOD_S = 1.0
"""The sensor's revisit in scene time (``tracking.time_interval``), whatever r is."""
SIZED = {
    "CREDAL_RATE_LIMIT": "none",
    "CREDAL_TENANT_INPUTS_PER_SECOND": "1000000",
    "CREDAL_TENANT_WORK_PER_MINUTE": "1000000000",
    "CREDAL_TENANT_BODY_BYTES_PER_SECOND": "1000000000",
    "CREDAL_TENANT_MAX_SESSIONS": "1000",
    "CREDAL_MAX_CONNECTIONS_PER_CLIENT": "1000",
    "CREDAL_SESSION_IDLE_SECONDS": "0",
}
"""A deployment's limits sized for the load (the engine's settings stay the defaults)."""


# ---------------------------------------------------------------- the sensor
def sensor_config() -> dict[str, Any]:
    """One detecting sensor's session: its physics, nothing tuned."""
    vertices = [[-HALF_SIDE_M, -HALF_SIDE_M], [HALF_SIDE_M, -HALF_SIDE_M]]
    vertices += [[HALF_SIDE_M, HALF_SIDE_M], [-HALF_SIDE_M, HALF_SIDE_M]]
    return {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "sensors": [
            {
                "id": "radar",
                "p_detect": P_DETECT,
                "measurement": {"r": [[SIGMA_M**2, 0.0], [0.0, SIGMA_M**2]]},
                "clutter_density": CLUTTER_PER_SCAN / (2 * HALF_SIDE_M) ** 2,
                "fov": {"kind": "polygon", "vertices": vertices},
            }
        ],
        "tracking": {"time_interval": SCAN_PERIOD_S},
    }


class Scans:
    """One sensor's scans, as ``stream`` messages: 20 targets on straight lines (a 5 × 4 grid
    2 km apart, 50–250 m/s in random directions), each detected with P_D, plus clutter."""

    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)
        grid = np.array([(2000.0 * (i % 5 - 2), 2000.0 * (i // 5 - 1.5)) for i in range(TARGETS)])
        heading = self.rng.uniform(0, 2 * np.pi, TARGETS)
        speed = self.rng.uniform(50, 250, TARGETS)
        self.start = grid
        self.velocity = np.column_stack([speed * np.cos(heading), speed * np.sin(heading)])
        self.index = 0

    def next(self) -> str:
        time_s = SCAN_PERIOD_S * (1 + self.index)
        self.index += 1
        truth = self.start + self.velocity * time_s
        seen = truth[self.rng.random(TARGETS) < P_DETECT]
        z = seen + self.rng.normal(0.0, SIGMA_M, seen.shape)
        clutter = self.rng.uniform(
            -HALF_SIDE_M, HALF_SIDE_M, (self.rng.poisson(CLUTTER_PER_SCAN), 2)
        )
        points = np.vstack([z, clutter])
        detections = [{"z": [round(float(x), 2), round(float(y), 2)]} for x, y in points]
        message = {"type": "detections", "sensor": "radar", "time": time_s}
        return json.dumps(message | {"detections": detections})


# ---------------------------------------------------------------- the load (own process)
@dataclass
class SensorLink:
    """One sensor's stream: when each unanswered scan was sent, and the round trips."""

    websocket: ClientConnection
    scans: Scans
    sent_at: list[float]
    answered: int = 0
    errors: int = 0
    skipped: list[float] = field(default_factory=list)
    """When scans fell due while :data:`MAX_BEHIND_S` of this sensor's were unanswered (not
    sent: counted lost, so an overloaded cell leaves no backlog to the next one)."""
    heard: asyncio.Event = field(default_factory=asyncio.Event)
    """Set at each answer (a saturating sensor sends its next scan then)."""


async def load(url: str, sessions: int, rate: float, warmup_s: float, window_s: float) -> None:
    """The load generator (``--load``): prints READY when the window starts, DONE when it ends,
    then one JSON line of what it saw. ``url``: the service, or the bare echo's ``ws://`` URL;
    ``rate`` 0: each sensor sends its next scan as soon as the last is answered (saturation)."""
    echo = url.startswith("ws://")
    links: list[SensorLink] = []
    created: list[tuple[str, str]] = []
    async with contextlib.AsyncExitStack() as stack:
        http = await stack.enter_async_context(httpx.AsyncClient(base_url=url, timeout=120))
        for number in range(sessions):
            if echo:
                target, headers = url, {}
            else:
                answer = await http.post("/v1/sessions", json=sensor_config())
                answer.raise_for_status()
                body = answer.json()
                created.append((body["id"], body["token"]))
                headers = {"Authorization": f"Bearer {body['token']}"}
                target = url.replace("http://", "ws://") + f"/v1/sessions/{body['id']}/stream"
            websocket = await stack.enter_async_context(
                connect(target, additional_headers=headers, max_size=None, open_timeout=120)
            )
            if not echo:
                await websocket.recv()  # ack
            links.append(SensorLink(websocket, Scans(seed=number), []))

        window: list[float] = []  # answered in the window: its round trips, ms
        marks: dict[str, float] = {}
        started = time.perf_counter()
        window_start = started + warmup_s
        window_end = window_start + window_s

        async def saturating(link: SensorLink) -> None:
            while time.perf_counter() < window_end:
                link.heard.clear()
                link.sent_at.append(time.perf_counter())
                await link.websocket.send(link.scans.next())
                await link.heard.wait()

        async def sensor(link: SensorLink, phase: float) -> None:
            if rate <= 0:
                return await saturating(link)
            due = started + phase
            behind = max(2, round(MAX_BEHIND_S * rate))
            while due < window_end:
                await asyncio.sleep(max(0.0, due - time.perf_counter()))
                if len(link.sent_at) - link.answered >= behind:
                    link.skipped.append(time.perf_counter())
                else:
                    link.sent_at.append(time.perf_counter())
                    await link.websocket.send(link.scans.next())
                due += 1.0 / rate

        async def reader(link: SensorLink) -> None:
            with contextlib.suppress(Exception):
                async for text in link.websocket:
                    now = time.perf_counter()
                    sent = link.sent_at[link.answered]
                    link.answered += 1
                    link.heard.set()
                    if '"type":"error"' in str(text)[:40]:
                        link.errors += 1
                    if window_start <= sent < window_end:
                        window.append((now - sent) * 1e3)

        async def clock() -> None:
            await asyncio.sleep(max(0.0, window_start - time.perf_counter()))
            marks["answered_at_start"] = sum(link.answered for link in links)
            print("READY", flush=True)
            await asyncio.sleep(max(0.0, window_end - time.perf_counter()))
            marks["answered_at_end"] = sum(link.answered for link in links)
            print("DONE", flush=True)

        readers = [asyncio.create_task(reader(link)) for link in links]
        phases = np.random.default_rng(0).uniform(0, 1.0 / max(rate, 1.0), len(links))
        await asyncio.gather(
            clock(), *(sensor(link, p) for link, p in zip(links, phases, strict=True))
        )
        deadline = time.perf_counter() + DRAIN_S
        while time.perf_counter() < deadline and any(
            link.answered < len(link.sent_at) for link in links
        ):
            await asyncio.sleep(0.05)
        in_window = sum(
            sum(window_start <= sent < window_end for sent in [*link.sent_at, *link.skipped])
            for link in links
        )
        for task in readers:
            task.cancel()
        for sid, token in created:  # the next cell starts from an empty service
            await http.delete(f"/v1/sessions/{sid}", headers={"Authorization": f"Bearer {token}"})
    result = {
        "sent_in_window": in_window,
        "answered_in_window": marks["answered_at_end"] - marks["answered_at_start"],
        "round_trips_ms": window,
        "errors": sum(link.errors for link in links),
    }
    print(json.dumps(result), flush=True)


# ---------------------------------------------------------------- the measuring side
def processes_of(pid: int) -> list[int]:
    """``pid`` and its children (a ``serve`` with workers)."""
    try:
        children = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
    except OSError:
        children = []
    return [pid, *(int(child) for child in children)]


def cpu_of(pids: list[int]) -> float:
    return sum(process_cpu_s(pid) for pid in pids)


@dataclass(frozen=True)
class Cell:
    """One K × r measurement of one server."""

    sessions: int
    rate: float
    sent: int
    answered_per_s: float
    p50_ms: float
    p99_ms: float
    cpu_ms_per_scan: float
    rss_mb: float
    errors: int
    window_s: float
    sockets: tuple[int, ...] = ()
    """Open sockets of each worker process at the window's end (how the kernel spread the
    streams; with one process, empty)."""

    @property
    def kept_up(self) -> bool:
        return self.answered_per_s * self.window_s >= KEPT_UP * self.sent

    @property
    def within(self) -> bool:
        return self.kept_up and self.p99_ms < P99_LIMIT_MS and self.errors == 0


@dataclass(frozen=True)
class Timing:
    warmup_s: float = WARMUP_S
    window_s: float = WINDOW_S


def measure(url: str, pids: list[int], sessions: int, rate: float, timing: Timing) -> Cell:
    """One cell: the load generator in its own process, the server's CPU and RSS from /proc
    (once the server is idle: the previous cell's sessions deleted)."""
    settle(pids)
    command = [sys.executable, str(Path(__file__).resolve()), "--load", url]
    warmup_s = max(timing.warmup_s, WARMUP_SCANS / rate) if rate > 0 else timing.warmup_s
    command += [str(sessions), str(rate), str(warmup_s), str(timing.window_s)]
    generator = subprocess.Popen(command, stdout=subprocess.PIPE, text=True)
    assert generator.stdout is not None
    marks: dict[str, float] = {}
    result: dict[str, Any] = {}
    sockets: tuple[int, ...] = ()
    for line in generator.stdout:
        word = line.strip()
        if word in ("READY", "DONE"):
            marks[word] = cpu_of(pids)
            marks[f"{word}_at"] = time.perf_counter()
            if word == "DONE":
                marks["rss"] = sum(rss_of(pid) for pid in pids) / 2**20
                sockets = tuple(connections_of(pids[1:]))
        elif word.startswith("{"):
            result = json.loads(word)
    if generator.wait() != 0 or not result:
        raise RuntimeError(f"the load generator failed ({url}, {sessions} × {rate} Hz)")
    elapsed = marks["DONE_at"] - marks["READY_at"]
    answered = int(result["answered_in_window"])
    trips = sorted(result["round_trips_ms"]) or [float("inf")]
    lost = int(result["sent_in_window"]) - len(result["round_trips_ms"])
    p99_index = min(len(trips) - 1, round(0.99 * (len(trips) - 1)))
    return Cell(
        sessions=sessions,
        rate=rate,
        sent=int(result["sent_in_window"]),
        answered_per_s=answered / elapsed,
        p50_ms=statistics.median(trips),
        p99_ms=float("inf")
        if lost > 0.01 * max(1, int(result["sent_in_window"]))
        else trips[p99_index],
        cpu_ms_per_scan=1e3 * (marks["DONE"] - marks["READY"]) / max(1, answered),
        rss_mb=marks["rss"],
        errors=int(result["errors"]),
        window_s=timing.window_s,
        sockets=sockets,
    )


@dataclass(frozen=True)
class Configuration:
    store: str
    workers: int

    @property
    def name(self) -> str:
        return f"{self.store.split(':', 1)[0]} × {self.workers}"


@contextmanager
def serving(configuration: Configuration) -> Iterator[tuple[str, list[int]]]:
    """``credal-fusion serve`` of the configuration, ready; its URL and processes."""
    port = free_port()
    environment = SIZED | {"CREDAL_WORKERS": str(configuration.workers)}
    store = configuration.store
    with contextlib.ExitStack() as stack:
        if store == "sqlite":
            folder = stack.enter_context(tempfile.TemporaryDirectory(prefix="capacity-"))
            store = f"sqlite:{folder}/capacity.db"
        elif store == "redis":
            prefix = f"capacity-{uuid.uuid4().hex[:8]}"
            environment |= {"CREDAL_REDIS_PREFIX": prefix}
            store = REDIS_URL
            stack.callback(forget_prefix, prefix)
        command = service_command(port, store)
        process = stack.enter_context(
            running(command, port, environment, ready="/readyz", start_timeout_s=START_TIMEOUT_S)
        )
        pids = processes_of(process.pid)
        deadline = time.monotonic() + 120
        while configuration.workers > 1 and len(pids) < configuration.workers + 1:
            assert time.monotonic() < deadline, "the workers did not start"
            time.sleep(0.1)
            pids = processes_of(process.pid)
        yield f"http://127.0.0.1:{port}", pids


def settle(pids: list[int], quiet_s: float = 1.0) -> None:
    """Wait until the server's processes are idle: every worker has started (imports, restore:
    each takes connections when the load starts) and the previous cell is done with."""
    deadline = time.monotonic() + 120
    before = cpu_of(pids)
    while time.monotonic() < deadline:
        time.sleep(quiet_s)
        now = cpu_of(pids)
        if now - before < 0.1 * quiet_s:
            return
        before = now


def forget_prefix(prefix: str) -> None:
    client = redis.Redis.from_url(REDIS_URL)
    keys = list(client.scan_iter(f"{prefix}:*"))
    if keys:
        client.delete(*keys)
    client.close()


def connections_of(pids: list[int]) -> list[int]:
    """Open sockets per process (how the kernel spread the connections over the workers)."""
    counts = []
    for pid in pids:
        with contextlib.suppress(OSError):
            fds = Path(f"/proc/{pid}/fd")
            counts.append(sum(os.readlink(fd).startswith("socket:") for fd in fds.iterdir()))
    return counts


def main(arguments: argparse.Namespace) -> int:
    grid = QUICK_GRID if arguments.quick else arguments.grid or GRID
    timing = Timing(1.0, 1.0) if arguments.quick else Timing()
    configurations = [
        Configuration(store, workers)
        for store, workers in (
            [("memory", 1)]
            if arguments.quick
            else [("memory", 1), ("sqlite", 1), ("sqlite", 2), ("redis", 1), ("redis", 2)]
        )
        if store in arguments.stores
        and (
            not arguments.configurations
            or f"{store}×{workers}" in [c.replace("x", "×") for c in arguments.configurations]
        )
    ]
    print(describe_machine())
    print(
        f"K WebSocket streams, each a detecting sensor: {TARGETS} targets, P_D {P_DETECT}, "
        f"σ {SIGMA_M:.0f} m, {CLUTTER_PER_SCAN:.0f} clutter/scan, defaults + physics; "
        f"{timing.warmup_s:.0f} s warm-up, {timing.window_s:.0f} s measured per cell; "
        "load generator in its own process"
    )
    print("limits sized for the load: " + " ".join(f"{k}={v}" for k, v in SIZED.items()))
    load_before = os.getloadavg()
    if arguments.scaling:
        for store in ("sqlite", "redis"):
            if store in arguments.stores:
                scaling(store, timing, SCALING_ROUNDS)
        print(
            f"machine load (1-minute average): {load_before[0]:.1f} at start,"
            f" {os.getloadavg()[0]:.1f} at end"
        )
        return 0
    results: dict[str, list[Cell]] = {}
    header = (
        f"{'server':13} {'K × r':>10} {'scans/s':>8} {'p50 ms':>8} {'p99 ms':>8} "
        f"{'CPU/scan':>9} {'RSS MB':>7}  within"
    )
    print(header)
    echo_port = free_port()
    with running(bare_command(echo_port), echo_port) as echo:
        echo_url = f"ws://127.0.0.1:{echo_port}/echo"
        results["bare echo"] = [
            show("bare echo", measure(echo_url, [echo.pid], k, r, timing)) for k, r in grid
        ]
    for configuration in configurations:
        with serving(configuration) as (url, pids):
            cells = []
            for k, r in grid:
                cells.append(show(configuration.name, measure(url, pids, k, r, timing)))
            for total in [] if arguments.quick else LADDER:  # up to the first over capacity
                rate = total / LADDER_SENSORS
                cell = show(configuration.name, measure(url, pids, LADDER_SENSORS, rate, timing))
                cells.append(cell)
                if not cell.within:
                    break
            results[configuration.name] = cells
    summary(results)
    for store in ("sqlite", "redis"):
        if store in arguments.stores:
            scaling(store, timing, 1 if arguments.quick else SCALING_ROUNDS)
    load_after = os.getloadavg()
    print(
        f"machine load (1-minute average, {os.cpu_count()} cores): {load_before[0]:.1f} at "
        f"start, {load_after[0]:.1f} at end"
    )
    return 0


def scaling(store: str, timing: Timing, rounds: int) -> list[float]:
    """2 workers against 1 at saturation: both servers and the bare echo up,
    :data:`SATURATING_SENSORS` sensors each sending its next scan when the last is answered,
    in windows alternating between the servers (the order flips each round: this machine's
    speed drifts within seconds), then one on the echo (the machine's speed in that round);
    the answered rate of each round's 2-worker window over its 1-worker neighbour."""
    rates: tuple[list[float], list[float]] = ([], [])
    echo_port = free_port()
    with (
        serving(Configuration(store, 1)) as (one_url, one_pids),
        serving(Configuration(store, 2)) as (two_url, two_pids),
        running(bare_command(echo_port), echo_port) as echo,
    ):
        servers = ((one_url, one_pids), (two_url, two_pids))
        for round_number in range(rounds):
            cells: dict[int, Cell] = {}
            for which in (1, 0) if round_number % 2 else (0, 1):
                url, pids = servers[which]
                cells[which] = measure(url, pids, SATURATING_SENSORS, 0.0, timing)
                rates[which].append(cells[which].answered_per_s)
            bare = measure(
                f"ws://127.0.0.1:{echo_port}/echo", [echo.pid], SATURATING_SENSORS, 0.0, timing
            )
            one, two = cells[0], cells[1]
            print(
                f"  {store} round {round_number + 1}: 1 worker {one.answered_per_s:.0f} scans/s"
                f" ({one.cpu_ms_per_scan:.2f} ms CPU/scan), 2 workers {two.answered_per_s:.0f}"
                f" ({two.cpu_ms_per_scan:.2f} ms; sockets {'/'.join(map(str, two.sockets))}),"
                f" 2 / 1 {two.answered_per_s / max(one.answered_per_s, 1e-9):.2f};"
                f" bare echo {bare.answered_per_s:.0f} messages/s ({bare.cpu_ms_per_scan:.2f} ms"
                f" CPU/message); load {os.getloadavg()[0]:.1f}",
                flush=True,
            )
    ratios = [two / one for one, two in zip(*rates, strict=True)]
    print(
        f"{store} at saturation ({SATURATING_SENSORS} sensors, each sending when answered), "
        f"scans/s by round: 1 worker {' '.join(f'{r:.0f}' for r in rates[0])}; 2 workers "
        f"{' '.join(f'{r:.0f}' for r in rates[1])}; 2 / 1 {' '.join(f'{r:.2f}' for r in ratios)}"
        f" (median {statistics.median(ratios):.2f}, goal ≥ 1.8: "
        f"{'met' if statistics.median(ratios) >= 1.8 else 'NOT met'})",
        flush=True,
    )
    return ratios


def show(name: str, cell: Cell) -> Cell:
    rate = f"{cell.sessions} × {cell.rate:g}"
    p99 = "lost" if cell.p99_ms == float("inf") else f"{cell.p99_ms:8.1f}"
    print(
        f"{name:13} {rate:>10} {cell.answered_per_s:8.0f} {cell.p50_ms:8.1f} {p99:>8} "
        f"{cell.cpu_ms_per_scan:7.2f}ms {cell.rss_mb:7.0f}  "
        f"{'yes' if cell.within else 'no'}{'' if cell.kept_up else ' (falls behind)'}"
        + (f"; sockets per worker {'/'.join(map(str, cell.sockets))}" if cell.sockets else ""),
        flush=True,
    )
    return cell


def capacity(cells: list[Cell]) -> float:
    """The highest rate answered at p99 < 50 ms (0: none)."""
    return max((cell.answered_per_s for cell in cells if cell.within), default=0.0)


def summary(results: dict[str, list[Cell]]) -> None:
    print(f"at p99 < {P99_LIMIT_MS:.0f} ms: scans/s (per worker process, a core each)")
    for name, cells in results.items():
        if name == "bare echo":
            continue
        workers = int(name.rsplit("× ", 1)[1])
        best = capacity(cells)
        cpu = statistics.median(cell.cpu_ms_per_scan for cell in cells)
        print(
            f"  {name:13} {best:6.0f} ({best / workers:5.0f} per core); median server CPU "
            f"{cpu:.2f} ms/scan"
        )
    echo = statistics.median(cell.cpu_ms_per_scan for cell in results["bare echo"])
    print(f"  bare echo CPU per message (median over the grid): {echo:.2f} ms")
    for store in ("sqlite", "redis"):
        one, two = results.get(f"{store} × 1"), results.get(f"{store} × 2")
        if one and two and capacity(one) > 0:
            ratio = capacity(two) / capacity(one)
            verdict = "met" if ratio >= 1.8 else "NOT met"
            print(f"  {store}: 2 workers / 1 at p99 < 50 ms = {ratio:.2f} (goal ≥ 1.8: {verdict})")


def parse(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--quick", action="store_true", help="one small cell, 1 s (smoke test)")
    parser.add_argument(
        "--stores",
        nargs="+",
        default=["memory", "sqlite", "redis"],
        choices=["memory", "sqlite", "redis"],
    )
    parser.add_argument(
        "--grid", nargs="+", type=_cell, help="cells K×r instead of the issue's (e.g. 100x5)"
    )
    parser.add_argument(
        "--scaling", action="store_true", help="2 workers against 1 (and the echo) alone"
    )
    parser.add_argument(
        "--configurations",
        nargs="+",
        help="store×workers to run (e.g. sqlite×2), default: every one",
    )
    return parser.parse_args(argv)


def _cell(text: str) -> tuple[int, float]:
    sessions, rate = text.lower().replace("×", "x").split("x")
    return int(sessions), float(rate)


if __name__ == "__main__":
    if len(sys.argv) == 7 and sys.argv[1] == "--load":
        url, k, r, warmup, window = sys.argv[2:]
        asyncio.run(load(url, int(k), float(r), float(warmup), float(window)))
        raise SystemExit(0)
    raise SystemExit(main(parse(sys.argv[1:])))
