"""Combination rules ([MTT] §2.2, eq 5-6).

All rules work on the sparse focal sets: the cost is the product of the
numbers of focal sets, never 2^|Ω|.
"""

from __future__ import annotations

from functools import reduce

import numpy as np

from core.belief.mass import MassFunction
from core.errors import FrameError


def _check_same_frame(first: MassFunction, second: MassFunction) -> None:
    if first.frame != second.frame:
        raise FrameError(
            f"mass functions are on different frames: {list(first.frame.labels)} "
            f"vs {list(second.frame.labels)}"
        )


def conjunctive(first: MassFunction, second: MassFunction) -> MassFunction:
    """Unnormalised conjunctive rule of the TBM ([MTT] eq 5).

    ``m(A) = Σ_{B ∩ C = A} m₁(B) m₂(C)``; the mass that lands on ∅ is the
    conflict between the two sources.
    """
    _check_same_frame(first, second)
    masks = np.bitwise_and.outer(first.masks, second.masks).ravel()
    masses = np.multiply.outer(first.masses, second.masses).ravel()
    return MassFunction.aggregate(first.frame, masks, masses)


def dempster(first: MassFunction, second: MassFunction) -> MassFunction:
    """Dempster's rule: the conjunctive rule, normalised ([MTT] eq 6).

    Raises
    ------
    TotalConflict
        When the sources are in total conflict.
    """
    return conjunctive(first, second).normalized()


def conjunctive_all(*sources: MassFunction) -> MassFunction:
    """Conjunctive combination of one or more sources (the rule is associative)."""
    if not sources:
        raise ValueError("conjunctive_all needs at least one mass function")
    return reduce(conjunctive, sources)


def conflict(first: MassFunction, second: MassFunction) -> float:
    """K = (m₁ ∩ m₂)(∅), without building the combination ([T2T] §2)."""
    _check_same_frame(first, second)
    disjoint = np.bitwise_and.outer(first.masks, second.masks) == 0
    return float(np.sum(np.multiply.outer(first.masses, second.masses)[disjoint]))
