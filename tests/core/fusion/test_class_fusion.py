"""Class fusion from sensor reports against pybelief and pyds."""

from __future__ import annotations

import numpy as np
import pyds
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from core.belief import TIE_TOLERANCE, DecisionState, Frame, MassFunction, TotalConflict
from core.fusion.classes import ClassState, accumulate_likelihoods, fuse_sensor_classes
from tests.core.belief.references import to_pybelief
from tests.core.belief.strategies import mass_functions

CLASSES = Frame(["liner", "bomber", "fighter"])


@given(
    st.lists(mass_functions(CLASSES), min_size=1, max_size=4),
    st.lists(st.floats(0.0, 1.0), min_size=4, max_size=4),
)
@settings(max_examples=100)
def test_fusion_equals_pybelief_combination_of_discounted_masses(
    masses: list[MassFunction], reliabilities: list[float]
) -> None:
    sensors = {f"s{k}": mass for k, mass in enumerate(masses)}
    reliability = {f"s{k}": reliabilities[k] for k in range(len(masses))}
    result = fuse_sensor_classes(sensors, reliability)
    assert result is not None
    # pybelief: discount takes the rate 1 − reliability; | is the unnormalised conjunctive rule.
    reference = None
    for sensor in sorted(sensors):
        discounted = to_pybelief(sensors[sensor]).discount(1.0 - reliability[sensor])
        reference = discounted if reference is None else reference | discounted
    assert reference is not None
    assert result.conflict == pytest.approx(reference[0], abs=1e-12)
    if reference[0] >= 1.0 - 1e-12:
        assert result.state is ClassState.TOTAL_CONFLICT
        return
    assert result.state is ClassState.DEFINED and result.mass is not None
    # Dempster normalisation written out: drop ∅, divide by 1 − K.
    kept = {mask: value for mask, value in reference.focal_elements().items() if mask != 0}
    normalised = type(reference)(
        CLASSES.labels, {m: v / sum(kept.values()) for m, v in kept.items()}
    )
    for labels, value in result.mass.focal_sets():
        assert value == pytest.approx(normalised[frozenset(labels)], abs=1e-12)
    assert float(np.sum(result.mass.masses)) == pytest.approx(1.0, abs=1e-12)
    pignistic = normalised.pignistic()
    assert_allclose(result.pignistic, [pignistic[label] for label in CLASSES.labels], atol=1e-12)
    assert_allclose(
        result.plausibility, [normalised.plausibility({c}) for c in CLASSES.labels], atol=1e-12
    )
    assert_allclose(result.belief, [normalised.belief({c}) for c in CLASSES.labels], atol=1e-12)
    # The decision from the reference BetP: a tie (top two within 1e-9) decides nothing.
    ranked = sorted(CLASSES.labels, key=lambda label: -pignistic[label])
    gap = pignistic[ranked[0]] - pignistic[ranked[1]]
    if abs(gap - TIE_TOLERANCE) > 1e-11:  # clear of the boundary, where rounding could tip it
        tied = gap <= TIE_TOLERANCE
        assert result.decision == (None if tied else ranked[0])
        assert result.decision_state is (DecisionState.TIED if tied else DecisionState.DECIDED)


def test_no_class_information_gives_none() -> None:
    assert fuse_sensor_classes({}, {}) is None


def test_hand_worked_two_sensor_fusion() -> None:
    # s1 (λ = 1): m({bomber, fighter}) = 0.6, m(Ω) = 0.4.
    # s2 (λ = 0.5): m({liner}) = 1 → discounted: m({liner}) = 0.5, m(Ω) = 0.5.
    # Conjunctive: {b,f}∩{l} = ∅: 0.3; {b,f}: 0.3; {l}: 0.2; Ω: 0.2 → conflict 0.3.
    # Normalised by 0.7: {b,f} 3/7, {l} 2/7, Ω 2/7; BetP(liner) = 2/7 + 2/21 = 8/21.
    s1 = MassFunction.from_sets(CLASSES, [(["bomber", "fighter"], 0.6), (CLASSES.labels, 0.4)])
    s2 = MassFunction.from_sets(CLASSES, [(["liner"], 1.0)])
    result = fuse_sensor_classes({"s1": s1, "s2": s2}, {"s1": 1.0, "s2": 0.5})
    assert result is not None and result.mass is not None
    assert result.conflict == pytest.approx(0.3)
    assert result.mass.mass(["bomber", "fighter"]) == pytest.approx(3 / 7)
    assert_allclose(result.pignistic, [8 / 21, 13 / 42, 13 / 42])
    assert result.decision == "liner"
    assert result.decision_state is DecisionState.DECIDED


def test_a_tie_decides_nothing() -> None:
    # [T2T]/README example: radar-1 (λ = 0.9) says m({bomber, fighter}) = 0.6, m(Ω) = 0.4.
    # Discounted: {b,f} 0.54, Ω 0.46. BetP(bomber) = BetP(fighter) = 0.54/2 + 0.46/3
    # = 0.42333…, BetP(liner) = 0.46/3 = 0.15333…: a tie at the top.
    radar = MassFunction.from_sets(CLASSES, [(["bomber", "fighter"], 0.6), (CLASSES.labels, 0.4)])
    result = fuse_sensor_classes({"radar-1": radar}, {"radar-1": 0.9})
    assert result is not None
    assert_allclose(result.pignistic, [0.46 / 3, 0.27 + 0.46 / 3, 0.27 + 0.46 / 3], atol=1e-12)
    assert result.decision is None
    assert result.decision_state is DecisionState.TIED
    # One more sensor leaning to the fighter breaks the tie.
    fighter = MassFunction.from_sets(CLASSES, [(["fighter"], 0.1), (CLASSES.labels, 0.9)])
    broken = fuse_sensor_classes(
        {"radar-1": radar, "radar-2": fighter}, {"radar-1": 0.9, "radar-2": 1.0}
    )
    assert broken is not None
    assert broken.decision == "fighter" and broken.decision_state is DecisionState.DECIDED


def test_total_conflict_between_certain_sensors_is_a_state_not_an_error() -> None:
    liner = MassFunction.from_sets(CLASSES, [(["liner"], 1.0)])
    fighter = MassFunction.from_sets(CLASSES, [(["fighter"], 1.0)])
    result = fuse_sensor_classes({"a": liner, "b": fighter}, {"a": 1.0, "b": 1.0})
    assert result is not None
    assert result.state is ClassState.TOTAL_CONFLICT
    assert result.conflict == 1.0 and result.decision is None
    assert result.decision_state is DecisionState.UNDEFINED


def test_likelihood_accumulation_equals_pyds_gbt_and_dempster() -> None:
    steps = [np.array([0.2, 0.7, 0.9]), np.array([0.1, 0.8, 0.6]), np.array([0.3, 0.3, 1.0])]
    mass = None
    reference = None
    for likelihoods in steps:
        mass, step_conflict = accumulate_likelihoods(mass, CLASSES, likelihoods)
        gbt = pyds.MassFunction.gbt(
            dict(zip(CLASSES.labels, likelihoods, strict=True)), normalization=False
        )
        unnormalised = (
            gbt if reference is None else reference.combine_conjunctive(gbt, normalization=False)
        )
        assert step_conflict == pytest.approx(unnormalised[frozenset()], abs=1e-12)
        reference = unnormalised.normalize()
    assert mass is not None and reference is not None
    for labels, value in mass.focal_sets():
        assert value == pytest.approx(reference[frozenset(labels)], abs=1e-12)


def test_likelihoods_contradicting_a_certain_mass_are_total_conflict() -> None:
    certain = MassFunction.from_sets(CLASSES, [(["liner"], 1.0)])
    with pytest.raises(TotalConflict):
        accumulate_likelihoods(certain, CLASSES, np.array([0.0, 1.0, 1.0]))
