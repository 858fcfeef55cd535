"""Mercier's BetP (and Dang–Han's beliefs) at any frame size (docs/algorithms.md §1.1, §3.4).

The normaliser 1 − m(∅) = Σ_j a_j Π_{k≠j}(1 − a_k) + Π_k (b_k + c_k) has one
factor per candidate: on a dense 1000 × 1000 problem it is ≈ 0.3^1000 and
underflowed to 0, which declared every item new. Two independent references:

- small frames: the straightforward linear-domain formula, the polynomials
  Π (b_k + c_k t) multiplied out and integrated exactly (numpy.polynomial);
- the dense 1000 × 1000 frame: the same formula written in log space
  (log-sum-exp over the Gauss–Legendre nodes of the exact order).
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.polynomial import Polynomial
from scipy.optimize import linear_sum_assignment
from scipy.special import logsumexp
from scipy.stats import chi2

from core.association import associate

GATE_GAMMA = np.log(2.0) / chi2.ppf(0.999, 2)
"""The default scale: s = exp(−γ D), γ = ln 2 / the 0.999 gate of a 2-D ``sum`` distance."""


def evidence(
    distance: np.ndarray, alpha: float, kind: str, gamma: float = GATE_GAMMA
) -> tuple[np.ndarray, ...]:
    """(a, b, c) of §3.4 with s = exp(−γ D): fuzzy (a = α(2s−1)⁺, b = α(1−2s)⁺) or likelihood (a = α s)."""
    s = np.exp(-gamma * distance)
    if kind == "fuzzy":
        a, b = alpha * np.maximum(0.0, 2 * s - 1), alpha * np.maximum(0.0, 1 - 2 * s)
    else:
        a, b = alpha * s, alpha * (1 - s)
    return a, b, 1.0 - a - b


def straightforward_betp(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, float]:
    """BetP(Y_j) and BetP(*) of one item, every product formed as it is written."""
    g = [Polynomial([bk, ck]) for bk, ck in zip(b, c, strict=True)]
    t = Polynomial([0.0, 1.0])
    full = np.prod(g) if g else Polynomial([1.0])
    singles = np.array([a[j] * np.prod(np.delete(1.0 - a, j)) for j in range(len(a))])
    normaliser = singles.sum() + np.prod(b + c)
    shared = np.array(
        [
            c[j] * (t * np.prod([g[k] for k in range(len(g)) if k != j])).integ()(1.0)
            for j in range(len(g))
        ]
    )
    star = full.integ()(1.0)
    return (singles + shared) / normaliser, star / normaliser


def positions(rng: np.random.Generator, n: int, box: float) -> tuple[np.ndarray, np.ndarray]:
    variances = rng.uniform(0.5, 1.5, (n, 2))
    return rng.uniform(0.0, box, (n, 2)), variances[:, :, None] * np.eye(2)


def sum_distances(known, incoming) -> np.ndarray:
    """D[ℓ, t] = Δᵀ (P_ℓ + P_t)⁻¹ Δ by numpy.linalg."""
    (kx, kp), (ix, ip) = known, incoming
    delta = kx[:, None, :] - ix[None, :, :]
    inverse = np.linalg.inv(kp[:, None] + ip[None, :])
    return np.einsum("lti,ltij,ltj->lt", delta, inverse, delta)


@pytest.mark.parametrize(("n", "box"), [(6, 1.0), (25, 0.5), (40, 3.0)])
@pytest.mark.parametrize(
    "options",
    [
        {},
        {"scale": "fixed"},
        {"evidence": "likelihood", "gate_probability": 1.0, "alpha": 0.7, "scale": "fixed"},
    ],
)
def test_small_frames_equal_the_straightforward_formula(n, box, options) -> None:
    rng = np.random.default_rng(n)
    known, incoming = positions(rng, n, box), positions(rng, n + 2, box)
    result = associate(known, incoming, "mercier", options)
    d = sum_distances(known, incoming)
    probability = options.get("gate_probability", 0.999)
    gate = np.inf if probability >= 1.0 else chi2.ppf(probability, 2)
    gamma = 0.5 if options.get("scale") == "fixed" else np.log(2.0) / gate
    a, b, c = evidence(d, options.get("alpha", 0.9), options.get("evidence", "fuzzy"), gamma)
    values = np.zeros(d.shape)
    star = np.ones(d.shape[1])
    for t in range(d.shape[1]):
        inside = np.flatnonzero(d[:, t] <= gate)
        values[inside, t], star[t] = straightforward_betp(a[inside, t], b[inside, t], c[inside, t])
    np.testing.assert_allclose(result.scores.dense(), values, rtol=1e-12, atol=1e-300)
    np.testing.assert_allclose(result.scores.new, star, rtol=1e-12, atol=1e-300)
    # [T2T] Table 1 maximisation on the reference scores: pairs of positive gain only
    gain = np.where(d <= gate, values - star[None, :], 0.0)
    rows, cols = linear_sum_assignment(np.maximum(gain, 0.0), maximize=True)
    expected = {int(r): int(k) for r, k in zip(rows, cols, strict=True) if gain[r, k] > 0.0}
    assert expected and result.assignment() == expected


def log_space_betp(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """BetP(Y_1..Y_n, *) of one item, every product a sum of logarithms (c > 0, b + c > 0)."""
    n = len(a)
    nodes, weights = np.polynomial.legendre.leggauss(n // 2 + 1)  # exact for degree n
    nodes, weights = (nodes + 1) / 2, weights / 2
    log_g = np.log(b[None, :] + c[None, :] * nodes[:, None])  # (L, n)
    log_others = log_g.sum(axis=1)[:, None] - log_g  # log Π_{k≠j} g_k(t_l)
    log_w = np.log(b + c)
    log_singles = np.log(a) + log_w.sum() - log_w  # log a_j Π_{k≠j}(1 − a_k)
    log_shared = np.log(c) + logsumexp(np.log(weights * nodes)[:, None] + log_others, axis=0)
    log_star = logsumexp(np.log(weights) + log_g.sum(axis=1))
    log_normaliser = logsumexp(np.append(log_singles, log_w.sum()))
    log_numerators = np.append(np.logaddexp(log_singles, log_shared), log_star)
    return np.exp(log_numerators - log_normaliser)


@pytest.fixture(scope="module")
def dense_layout() -> tuple[
    tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray], np.ndarray
]:
    n = 1000
    rng = np.random.default_rng(7)
    known = positions(rng, n, 0.7)
    order = rng.permutation(n)
    return known, (known[0][order], known[1][order]), order


def test_dense_thousand_by_thousand_pairs_every_item_with_its_own(dense_layout) -> None:
    """1000 items in a box 0.7 wide (unit variances): every pair supports "same" (D < 1),
    Π(1 − a_k) ≈ 1e-600; incoming = known exactly, shuffled, so item t's partner is known
    ``order[t]`` and its a = α is the row's largest."""
    known, incoming, order = dense_layout
    n = len(order)
    result = associate(known, incoming, "mercier")
    assert len(result.diagnostics.undefined) == 0
    assert result.diagnostics.candidate_pairs == n * n
    assert result.assignment() == {int(order[t]): t for t in range(n)}
    d = sum_distances(known, (incoming[0][:5], incoming[1][:5]))
    a, b, c = evidence(d, 0.9, "fuzzy")
    assert np.log(1.0 - a).sum(axis=0).max() < -600.0  # the product the old code formed
    matrix = result.scores.dense()
    for t in range(5):
        reference = log_space_betp(a[:, t], b[:, t], c[:, t])
        np.testing.assert_allclose(matrix[:, t], reference[:-1], rtol=1e-10)
        assert result.scores.new[t] == pytest.approx(reference[-1], rel=1e-10)
        assert int(np.argmax(matrix[:, t])) == order[t]


def test_dense_dang_han_beliefs_in_log_space(dense_layout) -> None:
    """[DH] eq 19 singleton beliefs m(Y_j) / (1 − m(∅)) had the same underflow."""
    known, incoming, order = dense_layout
    result = associate(known, incoming, "dang_han")
    assert len(result.diagnostics.undefined) == 0
    assert result.assignment() == {int(order[t]): t for t in range(len(order))}
    d = sum_distances(known, (incoming[0][:5], incoming[1][:5]))
    a, b, c = evidence(d, 0.9, "fuzzy")
    with np.errstate(divide="ignore"):
        log_keep = np.log(1.0 - a)
        log_singles = np.log(a) + log_keep.sum(axis=0) - log_keep
        log_star = np.log(b).sum(axis=0)
    log_normaliser = logsumexp(np.vstack([log_singles, np.log(b + c).sum(axis=0)]), axis=0)
    matrix = result.scores.dense()
    np.testing.assert_allclose(matrix[:, :5], np.exp(log_singles - log_normaliser), rtol=1e-10)
    np.testing.assert_allclose(result.scores.new[:5], np.exp(log_star - log_normaliser))
