"""Bounded work: the heaviest legal input of each route, with ``/healthz`` polled meanwhile.

Against a live server with reduced limits (the defaults' times are in
``bench/bounds.py``): each heaviest legal input is answered, the answer's size
stays within what the limits allow, one item more is refused before the work
(a small 422 naming the limit), and every ``/healthz`` polled during the work
is answered 200. No time is asserted.
"""

from __future__ import annotations

import json
import threading
from collections.abc import Callable, Iterator
from typing import Any, TypeVar

import httpx
import numpy as np
import pytest
from websockets.sync.client import connect

from core.belief.summary import MAX_FUSED_FOCAL_SETS
from tests.api.conftest import LiveServer, make_settings, serving

TRACKS = 100
FOCAL_SETS = 64
CLASSES = [f"c{index}" for index in range(20)]
PAIRS = 400
CLASS_PAIRS = 100
MAX_BODY = 1024 * 1024
T = TypeVar("T")
STATE = {"dim": 4, "position": [0, 2], "velocity": [1, 3]}


@pytest.fixture(scope="module")
def server() -> Iterator[LiveServer]:
    settings = make_settings(
        max_body_bytes=MAX_BODY,
        max_tracks_per_input=TRACKS,
        max_focal_sets=FOCAL_SETS,
        max_associate_pairs=PAIRS,
        max_associate_class_pairs=CLASS_PAIRS,
        rate_limit="none",
    )
    with serving(settings) as live:
        yield live


def tracks(count: int, evidence: str, seed: int) -> list[dict[str, Any]]:
    rng = np.random.default_rng(seed)
    result = []
    for index in range(count):
        track: dict[str, Any] = {
            "id": f"t{index}",
            "state": [300.0 * index, 5.0, 0.0, -2.0],
            "covariance": [[4, 0, 0, 0], [0, 1, 0, 0], [0, 0, 4, 0], [0, 0, 0, 1]],
        }
        if evidence == "likelihoods":
            track["classification"] = {
                "likelihoods": {c: float(rng.uniform(0.1, 0.9)) for c in CLASSES}
            }
        elif evidence == "mass":
            sets: list[list[str]] = []
            while len(sets) < FOCAL_SETS:
                members = [c for c in CLASSES if rng.random() < 0.5] or [CLASSES[0]]
                if members not in sets:
                    sets.append(members)
            masses = [{"set": members, "mass": 1.0 / FOCAL_SETS} for members in sets]
            track["classification"] = {"mass": masses}
        result.append(track)
    return result


def polled(url: str, work: Callable[[], T]) -> tuple[T, list[int]]:
    """``work()``'s answer and the statuses of ``/healthz`` polled while it ran."""
    statuses: list[int] = []
    done = threading.Event()

    def poll() -> None:
        with httpx.Client(base_url=url, timeout=60) as client:
            while True:  # at least one poll, however short the work
                statuses.append(client.get("/healthz").status_code)
                if done.is_set():
                    break

    poller = threading.Thread(target=poll)
    poller.start()
    try:
        answer = work()
    finally:
        done.set()
        poller.join()
    return answer, statuses


def session(url: str, sensors: int) -> tuple[str, dict[str, str]]:
    config = {
        "state": STATE,
        "classes": CLASSES,
        "sensors": [{"id": f"s{i}"} for i in range(sensors)],
    }
    created = httpx.post(f"{url}/v1/sessions", json=config).json()
    return created["id"], {"Authorization": f"Bearer {created['token']}"}


@pytest.mark.parametrize("evidence", ["none", "likelihoods", "mass"])
def test_the_heaviest_track_lists_from_two_sensors(server: LiveServer, evidence: str) -> None:
    sid, headers = session(server.url, 2)
    with httpx.Client(base_url=server.url, headers=headers, timeout=120) as client:
        for sensor, seed in (("s0", 1), ("s1", 2)):
            body = {"sensor": sensor, "time": 1.0, "tracks": tracks(TRACKS, evidence, seed)}
            assert len(json.dumps(body)) <= MAX_BODY
            answer, health = polled(
                server.url, lambda b=body: client.post(f"/v1/sessions/{sid}/tracks", json=b)
            )
            assert answer.status_code == 200, answer.text[:500]
            assert health and set(health) == {200}
        result = answer.json()
        assert len(result["tracks"]) <= 2 * TRACKS
        for track in result["tracks"]:
            classification = track["classification"]
            if evidence == "none":
                assert classification is None
                continue
            assert len(classification["mass"]) <= MAX_FUSED_FOCAL_SETS
            # two sensors' 32-focal-set masses combine to more than 32: summarized, and said so
            assert classification["summarized"] is (len(track["sources"]) == 2)
        picture, health = polled(server.url, lambda: client.get(f"/v1/sessions/{sid}/tracks"))
        assert picture.status_code == 200 and set(health) == {200}
        assert len(picture.content) <= 2 * len(answer.content)
        events, health = polled(server.url, lambda: client.get(f"/v1/sessions/{sid}/events"))
        assert events.status_code == 200 and set(health) == {200}
        assert [event["seq"] for event in events.json()["events"]] == [1, 2]


def test_one_track_more_is_refused_before_the_work(server: LiveServer) -> None:
    sid, headers = session(server.url, 1)
    body = {"sensor": "s0", "time": 1.0, "tracks": [{}] * (TRACKS + 1)}
    answer = httpx.post(f"{server.url}/v1/sessions/{sid}/tracks", json=body, headers=headers)
    assert answer.status_code == 422
    problem = answer.json()
    assert problem["limit"] == "max_tracks_per_input" and problem["actual"] == TRACKS + 1
    assert len(problem["errors"]) == 1 and len(answer.content) < 2048


def test_one_focal_set_more_is_refused(server: LiveServer) -> None:
    sid, headers = session(server.url, 1)
    body = {"sensor": "s0", "time": 1.0, "tracks": tracks(1, "mass", 3)}
    body["tracks"][0]["classification"]["mass"].append({"set": ["c0", "c1"], "mass": 0.0})
    answer = httpx.post(f"{server.url}/v1/sessions/{sid}/tracks", json=body, headers=headers)
    assert answer.status_code == 422 and answer.json()["limit"] == "max_focal_sets"
    assert answer.json()["errors"][0]["pointer"] == "#/tracks/0/classification/mass"


@pytest.mark.parametrize(
    ("evidence", "side", "limit"),
    [("none", 20, "max_associate_pairs"), ("likelihoods", 10, "max_associate_class_pairs")],
)
def test_the_heaviest_association_and_one_pair_more(
    server: LiveServer, evidence: str, side: int, limit: str
) -> None:
    body: dict[str, Any] = {
        "known": tracks(side, evidence, 4),
        "incoming": tracks(side, evidence, 5),
        "method": "mercier",
    }
    if evidence != "none":
        body["classes"] = CLASSES
    answer, health = polled(server.url, lambda: httpx.post(f"{server.url}/v1/associate", json=body))
    assert answer.status_code == 200, answer.text[:300]
    assert set(health) == {200}
    assert len(answer.json()["pairs"]) <= side
    body["incoming"] = tracks(side + 1, evidence, 5)
    refused = httpx.post(f"{server.url}/v1/associate", json=body)
    assert refused.status_code == 422 and refused.json()["limit"] == limit
    assert refused.json()["errors"][0]["pointer"] == "#/incoming"


def test_the_heaviest_session_config(server: LiveServer) -> None:
    polygon = [[500 + 400 * np.cos(a), 500 + 400 * np.sin(a)] for a in np.linspace(0, 6.2, 1000)]
    sensors = [{"id": f"s{i}", "fov": {"kind": "polygon", "vertices": polygon}} for i in range(3)]
    config = {"state": STATE, "classes": CLASSES, "sensors": sensors}
    answer, health = polled(
        server.url, lambda: httpx.post(f"{server.url}/v1/sessions", json=config, timeout=60)
    )
    assert answer.status_code == 201 and set(health) == {200}
    too_many = dict(config, sensors=[{"id": f"s{i}"} for i in range(65)])
    refused = httpx.post(f"{server.url}/v1/sessions", json=too_many)
    assert refused.status_code == 422 and refused.json()["limit"] == "max_sensors"


ORIGIN = {"lat": 43.6, "lon": 1.44, "alt": 150.0}


def test_the_heaviest_lists_in_the_geodetic_frame_and_over_websockets(server: LiveServer) -> None:
    """Geodetic answers and reads, GeoJSON, and a ``stream`` input with a geodetic
    subscriber open: every one answered whole, ``/healthz`` answered meanwhile."""
    config = {
        "state": STATE,
        "classes": CLASSES,
        "origin": ORIGIN,
        "sensors": [{"id": f"s{i}"} for i in range(3)],
    }
    created = httpx.post(f"{server.url}/v1/sessions", json=config).json()
    sid, auth = created["id"], {"Authorization": f"Bearer {created['token']}"}
    lists = [
        {"sensor": f"s{i}", "time": 1.0, "tracks": tracks(TRACKS, "likelihoods", seed=10 + i)}
        for i in range(3)
    ]
    with httpx.Client(base_url=server.url, headers=auth, timeout=120) as client:
        assert client.post(f"/v1/sessions/{sid}/tracks", json=lists[0]).status_code == 200
        answer, health = polled(
            server.url,
            lambda: client.post(
                f"/v1/sessions/{sid}/tracks", params={"frame": "geodetic"}, json=lists[1]
            ),
        )
        assert answer.status_code == 200 and set(health) == {200}
        assert answer.json()["tracks"] and all("geodetic" in t for t in answer.json()["tracks"])
        for params in ({"frame": "geodetic"}, {"format": "geojson"}):
            read, health = polled(
                server.url, lambda p=params: client.get(f"/v1/sessions/{sid}/tracks", params=p)
            )
            assert read.status_code == 200 and set(health) == {200}
            assert len(read.content) <= 2 * len(answer.content)
        features = client.get(f"/v1/sessions/{sid}/tracks", params={"format": "geojson"}).json()
        assert len(features["features"]) == len(
            client.get(f"/v1/sessions/{sid}/tracks").json()["tracks"]
        )

        ws = server.url.replace("http://", "ws://") + f"/v1/sessions/{sid}"
        headers = [("Authorization", auth["Authorization"])]

        def stream_with_a_subscriber() -> tuple[dict[str, Any], dict[str, Any]]:
            with (
                connect(f"{ws}/subscribe?frame=geodetic", additional_headers=headers) as sub,
                connect(f"{ws}/stream", additional_headers=headers) as stream,
            ):
                assert json.loads(sub.recv(timeout=30))["type"] == "ack"
                assert json.loads(stream.recv(timeout=30))["type"] == "ack"
                stream.send(json.dumps({"type": "tracks", "ref": "heavy", **lists[2]}))
                return json.loads(stream.recv(timeout=120)), json.loads(sub.recv(timeout=120))

        (answered, published), health = polled(server.url, stream_with_a_subscriber)
    assert set(health) == {200}
    assert answered["type"] == published["type"] == "result" and answered["ref"] == "heavy"
    mine, theirs = answered["result"], published["result"]
    assert theirs["seq"] == mine["seq"] == 3
    # the subscriber's copy is the same result with each track's geodetic position added
    assert all("geodetic" in track for track in theirs["tracks"])
    assert [{k: v for k, v in t.items() if k != "geodetic"} for t in theirs["tracks"]] == mine[
        "tracks"
    ]
