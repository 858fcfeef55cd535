"""ASTERIX in (app/inputs/asterix.py): the package's sample recording and a simulated scene.

- The sample recording of ``asterix-decoder`` (CAT034/048 over UDP: 128
  CAT048 reports of seven radars over 20 s) goes through a session with one
  polar sensor per radar: every report is accounted for exactly once (a
  detection of its radar, a duplicate, or without a position), and the
  detections logged are those the answers say.
- A longer scene encoded here from the specifications (a radar's scans
  with north markers, an ADS-B ground station's reports) gives, posted as
  ASTERIX (REST and WebSocket binary messages), the step results of the same
  scene posted as JSON (the values the encoding keeps, converted by hand:
  slant range and flight level to ground range; ground vector to east/north
  velocity; NACp/NACv to σ).
- Malformed data is a 422 ``malformed-asterix`` problem with the byte offset,
  and changes nothing.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import asterix  # type: ignore[import-untyped]
import numpy as np
from fastapi.testclient import TestClient

from app.inputs.asterix_decoder import IsolatedDecoder
from app.main import create_app
from core.fusion.reorder import REORDER_WINDOW
from tests.api.asterix_encoding import (
    FL_LSB,
    FOOT,
    GS_LSB,
    LATLON_LSB,
    NM,
    RHO_LSB,
    TA_LSB,
    THETA_LSB,
    block,
    cat021,
    cat034_north,
    cat048,
    quantised,
    udp_payloads,
)
from tests.api.conftest import make_settings
from tests.api.proj_oracle import proj_enu

ORIGIN = (43.6, 1.44, 150.0)
SITE = (43.65, 1.40, 200.0)
RADAR, ADSB = (1, 1), (1, 2)
PERIOD, SCANS, START = 4.0, 24, 36000.0
FLIGHT_LEVEL = 300.0
NACP, NACV = 9, 2
OCTET = "application/octet-stream"


def _session(client: TestClient, config: dict[str, Any]) -> tuple[str, dict[str, str]]:
    created = client.post("/v1/sessions", json=config)
    assert created.status_code == 201, created.text
    return created.json()["id"], {"Authorization": f"Bearer {created.json()['token']}"}


def _post(client: TestClient, sid: str, auth: dict[str, str], data: bytes, **params: str) -> Any:
    answer = client.post(
        f"/v1/sessions/{sid}/asterix",
        params=params,
        content=data,
        headers={**auth, "content-type": OCTET},
    )
    return answer


def test_the_sample_recording_accounts_for_every_report() -> None:
    recording = Path(asterix.get_sample_file("cat_034_048.pcap")).read_bytes()
    data = b"".join(udp_payloads(recording))
    plots = [r for r in asterix.parse(data, verbose=False) if r["category"] == 48]
    times = [r["I140"]["ToD"]["val"] for r in plots]
    assert len(plots) == 128 and 19.0 < max(times) - min(times) < 21.0
    sources = sorted({(r["I010"]["SAC"]["val"], r["I010"]["SIC"]["val"]) for r in plots})
    polar = {"kind": "polar", "sigma_range": 70.0, "sigma_azimuth_deg": 0.08}
    config = {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "sensors": [{"id": f"r{sac}-{sic}", "measurement": polar} for sac, sic in sources],
    }
    with TestClient(create_app(make_settings(max_body_bytes=1 << 20))) as client:
        sid, auth = _session(client, config)
        several = _post(client, sid, auth, data, sensor="r25-13")
        assert several.status_code == 422
        assert several.json()["errors"][0]["loc"] == ["query", "source"]
        outcome_of: dict[int, str] = {}
        for sac, sic in sources:
            sensor = f"r{sac}-{sic}"
            answer = _post(client, sid, auth, data, sensor=sensor, source=f"{sac}/{sic}")
            assert answer.status_code == 200, answer.text
            body = answer.json()
            for entry in body["records"]:
                if entry["category"] == 48 and entry["outcome"] != "other_source":
                    assert entry["offset"] not in outcome_of, entry
                    outcome_of[entry["offset"]] = entry["outcome"]
            detections = sum(entry["outcome"] == "detection" for entry in body["records"])
            events = client.get(f"/v1/sessions/{sid}/events", headers=auth).json()["events"]
            logged = sum(
                len(event["report"]["detections"])
                for event in events
                if event["report"]["sensor"] == sensor
            )
            assert logged == detections and len(body["results"]) >= 1
            assert sum(body["counts"].values()) == len(body["records"])
        assert len(outcome_of) == 128
        assert set(outcome_of.values()) <= {"detection", "duplicate", "no_position"}
        # the recording sends every packet twice: the second copy of a report is a duplicate
        distinct = {r["hexdata"]: r for r in plots}
        outcomes = list(outcome_of.values())
        assert outcomes.count("duplicate") == 128 - len(distinct) == 64
        assert outcomes.count("no_position") == sum("I040" not in r for r in distinct.values())


def test_the_sample_recording_as_it_arrives_is_tracked_centrally() -> None:
    """The recording's packets posted as they arrive, each to its radar's sensor: the
    radars' reports interleave out of time order (one radar's plots lag another's by up
    to 1.45 s), which the central tracker's reorder buffer puts in place (docs/algorithms.md
    §8.9): no report is refused, and every plot with a position is a detection. A report
    older than the window is a 409 that names the window."""
    recording = Path(asterix.get_sample_file("cat_034_048.pcap")).read_bytes()
    payloads = list(dict.fromkeys(udp_payloads(recording)))  # the recording sends each twice
    polar = {"kind": "polar", "sigma_range": 70.0, "sigma_azimuth_deg": 0.08}
    decoded = [asterix.parse(payload, verbose=False) for payload in payloads]
    sources = sorted(
        {(r["I010"]["SAC"]["val"], r["I010"]["SIC"]["val"]) for d in decoded for r in d}
    )
    config = {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "sensors": [
            {"id": f"r{sac}-{sic}", "measurement": polar, "local_tracker": False}
            for sac, sic in sources
        ],
    }
    # independently of the service: each packet's plots with a position, and how late its
    # median time is against the latest time of the packets before it
    positioned, latest, lags = 0, -math.inf, []
    for records in decoded:
        times = sorted(
            r["I140"]["ToD"]["val"] for r in records if r["category"] == 48 and "I040" in r
        )
        positioned += len(times)
        if times:
            median = times[(len(times) - 1) // 2]
            lags.append(latest - median)
            latest = max(latest, median)
    assert 1.0 < max(lags) < REORDER_WINDOW and sum(lag > 0 for lag in lags) > 20
    with TestClient(create_app(make_settings(max_body_bytes=1 << 20))) as client:
        sid, auth = _session(client, config)
        detections = 0
        for payload, records in zip(payloads, decoded, strict=True):
            sac, sic = records[0]["I010"]["SAC"]["val"], records[0]["I010"]["SIC"]["val"]
            answer = _post(client, sid, auth, payload, sensor=f"r{sac}-{sic}")
            assert answer.status_code == 200, answer.text
            outcomes = [entry["outcome"] for entry in answer.json()["records"]]
            assert "stale" not in outcomes
            detections += outcomes.count("detection")
        assert detections == positioned
        events = client.get(f"/v1/sessions/{sid}/events", headers=auth).json()["events"]
        assert sum(len(event["report"]["detections"]) for event in events) == positioned
        late = {
            "sensor": f"r{sources[0][0]}-{sources[0][1]}",
            "time": latest - REORDER_WINDOW - 1.0,
            "detections": [{"range": 50_000.0, "azimuth_deg": 10.0}],
        }
        refused = client.post(f"/v1/sessions/{sid}/detections", json=late, headers=auth)
        assert refused.status_code == 409, refused.text
        assert "reorder window" in refused.json()["detail"]


def _truth(time: float) -> list[np.ndarray]:
    """Two aircraft in the radar's ENU plane (m, m/s): [east, north, v_east, v_north]."""
    t = time - START
    return [
        np.array([-30_000.0 + 220.0 * t, 60_000.0, 220.0, 0.0]),
        np.array([40_000.0, 80_000.0 - 200.0 * t, 0.0, -200.0]),
    ]


def _scene() -> tuple[list[tuple[str, bytes]], list[tuple[str, dict[str, Any]]]]:
    """The scene as ASTERIX posts and as JSON inputs, in the same order."""
    rng = np.random.default_rng(11)
    site_enu = proj_enu(SITE)
    rise_q = quantised(FLIGHT_LEVEL, FL_LSB) * FL_LSB * 100.0 * FOOT - SITE[2]
    posts: list[tuple[str, bytes]] = []
    inputs: list[tuple[str, dict[str, Any]]] = []
    for scan in range(SCANS):
        time = START + PERIOD * scan
        records, detections = [], []
        for number, truth in enumerate(_truth(time)):
            ground = math.hypot(truth[0], truth[1]) + rng.normal(0.0, 50.0)
            azimuth = math.degrees(math.atan2(truth[0], truth[1])) % 360 + rng.normal(0.0, 0.08)
            slant = math.sqrt(ground**2 + rise_q**2)
            records.append(
                cat048(*RADAR, time, slant / NM, azimuth, FLIGHT_LEVEL, 0xA00000 + number, number)
            )
            rho = quantised(slant / NM, RHO_LSB) * RHO_LSB * NM
            theta = (quantised(azimuth, THETA_LSB) % 2**16) * THETA_LSB
            detections.append(
                {"range": math.sqrt(rho * rho - rise_q * rise_q), "azimuth_deg": theta}
            )
        posts.append(
            ("radar", block(34, [cat034_north(*RADAR, time, PERIOD)]) + block(48, records))
        )
        inputs.append(("detections", {"sensor": "radar", "time": time, "detections": detections}))
        time += PERIOD / 2
        reports, tracks = [], []
        for number, truth in enumerate(_truth(time)):
            east, north = truth[:2] + rng.normal(0.0, 15.0, 2)
            point = site_enu.transform(east, north, 0.0, direction="INVERSE")
            lat, lon = float(point[0]), float(point[1])
            speed = math.hypot(truth[2], truth[3]) / NM
            angle = math.degrees(math.atan2(truth[2], truth[3])) % 360
            address = 0xB00000 + number
            reports.append(
                cat021(*ADSB, time, lat, lon, address, speed, angle, 30_000.0, NACP, NACV)
            )
            ground_speed = quantised(speed, GS_LSB) * GS_LSB
            track_angle = (quantised(angle, TA_LSB) % 2**16) * TA_LSB
            position_sigma, velocity_sigma = 30.0 / 2.4477, 3.0 / 2.4477
            tracks.append(
                {
                    "id": f"{address:06X}",
                    "state": [
                        quantised(lat, LATLON_LSB) * LATLON_LSB,
                        ground_speed * NM * math.sin(math.radians(track_angle)),
                        quantised(lon, LATLON_LSB) * LATLON_LSB,
                        ground_speed * NM * math.cos(math.radians(track_angle)),
                    ],
                    "covariance": np.diag([position_sigma**2, velocity_sigma**2] * 2).tolist(),
                }
            )
        posts.append(("adsb", block(21, reports)))
        inputs.append(
            ("tracks", {"sensor": "adsb", "time": time, "frame": "geodetic", "tracks": tracks})
        )
    return posts, inputs


SCENE_CONFIG = {
    "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
    "origin": {"lat": ORIGIN[0], "lon": ORIGIN[1], "alt": ORIGIN[2]},
    "tracking": {"time_interval": PERIOD},
    "sensors": [
        {
            "id": "radar",
            "site": {"lat": SITE[0], "lon": SITE[1], "alt": SITE[2]},
            "measurement": {"kind": "polar", "sigma_range": 50.0, "sigma_azimuth_deg": 0.08},
            "p_detect": 0.95,
        },
        {"id": "adsb", "p_detect": 0.99},
    ],
}
SOURCES = {"radar": "1/1", "adsb": "1/2"}


def test_a_scene_as_asterix_gives_the_results_of_the_same_scene_as_json(client: TestClient) -> None:
    posts, inputs = _scene()
    twin, twin_auth = _session(client, SCENE_CONFIG)
    expected = []
    for kind, body in inputs:
        answer = client.post(f"/v1/sessions/{twin}/{kind}", json=body, headers=twin_auth)
        assert answer.status_code == 200, answer.text
        expected.append(answer.json())

    sid, auth = _session(client, SCENE_CONFIG)
    results: list[Any] = []
    records: list[Any] = []
    by_rest = len(posts) - 8
    for sensor, data in posts[:by_rest]:
        answer = _post(client, sid, auth, data, sensor=sensor)
        assert answer.status_code == 200, answer.text
        results += answer.json()["results"]
        records += answer.json()["records"]
    sockets = {
        sensor: client.websocket_connect(
            f"/v1/sessions/{sid}/stream?sensor={sensor}&source={source}", headers=auth
        )
        for sensor, source in SOURCES.items()
    }
    try:
        for socket in sockets.values():
            socket.__enter__().receive_json()  # ack
        for sensor, data in posts[by_rest:]:
            socket = sockets[sensor]
            socket.send_bytes(data)
            message = socket.receive_json()
            assert message["type"] == "asterix_result", message
            results += message["result"]["results"]
            records += message["result"]["records"]
    finally:
        for socket in sockets.values():
            socket.__exit__(None, None, None)

    assert results == expected
    confirmed = [t for t in expected[-1]["tracks"] if t["status"] == "confirmed"]
    assert len(confirmed) == 2  # the scene is tracked, not just equal
    plots = [entry for entry in records if entry["category"] == 48]
    assert {entry["outcome"] for entry in plots} == {"detection"}
    assert {entry["mode_s"] for entry in plots} == {"A00000", "A00001"}  # kept as a hint
    scans = [entry for entry in records if entry["category"] == 34]
    assert {entry["outcome"] for entry in scans} == {"scan_timing"}


def test_malformed_data_is_refused_with_its_byte_offset(client: TestClient) -> None:
    posts, _ = _scene()
    sid, auth = _session(client, SCENE_CONFIG)
    good = posts[0][1]
    truncated = good + good[:10]
    answer = _post(client, sid, auth, truncated, sensor="radar")
    assert answer.status_code == 422
    problem = answer.json()
    assert problem["type"].endswith(":malformed-asterix")
    assert problem["offset"] == len(good)
    assert problem["errors"][0]["pointer"] == "#"
    # a record whose FSPEC announces items the block does not hold
    broken = block(48, [bytes([0xFF, 0xFF, 0xFF, 0x00])])
    answer = _post(client, sid, auth, good + broken, sensor="radar")
    assert answer.status_code == 422 and answer.json()["offset"] == len(good) + 3
    with client.websocket_connect(f"/v1/sessions/{sid}/stream?sensor=radar", headers=auth) as ws:
        ws.receive_json()
        ws.send_bytes(truncated)
        message = ws.receive_json()
        assert message["type"] == "error" and message["problem"]["offset"] == len(good)
    assert client.get(f"/v1/sessions/{sid}", headers=auth).json()["seq"] == 0


def test_records_for_the_wrong_kind_of_sensor_are_refused(client: TestClient) -> None:
    posts, _ = _scene()
    sid, auth = _session(client, SCENE_CONFIG)
    adsb_blocks = posts[1][1]
    answer = _post(client, sid, auth, adsb_blocks, sensor="radar")
    assert answer.status_code == 422
    assert answer.json()["errors"][0]["loc"] == ["query", "sensor"]
    answer = _post(client, sid, auth, posts[0][1], sensor="nobody")
    assert answer.status_code == 422
    assert "unknown sensor" in answer.json()["errors"][0]["detail"]
    assert client.get(f"/v1/sessions/{sid}", headers=auth).json()["seq"] == 0


CRASHING_CAT205 = bytes.fromhex(
    "cd003cf5900102070840a0284057c004b0abcdef004df5900102070840a0284057c004b0abcdef006df590"
    "0102070840a0284057c004b0abcdef004d"
)
"""A CAT205 block (CAT048 records under another category byte) on which the decoder's C code
crashes its process."""

FUZZ = """
import random, sys
from app.inputs.asterix import MalformedAsterix, records
from tests.api.asterix_encoding import block, cat021, cat034_north, cat048
rng = random.Random(int(sys.argv[1]))
good = (
    block(48, [cat048(1, 2, 3600.5, 40.25, 123.4, 300.0, 0xABCDEF, 77)] * 3)
    + block(34, [cat034_north(1, 2, 3600.0, 4.0)])
    + block(21, [cat021(1, 3, 3601.0, 43.7, 1.4, 0x123456, 0.12, 45.0, 30000.0, 9, 2)])
)
for _ in range(int(sys.argv[2])):
    data = bytearray(good)
    for _ in range(rng.randint(1, 6)):
        data[rng.randrange(len(data))] = rng.randrange(256)
    if rng.random() < 0.3:
        data = data[: rng.randrange(len(data))]
    try:
        records(bytes(data))
    except MalformedAsterix:
        pass
print("survived")
"""


def test_mutated_blocks_are_decoded_or_refused_never_crash_the_process() -> None:
    """Random byte flips and truncations of well-formed CAT048/034/021 blocks (run in a child
    process, in case the isolation failed): each is decoded or refused as malformed, and the
    process lives."""
    done = subprocess.run(
        [sys.executable, "-c", FUZZ, "7", "3000"],
        cwd=Path(__file__).resolve().parents[2],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0 and done.stdout.strip() == "survived", done


def test_a_block_of_another_category_is_accounted_for_not_decoded(client: TestClient) -> None:
    sid, auth = _session(client, SCENE_CONFIG)
    answer = _post(client, sid, auth, CRASHING_CAT205 + _scene()[0][0][1], sensor="radar")
    assert answer.status_code == 200, answer.text
    first = answer.json()["records"][0]
    assert (first["offset"], first["category"], first["outcome"]) == (
        0,
        205,
        "unsupported_category",
    )
    assert len(answer.json()["results"]) == 1  # the radar's scan after it


def test_the_decoder_crashing_on_a_block_costs_that_block_only() -> None:
    """The C decoder dies on the CAT205 block; in its child process that is one refused block:
    a fresh child decodes the next one."""
    decoder = IsolatedDecoder()
    try:
        assert decoder.parse(CRASHING_CAT205) is None
        decoded = decoder.parse(block(34, [cat034_north(*RADAR, START, PERIOD)]))
        assert decoded is not None and decoded[0]["I041"]["RotS"]["val"] == PERIOD
    finally:
        decoder.close()
