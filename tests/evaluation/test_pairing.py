"""Track-to-track problems with their truth; the hachour implicit gate, exactly."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.association import associate
from core.simulation.tracklists import t2t_four
from core.simulation.two_class import t2t_two_class
from evaluation.pairing import decision_error_rate, list_pairs, partially_observed
from evaluation.units import implicit_gate


def test_one_problem_per_step_incoming_is_sensor_one_predicted_to_sensor_two() -> None:
    scenario = t2t_four(seed=0, n_steps=5)
    pairs = list_pairs(scenario.reports)
    assert len(pairs) == 5
    s1, s2 = scenario.reports[0], scenario.reports[1]
    np.testing.assert_array_equal(pairs[0].known_states, s2.states)
    lag = s2.time - s1.time
    np.testing.assert_allclose(
        pairs[0].incoming_states[:, 0], s1.states[:, 0] + s1.states[:, 1] * lag
    )
    assert pairs[0].truth() == {0: 0, 1: 1, 2: 2, 3: 3}
    assert pairs[0].known_classes is None


def test_truth_after_misses_and_perfect_decisions() -> None:
    pair = list_pairs(t2t_four(seed=0, n_steps=1, noise=0.0).reports)[0]
    partial = pair.keep(np.array([0, 2, 3]), np.array([1, 2]))
    assert partial.truth() == {0: None, 1: 1}
    assert partial.decide("gnn") == {0: None, 1: 1}
    assert decision_error_rate([pair], "denoeux") == 0.0
    rng = np.random.default_rng(0)
    assert all(len(p.known_targets) == 4 for p in partially_observed([pair] * 5, 0.0, rng))
    assert all(len(p.incoming_targets) == 0 for p in partially_observed([pair] * 5, 1.0, rng))


def test_class_masses_travel_with_their_tracks() -> None:
    scenario = t2t_two_class(seed=0, n_steps=3)
    pairs = list_pairs(scenario.reports, class_masses=scenario.class_masses)
    assert pairs[1].known_classes == scenario.class_masses[3]
    assert pairs[1].incoming_classes == scenario.class_masses[2]
    kept = pairs[1].keep(np.array([1]), np.array([0, 1]))
    assert kept.known_classes == (scenario.class_masses[3][1],)


def test_a_change_of_unit_leaves_every_mahalanobis_decision_unchanged() -> None:
    pairs = list_pairs(t2t_four(seed=1, separation=2.0, n_steps=10).reports)
    for method, options in (
        ("gnn", {"threshold": 20.0}),
        ("denoeux", {}),
        ("hachour", {"likelihood": "relative"}),
        ("mercier", {}),
    ):
        for pair in pairs:
            assert pair.decide(method, options) == pair.scaled(1e-3).decide(method, options)


def _true_pair_distances(pair_states: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    known, incoming, covariance = pair_states
    delta = incoming - known
    return np.einsum("ni,ij,nj->n", delta, np.linalg.inv(covariance), delta)


def test_hachour_density_in_metres_matches_exactly_the_pairs_inside_its_implicit_gate() -> None:
    # Targets 40 m apart: no competition, so a pair is matched iff its Pl > 1/2, i.e. iff
    # D < 2 ln 2 − q ln 2π − ln|C| (docs/algorithms.md §3.3) — at σ = 0.5 m that is D < 2.35.
    sigma = 0.5
    pairs = list_pairs(t2t_four(seed=2, position_sigma=sigma, separation=40.0, n_steps=40).reports)
    gate = implicit_gate(sigma)
    assert gate == pytest.approx(2.35, abs=0.01)
    matched = inside = total = 0
    for pair in pairs:
        covariance = pair.known_covariances[0]  # mean of two equal covariances
        distances = _true_pair_distances((pair.known_states, pair.incoming_states, covariance))
        decision = pair.decide("hachour", {"likelihood": "density"})
        for item, distance in enumerate(distances):
            assert (decision[item] == item) == (distance < gate)
        result = associate(
            (pair.known_states, pair.known_covariances),
            (pair.incoming_states, pair.incoming_covariances),
            "hachour",
            {"likelihood": "density"},
            "mean",
        )
        np.testing.assert_allclose(result.diagnostics.implicit_gate, gate, rtol=1e-9)
        matched += len(result.pair_known)
        inside += int(np.sum(distances < gate))
        total += len(distances)
    # True pairs have D ~ 2 χ²₄ under the mean covariance: P(D < 2.35) ≈ 0.07.
    assert matched == inside
    assert 0.02 < matched / total < 0.15


def test_hachour_density_in_kilometres_clips_every_close_pair_and_cannot_rank_them() -> None:
    pair = list_pairs(t2t_four(seed=0, separation=2.0, n_steps=1).reports)[0].scaled(1e-3)
    result = associate(
        (pair.known_states, pair.known_covariances),
        (pair.incoming_states, pair.incoming_covariances),
        "hachour",
        {"likelihood": "density"},
        "mean",
    )
    assert implicit_gate(0.5, 1e-3) == pytest.approx(2.35 + 8 * math.log(1e3), abs=0.01)
    assert result.diagnostics.clipped.sum() > 0
    clipped_pairs = result.scores.values[result.scores.values > 0]
    # Every candidate of an item has Pl = 1: its BetP is flat over them.
    for item in range(4):
        row = result.scores.values[result.scores.cols == item]
        np.testing.assert_allclose(row, row[0])
    assert len(clipped_pairs) > 4
