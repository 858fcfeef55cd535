"""The ``detections`` input kind: a sensor's detections (``POST …/detections``, WebSocket
``detections``), for the session's local tracker of that sensor.

Cartesian detections give ``z`` (and optionally their own ``r``); a polar
sensor's give range and azimuth (and elevation in 3-D), which its measurement
model (:mod:`core.models.measurement`) converts to positions with each
detection's own covariance.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from api_schemas.config import (
    CartesianMeasurement,
    SessionConfig,
)
from api_schemas.consistency import detection_report_issues
from api_schemas.events import DetectionsEvent
from api_schemas.examples import DETECTION_REPORT_EXAMPLES
from api_schemas.issues import FieldIssue
from api_schemas.reports import CartesianDetection, DetectionReport, PolarDetection
from api_schemas.timing import seconds
from api_schemas.ws import DetectionsMessage
from app.inputs.base import InputKind
from app.sessions.translate import class_frame, evidence_mass
from core.fusion.config import FusionConfig
from core.fusion.engine import SessionEngine
from core.fusion.reports import DetectionReport as CoreDetectionReport
from core.fusion.reports import StepResult
from core.models.measurement import MeasurementModel, Polar


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
        return engine.apply_detections(
            core_detection_report(report, config, engine.config), explain=explain
        )


def polar_detection_report(report: DetectionReport, model: Polar) -> CoreDetectionReport:
    """A polar sensor's detections, measured by its model (radians; NaN: no range-rate),
    converted by it to positions, each with its own covariance (:mod:`core.models`)."""
    detections = [d for d in report.detections if isinstance(d, PolarDetection)]
    assert len(detections) == len(report.detections)  # checked against the config before
    columns: list[list[float | None]] = [[d.range for d in detections]]
    columns.append([d.azimuth_deg for d in detections])
    if len(model.mapping) == 3:
        columns.append([d.elevation_deg for d in detections])
    measurements = np.array(columns, dtype=np.float64).T.reshape(-1, len(columns))
    measurements[:, 1:] = np.radians(measurements[:, 1:])
    if model.velocity_mapping is not None:
        rates = [math.nan if d.range_rate is None else d.range_rate for d in detections]
        measurements = np.column_stack([measurements, np.array(rates, dtype=np.float64)])
    return CoreDetectionReport.measured(report.sensor, seconds(report.time), model, measurements)


def core_detection_report(
    report: DetectionReport, config: SessionConfig, engine_config: FusionConfig
) -> CoreDetectionReport:
    """Wire detections as the core's: measurements (m × q), one R per detection when any
    gives its own ``r`` (the sensor's ``measurement.r`` for the others), and the class
    evidence of those that give it (a mass each on the session's class frame). They carry
    their sensor's measurement model, the one of its entry in ``engine_config`` (built with
    it, :func:`app.sessions.translate.sensor_spec`)."""
    model = next((s.model for s in engine_config.sensors if s.id == report.sensor), None)
    core = _measured(report, config, model)
    frame = class_frame(config.classes)
    if frame is None or all(d.classification is None for d in report.detections):
        return core
    masses = tuple(
        None if d.classification is None else evidence_mass(d.classification, frame)
        for d in report.detections
    )
    return dataclasses.replace(core, class_masses=masses)


def _measured(
    report: DetectionReport, config: SessionConfig, model: MeasurementModel | None
) -> CoreDetectionReport:
    """The detections' measurements and noises for the core, measured by ``model``."""
    sensor = config.sensor(report.sensor)
    if isinstance(model, Polar):
        return polar_detection_report(report, model)
    detections = [d for d in report.detections if isinstance(d, CartesianDetection)]
    assert len(detections) == len(report.detections)  # checked against the config before
    dim = len(detections[0].z) if detections else 2
    measurements = np.array([d.z for d in detections], dtype=np.float64).reshape(-1, dim)
    noise = None if sensor is None else sensor.measurement
    covariances = None
    if any(detection.r is not None for detection in detections):
        default = noise.r if isinstance(noise, CartesianMeasurement) else None
        covariances = np.array(
            [detection.r if detection.r is not None else default for detection in detections],
            dtype=np.float64,
        )
    if model is None:
        return CoreDetectionReport(report.sensor, seconds(report.time), measurements, covariances)
    return CoreDetectionReport.measured(
        report.sensor, seconds(report.time), model, measurements, covariances
    )
