"""The session engine: one deterministic state machine per fusion scene.

Built from a :class:`~core.fusion.config.FusionConfig`, it takes one input
at a time and returns the fused result of that step (docs/design.md "The session
engine"; docs/algorithms.md §6). Same configuration + same inputs in the same
order → bit-identical outputs. Its whole state exports to plain data
(:meth:`SessionEngine.export`) and restores exactly (:meth:`SessionEngine.restore`).

One track-list step ([T2T] Fig 1-2, generalised to N sensors and to time):

1. check the report (sensor known, newer than that sensor's previous report,
   numbers finite and within the bounds of ``core.numerics``, shapes right,
   class likelihoods not all zero);
2. predict the live fused tracks to the report time: each track's state is
   the fusion of every sensor's latest estimate predicted to that time;
3. associate the report's tracks with them by the session's method, with
   class information when both sides carry it (§3.6);
4. each associated report track becomes its sensor's latest estimate of the
   fused track; unassociated ones start tentative tracks;
5. life cycle, shared with the local tracker (:func:`core.lifecycle.advance`):
   hits and misses (a fused track the sensor should have seen — inside its
   field of view, not occluded — and did not report), confirmation (score,
   second sensor, ``min_points``), coasting, phantoms in blind zones or when
   occluded, termination (score, gate emptiness, out of range, phantom
   expiry); a newly confirmed track that matches a phantom hands its
   estimates to the phantom, which keeps its id ([HZ] §5.1,
   :func:`core.lifecycle.hand_over`);
6. class fusion per track from the sensors' latest class evidence.

**Transactions.** A step checkpoints the tracks' fields (their containers
are replaced, never changed in place), the estimate table and the sensor's
local tracker; when anything in it
raises — a refused input or an internal error — they come back and the
export is bit-identical to before. There is no check-before-change: the
step itself is the check.

**Readings.** The time of a step's result is the fusion time (the latest
report time seen): a late report (older than the fusion time, newer than
its sensor's previous report, §6.4) is associated at its own time and then
simply becomes that sensor's latest estimate. The score and the gate volume
use the position components, so the densities of
:class:`~core.lifecycle.LifeCycleConfig` are per unit of position space.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np

from core.arrays import FloatArray, IntArray
from core.association import ScoreMatrix, associate
from core.belief import MassFunction
from core.distance import Estimates, chi2_quantile
from core.distance.cholesky import quadratic_form_and_log_det
from core.errors import InvalidInput, StaleReport, TotalConflict
from core.fusion.classes import ClassAssessment, accumulate_likelihoods, fuse_sensor_classes
from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.detections import local_track_report
from core.fusion.reports import (
    AssociationView,
    DetectionReport,
    FusedTrackView,
    ReportedTrack,
    StepResult,
    TrackReport,
)
from core.fusion.table import EstimateTable
from core.fusion.track import FusedTrack, SensorEstimate
from core.lifecycle import (
    REASON_CODES,
    STATUS_CODES,
    TERMINATED,
    Evidence,
    LifeState,
    StatusReason,
    TrackStatus,
    advance,
    established,
    everywhere,
    hand_over,
    sensor_view,
)
from core.numerics import MAX_TIME, check_magnitudes
from core.tracking.tracker import LocalTracker

EXPORT_VERSION = 1
LIVE = (TrackStatus.TENTATIVE, TrackStatus.CONFIRMED, TrackStatus.COASTING)
CONTINUITY_GATE_PROBABILITY = 1.0 - 1e-9
"""Gate of track continuity: a sensor's own track id is strong evidence, so the
gate only catches a sensor that reuses an id for another object (not the
1-in-1000 noise excursion a 0.999 gate rejects at every thousandth report)."""


@dataclass(frozen=True)
class Decision:
    """One step's association by row (live fused track) and column (report track) index.

    ``pairs`` holds (row, col, score, basis): basis ``"continuity"`` (the sensor
    kept its track id; no method score) or ``"association"`` (the method's
    score). ``scores`` is the method's (sparse) matrix over ``matrix_rows ×
    matrix_cols``, made dense only when a step is explained; ``None`` when
    one side was empty after continuity and the method did not run.
    """

    method: str
    pairs: list[tuple[int, int, float | None, str]]
    new: list[int]
    missed: list[int]
    matrix_rows: IntArray
    matrix_cols: IntArray
    scores: ScoreMatrix | None


class SessionEngine:
    """The fused picture of one session and the rules that update it."""

    def __init__(self, config: FusionConfig) -> None:
        self.config = config
        self.seq = 0
        self.time: float | None = None
        self.next_number = 1
        self.last_report: dict[str, float] = {}
        self.tracks: list[FusedTrack] = []
        self.local_trackers: dict[str, LocalTracker] = {
            sensor.id: LocalTracker(sensor.tracker)
            for sensor in config.sensors
            if sensor.tracker is not None
        }
        layout = config.motion.layout
        self._position = np.asarray(layout.position, dtype=np.int64)
        self._coverage = config.coverage
        self._reliabilities = {sensor.id: sensor.reliability for sensor in config.sensors}
        self._table = EstimateTable(
            [sensor.id for sensor in config.sensors], config.motion, config.state_fusion
        )

    # ------------------------------------------------------------ the step
    def apply(self, report: TrackReport, *, explain: bool = False) -> StepResult:
        """Apply one sensor's track list; returns the step's fused result.

        Raises
        ------
        InvalidInput
            Unknown sensor, bad numbers or shapes, duplicate ids, class evidence
            that does not fit the session's class frame. The state is unchanged.
        StaleReport
            The report is not newer than the sensor's previous report.
        """
        with self._transaction():
            return self._apply(report, explain)

    def apply_detections(self, report: DetectionReport, *, explain: bool = False) -> StepResult:
        """Apply one sensor's detections: its local tracker, then the fusion step.

        The sensor's local tracker ([MTT] Fig 6, ``core.tracking``) updates its
        tracks with the detections; its confirmed tracks updated in this scan
        become the sensor's track list for :meth:`apply`
        (``core.fusion.detections``). Both are one transaction.

        Raises
        ------
        InvalidInput
            Unknown sensor, a sensor without a local tracker (one that sends
            track lists), bad shapes or numbers (any increasing time is accepted:
            the tracker predicts over any step).
        StaleReport
            The detections are not newer than the sensor's previous input:
            time never goes backwards for detections.
        """
        sensor = self.config.sensor(report.sensor)
        tracker = self.local_trackers.get(sensor.id)
        if tracker is None:
            raise InvalidInput(
                f"sensor {sensor.id!r} sends track lists: it has no local tracker for detections "
                "(configure its measurement model)"
            )
        check_time(report.time)
        last = self.last_report.get(sensor.id)
        if last is not None and report.time <= last:
            raise StaleReport(sensor.id, report.time, last)
        check_detection_magnitudes(report)
        with self._transaction(tracker):
            scan = tracker.step(
                report.time, report.measurements, report.covariances, range_rates=report.range_rates
            )
            tracks = local_track_report(
                tracker, scan, self.config.motion.layout, self.config.classes
            )
            return self._apply(TrackReport(sensor.id, report.time, tracks), explain)

    @contextmanager
    def _transaction(self, tracker: LocalTracker | None = None) -> Iterator[None]:
        """A step either succeeds whole or changes nothing (docs/design.md "The session engine").

        Each track's fields are checkpointed (:meth:`FusedTrack.checkpoint`: its
        containers are only ever replaced), as are the counters, the table's
        estimates and the local tracker; on any exception they come back, so the
        export is bit-identical to before.
        """
        seq, time, next_number = self.seq, self.time, self.next_number
        last_report, tracks = dict(self.last_report), self.tracks
        checkpoint = self._table.checkpoint()
        saved = None if tracker is None else tracker.checkpoint()
        fields = [track.checkpoint() for track in tracks]
        self.tracks = list(tracks)
        try:
            yield
        except BaseException:
            self.seq, self.time, self.next_number = seq, time, next_number
            self.last_report, self.tracks = last_report, tracks
            for track, kept in zip(tracks, fields, strict=True):
                track.rollback(kept)
            self._table.rollback(checkpoint)
            if tracker is not None and saved is not None:
                tracker.rollback(saved)
            raise

    def _apply(self, report: TrackReport, explain: bool) -> StepResult:
        """The step of :meth:`apply`, inside its transaction."""
        sensor, incoming = self._check(report)
        t = float(report.time)
        live = [track for track in self.tracks if track.status in LIVE]
        states, covariances = self._fused_at(live, t)
        decision = self._associate(live, states, covariances, report, incoming)

        rows = np.array([pair[0] for pair in decision.pairs], dtype=np.int64)
        cols = np.array([pair[1] for pair in decision.pairs], dtype=np.int64)
        increments = self._hit_increments(states[rows], covariances[rows], incoming, cols, sensor)
        self._record([live[row] for row in rows.tolist()], cols, report, incoming)
        created = self._start(np.asarray(decision.new, dtype=np.int64), report, incoming)
        self.tracks.extend(created)

        self.time = t if self.time is None else max(self.time, t)
        self.last_report[report.sensor] = t
        self.seq += 1
        terminated, confirmed = self._life_cycle(
            sensor, live, states, covariances, rows, increments
        )
        fresh = confirmed + [track for track in created if track.status is TrackStatus.CONFIRMED]
        self._hand_over_to_phantoms(fresh, terminated)
        self._absorb_duplicates(terminated, created)
        return self._result(report, decision, live, terminated, explain)

    # ------------------------------------------------------------ checks
    def _check(self, report: TrackReport) -> tuple[SensorSpec, Estimates]:
        """Validate a report without changing anything; returns its sensor and its estimates."""
        sensor = self.config.sensor(report.sensor)
        check_time(report.time)
        last = self.last_report.get(report.sensor)
        if last is not None and report.time <= last:
            raise StaleReport(report.sensor, report.time, last)
        ids = [track.id for track in report.tracks]
        if len(set(ids)) != len(ids):
            repeated = sorted(track_id for track_id, n in Counter(ids).items() if n > 1)
            raise InvalidInput(f"tracks: ids repeat: {repeated}")
        dim = self.config.dim
        for index, track in enumerate(report.tracks):
            if track.state.shape != (dim,) or track.covariance.shape != (dim, dim):
                raise InvalidInput(
                    f"tracks[{index}] (id {track.id!r}): state must have {dim} components and "
                    f"covariance {dim}×{dim}, got {track.state.shape} and {track.covariance.shape}"
                )
            if self.config.classes is not None or (
                track.class_mass is not None or track.class_likelihoods is not None
            ):
                self._check_classes(track, f"tracks[{index}] (id {track.id!r})")
        estimates = Estimates.of(
            np.array([track.state for track in report.tracks]).reshape(-1, dim),
            np.array([track.covariance for track in report.tracks]).reshape(-1, dim, dim),
            name="tracks",
            dimension=dim,
        )
        assert estimates.covariances is not None
        check_magnitudes(estimates.states, estimates.covariances, "tracks")
        return sensor, estimates

    def _check_classes(self, track: ReportedTrack, where: str) -> None:
        frame = self.config.classes
        if track.class_mass is not None and track.class_likelihoods is not None:
            raise InvalidInput(f"{where}: give a class mass or class likelihoods, not both")
        if frame is None:
            if track.class_mass is not None or track.class_likelihoods is not None:
                raise InvalidInput(
                    f"{where}: the session has no classes, but the track carries class evidence"
                )
            return
        if track.class_mass is not None and track.class_mass.frame != frame:
            raise InvalidInput(
                f"{where}: class mass is not on the session's classes {list(frame.labels)}"
            )
        if track.class_likelihoods is not None:
            likelihoods = track.class_likelihoods
            if likelihoods.shape != (len(frame),):
                raise InvalidInput(f"{where}: need one likelihood per class ({len(frame)})")
            if (
                not np.all(np.isfinite(likelihoods))
                or likelihoods.min() < 0.0
                or likelihoods.max() > 1.0
            ):
                raise InvalidInput(f"{where}: class likelihoods must lie in [0, 1]")
            if likelihoods.max() == 0.0:
                raise InvalidInput(
                    f"{where}: class likelihoods are all zero: the evidence rules out every class"
                )

    # ------------------------------------------------------- prediction
    def _fused_at(self, tracks: list[FusedTrack], time: float) -> tuple[FloatArray, FloatArray]:
        """The fused state of every track at ``time``: its sensors' estimates predicted and fused.

        The table keeps what it computed at the latest times until an estimate
        changes (:class:`~core.fusion.table.EstimateTable`), so the several
        looks of one step at the same time cost one computation per track.
        """
        rows = np.fromiter((track.row for track in tracks), dtype=np.int64, count=len(tracks))
        return self._table.fused_at(rows, time)

    # ------------------------------------------------------- association
    def _associate(
        self,
        live: list[FusedTrack],
        states: FloatArray,
        covariances: FloatArray,
        report: TrackReport,
        incoming: Estimates,
    ) -> Decision:
        """Continuity first (when on), then the session's method on what is left."""
        incoming_states, incoming_covariances = incoming.states, incoming.covariances
        assert incoming_covariances is not None
        kept = self._continuity(live, states, covariances, report, incoming)
        kept_rows = set(kept.values())
        rows = np.array([row for row in range(len(live)) if row not in kept_rows], dtype=np.int64)
        cols = np.array(
            [col for col in range(len(report.tracks)) if col not in kept], dtype=np.int64
        )
        pairs: list[tuple[int, int, float | None, str]] = sorted(
            (row, col, None, "continuity") for col, row in kept.items()
        )
        if len(rows) == 0 or len(cols) == 0:  # nothing left to decide: no method run
            return Decision(
                method=self.config.association_method,
                pairs=pairs,
                new=cols.tolist(),
                missed=rows.tolist(),
                matrix_rows=rows,
                matrix_cols=cols,
                scores=None,
            )
        known_classes, incoming_classes = self._association_classes(live, report)
        result = (
            associate(  # not checked again: the report by _check, the fused side by construction
                Estimates(states[rows], covariances[rows], "known"),
                Estimates(incoming_states[cols], incoming_covariances[cols], "incoming"),
                self.config.association_method,
                self.config.association_options,
                self.config.distance or "sum",
                None if known_classes is None else [known_classes[row] for row in rows],
                None if incoming_classes is None else [incoming_classes[col] for col in cols],
            )
        )
        pairs += [
            (int(rows[k]), int(cols[i]), float(score), "association")
            for k, i, score in zip(
                result.pair_known, result.pair_incoming, result.pair_score, strict=True
            )
        ]
        pairs.sort(key=lambda pair: (pair[0], pair[1]))
        return Decision(
            method=result.method,
            pairs=pairs,
            new=[int(cols[i]) for i in result.new],
            missed=[int(rows[k]) for k in result.missed],
            matrix_rows=rows,
            matrix_cols=cols,
            scores=result.scores,
        )

    def _continuity(
        self,
        live: list[FusedTrack],
        states: FloatArray,
        covariances: FloatArray,
        report: TrackReport,
        incoming: Estimates,
    ) -> dict[int, int]:
        """Report tracks the sensor keeps reporting under the id it gave a fused track.

        ``{report column: fused row}`` for every report track whose (sensor, id)
        is the latest estimate of a live fused track and still passes the χ²
        gate (:data:`CONTINUITY_GATE_PROBABILITY`) on the ``sum`` distance;
        empty when continuity is off.
        """
        if not self.config.track_continuity:
            return {}
        bound = {
            fused.estimates[report.sensor].track: row
            for row, fused in enumerate(live)
            if report.sensor in fused.estimates
        }
        pairs = [(col, bound[t.id]) for col, t in enumerate(report.tracks) if t.id in bound]
        if not pairs:
            return {}
        cols = np.array([col for col, _ in pairs], dtype=np.int64)
        rows = np.array([row for _, row in pairs], dtype=np.int64)
        assert incoming.covariances is not None
        distance, _ = _mahalanobis(
            incoming.states[cols] - states[rows], incoming.covariances[cols] + covariances[rows]
        )
        gate = chi2_quantile(CONTINUITY_GATE_PROBABILITY, self.config.dim)
        passed = distance <= gate
        return dict(zip(cols[passed].tolist(), rows[passed].tolist(), strict=True))

    def _association_classes(
        self, live: list[FusedTrack], report: TrackReport
    ) -> tuple[list[MassFunction] | None, list[MassFunction] | None]:
        """Class masses of both sides when the report carries class evidence (§3.6)."""
        frame = self.config.classes
        if frame is None or not any(
            t.class_mass is not None or t.class_likelihoods is not None for t in report.tracks
        ):
            return None, None
        vacuous = MassFunction.vacuous(frame)
        incoming = []
        for track in report.tracks:
            if track.class_mass is not None:
                incoming.append(_normalised_or_vacuous(track.class_mass))
            elif track.class_likelihoods is not None:
                try:
                    incoming.append(accumulate_likelihoods(None, frame, track.class_likelihoods)[0])
                except TotalConflict:
                    incoming.append(vacuous)
            else:
                incoming.append(vacuous)
        known = []
        for fused in live:
            assessment = self._classify(fused)
            known.append(
                vacuous if assessment is None or assessment.mass is None else assessment.mass
            )
        return known, incoming

    # ------------------------------------------------------- life cycle
    def _hit_increments(
        self,
        states: FloatArray,
        covariances: FloatArray,
        incoming: Estimates,
        cols: IntArray,
        sensor: SensorSpec,
    ) -> FloatArray:
        """Score increments ΔL of every associated pair, on the position components."""
        if len(cols) == 0:
            return np.zeros(0)
        assert incoming.covariances is not None
        position = self._position
        combined = (covariances + incoming.covariances[cols])[:, position][:, :, position]
        innovation = incoming.states[cols][:, position] - states[:, position]
        distance, log_det = _mahalanobis(innovation, combined)
        score = self.config.management.score_model(sensor.p_detect)
        return score.hit_increment(distance, log_det, len(self._position))

    def _record(
        self, tracks: list[FusedTrack], cols: IntArray, report: TrackReport, incoming: Estimates
    ) -> None:
        """Report tracks ``cols`` become their sensor's latest estimates of ``tracks``."""
        if not tracks:
            return
        states, covariances = incoming.states, incoming.covariances
        assert covariances is not None
        sensor = report.sensor
        rows = np.fromiter((fused.row for fused in tracks), dtype=np.int64, count=len(tracks))
        self._table.write(rows, sensor, states[cols], covariances[cols], report.time)
        for fused, col in zip(tracks, cols.tolist(), strict=True):
            reported = report.tracks[col]
            previous = fused.estimates.get(sensor)
            fused.set_estimate(
                sensor,
                SensorEstimate(
                    track=reported.id,
                    time=report.time,
                    class_mass=self._class_evidence(reported, previous),
                ),
            )

    def _class_evidence(
        self, reported: ReportedTrack, previous: SensorEstimate | None
    ) -> MassFunction | None:
        """A mass report replaces the sensor's mass; likelihoods accumulate on it (§5)."""
        if reported.class_mass is not None:
            return reported.class_mass
        if reported.class_likelihoods is not None and self.config.classes is not None:
            before = None if previous is None else previous.class_mass
            try:
                return accumulate_likelihoods(
                    before, self.config.classes, reported.class_likelihoods
                )[0]
            except TotalConflict:
                # The new evidence contradicts the sensor's past totally: start again from it.
                return accumulate_likelihoods(
                    None, self.config.classes, reported.class_likelihoods
                )[0]
        return None if previous is None else previous.class_mass

    def _life_cycle(
        self,
        sensor: SensorSpec,
        live: list[FusedTrack],
        states: FloatArray,
        covariances: FloatArray,
        hit_rows: IntArray,
        increments: FloatArray,
    ) -> tuple[list[FusedTrack], list[FusedTrack]]:
        """:func:`core.lifecycle.advance` over every track that is not terminated.

        Hits and misses are the step's (``live`` at the report time: ``states``,
        ``covariances`` as predicted before the update); coverage is looked at
        at the fusion time. Returns the tracks terminated and confirmed by it.
        """
        assert self.time is not None
        management = self.config.management
        candidates = [track for track in self.tracks if track.status is not TrackStatus.TERMINATED]
        count = len(candidates)
        if count == 0:
            return [], []
        index = {id(track): k for k, track in enumerate(candidates)}
        live_index = np.fromiter((index[id(track)] for track in live), np.int64, len(live))
        before = _read_life(candidates)
        detected = np.zeros(count, dtype=bool)
        hit_increment = np.zeros(count)
        detected[live_index[hit_rows]] = True
        hit_increment[live_index[hit_rows]] = increments
        seen = np.zeros(count, dtype=bool)
        hidden = np.zeros(count, dtype=bool)
        gate_log_det = np.zeros(count)
        position = self._position
        if live:
            live_status = before.status[live_index]
            established_rows = established(live_status)
            if len(position) >= 2:
                plane = states[:, position[:2]]
                live_seen, live_hidden = sensor_view(
                    sensor.fov, plane, plane[established_rows], management.occlusion_radius
                )
            else:
                _, live_seen, live_hidden = everywhere(len(live))
            seen[live_index], hidden[live_index] = live_seen, live_hidden
            established_miss = np.flatnonzero(live_seen & ~detected[live_index] & established_rows)
            if len(established_miss):
                gate_log_det[live_index[established_miss]] = self._gate_log_dets(
                    [live[row] for row in established_miss.tolist()],
                    covariances[established_miss],
                )
        fused_states, _ = self._fused_at(candidates, self.time)
        codes = (
            self._coverage.visibility(fused_states[:, position[:2]])
            if len(position) >= 2
            else everywhere(count)[0]
        )
        after, confirmed = advance(
            management,
            before,
            Evidence(
                time=self.time,
                detected=detected,
                hit_increment=hit_increment,
                seen=seen,
                miss_increment=management.score_model(sensor.p_detect).miss_increment,
                gate_log_det=gate_log_det,
                gate_dim=len(position),
                visibility=codes,
                occluded=hidden,
                sensors=np.array([len(t.estimates) for t in candidates], dtype=np.int64),
            ),
        )
        _write_life(candidates, after, before)
        ended = (after.status == TERMINATED) & (before.status != TERMINATED)
        return (
            [candidates[k] for k in np.flatnonzero(ended).tolist()],
            [candidates[k] for k in np.flatnonzero(confirmed).tolist()],
        )

    def _gate_log_dets(self, tracks: list[FusedTrack], predicted: FloatArray) -> FloatArray:
        """log|S| of each track's gate: its predicted covariance plus its newest estimate's,
        on the position components ([HZ] §4.2)."""
        position = self._position
        gates = []
        for fused, predicted_covariance in zip(tracks, predicted, strict=True):
            # ties by sensor id: not by dict order, which a restore through a store may change
            newest = max(sorted(fused.estimates), key=lambda sensor: fused.estimates[sensor].time)
            _, covariance = self._table.estimate(fused.row, newest)
            gates.append(
                predicted_covariance[np.ix_(position, position)]
                + covariance[np.ix_(position, position)]
            )
        return np.asarray(np.linalg.slogdet(np.array(gates))[1], dtype=np.float64)

    def _start(self, cols: IntArray, report: TrackReport, incoming: Estimates) -> list[FusedTrack]:
        """A fused track for each of the report tracks ``cols``: tentative, or confirmed at
        once when the session's only sensor is tracked here (its local tracker reports only
        the tracks it has confirmed, and with no other sensor a second test could only
        delay them), at the score ceiling. With several sensors the fused layer tests
        again: it absorbs a sensor's duplicates and waits for corroboration."""
        management = self.config.management
        sensor = self.config.sensor(report.sensor)
        initial = management.score_model(sensor.p_detect)
        status, reason, score = TrackStatus.TENTATIVE, StatusReason.INITIATED, initial.initial
        if sensor.tracker is not None and len(self.config.sensors) == 1:
            status, reason = TrackStatus.CONFIRMED, StatusReason.LOCAL_CONFIRMED
            score = min(management.score_ceiling, management.confirm_threshold)
        created = []
        for row in self._table.add_rows(len(cols)).tolist():
            created.append(
                FusedTrack(
                    id=f"F{self.next_number}",
                    status=status,
                    reason=reason,
                    score=score,
                    row=row,
                )
            )
            self.next_number += 1
        self._record(created, cols, report, incoming)
        return created

    def _hand_over_to_phantoms(self, fresh: list[FusedTrack], terminated: list[FusedTrack]) -> None:
        """A track confirmed in this step that matches a phantom gives it its estimates ([HZ] §5.1)."""
        phantoms = [track for track in self.tracks if track.status is TrackStatus.PHANTOM]
        self._merge(phantoms, fresh, StatusReason.MERGED_INTO_PHANTOM, terminated)

    def _absorb_duplicates(self, terminated: list[FusedTrack], created: list[FusedTrack]) -> None:
        """A tentative track that duplicates an established track of other sensors joins it.

        A sensor's first report of an object is associated by the method's gate;
        when that first decision misses (a 1 − gate_probability event per true
        pair), the sensor starts a second fused track of the same object. Such a
        tentative track, gated against a confirmed or coasting track that has
        no estimate from its sensors, is merged into it.
        """
        # a track created confirmed (a local tracker's) this step is a newcomer as well
        fresh = {id(track) for track in created if track.status is TrackStatus.CONFIRMED}
        tentative = [
            track
            for track in self.tracks
            if track.status is TrackStatus.TENTATIVE
            or (id(track) in fresh and track.status is TrackStatus.CONFIRMED)
        ]
        established_tracks = [
            track
            for track in self.tracks
            if track.status in (TrackStatus.CONFIRMED, TrackStatus.COASTING)
            and id(track) not in fresh
        ]
        self._merge(established_tracks, tentative, StatusReason.DUPLICATE, terminated)

    def _merge(
        self,
        keepers: list[FusedTrack],
        newcomers: list[FusedTrack],
        reason: StatusReason,
        terminated: list[FusedTrack],
    ) -> None:
        """Gate ``newcomers`` against ``keepers`` (GNN, ``sum`` distance); merge disjoint pairs.

        The keeper keeps its id, takes the newcomer's estimates and becomes
        (or stays) confirmed; the newcomer is terminated with ``reason``.
        """
        if not keepers or not newcomers or self.time is None:
            return
        keeper_states, keeper_covariances = self._fused_at(keepers, self.time)
        newcomer_states, newcomer_covariances = self._fused_at(newcomers, self.time)
        decision = associate(
            (keeper_states, keeper_covariances),
            (newcomer_states, newcomer_covariances),
            "gnn",
            {"gate_probability": self.config.management.gate_probability},
            "sum",
        )
        pairs = [
            (keepers[row], newcomers[col])
            for row, col in zip(decision.pair_known, decision.pair_incoming, strict=True)
            # a sensor that reports both as distinct objects knows better
            if not set(keepers[row].estimates) & set(newcomers[col].estimates)
        ]
        if not pairs:
            return
        for keeper, newcomer in pairs:
            for sensor_id, estimate in newcomer.estimates.items():
                keeper.set_estimate(sensor_id, estimate)
                self._table.move(newcomer.row, keeper.row, sensor_id)
        merged = [keeper for keeper, _ in pairs] + [newcomer for _, newcomer in pairs]
        count = len(pairs)
        _write_life(
            merged,
            hand_over(
                _read_life(merged),
                np.arange(count, dtype=np.int64),
                np.arange(count, 2 * count, dtype=np.int64),
                reason,
            ),
        )
        terminated.extend(newcomer for _, newcomer in pairs)

    # ------------------------------------------------------------ output
    def _classify(self, fused: FusedTrack) -> ClassAssessment | None:
        if self.config.classes is None:
            return None
        masses = {s: e.class_mass for s, e in fused.estimates.items() if e.class_mass is not None}
        return fuse_sensor_classes(masses, self._reliabilities) if masses else None

    def _result(
        self,
        report: TrackReport,
        decision: Decision,
        live: list[FusedTrack],
        terminated: list[FusedTrack],
        explain: bool,
    ) -> StepResult:
        assert self.time is not None
        ending = {id(track) for track in terminated}
        shown = sorted(
            (
                track
                for track in self.tracks
                if track.status is not TrackStatus.TERMINATED or id(track) in ending
            ),
            key=lambda track: track.number,
        )
        states, covariances = self._fused_at(shown, self.time)
        views = []
        for track, state, plain, covariance in zip(
            shown, states, states.tolist(), covariances, strict=True
        ):
            if track.status is not TrackStatus.TERMINATED:
                track.remember(self.time, plain)
            views.append(self._view(track, state, covariance))
        if terminated:
            self._keep(
                [track for track in self.tracks if track.status is not TrackStatus.TERMINATED]
            )
        association = AssociationView(
            method=decision.method,
            pairs=tuple(
                (live[row].id, report.tracks[col].id, score, basis)
                for row, col, score, basis in decision.pairs
            ),
            new=tuple(report.tracks[col].id for col in decision.new),
            missed=tuple(live[row].id for row in decision.missed),
            matrix=self._explained(report, decision, live) if explain else None,
        )
        return StepResult(
            seq=self.seq,
            time=self.time,
            sensor=report.sensor,
            tracks=tuple(views),
            association=association,
        )

    @staticmethod
    def _explained(
        report: TrackReport, decision: Decision, live: list[FusedTrack]
    ) -> tuple[tuple[str, ...], tuple[str, ...], FloatArray]:
        """The decision matrix: [T2T] Table 1 with a ``*:<track id>`` row per report track."""
        known = [live[row].id for row in decision.matrix_rows]
        incoming = [report.tracks[col].id for col in decision.matrix_cols]
        if decision.scores is None:
            return tuple(known), tuple(incoming), np.zeros((len(known), len(incoming)))
        return decision.scores.table(known, incoming)

    def _keep(self, tracks: list[FusedTrack]) -> None:
        """``tracks`` become the engine's tracks, rows 0, 1, … of the table in that order."""
        self._table.keep(np.fromiter((track.row for track in tracks), np.int64, len(tracks)))
        for row, track in enumerate(tracks):
            track.row = row
        self.tracks = tracks

    def _view(self, track: FusedTrack, state: FloatArray, covariance: FloatArray) -> FusedTrackView:
        return FusedTrackView(
            id=track.id,
            status=track.status,
            reason=track.reason,
            state=state,
            covariance=covariance,
            sources=track.sources(),
            classification=self._classify(track),
            score=track.score,
        )

    def picture(self, time: float | None = None) -> tuple[FusedTrackView, ...]:
        """The live fused tracks at ``time`` (default: the fusion time); changes nothing.

        The service's ``GET …/tracks``: each track's sensor estimates are
        predicted to ``time`` and fused, exactly as a step would.
        """
        at = self.time if time is None else float(time)
        if at is None or not self.tracks:
            return ()
        if not math.isfinite(at):
            raise InvalidInput(f"time must be finite, got {at!r}")
        shown = sorted(self.tracks, key=lambda track: track.number)
        states, covariances = self._fused_at(shown, at)
        return tuple(
            self._view(track, state, covariance)
            for track, state, covariance in zip(shown, states, covariances, strict=True)
        )

    # ------------------------------------------------------ persistence
    def export(self) -> dict[str, Any]:
        """The whole state as plain data (JSON-ready; floats round-trip exactly)."""
        return {
            "version": EXPORT_VERSION,
            "seq": self.seq,
            "time": self.time,
            "next_number": self.next_number,
            "last_report": dict(sorted(self.last_report.items())),
            "tracks": [
                track.to_plain(
                    {sensor: self._table.estimate(track.row, sensor) for sensor in track.estimates}
                )
                for track in self.tracks
            ],
            "local_trackers": {
                sensor: tracker.export() for sensor, tracker in sorted(self.local_trackers.items())
            },
        }

    @classmethod
    def restore(cls, config: FusionConfig, state: dict[str, Any]) -> SessionEngine:
        """Rebuild an engine from :meth:`export`'s output and the same configuration."""
        if state.get("version") != EXPORT_VERSION:
            raise InvalidInput(f"unknown engine export version {state.get('version')!r}")
        engine = cls(config)
        engine.seq = int(state["seq"])
        engine.time = None if state["time"] is None else float(state["time"])
        engine.next_number = int(state["next_number"])
        engine.last_report = {str(k): float(v) for k, v in state["last_report"].items()}
        restored = [FusedTrack.from_plain(plain, config.classes) for plain in state["tracks"]]
        tracks = [track for track, _ in restored]
        empty = [track.id for track in tracks if not track.estimates]
        if empty:
            raise InvalidInput(f"exported tracks without any sensor estimate: {empty}")
        rows = engine._table.add_rows(len(tracks)).tolist()
        for (track, kinematics), row in zip(restored, rows, strict=True):
            track.row = row
            for sensor, estimate in track.estimates.items():
                if sensor not in engine._table.slots:
                    raise InvalidInput(
                        f"exported track {track.id} has an estimate of sensor {sensor!r}, "
                        "which the config does not name"
                    )
                state_, covariance = kinematics[sensor]
                engine._table.write(
                    np.array([row]), sensor, state_[None], covariance[None], estimate.time
                )
        engine.tracks = tracks
        for sensor, plain in state["local_trackers"].items():
            tracker_config = config.sensor(sensor).tracker
            if tracker_config is None:
                raise InvalidInput(
                    f"exported state has a local tracker for {sensor!r}, the config none"
                )
            engine.local_trackers[sensor] = LocalTracker.restore(tracker_config, plain)
        return engine


def check_time(time: float) -> None:
    """A report time must be finite and of magnitude at most :data:`core.numerics.MAX_TIME`."""
    if not math.isfinite(time):
        raise InvalidInput(f"time must be finite, got {time!r}")
    if abs(time) > MAX_TIME:
        raise InvalidInput(f"time: magnitude {time!r} is beyond the limit {MAX_TIME:g} s")


def check_detection_magnitudes(report: DetectionReport) -> None:
    """Measurements within :data:`core.numerics.MAX_MAGNITUDE`, their noise within the
    variance bounds (shapes and finiteness are the tracker's to check)."""
    measurements = np.asarray(report.measurements, dtype=np.float64)
    if measurements.ndim != 2:
        return
    covariances = (
        None if report.covariances is None else np.asarray(report.covariances, dtype=np.float64)
    )
    if covariances is None or covariances.shape != (*measurements.shape, measurements.shape[1]):
        covariances = np.ones((len(measurements), 1, 1))
    check_magnitudes(measurements, covariances, "detections", ("z", "r"))


def _read_life(tracks: list[FusedTrack]) -> LifeState:
    """The life of ``tracks`` as arrays (:class:`core.lifecycle.LifeState`)."""
    return LifeState(
        status=np.array([STATUS_CODES[t.status] for t in tracks], dtype=np.int64),
        reason=np.array([REASON_CODES[t.reason] for t in tracks], dtype=np.int64),
        score=np.array([t.score for t in tracks], dtype=np.float64),
        hits=np.array([t.hits for t in tracks], dtype=np.int64),
        empty_gate=np.array([t.empty_gate_probability for t in tracks], dtype=np.float64),
        phantom_since=np.array(
            [math.nan if t.phantom_since is None else t.phantom_since for t in tracks],
            dtype=np.float64,
        ),
    )


def _write_life(tracks: list[FusedTrack], life: LifeState, before: LifeState | None = None) -> None:
    """Each track's status, reason, score, hits, empty-gate probability and phantom time
    (only of the tracks whose life differs from ``before``, when given)."""
    rows = np.arange(len(tracks))
    if before is not None:
        since, since_before = life.phantom_since, before.phantom_since
        same_since = (since == since_before) | (np.isnan(since) & np.isnan(since_before))
        changed = (
            (life.status != before.status)
            | (life.reason != before.reason)
            | (life.score != before.score)
            | (life.hits != before.hits)
            | (life.empty_gate != before.empty_gate)
            | ~same_since
        )
        rows = np.flatnonzero(changed)
    chosen = life.select(rows)
    for row, status, reason, score, hits, empty_gate, entered in zip(
        rows.tolist(),
        chosen.statuses(),
        chosen.reasons(),
        chosen.score.tolist(),
        chosen.hits.tolist(),
        chosen.empty_gate.tolist(),
        chosen.phantom_since.tolist(),
        strict=True,
    ):
        track = tracks[row]
        track.status, track.reason, track.score, track.hits = status, reason, score, int(hits)
        track.empty_gate_probability = empty_gate
        track.phantom_since = None if math.isnan(entered) else entered


def _mahalanobis(differences: FloatArray, covariances: FloatArray) -> tuple[FloatArray, FloatArray]:
    """D = Δᵀ C⁻¹ Δ and log|C| of every row (batched Cholesky of ``core.distance``)."""
    return quadratic_form_and_log_det(differences.T, np.moveaxis(covariances, 0, -1))


def _normalised_or_vacuous(mass: MassFunction) -> MassFunction:
    try:
        return mass.normalized()
    except TotalConflict:
        return MassFunction.vacuous(mass.frame)
