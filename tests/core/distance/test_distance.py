"""Distances against numpy.linalg, the KD-tree gate, the modified distance, the steady state."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose
from scipy.linalg import solve_discrete_are

from core.distance import (
    DistanceModel,
    Estimates,
    ModifiedScale,
    distance_matrix,
    gated_pairs,
    modified_distance,
    scale_factor,
    steady_state_covariance,
    threshold_from_probability,
)
from core.distance.cholesky import quadratic_form_and_log_det


def random_side(rng, n, q, scale=1.0):
    a = rng.normal(size=(n, q, q))
    return rng.normal(0, 5, size=(n, q)), scale * (a @ a.transpose(0, 2, 1) + 0.2 * np.eye(q))


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    q=st.integers(1, 6),
    kind=st.sampled_from(["mean", "sum", "innovation"]),
)
def test_distances_match_numpy(seed, q, kind):
    rng = np.random.default_rng(seed)
    kx, kp = random_side(rng, 5, q)
    ix, ip = random_side(rng, 4, q)
    w1, w2 = {"mean": (0.5, 0.5), "sum": (1.0, 1.0), "innovation": (1.0, 0.0)}[kind]
    known = Estimates.of(kx, kp)
    incoming = Estimates.of(ix, None if kind == "innovation" else ip)
    pairs = gated_pairs(known, incoming, math.inf, kind)
    for r, c, d, log_det in zip(pairs.rows, pairs.cols, pairs.distance, pairs.log_det, strict=True):
        covariance = w1 * kp[r] + w2 * ip[c]
        delta = kx[r] - ix[c]
        assert d == pytest.approx(delta @ np.linalg.solve(covariance, delta), rel=1e-9)
        assert log_det == pytest.approx(np.linalg.slogdet(covariance)[1], abs=1e-9)
    assert len(pairs) == 20


def test_lapack_path_for_large_dimension():
    rng = np.random.default_rng(3)
    q = 10
    x, p = random_side(rng, 50, q)
    d, log_det = quadratic_form_and_log_det(x.T.copy(), np.moveaxis(p, 0, -1).copy())
    expected = np.einsum("ni,ni->n", x, np.linalg.solve(p, x[:, :, None])[:, :, 0])
    assert_allclose(d, expected, rtol=1e-9)
    assert_allclose(log_det, np.linalg.slogdet(p)[1], atol=1e-9)


@pytest.mark.parametrize("positions", [None, (0, 2)])
def test_kd_tree_gate_keeps_exactly_the_pairs_under_the_gate(positions):
    # 300 × 300 = 90 000 pairs > ALL_PAIRS_LIMIT: the KD-tree path is used
    rng = np.random.default_rng(7)
    n, q = 300, 4
    kx = rng.uniform(0, 200, size=(n, q))
    ix = kx + rng.normal(0, 3, size=(n, q))
    scales = rng.uniform(0.5, 20, size=(n, 1, 1))
    kp = scales * np.eye(q)
    ip = rng.uniform(0.5, 5, size=(n, 1, 1)) * np.eye(q)
    known, incoming = Estimates.of(kx, kp), Estimates.of(ix, ip)
    model = DistanceModel(covariance="sum", positions=positions)
    gate = threshold_from_probability(0.999, q, model)
    pairs = gated_pairs(known, incoming, gate, model)
    full = distance_matrix(known, incoming, "sum")
    expected = np.argwhere(full <= gate)
    assert_allclose(np.column_stack([pairs.rows, pairs.cols]), expected)
    assert_allclose(pairs.distance, full[full <= gate], rtol=1e-12)
    assert len(pairs) < n * n / 10  # far pairs were not listed


def test_threshold_doubles_for_mean():
    # chi2.ppf(0.999, 4) = 18.4668; mean halves C so the threshold doubles (§3.1)
    assert threshold_from_probability(0.999, 4, DistanceModel("sum")) == pytest.approx(
        18.4668269529
    )
    assert threshold_from_probability(0.999, 4, DistanceModel("mean")) == pytest.approx(
        2 * 18.4668269529
    )


def test_scale_factor_solves_its_equation():
    u = np.array([0.1, 0.5, 1.0, 2.0, 10.0, 1e3, 1e8])
    for beta, k, alpha in ((10.0, 1.0, 4.0), (3.0, 2.0, 1.5)):
        v = scale_factor(u, beta=beta, k=k, alpha=alpha)
        assert_allclose(k * (v / beta) ** alpha + v, u, rtol=1e-12)
        assert np.all(v <= u) and np.all(np.diff(v) > 0)


def test_modified_distance_properties():
    d = np.array([0.5, 3.0, 12.0])
    # u = 1: v solves 1 = (v/10)^4 + v, v = 0.99990, so D_mod ≈ D (within 1e-4)
    assert_allclose(modified_distance(d, np.ones(3)), d, rtol=2e-4)
    # monotone in u, always ≥ D
    ratios = np.array([1.0, 2.0, 10.0, 100.0])
    values = modified_distance(np.full(4, 2.0), ratios)
    assert np.all(np.diff(values) > 0) and np.all(values >= 2.0)
    # large u: v → β (u/k)^{1/α}: D_mod/D = u / v → u^{3/4} / 10
    u = 1e8
    assert modified_distance(np.ones(1), np.array([u]))[0] == pytest.approx(
        u / (10 * u**0.25), rel=1e-3
    )


def test_modified_distance_penalises_a_large_covariance_track():
    # [HZ] Fig 1: a lost track (P = 100 I) and a well-localised one (P = P_ss = I) compete for
    # one measurement; plain Mahalanobis prefers the lost track, the modified distance does not.
    measurement = Estimates.of(np.array([[3.0, 0.0]]), None)
    tracks = Estimates.of(
        np.array([[0.0, 0.0], [-15.0, 0.0]]), np.array([np.eye(2), 100 * np.eye(2)])
    )
    plain = distance_matrix(tracks, measurement, "innovation")[:, 0]
    assert plain[1] < plain[0]  # 18²/100 = 3.24 < 3² = 9
    model = DistanceModel("innovation", modified=ModifiedScale.of(np.eye(2)))
    modified = distance_matrix(tracks, measurement, model)[:, 0]
    # track 0: u = 1 → ×1.0001; track 1: u = 100, v solves 100 = (v/10)^4 + v → v = 29.025,
    # D_mod = 3.24 · 100 / 29.025 = 11.163 > 9.0001
    assert modified[0] == pytest.approx(9.0, rel=2e-4)
    assert modified[1] == pytest.approx(3.24 * 100 / 29.02524993, rel=1e-8)
    assert modified[0] < modified[1]


def test_steady_state_matches_the_algebraic_riccati_solution():
    dt = 1.0
    f = np.array([[1, dt, 0, 0], [0, 1, 0, 0], [0, 0, 1, dt], [0, 0, 0, 1]], dtype=float)
    b = np.array([[dt**2 / 2, 0], [dt, 0], [0, dt**2 / 2], [0, dt]])
    q = 0.5 * b @ b.T
    h = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    r = 4.0 * np.eye(2)
    state = steady_state_covariance(f, q + 1e-9 * np.eye(4), h, r)
    expected = solve_discrete_are(f.T, h.T, q + 1e-9 * np.eye(4), r)
    assert_allclose(state.predicted, expected, rtol=1e-7, atol=1e-12)
    assert_allclose(state.innovation, h @ expected @ h.T + r, rtol=1e-7, atol=1e-12)
