"""Idempotency keys outlive the instance that answered them (issue 28): real servers.

On sqlite, a server answers inputs sent with a key, is killed with SIGKILL and
restarted on the same file; on the shared Redis, the instance that answered
is killed and two others take the session over (one had it in memory at an
older ``seq``: it catches up from the log; one loads it: snapshot, then the log
after it). Each resend of a keyed input gets the first answer, byte for byte,
and nothing is applied twice: the session's ``seq`` and its log
(``GET …/events``) still count each input once. Snapshots every 3 inputs,
so keys come back both from a snapshot and from the log after it; over REST
and over the ``stream`` WebSocket.
"""

from __future__ import annotations

import json
import signal
import subprocess
import time
from contextlib import AbstractContextManager, ExitStack
from pathlib import Path
from typing import Any

import httpx
from websockets.sync.client import connect

from tests.api.redis_support import REDIS_URL, redis_prefix
from tests.api.scenario import reports, session_config
from tests.e2e.service_process import instance

STEPS = 4
SNAPSHOT_EVERY = 3
LEASE_TTL_MS = 1000
SERVED_WITHIN_S = 30.0


def key(index: int) -> str:
    return f"scan-{index:04d}"


def post(client: httpx.Client, path: str, body: Any, headers: dict[str, str]) -> httpx.Response:
    """POST, waiting out 503s (a lease still held by the killed instance) as a client would."""
    deadline = time.monotonic() + SERVED_WITHIN_S
    while True:
        answer = client.post(path, json=body, headers=headers)
        if answer.status_code != 503 or time.monotonic() > deadline:
            return answer
        time.sleep(0.2)


def stream_send(url: str, sid: str, token: str, message: dict[str, Any]) -> dict[str, Any]:
    """One message over ``stream``: the connection's ``ack``, then the answer to it."""
    ws_url = url.replace("http://", "ws://") + f"/v1/sessions/{sid}/stream"
    with connect(ws_url, additional_headers={"Authorization": f"Bearer {token}"}) as connection:
        ack = json.loads(connection.recv(timeout=30))
        assert ack["type"] == "ack"
        connection.send(json.dumps(message))
        answer = json.loads(connection.recv(timeout=30))
        assert isinstance(answer, dict)
        return answer


def applied(client: httpx.Client, sid: str, headers: dict[str, str]) -> tuple[int, list[int]]:
    """The session's ``seq`` and the ``seq`` of every logged input."""
    summary = client.get(f"/v1/sessions/{sid}", headers=headers)
    events = client.get(f"/v1/sessions/{sid}/events", headers=headers)
    assert summary.status_code == events.status_code == 200, (summary.text, events.text)
    return summary.json()["seq"], [event["seq"] for event in events.json()["events"]]


def send_keyed(
    client: httpx.Client, url: str, sid: str, token: str, bodies: list[dict[str, Any]]
) -> dict[str, bytes]:
    """Inputs 1..STEPS-1 over REST, the last over ``stream``, each with its key; the answers."""
    headers = {"Authorization": f"Bearer {token}"}
    answers: dict[str, bytes] = {}
    for index, body in enumerate(bodies[:-1]):
        answer = client.post(
            f"/v1/sessions/{sid}/tracks",
            json=body,
            headers=headers | {"Idempotency-Key": key(index)},
        )
        assert answer.status_code == 200, answer.text
        assert answer.json()["seq"] == index + 1
        answers[key(index)] = answer.content
    last = len(bodies) - 1
    message = {"type": "tracks", "ref": "r", "idempotency_key": key(last), **bodies[last]}
    result = stream_send(url, sid, token, message)
    assert result["type"] == "result" and result["result"]["seq"] == len(bodies), result
    answers[key(last)] = json.dumps(result["result"]).encode()
    return answers


def check_resends(
    client: httpx.Client,
    url: str,
    sid: str,
    token: str,
    bodies: list[dict[str, Any]],
    answers: dict[str, bytes],
    indices: list[int],
) -> None:
    """Each of ``indices`` resent (the last over ``stream``) gets its first answer; another
    input under a used key is refused; the session still holds each input once."""
    headers = {"Authorization": f"Bearer {token}"}
    last = len(bodies) - 1
    for index in indices:
        if index == last:
            message = {"type": "tracks", "ref": "again", "idempotency_key": key(index)}
            result = stream_send(url, sid, token, message | bodies[index])
            assert result["type"] == "result", result
            assert result["ref"] == "again"
            assert result["result"] == json.loads(answers[key(index)])
        else:
            again = post(
                client,
                f"/v1/sessions/{sid}/tracks",
                bodies[index],
                headers | {"Idempotency-Key": key(index)},
            )
            assert again.status_code == 200, again.text
            assert again.content == answers[key(index)]
    other = post(
        client,
        f"/v1/sessions/{sid}/tracks",
        bodies[(indices[0] + 1) % len(bodies)],
        headers | {"Idempotency-Key": key(indices[0])},
    )
    assert other.status_code == 409, other.text
    assert other.json()["type"] == "urn:credal-fusion:problem:idempotency-key-reused"
    assert applied(client, sid, headers) == (len(bodies), list(range(1, len(bodies) + 1)))


def test_keys_survive_a_sigkill_and_restart_on_sqlite(tmp_path: Path) -> None:
    store = f"sqlite:{tmp_path / 'credal.db'}"
    environment = {"CREDAL_SNAPSHOT_EVERY": str(SNAPSHOT_EVERY)}
    bodies = reports(STEPS)
    with instance(store, environment) as (url, process), httpx.Client(base_url=url) as client:
        created = client.post("/v1/sessions", json=session_config()).json()
        sid, token = created["id"], created["token"]
        answers = send_keyed(client, url, sid, token, bodies)
        process.send_signal(signal.SIGKILL)
        process.wait()
    with instance(store, environment) as (url, _), httpx.Client(base_url=url) as client:
        # key 0 comes back from the snapshot (after input 3), the last from the log after it
        check_resends(client, url, sid, token, bodies, answers, [0, STEPS - 1])


def test_keys_survive_a_takeover_on_redis() -> None:
    bodies = reports(STEPS)

    def shared(prefix: str) -> AbstractContextManager[tuple[str, subprocess.Popen[bytes]]]:
        return instance(
            REDIS_URL,
            {
                "CREDAL_REDIS_PREFIX": prefix,
                "CREDAL_LEASE_TTL_MS": str(LEASE_TTL_MS),
                "CREDAL_SNAPSHOT_EVERY": str(SNAPSHOT_EVERY),
            },
        )

    with redis_prefix("idempotency") as prefix, ExitStack() as stack:
        a_url, a_process = stack.enter_context(shared(prefix))
        b_url, _ = stack.enter_context(shared(prefix))
        a = stack.enter_context(httpx.Client(base_url=a_url, timeout=30))
        b = stack.enter_context(httpx.Client(base_url=b_url, timeout=30))
        created = a.post("/v1/sessions", json=session_config()).json()
        sid, token = created["id"], created["token"]
        headers = {"Authorization": f"Bearer {token}"}
        assert applied(b, sid, headers) == (0, [])  # B holds the session in memory at seq 0
        answers = send_keyed(a, a_url, sid, token, bodies)
        a_process.send_signal(signal.SIGKILL)  # A dies holding the lease
        a_process.wait()
        # B catches up from the log (every input, with its key) once A's lease lapses
        check_resends(b, b_url, sid, token, bodies, answers, [1, STEPS - 1])
        # C has never seen the session: it loads the snapshot (after input 3) and the log after it
        c_url, _ = stack.enter_context(shared(prefix))
        c = stack.enter_context(httpx.Client(base_url=c_url, timeout=30))
        check_resends(c, c_url, sid, token, bodies, answers, [0, STEPS - 1])
