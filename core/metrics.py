"""Evaluation metrics (EVALUATION.md "Metrics").

- :func:`ospa` — Optimal SubPattern Assignment distance (Schuhmacher, Vo & Vo 2008);
- :func:`gospa` — Generalised OSPA with α = 2 and its decomposition into
  localisation, missed and false parts (Rahmathullah, García-Fernández & Svensson 2017);
- :func:`rms_error`, :func:`time_mean_error` — Monte-Carlo RMS error per
  step and its time mean ([DH] §5 eq 28-29);
- :func:`false_decision_rate` — the share of association decisions that
  differ from the truth ([T2T] §4, [MTT] §6.2.1);
- :func:`identity_switches` — how often a true object changes fused identity.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

from core.arrays import FloatArray
from core.errors import InvalidInput

Key = TypeVar("Key")
Identity = TypeVar("Identity")


def _points(points: ArrayLike, name: str) -> FloatArray:
    array = np.asarray(points, dtype=np.float64)
    if array.ndim == 1 and array.size == 0:
        array = array.reshape(0, 1)
    if array.ndim != 2:
        raise InvalidInput(f"{name} must be a 2-D array of points (n, d), got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise InvalidInput(f"{name} must be finite")
    return array


def _check_cutoff(cutoff: float, order: float) -> None:
    if not (np.isfinite(cutoff) and cutoff > 0.0):
        raise InvalidInput(f"cutoff must be a positive number, got {cutoff!r}")
    if not (np.isfinite(order) and order >= 1.0):
        raise InvalidInput(f"order must be a finite number >= 1, got {order!r}")


def _cut_costs(
    estimates: FloatArray, truths: FloatArray, cutoff: float, order: float
) -> FloatArray:
    if estimates.shape[1] != truths.shape[1] and len(estimates) and len(truths):
        raise InvalidInput(f"points differ in dimension: {estimates.shape[1]} vs {truths.shape[1]}")
    return np.asarray(np.minimum(cdist(estimates, truths), cutoff) ** order, dtype=np.float64)


def ospa(estimates: ArrayLike, truths: ArrayLike, cutoff: float, order: float = 1.0) -> float:
    """OSPA distance of order p with cut-off c between two finite sets of points."""
    _check_cutoff(cutoff, order)
    x, y = _points(estimates, "estimates"), _points(truths, "truths")
    n = max(len(x), len(y))
    if n == 0:
        return 0.0
    if min(len(x), len(y)) == 0:
        return float(cutoff)
    costs = _cut_costs(x, y, cutoff, order)
    rows, cols = linear_sum_assignment(costs)
    total = costs[rows, cols].sum() + cutoff**order * abs(len(x) - len(y))
    return float((total / n) ** (1.0 / order))


@dataclass(frozen=True)
class Gospa:
    """GOSPA (α = 2) and its parts; ``distance = (localisation + missed + false)^(1/p)``."""

    distance: float
    localisation: float
    missed: float
    false: float


def gospa(estimates: ArrayLike, truths: ArrayLike, cutoff: float, order: float = 1.0) -> Gospa:
    """GOSPA with α = 2: assigned pairs cost d^p, every missed or false point c^p / 2."""
    _check_cutoff(cutoff, order)
    x, y = _points(estimates, "estimates"), _points(truths, "truths")
    unmatched_cost = cutoff**order / 2.0
    localisation = 0.0
    matched = 0
    if len(x) and len(y):
        costs = _cut_costs(x, y, cutoff, order)
        rows, cols = linear_sum_assignment(costs)
        # A pair at the cut-off is no better than leaving both unassigned (c^p = 2 · c^p/2).
        real = costs[rows, cols] < cutoff**order
        localisation = float(costs[rows, cols][real].sum())
        matched = int(real.sum())
    missed = unmatched_cost * (len(y) - matched)
    false = unmatched_cost * (len(x) - matched)
    return Gospa(
        distance=float((localisation + missed + false) ** (1.0 / order)),
        localisation=localisation,
        missed=float(missed),
        false=float(false),
    )


def rms_error(truths: ArrayLike, estimates: ArrayLike) -> FloatArray:
    """RMS error per step over Monte-Carlo runs ([DH] eq 28).

    ``truths`` and ``estimates`` have shape (runs, steps, d) (or (steps, d) for
    one run); returns ``sqrt(mean_runs ‖x − x̂‖²)`` per step.
    """
    x = np.asarray(truths, dtype=np.float64)
    x_hat = np.asarray(estimates, dtype=np.float64)
    if x.shape != x_hat.shape or x.ndim not in (2, 3):
        raise InvalidInput(
            f"truths and estimates must share a (runs, steps, d) shape: {x.shape} vs {x_hat.shape}"
        )
    if x.ndim == 2:
        x, x_hat = x[None], x_hat[None]
    squared = np.sum((x - x_hat) ** 2, axis=-1)
    return np.asarray(np.sqrt(squared.mean(axis=0)), dtype=np.float64)


def time_mean_error(rms: ArrayLike) -> float:
    """Time-mean of the RMS error over the N steps ([DH] eq 29)."""
    return float(np.mean(np.asarray(rms, dtype=np.float64)))


def false_decision_rate(
    decisions: Sequence[Mapping[Key, Identity | None]],
    truth: Sequence[Mapping[Key, Identity | None]],
) -> float:
    """Share of decisions that differ from the truth, over every step.

    Each step maps an incoming item to the known item it was assigned to
    (``None``: declared new). An item missing from ``decisions`` counts as
    declared new. The denominator is the number of incoming items in
    ``truth`` over all steps.
    """
    if len(decisions) != len(truth):
        raise InvalidInput(f"decisions cover {len(decisions)} steps, truth {len(truth)}")
    total = sum(len(step) for step in truth)
    if total == 0:
        return 0.0
    wrong = sum(
        1
        for decided, true_step in zip(decisions, truth, strict=True)
        for item, partner in true_step.items()
        if decided.get(item) != partner
    )
    return wrong / total


def identity_switches(assigned: Sequence[Mapping[Key, Identity | None]]) -> int:
    """Times a true object's fused identity changes from one known id to another.

    ``assigned[k]`` maps each true object present at step k to the fused id
    that covers it (``None`` when none does). Losing an object and finding it
    again under the same id is not a switch; under another id it is.
    """
    last: dict[Key, Identity] = {}
    switches = 0
    for step in assigned:
        for truth_id, fused_id in step.items():
            if fused_id is None:
                continue
            if truth_id in last and last[truth_id] != fused_id:
                switches += 1
            last[truth_id] = fused_id
    return switches
