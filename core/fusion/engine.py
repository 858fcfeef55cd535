"""The session engine: one deterministic state machine per fusion scene.

Built from a :class:`~core.fusion.config.FusionConfig`, it takes one input
at a time and returns the fused result of that step (docs/design.md "The session
engine"; docs/algorithms.md §6). Same configuration + same inputs in the same
order → bit-identical outputs. Its whole state exports to plain data
(:meth:`SessionEngine.export`) and restores exactly (:meth:`SessionEngine.restore`).

One track-list step ([T2T] Fig 1-2, generalised to N sensors and to time) is
an assembly of the pipeline parts of :mod:`core.pipeline` (docs/algorithms.md
§7.5; the local tracker is the other), over the engine's rows: the estimate
table (kinematics, report times) and, row for row, the tracks' numbers and
lives (:class:`~core.fusion.track.FusedRows`):

1. check the report (sensor known, newer than that sensor's previous report,
   numbers finite and within the bounds of ``core.numerics``, shapes right,
   class likelihoods not all zero);
2. predict the live fused tracks to the report time: each track's state is
   the fusion of every sensor's latest estimate predicted to that time;
3. associate the report's tracks with them by the session's method, with
   class information when both sides carry it (§3.6; :mod:`core.fusion.associate`);
4. each associated report track becomes its sensor's latest estimate of the
   fused track; unassociated ones start tentative tracks;
5. life cycle, shared with the local tracker (:func:`core.lifecycle.advance`):
   hits and misses (a fused track the sensor should have seen — inside its
   field of view, not occluded — and did not report), confirmation (score,
   second sensor, ``min_points``), coasting, phantoms in blind zones or when
   occluded, termination (score, gate emptiness, out of range, phantom
   expiry); a newly confirmed track that matches a phantom hands its
   estimates to the phantom, which keeps its id ([HZ] §5.1,
   :func:`core.lifecycle.hand_over`); one that is the only track confirmed where a
   recently ended track is predicted takes that track's id (§8.15,
   :meth:`SessionEngine._hand_over_ended`);
6. class fusion per track from the sensors' latest class evidence.

**Transactions.** A step checkpoints the tracks' fields (their containers
are replaced, never changed in place), the rows (never changed in place), the
estimate table and the sensor's local tracker; when anything in it
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

import dataclasses
import math
import re
from collections import Counter
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np

from core.arrays import BoolArray, FloatArray, IntArray
from core.belief import MassFunction
from core.distance import Estimates
from core.distance.pairwise import chi2_quantile
from core.errors import InvalidInput, StaleReport, TotalConflict
from core.fusion.associate import Decision, associate_report
from core.fusion.classes import ClassAssessment, accumulate_likelihoods, fuse_sensor_classes
from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.detections import local_track_report
from core.fusion.reorder import ReorderBuffer
from core.fusion.reports import (
    AssociationView,
    DetectionReport,
    FusedTracks,
    FusedTrackView,
    ReportedTrack,
    StepResult,
    TrackReport,
)
from core.fusion.table import EstimateTable
from core.fusion.track import (
    HISTORY_LENGTH,
    EndedTrack,
    FusedRows,
    FusedTrack,
    Kinematics,
    SensorEstimate,
)
from core.lifecycle import (
    COASTING,
    CONFIRMED,
    LIFE_ARRAYS,
    PHANTOM,
    REASON_CODES,
    STATUS_CODES,
    TENTATIVE,
    TERMINATED,
    Evidence,
    LifeState,
    StatusReason,
    TrackStatus,
    advance,
    established,
    hand_over,
    initiated,
    reason_code,
)
from core.numerics import MAX_TIME, check_magnitudes
from core.pipeline.evidence import HIDING_MISSES, coasting_misses, coverage_look, hits, look
from core.pipeline.gate import position_distances
from core.pipeline.handover import ended_hand_over_pairs, hand_over_pairs
from core.pipeline.rows import TrackRows, ended
from core.tracking.tracker import LocalTracker

EXPORT_VERSION = 4
"""4: the recently ended fused tracks (``ended``, §8.15), which an older export restores
without; 3: the central tracker's reorder buffer (``central`` is its state before the oldest
buffered scan and the buffered scans, :meth:`ReorderBuffer.export`); 2: the central tracker's
state (``central``, §8.9), which restores with an empty buffer. A version-1 export restores
with an empty central tracker (its sessions' detecting sensors were tracked one by one: their
local trackers are dropped, the fused tracks go on and end as their sources' silence says)."""
OVERDUE_REVISITS = 2.5
"""A source is overdue on a fused track after this many of its revisits without updating it:
one ordinary miss (P_D 0.9: one scan in ten) never makes a track coast (§8.6)."""
STALE_REVISITS = 5.0
"""After this many revisits of every source of a fused track without an update, any sensor's
silence about it is a miss (§8.2: a track whose sources all stopped reporting still ends)."""
RESTART_REVISITS = 3.0
"""An ended fused track is remembered for this many revisits of the session's slowest sensor
(§8.15): a restart of its target is one detection that starts a track and one that confirms
it (single-point starts, ``min_points`` 2), with one ordinary miss before either, at most
three scans of the slowest sensor that sees it (fewer of a faster one)."""
_MERGED = (
    reason_code(StatusReason.MERGED_INTO_PHANTOM),
    reason_code(StatusReason.DUPLICATE),
)
"""Reasons of a termination that is no end: the track lives on in the one it joined."""
LIVE = (TrackStatus.TENTATIVE, TrackStatus.CONFIRMED, TrackStatus.COASTING)
_LIVE_CODES = tuple(STATUS_CODES[status] for status in LIVE)


class SessionEngine:
    """The fused picture of one session and the rules that update it."""

    def __init__(self, config: FusionConfig) -> None:
        self.config = config
        self.seq = 0
        self.time: float | None = None
        self.next_number = 1
        self.last_report: dict[str, float] = {}
        self.revisits: dict[str, float] = {}
        """Each source's revisit, learned from the intervals between its reports (§8.6)."""
        self.tracks: list[FusedTrack] = []
        """The fused tracks, ``tracks[k].row == k`` (their estimates and lives: ``_rows``)."""
        self.local_trackers: dict[str, LocalTracker] = {
            sensor.id: LocalTracker(sensor.tracker)
            for sensor in config.sensors
            if sensor.tracker is not None and not config.tracked_centrally(sensor.id)
        }
        self.central: LocalTracker | None = (
            None if config.central_tracker is None else LocalTracker(config.central_tracker)
        )
        """The central tracker over the detections of several sensors (§8.9), or None."""
        self.reorder = ReorderBuffer()
        """The central tracker's recent scans, to put a late one in its place (§8.9)."""
        self.ended: tuple[EndedTrack, ...] = ()
        """The fused tracks ended within the memory (§8.15), in the order they ended."""
        layout = config.motion.layout
        self._position = np.asarray(layout.position, dtype=np.int64)
        self._coverage = config.coverage
        self._reliabilities = self._source_reliabilities(config)
        self._table = EstimateTable(list(config.sources), config.motion, config.state_fusion)
        self._rows = FusedRows(self._table)

    # ------------------------------------------------------------ sensors
    def join(self, sensor: SensorSpec) -> None:
        """A sensor joins the session (an open session seeing it first), after the others:
        its slot in the estimate table, its local tracker; nothing else changes."""
        config = dataclasses.replace(self.config, sensors=(*self.config.sensors, sensor))
        self._table.add_slot(sensor.id)
        self._set_config(config)
        if sensor.tracker is not None and not config.tracked_centrally(sensor.id):
            self.local_trackers[sensor.id] = LocalTracker(sensor.tracker)

    def leave(self, sensor: str) -> None:
        """Undo :meth:`join` of ``sensor``, the last to join, before any of its inputs applied."""
        self._table.drop_slot(sensor)
        kept = tuple(spec for spec in self.config.sensors if spec.id != sensor)
        self._set_config(dataclasses.replace(self.config, sensors=kept))
        self.local_trackers.pop(sensor, None)

    @staticmethod
    def _source_reliabilities(config: FusionConfig) -> dict[str, float]:
        """λ of each source's class evidence ([MTT] eq 7): the sensors', and 1 for the central
        tracker, whose detections' evidence is discounted by their own sensor's."""
        return {source: config.source(source).reliability for source in config.sources}

    def _is_central(self, source: str) -> bool:
        """Whether ``source`` is the central tracker's source (not a sensor)."""
        return self.central is not None and source == self.config.central_source

    def tracker_of(self, sensor: str) -> LocalTracker | None:
        """The tracker of ``sensor``'s detections: the central tracker, its own, or None (a
        sensor that sends track lists)."""
        if self.central is not None and self.config.tracked_centrally(sensor):
            return self.central
        return self.local_trackers.get(sensor)

    def _set_config(self, config: FusionConfig) -> None:
        self.config = config
        self._coverage = config.coverage
        self._reliabilities = self._source_reliabilities(config)
        self._rows.sorted_slots = sorted(self._table.slots.items())

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
        if self._is_central(report.sensor):
            raise InvalidInput(
                f"{report.sensor!r} is the central tracker's source: it takes no track lists",
                loc=("sensor",),
            )
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
        if self.central is not None and self.config.tracked_centrally(sensor.id):
            return self._apply_central(self.central, sensor, report, explain)
        tracker = self.local_trackers.get(sensor.id)
        if tracker is None:
            raise InvalidInput(
                f"sensor {sensor.id!r} sends track lists: it has no local tracker for detections "
                "(configure its measurement model)",
                loc=("sensor",),
            )
        check_time(report.time)
        last = self.last_report.get(sensor.id)
        if last is not None and report.time <= last:
            raise StaleReport(sensor.id, report.time, last)
        check_detection_magnitudes(report)
        with self._transaction(tracker):
            scan = tracker.step(
                report.time,
                report.measurements,
                report.covariances,
                range_rates=report.range_rates,
                class_masses=report.class_masses,
                model=report.model,
            )
            tracks = local_track_report(
                tracker, scan, self.config.motion.layout, self.config.classes
            )
            return self._apply(TrackReport(sensor.id, report.time, tracks), explain)

    def _apply_central(
        self, central: LocalTracker, sensor: SensorSpec, report: DetectionReport, explain: bool
    ) -> StepResult:
        """One sensor's detections through the central tracker (§8.9), then the fusion step.

        The central tracker takes every centrally tracked sensor's detections in time
        order (two sensors may report at the same instant): a report a little older than
        the tracker's latest is put in its place by the reorder buffer
        (:mod:`core.fusion.reorder`), one older than its window is stale; the fused layer
        then takes the tracker's tracks at its latest time. Each detection's class evidence is discounted by its
        sensor's reliability ([MTT] eq 7) before it enters its track's class mass. Every
        track the tracker keeps (confirmed, coasting or phantom) is the track list of the
        central source at every step, so a fused track it carries follows it: confirmed
        at once, ended when the tracker ends it.
        """
        check_time(report.time)
        check_detection_magnitudes(report)
        masses = report.class_masses
        if masses is not None and sensor.reliability < 1.0:
            masses = tuple(
                None if mass is None else mass.discount(sensor.reliability) for mass in masses
            )
        source = self.config.central_source
        with self._transaction(central):
            scan = self.reorder.step(
                central,
                report.time,
                sensor.id,
                report.measurements,
                report.covariances,
                range_rates=report.range_rates,
                class_masses=masses,
                model=report.model,
            )
            tracks = local_track_report(
                central, scan, self.config.motion.layout, self.config.classes, every=True
            )
            result = self._apply(TrackReport(source, scan.time, tracks), explain)
            last = self.last_report.get(sensor.id, report.time)
            self.last_report[sensor.id] = max(last, report.time)
            return dataclasses.replace(result, sensor=sensor.id)

    @contextmanager
    def _transaction(self, tracker: LocalTracker | None = None) -> Iterator[None]:
        """A step either succeeds whole or changes nothing (docs/design.md "The session engine").

        Each track's fields are checkpointed (:meth:`FusedTrack.checkpoint`: its
        containers are only ever replaced), as are the counters, the rows (never
        changed in place), the table's estimates and the local tracker; on any
        exception they come back, so the export is bit-identical to before.
        """
        seq, time, next_number = self.seq, self.time, self.next_number
        last_report, tracks, revisits = dict(self.last_report), self.tracks, dict(self.revisits)
        checkpoint, rows = self._table.checkpoint(), self._rows.rows
        saved = None if tracker is None else tracker.checkpoint()
        buffered, ended = self.reorder.scans, self.ended
        fields = [track.checkpoint() for track in tracks]
        self.tracks = list(tracks)
        try:
            yield
        except BaseException:
            self.seq, self.time, self.next_number = seq, time, next_number
            self.last_report, self.tracks, self._rows.rows = last_report, tracks, rows
            self.revisits = revisits
            for track, kept in zip(tracks, fields, strict=True):
                track.rollback(kept)
            self._table.rollback(checkpoint)
            if tracker is not None and saved is not None:
                tracker.rollback(saved)
            self.reorder.scans = buffered
            self.ended = ended
            raise

    def _apply(self, report: TrackReport, explain: bool) -> StepResult:
        """The step of :meth:`apply`, inside its transaction: the pipeline of
        ``core.pipeline`` over the table's rows."""
        sensor, incoming = self._check(report)
        t = float(report.time)
        status_before = self._rows.rows.life.status
        live = np.flatnonzero(_is_live(self._rows.rows.life.status))
        states, covariances = self._table.fused_at(live, t)  # predict
        decision = associate_report(
            self.config,
            [self.tracks[row] for row in live.tolist()],
            states,
            covariances,
            report,
            incoming,
            self._classify,
            established(self._rows.rows.life.status[live]),
        )

        rows = np.array([pair[0] for pair in decision.pairs], dtype=np.int64)
        cols = np.array([pair[1] for pair in decision.pairs], dtype=np.int64)
        # a track its source coasted is that source's miss, not an estimate (§8.10)
        coasted = np.array([track.coasted for track in report.tracks], dtype=bool)
        missed_by_source = np.zeros(len(live), dtype=bool)
        missed_by_source[rows[coasted[cols]]] = True
        rows, cols = rows[~coasted[cols]], cols[~coasted[cols]]
        new = np.asarray(decision.new, dtype=np.int64)
        increments = (
            np.zeros(len(rows))  # the central tracker's tracks passed its test already (§8.9)
            if self._is_central(report.sensor)
            else self._hit_increments(states[rows], covariances[rows], incoming, cols, sensor)
        )
        self._record(live[rows], cols, report, incoming)  # update
        # nor does a phantom of the central tracker start one: it is a prediction (§8.2)
        startable = ~coasted & ~self._phantom_reports(report)
        created = self._start(new[startable[new]], report, incoming)

        self.time = t if self.time is None else max(self.time, t)
        self._learn_revisit(report.sensor, t)
        self.last_report[report.sensor] = t
        self.seq += 1
        terminated, confirmed = self._life_cycle(
            sensor, live, states, covariances, rows, increments, missed_by_source
        )
        status = self._rows.rows.life.status
        fresh = np.concatenate([confirmed, created[status[created] == CONFIRMED]])
        terminated = self._hand_over_to_phantoms(fresh, terminated)  # hand-over
        terminated = self._absorb_duplicates(terminated, created)
        terminated = self._join_duplicates(terminated, live[rows], report.sensor)
        terminated = self._hand_over_ended(fresh, terminated, status_before)
        return self._result(report, decision, live, terminated, explain)  # and keep the rows

    # ------------------------------------------------------------ checks
    def _check(self, report: TrackReport) -> tuple[SensorSpec, Estimates]:
        """Validate a report without changing anything; returns its sensor and its estimates."""
        sensor = self.config.source(report.sensor)
        check_time(report.time)
        last = self.last_report.get(report.sensor)
        central = self._is_central(report.sensor)  # its sensors may share an instant
        if last is not None and (report.time < last if central else report.time <= last):
            raise StaleReport(report.sensor, report.time, last)
        ids = [track.id for track in report.tracks]
        if len(set(ids)) != len(ids):
            repeated = sorted(track_id for track_id, n in Counter(ids).items() if n > 1)
            first = {track_id: index for index, track_id in reversed(list(enumerate(ids)))}
            second = next(index for index, track_id in enumerate(ids) if first[track_id] != index)
            raise InvalidInput(f"tracks: ids repeat: {repeated}", loc=("tracks", second, "id"))
        dim = self.config.dim
        for index, track in enumerate(report.tracks):
            if track.state.shape != (dim,) or track.covariance.shape != (dim, dim):
                raise InvalidInput(
                    f"tracks[{index}] (id {track.id!r}): state must have {dim} components and "
                    f"covariance {dim}×{dim}, got {track.state.shape} and {track.covariance.shape}",
                    loc=("tracks", index, "state" if track.state.shape != (dim,) else "covariance"),
                )
            if self.config.classes is not None or (
                track.class_mass is not None or track.class_likelihoods is not None
            ):
                self._check_classes(track, index)
        estimates = Estimates.of(
            np.array([track.state for track in report.tracks]).reshape(-1, dim),
            np.array([track.covariance for track in report.tracks]).reshape(-1, dim, dim),
            name="tracks",
            dimension=dim,
        )
        assert estimates.covariances is not None
        check_magnitudes(estimates.states, estimates.covariances, "tracks")
        return sensor, estimates

    def _check_classes(self, track: ReportedTrack, index: int) -> None:
        frame = self.config.classes
        where = f"tracks[{index}] (id {track.id!r})"
        evidence = "class_mass" if track.class_mass is not None else "class_likelihoods"
        if track.class_mass is not None and track.class_likelihoods is not None:
            raise InvalidInput(
                f"{where}: give a class mass or class likelihoods, not both",
                loc=("tracks", index, "class_likelihoods"),
            )
        if frame is None:
            if track.class_mass is not None or track.class_likelihoods is not None:
                raise InvalidInput(
                    f"{where}: the session has no classes, but the track carries class evidence",
                    loc=("tracks", index, evidence),
                )
            return
        if track.class_mass is not None and track.class_mass.frame != frame:
            raise InvalidInput(
                f"{where}: class mass is not on the session's classes {list(frame.labels)}",
                loc=("tracks", index, "class_mass"),
            )
        if track.class_likelihoods is not None:
            likelihoods = track.class_likelihoods
            at = ("tracks", index, "class_likelihoods")
            if likelihoods.shape != (len(frame),):
                raise InvalidInput(f"{where}: need one likelihood per class ({len(frame)})", loc=at)
            if (
                not np.all(np.isfinite(likelihoods))
                or likelihoods.min() < 0.0
                or likelihoods.max() > 1.0
            ):
                raise InvalidInput(f"{where}: class likelihoods must lie in [0, 1]", loc=at)
            if likelihoods.max() == 0.0:
                raise InvalidInput(
                    f"{where}: class likelihoods are all zero: the evidence rules out every class",
                    loc=at,
                )

    # ------------------------------------------------------- association
    # ------------------------------------------------------- life cycle
    def _hit_increments(
        self,
        states: FloatArray,
        covariances: FloatArray,
        incoming: Estimates,
        cols: IntArray,
        sensor: SensorSpec,
    ) -> FloatArray:
        """Score increments ΔL of every associated pair, on the position components
        ([MTT] §4.3, eq 16; docs/algorithms.md §6.5)."""
        if len(cols) == 0:
            return np.zeros(0)
        assert incoming.covariances is not None
        distance, log_det = position_distances(
            states, covariances, incoming.states[cols], incoming.covariances[cols], self._position
        )
        tracker = self.local_trackers.get(sensor.id)
        # a sensor's local tracker scans as its first (only) sensor
        own = None if tracker is None else tracker.clutter_density(tracker.config.sensors[0])
        score = self.config.management.report_score(sensor.p_detect, own)
        return score.hit_increment(distance, log_det, len(self._position))

    def _record(
        self, rows: IntArray, cols: IntArray, report: TrackReport, incoming: Estimates
    ) -> None:
        """Report tracks ``cols`` become their sensor's latest estimates of the tracks ``rows``."""
        if len(rows) == 0:
            return
        states, covariances = incoming.states, incoming.covariances
        assert covariances is not None
        sensor = report.sensor
        self._table.write(rows, sensor, states[cols], covariances[cols], report.time)
        for row, col in zip(rows.tolist(), cols.tolist(), strict=True):
            fused = self.tracks[row]
            reported = report.tracks[col]
            previous = fused.estimates.get(sensor)
            fused.set_estimate(
                sensor,
                SensorEstimate(
                    track=reported.id, class_mass=self._class_evidence(reported, previous)
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
        live: IntArray,
        states: FloatArray,
        covariances: FloatArray,
        hit_rows: IntArray,
        increments: FloatArray,
        missed_by_source: BoolArray,
    ) -> tuple[IntArray, IntArray]:
        """:func:`core.lifecycle.advance` over every track that is not terminated.

        Hits and misses are the step's (the ``live`` rows at the report time:
        ``states``, ``covariances`` as predicted before the update; ``missed_by_source``:
        the live tracks the report coasted, a miss wherever the sensor sees, §8.10);
        coverage is looked at at the fusion time. Returns the rows terminated and
        confirmed by it.
        """
        assert self.time is not None
        management = self.config.management
        before = self._rows.rows.life
        candidates = np.flatnonzero(before.status != TERMINATED)
        count = len(candidates)
        if count == 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        every = count == len(before)
        life = before if every else before.select(candidates)
        # where each live row sits among the candidates (all rows, unless a restore had others)
        at = live if every else np.searchsorted(candidates, live)
        detected, hit_increment = hits(count, at[hit_rows], increments)
        seen, hidden = np.zeros(count, dtype=bool), np.zeros(count, dtype=bool)
        miss_increment = np.zeros(count)
        gate_log_det = np.zeros(count)
        position = self._position
        by_gate = management.gate_visibility
        gate = chi2_quantile(management.gate_probability, len(position))
        if len(live):
            live_status = life.status[at]
            # §8.16: seen by its gate, a miss weighed by the probability that the sensor sees
            # the fused track's predicted position
            sight = look(
                self._coverage,
                sensor.fov,
                sensor.volume,
                states[:, position],
                covariances[:, position][:, :, position] if by_gate else None,
                live_status,
                management.occlusion_radius,
                sensor.p_detect,
                gate,
                life.misses[at] >= HIDING_MISSES - 1 if by_gate else None,
            )
            seen[at], hidden[at], miss_increment[at] = (
                sight.seen,
                sight.hidden,
                sight.miss_increment,
            )
            seen[at] &= self._silence_counts(live, sensor.id) | missed_by_source
            # §8.2: a hit on an established track another source keeps current never lowers
            # its score ([MTT] eq 16's ΔL < 0 refutes the fused estimate, not the object)
            vouched = np.zeros(count, dtype=bool)
            vouched[at] = self._vouched(live, sensor.id) & established(live_status)
            hit_increment = np.where(
                vouched & detected, np.maximum(hit_increment, 0.0), hit_increment
            )
            missed = np.flatnonzero(coasting_misses(live_status, seen[at], detected[at]))
            if len(missed):
                gate_log_det[at[missed]] = self._gate_log_dets(live[missed], covariances[missed])
        # coverage at the fusion time: the fused estimate, updated by the report where it was
        fused_states, fused_covariances = self._table.fused_at(candidates, self.time)
        codes, _ = coverage_look(
            self._coverage,
            fused_states[:, position],
            fused_covariances[:, position][:, :, position] if by_gate else None,
            gate,
            life.misses >= HIDING_MISSES - 1 if by_gate else None,
        )
        after, confirmed = advance(
            management,
            life,
            Evidence(
                time=self.time,
                detected=detected,
                hit_increment=hit_increment,
                seen=seen,
                miss_increment=miss_increment,
                gate_log_det=gate_log_det,
                gate_dim=len(position),
                visibility=codes,
                occluded=hidden,
                sensors=self._table.present[candidates].sum(axis=1),
            ),
        )
        after = self._status_by_sources(life, after, candidates)
        self._rows.rows = self._rows.rows.living(
            after if every else _replaced_life(before, candidates, after)
        )
        return candidates[ended(life, after)], candidates[confirmed]

    # -------------------------------------------- sources' silence and status (§8.2, §8.6)
    def _learn_revisit(self, sensor: str, t: float) -> None:
        """A source's revisit: the interval between its last two reports (from its second
        report on; an engine restored from an export without revisits learns each one
        again at that source's next report)."""
        last = self.last_report.get(sensor)
        # the central source reports every track it keeps at every step, however its sensors'
        # scans interleave: no revisit, it is current on the tracks of its latest report (§8.9)
        if last is not None and not self._is_central(sensor):
            self.revisits[sensor] = t - last

    def _current(self, rows: IntArray, revisits: float = OVERDUE_REVISITS) -> BoolArray:
        """(rows, sensors): the sensor carries the track and has updated it within
        ``revisits`` of its revisit; a sensor whose revisit is not known yet (one report
        so far) is current on the tracks of its latest report."""
        assert self.time is not None
        table = self._table
        sensors = list(table.slots)  # slot order
        revisit = np.array([self.revisits.get(s, math.nan) for s in sensors])
        latest = np.array([self.last_report.get(s, math.inf) for s in sensors])
        times = table.times[rows]
        within = np.where(
            np.isfinite(revisit),
            self.time - times <= revisits * revisit,  # NaN (not known): the other branch
            times >= latest,
        )
        return np.asarray(table.present[rows] & within, dtype=bool)

    def _reporting(self, rows: IntArray) -> BoolArray:
        """:meth:`_current` without the central tracker's phantoms: a phantom is its
        prediction, kept for a hand-over ([HZ] §5.1) and reported at every step, but none of
        its sensors saw the object there. It neither vouches for a track nor keeps another
        source's silence from counting (§8.2); it still keeps the track's id and status
        (:meth:`_status_by_sources`, :meth:`_unseen`)."""
        current = self._current(rows)
        held = self._central_phantoms(rows)
        if held:
            current[list(held), self._table.slot(self.config.central_source)] = False
        return current

    def _phantom_reports(self, report: TrackReport) -> BoolArray:
        """The tracks of ``report`` that are phantoms of the central tracker (§8.9)."""
        phantoms = self.central.phantoms if self.central is not None else {}
        if not phantoms or not self._is_central(report.sensor):
            return np.zeros(len(report.tracks), dtype=bool)
        return np.array([track.id in phantoms for track in report.tracks], dtype=bool)

    def _central_phantoms(self, rows: IntArray) -> dict[int, StatusReason]:
        """Positions in ``rows`` of the tracks whose central estimate is a track the central
        tracker keeps as a phantom (§8.9), with the phantom's reason."""
        source = self.config.central_source
        if self.central is None or source not in self._table.slots:
            return {}
        phantoms = self.central.phantoms
        if not phantoms:
            return {}
        held = {}
        for at, row in enumerate(rows.tolist()):
            estimate = self.tracks[row].estimates.get(source)
            if estimate is not None and estimate.track in phantoms:
                held[at] = phantoms[estimate.track]
        return held

    def _silence_counts(self, rows: IntArray, sensor: str) -> BoolArray:
        """Where ``sensor``'s silence about the tracks ``rows`` is a miss (§8.2).

        Only when no other source keeps the track up to date, and only if ``sensor``
        carries the track — it updated it within :data:`STALE_REVISITS` of its revisit:
        a source that never reported a target — a cooperative source's unequipped
        aircraft, a radar that has not picked it up — says nothing about it, nor does
        one that left it long ago (a radar whose horizon the aircraft went below).
        Once every source of the track has left it for :data:`STALE_REVISITS` of its
        revisits (a source that stopped reporting at all), any sensor's silence
        counts again, so that the track still ends. A central phantom keeps nothing up to
        date (``others``, :meth:`_reporting`) but is still reported: the central source
        carries its track, and the track is not stale — an ADS-B station that never reported
        a radar-only aircraft does not delete it in a blind zone (§8.11).
        """
        slot = self._table.slot(sensor)
        current = self._reporting(rows)
        others = np.delete(current, slot, axis=1).any(axis=1)
        recent = self._current(rows, STALE_REVISITS)
        stale = ~recent.any(axis=1)
        carried = recent[:, slot]
        return np.asarray((carried | stale) & ~others, dtype=bool)

    def _vouched(self, rows: IntArray, sensor: str) -> BoolArray:
        """The tracks ``rows`` another source than ``sensor`` keeps up to date (is current
        on, §8.6): a hit of ``sensor``'s report on them does not lower their score (§8.2).
        A source that returns from an outage with an accurate estimate of an aircraft the
        radars' overconfident track drifted from (a hit ΔL far below the delete
        threshold) then updates the track instead of deleting it. Its misses (a coasted
        track, §8.10) still count: they are what refutes another source's false track."""
        current = self._reporting(rows)
        others = np.delete(current, self._table.slot(sensor), axis=1)
        return np.asarray(others.any(axis=1), dtype=bool)

    def _status_by_sources(self, before: LifeState, after: LifeState, rows: IntArray) -> LifeState:
        """An established track is ``confirmed`` while one of its sources keeps it up to
        date at that source's revisit, ``coasting`` (``missed``) only when it is overdue
        for every one (§8.6); tentative, phantom and terminated tracks are as
        :func:`~core.lifecycle.advance` left them."""
        status = after.status
        established_rows = (status == CONFIRMED) | (status == COASTING)
        if not established_rows.any():
            return after
        current = self._current(rows).any(axis=1)
        new = np.where(established_rows, np.where(current, CONFIRMED, COASTING), status)
        moved = new != status
        if not moved.any():
            return after
        kept = before.status == CONFIRMED  # a confirmed track never left: its reason stays
        reason = np.where(
            moved,
            np.where(
                new == CONFIRMED,
                np.where(kept, before.reason, reason_code(StatusReason.REACQUIRED)),
                reason_code(StatusReason.MISSED),
            ),
            after.reason,
        )
        return dataclasses.replace(after, status=new, reason=reason)

    def _gate_log_dets(self, rows: IntArray, predicted: FloatArray) -> FloatArray:
        """log|S| of each row's gate: its predicted covariance plus its newest estimate's,
        on the position components ([HZ] §4.2)."""
        table, position = self._table, self._position
        # the newest estimate; ties by sensor id (not by dict order, which a restore
        # through a store may change)
        by_id = np.array([slot for _, slot in self._rows.sorted_slots], dtype=np.int64)
        times = np.where(table.present[rows][:, by_id], table.times[rows][:, by_id], -np.inf)
        newest = by_id[np.argmax(times, axis=1)]
        gates = (
            predicted[:, position][:, :, position]
            + table.covariances[rows, newest][:, position][:, :, position]
        )
        return np.asarray(np.linalg.slogdet(gates)[1], dtype=np.float64)

    def _start(self, cols: IntArray, report: TrackReport, incoming: Estimates) -> IntArray:
        """A fused track for each of the report tracks ``cols``; returns their rows.

        Tentative; or confirmed at once (:func:`core.lifecycle.initiated`) when the
        session's only sensor is tracked here (its local tracker reports only the
        tracks it has confirmed, and with no other sensor a second test could only
        delay them). With several sensors the fused layer tests again: it absorbs a
        sensor's duplicates and waits for corroboration."""
        if len(cols) == 0:
            return np.zeros(0, dtype=np.int64)
        management = self.config.management
        sensor = self.config.source(report.sensor)
        central = self._is_central(report.sensor)
        life = initiated(
            management,
            len(cols),
            management.score_model(sensor.p_detect).initial,
            confirmed_below=central
            or (sensor.tracker is not None and len(self.config.sensors) == 1),
        )
        rows = self._table.add_rows(len(cols))
        self._rows.rows = self._rows.rows.started(self.next_number, life)
        self.tracks = self.tracks + [
            FusedTrack(id=f"F{self.next_number + k}", rows=self._rows, row=row)
            for k, row in enumerate(rows.tolist())
        ]
        self.next_number += len(cols)
        self._record(rows, cols, report, incoming)
        return rows

    def _hand_over_to_phantoms(self, fresh: IntArray, terminated: IntArray) -> IntArray:
        """A track confirmed in this step that matches a phantom gives it its estimates
        ([HZ] §5.1); returns ``terminated`` and the newcomers it terminated. A pair is two
        objects only if a source is current on both (§8.6): the sensor that lost the
        phantom in a blind zone and now reports the newcomer saw one object twice. The older
        of a pair keeps its id (the phantom, unless the newcomer was started before it)."""
        phantoms = np.flatnonzero(self._rows.rows.life.status == PHANTOM)
        if len(phantoms) == 0 or len(fresh) == 0:
            return terminated
        current = self._current(np.arange(len(self._rows.rows.life.status)))
        return self._merge(
            phantoms,
            fresh,
            StatusReason.MERGED_INTO_PHANTOM,
            terminated,
            carried=current,
            older_keeps=True,
        )

    def _hand_over_ended(
        self, fresh: IntArray, terminated: IntArray, status_before: IntArray
    ) -> IntArray:
        """A track confirmed in this step where a recently ended track is predicted takes
        that track's id, when the match is unambiguous (§8.15); returns ``terminated``
        without the tracks ended in this step whose id a newcomer took (they go on).

        The tracks this step ended that were established before it (not merged into
        another) are remembered with their fused estimate; those ended longer ago than
        :meth:`memory` are forgotten. Each remembered track is predicted over its gap
        (F P Fᵀ + Q of the session's motion) and gated (``sum`` distance of the full state,
        ``gate_probability``) against the newcomers and the live established tracks; a
        pair is handed over only if it is its newcomer's only gated pair and its ended
        track's: a newcomer that could be either of two ended tracks (or a live track's
        duplicate), an ended track that two newcomers could be (or whose grown gate holds
        a live track), keeps its new id; so does a newcomer shown before its ended track
        ended (another object beside it, no restart).
        """
        assert self.time is not None
        time = self.time
        life = self._rows.rows.life
        status, reason = life.status, life.reason
        alive = np.ones(len(status), dtype=bool)
        alive[terminated] = False
        before = np.full(len(status), TENTATIVE, dtype=np.int64)
        before[: len(status_before)] = status_before
        ending = terminated[
            (established(before[terminated]) | (before[terminated] == PHANTOM))
            & ~np.isin(reason[terminated], _MERGED)
        ]
        ending = np.unique(ending)  # sorted, each row once
        memory = self.memory()
        kept = [entry for entry in self.ended if time - entry.time <= memory]
        remembered: list[tuple[EndedTrack, int]] = [(entry, -1) for entry in kept]
        if len(ending):
            states, covariances = self._table.fused_at(ending, time)
            for k, row in enumerate(ending.tolist()):
                track = self.tracks[row]
                entry = EndedTrack(track.id, time, states[k], covariances[k], tuple(track.history))
                remembered.append((entry, row))
        newcomers = np.unique(fresh[alive[fresh]])
        matched: set[int] = set()
        if len(remembered) and len(newcomers):
            matched = self._take_ended_ids(remembered, newcomers, alive)
        self.ended = tuple(
            entry for k, (entry, _) in enumerate(remembered) if k not in matched and memory > 0.0
        )
        continued = [remembered[k][1] for k in sorted(matched) if remembered[k][1] >= 0]
        return terminated[~np.isin(terminated, continued)] if continued else terminated

    def _take_ended_ids(
        self, remembered: list[tuple[EndedTrack, int]], newcomers: IntArray, alive: BoolArray
    ) -> set[int]:
        """Hand the ids of ``remembered`` ended tracks to the ``newcomers`` each uniquely
        gates (:meth:`_hand_over_ended`); returns the positions of the ended tracks taken."""
        assert self.time is not None
        time = self.time
        status = self._rows.rows.life.status
        others = np.flatnonzero(established(status) & alive)
        others = others[~np.isin(others, newcomers)]
        states, covariances = self._table.fused_at(np.concatenate([newcomers, others]), time)
        split = len(newcomers)
        known, incoming = ended_hand_over_pairs(
            (
                np.array([entry.state for entry, _ in remembered]),
                np.array([entry.covariance for entry, _ in remembered]),
            ),
            np.array([time - entry.time for entry, _ in remembered]),
            self.config.motion,
            (states[:split], covariances[:split]),
            (states[split:], covariances[split:]),
            self.config.management.gate_probability,
        )
        # a newcomer shown before its ended track ended was another object beside it, no
        # restart of it (its first shown time: none yet for one started in this step)
        first_shown = np.array(
            [
                self.tracks[row].history[0][0] if self.tracks[row].history else math.inf
                for row in newcomers[incoming].tolist()
            ]
        )
        after = first_shown > np.array([remembered[k][0].time for k in known.tolist()])
        known, incoming = known[after], incoming[after]
        if len(known) == 0:
            return set()
        numbers = self._rows.rows.numbers.copy()
        reasons = self._rows.rows.life.reason.copy()
        for position, row in zip(known.tolist(), newcomers[incoming].tolist(), strict=True):
            entry = remembered[position][0]
            track = self.tracks[row]
            since = track.history[0][0] if track.history else math.inf
            history = [item for item in entry.history if item[0] < since] + track.history
            track.id, track.number = entry.id, entry.number
            track.history = history[-HISTORY_LENGTH:]
            numbers[row] = entry.number
            reasons[row] = reason_code(StatusReason.REACQUIRED)
        life = dataclasses.replace(self._rows.rows.life, reason=reasons)
        self._rows.rows = TrackRows(numbers, life)
        return set(known.tolist())

    def memory(self) -> float:
        """How long an ended fused track is remembered (§8.15): :data:`RESTART_REVISITS` of
        the longest revisit of the session's sources and centrally tracked sensors (0 while
        no revisit is known)."""
        revisits = [value for value in self.revisits.values() if math.isfinite(value)]
        if self.central is not None:
            revisits += [float(v) for v in self.central.revisits.tolist() if math.isfinite(v)]
        return RESTART_REVISITS * max(revisits) if revisits else 0.0

    def _absorb_duplicates(self, terminated: IntArray, created: IntArray) -> IntArray:
        """A tentative track that duplicates an established track of other sensors joins it.

        A sensor's first report of an object is associated by the method's gate;
        when that first decision misses (a 1 − gate_probability event per true
        pair), the sensor starts a second fused track of the same object. Such a
        tentative track, gated against a confirmed or coasting track that has
        no estimate from its sensors, is merged into it.
        """
        status = self._rows.rows.life.status
        # a track created confirmed (a local tracker's) this step is a newcomer as well
        fresh = np.zeros(len(status), dtype=bool)
        fresh[created] = status[created] == CONFIRMED
        tentative = np.flatnonzero((status == TENTATIVE) | fresh)
        established_rows = np.flatnonzero(((status == CONFIRMED) | (status == COASTING)) & ~fresh)
        return self._merge(established_rows, tentative, StatusReason.DUPLICATE, terminated)

    def _join_duplicates(self, terminated: IntArray, updated: IntArray, sensor: str) -> IntArray:
        """An established track that duplicates another established track joins the older.

        A source whose track is off its own covariance (a local tracker that lags a
        turn) can start a fused track beside the one the other sources hold, which
        min_points confirms; once its reports fit the other track, the two are one
        object that no source reports twice. Each established track this report
        updated is gated (GNN, ``sum`` distance, ``gate_probability``) against the
        established tracks the report's source is not current on; a pair no source is
        current on both of (§8.6) is merged, the older id kept (§8.10).
        """
        status = self._rows.rows.life.status
        alive = np.ones(len(status), dtype=bool)
        alive[terminated] = False
        is_established = established(status) & alive
        newcomers = updated[is_established[updated]]
        if len(newcomers) == 0:
            return terminated
        every = np.arange(len(status))
        current = self._current(every)
        candidates = is_established & ~current[:, self._table.slot(sensor)]
        candidates[newcomers] = False
        return self._merge(
            np.flatnonzero(candidates),
            newcomers,
            StatusReason.DUPLICATE,
            terminated,
            carried=current,
            older_keeps=True,
        )

    def _merge(
        self,
        keepers: IntArray,
        newcomers: IntArray,
        reason: StatusReason,
        terminated: IntArray,
        carried: BoolArray | None = None,
        older_keeps: bool = False,
    ) -> IntArray:
        """Gate ``newcomers`` against ``keepers`` (GNN, ``sum`` distance); merge disjoint pairs.

        The keeper keeps its id, takes the newcomer's estimates and becomes
        (or stays) confirmed; the newcomer is terminated with ``reason``; with
        ``older_keeps``, the older of a pair (the smaller number) is the keeper, whichever
        list it came from. Disjoint: no sensor carries both (``carried``, (rows, sensors);
        default: has an estimate of both). Returns ``terminated`` and the newcomers merged.
        """
        if len(keepers) == 0 or len(newcomers) == 0 or self.time is None:
            return terminated
        table = self._table
        known, incoming = hand_over_pairs(
            table.fused_at(keepers, self.time),
            table.fused_at(newcomers, self.time),
            self.config.management.gate_probability,
        )
        # a sensor that reports both as distinct objects knows better
        carries = table.present if carried is None else carried
        disjoint = ~np.any(carries[keepers[known]] & carries[newcomers[incoming]], axis=1)
        keeper_rows, newcomer_rows = keepers[known[disjoint]], newcomers[incoming[disjoint]]
        if len(keeper_rows) == 0:
            return terminated
        if older_keeps:
            numbers = self._rows.rows.numbers
            older = numbers[newcomer_rows] < numbers[keeper_rows]
            keeper_rows, newcomer_rows = (
                np.where(older, newcomer_rows, keeper_rows),
                np.where(older, keeper_rows, newcomer_rows),
            )
        for keeper_row, newcomer_row in zip(
            keeper_rows.tolist(), newcomer_rows.tolist(), strict=True
        ):
            keeper, newcomer = self.tracks[keeper_row], self.tracks[newcomer_row]
            for sensor_id, estimate in newcomer.estimates.items():
                slot = table.slot(sensor_id)
                if table.present[keeper_row, slot] and (
                    table.times[keeper_row, slot] >= table.times[newcomer_row, slot]
                ):
                    continue  # the keeper's estimate of that sensor is the newer
                keeper.set_estimate(sensor_id, estimate)
                table.move(newcomer_row, keeper_row, sensor_id)
        self._rows.rows = self._rows.rows.living(
            hand_over(self._rows.rows.life, keeper_rows, newcomer_rows, reason)
        )
        return np.concatenate([terminated, newcomer_rows])

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
        live: IntArray,
        terminated: IntArray,
        explain: bool,
    ) -> StepResult:
        """The step's views (every track, those terminated in it included), then only the
        tracks still alive are kept."""
        assert self.time is not None
        live_ids = [self.tracks[row].id for row in live.tolist()]  # before the keep renumbers
        rows = self._rows.rows
        status = rows.life.status
        ending = np.zeros(len(status), dtype=bool)
        ending[terminated] = True
        shown = np.flatnonzero((status != TERMINATED) | ending)
        shown = shown[np.argsort(rows.numbers[shown], kind="stable")]
        states, covariances = self._table.fused_at(shown, self.time)
        views = self._views(shown, states, covariances)
        for row, plain in zip(
            shown[status[shown] != TERMINATED].tolist(),
            states[status[shown] != TERMINATED].tolist(),
            strict=True,
        ):
            self.tracks[row].remember(self.time, plain)
        alive = rows.alive
        if len(alive) < len(status):  # terminated rows, those whose id was handed over included
            self._keep(alive)
        association = AssociationView(
            method=decision.method,
            pairs=tuple(
                (live_ids[row], report.tracks[col].id, score, basis)
                for row, col, score, basis in decision.pairs
            ),
            new=tuple(report.tracks[col].id for col in decision.new),
            missed=tuple(live_ids[row] for row in decision.missed),
            matrix=self._explained(report, decision, live_ids) if explain else None,
        )
        return StepResult(
            seq=self.seq,
            time=self.time,
            sensor=report.sensor,
            tracks=views,
            association=association,
        )

    @staticmethod
    def _explained(
        report: TrackReport, decision: Decision, live_ids: list[str]
    ) -> tuple[tuple[str, ...], tuple[str, ...], FloatArray]:
        """The decision matrix: [T2T] Table 1 with a ``*:<track id>`` row per report track."""
        known = [live_ids[row] for row in decision.matrix_rows]
        incoming = [report.tracks[col].id for col in decision.matrix_cols]
        if decision.scores is None:
            return tuple(known), tuple(incoming), np.zeros((len(known), len(incoming)))
        return decision.scores.table(known, incoming)

    def _keep(self, rows: IntArray) -> None:
        """Only ``rows`` are kept, renumbered 0, 1, … in that order (tracks, table, lives)."""
        self._table.keep(rows)
        self._rows.rows = self._rows.rows.select(rows)
        tracks = [self.tracks[row] for row in rows.tolist()]
        for row, track in enumerate(tracks):
            track.row = row
        self.tracks = tracks

    def _views(self, rows: IntArray, states: FloatArray, covariances: FloatArray) -> FusedTracks:
        """The tracks ``rows`` as a step shows them, with their fused states at a time, as
        columns (no per-track view); a track held only by a phantom of the central tracker is
        shown a phantom (:meth:`_unseen`)."""
        life = self._rows.rows.life.select(rows)
        times = self._table.times[rows].tolist()
        statuses, reasons = life.statuses(), life.reasons()
        for at, reason in self._unseen(rows).items():
            statuses[at], reasons[at] = TrackStatus.PHANTOM, reason
        tracks = [self.tracks[row] for row in rows.tolist()]
        return FusedTracks(
            ids=tuple(track.id for track in tracks),
            statuses=tuple(statuses),
            reasons=tuple(reasons),
            states=states,
            covariances=covariances,
            sources=tuple(
                track.sources(report_times)
                for track, report_times in zip(tracks, times, strict=True)
            ),
            classifications=tuple(self._classify(track) for track in tracks),
            scores=tuple(life.score.tolist()),
        )

    def _unseen(self, rows: IntArray) -> dict[int, StatusReason]:
        """Positions in ``rows`` of the established tracks that no source but the central
        tracker is current on (§8.6) and that it keeps as a phantom — no sensor could see
        it (docs/algorithms.md §8.11) — with the phantom's reason. The central tracker
        reports its phantoms at every step, so its fused track keeps its id through the
        blind zone; it is shown a phantom (predicted, not seen), not confirmed."""
        held = self._central_phantoms(rows) if self.time is not None else {}
        if not held:
            return {}
        source = self._table.slot(self.config.central_source)
        others = np.delete(self._current(rows), source, axis=1).any(axis=1)
        shown = established(self._rows.rows.life.status[rows]) & ~others
        return {at: reason for at, reason in held.items() if shown[at]}

    def picture(self, time: float | None = None) -> Sequence[FusedTrackView]:
        """The live fused tracks at ``time`` (default: the fusion time); changes nothing.

        The service's ``GET …/tracks``: each track's sensor estimates are
        predicted to ``time`` and fused, exactly as a step would.
        """
        at = self.time if time is None else float(time)
        if at is None or not self.tracks:
            return ()
        if not math.isfinite(at):
            raise InvalidInput(f"time must be finite, got {at!r}")
        shown = np.argsort(self._rows.rows.numbers, kind="stable")
        return self._views(shown, *self._table.fused_at(shown, at))

    # ------------------------------------------------------ persistence
    def export(self) -> dict[str, Any]:
        """The whole state as plain data (JSON-ready; floats round-trip exactly)."""
        return {
            "version": EXPORT_VERSION,
            "seq": self.seq,
            "time": self.time,
            "next_number": self.next_number,
            "last_report": dict(sorted(self.last_report.items())),
            "revisits": dict(sorted(self.revisits.items())),
            "tracks": [track.to_plain(self._kinematics(track)) for track in self.tracks],
            "local_trackers": {
                sensor: tracker.export() for sensor, tracker in sorted(self.local_trackers.items())
            },
            "central": None if self.central is None else self.reorder.export(self.central),
            "ended": [entry.to_plain() for entry in self.ended],
        }

    def _kinematics(self, track: FusedTrack) -> Kinematics:
        table = self._table
        return {
            sensor: (
                float(table.times[track.row, table.slot(sensor)]),
                *table.estimate(track.row, sensor),
            )
            for sensor in track.estimates
        }

    @classmethod
    def restore(cls, config: FusionConfig, state: dict[str, Any]) -> SessionEngine:
        """Rebuild an engine from :meth:`export`'s output and the same configuration.

        Version 1 has no central tracker, version 2 no reorder buffer, version 3 no ended
        tracks (:data:`EXPORT_VERSION`); an unknown version is refused.
        """
        if state.get("version") not in (1, 2, 3, EXPORT_VERSION):
            raise InvalidInput(f"unknown engine export version {state.get('version')!r}")
        engine = cls(config)
        engine.seq = int(state["seq"])
        engine.time = None if state["time"] is None else float(state["time"])
        engine.next_number = int(state["next_number"])
        engine.last_report = {str(k): float(v) for k, v in state["last_report"].items()}
        # exports before issue 22 have no revisits: they are learned again from the next reports
        engine.revisits = {str(k): float(v) for k, v in state.get("revisits", {}).items()}
        plain_tracks = state["tracks"]
        empty = [plain["id"] for plain in plain_tracks if not plain["estimates"]]
        if empty:
            raise InvalidInput(f"exported tracks without any sensor estimate: {empty}")
        table = engine._table
        rows = table.add_rows(len(plain_tracks)).tolist()
        tracks = []
        for plain, row in zip(plain_tracks, rows, strict=True):
            track = FusedTrack(
                id=str(plain["id"]),
                rows=engine._rows,
                row=row,
                history=[
                    (float(time), [float(x) for x in fused]) for time, fused in plain["history"]
                ],
            )
            for sensor, entry in plain["estimates"].items():
                if sensor not in table.slots:
                    raise InvalidInput(
                        f"exported track {track.id} has an estimate of sensor {sensor!r}, "
                        "which the config does not name"
                    )
                estimate, time, state_, covariance = SensorEstimate.from_plain(
                    entry, config.classes
                )
                track.set_estimate(str(sensor), estimate)
                table.write(np.array([row]), sensor, state_[None], covariance[None], time)
            tracks.append(track)
        engine.tracks = tracks
        engine.ended = _plain_ended(
            state.get("ended", []),
            config.dim,
            {track.id for track in tracks},
            engine.next_number,
            engine.time,
        )
        engine._rows.rows = TrackRows(
            np.array([track.number for track in tracks], dtype=np.int64),
            _plain_lives(plain_tracks),
        )
        central = state.get("central")
        if central is not None:
            if config.central_tracker is None:
                raise InvalidInput("exported state has a central tracker, the config none")
            if state["version"] == 2:
                engine.central = LocalTracker.restore(config.central_tracker, central)
            else:
                engine.central = LocalTracker.restore(config.central_tracker, central["tracker"])
                models = {sensor.id: sensor.model for sensor in config.sensors}
                engine.reorder = ReorderBuffer.restore(engine.central, central, models)
        for sensor, plain in state["local_trackers"].items():
            if config.tracked_centrally(sensor):
                continue  # a version-1 export of a sensor now tracked centrally
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
        raise InvalidInput(f"time must be finite, got {time!r}", loc=("time",))
    if abs(time) > MAX_TIME:
        raise InvalidInput(
            f"time: magnitude {time!r} is beyond the limit {MAX_TIME:g} s", loc=("time",)
        )


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


def _is_live(status: IntArray) -> BoolArray:
    """Tentative, confirmed or coasting: the tracks a report is associated with."""
    live = np.zeros(len(status), dtype=bool)
    for code in _LIVE_CODES:
        live |= status == code
    return live


def _plain_ended(
    plain: object, dim: int, live: set[str], next_number: int, time: float | None
) -> tuple[EndedTrack, ...]:
    """The remembered ended tracks of an export (§8.15), each checked: its id ``F<n>`` once,
    not a live track's and numbered below ``next_number`` (never handed out twice, nor an
    id a track holds or is yet to get), ended at a finite time not after the fusion time,
    its state (dim,), covariance (dim, dim) and history (at most
    :data:`~core.fusion.track.HISTORY_LENGTH` states (dim,)) finite."""
    if not isinstance(plain, list):
        raise InvalidInput("exported ended tracks: need a list")
    ended = []
    for entry_plain in plain:
        try:
            entry = EndedTrack.from_plain(entry_plain)
        except (KeyError, TypeError, ValueError):
            name = entry_plain.get("id") if isinstance(entry_plain, dict) else None
            raise InvalidInput(
                f"exported ended track {name!r}: needs id, time, state, covariance, history"
            ) from None
        ended.append(entry)
    seen: set[str] = set()
    for entry in ended:
        shapes = entry.state.shape == (dim,) and entry.covariance.shape == (dim, dim)
        finite = shapes and np.isfinite(entry.state).all() and np.isfinite(entry.covariance).all()
        history = len(entry.history) <= HISTORY_LENGTH and all(
            len(state) == dim and math.isfinite(at) and all(map(math.isfinite, state))
            for at, state in entry.history
        )
        numbered = _ENDED_ID.fullmatch(entry.id) is not None and entry.number < next_number
        when = math.isfinite(entry.time) and (time is None or entry.time <= time)
        if not (finite and history and when and numbered) or entry.id in seen | live:
            raise InvalidInput(
                f"exported ended track {entry.id!r}: needs an id F<n> below next_number, "
                f"held by no track and no other ended track, a finite time not after the "
                f"fusion time, state ({dim},), covariance ({dim}, {dim}) and at most "
                f"{HISTORY_LENGTH} finite history states ({dim},)"
            )
        seen.add(entry.id)
    return tuple(ended)


_ENDED_ID = re.compile(r"F[1-9][0-9]*", re.ASCII)
"""A fused id (:meth:`SessionEngine._start` numbers them from 1)."""


def _replaced_life(life: LifeState, rows: IntArray, by: LifeState) -> LifeState:
    """``life`` with ``rows`` replaced by ``by`` (new arrays)."""
    arrays = []
    for name in LIFE_ARRAYS:
        values = getattr(life, name).copy()
        values[rows] = getattr(by, name)
        arrays.append(values)
    return LifeState(*arrays)


def _plain_lives(plain_tracks: list[dict[str, Any]]) -> LifeState:
    """The lives of exported tracks as arrays (:class:`core.lifecycle.LifeState`)."""
    return LifeState(
        status=np.array(
            [STATUS_CODES[TrackStatus(plain["status"])] for plain in plain_tracks], dtype=np.int64
        ),
        reason=np.array(
            [REASON_CODES[StatusReason(plain["reason"])] for plain in plain_tracks],
            dtype=np.int64,
        ),
        score=np.array([float(plain["score"]) for plain in plain_tracks], dtype=np.float64),
        hits=np.array([int(plain["hits"]) for plain in plain_tracks], dtype=np.int64),
        empty_gate=np.array(
            [float(plain["empty_gate_probability"]) for plain in plain_tracks], dtype=np.float64
        ),
        phantom_since=np.array(
            [
                math.nan if plain["phantom_since"] is None else float(plain["phantom_since"])
                for plain in plain_tracks
            ],
            dtype=np.float64,
        ),
        # an export written before the count has none: no misses in a row
        misses=np.array([int(plain.get("misses", 0)) for plain in plain_tracks], dtype=np.int64),
    )
