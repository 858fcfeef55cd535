"""Two real service instances (uvicorn subprocesses) share one session through the real Redis.

A sensor streams its inputs with the reference client (``app/commands/resilient.py``);
instance A applies them; a ``subscribe`` client on instance B receives
every result, in order, identical to A's answers. Then A is killed with
SIGKILL while it holds the session's lease: B refuses inputs (503 with
``Retry-After``) until the lease lapses, then takes the session over,
rebuilding it from the store, and the state continues exactly: B's results
equal those of one uninterrupted run. Redis must answer (the test fails, never
skips, without it); every key lives under a prefix of this test, deleted after.
The sensor's client fails over by itself and loses nothing: every input is
applied once, in order (README, "Clients and failures").
"""

from __future__ import annotations

import json
import signal
import subprocess
from contextlib import AbstractContextManager, ExitStack
from typing import Any

import httpx
from fastapi.testclient import TestClient
from websockets.sync.client import ClientConnection, connect

from app.commands.resilient import ResilientStream
from app.main import create_app
from tests.api.conftest import make_settings
from tests.api.redis_support import REDIS_URL, redis_prefix
from tests.api.scenario import reports, session_config
from tests.e2e.service_process import instance as serve

LEASE_TTL_MS = 1000
STEPS = 10
ON_A = 6
RECEIVE_TIMEOUT_S = 20.0


def instance(prefix: str) -> AbstractContextManager[tuple[str, subprocess.Popen[bytes]]]:
    """An instance on the shared Redis under ``prefix``, with a short lease."""
    return serve(
        REDIS_URL,
        {
            "CREDAL_REDIS_PREFIX": prefix,
            "CREDAL_LEASE_TTL_MS": str(LEASE_TTL_MS),
            "CREDAL_SNAPSHOT_EVERY": "4",
        },
    )


def uninterrupted(bodies: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The results of one run that is never interrupted (one in-process instance, memory store)."""
    with TestClient(create_app(make_settings(max_body_bytes=1 << 20))) as client:
        created = client.post("/v1/sessions", json=session_config()).json()
        headers = {"Authorization": f"Bearer {created['token']}"}
        path = f"/v1/sessions/{created['id']}/tracks"
        return [client.post(path, json=body, headers=headers).json() for body in bodies]


def receive(connection: ClientConnection) -> dict[str, Any]:
    message = json.loads(connection.recv(timeout=RECEIVE_TIMEOUT_S))
    assert isinstance(message, dict)
    return message


def test_a_session_moves_to_the_surviving_instance_and_continues_exactly() -> None:
    bodies = reports(STEPS)
    expected = uninterrupted(bodies)
    with redis_prefix("two-instances") as prefix, ExitStack() as stack:
        a_url, a_process = stack.enter_context(instance(prefix))
        b_url, _ = stack.enter_context(instance(prefix))
        a = stack.enter_context(httpx.Client(base_url=a_url, timeout=30))
        b = stack.enter_context(httpx.Client(base_url=b_url, timeout=30))
        created = a.post("/v1/sessions", json=session_config())
        assert created.status_code == 201, created.text
        sid = created.json()["id"]
        headers = {"Authorization": f"Bearer {created.json()['token']}"}
        path = f"/v1/sessions/{sid}/tracks"

        ws_url = b_url.replace("http://", "ws://") + f"/v1/sessions/{sid}/subscribe"
        subscriber = stack.enter_context(connect(ws_url, additional_headers=headers))
        assert receive(subscriber) == {"type": "ack", "ref": None, "seq": 0}

        # the sensor streams with the reference client, to A first (app/commands/resilient.py)
        sensor = ResilientStream([a_url, b_url], sid, created.json()["token"])
        stack.callback(sensor.close)
        for index in range(ON_A):
            delivery = sensor.send({"type": "tracks", **bodies[index]})
            assert (delivery.seq, delivery.result) == (index + 1, expected[index])
        for index in range(ON_A):  # B's subscriber: every result of A, in order
            message = receive(subscriber)
            assert message["type"] == "result"
            assert message["result"] == expected[index]

        a_process.send_signal(signal.SIGKILL)  # A dies holding the lease
        a_process.wait()
        refused = b.post(path, json=bodies[ON_A], headers=headers)
        assert refused.status_code == 503, refused.text
        assert refused.json()["type"] == "urn:credal-fusion:problem:session-leased"
        assert 1 <= int(refused.headers["Retry-After"]) <= LEASE_TTL_MS / 1000 + 1

        # the client's stream broke: it reconnects (to B), waits out the lease's time left, reads
        # ack.seq (its last input was applied) and goes on; B takes the session over
        for index in range(ON_A, STEPS):
            delivery = sensor.send({"type": "tracks", **bodies[index]})
            assert delivery.seq == index + 1
            assert delivery.result == expected[index]  # bit for bit: the state continued exactly
            message = receive(subscriber)
            assert message["result"] == expected[index]
        assert delivery.retries == 0 and sensor.next_url >= 2  # it failed over, then streamed
        summary = b.get(f"/v1/sessions/{sid}", headers=headers).json()
        assert summary["seq"] == STEPS
        events = b.get(f"/v1/sessions/{sid}/events", headers=headers).json()
        assert [event["seq"] for event in events["events"]] == list(range(1, STEPS + 1))
