"""Keeping the cumulative mass normalised: when BetP is unchanged, and when it is not.

A brute force on dense masses over every subset (written here, independent of
``core.belief``) accumulates the pedestrian preset's step masses ([MTT] §6.3)
two ways: unnormalised (the conjunctive rule of eq 11 as written) and
normalised after every step. Without discounting, and with instantaneous
discounting, the two give the same BetP and the classifier matches them;
with cumulative discounting they differ, and the classifier is the
normalised one.
"""

from __future__ import annotations

import numpy as np
import pytest

from core.classification import CredalClassifier
from core.tracking.presets import pedestrian

GAMMA = {"static": {"rambler"}, "walking": {"rambler", "sportsman"}, "running": {"sportsman"}}
# [MTT] §6.3.2: Relation 1 (ramblers static or walking), Relation 2 (sportsmen walking or running)


def _masks(frame_labels: tuple[str, ...], labels: set[str]) -> int:
    return sum(1 << frame_labels.index(label) for label in labels)


def _gbt(plausibilities: np.ndarray) -> np.ndarray:
    n = plausibilities.size
    mass = np.ones(1 << n)
    for subset in range(1 << n):
        for k in range(n):
            p = plausibilities[k]
            mass[subset] *= p if subset >> k & 1 else 1.0 - p
    return mass


def _conjunctive(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    combined = np.zeros_like(first)
    for a in range(first.size):
        for b in range(second.size):
            combined[a & b] += first[a] * second[b]
    return combined


def _discount(mass: np.ndarray, reliability: float) -> np.ndarray:
    discounted = reliability * mass
    discounted[-1] += 1.0 - reliability
    return discounted


def _betp(mass: np.ndarray, n: int) -> np.ndarray:
    betp = np.zeros(n)
    for subset in range(1, mass.size):
        members = [k for k in range(n) if subset >> k & 1]
        for k in members:
            betp[k] += mass[subset] / len(members)
    return betp / (1.0 - mass[0])


def _brute_force(
    steps: list[np.ndarray], discount: str, reliability: float, normalise: bool
) -> np.ndarray:
    preset = pedestrian()
    behaviours = preset.behaviours.frame.labels
    classes = preset.relation.target.labels
    gamma = [_masks(classes, GAMMA[label]) for label in behaviours]
    cumulative = np.zeros(1 << len(classes))
    cumulative[-1] = 1.0  # vacuous
    for plausibilities in steps:
        on_behaviours = _gbt(plausibilities)
        step = np.zeros_like(cumulative)
        for subset, mass in enumerate(on_behaviours):
            image = 0
            for k in range(len(behaviours)):
                if subset >> k & 1:
                    image |= gamma[k]
            step[image] += mass  # [MTT] eq 23
        if discount == "instantaneous":
            step = _discount(step, reliability)
        elif discount == "cumulative":
            cumulative = _discount(cumulative, reliability)
        cumulative = _conjunctive(cumulative, step)
        if normalise:
            cumulative[1:] /= 1.0 - cumulative[0]
            cumulative[0] = 0.0
    return _betp(cumulative, len(classes))


def _steps() -> list[np.ndarray]:
    """Walking, running, then standing still: the class changes and the steps conflict."""
    rng = np.random.default_rng(7)
    order = ["walking"] * 3 + ["running"] * 4 + ["static"] * 4
    labels = pedestrian().behaviours.frame.labels
    steps = []
    for behaviour in order:
        plausibilities = rng.uniform(0.05, 0.5, size=len(labels))
        plausibilities[labels.index(behaviour)] = 1.0  # the "max" likelihood scale
        steps.append(plausibilities)
    return steps


def _classified(discount: str, reliability: float) -> np.ndarray:
    preset = pedestrian()
    classifier = CredalClassifier(
        preset.behaviours, preset.relation, discount=discount, reliability=reliability
    )
    state = classifier.initial()
    for plausibilities in _steps():
        state = classifier.combine(state, classifier.step_mass(plausibilities))
    assert state.pignistic is not None
    return state.pignistic


@pytest.mark.parametrize(("discount", "reliability"), [("none", 1.0), ("instantaneous", 0.3)])
def test_normalising_each_step_leaves_betp_unchanged_without_cumulative_discounting(
    discount: str, reliability: float
) -> None:
    raw = _brute_force(_steps(), discount, reliability, normalise=False)
    normalised = _brute_force(_steps(), discount, reliability, normalise=True)
    np.testing.assert_allclose(normalised, raw, rtol=1e-12)
    np.testing.assert_allclose(_classified(discount, reliability), raw, rtol=1e-12)


def test_with_cumulative_discounting_normalising_each_step_changes_betp() -> None:
    raw = _brute_force(_steps(), "cumulative", 0.9, normalise=False)
    normalised = _brute_force(_steps(), "cumulative", 0.9, normalise=True)
    assert np.max(np.abs(normalised - raw)) > 1e-3  # far above rounding: they really differ
    np.testing.assert_allclose(_classified("cumulative", 0.9), normalised, rtol=1e-12)
