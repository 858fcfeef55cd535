"""Track-to-track and measurement-to-track association (docs/algorithms.md §3).

One module per method, each with its :class:`MethodSpec` (name, scopes,
options with defaults, default distance, ``run``), registered in one line of
:mod:`~core.association.registry` — :mod:`~core.association.gnn`,
:mod:`~core.association.denoeux`, :mod:`~core.association.hachour`,
:mod:`~core.association.mercier`, :mod:`~core.association.dang_han`,
:mod:`~core.association.cheap_jpda` (local tracking) — one result type
(:class:`AssociationResult`) and one entry point (:func:`associate`). Gated pairs only (:mod:`core.distance`); the assignment is
solved per connected cluster (:mod:`~core.association.assignment`).
"""

from core.association.assignment import Matching, max_gain_matching, solve_dense
from core.association.associate import (
    DEFAULT_DISTANCE,
    LOCAL_METHODS,
    LOCAL_TRACKING_DEFAULT,
    METHODS,
    TRACK_TO_TRACK_DEFAULT,
    associate,
    associate_measurements,
)
from core.association.cheap_jpda import JpdaWeights, cheap_jpda_weights
from core.association.classes import class_conflict
from core.association.problem import AssociationProblem
from core.association.registry import REGISTRY, method_spec, methods
from core.association.result import AssociationResult, Diagnostics, ScoreMatrix
from core.association.spec import MethodSpec

__all__ = [
    "DEFAULT_DISTANCE",
    "LOCAL_METHODS",
    "LOCAL_TRACKING_DEFAULT",
    "METHODS",
    "REGISTRY",
    "TRACK_TO_TRACK_DEFAULT",
    "AssociationProblem",
    "AssociationResult",
    "Diagnostics",
    "JpdaWeights",
    "Matching",
    "MethodSpec",
    "ScoreMatrix",
    "associate",
    "associate_measurements",
    "cheap_jpda_weights",
    "class_conflict",
    "max_gain_matching",
    "method_spec",
    "methods",
    "solve_dense",
]
