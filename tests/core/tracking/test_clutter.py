"""The clutter estimate's density (docs/algorithms.md §8.4), worked by hand.

β̂ = (n₀ λ₀ + Σ w_k c_k / V) / (n₀ + Σ w_k), λ₀ = 1 / V₀, V₀ the box grown by the prior's gate
on each side, n₀ = 1. A box of no volume (its detections' σ below the spacing of the doubles
at them: near 1 m that spacing is 2.2e-16, so 1.0 ± 3e-30 is 1.0) has no region to spread its
count over: its density is λ₀ alone. Before, it divided by 0 (a ZeroDivisionError, a 500 of the
service).
"""

from __future__ import annotations

import numpy as np
import pytest

from core.tracking.clutter import ClutterEstimate


def _box(low: list[float], high: list[float], false_alarms: float, scans: float) -> ClutterEstimate:
    return ClutterEstimate(false_alarms, scans, np.array(low), np.array(high))


def test_a_box_of_volume_gives_the_weighted_mean_of_prior_and_count() -> None:
    # V = 10 × 20 = 200, count 4 / 200 = 0.02; V₀ = 12 × 22 = 264; (1/264 + 0.02) / (1 + 2)
    estimate = _box([0.0, 0.0], [10.0, 20.0], false_alarms=4.0, scans=2.0)
    assert estimate.density(1.0) == pytest.approx((1.0 / 264.0 + 0.02) / 3.0, rel=1e-12)


def test_one_detection_of_a_sigma_below_the_doubles_spacing_gives_the_prior_alone() -> None:
    # the box: [1, 1] × [2, 2] (1 ± 3e-30 = 1); V₀ = (0 + 2) × (0 + 2) = 4, λ₀ = 0.25
    estimate = ClutterEstimate.empty(2).widened(np.array([[1.0, 2.0]]), 1e-30).counted(1)
    assert np.array_equal(estimate.low, estimate.high)
    assert estimate.density(1.0) == 0.25


def test_a_box_flat_along_one_axis_gives_the_prior_alone() -> None:
    # sides 10 and 0: V = 0; V₀ = 12 × 2 = 24
    estimate = _box([0.0, 5.0], [10.0, 5.0], false_alarms=3.0, scans=2.0)
    assert estimate.density(1.0) == pytest.approx(1.0 / 24.0, rel=1e-12)
