"""The front door (:mod:`app.http.front`) against a live uvicorn server: keyed tenants first,
refusals written once, ``/healthz`` answered before any other layer.

Clients without a key are address tenants (``CREDAL_ACCESS=open`` on loopback); a keyed
tenant's activity is made by its own requests. No assertion is on a time.
"""

from __future__ import annotations

import json
import re
import time
from collections.abc import Iterator
from typing import Any

import httpx
import pytest

from app.http import front
from app.http.requests import OFFLOAD_BYTES
from app.main import create_app
from tests.api.conftest import ADMIN_TOKEN, LiveServer, make_settings, serving

KEY = "alpha-key-0123456789abcdefghijklmnopqrstuvwxyz"
CONFIG: dict[str, Any] = {
    "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
    "sensors": [{"id": "s"}],
}


def tracks(count: int, time: float = 1.0) -> dict[str, Any]:
    """A track list of ``count`` tracks 300 m apart (small covariances: no two associate)."""
    covariance = [[4, 0, 0, 0], [0, 1, 0, 0], [0, 0, 4, 0], [0, 0, 0, 1]]
    return {
        "sensor": "s",
        "time": time,
        "tracks": [
            {"id": f"t{k}", "state": [300.0 * k, 1.0, 0.0, 1.0], "covariance": covariance}
            for k in range(count)
        ],
    }


LARGE = tracks(400)
SMALL = tracks(3)


def test_the_payloads_are_on_each_side_of_the_large_body_line() -> None:
    """What the door calls large is a body whose parsing is offloaded: > 32 KiB (and the
    test settings allow 64 KiB)."""
    assert OFFLOAD_BYTES == 32 * 1024
    compact: dict[str, Any] = {"separators": (",", ":")}  # as httpx writes it
    assert len(json.dumps(LARGE, **compact)) > 32 * 1024 > len(json.dumps(SMALL))
    assert len(json.dumps(LARGE, **compact)) < 64 * 1024


@pytest.fixture(scope="module")
def server() -> Iterator[LiveServer]:
    settings = make_settings(access="open", api_keys=f"alpha:{KEY}")
    with serving(settings) as live:
        yield live


def session(client: httpx.Client, key: str | None = None) -> tuple[str, dict[str, str]]:
    headers = {} if key is None else {"Authorization": f"Bearer {key}"}
    created = client.post("/v1/sessions", json=CONFIG, headers=headers)
    assert created.status_code == 201, created.text
    body = created.json()
    return f"/v1/sessions/{body['id']}", {"Authorization": f"Bearer {body['token']}"}


def keyed_working(client: httpx.Client) -> tuple[str, dict[str, str]]:
    """A keyed tenant's session, after one (small) input of it: the keyed tenant is served
    (its reads and the session's creation would not make it so)."""
    path, token = session(client, KEY)
    answer = client.post(f"{path}/tracks", json=SMALL, headers=token)
    assert answer.status_code == 200, answer.text
    return path, token


def refused_at_door(client: httpx.Client, limit: str) -> float:
    metrics = client.get("/metrics").text
    found = re.search(
        rf'^credal_requests_refused_at_door_total{{limit="{limit}"}} (\S+)$', metrics, re.M
    )
    return float(found.group(1)) if found else 0.0


def test_without_a_key_a_large_body_waits_while_keyed_tenants_are_served(
    server: LiveServer, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(front, "KEYED_GRACE_S", 3600.0)  # the keyed tenant stays "being served"
    with httpx.Client(base_url=server.url, timeout=30) as client:
        anonymous, anonymous_token = session(client)
        keyed, keyed_token = keyed_working(client)  # a keyed tenant's input: being served
        before = refused_at_door(client, "keyed_tenants_first")

        refused = client.post(f"{anonymous}/tracks", json=LARGE, headers=anonymous_token)
        assert refused.status_code == 503
        assert refused.headers["content-type"] == "application/problem+json"
        assert refused.headers["retry-after"] == "1"
        assert refused.headers["x-content-type-options"] == "nosniff"
        assert refused.headers["cache-control"] == "no-store"
        problem = refused.json()
        assert problem["type"] == "urn:credal-fusion:problem:overloaded"
        assert problem["status"] == 503
        assert problem["limit"] == "keyed_tenants_first"
        assert problem["retry_after"] == 1
        assert "API key" in problem["detail"]
        # nothing of it was applied; the connection stays usable
        assert client.get(f"{anonymous}/tracks", headers=anonymous_token).json()["tracks"] == []
        assert refused_at_door(client, "keyed_tenants_first") == before + 1

        # a small body without a key, and a large one with a key, go on
        small = client.post(f"{anonymous}/tracks", json=SMALL, headers=anonymous_token)
        assert small.status_code == 200, small.text
        assert len(small.json()["tracks"]) == 3
        large = client.post(f"{keyed}/tracks", json=tracks(400, 2.0), headers=keyed_token)
        assert large.status_code == 200, large.text
        assert len(large.json()["tracks"]) == 400
        # the operator's own session is no anonymous client's
        operated, operated_token = session(client, ADMIN_TOKEN)
        large = client.post(f"{operated}/tracks", json=LARGE, headers=operated_token)
        assert large.status_code == 200, large.text
        assert refused_at_door(client, "keyed_tenants_first") == before + 1


def test_without_keyed_tenants_served_a_large_body_is_taken(
    server: LiveServer, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(front, "KEYED_GRACE_S", 0.0)  # no keyed request is in flight now
    with httpx.Client(base_url=server.url, timeout=30) as client:
        anonymous, anonymous_token = session(client)
        taken = client.post(f"{anonymous}/tracks", json=LARGE, headers=anonymous_token)
        assert taken.status_code == 200, taken.text
        assert len(taken.json()["tracks"]) == 400


def test_healthz_is_answered_at_the_door_with_the_routes_document(server: LiveServer) -> None:
    with httpx.Client(base_url=server.url, timeout=30) as client:
        answer = client.get("/healthz")
        assert answer.status_code == 200
        assert answer.headers["content-type"] == "application/json"
        assert answer.headers["x-content-type-options"] == "nosniff"
        document = answer.json()
        assert document["status"] == "ok"
        schema = client.get("/openapi.json").json()["components"]["schemas"]["Health"]
        assert set(document) <= set(schema["properties"])
        assert set(schema.get("required", [])) <= set(document)


def test_a_rate_refusal_is_written_once_and_answered_the_same_everywhere() -> None:
    """Two refused requests of the address on two paths: the same document (no ``instance``:
    written once per server), the paths' own ``Cache-Control``."""
    with (
        serving(make_settings(rate_limit="2/minute")) as live,
        httpx.Client(base_url=live.url, timeout=30) as client,
    ):
        assert client.get("/readyz").status_code == 200
        assert client.get("/readyz").status_code == 200
        first = client.get("/v1/sessions/nothing")
        second = client.get("/metrics")
        assert first.status_code == second.status_code == 429
        same = ("type", "title", "status", "limit", "rate")
        assert {key: first.json()[key] for key in same} == {key: second.json()[key] for key in same}
        assert first.json()["limit"] == "rate_limit"
        assert first.json()["rate"] == "2 per 1 minute"
        assert "instance" not in first.json()
        assert first.headers["cache-control"] == "no-store"
        assert "cache-control" not in second.headers
        assert int(first.headers["retry-after"]) == first.json()["retry_after"]


def test_a_refusal_to_an_allowed_browser_origin_carries_its_cors_headers() -> None:
    """The door runs before the CORS middleware: its answers say what that middleware would."""
    settings = make_settings(rate_limit="1/minute", cors_origins="https://ops.example")
    with (
        serving(settings) as live,
        httpx.Client(base_url=live.url, timeout=30) as client,
    ):
        assert client.get("/readyz").status_code == 200
        allowed = client.get("/readyz", headers={"Origin": "https://ops.example"})
        other = client.get("/readyz", headers={"Origin": "https://evil.example"})
        assert allowed.status_code == other.status_code == 429
        assert allowed.headers["access-control-allow-origin"] == "https://ops.example"
        assert "access-control-allow-origin" not in other.headers
        health = client.get("/healthz", headers={"Origin": "https://ops.example"})
        assert health.status_code == 200
        assert health.headers["access-control-allow-origin"] == "https://ops.example"


def test_a_large_body_sent_again_before_retry_after_waits_it_out(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The address's previous keyed-first refusal said ``Retry-After`` (set here to end 2 s
    from now): the next one is held until then, counted, and is the same 503."""
    monkeypatch.setattr(front, "KEYED_GRACE_S", 3600.0)
    application = create_app(make_settings(access="open", api_keys=f"alpha:{KEY}"))
    with (
        serving(application.state.settings, application) as live,
        httpx.Client(base_url=live.url, timeout=30) as client,
    ):
        anonymous, anonymous_token = session(client)
        keyed_working(client)
        door = application.middleware_stack
        assert isinstance(door, front.FrontDoor)
        door.waiting_until["address:127.0.0.1"] = time.monotonic() + 2.0
        assert held_at_door(client) == 0.0
        held = client.post(f"{anonymous}/tracks", json=LARGE, headers=anonymous_token)
        assert held.status_code == 503
        assert held.json()["limit"] == "keyed_tenants_first"
        assert held_at_door(client) == 1.0
        assert refused_at_door(client, "keyed_tenants_first") == 1.0


def held_at_door(client: httpx.Client) -> float:
    found = re.search(
        r"^credal_requests_held_at_door_total (\S+)$", client.get("/metrics").text, re.M
    )
    return float(found.group(1)) if found else 0.0


def test_without_open_access_a_request_without_a_valid_token_is_not_told_to_wait(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """With ``CREDAL_ACCESS=keys`` an address tenant is a request whose token is missing or
    unknown (a typo, an ended session's): the application refuses it (401 without a token,
    404 for a session the token does not open, as when no keyed tenant is served), never the
    door's 503 ``keyed_tenants_first`` with ``Retry-After``, which would have the client retry
    for ever and tell it a keyed tenant is active."""
    monkeypatch.setattr(front, "KEYED_GRACE_S", 3600.0)  # the keyed tenant stays "being served"
    settings = make_settings(access="keys", api_keys=f"alpha:{KEY}")
    with serving(settings) as live, httpx.Client(base_url=live.url, timeout=30) as client:
        keyed, _ = session(client, KEY)
        wrong = {"Authorization": "Bearer not-a-token-of-this-service-0123456789"}
        unknown = client.post(f"{keyed}/tracks", json=LARGE, headers=wrong)
        assert unknown.status_code == 404, unknown.text
        assert unknown.json()["type"] == "urn:credal-fusion:problem:session-not-found"
        missing = client.post(f"{keyed}/tracks", json=LARGE)
        assert missing.status_code == 401, missing.text
        assert "retry-after" not in missing.headers


def test_with_cors_an_options_request_that_is_no_preflight_is_rate_limited() -> None:
    """Only a browser's preflight (``Origin`` and ``Access-Control-Request-Method``) is CORS's
    alone; any other ``OPTIONS`` request counts against the rate limit as on main, where the
    limit ran behind the CORS middleware (2 per minute here: the third is refused)."""
    settings = make_settings(access="open", rate_limit="2/minute", cors_origins="https://a.test")
    with serving(settings) as live, httpx.Client(base_url=live.url, timeout=30) as client:
        statuses = [client.options("/v1/sessions").status_code for _ in range(3)]
        assert statuses[:2] != [429, 429] and statuses[2] == 429, statuses
        preflight = {
            "Origin": "https://a.test",
            "Access-Control-Request-Method": "POST",
        }
        answered = client.options("/v1/sessions", headers=preflight)
        assert answered.status_code == 200, answered.text
        assert answered.headers["access-control-allow-origin"] == "https://a.test"


def test_without_a_key_a_large_stream_message_waits_as_a_large_body_does(
    server: LiveServer, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The ``stream`` WebSocket is no way around keyed tenants first: a message over 32 KiB
    of a client without a key is answered the door's refusal before it is parsed (nothing
    applied, the connection kept), a small one is applied; with no keyed tenant served the
    large one is taken."""
    from websockets.sync.client import connect

    monkeypatch.setattr(front, "KEYED_GRACE_S", 3600.0)  # the keyed tenant stays "being served"
    with httpx.Client(base_url=server.url, timeout=30) as client:
        anonymous, token = session(client)
        keyed_working(client)
        url = server.url.replace("http://", "ws://") + f"{anonymous}/stream"
        with connect(url, additional_headers=token, max_size=None) as ws:
            assert json.loads(ws.recv(timeout=10))["type"] == "ack"
            ws.send(json.dumps({"type": "tracks", "ref": "large", **LARGE}))
            refused = json.loads(ws.recv(timeout=30))
            assert refused["type"] == "error", refused
            assert refused["problem"]["status"] == 503
            assert refused["problem"]["limit"] == "keyed_tenants_first"
            ws.send(json.dumps({"type": "tracks", "ref": "small", **SMALL}))
            small = json.loads(ws.recv(timeout=30))
            assert small["type"] == "result" and small["ref"] == "small"
            assert len(small["result"]["tracks"]) == 3  # the large one was not applied
            monkeypatch.setattr(front, "KEYED_GRACE_S", 0.0)
            ws.send(json.dumps({"type": "tracks", "ref": "later", **tracks(400, time=2.0)}))
            taken = json.loads(ws.recv(timeout=30))
            assert taken["type"] == "result" and taken["ref"] == "later", taken


def test_a_keyed_session_not_held_in_memory_is_still_keyed(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A keyed tenant's session the registry no longer holds (evicted after a failed write,
    held by another instance, not yet restored) is its tenant's all the same: its token is
    read against the stored record, and its large body is taken while other keyed tenants
    are served. A token that opens no session stays an address's and waits."""
    monkeypatch.setattr(front, "KEYED_GRACE_S", 3600.0)  # the keyed tenants stay "being served"
    settings = make_settings(access="open", api_keys=f"alpha:{KEY}")
    app = create_app(settings)
    with serving(settings, app) as live, httpx.Client(base_url=live.url, timeout=30) as client:
        keyed_working(client)  # another keyed session's input: keyed tenants are served
        keyed, keyed_token = session(client, KEY)
        anonymous, anonymous_token = session(client)
        for path in (keyed, anonymous):
            app.state.registry.discard(path.rsplit("/", 1)[1])  # in the store only
        taken = client.post(f"{keyed}/tracks", json=LARGE, headers=keyed_token)
        assert taken.status_code == 200, taken.text
        assert len(taken.json()["tracks"]) == 400
        refused = client.post(f"{anonymous}/tracks", json=LARGE, headers=anonymous_token)
        assert refused.status_code == 503 and refused.json()["limit"] == "keyed_tenants_first"
        wrong = {"Authorization": "Bearer not-this-session-token-0123456789abcdef"}
        refused = client.post(f"{keyed}/tracks", json=LARGE, headers=wrong)
        assert refused.status_code == 503 and refused.json()["limit"] == "keyed_tenants_first"


def test_the_door_remembers_at_most_max_waiting_addresses(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The held refusals' memory is bounded whatever the crowd (every entry live here: a
    Retry-After of an hour), the oldest forgotten first: a crowd of more addresses than the
    bound (an IPv6 /48 holds 65 536 /64 tenants) made the door walk every live entry at each
    refusal (0.6 -> 120-180 µs per refusal beyond 4 096 live addresses) and keep them all."""
    import asyncio

    monkeypatch.setattr(front, "MAX_WAITING_ADDRESSES", 4)
    monkeypatch.setattr(front.KeyedFirst, "retry_after_s", 3600)
    door = front.FrontDoor(create_app(make_settings()), [], 1, 1)

    async def refuse_each() -> None:
        for k in range(6):
            await door._wait_your_turn(f"address:10.0.0.{k}")

    asyncio.run(refuse_each())
    assert list(door.waiting_until) == [f"address:10.0.0.{k}" for k in (2, 3, 4, 5)]


def test_a_keyed_tenants_reads_hold_no_anonymous_input_back(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Only a keyed tenant's work counts as its being served: a keyed dashboard polling its
    session (reads, however often; its session's creation too) leaves an anonymous client's
    large body taken; one keyed input, and the same body waits (503 keyed_tenants_first).
    The grace is an hour here: on main the polls alone kept every large anonymous body
    refused for as long as they came less than a second apart."""
    monkeypatch.setattr(front, "KEYED_GRACE_S", 3600.0)
    settings = make_settings(access="open", api_keys=f"alpha:{KEY}")
    with serving(settings) as live, httpx.Client(base_url=live.url, timeout=30) as client:
        keyed, keyed_token = session(client, KEY)
        anonymous, anonymous_token = session(client)
        for _ in range(3):  # the dashboard
            for read in (f"{keyed}/tracks", f"{keyed}/events", keyed):
                assert client.get(read, headers=keyed_token).status_code == 200
        taken = client.post(f"{anonymous}/tracks", json=LARGE, headers=anonymous_token)
        assert taken.status_code == 200, taken.text
        assert len(taken.json()["tracks"]) == 400

        work = client.post(f"{keyed}/tracks", json=SMALL, headers=keyed_token)
        assert work.status_code == 200, work.text
        refused = client.post(f"{anonymous}/tracks", json=tracks(400, 2.0), headers=anonymous_token)
        assert refused.status_code == 503, refused.text
        assert refused.json()["limit"] == "keyed_tenants_first"


@pytest.mark.parametrize(
    ("method", "path", "work"),
    [
        ("POST", "/v1/sessions/abc/tracks", True),
        ("POST", "/v1/sessions/abc/detections", True),
        ("POST", "/v1/sessions/abc/asterix", True),
        ("POST", "/v1/associate", True),
        ("POST", "/v1/sessions", False),  # a session's creation
        ("GET", "/v1/sessions/abc/tracks", False),
        ("GET", "/v1/sessions/abc/events", False),
        ("DELETE", "/v1/sessions/abc", False),
        ("GET", "/metrics", False),
    ],
)
def test_what_counts_as_a_keyed_tenants_work(method: str, path: str, work: bool) -> None:
    """Every ``POST`` of openapi.json but the session's creation is work (listed by hand)."""
    assert front.is_work(method, path) is work


def test_a_keyed_tenants_stream_input_is_work_as_its_rest_input_is(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A keyed sensor sending its scans over the ``stream`` WebSocket is served as one posting
    them: once its input is answered, an anonymous large body waits for
    :data:`~app.http.front.KEYED_GRACE_S` (its next scan is on its way), as after a REST
    input (:func:`test_a_keyed_tenants_reads_hold_no_anonymous_input_back`). Before, only
    the WebSocket input's time in the pipeline counted: between a keyed stream's scans every
    anonymous large body was taken."""
    from websockets.sync.client import connect

    monkeypatch.setattr(front, "KEYED_GRACE_S", 3600.0)
    settings = make_settings(access="open", api_keys=f"alpha:{KEY}")
    with serving(settings) as live, httpx.Client(base_url=live.url, timeout=30) as client:
        keyed, keyed_token = session(client, KEY)
        anonymous, anonymous_token = session(client)
        url = live.url.replace("http://", "ws://") + f"{keyed}/stream"
        with connect(url, additional_headers=keyed_token) as ws:
            assert json.loads(ws.recv(timeout=10))["type"] == "ack"
            ws.send(json.dumps({"type": "tracks", "ref": "scan", **SMALL}))
            answered = json.loads(ws.recv(timeout=30))
            assert answered["type"] == "result" and answered["ref"] == "scan", answered
        refused = client.post(f"{anonymous}/tracks", json=LARGE, headers=anonymous_token)
        assert refused.status_code == 503, refused.text[:200]
        assert refused.json()["limit"] == "keyed_tenants_first"
