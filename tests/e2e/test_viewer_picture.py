"""The viewer's picture as people meet it (issue 27), in headless Chromium on a live uvicorn.

The README's geodetic session is drawn on the offline Natural Earth map: the map
layer's pixels are counted by colour (structure, not a reference image), and
places PROJ puts on land and at sea are drawn in the land and sea colours. The
view follows a moving track until the user pans; labels never overlap each
other, a marker or the legend, and stay inside the plot; a 6-D track's
covariance can be scrolled into view whole and its numbers are written for
people (what rounds to 0 is 0); a 360° sector has no radial edge. Screenshots
land in the test's temporary directory.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest

from tests.api.conftest import LiveServer
from tests.api.proj_oracle import proj_enu
from tests.e2e.browser import BrowserPage, viewer_state, wait_for_seq

README = (Path(__file__).resolve().parents[2] / "README.md").read_text(encoding="utf-8")
LAYOUT_2D = {"dim": 4, "position": [0, 2], "velocity": [1, 3]}
WHEEL_STEPS = 14

PIXELS = """([x0, y0, w, h, colours, points]) => {
  const canvas = document.getElementById('plot'), ratio = window.devicePixelRatio || 1;
  const data = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data;
  const rgb = (hex) => [1, 3, 5].map((n) => parseInt(hex.slice(n, n + 2), 16));
  const wanted = Object.fromEntries(Object.entries(colours).map(([name, hex]) => [name, rgb(hex)]));
  const at = (x, y) => { const n = 4 * (Math.round(y * ratio) * canvas.width + Math.round(x * ratio)); return [data[n], data[n + 1], data[n + 2]]; };
  const nameOf = ([r, g, b]) => Object.keys(wanted).find((name) => wanted[name][0] === r && wanted[name][1] === g && wanted[name][2] === b) || 'other';
  const counts = { total: 0 };
  for (let y = y0 + 1; y < y0 + h - 1; y += 2) for (let x = x0 + 1; x < x0 + w - 1; x += 2) {
    const name = nameOf(at(x, y)); counts[name] = (counts[name] || 0) + 1; counts.total += 1;
  }
  // the colour most common in a 7×7 patch around each point (a grid line may cross it)
  const patches = points.map(([px, py]) => {
    const seen = {};
    for (let dy = -3; dy <= 3; dy++) for (let dx = -3; dx <= 3; dx++) { const name = nameOf(at(px + dx, py + dy)); seen[name] = (seen[name] || 0) + 1; }
    return Object.entries(seen).sort((a, b) => b[1] - a[1])[0][0];
  });
  return { counts, patches };
}"""


def open_session(client: httpx.Client, config: dict[str, Any]) -> tuple[str, str, dict[str, str]]:
    created = client.post("/v1/sessions", json=config)
    assert created.status_code == 201, created.text
    sid, token = created.json()["id"], created.json()["token"]
    return sid, token, {"Authorization": f"Bearer {token}"}


def post(client: httpx.Client, sid: str, headers: dict[str, str], path: str, body: Any) -> None:
    answer = client.post(f"/v1/sessions/{sid}/{path}", json=body, headers=headers)
    assert answer.status_code == 200, answer.text


def to_screen(shown: dict[str, Any], east: float, north: float) -> tuple[float, float]:
    """Where the page's view puts a session-plane point (its centre, scale and plot box)."""
    plot, mpp = shown["plot"], shown["metresPerPixel"]
    cx, cy = shown["centre"]
    return (
        plot["x0"] + plot["w"] / 2 + (east - cx) / mpp,
        plot["y0"] + plot["h"] / 2 - (north - cy) / mpp,
    )


def inside(box: dict[str, float], plot: dict[str, float]) -> bool:
    return (
        box["x"] >= plot["x0"]
        and box["y"] >= plot["y0"]
        and box["x"] + box["w"] <= plot["x0"] + plot["w"]
        and box["y"] + box["h"] <= plot["y0"] + plot["h"]
    )


def overlap(a: dict[str, float], b: dict[str, float]) -> bool:
    return (
        a["x"] < b["x"] + b["w"]
        and b["x"] < a["x"] + a["w"]
        and a["y"] < b["y"] + b["h"]
        and b["y"] < a["y"] + a["h"]
    )


def readme_geodetic_session() -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The README's geodetic example: its session body and its six detection inputs, read
    from the README itself (the same JSON, the same printf of ranges)."""
    block = next(
        body for body in re.findall(r"```sh\n(.*?)```", README, re.DOTALL) if "GEO=" in body
    )
    body = re.search(r"-d '(\{.*?\})'\)", block, re.DOTALL)
    assert body is not None, block
    config = json.loads(body.group(1))
    assert "origin" in config
    inputs = [
        {
            "sensor": "radar-t",
            "time": t,
            "detections": [{"range": 12000 + 100 * t, "azimuth_deg": 45}],
        }
        for t in range(6)
    ]
    assert "for t in 0 1 2 3 4 5" in block and "$((12000 + 100 * t))" in block
    return config, inputs


def test_the_readme_geodetic_session_is_drawn_on_the_map(
    live_server: LiveServer, browser_page: BrowserPage, tmp_path: Path
) -> None:
    page, log = browser_page.page, browser_page.log
    config, inputs = readme_geodetic_session()
    origin = config["origin"]
    oracle = proj_enu((origin["lat"], origin["lon"], origin["alt"]))
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        sid, token, headers = open_session(client, config)
        for body in inputs:
            post(client, sid, headers, "detections", body)
        page.goto(f"{live_server.url}/#session={sid}&token={token}")
        wait_for_seq(page, len(inputs))
        page.wait_for_function("() => (window.__viewer.state().map || {}).loaded === true")
        page.wait_for_function("() => window.__viewer.state().trails.F1 >= 2")  # its history
        close = viewer_state(page)
        page.screenshot(path=tmp_path / "viewer-map-close.png")
        # the aircraft 12.5 km from the radar, near Toulouse: the whole view is land
        colours = close["map"]["colours"]
        plot = close["plot"]
        box = [plot["x0"], plot["y0"], plot["w"], plot["h"], colours, []]
        counts = page.evaluate(PIXELS, box)["counts"]
        assert close["map"]["land"] >= 1
        assert counts.get("land", 0) > 0.8 * counts["total"], counts
        assert counts.get("sea", 0) == 0, counts

        # zoomed out about the view's centre (the wheel keeps the point under the cursor):
        # the Gulf of Lion and the Pyrenees come into the view
        canvas = page.locator("#plot").bounding_box()
        assert canvas is not None
        page.mouse.move(
            canvas["x"] + plot["x0"] + plot["w"] / 2, canvas["y"] + plot["y0"] + plot["h"] / 2
        )
        for _ in range(WHEEL_STEPS):
            page.mouse.wheel(0, 400)
        # every step taken (the page zooms by exp(0.0015 · deltaY) a step) before reading it
        page.wait_for_function(
            "mpp => window.__viewer.state().metresPerPixel > mpp",
            arg=close["metresPerPixel"] * math.exp(0.0015 * 400 * (WHEEL_STEPS - 0.5)),
        )
        far = viewer_state(page)
        page.screenshot(path=tmp_path / "viewer-map-far.png")
        assert not far["follow"]  # the user zoomed: the view is theirs
        # places PROJ puts in the session plane, on land and at sea (tens of km from any coast)
        places = {
            "Montagne Noire": (43.45, 2.30, "land"),
            "Rodez": (44.35, 2.57, "land"),
            "Gulf of Lion": (42.90, 3.70, "sea"),
            "off Marseille": (42.80, 5.20, "sea"),
        }
        points = []
        for lat, lon, _ in places.values():
            east, north, _ = oracle.transform(lat, lon, 0.0)
            x, y = to_screen(far, east, north)
            assert (
                plot["x0"] < x < plot["x0"] + plot["w"] and plot["y0"] < y < plot["y0"] + plot["h"]
            )
            points.append([x, y])
        seen = page.evaluate(PIXELS, [*box[:5], points])
        assert seen["patches"] == [kind for _, _, kind in places.values()], seen
        counts = seen["counts"]
        assert counts.get("land", 0) > 0.4 * counts["total"], counts
        assert counts.get("sea", 0) > 0.05 * counts["total"], counts
        assert far["map"]["borders"] >= 1  # France–Spain, France–Andorra

        # key F: the view follows the track again
        page.locator("body").press("f")
        page.wait_for_function("() => window.__viewer.state().follow")
        assert viewer_state(page)["metresPerPixel"] == pytest.approx(
            close["metresPerPixel"], rel=1e-6
        )

    map_requests = [url for url in log.requests if "/map/" in url]
    assert map_requests == [f"{live_server.url}/map/countries-50m.json"]
    local = (live_server.url, live_server.url.replace("http://", "ws://"))
    assert all(url.startswith(local) for url in log.requests), log.requests
    assert not log.console_errors, log.console_errors
    assert not log.failures, log.failures


def test_the_view_follows_a_moving_track_until_the_user_pans(
    live_server: LiveServer, browser_page: BrowserPage, tmp_path: Path
) -> None:
    page, log = browser_page.page, browser_page.log
    covariance = np.diag([400.0, 25.0, 400.0, 25.0]).tolist()

    def report(t: int) -> dict[str, Any]:  # 600 m/s east, 200 m/s north
        state_at = [600.0 * t, 600.0, 200.0 * t, 200.0]
        return {
            "sensor": "s",
            "time": float(t),
            "tracks": [{"id": "a", "state": state_at, "covariance": covariance}],
        }

    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        sid, token, headers = open_session(client, {"state": LAYOUT_2D, "sensors": [{"id": "s"}]})
        post(client, sid, headers, "tracks", report(0))
        page.goto(f"{live_server.url}/#session={sid}&token={token}")
        first = wait_for_seq(page, 1)
        assert first["follow"]
        for t in range(1, 16):
            post(client, sid, headers, "tracks", report(t))
            shown = wait_for_seq(page, t + 1)
            (mark,) = shown["drawn"]
            plot = shown["plot"]
            assert plot["x0"] < mark["x"] < plot["x0"] + plot["w"], (t, mark, plot)
            assert plot["y0"] < mark["y"] < plot["y0"] + plot["h"], (t, mark, plot)
            assert shown["outside"] == []
        # the track went 9 km east and 3 km north: the view went with it
        assert shown["centre"][0] - first["centre"][0] > 3000.0
        page.screenshot(path=tmp_path / "viewer-following.png")

        # a pan: the view stays where the user put it while the track moves on
        canvas = page.locator("#plot").bounding_box()
        assert canvas is not None
        page.mouse.move(canvas["x"] + 500, canvas["y"] + 400)
        page.mouse.down()
        page.mouse.move(canvas["x"] + 700, canvas["y"] + 400, steps=4)
        page.mouse.up()
        panned = viewer_state(page)
        assert not panned["follow"]
        assert page.locator("#follow").inner_text() == "follow (F)"
        for t in range(16, 24):
            post(client, sid, headers, "tracks", report(t))
        moved_on = wait_for_seq(page, 24)
        assert moved_on["centre"] == panned["centre"]
        assert moved_on["metresPerPixel"] == panned["metresPerPixel"]
        assert moved_on["outside"] == [moved_on["drawn"][0]["id"]]  # it left the view

        # the button brings the view back to the track and follows again
        page.click("#follow")
        page.wait_for_function("() => window.__viewer.state().follow")
        back = viewer_state(page)
        (mark,) = back["drawn"]
        plot = back["plot"]
        assert plot["x0"] < mark["x"] < plot["x0"] + plot["w"]
        assert plot["y0"] < mark["y"] < plot["y0"] + plot["h"]
        assert back["outside"] == []
    assert not log.console_errors, log.console_errors


def crowd_config() -> dict[str, Any]:
    """Two sensors; one radar with a 360° sector and a blind range."""
    return {
        "state": LAYOUT_2D,
        "classes": ["liner", "bomber", "fighter"],
        "sensors": [
            {
                "id": "radar",
                "fov": {
                    "kind": "sector",
                    "origin": [0.0, 0.0],
                    "heading_deg": 30.0,
                    "half_angle_deg": 180.0,
                    "range": [300.0, 3000.0],
                },
            },
            {"id": "esm"},
        ],
    }


def test_labels_never_collide_and_a_full_sector_has_no_seam(
    live_server: LiveServer, browser_page: BrowserPage, tmp_path: Path
) -> None:
    page, log = browser_page.page, browser_page.log
    covariance = np.diag([900.0, 1.0, 400.0, 1.0]).tolist()
    evidence = {
        "mass": [
            {"set": ["fighter"], "mass": 0.7},
            {"set": ["liner", "bomber", "fighter"], "mass": 0.3},
        ]
    }
    tracks = [  # 23 tracks 60 m apart: too crowded for every label
        {
            "id": f"t{n}",
            "state": [60.0 * (n % 6), 0.0, 60.0 * (n // 6), 0.0],
            "covariance": covariance,
            "classification": evidence,
        }
        for n in range(23)
    ]
    # one more 5 km away: the view holds both, the cluster is a few pixels across
    tracks.append({**tracks[0], "id": "far", "state": [5000.0, 0.0, 3000.0, 0.0]})
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        sid, token, headers = open_session(client, crowd_config())
        post(client, sid, headers, "tracks", {"sensor": "radar", "time": 1.0, "tracks": tracks})
        page.goto(f"{live_server.url}/#session={sid}&token={token}")
        wait_for_seq(page, 1)

        def check_labels() -> dict[str, Any]:
            shown = viewer_state(page)
            labels = [label for label in shown["labels"] if label["shown"]]
            assert len(shown["labels"]) == len(shown["drawn"]) == 24
            assert labels, "no label shown"
            legend = page.locator("#legend").bounding_box()
            canvas = page.locator("#plot").bounding_box()
            assert legend is not None and canvas is not None
            legend_box = {
                "x": legend["x"] - canvas["x"],
                "y": legend["y"] - canvas["y"],
                "w": legend["width"],
                "h": legend["height"],
            }
            markers = [{"x": m["x"] - 3, "y": m["y"] - 3, "w": 6, "h": 6} for m in shown["drawn"]]
            for n, label in enumerate(labels):
                assert inside(label, shown["plot"]), label
                assert not overlap(label, legend_box), label
                assert not any(overlap(label, marker) for marker in markers), label
                for other in labels[n + 1 :]:
                    assert not overlap(label, other), (label, other)
            return shown

        crowded = check_labels()
        assert any(not label["shown"] for label in crowded["labels"])  # some had to give way
        page.screenshot(path=tmp_path / "viewer-labels.png")

        # the selected track's label comes first
        hidden = next(label["id"] for label in crowded["labels"] if not label["shown"])
        page.evaluate("id => window.__viewer.select(id)", hidden)
        selected = check_labels()
        assert {label["id"]: label["shown"] for label in selected["labels"]}[hidden]

        # dragged against the plot's right edge: labels stay inside, none cut
        canvas = page.locator("#plot").bounding_box()
        assert canvas is not None
        plot = selected["plot"]
        rightmost = max(mark["x"] for mark in selected["drawn"])
        start = (canvas["x"] + rightmost, canvas["y"] + plot["y0"] + plot["h"] / 2)
        page.mouse.move(*start)
        page.mouse.down()
        page.mouse.move(start[0] + (plot["x0"] + plot["w"] - 6 - rightmost), start[1], steps=4)
        page.mouse.up()
        check_labels()
        page.screenshot(path=tmp_path / "viewer-labels-edge.png")

        # the 360° sector: its outer circle and its blind range's circle, no radial edge
        (field,) = viewer_state(page)["fields"]
        outer, blind = field["rings"]
        assert {round(math.hypot(x, y), 6) for x, y in outer} == {3000.0}
        assert {round(math.hypot(x, y), 6) for x, y in blind} == {300.0}
    assert not log.console_errors, log.console_errors


HUMAN = re.compile(r"^(−?)([\d\u2009]+(?:\.\d+)?)(?:×10([⁰¹²³⁴⁵⁶⁷⁸⁹]+))?$")


def read_number(text: str) -> float:
    """A number as the page writes it: thin-space groups, a true minus, ×10ⁿ."""
    match = HUMAN.match(text.strip())
    assert match, text
    sign, digits, power = match.groups()
    value = float(digits.replace("\u2009", ""))
    if power:
        value *= 10.0 ** int("".join(str("⁰¹²³⁴⁵⁶⁷⁸⁹".index(c)) for c in power))
    return -value if sign else value


def test_the_detail_panel_scrolls_and_writes_numbers_for_people(
    live_server: LiveServer, browser_page: BrowserPage, tmp_path: Path
) -> None:
    """A 6-D track on a short window: every cell of its 6×6 covariance can be scrolled into
    view and is on top there; each cell says the server's value to its shown precision, a
    9.1e-62 is 0, and no number is in e-notation."""
    page, log = browser_page.page, browser_page.log
    page.set_viewport_size({"width": 1100, "height": 560})
    config = {
        "state": {"dim": 6, "position": [0, 2, 4], "velocity": [1, 3, 5]},
        "sensors": [{"id": "s"}],
    }
    covariance = np.diag([2.5e7, 4.0, 1234.5678, 0.25, 90_000.0, 1e-3])
    covariance[0, 2] = covariance[2, 0] = 9.1e-62
    covariance[1, 3] = covariance[3, 1] = -0.5
    report = {
        "sensor": "s",
        "time": 3.0,
        "tracks": [
            {
                "id": "a",
                "state": [123_456.789, -251.3, 0.000_2, 3.0, 9_500.0, 1e-70],
                "covariance": covariance.tolist(),
            }
        ],
    }
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        sid, token, headers = open_session(client, config)
        post(client, sid, headers, "tracks", report)
        (track,) = client.get(f"/v1/sessions/{sid}/tracks", headers=headers).json()["tracks"]
        page.goto(f"{live_server.url}/#session={sid}&token={token}")
        wait_for_seq(page, 1)
        page.evaluate("id => window.__viewer.select(id)", track["id"])
        page.wait_for_selector("#details .matrix")

    details = page.locator("#details").inner_text()
    assert not re.search(r"\de[+-]?\d", details), details
    assert page.evaluate(
        "() => { const d = document.getElementById('details'); return d.scrollHeight > d.clientHeight; }"
    ), "the test means something: the details need scrolling on this window"
    table = page.locator("#details .matrix").nth(1)  # the covariance
    rows = table.locator("tr")
    assert rows.count() == 7  # a header and six rows
    for i in range(6):
        cells = rows.nth(i + 1).locator("td")
        assert cells.count() == 6
        for j in range(6):
            cell = cells.nth(j)
            cell.scroll_into_view_if_needed()
            on_top = cell.evaluate(
                """cell => { const r = cell.getBoundingClientRect();
                  const hit = document.elementFromPoint(r.left + r.width / 2, r.top + r.height / 2);
                  return hit === cell || cell.contains(hit); }"""
            )
            assert on_top, (i, j)
            value, text = track["covariance"][i][j], cell.inner_text()
            shown = read_number(text)
            magnitude = abs(value)
            if magnitude < 5e-4:
                assert text == "0", (i, j, text)
            elif magnitude >= 1e6:  # 3 significant digits
                assert shown == pytest.approx(value, rel=5e-3), (i, j, text)
            else:  # 4 significant digits, at most 3 decimals
                step = max(10.0 ** (math.floor(math.log10(magnitude)) - 3), 1e-3)
                assert abs(shown - value) <= step / 2 + 1e-12, (i, j, text, value)
    page.screenshot(path=tmp_path / "viewer-details-scrolled.png")
    assert not log.console_errors, log.console_errors


def test_the_map_is_the_vendored_natural_earth_file_with_its_licence(
    live_server: LiveServer,
) -> None:
    """``/map/countries-50m.json`` is world-atlas 2.0.2's file, byte for byte (the SHA-256 its
    provenance note gives), a TopoJSON topology with land and countries; the ISC licence and
    the public-domain note sit beside it."""
    folder = Path(__file__).resolve().parents[2] / "app" / "static" / "map"
    note = (folder / "README.md").read_text(encoding="utf-8")
    digest = re.search(r"SHA-256\s+`([0-9a-f]{64})`", note)
    assert digest is not None, note
    assert "public domain" in note and "ISC" in note
    licence = (folder / "LICENSE").read_text(encoding="utf-8")
    assert "Michael Bostock" in licence and "Permission to use, copy, modify" in licence
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        answer = client.get("/map/countries-50m.json")
    assert answer.status_code == 200
    assert answer.headers["content-type"].startswith("application/json")
    assert hashlib.sha256(answer.content).hexdigest() == digest.group(1)
    topology = answer.json()
    assert topology["type"] == "Topology"
    assert {"land", "countries"} <= set(topology["objects"])
