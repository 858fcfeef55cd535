"""Global Nearest Neighbour ([MTT] §4.2 Table 1; [T2T] §4; docs/algorithms.md §3.1).

Cost matrix ``[D | diag(T)]``: a known item ℓ is matched with an incoming item
t at cost D, or left unmatched at cost T. Minimising the total cost is
maximising Σ (T − D) over the matched pairs, so only pairs with D < T can
help: T is also the gate, and the problem is solved as a maximum-gain
matching on the gated pairs (:mod:`core.association.assignment`).

Options
-------
threshold : float > 0
    T directly (the "maximum distance" λ of [T2T] §4).
gate_probability : float in (0, 1)
    T = chi2.ppf(p, q), doubled for the ``mean`` covariance (§3.1). Default
    0.999 when neither option is given.

GNN cannot use class information ([T2T] §4): the diagnostics say so.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.association.assignment import max_gain_matching
from core.association.problem import AssociationProblem
from core.association.result import AssociationResult, Diagnostics, ScoreMatrix, build_result
from core.association.spec import BOTH_SCOPES, MethodSpec, NumberOption
from core.distance import threshold_from_probability

METHOD = "gnn"
DEFAULT_GATE_PROBABILITY = 0.999


@dataclass(frozen=True)
class GnnOptions:
    """Validated options of :func:`associate_gnn` (module docstring)."""

    threshold: float | None = None
    gate_probability: float | None = None

    def resolve_threshold(self, problem: AssociationProblem) -> float:
        """T, from the threshold or the gate probability."""
        if self.threshold is not None:
            return self.threshold
        assert self.gate_probability is not None
        return threshold_from_probability(
            self.gate_probability, problem.dimension, problem.distance
        )


def associate_gnn(problem: AssociationProblem, options: GnnOptions) -> AssociationResult:
    """Solve ``[D | diag(T)]`` on the gated pairs ([MTT] Table 1)."""
    threshold = options.resolve_threshold(problem)
    pairs = problem.pairs(threshold)
    matching = max_gain_matching(
        pairs.rows,
        pairs.cols,
        threshold - pairs.distance,
        problem.n_known,
        problem.n_incoming,
        solver=problem.solver,
        cluster=problem.cluster,
    )
    scores = ScoreMatrix(
        kind="distance",
        rows=pairs.rows,
        cols=pairs.cols,
        values=pairs.distance,
        new=np.full(problem.n_incoming, threshold),
        shape=(problem.n_known, problem.n_incoming),
        missing=np.inf,
    )
    notes: tuple[str, ...] = ()
    if problem.has_classes:
        notes = ("gnn cannot use class information ([T2T] §4): classes were ignored",)
    diagnostics = Diagnostics(
        uses_classes=False,
        classes_ignored=problem.has_classes,
        candidate_pairs=len(pairs),
        clusters=matching.clusters,
        largest_cluster=matching.largest_cluster,
        gate=threshold,
        notes=notes,
    )
    return build_result(METHOD, matching.rows, matching.cols, scores, diagnostics, pairs)


SPEC = MethodSpec(
    name=METHOD,
    scopes=BOTH_SCOPES,
    options=(
        NumberOption("threshold", None, low=0.0, doc="T, the maximum distance of a pair"),
        NumberOption(
            "gate_probability",
            DEFAULT_GATE_PROBABILITY,
            low=0.0,
            high=1.0,
            high_open=True,
            doc="T = chi2.ppf(p, q), doubled for the mean covariance",
        ),
    ),
    exclusive=(("threshold", "gate_probability"),),
    build=lambda values: GnnOptions(**values),
    run=associate_gnn,
    distance="mean",
    summary="Global Nearest Neighbour ([MTT] §4.2 Table 1)",
)
