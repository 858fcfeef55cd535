"""Class evidence carried by a sensor track or a detection.

A sensor reports either a mass function over the session's class frame
(``mass``: focal sets with their masses, summing to 1) or class likelihoods
(``likelihoods``: one value in [0, 1] per label, one step of evidence that the
service turns into a mass with the Generalized Bayesian Theorem).
"""

from __future__ import annotations

import math
from typing import Annotated, Self

from pydantic import Field, model_validator

from api_schemas.base import MAX_CLASSES, Label, UnitFloat, WireModel
from api_schemas.limits import MAX_FOCAL_SETS, bounded

MASS_SUM_TOLERANCE = 1e-9
"""Masses must sum to 1 within this tolerance (docs/algorithms.md §1)."""

FocalSetLabels = Annotated[list[Label], Field(min_length=1, max_length=MAX_CLASSES)]


class FocalMass(WireModel):
    """One focal set (a list of class labels) with its mass."""

    set: FocalSetLabels
    mass: UnitFloat

    @model_validator(mode="after")
    def _distinct_labels(self) -> Self:
        if len(set(self.set)) != len(self.set):
            raise ValueError(f"focal set {self.set} names a label twice")
        return self


class ClassEvidence(WireModel):
    """Class evidence: exactly one of ``mass`` or ``likelihoods``."""

    mass: (
        Annotated[
            list[FocalMass],
            Field(min_length=1, max_length=MAX_FOCAL_SETS),
            bounded("max_focal_sets", "focal sets"),
        ]
        | None
    ) = None
    likelihoods: (
        Annotated[dict[Label, UnitFloat], Field(min_length=1, max_length=MAX_CLASSES)] | None
    ) = None

    @model_validator(mode="after")
    def _one_kind_of_evidence(self) -> Self:
        if (self.mass is None) == (self.likelihoods is None):
            raise ValueError("give exactly one of 'mass' or 'likelihoods'")
        if self.mass is not None:
            seen: set[frozenset[str]] = set()
            for focal in self.mass:
                key = frozenset(focal.set)
                if key in seen:
                    raise ValueError(f"focal set {sorted(key)} appears twice in 'mass'")
                seen.add(key)
            total = math.fsum(focal.mass for focal in self.mass)
            if abs(total - 1.0) > MASS_SUM_TOLERANCE:
                raise ValueError(
                    f"masses sum to {total!r}, not 1 (tolerance {MASS_SUM_TOLERANCE:g})"
                )
        return self

    def labels(self) -> set[str]:
        """Every class label this evidence names."""
        if self.mass is not None:
            return {label for focal in self.mass for label in focal.set}
        return set(self.likelihoods or {})
