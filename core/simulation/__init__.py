"""Seeded ground-truth scenarios with simulated detections (EVALUATION.md)."""

from core.simulation.aircraft import aircraft_scenario
from core.simulation.nearby import close_pair_scenario, crossing_scenario
from core.simulation.pedestrian import pedestrian_scenario
from core.simulation.road import accelerating_scenario, overtaking_scenario, stealing_scenario
from core.simulation.scenario import CLUTTER, Manoeuvre, Region, Scan, Scenario, TargetTruth

SCENARIOS = {
    "aircraft": aircraft_scenario,
    "pedestrian": pedestrian_scenario,
    "close-pair": close_pair_scenario,
    "crossing": crossing_scenario,
    "accelerating": accelerating_scenario,
    "overtaking": overtaking_scenario,
}
"""Scenario generators by their EVALUATION.md id; each takes ``seed`` first."""

__all__ = [
    "CLUTTER",
    "SCENARIOS",
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
    "stealing_scenario",
]
