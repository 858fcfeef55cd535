"""Hand-worked cases, one per method: expected numbers with their arithmetic."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from core.association import associate


def one_dimensional(known, incoming, variance=0.5):
    """1-D states with variance 0.5 on both sides: the ``sum`` covariance is C = 1, D = Δ²."""
    k = np.asarray(known, dtype=float)[:, None]
    i = np.asarray(incoming, dtype=float)[:, None]
    return (
        (k, np.full((len(k), 1, 1), variance)),
        (i, np.full((len(i), 1, 1), variance)),
    )


def test_gnn_gate_probability_threshold():
    # D = Δ² = [[1, 900], [81, 400]]; T = chi2.ppf(0.999, 1) = 10.8276
    # only (0, 0) is under T: matched with score D = 1; known 1 missed, incoming 1 new.
    known, incoming = one_dimensional([0.0, 10.0], [1.0, 30.0])
    result = associate(known, incoming, "gnn")
    assert result.pairs == [(0, 0, 1.0)]
    assert_array_equal(result.missed, [1])
    assert_array_equal(result.new, [1])
    assert result.diagnostics.gate == pytest.approx(10.827566170662733)
    # the ``mean`` covariance halves C, so D doubles and so does T (§3.1)
    mean = associate(known, incoming, "gnn", distance="mean")
    assert mean.pairs == [(0, 0, pytest.approx(2.0))]
    assert mean.diagnostics.gate == pytest.approx(2 * 10.827566170662733)


def test_gnn_minimises_total_distance():
    # known [0, 2], incoming [1.2, 2.5]: D = [[1.44, 6.25], [0.64, 0.25]], threshold 10
    # {(0,0),(1,1)}: 1.44 + 0.25 = 1.69 < {(0,1),(1,0)}: 6.25 + 0.64 = 6.89
    known, incoming = one_dimensional([0.0, 2.0], [1.2, 2.5])
    result = associate(known, incoming, "gnn", {"threshold": 10.0})
    assert result.assignment() == {0: 0, 1: 1}
    assert_allclose(result.pair_score, [1.44, 0.25])


def test_denoeux_weight():
    # D = 1, γ = 0.5, α = 1: pl(1) = e^{-0.5}, pl(0) = 1 − e^{-0.5} = 0.393469
    # w = −0.5 − ln 0.393469 = −0.5 + 0.932752 = 0.432752 > 0: matched
    known, incoming = one_dimensional([0.0], [1.0])
    result = associate(known, incoming, "denoeux", {"gamma": 0.5})
    assert_allclose(result.pair_score, [0.43275212956718856], rtol=1e-12)
    # gate ln 2 / γ = 1.386294: D = 1.44 gives w < 0, not matched
    far = associate(*one_dimensional([0.0], [1.2]), "denoeux", {"gamma": 0.5})
    assert far.pairs == []
    assert far.diagnostics.gate == pytest.approx(math.log(2) / 0.5)


def test_hachour_relative_betp():
    # D = 1: Pl(ℓ) = e^{-0.5} = 0.606531, Pl(*) = 0.393469 (eq 5)
    # GBT: m({ℓ}) = 0.606531², m({*}) = 0.393469², m({ℓ,*}) = m(∅) = 0.606531·0.393469 = 0.238651
    # BetP(ℓ) = (0.367879 + 0.238651/2)/(1 − 0.238651) = 0.639924, BetP(*) = 0.360076
    known, incoming = one_dimensional([0.0], [1.0])
    result = associate(known, incoming, "hachour", {"likelihood": "relative"})
    assert_allclose(result.pair_score, [0.6399235965263012], rtol=1e-12)
    assert_allclose(result.scores.new, [0.36007640347369885], rtol=1e-12)
    plausibility = associate(
        known, incoming, "hachour", {"likelihood": "relative", "maximise": "plausibility"}
    )
    assert_allclose(plausibility.pair_score, [math.exp(-0.5)])


def test_hachour_density_implicit_gate():
    # C = 1, q = 1: G = e^{-0.5}/sqrt(2π) = 0.241971 < 1/2: the item cannot be matched.
    # m({ℓ}) = 0.241971², m({*}) = 0.758029², m({ℓ,*}) = m(∅) = 0.183420
    # BetP(ℓ) = (0.058550 + 0.091710)/0.816580 = 0.184012 < BetP(*) = 0.815988
    # implicit gate: D < 2 ln 2 − ln 2π − ln|C| = 1.386294 − 1.837877 = −0.451583 (never)
    known, incoming = one_dimensional([0.0], [1.0])
    result = associate(known, incoming, "hachour")
    assert result.pairs == []
    assert_array_equal(result.new, [0])
    assert_allclose(result.scores.values, [0.18401190617381158], rtol=1e-12)
    assert_allclose(result.diagnostics.implicit_gate, [-0.45158270528945477], rtol=1e-12)
    # with C = 0.01 (variances 0.005) G = e^{-D/2}/sqrt(2π·0.01) peaks at 3.99: clipped
    tight = (np.zeros((1, 1)), np.full((1, 1, 1), 0.005))
    clipped = associate(tight, (np.full((1, 1), 0.01), np.full((1, 1, 1), 0.005)), "hachour")
    assert_array_equal(clipped.diagnostics.clipped, [1])
    assert clipped.assignment() == {0: 0}
    # Pl = 1 (clipped) and Pl(*) = 0: BetP(ℓ) = 1
    assert_allclose(clipped.pair_score, [1.0])


def test_mercier_betp():
    # the fixed scale s = e^{-D/2} (the former reading); the gate scale: the next test
    # one incoming item at D = 1 from known 0 and D = 4 from known 1, α = 0.9:
    # known 0: s = e^{-0.5}: a₁ = 0.9(2s − 1) = 0.191755, b₁ = 0, c₁ = 0.808245
    # known 1: s = e^{-2}:   a₂ = 0, b₂ = 0.9(1 − 2s) = 0.656396, c₂ = 0.343604
    # m(Y₁) = a₁(1 − a₂) = 0.191755; m({Y₁,*}) = c₁ b₂ = 0.530529; m({Y₁,Y₂,*}) = c₁ c₂ = 0.277716
    # BetP(Y₁) = 0.191755 + 0.530529/2 + 0.277716/3 = 0.549592
    # BetP(Y₂) = 0.277716/3 = 0.092572; BetP(*) = 0.265265 + 0.092572 = 0.357836
    known, incoming = one_dimensional([0.0, 3.0], [1.0])
    result = associate(known, incoming, "mercier", {"scale": "fixed"})
    assert result.pairs == [(0, 0, pytest.approx(0.5495916346781186, rel=1e-12))]
    assert_allclose(result.scores.dense()[:, 0], [0.5495916346781186, 0.0925719181265031])
    assert_allclose(result.scores.new, [0.35783644719537844], rtol=1e-12)
    assert_array_equal(result.missed, [1])


def test_pairwise_evidence_on_the_gate_scale():
    # the default scale ([T2T] eq 11 with λ = the gate): s = exp(−γ D), γ = ln 2 / T,
    # T = chi2.ppf(0.999, 1) = 10.827566 (1-D, ``sum``: D = Δ²).
    # one known item at D = T/2: s = 2^(−1/2) = 0.707107;
    # fuzzy, α = 0.9: a = 0.9 (2s − 1) = 0.9 (√2 − 1) = 0.372792, b = 0, c = 0.627208
    # Mercier: m(Y) = a, m({Y, *}) = c → BetP(Y) = a + c/2 = 0.686396, BetP(*) = c/2 = 0.313604
    # Dang–Han: Bel(Y) = m(Y) / (1 − m(∅)) = a (one source: no conflict)
    gate = 10.827566170662733
    known, incoming = one_dimensional([0.0], [math.sqrt(gate / 2)])
    a = 0.9 * (math.sqrt(2.0) - 1.0)
    result = associate(known, incoming, "mercier")
    assert result.pairs == [(0, 0, pytest.approx(a + (1 - a) / 2, rel=1e-12))]
    assert result.scores.new[0] == pytest.approx((1 - a) / 2, rel=1e-12)
    dang_han = associate(known, incoming, "dang_han")
    assert dang_han.pairs == [(0, 0, pytest.approx(a, rel=1e-12))]
    # the fixed scale s = e^{−D/2} = e^{−T/4} = 0.0667 refutes the same pair:
    # a = 0, b = 0.9 (1 − 2s) = 0.779916 → BetP(*) = b + c/2 > BetP(Y) = c/2, declared new
    for method in ("mercier", "dang_han"):
        fixed = associate(known, incoming, method, {"scale": "fixed"})
        assert fixed.pairs == [] and list(fixed.new) == [0]
    # and a pair just outside the gate (D = 1.0001 T) leaves the frame under either scale
    outside = one_dimensional([0.0], [math.sqrt(1.0001 * gate)])
    assert associate(*outside, "mercier").pairs == []


def test_dang_han_mutual_check():
    # positions: known k0 = 0, k1 = −0.5; incoming t0 = 0.5, t1 = −0.3 (D = Δ²)
    # t0: D(k0) = 0.25, D(k1) = 1.00 → chooses k0     k0: D(t0) = 0.25, D(t1) = 0.09 → t1
    # t1: D(k0) = 0.09, D(k1) = 0.04 → chooses k1     k1: D(t1) = 0.04, D(t0) = 1.00 → t1
    # (m(Y_j) = a_j Π_{k≠j}(1 − a_k) ∝ a_j/(1 − a_j): the largest a, i.e. the smallest D)
    # mutual: only (k1, t1). t0 chose k0 but k0 chose t1: ignored → t0 new, k0 missed.
    known, incoming = one_dimensional([0.0, -0.5], [0.5, -0.3])
    result = associate(known, incoming, "dang_han", {"scale": "fixed"})
    assert result.assignment() == {1: 1}
    assert_array_equal(result.new, [0])
    assert_array_equal(result.missed, [0])
    # belief of t0 in k0: a(0.25) = 0.688494, a(1) = 0.191755
    # m(Y_k0) = 0.688494·0.808245 = 0.556472, m(Y_k1) = 0.191755·0.311506 = 0.059733, m(*) = 0
    # 1 − m(∅) = 0.556472 + 0.059733 + 0.311506·0.808245 = 0.867978 → Bel = 0.641113
    assert result.scores.dense()[0, 0] == pytest.approx(0.6411133567668019, rel=1e-12)
