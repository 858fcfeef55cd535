"""Checks of an input against its session's configuration (no engine needed).

Each function returns every problem found, located relative to the input's
body, so the service can answer one 422 that lists them all.
"""

from __future__ import annotations

from api_schemas.classification import ClassEvidence
from api_schemas.config import PolarMeasurement, SessionConfig
from api_schemas.issues import FieldIssue, Location
from api_schemas.reports import DetectionReport, PolarDetection, TrackReport


def _sensor_issues(sensor: str, config: SessionConfig) -> list[FieldIssue]:
    if not config.sensors or config.sensor(sensor) is not None:
        return []
    known = ", ".join(repr(entry.id) for entry in config.sensors)
    return [FieldIssue(("sensor",), f"unknown sensor {sensor!r} (configured: {known})", sensor)]


def _class_issues(
    evidence: ClassEvidence | None, config: SessionConfig, loc: Location
) -> list[FieldIssue]:
    if evidence is None:
        return []
    frame = set(config.classes)
    if not frame:
        return [FieldIssue(loc, "the session has no class frame ('classes' is empty)", None)]
    issues: list[FieldIssue] = []
    if evidence.mass is not None:
        for focal_index, focal in enumerate(evidence.mass):
            for label_index, label in enumerate(focal.set):
                if label not in frame:
                    issues.append(
                        FieldIssue(
                            (*loc, "mass", focal_index, "set", label_index),
                            f"unknown class {label!r} (frame: {', '.join(config.classes)})",
                            label,
                        )
                    )
    for label in sorted(set(evidence.likelihoods or {}) - frame):
        issues.append(
            FieldIssue(
                (*loc, "likelihoods", label),
                f"unknown class {label!r} (frame: {', '.join(config.classes)})",
                label,
            )
        )
    return issues


def track_report_issues(report: TrackReport, config: SessionConfig) -> list[FieldIssue]:
    """Problems of a track list under ``config``: sensor, state dimension, class labels."""
    issues = _sensor_issues(report.sensor, config)
    issues.extend(_frame_issues(report, config))
    dim = config.state.dim
    for index, track in enumerate(report.tracks):
        if len(track.state) != dim:
            issues.append(
                FieldIssue(
                    ("tracks", index, "state"),
                    f"state has {len(track.state)} components, the session's state dim is {dim}",
                    track.state,
                )
            )
        elif report.frame == "geodetic":
            issues.extend(_geodetic_state_issues(track.state, config, index))
        issues.extend(
            _class_issues(track.classification, config, ("tracks", index, "classification"))
        )
    return issues


def _frame_issues(report: TrackReport, config: SessionConfig) -> list[FieldIssue]:
    """A geodetic report needs the origin; a sensor-frame report a configured sensor (whose
    geodetic site has the session's origin: :class:`SessionConfig` refuses one without)."""
    if report.frame == "geodetic":
        if config.origin is None:
            return [
                FieldIssue(
                    ("frame",), "the session has no 'origin': geodetic tracks need one", "geodetic"
                )
            ]
        if len(config.state.position) < 2:
            return [FieldIssue(("frame",), "geodetic tracks need 2 or 3 positions", "geodetic")]
    if report.frame == "sensor":
        sensor = config.sensor(report.sensor)
        if sensor is None:
            return [
                FieldIssue(
                    ("frame",),
                    f"sensor {report.sensor!r} is not configured: its frame is unknown",
                    "sensor",
                )
            ]
    return []


def _geodetic_state_issues(
    state: list[float], config: SessionConfig, index: int
) -> list[FieldIssue]:
    """Latitude in [−90, 90] and longitude in [−180, 180] of a geodetic track's state."""
    if config.origin is None or len(config.state.position) < 2:
        return []
    issues: list[FieldIssue] = []
    latitude, longitude = config.state.position[0], config.state.position[1]
    for component, limit, name in ((latitude, 90.0, "latitude"), (longitude, 180.0, "longitude")):
        if not -limit <= state[component] <= limit:
            issues.append(
                FieldIssue(
                    ("tracks", index, "state", component),
                    f"{name} {state[component]!r} is outside [-{limit:g}, {limit:g}]",
                    state[component],
                )
            )
    return issues


def detection_report_issues(report: DetectionReport, config: SessionConfig) -> list[FieldIssue]:
    """Problems of a detection batch under ``config``: sensor, measurement size, noise, labels."""
    issues = _sensor_issues(report.sensor, config)
    measured = len(config.state.position)
    sensor = config.sensor(report.sensor)
    has_sensor_noise = sensor is not None and sensor.measurement is not None
    polar_sensor = sensor is not None and isinstance(sensor.measurement, PolarMeasurement)
    for index, detection in enumerate(report.detections):
        if isinstance(detection, PolarDetection):
            issues.extend(_polar_issues(detection, polar_sensor, measured, report.sensor, index))
        elif polar_sensor:
            issues.append(
                FieldIssue(
                    ("detections", index, "z"),
                    f"sensor {report.sensor!r} is polar: give range and azimuth_deg, not z",
                    detection.z,
                )
            )
        elif len(detection.z) != measured:
            issues.append(
                FieldIssue(
                    ("detections", index, "z"),
                    f"z has {len(detection.z)} components, the session measures {measured} positions",
                    detection.z,
                )
            )
        elif detection.r is None and not has_sensor_noise:
            issues.append(
                FieldIssue(
                    ("detections", index, "r"),
                    f"no noise: give 'r' here or 'measurement.r' for sensor {report.sensor!r}",
                    None,
                )
            )
        loc = ("detections", index, "classification")
        issues.extend(_class_issues(detection.classification, config, loc))
        if detection.classification is not None and config.tracking.preset is None:
            issues.append(
                FieldIssue(
                    loc,
                    "class evidence on detections joins the local tracks' classification, "
                    "which needs 'tracking.preset'",
                    None,
                )
            )
    return issues


def _polar_issues(
    detection: PolarDetection, polar_sensor: bool, measured: int, sensor: str, index: int
) -> list[FieldIssue]:
    """A polar detection only from a polar sensor, with an elevation exactly in 3-D."""
    if not polar_sensor:
        return [
            FieldIssue(
                ("detections", index, "range"),
                f"a polar detection from sensor {sensor!r}, whose measurement is not polar",
                detection.range,
            )
        ]
    if measured == 3 and detection.elevation_deg is None:
        return [
            FieldIssue(
                ("detections", index, "elevation_deg"),
                "a 3-D session needs elevation_deg on every polar detection",
                None,
            )
        ]
    if measured == 2 and detection.elevation_deg is not None:
        return [
            FieldIssue(
                ("detections", index, "elevation_deg"),
                "a 2-D session takes no elevation_deg",
                detection.elevation_deg,
            )
        ]
    return []
