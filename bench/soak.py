"""Soak: a few minutes of steady load on a live server per store; RSS and store size stay flat.

Run with ``make soak`` (not part of ``make test`` nor ``make bench``). For each
store (memory, sqlite on a fresh file, redis under a prefix of its own on
``CREDAL_SOAK_REDIS_URL``, default the local server) a ``credal-fusion serve``
subprocess takes, for ``SOAK_SECONDS`` (default 100 s per store):

* :data:`LONG_SESSIONS` sessions of :data:`SENSORS` sensors × :data:`TRACKS`
  tracks, each sensor reporting at :data:`REPORTS_PER_S` per second (paced;
  slower if the server is), with snapshots every :data:`SNAPSHOT_EVERY` inputs
  and :data:`LOG_RETENTION` inputs kept behind each snapshot;
* a churn of short sessions: create, :data:`CHURN_INPUTS` inputs, delete.

Every :data:`SAMPLE_EVERY_S` it samples the server's RSS (``/proc/PID/status``),
the store's own size (``credal_store_bytes`` of ``/metrics``), the inputs the
store holds and, for sqlite, the file size (database + WAL). It prints the
samples, then checks the two rules and exits 1 if one fails:

* RSS grows less than :data:`MAX_GROWTH` over the second half (the median of
  the last three samples against the median of the three around the middle);
* the store is flat: its size over the second half never exceeds by more than
  :data:`MAX_GROWTH` its largest size between 25 % and 50 % of the run (the
  retained log rises and falls by one snapshot period; it must not creep up).

Speed is not measured here (``bench/service.py`` does that).

``--crowd`` (``make soak`` runs it after the stores): on the sqlite store, the
same honest load (its sessions created with an API key, :data:`HONEST_KEY`, as
a client of a service on a network must) alone, then beside an anonymous attacker
process (no key: open access on loopback lets it create sessions and send inputs;
:func:`attack`, from other loopback addresses: slowloris connections, 16 MB headers, a
session flood, floods of the heaviest legal inputs and of explained ones), in
:data:`CROWD_PHASES` pairs of phases (alone, attacked, alone, attacked, …;
:data:`CROWD_SECONDS` of each kind in all), so a drift of the machine's other load
falls on both kinds. Two rules (exit 1 if either fails):

* the honest p99 beside the attacker "unchanged within 10 %": the ratio of the honest
  sensors' p99 attacked / alone with its 95 % interval, a BCa bootstrap over the pairs of
  phases (:func:`pair_bootstrap` says why pairs and not requests), expanded for so few
  pairs (:func:`expanded_level`). It fails only when the
  ratio is significantly above 1.10 (the interval's low end above it), holds when the whole
  interval is at or below 1.10, and says "inconclusive" (printing the interval) otherwise;
* the honest error rate (failed requests of every kind, each printed with its status and
  problem type) not higher beside the attacker: errors are a few in a thousand, so "within
  10 %" of one error is no test; the rates are compared by a one-sided Fisher exact test at
  5 % (an increase fails only when significant), and the 95 % upper bound of the increase
  (Newcombe's interval) is printed as what the run can rule out.

The processes share the machine's cores (with more than two, the attacker is pinned to one
of its own: :func:`attacker_core`): each phase prints the CPU seconds of the server, the
honest load and the attacker, and how long the server's event loop waited runnable for a
CPU (the machine's share of the latency). What the server controls is its own CPU per
honest input: printed alone and attacked, with the ratio's interval (reported, not judged).
"""

from __future__ import annotations

import asyncio
import math
import os
import re
import statistics
import sys
import tempfile
import time
import uuid
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import redis
from scipy import special, stats

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from machine import describe_machine
from service import config, free_port, process_cpu_s, running, service_command, track_list

from evaluation.intervals import Interval, rate_difference

SOAK_SECONDS = float(os.environ.get("SOAK_SECONDS", "100"))
REDIS_URL = os.environ.get("CREDAL_SOAK_REDIS_URL", "redis://127.0.0.1:6379/0")
LONG_SESSIONS = 2
SENSORS = 3
TRACKS = 30
REPORTS_PER_S = 8.0
"""Per sensor of a long session."""
CHURN_INPUTS = 5
SNAPSHOT_EVERY = 25
LOG_RETENTION = 100
SAMPLE_EVERY_S = 4.0
MAX_GROWTH = 0.05


@contextmanager
def serving(store: str, environment: dict[str, str]) -> Iterator[tuple[str, int]]:
    """``credal-fusion serve --store STORE``: its URL and pid once ready, stopped on exit."""
    port = free_port()
    settings = {
        "CREDAL_SNAPSHOT_EVERY": str(SNAPSHOT_EVERY),
        "CREDAL_LOG_RETENTION": str(LOG_RETENTION),
        "CREDAL_RATE_LIMIT": "none",
    }
    command = service_command(port, store)
    with running(command, port, environment | settings, ready="/readyz") as process:
        yield f"http://127.0.0.1:{port}", process.pid


@dataclass(frozen=True)
class Sample:
    at_s: float
    rss_bytes: int
    store_bytes: int
    store_inputs: int
    file_bytes: int | None
    inputs_sent: int


def rss_of(pid: int) -> int:
    status = Path(f"/proc/{pid}/status").read_text()
    match = re.search(r"^VmRSS:\s+(\d+) kB", status, re.MULTILINE)
    assert match is not None
    return int(match.group(1)) * 1024


def gauge(metrics: str, name: str) -> int:
    match = re.search(rf"^{name} (\S+)$", metrics, re.MULTILINE)
    return int(float(match.group(1))) if match else 0


class Load:
    """The load generator: long sessions at a paced rate, and a churn of short ones."""

    def __init__(self, url: str, deadline: float, key: str | None = None) -> None:
        self.url = url
        self.deadline = deadline
        self.creating = {} if key is None else {"Authorization": f"Bearer {key}"}
        """The headers of a session's creation: the tenant's API key, if it has one."""
        self.sent = 0
        self.requests = 0
        """Requests whose status is checked (the inputs, the churn's deletions)."""
        self.failures = 0
        self.failed: list[str] = []
        """What each failed request was and what it was answered (status, problem type)."""
        self.latencies: list[float] = []
        """Seconds of each long session's input (the honest sensors)."""

    def check(self, what: str, answer: httpx.Response, expected: int = 200) -> None:
        """Count ``answer`` as a failure unless it has the ``expected`` status; say why."""
        self.requests += 1
        if answer.status_code == expected:
            return
        self.failures += 1
        try:
            problem = answer.json()
            why = " ".join(
                f"{key}={problem[key]}"
                for key in ("type", "limit", "detail")
                if isinstance(problem, dict) and key in problem
            )
        except ValueError:
            why = answer.text[:200]
        self.failed.append(f"{what}: {answer.status_code} {why}")

    async def long_session(self, client: httpx.AsyncClient, number: int) -> None:
        sensors = [f"s{number}-{k}" for k in range(SENSORS)]
        created = (
            await client.post("/v1/sessions", json=config(sensors), headers=self.creating)
        ).json()
        headers = {"Authorization": f"Bearer {created['token']}"}
        path = f"/v1/sessions/{created['id']}/tracks"
        await asyncio.gather(
            *(self.sensor(client, path, headers, sensor, k) for k, sensor in enumerate(sensors))
        )

    async def sensor(
        self, client: httpx.AsyncClient, path: str, headers: dict[str, str], sensor: str, k: int
    ) -> None:
        step = 0
        started = time.monotonic()
        while time.monotonic() < self.deadline:
            body = track_list(sensor, 1.0 + step / REPORTS_PER_S + k / (SENSORS * 100), TRACKS)
            sent_at = time.perf_counter()
            answer = await client.post(path, json=body, headers=headers)
            self.latencies.append(time.perf_counter() - sent_at)
            self.sent += 1
            self.check(f"{sensor} input at t={body['time']:.3f}", answer)
            step += 1
            pause = started + step / REPORTS_PER_S - time.monotonic()
            if pause > 0:
                await asyncio.sleep(pause)

    async def churn(self, client: httpx.AsyncClient) -> None:
        cycle = 0
        while time.monotonic() < self.deadline:
            created = (
                await client.post("/v1/sessions", json=config(["c"]), headers=self.creating)
            ).json()
            headers = {"Authorization": f"Bearer {created['token']}"}
            path = f"/v1/sessions/{created['id']}"
            for step in range(CHURN_INPUTS):
                answer = await client.post(
                    f"{path}/tracks", json=track_list("c", 1.0 + step, 10), headers=headers
                )
                self.sent += 1
                self.check(f"churn input {step}", answer)
            self.check("churn delete", await client.delete(path, headers=headers), 204)
            cycle += 1
            await asyncio.sleep(0.25)

    async def run(self) -> None:
        limits = httpx.Limits(max_connections=LONG_SESSIONS * SENSORS + 2)
        async with httpx.AsyncClient(base_url=self.url, timeout=60, limits=limits) as client:
            await asyncio.gather(
                *(self.long_session(client, number) for number in range(LONG_SESSIONS)),
                self.churn(client),
            )


async def soak(url: str, pid: int, database: Path | None) -> list[Sample]:
    started = time.monotonic()
    load = Load(url, started + SOAK_SECONDS)
    samples: list[Sample] = []

    async def sample() -> None:
        async with httpx.AsyncClient(base_url=url, timeout=60) as client:
            while time.monotonic() < load.deadline:
                await asyncio.sleep(SAMPLE_EVERY_S)
                metrics = (await client.get("/metrics")).text
                files = None
                if database is not None:
                    files = sum(
                        path.stat().st_size
                        for path in (database, database.with_name(database.name + "-wal"))
                        if path.exists()
                    )
                samples.append(
                    Sample(
                        at_s=time.monotonic() - started,
                        rss_bytes=rss_of(pid),
                        store_bytes=gauge(metrics, "credal_store_bytes"),
                        store_inputs=gauge(metrics, "credal_store_inputs"),
                        file_bytes=files,
                        inputs_sent=load.sent,
                    )
                )

    await asyncio.gather(load.run(), sample())
    if load.failures:
        raise RuntimeError(
            f"{load.failures} requests failed during the soak: " + "; ".join(load.failed)
        )
    return samples


def verdict(samples: list[Sample]) -> tuple[float, float, bool]:
    """(RSS growth over the second half, store growth past its 25-50 % peak, both within bounds)."""
    middle = len(samples) // 2
    rss_middle = statistics.median(s.rss_bytes for s in samples[middle - 1 : middle + 2])
    rss_end = statistics.median(s.rss_bytes for s in samples[-3:])
    rss_growth = rss_end / rss_middle - 1.0
    settled = max(s.store_bytes for s in samples[len(samples) // 4 : middle + 1])
    store_growth = max(s.store_bytes for s in samples[middle:]) / settled - 1.0
    return rss_growth, store_growth, rss_growth < MAX_GROWTH and store_growth <= MAX_GROWTH


def report(name: str, samples: list[Sample]) -> bool:
    print(f"\n== {name}: {SOAK_SECONDS:.0f} s")
    print(
        f"{'t (s)':>6} {'inputs sent':>11} {'RSS (MB)':>9} {'store (KB)':>11} {'logged':>7} {'file (KB)':>10}"
    )
    for s in samples:
        file_kb = "" if s.file_bytes is None else f"{s.file_bytes / 1024:.0f}"
        print(
            f"{s.at_s:6.0f} {s.inputs_sent:11d} {s.rss_bytes / 2**20:9.1f} "
            f"{s.store_bytes / 1024:11.0f} {s.store_inputs:7d} {file_kb:>10}"
        )
    rss_growth, store_growth, ok = verdict(samples)
    rate = samples[-1].inputs_sent / samples[-1].at_s
    print(
        f"{name}: {rate:.0f} inputs/s; RSS growth over the second half {rss_growth:+.1%}; "
        f"store size past its settled peak {store_growth:+.1%} -> {'ok' if ok else 'FAILED'}"
    )
    return ok


CROWD_SECONDS = float(os.environ.get("CROWD_SECONDS", "80"))
"""Seconds of each kind of phase (alone, attacked), split into :data:`CROWD_PHASES` phases."""
HONEST_KEY = "honest-soak-key-0123456789abcdefghijklmnop"
"""The honest client's API key (``CREDAL_API_KEYS``): its tenant is ``key:honest``. The server
listens on loopback, so access stays open (``auto``): the attacker needs no key to create
sessions and send inputs, as an address tenant (app/http/front.py: keyed tenants first)."""
ATTACKER = "127.0.0.77"
"""The attacker's main address (any 127.x.y.z is loopback on Linux); its slowloris
connections also come from 50 others."""


def attack(url: str, seconds: float, ready: Any = None, core: int | None = None) -> None:
    """An anonymous client spending what it can for ``seconds`` (run in its own process):
    pinned to ``core`` if one is given; ``ready`` (an event) is set when it starts."""
    import contextlib
    import socket

    if core is not None:
        os.sched_setaffinity(0, {core})
    port = int(url.rsplit(":", 1)[1])
    transport = httpx.HTTPTransport(local_address=ATTACKER)
    heavy = track_list("a", 1.0, 2000)
    header = b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Pad: " + b"a" * (16 << 20) + b"\r\n\r\n"
    held: list[socket.socket] = []
    tokens: list[tuple[str, dict[str, str]]] = []
    with httpx.Client(base_url=url, transport=transport, timeout=30) as client:
        if ready is not None:
            ready.set()
        deadline = time.monotonic() + seconds
        round_number = 0
        while time.monotonic() < deadline:
            round_number += 1
            for index in range(20):  # slowloris: a trickle on every held connection
                source = f"127.0.9.{(round_number * 20 + index) % 50 + 1}"
                with contextlib.suppress(OSError):
                    held.append(socket.create_connection(("127.0.0.1", port), 5, (source, 0)))
            for connection in list(held):
                try:
                    connection.send(b"G")
                except OSError:
                    held.remove(connection)
                    connection.close()
            with (
                contextlib.suppress(OSError),
                socket.create_connection(("127.0.0.1", port), 5, (ATTACKER, 0)) as bomb,
            ):
                bomb.sendall(header)
            created = client.post("/v1/sessions", json=config(["a"]))
            if created.status_code == 201:
                body = created.json()
                tokens.append((body["id"], {"Authorization": f"Bearer {body['token']}"}))
            for sid, headers in tokens[-5:]:
                client.post(f"/v1/sessions/{sid}/tracks", json=heavy, headers=headers)
                client.post(
                    f"/v1/sessions/{sid}/tracks",
                    params={"explain": "true"},
                    json=heavy,
                    headers=headers,
                )
            time.sleep(0.05)
    for connection in held:
        connection.close()


CROWD_PHASES = 10
"""Pairs of phases (alone, then attacked), one after the other: the machine's other load
drifts over minutes (two honest-alone phases of one run had p99s 30 % apart), and each
pair's two phases share their minute of it. Pairs, not requests, are what the intervals
resample (:func:`pair_bootstrap`); 10 of 8 s by default."""
BOOTSTRAP_RESAMPLES = 4000
BOOTSTRAP_SEED = 28
"""The resamples' seed: the same phases give the same interval."""
P99_BOUND = 1.10
"""The honest p99 beside the attacker "unchanged within 10 %": at most 1.10 × alone."""
INTERVAL = "95 %, BCa bootstrap over the pairs of phases, expanded for few pairs"


@dataclass
class Phase:
    """The honest load's account of one phase, and the CPU seconds each process spent in it."""

    attacked: bool
    latencies: list[float]
    sent: int
    requests: int
    failures: int
    failed: list[str]
    server_cpu: float
    server_wait: float
    honest_cpu: float
    attacker_cpu: float


def loop_thread_wait_s(pid: int) -> float:
    """Seconds the server's event-loop (main) thread waited runnable for a CPU so far (Linux
    ``schedstat``; NaN where there is none): the machine's share of its latency."""
    try:
        return int(Path(f"/proc/{pid}/task/{pid}/schedstat").read_text().split()[1]) / 1e9
    except (OSError, IndexError, ValueError):
        return float("nan")


def pin_threads(pid: int, cores: set[int]) -> None:
    """Every thread of process ``pid`` to ``cores``: Linux's ``sched_setaffinity(pid)`` sets
    the one thread whose id is ``pid`` (a server ready has several: the store's, the thread
    pool's), and only threads created after it by that thread inherit its cores."""
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            os.sched_setaffinity(int(task.name), cores)
        except ProcessLookupError:  # ended since it was listed
            continue


def attacker_core(server_pid: int) -> tuple[int | None, str]:
    """With more than two cores usable here: one of them the attacker's alone (the server and
    this process, the honest load, keep the others); with two or fewer none is pinned. The
    core (or None) and a line saying which."""
    cores = sorted(os.sched_getaffinity(0))
    if len(cores) <= 2:
        return None, (
            f"{len(cores)} cores usable: the attacker is not pinned (it would leave the server "
            "and the honest load one core); all three processes share them"
        )
    core, others = cores[-1], set(cores[:-1])
    pin_threads(server_pid, others)
    pin_threads(os.getpid(), others)
    return core, (
        f"{len(cores)} cores usable: the attacker pinned to core {core}, the server and the "
        f"honest load to cores {sorted(others)}"
    )


def crowd_phase(url: str, pid: int, attacked: bool, seconds: float, core: int | None) -> Phase:
    """The honest load for ``seconds``, beside :func:`attack` if ``attacked`` (started, and
    ready, before the honest load starts)."""
    import multiprocessing

    attacker = None
    if attacked:
        spawn = multiprocessing.get_context("spawn")
        ready = spawn.Event()
        attacker = spawn.Process(target=attack, args=(url, seconds, ready, core))
        attacker.start()
        if not ready.wait(60):
            raise RuntimeError("the attacker process did not start within 60 s")
    server_cpu, server_wait = process_cpu_s(pid), loop_thread_wait_s(pid)
    honest_cpu = time.process_time()
    load = Load(url, time.monotonic() + seconds, HONEST_KEY)
    asyncio.run(load.run())
    honest_cpu = time.process_time() - honest_cpu
    server_cpu, server_wait = process_cpu_s(pid) - server_cpu, loop_thread_wait_s(pid) - server_wait
    attacker_cpu = 0.0
    if attacker is not None:
        attacker_cpu = process_cpu_s(attacker.pid or 0)
        attacker.join()
    return Phase(
        attacked,
        load.latencies,
        load.sent,
        load.requests,
        load.failures,
        load.failed,
        server_cpu,
        server_wait,
        honest_cpu,
        attacker_cpu,
    )


def p99(latencies: np.ndarray) -> float:
    """The 99th percentile as the crowd soak prints it: the sorted value at
    ``int(0.99 * (n - 1))`` (numpy's ``lower`` quantile)."""
    return float(np.quantile(latencies, 0.99, method="lower"))


def expanded_level(pairs: int, confidence: float = 0.95) -> float:
    """The level at which a bootstrap over ``pairs`` units is computed for a ``confidence``
    interval: Hesterberg's expansion for small samples (Hesterberg 2015, "What teachers should
    know about the bootstrap", Am Stat 69:371: the two tails at
    ``Φ(−√(n/(n−1)) t_{n−1})`` instead of ``(1 − confidence) / 2``). A plain bootstrap of 8
    pairs is too narrow: on simulated runs at the 1.10 bound (8 pairs of 400 lognormal
    latencies, each phase drifting by 5 or 15 %; 100 runs each, the phases of
    ``test_soak_bench``) the 95 % BCa interval of the pooled p99 ratio put its low end above
    1.10 in 4-7 % of them (2.5 % is its one-sided level), the expanded one in 3-5 % (12
    pairs: 2 %); a t interval of the pairs' log ratios, 1-3 %."""
    t = float(stats.t.ppf((1 + confidence) / 2, pairs - 1))
    return 1 - 2 * float(special.ndtr(-math.sqrt(pairs / (pairs - 1)) * t))


def pair_bootstrap(
    statistic: Callable[[np.ndarray], float],
    pairs: int,
    resamples: int = BOOTSTRAP_RESAMPLES,
    seed: int = BOOTSTRAP_SEED,
    level: float = 0.95,
) -> Interval:
    """``statistic`` of the pairs of phases (given their indices, repeats allowed) over all
    ``pairs``, with its bias-corrected and accelerated (BCa) bootstrap interval at ``level``
    (Efron & Tibshirani 1993, 14.3: ``z0`` from the resamples below the estimate, ties counted
    half; the acceleration from the jackknife over pairs; the resamples' quantiles linear) —
    what ``scipy.stats.bootstrap(method="BCa")`` computes, over pairs. The crowd soak asks
    it at :func:`expanded_level` for a 95 % interval.

    Why pairs of phases and not requests: the honest latencies of one phase are not
    independent draws — the machine's other load of that minute moves all of them (one
    run's two alone phases: p99 41.2 and 53.7 ms) — so resampling requests, even within
    their phases, takes each phase's machine as fixed and gives an interval as narrow as if
    there were no drift: a drift falling more on the attacked phases would read as the
    attacker's. A pair (an alone phase and the attacked one after it) is the unit the run
    repeats; resampling pairs carries the phase-to-phase spread into the interval, and keeps
    each attacked phase with the alone phase of its minute."""
    rng = np.random.default_rng(seed)
    everything = np.arange(pairs)
    estimate = statistic(everything)
    resampled = np.array(
        [statistic(rng.integers(0, pairs, pairs)) for _ in range(resamples)], dtype=np.float64
    )
    below = np.count_nonzero(resampled < estimate) + np.count_nonzero(resampled <= estimate)
    z0 = float(special.ndtri(below / (2 * resamples)))
    if not math.isfinite(z0):  # every resample on one side of the estimate: no BCa interval
        return Interval(float(estimate), math.nan, math.nan)  # (scipy's NaN too): inconclusive
    jackknife = np.array([statistic(np.delete(everything, left)) for left in everything])
    spread = jackknife.mean() - jackknife
    squares = float(np.sum(spread**2))
    acceleration = float(np.sum(spread**3)) / (6 * squares**1.5) if squares > 0 else 0.0
    levels = []
    for z in (special.ndtri((1 - level) / 2), special.ndtri((1 + level) / 2)):
        levels.append(float(special.ndtr(z0 + (z0 + z) / (1 - acceleration * (z0 + z)))))
    low, high = np.quantile(resampled, levels)
    return Interval(float(estimate), float(low), float(high))


def p99_verdict(ratio: Interval, bound: float = P99_BOUND) -> tuple[bool, str]:
    """Is the honest p99 beside the attacker "unchanged within 10 %"? It fails only when the
    ratio is significantly above ``bound`` (the interval's low end above it); it holds when
    the whole interval is at or below it; otherwise the run cannot tell (inconclusive, not a
    failure: the interval says how wide)."""
    interval = f"[{ratio.low:.2f}, {ratio.high:.2f}]"
    if ratio.low > bound:
        word, ok = "FAILED (significantly above", False
    elif ratio.high <= bound:
        word, ok = "ok (within", True
    else:
        word, ok = "inconclusive (the interval holds", True
    return ok, f"honest p99 × {ratio.estimate:.2f} {interval} ({INTERVAL}): {word} {bound:.2f})"


def crowd() -> int:
    """Pairs of phases, the honest load alone then beside :func:`attack` (:data:`CROWD_PHASES`
    pairs): the honest p99 and error rate compared, with the CPU seconds the server, the honest
    load and the attacker spent in each phase, the seconds the server's event loop waited for
    a CPU (the machine's: 2 cores shared by every process here and any other), and the
    server's CPU per honest input alone and attacked (the part the server controls)."""
    print(describe_machine())
    phases: list[Phase] = []
    seconds = CROWD_SECONDS / CROWD_PHASES
    with tempfile.TemporaryDirectory(prefix="credal-soak-") as directory:
        database = Path(directory) / "crowd.db"
        settings = {"CREDAL_RATE_LIMIT": "1000/second", "CREDAL_API_KEYS": f"honest:{HONEST_KEY}"}
        with serving(f"sqlite:{database}", settings) as (url, pid):
            core, pinning = attacker_core(pid)
            print(pinning)
            for _ in range(CROWD_PHASES):
                for attacked in (False, True):
                    phases.append(crowd_phase(url, pid, attacked, seconds, core))
    print(
        f"{CROWD_PHASES} pairs of {seconds:.0f} s phases (alone, attacked); per phase: the honest "
        "inputs and p99, the server's CPU per honest input, the CPU seconds of the server, the "
        "honest load and the attacker, and the seconds the server's event loop waited runnable "
        "for a CPU"
    )
    alone = [phase for phase in phases if not phase.attacked]
    attacked_phases = [phase for phase in phases if phase.attacked]
    for number, pair in enumerate(zip(alone, attacked_phases, strict=True), 1):
        for phase in pair:
            who = "attacked" if phase.attacked else "alone"
            print(
                f"  {number:2d} {who:8} {len(phase.latencies):5d} inputs  p99 "
                f"{p99(np.array(phase.latencies)) * 1000:7.1f} ms  server "
                f"{phase.server_cpu / max(phase.sent, 1) * 1000:5.2f} ms CPU/input; CPU: server "
                f"{phase.server_cpu:5.1f} s, honest {phase.honest_cpu:5.1f} s, attacker "
                f"{phase.attacker_cpu:5.1f} s; loop waiting for a CPU {phase.server_wait:5.1f} s"
            )
            for failure in phase.failed:
                print(f"     failed: {failure}")
    rows = []
    for who, mine in (("honest alone", alone), ("honest + anonymous attacker", attacked_phases)):
        latencies = np.sort(np.concatenate([np.array(phase.latencies) for phase in mine]))
        requests = sum(phase.requests for phase in mine)
        failures = sum(phase.failures for phase in mine)
        cpu = sum(phase.server_cpu for phase in mine) / sum(phase.sent for phase in mine)
        rows.append((failures, requests))
        print(
            f"{who:30} {len(latencies):6d} inputs  errors {failures}/{requests} requests  "
            f"p50 {latencies[len(latencies) // 2] * 1000:6.1f} ms  p99 "
            f"{p99(latencies) * 1000:6.1f} ms  server CPU {cpu * 1000:5.2f} ms per input"
        )
    lone = [np.array(phase.latencies) for phase in alone]
    beside = [np.array(phase.latencies) for phase in attacked_phases]

    def p99_ratio(pairs: np.ndarray) -> float:
        return p99(np.concatenate([beside[k] for k in pairs])) / p99(
            np.concatenate([lone[k] for k in pairs])
        )

    def cpu_ratio(pairs: np.ndarray) -> float:
        def per_input(mine: list[Phase]) -> float:
            chosen = [mine[k] for k in pairs]
            return float(sum(p.server_cpu for p in chosen) / sum(p.sent for p in chosen))

        return per_input(attacked_phases) / per_input(alone)

    level = expanded_level(CROWD_PHASES)
    p99_ok, verdict = p99_verdict(pair_bootstrap(p99_ratio, CROWD_PHASES, level=level))
    print(verdict)
    cost = pair_bootstrap(cpu_ratio, CROWD_PHASES, level=level)
    print(
        f"server CPU per honest input × {cost.estimate:.2f} [{cost.low:.2f}, {cost.high:.2f}] "
        f"({INTERVAL}): what the attacker's refused and served requests cost the server, per "
        "honest input (reported, not judged)"
    )
    ((failed_alone, requests_alone), (failed_attacked, requests_attacked)) = rows
    errors_ok, verdict = error_verdict(
        failed_alone, requests_alone, failed_attacked, requests_attacked
    )
    print(verdict)
    return 0 if p99_ok and errors_ok else 1


SIGNIFICANCE = 0.05
"""One-sided level of the error-rate test (an increase beside the attacker fails only
when a Fisher exact test finds it at this level)."""


def error_verdict(
    failed_alone: int, requests_alone: int, failed_attacked: int, requests_attacked: int
) -> tuple[bool, str]:
    """Is the honest error rate higher beside the attacker? One-sided Fisher exact test of
    the two counts; the increase with its 95 % interval (Newcombe) says what the run rules out."""
    increase = rate_difference(failed_alone, requests_alone, failed_attacked, requests_attacked)
    table = [
        [failed_attacked, requests_attacked - failed_attacked],
        [failed_alone, requests_alone - failed_alone],
    ]
    p_value = float(stats.fisher_exact(table, alternative="greater").pvalue)
    ok = p_value >= SIGNIFICANCE
    return ok, (
        f"honest errors {failed_alone}/{requests_alone} alone → {failed_attacked}/"
        f"{requests_attacked} beside the attacker: increase {increase.estimate:+.2%} "
        f"[{increase.low:+.2%}, {increase.high:+.2%}] (95 %, Newcombe); one-sided Fisher exact "
        f"p = {p_value:.2g}: {'ok' if ok else 'FAILED'} (an increase fails when p < "
        f"{SIGNIFICANCE:g}; this run rules out one above {increase.high:.2%})"
    )


def main() -> int:
    if "--crowd" in sys.argv[1:]:
        return crowd()
    print(describe_machine())
    print(
        f"soak: {LONG_SESSIONS} sessions × {SENSORS} sensors × {TRACKS} tracks at "
        f"{REPORTS_PER_S:g} reports/s per sensor, churn of {CHURN_INPUTS}-input sessions; "
        f"snapshot every {SNAPSHOT_EVERY}, log retention {LOG_RETENTION}"
    )
    results = []
    with tempfile.TemporaryDirectory(prefix="credal-soak-") as directory:
        database = Path(directory) / "soak.db"
        prefix = f"credal-fusion-soak:{uuid.uuid4().hex[:12]}"
        stores = [
            ("memory", "memory", {}, None),
            ("sqlite", f"sqlite:{database}", {}, database),
            ("redis", REDIS_URL, {"CREDAL_REDIS_PREFIX": prefix}, None),
        ]
        try:
            for name, store, environment, path in stores:
                with serving(store, environment) as (url, pid):
                    results.append(report(name, asyncio.run(soak(url, pid, path))))
        finally:
            client = redis.Redis.from_url(REDIS_URL)
            keys = list(client.scan_iter(match=f"{prefix}:*"))
            if keys:
                client.unlink(*keys)
            client.close()
    return 0 if all(results) else 1


if __name__ == "__main__":
    raise SystemExit(main())
