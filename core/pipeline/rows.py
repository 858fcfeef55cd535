"""The rows of a tracking layer: each track's number and life (docs/algorithms.md §7.3).

Both layers keep their tracks as rows of arrays: the local tracker's IMM
state, the engine's estimate table, and, aligned with them, a
:class:`TrackRows` of numbers (the integer of the id) and the
:class:`~core.lifecycle.LifeState`. New tracks are appended with fresh
numbers; the rows terminated in a step are dropped at its end. Never changed
in place: every operation returns new rows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.arrays import BoolArray, IntArray
from core.lifecycle import TERMINATED, LifeState


@dataclass(frozen=True)
class TrackRows:
    """Numbers (n,) and lives of n tracks, row for row."""

    numbers: IntArray
    life: LifeState

    @classmethod
    def empty(cls) -> TrackRows:
        return cls(np.zeros(0, dtype=np.int64), LifeState.empty())

    def __len__(self) -> int:
        return len(self.numbers)

    def select(self, rows: IntArray) -> TrackRows:
        return TrackRows(self.numbers[rows], self.life.select(rows))

    def living(self, life: LifeState) -> TrackRows:
        """The same rows with the life ``life``."""
        return TrackRows(self.numbers, life)

    def started(self, first_number: int, life: LifeState) -> TrackRows:
        """These rows and ``len(life)`` new ones numbered from ``first_number``."""
        numbers = np.arange(first_number, first_number + len(life), dtype=np.int64)
        return TrackRows(np.concatenate([self.numbers, numbers]), self.life.concatenate(life))

    @property
    def alive(self) -> IntArray:
        """Rows not terminated, in order (what a step keeps)."""
        return np.flatnonzero(self.life.status != TERMINATED)


def ended(before: LifeState, after: LifeState) -> BoolArray:
    """Rows that a step terminated (``after`` of the same rows as ``before``)."""
    return np.asarray((after.status == TERMINATED) & (before.status != TERMINATED), dtype=bool)
