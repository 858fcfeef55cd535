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


@dataclass
class SensorEstimate:
    """A sensor's latest estimate of a fused track, with its class evidence."""

    track: str
    time: float
    state: FloatArray
    covariance: FloatArray
    class_mass: MassFunction | None = None
    _source: Source | None = field(default=None, init=False, repr=False, compare=False)

    def source(self, sensor: str) -> Source:
        """This estimate as a source of its fused track (built once: a step shows every source)."""
        if self._source is None or self._source.sensor != sensor:
            self._source = Source(sensor, self.track, self.time)
        return self._source

    def to_plain(self) -> dict[str, Any]:
        return {
            "track": self.track,
            "time": self.time,
            "state": self.state.tolist(),
            "covariance": self.covariance.tolist(),
            "class_mass": None if self.class_mass is None else mass_to_plain(self.class_mass),
        }

    @classmethod
    def from_plain(cls, plain: dict[str, Any], frame: Frame | None) -> SensorEstimate:
        mass = plain["class_mass"]
        return cls(
            track=str(plain["track"]),
            time=float(plain["time"]),
            state=np.asarray(plain["state"], dtype=np.float64),
            covariance=np.asarray(plain["covariance"], dtype=np.float64),
            class_mass=None if mass is None or frame is None else mass_from_plain(mass, frame),
        )


@dataclass
class FusedTrack:
    """One object of the fused picture.

    Attributes
    ----------
    id : stable fused id ("F1", "F2", ...).
    status, reason : where the track is in its life and why it got there.
    score : SPRT log-likelihood ratio (``core.lifecycle``).
    hits : reports associated with it.
    estimates : the latest estimate of each contributing sensor, by sensor id.
    empty_gate_probability : [HZ] §4.2 product while coasting (1 otherwise).
    phantom_since : when it entered a blind zone or occlusion (None otherwise).
    history : recent (time, fused state) pairs, oldest first.
    revision, fused_cache : the fused state last computed, valid while no
        estimate changed (not exported: derived data).
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
    revision: int = field(default=0, compare=False)
    fused_cache: tuple[float, int, FloatArray, FloatArray] | None = field(
        default=None, compare=False, repr=False
    )
    stack_cache: tuple[int, FloatArray, FloatArray, FloatArray] | None = field(
        default=None, compare=False, repr=False
    )

    def stacked(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The estimates as arrays: states (k, d), covariances (k, d, d), times (k,)."""
        cache = self.stack_cache
        if cache is None or cache[0] != self.revision:
            estimates = list(self.estimates.values())
            cache = (
                self.revision,
                np.array([e.state for e in estimates]),
                np.array([e.covariance for e in estimates]),
                np.array([e.time for e in estimates]),
            )
            self.stack_cache = cache
        return cache[1], cache[2], cache[3]

    def set_estimate(self, sensor: str, estimate: SensorEstimate) -> None:
        """Record a sensor's latest estimate (and forget the cached fused state).

        The stacked arrays follow a replaced estimate (same slot: a dict keeps
        the position of a key it already holds) instead of being rebuilt.
        """
        cache = self.stack_cache
        slot = list(self.estimates).index(sensor) if sensor in self.estimates else None
        self.estimates[sensor] = estimate
        self.revision += 1
        if cache is not None and cache[0] == self.revision - 1 and slot is not None:
            states, covariances, times = cache[1].copy(), cache[2].copy(), cache[3].copy()
            states[slot], covariances[slot], times[slot] = (
                estimate.state,
                estimate.covariance,
                estimate.time,
            )
            self.stack_cache = (self.revision, states, covariances, times)

    def cached_fusion(self, time: float) -> tuple[FloatArray, FloatArray] | None:
        """The fused state at ``time`` if it was computed from the current estimates."""
        cache = self.fused_cache
        if cache is None or cache[0] != time or cache[1] != self.revision:
            return None
        return cache[2], cache[3]

    @property
    def number(self) -> int:
        """The integer part of the id, for a stable order."""
        return int(self.id[1:])

    @property
    def last_time(self) -> float:
        return max(estimate.time for estimate in self.estimates.values())

    def remember(self, time: float, state: FloatArray) -> None:
        """Append a fused state to the bounded history (replacing one at the same time)."""
        if self.history and self.history[-1][0] == time:
            self.history.pop()
        self.history.append((time, state.tolist()))
        del self.history[:-HISTORY_LENGTH]

    def to_plain(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "status": self.status.value,
            "reason": self.reason.value,
            "score": self.score,
            "hits": self.hits,
            "estimates": {sensor: e.to_plain() for sensor, e in self.estimates.items()},
            "empty_gate_probability": self.empty_gate_probability,
            "phantom_since": self.phantom_since,
            "history": [[time, state] for time, state in self.history],
        }

    @classmethod
    def from_plain(cls, plain: dict[str, Any], frame: Frame | None) -> FusedTrack:
        return cls(
            id=str(plain["id"]),
            status=TrackStatus(plain["status"]),
            reason=StatusReason(plain["reason"]),
            score=float(plain["score"]),
            hits=int(plain["hits"]),
            estimates={
                str(sensor): SensorEstimate.from_plain(estimate, frame)
                for sensor, estimate in plain["estimates"].items()
            },
            empty_gate_probability=float(plain["empty_gate_probability"]),
            phantom_since=None if plain["phantom_since"] is None else float(plain["phantom_since"]),
            history=[(float(time), [float(x) for x in state]) for time, state in plain["history"]],
        )


def mass_to_plain(mass: MassFunction) -> dict[str, list[Any]]:
    """A mass function as two JSON lists (masks, masses): exact round trip."""
    return {"masks": mass.masks.tolist(), "masses": mass.masses.tolist()}


def mass_from_plain(plain: dict[str, list[Any]], frame: Frame) -> MassFunction:
    return MassFunction(
        frame,
        np.asarray(plain["masks"], dtype=np.int64),
        np.asarray(plain["masses"], dtype=np.float64),
    )
