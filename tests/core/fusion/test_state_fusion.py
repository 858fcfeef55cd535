"""State fusion rules against brute force and textbook formulas."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.optimize import minimize_scalar

from core.arrays import FloatArray
from core.errors import InvalidInput
from core.fusion.state import StateFusion, fuse_estimates, optimal_ci_weight


def random_spd(rng: np.random.Generator, dim: int, scale: float = 1.0) -> FloatArray:
    root = rng.normal(size=(dim, dim)) * scale
    return root @ root.T + 0.05 * scale**2 * np.eye(dim)


def ci_trace(omega: float, first: FloatArray, second: FloatArray) -> float:
    """tr (ω P₁⁻¹ + (1 − ω) P₂⁻¹)⁻¹, written directly."""
    return float(
        np.trace(np.linalg.inv(omega * np.linalg.inv(first) + (1 - omega) * np.linalg.inv(second)))
    )


def brute_force_weight(first: FloatArray, second: FloatArray) -> tuple[float, float]:
    """Scan ω on a grid of 2001 points, then refine with scipy's bounded Brent search."""
    grid = np.linspace(0.0, 1.0, 2001)
    traces = np.array([ci_trace(w, first, second) for w in grid])
    best = int(np.argmin(traces))
    low, high = grid[max(best - 1, 0)], grid[min(best + 1, len(grid) - 1)]
    refined = minimize_scalar(
        ci_trace,
        bounds=(low, high),
        args=(first, second),
        method="bounded",
        options={"xatol": 1e-12},
    )
    if refined.fun < traces[best]:
        return float(refined.x), float(refined.fun)
    return float(grid[best]), float(traces[best])


def test_ci_weight_equals_brute_force_scan() -> None:
    rng = np.random.default_rng(1)
    firsts = np.array([random_spd(rng, 4, rng.uniform(0.1, 30)) for _ in range(40)])
    seconds = np.array([random_spd(rng, 4, rng.uniform(0.1, 30)) for _ in range(40)])
    # Two boundary cases: one estimate dominates in every direction.
    firsts[0], seconds[0] = np.eye(4), 100 * np.eye(4)
    firsts[1], seconds[1] = 100 * np.eye(4), np.eye(4)
    # And equal covariances: tr P(ω) is flat, every ω is optimal; the midpoint averages the states.
    firsts[2] = seconds[2] = random_spd(rng, 4)
    omega = optimal_ci_weight(firsts, seconds)
    assert omega[0] == 1.0 and omega[1] == 0.0 and omega[2] == 0.5
    for k in range(len(firsts)):
        best_omega, best_trace = brute_force_weight(firsts[k], seconds[k])
        ours = ci_trace(float(omega[k]), firsts[k], seconds[k])
        # Never smaller than the optimum (that would be inconsistent), and no worse than brute force.
        assert ours >= best_trace * (1 - 1e-9)
        assert ours <= best_trace * (1 + 1e-9)
        if k != 2:  # flat case: every ω is optimal
            assert omega[k] == pytest.approx(best_omega, abs=1e-4)


def test_covariance_intersection_of_two_reports_the_optimal_trace() -> None:
    rng = np.random.default_rng(2)
    covariances = np.array([[random_spd(rng, 4), random_spd(rng, 4)] for _ in range(10)])
    states = rng.normal(size=(10, 2, 4))
    present = np.ones((10, 2), dtype=bool)
    state, covariance, weights = fuse_estimates(states, covariances, present, np.zeros((10, 2)))
    for k in range(10):
        _, best_trace = brute_force_weight(covariances[k, 0], covariances[k, 1])
        assert np.trace(covariance[k]) >= best_trace * (1 - 1e-9)
        assert np.trace(covariance[k]) == pytest.approx(best_trace, rel=1e-9)
        w = weights[k, 0]
        info = w * np.linalg.inv(covariances[k, 0]) + (1 - w) * np.linalg.inv(covariances[k, 1])
        expected = np.linalg.solve(
            info,
            w * np.linalg.solve(covariances[k, 0], states[k, 0])
            + (1 - w) * np.linalg.solve(covariances[k, 1], states[k, 1]),
        )
        assert_allclose(state[k], expected, rtol=1e-9, atol=1e-12)


def test_fast_ci_weights_for_three_sensors_follow_niehsen() -> None:
    # ω_i ∝ 1/tr P_i: traces 4, 8, 16 → ω = (4, 2, 1) / 7.
    covariances = np.array([[np.eye(4), 2 * np.eye(4), 4 * np.eye(4)]])
    states = np.array([[[0.0, 0, 0, 0], [7.0, 0, 0, 0], [14.0, 0, 0, 0]]])
    state, covariance, weights = fuse_estimates(
        states, covariances, np.ones((1, 3), bool), np.zeros((1, 3))
    )
    assert_allclose(weights[0], [4 / 7, 2 / 7, 1 / 7])
    # P⁻¹ = 4/7·1 + 2/7·1/2 + 1/7·1/4 = (16 + 4 + 1)/28 = 3/4 → P = 4/3 I.
    assert_allclose(covariance[0], 4 / 3 * np.eye(4))
    # P⁻¹x = 4/7·0 + 2/7·7/2 + 1/7·14/4 = 1 + 0.5 = 1.5 → x = 2 on the first axis.
    assert_allclose(state[0], [2.0, 0, 0, 0])


def test_independent_rule_equals_the_kalman_update_of_one_estimate_by_the_other() -> None:
    rng = np.random.default_rng(3)
    p1, p2 = random_spd(rng, 4), random_spd(rng, 4)
    x1, x2 = rng.normal(size=4), rng.normal(size=4)
    gain = p1 @ np.linalg.inv(p1 + p2)
    expected_x = x1 + gain @ (x2 - x1)
    expected_p = (np.eye(4) - gain) @ p1
    state, covariance, _ = fuse_estimates(
        np.array([[x1, x2]]),
        np.array([[p1, p2]]),
        np.ones((1, 2), bool),
        np.zeros((1, 2)),
        "independent",
    )
    assert_allclose(state[0], expected_x, rtol=1e-9, atol=1e-12)
    assert_allclose(covariance[0], expected_p, rtol=1e-9, atol=1e-12)


def test_latest_picks_the_newest_present_estimate_and_ties_go_to_the_first_slot() -> None:
    states = np.arange(2 * 3 * 2, dtype=float).reshape(2, 3, 2)
    covariances = np.broadcast_to(np.eye(2), (2, 3, 2, 2)).copy()
    present = np.array([[True, True, False], [True, True, True]])
    times = np.array([[1.0, 2.0, 9.0], [5.0, 5.0, 4.0]])
    state, _, weights = fuse_estimates(states, covariances, present, times, StateFusion.LATEST)
    assert_allclose(state, [states[0, 1], states[1, 0]])
    assert_allclose(weights, [[0, 1, 0], [1, 0, 0]])


def test_single_estimate_passes_through_every_rule() -> None:
    rng = np.random.default_rng(4)
    p = random_spd(rng, 4)
    x = rng.normal(size=4)
    states = np.array([[x, np.zeros(4)]])
    covariances = np.array([[p, np.eye(4)]])
    present = np.array([[True, False]])
    for rule in StateFusion:
        state, covariance, _ = fuse_estimates(states, covariances, present, np.zeros((1, 2)), rule)
        assert_allclose(state[0], x, rtol=1e-10, atol=1e-12)
        assert_allclose(covariance[0], p, rtol=1e-10, atol=1e-12)


def test_invalid_layouts_are_rejected() -> None:
    with pytest.raises(InvalidInput, match="at least one sensor estimate"):
        fuse_estimates(
            np.zeros((1, 2, 2)), np.zeros((1, 2, 2, 2)), np.zeros((1, 2), bool), np.zeros((1, 2))
        )
    with pytest.raises(InvalidInput, match="disagree"):
        fuse_estimates(
            np.zeros((1, 2, 2)), np.zeros((1, 2, 3, 3)), np.ones((1, 2), bool), np.zeros((1, 2))
        )
    with pytest.raises(ValueError, match="not_a_rule"):
        fuse_estimates(
            np.zeros((1, 1, 2)),
            np.ones((1, 1, 2, 2)),
            np.ones((1, 1), bool),
            np.zeros((1, 1)),
            "not_a_rule",
        )


@pytest.mark.parametrize("rule", list(StateFusion))
def test_a_track_fuses_to_the_same_bits_whatever_else_is_in_the_batch(rule: StateFusion) -> None:
    """Determinism across restore: a track's fused state must not depend on the batch size
    (the engine recomputes different subsets of tracks before and after a restore)."""
    rng = np.random.default_rng(11)
    tracks, slots, dim = 300, 3, 4
    states = rng.normal(size=(tracks, slots, dim))
    covariances = np.array(
        [[random_spd(rng, dim) for _ in range(slots)] for _ in range(tracks)], dtype=np.float64
    )
    present = np.ones((tracks, slots), dtype=bool)
    present[::3, 2] = False  # some tracks with two estimates (the exact-ω path)
    present[1::7, 1:] = False  # some with one
    times = rng.uniform(0, 5, size=(tracks, slots))
    state, covariance, weights = fuse_estimates(states, covariances, present, times, rule)
    for chosen in (np.arange(10), np.array([5, 150, 299])):
        alone = fuse_estimates(
            states[chosen], covariances[chosen], present[chosen], times[chosen], rule
        )
        np.testing.assert_array_equal(alone[0], state[chosen])
        np.testing.assert_array_equal(alone[1], covariance[chosen])
        np.testing.assert_array_equal(alone[2], weights[chosen])


def test_optimal_ci_weight_of_an_ill_conditioned_tiny_pair_matches_a_grid_search() -> None:
    """Issue 14: a valid but ill-conditioned covariance at scale 1e-96 made a 500 (Cholesky of P₂⁻¹).

    ω is scale-invariant, so the grid search runs on the pair rescaled to unit size,
    where plain inverses are accurate.
    """
    rng = np.random.default_rng(81)  # a pair the explicit-inverse formulation refused
    pair = []
    for _ in range(2):
        basis, _ = np.linalg.qr(rng.normal(size=(4, 4)))
        pair.append((basis * 10.0 ** rng.uniform(-5.5, 5.5, size=4)) @ basis.T)
    first, second = ((matrix + matrix.T) / 2.0 for matrix in pair)
    scale = 1e-96
    omega = float(optimal_ci_weight((first * scale)[None], (second * scale)[None])[0])
    grid = np.linspace(0.0, 1.0, 20_001)
    info_first, info_second = np.linalg.inv(first), np.linalg.inv(second)
    traces = [np.trace(np.linalg.inv(w * info_first + (1 - w) * info_second)) for w in grid]
    best = float(grid[int(np.argmin(traces))])
    assert abs(omega - best) <= 1e-3
