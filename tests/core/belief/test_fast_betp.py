"""The O(N²) pignistic paths against brute-force enumeration of every subset."""

from __future__ import annotations

import numpy as np
import pyds
import pytest
from numpy.testing import assert_allclose
from pybelief import MassFunction as PyBeliefMass

from core.arrays import FloatArray
from core.belief import gbt_betp, gbt_betp_rows, pairwise_evidence_betp_rows

SPECIAL = np.array([0.0, 1.0, 1e-12, 1.0 - 1e-12])


def brute_force_gbt_betp(p: FloatArray) -> FloatArray | None:
    """Enumerate all 2^N subsets: m(A) = Π_{A} p Π_{not A}(1 − p), BetP by [MTT] eq 8."""
    n = len(p)
    betp = np.zeros(n)
    nonempty_total = 0.0
    for mask in range(1, 1 << n):
        member = np.array([(mask >> k) & 1 == 1 for k in range(n)])
        mass = float(np.prod(np.where(member, p, 1.0 - p)))
        nonempty_total += mass
        betp[member] += mass / member.sum()
    # Normalise by Σ_{A≠∅} m(A) = 1 − m(∅), summed directly: no cancellation.
    return None if nonempty_total == 0.0 else betp / nonempty_total


def plausibility_cases(rng: np.random.Generator) -> list[FloatArray]:
    cases = []
    for n in range(1, 15):
        cases.append(rng.uniform(0.0, 1.0, n))
        cases.append(rng.choice(SPECIAL, n))  # only 0, 1 and near-0, near-1
        mixed = rng.uniform(0.0, 1.0, n)
        mixed[rng.random(n) < 0.4] = rng.choice(SPECIAL)
        cases.append(mixed)
    return cases


def test_gbt_betp_equals_enumeration_for_n_up_to_14() -> None:
    rng = np.random.default_rng(20261122)
    worst = 0.0
    for p in plausibility_cases(rng):
        expected = brute_force_gbt_betp(p)
        fast = gbt_betp(p)
        if expected is None:
            assert fast is None
            continue
        assert fast is not None
        worst = max(worst, float(np.max(np.abs(fast - expected))))
        assert fast.sum() == pytest.approx(1.0, abs=1e-12)
        assert np.all(fast[p == 0.0] == 0.0)  # zero plausibility, zero BetP
    assert worst <= 1e-12


def test_gbt_betp_is_undefined_only_when_every_plausibility_is_zero() -> None:
    assert gbt_betp(np.zeros(5)) is None
    single = gbt_betp(np.array([0.0, 1e-12, 0.0]))
    assert single is not None
    assert_allclose(single, [0.0, 1.0, 0.0])


def test_gbt_betp_matches_pyds_quadratic_recursion_on_large_frames() -> None:
    # pyds.gbt_pignistic: an independent O(N²) recursion over cardinalities.
    rng = np.random.default_rng(7)
    p = rng.uniform(0.0, 1.0, 60)
    labels = [f"t{k}" for k in range(len(p))]
    likelihoods = list(zip(labels, p, strict=True))
    fast = gbt_betp(p)
    assert fast is not None
    for k in (0, 17, 59):
        assert fast[k] == pytest.approx(pyds.gbt_pignistic(labels[k], likelihoods), abs=1e-12)


def test_batched_rows_equal_single_rows_with_padding_zeros() -> None:
    rng = np.random.default_rng(3)
    rows = rng.uniform(0.0, 1.0, (6, 9))
    rows[rng.random(rows.shape) < 0.5] = 0.0
    rows[2] = 0.0  # undefined row
    betp, defined = gbt_betp_rows(rows)
    for row, expected_row, ok in zip(rows, betp, defined, strict=True):
        single = gbt_betp(row)
        assert ok == (single is not None)
        assert_allclose(expected_row, single if single is not None else np.zeros(9), atol=1e-14)


def brute_force_pairwise(a: FloatArray, b: FloatArray, c: FloatArray) -> FloatArray | None:
    """Combine the n simple masses on Θ = {Y_1..Y_n, *} with pybelief's conjunctive rule.

    Source k: m_k({Y_k}) = a_k, m_k(Θ \\ {Y_k}) = b_k (i.e. ¬Y_k), m_k(Θ) = c_k.
    """
    n = len(a)
    labels = [f"Y{k}" for k in range(n)] + ["*"]
    full = (1 << (n + 1)) - 1
    combined = PyBeliefMass(labels)  # vacuous
    for k in range(n):
        source = {1 << k: a[k], full & ~(1 << k): b[k], full: c[k]}
        merged: dict[int, float] = {}
        for mask, value in source.items():
            if value > 0:
                merged[mask] = merged.get(mask, 0.0) + value
        combined = combined | PyBeliefMass(labels, merged)
    if combined[0] >= 1.0 - 1e-15:
        return None
    pignistic = combined.pignistic()
    return np.array([pignistic[label] for label in labels])


def test_pairwise_evidence_betp_equals_enumeration() -> None:
    rng = np.random.default_rng(11)
    for n in range(1, 9):
        for _ in range(4):
            raw = rng.dirichlet(np.ones(3), size=n)
            if rng.random() < 0.5:  # some certain refutations (Pl = 0) and certain supports
                raw[rng.random(n) < 0.3] = [0.0, 1.0, 0.0]
            a, b, c = raw[:, 0], raw[:, 1], raw[:, 2]
            expected = brute_force_pairwise(a, b, c)
            betp, defined = pairwise_evidence_betp_rows(a[None], b[None], c[None])
            if expected is None:
                assert not defined[0]
                continue
            assert defined[0]
            assert_allclose(betp[0], expected, atol=1e-12)
            assert betp[0].sum() == pytest.approx(1.0, abs=1e-12)


def test_pairwise_evidence_total_conflict_is_reported() -> None:
    # Two candidates each certain to be the source: m(Y_1) m(Y_2) conflict totally.
    betp, defined = pairwise_evidence_betp_rows(
        np.array([[1.0, 1.0]]), np.array([[0.0, 0.0]]), np.array([[0.0, 0.0]])
    )
    assert not defined[0]
    assert np.all(betp == 0.0)


@pytest.mark.parametrize("bad", [np.array([0.2, np.nan]), np.array([1.5]), np.array([-0.1])])
def test_gbt_betp_rejects_invalid_plausibilities(bad: FloatArray) -> None:
    with pytest.raises(ValueError, match="plausibilities"):
        gbt_betp(bad)


def test_hand_worked_gbt_betp() -> None:
    # p = (1, 0.5): focal sets {0}: 1·0.5 = 0.5 and {0,1}: 1·0.5 = 0.5, m(∅) = 0.
    # BetP(0) = 0.5 + 0.5/2 = 0.75, BetP(1) = 0.5/2 = 0.25.
    p = np.array([1.0, 0.5])
    for result in (brute_force_gbt_betp(p), gbt_betp(p)):
        assert result is not None
        assert_allclose(result, [0.75, 0.25], atol=1e-15)
