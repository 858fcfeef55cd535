"""Parameterless credal assignment ([T2T] §3, the seeds' own method; docs/algorithms.md §3.3).

For each incoming item t and known item ℓ (eq 3–4)::

    G_{ℓ,t} = exp(−D/2) / sqrt((2π)^q |C|),   Pl_t({ℓ}) = G_{ℓ,t},
    Pl_t({*}) = 1 − max_ℓ Pl_t({ℓ})                                   (eq 5)

then the GBT mass m_t (eq 6), its exact BetP_t (§1.1, ``gbt_betp_rows``) and
the assignment maximising Σ BetP r over the (n_known + n_incoming) × n_incoming
matrix of Table 1, where row ``*_t`` is allowed only in column t (eq 7–10).
Each column takes exactly one row, so the objective is
``Σ_t BetP_t(*) + Σ_{matched} (BetP_t(ℓ) − BetP_t(*))``: a maximum-gain
matching on the gains ``BetP_t(ℓ) − BetP_t(*)``.

For the GBT, ``BetP_t(ℓ) > BetP_t(*)`` exactly when ``Pl_t(ℓ) > Pl_t(*)``, so
an item is matched only if its best plausibility exceeds 1/2 (without
classes): the *implicit gate* ``D < 2 ln 2 − q ln 2π − log|C|`` (density) or
``D < 2 ln 2`` (relative), reported per incoming item.

Options
-------
likelihood : {"density", "relative"}
    **Reading** (§3.3): G is a density and may exceed 1. ``"density"``
    (default, faithful): Pl = min(G, 1), the clipped plausibilities are
    counted per incoming item. ``"relative"``: Pl = exp(−D/2) (the density
    over its peak; unit-invariant).
maximise : {"betp", "plausibility"}
    Maximise Σ BetP (default, eq 7) or Σ Pl ([T2T] §4 notes both).
plausibility_floor : float in [0, 1)
    **Reading** (numerical): plausibilities below it count as 0 — those
    elements are absent from the frame (§1.1: they "cost nothing") — which
    bounds the distances that must be solved. Default 1e-12; 0 solves every
    pair (small problems only).

Class information (§3.6) is a second source on the same frame with
Pl({ℓ}) = 1 − K (K the class conflict of the pair) and Pl({*}) = 1. Contour
functions of independent sources multiply (the conjunctive combination of two
GBT masses is the GBT mass of the products), so::

    Pl_t({ℓ}) = min(G_{ℓ,t}, 1) · (1 − K_{ℓ,t}),   Pl_t({*}) = 1 − max_ℓ min(G_{ℓ,t}, 1)

— the factor applies after the clipping (before it, class evidence vanished
wherever G > 1/(1 − K)), and Pl(*) stays that of the distances. The implicit
gate becomes ``G (1 − K) > 1 − G`` for the item's closest pair. An item whose
every candidate is vetoed (Pl = 0) while Pl(*) = 0 has all its mass on ∅: its
BetP is undefined, it is declared new and listed in ``diagnostics.undefined``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray
from core.association.assignment import max_gain_matching
from core.association.problem import AssociationProblem
from core.association.result import AssociationResult, Diagnostics, ScoreMatrix, build_result
from core.association.rows import RaggedRows
from core.association.spec import BOTH_SCOPES, ChoiceOption, MethodSpec, NumberOption
from core.belief import gbt_betp_rows
from core.distance import CandidatePairs

METHOD = "hachour"
DEFAULT_PLAUSIBILITY_FLOOR = 1e-12
LOG_TWO_PI = math.log(2.0 * math.pi)


@dataclass(frozen=True)
class HachourOptions:
    """Validated options of :func:`associate_hachour` (module docstring)."""

    likelihood: str = "density"
    maximise: str = "betp"
    plausibility_floor: float = DEFAULT_PLAUSIBILITY_FLOOR


def log_likelihood(pairs: CandidatePairs, likelihood: str) -> FloatArray:
    """ln G per pair ([T2T] eq 4), or −D/2 for the ``relative`` reading."""
    if likelihood == "relative":
        return -0.5 * pairs.distance
    return -0.5 * (pairs.distance + pairs.dimension * LOG_TWO_PI + pairs.log_det)


def distance_bound(problem: AssociationProblem, options: HachourOptions) -> float:
    """Largest D at which some pair can still reach Pl ≥ plausibility_floor."""
    if options.plausibility_floor == 0.0:
        return np.inf
    bound = -2.0 * math.log(options.plausibility_floor)
    if options.likelihood == "density":
        bound -= problem.dimension * LOG_TWO_PI + problem.smallest_log_det()
    return max(bound, 0.0)


def associate_hachour(problem: AssociationProblem, options: HachourOptions) -> AssociationResult:
    """GBT masses from likelihoods, exact BetP, Hungarian step on Table 1 ([T2T] §3)."""
    n_known, n_incoming = problem.n_known, problem.n_incoming
    gate = distance_bound(problem, options)
    pairs = problem.pairs(gate)
    log_g = log_likelihood(pairs, options.likelihood)
    clipped_pair = log_g > 0.0
    distance_plausibility = np.exp(np.minimum(log_g, 0.0))  # Pl = min(G, 1) (§3.3 reading)
    best = np.zeros(n_incoming)
    np.maximum.at(best, pairs.cols, distance_plausibility)
    star = 1.0 - best  # [T2T] eq 5, from the distances alone
    # §3.6: the class source has Pl(ℓ) = 1 − K and Pl(*) = 1; contour functions of
    # independent sources multiply, so only Pl(ℓ) changes, after the clipping.
    class_plausibility = problem.class_plausibility(pairs)
    class_factor = np.ones(len(pairs)) if class_plausibility is None else class_plausibility
    plausibility = distance_plausibility * class_factor
    keep = (plausibility >= options.plausibility_floor) & (plausibility > 0.0)
    # implicit gate: the item's closest pair ℓ is matched iff G(1 − K) > 1 − G, i.e.
    # D < 2 ln(1 + (1 − K)) − q ln 2π − log|C| (density; relative: without the last two)
    with np.errstate(divide="ignore"):
        pair_gate = 2.0 * np.log1p(class_factor) + 2.0 * log_g + pairs.distance
    implicit_gate = np.full(n_incoming, 2.0 * math.log(2.0))
    if options.likelihood == "density":  # items without candidates: the bound over all C
        implicit_gate -= problem.dimension * LOG_TWO_PI + problem.smallest_log_det()
    if len(pairs):
        per_item = np.full(n_incoming, -np.inf)
        np.maximum.at(per_item, pairs.cols, pair_gate)
        has = np.bincount(pairs.cols, minlength=n_incoming) > 0
        implicit_gate[has] = per_item[has]
    clipped = np.bincount(pairs.cols[clipped_pair], minlength=n_incoming).astype(np.int64)
    pairs, plausibility = pairs.select(keep), plausibility[keep]
    # an item whose frame keeps nothing plausible (every known item vetoed by classes,
    # Pl(*) = 0) has all its mass on ∅: BetP undefined, the item is declared new
    frame_size = np.bincount(pairs.cols, minlength=n_incoming)
    undefined = np.flatnonzero((frame_size == 0) & (star <= 0.0)).astype(np.int64)

    if options.maximise == "plausibility":
        values, new = plausibility, star.copy()
    else:
        values = np.zeros(len(pairs))
        new = np.where(star > 0.0, 1.0, 0.0)  # an item without candidates: BetP(*) = 1
        ragged = RaggedRows.of(pairs.cols, n_incoming)
        for items, pair_index in ragged.blocks():
            inside = pair_index >= 0
            rows_pl = np.where(inside, plausibility[np.maximum(pair_index, 0)], 0.0)
            rows_pl = np.concatenate([rows_pl, star[items][:, None]], axis=1)
            betp, _ = gbt_betp_rows(rows_pl)  # defined: some Pl of the row is > 0
            values[pair_index[inside]] = betp[:, :-1][inside]
            new[items] = betp[:, -1]
    gain = values - new[pairs.cols]
    matching = max_gain_matching(
        pairs.rows,
        pairs.cols,
        gain,
        n_known,
        n_incoming,
        solver=problem.solver,
        cluster=problem.cluster,
    )
    scores = ScoreMatrix(
        kind=options.maximise,
        rows=pairs.rows,
        cols=pairs.cols,
        values=values,
        new=new,
        shape=(n_known, n_incoming),
        missing=0.0,
    )
    notes: tuple[str, ...] = ()
    if options.likelihood == "density" and clipped.any():
        notes = (
            f"{int(clipped.sum())} plausibilities exceeded 1 (likelihood='density') and were clipped",
        )
    diagnostics = Diagnostics(
        uses_classes=class_plausibility is not None,
        candidate_pairs=len(pairs),
        clusters=matching.clusters,
        largest_cluster=matching.largest_cluster,
        gate=gate,
        clipped=clipped,
        implicit_gate=implicit_gate,
        undefined=undefined,
        notes=notes,
    )
    return build_result(METHOD, matching.rows, matching.cols, scores, diagnostics, pairs)


SPEC = MethodSpec(
    name=METHOD,
    scopes=BOTH_SCOPES,
    options=(
        ChoiceOption(
            "likelihood",
            "density",
            ("density", "relative"),
            doc="G a density (Pl = min(G, 1)) or exp(−D/2) (unit-invariant)",
        ),
        ChoiceOption(
            "maximise", "betp", ("betp", "plausibility"), doc="maximise Σ BetP (eq 7) or Σ Pl"
        ),
        NumberOption(
            "plausibility_floor",
            DEFAULT_PLAUSIBILITY_FLOOR,
            low=0.0,
            high=1.0,
            low_open=False,
            high_open=True,
            doc="plausibilities below it count as 0 (bounds the distances solved)",
        ),
    ),
    build=lambda values: HachourOptions(**values),
    run=associate_hachour,
    distance="mean",
    summary="Parameterless credal assignment ([T2T] §3)",
)
