"""Seeded ground-truth scenarios with simulated detections (EVALUATION.md)."""

from core.simulation.aircraft import aircraft_scenario
from core.simulation.pedestrian import pedestrian_scenario
from core.simulation.scenario import CLUTTER, Manoeuvre, Scan, Scenario, TargetTruth

__all__ = [
    "CLUTTER",
    "Manoeuvre",
    "Scan",
    "Scenario",
    "TargetTruth",
    "aircraft_scenario",
    "pedestrian_scenario",
]
