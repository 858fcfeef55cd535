"""The session engine: one deterministic state machine per fusion scene.

Built from a :class:`~core.fusion.config.FusionConfig`, it takes one input
at a time and returns the fused result of that step (DESIGN.md "The session
engine"; ALGORITHMS.md §6). Same configuration + same inputs in the same
order → bit-identical outputs. Its whole state exports to plain data
(:meth:`SessionEngine.export`) and restores exactly (:meth:`SessionEngine.restore`).

One track-list step ([T2T] Fig 1-2, generalised to N sensors and to time):

1. check the report (sensor known, newer than that sensor's previous report,
   numbers finite, shapes right) — nothing changes on a refused report;
2. predict the live fused tracks to the report time: each track's state is
   the fusion of every sensor's latest estimate predicted to that time;
3. associate the report's tracks with them by the session's method, with
   class information when both sides carry it (§3.6);
4. each associated report track becomes its sensor's latest estimate of the
   fused track; unassociated ones start tentative tracks; fused tracks the
   sensor should have seen (inside its field of view, not occluded) and did
   not count a miss;
5. life cycle: confirm (score, second sensor, ``min_points``), coast, phantom
   in blind zones or occlusion, terminate (score, gate emptiness, out of
   range, phantom expiry); a newly confirmed track that matches a phantom
   hands its estimates to the phantom, which keeps its id ([HZ] §5.1);
6. class fusion per track from the sensors' latest class evidence.

**Readings.** The time of a step's result is the fusion time (the latest
report time seen): a late report (older than the fusion time, newer than
its sensor's previous report, §6.4) is associated at its own time and then
simply becomes that sensor's latest estimate. The score and the gate volume
use the position components, so the densities of
:class:`~core.fusion.config.TrackManagement` are per unit of position space.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass
from typing import Any

import numpy as np

from core.arrays import BoolArray, FloatArray, IntArray
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
from core.geometry import Sector, Visibility, occluded
from core.lifecycle import StatusReason, TrackStatus, gate_emptiness_factor, gate_volume
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
        self._gate = chi2_quantile(config.management.gate_probability, len(layout.position))
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
        sensor, incoming = self._check(report)
        t = float(report.time)
        live = [track for track in self.tracks if track.status in LIVE]
        states, covariances = self._fused_at(live, t)
        self._check_horizon(t, incoming)
        decision = self._associate(live, states, covariances, report, incoming)
        terminated: list[FusedTrack] = []
        confirmed: list[FusedTrack] = []

        rows = np.array([pair[0] for pair in decision.pairs], dtype=np.int64)
        cols = np.array([pair[1] for pair in decision.pairs], dtype=np.int64)
        increments = self._hit_increments(states[rows], covariances[rows], incoming, cols, sensor)
        hit = [live[row] for row in rows.tolist()]
        self._record(hit, cols, report, incoming)
        for fused, increment in zip(hit, increments.tolist(), strict=True):
            was_tentative = fused.status is TrackStatus.TENTATIVE
            self._hit(fused, increment)
            if was_tentative and fused.status is TrackStatus.CONFIRMED:
                confirmed.append(fused)
        missed = np.asarray(decision.missed, dtype=np.int64)
        seen = self._seen_by(sensor, states[missed], states) if len(missed) else np.zeros(0, bool)
        for row, visible in zip(missed, seen, strict=True):
            if visible:
                self._miss(live[row], covariances[row], sensor.p_detect)
        created = self._start(np.asarray(decision.new, dtype=np.int64), report, incoming)
        self.tracks.extend(created)
        confirmed.extend(track for track in created if track.status is TrackStatus.CONFIRMED)

        self.time = t if self.time is None else max(self.time, t)
        self.last_report[report.sensor] = t
        self.seq += 1
        self._manage(self.time, terminated)
        self._hand_over_to_phantoms(confirmed, terminated)
        self._absorb_duplicates(terminated)
        return self._result(report, decision, live, terminated, explain)

    def apply_detections(self, report: DetectionReport, *, explain: bool = False) -> StepResult:
        """Apply one sensor's detections: its local tracker, then the fusion step.

        The sensor's local tracker ([MTT] Fig 6, ``core.tracking``) updates its
        tracks with the detections; its confirmed tracks updated in this scan
        become the sensor's track list for :meth:`apply`
        (``core.fusion.detections``).

        Raises
        ------
        InvalidInput
            Unknown sensor, a sensor without a local tracker (one that sends
            track lists), bad shapes or numbers, a time off the tracker's ΔT grid.
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
        if not math.isfinite(report.time):
            raise InvalidInput(f"time must be finite, got {report.time!r}")
        last = self.last_report.get(sensor.id)
        if last is not None and report.time <= last:
            raise StaleReport(sensor.id, report.time, last)
        self._check_horizon(float(report.time), None)
        late = self.time is not None and report.time < self.time
        before = tracker.export() if late else None  # only a late scan can be refused after it
        scan = tracker.step(report.time, report.measurements, report.covariances)
        tracks = local_track_report(tracker, scan, self.config.motion.layout, self.config.classes)
        try:
            return self.apply(TrackReport(sensor.id, report.time, tracks), explain=explain)
        except InvalidInput:
            if before is not None:
                assert sensor.tracker is not None
                self.local_trackers[sensor.id] = LocalTracker.restore(sensor.tracker, before)
            raise

    # ------------------------------------------------------------ checks
    def _check(self, report: TrackReport) -> tuple[SensorSpec, Estimates]:
        """Validate a report without changing anything; returns its sensor and its estimates."""
        sensor = self.config.sensor(report.sensor)
        if not math.isfinite(report.time):
            raise InvalidInput(f"time must be finite, got {report.time!r}")
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
        return sensor, estimates

    def _check_horizon(self, time: float, incoming: Estimates | None) -> None:
        """Refuse, before anything changes, a step at ``time`` whose fusion time some estimate
        cannot be predicted to (``MotionModel.predict`` overflows: :class:`InvalidInput`).

        The step predicts every track that is not terminated, and the report's
        own tracks, to the fusion time; the live tracks were just predicted to
        ``time``, and what was predicted is kept, so this costs nothing more
        when the report is not late.
        """
        fusion_time = time if self.time is None else max(self.time, time)
        self._fused_at(
            [track for track in self.tracks if track.status is not TrackStatus.TERMINATED],
            fusion_time,
        )
        if incoming is not None and len(incoming) and fusion_time != time:
            assert incoming.covariances is not None
            self.config.motion.predict(
                incoming.states, incoming.covariances, np.full(len(incoming), fusion_time - time)
            )

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

    def _hit(self, fused: FusedTrack, increment: float) -> None:
        fused.score = min(fused.score + increment, self.config.management.score_ceiling)
        fused.hits += 1
        fused.empty_gate_probability = 1.0
        if fused.status is TrackStatus.COASTING:
            fused.status, fused.reason = TrackStatus.CONFIRMED, StatusReason.REACQUIRED
        elif fused.status is TrackStatus.TENTATIVE:
            self._maybe_confirm(fused)

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
                    state=states[col],  # rows of the report's own arrays (built by _check)
                    covariance=covariances[col],
                    class_mass=self._class_evidence(reported, previous),
                ),
            )

    def _maybe_confirm(self, fused: FusedTrack) -> None:
        management = self.config.management
        if len(fused.estimates) >= 2:
            fused.status, fused.reason = TrackStatus.CONFIRMED, StatusReason.SECOND_SENSOR
        elif management.min_points is not None and fused.hits >= management.min_points:
            fused.status, fused.reason = TrackStatus.CONFIRMED, StatusReason.MIN_POINTS
        elif fused.score >= management.thresholds.confirm_threshold:
            fused.status, fused.reason = TrackStatus.CONFIRMED, StatusReason.SCORE_CONFIRMED

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

    def _miss(self, fused: FusedTrack, predicted_covariance: FloatArray, p_detect: float) -> None:
        management = self.config.management
        score = management.score_model(p_detect)
        fused.score += score.miss_increment
        if fused.status is TrackStatus.CONFIRMED:
            fused.status, fused.reason = TrackStatus.COASTING, StatusReason.MISSED
        if fused.status is TrackStatus.COASTING:
            position = self._position
            # ties by sensor id: not by dict order, which a restore through a store may change
            newest = max(
                (fused.estimates[sensor] for sensor in sorted(fused.estimates)),
                key=lambda estimate: estimate.time,
            )
            gate_covariance = (
                predicted_covariance[np.ix_(position, position)]
                + newest.covariance[np.ix_(position, position)]
            )
            volume = gate_volume(
                self._gate, np.array([np.linalg.slogdet(gate_covariance)[1]]), len(position)
            )
            factor = gate_emptiness_factor(
                management.false_target_density, management.new_target_density, volume
            )
            fused.empty_gate_probability *= float(factor[0])

    def _seen_by(self, sensor: SensorSpec, missed: FloatArray, everyone: FloatArray) -> BoolArray:
        """Which missed tracks ``sensor`` should have reported: in its field of view, not occluded.

        ``missed`` and ``everyone`` are fused states at the report time; every
        live track (``everyone``) can hide another from a sector's origin when
        ``occlusion_radius`` > 0 ([HZ] §2.1).
        """
        if sensor.fov is None or len(self._position) < 2:
            return np.ones(len(missed), dtype=bool)
        plane = self._position[:2]
        seen = sensor.fov.contains(missed[:, plane])
        radius = self.config.management.occlusion_radius
        if radius > 0.0 and isinstance(sensor.fov, Sector):
            seen &= ~occluded(sensor.fov.origin, missed[:, plane], everyone[:, plane], radius)
        return seen

    def _start(self, cols: IntArray, report: TrackReport, incoming: Estimates) -> list[FusedTrack]:
        """A tentative fused track for each of the report tracks ``cols``."""
        initial = self.config.management.score_model(self.config.sensor(report.sensor).p_detect)
        created = []
        for row in self._table.add_rows(len(cols)).tolist():
            created.append(
                FusedTrack(
                    id=f"F{self.next_number}",
                    status=TrackStatus.TENTATIVE,
                    reason=StatusReason.INITIATED,
                    score=initial.initial,
                    row=row,
                )
            )
            self.next_number += 1
        self._record(created, cols, report, incoming)
        for fused in created:
            self._maybe_confirm(fused)
        return created

    def _manage(self, time: float, terminated: list[FusedTrack]) -> None:
        """Deletion, gate emptiness, blind zones, occlusion, out of range, phantom expiry."""
        management = self.config.management
        delete_below = management.thresholds.delete_threshold
        candidates = [track for track in self.tracks if track.status is not TrackStatus.TERMINATED]
        if not candidates:
            return
        states, _ = self._fused_at(candidates, time)
        if len(self._position) >= 2:
            codes = self._coverage.visibility(states[:, self._position[:2]])
        else:
            codes = np.full(len(candidates), int(Visibility.VISIBLE))
        out_of_range, blind = int(Visibility.OUT_OF_RANGE), int(Visibility.BLIND_ZONE)
        for track, where in zip(candidates, codes.tolist(), strict=True):
            reason: StatusReason | None = None
            if where == out_of_range:
                reason = StatusReason.OUT_OF_RANGE
            elif track.status is TrackStatus.PHANTOM:
                assert track.phantom_since is not None
                if time - track.phantom_since > management.phantom_lifetime:
                    reason = StatusReason.PHANTOM_EXPIRED
            elif where == blind:
                if track.status is TrackStatus.TENTATIVE:
                    reason = StatusReason.BLIND_ZONE
                else:
                    track.status, track.reason = TrackStatus.PHANTOM, StatusReason.BLIND_ZONE
                    track.phantom_since = time
            elif track.score <= delete_below:
                reason = StatusReason.SCORE_DELETED
            elif (
                track.status is TrackStatus.COASTING
                and track.empty_gate_probability < management.termination_probability
            ):
                reason = StatusReason.GATE_EMPTINESS
            if reason is not None:
                track.status, track.reason = TrackStatus.TERMINATED, reason
                terminated.append(track)

    def _hand_over_to_phantoms(self, fresh: list[FusedTrack], terminated: list[FusedTrack]) -> None:
        """A track confirmed in this step that matches a phantom gives it its estimates ([HZ] §5.1)."""
        phantoms = [track for track in self.tracks if track.status is TrackStatus.PHANTOM]
        self._merge(phantoms, fresh, StatusReason.MERGED_INTO_PHANTOM, terminated)

    def _absorb_duplicates(self, terminated: list[FusedTrack]) -> None:
        """A tentative track that duplicates an established track of other sensors joins it.

        A sensor's first report of an object is associated by the method's gate;
        when that first decision misses (a 1 − gate_probability event per true
        pair), the sensor starts a second fused track of the same object. Such a
        tentative track, gated against a confirmed or coasting track that has
        no estimate from its sensors, is merged into it.
        """
        tentative = [track for track in self.tracks if track.status is TrackStatus.TENTATIVE]
        established = [
            track
            for track in self.tracks
            if track.status in (TrackStatus.CONFIRMED, TrackStatus.COASTING)
        ]
        self._merge(established, tentative, StatusReason.DUPLICATE, terminated)

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
        for row, col in zip(decision.pair_known, decision.pair_incoming, strict=True):
            keeper, newcomer = keepers[row], newcomers[col]
            if set(keeper.estimates) & set(newcomer.estimates):
                continue  # a sensor that reports both as distinct objects knows better
            for sensor_id, estimate in newcomer.estimates.items():
                keeper.set_estimate(sensor_id, estimate)
                self._write_estimate(keeper.row, sensor_id, estimate)
            if keeper.status is not TrackStatus.CONFIRMED:
                keeper.status, keeper.reason = TrackStatus.CONFIRMED, StatusReason.REACQUIRED
            keeper.phantom_since = None
            keeper.empty_gate_probability = 1.0
            keeper.score = max(keeper.score, newcomer.score)
            keeper.hits += newcomer.hits
            newcomer.status, newcomer.reason = TrackStatus.TERMINATED, reason
            terminated.append(newcomer)

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

    def _write_estimate(self, row: int, sensor: str, estimate: SensorEstimate) -> None:
        """One sensor estimate into the table's ``row`` (a merge, a restore; steps write in bulk)."""
        self._table.write(
            np.array([row]), sensor, estimate.state[None], estimate.covariance[None], estimate.time
        )

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
            "tracks": [track.to_plain() for track in self.tracks],
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
        tracks = [FusedTrack.from_plain(plain, config.classes) for plain in state["tracks"]]
        empty = [track.id for track in tracks if not track.estimates]
        if empty:
            raise InvalidInput(f"exported tracks without any sensor estimate: {empty}")
        for track, row in zip(tracks, engine._table.add_rows(len(tracks)).tolist(), strict=True):
            track.row = row
            for sensor, estimate in track.estimates.items():
                if sensor not in engine._table.slots:
                    raise InvalidInput(
                        f"exported track {track.id} has an estimate of sensor {sensor!r}, "
                        "which the config does not name"
                    )
                engine._write_estimate(row, sensor, estimate)
        engine.tracks = tracks
        for sensor, plain in state["local_trackers"].items():
            tracker_config = config.sensor(sensor).tracker
            if tracker_config is None:
                raise InvalidInput(
                    f"exported state has a local tracker for {sensor!r}, the config none"
                )
            engine.local_trackers[sensor] = LocalTracker.restore(tracker_config, plain)
        return engine


def _mahalanobis(differences: FloatArray, covariances: FloatArray) -> tuple[FloatArray, FloatArray]:
    """D = Δᵀ C⁻¹ Δ and log|C| of every row (batched Cholesky of ``core.distance``)."""
    return quadratic_form_and_log_det(differences.T, np.moveaxis(covariances, 0, -1))


def _normalised_or_vacuous(mass: MassFunction) -> MassFunction:
    try:
        return mass.normalized()
    except TotalConflict:
        return MassFunction.vacuous(mass.frame)
