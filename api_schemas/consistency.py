"""Checks of an input against its session's configuration (no engine needed).

Each function returns every problem found, located relative to the input's
body, so the service can answer one 422 that lists them all.
"""

from __future__ import annotations

from api_schemas.classification import ClassEvidence
from api_schemas.config import SessionConfig
from api_schemas.issues import FieldIssue, Location
from api_schemas.reports import DetectionReport, TrackReport


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
        issues.extend(
            _class_issues(track.classification, config, ("tracks", index, "classification"))
        )
    return issues


def detection_report_issues(report: DetectionReport, config: SessionConfig) -> list[FieldIssue]:
    """Problems of a detection batch under ``config``: sensor, measurement size, noise, labels."""
    issues = _sensor_issues(report.sensor, config)
    measured = len(config.state.position)
    sensor = config.sensor(report.sensor)
    has_sensor_noise = sensor is not None and sensor.measurement is not None
    for index, detection in enumerate(report.detections):
        if len(detection.z) != measured:
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
        issues.extend(
            _class_issues(detection.classification, config, ("detections", index, "classification"))
        )
    return issues
