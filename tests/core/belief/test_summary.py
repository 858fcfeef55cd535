"""Summarized masses ([LGS86]) are weakenings of the originals; the bounded GBT is exact when it fits."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from core.belief import Frame, MassFunction, gbt_mass
from core.belief.summary import bounded_gbt_mass, summarize

LABELS = [f"c{index}" for index in range(6)]
FRAME = Frame(LABELS)


def random_mass(rng: np.random.Generator, count: int, with_conflict: bool) -> MassFunction:
    masks = rng.choice(np.arange(1, 1 << len(LABELS)), size=count, replace=False)
    if with_conflict:
        masks[0] = 0
    weights = rng.uniform(0.01, 1.0, size=count)
    return MassFunction.aggregate(FRAME, masks.astype(np.int64), weights / weights.sum())


def brute_belief_plausibility(mass: MassFunction, subset: int) -> tuple[float, float]:
    """Bel(A) and Pl(A) summed by hand over the focal sets (nonempty ones for Bel)."""
    belief = sum(
        m for mask, m in zip(mass.masks, mass.masses, strict=True) if mask and mask & ~subset == 0
    )
    plausibility = sum(m for mask, m in zip(mass.masks, mass.masses, strict=True) if mask & subset)
    return float(belief), float(plausibility)


@pytest.mark.parametrize("seed", range(6))
def test_a_summary_never_claims_more_than_the_mass(seed: int) -> None:
    rng = np.random.default_rng(seed)
    original = random_mass(rng, 40, with_conflict=seed % 2 == 0)
    summary, cut = summarize(original, 8)
    assert cut and len(summary) <= 8
    assert summary.masses.sum() == pytest.approx(1.0, abs=1e-12)
    assert summary.conflict == pytest.approx(original.conflict, abs=1e-15)  # m(∅) kept
    for size in range(1, len(LABELS) + 1):
        for members in itertools.combinations(range(len(LABELS)), size):
            subset = sum(1 << index for index in members)
            bel, pl = brute_belief_plausibility(summary, subset)
            bel0, pl0 = brute_belief_plausibility(original, subset)
            assert bel <= bel0 + 1e-12 and pl >= pl0 - 1e-12


def test_a_summary_keeps_the_largest_focal_sets() -> None:
    rng = np.random.default_rng(9)
    original = random_mass(rng, 30, with_conflict=False)
    summary, _ = summarize(original, 5)
    largest = original.masks[np.argsort(original.masses)[-4:]]
    assert set(largest.tolist()) <= set(summary.masks.tolist())


def test_within_the_bound_nothing_changes() -> None:
    original = random_mass(np.random.default_rng(3), 8, with_conflict=True)
    summary, cut = summarize(original, 8)
    assert not cut and summary is original


def test_the_bounded_gbt_equals_the_gbt_when_it_fits() -> None:
    plausibility = np.array([0.2, 0.7, 1.0, 0.0, 0.5, 0.9])  # 4 fractional: 16 focal sets
    exact = gbt_mass(FRAME, plausibility)
    bounded, cut = bounded_gbt_mass(FRAME, plausibility, limit=16)
    assert not cut
    np.testing.assert_array_equal(bounded.masks, exact.masks)
    np.testing.assert_allclose(bounded.masses, exact.masses, rtol=0, atol=1e-15)


def test_the_bounded_gbt_of_20_classes_is_bounded_and_weaker() -> None:
    frame = Frame([f"k{index}" for index in range(20)])
    plausibility = np.linspace(0.05, 0.95, 20)
    bounded, cut = bounded_gbt_mass(frame, plausibility, limit=32)
    assert cut and len(bounded) <= 32
    assert bounded.masses.sum() == pytest.approx(1.0, abs=1e-12)
    # Pl({c}) of the GBT mass is p_c ([MTT] eq 10); a weakening can only raise it
    assert np.all(bounded.singleton_plausibility() >= plausibility - 1e-12)
