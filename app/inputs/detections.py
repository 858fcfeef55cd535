"""The ``detections`` input kind: a sensor's detections (``POST …/detections``, WebSocket
``detections``), for the session's local tracker of that sensor.

Cartesian detections give ``z`` (and optionally their own ``r``); a polar
sensor's give range and azimuth (and elevation in 3-D), converted here to
positions with each detection's own covariance (:mod:`app.geo.polar`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from api_schemas.config import (
    CartesianMeasurement,
    PolarMeasurement,
    SensorConfig,
    SessionConfig,
)
from api_schemas.consistency import detection_report_issues
from api_schemas.events import DetectionsEvent
from api_schemas.examples import DETECTION_REPORT_EXAMPLES
from api_schemas.issues import FieldIssue
from api_schemas.reports import CartesianDetection, DetectionReport, PolarDetection
from api_schemas.timing import seconds
from api_schemas.ws import DetectionsMessage
from app.geo.geodesy import LocalFrame, rotate_covariances
from app.geo.polar import polar_to_cartesian
from app.inputs.base import InputKind
from app.sessions.translate import class_frame, evidence_mass, sensor_site, session_origin
from core.fusion.engine import SessionEngine
from core.fusion.reports import DetectionReport as CoreDetectionReport
from core.fusion.reports import StepResult


class Detections(InputKind[DetectionReport]):
    """A sensor's detections at one time."""

    tag = "detections"
    examples = DETECTION_REPORT_EXAMPLES
    report_model = DetectionReport
    message_model = DetectionsMessage
    event_model = DetectionsEvent
    summary = "A sensor's detections; answered by one `result` (or `error`)."

    description = """One sensor's detections → the fused result of that step.

    The session's local tracker for that sensor (configured by its
    ``measurement`` model and ``tracking``) updates its tracks; its confirmed
    tracks updated by this scan enter the fusion step like a track list.
    409 ``stale-report`` when the batch is not newer than the sensor's
    previous input (scans may come at any increasing times, on no grid);
    422 for a sensor without a measurement model.
    """

    def sensor(self, report: DetectionReport) -> str:
        return report.sensor

    def items(self, report: DetectionReport) -> int:
        return len(report.detections)

    def issues(self, report: DetectionReport, config: SessionConfig) -> list[FieldIssue]:
        return detection_report_issues(report, config)

    def run(
        self, engine: SessionEngine, report: DetectionReport, config: SessionConfig, explain: bool
    ) -> StepResult:
        return engine.apply_detections(core_detection_report(report, config), explain=explain)


def site_axes(sensor: SensorConfig, origin: LocalFrame | None, dimension: int) -> np.ndarray | None:
    """Rotation (d × d) from the ENU axes at a geodetic site to the session's at ``origin``
    (``None`` at a session-frame ``position``: the sensor measures in the session's axes)."""
    site = sensor.site
    if site is None or site.lat is None or site.lon is None or origin is None:
        return None
    rotation: np.ndarray = origin.rotation_from(site.lat, site.lon)[0][:dimension, :dimension]
    return rotation


def polar_detection_report(
    report: DetectionReport, config: SessionConfig, sensor: SensorConfig
) -> CoreDetectionReport:
    """A polar sensor's detections as converted positions, each with its own covariance.

    Azimuth and elevation are measured in the site's own ENU axes: at a
    geodetic site the converted offsets and covariances are turned into the
    session's axes (``R_origin R_siteᵀ``, exact: :mod:`app.geo.geodesy`); the
    tilt between the two planes is 0.009° per km from the origin.
    """
    noise = sensor.measurement
    assert isinstance(noise, PolarMeasurement)
    dim = len(config.state.position)
    origin = session_origin(config)  # once, for the site and its axes
    site, _ = sensor_site(sensor, origin)
    detections = [d for d in report.detections if isinstance(d, PolarDetection)]
    assert len(detections) == len(report.detections)  # checked against the config before
    ranges = np.array([d.range for d in detections], dtype=np.float64)
    azimuths = np.array([d.azimuth_deg for d in detections], dtype=np.float64)
    elevations = (
        np.array([d.elevation_deg for d in detections], dtype=np.float64) if dim == 3 else None
    )
    offsets, covariances = polar_to_cartesian(
        ranges,
        azimuths,
        noise.polar_sigmas,
        np.zeros(dim),
        elevations,
        noise.sigma_elevation_deg,
    )
    offsets, covariances = offsets.reshape(-1, dim), covariances.reshape(-1, dim, dim)
    turn = site_axes(sensor, origin, dim)
    if turn is not None:
        offsets = offsets @ turn.T
        covariances = rotate_covariances(np.broadcast_to(turn, covariances.shape), covariances)
    range_rates = None
    if noise.sigma_range_rate is not None and any(d.range_rate is not None for d in detections):
        range_rates = np.array(
            [math.nan if d.range_rate is None else d.range_rate for d in detections],
            dtype=np.float64,
        )
    return CoreDetectionReport(
        report.sensor, seconds(report.time), offsets + site[:dim], covariances, range_rates
    )


def core_detection_report(report: DetectionReport, config: SessionConfig) -> CoreDetectionReport:
    """Wire detections as the core's: measurements (m × q), one R per detection when any
    gives its own ``r`` (the sensor's ``measurement.r`` for the others), and the class
    evidence of those that give it (a mass each on the session's class frame)."""
    core = _measured(report, config)
    frame = class_frame(config.classes)
    if frame is None or all(d.classification is None for d in report.detections):
        return core
    masses = tuple(
        None if d.classification is None else evidence_mass(d.classification, frame)
        for d in report.detections
    )
    return dataclasses.replace(core, class_masses=masses)


def _measured(report: DetectionReport, config: SessionConfig) -> CoreDetectionReport:
    """The detections' measurements and noises for the core."""
    sensor = config.sensor(report.sensor)
    if sensor is not None and isinstance(sensor.measurement, PolarMeasurement):
        return polar_detection_report(report, config, sensor)
    detections = [d for d in report.detections if isinstance(d, CartesianDetection)]
    assert len(detections) == len(report.detections)  # checked against the config before
    dim = len(detections[0].z) if detections else 2
    measurements = np.array([d.z for d in detections], dtype=np.float64).reshape(-1, dim)
    if all(detection.r is None for detection in detections):
        return CoreDetectionReport(report.sensor, seconds(report.time), measurements, None)
    noise = None if sensor is None else sensor.measurement
    default = noise.r if isinstance(noise, CartesianMeasurement) else None
    covariances = np.array(
        [detection.r if detection.r is not None else default for detection in detections],
        dtype=np.float64,
    )
    return CoreDetectionReport(report.sensor, seconds(report.time), measurements, covariances)
