"""Mercier's credal assignment: pairwise evidence, exact BetP, Hungarian step.

([T2T] ref [8]; docs/algorithms.md §3.4.) For each incoming item t, the pairwise
sources (a_ℓ, b_ℓ, c_ℓ) of its candidates ℓ (:mod:`core.association.pairwise_evidence`)
are combined conjunctively on Θ_t = {Y_1..Y_n, *}; BetP_t is computed exactly
in O(n²) (``pairwise_evidence_betp_rows``, §1.1). The assignment then
maximises Σ BetP r over the matrix of [T2T] Table 1, as in §3.3: a
maximum-gain matching on ``BetP_t(Y_ℓ) − BetP_t(*)``.

An item whose combination is in total conflict has no BetP: it is declared
new and listed in ``diagnostics.undefined``. Total conflict is decided on
logarithms: on a dense frame 1 − m(∅) holds a product of one factor per
candidate (≈ 0.1^1000 for 1000 candidates), small but not 0 (§1.1 "Scale").

Options
-------
alpha : float in (0, 1], default 0.9
gate_probability : float in (0, 1], default 0.999 (the frame; see the Reading
    in :mod:`core.association.pairwise_evidence`)
evidence : "fuzzy" (default, Reading of [DH] eq 23–27) | "likelihood"
scale : "gate" (default: s = exp(−γ D), γ = ln 2 / gate, [T2T] eq 11) | "fixed" (s = exp(−D/2));
    see :mod:`core.association.pairwise_evidence`
"""

from __future__ import annotations

import numpy as np

from core.association.assignment import max_gain_matching
from core.association.pairwise_evidence import EVIDENCE_OPTIONS, EvidenceOptions, score_rows
from core.association.problem import AssociationProblem
from core.association.result import AssociationResult, Diagnostics, ScoreMatrix, build_result
from core.association.spec import BOTH_SCOPES, MethodSpec

METHOD = "mercier"


def associate_mercier(problem: AssociationProblem, options: EvidenceOptions) -> AssociationResult:
    """BetP per incoming item on its gated frame, then the Hungarian step."""
    gate = options.gate(problem)
    pairs = problem.pairs(gate)
    evidence = options.pair_evidence(problem, pairs)
    values, star, defined = score_rows(pairs.cols, problem.n_incoming, evidence, "betp")
    star = np.where(defined, star, 0.0)
    gain = np.where(defined[pairs.cols], values - star[pairs.cols], 0.0)
    matching = max_gain_matching(
        pairs.rows,
        pairs.cols,
        gain,
        problem.n_known,
        problem.n_incoming,
        solver=problem.solver,
        cluster=problem.cluster,
    )
    scores = ScoreMatrix(
        kind="betp",
        rows=pairs.rows,
        cols=pairs.cols,
        values=values,
        new=star,
        shape=(problem.n_known, problem.n_incoming),
        missing=0.0,
    )
    diagnostics = Diagnostics(
        uses_classes=problem.has_classes,
        candidate_pairs=len(pairs),
        clusters=matching.clusters,
        largest_cluster=matching.largest_cluster,
        gate=gate,
        undefined=np.flatnonzero(~defined).astype(np.int64),
    )
    return build_result(METHOD, matching.rows, matching.cols, scores, diagnostics, pairs)


SPEC = MethodSpec(
    name=METHOD,
    scopes=BOTH_SCOPES,
    options=EVIDENCE_OPTIONS,
    build=lambda values: EvidenceOptions.of(METHOD, values),
    run=associate_mercier,
    distance="mean",
    summary="Mercier's credal assignment: pairwise evidence, exact BetP, Hungarian step",
)
