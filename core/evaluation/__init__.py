"""The papers' experiments, reproduced on the core (EVALUATION.md, issue 7).

One module per experiment, each a function of sizes and seeds returning
plain result data (numpy arrays in frozen dataclasses), so that tests run
them reduced and :mod:`core.evaluation.figures` draws them full size:

- :mod:`~core.evaluation.four_targets` — [T2T] Fig 4, false decisions vs λ / γ;
- :mod:`~core.evaluation.two_class` — [T2T] Fig 6, distance only vs distance + class;
- :mod:`~core.evaluation.aircraft` — [MTT] Fig 12–15, credal vs Bayesian classification;
- :mod:`~core.evaluation.pedestrian` — [MTT] Fig 20–23, discounting for changing classes;
- :mod:`~core.evaluation.units` — is the "parameterless" ``hachour`` unit-free?
- :mod:`~core.evaluation.pairing` — the track-to-track problems and their false decision rate;
- :mod:`~core.evaluation.close_pair` — [MTT] Fig 16, false assignments of two close targets;
- :mod:`~core.evaluation.crossing` — [MTT] Fig 17–18, a fighter crosses an unknown aircraft;
- :mod:`~core.evaluation.road_four` — [DH] Fig 1–5, RMS errors vs cheap JPDA in clutter;
- :mod:`~core.evaluation.accelerating` — [HZ] Fig 5, modified distance and termination;
- :mod:`~core.evaluation.overtaking` — [HZ] Fig 6, phantoms through a blind zone;
- :mod:`~core.evaluation.tracking` — running the local tracker over a scenario (shared).

The figures module (matplotlib) is not imported here: ``from
core.evaluation.figures import FIGURES, reproduce``.
"""

from core.evaluation.aircraft import AircraftClassification, aircraft_classification
from core.evaluation.four_targets import ThresholdSweep, threshold_sweep
from core.evaluation.pairing import ListPair, decision_error_rate, list_pairs, partially_observed
from core.evaluation.pedestrian import (
    ClassTrace,
    PedestrianClassification,
    pedestrian_classification,
)
from core.evaluation.two_class import ClassComparison, class_comparison
from core.evaluation.units import NoiseStudy, UnitSweep, noise_study, unit_sweep

__all__ = [
    "AircraftClassification",
    "ClassComparison",
    "ClassTrace",
    "ListPair",
    "NoiseStudy",
    "PedestrianClassification",
    "ThresholdSweep",
    "UnitSweep",
    "aircraft_classification",
    "class_comparison",
    "decision_error_rate",
    "list_pairs",
    "noise_study",
    "partially_observed",
    "pedestrian_classification",
    "threshold_sweep",
    "unit_sweep",
]
