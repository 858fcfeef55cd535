"""The one result type of every association method (docs/algorithms.md §3).

Rows are the known items ℓ (tracks with predicted estimates), columns the
incoming items t (tracks of a report, or measurements). The score matrix is
kept sparse (only gated pairs) so that 10 000 × 10 000 problems never form a
dense matrix; :meth:`ScoreMatrix.dense` builds one on request.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from core.arrays import FloatArray, IntArray
from core.distance import CandidatePairs

STAR_ROW = "*:"
"""Prefix of the row ``*_t`` of [T2T] Table 1 in a labelled table: ``*:<incoming id>``."""


@dataclass(frozen=True, eq=False)
class ScoreMatrix:
    """The decision matrix of a method, as sparse triplets.

    Attributes
    ----------
    kind : str
        What the values are: ``"distance"`` (gnn, minimised), ``"weight"``
        (denoeux contour weight w), ``"betp"`` / ``"plausibility"`` (hachour,
        mercier), ``"belief"`` / ``"betp"`` (dang_han).
    rows, cols : ndarray of int64
        Known and incoming index of each stored pair.
    values : ndarray
        The score of each stored pair.
    new : ndarray, shape (n_incoming,)
        Score of declaring each incoming item new: the diagonal ``*_t`` cells of
        [T2T] Table 1 (gnn: the threshold T; denoeux: 0).
    shape : (int, int)
        (n_known, n_incoming).
    missing : float
        The value of a pair that is not stored (outside the gate).
    """

    kind: str
    rows: IntArray
    cols: IntArray
    values: FloatArray
    new: FloatArray
    shape: tuple[int, int]
    missing: float

    def dense(self) -> FloatArray:
        """The n_known × n_incoming matrix, ``missing`` outside the gate."""
        matrix = np.full(self.shape, self.missing)
        matrix[self.rows, self.cols] = self.values
        return matrix

    def extended(self, forbidden: float = -np.inf) -> FloatArray:
        """The (n_known + n_incoming) × n_incoming matrix of [T2T] Table 1.

        Row n_known + t is ``*_t``: only its cell in column t is allowed, the
        others hold ``forbidden`` (not 0).
        """
        n_incoming = self.shape[1]
        lower = np.full((n_incoming, n_incoming), forbidden)
        np.fill_diagonal(lower, self.new)
        return np.vstack([self.dense(), lower])

    def table(
        self, known_ids: Sequence[str], incoming_ids: Sequence[str]
    ) -> tuple[tuple[str, ...], tuple[str, ...], FloatArray]:
        """[T2T] Table 1 with labels: rows ``known_ids`` then ``*:<incoming id>``, columns
        ``incoming_ids``; forbidden cells are NaN (``null`` on the wire)."""
        rows = (*known_ids, *(f"{STAR_ROW}{incoming}" for incoming in incoming_ids))
        return rows, tuple(incoming_ids), self.extended(forbidden=np.nan)


@dataclass(frozen=True, eq=False)
class Diagnostics:
    """What a method saw and did, per item where it matters.

    Attributes
    ----------
    uses_classes : bool
        Class information entered the decision.
    classes_ignored : bool
        Classes were given but the method cannot use them (gnn, [T2T] §4).
    candidate_pairs : int
        Pairs inside the gate (the sparse score matrix).
    clusters, largest_cluster : int
        Connected components solved, and rows + columns of the largest.
    gate : float
        The distance gate the candidates were taken from (``inf``: none).
    clipped : ndarray of int64, shape (n_incoming,) or empty
        hachour ``likelihood="density"``: plausibilities clipped at 1 per incoming item.
    implicit_gate : ndarray, shape (n_incoming,) or empty
        hachour: per incoming item, the largest D at which its best pair can
        still be matched (G (1 − K) > 1 − G; without classes Pl > 1/2, §3.3).
    undefined : ndarray of int64
        Items whose combined mass was in total conflict (BetP undefined):
        they are declared new / missed.
    notes : tuple of str
        Human-readable remarks (e.g. why classes were ignored).
    """

    uses_classes: bool = False
    classes_ignored: bool = False
    candidate_pairs: int = 0
    clusters: int = 0
    largest_cluster: int = 0
    gate: float = float("inf")
    clipped: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    implicit_gate: FloatArray = field(default_factory=lambda: np.zeros(0))
    undefined: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    notes: tuple[str, ...] = ()


@dataclass(frozen=True, eq=False)
class AssociationResult:
    """The decision of an association method.

    Attributes
    ----------
    method : str
    pair_known, pair_incoming : ndarray of int64
        Matched pairs (ℓ, t), sorted by ℓ.
    pair_score : ndarray
        The method's score of each matched pair (its value in ``scores``).
    new : ndarray of int64
        Incoming items matched with nothing (new targets), ascending.
    missed : ndarray of int64
        Known items matched with nothing (not observed), ascending.
    scores : ScoreMatrix
    diagnostics : Diagnostics
    gated : CandidatePairs or None
        The gated pairs the method decided on (their D, log|C|, and the plain D a local
        tracker scores hits with); every run of a registered method sets it.
    """

    method: str
    pair_known: IntArray
    pair_incoming: IntArray
    pair_score: FloatArray
    new: IntArray
    missed: IntArray
    scores: ScoreMatrix
    diagnostics: Diagnostics
    gated: CandidatePairs | None = None

    @property
    def pairs(self) -> list[tuple[int, int, float]]:
        """Matched pairs as ``(known, incoming, score)`` tuples."""
        return [
            (int(k), int(i), float(s))
            for k, i, s in zip(self.pair_known, self.pair_incoming, self.pair_score, strict=True)
        ]

    def assignment(self) -> dict[int, int]:
        """``{known: incoming}`` of the matched pairs."""
        return {int(k): int(i) for k, i in zip(self.pair_known, self.pair_incoming, strict=True)}


def build_result(
    method: str,
    matched_known: IntArray,
    matched_incoming: IntArray,
    scores: ScoreMatrix,
    diagnostics: Diagnostics,
    gated: CandidatePairs,
) -> AssociationResult:
    """Fill in pair scores, new and missed items from a matching (sorted by known); ``gated``:
    the pairs the method decided on."""
    n_known, n_incoming = scores.shape
    order = np.argsort(matched_known, kind="stable")
    matched_known = matched_known[order].astype(np.int64)
    matched_incoming = matched_incoming[order].astype(np.int64)
    # stored pairs are sorted by (row, col): locate each matched pair
    keys = scores.rows * max(n_incoming, 1) + scores.cols
    wanted = matched_known * max(n_incoming, 1) + matched_incoming
    position = np.searchsorted(keys, wanted)
    pair_score = scores.values[position] if len(wanted) else np.zeros(0)
    new_mask = np.ones(n_incoming, dtype=bool)
    new_mask[matched_incoming] = False
    missed_mask = np.ones(n_known, dtype=bool)
    missed_mask[matched_known] = False
    return AssociationResult(
        method=method,
        pair_known=matched_known,
        pair_incoming=matched_incoming,
        pair_score=np.asarray(pair_score, dtype=np.float64),
        new=np.flatnonzero(new_mask).astype(np.int64),
        missed=np.flatnonzero(missed_mask).astype(np.int64),
        scores=scores,
        diagnostics=diagnostics,
        gated=gated,
    )
