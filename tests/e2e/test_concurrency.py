"""Eight clients post to one session at once: seq contiguous, no input lost or applied twice."""

from __future__ import annotations

import threading
from typing import Any

import httpx

from tests.api.conftest import LiveServer
from tests.api.scenario import session_config, track_report

CLIENTS = 8
INPUTS_PER_CLIENT = 6
SENSORS = [f"sensor-{index}" for index in range(CLIENTS)]


def test_eight_clients_at_once(live_server: LiveServer) -> None:
    created = httpx.post(f"{live_server.url}/v1/sessions", json=session_config(SENSORS)).json()
    sid, headers = created["id"], {"Authorization": f"Bearer {created['token']}"}
    start = threading.Barrier(CLIENTS)
    answers: dict[str, list[dict[str, Any]]] = {sensor: [] for sensor in SENSORS}
    failures: list[BaseException] = []

    def client(sensor: str, index: int) -> None:
        try:
            with httpx.Client(base_url=live_server.url, headers=headers, timeout=60) as http:
                start.wait()
                for step in range(INPUTS_PER_CLIENT):
                    body = track_report(sensor, 1.0 + step, seed=index * 100 + step, targets=2)
                    answer = http.post(f"/v1/sessions/{sid}/tracks", json=body)
                    assert answer.status_code == 200, answer.text
                    answers[sensor].append(answer.json())
        except BaseException as error:
            failures.append(error)

    threads = [
        threading.Thread(target=client, args=(sensor, index))
        for index, sensor in enumerate(SENSORS)
    ]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not failures, failures

    total = CLIENTS * INPUTS_PER_CLIENT
    seqs = sorted(result["seq"] for results in answers.values() for result in results)
    assert seqs == list(range(1, total + 1))
    events = httpx.get(f"{live_server.url}/v1/sessions/{sid}/events", headers=headers).json()[
        "events"
    ]
    assert [event["seq"] for event in events] == list(range(1, total + 1))
    for sensor in SENSORS:  # each client's inputs were applied once each, in its order
        logged = [
            event["report"]["time"] for event in events if event["report"]["sensor"] == sensor
        ]
        assert logged == [1.0 + step for step in range(INPUTS_PER_CLIENT)]
        assert [r["seq"] for r in answers[sensor]] == sorted(r["seq"] for r in answers[sensor])
    for event in events:  # the answer with seq n is the result of the logged input n
        result = next(
            r for results in answers.values() for r in results if r["seq"] == event["seq"]
        )
        assert result["sensor"] == event["report"]["sensor"]
    summary = httpx.get(f"{live_server.url}/v1/sessions/{sid}", headers=headers).json()
    assert summary["seq"] == total
    assert [sensor["inputs"] for sensor in summary["sensors"]] == [INPUTS_PER_CLIENT] * CLIENTS
