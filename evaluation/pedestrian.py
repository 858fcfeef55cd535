"""[MTT] §6.3.3 (Fig 20–23): classes that change, standard vs discounted credal classification.

Pedestrian 1 walks (steps 1–39), runs (40–119) and stops (120–239): after a
doubt it should be a sportsman, then a rambler. The stop is at step 120
because [MTT] puts the class change there ("suddenly at time step 120 the
likelihoods are associated to another class"; the standard algorithm
"cannot even compute the pignistic probabilities after time step 120"), and
the scene continues to 300 with walking from 240 for Fig 22–23 — the paper's
own timing, which is :func:`core.simulation.pedestrian_scenario`'s default
(one definition of the scene for this figure, Fig 19 and the tests;
**Reading:** the start of the run, step 40, and the speeds). It is tracked by the
pedestrian IMM on its own detections
(:func:`core.simulation.replay.replay_single_target`) and classified

- ``standard``: the conjunctive accumulation of [MTT] §5.2 (Fig 20: it
  cannot follow the stop — total conflict, or a mass stuck on sportsman);
- ``instantaneous 0.3``: the step mass discounted with λ = 0.3 (Fig 21);
- ``bayesian``: the Bayesian baseline, for comparison;

and, on the continued scene where it walks again from step 240 (Fig 22–23),
``cumulative 0.9`` (the accumulated mass discounted: it forgets and drifts
back to doubt on the shared walking behaviour) and ``instantaneous 0.9``.
The paper shows one realisation; so does this (one seed).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray, IntArray
from core.simulation import pedestrian_scenario
from core.simulation.pedestrian import STOP_AT
from core.simulation.replay import SingleTargetReplay, replay_single_target
from core.simulation.scenario import Scenario
from core.tracking.presets import pedestrian

TARGET = 1
WALK_AGAIN_AT = 240
"""[MTT] Fig 22–23: "a walking mode appears near time step 240"."""


def paper_scene(seed: int = 0, *, walk_again: bool = False) -> Scenario:
    """The pedestrians of [MTT] Fig 19: :func:`core.simulation.pedestrian_scenario` as it stands.

    Its default timing is the paper's (stop at 120, 240 steps); ``walk_again``
    continues to step 300 with walking from 240 (Fig 22–23).
    """
    return pedestrian_scenario(seed, walk_again_at=WALK_AGAIN_AT if walk_again else None)


RUNS: dict[str, tuple[bool, dict[str, object]]] = {
    "standard": (False, {"discount": "none"}),
    "instantaneous 0.3": (False, {"discount": "instantaneous", "reliability": 0.3}),
    "cumulative 0.9, walks again": (True, {"discount": "cumulative", "reliability": 0.9}),
    "instantaneous 0.9, walks again": (True, {"discount": "instantaneous", "reliability": 0.9}),
}
"""Label → (the continued scene?, credal options)."""


@dataclass(frozen=True)
class ClassTrace:
    """One classifier's output over time.

    Attributes
    ----------
    steps : ndarray of int64, shape (k,)
    probabilities : ndarray, shape (k, 2)
        BetP (credal) or posterior (Bayesian) of rambler, sportsman; NaN rows
        where the credal mass is in total conflict.
    step_conflicts : ndarray, shape (k,)
        K of each step's combination (zeros for the Bayesian baseline).
    """

    steps: IntArray
    probabilities: FloatArray
    step_conflicts: FloatArray

    def first_step_above(self, label_index: int, after: int, level: float = 0.5) -> float:
        """First step ≥ ``after`` where P(label) > ``level`` (NaN if never)."""
        rows = np.flatnonzero((self.steps >= after) & (self.probabilities[:, label_index] > level))
        return float(self.steps[rows[0]]) if len(rows) else float("nan")


@dataclass(frozen=True)
class PedestrianClassification:
    """Traces of every classifier of :data:`RUNS` plus the Bayesian baseline.

    Attributes
    ----------
    seed : int
    classes : tuple of str
        rambler, sportsman.
    traces : dict of str to ClassTrace
        Keys of :data:`RUNS` and ``"bayesian"``.
    phases : tuple of (int, int, str)
        Pedestrian 1's phases on the continued scene (first, last step, label).
    """

    seed: int
    classes: tuple[str, ...]
    traces: dict[str, ClassTrace]
    phases: tuple[tuple[int, int, str], ...]


def _credal_trace(replay: SingleTargetReplay) -> ClassTrace:
    return ClassTrace(replay.steps, replay.pignistic(), replay.step_conflicts())


def pedestrian_classification(seed: int = 0) -> PedestrianClassification:
    """Replay pedestrian 1 with each classifier of :data:`RUNS` (one realisation, ``seed``)."""
    preset = pedestrian()
    scenes = {False: paper_scene(seed), True: paper_scene(seed, walk_again=True)}
    traces: dict[str, ClassTrace] = {}
    for label, (continued, options) in RUNS.items():
        replay = replay_single_target(scenes[continued], TARGET, preset, options)
        traces[label] = _credal_trace(replay)
        if label == "standard":
            traces["bayesian"] = ClassTrace(
                replay.steps, replay.bayesian, np.zeros(len(replay.steps))
            )
    return PedestrianClassification(
        seed=seed,
        classes=preset.classes.labels,
        traces=traces,
        phases=tuple(
            (m.first_step, m.last_step, m.label)
            for m in scenes[True].manoeuvres
            if m.target_id == TARGET
        ),
    )


@dataclass(frozen=True)
class StopOutcomes:
    """What the standard and the instantaneous-0.3 classifiers do at the stop, per realisation.

    The paper shows one realisation; these are the claims of Fig 20–21 over
    several (seeded) noise realisations of the same scene.

    Attributes
    ----------
    seeds : tuple of int
    closest_to_total : ndarray, shape (runs,)
        Standard: the smallest 1 − K of a step's combination from the stop on
        (0: total conflict; BetP undefined from then on).
    undefined : ndarray of bool, shape (runs,)
        Standard: BetP undefined at some step from the stop on (total conflict).
    follows : ndarray of bool, shape (runs,)
        Standard: BetP(rambler) > 0.5 at some step from the stop on.
    rambler_from : ndarray, shape (runs,)
        Instantaneous λ = 0.3: first step ≥ the stop with BetP(rambler) > 0.5
        (NaN: never).
    """

    seeds: tuple[int, ...]
    closest_to_total: FloatArray
    undefined: np.ndarray
    follows: np.ndarray
    rambler_from: FloatArray


def stop_outcomes(seeds: tuple[int, ...] = tuple(range(20))) -> StopOutcomes:
    """Fig 20–21's claims over ``seeds`` (class change at :data:`core.simulation.pedestrian.STOP_AT`)."""
    preset = pedestrian()
    rambler = preset.classes.labels.index("rambler")
    closest, undefined, follows, rambler_from = [], [], [], []
    for seed in seeds:
        scene = paper_scene(seed)
        standard = _credal_trace(replay_single_target(scene, TARGET, preset, RUNS["standard"][1]))
        after = standard.steps >= STOP_AT
        closest.append(max(0.0, float(np.min(1.0 - standard.step_conflicts[after]))))
        undefined.append(bool(np.isnan(standard.probabilities[after]).any()))
        follows.append(not np.isnan(standard.first_step_above(rambler, STOP_AT)))
        discounted = replay_single_target(scene, TARGET, preset, RUNS["instantaneous 0.3"][1])
        rambler_from.append(_credal_trace(discounted).first_step_above(rambler, STOP_AT))
    return StopOutcomes(
        seeds=tuple(seeds),
        closest_to_total=np.array(closest),
        undefined=np.array(undefined),
        follows=np.array(follows),
        rambler_from=np.array(rambler_from),
    )
