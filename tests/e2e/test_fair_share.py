"""A flooding tenant does not starve another's sensor, and an input kept waiting is refused
rather than answered late (issues 28 and 29), on a real server.

Open access: each client address is a tenant (any 127.x.y.z is loopback on Linux). The
assertions are on answers, counts and order, never on time.
"""

from __future__ import annotations

import threading
from typing import Any

import httpx
import pytest

from api_schemas.reports import TrackReport
from tests.api.scenario import session_config, track_report
from tests.e2e.service_process import instance
from tests.e2e.test_overload import join, threads_of

FLOOD_ADDRESS = "127.0.0.77"
FLOODERS = 8
POLITE_INPUTS = 12
TARGETS = 40
"""Targets per report: a step of 40 reported on 40 fused tracks runs in a worker thread
(app.sessions.work.TINY_WORK), so a flood's inputs wait in flight beside it."""


def create(client: httpx.Client, sensors: list[str]) -> tuple[str, dict[str, str]]:
    created = client.post("/v1/sessions", json=session_config(sensors))
    assert created.status_code == 201, created.text
    body = created.json()
    return body["id"], {"Authorization": f"Bearer {body['token']}"}


def logged_reports(url: str, sid: str, headers: dict[str, str]) -> list[TrackReport]:
    """Every input in the session's log, page by page (a page stops at 4 MiB), seq contiguous."""
    events: list[dict[str, Any]] = []
    while True:
        page = httpx.get(
            f"{url}/v1/sessions/{sid}/events",
            params={"after": len(events)},
            headers=headers,
            timeout=30,
        ).json()
        events += page["events"]
        if len(events) >= page["last_seq"]:
            break
    assert [event["seq"] for event in events] == list(range(1, len(events) + 1))
    return [TrackReport.model_validate(event["report"]) for event in events]


def metric(url: str, line_start: str) -> float:
    text = httpx.get(f"{url}/metrics", timeout=30).text
    values = [
        float(line.rsplit(" ", 1)[1]) for line in text.splitlines() if line.startswith(line_start)
    ]
    return sum(values)


REFUSING = {
    "guard": ({"CREDAL_OVERLOAD_DELAY_MS": "1"}, 503, "overload_delay_ms"),
    "cap": (
        {"CREDAL_OVERLOAD_DELAY_MS": "0", "CREDAL_TENANT_MAX_IN_FLIGHT": "4"},
        429,
        "tenant_max_in_flight",
    ),
}


@pytest.mark.parametrize("refusing", list(REFUSING))
def test_a_flooding_tenant_is_refused_and_a_polite_tenant_is_answered_in_full(
    refusing: str,
) -> None:
    """Eight connections of one tenant post without pause (ignoring every refusal) while a
    polite tenant's sensor sends 12 inputs, each after the answer to the last. ``guard``: the
    overload guard at 1 ms, which refuses any input while others are in flight unless its
    tenant holds less than its share of them; ``cap``: no guard, and the flooding tenant may
    have 4 inputs in flight. Either way the polite sensor's inputs are all answered 200 in
    order (seq 1…12, its log exactly those reports), and the flood is refused (503 naming
    ``overload_delay_ms``, or 429 naming ``tenant_max_in_flight``; ``Retry-After``,
    problem+json), its logs holding exactly its answered inputs, ``/metrics`` counting
    the cap's refusals."""
    settings, status, limit = REFUSING[refusing]
    with instance("memory", settings) as (url, _):
        flood_transport = httpx.HTTPTransport(local_address=FLOOD_ADDRESS)
        with httpx.Client(base_url=url, transport=flood_transport, timeout=60) as client:
            floods = [create(client, [f"f{index}"]) for index in range(FLOODERS)]
        with httpx.Client(base_url=url) as client:
            polite_sid, polite_headers = create(client, ["radar"])
        flooding = threading.Event()
        polite_done = threading.Event()
        flood_answers: dict[str, list[httpx.Response]] = {sid: [] for sid, _ in floods}
        accepted: dict[str, list[dict[str, Any]]] = {sid: [] for sid, _ in floods}

        def flood(sid: str, headers: dict[str, str]) -> None:
            sensor = f"f{[s for s, _ in floods].index(sid)}"
            transport = httpx.HTTPTransport(local_address=FLOOD_ADDRESS)
            with httpx.Client(
                base_url=url, transport=transport, headers=headers, timeout=60
            ) as http:
                step = 0
                while not polite_done.is_set() and step < 5000:
                    body = track_report(sensor, 1.0 + step, seed=step, targets=TARGETS)
                    answer = http.post(f"/v1/sessions/{sid}/tracks", json=body)
                    flood_answers[sid].append(answer)
                    if answer.status_code == 200:
                        accepted[sid].append(body)
                    else:
                        flooding.set()
                    step += 1

        threads = threads_of(flood, floods)
        assert flooding.wait(timeout=120), "the flood was never refused"
        polite: list[httpx.Response] = []
        bodies = [track_report("radar", 1.0 + step, seed=step) for step in range(POLITE_INPUTS)]
        try:
            with httpx.Client(base_url=url, headers=polite_headers, timeout=60) as http:
                for body in bodies:
                    polite.append(http.post(f"/v1/sessions/{polite_sid}/tracks", json=body))
        finally:
            polite_done.set()
            join(threads)

        assert [answer.status_code for answer in polite] == [200] * POLITE_INPUTS, [
            answer.text for answer in polite if answer.status_code != 200
        ]
        assert [answer.json()["seq"] for answer in polite] == list(range(1, POLITE_INPUTS + 1))
        assert logged_reports(url, polite_sid, polite_headers) == [
            TrackReport.model_validate(body) for body in bodies
        ]

        refusals = [
            a for answers in flood_answers.values() for a in answers if a.status_code != 200
        ]
        for answer in refusals:
            assert answer.headers["Content-Type"].startswith("application/problem+json")
            assert int(answer.headers["Retry-After"]) >= 1
            # the flood may meet the tenant's other rates first: 8 connections of 11 KB bodies
            # answered faster than a thread hop per input reach 2 MiB/s
            tenant_rates = ("tenant_inputs_per_second", "tenant_body_bytes_per_second")
            assert answer.json()["limit"] in (limit, *tenant_rates), answer.text
        mine = [a for a in refusals if a.json()["limit"] == limit]
        assert mine and {a.status_code for a in mine} == {status}
        for sid, headers in floods:  # a refused input left nothing in the flood's logs either
            assert logged_reports(url, sid, headers) == [
                TrackReport.model_validate(body) for body in accepted[sid]
            ]
        capped = metric(url, 'credal_inputs_refused_waiting_total{limit="tenant_max_in_flight"}')
        assert capped == sum(a.json()["limit"] == "tenant_max_in_flight" for a in refusals)


def test_an_input_kept_waiting_beyond_max_queue_ms_is_refused_unapplied_and_unlogged() -> None:
    """Four sensors post to one session at once, each its next report after every answer, with
    ``max_queue_ms`` = 1: an input whose request was read while others' were, and whose step
    waits for theirs, is refused 503 ``overloaded`` naming ``max_queue_ms`` with
    ``Retry-After``, before its step. The session's log holds exactly the inputs answered
    200, in each sensor's order, its seq counts them, and the refused ones are nowhere: not
    applied, not logged."""
    sensors = ["a", "b", "c", "d"]
    with instance("memory", {"CREDAL_MAX_QUEUE_MS": "1", "CREDAL_OVERLOAD_DELAY_MS": "0"}) as (
        url,
        _,
    ):
        with httpx.Client(base_url=url) as client:
            sid, headers = create(client, sensors)
        accepted: dict[str, list[dict[str, Any]]] = {name: [] for name in sensors}
        refused: dict[str, list[dict[str, Any]]] = {name: [] for name in sensors}
        problems: list[dict[str, Any]] = []

        def sensor(name: str, _: dict[str, str]) -> None:
            with httpx.Client(base_url=url, headers=headers, timeout=60) as http:
                for step in range(300):
                    if len(problems) >= 3:
                        return
                    body = track_report(name, 1.0 + step, seed=step)
                    answer = http.post(f"/v1/sessions/{sid}/tracks", json=body)
                    if answer.status_code == 200:
                        accepted[name].append(body)
                    else:
                        assert answer.status_code == 503, answer.text
                        assert int(answer.headers["Retry-After"]) >= 1
                        problems.append(answer.json())
                        refused[name].append(body)

        join(threads_of(sensor, [(name, {}) for name in sensors]))

        assert problems, "no input was kept waiting"
        for problem in problems:
            assert problem["type"] == "urn:credal-fusion:problem:overloaded"
            assert problem["limit"] == "max_queue_ms"
            assert problem["queued_ms"] > 1
        logged = logged_reports(url, sid, headers)
        for name in sensors:
            assert [r for r in logged if r.sensor == name] == [
                TrackReport.model_validate(body) for body in accepted[name]
            ]
            times = {r.time for r in logged if r.sensor == name}
            assert not times & {body["time"] for body in refused[name]}
        summary = httpx.get(f"{url}/v1/sessions/{sid}", headers=headers, timeout=30).json()
        assert summary["seq"] == sum(len(inputs) for inputs in accepted.values()) == len(logged)
        assert metric(url, 'credal_inputs_refused_waiting_total{limit="max_queue_ms"}') == len(
            problems
        )
