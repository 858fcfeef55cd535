"""Maximum-weight partial matching on a sparse bipartite graph, cluster by cluster.

Every method of docs/algorithms.md §3 that solves an assignment reduces to: given
candidate pairs (ℓ, t) with a *gain* g > 0 (what matching ℓ with t adds to
the objective compared with leaving both unmatched), pick a partial matching
maximising Σ g. Pairs with g ≤ 0 never help and are dropped first.

That problem separates over the connected components of the candidate graph.
Components that are a single pair or a star (one row or one column) are
solved in closed form for all components at once (the best pair); the others
each get a dense linear assignment on their own rows × columns, with 0 for
absent pairs (a zero-gain pair is the same as no pair, so the full rectangular
assignment and the partial matching have the same optimum).

Solvers: ``"lapjv"`` (Jonker–Volgenant from the ``lapx`` package, the
default: faster, see ``bench/association.py``) and ``"scipy"``
(``scipy.optimize.linear_sum_assignment``, the reference). Both are
deterministic; on exact ties they may pick different optimal matchings.
With ``"lapjv"``, a large component in which every pair has a positive gain
(a dense layout: everything inside every gate) is solved on a few candidates
per item and certified optimal on the whole matrix by LP duality
(:func:`solve_complete`), four times faster than a dense solve of 1000 × 1000
nearly tied gains; it falls back to the dense solve when it cannot certify.

Tie rule: a star component takes its best pair, ties broken by the lowest
row, then the lowest column; elsewhere an exactly tied optimum is the
solver's.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

import lap
import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_matrix, csr_matrix
from scipy.sparse.csgraph import connected_components, min_weight_full_bipartite_matching

from core.arrays import FloatArray, IntArray
from core.errors import InvalidInput

Solver = Literal["lapjv", "scipy"]
SOLVERS: tuple[str, ...] = get_args(Solver)


@dataclass(frozen=True, eq=False)
class Matching:
    """A partial matching, sorted by row.

    Attributes
    ----------
    rows, cols : ndarray of int64
        Matched pairs.
    clusters : int
        Connected components of the graph of positive-gain pairs.
    largest_cluster : int
        Rows + columns of the largest component.
    """

    rows: IntArray
    cols: IntArray
    clusters: int
    largest_cluster: int


def solve_dense(gain: FloatArray, solver: Solver = "lapjv") -> tuple[IntArray, IntArray]:
    """Maximum-gain partial matching of a dense gain matrix (pairs with gain ≤ 0 dropped)."""
    if gain.size == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty.copy()
    if solver == "scipy":
        rows, cols = linear_sum_assignment(gain, maximize=True)
    elif solver == "lapjv":
        square = gain.shape[0] == gain.shape[1]
        rows, cols = lap.lapjvx(-gain, extend_cost=not square, return_cost=False)
    else:
        raise InvalidInput(f"solver must be one of {list(SOLVERS)}, got {solver!r}")
    rows = np.asarray(rows, dtype=np.int64)
    cols = np.asarray(cols, dtype=np.int64)
    keep = gain[rows, cols] > 0.0
    rows, cols = rows[keep], cols[keep]
    order = np.argsort(rows, kind="stable")
    return rows[order], cols[order]


SPARSE_MIN_SIDE = 128
"""Complete components (every pair has a positive gain) with both sides at least this
large are solved on a few candidates per item, then certified (:func:`solve_complete`)."""

SPARSE_CANDIDATES = 24
"""Candidates kept per row and per column for the first sparse solve."""

SHORTEST_PATH_PASSES = 256
"""Relaxation passes of the certificate's shortest paths before it gives up."""

RESEED = 8
"""After a round with violators, each row and column that had one also takes its RESEED
pairs of smallest reduced cost under the round's duals (fewer rounds)."""

SPARSE_ROUNDS = 6
"""Sparse solves before the certified path gives up and solves the dense matrix."""


def solve_complete(gain: FloatArray) -> tuple[IntArray, IntArray] | None:
    """Maximum-gain matching of a dense matrix whose every gain is > 0, through a sparse solve.

    On such a matrix an optimal partial matching covers the smaller side (any
    uncovered row and column would add a positive pair), so the problem is a
    rectangular assignment. It is solved on the ``SPARSE_CANDIDATES`` best
    pairs of every row and of every column (``min_weight_full_bipartite_matching``),
    then **certified** on the whole matrix by LP duality: with rows covered and
    u, v the duals of ``max Σ g x`` over partial matchings (u_i + v_j ≥ g_ij,
    u, v ≥ 0, v = 0 on uncovered columns, equality on matched pairs), the
    largest feasible v follows from the matching by shortest paths
    (Bellman–Ford on the columns: ``v_k ≥ v_σ(i) + g_ik − g_iσ(i)``), and the
    matching is optimal on the whole matrix when no pair outside the candidates
    has ``g_ij > u_i + v_j``. Pairs that do are added, with the pairs of
    smallest reduced cost of their rows and columns, and the sparse problem
    solved again. The answer is the dense solvers' optimum (ties apart: an
    exactly tied optimum may be another one). Returns None when the certificate
    cannot be had in ``SPARSE_ROUNDS`` solves; the caller then solves densely.
    """
    transposed = gain.shape[0] > gain.shape[1]
    matrix = gain.T if transposed else gain  # rows ≤ columns
    n, m = matrix.shape
    k = min(SPARSE_CANDIDATES, m - 1)
    candidates = np.zeros((n, m), dtype=bool)
    row_best = np.argpartition(-matrix, k, axis=1)[:, : k + 1]
    candidates[np.arange(n)[:, None], row_best] = True
    if n > k + 1:
        col_best = np.argpartition(-matrix, k, axis=0)[: k + 1, :]
        candidates[col_best, np.arange(m)[None, :]] = True
    tolerance = 1e-12 * float(np.abs(matrix).max())
    ceiling = float(matrix.max()) + 1.0
    for _ in range(SPARSE_ROUNDS):
        rows, cols = np.nonzero(candidates)
        values = matrix[rows, cols]
        found = _sparse_assignment(rows, cols, ceiling - values, n, m, candidates)
        if found is None:  # the candidates hold no matching covering the rows
            return None
        match = found
        column_row = np.full(m, -1, dtype=np.int64)
        column_row[match] = np.arange(n)
        # shortest paths over columns, node m standing for every uncovered column (v = 0):
        # edge σ(i) → k of weight g_iσ(i) − g_ik for every candidate (i, k), k ≠ σ(i), and
        # m → every covered column of weight 0; w = −v = the distances from node m
        own = matrix[np.arange(n), match]
        other = cols != match[rows]
        sources = match[rows[other]]
        targets = np.where(column_row[cols[other]] >= 0, cols[other], m)
        weights = own[rows[other]] - values[other]
        sources = np.concatenate([sources, np.full(n, m)])
        targets = np.concatenate([targets, match])
        weights = np.concatenate([weights, np.zeros(n)])
        distance = _shortest_from(m, sources, targets, weights, m + 1)
        if distance is None:  # a negative cycle (rounding on a tied optimum): dense decides
            return None
        v = np.where(column_row >= 0, -distance[:m], 0.0)
        u = own - v[match]
        if np.any(u < -tolerance) or not np.all(np.isfinite(v)):
            return None
        violated = (matrix > u[:, None] + v[None, :] + tolerance) & ~candidates
        if not violated.any():
            matched_rows, matched_cols = np.arange(n, dtype=np.int64), match
            if transposed:
                matched_rows, matched_cols = match, np.arange(n, dtype=np.int64)
            order = np.argsort(matched_rows, kind="stable")
            return matched_rows[order], matched_cols[order]
        candidates |= violated
        # rows and columns that had a violator also take their next best pairs by reduced
        # cost (u_i + v_j − g_ij): the next solve's duals move there first
        reduced = u[:, None] + v[None, :] - matrix
        bad_rows = np.flatnonzero(violated.any(axis=1))
        bad_cols = np.flatnonzero(violated.any(axis=0))
        extra = min(RESEED, m - 1)
        if len(bad_rows) and extra > 0:
            best = np.argpartition(reduced[bad_rows], extra, axis=1)[:, :extra]
            candidates[bad_rows[:, None], best] = True
        extra = min(RESEED, n - 1)
        if len(bad_cols) and extra > 0:
            best = np.argpartition(reduced[:, bad_cols], extra, axis=0)[:extra, :]
            candidates[best, bad_cols[None, :]] = True
    return None


def _sparse_assignment(
    rows: IntArray,
    cols: IntArray,
    costs: FloatArray,
    n: int,
    m: int,
    candidates: np.ndarray,
) -> IntArray | None:
    """The column of each row in a minimum-cost assignment covering the rows (n ≤ m),
    over the candidate pairs (sorted by row, then column), or None when there is none.

    Square problems go to lapx's ``lapmod`` (about twice as fast), whose answer is
    checked (on an infeasible graph it returns pairs that are not candidates); the
    rest, and anything ``lapmod`` did not solve, to scipy's
    ``min_weight_full_bipartite_matching``.
    """
    if n == m:
        starts = np.searchsorted(rows, np.arange(n + 1))
        match = np.asarray(lap.lapmod(n, costs, starts, cols, return_cost=False)[0], np.int64)
        valid = np.all((match >= 0) & (match < m))
        if valid and candidates[np.arange(n), match].all() and len(np.unique(match)) == n:
            return match
    graph = csr_matrix((costs, (rows, cols)), shape=(n, m))
    try:
        _, found = min_weight_full_bipartite_matching(graph)
    except ValueError:
        return None
    return np.asarray(found, dtype=np.int64)


def _shortest_from(
    source: int, sources: IntArray, targets: IntArray, weights: FloatArray, nodes: int
) -> FloatArray | None:
    """Bellman–Ford distances from ``source``, every edge relaxed at once per pass.

    Parallel edges are allowed. Passes stop when nothing changes (as many as the
    edges of the longest shortest path, a handful here); None after ``nodes``
    passes (a negative cycle) or ``SHORTEST_PATH_PASSES`` (the caller then solves
    densely: slow convergence costs no more than that).
    """
    distance = np.full(nodes, np.inf)
    distance[source] = 0.0
    for _ in range(min(nodes, SHORTEST_PATH_PASSES)):
        relaxed = distance.copy()
        np.minimum.at(relaxed, targets, distance[sources] + weights)
        if np.array_equal(relaxed, distance):
            return distance
        distance = relaxed
    return None


def solve_component(gain: FloatArray, solver: Solver) -> tuple[IntArray, IntArray]:
    """One component's matching: certified sparse for large complete ones, else dense."""
    if solver == "lapjv" and min(gain.shape) >= SPARSE_MIN_SIDE and bool(np.all(gain > 0.0)):
        found = solve_complete(gain)
        if found is not None:
            return found
    return solve_dense(gain, solver)


def sorted_members(indices: IntArray, size: int) -> IntArray:
    """The distinct values of ``indices`` (all in range(size)), ascending: a count when dense."""
    if len(indices) >= size:
        return np.flatnonzero(np.bincount(indices, minlength=size)).astype(np.int64)
    return np.unique(indices).astype(np.int64)


SMALL_PAIRS = 64
"""Up to this many positive pairs the components are found in plain Python (a local
tracker's scan: a few tracks and detections, where array and sparse-graph set-up
cost more than the work)."""


def _small_matching(
    rows: IntArray, cols: IntArray, gain: FloatArray, n_rows: int, solver: Solver
) -> Matching:
    """:func:`max_gain_matching` on few pairs: the same components, the same rules."""
    row_list, col_list, gain_list = rows.tolist(), cols.tolist(), gain.tolist()
    parent = list(range(n_rows + max(col_list) + 1))

    def root(node: int) -> int:
        while parent[node] != node:
            parent[node] = parent[parent[node]]
            node = parent[node]
        return node

    for row, col in zip(row_list, col_list, strict=True):
        parent[root(row)] = root(n_rows + col)
    members: dict[int, list[int]] = {}
    for edge, row in enumerate(row_list):
        members.setdefault(root(row), []).append(edge)
    chosen: list[tuple[int, int]] = []
    largest = 0
    for edges in members.values():
        local_rows = sorted({row_list[e] for e in edges})
        local_cols = sorted({col_list[e] for e in edges})
        largest = max(largest, len(local_rows) + len(local_cols))
        if len(local_rows) == 1 or len(local_cols) == 1:  # a star: its best pair
            best = min(edges, key=lambda e: (-gain_list[e], row_list[e], col_list[e]))
            chosen.append((row_list[best], col_list[best]))
            continue
        row_slot = {row: slot for slot, row in enumerate(local_rows)}
        col_slot = {col: slot for slot, col in enumerate(local_cols)}
        dense = np.zeros((len(local_rows), len(local_cols)))
        for e in edges:
            dense[row_slot[row_list[e]], col_slot[col_list[e]]] = gain_list[e]
        matched_rows, matched_cols = solve_dense(dense, solver)
        chosen.extend(
            (local_rows[r], local_cols[c])
            for r, c in zip(matched_rows.tolist(), matched_cols.tolist(), strict=True)
        )
    chosen.sort()
    matched = np.array(chosen, dtype=np.int64).reshape(-1, 2)
    return Matching(matched[:, 0].copy(), matched[:, 1].copy(), len(members), largest)


def max_gain_matching(
    rows: IntArray,
    cols: IntArray,
    gain: FloatArray,
    n_rows: int,
    n_cols: int,
    *,
    solver: Solver = "lapjv",
    cluster: bool = True,
) -> Matching:
    """Maximum-gain partial matching over sparse candidate pairs.

    Parameters
    ----------
    rows, cols : ndarray of int, shape (P,)
        Candidate pairs (no pair twice).
    gain : ndarray, shape (P,)
        Finite gains; pairs with gain ≤ 0 are never matched.
    n_rows, n_cols : int
        Sizes of the two sides.
    solver : {"lapjv", "scipy"}
    cluster : bool
        Solve each connected component on its own (default). ``False``
        solves one dense n_rows × n_cols problem (reference for tests).
    """
    if solver not in SOLVERS:
        raise InvalidInput(f"solver must be one of {list(SOLVERS)}, got {solver!r}")
    keep = gain > 0.0
    rows, cols, gain = rows[keep], cols[keep], gain[keep]
    empty = np.zeros(0, dtype=np.int64)
    if len(rows) == 0:
        return Matching(empty, empty.copy(), 0, 0)
    if not cluster:
        dense = np.zeros((n_rows, n_cols))
        dense[rows, cols] = gain
        matched_rows, matched_cols = solve_dense(dense, solver)
        return Matching(matched_rows, matched_cols, 1, n_rows + n_cols)
    if len(rows) <= SMALL_PAIRS:
        return _small_matching(rows, cols, gain, n_rows, solver)
    if len(rows) == n_rows * n_cols and min(n_rows, n_cols) >= 2:
        # every pair positive: one component, neither a single pair nor a star
        keys = rows * n_cols + cols
        if np.array_equal(keys, np.arange(len(keys))):  # sorted by (row, column)
            dense = gain.reshape(n_rows, n_cols)
        else:
            dense = np.zeros((n_rows, n_cols))
            dense[rows, cols] = gain
        matched_rows, matched_cols = solve_component(dense, solver)
        return Matching(matched_rows, matched_cols, 1, n_rows + n_cols)

    graph = coo_matrix(
        (np.ones(len(rows)), (rows, cols + n_rows)), shape=(n_rows + n_cols, n_rows + n_cols)
    )
    _, labels = connected_components(graph, directed=False)
    edge_label = labels[rows]
    used_labels = sorted_members(edge_label, len(labels))
    n_components = len(used_labels)
    renumber = np.zeros(len(labels), dtype=np.int64)  # labels with edges → 0..n_components−1
    renumber[used_labels] = np.arange(n_components)
    edge_component = renumber[edge_label]
    node_component = renumber[labels]
    in_graph = np.zeros(n_rows + n_cols, dtype=bool)
    in_graph[rows] = True
    in_graph[cols + n_rows] = True
    row_count = np.bincount(node_component[:n_rows][in_graph[:n_rows]], minlength=n_components)
    col_count = np.bincount(node_component[n_rows:][in_graph[n_rows:]], minlength=n_components)
    largest = int((row_count + col_count).max())

    star = (row_count == 1) | (col_count == 1)
    star_edges = star[edge_component]
    # Stars: the best pair of each component (ties: lowest row, then column).
    in_star = np.flatnonzero(star_edges)
    order = in_star[
        np.lexsort((cols[in_star], rows[in_star], -gain[in_star], edge_component[in_star]))
    ]
    first = np.ones(len(order), dtype=bool)
    first[1:] = edge_component[order][1:] != edge_component[order][:-1]
    chosen_rows = [rows[order[first]]]
    chosen_cols = [cols[order[first]]]

    general = np.flatnonzero(~star_edges)
    if len(general):
        components = edge_component[general]
        if components[0] == components[-1] and np.all(components == components[0]):
            by_component, bounds = general, np.zeros(0, dtype=np.int64)  # one cluster
        else:
            by_component = general[np.argsort(components, kind="stable")]
            bounds = np.flatnonzero(np.diff(edge_component[by_component])) + 1
        row_slot = np.zeros(n_rows, dtype=np.int64)  # local index of each row, per component
        col_slot = np.zeros(n_cols, dtype=np.int64)
        for edges in np.split(by_component, bounds):
            edge_rows, edge_cols = rows[edges], cols[edges]
            local_rows, local_cols = (
                sorted_members(edge_rows, n_rows),
                sorted_members(edge_cols, n_cols),
            )
            row_slot[local_rows] = np.arange(len(local_rows))
            col_slot[local_cols] = np.arange(len(local_cols))
            dense = np.zeros((len(local_rows), len(local_cols)))
            dense[row_slot[edge_rows], col_slot[edge_cols]] = gain[edges]
            matched_rows, matched_cols = solve_component(dense, solver)
            chosen_rows.append(local_rows[matched_rows])
            chosen_cols.append(local_cols[matched_cols])
    all_rows = np.concatenate(chosen_rows)
    all_cols = np.concatenate(chosen_cols)
    order = np.argsort(all_rows, kind="stable")
    return Matching(all_rows[order], all_cols[order], n_components, largest)
