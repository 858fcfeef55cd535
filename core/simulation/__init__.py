"""Seeded ground-truth scenarios with simulated detections (EVALUATION.md)."""

from collections.abc import Callable

from core.simulation.aircraft import aircraft_scenario
from core.simulation.nearby import close_pair_scenario, crossing_scenario
from core.simulation.pedestrian import pedestrian_scenario
from core.simulation.road import (
    accelerating_scenario,
    overtaking_scenario,
    road_four_scenario,
    stealing_scenario,
)
from core.simulation.scenario import CLUTTER, Manoeuvre, Region, Scan, Scenario, TargetTruth
from core.simulation.two_class import ClassifiedTrackListScenario, t2t_two_class

SCENARIOS: dict[str, Callable[..., Scenario]] = {
    "aircraft": aircraft_scenario,
    "pedestrian": pedestrian_scenario,
    "close-pair": close_pair_scenario,
    "crossing": crossing_scenario,
    "accelerating": accelerating_scenario,
    "overtaking": overtaking_scenario,
    "road-four": road_four_scenario,
}
"""Scenario generators by their EVALUATION.md id; each takes ``seed`` first.

The track-list scenarios (``t2t-four``, ``t2t-two-class``, crossing traffic)
return track lists, not detections, and are imported from their modules
(:func:`t2t_two_class` is exported here too)."""

__all__ = [
    "CLUTTER",
    "SCENARIOS",
    "ClassifiedTrackListScenario",
    "Manoeuvre",
    "Region",
    "Scan",
    "Scenario",
    "TargetTruth",
    "accelerating_scenario",
    "aircraft_scenario",
    "close_pair_scenario",
    "crossing_scenario",
    "overtaking_scenario",
    "pedestrian_scenario",
    "road_four_scenario",
    "stealing_scenario",
    "t2t_two_class",
]
