"""Redis outages timed: how fast the service notices and how fast it recovers by itself.

Run with ``python bench/outage.py``. A private ``redis-server`` (its own port,
append-only file) and a real service instance (``credal-fusion serve``) on
it, as in ``tests/e2e/test_store_outage.py``, which checks what clients are
told and that nothing is lost; this script only times it, a few rounds:

- *killed*: the service starts with Redis up (the start-up time: the baseline
  of the next scenario's); Redis is killed (SIGKILL) under a live session; the time to the
  first input answered 503 ``store-unavailable``, then, after Redis restarts
  on the same port, the time until ``/readyz`` says ready and until the next
  input is accepted;
- *down at start*: the service starts while Redis is not running; the time
  until ``/healthz`` answers (the process is alive), then, once Redis starts,
  the time until ``/readyz`` says ready and a session can be created.

- *frozen*: Redis stopped (SIGSTOP) under a live session: how long an input
  and ``/readyz`` take to answer 503 (the store's 2 s command timeout);
- *failover*: two instances on one Redis, the one a sensor streams to killed
  (SIGKILL): how long until the reference client (``app/commands/resilient.py``)
  has its next input applied through the other (the 3 s lease), and after how
  many tries.

Never asserts a time: the shared machine's load moves every number.
"""

from __future__ import annotations

import signal
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import httpx

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.api.scenario import reports, session_config  # noqa: E402
from tests.e2e.service_process import PrivateRedis, instance  # noqa: E402

ROUNDS = 3
TIMEOUT_S = 30.0
POLL_S = 0.01


def until(condition: Callable[[], bool]) -> float:
    """Seconds until ``condition()`` holds (polled every 10 ms)."""
    started = time.monotonic()
    while not condition():
        if time.monotonic() - started > TIMEOUT_S:
            raise RuntimeError("no recovery within the timeout")
        time.sleep(POLL_S)
    return time.monotonic() - started


def answers(client: httpx.Client, path: str, status: int) -> Callable[[], bool]:
    def check() -> bool:
        try:
            return client.get(path).status_code == status
        except httpx.TransportError:
            return False

    return check


def killed(directory: Path) -> dict[str, float]:
    """Redis killed under a live session, then restarted on its port."""
    bodies = reports(3)
    server = PrivateRedis(directory)
    server.start()
    try:
        launched = time.monotonic()
        with instance(server.url) as (url, _), httpx.Client(base_url=url, timeout=30) as client:
            alive = time.monotonic() - launched
            created = client.post("/v1/sessions", json=session_config()).json()
            headers = {"Authorization": f"Bearer {created['token']}"}
            path = f"/v1/sessions/{created['id']}/tracks"
            client.post(path, json=bodies[0], headers=headers).raise_for_status()
            server.kill()
            down = time.monotonic()
            if client.post(path, json=bodies[1], headers=headers).status_code != 503:
                raise RuntimeError("an input was accepted with Redis down")
            first_503 = time.monotonic() - down
            server.start()
            ready = until(answers(client, "/readyz", 200))
            accepted = until(
                lambda: client.post(path, json=bodies[1], headers=headers).status_code == 200
            )
            return {
                "alive after launch (Redis up: the baseline)": alive,
                "first 503 after the kill": first_503,
                "ready after Redis restarted": ready,
                "next input accepted after ready": accepted,
            }
    finally:
        server.stop()


def down_at_start(directory: Path) -> dict[str, float]:
    """The service started while Redis is not running, Redis started afterwards."""
    server = PrivateRedis(directory)  # its port chosen, not started
    try:
        launched = time.monotonic()
        with instance(server.url) as (url, _), httpx.Client(base_url=url, timeout=30) as client:
            alive = time.monotonic() - launched
            if client.get("/readyz").status_code != 503:
                raise RuntimeError("ready without its store")
            server.start()
            ready = until(answers(client, "/readyz", 200))
            created = client.post("/v1/sessions", json=session_config())
            if created.status_code != 201:
                raise RuntimeError(f"no session once ready: {created.status_code}")
            return {"alive after launch (Redis down)": alive, "ready after Redis started": ready}
    finally:
        server.stop()


def frozen(directory: Path) -> dict[str, float]:
    """Redis frozen (SIGSTOP) under a live session: how long an input and /readyz take to say so."""
    bodies = reports(2)
    server = PrivateRedis(directory)
    server.start()
    try:
        with instance(server.url) as (url, _), httpx.Client(base_url=url, timeout=30) as client:
            created = client.post("/v1/sessions", json=session_config()).json()
            headers = {"Authorization": f"Bearer {created['token']}"}
            path = f"/v1/sessions/{created['id']}/tracks"
            client.post(path, json=bodies[0], headers=headers).raise_for_status()
            assert server.process is not None
            server.process.send_signal(signal.SIGSTOP)
            try:
                started = time.monotonic()
                status = client.post(path, json=bodies[1], headers=headers).status_code
                answered = time.monotonic() - started
                started = time.monotonic()
                ready = client.get("/readyz").status_code
                readiness = time.monotonic() - started
            finally:
                server.process.send_signal(signal.SIGCONT)
            if status != 503 or ready != 503:
                raise RuntimeError(f"frozen Redis not told: input {status}, /readyz {ready}")
            return {
                "frozen: input answered 503 after": answered,
                "frozen: /readyz 503 after": readiness,
            }
    finally:
        server.stop()


def failover(directory: Path) -> dict[str, float]:
    """Two instances on one Redis; the one a sensor streams to is killed (SIGKILL): how long until
    the reference client's next input is applied through the other, and after how many tries."""
    from app.commands.resilient import ResilientStream

    bodies = reports(4)
    server = PrivateRedis(directory)
    server.start()
    try:
        with instance(server.url) as (url_a, process_a), instance(server.url) as (url_b, _):
            created = httpx.post(f"{url_a}/v1/sessions", json=session_config(), timeout=30).json()
            client = ResilientStream([url_a, url_b], created["id"], created["token"])
            try:
                for body in bodies[:3]:
                    client.send({"type": "tracks", **body})
                process_a.send_signal(signal.SIGKILL)
                process_a.wait()
                killed_at = time.monotonic()
                delivery = client.send({"type": "tracks", **bodies[3]})
                taken_over = time.monotonic() - killed_at
            finally:
                client.close()
            if delivery.seq != 4:
                raise RuntimeError(f"input applied as seq {delivery.seq}, not 4")
            return {
                "failover: next input applied after the kill": taken_over,
                "failover: tries before it": float(delivery.retries),
            }
    finally:
        server.stop()


def main() -> int:
    rows: dict[str, list[float]] = {}
    for scenario in (killed, down_at_start, frozen, failover):
        for _ in range(ROUNDS):
            with tempfile.TemporaryDirectory(prefix="credal-outage-") as directory:
                for name, seconds in scenario(Path(directory)).items():
                    rows.setdefault(name, []).append(seconds)
    width = max(len(name) for name in rows)
    print(f"{'redis outage (' + str(ROUNDS) + ' rounds)':{width}}  median s  rounds s")
    for name, values in rows.items():
        each = " ".join(f"{value:.3f}" for value in values)
        print(f"{name:{width}}  {statistics.median(values):8.3f}  {each}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
