"""Several detecting sensors: each alone, all fused by the session, Stone Soup's multi-sensor
trackers on the same detections (issue 23).

Scene: what Stone Soup's ``MultiTargetGroundTruthSimulator`` simulates (2-D constant
velocity with its CV model, births and deaths; :func:`simulated_truth`), truth every 1/3 s, seen by three sensors of different quality,
each scanning once a second, 1/3 s after the previous one (staggered report times):
σ 1 / 2 / 1.5 m, P_D 0.9 / 0.7 / 0.8, each with Poisson clutter uniform over its
coverage (the scene's clutter density). ``full``: every sensor covers the whole
square; ``sectors``: the first covers the left two thirds, the third the right two
thirds, the second all (the middle third is seen by all three). ``3d``: the same in
3-D (a CV model on each axis, targets in a box of the square's side and half its
height), seen by three polar radars at different sites 4-5 km away (range, azimuth,
elevation; σ_range 2 / 4 / 3 m and σ_angle 0.04° / 0.08° / 0.06°, about 3 / 6 / 5 m
across at that range; the same P_D), clutter uniform over the box; the sessions get
each radar's polar model and site, Stone Soup its ``CartesianToElevationBearingRange``
with an extended Kalman updater.

Runs, all on the same detections:

- ``alone-k``: a session with sensor k only (its own local tracker: the service path);
- ``fused``: one session with the three sensors, **defaults plus physics** (each
  sensor's R, P_D, clutter density and field of view, the birth density and
  ``motion.q``; no velocity prior, no management knob): the central tracker
  (docs/algorithms.md §8.9, the default path of detecting sensors);
- ``fused-t2t``: the same sensors flagged ``local_tracker: true``: each its own local
  tracker, then credal track-to-track fusion (the path before issue 23);
- ``lists`` (``lists-<method>``): the sensors as **track-list sources**: each sensor's
  own session (``alone-k``) posts its confirmed and coasting tracks at its scan (those the
  scan did not update flagged ``coasted``) to one session of three track-list sources
  (each its P_D and field of view), the default association method (each method);
  ``lists-rst``: the same,
  each source starting afresh once (its tracks lost, its ids numbered from F1 again: at
  half the run, 5 s and 10 s later);
- ``ss-gnn`` / ``ss-jpda``: Stone Soup 1.9.1 fed every sensor's detections in time
  order, each detection with its own sensor's ``LinearGaussian`` (its R; in 3-D its polar
  model, its PDA clutter density the box's converted at the box centre's range); a scan
  associates only the tracks inside its sensor's coverage; JPDA's ``PDAHypothesiser``
  is the scanning sensor's (its P_D and clutter density); ``MultiMeasurementInitiator``
  (min_points 2, the truth's velocity spread as prior), deletion after 3 s without an
  update (the tutorial's three 1 s scans); ``ss-gnn*`` / ``ss-jpda*``: deletion tuned in
  Stone Soup's favour (:data:`TUNED`).

Sessions are built through the service's own translation (the wire ``SessionConfig`` →
``FusionConfig``) and run in process. Every run is scored at the same instants, once a
second just after the last sensor's scan (a run's tracks predicted there: Stone Soup's
by its predictor, a session's by ``picture``), confirmed and coasting tracks, by Stone
Soup's GOSPA (c = 10 m, p = 1, α = 2), id switches by :func:`core.metrics.identity_switches`.

Goals (issue 23): fused ≤ 0.85× the best sensor alone and no more id switches; fused ≤
Stone Soup's multi-sensor GNN and JPDA (tutorial and tuned); track lists fused ≤ 1.0× the
best sensor alone and no more id switches, and no more after the sources' restarts.

Run: ``.venv/bin/python bench/multisensor.py [~10 ~50] [full sectors 3d] [lists]`` (several
minutes on a quiet 2-core machine, most of it Stone Soup's JPDA on ~50; ``lists``: only the
``alone-k`` and track-list rows and goals).
"""

from __future__ import annotations

import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"  # before numpy

import datetime  # noqa: E402
import sys  # noqa: E402
from collections.abc import Iterator  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment  # noqa: E402
from stonesoup.dataassociator.probability import JPDAwithLBP  # noqa: E402
from stonesoup.deleter.time import UpdateTimeDeleter  # noqa: E402
from stonesoup.gater.distance import DistanceGater  # noqa: E402
from stonesoup.hypothesiser.distance import DistanceHypothesiser  # noqa: E402
from stonesoup.hypothesiser.probability import PDAHypothesiser  # noqa: E402
from stonesoup.initiator.simple import MultiMeasurementInitiator  # noqa: E402
from stonesoup.measures import Mahalanobis  # noqa: E402
from stonesoup.models.measurement.linear import LinearGaussian  # noqa: E402
from stonesoup.models.measurement.nonlinear import (  # noqa: E402
    CartesianToElevationBearingRange,
)
from stonesoup.models.transition.linear import (  # noqa: E402
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)
from stonesoup.predictor.kalman import KalmanPredictor  # noqa: E402
from stonesoup.types.detection import Clutter, TrueDetection  # noqa: E402
from stonesoup.types.groundtruth import GroundTruthPath, GroundTruthState  # noqa: E402
from stonesoup.types.state import GaussianState, State  # noqa: E402
from stonesoup.types.track import Track  # noqa: E402
from stonesoup.updater.kalman import ExtendedKalmanUpdater, KalmanUpdater  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from machine import describe_machine  # noqa: E402
from peers import _jpda_posterior, gospa_terms  # noqa: E402

from api_schemas.config import AssociationConfig, SessionConfig  # noqa: E402
from api_schemas.reports import DetectionReport as WireDetectionReport  # noqa: E402
from app.inputs.detections import core_detection_report  # noqa: E402
from app.sessions.translate import fusion_config  # noqa: E402
from core.association import METHODS  # noqa: E402
from core.fusion.config import FusionConfig  # noqa: E402
from core.fusion.engine import SessionEngine  # noqa: E402
from core.fusion.reports import DetectionReport, ReportedTrack, TrackReport  # noqa: E402
from core.metrics import identity_switches  # noqa: E402

START = datetime.datetime(2026, 1, 1)
DEFAULT_METHOD = AssociationConfig.model_fields["method"].default
"""The track-to-track association method of a session that names none (row ``lists``)."""
Q = 0.05  # m²/s³, Stone Soup ConstantVelocity noise_diff_coeff (bench/peers.py)
SUBSTEPS = 3
"""Sensors, and truth steps per second: sensor k scans at whole seconds + k/3 s."""
SENSORS: tuple[tuple[float, float], ...] = ((1.0, 0.9), (2.0, 0.7), (1.5, 0.8))
"""(σ m, P_D) of each sensor (issue 23's)."""
CUTOFF = 10.0
LIVE = ("confirmed", "coasting")
CLUTTER_PER_TARGET = 0.5
"""False detections per scan over the whole square, per initial target (bench/peers.py)."""
DEATH = 0.02
"""Death probability per second."""
VELOCITY_STD = 2.0
SEEDS = {"~10": 41, "~50": 42}
TUTORIAL = (3.0, 3.0)
"""Stone Soup's deletion after (s without an update) of tentative and of confirmed tracks:
the tutorial's three 1 s scans."""
TUNED = (0.7, 1.5)
"""The same, tuned in Stone Soup's favour on ``~10 full`` (the smallest GOSPA of its GNN
among (3, 3), (1, 3), (0.7, 3), (0.7, 2), (0.7, 1.5)): a tentative track needs its second
detection within the next two scans; rows ``ss-gnn*``, ``ss-jpda*``."""
"""Seeds not looked at while the central tracker was built."""
RADARS: tuple[tuple[tuple[float, float, float], float, float], ...] = (
    ((-3000.0, -3000.0, -1000.0), 2.0, 0.04),
    ((3000.0, -3000.0, -1000.0), 4.0, 0.08),
    ((0.0, 4000.0, -1000.0), 3.0, 0.06),
)
"""The 3-D scene's radars: (site m, σ_range m, σ_azimuth = σ_elevation degrees)."""


@dataclass
class Scan:
    sensor: int
    time: float
    z: np.ndarray  # (m, 2), sorted; in 3-D (m, 3) of (range, azimuth°, elevation°)
    detections: set[Any]  # the same, as Stone Soup detections


@dataclass
class Scene:
    name: str
    side: float
    truths: list[GroundTruthPath]
    scans: list[Scan]
    covers: list[tuple[float, float]]  # each sensor's x interval
    clutter_density: float
    birth_density: float
    targets: float = 0.0
    axes: int = 2

    @property
    def positions(self) -> tuple[int, ...]:
        return tuple(range(0, 2 * self.axes, 2))

    @property
    def polar(self) -> bool:
        return self.axes == 3

    def model(self, sensor: int) -> Any:
        """Sensor ``sensor``'s Stone Soup measurement model."""
        if not self.polar:
            return measurement(SENSORS[sensor][0])
        site, sigma_range, sigma_angle = RADARS[sensor]
        angle = np.radians(sigma_angle) ** 2
        return CartesianToElevationBearingRange(
            ndim_state=6,
            mapping=(0, 2, 4),
            noise_covar=np.diag([angle, angle, sigma_range**2]),
            translation_offset=np.array(site).reshape(3, 1),
        )

    def truth_at(self, when: datetime.datetime) -> list[tuple[str, State]]:
        return [
            (str(path.id), path[when])
            for path in self.truths
            if path[0].timestamp <= when <= path[-1].timestamp
        ]

    def eval_times(self) -> list[float]:
        """Once a second, at the last sensor's scan."""
        return [scan.time for scan in self.scans if scan.sensor == SUBSTEPS - 1]


def transition(axes: int = 2) -> CombinedLinearGaussianTransitionModel:
    return CombinedLinearGaussianTransitionModel([ConstantVelocity(Q)] * axes)


def measurement(sigma: float) -> LinearGaussian:
    return LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2) * sigma**2)


def birth(path: GroundTruthPath) -> int:
    """A path's number (its id is ``t<number>``, in order of birth)."""
    return int(str(path.id)[1:])


def simulated_truth(
    seed: int, side: float, targets: int, steps: int, dt: float, axes: int = 2
) -> Iterator[tuple[datetime.datetime, set[GroundTruthPath]]]:
    """What Stone Soup's ``MultiTargetGroundTruthSimulator`` does (its CV model's F and Q,
    ``targets`` at the start, births = deaths in the mean, births over the square's centre
    half), drawn from one seeded generator in a fixed order (the simulator draws in the
    order of a set of random uuids: its truth changes from run to run)."""
    rng = np.random.default_rng(seed)
    model = transition(axes)
    f, q = (
        model.matrix(time_interval=datetime.timedelta(seconds=dt)),
        model.covar(time_interval=datetime.timedelta(seconds=dt)),
    )
    spread = np.array([side / 4, VELOCITY_STD, side / 4, VELOCITY_STD, side / 8, 0.5][: 2 * axes])
    living: list[GroundTruthPath] = []
    number = 0

    def born(when: datetime.datetime) -> GroundTruthPath:
        nonlocal number
        path = GroundTruthPath(id=f"t{number}")
        number += 1
        path.append(GroundTruthState(rng.normal(0.0, spread).reshape(-1, 1), timestamp=when))
        return path

    when = START
    living = [born(when) for _ in range(targets)]
    for _ in range(steps):
        yield when, set(living)
        when += datetime.timedelta(seconds=dt)
        living = [path for path in living if rng.random() >= DEATH * dt]
        for path in living:
            state = f @ path[-1].state_vector + rng.multivariate_normal(
                np.zeros(2 * axes), q
            ).reshape(-1, 1)
            path.append(GroundTruthState(state, timestamp=when))
        living += [born(when) for _ in range(rng.poisson(targets * DEATH * dt))]


def build_scene(name: str, targets: int, seconds: int, layout: str) -> Scene:
    seed = SEEDS[name]
    side = 400.0 * np.sqrt(targets / 10.0)
    truth = simulated_truth(seed, side, targets, seconds * SUBSTEPS, 1.0 / SUBSTEPS)
    half = side / 2
    third = side / 6
    covers = (
        [(-half, half)] * 3 if layout == "full" else [(-half, third), (-half, half), (-third, half)]
    )
    density = targets * CLUTTER_PER_TARGET / side**2
    rng = np.random.default_rng(seed + 7)
    scans: list[Scan] = []
    paths: set[GroundTruthPath] = set()
    counts = []
    for step, (when, living) in enumerate(truth):
        paths |= set(living)
        counts.append(len(living))
        k = step % SUBSTEPS
        sigma, p_detect = SENSORS[k]
        model = measurement(sigma)
        low, high = covers[k]
        found: list[tuple[np.ndarray, Any]] = []
        for path in sorted(living, key=birth):  # not by id: a path's id is a random uuid
            state = path[-1]
            x = float(state.state_vector[0])
            if not (low <= x <= high and -half <= float(state.state_vector[2]) <= half):
                continue
            if rng.random() >= p_detect:
                continue
            z = np.asarray(state.state_vector, dtype=float).ravel()[[0, 2]] + rng.normal(
                0.0, sigma, 2
            )
            found.append(
                (
                    z,
                    TrueDetection(
                        z.reshape(2, 1),
                        timestamp=when,
                        measurement_model=model,
                        groundtruth_path=path,
                    ),
                )
            )
        area = (high - low) * side
        for _ in range(rng.poisson(density * area)):
            z = np.array([rng.uniform(low, high), rng.uniform(-half, half)])
            found.append((z, Clutter(z.reshape(2, 1), timestamp=when, measurement_model=model)))
        found.sort(key=lambda item: (float(item[0][0]), float(item[0][1])))
        z = np.array([item[0] for item in found]).reshape(-1, 2)
        scans.append(Scan(k, (when - START).total_seconds(), z, {item[1] for item in found}))
    truths = sorted(paths, key=birth)
    return Scene(
        name=f"{name} {layout}",
        side=side,
        truths=truths,
        scans=scans,
        covers=covers,
        clutter_density=density,
        birth_density=max(targets * DEATH, 1e-3) / side**2,
        targets=float(np.mean(counts)),
    )


def build_scene_3d(name: str, targets: int, seconds: int) -> Scene:
    """The ``3d`` layout: the truth in 3-D, three polar radars at their sites (module
    docstring); clutter uniform over the box (half the side high), seen as polar detections."""
    seed = SEEDS[name] + 100
    side = 400.0 * np.sqrt(targets / 10.0)
    truth = simulated_truth(seed, side, targets, seconds * SUBSTEPS, 1.0 / SUBSTEPS, axes=3)
    half = side / 2
    low, high = np.array([-half, -half, -half / 2]), np.array([half, half, half / 2])
    volume = float(np.prod(high - low))
    density = targets * CLUTTER_PER_TARGET / volume
    rng = np.random.default_rng(seed + 7)
    scans: list[Scan] = []
    paths: set[GroundTruthPath] = set()
    counts = []
    probe = Scene("", side, [], [], [], 0.0, 0.0, axes=3)
    for step, (when, living) in enumerate(truth):
        paths |= set(living)
        counts.append(len(living))
        k = step % SUBSTEPS
        p_detect = SENSORS[k][1]
        model = probe.model(k)
        _, sigma_range, sigma_angle = RADARS[k]
        sigmas = np.array([np.radians(sigma_angle), np.radians(sigma_angle), sigma_range])
        found: list[tuple[np.ndarray, Any]] = []
        for path in sorted(living, key=birth):
            state = path[-1]
            position = np.asarray(state.state_vector, dtype=float).ravel()[[0, 2, 4]]
            if not np.all((low <= position) & (position <= high)):
                continue
            if rng.random() >= p_detect:
                continue
            polar = np.asarray(model.function(state, noise=False), dtype=float).ravel()
            polar = polar + rng.normal(0.0, sigmas)
            found.append(
                (
                    polar,
                    TrueDetection(
                        polar.reshape(3, 1),
                        timestamp=when,
                        measurement_model=model,
                        groundtruth_path=path,
                    ),
                )
            )
        for _ in range(rng.poisson(density * volume)):
            where = rng.uniform(low, high)
            state = State(np.array([where[0], 0.0, where[1], 0.0, where[2], 0.0]).reshape(6, 1))
            polar = np.asarray(model.function(state, noise=False), dtype=float).ravel()
            found.append(
                (polar, Clutter(polar.reshape(3, 1), timestamp=when, measurement_model=model))
            )
        found.sort(key=lambda item: (float(item[0][2]), float(item[0][1])))
        # (elevation, bearing, range) → (range, azimuth° clockwise from north, elevation°)
        z = np.array(
            [
                [item[0][2], (90.0 - np.degrees(item[0][1])) % 360.0, np.degrees(item[0][0])]
                for item in found
            ]
        ).reshape(-1, 3)
        scans.append(Scan(k, (when - START).total_seconds(), z, {item[1] for item in found}))
    truths = sorted(paths, key=birth)
    return Scene(
        name=f"{name} 3d",
        side=side,
        truths=truths,
        scans=scans,
        covers=[(-half, half)] * 3,
        clutter_density=density,
        birth_density=max(targets * DEATH, 1e-3) / volume,
        targets=float(np.mean(counts)),
        axes=3,
    )


# ----------------------------------------------------------------- runs
Estimates = list[tuple[str, np.ndarray]]


def session_config(scene: Scene, sensors: list[int], local: bool) -> dict[str, Any]:
    if scene.polar:
        return {
            "state": {"dim": 6, "position": [0, 2, 4], "velocity": [1, 3, 5]},
            "motion": {"model": "constant_velocity", "q": Q},
            "sensors": [
                {
                    "id": f"s{k}",
                    "p_detect": SENSORS[k][1],
                    "measurement": {
                        "kind": "polar",
                        "sigma_range": RADARS[k][1],
                        "sigma_azimuth_deg": RADARS[k][2],
                        "sigma_elevation_deg": RADARS[k][2],
                    },
                    "site": {"position": list(RADARS[k][0])},
                    "clutter_density": scene.clutter_density,
                    "local_tracker": local,
                }
                for k in sensors
            ],
            "tracking": {"time_interval": 1.0, "birth_density": scene.birth_density},
        }
    half = float(scene.side / 2)
    return {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "motion": {"model": "constant_velocity", "q": Q},
        "sensors": [
            {
                "id": f"s{k}",
                "p_detect": SENSORS[k][1],
                "measurement": {"r": (np.eye(2) * SENSORS[k][0] ** 2).tolist()},
                "clutter_density": scene.clutter_density,
                "fov": {
                    "kind": "polygon",
                    "vertices": [
                        [float(scene.covers[k][0]), -half],
                        [float(scene.covers[k][1]), -half],
                        [float(scene.covers[k][1]), half],
                        [float(scene.covers[k][0]), half],
                    ],
                },
                "local_tracker": local,
            }
            for k in sensors
        ],
        "tracking": {"time_interval": 1.0, "birth_density": scene.birth_density},
    }


def session_run(scene: Scene, sensors: list[int], local: bool = False) -> list[Estimates]:
    wire = SessionConfig.model_validate(session_config(scene, sensors, local))
    engine = SessionEngine(fusion_config(wire))
    out: list[Estimates] = []
    for scan in scene.scans:
        if scan.sensor in sensors:
            engine.apply_detections(detection_report(scene, wire, scan, engine.config))
        if scan.sensor == SUBSTEPS - 1:
            out.append(
                [
                    (t.id, np.asarray(t.state))
                    for t in engine.picture(scan.time)
                    if t.status.value in LIVE
                ]
            )
    return out


def track_list_config(scene: Scene, method: str) -> dict[str, Any]:
    """The session of the three sensors as track-list sources: each its P_D and field of
    view (the physics of a source that sends tracks), association ``method``."""
    config = session_config(scene, list(range(len(SENSORS))), local=False)
    for sensor in config["sensors"]:
        for detecting in ("measurement", "site", "clutter_density", "local_tracker"):
            sensor.pop(detecting, None)
    config["association"] = {"method": method}
    return config


def track_list_run(
    scene: Scene,
    method: str = "denoeux",
    restarts: dict[int, float] | None = None,
    coasted: bool = True,
) -> list[Estimates]:
    """Each sensor's own single-sensor session (``alone-k``) posts its confirmed and coasting
    tracks (its picture at its scan) as a track list to one session of three track-list
    sources, a track its scan did not update flagged ``coasted`` (``coasted`` False: none
    flagged). ``restarts``: sensor k's session starts afresh at that time (its tracks lost,
    its ids numbered from F1 again)."""
    wires = [
        SessionConfig.model_validate(session_config(scene, [k], False)) for k in range(len(SENSORS))
    ]
    sources = [SessionEngine(fusion_config(wire)) for wire in wires]
    fused = SessionEngine(
        fusion_config(SessionConfig.model_validate(track_list_config(scene, method)))
    )
    pending = dict(restarts or {})
    out: list[Estimates] = []
    for scan in scene.scans:
        k = scan.sensor
        if k in pending and scan.time >= pending[k]:
            del pending[k]
            sources[k] = SessionEngine(fusion_config(wires[k]))
        source = sources[k]
        source.apply_detections(detection_report(scene, wires[k], scan, source.config))
        tracks = tuple(
            ReportedTrack(
                t.id,
                np.asarray(t.state),
                np.asarray(t.covariance),
                coasted=coasted and max(source.time for source in t.sources) < scan.time,
            )
            for t in source.picture(scan.time)
            if t.status.value in LIVE
        )
        fused.apply(TrackReport(f"s{k}", scan.time, tracks))
        if k == SUBSTEPS - 1:
            out.append(
                [
                    (t.id, np.asarray(t.state))
                    for t in fused.picture(scan.time)
                    if t.status.value in LIVE
                ]
            )
    return out


def restarts(seconds: int) -> dict[int, float]:
    """When each source of ``lists-rst`` starts afresh: the first at half the run, the
    others 5 s and 10 s later."""
    return {k: seconds / 2 + 5.0 * k for k in range(len(SENSORS))}


def detection_report(
    scene: Scene, wire: SessionConfig, scan: Scan, engine_config: FusionConfig
) -> DetectionReport:
    """A scan as the core takes it: as given in 2-D; in 3-D its polar detections through the
    service's conversion (``app.inputs.detections``: converted positions, each its own R)."""
    if not scene.polar:
        return DetectionReport(f"s{scan.sensor}", scan.time, scan.z)
    body = {
        "sensor": f"s{scan.sensor}",
        "time": scan.time,
        "detections": [
            {"range": float(r), "azimuth_deg": float(a), "elevation_deg": float(e)}
            for r, a, e in scan.z.tolist()
        ],
    }
    return core_detection_report(WireDetectionReport.model_validate(body), wire, engine_config)


def clutter_in_measurement_space(scene: Scene, sensor: int) -> float:
    """The PDA's clutter density in the sensor's measurement space: the scene's in 2-D; in
    3-D the box's per m³ times the polar cell's volume element r² cos(elevation) at the box
    centre (per rad² m)."""
    if not scene.polar:
        return scene.clutter_density
    site = np.array(RADARS[sensor][0])
    offset = -site
    r = float(np.linalg.norm(offset))
    cos_elevation = float(np.hypot(offset[0], offset[1]) / r)
    return scene.clutter_density * r**2 * cos_elevation


def inside(scene: Scene, sensor: int, state: Any) -> bool:
    if scene.polar:
        return True
    low, high = scene.covers[sensor]
    half = scene.side / 2
    x, y = float(state.state_vector[0]), float(state.state_vector[2])
    return low <= x <= high and -half <= y <= half


def stone_soup_run(
    scene: Scene, kind: str, deletion: tuple[float, float] = TUTORIAL
) -> list[Estimates]:
    """Stone Soup's tutorial loop over every sensor's scans in time order (module docstring);
    ``deletion``: seconds without an update that delete a tentative and a confirmed track."""
    hold, delete = deletion
    predictor = KalmanPredictor(transition(scene.axes))
    updater = ExtendedKalmanUpdater if scene.polar else KalmanUpdater
    updaters = [updater(scene.model(k)) for k in range(len(SENSORS))]
    associators: list[Any] = []
    for k, (_, p_detect) in enumerate(SENSORS):
        if kind == "ss-jpda":
            hypothesiser: Any = PDAHypothesiser(
                predictor=predictor,
                updater=updaters[k],
                clutter_spatial_density=clutter_in_measurement_space(scene, k),
                prob_detect=p_detect,
            )
            hypothesiser = DistanceGater(hypothesiser, measure=Mahalanobis(), gate_threshold=16)
            associators.append(JPDAwithLBP(hypothesiser=hypothesiser))
        else:
            associators.append(
                GNNWith2DAssignment(
                    DistanceHypothesiser(predictor, updaters[k], Mahalanobis(), missed_distance=3)
                )
            )
    deleter = UpdateTimeDeleter(time_since_update=datetime.timedelta(seconds=delete))
    initiator = MultiMeasurementInitiator(
        prior_state=GaussianState(
            np.zeros((2 * scene.axes, 1)), np.diag([0.0, VELOCITY_STD**2] * scene.axes)
        ),
        measurement_model=scene.model(0),
        deleter=UpdateTimeDeleter(time_since_update=datetime.timedelta(seconds=hold)),
        data_associator=GNNWith2DAssignment(
            DistanceHypothesiser(predictor, updaters[0], Mahalanobis(), missed_distance=3)
        ),
        updater=updaters[0],
        min_points=2,
    )
    tracks: set[Track] = set()
    out: list[Estimates] = []
    for scan in scene.scans:
        when = START + datetime.timedelta(seconds=scan.time)
        k = scan.sensor
        seen = {
            track
            for track in tracks
            if inside(scene, k, predictor.predict(track.state, timestamp=when))
        }
        associations = associators[k].associate(seen, scan.detections, when)
        unassociated = set(scan.detections)
        for track, hypothesis in associations.items():
            if kind == "ss-jpda":
                track.append(_jpda_posterior(hypothesis, updaters[k], when))
                for single in hypothesis:
                    if single:
                        unassociated.discard(single.measurement)
            elif hypothesis:
                track.append(updaters[k].update(hypothesis))
                unassociated.discard(hypothesis.measurement)
            else:
                track.append(hypothesis.prediction)
        tracks -= deleter.delete_tracks(tracks, timestamp=when)
        tracks |= initiator.initiate(unassociated, when)
        if k == SUBSTEPS - 1:
            out.append(
                [
                    (
                        str(track.id),
                        np.asarray(
                            predictor.predict(track.state, timestamp=when).state_vector,
                            dtype=float,
                        ).ravel(),
                    )
                    for track in tracks
                ]
            )
    return out


# --------------------------------------------------------------- scoring
@dataclass(frozen=True)
class Score:
    gospa: float
    localisation: float
    missed: float
    false: float
    switches: int


def score(scene: Scene, estimates: list[Estimates]) -> Score:
    whens = [START + datetime.timedelta(seconds=t) for t in scene.eval_times()]
    parts, assigned = gospa_terms(
        ((when, scene.truth_at(when), step) for when, step in zip(whens, estimates, strict=True)),
        cutoff=CUTOFF,
        positions=scene.positions,
    )
    return Score(*parts, identity_switches(assigned))


SCENES = {"~10": (10, 60), "~50": (50, 40)}
LAYOUTS = ("full", "sectors", "3d")


def fused_goals(scores: dict[str, Score], best: str) -> list[tuple[str, bool]]:
    """Issue 23's goals of the detections fused centrally, met or not."""
    fused = scores["fused"]
    return [
        (f"fused ≤ 0.85× best alone ({best})", fused.gospa <= 0.85 * scores[best].gospa),
        (f"fused id switches ≤ {best}'s", fused.switches <= scores[best].switches),
        *(
            (f"fused ≤ {kind}", fused.gospa <= scores[kind].gospa)
            for kind in ("ss-gnn", "ss-jpda", "ss-gnn*", "ss-jpda*")
        ),
    ]


def main() -> int:
    print(describe_machine())
    print(
        f"sensors (σ m, P_D) = {SENSORS}, scans 1/3 s apart, each once a second; q = {Q:g} "
        f"m²/s³; GOSPA c = {CUTOFF:g} m, p = 1, α = 2, meaned over the scoring instants; "
        "sessions: defaults + physics (R, P_D, clutter density, field of view, birth "
        "density, motion.q), no velocity prior"
    )
    chosen = sys.argv[1:]
    lists_only = "lists" in chosen  # the track-list rows only (no Stone Soup: minutes, not tens)
    names = [name for name in SCENES if name in chosen] or list(SCENES)
    layouts = [layout for layout in LAYOUTS if layout in chosen] or list(LAYOUTS)
    header = (
        f"{'scene':>12} {'targets':>7} {'run':>14} {'GOSPA':>7} {'loc':>6} {'miss':>6} "
        f"{'false':>6} {'idsw':>5} {'/best':>6}"
    )
    for name in names:
        targets, seconds = SCENES[name]
        for layout in layouts:
            scene = (
                build_scene_3d(name, targets, seconds)
                if layout == "3d"
                else build_scene(name, targets, seconds, layout)
            )
            runs: dict[str, list[Estimates]] = {
                f"alone-{k}": session_run(scene, [k]) for k in range(len(SENSORS))
            }
            if not lists_only:
                runs["fused"] = session_run(scene, list(range(len(SENSORS))))
                runs["fused-t2t"] = session_run(scene, list(range(len(SENSORS))), local=True)
            for method in METHODS:
                label = "lists" if method == DEFAULT_METHOD else f"lists-{method}"
                runs[label] = track_list_run(scene, method)
            runs["lists-rst"] = track_list_run(scene, restarts=restarts(seconds))
            for kind in () if lists_only else ("ss-gnn", "ss-jpda"):
                runs[kind] = stone_soup_run(scene, kind)
                runs[f"{kind}*"] = stone_soup_run(scene, kind, TUNED)
            scores = {label: score(scene, estimates) for label, estimates in runs.items()}
            best = min(
                (label for label in scores if label.startswith("alone")),
                key=lambda label: scores[label].gospa,
            )
            print(header)
            for label, result in scores.items():
                print(
                    f"{scene.name:>12} {scene.targets:7.1f} {label:>14} {result.gospa:7.2f} "
                    f"{result.localisation:6.2f} {result.missed:6.2f} {result.false:6.2f} "
                    f"{result.switches:5d} {result.gospa / scores[best].gospa:6.2f}"
                )
            checks = [] if lists_only else fused_goals(scores, best)
            lists = scores["lists"]
            checks += [
                (f"lists ≤ 1.0× best alone ({best})", lists.gospa <= scores[best].gospa),
                (f"lists id switches ≤ {best}'s", lists.switches <= scores[best].switches),
                (
                    "lists-rst id switches ≤ lists'",
                    scores["lists-rst"].switches <= lists.switches,
                ),
            ]
            for text, ok in checks:
                print(f"{scene.name:>12} goal {text}: {'met' if ok else 'NOT met'}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
