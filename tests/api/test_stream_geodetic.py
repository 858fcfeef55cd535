"""Over a real WebSocket: ``?frame=geodetic`` (and ``?format=geojson``) on ``stream`` and
``subscribe``.

A polar radar at a geodetic site streams its detections; every fused track of
every ``result`` sent on a ``?frame=geodetic`` connection carries its WGS84
position, checked against PROJ and pymap3d from the track's session-frame
state. A connection without the parameter gets none; a session without an
origin, or another frame, refuses the upgrade with the 422 naming
``query/frame``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from typing import Any

import httpx
import numpy as np
import pymap3d
import pytest
from websockets.sync.client import ClientConnection, connect

from api_schemas.ws import server_message_adapter

from .conftest import LiveServer, make_settings, serving
from .proj_oracle import proj_enu
from .redis_support import REDIS_URL, redis_prefix

ORIGIN = {"lat": 43.6, "lon": 1.44, "alt": 150.0}
CONFIG = {
    "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
    "origin": ORIGIN,
    "motion": {"model": "constant_velocity", "q": 1.0},
    "sensors": [
        {
            "id": "radar",
            "site": {"lat": 43.55, "lon": 1.40, "alt": 160.0},
            "measurement": {"kind": "polar", "sigma_range": 20.0, "sigma_azimuth_deg": 0.2},
        }
    ],
    "tracking": {"thresholds": {"min_points": 3}},
}
TIMEOUT_S = 30.0


def _url(server: LiveServer, sid: str, channel: str, query: str = "") -> str:
    return server.url.replace("http://", "ws://") + f"/v1/sessions/{sid}/{channel}{query}"


def _receive(connection: ClientConnection) -> dict[str, Any]:
    message = json.loads(connection.recv(timeout=TIMEOUT_S))
    server_message_adapter.validate_python(message)
    assert isinstance(message, dict)
    return message


def _create(client: httpx.Client, config: dict[str, Any]) -> tuple[str, dict[str, str]]:
    created = client.post("/v1/sessions", json=config)
    assert created.status_code == 201, created.text
    return created.json()["id"], {"Authorization": f"Bearer {created.json()['token']}"}


def _check_geodetic(tracks: list[dict[str, Any]]) -> None:
    oracle = proj_enu((ORIGIN["lat"], ORIGIN["lon"], ORIGIN["alt"]))
    for track in tracks:
        east, north = track["state"][0], track["state"][2]
        lat, lon, alt = oracle.transform(east, north, 0.0, direction="INVERSE")
        other = pymap3d.enu2geodetic(east, north, 0.0, ORIGIN["lat"], ORIGIN["lon"], ORIGIN["alt"])
        geodetic = track["geodetic"]
        np.testing.assert_allclose([geodetic["lat"], geodetic["lon"]], [lat, lon], atol=1e-9)
        np.testing.assert_allclose([geodetic["lat"], geodetic["lon"]], other[:2], atol=1e-9)
        assert math.isclose(geodetic["alt"], alt, abs_tol=1e-3)
        assert math.isclose(geodetic["alt"], other[2], abs_tol=1e-3)


@pytest.fixture(params=["memory", "redis"])
def store_server(request: pytest.FixtureRequest) -> Iterator[LiveServer]:
    """A live server on the memory store (a geodetic subscriber's text is written beside the
    step) and on Redis (subscribers are fed through Redis: the text is converted)."""
    if request.param == "memory":
        with serving(make_settings()) as server:
            yield server
        return
    with (
        redis_prefix("geodetic") as prefix,
        serving(make_settings(store=REDIS_URL, redis_prefix=prefix)) as server,
    ):
        yield server


def test_stream_and_subscribe_answer_in_geodetic(store_server: LiveServer) -> None:
    live_server = store_server
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        sid, headers = _create(client, CONFIG)
    with (
        connect(
            _url(live_server, sid, "subscribe", "?frame=geodetic"), additional_headers=headers
        ) as geodetic_subscriber,
        connect(_url(live_server, sid, "subscribe"), additional_headers=headers) as plain,
        connect(
            _url(live_server, sid, "subscribe", "?format=geojson"), additional_headers=headers
        ) as features,
        connect(
            _url(live_server, sid, "stream", "?frame=geodetic"), additional_headers=headers
        ) as stream,
    ):
        for connection in (geodetic_subscriber, plain, features, stream):
            assert _receive(connection)["type"] == "ack"
        answers = []
        for scan in range(6):
            detection = {"range": 12_000.0 + 100.0 * scan, "azimuth_deg": 45.0}
            body = {"type": "detections", "ref": f"s{scan}", "sensor": "radar", "time": scan}
            stream.send(json.dumps(body | {"detections": [detection]}))
            answers.append(_receive(stream))
        subscribed = [_receive(geodetic_subscriber) for _ in answers]
        unconverted = [_receive(plain) for _ in answers]
        collections = [_receive(features)["result"] for _ in answers]
    assert [answer["ref"] for answer in answers] == [f"s{scan}" for scan in range(6)]
    assert answers[-1]["result"]["tracks"], answers[-1]  # the radar's target is fused
    for answer, collection in zip(answers, collections, strict=True):
        assert collection["type"] == "FeatureCollection"
        assert collection["seq"] == answer["result"]["seq"]
        points = [(f["id"], f["geometry"]["coordinates"]) for f in collection["features"]]
        tracks = answer["result"]["tracks"]
        assert [track_id for track_id, _ in points] == [track["id"] for track in tracks]
        for (_, (lon, lat, alt)), track in zip(points, tracks, strict=True):
            assert [lat, lon, alt] == [track["geodetic"][key] for key in ("lat", "lon", "alt")]
    for answer, received, bare in zip(answers, subscribed, unconverted, strict=True):
        assert answer["type"] == received["type"] == bare["type"] == "result"
        _check_geodetic(answer["result"]["tracks"])
        _check_geodetic(received["result"]["tracks"])
        assert received["result"] == answer["result"]
        assert all("geodetic" not in track for track in bare["result"]["tracks"])
        assert [t["state"] for t in bare["result"]["tracks"]] == [
            t["state"] for t in answer["result"]["tracks"]
        ]


@pytest.mark.parametrize(
    ("origin", "query"),
    [(False, "?frame=geodetic"), (True, "?frame=ecef")],
    ids=["no-origin", "unknown-frame"],
)
@pytest.mark.parametrize("channel", ["stream", "subscribe"])
def test_a_frame_the_session_cannot_give_refuses_the_upgrade(
    live_server: LiveServer, channel: str, origin: bool, query: str
) -> None:
    config = CONFIG if origin else {"state": CONFIG["state"]}
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        sid, headers = _create(client, config)
    try:
        with connect(_url(live_server, sid, channel, query), additional_headers=headers):
            raise AssertionError("the upgrade should have been refused")
    except Exception as refused:  # websockets.InvalidStatus
        response = getattr(refused, "response", None)
        assert response is not None and response.status_code == 422
        problem = json.loads(response.body)
        assert problem["status"] == 422
        assert any("frame" in str(error) for error in problem["errors"]), problem
