"""The sensors' latest estimates of every fused track, as arrays, fused at a time.

One row per fused track, one slot per sensor (in the configuration's order):
states (R, S, d), covariances (R, S, d, d), report times (R, S) and a
``present`` mask. :meth:`EstimateTable.fused_at` predicts the present slots
of the rows asked for to a time and fuses them (ALGORITHMS.md §6 step 4,
``core.fusion.state``).

What it computed at the latest time asked for — every slot's prediction and
information matrix P⁻¹, every row's fused state — is kept until an estimate
of the row changes. A step that replaces one sensor's estimate of a track at
that time (the usual step: the report time is the fusion time) then predicts
and inverts that slot alone before fusing the row again.

Every number is computed per row and per matrix (LAPACK one matrix at a time,
sums in slot order), so a row's fused state has the same bits whatever else is
computed with it and whether its slots came from the kept results or not: an
engine restored from its export continues bit for bit.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from core.arrays import BoolArray, FloatArray, IntArray
from core.errors import InvalidInput
from core.fusion.motion import MotionModel
from core.fusion.state import StateFusion, fuse_information, fusion_weights


class EstimateTable:
    """Every fused track's latest estimate from each sensor, and their fusion at one time."""

    def __init__(self, sensors: Sequence[str], motion: MotionModel, rule: StateFusion) -> None:
        self.slots = {sensor: slot for slot, sensor in enumerate(sensors)}
        self.motion = motion
        self.rule = StateFusion(rule)
        self._rows = 0
        self.at: float | None = None
        """The time of the kept predictions and fused states."""
        self._allocate(0)

    def _allocate(self, capacity: int) -> None:
        slots, dim = len(self.slots), self.motion.layout.dim
        self.states: FloatArray = np.zeros((capacity, slots, dim))
        self.covariances: FloatArray = np.zeros((capacity, slots, dim, dim))
        self.times: FloatArray = np.zeros((capacity, slots))
        self.present: BoolArray = np.zeros((capacity, slots), dtype=bool)
        # kept at ``self.at``
        self._predicted: FloatArray = np.zeros((capacity, slots, dim))
        self._predicted_cov: FloatArray = np.zeros((capacity, slots, dim, dim))
        self._predicted_ok: BoolArray = np.zeros((capacity, slots), dtype=bool)
        self._information: FloatArray = np.zeros((capacity, slots, dim, dim))
        self._information_ok: BoolArray = np.zeros((capacity, slots), dtype=bool)
        self._fused: FloatArray = np.zeros((capacity, dim))
        self._fused_cov: FloatArray = np.zeros((capacity, dim, dim))
        self._fused_ok: BoolArray = np.zeros(capacity, dtype=bool)

    _ARRAYS = (
        "states",
        "covariances",
        "times",
        "present",
        "_predicted",
        "_predicted_cov",
        "_predicted_ok",
        "_information",
        "_information_ok",
        "_fused",
        "_fused_cov",
        "_fused_ok",
    )

    def __len__(self) -> int:
        return self._rows

    # ------------------------------------------------------------ rows
    def add_rows(self, count: int) -> IntArray:
        """``count`` new rows without estimates; returns their indices."""
        first = self._rows
        if first + count > len(self.present):
            kept = {name: getattr(self, name)[:first] for name in self._ARRAYS}
            self._allocate(max(2 * len(self.present), first + count, 8))
            for name, values in kept.items():
                getattr(self, name)[:first] = values
        self._rows = first + count
        rows = np.arange(first, first + count, dtype=np.int64)
        self.present[rows] = False
        self._predicted_ok[rows] = False
        self._information_ok[rows] = False
        self._fused_ok[rows] = False
        return rows

    def keep(self, rows: IntArray) -> None:
        """Keep only ``rows``, renumbered 0, 1, … in the order given."""
        for name in self._ARRAYS:
            values = getattr(self, name)
            values[: len(rows)] = values[rows]
        self._rows = len(rows)

    def slot(self, sensor: str) -> int:
        try:
            return self.slots[sensor]
        except KeyError:
            raise InvalidInput(f"unknown sensor {sensor!r}") from None

    def write(
        self,
        rows: IntArray,
        sensor: str,
        states: FloatArray,
        covariances: FloatArray,
        times: FloatArray | float,
    ) -> None:
        """``sensor``'s latest estimate of each of ``rows`` (states (n, d), covariances (n, d, d))."""
        slot = self.slot(sensor)
        self.states[rows, slot] = states
        self.covariances[rows, slot] = covariances
        self.times[rows, slot] = times
        self.present[rows, slot] = True
        self._predicted_ok[rows, slot] = False
        self._information_ok[rows, slot] = False
        self._fused_ok[rows] = False

    # ------------------------------------------------------------ fusion
    def fused_at(self, rows: IntArray, time: float) -> tuple[FloatArray, FloatArray]:
        """The fused state (n, d) and covariance (n, d, d) of ``rows`` (distinct) at ``time``.

        Raises
        ------
        InvalidInput
            The prediction to ``time`` overflows (``MotionModel.predict``).
        """
        if self.at != time:
            self._predicted_ok[:] = False
            self._information_ok[:] = False
            self._fused_ok[:] = False
            self.at = time
        need = rows[~self._fused_ok[rows]]
        if len(need):
            self._fuse(need, time)
        return self._fused[rows], self._fused_cov[rows]

    def _fuse(self, rows: IntArray, time: float) -> None:
        present = self.present[rows]
        stale_row, stale_slot = np.nonzero(present & ~self._predicted_ok[rows])
        stale = rows[stale_row]
        if len(stale):
            dt = time - self.times[stale, stale_slot]
            now = dt == 0.0  # estimates of this very time (a step's own report): taken as they are
            if now.any():
                rows_now, slots_now = stale[now], stale_slot[now]
                covariance = self.covariances[rows_now, slots_now]
                self._predicted[rows_now, slots_now] = self.states[rows_now, slots_now]
                self._predicted_cov[rows_now, slots_now] = (
                    covariance + np.swapaxes(covariance, -1, -2)
                ) / 2.0
            if not now.all():
                later = ~now
                rows_later, slots_later = stale[later], stale_slot[later]
                (
                    self._predicted[rows_later, slots_later],
                    self._predicted_cov[rows_later, slots_later],
                ) = self.motion.predict(
                    self.states[rows_later, slots_later],
                    self.covariances[rows_later, slots_later],
                    dt[later],
                )
            self._predicted_ok[stale, stale_slot] = True
        weights = fusion_weights(self._predicted_cov[rows], present, self.times[rows], self.rule)
        weighted = weights > 0.0
        several = weighted.sum(axis=1) > 1
        single = rows[~several]
        if len(single):  # one weighted estimate (ω = 1): the fusion is that estimate
            slot = np.argmax(weighted[~several], axis=1)
            self._fused[single] = self._predicted[single, slot]
            self._fused_cov[single] = self._predicted_cov[single, slot]
        multiple = rows[several]
        if len(multiple):
            chosen = weights[several]
            todo_row, todo_slot = np.nonzero(weighted[several] & ~self._information_ok[multiple])
            todo = multiple[todo_row]
            if len(todo):  # per matrix: the same bits whatever the batch
                self._information[todo, todo_slot] = np.linalg.inv(
                    self._predicted_cov[todo, todo_slot]
                )
                self._information_ok[todo, todo_slot] = True
            self._fused[multiple], self._fused_cov[multiple] = fuse_information(
                self._predicted[multiple], self._information[multiple], chosen
            )
        self._fused_ok[rows] = True
