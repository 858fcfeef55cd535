"""Hand-over: newly confirmed rows matched to the rows that keep their identity
(docs/algorithms.md §4 "Invisibility", [HZ] §5.1; §8.15 for ended tracks).

A track confirmed in this step may be an old target coming out of a blind
zone or an occlusion: it is compared with the phantoms (the fusion engine
also compares a sensor's new track with the established tracks it may
duplicate). Global nearest neighbour on the ``sum`` distance of the full
state, gated at the life cycle's ``gate_probability``; each matched keeper
then takes the newcomer's estimate and :func:`core.lifecycle.hand_over`
moves the life.

A track confirmed where a recently *ended* track is predicted may be that
target restarted (every sensor missed it long enough to delete it): the
fused layer hands it the ended track's id, but only on an unambiguous match
(``unique``): the newcomer gated by that one keeper and the keeper gating
that one newcomer (:func:`unique_gated`).
"""

from __future__ import annotations

import numpy as np

from core.arrays import BoolArray, FloatArray, IntArray
from core.association import associate
from core.models import MappedMotion


def hand_over_pairs(
    keepers: tuple[FloatArray, FloatArray],
    newcomers: tuple[FloatArray, FloatArray],
    gate_probability: float,
    *,
    unique: bool = False,
) -> tuple[IntArray, IntArray]:
    """(keeper index, newcomer index) of each matched pair; ``keepers`` and ``newcomers``
    are (means (n, d), covariances (n, d, d)), neither empty.

    ``unique``: only the gated pairs whose keeper gates no other newcomer and whose
    newcomer is gated by no other keeper (GNN would match each of them: its gain is
    positive and nothing competes for either side); every ambiguous pair is left out."""
    decision = associate(keepers, newcomers, "gnn", {"gate_probability": gate_probability}, "sum")
    if not unique:
        return decision.pair_known, decision.pair_incoming
    scores = decision.scores
    gated = np.isfinite(scores.values)
    rows, cols = scores.rows[gated], scores.cols[gated]
    keep = unique_gated(rows, cols, *scores.shape)
    return rows[keep], cols[keep]


def unique_gated(rows: IntArray, cols: IntArray, n_rows: int, n_cols: int) -> BoolArray:
    """The gated pairs (``rows[k]``, ``cols[k]``) whose row and column each occur in no
    other pair."""
    row_count = np.bincount(rows, minlength=n_rows)
    col_count = np.bincount(cols, minlength=n_cols)
    return np.asarray((row_count[rows] == 1) & (col_count[cols] == 1), dtype=bool)


def ended_hand_over_pairs(
    ended: tuple[FloatArray, FloatArray],
    gaps: FloatArray,
    motion: MappedMotion,
    newcomers: tuple[FloatArray, FloatArray],
    others: tuple[FloatArray, FloatArray],
    gate_probability: float,
) -> tuple[IntArray, IntArray]:
    """(ended index, newcomer index) of each unambiguous restart (docs/algorithms.md §8.15).

    ``ended``: the ended tracks' estimates when they ended, ``gaps`` (s) since; each is
    predicted over its gap (x ← F x, P ← F P Fᵀ + Q of ``motion``) and gated against the
    ``newcomers`` (tracks just confirmed) and the ``others`` (the live established
    tracks), all (means, covariances) at one time. A pair is kept only if it is its
    newcomer's only gated pair — no other ended track and no live track gates it (it may
    be a live track's duplicate) — and its ended track's — no other newcomer and no live
    track lies in its grown gate (:func:`hand_over_pairs` with ``unique``)."""
    predicted, predicted_cov = motion.predict(ended[0], ended[1], gaps)
    n_ended, n_new = len(predicted), len(newcomers[0])
    known, incoming = hand_over_pairs(
        (np.concatenate([predicted, others[0]]), np.concatenate([predicted_cov, others[1]])),
        (np.concatenate([newcomers[0], others[0]]), np.concatenate([newcomers[1], others[1]])),
        gate_probability,
        unique=True,
    )
    take = (known < n_ended) & (incoming < n_new)
    return known[take], incoming[take]
