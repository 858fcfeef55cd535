"""Dang & Han's bidirectional evidential association ([DH] §3.4 and §4 steps 3–5).

The pairwise evidence (:mod:`core.association.pairwise_evidence`) is combined
in both directions: for each incoming item over its candidate known items
(``*``: a new target), and for each known item over its candidate incoming
items (``*``: not observed). Each side picks its highest-scoring partner;
a pair is kept only when both sides chose each other ("if the decision from
the first matrix is consistent with that of the second matrix, the decision
is validated, otherwise the decision is ignored"). Unpaired incoming items
are new, unpaired known items missed. No assignment problem is solved.

Decision rule: a side chooses the partner with the highest score when that
score is > 0 and strictly above the score of ``*`` (ties between partners: the
lowest index); otherwise it chooses ``*``. An item in total conflict chooses ``*``.

Options
-------
alpha, gate_probability, evidence, scale : as for ``mercier``
score : {"belief", "betp"}
    **Reading**: [DH] decides "by the maximum belief" on the matrix of
    combined masses of eq 19 — for the singletons Y_j and * the mass is the
    belief (``"belief"``, default, normalised by Dempster's rule). ``"betp"``
    uses the exact pignistic probabilities instead.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from core.arrays import BoolArray, FloatArray, IntArray
from core.association.pairwise_evidence import EVIDENCE_OPTIONS, EvidenceOptions, score_rows
from core.association.problem import AssociationProblem
from core.association.result import AssociationResult, Diagnostics, ScoreMatrix, build_result
from core.association.spec import BOTH_SCOPES, ChoiceOption, MethodSpec

METHOD = "dang_han"


@dataclass(frozen=True)
class DangHanOptions:
    """Validated options of :func:`associate_dang_han`."""

    evidence: EvidenceOptions
    score: str = "belief"

    @classmethod
    def of(cls, values: dict[str, Any]) -> DangHanOptions:
        """The options from their parsed values (:data:`SPEC`)."""
        return cls(EvidenceOptions.of(METHOD, values), values["score"])


def best_partner(
    items: IntArray,
    partners: IntArray,
    values: FloatArray,
    star: FloatArray,
    defined: BoolArray,
    n_items: int,
) -> IntArray:
    """Each item's chosen partner (−1 for ``*``), by the rule of the module docstring."""
    choice_of = np.full(n_items, -1, dtype=np.int64)
    eligible = (values > 0.0) & (values > star[items]) & defined[items]
    if not eligible.any():
        return choice_of
    index = np.flatnonzero(eligible)
    eligible_items, eligible_values = items[index], values[index]
    # per item: the highest score, then the lowest partner among the pairs reaching it
    # (two unbuffered reductions, O(P); a sort of the pairs was most of the method's time)
    best = np.full(n_items, -np.inf)
    np.maximum.at(best, eligible_items, eligible_values)
    at_best = eligible_values == best[eligible_items]
    lowest = np.full(n_items, np.iinfo(np.int64).max)
    np.minimum.at(lowest, eligible_items[at_best], partners[index][at_best])
    chosen = best > -np.inf
    choice_of[chosen] = lowest[chosen]
    return choice_of


def associate_dang_han(problem: AssociationProblem, options: DangHanOptions) -> AssociationResult:
    """Mutual best choice between the two belief matrices ([DH] §3.4)."""
    n_known, n_incoming = problem.n_known, problem.n_incoming
    gate = options.evidence.gate(problem)
    pairs = problem.pairs(gate)
    evidence = options.evidence.pair_evidence(problem, pairs)
    forward, forward_star, forward_defined = score_rows(
        pairs.cols, n_incoming, evidence, options.score
    )
    backward, backward_star, backward_defined = score_rows(
        pairs.rows, n_known, evidence, options.score
    )
    incoming_choice = best_partner(
        pairs.cols, pairs.rows, forward, forward_star, forward_defined, n_incoming
    )
    known_choice = best_partner(
        pairs.rows, pairs.cols, backward, backward_star, backward_defined, n_known
    )
    chosen_known = np.flatnonzero(known_choice >= 0)
    mutual = incoming_choice[known_choice[chosen_known]] == chosen_known
    matched_known = chosen_known[mutual]
    matched_incoming = known_choice[matched_known]
    scores = ScoreMatrix(
        kind=options.score,
        rows=pairs.rows,
        cols=pairs.cols,
        values=forward,
        new=np.where(forward_defined, forward_star, 0.0),
        shape=(n_known, n_incoming),
        missing=0.0,
    )
    conflicted_known = int((~backward_defined).sum())
    notes = (
        (f"{conflicted_known} known items in total conflict chose nothing",)
        if conflicted_known
        else ()
    )
    diagnostics = Diagnostics(
        uses_classes=problem.has_classes,
        candidate_pairs=len(pairs),
        gate=gate,
        undefined=np.flatnonzero(~forward_defined).astype(np.int64),
        notes=notes,
    )
    return build_result(METHOD, matched_known, matched_incoming, scores, diagnostics, pairs)


SPEC = MethodSpec(
    name=METHOD,
    scopes=BOTH_SCOPES,
    options=(
        *EVIDENCE_OPTIONS,
        ChoiceOption(
            "score",
            "belief",
            ("belief", "betp"),
            doc="decide by the maximum belief ([DH] eq 19) or by the pignistic probability",
        ),
    ),
    build=DangHanOptions.of,
    run=associate_dang_han,
    distance="mean",
    summary="Dang & Han's bidirectional evidential association ([DH] §3.4)",
)
