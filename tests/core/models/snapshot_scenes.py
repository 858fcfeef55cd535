"""Scenes run through the service's own path, for the measurement-model tests.

Each scene runs in process through the wire config and detections
(:mod:`api_schemas`), their translation to the core
(:func:`app.sessions.translate.fusion_config`,
:func:`app.inputs.detections.core_detection_report`), the session engine, the
result writer (:func:`app.outputs.json_results.step_json`) and the engine's
export, and is summarised by the sha256 of every step's result text and of the
final export. A refactoring compares these hashes before and after by hand
(``python -m tests.core.models.snapshot_scenes`` prints them); no test pins them,
since they are the code's own earlier output, not an oracle.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import orjson
import pymap3d

from api_schemas.config import SessionConfig
from api_schemas.reports import DetectionReport
from app.inputs.detections import core_detection_report
from app.outputs.json_results import step_json
from app.sessions.translate import fusion_config
from core.fusion.engine import SessionEngine

ORIGIN = (52.0, 4.0, 0.0)
"""The geodetic scene's origin (lat, lon, alt)."""


def _sha(text: str | bytes) -> str:
    data = text.encode() if isinstance(text, str) else text
    return hashlib.sha256(data).hexdigest()


def run(config: dict[str, Any], reports: list[dict[str, Any]]) -> dict[str, str]:
    """The sha256 of every step's result (in one hash, in order) and of the final export."""
    session = SessionConfig.model_validate(config)
    engine = SessionEngine(fusion_config(session))
    steps = hashlib.sha256()
    for seq, body in enumerate(reports, start=1):
        wire = DetectionReport.model_validate(body)
        result = engine.apply_detections(
            core_detection_report(wire, session, engine.config), explain=True
        )
        steps.update(step_json(result, seq).encode())
    export = orjson.dumps(engine.export(), option=orjson.OPT_SERIALIZE_NUMPY)
    return {"steps": steps.hexdigest(), "export": _sha(export)}


def _targets_2d(scan: int) -> np.ndarray:
    """Three straight-flying targets in the plane (m)."""
    t = float(scan)
    return np.array(
        [
            [-4000.0 + 120.0 * t, 3000.0 - 40.0 * t],
            [5000.0 - 90.0 * t, -2000.0 + 70.0 * t],
            [1000.0 + 10.0 * t, 8000.0 - 150.0 * t],
        ]
    )


def linear_2d() -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """A 2-D Cartesian sensor: three targets, clutter, some detections with their own r."""
    rng = np.random.default_rng(25)
    config = {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "sensors": [
            {"id": "cam", "measurement": {"kind": "cartesian", "r": [[400.0, 0.0], [0.0, 400.0]]}}
        ],
        "tracking": {"preset": "aircraft", "time_interval": 1.0},
    }
    reports = []
    for scan in range(25):
        detections: list[dict[str, Any]] = []
        for index, truth in enumerate(_targets_2d(scan)):
            if rng.random() < 0.9:
                z = truth + rng.normal(0.0, 20.0, 2)
                entry: dict[str, Any] = {"z": z.tolist()}
                if index == 1:
                    entry["r"] = [[900.0, 100.0], [100.0, 600.0]]
                detections.append(entry)
        for _ in range(int(rng.integers(0, 3))):
            detections.append({"z": rng.uniform(-10000.0, 10000.0, 2).tolist()})
        reports.append({"sensor": "cam", "time": float(scan), "detections": detections})
    return config, reports


def _polar(offset: np.ndarray, velocity: np.ndarray | None = None) -> dict[str, float]:
    """Range, azimuth (clockwise from north), elevation (3-D) and range-rate of an ENU offset."""
    east, north = float(offset[0]), float(offset[1])
    up = float(offset[2]) if len(offset) == 3 else 0.0
    rho = math.sqrt(east**2 + north**2 + up**2)
    entry = {"range": rho, "azimuth_deg": math.degrees(math.atan2(east, north))}
    if len(offset) == 3:
        entry["elevation_deg"] = math.degrees(math.atan2(up, math.hypot(east, north)))
    if velocity is not None:
        entry["range_rate"] = float(np.dot(offset, velocity) / rho)
    return entry


def polar_2d() -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """A planar radar at a session-frame site with range-rate; noisy polar detections."""
    rng = np.random.default_rng(26)
    site = np.array([1000.0, -500.0])
    config = {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "sensors": [
            {
                "id": "radar",
                "site": {"position": site.tolist()},
                "measurement": {
                    "kind": "polar",
                    "sigma_range": 20.0,
                    "sigma_azimuth_deg": 0.2,
                    "sigma_range_rate": 1.0,
                },
            }
        ],
    }
    velocities = np.array([[120.0, -40.0], [-90.0, 70.0], [10.0, -150.0]])
    reports = []
    for scan in range(25):
        detections = []
        for truth, velocity in zip(_targets_2d(scan), velocities, strict=True):
            entry = _polar(truth - site, velocity)
            entry["range"] += float(rng.normal(0.0, 20.0))
            entry["azimuth_deg"] += float(rng.normal(0.0, 0.2))
            entry["range_rate"] += float(rng.normal(0.0, 1.0))
            if scan % 7 == 3:
                del entry["range_rate"]  # a detection without its Doppler
            detections.append(entry)
        reports.append({"sensor": "radar", "time": float(scan), "detections": detections})
    return config, reports


def _geodetic_targets(scan: float) -> tuple[np.ndarray, np.ndarray]:
    """Two aircraft in the origin's ENU frame (m) and their velocities (m/s)."""
    velocities = np.array([[150.0, -60.0, 0.0], [-120.0, -100.0, 5.0]])
    starts = np.array([[12000.0, 16000.0, 3000.0], [30000.0, 25000.0, 6000.0]])
    return starts + scan * velocities, velocities


def geodetic_3d(*, central: bool) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """Two 3-D radars with range-rate at geodetic sites of a session with a WGS84 origin;
    ``central``: tracked together (with one report late, reordered), else each on its own."""
    rng = np.random.default_rng(27 if central else 28)
    lat0, lon0, alt0 = ORIGIN
    sites = {"north": (52.2, 4.1, 40.0), "west": (51.9, 3.7, 15.0)}
    measurement = {
        "kind": "polar",
        "sigma_range": 25.0,
        "sigma_azimuth_deg": 0.15,
        "sigma_elevation_deg": 0.25,
        "sigma_range_rate": 2.0,
    }
    config = {
        "origin": {"lat": lat0, "lon": lon0, "alt": alt0},
        "state": {"dim": 6, "position": [0, 2, 4], "velocity": [1, 3, 5]},
        "sensors": [
            {
                "id": name,
                "site": {"lat": lat, "lon": lon, "alt": alt},
                "measurement": measurement,
                "local_tracker": not central,
            }
            for name, (lat, lon, alt) in sites.items()
        ],
    }
    reports = []
    for scan in range(20):
        for order, (name, (lat, lon, alt)) in enumerate(sites.items()):
            time = scan + 0.5 * order
            positions, velocities = _geodetic_targets(time)
            detections = []
            for position, velocity in zip(positions, velocities, strict=True):
                # the target as seen from the site: its ENU offset and velocity in the site's axes
                target = pymap3d.enu2geodetic(*position, lat0, lon0, alt0)
                offset = np.array(pymap3d.geodetic2enu(*target, lat, lon, alt))
                turned = np.array(
                    pymap3d.ecef2enuv(*pymap3d.enu2uvw(*velocity, lat0, lon0), lat, lon)
                )
                entry = _polar(offset, turned)
                entry["range"] += float(rng.normal(0.0, 25.0))
                entry["azimuth_deg"] += float(rng.normal(0.0, 0.15))
                entry["elevation_deg"] += float(rng.normal(0.0, 0.25))
                entry["range_rate"] += float(rng.normal(0.0, 2.0))
                detections.append(entry)
            reports.append({"sensor": name, "time": time, "detections": detections})
    if central:  # one report two scans late: the reorder buffer puts it in its place
        late = reports.pop(10)
        reports.insert(13, late)
    return config, reports


def geodetic_3d_local() -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """Two 3-D radars each on its own tracker."""
    return geodetic_3d(central=False)


def geodetic_3d_central() -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """Two 3-D radars tracked together, one report late."""
    return geodetic_3d(central=True)


Scene = Callable[[], tuple[dict[str, Any], list[dict[str, Any]]]]
SCENES: dict[str, Scene] = {
    "linear_2d": linear_2d,
    "polar_2d": polar_2d,
    "geodetic_3d_local": geodetic_3d_local,
    "geodetic_3d_central": geodetic_3d_central,
}


def hashes() -> Iterator[tuple[str, dict[str, str]]]:
    """Every scene's hashes."""
    for name, scene in SCENES.items():
        yield name, run(*scene())


if __name__ == "__main__":
    for name, digests in hashes():
        print(f"{name!r}: {digests!r},")
