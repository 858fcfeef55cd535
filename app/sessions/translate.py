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

import math
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from api_schemas.associate import AssociateRequest
from api_schemas.association import AssociationOptions
from api_schemas.classification import ClassEvidence
from api_schemas.config import (
    CartesianMeasurement,
    PolarMeasurement,
    PolygonFieldOfView,
    SectorFieldOfView,
    SensorConfig,
    SessionConfig,
    TrackThresholds,
    TwoPointInitiation,
)
from api_schemas.issues import FieldIssue
from api_schemas.reports import SensorTrack
from app.errors import InvalidFields
from app.geo.geodesy import (
    LocalFrame,
    heading_rotation,
)
from app.geo.geojson import GeodeticOutput
from app.outputs.json_results import finite_or_none
from core.association import AssociationResult
from core.belief import Frame, MassFunction
from core.errors import InvalidInput, TotalConflict
from core.fusion.classes import accumulate_likelihoods
from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.motion import MotionModel, StateLayout
from core.fusion.state import StateFusion
from core.geometry import FieldOfView, PolygonView, Sector
from core.lifecycle import LifeCycleConfig
from core.models.measurement import MEASUREMENT_MODELS, MeasurementModel
from core.tracking.config import DEFAULT_IMM_DISTANCE, ClassificationOptions, LocalTrackerConfig
from core.tracking.models import LinearMeasurementModel, ModelBank, constant_velocity
from core.tracking.presets import MIN_MANOEUVRE_DENSITY, preset, with_classes
from core.volume import RadarVolume

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
        raise InvalidFields([FieldIssue(("sensors", index, "fov"), str(error), None)]) from None
    try:  # a σ the model refuses is located at its field
        model = measurement_model(config, sensor)
    except InvalidInput as error:
        where = ("sensors", index, "measurement", *error.loc)
        raise InvalidFields([FieldIssue(where, str(error), None)]) from None
    volume = radar_volume(sensor, config)
    tracker = local_tracker_config(config, sensor, fov, volume)
    if tracker is not None:
        confirmable(tracker, sensor, index, fov)
    return SensorSpec(
        id=sensor.id,
        reliability=sensor.reliability,
        p_detect=sensor.p_detect,
        fov=fov,
        volume=volume,
        tracker=tracker,
        local_tracker=sensor.local_tracker,
        model=model,
    )


def radar_volume(sensor: SensorConfig, config: SessionConfig) -> RadarVolume | None:
    """A 3-D radar's coverage volume (``coverage``) in the session frame: at its site, in
    its site's ENU axes (turned from the session's exactly, as its detections are:
    :func:`site_axes`, inverted)."""
    coverage = sensor.coverage
    if coverage is None:
        return None
    origin = session_origin(config)
    site, _ = sensor_site(sensor, origin)
    turned = site_axes(sensor, origin, 3)  # the site's ENU → the session's
    axes = np.eye(3) if turned is None else turned.T
    return RadarVolume(
        site=(float(site[0]), float(site[1]), float(site[2])),
        axes=tuple((float(a), float(b), float(c)) for a, b, c in axes.tolist()),
        range_max=coverage.range_max,
        elevation_min_deg=coverage.elevation_min_deg,
        elevation_max_deg=coverage.elevation_max_deg,
        antenna_height=coverage.antenna_height,
    )


def confirmable(
    tracker: LocalTrackerConfig,
    sensor: SensorConfig,
    index: int,
    fov: FieldOfView | None = None,
) -> None:
    """Refuse (a validation error at the density) a sensor whose tracks can never be confirmed.

    A hit adds ``ΔL = ln[P_D / ((2π)^{q/2} β_FT √|S|)] − D/2`` ([MTT] §4.3) and S is at
    least the detections' R: when even a detection exactly at the prediction (D = 0,
    S = R) lowers the score, no run of detections ever confirms a track. Checked where
    β_FT is known (given, or the paper profile's): with ``measurement.r``, at that R; for
    a polar sensor, whose converted R grows with the range ρ
    (``|R| = σ_ρ² (ρ σ_a)² [(ρ σ_e)²]``, at elevation 0), at the nearest range it covers
    — its sector's near range, or σ_ρ without one (nearer than its own range noise
    nothing is resolved). An estimated β_FT is not checked: it follows the data (the
    detections over their box, docs/algorithms.md §8.4).
    """
    clutter = tracker.physics(sensor.id)[1]
    if clutter is None:
        return
    noise = sensor.measurement
    q = tracker.measured
    where = "noise r"
    if isinstance(noise, CartesianMeasurement):
        r = np.asarray(tracker.model_bank().measurement.noise_covariance, dtype=np.float64)
        log_det = float(np.linalg.slogdet(r)[1])
    elif isinstance(noise, PolarMeasurement):
        sigma_range, sigma_azimuth_deg = noise.polar_sigmas
        near = max(fov.range_min, sigma_range) if isinstance(fov, Sector) else sigma_range
        sigmas = [sigma_range, near * math.radians(sigma_azimuth_deg)]
        if q == 3 and noise.sigma_elevation_deg is not None:
            sigmas.append(near * math.radians(noise.sigma_elevation_deg))
        log_det = 2.0 * sum(math.log(sigma) for sigma in sigmas)
        where = f"polar noise at {near:.3g} m, the nearest range it covers"
    else:
        return
    best = tracker.life_cycle.scan_score(sensor.p_detect, clutter).hit_increment(
        np.zeros(1), np.array([log_det]), q
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
        f"({where}, P_D {sensor.p_detect:g}) is {math.exp(min(-best, 700.0)):.3g} times as likely clutter "
        f"as target (hit score {best:.3g} ≤ 0). Fix: give clutter_density per {unit} per "
        f"scan (false alarms per scan divided by the covered {'area' if q == 2 else 'volume'}), "
        "or leave it out to have "
        "it estimated from the sensor's detections"
    )
    raise InvalidFields([FieldIssue(location, message, clutter)])


def local_tracker_config(
    config: SessionConfig,
    sensor: SensorConfig,
    fov: FieldOfView | None,
    volume: RadarVolume | None = None,
) -> LocalTrackerConfig | None:
    """The local tracker of a sensor that sends detections (it has a measurement model)."""
    if sensor.measurement is None:
        return None
    tracking = config.tracking
    interval = tracking.time_interval
    axes = len(config.state.position)
    noise = sensor.measurement
    r = (
        polar_reference_noise(noise, fov, axes)
        if isinstance(noise, PolarMeasurement)
        else tuple(tuple(float(x) for x in row) for row in noise.r)
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
        fields_of_view={sensor.id: fov},
        volumes={} if volume is None else {sensor.id: volume},
        classification=ClassificationOptions() if config.classes else None,
        class_behaviours=class_behaviours(config),
        id_prefix=f"{sensor.id}:",
    )


def class_behaviours(config: SessionConfig) -> dict[str, tuple[str, ...]] | None:
    """The session's own classes and the behaviours each allows, in the class frame's order;
    one the preset refuses is a validation error at ``tracking/class_behaviours``."""
    allowed = config.tracking.class_behaviours
    if allowed is None or config.tracking.preset is None:
        return None
    ordered = {label: tuple(allowed[label]) for label in config.classes}
    try:
        with_classes(preset(config.tracking.preset), ordered)
    except InvalidInput as error:
        raise InvalidFields(
            [FieldIssue(("tracking", "class_behaviours"), str(error), allowed)]
        ) from None
    return ordered


def measurement_model(config: SessionConfig, sensor: SensorConfig) -> MeasurementModel | None:
    """A detecting sensor's measurement model of its local tracker's ``[x, ẋ, …]`` state
    (:mod:`core.models.measurement`); None for a sensor that sends track lists. Built once
    per engine configuration (:func:`sensor_spec`): its sensor's entry keeps it
    (:attr:`core.fusion.config.SensorSpec.model`) and every detection report of the sensor
    takes it from there (:func:`app.inputs.detections.core_detection_report`).

    A polar sensor's site and axes are in the session frame: azimuth and elevation
    are measured in the site's own ENU axes, turned into the session's at a
    geodetic site (``R_origin R_siteᵀ``, exact: :mod:`app.geo.geodesy`; the tilt
    between the two planes is 0.009° per km from the origin). The model is the
    registry's of the sensor's ``measurement.kind``
    (:data:`core.models.measurement.MEASUREMENT_MODELS`).
    """
    noise = sensor.measurement
    if noise is None:
        return None
    axes = len(config.state.position)
    origin = session_origin(config)  # once, for the site and its axes
    site, _ = sensor_site(sensor, origin)
    build = MEASUREMENT_MODELS[noise.kind]
    return build(site[:axes], site_axes(sensor, origin, axes), **noise.model_dump(exclude={"kind"}))


def site_axes(sensor: SensorConfig, origin: LocalFrame | None, dimension: int) -> np.ndarray | None:
    """Rotation (d × d) from the ENU axes at a geodetic site to the session's at ``origin``
    (``None`` at a session-frame ``position``: the sensor measures in the session's axes)."""
    site = sensor.site
    if site is None or site.lat is None or site.lon is None or origin is None:
        return None
    rotation: np.ndarray = origin.rotation_from(site.lat, site.lon)[0][:dimension, :dimension]
    return rotation


POLAR_REFERENCE_RANGE = 50_000.0
"""Range (m) of a polar sensor's reference noise when no sector field of view bounds it."""


def polar_reference_noise(
    noise: PolarMeasurement, fov: FieldOfView | None, axes: int
) -> tuple[tuple[float, ...], ...]:
    """The R a polar sensor's tracker uses where a detection's own covariance is not passed.

    Every polar detection is gated, scored, updated and starts its tracks
    with its own converted covariance (:meth:`core.models.measurement.Polar.converted`,
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


def motion_parameters(config: SessionConfig) -> dict[str, float]:
    """The parameters of the session's motion model: ``q`` (:func:`motion_density`) of the
    white-noise models, the given ones of the singer model (left out: its defaults,
    :mod:`core.models.singer`)."""
    if config.motion.model != "singer":
        return {"q": motion_density(config)}
    return config.motion.model_dump(
        include={"manoeuvre_time", "acceleration_std"}, exclude_none=True
    )


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
        acceleration=tuple(config.state.acceleration),
    )
    motion = MotionModel(layout, config.motion.model, **motion_parameters(config))
    sensors = [sensor_spec(sensor, index, config) for index, sensor in enumerate(config.sensors)]
    sensors += [SensorSpec(id=sensor_id) for sensor_id in extra_sensors]
    thresholds = config.tracking.thresholds
    association = config.association
    try:
        region = None if config.region is None else field_of_view(config.region)
    except InvalidInput as error:
        raise InvalidFields([FieldIssue(("region",), str(error), None)]) from None
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


def session_origin(config: SessionConfig) -> LocalFrame | None:
    """The session's ENU frame at its WGS84 ``origin`` (``None`` without one)."""
    origin = config.origin
    return None if origin is None else LocalFrame(origin.lat, origin.lon, origin.alt)


def session_geodetic(config: SessionConfig) -> GeodeticOutput | None:
    """Geodetic positions of the session's tracks (``?frame=geodetic``; ``None`` without an
    ``origin``)."""
    frame = session_origin(config)
    return (
        None
        if frame is None
        else GeodeticOutput(frame, tuple(config.state.position), tuple(config.state.velocity))
    )


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


# ------------------------------------------------------- stateless associate
def evidence_mass(evidence: ClassEvidence | None, frame: Frame) -> MassFunction:
    """Reported class evidence as one mass function on ``frame``: focal sets as given,
    likelihoods by [MTT] eq 10 (GBT); vacuous without evidence or when they contradict
    themselves totally."""
    vacuous = MassFunction.vacuous(frame)
    if evidence is None:
        return vacuous
    if evidence.mass is not None:
        return class_mass(evidence, frame)
    try:
        return accumulate_likelihoods(None, frame, class_likelihoods(evidence, frame))[0]
    except TotalConflict:
        return vacuous


def evidence_masses(tracks: Sequence[SensorTrack], frame: Frame) -> list[MassFunction]:
    """Class masses of one side of ``POST /v1/associate`` (vacuous where a track has none)."""
    return [evidence_mass(track.classification, frame) for track in tracks]


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
