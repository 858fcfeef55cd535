"""[MTT] Fig 4–5, 10–11 and 19: the scenes themselves, tracked — and the track scores.

- Fig 10–11: the four aircraft of :func:`core.simulation.aircraft_scenario`
  tracked by the :class:`LocalTracker` (13-model IMM, GNN): measurements and
  estimates in the plane and x over time. [MTT]: targets 3 and 4 appear at
  steps 30 and 70, target 2 disappears at 100 and "the algorithm continues to
  predict its trajectory until the end of the simulation at time step 120
  because its score function has not yet reached the deletion threshold".
- Fig 4–5: the score L ([MTT] eq 16) of each track. [MTT]'s own Fig 4–5
  scene is given only by its events (targets 3, 4 appear at 15, 45; targets
  2, 3, 4 are not detected from steps 35, 55, 90; target 2 is deleted at 100;
  target 3 reappears at 69). **Reading:** we impose those detection gaps on
  the Fig 10 scene (:data:`SCORE_GAPS`: the detections of a target in its
  gaps are removed); its appearances stay at 30 and 70.
- Fig 19: the pedestrians' y over time (:func:`evaluation.pedestrian.paper_scene`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from core.arrays import BoolArray, FloatArray, IntArray
from core.simulation import aircraft_scenario
from core.simulation.scenario import Scenario
from core.tracking.config import LocalTrackerConfig
from evaluation.pedestrian import paper_scene
from evaluation.tracking import NO_TERMINATION, life_cycle, track_scenario

SCORE_GAPS: dict[int, tuple[int, int]] = {2: (35, 120), 3: (55, 68), 4: (90, 120)}
"""Target → (first, last) step without detections ([MTT] §4.3's events)."""


@dataclass(frozen=True)
class TrackedScene:
    """One tracked scene for the plan, time and score panels.

    Attributes
    ----------
    truths : dict of int to ndarray, shape (steps, 4)
        Truth per target, NaN where absent.
    detection_steps : ndarray of int64, shape (m,)
    detections : ndarray, shape (m, 2)
    detection_targets : ndarray of int64, shape (m,)
    tracks : dict of str to ndarray, shape (steps, 4)
        Every confirmed track's estimate, NaN where absent.
    scores : dict of str to ndarray, shape (steps,)
        The same tracks' scores L.
    delete_threshold, confirm_threshold : float
        The SPRT thresholds T₁ (deletion) and T₂ (confirmation).
    last_step : dict of str to int
        The last step each track was alive.
    """

    truths: dict[int, FloatArray]
    detection_steps: IntArray
    detections: FloatArray
    detection_targets: IntArray
    tracks: dict[str, FloatArray]
    scores: dict[str, FloatArray]
    delete_threshold: float
    confirm_threshold: float
    last_step: dict[str, int]


def _without_gaps(scenario: Scenario, gaps: dict[int, tuple[int, int]]) -> Scenario:
    scans = []
    for scan in scenario.scans:
        keep = np.array(
            [
                not (int(t) in gaps and gaps[int(t)][0] <= scan.step <= gaps[int(t)][1])
                for t in scan.target_ids
            ],
            dtype=bool,
        ).reshape(-1)
        scans.append(
            replace(scan, measurements=scan.measurements[keep], target_ids=scan.target_ids[keep])
        )
    return replace(scenario, scans=tuple(scans))


def tracked_aircraft(
    seed: int = 0, *, gaps: bool = False, raw_score: bool = True, n_steps: int = 121
) -> TrackedScene:
    """Fig 10–11 (``gaps=False``) or Fig 4–5's events (``gaps=True``), one seeded run.

    ``raw_score``: [MTT] §4.3's plain SPRT (no score clamp, no gate-emptiness
    test: :data:`~evaluation.tracking.NO_TERMINATION`); False: our default
    life cycle, whose score is clamped near the confirmation threshold.
    """
    scenario = aircraft_scenario(seed=seed, n_steps=n_steps)
    if gaps:
        scenario = _without_gaps(scenario, SCORE_GAPS)
    settings: dict[str, object] = dict(NO_TERMINATION) if raw_score else {}
    config = LocalTrackerConfig.paper(
        fields_of_view={"radar": None}, life_cycle=life_cycle(settings)
    )
    run = track_scenario(scenario, config)
    truths = {}
    for truth in scenario.truths:
        states = np.full((scenario.n_steps, 4), np.nan)
        states[truth.first_step : truth.first_step + len(truth.states)] = truth.states
        truths[truth.target_id] = states
    confirmed = sorted(run.confirmed_ids())
    tracks = {track: run.trajectory(track, scenario.n_steps) for track in confirmed}
    return TrackedScene(
        truths=truths,
        detection_steps=run.detection_steps,
        detections=run.measurements,
        detection_targets=run.detection_targets,
        tracks=tracks,
        scores={track: run.score_of(track, scenario.n_steps) for track in confirmed},
        delete_threshold=float(config.score.delete_threshold),
        confirm_threshold=float(config.score.confirm_threshold),
        last_step={track: max(run.status_of(track)) for track in confirmed},
    )


@dataclass(frozen=True)
class SceneEvents:
    """[MTT] Fig 4–5 and 10–11's events over seeds (plain SPRT), one entry per seed.

    Attributes
    ----------
    seeds : tuple of int
    target_2_predicted_to_end : ndarray of bool
        Fig 10–11 scene: target 2's track is still alive at the last step (the paper's claim).
    target_4_taken : ndarray of bool
        Fig 4–5 events: target 4's detections (steps 70–89) went mostly to target 2's
        coasting track (the event one seed showed).
    """

    seeds: tuple[int, ...]
    target_2_predicted_to_end: BoolArray
    target_4_taken: BoolArray


def scene_events(seeds: Sequence[int], n_steps: int = 121) -> SceneEvents:
    """Count the plain-SPRT events of :func:`tracked_aircraft` over ``seeds``."""
    alive, taken = [], []
    config = LocalTrackerConfig(
        fields_of_view={"radar": None}, life_cycle=life_cycle(dict(NO_TERMINATION))
    )
    for seed in seeds:
        plain = aircraft_scenario(seed=seed, n_steps=n_steps)
        run = track_scenario(plain, config)
        own = run.track_of(2, 1, 34)
        alive.append(own is not None and max(run.status_of(own)) == n_steps - 1)
        gapped = track_scenario(_without_gaps(plain, SCORE_GAPS), config)
        own = gapped.track_of(2, 1, 34)
        taken.append(own is not None and gapped.track_of(4, 70, 89) == own)
    return SceneEvents(tuple(seeds), np.array(alive), np.array(taken))


def pedestrian_truths(seed: int = 0) -> FloatArray:
    """Fig 19: the two pedestrians' y over time on the continued scene, shape (2, steps)."""
    scenario = paper_scene(seed, walk_again=True)
    return np.stack([truth.states[:, 2] for truth in scenario.truths])
