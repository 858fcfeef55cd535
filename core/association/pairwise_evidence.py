"""Pairwise evidence of the Royère / Mercier / Dang–Han family ([DH] §3, docs/algorithms.md §3.4).

For an item i and a candidate partner j, a mass function on {Y_j, ¬Y_j}
("i comes from j" or not): ``a`` on Y_j, ``b`` on ¬Y_j, ``c = 1 − a − b`` on Θ.

Evidence models (option ``evidence``; ``f`` is pluggable):

- ``"fuzzy"`` (default) — **Reading of [DH] eq 23–27** (garbled in the text):
  from the fuzzy similarity ``s``, ``a = α max(0, 2s − 1)``,
  ``b = α max(0, 1 − 2s)``.
- ``"likelihood"`` — the generic form of docs/algorithms.md §3.4 with f = s:
  ``a = α s``, ``b = α (1 − s)``, ``c = 1 − α``.

The similarity's scale (option ``scale``) — **Reading:** [T2T] §1 says
Mercier's method "models information in the same way as" Denœux's, whose
weight is ``exp(−γ D)`` with γ tied to the non-association distance λ by
``exp(−γλ) = 1 − exp(−γλ)``, i.e. ``γ = ln 2 / λ`` ([T2T] eq 11):

- ``"gate"`` (default): ``s = exp(−γ D)`` with ``γ = ln 2 / T`` and T the
  method's own gate (``gate_probability``, docs/algorithms.md §3.1). Then
  ``s > 1/2`` exactly when D < T: the fuzzy evidence supports a pair inside
  the gate and refutes it outside, as GNN's threshold and Denœux's γ do.
- ``"fixed"``: ``s = exp(−D/2)`` whatever the gate (the reading used before;
  the fuzzy evidence then supports a pair only when D < 2 ln 2 ≈ 1.39, which
  rejects about half of the true pairs of a 2-D measurement).

The models below take the distance already put on the ``s = exp(−D/2)``
scale: ``"gate"`` passes ``2γ D``.

Class information (§3.6) is a second source on the same pair with mass K on
¬Y_j and 1 − K on Θ; Dempster's rule gives
``a' = a(1−K)/(1−aK)``, ``b' = (b + cK)/(1−aK)``, ``c' = c(1−K)/(1−aK)``
(the contour function of Y_j is multiplied by 1 − K, up to normalisation).
If ``aK = 1`` the two sources are in total conflict on that pair; the class
veto wins (the pair is refuted: a' = c' = 0, b' = 1).

The frame of each item is its candidates within the gate (option
``gate_probability``): **Reading** — [DH] §2 builds its matrices over the
*validated* measurements inside the tracking gate, which also keeps large
problems sparse. ``gate_probability = 1`` puts every item in every frame.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from core.arrays import BoolArray, FloatArray, IntArray
from core.association.problem import AssociationProblem
from core.association.rows import RaggedRows
from core.association.spec import ChoiceOption, NumberOption, OptionSpec
from core.belief import pairwise_evidence_betp_rows
from core.belief.gbt import leave_one_out_sums
from core.distance import CandidatePairs, threshold_from_probability
from core.errors import OptionError

Evidence = tuple[FloatArray, FloatArray, FloatArray]
EvidenceModel = Callable[[FloatArray, float], Evidence]


def fuzzy_evidence(distance: FloatArray, alpha: float) -> Evidence:
    """[DH] eq 23–27 as read in docs/algorithms.md §3.4: s = e^{−D/2}, a = α(2s−1)⁺, b = α(1−2s)⁺.

    ``distance`` is on the e^{−D/2} scale (the ``scale`` option rescales D first).
    """
    similarity = np.exp(-0.5 * distance)
    support = alpha * np.maximum(0.0, 2.0 * similarity - 1.0)
    refute = alpha * np.maximum(0.0, 1.0 - 2.0 * similarity)
    return support, refute, np.maximum(0.0, 1.0 - support - refute)


def likelihood_evidence(distance: FloatArray, alpha: float) -> Evidence:
    """Generic §3.4 form with f = e^{−D/2}: a = α f, b = α (1 − f), c = 1 − α."""
    similarity = np.exp(-0.5 * distance)
    support = alpha * similarity
    refute = alpha * (1.0 - similarity)
    return support, refute, np.maximum(0.0, 1.0 - support - refute)


EVIDENCE_MODELS: dict[str, EvidenceModel] = {
    "fuzzy": fuzzy_evidence,
    "likelihood": likelihood_evidence,
}


def with_class_evidence(evidence: Evidence, class_plausibility: FloatArray) -> Evidence:
    """Dempster combination with the class source (module docstring)."""
    support, refute, ignorance = evidence
    conflict = 1.0 - class_plausibility  # K
    normaliser = 1.0 - support * conflict
    total = normaliser <= 0.0
    safe = np.where(total, 1.0, normaliser)
    new_support = np.where(total, 0.0, support * class_plausibility / safe)
    new_refute = np.where(total, 1.0, (refute + ignorance * conflict) / safe)
    new_ignorance = np.where(total, 0.0, ignorance * class_plausibility / safe)
    new_ignorance = np.clip(new_ignorance, 0.0, 1.0)
    new_refute = np.clip(1.0 - new_support - new_ignorance, 0.0, 1.0)
    return new_support, new_refute, new_ignorance


def singleton_belief_rows(
    support: FloatArray, refute: FloatArray, ignorance: FloatArray
) -> tuple[FloatArray, BoolArray]:
    """Normalised masses of the singletons of the combined mass ([DH] eq 19), row by row.

    ``m(Y_j) = a_j Π_{k≠j}(1 − a_k)``, ``m(*) = Π_k b_k``, divided by
    ``1 − m(∅) = Σ_j a_j Π_{k≠j}(1 − a_k) + Π_k (b_k + c_k)`` (Dempster's rule).
    For singletons m = Bel. Columns Y_1..Y_n then ``*``; the second array
    tells which rows are defined (not in total conflict).
    """
    # Products of one factor per candidate underflow on large frames (0.1^1000): they are
    # formed as sums of logarithms and divided by the row's largest term (as in
    # ``pairwise_evidence_betp_rows``); the ratios are unchanged.
    with np.errstate(divide="ignore"):  # log 0 = −inf
        log_singles = np.log(support) + leave_one_out_sums(np.log(1.0 - support))
        log_star = np.log(refute).sum(axis=-1)
        log_full = np.log(refute + ignorance).sum(axis=-1)
    log_scale = np.maximum(log_singles.max(axis=-1, initial=-np.inf), log_full)  # m(*) ≤ Π(b + c)
    defined = log_scale > -np.inf
    shift = np.where(defined, log_scale, 0.0)
    singles = np.exp(log_singles - shift[:, None])
    star = np.exp(log_star - shift)
    normaliser = singles.sum(axis=-1) + np.exp(log_full - shift)
    safe = np.where(defined, normaliser, 1.0)[:, None]
    belief = np.concatenate([singles, star[:, None]], axis=1) / safe
    belief[~defined] = 0.0
    return belief, defined


def score_rows(
    items: IntArray,
    n_items: int,
    evidence: Evidence,
    score: str,
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Score every pair from its item's point of view.

    Parameters
    ----------
    items : ndarray of int, shape (P,)
        The item (row of the decision) of each pair; its frame is the pairs
        that share the item, plus ``*``.
    n_items : int
    evidence : (a, b, c) per pair
    score : {"betp", "belief"}
        Exact BetP of the combined mass (``pairwise_evidence_betp_rows``, §1.1)
        or the normalised singleton masses of [DH] eq 19.

    Returns
    -------
    values : ndarray, shape (P,)
        Score of Y_j for each pair.
    star : ndarray, shape (n_items,)
        Score of ``*`` per item (1 for an item without candidates).
    defined : ndarray of bool, shape (n_items,)
        False where the item's combined mass is in total conflict (scores 0).
    """
    support, refute, ignorance = evidence
    values = np.zeros(len(items))
    star = np.ones(n_items)
    defined = np.ones(n_items, dtype=bool)
    ragged = RaggedRows.of(items, n_items)
    for block, pair_index in ragged.blocks():
        inside = pair_index >= 0
        safe_index = np.maximum(pair_index, 0)
        # padding is a certain refutation (a = c = 0, b = 1): neutral in every product
        a = np.where(inside, support[safe_index], 0.0)
        b = np.where(inside, refute[safe_index], 1.0)
        c = np.where(inside, ignorance[safe_index], 0.0)
        if score == "betp":
            result, block_defined = pairwise_evidence_betp_rows(a, b, c)
        else:
            result, block_defined = singleton_belief_rows(a, b, c)
        values[pair_index[inside]] = result[:, :-1][inside]
        star[block] = result[:, -1]
        defined[block] = block_defined
    return values, star, defined


DEFAULT_ALPHA = 0.9
DEFAULT_GATE_PROBABILITY = 0.999
SCALES = ("gate", "fixed")
"""The similarity's scale (module docstring): γ = ln 2 / gate, or the fixed e^{−D/2}."""
DEFAULT_SCALE = "gate"
EVIDENCE_OPTIONS: tuple[OptionSpec, ...] = (
    NumberOption(
        "alpha", DEFAULT_ALPHA, low=0.0, high=1.0, doc="reliability α of each pairwise source"
    ),
    NumberOption(
        "gate_probability",
        DEFAULT_GATE_PROBABILITY,
        low=0.0,
        high=1.0,
        doc="each item's frame: its candidates with D ≤ chi2.ppf(p, q); 1 keeps every pair",
    ),
    ChoiceOption(
        "evidence",
        "fuzzy",
        tuple(EVIDENCE_MODELS),
        doc="pairwise evidence: fuzzy ([DH] eq 23–27) or likelihood (§3.4)",
        pluggable=True,
    ),
    ChoiceOption(
        "scale", DEFAULT_SCALE, SCALES, doc="similarity exp(−γD), γ = ln 2 / gate, or exp(−D/2)"
    ),
)
"""The options of the pairwise evidence, shared by ``mercier`` and ``dang_han``."""


@dataclass(frozen=True)
class EvidenceOptions:
    """Options shared by ``mercier`` and ``dang_han``.

    Attributes
    ----------
    alpha : float in (0, 1]
        Reliability α of each pairwise source (default 0.9, §3.4).
    gate_probability : float in (0, 1]
        The frame of each item holds the candidates with D ≤ chi2.ppf(p, q)
        (doubled for ``mean``); 1 keeps every pair. Default 0.999.
    evidence : {"fuzzy", "likelihood"} or an EvidenceModel callable
    scale : {"gate", "fixed"}
        s = exp(−γ D) with γ = ln 2 / gate (default), or exp(−D/2) (module docstring).
    """

    alpha: float = DEFAULT_ALPHA
    gate_probability: float = DEFAULT_GATE_PROBABILITY
    evidence: str | EvidenceModel = "fuzzy"
    scale: str = DEFAULT_SCALE

    @classmethod
    def of(cls, method: str, values: dict[str, Any]) -> EvidenceOptions:
        """The options from their parsed values; ``scale`` ``gate`` needs a gate below 1."""
        if values["scale"] == "gate" and values["gate_probability"] >= 1.0:
            raise OptionError(
                f"{method}: option 'scale' 'gate' takes γ = ln 2 / gate from 'gate_probability', "
                "which must then be below 1 (or use 'scale' 'fixed')"
            )
        return cls(values["alpha"], values["gate_probability"], values["evidence"], values["scale"])

    def gate(self, problem: AssociationProblem) -> float:
        """The frame's distance gate (inf for gate_probability = 1)."""
        if self.gate_probability >= 1.0:
            return np.inf
        return threshold_from_probability(
            self.gate_probability, problem.dimension, problem.distance
        )

    def similarity_factor(self, problem: AssociationProblem) -> float:
        """The factor that puts D on the models' e^{−D/2} scale: 2γ = 2 ln 2 / gate, or 1."""
        if self.scale == "fixed":
            return 1.0
        return 2.0 * math.log(2.0) / self.gate(problem)  # [T2T] eq 11 with λ = the gate

    def pair_evidence(self, problem: AssociationProblem, pairs: CandidatePairs) -> Evidence:
        """(a, b, c) of every pair, with the class source combined in when present."""
        model = self.evidence if callable(self.evidence) else EVIDENCE_MODELS[self.evidence]
        evidence = model(pairs.distance * self.similarity_factor(problem), self.alpha)
        class_plausibility = problem.class_plausibility(pairs)
        if class_plausibility is not None:
            evidence = with_class_evidence(evidence, class_plausibility)
        return evidence
