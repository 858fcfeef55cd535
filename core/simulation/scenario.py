"""Ground truth and simulated detections: the plain data every scenario returns.

Conventions shared by the generators:

- Steps are integers ``0 .. n_steps − 1``, time ``step × time_interval``.
- The state is ``[x, ẋ, y, ẏ]``; a target's input ``u_k`` (or speed) at step k
  drives the transition from step k − 1 to step k, so a manoeuvre "during
  steps 50–54" shows in the positions of steps 50 … 54.
- A target "appears at k" has a first truth state at step k; it "disappears at
  k" has its last truth state at step k − 1 and no detection from k on.
- Detections of a scan carry the id of the target they come from (−1 for
  clutter), for evaluation only: a tracker must not read them.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TypeAlias

import numpy as np

from core.arrays import FloatArray, IntArray
from core.errors import ScenarioError
from core.tracking.models import POSITION_INDICES, input_matrix

CLUTTER = -1
"""Target id of a clutter (false alarm) detection."""

Region: TypeAlias = tuple[tuple[float, float], tuple[float, float]]
"""An axis-aligned rectangle ``((x_min, x_max), (y_min, y_max))``."""


def inside(region: Region, position: FloatArray) -> bool:
    """Whether ``position`` (x, y) lies in ``region`` (bounds included)."""
    (x0, x1), (y0, y1) = region
    return bool(x0 <= position[0] <= x1 and y0 <= position[1] <= y1)


@dataclass(frozen=True)
class TargetTruth:
    """The true trajectory of one target.

    Attributes
    ----------
    target_id : int
    first_step : int
        Step of the first state.
    states : ndarray, shape (k, 4)
        States at steps ``first_step .. first_step + k − 1``.
    """

    target_id: int
    first_step: int
    states: FloatArray

    @property
    def last_step(self) -> int:
        """Step of the last state (inclusive)."""
        return self.first_step + len(self.states) - 1

    def alive(self, step: int) -> bool:
        """Whether the target exists at ``step``."""
        return self.first_step <= step <= self.last_step

    def state_at(self, step: int) -> FloatArray:
        """The true state at ``step``."""
        if not self.alive(step):
            raise ScenarioError(f"target {self.target_id} does not exist at step {step}")
        return np.asarray(self.states[step - self.first_step], dtype=np.float64)


@dataclass(frozen=True)
class Manoeuvre:
    """A window of steps (inclusive) during which a target follows a given input or phase.

    Attributes
    ----------
    target_id : int
    first_step, last_step : int
    label : str
        E.g. ``"2g"``, ``"4g"``, ``"run"``.
    value : tuple of float
        The acceleration input (m/s²) or the speeds (m/s) of that window.
    """

    target_id: int
    first_step: int
    last_step: int
    label: str
    value: tuple[float, float]


@dataclass(frozen=True)
class Scan:
    """The detections of one sensor at one step.

    Attributes
    ----------
    step : int
    time : float
    sensor : str
    measurements : ndarray, shape (m, 2)
    target_ids : ndarray of int64, shape (m,)
        Origin of each detection (:data:`CLUTTER` for false alarms).
    """

    step: int
    time: float
    sensor: str
    measurements: FloatArray
    target_ids: IntArray


@dataclass(frozen=True)
class Scenario:
    """A seeded scenario: truth, manoeuvre windows and scans.

    Attributes
    ----------
    name : str
    seed : int
    time_interval : float
    n_steps : int
    truths : tuple of TargetTruth
    manoeuvres : tuple of Manoeuvre
    scans : tuple of Scan
        In time order; several scans per step when several sensors observe.
    measurement_noise : ndarray, shape (2, 2)
        The R used to simulate the detections.
    sensor_regions : dict
        What each simulated sensor sees, as an axis-aligned rectangle
        ``{sensor: ((x_min, x_max), (y_min, y_max))}``; empty when one sensor
        sees everything.
    """

    name: str
    seed: int
    time_interval: float
    n_steps: int
    truths: tuple[TargetTruth, ...]
    manoeuvres: tuple[Manoeuvre, ...]
    scans: tuple[Scan, ...]
    measurement_noise: FloatArray
    sensor_regions: Mapping[str, Region] = field(default_factory=dict)

    def truth(self, target_id: int) -> TargetTruth:
        """The truth of one target."""
        for truth in self.truths:
            if truth.target_id == target_id:
                return truth
        raise ScenarioError(f"no target {target_id} in scenario {self.name!r}")

    def detections(self, target_id: int) -> tuple[IntArray, FloatArray]:
        """Steps and measurements ``(k,), (k, 2)`` of one target's own detections."""
        steps: list[int] = []
        rows: list[FloatArray] = []
        for scan in self.scans:
            hits = scan.target_ids == target_id
            steps.extend([scan.step] * int(hits.sum()))
            rows.extend(scan.measurements[hits])
        return np.asarray(steps, dtype=np.int64), np.asarray(rows, dtype=np.float64).reshape(-1, 2)


def propagate(
    initial: Sequence[float],
    accelerations: FloatArray,
    time_interval: float,
    noise_intensity: float,
    rng: np.random.Generator,
) -> FloatArray:
    """Truth by [MTT] eq 24: ``x_k = F x_{k−1} + B u_k + w_k``, ``w ~ N(0, q B Bᵀ)``.

    ``accelerations[k]`` (shape (k, 2)) drives the step into state k (row 0 is unused).
    Returns the states, shape (k, 4).
    """
    b = input_matrix(time_interval)
    f = np.array(
        [[1, time_interval, 0, 0], [0, 1, 0, 0], [0, 0, 1, time_interval], [0, 0, 0, 1]],
        dtype=np.float64,
    )
    steps = len(accelerations)
    states = np.zeros((steps, 4))
    states[0] = initial
    noise = rng.standard_normal((steps, 2)) * np.sqrt(noise_intensity)
    for k in range(1, steps):
        states[k] = f @ states[k - 1] + b @ (accelerations[k] + noise[k])
    return states


def observe(
    truths: Sequence[TargetTruth],
    n_steps: int,
    time_interval: float,
    measurement_noise: FloatArray,
    rng: np.random.Generator,
    *,
    sensor: str = "sensor",
    p_detect: float = 1.0,
    clutter_rate: float = 0.0,
    region: Region | None = None,
    visible: Callable[[FloatArray], bool] | None = None,
) -> list[Scan]:
    """Simulate one sensor: noisy positions with probability ``p_detect``, plus clutter.

    Parameters
    ----------
    clutter_rate : float
        Mean of the Poisson number of false alarms per scan, uniform in ``region``.
    region : ((x_min, x_max), (y_min, y_max)), optional
        Needed when ``clutter_rate > 0``; clutter falling outside ``visible`` is dropped.
    visible : callable, optional
        ``visible(position) -> bool``: whether the sensor sees a position.
    """
    if clutter_rate > 0.0 and region is None:
        raise ScenarioError("clutter needs a region")
    # Square root of a positive semi-definite R (R = 0 gives noise-free detections).
    eigenvalues, eigenvectors = np.linalg.eigh(np.asarray(measurement_noise, dtype=np.float64))
    chol = eigenvectors * np.sqrt(np.clip(eigenvalues, 0.0, None))
    pos = list(POSITION_INDICES)
    scans: list[Scan] = []
    for step in range(n_steps):
        rows: list[FloatArray] = []
        ids: list[int] = []
        for truth in truths:
            if not truth.alive(step):
                continue
            position = truth.state_at(step)[pos]
            seen = visible is None or visible(position)
            if seen and rng.random() < p_detect:
                rows.append(position + chol @ rng.standard_normal(2))
                ids.append(truth.target_id)
        if clutter_rate > 0.0 and region is not None:
            (x0, x1), (y0, y1) = region
            for _ in range(rng.poisson(clutter_rate)):
                point = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
                if visible is None or visible(point):
                    rows.append(point)
                    ids.append(CLUTTER)
        scans.append(
            Scan(
                step=step,
                time=step * time_interval,
                sensor=sensor,
                measurements=np.asarray(rows, dtype=np.float64).reshape(-1, 2),
                target_ids=np.asarray(ids, dtype=np.int64),
            )
        )
    return scans
