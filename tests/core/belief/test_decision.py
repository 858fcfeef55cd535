"""The pignistic decision: a class, a tie, or nothing to decide on."""

from __future__ import annotations

import numpy as np

from core.belief import TIE_TOLERANCE, DecisionState, pignistic_decision

LABELS = ("liner", "bomber", "fighter")


def test_a_clear_maximum_is_decided() -> None:
    assert pignistic_decision(LABELS, np.array([0.2, 0.3, 0.5])) == (
        "fighter",
        DecisionState.DECIDED,
    )


def test_top_values_within_the_tolerance_are_tied_wherever_they_sit() -> None:
    near = 0.4 + TIE_TOLERANCE / 2
    for betp in ([0.4, near, 0.2 - TIE_TOLERANCE / 2], [near, 0.2 - TIE_TOLERANCE / 2, 0.4]):
        assert pignistic_decision(LABELS, np.array(betp)) == (None, DecisionState.TIED)
    third = 1 / 3
    assert pignistic_decision(LABELS, np.array([third, third, third])) == (
        None,
        DecisionState.TIED,
    )


def test_a_lead_just_beyond_the_tolerance_decides() -> None:
    lead = 3 * TIE_TOLERANCE
    assert pignistic_decision(LABELS, np.array([0.3, 0.35 + lead, 0.35 - lead])) == (
        "bomber",
        DecisionState.DECIDED,
    )


def test_no_betp_is_undefined() -> None:
    assert pignistic_decision(LABELS, None) == (None, DecisionState.UNDEFINED)
