"""``time`` as an RFC 3339 timestamp: converted to Unix seconds, one way per session.

Expected seconds come from an independent conversion (``calendar.timegm`` of the
broken-down UTC time, the offset subtracted by hand), never from the service's
:func:`~api_schemas.timing.timestamp_seconds`. Over a live server: track lists,
detections, ``GET …/tracks?time=``, the WebSocket ``stream``, and the session's
``time_epoch``; a rebuilt session keeps its epoch (snapshot and log).
"""

from __future__ import annotations

import asyncio
import calendar
import json
from typing import Any

import httpx
import numpy as np
import pytest
from websockets.sync.client import connect

from api_schemas.timing import timestamp_seconds
from app.inputs import parse_input
from tests.api.conftest import LiveServer, live_server
from tests.api.test_registry import new_session, registry

__all__ = ["live_server"]

COVARIANCE = [[4, 0, 0, 0], [0, 1, 0, 0], [0, 0, 4, 0], [0, 0, 0, 1]]
CONFIG: dict[str, Any] = {
    "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
    "motion": {"model": "constant_velocity", "q": 1.0},
    "sensors": [
        {"id": "radar-1"},
        {"id": "radar-2"},
        {"id": "radar-3", "measurement": {"r": [[25, 0], [0, 25]]}},
    ],
    "tracking": {"preset": "aircraft", "time_interval": 1.0},
}
START = calendar.timegm((2026, 12, 3, 8, 0, 0))  # 2026-12-03T08:00:00Z, by the C library
RECEIVE_TIMEOUT_S = 30.0


def stamp(offset_s: float) -> str:
    """START + offset as text, built by hand (an independent formatting)."""
    whole = int(offset_s // 1)
    fraction = round(offset_s - whole, 6)
    minutes, seconds = divmod(whole, 60)
    text = f"2026-12-03T08:{minutes:02d}:{seconds:02d}"
    return text + (f"{fraction:.6f}"[1:] if fraction else "") + "Z"


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("2026-12-03T08:00:00Z", START),
        ("2026-12-03t08:00:00z", START),
        ("2026-12-03 08:00:00Z", START),
        ("2026-12-03T09:30:00+01:30", START),
        ("2026-12-02T23:00:00-09:00", START),
        ("2026-12-03T08:00:00.25Z", START + 0.25),
        ("2026-12-03T08:00:00.000000001Z", START + 1e-9),
        ("1970-01-01T00:00:00Z", 0.0),
        ("1969-12-31T23:59:59.5Z", -0.5),
        ("2024-02-29T00:00:00Z", calendar.timegm((2024, 2, 29, 0, 0, 0))),
    ],
)
def test_timestamps_are_seconds_since_the_unix_epoch(text: str, expected: float) -> None:
    assert timestamp_seconds(text) == pytest.approx(expected, abs=1e-6)


@pytest.mark.parametrize(
    "text",
    [
        "2026-12-03T08:00:00",  # no UTC offset: which clock?
        "2026-12-03",
        "2026-13-03T08:00:00Z",
        "2026-02-30T08:00:00Z",
        "2026-12-03T24:00:00Z",
        "2026-12-03T08:00:60Z",  # a leap second: POSIX time has none
        "1796284800",
        "now",
        "",
    ],
)
def test_what_is_not_an_rfc_3339_timestamp_is_refused_at_time(
    live_server: LiveServer, text: str
) -> None:
    with httpx.Client(base_url=live_server.url) as client:
        sid, headers = session(client)
        answer = client.post(
            f"/v1/sessions/{sid}/tracks", json=track_list("radar-1", text), headers=headers
        )
        assert answer.status_code == 422, answer.text
        assert answer.headers["content-type"].startswith("application/problem+json")
        [error] = answer.json()["errors"]
        assert error["pointer"] == "#/time", error
        assert "RFC 3339" in error["detail"] or "date and time" in error["detail"], error
        summary = client.get(f"/v1/sessions/{sid}", headers=headers).json()
        assert (summary["seq"], summary["time"], summary["time_epoch"]) == (0, None, None)


def session(
    client: httpx.Client, config: dict[str, Any] | None = None
) -> tuple[str, dict[str, str]]:
    created = client.post("/v1/sessions", json=config or CONFIG)
    assert created.status_code == 201, created.text
    return created.json()["id"], {"Authorization": f"Bearer {created.json()['token']}"}


def track_list(sensor: str, time: float | str, x: float = 100.0) -> dict[str, Any]:
    return {
        "sensor": sensor,
        "time": time,
        "tracks": [{"id": "t", "state": [x, 3, 250, -1], "covariance": COVARIANCE}],
    }


def scene(times: list[float | str]) -> list[tuple[str, dict[str, Any]]]:
    """Two track-list radars, then radar-3's detections (an IMM), at ``times``."""
    inputs: list[tuple[str, dict[str, Any]]] = [
        ("tracks", track_list("radar-1", times[0])),
        ("tracks", track_list("radar-2", times[1], x=101.5)),
    ]
    for k, time in enumerate(times[2:], start=1):
        z = [100.0 + 3 * k, 250.0 - k]
        inputs.append(("detections", {"sensor": "radar-3", "time": time, "detections": [{"z": z}]}))
    return inputs


OFFSETS = [0.0, 0.5, 1.0, 2.0, 3.25, 4.0, 5.0]


def test_timestamps_give_the_results_of_the_same_unix_seconds(live_server: LiveServer) -> None:
    """One scene sent twice: times as timestamps, and as the Unix seconds worked out here.
    Every answer is the same (times, states to 1e-9 relative), and the first session says
    its epoch is unix, the second arbitrary."""
    stamped = scene([stamp(offset) for offset in OFFSETS])
    numbered = scene([START + offset for offset in OFFSETS])
    with httpx.Client(base_url=live_server.url) as client:
        answers = []
        for inputs in (stamped, numbered):
            sid, headers = session(client)
            results = []
            for kind, body in inputs:
                answer = client.post(f"/v1/sessions/{sid}/{kind}", json=body, headers=headers)
                assert answer.status_code == 200, answer.text
                results.append(answer.json())
            summary = client.get(f"/v1/sessions/{sid}", headers=headers).json()
            answers.append((results, summary))
    (by_stamp, stamp_summary), (by_number, number_summary) = answers
    assert [r["time"] for r in by_stamp] == [START + offset for offset in OFFSETS]
    for left, right in zip(by_stamp, by_number, strict=True):
        assert [t["id"] for t in left["tracks"]] == [t["id"] for t in right["tracks"]]
        for one, other in zip(left["tracks"], right["tracks"], strict=True):
            np.testing.assert_allclose(one["state"], other["state"], rtol=1e-9)
            np.testing.assert_allclose(one["covariance"], other["covariance"], rtol=1e-9)
    assert stamp_summary["time_epoch"] == "unix" and number_summary["time_epoch"] == "arbitrary"
    assert stamp_summary["time"] == number_summary["time"] == START + OFFSETS[-1]
    assert by_stamp[-1]["tracks"][0]["status"] == "confirmed"


def test_a_session_keeps_to_its_first_inputs_way(live_server: LiveServer) -> None:
    with httpx.Client(base_url=live_server.url) as client:
        unix, unix_headers = session(client)
        arbitrary, arbitrary_headers = session(client)
        first = client.post(
            f"/v1/sessions/{unix}/tracks",
            json=track_list("radar-1", stamp(0)),
            headers=unix_headers,
        )
        assert first.status_code == 200, first.text
        numbers = client.post(
            f"/v1/sessions/{arbitrary}/tracks",
            json=track_list("radar-1", 12),
            headers=arbitrary_headers,
        )
        assert numbers.status_code == 200, numbers.text
        for sid, headers, time, says in (
            (unix, unix_headers, START + 1.0, "timestamps"),
            (arbitrary, arbitrary_headers, stamp(1), "seconds of its own epoch"),
        ):
            refused = client.post(
                f"/v1/sessions/{sid}/tracks", json=track_list("radar-2", time), headers=headers
            )
            assert refused.status_code == 422, refused.text
            [error] = refused.json()["errors"]
            assert error["pointer"] == "#/time" and says in error["detail"], error
            assert client.get(f"/v1/sessions/{sid}", headers=headers).json()["seq"] == 1

        # reads: a number is always seconds; a timestamp only where the clock is Unix time
        ahead = client.get(
            f"/v1/sessions/{unix}/tracks", params={"time": stamp(10)}, headers=unix_headers
        )
        assert ahead.status_code == 200, ahead.text
        assert ahead.json()["time"] == START + 10
        same = client.get(
            f"/v1/sessions/{unix}/tracks", params={"time": START + 10}, headers=unix_headers
        )
        assert same.json() == ahead.json()
        refused = client.get(
            f"/v1/sessions/{arbitrary}/tracks",
            params={"time": stamp(10)},
            headers=arbitrary_headers,
        )
        assert refused.status_code == 422, refused.text
        [error] = refused.json()["errors"]
        assert error["pointer"] == "#/query/time", error


def test_the_stream_takes_timestamps_and_the_log_keeps_them(live_server: LiveServer) -> None:
    with httpx.Client(base_url=live_server.url) as client:
        sid, headers = session(client)
        url = live_server.url.replace("http://", "ws://") + f"/v1/sessions/{sid}/stream"
        with connect(url, additional_headers=headers) as stream:
            assert json.loads(stream.recv(timeout=RECEIVE_TIMEOUT_S))["type"] == "ack"
            message = {"type": "tracks", "ref": "a", **track_list("radar-1", stamp(2.5))}
            stream.send(json.dumps(message))
            answer = json.loads(stream.recv(timeout=RECEIVE_TIMEOUT_S))
            assert answer["type"] == "result", answer
            assert answer["result"]["time"] == START + 2.5
            stream.send(json.dumps({**message, "ref": "b", "time": START + 3.0}))
            refused = json.loads(stream.recv(timeout=RECEIVE_TIMEOUT_S))
            assert refused["type"] == "error" and refused["problem"]["status"] == 422, refused
            assert refused["problem"]["errors"][0]["pointer"] == "#/time"
        events = client.get(f"/v1/sessions/{sid}/events", headers=headers).json()["events"]
        assert [event["report"]["time"] for event in events] == [stamp(2.5)]


def test_a_rebuilt_session_keeps_its_epoch() -> None:
    """From the log alone, and from a snapshot (``snapshot_every`` 2) plus the log."""

    async def scenario(snapshot_every: int) -> None:
        live = registry(snapshot_every=snapshot_every)
        new_session(live, CONFIG)
        target = await live.get("s1")
        for kind, body in scene([stamp(offset) for offset in OFFSETS[:3]]):
            await live.submit(target, parse_input(kind, body))
        live.discard("s1")
        rebuilt = await live.get("s1")
        assert rebuilt is not target and rebuilt.seq == 3
        assert rebuilt.time_epoch == "unix"
        late = parse_input("tracks", track_list("radar-1", START + 9.0))
        with pytest.raises(Exception, match="RFC 3339 timestamps"):
            await live.submit(rebuilt, late)

    for every in (2, 100):
        asyncio.run(scenario(every))
