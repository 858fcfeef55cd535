"""[MTT] §6.1.3 (Fig 12–15): credal vs Bayesian classification of aircraft target 2.

Target 2 of the ``aircraft`` scenario flies straight, makes a 2g manoeuvre
(steps 50–54), a sharp 4g one (70–75) and disappears at step 100. It is
tracked by the 13-model IMM on its own detections and classified by the
credal chain and the Bayesian baseline (whose behaviour posteriors are
Fig 13)
(:func:`core.simulation.replay.replay_single_target`); the paper's Fig 12–13
are "averages of 20 Monte Carlo simulations", and so are these curves.

Both readings of μ_j in [MTT] eq 19/22 are run (``mode_probabilities``:
the IMM's posterior ``"updated"``, or the step's prior ``"predicted"``; the
Reading in :mod:`core.classification.behaviours`): Fig 12–13's claims turn on
it.

The paper's claim (Fig 14–15): the credal classifier shows total ignorance
before the first manoeuvre, a doubt between bomber and fighter after it and
fighter after the sharp one; the Bayesian classifier ends on fighter too but
"fails in doubt situations" (it favours one of bomber and fighter).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray, IntArray
from core.classification.bayesian import class_given_behaviour
from core.classification.behaviours import ModeProbabilities
from core.metrics import time_to_decision
from core.simulation import aircraft_scenario
from core.simulation.replay import replay_single_target
from core.tracking.presets import aircraft

TARGET = 2
DOUBT_STEPS = (55, 69)
"""Between the manoeuvres: the truth allows bomber and fighter."""


@dataclass(frozen=True)
class AircraftClassification:
    """Class probabilities of target 2 over time, per Monte Carlo run.

    Attributes
    ----------
    seeds : tuple of int
    classes : tuple of str
        liner, bomber, fighter.
    steps : ndarray of int64, shape (k,)
    credal : ndarray, shape (runs, k, 3)
        BetP of the credal classifier.
    bayesian : ndarray, shape (runs, k, 3)
        Class probabilities of the Bayesian baseline.
    bayesian_behaviours : ndarray, shape (runs, k, 3)
        Its behaviour posteriors P(b | Z_k) (Fig 13): ``P(C) = M P(B)`` ([MTT]
        eq 21) solved for P(B) — M is square and triangular for the aircraft
        (1/3, 1/2, 1 on its diagonal), so the class probabilities determine them.
    behaviours : ndarray, shape (runs, k, 3)
        Scaled behaviour plausibilities (Fig 12); NaN once the target is gone.
    manoeuvres : tuple of (int, int, str)
        The manoeuvre windows of target 2 (first step, last step, label).
    mode_probabilities : "updated" | "predicted"
        The μ reading the classifiers ran with.
    """

    seeds: tuple[int, ...]
    classes: tuple[str, ...]
    steps: IntArray
    credal: FloatArray
    bayesian: FloatArray
    bayesian_behaviours: FloatArray
    behaviours: FloatArray
    manoeuvres: tuple[tuple[int, int, str], ...]
    mode_probabilities: ModeProbabilities = "updated"

    def b1_margin(self, first: int = 10, last: int = 49) -> FloatArray:
        """Per run, mean over the steps of Pl(b1) − max(Pl(b2), Pl(b3)) (Fig 12: > 0 claimed)."""
        rows = (self.steps >= first) & (self.steps <= last)
        pl = self.behaviours[:, rows]
        return np.asarray(np.mean(pl[:, :, 0] - pl[:, :, 1:].max(axis=2), axis=1), dtype=np.float64)

    def b1_growth(self, first: int = 5, last: int = 49) -> FloatArray:
        """Per run, P(b1 | Z) at ``last`` minus at ``first`` (Fig 13: b1 "tends to grow")."""
        i, j = (int(np.flatnonzero(self.steps == k)[0]) for k in (first, last))
        return np.asarray(
            self.bayesian_behaviours[:, j, 0] - self.bayesian_behaviours[:, i, 0], dtype=np.float64
        )

    def doubt_gap(self, kind: str) -> float:
        """Mean |P(bomber) − P(fighter)| over the doubt steps 55–69 (0: a perfect doubt)."""
        probabilities = self.credal if kind == "credal" else self.bayesian
        rows = (self.steps >= DOUBT_STEPS[0]) & (self.steps <= DOUBT_STEPS[1])
        bomber, fighter = self.classes.index("bomber"), self.classes.index("fighter")
        return float(
            np.mean(np.abs(probabilities[:, rows, bomber] - probabilities[:, rows, fighter]))
        )

    def decision_steps(self, kind: str, label: str = "fighter", level: float = 0.9) -> FloatArray:
        """Per run, the first step from which P(label) stays ≥ ``level`` to the end (NaN: never).

        :func:`core.metrics.time_to_decision` counted from the first classified step.
        """
        probabilities = self.credal if kind == "credal" else self.bayesian
        delay = time_to_decision(probabilities, self.classes.index(label), level=level)
        return np.asarray(self.steps[0] + delay, dtype=np.float64)

    def decision_step(self, kind: str, label: str = "fighter", level: float = 0.9) -> float:
        """Mean over the runs of :meth:`decision_steps`."""
        return float(np.mean(self.decision_steps(kind, label, level)))

    def run_spread(self, kind: str) -> float:
        """Largest range over the runs, at any step and class, of the probabilities.

        0 when every run gives the same curve. It is ~0 here although every
        run has its own noise (the seed is varied): at σ² = 0.2 m² the
        behaviour plausibilities are 0 or 1 at nearly every step of every run
        (the manoeuvre likelihood ratios are decisive), and the class outputs
        are functions of them.
        """
        probabilities = self.credal if kind == "credal" else self.bayesian
        return float(np.nanmax(np.ptp(probabilities, axis=0)))


def aircraft_classification(
    seeds: Sequence[int] = tuple(range(20)), mode_probabilities: ModeProbabilities = "updated"
) -> AircraftClassification:
    """Replay target 2 of the ``aircraft`` scenario once per seed ([MTT]: 20 runs)."""
    preset = aircraft()
    replays = [
        replay_single_target(
            aircraft_scenario(seed=seed), TARGET, preset, mode_probabilities=mode_probabilities
        )
        for seed in seeds
    ]
    scenario = aircraft_scenario(seed=seeds[0])
    bayesian = np.stack([replay.bayesian for replay in replays])
    matrix = class_given_behaviour(preset.relation)  # (|C|, |B|)
    behaviour_posteriors = np.asarray(
        np.linalg.solve(matrix, bayesian.reshape(-1, 3).T).T, dtype=np.float64
    )
    return AircraftClassification(
        seeds=tuple(seeds),
        classes=preset.classes.labels,
        steps=replays[0].steps,
        credal=np.stack([replay.pignistic() for replay in replays]),
        bayesian=bayesian,
        bayesian_behaviours=behaviour_posteriors.reshape(bayesian.shape),
        behaviours=np.stack([replay.behaviour_plausibilities for replay in replays]),
        manoeuvres=tuple(
            (m.first_step, m.last_step, m.label)
            for m in scenario.manoeuvres
            if m.target_id == TARGET
        ),
        mode_probabilities=mode_probabilities,
    )
