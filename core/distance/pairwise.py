"""Mahalanobis distances between two lists, over gated pairs only (docs/algorithms.md §2).

For estimates (x₁, P₁) of the known side and (x₂, P₂) of the incoming side,
Δ = x₁ − x₂ and ``D = Δᵀ C⁻¹ Δ`` with

- ``"mean"``: C = (P₁ + P₂)/2 ([T2T] eq 1–2);
- ``"sum"``: C = P₁ + P₂ ([HZ] §2: the covariance of Δ for independent
  errors, so D ~ χ²_q for a true pair);
- ``"innovation"``: C = S, the known side's innovation covariance, and the
  incoming side holds measurements z ([MTT] eq 15: the known states are the
  predicted measurements ẑ).

Optionally D is replaced by the modified distance of [HZ] §4.1
(:mod:`core.distance.modified`).

Gate: since ``|Δ|² ≤ λ_max(C) D``, every pair with D ≤ T lies within the
Euclidean radius ``sqrt(T (w₁ max λ_max(P₁) + w₂ max λ_max(P₂)))`` (w the
weights of C) on any subset of the components. A KD-tree
(``scipy.spatial.cKDTree``) on the position components lists the pairs within
that radius; only those are solved, in vectorised blocks, and only those with
D ≤ T are returned. Far pairs are never solved and no N × M matrix is formed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Literal, get_args

import numpy as np
from scipy.spatial import cKDTree
from scipy.stats import chi2

from core.arrays import FloatArray, IntArray
from core.distance.cholesky import UNROLLED_MAX_DIMENSION, quadratic_form_and_log_det
from core.distance.estimates import Estimates
from core.distance.modified import ModifiedScale
from core.errors import InvalidInput

CovarianceKind = Literal["mean", "sum", "innovation"]

COVARIANCE_WEIGHTS: dict[str, tuple[float, float]] = {
    "mean": (0.5, 0.5),  # [T2T] eq 2
    "sum": (1.0, 1.0),  # [HZ] §2
    "innovation": (1.0, 0.0),  # [MTT] eq 15: S carries everything
}

ALL_PAIRS_LIMIT = 4096
"""Problems with at most this many pairs skip the KD-tree and solve every pair."""

UNBOUNDED_PAIRS_LIMIT = 20_000_000
"""Largest N × M enumerated when the gate is infinite (beyond: error, not a memory blow-up)."""

BLOCK_PAIRS = 1 << 16
"""Pairs solved per vectorised block (bounds the temporaries)."""


@dataclass(frozen=True)
class DistanceModel:
    """Which distance to compute.

    Attributes
    ----------
    covariance : {"mean", "sum", "innovation"}
        How C is formed from the two covariances (module docstring).
    modified : ModifiedScale or None
        When set, D is replaced by the modified distance of [HZ] §4.1, with u
        taken from the *known* item's covariance against its steady state.
    positions : tuple of int or None
        State components the KD-tree gate uses (None: all). Any subset gives
        a correct gate; positions give a low-dimensional tree.
    """

    covariance: CovarianceKind = "sum"
    modified: ModifiedScale | None = None
    positions: tuple[int, ...] | None = None

    @classmethod
    def of(cls, distance: str | DistanceModel) -> DistanceModel:
        """Accept a covariance name or a model; reject anything else by name."""
        if isinstance(distance, DistanceModel):
            model = distance
        elif isinstance(distance, str) and distance in get_args(CovarianceKind):
            model = cls(covariance=distance)  # type: ignore[arg-type]
        else:
            raise InvalidInput(
                f"distance must be one of {list(get_args(CovarianceKind))} or a DistanceModel, "
                f"got {distance!r}"
            )
        if model.covariance not in COVARIANCE_WEIGHTS:
            raise InvalidInput(
                f"distance covariance must be one of {list(COVARIANCE_WEIGHTS)}, got {model.covariance!r}"
            )
        return model

    @property
    def chi2_scale(self) -> float:
        """D of a true pair is ``chi2_scale · χ²_q``: 2 for ``mean`` (C is halved), else 1."""
        return 2.0 if self.covariance == "mean" else 1.0


@lru_cache(maxsize=512)
def chi2_quantile(probability: float, dimension: int) -> float:
    """``chi2.ppf(p, q)``, cached: gates are asked for at every step with the same few values."""
    return float(chi2.ppf(probability, dimension))


def threshold_from_probability(probability: float, dimension: int, model: DistanceModel) -> float:
    """T with P(D ≤ T) = probability for a true pair (docs/algorithms.md §3.1).

    ``chi2.ppf(p, q)``, doubled for the ``mean`` covariance whose C is halved.
    The modified distance is ≥ D, so the same T is a (tighter) gate there.
    """
    return model.chi2_scale * chi2_quantile(probability, dimension)


@dataclass(frozen=True, eq=False)
class CandidatePairs:
    """Gated pairs of a known and an incoming list, sorted by (row, column).

    Attributes
    ----------
    rows, cols : ndarray of int64, shape (P,)
        Known index ℓ and incoming index t of each pair.
    distance : ndarray, shape (P,)
        D (modified when the model says so).
    log_det : ndarray, shape (P,)
        log|C| of each pair.
    n_known, n_incoming, dimension : int
    plain : ndarray, shape (P,), or None
        The unmodified D ([MTT] eq 15) when ``distance`` is modified or ranked otherwise
        (a local tracker's gating, :mod:`core.tracking.gating`); None: ``distance`` is it.
    """

    rows: IntArray
    cols: IntArray
    distance: FloatArray
    log_det: FloatArray
    n_known: int
    n_incoming: int
    dimension: int
    plain: FloatArray | None = None

    def __len__(self) -> int:
        return len(self.rows)

    @property
    def plain_distance(self) -> FloatArray:
        """The unmodified D of each pair: the one a Gaussian likelihood ([MTT] eq 15) uses."""
        return self.distance if self.plain is None else self.plain

    def select(self, keep: np.ndarray) -> CandidatePairs:
        """The pairs where ``keep`` is true (order kept)."""
        return CandidatePairs(
            self.rows[keep],
            self.cols[keep],
            self.distance[keep],
            self.log_det[keep],
            self.n_known,
            self.n_incoming,
            self.dimension,
            None if self.plain is None else self.plain[keep],
        )

    def dense(self, fill: float = np.inf) -> FloatArray:
        """D as an n_known × n_incoming matrix, ``fill`` outside the gate (small problems)."""
        matrix = np.full((self.n_known, self.n_incoming), fill)
        matrix[self.rows, self.cols] = self.distance
        return matrix


def _check_sides(known: Estimates, incoming: Estimates, model: DistanceModel) -> None:
    if len(known) and len(incoming) and known.dimension != incoming.dimension:
        raise InvalidInput(
            f"known states have dimension {known.dimension}, incoming {incoming.dimension}"
        )
    if known.covariances is None:
        raise InvalidInput("known: covariances are required")
    if model.covariance != "innovation" and incoming.covariances is None:
        raise InvalidInput(
            f"incoming: covariances are required for the {model.covariance!r} distance "
            "(use 'innovation' for measurements)"
        )
    if model.positions is not None:
        dimension = known.dimension if len(known) else incoming.dimension
        bad = [p for p in model.positions if not 0 <= p < dimension]
        if bad or not model.positions:
            raise InvalidInput(
                f"distance positions must be distinct state components in [0, {dimension}), "
                f"got {list(model.positions)}"
            )


def _largest_eigenvalue(covariances: FloatArray | None) -> float:
    if covariances is None or len(covariances) == 0:
        return 0.0
    return float(np.linalg.eigvalsh(covariances)[:, -1].max())


def _all_pairs(n: int, m: int) -> tuple[IntArray, IntArray]:
    """Every (row, column) index pair, sorted by row then column."""
    rows = np.repeat(np.arange(n, dtype=np.int64), m)
    cols = np.tile(np.arange(m, dtype=np.int64), n)
    return rows, cols


def _candidate_index_pairs(
    known: Estimates, incoming: Estimates, gate: float, model: DistanceModel
) -> tuple[IntArray, IntArray]:
    n, m = len(known), len(incoming)
    if not np.isfinite(gate) or n * m <= ALL_PAIRS_LIMIT:
        if n * m > UNBOUNDED_PAIRS_LIMIT:
            raise InvalidInput(
                f"an unbounded gate on {n} known × {m} incoming items would solve {n * m} pairs; "
                "use a finite gate (e.g. gate_probability < 1)"
            )
        return _all_pairs(n, m)
    w_known, w_incoming = COVARIANCE_WEIGHTS[model.covariance]
    bound = w_known * _largest_eigenvalue(known.covariances) + w_incoming * _largest_eigenvalue(
        incoming.covariances
    )
    radius = float(np.sqrt(gate * bound))
    columns: Sequence[int] | slice = (
        list(model.positions) if model.positions is not None else slice(None)
    )
    both = np.concatenate([known.states[:, columns], incoming.states[:, columns]])
    if float(np.linalg.norm(both.max(axis=0) - both.min(axis=0))) <= radius:
        # every pair is within the radius (dense layout): enumerate, no tree
        return _all_pairs(n, m)
    known_tree = cKDTree(known.states[:, columns])
    incoming_tree = cKDTree(incoming.states[:, columns])
    close = known_tree.sparse_distance_matrix(incoming_tree, radius, output_type="ndarray")
    rows = close["i"].astype(np.int64)
    cols = close["j"].astype(np.int64)
    order = np.lexsort((cols, rows))
    return rows[order], cols[order]


def _combined_covariances(
    known_cov: FloatArray,
    incoming_cov: FloatArray | None,
    rows: IntArray,
    cols: IntArray,
    w_known: float,
    w_incoming: float,
) -> FloatArray:
    """``C = w₁ P₁ + w₂ P₂`` per pair, component-major (q, q, n).

    The unrolled factorisation reads the lower triangle only, so for q ≤
    ``UNROLLED_MAX_DIMENSION`` only that is formed (the upper entries are left
    unset); a weight of 1 is not multiplied by.
    """
    q = known_cov.shape[0]
    with_incoming = bool(w_incoming) and incoming_cov is not None
    if q > UNROLLED_MAX_DIMENSION:
        combined = known_cov[:, :, rows] * w_known
        if with_incoming:
            assert incoming_cov is not None
            combined = combined + incoming_cov[:, :, cols] * w_incoming
        return np.asarray(combined, dtype=np.float64)
    combined = np.empty((q, q, len(rows)))
    for i in range(q):
        for j in range(i + 1):
            entry = combined[i, j]
            np.take(known_cov[i, j], rows, out=entry)
            if w_known != 1.0:
                entry *= w_known
            if with_incoming:
                assert incoming_cov is not None
                other = incoming_cov[i, j].take(cols)
                entry += other if w_incoming == 1.0 else other * w_incoming
    return combined


def gated_pairs(
    known: Estimates,
    incoming: Estimates,
    gate: float,
    distance: str | DistanceModel = "sum",
) -> CandidatePairs:
    """Every pair (ℓ, t) with D ≤ ``gate``, solved only near the gate.

    Parameters
    ----------
    known, incoming : Estimates
        Rows and columns. For ``"innovation"`` the known states are ẑ with
        their innovation covariances S and the incoming states are z.
    gate : float
        T, ≥ 0; ``inf`` keeps every pair (small problems only).
    distance : str or DistanceModel

    Returns
    -------
    CandidatePairs
    """
    model = DistanceModel.of(distance)
    if not gate >= 0.0:
        raise InvalidInput(f"gate must be ≥ 0, got {gate!r}")
    n, m = len(known), len(incoming)
    q = known.dimension if n else incoming.dimension
    empty = np.zeros(0, dtype=np.int64)
    if n == 0 or m == 0:
        return CandidatePairs(empty, empty.copy(), np.zeros(0), np.zeros(0), n, m, q)
    _check_sides(known, incoming, model)
    assert known.covariances is not None
    rows, cols = _candidate_index_pairs(known, incoming, gate, model)
    ratio = None if model.modified is None else model.modified.ratio(known.covariances)
    w_known, w_incoming = COVARIANCE_WEIGHTS[model.covariance]
    known_states = known.states.T
    incoming_states = incoming.states.T
    known_cov = known.covariances.transpose(1, 2, 0)
    incoming_cov = None if incoming.covariances is None else incoming.covariances.transpose(1, 2, 0)
    distances = np.empty(len(rows))
    log_dets = np.empty(len(rows))
    for start in range(0, len(rows), BLOCK_PAIRS):
        r = rows[start : start + BLOCK_PAIRS]
        c = cols[start : start + BLOCK_PAIRS]
        differences = known_states[:, r] - incoming_states[:, c]
        combined = _combined_covariances(known_cov, incoming_cov, r, c, w_known, w_incoming)
        block_distance, block_log_det = quadratic_form_and_log_det(differences, combined)
        if ratio is not None:
            block_distance = block_distance * ratio[r]
        distances[start : start + BLOCK_PAIRS] = block_distance
        log_dets[start : start + BLOCK_PAIRS] = block_log_det
    keep = distances <= gate
    if keep.all():
        return CandidatePairs(rows, cols, distances, log_dets, n, m, q)
    return CandidatePairs(rows[keep], cols[keep], distances[keep], log_dets[keep], n, m, q)


def distance_matrix(
    known: Estimates, incoming: Estimates, distance: str | DistanceModel = "sum"
) -> FloatArray:
    """Dense N × M matrix of D over all pairs (small problems, tests, display)."""
    return gated_pairs(known, incoming, np.inf, distance).dense()
