"""Frames of discernment and subsets as bit masks.

A frame is an ordered tuple of distinct labels; a subset is an integer bit mask
over that order (bit ``i`` set means label ``i`` is in the subset), as
docs/algorithms.md §1 fixes.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from core.arrays import BoolArray, IntArray
from core.errors import FrameError

MAX_FRAME_SIZE = 20
"""Largest frame a mass function may be defined on (class and behaviour frames).

Association frames can be far larger; they are never materialised as mass
functions, only handled by the closed forms of :mod:`core.belief.gbt`.
"""


@dataclass(frozen=True)
class Frame:
    """An ordered frame of discernment.

    Parameters
    ----------
    labels : sequence of str
        Distinct, non-empty labels; at most :data:`MAX_FRAME_SIZE` of them.

    Raises
    ------
    FrameError
        If the frame is empty, too large, or has duplicate or empty labels.
    """

    labels: tuple[str, ...]
    _index: dict[str, int] = field(init=False, repr=False, compare=False)

    def __init__(self, labels: Sequence[str]) -> None:
        labels = tuple(labels)
        if not labels:
            raise FrameError("frame is empty: give at least one label")
        if len(labels) > MAX_FRAME_SIZE:
            raise FrameError(
                f"frame has {len(labels)} labels, more than the limit {MAX_FRAME_SIZE}"
            )
        for label in labels:
            if not isinstance(label, str) or not label:
                raise FrameError(f"frame label {label!r} is not a non-empty string")
        duplicates = sorted({label for label in labels if labels.count(label) > 1})
        if duplicates:
            raise FrameError(f"frame has duplicate labels: {duplicates}")
        object.__setattr__(self, "labels", labels)
        object.__setattr__(self, "_index", {label: i for i, label in enumerate(labels)})

    def __len__(self) -> int:
        return len(self.labels)

    @property
    def full(self) -> int:
        """The mask of the whole frame Ω."""
        return (1 << len(self.labels)) - 1

    def index(self, label: str) -> int:
        """Position of ``label`` in the frame."""
        try:
            return self._index[label]
        except KeyError:
            raise FrameError(f"label {label!r} is not in the frame {list(self.labels)}") from None

    def mask(self, labels: Iterable[str]) -> int:
        """Bit mask of a set of labels (the empty iterable gives ∅ = 0)."""
        mask = 0
        for label in labels:
            mask |= 1 << self.index(label)
        return mask

    def subset(self, mask: int) -> tuple[str, ...]:
        """Labels of a mask, in frame order."""
        self.check_mask(mask)
        return tuple(label for i, label in enumerate(self.labels) if mask >> i & 1)

    def check_mask(self, mask: int) -> None:
        """Raise :class:`FrameError` unless ``mask`` is a subset of the frame."""
        if mask < 0 or mask > self.full:
            raise FrameError(f"subset mask {mask} is outside the frame of {len(self)} labels")

    def bits(self, masks: IntArray) -> BoolArray:
        """Membership matrix: ``bits[i, k]`` is True when label ``k`` is in ``masks[i]``."""
        member = (masks[:, None] >> np.arange(len(self.labels), dtype=np.int64)) & 1 == 1
        return np.asarray(member, dtype=np.bool_)


def popcount(masks: IntArray) -> IntArray:
    """Cardinality |A| of each mask (vectorised)."""
    return np.bitwise_count(masks.astype(np.uint64)).astype(np.int64)
