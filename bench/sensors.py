"""Sensors in the world: conversion cost next to the Cartesian equivalent (issue 17).

Two scenes of 1 000 targets on a 2 km grid around a WGS84 origin, each timed
as the service runs an input: the wire body validated (pydantic), translated
(conversion to the session frame) and applied to the engine (one step):

- a polar scan: 1 000 range-azimuth detections of a radar at a geodetic site
  (converted measurements with their own covariances, then a local-tracker
  scan that starts 1 000 tracks from the previous scan's seeds and a fusion
  step), against the same detections as Cartesian ``z`` with the sensor's ``r``;
- a geodetic report: 1 000 tracks in lat/lon with east/north velocities,
  against the same tracks in the session frame (one fusion step that starts
  1 000 fused tracks).

Median ms of each, and the ratio to its Cartesian twin in the same run.
Floor (issue 17): ratio ≤ 2.

Run: ``.venv/bin/python bench/sensors.py``.
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from api_schemas.config import SessionConfig
from api_schemas.reports import DetectionReport, TrackReport
from app.geo.geodesy import LocalFrame
from app.inputs.detections import core_detection_report
from app.inputs.tracks import session_frame_report
from app.sessions.translate import fusion_config
from core.fusion.engine import SessionEngine

TARGETS = 1000
REPEATS = 9
FLOOR_RATIO = 2.0
ORIGIN = {"lat": 45.0, "lon": 5.0, "alt": 0.0}
SITE = (44.9, 4.9, 100.0)
LAYOUT = {"dim": 4, "position": [0, 2], "velocity": [1, 3]}


def _grid() -> np.ndarray:
    side = math.ceil(math.sqrt(TARGETS))
    xs, ys = np.meshgrid(np.arange(side) * 2000.0 - 30_000, np.arange(side) * 2000.0 + 5_000)
    return np.stack([xs.ravel(), ys.ravel()], -1)[:TARGETS]


def _config(sensor: dict[str, Any]) -> SessionConfig:
    return SessionConfig.model_validate(
        {
            "state": LAYOUT,
            "origin": ORIGIN,
            "motion": {"model": "constant_velocity", "q": 1.0},
            "sensors": [sensor],
        }
    )


def _detection_bodies(polar: bool) -> list[dict[str, Any]]:
    frame = LocalFrame(**ORIGIN)
    site = frame.from_geodetic(*SITE)[0, :2]
    bodies = []
    for scan in range(2):
        points = _grid() + np.array([10.0 * scan, 0.0])
        if polar:
            offset = points - site
            detections = [
                {"range": float(np.hypot(*d)), "azimuth_deg": math.degrees(math.atan2(*d))}
                for d in offset
            ]
        else:
            detections = [{"z": point.tolist()} for point in points]
        bodies.append({"sensor": "radar", "time": float(scan), "detections": detections})
    return bodies


def _track_body(geodetic: bool) -> dict[str, Any]:
    frame = LocalFrame(**ORIGIN)
    points = _grid()
    covariance = np.diag([100.0, 4.0, 100.0, 4.0]).tolist()
    if geodetic:
        lla = frame.to_geodetic(np.column_stack([points, np.zeros(len(points))]))
        states = [[lat, 10.0, lon, 0.0] for lat, lon, _ in lla.tolist()]
        report_frame = "geodetic"
    else:
        states = [[x, 10.0, y, 0.0] for x, y in points.tolist()]
        report_frame = "session"
    tracks = [
        {"id": f"t{n}", "state": state, "covariance": covariance} for n, state in enumerate(states)
    ]
    return {"sensor": "adsb", "time": 1.0, "frame": report_frame, "tracks": tracks}


Timed = tuple[Callable[[], object], Callable[[object], object]]
"""``(prepare, run)``: ``run(prepare())`` is timed, ``prepare`` is not."""


def _paired_medians(converted: Timed, plain: Timed) -> tuple[float, float]:
    """Median ms of each, their samples alternated so both see the same machine load."""
    samples: tuple[list[float], list[float]] = ([], [])
    for _ in range(REPEATS):
        for (prepare, run), times in zip((converted, plain), samples, strict=True):
            state = prepare()
            start = time.perf_counter()
            run(state)
            times.append((time.perf_counter() - start) * 1e3)
    return statistics.median(samples[0]), statistics.median(samples[1])


def detections_step(polar: bool) -> Timed:
    """Validate + convert + one tracker/fusion scan of 1 000 detections (after a seeding scan)."""
    measurement: dict[str, Any] = (
        {"kind": "polar", "sigma_range": 20.0, "sigma_azimuth_deg": 0.2}
        if polar
        else {"r": [[400.0, 0.0], [0.0, 400.0]]}
    )
    sensor = {
        "id": "radar",
        "site": {"lat": SITE[0], "lon": SITE[1], "alt": SITE[2]},
        "measurement": measurement,
    }
    config = _config(sensor)
    first, second = _detection_bodies(polar)

    def prepare() -> SessionEngine:
        engine = SessionEngine(fusion_config(config))
        engine.apply_detections(
            core_detection_report(DetectionReport.model_validate(first), config, engine.config)
        )
        return engine

    def run(engine: object) -> None:
        assert isinstance(engine, SessionEngine)
        report = DetectionReport.model_validate(second)
        engine.apply_detections(core_detection_report(report, config, engine.config))

    return prepare, run


def tracks_step(geodetic: bool) -> Timed:
    """Validate + convert + one fusion step of a 1 000-track report."""
    config = _config({"id": "adsb"})
    body = _track_body(geodetic)

    def run(engine: object) -> None:
        assert isinstance(engine, SessionEngine)
        engine.apply(session_frame_report(TrackReport.model_validate(body), config))

    return (lambda: SessionEngine(fusion_config(config))), run


def main() -> None:
    rows = [
        (
            "1000-detection scan",
            detections_step(True),
            detections_step(False),
            "polar",
            "cartesian",
        ),
        ("1000-track report", tracks_step(True), tracks_step(False), "geodetic", "session frame"),
    ]
    print(f"median of {REPEATS}, ms (validate + convert + one step)")
    for name, converted_step, plain_step, kind, twin in rows:
        converted, plain = _paired_medians(converted_step, plain_step)
        ratio = converted / plain
        verdict = "ok" if ratio <= FLOOR_RATIO else f"ABOVE the {FLOOR_RATIO:g}x floor"
        print(
            f"{name:22s} {kind:9s} {converted:8.1f}   {twin:13s} {plain:8.1f}"
            f"   ratio {ratio:4.2f}  {verdict}"
        )


if __name__ == "__main__":
    main()
