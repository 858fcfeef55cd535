"""GET /v1/sessions/{sid}/events exports the logged inputs as typed events, paged by seq."""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

from fastapi.testclient import TestClient

from api_schemas.events import EventLog
from api_schemas.reports import DetectionReport, TrackReport
from app.inputs import Input, input_kind
from app.sessions.log import event_from_entry
from app.stores import Store
from tests.api.examples import DETECTION_REPORT, SESSION_CONFIG, TRACK_REPORT


def log_input(report: TrackReport | DetectionReport) -> dict[str, Any]:
    """The log form of a report (its kind's, as the registry logs it)."""
    tag = "tracks" if type(report) is TrackReport else "detections"
    return Input(input_kind(tag), report).logged()


def test_events_round_trip_through_the_log(client: TestClient) -> None:
    created = client.post("/v1/sessions", json=SESSION_CONFIG).json()
    sid, headers = created["id"], {"Authorization": f"Bearer {created['token']}"}
    store: Store = client.app.state.store  # type: ignore[attr-defined]
    reports = [
        TrackReport.model_validate(TRACK_REPORT),
        DetectionReport.model_validate(DETECTION_REPORT),
        TrackReport.model_validate(dict(TRACK_REPORT, time=13.5)),
    ]
    for seq, report in enumerate(reports, start=1):
        store.append(sid, seq, log_input(report), datetime.now(UTC))

    everything = EventLog.model_validate(
        client.get(f"/v1/sessions/{sid}/events", headers=headers).json()
    )
    assert [event.seq for event in everything.events] == [1, 2, 3]
    assert [event.type for event in everything.events] == ["tracks", "detections", "tracks"]
    assert everything.events[0].report == reports[0]
    assert everything.events[1].report == reports[1]
    assert everything.last_seq == 3

    page = client.get(
        f"/v1/sessions/{sid}/events", params={"after": 1, "limit": 1}, headers=headers
    ).json()
    assert [event["seq"] for event in page["events"]] == [2]
    assert page["last_seq"] == 3

    bad = client.get(f"/v1/sessions/{sid}/events", params={"after": -1}, headers=headers)
    assert bad.status_code == 422
    assert bad.json()["errors"][0]["loc"] == ["query", "after"]


def test_log_form_is_tagged_plain_json() -> None:
    report = TrackReport.model_validate(TRACK_REPORT)
    logged = log_input(report)
    assert logged["type"] == "tracks"
    assert logged["report"]["tracks"][0]["id"] == "17"
    assert (
        "r"
        not in log_input(DetectionReport.model_validate(DETECTION_REPORT))["report"]["detections"][
            0
        ]
    )
    from app.stores import LogEntry

    event = event_from_entry(LogEntry(seq=4, received_at=datetime.now(UTC), input=logged))
    assert event.type == "tracks" and event.report == report
