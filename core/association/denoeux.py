"""Credal association with parameter γ ([T2T] §4 and its ref [7]; docs/algorithms.md §3.2).

Per pair, evidence on {associated (1), not (0)}:
``m({1}) = α e^{−γD}``, ``m({0}) = α (1 − e^{−γD})``, ``m(Θ) = 1 − α``. Its
contour function gives ``pl(1) = 1 − m({0})``, ``pl(0) = 1 − m({1})`` and the
weight ``w = ln pl(1) − ln pl(0)``. The most plausible relation maximises Σ w
over partial matchings: a maximum-gain matching on w, pairs with w ≤ 0 dropped.

w > 0 exactly when e^{−γD} > 1/2, i.e. D < ln 2 / γ, whatever α ∈ (0, 1]: that
is the gate, and with α = 1, γ = ln 2 / λ ([T2T] eq 11) the same pairs are
admissible as for GNN with threshold λ. Class information (§3.6) adds
``ln(1 − K)`` ≤ 0 to w (contour functions of independent sources multiply).

Plausibilities are floored at the smallest normal double before the logarithm
(``pl(0) → 0`` when D → 0 with α = 1), so w stays finite (§3.7).

Options
-------
gamma : float > 0
gate_probability : float in (0, 1)
    γ = ln 2 / T with T = chi2.ppf(p, q) (doubled for ``mean``). Default 0.999
    when neither is given.
alpha : float in (0, 1]
    Default 1, as in [T2T].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray
from core.association.assignment import max_gain_matching
from core.association.problem import AssociationProblem
from core.association.result import AssociationResult, Diagnostics, ScoreMatrix, build_result
from core.association.spec import BOTH_SCOPES, MethodSpec, NumberOption
from core.distance import threshold_from_probability

METHOD = "denoeux"
DEFAULT_GATE_PROBABILITY = 0.999
PLAUSIBILITY_FLOOR = float(np.finfo(np.float64).tiny)


@dataclass(frozen=True)
class DenoeuxOptions:
    """Validated options of :func:`associate_denoeux` (module docstring)."""

    gamma: float | None = None
    gate_probability: float | None = None
    alpha: float = 1.0

    def resolve_gamma(self, problem: AssociationProblem) -> float:
        """γ, given or from the gate probability (γ = ln 2 / T)."""
        if self.gamma is not None:
            return self.gamma
        assert self.gate_probability is not None
        threshold = threshold_from_probability(
            self.gate_probability, problem.dimension, problem.distance
        )
        return math.log(2.0) / threshold


def contour_weight(distance: FloatArray, gamma: float, alpha: float) -> FloatArray:
    """``w = ln pl(1) − ln pl(0)`` of the pairwise evidence, without cancellation.

    ``pl(1) = 1 − α (1 − e^{−γD})`` and ``pl(0) = 1 − α e^{−γD} = (1 − α) + α (1 − e^{−γD})``.
    """
    one_minus = -np.expm1(-gamma * distance)  # 1 − e^{−γD}, exact near 0
    plausible_one = 1.0 - alpha * one_minus
    plausible_zero = (1.0 - alpha) + alpha * one_minus
    return np.asarray(
        np.log(np.maximum(plausible_one, PLAUSIBILITY_FLOOR))
        - np.log(np.maximum(plausible_zero, PLAUSIBILITY_FLOOR)),
        dtype=np.float64,
    )


def associate_denoeux(problem: AssociationProblem, options: DenoeuxOptions) -> AssociationResult:
    """Maximise Σ w r over partial matchings ([T2T] ref [7])."""
    gamma = options.resolve_gamma(problem)
    gate = math.log(2.0) / gamma
    pairs = problem.pairs(gate)
    weight = contour_weight(pairs.distance, gamma, options.alpha)
    class_plausibility = problem.class_plausibility(pairs)
    if class_plausibility is not None:
        weight = weight + np.log(np.maximum(class_plausibility, PLAUSIBILITY_FLOOR))
    matching = max_gain_matching(
        pairs.rows,
        pairs.cols,
        weight,
        problem.n_known,
        problem.n_incoming,
        solver=problem.solver,
        cluster=problem.cluster,
    )
    scores = ScoreMatrix(
        kind="weight",
        rows=pairs.rows,
        cols=pairs.cols,
        values=weight,
        new=np.zeros(problem.n_incoming),
        shape=(problem.n_known, problem.n_incoming),
        missing=-np.inf,
    )
    diagnostics = Diagnostics(
        uses_classes=class_plausibility is not None,
        candidate_pairs=len(pairs),
        clusters=matching.clusters,
        largest_cluster=matching.largest_cluster,
        gate=gate,
    )
    return build_result(METHOD, matching.rows, matching.cols, scores, diagnostics, pairs)


SPEC = MethodSpec(
    name=METHOD,
    scopes=BOTH_SCOPES,
    options=(
        NumberOption("gamma", None, low=0.0, doc="γ of the pairwise evidence e^{−γD}"),
        NumberOption(
            "gate_probability",
            DEFAULT_GATE_PROBABILITY,
            low=0.0,
            high=1.0,
            high_open=True,
            doc="γ = ln 2 / T, T = chi2.ppf(p, q) (doubled for the mean covariance)",
        ),
        NumberOption("alpha", 1.0, low=0.0, high=1.0, doc="reliability α of each pair's evidence"),
    ),
    exclusive=(("gamma", "gate_probability"),),
    build=lambda values: DenoeuxOptions(**values),
    run=associate_denoeux,
    distance="sum",
    summary="Credal association with parameter γ ([T2T] ref [7]); the track-to-track default",
)
