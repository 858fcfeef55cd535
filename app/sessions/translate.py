"""Translation between the wire models (:mod:`api_schemas`) and the session engine (:mod:`core`).

Config: :func:`fusion_config` turns a validated ``SessionConfig`` into the
engine's ``FusionConfig``; what the core still refuses (a self-intersecting
field-of-view polygon) comes back as a validation error located at the field.
Inputs: :func:`core_track_report`. Outputs: the one writer of the
contract's result shape (:mod:`api_schemas.results` documents it, and
``tests/api/test_result_writer.py`` validates its output against those
models): :func:`step_json` for a step result (the per-input hot path),
:func:`picture_json` for fused tracks (``GET …/tracks``), both written by
orjson in C straight from the engine's views (numpy arrays and ``Source``
dataclasses, no intermediate lists); every non-finite score of a matrix is
``null``, any other non-finite number refused.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Iterator, Sequence
from typing import Any

import numpy as np
import orjson

from api_schemas.associate import AssociateRequest
from api_schemas.association import AssociationOptions
from api_schemas.classification import ClassEvidence
from api_schemas.config import (
    MeasurementModel,
    PolygonFieldOfView,
    SectorFieldOfView,
    SensorConfig,
    SessionConfig,
    TrackThresholds,
    TwoPointInitiation,
)
from api_schemas.issues import FieldIssue
from api_schemas.reports import DetectionReport, SensorTrack, TrackReport
from app.geo.geodesy import (
    LocalFrame,
    geodetic_to_session,
    heading_rotation,
    rotate_covariances,
    sensor_to_session,
)
from app.geo.geojson import GeodeticOutput, feature_collection
from app.geo.polar import polar_to_cartesian
from app.http.errors import request_validation_error
from app.http.responses import itemwise
from core.association import AssociationResult
from core.belief import Frame, MassFunction
from core.errors import InvalidInput, TotalConflict
from core.fusion.classes import ClassAssessment, accumulate_likelihoods
from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.motion import MotionKind, MotionModel, StateLayout
from core.fusion.reports import (
    AssociationView,
    FusedTrackView,
    ReportedTrack,
    StepResult,
)
from core.fusion.reports import DetectionReport as CoreDetectionReport
from core.fusion.reports import TrackReport as CoreTrackReport
from core.fusion.state import StateFusion
from core.geometry import FieldOfView, PolygonView, Sector
from core.lifecycle import LifeCycleConfig
from core.tracking.config import DEFAULT_IMM_DISTANCE, ClassificationOptions, LocalTrackerConfig
from core.tracking.models import LinearMeasurementModel, ModelBank, constant_velocity
from core.tracking.presets import MIN_MANOEUVRE_DENSITY, preset
from core.tracking.range_rate import RangeRateModel

PlainObject = dict[str, Any]

ENGINE_ONLY_OPTIONS = frozenset({"distance", "imm_distance"})
"""Wire options that are not method options of the core (the distance is its own argument)."""


# ------------------------------------------------------------------ config
def class_frame(classes: Sequence[str]) -> Frame | None:
    """The class frame of a session (``None`` without classes)."""
    return Frame(list(classes)) if classes else None


def field_of_view(
    fov: SectorFieldOfView | PolygonFieldOfView,
    site: np.ndarray | None = None,
    heading_deg: float = 0.0,
) -> FieldOfView:
    """A field of view as core geometry in the session frame.

    One given in the sensor's frame (``frame: "sensor"``) is moved to its
    ``site`` and turned by its heading (the sensor frame of
    :func:`~app.geo.geodesy.sensor_to_session`): a point ``p`` goes to
    ``site + H p``, a sector's axis (counter-clockwise from +x) turns by
    −heading (the heading is clockwise from north).
    """
    relative = fov.frame == "sensor"
    place = np.zeros(2) if site is None or not relative else np.asarray(site[:2], dtype=float)
    turn = heading_rotation(heading_deg if relative else 0.0, 2)
    if isinstance(fov, SectorFieldOfView):
        apex = place + turn @ np.asarray(fov.origin or (0.0, 0.0), dtype=np.float64)
        return Sector(
            origin=(float(apex[0]), float(apex[1])),
            heading_deg=fov.heading_deg - (heading_deg if relative else 0.0),
            half_angle_deg=fov.half_angle_deg,
            range_min=fov.range[0],
            range_max=fov.range[1],
        )
    vertices = place + np.asarray(fov.vertices, dtype=np.float64)[:, :2] @ turn.T
    return PolygonView(vertices=tuple((float(x), float(y)) for x, y in vertices.tolist()))


def sensor_spec(sensor: SensorConfig, index: int, config: SessionConfig) -> SensorSpec:
    """One sensor; a field of view the core refuses is a validation error at ``sensors/i/fov``.
    A field of view in the sensor's frame is placed at its site and heading here, once."""
    try:
        site, heading = sensor_site(sensor, session_origin(config))
        fov = None if sensor.fov is None else field_of_view(sensor.fov, site, heading)
    except InvalidInput as error:
        raise request_validation_error(
            [FieldIssue(("sensors", index, "fov"), str(error), None)]
        ) from None
    tracker = local_tracker_config(config, sensor, fov)
    if tracker is not None:
        confirmable(tracker, sensor, index)
    return SensorSpec(
        id=sensor.id,
        reliability=sensor.reliability,
        p_detect=sensor.p_detect,
        fov=fov,
        tracker=tracker,
    )


def confirmable(tracker: LocalTrackerConfig, sensor: SensorConfig, index: int) -> None:
    """Refuse (a validation error at the density) a sensor whose tracks can never be confirmed.

    A hit adds ``ΔL = ln[P_D / ((2π)^{q/2} β_FT √|S|)] − D/2`` ([MTT] §4.3) and S is at
    least the detections' R: when even a detection exactly at the prediction (D = 0,
    S = R) lowers the score, no run of detections ever confirms a track. Checked where
    R is one matrix (``measurement.r``) and β_FT is known (given, or the paper profile's);
    a polar sensor's R shrinks near its site and an estimated β_FT follows the data.
    """
    clutter = tracker.physics(sensor.id)[1]
    if clutter is None or sensor.measurement is None or sensor.measurement.r is None:
        return
    r = np.asarray(tracker.model_bank().measurement.noise_covariance, dtype=np.float64)
    q = r.shape[0]
    best = tracker.life_cycle.scan_score(sensor.p_detect, clutter).hit_increment(
        np.zeros(1), np.array([np.linalg.slogdet(r)[1]]), q
    )[0]
    if best > 0.0:
        return
    unit = "m²" if q == 2 else ("m³" if q == 3 else "m")
    field = "clutter_density" if sensor.clutter_density is not None else None
    location: tuple[str | int, ...] = (
        ("sensors", index, field) if field is not None else ("tracking", "profile")
    )
    message = (
        f"no track of sensor {sensor.id!r} can ever be confirmed: at a clutter density of "
        f"{clutter:.3g} per {unit} per scan, a detection exactly where a track predicts it "
        f"(noise r, P_D {sensor.p_detect:g}) is {math.exp(-best):.3g} times as likely clutter "
        f"as target (hit score {best:.3g} ≤ 0). Fix: give clutter_density per {unit} per "
        "scan (false alarms per scan divided by the covered area), or leave it out to have "
        "it estimated from the sensor's detections"
    )
    raise request_validation_error([FieldIssue(location, message, clutter)])


def local_tracker_config(
    config: SessionConfig, sensor: SensorConfig, fov: FieldOfView | None
) -> LocalTrackerConfig | None:
    """The local tracker of a sensor that sends detections (it has a measurement model)."""
    if sensor.measurement is None:
        return None
    tracking = config.tracking
    interval = tracking.time_interval
    axes = len(config.state.position)
    r = (
        polar_reference_noise(sensor.measurement, fov, axes)
        if sensor.measurement.r is None
        else tuple(tuple(float(x) for x in row) for row in sensor.measurement.r)
    )
    bank = None
    if tracking.preset is None:
        # one constant-velocity model, Q of motion.q's continuous white-noise form
        bank = ModelBank(
            models=(
                constant_velocity(interval, motion_density(config), axes=axes, noise="continuous"),
            ),
            measurement=LinearMeasurementModel.position(1.0, 2 * axes),
            mode_transition=np.ones((1, 1)),
        )
    options = tracking.association.options
    thresholds = tracking.thresholds
    initiation = tracking.initiation
    return LocalTrackerConfig(
        preset=tracking.preset or "aircraft",
        time_interval=interval,
        axes=axes if tracking.preset is not None else 2,
        bank=bank,
        measurement_noise=r,
        association_method=tracking.association.method,
        association_options=method_options(options),
        imm_distance=options.imm_distance or DEFAULT_IMM_DISTANCE,
        p_detect=sensor.p_detect,
        life_cycle=life_cycle_config(
            thresholds,
            tracking.birth_density,
            clutter_density=sensor.clutter_density,
            paper=tracking.profile == "paper",
            dim=axes,
        ),
        initiation=initiation.kind,
        max_speed=(
            initiation.max_speed
            if isinstance(initiation, TwoPointInitiation)
            else LocalTrackerConfig.max_speed
        ),
        initial_velocity_std=initiation.velocity_std,
        range_rate=range_rate_model(config, sensor, axes),
        fields_of_view={sensor.id: fov},
        classification=ClassificationOptions() if config.classes else None,
        id_prefix=f"{sensor.id}:",
    )


def range_rate_model(
    config: SessionConfig, sensor: SensorConfig, axes: int
) -> RangeRateModel | None:
    """A polar sensor's range-rate model (its site, ``sigma_range_rate``), or None without σ:
    the detections' ``range_rate`` then stays unused."""
    noise = sensor.measurement
    if noise is None or noise.kind != "polar" or noise.sigma_range_rate is None:
        return None
    site, _ = sensor_site(sensor, session_origin(config))
    return RangeRateModel(tuple(float(x) for x in site[:axes]), noise.sigma_range_rate)


POLAR_REFERENCE_RANGE = 50_000.0
"""Range (m) of a polar sensor's reference noise when no sector field of view bounds it."""


def polar_reference_noise(
    noise: MeasurementModel, fov: FieldOfView | None, axes: int
) -> tuple[tuple[float, ...], ...]:
    """The R a polar sensor's tracker uses where a detection's own covariance is not passed.

    Every polar detection is gated, scored, updated and starts its tracks
    with its own converted covariance (:mod:`app.geo.polar`,
    :mod:`core.tracking.initiator`); the bank's R is left only where a
    track has no detection: the gate volume of a coasting track and the
    zero-step prediction of a second scan at the same time. That R is the
    largest converted noise over the sensor's coverage, isotropic:
    ``max(σ_ρ², (ρ_max σ_a)²)`` per axis, ``ρ_max`` the sector's far range or
    :data:`POLAR_REFERENCE_RANGE`, so a coasting track's gate is never
    smaller than its detections'.
    """
    far = fov.range_max if isinstance(fov, Sector) else POLAR_REFERENCE_RANGE
    sigma_range, sigma_azimuth_deg = noise.polar_sigmas
    sigmas = [sigma_range, far * math.radians(sigma_azimuth_deg)]
    if axes == 3 and noise.sigma_elevation_deg is not None:
        sigmas.append(far * math.radians(noise.sigma_elevation_deg))
    variance = max(sigmas) ** 2
    return tuple(
        tuple(variance if row == col else 0.0 for col in range(axes)) for row in range(axes)
    )


def life_cycle_config(
    thresholds: TrackThresholds,
    birth_density: float | None,
    clutter_density: float | None = None,
    *,
    paper: bool = False,
    dim: int = 2,
) -> LifeCycleConfig:
    """The life cycle of both layers from the wire thresholds and densities.

    A local tracker gets its sensor's ``clutter_density``; the fused layer,
    whose inputs are tracks and not detections, the default of its dimension.
    A ``null`` density stays None (the core estimates β_FT, or fills in
    :func:`~core.lifecycle.default_density` in the fused layer); ``paper``: the
    paper profile (:meth:`LifeCycleConfig.paper` of ``dim`` positions), whose
    unset densities are one per km^q.
    """
    values: dict[str, Any] = {
        "false_confirmation": thresholds.false_confirmation,
        "true_deletion": thresholds.true_deletion,
        "termination_probability": thresholds.termination_probability,
        "min_points": thresholds.min_points,
        "score_ceiling": thresholds.score_ceiling,
    }
    densities: dict[str, Any] = {
        "false_target_density": clutter_density,
        "new_target_density": birth_density,
    }
    if paper:
        given = {name: value for name, value in densities.items() if value is not None}
        return LifeCycleConfig.paper(dim, **values, **given)
    return LifeCycleConfig(**values, **densities)


def motion_density(config: SessionConfig) -> float:
    """The session's ``motion.q``; by default (``null``) the preset's manoeuvre density when
    the session tracks detections with a preset (:meth:`TrackingPreset.manoeuvre_density`:
    the fused layer then follows every manoeuvre of the bank), else
    :data:`~core.tracking.presets.MIN_MANOEUVRE_DENSITY`."""
    if config.motion.q is not None:
        return float(config.motion.q)
    detecting = any(sensor.measurement is not None for sensor in config.sensors)
    if config.tracking.preset is None or not detecting:
        return MIN_MANOEUVRE_DENSITY
    chosen = preset(config.tracking.preset, time_interval=config.tracking.time_interval)
    return chosen.manoeuvre_density()


def method_options(options: AssociationOptions) -> dict[str, object]:
    """The core method options of a resolved wire options object."""
    return {
        name: value
        for name, value in options.model_dump(exclude_none=True).items()
        if name not in ENGINE_ONLY_OPTIONS
    }


def fusion_config(config: SessionConfig, extra_sensors: Iterable[str] = ()) -> FusionConfig:
    """The engine configuration of a session.

    A session that configures no sensor accepts any sensor id: each one seen
    joins as ``extra_sensors`` (default reliability and P_D, seeing everywhere).
    """
    layout = StateLayout(
        dim=config.state.dim,
        position=tuple(config.state.position),
        velocity=tuple(config.state.velocity),
    )
    motion = MotionModel(
        layout=layout, kind=MotionKind(config.motion.model), q=motion_density(config)
    )
    sensors = [sensor_spec(sensor, index, config) for index, sensor in enumerate(config.sensors)]
    sensors += [SensorSpec(id=sensor_id) for sensor_id in extra_sensors]
    thresholds = config.tracking.thresholds
    association = config.association
    try:
        region = None if config.region is None else field_of_view(config.region)
    except InvalidInput as error:
        raise request_validation_error([FieldIssue(("region",), str(error), None)]) from None
    assert region is None or isinstance(region, PolygonView)
    return FusionConfig(
        region=region,
        motion=motion,
        sensors=tuple(sensors),
        classes=class_frame(config.classes),
        association_method=association.method,
        association_options=method_options(association.options),
        distance=association.options.distance or "sum",
        state_fusion=StateFusion(config.fusion.state),
        management=life_cycle_config(
            thresholds,
            config.tracking.birth_density,
            paper=config.tracking.profile == "paper",
            dim=len(config.state.position),
        ),
    )


# ------------------------------------------------------------------ inputs
def class_mass(evidence: ClassEvidence, frame: Frame) -> MassFunction:
    """Reported focal sets as a mass function on ``frame``."""
    assert evidence.mass is not None
    return MassFunction.from_sets(frame, [(focal.set, focal.mass) for focal in evidence.mass])


def class_likelihoods(evidence: ClassEvidence, frame: Frame) -> np.ndarray:
    """Reported likelihoods as an array in frame order (a class not named gets 1: no evidence)."""
    values = evidence.likelihoods or {}
    return np.array([values.get(label, 1.0) for label in frame.labels], dtype=np.float64)


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
    )


def core_track_report(report: TrackReport, frame: Frame | None) -> CoreTrackReport:
    """A sensor's track list for the engine."""
    return CoreTrackReport(
        sensor=report.sensor,
        time=report.time,
        tracks=tuple(reported_track(track, frame) for track in report.tracks),
    )


def session_origin(config: SessionConfig) -> LocalFrame | None:
    """The session's ENU frame at its WGS84 ``origin`` (``None`` without one)."""
    origin = config.origin
    return None if origin is None else LocalFrame(origin.lat, origin.lon, origin.alt)


def session_geodetic(config: SessionConfig) -> GeodeticOutput | None:
    """Geodetic positions of the session's tracks (``?frame=geodetic``; ``None`` without an
    ``origin``)."""
    frame = session_origin(config)
    return None if frame is None else GeodeticOutput(frame, tuple(config.state.position))


def sensor_site(sensor: SensorConfig | None, origin: LocalFrame | None) -> tuple[np.ndarray, float]:
    """A sensor's site in the session frame (3 coordinates; default the origin) and heading;
    ``origin`` is the session's (:func:`session_origin`: a geodetic site needs it)."""
    site = None if sensor is None else sensor.site
    if site is None:
        return np.zeros(3), 0.0
    if site.position is not None:
        position = np.zeros(3)
        position[: len(site.position)] = site.position
        return position, site.heading_deg
    assert origin is not None and site.lat is not None and site.lon is not None  # config-checked
    altitude = origin.alt if site.alt is None else site.alt
    return origin.from_geodetic(site.lat, site.lon, altitude)[0], site.heading_deg


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
    if report.frame == "sensor":
        site, heading = sensor_site(config.sensor(report.sensor), session_origin(config))
        states, covariances = sensor_to_session(
            states, covariances, position, velocity, site, heading
        )
    else:
        frame = session_origin(config)
        assert frame is not None  # checked against the config before
        states, covariances = geodetic_to_session(frame, states, covariances, position, velocity)
    tracks = tuple(
        dataclasses.replace(track, state=state, covariance=covariance)
        for track, state, covariance in zip(core.tracks, states, covariances, strict=True)
    )
    return dataclasses.replace(core, tracks=tracks)


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
    assert noise is not None
    dim = len(config.state.position)
    origin = session_origin(config)  # once, for the site and its axes
    site, _ = sensor_site(sensor, origin)
    detections = report.detections
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
        report.sensor, report.time, offsets + site[:dim], covariances, range_rates
    )


# ------------------------------------------------------------------ outputs
def core_detection_report(report: DetectionReport, config: SessionConfig) -> CoreDetectionReport:
    """Wire detections as the core's: measurements (m × q) and, when any detection gives its
    own ``r``, one R per detection (the sensor's ``measurement.r`` for the others)."""
    polar = config.sensor(report.sensor)
    if polar is not None and polar.measurement is not None and polar.measurement.kind == "polar":
        return polar_detection_report(report, config, polar)
    dim = len(report.detections[0].z or ()) if report.detections else 2
    measurements = np.array([d.z for d in report.detections], dtype=np.float64).reshape(-1, dim)
    if all(detection.r is None for detection in report.detections):
        return CoreDetectionReport(report.sensor, report.time, measurements, None)
    sensor = next((s for s in config.sensors if s.id == report.sensor), None)
    default = None if sensor is None or sensor.measurement is None else sensor.measurement.r
    covariances = np.array(
        [detection.r if detection.r is not None else default for detection in report.detections],
        dtype=np.float64,
    )
    return CoreDetectionReport(report.sensor, report.time, measurements, covariances)


def finite_or_none(value: float | None) -> float | None:
    """``value`` if it is a finite number, else ``None``."""
    return value if value is not None and math.isfinite(value) else None


def _check_finite(views: Sequence[FusedTrackView]) -> None:
    """Raise ``ValueError`` naming the first track with a non-finite state or covariance.

    One test over every track of the step (the arrays are small: per-track
    calls would cost more than the test); the culprit is looked for only then.
    """
    if not views:
        return
    states = np.concatenate([view.state for view in views])
    covariances = np.concatenate([view.covariance.ravel() for view in views])
    if np.isfinite(states).all() and np.isfinite(covariances).all():
        return
    for view in views:
        for what, values in (("state", view.state), ("covariance", view.covariance)):
            if not np.isfinite(values).all():
                raise ValueError(f"fused track {view.id!r}: non-finite {what}")


def _class_fast(assessment: ClassAssessment | None) -> PlainObject | None:
    """A track's classification in the contract's shape; a non-finite conflict raises.

    Under total conflict every distribution is ``None`` (only the state and the
    conflict are known).
    """
    if assessment is None:
        return None
    conflict = float(assessment.conflict)
    if not math.isfinite(conflict):
        raise ValueError("non-finite class conflict")
    mass = assessment.mass
    if mass is None:
        return {
            "state": assessment.state.value,
            "mass": None,
            "pignistic": None,
            "belief": None,
            "plausibility": None,
            "conflict": assessment.conflict,
            "decision": None,
            "decision_state": assessment.decision_state.value,
            "summarized": assessment.summarized,
        }
    labels = mass.frame.labels
    return {
        "state": assessment.state.value,
        "mass": [{"set": list(subset), "mass": value} for subset, value in mass.focal_sets()],
        "pignistic": dict(zip(labels, assessment.pignistic.tolist(), strict=True)),
        "belief": dict(zip(labels, assessment.belief.tolist(), strict=True)),
        "plausibility": dict(zip(labels, assessment.plausibility.tolist(), strict=True)),
        "conflict": assessment.conflict,
        "decision": assessment.decision,
        "decision_state": assessment.decision_state.value,
        "summarized": assessment.summarized,
    }


def _track_fast(view: FusedTrackView) -> PlainObject:
    score = float(view.score)
    if not math.isfinite(score):
        raise ValueError(f"fused track {view.id!r}: non-finite score")
    return {
        "id": view.id,
        "status": view.status.value,
        "state": np.ascontiguousarray(view.state, dtype=np.float64),  # finite: _check_finite
        "covariance": np.ascontiguousarray(view.covariance, dtype=np.float64),
        "sources": view.sources,  # frozen dataclasses (sensor, track, time): the wire names
        "classification": _class_fast(view.classification),
        "score": score,
        "reason": view.reason.value,
    }


def _association_plain(association: AssociationView) -> PlainObject:
    matrix = association.matrix
    return {
        "method": association.method,
        "pairs": [
            {"fused": fused, "track": track, "score": finite_or_none(score), "basis": basis}
            for fused, track, score, basis in association.pairs
        ],
        "new": list(association.new),
        "missed": list(association.missed),
        "matrix": None
        if matrix is None
        else {
            "rows": list(matrix[0]),
            "cols": list(matrix[1]),
            "values": [[finite_or_none(value) for value in row] for row in matrix[2].tolist()],
        },
    }


def step_json(step: StepResult, seq: int, geodetic: GeodeticOutput | None = None) -> str:
    """A step result in the contract's shape (``StepResult``), numbered ``seq`` (the
    session's input number), as compact JSON text (hot path); ``geodetic``: with each
    track's ``geodetic`` position (``?frame=geodetic``).

    Refuses (``ValueError``) a non-finite time, state, covariance or score instead
    of writing ``null``; a pair's or a matrix cell's non-finite score is ``null``.
    """
    if not math.isfinite(step.time):
        raise ValueError("non-finite step time")
    document = {
        "seq": seq,
        "time": step.time,
        "sensor": step.sensor,
        "tracks": track_items(step.tracks, geodetic),
        "association": _association_plain(step.association),
    }
    return itemwise(document, wire_json)  # no single C call for a 10 MB answer


def picture_json(
    seq: int,
    time: float | None,
    views: Sequence[FusedTrackView],
    geodetic: GeodeticOutput | None = None,
) -> str:
    """The live fused tracks at ``time`` (a ``FusedPicture``) as compact JSON text."""
    document = {"seq": seq, "time": time, "tracks": track_items(views, geodetic)}
    return itemwise(document, wire_json)


def picture_geojson(
    views: Sequence[FusedTrackView], geodetic: GeodeticOutput, velocity: tuple[int, ...]
) -> str:
    """The live fused tracks as a GeoJSON FeatureCollection (``?format=geojson``), written
    a feature at a time."""
    _check_finite(views)
    tracks = [
        {
            "id": view.id,
            "status": view.status.value,
            "state": view.state,
            "classification": _decision(view.classification),
        }
        for view in views
    ]
    return itemwise(feature_collection(tracks, geodetic, velocity))


def _decision(assessment: ClassAssessment | None) -> PlainObject | None:
    """What a GeoJSON feature says of a track's class: its decision and BetP."""
    if assessment is None or assessment.mass is None:
        return None
    labels = assessment.mass.frame.labels
    return {
        "decision": assessment.decision,
        "pignistic": dict(zip(labels, assessment.pignistic.tolist(), strict=True)),
    }


def track_items(
    views: Sequence[FusedTrackView], geodetic: GeodeticOutput | None = None
) -> Iterator[PlainObject]:
    """Fused tracks in the contract's shape (``FusedTrack``), for :func:`wire_json`, made one
    at a time as they are written (:func:`~app.http.responses.itemwise`): states and
    covariances stay numpy arrays, sources ``Source`` dataclasses (orjson writes both in C).
    Refuses (``ValueError``, before the first) a non-finite state, covariance or score."""
    _check_finite(views)
    if geodetic is None:
        return (_track_fast(view) for view in views)
    points = geodetic.points([view.state for view in views])
    return (
        {**_track_fast(view), "geodetic": point} for view, point in zip(views, points, strict=True)
    )


def track_fields(views: Sequence[FusedTrackView]) -> list[PlainObject]:
    """:func:`track_items` as a list."""
    return list(track_items(views))


def wire_json(document: object) -> str:
    """Compact JSON text of a document holding :func:`track_fields` output."""
    return orjson.dumps(document, option=orjson.OPT_SERIALIZE_NUMPY).decode()


# ------------------------------------------------------- stateless associate
def evidence_masses(tracks: Sequence[SensorTrack], frame: Frame) -> list[MassFunction]:
    """Class masses of one side of ``POST /v1/associate`` (vacuous where a track has none)."""
    vacuous = MassFunction.vacuous(frame)
    masses = []
    for track in tracks:
        evidence = track.classification
        if evidence is None:
            masses.append(vacuous)
        elif evidence.mass is not None:
            masses.append(class_mass(evidence, frame))
        else:
            try:
                masses.append(
                    accumulate_likelihoods(None, frame, class_likelihoods(evidence, frame))[0]
                )
            except TotalConflict:
                masses.append(vacuous)
    return masses


def side_arrays(tracks: Sequence[SensorTrack], dim: int) -> tuple[np.ndarray, np.ndarray]:
    """States (N × d) and covariances (N × d × d) of one side."""
    states = np.array([track.state for track in tracks], dtype=np.float64).reshape(-1, dim)
    covariances = np.array([track.covariance for track in tracks], dtype=np.float64).reshape(
        -1, dim, dim
    )
    return states, covariances


def associate_plain(request: AssociateRequest, result: AssociationResult) -> PlainObject:
    """The answer of ``POST /v1/associate`` in the contract's shape."""
    known = [track.id for track in request.known]
    incoming = [track.id for track in request.incoming]
    rows, cols, table = result.scores.table(known, incoming)  # [T2T] Table 1, `*:` rows
    diagnostics = result.diagnostics
    return {
        "pairs": [
            {"known": known[row], "incoming": incoming[col], "score": finite_or_none(score)}
            for row, col, score in result.pairs
        ],
        "new": [incoming[int(col)] for col in result.new],
        "missed": [known[int(row)] for row in result.missed],
        "matrix": {
            "rows": list(rows),
            "cols": list(cols),
            "values": [[finite_or_none(value) for value in row] for row in table.tolist()],
        },
        "diagnostics": {
            "method": result.method,
            "score_kind": result.scores.kind,
            "uses_classes": diagnostics.uses_classes,
            "classes_ignored": diagnostics.classes_ignored,
            "candidate_pairs": int(diagnostics.candidate_pairs),
            "clusters": int(diagnostics.clusters),
            "largest_cluster": int(diagnostics.largest_cluster),
            "gate": finite_or_none(float(diagnostics.gate)),
            "clipped": int(np.sum(diagnostics.clipped)),
            "undefined": len(diagnostics.undefined),
            "notes": "; ".join(diagnostics.notes) or None,
        },
    }
