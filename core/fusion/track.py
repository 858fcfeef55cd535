"""A fused track's state: the latest estimate of every sensor that reports it."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from core.arrays import FloatArray
from core.belief import Frame, MassFunction
from core.fusion.reports import Source
from core.lifecycle import StatusReason, TrackStatus

HISTORY_LENGTH = 100
"""Fused states kept per track for ``GET /tracks/{id}``."""


Kinematics = dict[str, tuple[FloatArray, FloatArray]]
"""Each sensor's latest state and covariance of one track (what the export carries)."""


@dataclass(frozen=True)
class SensorEstimate:
    """A sensor's latest estimate of a fused track: which sensor track, its time, its class
    evidence. Its state and covariance live in one place only: the engine's
    :class:`~core.fusion.table.EstimateTable` (the track's row, the sensor's slot)."""

    track: str
    time: float
    class_mass: MassFunction | None = None

    def to_plain(self, state: FloatArray, covariance: FloatArray) -> dict[str, Any]:
        return {
            "track": self.track,
            "time": self.time,
            "state": state.tolist(),
            "covariance": covariance.tolist(),
            "class_mass": None if self.class_mass is None else mass_to_plain(self.class_mass),
        }

    @classmethod
    def from_plain(
        cls, plain: dict[str, Any], frame: Frame | None
    ) -> tuple[SensorEstimate, FloatArray, FloatArray]:
        """The estimate, its state and its covariance."""
        mass = plain["class_mass"]
        estimate = cls(
            track=str(plain["track"]),
            time=float(plain["time"]),
            class_mass=None if mass is None or frame is None else mass_from_plain(mass, frame),
        )
        state = np.asarray(plain["state"], dtype=np.float64)
        covariance = np.asarray(plain["covariance"], dtype=np.float64)
        return estimate, state, covariance


@dataclass
class FusedTrack:
    """One object of the fused picture.

    Attributes
    ----------
    id : stable fused id ("F1", "F2", ...).
    status, reason : where the track is in its life and why it got there.
    score : SPRT log-likelihood ratio (``core.lifecycle``).
    hits : reports associated with it.
    estimates : the latest estimate of each contributing sensor, by sensor id (its
        state and covariance: in the engine's table, at ``row``).
    empty_gate_probability : [HZ] §4.2 product while coasting (1 otherwise).
    phantom_since : when it entered a blind zone or occlusion (None otherwise).
    history : recent (time, fused state) pairs, oldest first.
    row : its row in the engine's :class:`~core.fusion.table.EstimateTable`
        (not exported: the engine numbers the rows).
    number : the integer part of the id, for a stable order.
    """

    id: str
    status: TrackStatus
    reason: StatusReason
    score: float
    hits: int = 1
    estimates: dict[str, SensorEstimate] = field(default_factory=dict)
    empty_gate_probability: float = 1.0
    phantom_since: float | None = None
    history: list[tuple[float, list[float]]] = field(default_factory=list)
    row: int = field(default=-1, compare=False, repr=False)
    number: int = field(default=0, init=False, compare=False, repr=False)
    _sources: dict[str, Source] = field(default_factory=dict, init=False, compare=False, repr=False)
    """Each estimate as a source of the track, in sensor order (what every step shows)."""

    def __post_init__(self) -> None:
        self._sources = {
            sensor: Source(sensor, estimate.track, estimate.time)
            for sensor, estimate in sorted(self.estimates.items())
        }
        self.number = int(self.id[1:])

    def checkpoint(self) -> dict[str, Any]:
        """The track's fields as they are, for :meth:`rollback`. Its containers (estimates,
        sources, history) are never changed in place, only replaced: a shallow copy is exact."""
        return self.__dict__.copy()

    def rollback(self, checkpoint: dict[str, Any]) -> None:
        """The fields of ``checkpoint`` again (a step failed)."""
        self.__dict__ = checkpoint

    def set_estimate(self, sensor: str, estimate: SensorEstimate) -> None:
        """Record ``sensor``'s latest estimate of this track (new containers, see checkpoint)."""
        known = sensor in self.estimates
        self.estimates = {**self.estimates, sensor: estimate}
        sources = {**self._sources, sensor: Source(sensor, estimate.track, estimate.time)}
        self._sources = sources if known else dict(sorted(sources.items()))

    def sources(self) -> tuple[Source, ...]:
        """The contributing sensor tracks, by sensor id."""
        return tuple(self._sources.values())

    @property
    def last_time(self) -> float:
        return max(estimate.time for estimate in self.estimates.values())

    def remember(self, time: float, state: list[float]) -> None:
        """Append a fused state to the bounded history (replacing one at the same time);
        a new list, the old one is left as it was (see checkpoint)."""
        kept = self.history[:-1] if self.history and self.history[-1][0] == time else self.history
        self.history = [*kept[len(kept) - HISTORY_LENGTH + 1 :], (time, state)]

    def to_plain(self, kinematics: Kinematics) -> dict[str, Any]:
        """Plain data, each estimate with its state and covariance from ``kinematics``."""
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
            "history": [[time, state] for time, state in self.history],
        }

    @classmethod
    def from_plain(
        cls, plain: dict[str, Any], frame: Frame | None
    ) -> tuple[FusedTrack, Kinematics]:
        """The track and each of its estimates' state and covariance."""
        estimates, kinematics = {}, {}
        for sensor, entry in plain["estimates"].items():
            estimate, state, covariance = SensorEstimate.from_plain(entry, frame)
            estimates[str(sensor)] = estimate
            kinematics[str(sensor)] = (state, covariance)
        track = cls(
            id=str(plain["id"]),
            status=TrackStatus(plain["status"]),
            reason=StatusReason(plain["reason"]),
            score=float(plain["score"]),
            hits=int(plain["hits"]),
            estimates=estimates,
            empty_gate_probability=float(plain["empty_gate_probability"]),
            phantom_since=None if plain["phantom_since"] is None else float(plain["phantom_since"]),
            history=[(float(time), [float(x) for x in state]) for time, state in plain["history"]],
        )
        return track, kinematics


def mass_to_plain(mass: MassFunction) -> dict[str, list[Any]]:
    """A mass function as two JSON lists (masks, masses): exact round trip."""
    return {"masks": mass.masks.tolist(), "masses": mass.masses.tolist()}


def mass_from_plain(plain: dict[str, list[Any]], frame: Frame) -> MassFunction:
    return MassFunction(
        frame,
        np.asarray(plain["masks"], dtype=np.int64),
        np.asarray(plain["masses"], dtype=np.float64),
    )
