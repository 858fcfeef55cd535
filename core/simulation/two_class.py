"""The ``t2t-two-class`` scenario: [T2T] §4 scenario 2 (Fig 5–6).

Two nearby targets of different classes, both seen at every step by two
sensors that report track lists; each reported track carries the class mass
function of that sensor's own classifier ([T2T] §2 Fig 2: "local
classification feedbacks"). The experiment compares association on distance
only with association on distance and class (:mod:`evaluation.two_class`).

**Reading:** [T2T] gives neither coordinates, nor noise, nor the class
masses (Fig 5 is not in the text). Here:

- the targets fly east at 10 m/s on parallel lines ``separation`` metres
  apart (target 0 of class ``c1`` below, target 1 of class ``c2`` above);
- a sensor's estimate is the true state plus an error drawn from the
  covariance it reports (round, position σ ``position_sigma``, velocity σ
  half of it), independently at every report, as in
  :func:`core.simulation.tracklists.t2t_four`; sensor ``s2`` reports 1 ms
  after ``s1``;
- a sensor's class mass function on {c1, c2} puts ``s`` on one singleton and
  ``1 − s`` on the whole frame, with ``s = class_confidence × U(0.5, 1)``;
  the singleton is the true class, or the other one with probability
  ``class_error`` (a local classifier that is sometimes wrong).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray
from core.belief import Frame, MassFunction
from core.errors import ScenarioError
from core.simulation.scenario import TargetTruth
from core.simulation.tracklists import SensorTrackList, estimate_covariance

CLASSES = Frame(("c1", "c2"))
"""The class frame C = {c1, c2} ([T2T] §2 notation)."""

SENSORS = ("s1", "s2")
SPEED = 10.0
"""Speed of both targets (m/s), along x."""
REPORT_OFFSET = 1e-3
"""Delay of ``s2``'s report after ``s1``'s, as a fraction of the time interval."""


@dataclass(frozen=True)
class ClassifiedTrackListScenario:
    """Ground truth and the sensors' track lists with one class mass per track.

    Attributes
    ----------
    name : str
    seed : int
    sensors : tuple of str
    classes : Frame
        The class frame.
    true_classes : tuple of str
        The class label of each target, indexed by target id.
    truths : tuple of TargetTruth
    reports : tuple of SensorTrackList
        In arrival order (``s1`` then ``s2`` at every step).
    class_masses : tuple of tuple of MassFunction
        ``class_masses[r][i]`` is the class mass function of track ``i`` of
        ``reports[r]``.
    """

    name: str
    seed: int
    sensors: tuple[str, ...]
    classes: Frame
    true_classes: tuple[str, ...]
    truths: tuple[TargetTruth, ...]
    reports: tuple[SensorTrackList, ...]
    class_masses: tuple[tuple[MassFunction, ...], ...]


def _class_mass(
    rng: np.random.Generator, true_index: int, confidence: float, error: float
) -> MassFunction:
    support = confidence * rng.uniform(0.5, 1.0)
    label = true_index if rng.random() >= error else 1 - true_index
    singleton = 1 << label
    if support <= 0.0:
        return MassFunction.vacuous(CLASSES)
    return MassFunction.from_masks(CLASSES, [singleton, CLASSES.full], [support, 1.0 - support])


def t2t_two_class(
    seed: int = 0,
    position_sigma: float = 0.5,
    separation: float = 1.5,
    n_steps: int = 20,
    class_confidence: float = 0.9,
    class_error: float = 0.05,
    time_interval: float = 1.0,
) -> ClassifiedTrackListScenario:
    """Two targets ``separation`` metres apart, of classes c1 and c2, seen by two sensors.

    Parameters
    ----------
    seed : int
        Seeds every random draw (errors, class masses).
    position_sigma : float > 0
        Position σ (m) of the reported covariance and of the actual errors.
    separation : float > 0
        Distance (m) between the two parallel tracks.
    n_steps : int > 0
    class_confidence : float in [0, 1]
        Upper bound of the mass a sensor puts on a singleton class.
    class_error : float in [0, 1]
        Probability that a sensor's singleton is the wrong class.
    time_interval : float > 0

    Returns
    -------
    ClassifiedTrackListScenario
        ``2 × n_steps`` reports of two tracks each, tracks in target order.

    Raises
    ------
    ScenarioError
        A parameter is out of its range.
    """
    if not (
        position_sigma > 0.0
        and separation > 0.0
        and n_steps > 0
        and time_interval > 0.0
        and 0.0 <= class_confidence <= 1.0
        and 0.0 <= class_error <= 1.0
    ):
        raise ScenarioError(
            "t2t_two_class needs positive σ, separation, steps and interval, "
            "and class confidence and error in [0, 1]"
        )
    rng = np.random.default_rng(seed)
    times = np.arange(n_steps, dtype=np.float64) * time_interval
    truths = tuple(
        TargetTruth(target, 0, _straight(times, target * separation)) for target in (0, 1)
    )
    covariance = estimate_covariance(position_sigma, position_sigma / 2.0)
    root = np.linalg.cholesky(covariance)
    reports: list[SensorTrackList] = []
    masses: list[tuple[MassFunction, ...]] = []
    for step in range(n_steps):
        for offset, sensor in enumerate(SENSORS):
            lag = offset * REPORT_OFFSET * time_interval
            exact = np.array([truth.state_at(step) for truth in truths])
            exact[:, 0] += exact[:, 1] * lag
            exact[:, 2] += exact[:, 3] * lag
            errors = rng.standard_normal((2, 4)) @ root.T
            reports.append(
                SensorTrackList(
                    sensor=sensor,
                    time=step * time_interval + lag,
                    step=step,
                    track_ids=(f"{sensor}-0", f"{sensor}-1"),
                    states=exact + errors,
                    covariances=np.repeat(covariance[None], 2, axis=0),
                    target_ids=np.array([0, 1], dtype=np.int64),
                )
            )
            masses.append(
                tuple(_class_mass(rng, target, class_confidence, class_error) for target in (0, 1))
            )
    return ClassifiedTrackListScenario(
        name="t2t-two-class",
        seed=seed,
        sensors=SENSORS,
        classes=CLASSES,
        true_classes=CLASSES.labels,
        truths=truths,
        reports=tuple(reports),
        class_masses=tuple(masses),
    )


def _straight(times: FloatArray, y: float) -> FloatArray:
    states = np.zeros((len(times), 4))
    states[:, 0] = SPEED * times
    states[:, 1] = SPEED
    states[:, 2] = y
    return states
