"""What goes into and comes out of one fusion step."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import overload

import numpy as np

from core.arrays import FloatArray
from core.belief import MassFunction
from core.fusion.classes import ClassAssessment
from core.lifecycle import StatusReason, TrackStatus
from core.models.measurement import MeasurementModel


@dataclass(frozen=True)
class ReportedTrack:
    """One track of a sensor's track list.

    ``class_mass`` is the sensor's own class belief; ``class_likelihoods``
    one step of class evidence (per class of the session frame, in [0, 1]).
    At most one of the two. ``coasted``: the source did not update the track in
    its latest scan (its prediction; MATLAB's ``objectTrack.IsCoasted``): a miss of
    that source, not an estimate (docs/algorithms.md §8.10).
    """

    id: str
    state: FloatArray
    covariance: FloatArray
    class_mass: MassFunction | None = None
    class_likelihoods: FloatArray | None = None
    coasted: bool = False


@dataclass(frozen=True)
class TrackReport:
    """A sensor's track list at one time."""

    sensor: str
    time: float
    tracks: tuple[ReportedTrack, ...]


@dataclass(frozen=True)
class DetectionReport:
    """A sensor's detections at one time: measurements ``z`` (m × q) and, optionally,
    each detection's own noise covariance (m × q × q; default: the sensor's R),
    range-rate (m,; NaN: none; for a sensor whose tracker has a range-rate model) and
    class evidence (m masses on the session's class frame; None: none), combined into
    the class mass of the local track it updates or starts. ``model``: the measurement
    model the detections were measured by (Stone Soup's ``Detection.measurement_model``;
    :meth:`measured` converts a polar model's measurements to these positions)."""

    sensor: str
    time: float
    measurements: FloatArray
    covariances: FloatArray | None = None
    range_rates: FloatArray | None = None
    class_masses: tuple[MassFunction | None, ...] | None = None
    model: MeasurementModel | None = field(default=None, compare=False)

    @classmethod
    def measured(
        cls,
        sensor: str,
        time: float,
        model: MeasurementModel,
        measurements: FloatArray,
        covariances: FloatArray | None = None,
    ) -> DetectionReport:
        """Detections measured by ``model``: a model that converts (a radar's,
        :class:`~core.models.measurement.ConvertedModel`) gives the positions, their
        covariances and range-rates; the others' measurements are the positions already
        (with ``covariances``: their own R)."""
        # ConvertedModel by its method: a protocol's isinstance costs tens of µs a report
        converted = getattr(model, "converted", None)
        if converted is not None:
            positions, noises, rates = converted(measurements)
            return cls(sensor, time, positions, noises, rates, model=model)
        return cls(sensor, time, measurements, covariances, model=model)


@dataclass(frozen=True)
class Source:
    """A sensor track that contributes to a fused track."""

    sensor: str
    track: str
    time: float


@dataclass(frozen=True)
class FusedTrackView:
    """One fused track as a step reports it (docs/algorithms.md §6 "Fused output")."""

    id: str
    status: TrackStatus
    reason: StatusReason
    state: FloatArray
    covariance: FloatArray
    sources: tuple[Source, ...]
    classification: ClassAssessment | None
    score: float


@dataclass(frozen=True, eq=False)
class FusedTracks(Sequence[FusedTrackView]):
    """Fused tracks as columns, a row per track (what a step shows): the writers read the
    columns (one array of states, one of covariances); a :class:`FusedTrackView` is made only
    when a track is asked for by index or iteration. ``states`` (n, d) and ``covariances``
    (n, d, d) are the fused estimates, ``scores`` the SPRT scores, the others a value per
    track."""

    ids: tuple[str, ...]
    statuses: tuple[TrackStatus, ...]
    reasons: tuple[StatusReason, ...]
    states: FloatArray
    covariances: FloatArray
    sources: tuple[tuple[Source, ...], ...]
    classifications: tuple[ClassAssessment | None, ...]
    scores: tuple[float, ...]

    @classmethod
    def of(cls, views: Sequence[FusedTrackView]) -> FusedTracks:
        """The columns of ``views`` (themselves when they are columns already)."""
        if isinstance(views, FusedTracks):
            return views
        dim = len(views[0].state) if views else 0
        shape = (len(views), dim)
        return cls(
            ids=tuple(view.id for view in views),
            statuses=tuple(view.status for view in views),
            reasons=tuple(view.reason for view in views),
            states=np.array([view.state for view in views], dtype=np.float64).reshape(shape),
            covariances=np.array([view.covariance for view in views], dtype=np.float64).reshape(
                (*shape, dim)
            ),
            sources=tuple(view.sources for view in views),
            classifications=tuple(view.classification for view in views),
            scores=tuple(view.score for view in views),
        )

    def __len__(self) -> int:
        return len(self.ids)

    def view(self, index: int) -> FusedTrackView:
        """Track ``index`` as a :class:`FusedTrackView` (its arrays are rows of the columns)."""
        return FusedTrackView(
            id=self.ids[index],
            status=self.statuses[index],
            reason=self.reasons[index],
            state=self.states[index],
            covariance=self.covariances[index],
            sources=self.sources[index],
            classification=self.classifications[index],
            score=self.scores[index],
        )

    @overload
    def __getitem__(self, index: int) -> FusedTrackView: ...

    @overload
    def __getitem__(self, index: slice) -> tuple[FusedTrackView, ...]: ...

    def __getitem__(self, index: int | slice) -> FusedTrackView | tuple[FusedTrackView, ...]:
        if isinstance(index, slice):
            return tuple(self.view(at) for at in range(len(self))[index])
        return self.view(range(len(self))[index])

    def __iter__(self) -> Iterator[FusedTrackView]:
        return (self.view(index) for index in range(len(self)))


@dataclass(frozen=True)
class AssociationView:
    """The association decision of a step, by ids.

    ``pairs`` are (fused id, report track id, score, basis): basis
    ``"continuity"`` when the sensor kept reporting the track under the id it
    gave it (score None), ``"association"`` when the method decided (its score).
    ``matrix`` (rows: fused ids then one ``*:<report track id>`` row per column,
    the ``*_t`` rows of [T2T] Table 1; cols: report track ids; values: the
    method's scores over what it decided, NaN on forbidden cells) is filled only
    when an explanation is asked for.
    """

    method: str
    pairs: tuple[tuple[str, str, float | None, str], ...]
    new: tuple[str, ...]
    missed: tuple[str, ...]
    matrix: tuple[tuple[str, ...], tuple[str, ...], FloatArray] | None = None


@dataclass(frozen=True)
class StepResult:
    """The result of applying one input: every live fused track at ``time`` (the engine gives
    them as :class:`FusedTracks`)."""

    seq: int
    time: float
    sensor: str
    tracks: Sequence[FusedTrackView]
    association: AssociationView
