"""A fused track: its id, which sensor track each sensor reports it as, its history.

Each fact of a track lives in one place. The engine keeps its tracks as rows
(:class:`FusedRows`): the sensors' latest kinematic estimates and their
report times in the :class:`~core.fusion.table.EstimateTable`, the numbers
and the lives (status, reason, score, hits, empty-gate probability, phantom
time) in a :class:`~core.pipeline.rows.TrackRows`, both at the track's
``row``. A :class:`FusedTrack` holds the rest — each sensor's track id and
class evidence, the fused history — and reads its life from its rows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from core.arrays import FloatArray
from core.belief import Frame, MassFunction
from core.fusion.reports import Source
from core.fusion.table import EstimateTable
from core.lifecycle import REASONS, STATUSES, StatusReason, TrackStatus
from core.pipeline.rows import TrackRows

HISTORY_LENGTH = 100
"""Fused states kept per track for ``GET /tracks/{id}``."""


Kinematics = dict[str, tuple[float, FloatArray, FloatArray]]
"""Each sensor's latest report time, state and covariance of one track (what the export carries)."""


class FusedRows:
    """Where a session's fused tracks live, row for row: the estimate table and the rows.

    ``rows`` is replaced, never changed in place (a step's transaction keeps
    the reference); the table has its own checkpoint.
    """

    def __init__(self, table: EstimateTable) -> None:
        self.table = table
        self.rows = TrackRows.empty()
        self.sorted_slots = sorted(table.slots.items())
        """(sensor, slot) by sensor id: the order a track shows its sources in."""


@dataclass(frozen=True)
class SensorEstimate:
    """A sensor's latest estimate of a fused track: which sensor track, its class evidence.
    Its time, state and covariance live in the engine's
    :class:`~core.fusion.table.EstimateTable` (the track's row, the sensor's slot)."""

    track: str
    class_mass: MassFunction | None = None

    def to_plain(self, time: float, state: FloatArray, covariance: FloatArray) -> dict[str, Any]:
        return {
            "track": self.track,
            "time": time,
            "state": state.tolist(),
            "covariance": covariance.tolist(),
            "class_mass": None if self.class_mass is None else mass_to_plain(self.class_mass),
        }

    @classmethod
    def from_plain(
        cls, plain: dict[str, Any], frame: Frame | None
    ) -> tuple[SensorEstimate, float, FloatArray, FloatArray]:
        """The estimate, its time, its state and its covariance."""
        mass = plain["class_mass"]
        estimate = cls(
            track=str(plain["track"]),
            class_mass=None if mass is None or frame is None else mass_from_plain(mass, frame),
        )
        state = np.asarray(plain["state"], dtype=np.float64)
        covariance = np.asarray(plain["covariance"], dtype=np.float64)
        return estimate, float(plain["time"]), state, covariance


@dataclass
class FusedTrack:
    """One object of the fused picture.

    Attributes
    ----------
    id : stable fused id ("F1", "F2", ...).
    estimates : the latest estimate of each contributing sensor, by sensor id (its
        time, state and covariance: in the engine's table, at ``row``).
    history : recent (time, fused state) pairs, oldest first.
    row : its row in the engine's :class:`FusedRows` (not exported: the engine
        numbers the rows).
    number : the integer part of the id, for a stable order.

    ``status``, ``reason``, ``score`` (SPRT log-likelihood ratio), ``hits``,
    ``empty_gate_probability`` ([HZ] §4.2 product while coasting),
    ``phantom_since`` (None unless a phantom) and ``misses`` (in a row) are read
    from the rows.
    """

    id: str
    rows: FusedRows = field(compare=False, repr=False)
    row: int = field(default=-1, compare=False, repr=False)
    estimates: dict[str, SensorEstimate] = field(default_factory=dict)
    history: list[tuple[float, list[float]]] = field(default_factory=list)
    number: int = field(default=0, init=False, compare=False, repr=False)
    _sources: dict[str, Source] = field(default_factory=dict, init=False, compare=False, repr=False)
    """A memo of :meth:`sources` by sensor, made from the table's times (a sensor's entry
    is dropped when its estimate changes)."""

    def __post_init__(self) -> None:
        self.number = int(self.id[1:])

    # ------------------------------------------------------------ its life
    @property
    def status(self) -> TrackStatus:
        return STATUSES[int(self.rows.rows.life.status[self.row])]

    @property
    def reason(self) -> StatusReason:
        return REASONS[int(self.rows.rows.life.reason[self.row])]

    @property
    def score(self) -> float:
        return float(self.rows.rows.life.score[self.row])

    @property
    def hits(self) -> int:
        return int(self.rows.rows.life.hits[self.row])

    @property
    def empty_gate_probability(self) -> float:
        return float(self.rows.rows.life.empty_gate[self.row])

    @property
    def misses(self) -> int:
        return int(self.rows.rows.life.misses[self.row])

    @property
    def phantom_since(self) -> float | None:
        entered = float(self.rows.rows.life.phantom_since[self.row])
        return None if math.isnan(entered) else entered

    # ------------------------------------------------------------ its estimates
    def checkpoint(self) -> dict[str, Any]:
        """The track's fields as they are, for :meth:`rollback`. Its containers (estimates,
        history) are never changed in place, only replaced: a shallow copy is exact."""
        return self.__dict__.copy()

    def rollback(self, checkpoint: dict[str, Any]) -> None:
        """The fields of ``checkpoint`` again (a step failed)."""
        self.__dict__ = checkpoint

    def set_estimate(self, sensor: str, estimate: SensorEstimate) -> None:
        """Record ``sensor``'s latest estimate of this track (new dicts, see checkpoint)."""
        self.estimates = {**self.estimates, sensor: estimate}
        if sensor in self._sources:
            self._sources = {**self._sources}
            del self._sources[sensor]

    def sources(self, report_times: list[float] | None = None) -> tuple[Source, ...]:
        """The contributing sensor tracks, by sensor id, with their report times
        (``report_times``: the table's times of this row by slot, when at hand)."""
        memo, estimates = self._sources, self.estimates
        if len(memo) != len(estimates):
            times = (
                self.rows.table.times[self.row].tolist() if report_times is None else report_times
            )
            slots = self.rows.table.slots
            memo = {**memo}
            for sensor in estimates.keys() - memo.keys():  # the sensors that reported since
                memo[sensor] = Source(sensor, estimates[sensor].track, times[slots[sensor]])
            memo = dict(sorted(memo.items()))
            self._sources = memo
        return tuple(memo.values())

    def remember(self, time: float, state: list[float]) -> None:
        """Append a fused state to the bounded history (replacing one at the same time);
        a new list, the old one is left as it was (see checkpoint)."""
        kept = self.history[:-1] if self.history and self.history[-1][0] == time else self.history
        self.history = [*kept[len(kept) - HISTORY_LENGTH + 1 :], (time, state)]

    # ------------------------------------------------------------ plain data
    def to_plain(self, kinematics: Kinematics) -> dict[str, Any]:
        """Plain data, each estimate with its time, state and covariance from ``kinematics``."""
        return {
            "id": self.id,
            "status": self.status.value,
            "reason": self.reason.value,
            "score": self.score,
            "hits": self.hits,
            "estimates": {
                sensor: estimate.to_plain(*kinematics[sensor])
                for sensor, estimate in self.estimates.items()
            },
            "empty_gate_probability": self.empty_gate_probability,
            "phantom_since": self.phantom_since,
            "misses": self.misses,
            "history": [[time, state] for time, state in self.history],
        }


def mass_to_plain(mass: MassFunction) -> dict[str, list[Any]]:
    """A mass function as two JSON lists (masks, masses): exact round trip."""
    return {"masks": mass.masks.tolist(), "masses": mass.masses.tolist()}


def mass_from_plain(plain: dict[str, list[Any]], frame: Frame) -> MassFunction:
    return MassFunction(
        frame,
        np.asarray(plain["masks"], dtype=np.int64),
        np.asarray(plain["masses"], dtype=np.float64),
    )


@dataclass(frozen=True, eq=False)
class EndedTrack:
    """A fused track the picture ended recently, remembered so that a track confirmed
    where it is predicted can take its id (docs/algorithms.md §8.15).

    Attributes
    ----------
    id : its fused id.
    time : when it ended (the fusion time of that step).
    state, covariance : its fused estimate at that time.
    history : its fused history, oldest first (what ``GET /tracks/{id}`` showed).
    """

    id: str
    time: float
    state: FloatArray
    covariance: FloatArray
    history: tuple[tuple[float, list[float]], ...] = ()

    @property
    def number(self) -> int:
        """The integer part of the id."""
        return int(self.id[1:])

    def to_plain(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "time": self.time,
            "state": self.state.tolist(),
            "covariance": self.covariance.tolist(),
            "history": [[time, state] for time, state in self.history],
        }

    @classmethod
    def from_plain(cls, plain: dict[str, Any]) -> EndedTrack:
        return cls(
            id=str(plain["id"]),
            time=float(plain["time"]),
            state=np.asarray(plain["state"], dtype=np.float64),
            covariance=np.asarray(plain["covariance"], dtype=np.float64),
            history=tuple(
                (float(time), [float(x) for x in state]) for time, state in plain["history"]
            ),
        )
