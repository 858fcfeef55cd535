"""Ragged rows: each item's candidate pairs, packed into padded blocks for row-wise BetP.

An item's frame holds its gated candidates plus ``*``. Rows differ in
length, so items are sorted by candidate count and packed in blocks whose
padding stays small and whose work (rows × width × quadrature nodes) stays
under a budget: memory is bounded however dense the problem is.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from core.arrays import IntArray

WORK_BUDGET = 1 << 22
"""Largest rows × width × ROW_TEMPORARIES of one block (about 32 MB of floats in all); the
quadrature's rows × nodes × width temporaries are split further where they are formed
(``core.belief.gbt.NODE_BUDGET``)."""

ROW_TEMPORARIES = 16
"""Row-sized arrays the BetP of one block holds at once (a bound, for the budget)."""


@dataclass(frozen=True, eq=False)
class RaggedRows:
    """Pairs grouped by item.

    Attributes
    ----------
    order : ndarray of int64
        Pair indices sorted by item (stable: within an item, pair order kept).
    starts, counts : ndarray of int64, shape (n_items,)
        Where each item's pairs start in ``order``, and how many it has.
    """

    order: IntArray
    starts: IntArray
    counts: IntArray

    @classmethod
    def of(cls, items: IntArray, n_items: int) -> RaggedRows:
        order = np.argsort(items, kind="stable").astype(np.int64)
        counts = np.bincount(items, minlength=n_items).astype(np.int64)
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
        return cls(order, starts, counts)

    def blocks(self, budget: int = WORK_BUDGET) -> Iterator[tuple[IntArray, IntArray]]:
        """Blocks of items with candidates: ``(items, pair_index)``.

        ``pair_index`` has shape (len(items), width); entry (i, k) is the
        k-th pair of item i, or −1 past its count.
        """
        items = np.flatnonzero(self.counts > 0)
        items = items[np.argsort(self.counts[items], kind="stable")]
        start = 0
        while start < len(items):
            width = int(self.counts[items[start]])
            ceiling = 2 * width  # rows of up to twice the shortest share a block
            cost_per_row = (ceiling + 1) * ROW_TEMPORARIES
            stop = start + max(1, budget // cost_per_row)
            stop = min(
                stop,
                start + int(np.searchsorted(self.counts[items[start:]], ceiling, side="right")),
            )
            block = items[start:stop]
            block_width = int(self.counts[block].max())
            offsets = np.arange(block_width)
            inside = offsets[None, :] < self.counts[block][:, None]
            positions = np.where(inside, self.starts[block][:, None] + offsets[None, :], 0)
            pair_index = np.where(inside, self.order[positions], -1)
            yield block, pair_index
            start = stop
