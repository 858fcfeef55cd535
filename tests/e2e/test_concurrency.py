"""Eight clients post to one session at once: seq contiguous, no input lost or applied twice."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import httpx

from tests.api.conftest import LiveServer
from tests.api.scenario import session_config, track_report

CLIENTS = 8
INPUTS_PER_CLIENT = 6
SENSORS = [f"sensor-{index}" for index in range(CLIENTS)]

Post = Callable[[httpx.Client, str, dict[str, Any]], httpx.Response]


def plain_post(http: httpx.Client, path: str, body: dict[str, Any]) -> httpx.Response:
    return http.post(path, json=body)


def clients_at_once(
    url: str,
    sid: str,
    headers: dict[str, str],
    sensors: list[str],
    inputs_per_client: int,
    post: Post = plain_post,
) -> dict[str, list[dict[str, Any]]]:
    """One client per sensor, all started at once, each posting ``inputs_per_client`` track
    reports (times 1, 2, …) to session ``sid`` with ``post``; every answer by sensor."""
    start = threading.Barrier(len(sensors))
    answers: dict[str, list[dict[str, Any]]] = {sensor: [] for sensor in sensors}
    failures: list[BaseException] = []

    def client(sensor: str, index: int) -> None:
        try:
            with httpx.Client(base_url=url, headers=headers, timeout=60) as http:
                start.wait()
                for step in range(inputs_per_client):
                    body = track_report(sensor, 1.0 + step, seed=index * 100 + step, targets=2)
                    answer = post(http, f"/v1/sessions/{sid}/tracks", body)
                    assert answer.status_code == 200, answer.text
                    answers[sensor].append(answer.json())
        except BaseException as error:
            failures.append(error)

    threads = [
        threading.Thread(target=client, args=(sensor, index))
        for index, sensor in enumerate(sensors)
    ]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not failures, failures
    return answers


def applied_once_in_order(
    url: str,
    sid: str,
    headers: dict[str, str],
    answers: dict[str, list[dict[str, Any]]],
    inputs_per_client: int,
) -> None:
    """Each seq answered once (no input twice), the log contiguous, each client's inputs
    logged once each in its order, and the answer with seq n the result of logged input n."""
    total = len(answers) * inputs_per_client
    seqs = sorted(result["seq"] for results in answers.values() for result in results)
    assert seqs == list(range(1, total + 1))
    events = httpx.get(f"{url}/v1/sessions/{sid}/events", headers=headers).json()["events"]
    assert [event["seq"] for event in events] == list(range(1, total + 1))
    for sensor in answers:
        logged = [e["report"]["time"] for e in events if e["report"]["sensor"] == sensor]
        assert logged == [1.0 + step for step in range(inputs_per_client)]
    for event in events:
        result = next(
            r for results in answers.values() for r in results if r["seq"] == event["seq"]
        )
        assert result["sensor"] == event["report"]["sensor"]


def test_eight_clients_at_once(live_server: LiveServer) -> None:
    created = httpx.post(f"{live_server.url}/v1/sessions", json=session_config(SENSORS)).json()
    sid, headers = created["id"], {"Authorization": f"Bearer {created['token']}"}
    answers = clients_at_once(live_server.url, sid, headers, SENSORS, INPUTS_PER_CLIENT)
    applied_once_in_order(live_server.url, sid, headers, answers, INPUTS_PER_CLIENT)
    for sensor in SENSORS:  # each client's answers in its order
        assert [r["seq"] for r in answers[sensor]] == sorted(r["seq"] for r in answers[sensor])
    summary = httpx.get(f"{live_server.url}/v1/sessions/{sid}", headers=headers).json()
    assert summary["seq"] == CLIENTS * INPUTS_PER_CLIENT
    assert [sensor["inputs"] for sensor in summary["sensors"]] == [INPUTS_PER_CLIENT] * CLIENTS
