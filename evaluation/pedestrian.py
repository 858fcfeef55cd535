"""[MTT] §6.3.3 (Fig 20–23): classes that change, standard vs discounted credal classification.

Pedestrian 1 walks (steps 1–39), runs (40–59) and stops (60–139): after a
doubt it should be a sportsman, then a rambler. It is tracked by the
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
from core.simulation.replay import SingleTargetReplay, replay_single_target
from core.tracking.presets import pedestrian

TARGET = 1
WALK_AGAIN_AT = 240

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
    scenes = {
        False: pedestrian_scenario(seed=seed),
        True: pedestrian_scenario(seed=seed, walk_again_at=WALK_AGAIN_AT),
    }
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
