"""Overload is refused, not spread: a saturated server refuses new inputs with 503 ``overloaded``
(``Retry-After``; on a stream, an ``error`` carrying the same problem) before any work, and
a refused input changes nothing.

A real server with ``CREDAL_OVERLOAD_DELAY_MS`` set far below what concurrent senders
cost (1 ms), so that it is saturated in a test's time; the senders ignore ``Retry-After``
and keep sending. Each session's log must hold exactly the inputs answered 200 (or
``result``), in order: nothing of a refused one. Whether the answers stay timely is
measured, not asserted here (``bench/store_cost.py``).
"""

from __future__ import annotations

import json
import threading
from pathlib import Path
from typing import Any

import httpx
from websockets.sync.client import connect

from api_schemas.reports import TrackReport
from tests.api.scenario import reports, session_config
from tests.e2e.service_process import instance

SENDERS = 6
MAX_INPUTS = 400
"""Per sender: enough to saturate the server many times over; a sender stops at its first
refusal (once the stream too has seen one)."""


def problem_is_overloaded(problem: dict[str, Any]) -> None:
    assert problem["status"] == 503
    assert problem["type"] == "urn:credal-fusion:problem:overloaded"
    assert problem["limit"] == "overload_delay_ms"
    assert problem["retry_after"] >= 1


def threads_of(target: Any, arguments: list[tuple[str, dict[str, str]]]) -> list[threading.Thread]:
    """Started threads running ``target(*a)`` for each ``a``; a failure in one is re-raised by
    :func:`join`."""
    failures: list[BaseException] = []

    def run(*args: Any) -> None:
        try:
            target(*args)
        except BaseException as error:
            failures.append(error)
            raise

    threads = [threading.Thread(target=run, args=args) for args in arguments]
    for thread in threads:
        thread.failures = failures  # type: ignore[attr-defined]
        thread.start()
    return threads


def join(threads: list[threading.Thread]) -> None:
    for thread in threads:
        thread.join()
    for thread in threads:
        for failure in thread.failures:  # type: ignore[attr-defined]
            raise failure


def logged_reports(url: str, sid: str, headers: dict[str, str]) -> list[TrackReport]:
    events = httpx.get(f"{url}/v1/sessions/{sid}/events", headers=headers, timeout=30).json()
    assert [event["seq"] for event in events["events"]] == list(range(1, len(events["events"]) + 1))
    return [TrackReport.model_validate(event["report"]) for event in events["events"]]


def test_a_saturated_server_refuses_inputs_with_503_and_changes_nothing(tmp_path: Path) -> None:
    bodies = reports(MAX_INPUTS)
    with instance(f"sqlite:{tmp_path / 'overload.db'}", {"CREDAL_OVERLOAD_DELAY_MS": "1"}) as (
        url,
        _,
    ):
        sessions = []
        for _ in range(SENDERS + 1):
            created = httpx.post(f"{url}/v1/sessions", json=session_config()).json()
            sessions.append((created["id"], {"Authorization": f"Bearer {created['token']}"}))
        accepted: dict[str, list[dict[str, Any]]] = {sid: [] for sid, _ in sessions}
        refusals: list[httpx.Response] = []
        stream_refused = threading.Event()

        def send(sid: str, headers: dict[str, str]) -> None:
            with httpx.Client(base_url=url, headers=headers, timeout=60) as client:
                for body in bodies:
                    answer = client.post(f"/v1/sessions/{sid}/tracks", json=body)
                    if answer.status_code == 200:
                        assert answer.json()["seq"] == len(accepted[sid]) + 1
                        accepted[sid].append(body)
                        continue
                    assert answer.status_code == 503, answer.text
                    refusals.append(answer)
                    if stream_refused.is_set():
                        return

        (stream_sid, stream_headers), senders = sessions[0], sessions[1:]
        threads = threads_of(send, senders)
        stream_problems = []
        token = stream_headers["Authorization"].removeprefix("Bearer ")
        address = url.replace("http://", "ws://") + f"/v1/sessions/{stream_sid}/stream"
        with connect(address, subprotocols=["bearer", token]) as stream:  # type: ignore[list-item]
            assert json.loads(stream.recv(timeout=60))["type"] == "ack"
            for index, body in enumerate(bodies):
                stream.send(json.dumps({"type": "tracks", "ref": f"m{index}", **body}))
                answer = json.loads(stream.recv(timeout=60))
                assert answer["ref"] == f"m{index}"
                if answer["type"] == "result":
                    assert answer["result"]["seq"] == len(accepted[stream_sid]) + 1
                    accepted[stream_sid].append(body)
                    continue
                assert answer["type"] == "error", answer
                stream_problems.append(answer["problem"])
                stream_refused.set()
                if refusals:
                    break
        stream_refused.set()
        join(threads)

        assert refusals, "the saturated server refused no REST input"
        for refusal in refusals:
            assert int(refusal.headers["Retry-After"]) >= 1
            assert refusal.headers["Content-Type"].startswith("application/problem+json")
            problem_is_overloaded(refusal.json())
        assert stream_problems, "the saturated server refused no stream input"
        for problem in stream_problems:
            problem_is_overloaded(problem)
        for sid, headers in sessions:  # a refused input left nothing in the log
            assert logged_reports(url, sid, headers) == [
                TrackReport.model_validate(body) for body in accepted[sid]
            ]
            summary = httpx.get(f"{url}/v1/sessions/{sid}", headers=headers, timeout=30).json()
            assert summary["seq"] == len(accepted[sid])
        metrics = httpx.get(f"{url}/metrics", timeout=30).text
        refused = next(
            line for line in metrics.splitlines() if line.startswith("credal_inputs_refused_overl")
        )
        assert float(refused.rsplit(" ", 1)[1]) == len(refusals) + len(stream_problems)


def test_overload_refusal_can_be_turned_off(tmp_path: Path) -> None:
    """``CREDAL_OVERLOAD_DELAY_MS=0``: a server never refuses for load (it falls behind)."""
    bodies = reports(60)
    with instance("memory", {"CREDAL_OVERLOAD_DELAY_MS": "0"}) as (url, _):
        sessions = []
        for _ in range(SENDERS):
            created = httpx.post(f"{url}/v1/sessions", json=session_config()).json()
            sessions.append((created["id"], {"Authorization": f"Bearer {created['token']}"}))

        def send(sid: str, headers: dict[str, str]) -> None:
            with httpx.Client(base_url=url, headers=headers, timeout=60) as client:
                for body in bodies:
                    answer = client.post(f"/v1/sessions/{sid}/tracks", json=body)
                    assert answer.status_code == 200, answer.text

        join(threads_of(send, sessions))
        for sid, headers in sessions:
            assert len(logged_reports(url, sid, headers)) == len(bodies)
