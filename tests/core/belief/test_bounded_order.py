"""The fast BetP paths (bounded node count, leave-one-out by division) against the
straightforward ones (exact order, prefix/suffix products) of ``slow_betp``: the
same BetP to 1e-12, and the same association decisions, on random small and
medium problems, dense and sparse."""

from __future__ import annotations

import numpy as np
import pytest

import core.association.hachour as hachour_module
import core.association.pairwise_evidence as pairwise_module
from core.association import associate
from core.belief import gbt_betp_rows, pairwise_evidence_betp_rows

from .slow_betp import slow_gbt_betp_rows, slow_pairwise_evidence_betp_rows

SPECIAL = np.array([0.0, 1.0, 1e-12, 1.0 - 1e-12, 0.5])


def plausibility_rows(rng: np.random.Generator, width: int) -> np.ndarray:
    """Rows of every kind met in association: near 1, tiny, uniform, mixed with 0 and 1."""
    return np.clip(
        np.vstack(
            [
                rng.uniform(0.9, 1.0, width),
                rng.uniform(0.0, 0.04, width),
                rng.uniform(0.0, 1.0, width),
                np.where(rng.random(width) < 0.3, rng.choice(SPECIAL, width), rng.random(width)),
                np.full(width, 0.97) + rng.normal(0.0, 1e-3, width),
                np.where(rng.random(width) < 0.5, 1.0, rng.uniform(0.99, 1.0, width)),
            ]
        ),
        0.0,
        1.0,
    )


@pytest.mark.parametrize("width", [1, 2, 5, 14, 40, 150, 400, 1000])
def test_gbt_rows_match_the_exact_order(width: int) -> None:
    rng = np.random.default_rng(width)
    rows = plausibility_rows(rng, width)
    fast, fast_defined = gbt_betp_rows(rows)
    slow, slow_defined = slow_gbt_betp_rows(rows)
    np.testing.assert_array_equal(fast_defined, slow_defined)
    np.testing.assert_allclose(fast, slow, rtol=0.0, atol=1e-12)


def evidence_rows(rng: np.random.Generator, width: int) -> tuple[np.ndarray, ...]:
    """(a, b, c) rows: fuzzy-like (b = 0 or a = 0), likelihood-like, with a = 1 and b = 1 cases."""
    alpha = rng.uniform(0.5, 1.0, (5, 1))
    s = rng.uniform(0.0, 1.0, (5, width))
    s[1] = rng.uniform(0.9, 1.0, width)
    s[2] = rng.uniform(0.0, 0.45, width)
    a = alpha * np.maximum(0.0, 2 * s - 1)
    b = alpha * np.maximum(0.0, 1 - 2 * s)
    a[3], b[3] = alpha[3] * s[3], alpha[3] * (1 - s[3])  # likelihood evidence
    a[4, 0], b[4, 0] = 1.0, 0.0  # a certain support: no bound, the exact order
    a[4, -1], b[4, -1] = 0.0, 1.0
    c = np.clip(1.0 - a - b, 0.0, 1.0)
    return a, b, c


@pytest.mark.parametrize("width", [1, 3, 9, 30, 120, 300])
def test_pairwise_rows_match_the_exact_order(width: int) -> None:
    rng = np.random.default_rng(100 + width)
    a, b, c = evidence_rows(rng, width)
    fast, fast_defined = pairwise_evidence_betp_rows(a, b, c)
    slow, slow_defined = slow_pairwise_evidence_betp_rows(a, b, c)
    np.testing.assert_array_equal(fast_defined, slow_defined)
    np.testing.assert_allclose(fast, slow, rtol=0.0, atol=1e-12)


def sides(
    rng: np.random.Generator, n: int, box: float, scale: float
) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    def side(count: int) -> tuple[np.ndarray, np.ndarray]:
        variances = rng.uniform(0.5, 1.5, (count, 2)) * scale
        return rng.uniform(0.0, box, (count, 2)), variances[:, :, None] * np.eye(2)

    return side(n), side(n + int(rng.integers(-3, 4)))


@pytest.mark.parametrize(
    ("method", "options"),
    [
        ("hachour", {}),
        ("hachour", {"likelihood": "relative"}),
        ("hachour", {"likelihood": "relative", "plausibility_floor": 0.0}),
        ("mercier", {}),
        ("mercier", {"evidence": "likelihood", "gate_probability": 1.0, "scale": "fixed"}),
        ("dang_han", {"score": "betp"}),
    ],
)
@pytest.mark.parametrize(
    ("n", "box", "scale"), [(8, 1.0, 1.0), (60, 0.3, 1.0), (60, 2.0, 0.05), (150, 40.0, 1.0)]
)
def test_decisions_match_the_exact_order(monkeypatch, method, options, n, box, scale) -> None:
    rng = np.random.default_rng(n)
    known, incoming = sides(rng, n, box, scale)
    fast = associate(known, incoming, method, options)
    monkeypatch.setattr(hachour_module, "gbt_betp_rows", slow_gbt_betp_rows)
    monkeypatch.setattr(
        pairwise_module, "pairwise_evidence_betp_rows", slow_pairwise_evidence_betp_rows
    )
    slow = associate(known, incoming, method, options)
    # not all "new" (hachour's density gate needs |C| small: G > 1/2)
    assert fast.pairs or (method, options, scale) == ("hachour", {}, 1.0)
    np.testing.assert_allclose(fast.scores.dense(), slow.scores.dense(), rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(fast.scores.new, slow.scores.new, rtol=0.0, atol=1e-12)
    if not slow.diagnostics.clipped.any():
        assert fast.assignment() == slow.assignment()
    else:  # plausibilities clipped at 1 make exact ties: the fast matching is optimal on slow's scores
        assert table_value(slow, fast) == pytest.approx(table_value(slow, slow), abs=1e-12)


def table_value(scored, decided) -> float:
    """Σ of ``scored``'s Table 1 cells chosen by ``decided``'s matching ([T2T] eq 7)."""
    matrix = scored.scores.dense()
    total = matrix[decided.pair_known, decided.pair_incoming].sum()
    return float(total + scored.scores.new[decided.new].sum())
