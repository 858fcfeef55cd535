"""Evaluation metrics (EVALUATION.md "Metrics").

- :func:`ospa` — Optimal SubPattern Assignment distance (Schuhmacher, Vo & Vo 2008);
- :func:`gospa` — Generalised OSPA with α = 2 and its decomposition into
  localisation, missed and false parts (Rahmathullah, García-Fernández & Svensson 2017);
- :func:`rms_error`, :func:`time_mean_error` — Monte-Carlo RMS error per
  step and its time mean ([DH] §5 eq 28-29);
- :func:`false_decision_rate` — the share of association decisions that
  differ from the truth ([T2T] §4, [MTT] §6.2.1);
- :func:`identity_switches` — how often a true object changes fused identity;
- :func:`coverage` — which track covers which true object at one step (GOSPA-style
  assignment with a cut-off), the input of the three below;
- :func:`track_losses` — how often a covered true object becomes uncovered;
- :func:`false_tracks` — tracks that never cover a true object;
- :func:`time_to_decision` — classification: steps until the true class is
  decided for good (EVALUATION.md "time to correct decision").
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
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


def coverage(
    truths: Mapping[Key, ArrayLike],
    tracks: Mapping[Identity, ArrayLike],
    cutoff: float,
) -> dict[Key, Identity | None]:
    """Which track covers each true object at one step.

    The truth–track pairs minimising the total distance (Hungarian, as in
    OSPA/GOSPA) among the pairs closer than ``cutoff``; a true object left
    without a track maps to None.

    Parameters
    ----------
    truths : mapping id → position (d,)
    tracks : mapping id → position (d,)
    cutoff : float
        Largest distance at which a track covers a true object.
    """
    _check_cutoff(cutoff, 1.0)
    truth_ids, track_ids = list(truths), list(tracks)
    found: dict[Key, Identity | None] = dict.fromkeys(truth_ids)
    if not truth_ids or not track_ids:
        return found
    x = _points(
        np.array([np.asarray(truths[key], dtype=np.float64) for key in truth_ids]), "truths"
    )
    y = _points(
        np.array([np.asarray(tracks[key], dtype=np.float64) for key in track_ids]), "tracks"
    )
    distances = cdist(x, y)
    # Pairs beyond the cut-off cost more than leaving both unpaired.
    costs = np.where(distances < cutoff, distances, 2.0 * cutoff + 1.0)
    rows, cols = linear_sum_assignment(costs)
    for row, col in zip(rows.tolist(), cols.tolist(), strict=True):
        if distances[row, col] < cutoff:
            found[truth_ids[row]] = track_ids[col]
    return found


def track_losses(assigned: Sequence[Mapping[Key, Identity | None]]) -> int:
    """Times a true object that was covered by a track is covered by none at the next step.

    ``assigned[k]`` maps each true object present at step k to the track
    covering it (None: none). An object absent from a step (not yet born,
    or gone) is not lost; one covered again later and lost again counts twice.
    """
    covered: dict[Key, bool] = {}
    losses = 0
    for step in assigned:
        for truth_id, track_id in step.items():
            if track_id is None and covered.get(truth_id, False):
                losses += 1
            covered[truth_id] = track_id is not None
        for truth_id in set(covered) - set(step):
            covered[truth_id] = False
    return losses


def false_tracks(
    tracks: Iterable[Identity], assigned: Sequence[Mapping[Key, Identity | None]]
) -> int:
    """How many of ``tracks`` (e.g. every confirmed track id) never cover a true object."""
    used = {track_id for step in assigned for track_id in step.values() if track_id is not None}
    return len(set(tracks) - used)


def time_to_decision(
    probabilities: ArrayLike, true_class: int, level: float = 0.5, start: int = 0
) -> FloatArray:
    """Steps from ``start`` until the true class's probability stays ≥ ``level`` to the end.

    Parameters
    ----------
    probabilities : array (..., steps, classes)
        Class probabilities (e.g. BetP) over time; NaN rows (no decision
        possible) count as undecided.
    true_class : int
        Column of the true class.
    level : float
        Decision threshold (0.5: the true class has the majority).
    start : int
        Step from which the decision is due (e.g. the step of the manoeuvre that reveals the class).

    Returns
    -------
    ndarray, shape (...)
        ``k − start`` for the first step k ≥ start from which the decision
        holds at every later step (0: decided from ``start`` on); NaN when
        it does not hold at the last step.
    """
    p = np.asarray(probabilities, dtype=np.float64)
    if p.ndim < 2:
        raise InvalidInput(f"probabilities must be (..., steps, classes), got shape {p.shape}")
    steps = p.shape[-2]
    if not 0 <= start < steps:
        raise InvalidInput(f"start must be a step in [0, {steps}), got {start!r}")
    if not 0 <= true_class < p.shape[-1]:
        raise InvalidInput(f"true_class must be a column in [0, {p.shape[-1]})")
    decided = np.nan_to_num(p[..., start:, true_class], nan=-np.inf) >= level
    stays = np.flip(np.logical_and.accumulate(np.flip(decided, axis=-1), axis=-1), axis=-1)
    first = np.argmax(stays, axis=-1).astype(np.float64)
    return np.asarray(np.where(stays.any(axis=-1), first, np.nan), dtype=np.float64)
