"""Both readings of [MTT] §5.1.1's μ_j, worked by hand on straight flight.

In straight flight the manoeuvre models' likelihoods are negligible next to
the constant-velocity model's (Λ_j/Λ₁ < 1e-9 at σ² = 0.2 m²), so:

- ``"updated"`` μ (the posterior, ≈ (1, 0, …, 0)): Pl(b) = Λ₁ for every nested
  behaviour, scaled (1, 1, 1) — no behaviour is preferred;
- ``"predicted"`` μ̄ (the prior after mixing with the 0.95-diagonal
  transitions from μ ≈ (1, 0, …)): μ̄₁ = 0.95, every other μ̄_j = 0.05/12, so
  Pl(b2)/Pl(b1) = 0.95 / (0.95 + 4·0.05/12) = 0.982759 and
  Pl(b3)/Pl(b1) = 0.95 / (0.95 + 12·0.05/12) = 0.95 — the "slightly more
  important" b1 of [MTT] Fig 12.
"""

from __future__ import annotations

import numpy as np
import pytest

from core.errors import ScenarioError, TrackingError
from core.simulation import aircraft_scenario
from core.simulation.replay import replay_single_target
from core.tracking.config import ClassificationOptions, LocalTrackerConfig
from core.tracking.imm import IMMUpdater
from core.tracking.presets import aircraft
from core.tracking.tracker import LocalTracker


@pytest.mark.parametrize(
    ("reading", "expected"),
    [("updated", (1.0, 1.0, 1.0)), ("predicted", (1.0, 0.95 / (0.95 + 4 * 0.05 / 12), 0.95))],
)
def test_straight_flight_behaviour_plausibilities(reading, expected) -> None:
    replay = replay_single_target(
        aircraft_scenario(seed=3), 2, aircraft(), mode_probabilities=reading
    )
    for step in (20, 40):  # before the first manoeuvre (50)
        assert replay.behaviour_plausibilities[replay.index(step)] == pytest.approx(
            expected, abs=1e-6
        )


def test_unknown_reading_is_refused() -> None:
    with pytest.raises(ScenarioError, match="mode_probabilities"):
        replay_single_target(aircraft_scenario(seed=0), 2, aircraft(), mode_probabilities="mixed")  # type: ignore[arg-type]
    with pytest.raises(TrackingError, match="mode_probabilities"):
        ClassificationOptions(mode_probabilities="mixed")  # type: ignore[arg-type]


@pytest.mark.parametrize("reading", ["updated", "predicted"])
def test_the_tracker_classifies_with_the_mu_of_its_reading(
    reading: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The local tracker hands its classifier the step's posterior μ or its prior c̄.

    Spied: the prior of each scan is what the IMM predictor returns, the
    posterior what the updater returns; the classifier must receive the one
    its ``mode_probabilities`` names (one target: every track is a candidate).
    """
    scenario = aircraft_scenario(seed=1, n_steps=12)
    config = LocalTrackerConfig(
        classification=ClassificationOptions(mode_probabilities=reading),  # type: ignore[arg-type]
        fields_of_view={"radar": None},
    )
    tracker = LocalTracker(config)
    assert tracker.classifier is not None
    priors: list[np.ndarray] = []
    posteriors: list[np.ndarray] = []
    given: list[np.ndarray] = []
    predict, update = tracker.predictor.predict, IMMUpdater.update
    classify = tracker.classifier.update

    def spy_predict(*args, **kwargs):
        found = predict(*args, **kwargs)
        priors.append(found.log_mode_probabilities.copy())
        return found

    def spy_update(self, *args, **kwargs):
        found = update(self, *args, **kwargs)
        posteriors.append(found.state.log_mode_probabilities.copy())
        return found

    def spy_classify(batch, log_mu, *args, **kwargs):
        given.append(np.array(log_mu, copy=True))
        return classify(batch, log_mu, *args, **kwargs)

    monkeypatch.setattr(tracker.predictor, "predict", spy_predict)
    monkeypatch.setattr(tracker.classifier, "update", spy_classify)
    monkeypatch.setattr(IMMUpdater, "update", spy_update)
    for scan in scenario.scans:
        keep = scan.target_ids == 1  # one target: its track is every candidate
        tracker.step(scan.time, scan.measurements[keep])
    assert len(given) >= 5
    reference = priors if reading == "predicted" else posteriors
    for passed in given:
        assert any(
            candidate.shape == passed.shape and np.array_equal(candidate, passed)
            for candidate in reference
        )
    other = posteriors if reading == "predicted" else priors
    assert not all(any(c.shape == p.shape and np.array_equal(c, p) for c in other) for p in given)
