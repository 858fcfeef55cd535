"""The paths of ``max_gain_matching`` (few pairs in plain Python, the vectorised
clusters, one dense solve) against each other and against enumeration: the same
components and, with ties (integer gains), the same documented choice."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

import core.association.assignment as assignment
from core.association.assignment import max_gain_matching

from .brute_force import partial_matchings


def random_graph(
    rng: np.random.Generator, n_rows: int, n_cols: int, density: float, integer: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    present = rng.random((n_rows, n_cols)) < density
    rows, cols = np.nonzero(present)
    if integer:  # many exact ties, and gains ≤ 0 that must be dropped
        gain = rng.integers(-1, 4, size=len(rows)).astype(float)
    else:
        gain = rng.normal(1.0, 1.0, size=len(rows))
    return rows.astype(np.int64), cols.astype(np.int64), gain


def best_value(rows: np.ndarray, cols: np.ndarray, gain: np.ndarray, n: int, m: int) -> float:
    table = {(int(r), int(c)): float(g) for r, c, g in zip(rows, cols, gain, strict=True)}
    return max(
        sum(max(table.get(pair, 0.0), 0.0) for pair in matching)
        for matching in partial_matchings(n, m)
    )


@pytest.mark.parametrize("integer", [False, True])
def test_small_path_equals_vectorised_path(integer: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(5 + integer)
    for _ in range(150):
        n, m = int(rng.integers(1, 9)), int(rng.integers(1, 9))
        rows, cols, gain = random_graph(rng, n, m, float(rng.uniform(0.1, 0.6)), integer)
        small = max_gain_matching(rows, cols, gain, n, m)
        with monkeypatch.context() as patch:
            patch.setattr(assignment, "SMALL_PAIRS", -1)
            vectorised = max_gain_matching(rows, cols, gain, n, m)
        np.testing.assert_array_equal(small.rows, vectorised.rows)
        np.testing.assert_array_equal(small.cols, vectorised.cols)
        assert (small.clusters, small.largest_cluster) == (
            vectorised.clusters,
            vectorised.largest_cluster,
        )
        if n <= 5 and m <= 5:
            chosen = {(int(r), int(c)) for r, c in zip(small.rows, small.cols, strict=True)}
            table = {(int(r), int(c)): g for r, c, g in zip(rows, cols, gain, strict=True)}
            value = sum(table[pair] for pair in chosen)
            assert value == pytest.approx(best_value(rows, cols, gain, n, m), abs=1e-12)


def test_star_ties_pick_the_lowest_row_then_column() -> None:
    # one column with three equal candidates; one row with two equal candidates
    rows = np.array([0, 1, 2, 3, 3], dtype=np.int64)
    cols = np.array([0, 0, 0, 2, 1], dtype=np.int64)
    gain = np.array([2.0, 2.0, 2.0, 1.0, 1.0])
    matching = max_gain_matching(rows, cols, gain, 4, 3)
    assert list(zip(matching.rows.tolist(), matching.cols.tolist(), strict=True)) == [
        (0, 0),
        (3, 1),
    ]
    assert (matching.clusters, matching.largest_cluster) == (2, 4)


def geometric_gain(rng: np.random.Generator, n: int, m: int) -> np.ndarray:
    """Every pair positive, nearly tied: positions in one small box (the dense layout)."""
    known = rng.uniform(0.0, 1.0, (n, 2))
    incoming = rng.uniform(0.0, 1.0, (m, 2))
    squared = ((known[:, None, :] - incoming[None, :, :]) ** 2).sum(axis=2)
    return 10.0 - squared


@pytest.mark.parametrize(("n", "m"), [(60, 60), (40, 90), (90, 40), (150, 150)])
@pytest.mark.parametrize("kind", ["geometric", "uniform"])
def test_certified_sparse_solve_equals_the_dense_solvers(n: int, m: int, kind: str) -> None:
    rng = np.random.default_rng(n * m + len(kind))
    gain = geometric_gain(rng, n, m) if kind == "geometric" else rng.uniform(0.1, 1.0, (n, m))
    found = assignment.solve_complete(gain)
    assert found is not None  # certified, not handed back to the dense solver
    rows, cols = found
    reference_rows, reference_cols = linear_sum_assignment(gain, maximize=True)
    np.testing.assert_array_equal(rows, reference_rows)
    np.testing.assert_array_equal(cols, reference_cols)


def test_large_complete_components_take_the_certified_path(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    rng = np.random.default_rng(3)
    gain = geometric_gain(rng, 70, 50)
    calls: list[tuple[int, int]] = []
    certified = assignment.solve_complete

    def spy(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        calls.append(matrix.shape)
        return certified(matrix)

    monkeypatch.setattr(assignment, "SPARSE_MIN_SIDE", 40)
    monkeypatch.setattr(assignment, "solve_complete", spy)
    rows, cols = np.nonzero(np.ones_like(gain, dtype=bool))
    matching = max_gain_matching(rows, cols, gain[rows, cols], 70, 50)
    assert calls == [(70, 50)]
    reference_rows, reference_cols = linear_sum_assignment(gain, maximize=True)
    np.testing.assert_array_equal(matching.rows, reference_rows)
    np.testing.assert_array_equal(matching.cols, reference_cols)


def test_sparse_assignment_refuses_a_graph_without_a_perfect_matching() -> None:
    # rows 0 and 1 can only take column 0: lapmod answers with a pair that is no candidate
    candidates = np.zeros((3, 3), dtype=bool)
    candidates[[0, 1, 2, 2], [0, 0, 1, 2]] = True
    rows, cols = np.nonzero(candidates)
    costs = np.array([1.0, 2.0, 1.0, 3.0])
    assert assignment._sparse_assignment(rows, cols, costs, 3, 3, candidates) is None
    candidates[1, 2] = True  # now 0-0, 1-2, 2-1 is the only perfect matching
    rows, cols = np.nonzero(candidates)
    costs = np.ones(len(rows))
    found = assignment._sparse_assignment(rows, cols, costs, 3, 3, candidates)
    assert found is not None
    np.testing.assert_array_equal(found, [0, 2, 1])
