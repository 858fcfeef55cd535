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

import pytest

from core.errors import ScenarioError, TrackingError
from core.simulation import aircraft_scenario
from core.simulation.replay import replay_single_target
from core.tracking.config import ClassificationOptions
from core.tracking.presets import aircraft


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
