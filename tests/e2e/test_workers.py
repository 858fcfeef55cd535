"""``serve --workers 2`` on sqlite: two real worker processes share the sessions.

Which worker a connection reaches is the kernel's choice; to make it the test's,
the other worker is stopped (SIGSTOP) while the connection is opened, then
continued: a kept-alive connection stays with the worker that accepted it.
A session created through worker A is served by worker B (read from the
store), B's ``subscribe`` client receives the results A applies (through the
workers' links), and an input sent to B while A holds the session's lease is
refused (503, ``Retry-After``), then applied by B once the lease lapses,
continuing exactly: every result equals the one of an uninterrupted run in one
process. Several clients posting to one session through both workers never
break ``seq`` or the log; and the workers end with their ``serve``, even when it is
killed.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any

import httpx
from websockets.sync.client import connect

from tests.api.scenario import reports, session_config
from tests.e2e.service_process import instance
from tests.e2e.test_concurrency import applied_once_in_order, clients_at_once
from tests.e2e.test_two_instances import uninterrupted

LEASE_TTL_MS = 400
WORKERS = {"CREDAL_WORKERS": "2", "CREDAL_LEASE_TTL_MS": str(LEASE_TTL_MS)}
START_TIMEOUT_S = 90.0


def worker_pids(process: subprocess.Popen[bytes]) -> list[int]:
    """The worker processes of ``serve`` (its children), once both run."""
    deadline = time.monotonic() + START_TIMEOUT_S
    while True:
        children = Path(f"/proc/{process.pid}/task/{process.pid}/children").read_text().split()
        if len(children) == 2:
            return [int(pid) for pid in children]
        assert time.monotonic() < deadline, f"workers: {children}"
        time.sleep(0.05)


@contextmanager
def only(url: str, serving: int, others: list[int]) -> Iterator[None]:
    """Only the worker ``serving`` accepts connections meanwhile (the others are stopped)."""
    stopped = [pid for pid in others if pid != serving]
    for pid in stopped:
        os.kill(pid, signal.SIGSTOP)
    try:
        deadline = time.monotonic() + START_TIMEOUT_S
        while True:  # it has started (the first healthy answer may have come from the other)
            try:
                if httpx.get(f"{url}/healthz", timeout=1).status_code == 200:
                    break
            except httpx.TransportError:
                pass
            assert time.monotonic() < deadline, "the worker did not start"
        yield
    finally:
        for pid in stopped:
            os.kill(pid, signal.SIGCONT)


def post_until_applied(
    client: httpx.Client, path: str, body: dict[str, Any]
) -> tuple[httpx.Response, int]:
    """Post ``body``, again after each 503 (the session's lease held by the other worker)."""
    refusals = 0
    while True:
        answer = client.post(path, json=body)
        if answer.status_code != 503:
            return answer, refusals
        assert answer.json()["type"] == "urn:credal-fusion:problem:session-leased", answer.text
        assert 1 <= int(answer.headers["Retry-After"]) <= LEASE_TTL_MS / 1000 + 1
        refusals += 1
        time.sleep(0.05)


def test_a_session_is_shared_by_the_two_workers(tmp_path: Path) -> None:
    bodies = reports(5)
    expected = uninterrupted(bodies)
    with ExitStack() as stack:
        url, process = stack.enter_context(instance(f"sqlite:{tmp_path / 'db'}", WORKERS))
        a, b = worker_pids(process)
        with only(url, a, [a, b]):
            on_a = stack.enter_context(httpx.Client(base_url=url, timeout=30))
            created = on_a.post("/v1/sessions", json=session_config())
            assert created.status_code == 201, created.text
            sid, token = created.json()["id"], created.json()["token"]
            on_a.headers["Authorization"] = f"Bearer {token}"
            path = f"/v1/sessions/{sid}/tracks"
            for index in range(3):
                answer = on_a.post(path, json=bodies[index])
                assert answer.json() == expected[index]
        with only(url, b, [a, b]):
            on_b = stack.enter_context(httpx.Client(base_url=url, timeout=30))
            on_b.headers["Authorization"] = f"Bearer {token}"
            summary = on_b.get(f"/v1/sessions/{sid}")  # B never saw it: read from the store
            assert summary.status_code == 200 and summary.json()["seq"] == 3
            ws_url = url.replace("http://", "ws://") + f"/v1/sessions/{sid}/subscribe"
            subscriber = stack.enter_context(
                connect(ws_url, additional_headers={"Authorization": f"Bearer {token}"})
            )
            assert json.loads(subscriber.recv(timeout=30)) == {"type": "ack", "ref": None, "seq": 3}

        answer = on_a.post(path, json=bodies[3])  # A holds the lease, applies; B's subscriber hears
        assert answer.json() == expected[3]
        message = json.loads(subscriber.recv(timeout=30))
        assert (message["type"], message["result"]) == ("result", expected[3])

        answer, refusals = post_until_applied(on_b, path, bodies[4])  # B, once A's lease lapses
        assert refusals >= 1, "the lease of A was not in force"
        assert answer.json() == expected[4]  # B caught up with the log: the state continued
        message = json.loads(subscriber.recv(timeout=30))
        assert (message["type"], message["result"]) == ("result", expected[4])

        events = on_a.get(f"/v1/sessions/{sid}/events").json()["events"]  # A catches up too
        assert [event["seq"] for event in events] == [1, 2, 3, 4, 5]
        assert on_a.get(f"/v1/sessions/{sid}").json()["seq"] == 5


CLIENTS = 4
INPUTS_PER_CLIENT = 5


def test_clients_of_both_workers_never_break_seq(tmp_path: Path) -> None:
    sensors = [f"sensor-{index}" for index in range(CLIENTS)]
    with instance(f"sqlite:{tmp_path / 'db'}", WORKERS) as (url, process):
        workers = worker_pids(process)
        created = httpx.post(f"{url}/v1/sessions", json=session_config(sensors)).json()
        sid, headers = created["id"], {"Authorization": f"Bearer {created['token']}"}
        answers = clients_at_once(
            url,
            sid,
            headers,
            sensors,
            INPUTS_PER_CLIENT,
            lambda http, path, body: post_until_applied(http, path, body)[0],
        )
        applied_once_in_order(url, sid, headers, answers, INPUTS_PER_CLIENT)

        process.send_signal(signal.SIGKILL)  # no worker outlives its serve, even killed
        process.wait()
        deadline = time.monotonic() + START_TIMEOUT_S
        while any(alive(pid) for pid in workers):
            assert time.monotonic() < deadline, "a worker outlived its serve"
            time.sleep(0.05)


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"
