"""Track-to-track association problems with their truth, and their false decision rate.

[T2T] §4: "match estimations of sensor 1 to estimations of sensor 2". In the
paper's Table 1 each estimate t of sensor i gets a plausibility on the
targets already known by sensor j (eq 3–5), so here sensor 1's tracks are the
*incoming* items (columns) and sensor 2's the *known* ones (rows). For
``gnn`` and ``denoeux`` the side does not matter; for ``hachour`` and
``mercier`` (not symmetric, [T2T] §3) it does.

A decision is wrong when an incoming track is paired with a track of another
target, or declared new although its target is in the known list, or paired
although it is not (:func:`core.metrics.false_decision_rate`).

**Ties are not decisions.** The simulated lists come in truth order (track i
of each list is target i). A method whose scores tie (e.g. ``hachour`` with
every plausibility clipped to 1) is then decided by its solver's tie-break on
that order, which may happen to favour the truth or not. So
:func:`decision_outcome` puts both lists of every problem in a random order
(seeded per run: ``[seed, ORDER_STREAM, order]``) before deciding, and counts
as *tied* each decision that another random order of the same lists changes
(:data:`TIE_PROBES` further orders: a lower bound on the ties).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from core.arrays import FloatArray, IntArray
from core.association import associate
from core.belief import MassFunction
from core.metrics import false_decision_rate
from core.simulation.tracklists import SensorTrackList

Decision = dict[int, int | None]
"""Incoming index → the known index it was paired with (``None``: declared new)."""

ORDER_STREAM = 11
"""Second word of the seed of the list orders (the noise uses the run seed alone)."""
TIE_PROBES = 2
"""Further random orders in which each decision is re-taken to find the ties."""


@dataclass(frozen=True)
class ListPair:
    """One association problem: a known track list, an incoming one, and their targets.

    Attributes
    ----------
    known_states, incoming_states : ndarray, shapes (n, 4) and (m, 4)
        ``[x, ẋ, y, ẏ]``; the incoming states are predicted to the known list's time.
    known_covariances, incoming_covariances : ndarray, shapes (n, 4, 4) and (m, 4, 4)
    known_targets, incoming_targets : ndarray of int64
        The true target of each track (evaluation only).
    known_classes, incoming_classes : tuple of MassFunction or None
        Class mass functions of the tracks, when the sensors report them.
    """

    known_states: FloatArray
    known_covariances: FloatArray
    known_targets: IntArray
    incoming_states: FloatArray
    incoming_covariances: FloatArray
    incoming_targets: IntArray
    known_classes: tuple[MassFunction, ...] | None = None
    incoming_classes: tuple[MassFunction, ...] | None = None

    def truth(self) -> Decision:
        """The right decision: each incoming track to the known track of its target, if any."""
        row_of = {int(target): row for row, target in enumerate(self.known_targets)}
        return {col: row_of.get(int(target)) for col, target in enumerate(self.incoming_targets)}

    def scaled(self, factor: float) -> ListPair:
        """The same problem in other length units: states × ``factor``, covariances × ``factor²``.

        Every Mahalanobis distance is unchanged; log|C| moves by ``q ln factor²``.
        """
        return replace(
            self,
            known_states=self.known_states * factor,
            known_covariances=self.known_covariances * factor**2,
            incoming_states=self.incoming_states * factor,
            incoming_covariances=self.incoming_covariances * factor**2,
        )

    def keep(self, known: IntArray, incoming: IntArray) -> ListPair:
        """Only the known tracks ``known`` and the incoming tracks ``incoming`` (indices)."""
        return ListPair(
            known_states=self.known_states[known],
            known_covariances=self.known_covariances[known],
            known_targets=self.known_targets[known],
            incoming_states=self.incoming_states[incoming],
            incoming_covariances=self.incoming_covariances[incoming],
            incoming_targets=self.incoming_targets[incoming],
            known_classes=(
                None
                if self.known_classes is None
                else tuple(self.known_classes[int(i)] for i in known)
            ),
            incoming_classes=(
                None
                if self.incoming_classes is None
                else tuple(self.incoming_classes[int(i)] for i in incoming)
            ),
        )

    def reordered(self, rng: np.random.Generator) -> ListPair:
        """Both lists in a random order (the truth travels with the tracks)."""
        return self.keep(
            rng.permutation(len(self.known_targets)).astype(np.int64),
            rng.permutation(len(self.incoming_targets)).astype(np.int64),
        )

    def decide_targets(
        self,
        method: str,
        options: Mapping[str, object] | None = None,
        distance: str = "mean",
        use_classes: bool = False,
    ) -> dict[int, int | None]:
        """:meth:`decide`, told in targets: incoming track's target → partner's target."""
        decision = self.decide(method, options, distance, use_classes)
        return {
            int(self.incoming_targets[col]): None if row is None else int(self.known_targets[row])
            for col, row in decision.items()
        }

    def decide(
        self,
        method: str,
        options: Mapping[str, object] | None = None,
        distance: str = "mean",
        use_classes: bool = False,
    ) -> Decision:
        """Run one association method on this problem."""
        classes = use_classes and self.known_classes is not None
        result = associate(
            (self.known_states, self.known_covariances),
            (self.incoming_states, self.incoming_covariances),
            method,
            options,
            distance,
            known_classes=self.known_classes if classes else None,
            incoming_classes=self.incoming_classes if classes else None,
        )
        decision: Decision = dict.fromkeys(range(len(self.incoming_targets)))
        decision.update(
            {
                int(col): int(row)
                for row, col in zip(result.pair_known, result.pair_incoming, strict=True)
            }
        )
        return decision


def _predicted(track_list: SensorTrackList, time: float) -> FloatArray:
    """Constant-velocity prediction of the positions to ``time`` (covariances unchanged)."""
    lag = time - track_list.time
    states = track_list.states.copy()
    states[:, [0, 2]] += states[:, [1, 3]] * lag
    return states


def list_pairs(
    reports: Sequence[SensorTrackList],
    known_sensor: str = "s2",
    incoming_sensor: str = "s1",
    class_masses: Sequence[Sequence[MassFunction]] | None = None,
) -> list[ListPair]:
    """One :class:`ListPair` per step that both sensors report, in step order.

    The incoming list is predicted to the known list's time (the sensors of
    the t2t scenarios report 1 ms apart). ``class_masses[r]`` are the class
    masses of the tracks of ``reports[r]``, when given.
    """
    by_step: dict[int, dict[str, int]] = {}
    for index, report in enumerate(reports):
        by_step.setdefault(report.step, {})[report.sensor] = index
    pairs = []
    for step in sorted(by_step):
        indices = by_step[step]
        if known_sensor not in indices or incoming_sensor not in indices:
            continue
        known, incoming = reports[indices[known_sensor]], reports[indices[incoming_sensor]]
        pairs.append(
            ListPair(
                known_states=known.states,
                known_covariances=known.covariances,
                known_targets=known.target_ids,
                incoming_states=_predicted(incoming, known.time),
                incoming_covariances=incoming.covariances,
                incoming_targets=incoming.target_ids,
                known_classes=(
                    None if class_masses is None else tuple(class_masses[indices[known_sensor]])
                ),
                incoming_classes=(
                    None if class_masses is None else tuple(class_masses[indices[incoming_sensor]])
                ),
            )
        )
    return pairs


def decision_error_rate(
    pairs: Sequence[ListPair],
    method: str,
    options: Mapping[str, object] | None = None,
    distance: str = "mean",
    use_classes: bool = False,
) -> float:
    """False decision rate of one method over the problems ([T2T] §4, core.metrics)."""
    decisions = [pair.decide(method, options, distance, use_classes) for pair in pairs]
    return false_decision_rate(decisions, [pair.truth() for pair in pairs])


@dataclass(frozen=True)
class Outcome:
    """One method on one run's problems, the lists in a random order.

    Attributes
    ----------
    rate : float
        False decision rate ([T2T] §4).
    tie_rate : float
        Share of the decisions that another order of the same lists changes.
    decisions : int
        Incoming tracks decided (the denominator of both rates).
    """

    rate: float
    tie_rate: float
    decisions: int


def decision_outcome(
    pairs: Sequence[ListPair],
    method: str,
    options: Mapping[str, object] | None = None,
    distance: str = "mean",
    use_classes: bool = False,
    *,
    seed: int,
    order: int = 0,
    tie_probes: int = TIE_PROBES,
) -> Outcome:
    """False decision rate and tie rate of one method, the lists shuffled per run.

    ``seed`` is the run's (the same permutations for every method of a run:
    comparisons between methods are paired); ``order`` picks another family
    of random orders, for the check that the order changes nothing.
    ``tie_probes`` further orders look for ties; the rate is the first
    order's whatever their number, so a search that needs only rates (a
    tuning grid) passes 0 and gets the same rates three times faster (its
    tie rate is then 0 by construction and is not to be reported).
    """
    rngs = [
        np.random.default_rng([seed, ORDER_STREAM, order, probe]) for probe in range(1 + tie_probes)
    ]
    wrong = tied = decisions = 0
    for pair in pairs:
        decided = [
            pair.reordered(rng).decide_targets(method, options, distance, use_classes)
            for rng in rngs
        ]
        known = set(pair.known_targets.tolist())
        truth = {
            int(target): int(target) if target in known else None
            for target in pair.incoming_targets.tolist()
        }
        decisions += len(truth)
        wrong += sum(decided[0][target] != partner for target, partner in truth.items())
        tied += sum(len({probe[target] for probe in decided}) > 1 for target in truth)
    if decisions == 0:
        return Outcome(0.0, 0.0, 0)
    return Outcome(wrong / decisions, tied / decisions, decisions)


def partially_observed(
    pairs: Sequence[ListPair], unseen: float, rng: np.random.Generator
) -> list[ListPair]:
    """Each sensor independently misses each track with probability ``unseen``.

    Partially observed targets are what a gate is for ([T2T] §1, §4): a
    target seen by one sensor only must be declared new (incoming) or not
    observed (known), not paired with another target's track.
    """
    kept = []
    for pair in pairs:
        known = np.flatnonzero(rng.random(len(pair.known_targets)) >= unseen)
        incoming = np.flatnonzero(rng.random(len(pair.incoming_targets)) >= unseen)
        kept.append(pair.keep(known.astype(np.int64), incoming.astype(np.int64)))
    return kept
