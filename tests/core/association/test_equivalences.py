"""denoeux ↔ gnn threshold equivalence ([T2T] eq 11) and clustered ↔ unclustered solves."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from core.association import associate
from core.distance import Estimates, distance_matrix


def decided(result):
    return {(int(k), int(i)) for k, i in zip(result.pair_known, result.pair_incoming, strict=True)}


def uncontested(seed: int, threshold: float):
    """Random 2-D instance where the pairs with D < λ form a matching (no competition)."""
    rng = np.random.default_rng(seed)
    n, m = rng.integers(1, 8, size=2)
    known = Estimates.of(rng.uniform(0, 30, size=(n, 2)), np.tile(np.eye(2), (n, 1, 1)))
    incoming = Estimates.of(
        np.concatenate(
            [
                known.states[: min(n, m)] + rng.normal(0, 2.0, size=(min(n, m), 2)),
                rng.uniform(0, 30, size=(m - min(n, m), 2)),
            ]
        ),
        np.tile(0.5 * np.eye(2), (m, 1, 1)),
    )
    d = distance_matrix(known, incoming)
    inside = d < threshold
    contested = (inside.sum(axis=0) > 1).any() or (inside.sum(axis=1) > 1).any()
    return known, incoming, d, contested


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), threshold=st.sampled_from([2.0, 6.0, 12.0]))
def test_denoeux_decides_like_gnn_when_uncontested(seed, threshold):
    known, incoming, d, contested = uncontested(seed, threshold)
    if contested:
        return
    gnn = associate(known, incoming, "gnn", {"threshold": threshold})
    denoeux = associate(
        known, incoming, "denoeux", {"gamma": math.log(2) / threshold, "alpha": 1.0}
    )
    assert decided(gnn) == decided(denoeux)
    # both equal the pairs under the threshold
    assert decided(gnn) == {
        (int(i), int(j)) for i, j in zip(*np.nonzero(d < threshold), strict=True)
    }


def test_contested_case_gnn_and_denoeux_differ():
    # 1-D, variances 0.5 on both sides: C = 1 and D = Δ². λ = 10, γ = ln 2 / 10.
    # k0 = 0, k1 = 0.1 + √5; t0 = 0.1, t1 = −√5:
    #   D(k0,t0) = 0.01, D(k0,t1) = 5, D(k1,t0) = 5, D(k1,t1) = 20.9 > λ.
    # GNN maximises Σ (λ − D): {(k0,t0)}: 9.99  <  {(k0,t1),(k1,t0)}: 5 + 5 = 10   → the cross pairs.
    # denoeux maximises Σ w, w(D) = −γD − ln(1 − e^{−γD}):
    #   w(0.01) = 7.273922  >  2 w(5) = 2 · 0.881374 = 1.762747             → (k0, t0) alone.
    root5 = math.sqrt(5.0)
    known = (np.array([[0.0], [0.1 + root5]]), np.full((2, 1, 1), 0.5))
    incoming = (np.array([[0.1], [-root5]]), np.full((2, 1, 1), 0.5))
    gnn = associate(known, incoming, "gnn", {"threshold": 10.0})
    denoeux = associate(known, incoming, "denoeux", {"gamma": math.log(2) / 10.0})
    assert gnn.assignment() == {0: 1, 1: 0}
    np.testing.assert_allclose(gnn.pair_score, [5.0, 5.0])
    assert denoeux.assignment() == {0: 0}
    np.testing.assert_allclose(denoeux.pair_score, [7.273921605954646], rtol=1e-9)
    dense = denoeux.scores.dense()
    assert dense[0, 1] == pytest.approx(0.8813735870195429, rel=1e-9)


def clustered_instance(seed: int, scale: float = 1.0):
    """Several well-separated clusters of a few mutually-gated items each."""
    rng = np.random.default_rng(seed)
    centres = rng.uniform(0, 1000, size=(rng.integers(3, 7), 2))
    known_states, incoming_states = [], []
    for centre in centres:
        spread = np.sqrt(scale)
        known_states.append(centre + rng.normal(0, spread, size=(rng.integers(1, 5), 2)))
        incoming_states.append(centre + rng.normal(0, spread, size=(rng.integers(1, 5), 2)))
    ks, ins = np.concatenate(known_states), np.concatenate(incoming_states)
    ks, ins = ks[rng.permutation(len(ks))], ins[rng.permutation(len(ins))]

    def covariances(count):
        a = rng.normal(size=(count, 2, 2)) * 0.5
        return scale * (a @ a.transpose(0, 2, 1) + 0.5 * np.eye(2))

    return (ks, covariances(len(ks))), (ins, covariances(len(ins)))


@pytest.mark.parametrize(
    ("method", "options", "scale"),
    [
        ("gnn", {}, 1.0),
        ("denoeux", {}, 1.0),
        ("hachour", {"likelihood": "relative"}, 1.0),
        ("hachour", {}, 0.12),  # small covariances: densities above 1/2
        ("mercier", {}, 1.0),
    ],
)
def test_clustered_equals_unclustered(method, options, scale):
    clusters_seen = matched = 0
    for seed in range(25):
        known, incoming = clustered_instance(seed, scale)
        clustered = associate(known, incoming, method, options)
        whole = associate(known, incoming, method, options, solver="scipy", cluster=False)
        if clustered.diagnostics.clipped.any():
            continue  # clipped plausibilities tie exactly; either optimum is right
        assert decided(clustered) == decided(whole), seed
        np.testing.assert_array_equal(clustered.new, whole.new)
        np.testing.assert_array_equal(clustered.missed, whole.missed)
        clusters_seen = max(clusters_seen, clustered.diagnostics.clusters)
        matched += len(clustered.pair_known)
    assert clusters_seen >= 3  # the instances really have several clusters
    assert matched >= 25
