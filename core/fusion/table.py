"""The sensors' latest estimates of every fused track, as arrays, fused at a time.

One row per fused track, one slot per sensor (in the configuration's order):
states (R, S, d), covariances (R, S, d, d), report times (R, S) and a
``present`` mask. :meth:`EstimateTable.fused_at` predicts the present slots
of the rows asked for to a time and fuses them (docs/algorithms.md §6 step 4,
``core.fusion.state``).

What it computed at the last :data:`KEPT_TIMES` times asked for — every
slot's prediction and information matrix P⁻¹, every row's fused state — is
kept until an estimate of the row changes. A step that replaces one sensor's
estimate of a track at such a time then predicts and inverts that slot alone
before fusing the row again: the usual step (its report time is the fusion
time), and a late report's step too (associated at its own time, then fused
again at the fusion time, which earlier steps already used).

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
from core.fusion.state import StateFusion, fuse_information, fusion_weights
from core.models import MappedMotion
from core.pipeline.predict import predict_estimates

KEPT_TIMES = 2
"""Times whose predictions and fused states are kept (the fusion time and one other)."""


class _Kept:
    """Predictions, information matrices and fused states of the table's rows at one time."""

    def __init__(self, at: float, capacity: int, slots: int, dim: int) -> None:
        self.at = at
        self.predicted: FloatArray = np.zeros((capacity, slots, dim))
        self.predicted_cov: FloatArray = np.zeros((capacity, slots, dim, dim))
        self.predicted_ok: BoolArray = np.zeros((capacity, slots), dtype=bool)
        self.information: FloatArray = np.zeros((capacity, slots, dim, dim))
        self.information_ok: BoolArray = np.zeros((capacity, slots), dtype=bool)
        self.fused: FloatArray = np.zeros((capacity, dim))
        self.fused_cov: FloatArray = np.zeros((capacity, dim, dim))
        self.fused_ok: BoolArray = np.zeros(capacity, dtype=bool)

    def grown(self, capacity: int, used: int) -> _Kept:
        """A copy with room for ``capacity`` rows, of which the first ``used`` are kept."""
        predicted = self.predicted
        grown = _Kept(self.at, capacity, predicted.shape[1], predicted.shape[2])
        for name in _KEPT_ARRAYS:
            getattr(grown, name)[:used] = getattr(self, name)[:used]
        return grown

    def keep(self, rows: IntArray) -> None:
        """Keep only ``rows``, renumbered 0, 1, … in the order given."""
        for name in _KEPT_ARRAYS:
            values = getattr(self, name)
            values[: len(rows)] = values[rows]

    def forget(self, rows: IntArray | slice, slot: int | slice = slice(None)) -> None:
        """Nothing kept for ``slot`` of ``rows`` (and the rows' fused states)."""
        self.predicted_ok[rows, slot] = False
        self.information_ok[rows, slot] = False
        self.fused_ok[rows] = False


_KEPT_ARRAYS = (
    "predicted",
    "predicted_cov",
    "predicted_ok",
    "information",
    "information_ok",
    "fused",
    "fused_cov",
    "fused_ok",
)
_ESTIMATE_ARRAYS = ("states", "covariances", "times", "present")


class EstimateTable:
    """Every fused track's latest estimate from each sensor, and their fusion at a time."""

    def __init__(self, sensors: Sequence[str], motion: MappedMotion, rule: StateFusion) -> None:
        self.slots = {sensor: slot for slot, sensor in enumerate(sensors)}
        self.motion = motion
        self.rule = StateFusion(rule)
        self._rows = 0
        self._kept: list[_Kept] = []
        """Most recently used first, at most :data:`KEPT_TIMES`."""
        self._allocate(0)

    def _allocate(self, capacity: int) -> None:
        slots, dim = len(self.slots), self.motion.layout.dim
        self.states: FloatArray = np.zeros((capacity, slots, dim))
        self.covariances: FloatArray = np.zeros((capacity, slots, dim, dim))
        self.times: FloatArray = np.zeros((capacity, slots))
        self.present: BoolArray = np.zeros((capacity, slots), dtype=bool)

    def __len__(self) -> int:
        return self._rows

    # ------------------------------------------------------------ rows
    def add_rows(self, count: int) -> IntArray:
        """``count`` new rows without estimates; returns their indices."""
        first = self._rows
        if first + count > len(self.present):
            capacity = max(2 * len(self.present), first + count, 8)
            estimates = [(name, getattr(self, name)[:first]) for name in _ESTIMATE_ARRAYS]
            self._allocate(capacity)
            for name, values in estimates:
                getattr(self, name)[:first] = values
            self._kept = [kept.grown(capacity, first) for kept in self._kept]
        self._rows = first + count
        rows = np.arange(first, first + count, dtype=np.int64)
        self.present[rows] = False
        for kept in self._kept:
            kept.forget(rows)
        return rows

    def keep(self, rows: IntArray) -> None:
        """Keep only ``rows``, renumbered 0, 1, … in the order given."""
        for name in _ESTIMATE_ARRAYS:
            values = getattr(self, name)
            values[: len(rows)] = values[rows]
        for kept in self._kept:
            kept.keep(rows)
        self._rows = len(rows)

    def add_slot(self, sensor: str) -> None:
        """A slot for a sensor that joins, after the others: no row has its estimate yet."""
        if sensor in self.slots:
            raise InvalidInput(f"sensor {sensor!r} has a slot already")
        self._resize_slots({**self.slots, sensor: len(self.slots)})

    def drop_slot(self, sensor: str) -> None:
        """Take back the slot :meth:`add_slot` just added (no row has an estimate in it)."""
        if list(self.slots)[-1:] != [sensor] or self.present[: self._rows, -1].any():
            raise InvalidInput(f"sensor {sensor!r} is not the last, empty slot")
        self._resize_slots({name: slot for name, slot in self.slots.items() if name != sensor})

    def _resize_slots(self, slots: dict[str, int]) -> None:
        """The same rows with ``slots`` (the old ones first, in order); computed results go
        (recomputed on demand, with the same bits)."""
        rows, kept = self._rows, min(len(slots), len(self.slots))
        estimates = [(name, getattr(self, name)[:rows, :kept]) for name in _ESTIMATE_ARRAYS]
        self.slots = slots
        self._allocate(len(self.present))
        for name, values in estimates:
            getattr(self, name)[:rows, :kept] = values
        self._kept = []

    def checkpoint(self) -> tuple[int, tuple[FloatArray, ...]]:
        """The estimates as they are (copies), for :meth:`rollback`."""
        rows = self._rows
        return rows, tuple(getattr(self, name)[:rows].copy() for name in _ESTIMATE_ARRAYS)

    def rollback(self, checkpoint: tuple[int, tuple[FloatArray, ...]]) -> None:
        """The estimates of ``checkpoint`` again; what was computed from others is forgotten
        (recomputed on demand, with the same bits: module docstring)."""
        rows, arrays = checkpoint
        self._allocate(max(rows, 8))
        for name, values in zip(_ESTIMATE_ARRAYS, arrays, strict=True):
            getattr(self, name)[:rows] = values
        self._rows = rows
        self._kept = []

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
        for kept in self._kept:
            kept.forget(rows, slot)

    def estimate(self, row: int, sensor: str) -> tuple[FloatArray, FloatArray]:
        """``sensor``'s latest state and covariance of ``row`` (copies)."""
        slot = self.slot(sensor)
        return self.states[row, slot].copy(), self.covariances[row, slot].copy()

    def move(self, source: int, target: int, sensor: str) -> None:
        """``sensor``'s estimate of row ``source`` becomes its estimate of row ``target``."""
        slot = self.slot(sensor)
        self.write(
            np.array([target]),
            sensor,
            self.states[source, slot][None],
            self.covariances[source, slot][None],
            float(self.times[source, slot]),
        )

    # ------------------------------------------------------------ fusion
    def fused_at(self, rows: IntArray, time: float) -> tuple[FloatArray, FloatArray]:
        """The fused state (n, d) and covariance (n, d, d) of ``rows`` (distinct) at ``time``.

        Raises
        ------
        InvalidInput
            The prediction to ``time`` overflows (``MappedMotion.predict``).
        """
        kept = self._kept_at(time)
        need = rows[~kept.fused_ok[rows]]
        if len(need):
            self._fuse(kept, need)
        return kept.fused[rows], kept.fused_cov[rows]

    def _kept_at(self, time: float) -> _Kept:
        """What is kept at ``time`` (made the most recent), or a fresh record for it."""
        for index, kept in enumerate(self._kept):
            if kept.at == time:
                self._kept.insert(0, self._kept.pop(index))
                return kept
        if len(self._kept) >= KEPT_TIMES:
            kept = self._kept.pop()  # the least recently used: its arrays are reused
            kept.at = time
            kept.forget(slice(None))
        else:
            kept = _Kept(time, len(self.present), len(self.slots), self.motion.layout.dim)
        self._kept.insert(0, kept)
        return kept

    def _fuse(self, kept: _Kept, rows: IntArray) -> None:
        """Predict what is not kept of ``rows`` to ``kept.at``, invert, fuse."""
        time = kept.at
        present = self.present[rows]
        stale_row, stale_slot = np.nonzero(present & ~kept.predicted_ok[rows])
        stale = rows[stale_row]
        if len(stale):
            # a step's own report (Δt = 0) is taken as it is
            kept.predicted[stale, stale_slot], kept.predicted_cov[stale, stale_slot] = (
                predict_estimates(
                    self.motion,
                    self.states[stale, stale_slot],
                    self.covariances[stale, stale_slot],
                    time - self.times[stale, stale_slot],
                )
            )
            kept.predicted_ok[stale, stale_slot] = True
        weights = fusion_weights(kept.predicted_cov[rows], present, self.times[rows], self.rule)
        weighted = weights > 0.0
        several = weighted.sum(axis=1) > 1
        single = rows[~several]
        if len(single):  # one weighted estimate (ω = 1): the fusion is that estimate
            slot = np.argmax(weighted[~several], axis=1)
            kept.fused[single] = kept.predicted[single, slot]
            kept.fused_cov[single] = kept.predicted_cov[single, slot]
        multiple = rows[several]
        if len(multiple):
            chosen = weights[several]
            todo_row, todo_slot = np.nonzero(weighted[several] & ~kept.information_ok[multiple])
            todo = multiple[todo_row]
            if len(todo):  # per matrix: the same bits whatever the batch
                kept.information[todo, todo_slot] = np.linalg.inv(
                    kept.predicted_cov[todo, todo_slot]
                )
                kept.information_ok[todo, todo_slot] = True
            kept.fused[multiple], kept.fused_cov[multiple] = fuse_information(
                kept.predicted[multiple], kept.information[multiple], chosen
            )
        kept.fused_ok[rows] = True
