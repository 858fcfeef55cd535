"""Several detecting sensors: each alone, all fused by the session, Stone Soup's multi-sensor
trackers on the same detections (issue 23).

Scene: what Stone Soup's ``MultiTargetGroundTruthSimulator`` simulates (2-D constant
velocity with its CV model, births and deaths; :func:`simulated_truth`), truth every 1/3 s, seen by three sensors of different quality,
each scanning once a second, 1/3 s after the previous one (staggered report times):
σ 1 / 2 / 1.5 m, P_D 0.9 / 0.7 / 0.8, each with Poisson clutter uniform over its
coverage (the scene's clutter density). ``full``: every sensor covers the whole
square; ``sectors``: the first covers the left two thirds, the third the right two
thirds, the second all (the middle third is seen by all three).

Runs, all on the same detections:

- ``alone-k``: a session with sensor k only (its own local tracker: the service path);
- ``fused``: one session with the three sensors flagged ``local_tracker: false``,
  otherwise **defaults plus physics** (each
  sensor's R, P_D, clutter density and field of view, the birth density and
  ``motion.q``; no velocity prior, no management knob): the central tracker
  (docs/algorithms.md §8.9);
- ``fused-t2t``: the same sensors with ``local_tracker: true`` (the default): each its own local
  tracker, then credal track-to-track fusion (the path before issue 23);
- ``ss-gnn`` / ``ss-jpda``: Stone Soup 1.9.1 fed every sensor's detections in time
  order, each detection with its own sensor's ``LinearGaussian`` (its R); a scan
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
Stone Soup's multi-sensor GNN and JPDA (tutorial and tuned).

Run: ``.venv/bin/python bench/multisensor.py [~10 ~50] [full sectors]`` (several minutes
on a quiet 2-core machine, most of it Stone Soup's JPDA on ~50).
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
from stonesoup.models.transition.linear import (  # noqa: E402
    CombinedLinearGaussianTransitionModel,
    ConstantVelocity,
)
from stonesoup.predictor.kalman import KalmanPredictor  # noqa: E402
from stonesoup.types.detection import Clutter, TrueDetection  # noqa: E402
from stonesoup.types.groundtruth import GroundTruthPath, GroundTruthState  # noqa: E402
from stonesoup.types.state import GaussianState, State  # noqa: E402
from stonesoup.types.track import Track  # noqa: E402
from stonesoup.updater.kalman import KalmanUpdater  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from machine import describe_machine  # noqa: E402
from peers import _jpda_posterior, gospa_terms  # noqa: E402

from api_schemas.config import SessionConfig  # noqa: E402
from app.sessions.translate import fusion_config  # noqa: E402
from core.fusion.engine import SessionEngine  # noqa: E402
from core.fusion.reports import DetectionReport  # noqa: E402
from core.metrics import identity_switches  # noqa: E402

START = datetime.datetime(2026, 1, 1)
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


@dataclass
class Scan:
    sensor: int
    time: float
    z: np.ndarray  # (m, 2), sorted
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

    def truth_at(self, when: datetime.datetime) -> list[tuple[str, State]]:
        return [
            (str(path.id), path[when])
            for path in self.truths
            if path[0].timestamp <= when <= path[-1].timestamp
        ]

    def eval_times(self) -> list[float]:
        """Once a second, at the last sensor's scan."""
        return [scan.time for scan in self.scans if scan.sensor == SUBSTEPS - 1]


def transition() -> CombinedLinearGaussianTransitionModel:
    return CombinedLinearGaussianTransitionModel([ConstantVelocity(Q), ConstantVelocity(Q)])


def measurement(sigma: float) -> LinearGaussian:
    return LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2) * sigma**2)


def birth(path: GroundTruthPath) -> int:
    """A path's number (its id is ``t<number>``, in order of birth)."""
    return int(str(path.id)[1:])


def simulated_truth(
    seed: int, side: float, targets: int, steps: int, dt: float
) -> Iterator[tuple[datetime.datetime, set[GroundTruthPath]]]:
    """What Stone Soup's ``MultiTargetGroundTruthSimulator`` does (its CV model's F and Q,
    ``targets`` at the start, births = deaths in the mean, births over the square's centre
    half), drawn from one seeded generator in a fixed order (the simulator draws in the
    order of a set of random uuids: its truth changes from run to run)."""
    rng = np.random.default_rng(seed)
    model = transition()
    f, q = (
        model.matrix(time_interval=datetime.timedelta(seconds=dt)),
        model.covar(time_interval=datetime.timedelta(seconds=dt)),
    )
    spread = np.array([side / 4, VELOCITY_STD, side / 4, VELOCITY_STD])
    living: list[GroundTruthPath] = []
    number = 0

    def born(when: datetime.datetime) -> GroundTruthPath:
        nonlocal number
        path = GroundTruthPath(id=f"t{number}")
        number += 1
        path.append(GroundTruthState(rng.normal(0.0, spread).reshape(4, 1), timestamp=when))
        return path

    when = START
    living = [born(when) for _ in range(targets)]
    for _ in range(steps):
        yield when, set(living)
        when += datetime.timedelta(seconds=dt)
        living = [path for path in living if rng.random() >= DEATH * dt]
        for path in living:
            state = f @ path[-1].state_vector + rng.multivariate_normal(np.zeros(4), q).reshape(
                4, 1
            )
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


# ----------------------------------------------------------------- runs
Estimates = list[tuple[str, np.ndarray]]


def session_config(scene: Scene, sensors: list[int], local: bool) -> dict[str, Any]:
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
            engine.apply_detections(DetectionReport(f"s{scan.sensor}", scan.time, scan.z))
        if scan.sensor == SUBSTEPS - 1:
            out.append(
                [
                    (t.id, np.asarray(t.state))
                    for t in engine.picture(scan.time)
                    if t.status.value in LIVE
                ]
            )
    return out


def inside(scene: Scene, sensor: int, state: Any) -> bool:
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
    predictor = KalmanPredictor(transition())
    updaters = [KalmanUpdater(measurement(sigma)) for sigma, _ in SENSORS]
    associators: list[Any] = []
    for k, (_, p_detect) in enumerate(SENSORS):
        if kind == "ss-jpda":
            hypothesiser: Any = PDAHypothesiser(
                predictor=predictor,
                updater=updaters[k],
                clutter_spatial_density=scene.clutter_density,
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
            np.zeros((4, 1)), np.diag([0.0, VELOCITY_STD**2, 0.0, VELOCITY_STD**2])
        ),
        measurement_model=measurement(SENSORS[0][0]),
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
    )
    return Score(*parts, identity_switches(assigned))


SCENES = {"~10": (10, 60), "~50": (50, 40)}
LAYOUTS = ("full", "sectors")


def main() -> int:
    print(describe_machine())
    print(
        f"sensors (σ m, P_D) = {SENSORS}, scans 1/3 s apart, each once a second; q = {Q:g} "
        f"m²/s³; GOSPA c = {CUTOFF:g} m, p = 1, α = 2, meaned over the scoring instants; "
        "sessions: defaults + physics (R, P_D, clutter density, field of view, birth "
        "density, motion.q), no velocity prior"
    )
    chosen = sys.argv[1:]
    names = [name for name in SCENES if name in chosen] or list(SCENES)
    layouts = [layout for layout in LAYOUTS if layout in chosen] or list(LAYOUTS)
    header = (
        f"{'scene':>12} {'targets':>7} {'run':>10} {'GOSPA':>7} {'loc':>6} {'miss':>6} "
        f"{'false':>6} {'idsw':>5} {'/best':>6}"
    )
    for name in names:
        targets, seconds = SCENES[name]
        for layout in layouts:
            scene = build_scene(name, targets, seconds, layout)
            runs: dict[str, list[Estimates]] = {
                f"alone-{k}": session_run(scene, [k]) for k in range(len(SENSORS))
            }
            runs["fused"] = session_run(scene, list(range(len(SENSORS))))
            runs["fused-t2t"] = session_run(scene, list(range(len(SENSORS))), local=True)
            for kind in ("ss-gnn", "ss-jpda"):
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
                    f"{scene.name:>12} {scene.targets:7.1f} {label:>10} {result.gospa:7.2f} "
                    f"{result.localisation:6.2f} {result.missed:6.2f} {result.false:6.2f} "
                    f"{result.switches:5d} {result.gospa / scores[best].gospa:6.2f}"
                )
            fused = scores["fused"]
            checks = [
                (f"fused ≤ 0.85× best alone ({best})", fused.gospa <= 0.85 * scores[best].gospa),
                (
                    f"fused id switches ≤ {best}'s",
                    fused.switches <= scores[best].switches,
                ),
                *(
                    (f"fused ≤ {kind}", fused.gospa <= scores[kind].gospa)
                    for kind in ("ss-gnn", "ss-jpda", "ss-gnn*", "ss-jpda*")
                ),
            ]
            for text, ok in checks:
                print(f"{scene.name:>12} goal {text}: {'met' if ok else 'NOT met'}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
