"""What a :class:`~core.tracking.tracker.LocalTracker` step returns: local tracks as plain values.

Every track carries its status and the reason of its last status change
(:class:`~core.lifecycle.StatusReason`), its combined IMM estimate, its SPRT
score and, when the tracker classifies, its class mass and BetP.
``to_plain()`` gives lists, floats, ints, str and None only; non-finite floats
are written as the strings ``"inf"``, ``"-inf"``, ``"nan"`` (:func:`plain_floats`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from core.arrays import FloatArray
from core.belief import MassFunction
from core.lifecycle import StatusReason, TrackStatus


def plain_float(value: float) -> float | str:
    """A float, or its name when it is not finite (plain JSON has no inf / nan)."""
    return value if math.isfinite(value) else str(value)


def plain_floats(values: FloatArray | float) -> Any:
    """Nested lists of floats (:func:`plain_float` for the non-finite ones)."""
    array = np.asarray(values, dtype=np.float64)
    if np.all(np.isfinite(array)):
        return array.tolist()
    return np.vectorize(plain_float, otypes=[object])(array).tolist()


def float_array(values: Any) -> FloatArray:
    """The inverse of :func:`plain_floats` (``"inf"`` and friends parse as floats)."""
    return np.asarray(np.array(values, dtype=np.float64), dtype=np.float64)


def mass_to_plain(mass: MassFunction) -> dict[str, Any]:
    """Focal masks and masses as lists."""
    return {"masks": mass.masks.tolist(), "masses": mass.masses.tolist()}


@dataclass(frozen=True, eq=False)
class LocalTrack:
    """One track of a sensor system at the end of a step.

    Attributes
    ----------
    id : str
    status : TrackStatus
    reason : StatusReason
        Why the status last changed.
    state, covariance : ndarray, shapes (n,), (n, n)
        The combined IMM estimate ([MTT] §3).
    mode_probabilities : ndarray, shape (r,)
    score : float
        SPRT log-likelihood ratio ([MTT] §4.3).
    hits : int
        Detections the track was updated with (its initiation points included).
    class_mass : MassFunction or None
        Cumulative class mass ([MTT] §5.2); None without classification.
    pignistic : ndarray or None
        BetP of each class; None without classification or in ``total_conflict``.
    """

    id: str
    status: TrackStatus
    reason: StatusReason
    state: FloatArray
    covariance: FloatArray
    mode_probabilities: FloatArray
    score: float
    hits: int
    class_mass: MassFunction | None = None
    pignistic: FloatArray | None = None

    def to_plain(self) -> dict[str, Any]:
        """Plain data (see the module docstring)."""
        return {
            "id": self.id,
            "status": self.status.value,
            "reason": self.reason.value,
            "state": plain_floats(self.state),
            "covariance": plain_floats(self.covariance),
            "mode_probabilities": plain_floats(self.mode_probabilities),
            "score": plain_float(self.score),
            "hits": self.hits,
            "class_mass": None if self.class_mass is None else mass_to_plain(self.class_mass),
            "pignistic": None if self.pignistic is None else plain_floats(self.pignistic),
        }


@dataclass(frozen=True, eq=False)
class LocalTracks:
    """A scan's local tracks as columns, a row per track in id-number order: what the fusion
    step reads (:func:`core.fusion.detections.local_track_report`) without a
    :class:`LocalTrack` per track. ``states`` (n, s), ``covariances`` (n, s, s) and
    ``mode_probabilities`` (n, r) are arrays; the others hold a value per track."""

    ids: tuple[str, ...]
    statuses: tuple[TrackStatus, ...]
    reasons: tuple[StatusReason, ...]
    states: FloatArray
    covariances: FloatArray
    mode_probabilities: FloatArray
    scores: tuple[float, ...]
    hits: tuple[int, ...]
    class_masses: tuple[MassFunction | None, ...]
    pignistic: tuple[FloatArray | None, ...]

    def __len__(self) -> int:
        return len(self.ids)

    def track(self, index: int) -> LocalTrack:
        """Row ``index`` as a :class:`LocalTrack` (its arrays are rows of the columns)."""
        return LocalTrack(
            id=self.ids[index],
            status=self.statuses[index],
            reason=self.reasons[index],
            state=self.states[index],
            covariance=self.covariances[index],
            mode_probabilities=self.mode_probabilities[index],
            score=self.scores[index],
            hits=self.hits[index],
            class_mass=self.class_masses[index],
            pignistic=self.pignistic[index],
        )


TALLY_FIELDS = (
    "detections",
    "joined_established",
    "joined_tentative",
    "started",
    "unused",
    "confirmed",
    "refuted",
    "refuted_detections",
    "ended",
)
"""The counts of a :class:`ScanTally`, in order."""


@dataclass(frozen=True)
class ScanTally:
    """What a tracker did with a sensor's detections (one scan, or summed over scans):
    the answer to "why is nothing tracked" (docs/algorithms.md §8).

    Attributes
    ----------
    detections : detections received.
    joined_established : detections that updated a confirmed or coasting track.
    joined_tentative : detections that updated a tentative track.
    started : detections that started a track (two-point: the pair's second).
    unused : detections that did neither (two-point seeds, detections left out by the
        association, pairs whose start score was at the delete threshold).
    confirmed : tracks confirmed.
    refuted : tentative tracks terminated without ever being confirmed (their starts
        refuted: clutter), with ``refuted_detections`` detections between them.
    ended : established tracks terminated, with ``ended_reasons`` (reason → count).
    """

    detections: int = 0
    joined_established: int = 0
    joined_tentative: int = 0
    started: int = 0
    unused: int = 0
    confirmed: int = 0
    refuted: int = 0
    refuted_detections: int = 0
    ended: int = 0
    ended_reasons: Mapping[str, int] = field(default_factory=dict)

    def __add__(self, other: ScanTally) -> ScanTally:
        reasons = dict(self.ended_reasons)
        for reason, count in other.ended_reasons.items():
            reasons[reason] = reasons.get(reason, 0) + count
        counts = {name: getattr(self, name) + getattr(other, name) for name in TALLY_FIELDS}
        return ScanTally(**counts, ended_reasons=dict(sorted(reasons.items())))

    def to_plain(self) -> dict[str, Any]:
        plain: dict[str, Any] = {name: getattr(self, name) for name in TALLY_FIELDS}
        plain["ended_reasons"] = dict(self.ended_reasons)
        return plain

    @classmethod
    def from_plain(cls, plain: Mapping[str, Any]) -> ScanTally:
        counts = {name: int(plain[name]) for name in TALLY_FIELDS}
        reasons = {str(k): int(v) for k, v in plain["ended_reasons"].items()}
        return cls(**counts, ended_reasons=reasons)


@dataclass(frozen=True, eq=False)
class TrackerStep:
    """The result of one scan.

    Attributes
    ----------
    time : float
    sensor : str
    columns : LocalTracks
        Every track alive after the scan and every track terminated during
        it (status ``terminated`` with its reason), by id number; ``tracks``: the same
        as :class:`LocalTrack` values (made when first asked for).
    assignment : tuple of (str or None)
        Per detection, in input order: the id of the track it updated or
        started (after any phantom hand-over), or None (a seed of two-point
        initiation, or a detection the association left out).
    """

    time: float
    sensor: str
    columns: LocalTracks
    assignment: tuple[str | None, ...]
    tally: ScanTally = field(default_factory=lambda: ScanTally())
    clutter_density: float = math.nan
    updated: tuple[str, ...] = ()

    @cached_property
    def tracks(self) -> tuple[LocalTrack, ...]:
        """Every track of :attr:`columns` as a :class:`LocalTrack`."""
        return tuple(self.columns.track(index) for index in range(len(self.columns)))

    def track(self, track_id: str) -> LocalTrack:
        """The track with that id (KeyError when absent)."""
        for candidate in self.tracks:
            if candidate.id == track_id:
                return candidate
        raise KeyError(track_id)

    def to_plain(self) -> dict[str, Any]:
        """Plain data (see the module docstring)."""
        return {
            "time": plain_float(self.time),
            "sensor": self.sensor,
            "tracks": [track.to_plain() for track in self.tracks],
            "assignment": list(self.assignment),
            "tally": self.tally.to_plain(),
            "clutter_density": plain_float(self.clutter_density),
            "updated": list(self.updated),
        }
