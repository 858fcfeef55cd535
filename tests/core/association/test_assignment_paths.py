"""The paths of ``max_gain_matching`` (few pairs in plain Python, the vectorised
clusters, one dense solve) against each other and against enumeration: the same
components and, with ties (integer gains), the same documented choice."""

from __future__ import annotations

import numpy as np
import pytest

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
