"""One sensor system's multi-target tracker: detections in, local tracks out ([MTT] Fig 6).

:class:`LocalTracker` is one assembly of the pipeline parts of
:mod:`core.pipeline` (docs/algorithms.md §7.5; the fusion engine is the
other). It runs, for each scan of one of its sensors, with every array
batched over tracks (and over the models of the IMM):

1. **predict** every live track to the scan time
   (:func:`core.pipeline.predict.predict_bank`, :class:`IMMPredictor`):
   one closed-form step over the time since the previous scan, whatever it
   is (scans need not lie on a grid; a gap costs what one scan costs), none
   for a second sensor at the same time;
2. **visibility** of each predicted position ([HZ] §2.1,
   :mod:`core.pipeline.evidence`): inside the scan
   sensor's field of view and not occluded by a known track (then a missing
   detection is a miss), in a blind zone, or out of range of every sensor;
3. **association** (:mod:`core.tracking.associate`) of detections with the
   non-phantom tracks by any method
   of :mod:`core.association` on the closest-model or combined distance, plain
   or modified (:mod:`core.tracking.gating`), or the ``cheap_jpda`` baseline
   (:mod:`core.tracking.jpda`);
4. **update** (:class:`IMMUpdater`, or the PDA update) and credal
   **classification** of the updated tracks ([MTT] §5.2), all tracks at once
   (:class:`~core.classification.batched.BatchedCredalClassifier`);
5. **life cycle** (:func:`core.lifecycle.advance`, shared with the fusion
   engine): track score ([MTT] §4.3; a hit adds ΔL of the pair's model),
   coasting, empty-gate probability ([HZ] §4.2, A_G from the combined S) and
   the table of [HZ] §5.1 (out of range, phantom expiry, blind zone or
   occlusion → phantom, score deletion, gate emptiness, confirmation);
6. **hand-over** ([HZ] §5.1, :mod:`core.pipeline.handover`,
   :func:`core.lifecycle.hand_over`): a track
   confirmed in this scan is compared with the phantoms (GNN, ``sum``
   distance on the full state, the life cycle's gate probability); a
   matching phantom takes its estimate and keeps its identity, and the
   newcomer is terminated (``merged_into_phantom``);
7. **initiation** from the detections nobody used (two-point or single-point,
   :mod:`core.tracking.config`).

Phantoms are never matched with detections. Every status change records its
reason. The tracker is deterministic and its whole state exports to plain data
(:meth:`LocalTracker.export`) that :meth:`LocalTracker.restore` continues
exactly. A step is a transaction: the state's arrays are never changed in
place, so a step that raises puts the previous references back and leaves
the tracker as it was.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.stats import chi2

from core.arrays import BoolArray, FloatArray, IntArray
from core.belief import MassFunction
from core.classification import CredalClassification
from core.classification.batched import (
    BatchedCredalClassifier,
    CredalBatch,
    dense_to_mass,
    mass_to_dense,
)
from core.classification.calibration import (
    RecentDetections,
    noise_calibrated_log_likelihoods,
    resolved_accelerations,
    sharp_predictions,
)
from core.distance.estimates import check_covariances
from core.distance.pairwise import chi2_quantile
from core.errors import TrackingError
from core.lifecycle import (
    CONFIRMED,
    PHANTOM,
    REASON_CODES,
    REASONS,
    STATUS_CODES,
    STATUSES,
    TENTATIVE,
    TERMINATED,
    Evidence,
    LifeState,
    ScoreModel,
    StatusReason,
    TrackStatus,
    advance,
    default_density,
    established,
    hand_over,
    initiated,
    several_sensors_shift,
)
from core.models.measurement import MeasurementModel, Polar
from core.pipeline.evidence import (
    HIDING_MISSES,
    coasting_misses,
    gates_seen,
    hits,
    look,
    seen_by,
    sensor_miss_runs,
)
from core.pipeline.handover import hand_over_pairs
from core.pipeline.predict import predict_bank, without_inputs
from core.pipeline.rows import TrackRows
from core.tracking.associate import Association, DetectionAssociator
from core.tracking.clutter import ClutterEstimate, prior_gate
from core.tracking.config import LocalTrackerConfig
from core.tracking.imm import IMMPrediction, IMMPredictor, IMMState
from core.tracking.initiator import pair_seeds, single_point_initiation, two_point_initiation
from core.tracking.presets import VELOCITY, TrackingPreset, VelocityConvention
from core.tracking.range_rate import range_rate_update, require_velocities
from core.tracking.track import (
    LocalTracks,
    ScanTally,
    TrackerStep,
    float_array,
    mass_to_plain,
    plain_floats,
)

EXPORT_VERSION = 4
"""4: each track's misses in a row of every sensor (``sensor_misses``) and whether each
sensor's latest scan detected it (``sensor_detected_last``), each
sensor's last two scan times (``scan_times``), and a central tracker's undetected births
per coverage cell (``births``; absent in an older one: none yet); 3: each track's ``misses`` in a row, each sensor's clutter estimate and tally;
2: the seeds' covariances (``seed_covariances``). An older export restores with no
misses, empty estimates and tallies, and (version 1) its seeds with the bank's R, the R
they were started with then."""
VOUCH_REVISITS = 1.5
"""A sensor's latest scan vouches for the tracks it detected until this many of its revisits
have passed (its next scan is overdue: a sensor that stopped scanning vouches for nothing)."""
SEED_NOISE_GATE = 0.999
"""Gate probability of the measurement-noise part of the seed distance bound."""
STEADY_ROUNDING = 1e-12
"""A cell's share of β_NT this close to 1 is 1: one sensor scanning its cell every ΔT
detects P_D · (1/P_D) of it, which rounding would leave a bit off the sensor alone's."""


def _select_prediction(prediction: IMMPrediction, rows: IntArray) -> IMMPrediction:
    held = prediction.log_held_probabilities
    return IMMPrediction(
        prediction.means[rows],
        prediction.covariances[rows],
        prediction.log_mode_probabilities[rows],
        prediction.measurement_means[rows],
        prediction.innovation_covariances[rows],
        None if held is None else held[rows],
    )


START_PASS = 2
"""The pass of the single-point starts (:func:`_passes`), which branch instead."""


def _passes(life: LifeState, measured: BoolArray, refined: BoolArray) -> IntArray:
    """The association pass of each track (docs/algorithms.md §4 "Assignment", §8.3): the
    established first, then the tentative tracks with two hits or more, then the starts,
    which share the detections left: the tracks of one detection, whose gate is the
    velocity prior's and would take the others' detections in one assignment on D; those
    of several detections of one instant (``measured`` False), whose velocity is still the
    prior's; and the tentative tracks hit at this instant already (``refined``), which a
    detection of it can refine but not test."""
    started = (life.hits >= 2) & measured & ~refined
    return np.where(established(life.status) & measured, 0, np.where(started, 1, START_PASS))


def _concatenate(first: IMMState, second: IMMState) -> IMMState:
    return IMMState(
        np.concatenate([first.means, second.means]),
        np.concatenate([first.covariances, second.covariances]),
        np.concatenate([first.log_mode_probabilities, second.log_mode_probabilities]),
    )


def _replaced(state: IMMState, rows: IntArray, by: IMMState) -> IMMState:
    """``state`` with ``rows`` replaced by the rows of ``by`` (new arrays)."""
    means, covariances = state.means.copy(), state.covariances.copy()
    log_mu = state.log_mode_probabilities.copy()
    means[rows], covariances[rows], log_mu[rows] = (
        by.means,
        by.covariances,
        by.log_mode_probabilities,
    )
    return IMMState(means, covariances, log_mu)


class LocalTracker:
    """Multi-target tracker of one sensor system (module docstring).

    Parameters
    ----------
    config : LocalTrackerConfig
    """

    def __init__(self, config: LocalTrackerConfig) -> None:
        self.config = config
        found: TrackingPreset | None = config.tracking_preset()
        self.preset = found
        """The tracking preset (None with an explicit bank), built once per tracker."""
        self.bank = config.model_bank(found)
        self.predictor = IMMPredictor(self.bank)
        self._noise = self.bank.measurement.noise_covariance
        self._q = self.bank.measurement.dim
        self._conventions: tuple[VelocityConvention, ...] = (
            (VELOCITY,) * self.bank.axes if found is None else found.conventions
        )
        self._associator = DetectionAssociator(
            config, self.bank, config.score, velocities=found is None or not found.headings
        )
        self.classifier: BatchedCredalClassifier | None = None
        self._significance: float | None = None
        if found is not None and config.classification is not None:
            chosen = config.classification
            self._significance = chosen.significance
            self.classifier = BatchedCredalClassifier(
                found.behaviours,
                found.relation,
                likelihood_scale=chosen.likelihood_scale,
                discount=chosen.discount,
                reliability=chosen.reliability,
                accumulation=chosen.accumulation,
            )
        # single-point starts branch on their second scan (docs/algorithms.md §8.3)
        self._branching = config.initiation == "single_point" and (not self._associator.soft)
        self._coverage = config.coverage
        self._views = dict(config.fields_of_view)
        self._volumes = dict(config.volumes)
        self._visibility_gate = chi2_quantile(config.life_cycle.gate_probability, self._q)
        # each coverage volume's size, m³: the default birth density (§8.12)
        self._measures = {name: volume.measure for name, volume in self._volumes.items()}
        # The state: one row per live track.
        self.time: float | None = None
        self.next_number = 1
        n, r = self.bank.state_dim, self.bank.n_models
        self._rows = TrackRows.empty()
        self._state = IMMState(np.zeros((0, r, n)), np.zeros((0, r, n, n)), np.zeros((0, r)))
        self._classes: CredalBatch | None = (
            None if self.classifier is None else self.classifier.initial(0)
        )
        # each track's last two detections, for the calibrated classification (§8.5)
        self._recent: RecentDetections | None = (
            None if self._significance is None else RecentDetections.empty(0, self._q)
        )
        self._seeds: FloatArray = np.zeros((0, self._q))
        self._seed_noises: FloatArray = np.zeros((0, self._q, self._q))
        self._seed_times: FloatArray = np.zeros(0)
        self._seed_sensors: IntArray = np.zeros(0, dtype=np.int64)
        # each track's first and latest detection times: its velocity is measured once they
        # differ (several sensors' detections of one instant measure none, §8.3)
        self._detection_times: FloatArray = np.zeros((0, 2))
        # per sensor: the run after which its silence about an established track is no miss
        limits = [
            config.life_cycle.sensor_misses(config.physics(name)[0]) for name in config.sensors
        ]
        self._miss_limits = np.array([0 if n is None else n for n in limits], dtype=np.int64)
        self._counting = np.array([n is None for n in limits])  # no ceiling: every miss counts
        # per track and sensor (column of config.sensors), §8.9: its misses in a row since it
        # last detected the track (its limit: never), and whether its latest scan (wherever
        # it looked: a scan that could not see the track withdraws the vouch) detected it
        self._sensor_misses: IntArray = np.zeros((0, len(config.sensors)), dtype=np.int64)
        self._vouching: BoolArray = np.zeros((0, len(config.sensors)), dtype=bool)
        # per sensor: its previous and latest scan times (NaN: none yet)
        self._scan_times: FloatArray = np.full((len(config.sensors), 2), np.nan)
        # per sensor: the clutter estimate (when β_FT is not given) and what was done
        self._clutter = {name: ClutterEstimate.empty(self._q) for name in config.sensors}
        self.tallies: dict[str, ScanTally] = {name: ScanTally() for name in config.sensors}
        """Per sensor, what its detections did, summed over its scans (:class:`ScanTally`)."""
        self._sigma = float(np.sqrt(np.linalg.eigvalsh(self._noise)[-1]))
        # §8.9: the sensors whose coverage is given share the births (with a given β_NT);
        # each coverage cell (the sensors whose coverage contains it, by column) → its
        # undetected targets' intensity in units of β_NT
        self._sharing = np.array(
            [
                config.life_cycle.new_target_density is not None
                and len(config.sensors) >= 2
                and (self._views[name] is not None or name in self._volumes)
                for name in config.sensors
            ],
            dtype=bool,
        )
        self._births: dict[tuple[int, ...], float] = {}

    # ------------------------------------------------------------------ api
    @property
    def n_tracks(self) -> int:
        """Live tracks (terminated ones are dropped after the step that ends them)."""
        return len(self._rows)

    @property
    def phantoms(self) -> dict[str, StatusReason]:
        """The tracks kept as phantoms (no sensor could see them, [HZ] §5.1): id → reason."""
        rows = np.flatnonzero(self._rows.life.status == PHANTOM)
        reasons = self._rows.life.reason[rows].tolist()
        return {
            self._track_id(int(number)): REASONS[code]
            for number, code in zip(self._rows.numbers[rows].tolist(), reasons, strict=True)
        }

    def step(
        self,
        time: float,
        measurements: ArrayLike,
        measurement_covariances: ArrayLike | None = None,
        sensor: str | None = None,
        range_rates: ArrayLike | None = None,
        class_masses: Sequence[MassFunction | None] | None = None,
        model: MeasurementModel | None = None,
    ) -> TrackerStep:
        """Process one scan of ``sensor`` (default: the first configured sensor).

        Parameters
        ----------
        time : float
            Scan time; not earlier than the previous scan (any step: the
            tracks are predicted over it in closed form).
        measurements : array (m, q)
        measurement_covariances : array (m, q, q), optional
            Each detection's own R (default: the bank's R).
        sensor : str, optional
        range_rates : array (m,), optional
            Each detection's range-rate (NaN: none), measured by ``model``
            (:mod:`core.tracking.range_rate`).
        class_masses : sequence of MassFunction or None, optional
            Each detection's own class evidence (None: none), on the classifier's
            class frame: combined into the class mass of the track it updates or
            starts, as one more step of its accumulation ([MTT] eq 11; a tracker
            without classification, or accumulating on behaviours, refuses it).
        model : MeasurementModel, optional
            The model the detections were measured by (the report's,
            :class:`~core.fusion.reports.DetectionReport`): a polar model with a
            range-rate gives the range-rates' site and σ.

        Raises
        ------
        TrackingError
            Unknown sensor, a time that goes back, wrong shapes, non-finite
            numbers; nothing changes then.
        """
        before = self.checkpoint()
        try:
            self._evidence = self._class_evidence(class_masses)
            return self._step(
                time, measurements, measurement_covariances, sensor, range_rates, model
            )
        except BaseException:
            self.rollback(before)
            raise
        finally:
            self.__dict__.pop("_evidence", None)
            self.__dict__.pop("_column", None)

    def _class_evidence(
        self, class_masses: Sequence[MassFunction | None] | None
    ) -> tuple[FloatArray, BoolArray] | None:
        """The detections' class masses as dense rows on the accumulation frame, and which
        detections have one (``None`` without any)."""
        if class_masses is None or all(mass is None for mass in class_masses):
            return None
        classifier = self.classifier
        if classifier is None or classifier.accumulation != "classes":
            raise TrackingError(
                "class evidence on detections needs the tracker's classification on classes",
                loc=("class_masses",),
            )
        dense = np.zeros((len(class_masses), classifier.frame.full + 1))
        given = np.zeros(len(class_masses), dtype=bool)
        for index, mass in enumerate(class_masses):
            if mass is None:
                continue
            if mass.frame != classifier.frame:
                raise TrackingError(
                    f"class evidence of detection {index} is not on the class frame",
                    loc=("class_masses", index),
                )
            dense[index], given[index] = mass_to_dense(mass), True
        return dense, given

    def _combine_evidence(self, rows: IntArray, detections: IntArray) -> None:
        """Combine the class evidence of ``detections`` into the class masses of ``rows``
        (the tracks they updated or started), one more accumulation step each."""
        evidence = getattr(self, "_evidence", None)
        if evidence is None or self.classifier is None or self._classes is None:
            return
        dense, given = evidence
        has = given[detections]
        if not has.any():
            return
        rows, detections = rows[has], detections[has]
        combined = self.classifier.combine(self._classes.select(rows), dense[detections])
        self._classes = self._classes.replace(rows, combined)

    @property
    def revisits(self) -> FloatArray:
        """Each sensor's revisit, in the order of ``config.sensors``: the interval between its
        last two scans (NaN before its second)."""
        return np.asarray(self._scan_times[:, 1] - self._scan_times[:, 0], dtype=np.float64)

    def _position_covariances(self, prediction: IMMPrediction) -> FloatArray:
        """HPHᵀ of each row's model-combined prediction: the covariance of its predicted
        position, without the measurement noise (docs/algorithms.md §8.16)."""
        _, covariance = prediction.combined()
        matrix = self.bank.measurement.matrix
        return np.asarray(matrix @ covariance @ matrix.T, dtype=np.float64)

    def checkpoint(self) -> dict[str, Any]:
        """The state as it is, for :meth:`rollback` (references: no array is changed in place)."""
        return dict(self.__dict__)

    def rollback(self, checkpoint: dict[str, Any]) -> None:
        """The state of ``checkpoint`` again (a step, or a caller's transaction, failed)."""
        self.__dict__.clear()
        self.__dict__.update(checkpoint)

    def _step(
        self,
        time: float,
        measurements: ArrayLike,
        measurement_covariances: ArrayLike | None,
        sensor: str | None,
        range_rates: ArrayLike | None = None,
        model: MeasurementModel | None = None,
    ) -> TrackerStep:
        """The pipeline (``core.pipeline``): predict, look, associate, update, life cycle,
        hand-over, initiate, keep the rows."""
        z, own_noise, sensor_name, elapsed = self._check(
            time, measurements, measurement_covariances, sensor
        )
        range_rate = self._range_rate_model(range_rates, model)
        doppler = self._check_range_rates(range_rates, len(z))
        own_noise = self._own_noise(sensor_name, own_noise, len(z))
        noises = (
            np.broadcast_to(self._noise, (len(z), self._q, self._q))
            if own_noise is None
            else own_noise
        )
        claimed_any = bool(np.any(established(self._rows.life.status)))
        score = self._scan_score(sensor_name, time, z, noises, counted=not claimed_any)
        prediction = predict_bank(self.predictor, self._state, elapsed)
        first, latest = self._detection_times.T
        # §8.3: at an instant it was hit at, a tentative track's detections are positions
        again = latest == time  # and no track's hits count that instant twice
        refined = (self._rows.life.status == TENTATIVE) & again
        passes = _passes(self._rows.life, latest > first, refined)
        if self._branching:  # §8.3: a start's second detection is its velocity, not a manoeuvre
            starts = np.flatnonzero(passes == START_PASS)
            prediction = without_inputs(prediction, self.bank, starts, elapsed)
        positions, gates = prediction.combined_measurement()
        before = self._rows.life
        status = before.status
        column = self._column = self.config.sensors.index(sensor_name)
        # §8.16: seen, missed or hidden by its gate, a miss weighed by the probability that
        # the sensor sees the predicted position N(x̂, HPHᵀ)
        covariances = (
            self._position_covariances(prediction)
            if self.config.life_cycle.gate_visibility
            else None
        )
        sight = look(
            self._coverage,
            self._views[sensor_name],
            self._volumes.get(sensor_name),
            positions,
            covariances,
            status,
            self.config.life_cycle.occlusion_radius,
            score.p_detect,
            self._visibility_gate,
            # this sensor's own misses at its previous scans, none detecting it since (§8.16):
            # its run of HIDING_MISSES − 1 = 2 (which another sensor's detection does not
            # end), both after the row's latest detection (its two latest scans)
            (self._sensor_misses[:, column] >= HIDING_MISSES - 1)
            & (before.misses > 0)
            & (latest < self._scan_times[column, 0])
            if self.config.life_cycle.gate_visibility
            else None,
        )
        codes, seen, hidden = sight.codes, sight.seen, sight.hidden
        births = self._shared_births(column, z, elapsed, score.p_detect)
        counted = seen & self._carried(column, status)
        shift = self._deletion_shift(time, positions, covariances, status)
        candidates = np.flatnonzero(
            (status != PHANTOM) & self._can_be_hit(prediction, score, shift)
        )
        association = self._associator.associate(
            prediction
            if len(candidates) == len(status)  # every track, in order: no copy
            else _select_prediction(prediction, candidates),
            z,
            own_noise,
            passes[candidates],
            score,
            branching=START_PASS if self._branching else None,
        )
        if doppler is not None and range_rate is not None and len(association.rows):
            measured = np.isfinite(doppler[association.cols])
            association = replace(
                association,
                update=range_rate_update(
                    association.update,
                    association.rows[measured],
                    doppler[association.cols[measured]],
                    range_rate,
                    self.bank.axes,
                ),
            )
        self._update(prediction, candidates, association, (time, z, noises))
        hit_rows = candidates[association.rows]
        # §8.3: a tentative track's or start's detection of an instant it was hit at is one
        # more position of it, and a start of its own would duplicate it
        repeated = association.cols[refined[hit_rows]]
        latest = latest.copy()
        latest[hit_rows] = time
        self._detection_times = np.stack([first, latest], axis=1)
        self._combine_evidence(candidates[association.rows], association.cols)
        hit = association.update.detected
        detected, gain = hits(len(status), candidates[hit], association.hit_gain[hit])
        # §8.3: and it scores one detection of each instant (the sensors agreeing on where it
        # is say nothing of how it moves, which its next instant tests)
        gain = np.where(refined, 0.0, gain)
        life, newly_confirmed = advance(
            self.config.life_cycle,
            before,
            Evidence(
                time=time,
                detected=detected,
                hit_increment=gain,
                seen=counted,
                miss_increment=sight.miss_increment,
                full_miss_increment=score.miss_increment,
                # log|S|: A_G of the tracks that coast through a miss
                gate_log_det=(
                    np.linalg.slogdet(gates)[1]
                    if np.any(coasting_misses(status, counted, detected))
                    else np.zeros(len(status))
                ),
                gate_dim=self._q,
                visibility=codes,
                occluded=hidden,
                densities=(score.false_target_density, score.new_target_density),
                velocity_measured=latest > first,
                vouched=self._vouched(column, time),
                repeated=again,
                deletion_shift=shift,
            ),
        )
        self._rows = self._rows.living(life)
        self._sensor_misses = sensor_miss_runs(self._sensor_misses, column, seen, detected)
        vouching = self._vouching.copy()
        vouching[:, column] = detected
        self._vouching = vouching
        scan_times = self._scan_times.copy()
        scan_times[column] = (scan_times[column, 1], time)
        self._scan_times = scan_times
        # Per-detection assignment (by track number for now).
        numbers = np.full(len(z), -1, dtype=np.int64)
        numbers[association.cols] = self._rows.numbers[candidates[association.rows]]
        free = np.ones(len(z), dtype=bool)
        free[association.used] = False  # a start's detections start tracks too (§8.3)
        in_pass = ~free[association.cols]  # the detections the passes took (np.isin's answer)
        joined = established(status[candidates[association.rows[in_pass]]])
        claimed = np.zeros(len(z), dtype=bool)  # by an established track
        claimed[association.cols[in_pass][joined]] = True
        updated = self._rows.numbers[np.flatnonzero(detected)]  # every track hit (§8.3: starts
        # may share a detection, which the assignment names once)
        self._hand_over(newly_confirmed, numbers, updated)
        if association.branches is not None:
            split = association.branches
            parents = candidates[split.rows]
            self._append(
                split.state,
                split.cols,
                numbers,
                before.score[parents] + np.where(refined[parents], 0.0, split.gain),
                hits=before.hits[parents] + ~again[parents],  # the instants of its detections
                times=(first[parents], time),
                recent=None
                if self._recent is None  # the start's first detection, then the branch's
                else self._recent.select(parents).latest_replaced(
                    time, z[split.cols], noises[split.cols]
                ),
            )
        free[repeated] = False
        started = self._initiate(time, sensor_name, z, noises, free, numbers, score, births)
        tally = self._tally(before, life, len(z), joined, started, newly_confirmed)
        self._count(sensor_name, tally, z[~claimed], noises[~claimed], counted=not claimed_any)
        return self._result(time, sensor_name, numbers, tally, score.false_target_density, updated)

    def _scan_score(
        self, sensor: str, time: float, z: FloatArray, noises: FloatArray, counted: bool
    ) -> ScoreModel:
        """The SPRT of this scan: its sensor's P_D and β_FT, given or estimated
        (:mod:`core.tracking.clutter`), and its β_NT (§8.12: of its coverage volume when
        it has one). ``counted``: no established track could claim a
        detection, so every one counts (and widens the region) before the scan is scored."""
        p_detect, clutter = self.config.physics(sensor)
        if clutter is None:
            if counted:
                self._clutter = {**self._clutter, sensor: self._counted(sensor, z, noises)}
            clutter = self.clutter_density(sensor)
            if clutter is None:  # nothing seen yet: the prior of one false alarm per km^q
                clutter = default_density(self._q)
        # the births since the sensor last looked; at its first scan every target is new to
        # it (no bound: β_FT's cap, prior odds 1)
        latest = float(self._scan_times[self.config.sensors.index(sensor), 1])
        since = time - latest if math.isfinite(latest) else math.inf
        if not since > 0.0:
            since = self.config.time_interval
        return self.config.life_cycle.scan_score(
            p_detect, clutter, self._measures.get(sensor), since
        )

    def _shared_births(
        self, column: int, z: FloatArray, elapsed: float, p_detect: float
    ) -> FloatArray:
        """ln of each detection's share of β_NT (docs/algorithms.md §8.9): 0 (all of it, at
        every scan: the SPRT of one sensor) unless the sensors share the births, then the
        part of the undetected targets' intensity where it lies that this scan detects.

        The intensity (the undetected targets' Poisson intensity of the PMBM filter
        [Williams 2015]) is one number per coverage cell — the sensors whose coverage
        contains a place (:func:`seen_by`, no occlusion) — in units of β_NT: births of
        β_NT per ΔT (``time_interval``) everywhere, and each scan thins the cells its
        sensor covers by 1 − P_D and detects P_D of it. A detection's cell has its own
        sensor in any case (it saw there). A cell starts at 1/P_D at the first detection
        in it (a sensor alone's β_NT at its first scan), so a cell that one sensor scans
        every ΔT (the papers' sensors of fields of view that do not overlap) detects β_NT
        at every scan, as before. A sensor whose coverage is not given (no field of view,
        no volume) shares nothing: where it looks is unknown, so its scans neither thin
        the cells nor take a share; they keep all of β_NT."""
        shares = np.zeros(len(z))
        step = elapsed / self.config.time_interval
        cells = {cell: share + step for cell, share in self._births.items()}
        if not self._sharing[column]:
            self._births = cells
            return shares
        covered = np.zeros((len(z), len(self._sharing)), dtype=bool)
        for other, name in enumerate(self.config.sensors):
            if self._sharing[other] and len(z):
                covered[:, other], _ = seen_by(
                    self._views[name],
                    z,
                    np.zeros(len(z), dtype=np.int64),
                    0.0,
                    self._volumes.get(name),
                )
        covered[:, column] = True
        kinds, which = np.unique(covered, axis=0, return_inverse=True)
        keys = [tuple(np.flatnonzero(kind).tolist()) for kind in kinds]
        for key in keys:
            cells.setdefault(key, 1.0 / p_detect)
        detected = np.array([p_detect * cells[key] for key in keys])
        detected = np.where(np.abs(detected - 1.0) <= STEADY_ROUNDING, 1.0, detected)
        self._births = {
            cell: (1.0 - p_detect) * share if column in cell else share
            for cell, share in cells.items()
        }
        if len(z):
            shares = np.log(detected)[np.asarray(which).reshape(-1)]
        return shares

    def _counted(self, sensor: str, z: FloatArray, noises: FloatArray) -> ClutterEstimate:
        """The sensor's estimate after a scan's unclaimed detections ``z`` (their noises)."""
        sigma = self._sigma
        if len(z):
            sigma = max(sigma, float(np.sqrt(np.linalg.eigvalsh(noises)[:, -1].max())))
        return self._clutter[sensor].widened(z, sigma).counted(len(z))

    def _tally(
        self,
        before: LifeState,
        after: LifeState,
        detections: int,
        joined: BoolArray,
        started: int,
        newly_confirmed: BoolArray,
    ) -> ScanTally:
        """What this scan did with its detections and tracks (:class:`ScanTally`)."""
        ended = (after.status == TERMINATED) & (before.status != TERMINATED)
        refuted = ended & (before.status == TENTATIVE)
        closed = ended & (before.status != TENTATIVE)
        reasons: dict[str, int] = {}
        for code in after.reason[closed].tolist():
            name = REASONS[code].value
            reasons[name] = reasons.get(name, 0) + 1
        with_track = len(joined)
        return ScanTally(
            detections=detections,
            joined_established=int(joined.sum()),
            joined_tentative=with_track - int(joined.sum()),
            started=started,
            unused=detections - with_track - started,
            confirmed=int(newly_confirmed.sum()),
            refuted=int(refuted.sum()),
            refuted_detections=int(after.hits[refuted].sum()),
            ended=int(closed.sum()),
            ended_reasons=dict(sorted(reasons.items())),
        )

    def _count(
        self,
        sensor: str,
        tally: ScanTally,
        unclaimed: FloatArray,
        noises: FloatArray,
        counted: bool,
    ) -> None:
        """The sensor's tally, and its clutter estimate after the scan's detections no
        established track claimed (``unclaimed``: :mod:`core.tracking.clutter`), unless
        ``counted`` before it."""
        self.tallies = {**self.tallies, sensor: self.tallies[sensor] + tally}
        if counted or self.config.physics(sensor)[1] is not None:
            return
        self._clutter = {**self._clutter, sensor: self._counted(sensor, unclaimed, noises)}

    def clutter_density(self, sensor: str) -> float | None:
        """The β_FT the sensor's next scan starts from: given, or its estimate so far (None
        before its first detection)."""
        given = self.config.physics(sensor)[1]
        if given is not None:
            return given
        estimate = self._clutter[sensor]
        if not np.all(np.isfinite(estimate.low)):
            return None
        return estimate.density(
            prior_gate(self.config.velocity_std, self.config.time_interval, self._sigma)
        )

    # ------------------------------------------------------------ checks
    def _check(
        self,
        time: float,
        measurements: ArrayLike,
        measurement_covariances: ArrayLike | None,
        sensor: str | None,
    ) -> tuple[FloatArray, FloatArray | None, str, float]:
        sensor_name = self.config.sensors[0] if sensor is None else sensor
        if sensor_name not in self._views:
            raise TrackingError(
                f"unknown sensor {sensor_name!r}; known: {list(self._views)}", loc=("sensor",)
            )
        if not math.isfinite(time):
            raise TrackingError(f"time must be finite, got {time!r}", loc=("time",))
        z = np.asarray(measurements, dtype=np.float64)
        if z.size == 0:
            z = z.reshape(0, self._q)
        if z.ndim != 2 or z.shape[1] != self._q:
            raise TrackingError(
                f"measurements must have shape (m, {self._q}), got {z.shape}",
                loc=("measurements",),
            )
        if not np.all(np.isfinite(z)):
            row = int(np.argmax(~np.isfinite(z).all(axis=1)))
            raise TrackingError("measurements must be finite", loc=("measurements", row))
        own: FloatArray | None = None
        if measurement_covariances is not None:
            own = np.asarray(measurement_covariances, dtype=np.float64)
            if own.size == 0:
                own = own.reshape(0, self._q, self._q)
            if own.shape != (len(z), self._q, self._q):
                raise TrackingError(
                    f"measurement_covariances must have shape ({len(z)}, {self._q}, {self._q})",
                    loc=("measurement_covariances",),
                )
            if len(own):
                check_covariances(own, "measurement_covariances")
        elapsed = 0.0
        if self.time is not None:
            elapsed = time - self.time
            if elapsed < 0.0:
                raise TrackingError(
                    f"scan time {time!r} is before the previous scan's time {self.time!r}",
                    loc=("time",),
                )
        return z, own, sensor_name, elapsed

    def _own_noise(
        self, sensor: str, own_noise: FloatArray | None, count: int
    ) -> FloatArray | None:
        """The detections' own R, or the R of their sensor when it is not the bank's
        (``sensor_physics``: a central tracker's sensors, §8.9); None: the bank's."""
        if own_noise is not None:
            return own_noise
        noise = self.config.noise(sensor)
        if noise is None:
            return None
        return np.broadcast_to(noise, (count, self._q, self._q)).copy()

    def _range_rate_model(
        self, range_rates: ArrayLike | None, model: MeasurementModel | None
    ) -> Polar | None:
        """The polar model with a range-rate that measured the scan's ``range_rates``, or
        None without range-rates."""
        if range_rates is None:
            return None
        if not isinstance(model, Polar) or model.velocity_mapping is None:
            raise TrackingError("range_rates need a polar measurement model with a range-rate")
        require_velocities(self.preset)
        return model

    def _check_range_rates(self, range_rates: ArrayLike | None, count: int) -> FloatArray | None:
        """Each detection's range-rate (NaN: none), or None."""
        if range_rates is None:
            return None
        if self._associator.soft:
            raise TrackingError(f"{self.config.association_method} takes no range-rates")
        doppler = np.asarray(range_rates, dtype=np.float64).reshape(-1)
        if doppler.shape != (count,) or np.any(np.isinf(doppler)):
            raise TrackingError(f"range_rates must be {count} finite numbers (NaN: none)")
        return doppler

    def _carried(self, column: int, status: IntArray) -> BoolArray:
        """Rows whose miss by the sensor of ``column`` counts: every tentative one, every
        one with at most ``initiation_hits`` hits (a young track is tested by every scan
        that could see it), and the established ones it carries — it has detected them and
        not missed them :meth:`LifeCycleConfig.sensor_misses` times in a row since
        (docs/algorithms.md §8.9)."""
        if self._counting[column]:
            return np.ones(len(status), dtype=bool)
        young = self._rows.life.hits <= self.config.life_cycle.initiation_hits
        return np.asarray(
            ~established(status)
            | young
            | (self._sensor_misses[:, column] < self._miss_limits[column]),
            dtype=np.bool_,
        )

    def _vouched(self, column: int, time: float) -> BoolArray:
        """Rows that another sensor than the scanning one (``column``) detected at its latest
        scan (wherever it looked), if that scan is not overdue: not older than
        :data:`VOUCH_REVISITS` of its revisit (known from its second scan on;
        docs/algorithms.md §8.9)."""
        previous, latest = self._scan_times[:, 0], self._scan_times[:, 1]
        revisit = latest - previous
        fresh = np.isfinite(revisit) & (time - latest <= VOUCH_REVISITS * revisit)
        fresh[column] = False
        return np.asarray((self._vouching & fresh).any(axis=1), dtype=np.bool_)

    def _deletion_shift(
        self,
        time: float,
        positions: FloatArray,
        covariances: FloatArray | None,
        status: IntArray,
    ) -> FloatArray:
        """Each row's shift of its delete threshold, ``ln(T_c / T_max)`` of the sensors that
        look at it (:func:`~core.lifecycle.several_sensors_shift`, docs/algorithms.md
        §8.14): established, carried by the sensor (:meth:`_carried`), inside its view and
        volume or its gate seen (§8.16; ``covariances``: HPHᵀ of each row, None for the
        papers' test at the predicted position), the sensor's revisit known and its latest scan not
        overdue (:data:`VOUCH_REVISITS`). 0 for the other rows, and for every row of a
        single sensor's tracker."""
        shift = np.zeros(len(status))
        rows = np.flatnonzero(established(status))
        if len(self.config.sensors) < 2 or len(rows) == 0:
            return shift
        previous, latest = self._scan_times[:, 0], self._scan_times[:, 1]
        revisit = latest - previous
        revisits = np.full((len(rows), len(self.config.sensors)), np.inf)
        gate_seen = gates_seen(self._coverage, positions, covariances, self._visibility_gate)
        for column, name in enumerate(self.config.sensors):
            period = float(revisit[column])
            if not (math.isfinite(period) and period > 0.0):
                continue
            if time - float(latest[column]) > VOUCH_REVISITS * period:
                continue  # a sensor that stopped scanning looks at nothing
            carried = self._counting[column] | (
                self._sensor_misses[rows, column] < self._miss_limits[column]
            )
            seen, _ = seen_by(
                self._views[name],
                positions[rows],
                status[rows],
                self.config.life_cycle.occlusion_radius,
                self._volumes.get(name),
            )
            revisits[:, column] = np.where(
                carried & (seen | gate_seen[column, rows]), period, np.inf
            )
        shift[rows] = several_sensors_shift(revisits)
        return shift

    # ---------------------------------------------------------- predict
    def _can_be_hit(
        self, prediction: IMMPrediction, scan: ScoreModel, shift: FloatArray
    ) -> BoolArray:
        """Tracks a detection could keep alive: the largest hit increment they could get
        (distance 0, their most certain model, no measurement noise: ``log |H P_j Hᵀ|``)
        leaves their score above the delete threshold (lowered by ``shift``, §8.14), or a
        start that a hit keeps (``initiation_hits``).

        A prediction so uncertain that no detection can (a scan after a long gap)
        is not associated: the track misses, its gate empties ([HZ] §4.2) and
        it is terminated, and the scan costs what any scan costs instead of
        gating every detection with every track.
        """
        life = self._rows.life
        score = life.score
        if len(score) == 0:
            return np.zeros(0, dtype=bool)
        sign, log_det = np.linalg.slogdet(prediction.innovation_covariances - self._noise)
        log_det = np.where(sign > 0.0, log_det, -np.inf).min(axis=1)
        best = scan.hit_increment(np.zeros_like(log_det), log_det, self._q)
        starting = (life.status == TENTATIVE) & (life.hits < self.config.life_cycle.initiation_hits)
        return np.asarray((score + best > scan.delete_threshold + shift) | starting, dtype=np.bool_)

    # ------------------------------------------------------------ update
    def _update(
        self,
        prediction: IMMPrediction,
        candidates: IntArray,
        association: Association,
        scan: tuple[float, FloatArray, FloatArray],
    ) -> None:
        """The state: the prediction, with the associated tracks' update; their classes
        ([MTT] §5.2, all at once). ``scan``: the time, detections and their R."""
        update = association.update
        self._state = _replaced(prediction.as_state(), candidates, update.state)
        if self.classifier is not None and self._classes is not None and len(candidates):
            every = len(candidates) == len(self._rows)
            log_likelihoods, detected = update.log_likelihoods, update.detected
            significance = self._significance
            if significance is not None:  # §8.5: what the sensor's noise alone gives is no evidence
                log_likelihoods = noise_calibrated_log_likelihoods(
                    log_likelihoods,
                    update.innovations,
                    update.innovation_covariances,
                    significance,
                )
                # and only a track confirmed and detected at its previous scan, whose best
                # model predicted sharply, compares the models over one manoeuvre (a
                # tentative track's velocity is a guess, a coasting one spans a gap)
                h = self.bank.measurement.matrix
                predicted = h @ prediction.covariances[candidates] @ h.T
                detected = (
                    detected
                    & (self._rows.life.status[candidates] == CONFIRMED)
                    & sharp_predictions(
                        update.log_likelihoods, update.innovation_covariances, predicted
                    )
                    & self._accelerated(candidates, association, scan, significance)
                )
            chosen = self.config.classification
            log_mu = (  # [MTT] eq 19/22: posterior or prior μ (core.classification.behaviours)
                prediction.log_mode_probabilities[candidates]
                if chosen is not None and chosen.mode_probabilities == "predicted"
                else update.log_mode_probabilities
            )
            classified = self.classifier.update(
                self._classes if every else self._classes.select(candidates),
                log_mu,
                log_likelihoods,
                detected,
            )
            self._classes = classified if every else self._classes.replace(candidates, classified)

    def _accelerated(
        self,
        candidates: IntArray,
        association: Association,
        scan: tuple[float, FloatArray, FloatArray],
        significance: float,
    ) -> BoolArray:
        """Of ``candidates``: whose last three detections, this scan's included, show an
        acceleration beyond their noise (§8.5, ``resolved_accelerations``); the tracks hit
        remember this scan's detection."""
        shown = np.zeros(len(candidates), dtype=bool)
        if self._recent is None or len(association.rows) == 0:
            return shown
        time, z, noises = scan
        tracks, cols = candidates[association.rows], association.cols
        shown[association.rows] = resolved_accelerations(
            *self._recent.with_detection(tracks, time, z[cols], noises[cols]), significance
        )
        self._recent = self._recent.pushed(tracks, time, z[cols], noises[cols])
        return shown

    # -------------------------------------------------------- hand-over
    def _hand_over(self, newly_confirmed: BoolArray, numbers: IntArray, updated: IntArray) -> None:
        """Newly confirmed tracks that match a phantom give it their estimate ([HZ] §5.1)."""
        life = self._rows.life
        phantoms = np.flatnonzero(life.status == PHANTOM)
        fresh = np.flatnonzero(newly_confirmed)
        if len(phantoms) == 0 or len(fresh) == 0:
            return
        means, covariances = self._state.combined()
        known, incoming = hand_over_pairs(
            (means[phantoms], covariances[phantoms]),
            (means[fresh], covariances[fresh]),
            self.config.life_cycle.gate_probability,
        )
        if len(known) == 0:
            return
        keepers, newcomers = phantoms[known], fresh[incoming]
        self._state = _replaced(self._state, keepers, self._state.select(newcomers))
        if self._recent is not None:
            self._recent = self._recent.replace(keepers, self._recent.select(newcomers))
        runs = self._sensor_misses.copy()  # the newcomer's detections are the latest
        runs[keepers] = np.minimum(runs[keepers], runs[newcomers])
        self._sensor_misses = runs
        vouching = self._vouching.copy()
        vouching[keepers] = vouching[newcomers]
        self._vouching = vouching
        times = self._detection_times.copy()  # the keeper's first, the newcomer's latest
        times[keepers, 1] = times[newcomers, 1]
        self._detection_times = times
        self._rows = self._rows.living(
            hand_over(life, keepers, newcomers, StatusReason.MERGED_INTO_PHANTOM)
        )
        if self.classifier is not None and self._classes is not None:
            # The newcomer's cumulative mass is one more piece of evidence for the keeper.
            merged = self.classifier.combine(
                self._classes.select(keepers), self._classes.masses[newcomers]
            )
            self._classes = self._classes.replace(keepers, merged)
        own = self._rows.numbers
        for keeper, newcomer in zip(keepers.tolist(), newcomers.tolist(), strict=True):
            numbers[numbers == own[newcomer]] = own[keeper]
            updated[updated == own[newcomer]] = own[keeper]

    # -------------------------------------------------------- initiation
    def _initiate(
        self,
        time: float,
        sensor: str,
        z: FloatArray,
        noises: FloatArray,
        free: BoolArray,
        numbers: IntArray,
        score: ScoreModel,
        births: FloatArray,
    ) -> int:
        """New tentative tracks from the detections nobody used (config Readings), each
        started and scored with its detections' own covariances ``noises`` (m, q, q) and
        its share of the births (``births``, ln: :meth:`_shared_births`); returns how many
        detections started one."""
        detections = np.flatnonzero(free)
        if self.config.initiation == "single_point":
            starts = detections
            state = single_point_initiation(
                self.bank, z[starts], self.config.velocity_std, noises=noises[starts]
            )
            self._append(
                state,
                starts,
                numbers,
                score.initial + births[starts],
                times=(time, time),
                recent=None
                if self._recent is None
                else RecentDetections.first(time, z[starts], noises[starts]),
            )
            return len(starts)
        sensor_index = self.config.sensors.index(sensor)
        mine = self._seed_sensors == sensor_index
        older = mine & (self._seed_times < time)
        seeds, seed_noises = self._seeds[older], self._seed_noises[older]
        seed_times = self._seed_times[older]
        starts = np.zeros(0, dtype=np.int64)
        if len(seeds) and len(detections):
            # The sensor's seeds all come from its latest earlier scan (older ones are dropped below).
            interval = float(time - seed_times.max())
            noise_gate = float(chi2.ppf(SEED_NOISE_GATE, self._q))
            # the gate on R₀ + R₁ by its largest eigenvalue, pair by pair
            seed_largest = np.linalg.eigvalsh(seed_noises)[:, -1]
            detection_largest = np.linalg.eigvalsh(noises[detections])[:, -1]
            radius = self.config.max_speed * interval + np.sqrt(
                noise_gate * (seed_largest[:, None] + detection_largest[None, :])
            )
            seed_index, detection_index = pair_seeds(seeds, z[detections], radius)
            if len(seed_index):
                starts = detections[detection_index]
                first, first_noises = seeds[seed_index], seed_noises[seed_index]
                # [MTT] §4.3: the pair's score has both detections' evidence; a pair
                # scoring at or below the delete threshold starts no track.
                spread = self.config.velocity_std**2 * interval**2
                pair_covariance = first_noises + noises[starts] + spread * np.eye(self._q)
                start_score = score.two_point_initial(z[starts] - first, pair_covariance)
                start_score = start_score + births[starts]
                alive = start_score > self.config.life_cycle.delete_threshold
                starts, first, start_score = starts[alive], first[alive], start_score[alive]
                state = two_point_initiation(
                    self.bank,
                    first,
                    z[starts],
                    interval,
                    first_noises=first_noises[alive],
                    second_noises=noises[starts],
                    velocity=self._conventions,
                )
                order = np.argsort(starts, kind="stable")
                starts = starts[order]
                state = state.select(order)
                first_times = seed_times[seed_index][alive][order]
                self._append(
                    state,
                    starts,
                    numbers,
                    start_score[order],
                    hits=2,
                    times=(first_times, time),
                    recent=RecentDetections(
                        np.stack([first_times, np.full(len(starts), time)], axis=1),
                        np.stack([first[order], z[starts]], axis=1),
                        np.stack([first_noises[alive][order], noises[starts]], axis=1),
                    ),
                )
        remaining = np.setdiff1d(detections, starts)
        kept = ~older
        self._seeds = np.concatenate([self._seeds[kept], z[remaining]])
        self._seed_noises = np.concatenate([self._seed_noises[kept], noises[remaining]])
        self._seed_times = np.concatenate([self._seed_times[kept], np.full(len(remaining), time)])
        self._seed_sensors = np.concatenate(
            [self._seed_sensors[kept], np.full(len(remaining), sensor_index, dtype=np.int64)]
        )
        return len(starts)

    def _append(
        self,
        state: IMMState,
        detections: IntArray,
        numbers: IntArray,
        start: float | FloatArray,
        hits: int | IntArray = 1,
        *,
        times: tuple[float | FloatArray, float],
        recent: RecentDetections | None = None,
    ) -> None:
        """New tentative tracks of ``detections`` of the scanning sensor (``self._column``);
        ``times``: the times of their first and latest detections; ``recent``: their
        detections so far (with the calibrated classification)."""
        count = len(detections)
        if count == 0:
            return
        first, latest = (np.broadcast_to(time, (count,)) for time in times)
        self._detection_times = np.concatenate(
            [self._detection_times, np.stack([first, latest], axis=1)]
        )
        if self._recent is not None:
            self._recent = self._recent.concatenate(
                RecentDetections.empty(count, self._q) if recent is None else recent
            )
        self._rows = self._rows.started(
            self.next_number, initiated(self.config.life_cycle, count, start, hits)
        )
        # a detection that updated a track names that one (a start's detections start
        # tracks too: the assignment says which track each detection updated first)
        numbers[detections] = np.where(
            numbers[detections] < 0, self._rows.numbers[-count:], numbers[detections]
        )
        self.next_number += count
        self._state = _concatenate(self._state, state)
        # detected by the scanning sensor only: the others do not carry it yet (§8.9)
        runs = np.tile(self._miss_limits, (count, 1))
        runs[:, self._column] = 0
        vouching = np.zeros((count, len(self.config.sensors)), dtype=bool)
        vouching[:, self._column] = True
        self._sensor_misses = np.concatenate([self._sensor_misses, runs])
        self._vouching = np.concatenate([self._vouching, vouching])
        if self.classifier is not None and self._classes is not None:
            self._classes = self._classes.concatenate(self.classifier.initial(count))
            self._combine_evidence(np.arange(len(self._rows) - count, len(self._rows)), detections)

    # ------------------------------------------------------------ output
    def _track_id(self, number: int) -> str:
        return f"{self.config.id_prefix}{number}"

    def _result(
        self,
        time: float,
        sensor: str,
        numbers: IntArray,
        tally: ScanTally,
        clutter: float,
        updated: IntArray,
    ) -> TrackerStep:
        means, covariances = self._state.combined()
        own = self._rows.numbers
        order = np.argsort(own, kind="stable")
        rows = order.tolist()
        classes = self._classes
        class_masses: tuple[MassFunction | None, ...] = (None,) * len(rows)
        pignistic: tuple[FloatArray | None, ...] = (None,) * len(rows)
        if self.classifier is not None and classes is not None:
            masses = self.classifier.class_mass_functions(classes)
            defined = classes.defined.tolist()
            class_masses = tuple(masses[row] for row in rows)
            pignistic = tuple(classes.pignistic[row] if defined[row] else None for row in rows)
        life = self._rows.life
        numbers_in_order = own[order].tolist()
        ids = {number: self._track_id(number) for number in numbers_in_order}
        # every track's fields as columns in id order: plain ints and floats once for all
        tracks = LocalTracks(
            ids=tuple(ids.values()),
            statuses=tuple(STATUSES[code] for code in life.status[order].tolist()),
            reasons=tuple(REASONS[code] for code in life.reason[order].tolist()),
            states=means[order],
            covariances=covariances[order],
            mode_probabilities=self._state.mode_probabilities[order],
            scores=tuple(life.score[order].tolist()),
            hits=tuple(life.hits[order].tolist()),
            class_masses=class_masses,
            pignistic=pignistic,
        )
        self._keep(self._rows.alive)
        self.time = time
        # each detection's and each updated track's id (a number the scan's tracks have; the
        # id is made anew only for one they do not)
        assignment = tuple(
            None if n < 0 else ids.get(n) or self._track_id(n) for n in numbers.tolist()
        )
        return TrackerStep(
            time=time,
            sensor=sensor,
            columns=tracks,
            assignment=assignment,
            tally=tally,
            clutter_density=clutter,
            updated=tuple(ids.get(n) or self._track_id(n) for n in np.unique(updated).tolist()),
        )

    def _keep(self, rows: IntArray) -> None:
        self._rows = self._rows.select(rows)
        self._detection_times = self._detection_times[rows]
        self._state = self._state.select(rows)
        self._sensor_misses = self._sensor_misses[rows]
        self._vouching = self._vouching[rows]
        if self._classes is not None:
            self._classes = self._classes.select(rows)
        if self._recent is not None:
            self._recent = self._recent.select(rows)

    # ------------------------------------------------------- persistence
    def export(self) -> dict[str, Any]:
        """The whole state as plain data (lists, floats, ints, str, None; see :mod:`core.tracking.track`)."""
        tracks = []
        numbers, life = self._rows.numbers, self._rows.life
        for row in range(len(numbers)):
            entry: dict[str, Any] = {
                "number": int(numbers[row]),
                "status": STATUSES[int(life.status[row])].value,
                "reason": REASONS[int(life.reason[row])].value,
                "score": plain_floats(life.score[row]),
                "hits": int(life.hits[row]),
                "empty_gate_probability": plain_floats(life.empty_gate[row]),
                "phantom_since": plain_floats(life.phantom_since[row]),
                "misses": int(life.misses[row]),
                "sensor_misses": self._sensor_misses[row].tolist(),
                "sensor_detected_last": self._vouching[row].tolist(),
                "means": plain_floats(self._state.means[row]),
                "covariances": plain_floats(self._state.covariances[row]),
                "log_mode_probabilities": plain_floats(self._state.log_mode_probabilities[row]),
                "detection_times": plain_floats(self._detection_times[row]),
                "classification": None,
            }
            if self.classifier is not None and self._classes is not None:
                classes = self._classes
                entry["classification"] = {
                    "mass": mass_to_plain(
                        dense_to_mass(self.classifier.frame, classes.masses[row])
                    ),
                    "step_conflict": plain_floats(classes.step_conflicts[row]),
                    "log_normaliser": plain_floats(classes.log_normalisers[row]),
                    "steps": int(classes.steps[row]),
                }
            if self._recent is not None:
                entry["recent_detections"] = self._recent.to_plain(row)
            tracks.append(entry)
        return {
            "version": EXPORT_VERSION,
            "time": None if self.time is None else plain_floats(np.float64(self.time)),
            "next_number": self.next_number,
            "seeds": plain_floats(self._seeds),
            "seed_covariances": plain_floats(self._seed_noises),
            "seed_times": plain_floats(self._seed_times),
            "seed_sensors": self._seed_sensors.tolist(),
            "clutter": {name: estimate.to_plain() for name, estimate in self._clutter.items()},
            "tallies": {name: tally.to_plain() for name, tally in self.tallies.items()},
            "scan_times": plain_floats(self._scan_times),
            "births": [
                [[self.config.sensors[column] for column in cell], share]
                for cell, share in self._births.items()
            ],
            "tracks": tracks,
        }

    @classmethod
    def restore(cls, config: LocalTrackerConfig, plain: dict[str, Any]) -> LocalTracker:
        """Rebuild a tracker from :meth:`export`'s output and the same configuration."""
        version = plain.get("version")
        if version not in (1, 2, 3, EXPORT_VERSION):
            raise TrackingError(f"unknown tracker export version {version!r}")
        tracker = cls(config)
        tracker.time = None if plain["time"] is None else float(float_array(plain["time"]))
        tracker.next_number = int(plain["next_number"])
        q = tracker._q
        tracker._seeds = float_array(plain["seeds"]).reshape(-1, q)
        tracker._seed_noises = (
            float_array(plain["seed_covariances"]).reshape(-1, q, q)
            if version != 1
            else np.broadcast_to(tracker._noise, (len(tracker._seeds), q, q)).copy()
        )
        if version >= 3:
            tracker._clutter = {
                name: ClutterEstimate.from_plain(plain["clutter"][name]) for name in config.sensors
            }
            tracker.tallies = {
                name: ScanTally.from_plain(plain["tallies"][name]) for name in config.sensors
            }
        tracker._seed_times = float_array(plain["seed_times"]).reshape(-1)
        tracker._seed_sensors = np.array(plain["seed_sensors"], dtype=np.int64).reshape(-1)
        entries = plain["tracks"]
        n, r = tracker.bank.state_dim, tracker.bank.n_models
        life = LifeState(
            status=np.array(
                [STATUS_CODES[TrackStatus(e["status"])] for e in entries], dtype=np.int64
            ),
            reason=np.array(
                [REASON_CODES[StatusReason(e["reason"])] for e in entries], dtype=np.int64
            ),
            score=float_array([e["score"] for e in entries]).reshape(-1),
            hits=np.array([e["hits"] for e in entries], dtype=np.int64),
            empty_gate=float_array([e["empty_gate_probability"] for e in entries]).reshape(-1),
            phantom_since=float_array([e["phantom_since"] for e in entries]).reshape(-1),
            misses=np.array([e.get("misses", 0) for e in entries], dtype=np.int64),
        )
        tracker._rows = TrackRows(np.array([e["number"] for e in entries], dtype=np.int64), life)
        sensors = len(config.sensors)  # an older export: every sensor carries every track
        tracker._sensor_misses = np.array(
            [e.get("sensor_misses", [0] * sensors) for e in entries], dtype=np.int64
        ).reshape(-1, sensors)
        tracker._vouching = np.array(
            [e.get("sensor_detected_last", [False] * sensors) for e in entries], dtype=bool
        ).reshape(-1, sensors)
        if "scan_times" in plain:
            tracker._scan_times = float_array(plain["scan_times"]).reshape(sensors, 2)
        tracker._births = {  # an older export: none yet
            tuple(config.sensors.index(name) for name in cell): float(share)
            for cell, share in plain.get("births", [])
        }
        # an export without them: each track's detections span two instants, or (a start of
        # one detection) are of the export's time
        tracker._detection_times = float_array(
            [
                e.get(
                    "detection_times",
                    [-math.inf if e["hits"] >= 2 else plain["time"], plain["time"]],
                )
                for e in entries
            ]
        ).reshape(-1, 2)
        tracker._state = IMMState(
            float_array([e["means"] for e in entries]).reshape(-1, r, n),
            float_array([e["covariances"] for e in entries]).reshape(-1, r, n, n),
            float_array([e["log_mode_probabilities"] for e in entries]).reshape(-1, r),
        )
        if tracker.classifier is not None:
            tracker._classes = tracker.classifier.from_classifications(
                [tracker._classification(e["classification"]) for e in entries]
            )
        if tracker._recent is not None:  # an export without them: none yet
            tracker._recent = RecentDetections.from_plain(
                [e.get("recent_detections", []) for e in entries], q
            )
        return tracker

    def _classification(self, plain: dict[str, Any]) -> CredalClassification:
        assert self.classifier is not None
        classifier = self.classifier
        mass = MassFunction(
            classifier.frame,
            np.array(plain["mass"]["masks"], dtype=np.int64),
            np.array(plain["mass"]["masses"], dtype=np.float64),
        )
        class_mass = (
            mass if classifier.accumulation == "classes" else classifier.relation.transfer(mass)
        )
        pignistic = class_mass.pignistic()
        return CredalClassification(
            mass=mass,
            class_mass=class_mass,
            pignistic=pignistic,
            step_conflict=float(float_array(plain["step_conflict"])),
            log_normaliser=float(float_array(plain["log_normaliser"])),
            status="ok" if pignistic is not None else "total_conflict",
            steps=int(plain["steps"]),
        )
