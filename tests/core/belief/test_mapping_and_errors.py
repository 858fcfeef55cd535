"""The multi-valued mapping of [MTT] §5.2.1 and the documented errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_array_equal

from core.belief import (
    MAX_FRAME_SIZE,
    Frame,
    FrameError,
    MassError,
    MassFunction,
    Relation,
    TotalConflict,
    dempster,
)
from core.errors import InvalidInput

from .strategies import mass_functions

BEHAVIOURS = Frame(["b1", "b2", "b3"])

# [MTT] §6.1.2, printed matrix M̄ (rows: class subsets, columns: behaviour subsets,
# both in binary order ∅, {1}, {2}, {1,2}, {3}, {1,3}, {2,3}, {1,2,3}).
AIRCRAFT_MATRIX = np.array(
    [
        [1, 0, 0, 0, 0, 0, 0, 0],
        [0, 0, 0, 0, 0, 0, 0, 0],
        [0, 0, 0, 0, 0, 0, 0, 0],
        [0, 0, 0, 0, 0, 0, 0, 0],
        [0, 0, 0, 0, 1, 0, 0, 0],
        [0, 0, 0, 0, 0, 0, 0, 0],
        [0, 0, 1, 0, 0, 0, 1, 0],
        [0, 1, 0, 1, 0, 1, 0, 1],
    ]
)
# [MTT] §6.3.2, printed 4 × 8 matrix M̄ for the pedestrians.
PEDESTRIAN_MATRIX = np.array(
    [
        [1, 0, 0, 0, 0, 0, 0, 0],
        [0, 1, 0, 0, 0, 0, 0, 0],
        [0, 0, 0, 0, 1, 0, 0, 0],
        [0, 0, 1, 1, 0, 1, 1, 1],
    ]
)


def aircraft_relation() -> Relation:
    classes = Frame(["liner", "bomber", "fighter"])
    return Relation.from_mapping(
        BEHAVIOURS,
        classes,
        {"b1": ["liner", "bomber", "fighter"], "b2": ["bomber", "fighter"], "b3": ["fighter"]},
    )


def pedestrian_relation() -> Relation:
    classes = Frame(["rambler", "sportsman"])
    return Relation.from_mapping(
        BEHAVIOURS,
        classes,
        {"b1": ["rambler"], "b2": ["rambler", "sportsman"], "b3": ["sportsman"]},
    )


def test_aircraft_matrix_is_reproduced_exactly() -> None:
    assert_array_equal(aircraft_relation().matrix(), AIRCRAFT_MATRIX)


def test_pedestrian_matrix_is_reproduced_exactly() -> None:
    assert_array_equal(pedestrian_relation().matrix(), PEDESTRIAN_MATRIX)


@given(mass_functions(BEHAVIOURS, allow_empty=True, max_focal=8))
@settings(max_examples=100)
def test_transfer_equals_the_matrix_product_of_eq_23(mass: MassFunction) -> None:
    relation = aircraft_relation()
    dense = np.zeros(8)
    dense[mass.masks] = mass.masses
    expected = relation.matrix() @ dense  # m^C = M̄ m^B
    result = relation.transfer(mass)
    got = np.zeros(8)
    got[result.masks] = result.masses
    np.testing.assert_allclose(got, expected, atol=1e-15)


def test_hand_worked_transfer() -> None:
    # m^B({b2}) = 0.6, m^B({b1, b3}) = 0.4 → m^C({bomber, fighter}) = 0.6, m^C(Ω) = 0.4.
    relation = aircraft_relation()
    mass = MassFunction.from_sets(BEHAVIOURS, [(["b2"], 0.6), (["b1", "b3"], 0.4)])
    result = relation.transfer(mass)
    assert result.mass(["bomber", "fighter"]) == pytest.approx(0.6)
    assert result.mass(["liner", "bomber", "fighter"]) == pytest.approx(0.4)
    assert len(result) == 2


@pytest.mark.parametrize(
    ("labels", "message"),
    [
        ([], "frame is empty"),
        (["a", "b", "a"], "duplicate labels: \\['a'\\]"),
        ([f"c{i}" for i in range(MAX_FRAME_SIZE + 1)], "21 labels, more than the limit 20"),
        (["a", ""], "not a non-empty string"),
    ],
)
def test_invalid_frames_are_rejected(labels: list[str], message: str) -> None:
    with pytest.raises(FrameError, match=message):
        Frame(labels)


FRAME = Frame(["liner", "bomber", "fighter"])


@pytest.mark.parametrize(
    ("focal_sets", "error", "message"),
    [
        ([(["liner"], -0.1), (["bomber"], 1.1)], MassError, "\\['liner'\\] is negative"),
        ([(["liner"], float("nan")), (["bomber"], 1.0)], MassError, "\\['liner'\\] is not finite"),
        ([(["liner"], float("inf"))], MassError, "is not finite"),
        ([(["liner"], 0.5), (["bomber"], 0.4)], MassError, "sum to 0.9.*not 1"),
        ([(["submarine"], 1.0)], FrameError, "'submarine' is not in the frame"),
        ([(["liner"], 0.5), (["liner"], 0.5)], MassError, "focal sets repeat: \\[\\['liner'\\]\\]"),
        ([], MassError, "at least one focal set"),
    ],
)
def test_invalid_mass_functions_are_rejected(
    focal_sets: list[tuple[list[str], float]], error: type[Exception], message: str
) -> None:
    with pytest.raises(error, match=message):
        MassFunction.from_sets(FRAME, focal_sets)


def test_every_input_error_is_a_value_error_and_invalid_input() -> None:
    for error in (FrameError, MassError):
        assert issubclass(error, InvalidInput)
        assert issubclass(error, ValueError)


def test_mask_outside_frame_is_rejected() -> None:
    with pytest.raises(FrameError, match="mask 8 is outside the frame of 3 labels"):
        MassFunction.from_masks(FRAME, [8], [1.0])


@pytest.mark.parametrize("reliability", [-0.1, 1.5, float("nan")])
def test_discount_rejects_reliability_outside_unit_interval(reliability: float) -> None:
    with pytest.raises(MassError, match="reliability must be in \\[0, 1\\]"):
        MassFunction.vacuous(FRAME).discount(reliability)


def test_dempster_total_conflict_is_typed_and_carries_the_conflict() -> None:
    liner = MassFunction.from_sets(FRAME, [(["liner"], 1.0)])
    fighter = MassFunction.from_sets(FRAME, [(["fighter"], 1.0)])
    with pytest.raises(TotalConflict) as caught:
        dempster(liner, fighter)
    assert caught.value.conflict == 1.0


def test_pignistic_is_undefined_on_all_empty_mass() -> None:
    empty = MassFunction.from_masks(FRAME, [0], [1.0])
    assert empty.pignistic() is None
    with pytest.raises(TotalConflict):
        empty.normalized()


def test_relation_errors_name_the_problem() -> None:
    with pytest.raises(FrameError, match="no image for 'b3'"):
        Relation.from_mapping(BEHAVIOURS, FRAME, {"b1": ["liner"], "b2": ["bomber"]})
    with pytest.raises(FrameError, match="outside the source frame: \\['b9'\\]"):
        Relation.from_mapping(BEHAVIOURS, FRAME, {"b1": [], "b2": [], "b3": [], "b9": []})
    with pytest.raises(FrameError, match="maps 'b1' to the empty set"):
        Relation.from_mapping(BEHAVIOURS, FRAME, {"b1": [], "b2": ["liner"], "b3": ["liner"]})


@given(st.integers(0, 7))
def test_frame_mask_round_trip(mask: int) -> None:
    assert FRAME.mask(FRAME.subset(mask)) == mask


def test_plausibility_never_exceeds_one_when_the_masses_round_above_it() -> None:
    # Four masses drawn from a Dirichlet whose float64 sum is 1 + 2⁻⁵² (a whole-mass
    # sum, as a fused class mass has; AVX-512 kernels round other sums this way).
    masses = [0.5017535083586557, 0.1583447529128556, 0.12389774916694181, 0.21600398956154693]
    assert sum(masses) > 1.0
    frame = Frame(["a", "b", "c", "d"])
    mass = MassFunction.from_sets(frame, list(zip(["a", "ab", "ac", "ad"], masses, strict=True)))
    # "a" lies in every focal set: Pl({a}) = Σ m = 1 by hand, never above it
    assert mass.singleton_plausibility()[0] == 1.0
    assert np.all(mass.singleton_plausibility() <= 1.0)
