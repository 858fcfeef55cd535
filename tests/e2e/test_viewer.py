"""The live viewer in a real browser: headless Chromium on a live uvicorn server.

The session is fed over REST while the page is open; every check reads the
page itself (its ``window.__viewer.state()`` hook, the DOM, the mouse) and
compares it with the server's REST answers and with values worked out here:
screen offsets from the tracks' positions, ellipse sizes from numpy's
eigenvalues, the tie of a target whose evidence is symmetric in two classes.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest
from playwright.sync_api import Page
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from tests.api.conftest import LiveServer
from tests.api.proj_oracle import proj_enu
from tests.api.scenario import reports, session_config, truth
from tests.e2e.browser import BrowserPage, viewer_state, wait_for_seq

RECEIVE_TIMEOUT_S = 20.0
STEPS_BEFORE = 6  # fed before the page opens: its trails start from the tracks' history
STEPS_AFTER = 6  # fed while the page is open
STEPS_AFTER_RECONNECT = 2
MIN_SEMI_AXIS_PX = 4  # the page's floor for a 2-σ ellipse on screen
SECTOR = {
    "kind": "sector",
    "origin": [-1000.0, -1500.0],
    "heading_deg": 45.0,
    "half_angle_deg": 60.0,
    "range": [0.0, 10_000.0],
}
SEEDED_TRAILS = "() => Object.values(window.__viewer.state().trails).every(length => length >= 2)"
POLYGON = {"kind": "polygon", "vertices": [[-500.0, 0.0], [5000.0, 0.0], [5000.0, 2000.0]]}


def viewer_config() -> dict[str, Any]:
    """The scenario's two radars, each with a field of view that the page draws."""
    config = session_config()
    for sensor, fov in zip(config["sensors"], (SECTOR, POLYGON), strict=True):
        sensor["fov"] = fov
    return config


def wait_for_connection(page: Page, connection: str) -> None:
    """Wait until the page says its connection is ``connection`` (live, refused, ended, ...)."""
    page.wait_for_function("c => window.__viewer.state().connection === c", arg=connection)


def post(client: httpx.Client, sid: str, headers: dict[str, str], bodies: list[Any]) -> None:
    for body in bodies:
        answer = client.post(f"/v1/sessions/{sid}/tracks", json=body, headers=headers)
        assert answer.status_code == 200, answer.text


def nearest_track(picture: dict[str, Any], target: int) -> dict[str, Any]:
    """The fused track closest to ``target``'s true position at the picture's time."""
    x, _, y, _ = truth(target, picture["time"])
    tracks: list[dict[str, Any]] = picture["tracks"]
    return min(tracks, key=lambda t: math.hypot(t["state"][0] - x, t["state"][2] - y))


def test_the_viewer_draws_a_live_session(
    live_server: LiveServer, browser_page: BrowserPage, tmp_path: Path
) -> None:
    page, log = browser_page.page, browser_page.log
    bodies = reports(STEPS_BEFORE + STEPS_AFTER + STEPS_AFTER_RECONNECT)
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        created = client.post("/v1/sessions", json=viewer_config()).json()
        sid, token = created["id"], created["token"]
        headers = {"Authorization": f"Bearer {token}"}
        post(client, sid, headers, bodies[:STEPS_BEFORE])

        page.goto(f"{live_server.url}/#session={sid}&token={token}")
        wait_for_seq(page, STEPS_BEFORE)
        page.wait_for_function(SEEDED_TRAILS)  # the page asks for each track's history
        opened = viewer_state(page)
        assert opened["connection"] == "live"
        assert len(opened["trails"]) == len(opened["drawn"]) > 0
        assert opened["axes"]["x"]["title"].startswith("x (")  # no origin: metres
        page.screenshot(path=tmp_path / "viewer-overview.png")

        # zoom in on one track with the wheel: new results must not re-zoom the view
        canvas = page.locator("#plot").bounding_box()
        assert canvas is not None
        early = client.get(f"/v1/sessions/{sid}/tracks", headers=headers).json()
        mark = next(m for m in opened["drawn"] if m["id"] == nearest_track(early, 1)["id"])
        page.mouse.move(canvas["x"] + mark["x"], canvas["y"] + mark["y"])
        for _ in range(3):
            page.mouse.wheel(0, -600)
        page.wait_for_function(
            "limit => window.__viewer.state().metresPerPixel < limit",
            arg=opened["metresPerPixel"] / 10,
        )
        zoomed = viewer_state(page)["metresPerPixel"]

        post(client, sid, headers, bodies[STEPS_BEFORE : STEPS_BEFORE + STEPS_AFTER])
        server_seq = client.get(f"/v1/sessions/{sid}", headers=headers).json()["seq"]
        assert server_seq == STEPS_BEFORE + STEPS_AFTER
        shown = wait_for_seq(page, server_seq)
        picture = client.get(f"/v1/sessions/{sid}/tracks", headers=headers).json()
        assert picture["seq"] == server_seq
        assert shown["connection"] == "live" and shown["status"] == "live"
        assert shown["metresPerPixel"] == zoomed

        # the tracks drawn are the server's, where their positions put them
        drawn = {mark["id"]: mark for mark in shown["drawn"]}
        tracks = {track["id"]: track for track in picture["tracks"]}
        assert len(shown["drawn"]) == len(picture["tracks"]) > 0
        assert set(drawn) == set(tracks)
        first = picture["tracks"][0]
        for track_id, track in tracks.items():
            dx = (track["state"][0] - first["state"][0]) / zoomed
            dy = (track["state"][2] - first["state"][2]) / zoomed
            assert drawn[track_id]["x"] - drawn[first["id"]]["x"] == pytest.approx(dx, abs=0.01)
            assert drawn[track_id]["y"] - drawn[first["id"]]["y"] == pytest.approx(-dy, abs=0.01)
            position = np.array(track["covariance"])[np.ix_([0, 2], [0, 2])]
            semi_axes = 2 * np.sqrt(np.linalg.eigvalsh(position)) / zoomed  # 2-σ, in pixels
            assert drawn[track_id]["rx"] == pytest.approx(max(semi_axes[1], MIN_SEMI_AXIS_PX))
            assert drawn[track_id]["ry"] == pytest.approx(max(semi_axes[0], MIN_SEMI_AXIS_PX))
        assert all(length >= 2 for length in shown["trails"].values())

        # target 0's evidence is symmetric in bomber and fighter: a tie, drawn as undecided;
        # target 1's is mostly liner
        tied = drawn[nearest_track(picture, 0)["id"]]["label"]
        assert tied.startswith("undecided") and "bomber" in tied and "fighter" in tied
        liner = nearest_track(picture, 1)
        assert drawn[liner["id"]]["label"].startswith("liner ")

        # a click on a track shows its details
        page.mouse.click(
            canvas["x"] + drawn[liner["id"]]["x"], canvas["y"] + drawn[liner["id"]]["y"]
        )
        page.wait_for_function("id => window.__viewer.state().selected === id", arg=liner["id"])
        details = page.locator("#details").inner_text()
        assert f"track {liner['id']}" in details and "liner" in details and "conflict" in details
        for source in liner["sources"]:
            assert source["sensor"] in details and source["track"] in details
        page.screenshot(path=tmp_path / "viewer-zoomed.png")

        # a drag pans the picture by as many pixels; the trail length is the user's to set
        before = {mark["id"]: mark for mark in viewer_state(page)["drawn"]}
        start = (canvas["x"] + 300, canvas["y"] + 600)
        page.mouse.move(*start)
        page.mouse.down()
        page.mouse.move(start[0] + 120, start[1] - 40, steps=5)
        page.mouse.up()
        for mark in viewer_state(page)["drawn"]:
            assert mark["x"] - before[mark["id"]]["x"] == pytest.approx(120, abs=0.01)
            assert mark["y"] - before[mark["id"]]["y"] == pytest.approx(-40, abs=0.01)
        page.fill("#trail", "3")
        page.dispatch_event("#trail", "change")
        assert set(viewer_state(page)["trails"].values()) == {3}

        # a dropped connection comes back by itself and the page catches up
        page.evaluate("link.socket.close(4001, 'test drops the connection')")
        post(client, sid, headers, bodies[STEPS_BEFORE + STEPS_AFTER :])
        caught_up = wait_for_seq(page, server_seq + STEPS_AFTER_RECONNECT)
        wait_for_connection(page, "live")
        assert caught_up["seq"] == server_seq + STEPS_AFTER_RECONNECT
        subscriptions = [url for url in log.requests if url.startswith("ws://")]
        assert len(subscriptions) == 2  # the first one and the reconnection

        # the fragment lost its token once read; the tab keeps it: a reload needs no retyping
        assert token not in page.url and page.url.endswith(f"#session={sid}")
        assert page.evaluate(f"sessionStorage.getItem('credal-fusion.token.{sid}')") == token
        page.reload()
        wait_for_seq(page, server_seq + STEPS_AFTER_RECONNECT)
        wait_for_connection(page, "live")

        assert not log.console_errors, log.console_errors
        assert not log.failures, log.failures
        local = (live_server.url, live_server.url.replace("http://", "ws://"))
        assert log.requests and all(url.startswith(local) for url in log.requests), log.requests
        assert not [url for url in log.requests if token in url]

        # a wrong token is refused and not retried; the tab's token stays the good one
        page.evaluate(f"location.hash = 'session={sid}&token=not-the-token'")
        wait_for_connection(page, "refused")
        assert "404" in viewer_state(page)["status"]  # as for an unknown session
        assert page.evaluate(f"sessionStorage.getItem('credal-fusion.token.{sid}')") == token

        # the session's end is shown as such
        page.evaluate(f"location.hash = 'session={sid}&token={token}'")
        wait_for_connection(page, "live")
        assert client.delete(f"/v1/sessions/{sid}", headers=headers).status_code == 204
        wait_for_connection(page, "ended")
        assert "session ended" in viewer_state(page)["status"]


def test_the_viewer_labels_a_geodetic_session_in_degrees(
    live_server: LiveServer, browser_page: BrowserPage, tmp_path: Path
) -> None:
    """With an origin the ticks are degrees (PROJ's at their screen positions, to the label's
    last digit) and a selected track's details show its lat/lon/alt (PROJ's)."""
    page, log = browser_page.page, browser_page.log
    origin = {"lat": 48.85, "lon": 2.35, "alt": 100.0}
    config = {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "origin": origin,
        "sensors": [{"id": "s"}],
    }
    covariance = np.diag([400.0, 1.0, 400.0, 1.0]).tolist()
    states = [[12_000.0, 5.0, -7_000.0, 0.0], [-3_000.0, 0.0, 4_000.0, 5.0]]
    report = {
        "sensor": "s",
        "time": 1.0,
        "tracks": [
            {"id": f"t{n}", "state": state, "covariance": covariance}
            for n, state in enumerate(states)
        ],
    }
    oracle = proj_enu((origin["lat"], origin["lon"], origin["alt"]))
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        created = client.post("/v1/sessions", json=config).json()
        sid, token = created["id"], created["token"]
        headers = {"Authorization": f"Bearer {token}"}
        post(client, sid, headers, [report])
        picture = client.get(f"/v1/sessions/{sid}/tracks", headers=headers).json()
        page.goto(f"{live_server.url}/#session={sid}&token={token}")
        shown = wait_for_seq(page, 1)
        page.screenshot(path=tmp_path / "viewer-geodetic.png")

    axes, mpp = shown["axes"], shown["metresPerPixel"]
    assert "longitude" in axes["x"]["title"] and "latitude" in axes["y"]["title"]
    anchor = picture["tracks"][0]
    mark = next(m for m in shown["drawn"] if m["id"] == anchor["id"])
    for axis, ticks in (("x", axes["x"]["ticks"]), ("y", axes["y"]["ticks"])):
        assert len(ticks) >= 3
        for tick in ticks:
            assert tick["label"].endswith("°")
            text = tick["label"][:-1]
            precision = 10.0 ** -(len(text.split(".")[1]) if "." in text else 0)
            if axis == "x":  # the tick's east offset, from the track's screen position
                east = anchor["state"][0] + (tick["px"] - mark["x"]) * mpp
                _, expected, _ = oracle.transform(east, 0.0, 0.0, direction="INVERSE")
            else:
                north = anchor["state"][2] - (tick["px"] - mark["y"]) * mpp
                expected, _, _ = oracle.transform(0.0, north, 0.0, direction="INVERSE")
            assert float(text) == pytest.approx(expected, abs=precision / 2), (axis, tick)
            # the page's tangent plane is good to well under a pixel here (~20 m)
            assert float(text) == pytest.approx(expected, abs=1e-4), (axis, tick)
    # the ticks span the two tracks' ~0.2° of longitude
    lons = [float(t["label"][:-1]) for t in axes["x"]["ticks"]]
    assert max(lons) - min(lons) >= 0.15

    page.evaluate("id => window.__viewer.select(id)", anchor["id"])
    details = page.locator("#geodetic").inner_text()
    lat, lon, alt = oracle.transform(
        anchor["state"][0], anchor["state"][2], 0.0, direction="INVERSE"
    )
    shown_lat, shown_lon, shown_alt = (
        float(part.split()[1].rstrip("°m")) for part in details.split(" · ")
    )
    assert shown_lat == pytest.approx(lat, abs=1e-6)
    assert shown_lon == pytest.approx(lon, abs=1e-6)
    assert shown_alt == pytest.approx(alt, abs=0.1)
    assert alt > origin["alt"] + 10.0  # the tangent plane rises above the ellipsoid: ~15 m
    page.screenshot(path=tmp_path / "viewer-geodetic-details.png")
    assert not log.console_errors, log.console_errors
    assert not log.failures, log.failures


def test_the_viewer_draws_a_field_of_view_given_relative_to_a_geodetic_site(
    live_server: LiveServer, browser_page: BrowserPage
) -> None:
    """A radar's sector in its own frame (site lat/lon, heading 30°) is drawn where PROJ puts
    the site, turned by the heading: apex, and the outer corners at ±40° of its axis."""
    page, log = browser_page.page, browser_page.log
    origin = {"lat": 48.85, "lon": 2.35, "alt": 100.0}
    site = {"lat": 48.80, "lon": 2.30, "alt": 120.0, "heading_deg": 30.0}
    fov = {
        "kind": "sector",
        "frame": "sensor",
        "heading_deg": 90.0,
        "half_angle_deg": 40.0,
        "range": [500.0, 20_000.0],
    }
    config = {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "origin": origin,
        "sensors": [{"id": "radar", "site": site, "fov": fov}],
    }
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        created = client.post("/v1/sessions", json=config)
        assert created.status_code == 201, created.text
        sid, token = created.json()["id"], created.json()["token"]
        page.goto(f"{live_server.url}/#session={sid}&token={token}")
        page.wait_for_function("() => window.__viewer.state().fields.length === 1")
        (field,) = viewer_state(page)["fields"]
    oracle = proj_enu((origin["lat"], origin["lon"], origin["alt"]))
    east, north, _ = oracle.transform(site["lat"], site["lon"], site["alt"])
    assert field["apex"] == pytest.approx([east, north], abs=1e-3)
    heading = math.radians(site["heading_deg"])
    for corner, sensor_angle in ((field["outline"][0], 50.0), (field["outline"][64], 130.0)):
        # the sensor-frame point at 20 km, `sensor_angle` ccw from its x axis, in the session
        x, y = (20_000.0 * f(math.radians(sensor_angle)) for f in (math.cos, math.sin))
        expected = [
            east + math.cos(heading) * x + math.sin(heading) * y,
            north - math.sin(heading) * x + math.cos(heading) * y,
        ]
        assert corner == pytest.approx(expected, abs=1e-3)
    # the sector's axis is the radar's heading: 30° clockwise from north
    middle = field["outline"][32]
    bearing = math.degrees(math.atan2(middle[0] - east, middle[1] - north))
    assert bearing == pytest.approx(site["heading_deg"], abs=1e-6)
    assert not log.console_errors, log.console_errors
    assert not log.failures, log.failures


def test_the_viewer_login_subscribes_with_the_bearer_subprotocol(live_server: LiveServer) -> None:
    """The page's WebSocket login, ``["bearer", token]`` as subprotocols, is accepted; a wrong token is not."""
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        created = client.post("/v1/sessions", json=session_config()).json()
        sid, token = created["id"], created["token"]
        url = live_server.url.replace("http://", "ws://") + f"/v1/sessions/{sid}/subscribe"
        with connect(url, subprotocols=["bearer", token]) as viewer:  # type: ignore[list-item]
            assert viewer.subprotocol == "bearer"
            assert json.loads(viewer.recv(timeout=RECEIVE_TIMEOUT_S))["type"] == "ack"
            body = reports(1)[0]
            headers = {"Authorization": f"Bearer {token}"}
            posted = client.post(f"/v1/sessions/{sid}/tracks", json=body, headers=headers)
            message = json.loads(viewer.recv(timeout=RECEIVE_TIMEOUT_S))
            assert message["type"] == "result" and message["result"] == posted.json()
        with (
            pytest.raises(InvalidStatus) as refused,
            connect(url, subprotocols=["bearer", "not-the-token"]),  # type: ignore[list-item]
        ):
            pass
        assert refused.value.response.status_code == 404
