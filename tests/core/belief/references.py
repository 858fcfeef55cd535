"""Adapters to the two independent reference libraries, pybelief and pyds.

Conventions differ (see the docstrings); every conversion is spelled out here
so that the tests compare like with like.
"""

from __future__ import annotations

import pyds
from pybelief import MassFunction as PyBeliefMass

from core.belief import MassFunction


def to_pybelief(mass: MassFunction) -> PyBeliefMass:
    """Same frame order and bit masks: pybelief stores ``{mask: mass}``."""
    return PyBeliefMass(
        mass.frame.labels,
        {int(k): float(v) for k, v in zip(mass.masks, mass.masses, strict=True)},
    )


def to_pyds(mass: MassFunction) -> pyds.MassFunction:
    """pyds keys are frozensets of labels; it has no explicit frame."""
    return pyds.MassFunction({frozenset(labels): value for labels, value in mass.focal_sets()})


def all_subsets(mass: MassFunction) -> list[tuple[str, ...]]:
    return [mass.frame.subset(mask) for mask in range(mass.frame.full + 1)]
