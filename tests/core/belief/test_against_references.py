"""core.belief against two independent libraries: pybelief and py-dempster-shafer (pyds).

Conventions minded here:
- pybelief ``discount(alpha)`` takes a discount *rate* (1 − reliability);
  its ``|`` is the unnormalised conjunctive rule and ``&`` Dempster's rule.
- pyds has no discounting, its ``|`` is the disjunctive rule and ``&`` is
  Dempster's rule; it returns ``{}`` on total conflict.
"""

from __future__ import annotations

import numpy as np
import pyds
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from core.belief import (
    Frame,
    MassFunction,
    TotalConflict,
    conflict,
    conjunctive,
    dempster,
    gbt_mass,
)
from core.errors import TotalConflict as TotalConflictFromErrors

from .references import all_subsets, to_pybelief, to_pyds
from .strategies import frames, mass_functions, mass_pairs


def as_dict(mass: MassFunction) -> dict[int, float]:
    return {int(k): float(v) for k, v in zip(mass.masks, mass.masses, strict=True)}


def assert_same_masses(ours: dict[int, float], reference: dict[int, float]) -> None:
    keys = set(ours) | set(reference)
    for key in keys:
        assert ours.get(key, 0.0) == pytest.approx(reference.get(key, 0.0), abs=1e-12), key


def test_total_conflict_is_the_errors_module_type() -> None:
    assert TotalConflict is TotalConflictFromErrors


@given(st.data())
@settings(max_examples=150)
def test_plausibility_and_belief_match_both_libraries(draw: st.DataObject) -> None:
    frame = draw.draw(frames())
    mass = draw.draw(mass_functions(frame))
    pb, ds = to_pybelief(mass), to_pyds(mass)
    for subset in all_subsets(mass):
        if not subset:
            continue
        assert mass.plausibility(subset) == pytest.approx(pb.plausibility(set(subset)), abs=1e-12)
        assert mass.plausibility(subset) == pytest.approx(ds.pl(subset), abs=1e-12)
        assert mass.belief(subset) == pytest.approx(pb.belief(set(subset)), abs=1e-12)
        assert mass.belief(subset) == pytest.approx(ds.bel(subset), abs=1e-12)
    assert_allclose(
        mass.singleton_plausibility(),
        [pb.plausibility({label}) for label in frame.labels],
        atol=1e-12,
    )
    assert_allclose(
        mass.singleton_belief(), [pb.belief({label}) for label in frame.labels], atol=1e-12
    )


@given(mass_pairs())
@settings(max_examples=150)
def test_conjunctive_rule_matches_pybelief(pair: tuple[MassFunction, MassFunction]) -> None:
    first, second = pair
    ours = conjunctive(first, second)
    reference = to_pybelief(first) | to_pybelief(second)
    assert_same_masses(as_dict(ours), dict(reference.focal_elements()))
    assert ours.conflict == pytest.approx(
        to_pybelief(first).conflict(to_pybelief(second)), abs=1e-12
    )
    assert conflict(first, second) == pytest.approx(ours.conflict, abs=1e-12)


@given(mass_pairs())
@settings(max_examples=150)
def test_dempster_rule_matches_both_libraries(pair: tuple[MassFunction, MassFunction]) -> None:
    first, second = pair
    reference_ds = to_pyds(first) & to_pyds(second)
    if not reference_ds:  # pyds: total conflict
        with pytest.raises(TotalConflict):
            dempster(first, second)
        return
    ours = dempster(first, second)
    reference_pb = to_pybelief(first) & to_pybelief(second)
    assert_same_masses(as_dict(ours), dict(reference_pb.focal_elements()))
    for labels, value in ours.focal_sets():
        assert value == pytest.approx(reference_ds[frozenset(labels)], abs=1e-12)
    assert float(np.sum(ours.masses)) == pytest.approx(1.0, abs=1e-12)


@given(st.data())
@settings(max_examples=150)
def test_pignistic_matches_both_libraries(draw: st.DataObject) -> None:
    frame = draw.draw(frames())
    mass = draw.draw(mass_functions(frame, allow_empty=True))
    ours = mass.pignistic()
    if mass.conflict >= 1.0 - 1e-12:
        assert ours is None
        return
    assert ours is not None
    reference = to_pybelief(mass).pignistic()
    assert_allclose(ours, [reference[label] for label in frame.labels], atol=1e-12)
    assert ours.sum() == pytest.approx(1.0, abs=1e-12)
    if mass.conflict == 0.0:  # pyds divides by |A| and would fail on ∅
        reference_ds = to_pyds(mass).pignistic()
        assert_allclose(
            ours, [reference_ds[frozenset({label})] for label in frame.labels], atol=1e-12
        )


@given(st.data(), st.floats(0.0, 1.0))
@settings(max_examples=150)
def test_discounting_follows_mtt_eq7_and_pybelief_rate(
    draw: st.DataObject, reliability: float
) -> None:
    frame = draw.draw(frames())
    mass = draw.draw(mass_functions(frame, allow_empty=True))
    ours = as_dict(mass.discount(reliability))
    # [MTT] eq 7, written out: m^λ(A) = λ m(A) (A ≠ Ω), m^λ(Ω) = λ m(Ω) + 1 − λ.
    by_formula = {
        int(k): reliability * float(v) for k, v in zip(mass.masks, mass.masses, strict=True)
    }
    by_formula[frame.full] = by_formula.get(frame.full, 0.0) + 1.0 - reliability
    assert_same_masses(ours, by_formula)
    # pybelief takes the discount rate 1 − λ.
    assert_same_masses(ours, dict(to_pybelief(mass).discount(1.0 - reliability).focal_elements()))


@given(st.lists(st.sampled_from([0.0, 1.0, 1e-12, 0.25, 0.5, 0.9]), min_size=1, max_size=6))
@settings(max_examples=100)
def test_gbt_mass_matches_pyds(plausibility: list[float]) -> None:
    frame = Frame("abcdef"[: len(plausibility)])
    ours = gbt_mass(frame, np.array(plausibility))
    reference = pyds.MassFunction.gbt(
        dict(zip(frame.labels, plausibility, strict=True)), normalization=False
    )
    for labels, value in ours.focal_sets():
        assert value == pytest.approx(reference[frozenset(labels)], abs=1e-15)
    assert float(np.sum(ours.masses)) == pytest.approx(1.0, abs=1e-12)
    # m(∅) = Π(1 − p_k)  ([MTT] eq 10 with A = ∅)
    assert ours.conflict == pytest.approx(float(np.prod(1.0 - np.array(plausibility))), abs=1e-15)


def test_conjunctive_rule_on_a_20_label_frame_matches_pybelief() -> None:
    # Large frame, few focal sets: exercises the sorting aggregation path.
    rng = np.random.default_rng(5)
    frame = Frame([f"c{i}" for i in range(20)])
    masses = []
    for _ in range(2):
        masks = rng.choice(np.arange(1, frame.full + 1), size=30, replace=False)
        weights = rng.random(30)
        masses.append(MassFunction.from_masks(frame, masks, weights / weights.sum()))
    ours = conjunctive(masses[0], masses[1])
    reference = to_pybelief(masses[0]) | to_pybelief(masses[1])
    assert_same_masses(as_dict(ours), dict(reference.focal_elements()))
