"""Class information flips a wrong distance-only decision (the point of [T2T] Fig 6)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.association import associate, class_conflict
from core.belief import Frame, MassFunction
from core.errors import InvalidInput

FRAME = Frame(["liner", "bomber", "fighter"])


def mass(*focal):
    return MassFunction.from_sets(FRAME, focal)


FIGHTER = mass((["fighter"], 0.9), (FRAME.labels, 0.1))
LINER = mass((["liner"], 0.9), (FRAME.labels, 0.1))


def scene():
    """Two known tracks, one incoming track between them, nearer the wrong one.

    1-D, variances 0.125 on both sides (C = 0.25): k0 (liner) at 0, k1 (fighter) at 0.8,
    the incoming track (a fighter) at 0.35: D(k0) = 0.49, D(k1) = 0.81.
    Distance alone picks k0; K(fighter, liner) = 0.9·0.9 = 0.81 is evidence against it.
    hachour density: G = e^{−D/2}/sqrt(2π·0.25): G(k0) = 0.6239, G(k1) = 0.5316 (no clipping);
    with classes Pl(k0) = 0.6239·0.19 = 0.1185, Pl(*) = 1 − 0.6239 (the distances' own, §3.6)
    and k1 wins (0.5316 > 0.3761).
    """
    known = (np.array([[0.0], [0.8]]), np.full((2, 1, 1), 0.125))
    incoming = (np.array([[0.35]]), np.full((1, 1, 1), 0.125))
    return known, incoming, [LINER, FIGHTER], [FIGHTER]


def test_conflict_per_pair():
    # K(fighter-ish, liner-ish) = m1({fighter}) m2({liner}) = 0.81; with itself 0
    k = class_conflict([LINER, FIGHTER], [FIGHTER], np.array([0, 1]), np.array([0, 0]))
    np.testing.assert_allclose(k, [0.81, 0.0])


@pytest.mark.parametrize(
    ("method", "options"),
    [
        ("denoeux", {"gamma": math.log(2) / 4.0}),
        ("hachour", {}),
        ("hachour", {"likelihood": "relative"}),
        ("mercier", {}),
        ("dang_han", {}),
    ],
)
def test_classes_flip_the_decision(method, options):
    known, incoming, known_classes, incoming_classes = scene()
    without = associate(known, incoming, method, options)
    assert without.assignment() == {0: 0}  # distance only: the nearer, wrong track
    assert not without.diagnostics.clipped.any()
    assert not without.diagnostics.uses_classes
    with_classes = associate(
        known,
        incoming,
        method,
        options,
        known_classes=known_classes,
        incoming_classes=incoming_classes,
    )
    assert with_classes.assignment() == {1: 0}
    assert with_classes.diagnostics.uses_classes


def test_denoeux_adds_log_class_plausibility():
    # w(k0) = −γD − ln(1 − e^{−γD}) + ln(1 − 0.81), γ = ln2/4, D = 0.49
    known, incoming, known_classes, incoming_classes = scene()
    gamma = math.log(2) / 4.0
    result = associate(
        known,
        incoming,
        "denoeux",
        {"gamma": gamma},
        known_classes=known_classes,
        incoming_classes=incoming_classes,
    )
    d = 0.49
    expected = -gamma * d - math.log(1 - math.exp(-gamma * d)) + math.log(0.19)
    assert result.scores.dense()[0, 0] == pytest.approx(expected, rel=1e-9)


def test_gnn_reports_it_cannot_use_classes():
    known, incoming, known_classes, incoming_classes = scene()
    result = associate(
        known, incoming, "gnn", known_classes=known_classes, incoming_classes=incoming_classes
    )
    assert result.assignment() == {0: 0}
    assert result.diagnostics.classes_ignored
    assert not result.diagnostics.uses_classes
    assert "cannot use class" in result.diagnostics.notes[0]


def test_class_errors():
    known, incoming, known_classes, incoming_classes = scene()
    with pytest.raises(InvalidInput, match="both sides"):
        associate(known, incoming, "hachour", known_classes=known_classes)
    with pytest.raises(InvalidInput, match="one mass function per item"):
        associate(
            known,
            incoming,
            "hachour",
            known_classes=known_classes[:1],
            incoming_classes=incoming_classes,
        )
    other = MassFunction.vacuous(Frame(["a", "b"]))
    with pytest.raises(InvalidInput, match="same class frame"):
        associate(known, incoming, "hachour", known_classes=known_classes, incoming_classes=[other])


@pytest.mark.parametrize(
    ("method", "options"),
    [
        ("denoeux", {}),
        ("hachour", {}),
        ("mercier", {"alpha": 1.0}),
        ("dang_han", {"alpha": 1.0}),
        ("dang_han", {"alpha": 1.0, "score": "betp"}),
    ],
)
def test_total_class_conflict_vetoes_a_perfect_kinematic_match(method, options):
    # identical states (D = 0; with α = 1 the pairwise source is certain: a = 1) but
    # certain, disjoint classes: K = 1, pl_class = 0. Dempster's rule is undefined for
    # that pair (aK = 1): the class veto wins and nothing is matched.
    certain_fighter = mass((["fighter"], 1.0))
    certain_liner = mass((["liner"], 1.0))
    state = (np.zeros((1, 1)), np.full((1, 1, 1), 0.01))
    result = associate(
        state,
        state,
        method,
        options,
        known_classes=[certain_liner],
        incoming_classes=[certain_fighter],
    )
    assert result.pairs == []
    same = associate(
        state,
        state,
        method,
        options,
        known_classes=[certain_liner],
        incoming_classes=[certain_liner],
    )
    assert same.assignment() == {0: 0}
