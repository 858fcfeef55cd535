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
a client of a service on a network must) for :data:`CROWD_SECONDS` alone, then
as long again with an anonymous attacker process (no key: open access on
loopback lets it create sessions and send inputs) beside it (:func:`attack`, from other loopback
addresses: slowloris connections, 16 MB headers, a session flood, floods of
the heaviest legal inputs and of explained ones). The honest sensors' p99
latency must stay within 10 % of their run alone, and the honest error rate
(failed requests of every kind, each printed with its status and problem type)
must not be higher beside the attacker: errors are a few in a thousand, so "within
10 %" of one error is no test; the rates are compared by a one-sided Fisher exact
test at 5 % (an increase fails only when significant), and the 95 % upper bound of
the increase (Newcombe's interval) is printed as what the run can rule out (exit 1
if either rule fails). The two kinds of phase alternate (:data:`CROWD_PHASES` of each), so a
drift of the machine's other load falls on both. Both processes share the
machine's cores with the server: each phase prints the CPU seconds of the
server, the honest load and the attacker, and how long the server's event
loop waited runnable for a CPU (the machine's share of the latency).
"""

from __future__ import annotations

import asyncio
import os
import re
import statistics
import sys
import tempfile
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import httpx
import redis
from scipy import stats

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from machine import describe_machine
from service import config, free_port, process_cpu_s, running, service_command, track_list

from evaluation.intervals import rate_difference

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


CROWD_SECONDS = float(os.environ.get("CROWD_SECONDS", "60"))
HONEST_KEY = "honest-soak-key-0123456789abcdefghijklmnop"
"""The honest client's API key (``CREDAL_API_KEYS``): its tenant is ``key:honest``. The server
listens on loopback, so access stays open (``auto``): the attacker needs no key to create
sessions and send inputs, as an address tenant (app/http/front.py: keyed tenants first)."""
ATTACKER = "127.0.0.77"
"""The attacker's main address (any 127.x.y.z is loopback on Linux); its slowloris
connections also come from 50 others."""


def attack(url: str, seconds: float) -> None:
    """An anonymous client spending what it can for ``seconds`` (run in its own process)."""
    import contextlib
    import socket

    port = int(url.rsplit(":", 1)[1])
    deadline = time.monotonic() + seconds
    transport = httpx.HTTPTransport(local_address=ATTACKER)
    heavy = track_list("a", 1.0, 2000)
    header = b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Pad: " + b"a" * (16 << 20) + b"\r\n\r\n"
    held: list[socket.socket] = []
    tokens: list[tuple[str, dict[str, str]]] = []
    with httpx.Client(base_url=url, transport=transport, timeout=30) as client:
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


CROWD_PHASES = 2
"""Phases of each kind, alternating (alone, attacked, alone, attacked): the machine's other
load drifts over minutes, and alternating shares the drift between the two kinds."""


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


def crowd_phase(url: str, pid: int, attacked: bool, seconds: float) -> Phase:
    """The honest load for ``seconds``, beside :func:`attack` if ``attacked``."""
    import multiprocessing

    attacker = None
    if attacked:
        spawn = multiprocessing.get_context("spawn")
        attacker = spawn.Process(target=attack, args=(url, seconds))
        attacker.start()
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


def crowd() -> int:
    """Honest load alone, then beside :func:`attack`, alternating (:data:`CROWD_PHASES` each):
    the honest p99 and error rate compared, with the CPU seconds the server, the honest load
    and the attacker spent in each phase, and the seconds the server's event loop waited for
    a CPU (the machine's: 2 cores shared by every process here and any other)."""
    print(describe_machine())
    phases: list[Phase] = []
    seconds = CROWD_SECONDS / CROWD_PHASES
    with tempfile.TemporaryDirectory(prefix="credal-soak-") as directory:
        database = Path(directory) / "crowd.db"
        settings = {"CREDAL_RATE_LIMIT": "1000/second", "CREDAL_API_KEYS": f"honest:{HONEST_KEY}"}
        with serving(f"sqlite:{database}", settings) as (url, pid):
            for _ in range(CROWD_PHASES):
                for attacked in (False, True):
                    phases.append(crowd_phase(url, pid, attacked, seconds))
    print(
        f"{CROWD_PHASES} phases of {seconds:.0f} s of each kind, alternating; CPU seconds per "
        "phase (the server's, the honest load's, the attacker's) and the seconds the server's "
        "event loop waited runnable for a CPU"
    )
    rows = []
    for attacked in (False, True):
        mine = [phase for phase in phases if phase.attacked == attacked]
        who = "honest + anonymous attacker" if attacked else "honest alone"
        for phase in mine:
            latencies = sorted(phase.latencies)
            print(
                f"  {who:28} {len(latencies):6d} inputs  p99 "
                f"{latencies[int(0.99 * (len(latencies) - 1))] * 1000:7.1f} ms  CPU: server "
                f"{phase.server_cpu:5.1f} s, honest {phase.honest_cpu:5.1f} s, attacker "
                f"{phase.attacker_cpu:5.1f} s; server loop waiting for a CPU "
                f"{phase.server_wait:5.1f} s"
            )
            for failure in phase.failed:
                print(f"    failed: {failure}")
        latencies = sorted(latency for phase in mine for latency in phase.latencies)
        requests = sum(phase.requests for phase in mine)
        failures = sum(phase.failures for phase in mine)
        p50 = latencies[len(latencies) // 2]
        p99 = latencies[int(0.99 * (len(latencies) - 1))]
        rows.append((failures, requests, p99))
        print(
            f"{who:30} {len(latencies):6d} inputs  errors {failures}/{requests} requests  "
            f"p50 {p50 * 1000:6.1f} ms  p99 {p99 * 1000:6.1f} ms"
        )
    (
        (failed_alone, requests_alone, p99_alone),
        (failed_attacked, requests_attacked, p99_attacked),
    ) = rows
    p99_ok = p99_attacked <= 1.1 * p99_alone
    print(
        f"honest p99 × {p99_attacked / p99_alone:.2f}: {'ok' if p99_ok else 'FAILED'} (within 10 %)"
    )
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
