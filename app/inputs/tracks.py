"""The ``tracks`` input kind: a sensor's track list (``POST …/tracks``, WebSocket ``tracks``).

Its tracks go to track-to-track fusion ([T2T]) in the session frame: a
``"sensor"`` or ``"geodetic"`` report is turned into it first, the whole
report in one vectorised pass (:mod:`app.geo.geodesy`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from api_schemas.config import SessionConfig
from api_schemas.consistency import track_report_issues
from api_schemas.events import TracksEvent
from api_schemas.examples import TRACK_REPORT_EXAMPLES
from api_schemas.issues import FieldIssue
from api_schemas.reports import SensorTrack, TrackReport
from api_schemas.timing import seconds
from api_schemas.ws import TracksMessage
from app.geo.geodesy import geodetic_to_session, sensor_to_session
from app.inputs.base import InputKind
from app.sessions.translate import (
    class_frame,
    class_likelihoods,
    class_mass,
    sensor_site,
    session_origin,
)
from core.belief import Frame
from core.fusion.engine import SessionEngine
from core.fusion.reports import ReportedTrack, StepResult
from core.fusion.reports import TrackReport as CoreTrackReport


class Tracks(InputKind[TrackReport]):
    """A sensor's track list at one time."""

    tag = "tracks"
    examples = TRACK_REPORT_EXAMPLES
    report_model = TrackReport
    message_model = TracksMessage
    event_model = TracksEvent
    summary = "A sensor's track list; answered by one `result` (or `error`)."

    description = """One sensor's track list → the fused result of that step (acknowledged once logged).

    409 ``stale-report`` (with ``time`` and ``last_time``) for a report not
    newer than the sensor's previous one.
    """

    def sensor(self, report: TrackReport) -> str:
        return report.sensor

    def items(self, report: TrackReport) -> int:
        return len(report.tracks)

    def issues(self, report: TrackReport, config: SessionConfig) -> list[FieldIssue]:
        return track_report_issues(report, config)

    def run(
        self, engine: SessionEngine, report: TrackReport, config: SessionConfig, explain: bool
    ) -> StepResult:
        return engine.apply(session_frame_report(report, config), explain=explain)


def reported_track(track: SensorTrack, frame: Frame | None) -> ReportedTrack:
    """One sensor track for the engine."""
    evidence = track.classification
    mass = likelihoods = None
    if evidence is not None and frame is not None:
        if evidence.mass is not None:
            mass = class_mass(evidence, frame)
        else:
            likelihoods = class_likelihoods(evidence, frame)
    return ReportedTrack(
        id=track.id,
        state=np.asarray(track.state, dtype=np.float64),
        covariance=np.asarray(track.covariance, dtype=np.float64),
        class_mass=mass,
        class_likelihoods=likelihoods,
        coasted=track.coasted,
    )


def core_track_report(report: TrackReport, frame: Frame | None) -> CoreTrackReport:
    """A sensor's track list for the engine."""
    return CoreTrackReport(
        sensor=report.sensor,
        time=seconds(report.time),
        tracks=tuple(reported_track(track, frame) for track in report.tracks),
    )


def session_frame_report(report: TrackReport, config: SessionConfig) -> CoreTrackReport:
    """A track list for the engine in the session frame, whatever its ``frame``.

    ``"sensor"``: turned by the sensor's heading and moved to its site;
    ``"geodetic"``: lat/lon/alt to session ENU, velocities and covariance
    turned between the tangent planes (:mod:`app.geo.geodesy`). States and
    covariances of the whole report are converted in one vectorised pass.
    """
    core = core_track_report(report, class_frame(config.classes))
    if report.frame == "session" or not core.tracks:
        return core
    dim = config.state.dim
    states = np.array([track.state for track in core.tracks]).reshape(-1, dim)
    covariances = np.array([track.covariance for track in core.tracks]).reshape(-1, dim, dim)
    position, velocity = tuple(config.state.position), tuple(config.state.velocity)
    acceleration = tuple(config.state.acceleration)
    if report.frame == "sensor":
        site, heading = sensor_site(config.sensor(report.sensor), session_origin(config))
        states, covariances = sensor_to_session(
            states, covariances, position, velocity, site, heading, acceleration
        )
    else:
        frame = session_origin(config)
        assert frame is not None  # checked against the config before
        states, covariances = geodetic_to_session(
            frame, states, covariances, position, velocity, acceleration
        )
    tracks = tuple(
        dataclasses.replace(track, state=state, covariance=covariance)
        for track, state, covariance in zip(core.tracks, states, covariances, strict=True)
    )
    return dataclasses.replace(core, tracks=tracks)
