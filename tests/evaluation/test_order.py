"""Ties are not decisions: random list orders, tie counts, and 95 % intervals.

The reported rates must not depend on the order the lists come in: shuffled
with another family of random orders, no rate moves out of its interval.
Exact ties (two known tracks at the same place) are counted as ties; a
tie-free problem has none and its rate is the truth-order rate.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.simulation.tracklists import t2t_four
from evaluation.four_targets import threshold_sweep
from evaluation.intervals import (
    bootstrap_interval,
    mean_interval,
    paired_difference,
    rate_interval,
    wilson,
)
from evaluation.pairing import ListPair, decision_error_rate, decision_outcome, list_pairs


def test_shuffling_the_lists_moves_no_rate_out_of_its_interval() -> None:
    kwargs = {"seeds": tuple(range(4)), "thresholds": (4.0, 50.0), "n_steps": 6}
    first, second = threshold_sweep(**kwargs, order=0), threshold_sweep(**kwargs, order=1)
    compared = [(first.gnn[:, col], second.gnn[:, col]) for col in range(2)] + [
        (first.denoeux[:, col], second.denoeux[:, col]) for col in range(2)
    ]
    compared += [(first.hachour[label], second.hachour[label]) for label in first.hachour]
    for one, other in compared:
        interval = rate_interval(one, first.decisions)
        assert float(np.average(other, weights=first.decisions)) in interval, interval
    # the kilometre scene is decided by ties, and they are counted
    assert first.ties["density, km"].mean() > 0.3
    assert first.ties["gnn"][:, 1].max() == 0.0


def _duplicated(count: int) -> ListPair:
    """``count`` targets far apart; each known track appears twice at the same place."""
    states = np.zeros((count, 4))
    states[:, 0] = 1000.0 * np.arange(count)
    covariances = np.broadcast_to(np.eye(4), (count, 4, 4)).copy()
    targets = np.arange(count, dtype=np.int64)
    return ListPair(
        known_states=np.concatenate([states, states]),
        known_covariances=np.concatenate([covariances, covariances]),
        known_targets=np.concatenate([targets, targets + count]),
        incoming_states=states + 0.1,
        incoming_covariances=covariances,
        incoming_targets=targets,
    )


def test_exact_ties_are_counted_and_a_tie_free_problem_has_none() -> None:
    tied = decision_outcome([_duplicated(20)], "gnn", {"threshold": 20.0}, seed=0)
    assert tied.decisions == 20
    # each incoming track has two partners at the same distance: which one is
    # chosen follows the order, so about half the decisions are wrong and most
    # change between orders
    assert 0.2 < tied.rate < 0.8
    assert tied.tie_rate > 0.5
    clean = list_pairs(t2t_four(seed=3, separation=50.0, n_steps=5).reports)
    outcome = decision_outcome(clean, "gnn", {"threshold": 20.0}, seed=3)
    assert outcome.tie_rate == 0.0
    assert outcome.rate == decision_error_rate(clean, "gnn", {"threshold": 20.0})


def test_wilson_interval_by_hand() -> None:
    z2 = 1.959963984540054**2
    low, high = wilson(0, 10)
    assert low == 0.0
    assert high == pytest.approx(z2 / (10 + z2), rel=1e-12)  # k = 0: n̂ = z² / (n + z²)
    low, high = wilson(5, 10)
    half = math.sqrt(z2 * 0.25 / 10 + z2**2 / 400) / (1 + z2 / 10)
    assert (low, high) == pytest.approx((0.5 - half, 0.5 + half), rel=1e-12)


def test_rate_interval_is_never_zero_wide_and_mean_interval_is_student() -> None:
    interval = rate_interval([0.0, 0.0, 0.0], [40, 40, 40])  # identical runs
    assert interval.estimate == 0.0 and interval.high == pytest.approx(wilson(0, 120)[1])
    values = mean_interval([1.0, 2.0, 3.0])
    half = 4.302652729911275 * 1.0 / math.sqrt(3.0)  # t(0.975, 2) · s / √n, s = 1
    assert (values.low, values.high) == pytest.approx((2.0 - half, 2.0 + half), rel=1e-9)


def test_mean_interval_of_a_quantity_that_cannot_go_below_its_floor() -> None:
    """A GOSPA false term of 0, 0, 0.3 over three seeds: Student's interval is
    0.1 ± t(0.975, 2)·s/√3 (s = 0.1√3, worked by hand), reaching below 0 where the mean of
    a term ≥ 0 cannot be; with ``floor=0`` it is cut there, its upper end unchanged."""
    values = [0.0, 0.0, 0.3]
    half = 4.302652729911275 * 0.1 * math.sqrt(3.0) / math.sqrt(3.0)
    plain = mean_interval(values)
    assert (plain.low, plain.high) == pytest.approx((0.1 - half, 0.1 + half), rel=1e-9)
    assert plain.low < 0.0
    cut = mean_interval(values, floor=0.0)
    assert (cut.estimate, cut.low, cut.high) == pytest.approx((0.1, 0.0, 0.1 + half), rel=1e-9)


def test_paired_difference_by_hand() -> None:
    result = paired_difference([2.0, 4.0, 6.0], [1.0, 2.0, 3.0])  # differences 1, 2, 3
    assert result.difference.estimate == pytest.approx(2.0)
    # t = mean / (s/√n) = 2 / (1/√3) = 2√3 on ν = 2 degrees of freedom, where
    # Student's CDF is F(t) = 1/2 + t / (2√(2 + t²)): two-sided p = 1 − t/√(2 + t²)
    t = 2.0 * math.sqrt(3.0)
    p_by_hand = 1.0 - t / math.sqrt(2.0 + t * t)
    assert result.p_value == pytest.approx(p_by_hand, rel=1e-9)
    assert paired_difference([1.0, 1.0], [1.0, 1.0]).p_value == 1.0


def test_the_bootstrap_of_a_mean_is_the_normal_interval() -> None:
    # For a plain mean the percentile bootstrap approaches x̄ ± z s/√n (hand formula).
    values = np.random.default_rng(3).normal(2.0, 1.0, size=400)
    estimate, low, high = bootstrap_interval(lambda rows: np.array([values[rows].mean()]), 400)
    half = 1.959964 * values.std(ddof=1) / np.sqrt(400)
    assert estimate[0] == pytest.approx(values.mean())
    assert low[0] == pytest.approx(values.mean() - half, abs=0.15 * half)
    assert high[0] == pytest.approx(values.mean() + half, abs=0.15 * half)
