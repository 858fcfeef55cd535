"""[MTT] §6.3.3 (Fig 20–23): classes that change, standard vs discounted credal classification.

Pedestrian 1 walks (steps 1–39), runs (40–119) and stops (120–239): after a
doubt it should be a sportsman, then a rambler. The stop is at step 120
because [MTT] puts the class change there ("suddenly at time step 120 the
likelihoods are associated to another class"; the standard algorithm
"cannot even compute the pignistic probabilities after time step 120"), and
the scene continues to 300 with walking from 240 for Fig 22–23 — the paper's
own timing (:func:`paper_scenario`). **Reading:** the start of the run (step
40) and the speeds are those of :func:`core.simulation.pedestrian_scenario`,
whose stop at step 60 is our earlier, shorter variant. It is tracked by the
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
from core.simulation.pedestrian import RUN, STOP, WALK
from core.simulation.replay import SingleTargetReplay, replay_single_target
from core.simulation.scenario import Manoeuvre, Scenario, TargetTruth, observe
from core.tracking.presets import pedestrian

TARGET = 1
RUN_AT = 40
STOP_AT = 120
"""[MTT] §6.3.3: the class change (sportsman → rambler) at time step 120."""
WALK_AGAIN_AT = 240
"""[MTT] Fig 22–23: "a walking mode appears near time step 240"."""
SCENE_STEPS = (240, 300)
"""Steps of the scene without and with the second walk."""
MEASUREMENT_VARIANCE = 0.05
"""R of the ``pedestrian`` preset (m² per axis)."""


def paper_scenario(seed: int = 0, *, walk_again: bool = False) -> Scenario:
    """The pedestrians of [MTT] Fig 19 with the paper's timing (module docstring).

    Pedestrian 1: walk (2, 2) m/s to step 39, run (6, 6) to 119, stop (0, 0)
    from 120 (to 239, then walk again with ``walk_again``); pedestrian 2 walks
    (2, 0) throughout, 50 m away; no process noise, R = 0.05 I, P_D = 1 —
    :func:`core.simulation.pedestrian_scenario`'s construction with the stop moved.
    """
    steps = SCENE_STEPS[walk_again]
    rng = np.random.default_rng(seed)
    windows = [
        Manoeuvre(1, 1, RUN_AT - 1, "walk", WALK),
        Manoeuvre(1, RUN_AT, STOP_AT - 1, "run", RUN),
        Manoeuvre(1, STOP_AT, (WALK_AGAIN_AT if walk_again else steps) - 1, "stop", STOP),
    ]
    if walk_again:
        windows.append(Manoeuvre(1, WALK_AGAIN_AT, steps - 1, "walk", WALK))
    windows.append(Manoeuvre(2, 1, steps - 1, "walk", (2.0, 0.0)))
    truths = []
    for target_id, y0 in ((1, 0.0), (2, 50.0)):
        speeds = np.zeros((steps, 2))
        for window in windows:
            if window.target_id == target_id:
                speeds[window.first_step : window.last_step + 1] = window.value
        states = np.zeros((steps, 4))
        states[:, 1] = states[:, 3] = 1.0  # headings h = +1 ([MTT] eq 26)
        states[:, 0] = np.cumsum(speeds[:, 0])
        states[:, 2] = y0 + np.cumsum(speeds[:, 1])
        truths.append(TargetTruth(target_id, 0, states))
    noise = MEASUREMENT_VARIANCE * np.eye(2)
    return Scenario(
        name="pedestrian",
        seed=seed,
        time_interval=1.0,
        n_steps=steps,
        truths=tuple(truths),
        manoeuvres=tuple(windows),
        scans=tuple(observe(truths, steps, 1.0, noise, rng, sensor="camera")),
        measurement_noise=noise,
    )


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
    scenes = {False: paper_scenario(seed), True: paper_scenario(seed, walk_again=True)}
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
