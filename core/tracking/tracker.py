"""One sensor system's multi-target tracker: detections in, local tracks out ([MTT] Fig 6).

:class:`LocalTracker` runs, for each scan of one of its sensors, with every
array batched over tracks (and over the models of the IMM):

1. **predict** every live track to the scan time (:class:`IMMPredictor`):
   one closed-form step over the time since the previous scan, whatever it
   is (scans need not lie on a grid; a gap costs what one scan costs), none
   for a second sensor at the same time;
2. **visibility** of each predicted position ([HZ] §2.1): inside the scan
   sensor's field of view and not occluded by a known track (then a missing
   detection is a miss), in a blind zone, or out of range of every sensor;
3. **association** of detections with the non-phantom tracks by any method
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
6. **hand-over** ([HZ] §5.1, :func:`core.lifecycle.hand_over`): a track
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
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.stats import chi2

from core.arrays import BoolArray, FloatArray, IntArray
from core.association import associate
from core.association.associate import METHODS
from core.belief import MassFunction
from core.classification import CredalClassification
from core.classification.batched import BatchedCredalClassifier, CredalBatch, dense_to_mass
from core.distance import DistanceModel, Estimates, ModifiedScale, steady_state_covariance
from core.distance.estimates import check_covariances
from core.errors import TrackingError
from core.lifecycle import (
    PHANTOM,
    REASON_CODES,
    REASONS,
    STATUS_CODES,
    STATUSES,
    TERMINATED,
    Evidence,
    LifeState,
    StatusReason,
    TrackStatus,
    advance,
    established,
    everywhere,
    hand_over,
    visibility,
)
from core.tracking.config import CHEAP_JPDA, LocalTrackerConfig
from core.tracking.gating import TrackGatingProblem, gate_pairs
from core.tracking.imm import IMMPrediction, IMMPredictor, IMMState, IMMUpdate, IMMUpdater
from core.tracking.initiator import pair_seeds, single_point_initiation, two_point_initiation
from core.tracking.jpda import cheap_jpda_weights, clutter_bias, pda_update
from core.tracking.presets import VELOCITY, TrackingPreset, VelocityConvention
from core.tracking.range_rate import range_rate_update
from core.tracking.track import LocalTrack, TrackerStep, float_array, mass_to_plain, plain_floats

EXPORT_VERSION = 2
"""2: the seeds' covariances (``seed_covariances``); a version-1 export (without them)
restores its seeds with the bank's R, the R they were started with then."""
SEED_NOISE_GATE = 0.999
"""Gate probability of the measurement-noise part of the seed distance bound."""


def _as_prediction(bank_h: FloatArray, noise: FloatArray, state: IMMState) -> IMMPrediction:
    """A zero-step prediction: the posterior itself (a second sensor at the same time)."""
    h_t = bank_h.T
    return IMMPrediction(
        means=state.means,
        covariances=state.covariances,
        log_mode_probabilities=state.log_mode_probabilities,
        measurement_means=state.means @ h_t,
        innovation_covariances=bank_h @ state.covariances @ h_t + noise,
    )


def _select_prediction(prediction: IMMPrediction, rows: IntArray) -> IMMPrediction:
    return IMMPrediction(
        prediction.means[rows],
        prediction.covariances[rows],
        prediction.log_mode_probabilities[rows],
        prediction.measurement_means[rows],
        prediction.innovation_covariances[rows],
    )


def _concatenate(first: IMMState, second: IMMState) -> IMMState:
    return IMMState(
        np.concatenate([first.means, second.means]),
        np.concatenate([first.covariances, second.covariances]),
        np.concatenate([first.log_mode_probabilities, second.log_mode_probabilities]),
    )


class LocalTracker:
    """Multi-target tracker of one sensor system (module docstring).

    Parameters
    ----------
    config : LocalTrackerConfig
    """

    def __init__(self, config: LocalTrackerConfig) -> None:
        self.config = config
        self._score_model = config.score  # the SPRT of this tracker's sensors, built once
        found: TrackingPreset | None = config.tracking_preset()
        self.bank = config.model_bank()
        self.predictor = IMMPredictor(self.bank)
        self.updater = IMMUpdater(self.bank)
        self._h = self.bank.measurement.matrix
        self._noise = self.bank.measurement.noise_covariance
        self._q = self.bank.measurement.dim
        self._conventions: tuple[VelocityConvention, ...] = (
            (VELOCITY,) * self.bank.axes if found is None else found.conventions
        )
        if config.range_rate is not None and set(self._conventions) != {VELOCITY}:
            raise TrackingError("a range-rate needs velocities in the state, not headings")
        self.classifier: BatchedCredalClassifier | None = None
        if found is not None and config.classification is not None:
            chosen = config.classification
            self.classifier = BatchedCredalClassifier(
                found.behaviours,
                found.relation,
                likelihood_scale=chosen.likelihood_scale,
                discount=chosen.discount,
                reliability=chosen.reliability,
                accumulation=chosen.accumulation,
            )
        self._method = config.association_method
        options = dict(config.association_options)
        if self._method == CHEAP_JPDA:
            unknown = sorted(set(options) - {"bias", "gate_probability"})
            if unknown:
                raise TrackingError(f"cheap_jpda: unknown option(s) {unknown}")
            probability = float(options.get("gate_probability", 0.999))  # type: ignore[arg-type]
            if not 0.0 < probability < 1.0:
                raise TrackingError("cheap_jpda: gate_probability must be in (0, 1)")
            self._bias = float(
                options.get(  # type: ignore[arg-type]
                    "bias",
                    clutter_bias(
                        self._score_model.false_target_density, config.p_detect, probability
                    ),
                )
            )
            self._jpda_gate = float(chi2.ppf(probability, self._q))
            self._parsed_options: Any = None
        elif self._method in METHODS:
            self._parsed_options = METHODS[self._method][0](options)
        else:
            raise TrackingError(
                f"unknown association method {self._method!r}; "
                f"choose one of {[*METHODS, CHEAP_JPDA]}"
            )
        self._modified: ModifiedScale | None = None
        self._modified_sum: ModifiedScale | None = None
        if config.distance == "modified":
            first = self.bank.models[0]
            steady = steady_state_covariance(
                first.transition, first.process_noise, self._h, self._noise
            )
            kwargs = {
                "beta": config.modified_beta,
                "k": config.modified_k,
                "alpha": config.modified_alpha,
            }
            self._modified = ModifiedScale.of(steady.innovation, **kwargs)
            self._modified_sum = ModifiedScale.of(steady.innovation - self._noise, **kwargs)
        self._coverage = config.coverage
        self._views = dict(config.fields_of_view)
        # The state: one row per live track.
        self.time: float | None = None
        self.next_number = 1
        n, r = self.bank.state_dim, self.bank.n_models
        self._numbers: IntArray = np.zeros(0, dtype=np.int64)
        self._life = LifeState.empty()
        self._state = IMMState(np.zeros((0, r, n)), np.zeros((0, r, n, n)), np.zeros((0, r)))
        self._classes: CredalBatch | None = (
            None if self.classifier is None else self.classifier.initial(0)
        )
        self._seeds: FloatArray = np.zeros((0, self._q))
        self._seed_noises: FloatArray = np.zeros((0, self._q, self._q))
        self._seed_times: FloatArray = np.zeros(0)
        self._seed_sensors: IntArray = np.zeros(0, dtype=np.int64)

    # ------------------------------------------------------------------ api
    @property
    def n_tracks(self) -> int:
        """Live tracks (terminated ones are dropped after the step that ends them)."""
        return len(self._numbers)

    def step(
        self,
        time: float,
        measurements: ArrayLike,
        measurement_covariances: ArrayLike | None = None,
        sensor: str | None = None,
        range_rates: ArrayLike | None = None,
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
            Each detection's range-rate (NaN: none), for a tracker configured
            with a ``range_rate`` model (:mod:`core.tracking.range_rate`).

        Raises
        ------
        TrackingError
            Unknown sensor, a time that goes back, wrong shapes, non-finite
            numbers; nothing changes then.
        """
        before = self.checkpoint()
        try:
            return self._step(time, measurements, measurement_covariances, sensor, range_rates)
        except BaseException:
            self.rollback(before)
            raise

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
    ) -> TrackerStep:
        z, own_noise, sensor_name, elapsed = self._check(
            time, measurements, measurement_covariances, sensor
        )
        doppler = self._check_range_rates(range_rates, len(z))
        prediction = self._predict(elapsed)
        tracks = len(self._numbers)
        combined_z, combined_s = prediction.combined_measurement()
        codes, seen, hidden = self._visibility(combined_z, sensor_name)

        candidates = np.flatnonzero((self._life.status != PHANTOM) & self._can_be_hit(prediction))
        sub = _select_prediction(prediction, candidates)
        if self._method == CHEAP_JPDA:  # soft: every track shares every gated detection
            update, pair_rows, pair_cols, hit_gain, used = self._jpda(sub, z, own_noise)
        else:
            update, pair_rows, pair_cols, hit_gain, used = self._associate(
                sub, z, own_noise, established(self._life.status[candidates])
            )
        if doppler is not None and self.config.range_rate is not None and len(pair_rows):
            measured = np.isfinite(doppler[pair_cols])
            update = range_rate_update(
                update,
                pair_rows[measured],
                doppler[pair_cols[measured]],
                self.config.range_rate,
                self.bank.axes,
            )
        detected = np.zeros(tracks, dtype=bool)
        detected[candidates] = update.detected
        means = prediction.means.copy()
        covariances = prediction.covariances.copy()
        log_mu = prediction.log_mode_probabilities.copy()
        means[candidates] = update.state.means
        covariances[candidates] = update.state.covariances
        log_mu[candidates] = update.state.log_mode_probabilities
        self._state = IMMState(means, covariances, log_mu)
        if self.classifier is not None and self._classes is not None and len(candidates):
            every = len(candidates) == tracks
            classified = self.classifier.update(
                self._classes if every else self._classes.select(candidates),
                update.log_mode_probabilities,
                update.log_likelihoods,
                update.detected,
            )
            self._classes = classified if every else self._classes.replace(candidates, classified)

        gain = np.zeros(tracks)
        gain[candidates] = hit_gain
        status = self._life.status
        established_miss = seen & ~detected & established(status)
        self._life, newly_confirmed = advance(
            self.config.life_cycle,
            self._life,
            Evidence(
                time=time,
                detected=detected,
                hit_increment=gain,
                seen=seen,
                miss_increment=self._score_model.miss_increment,
                # log|S|: A_G of the tracks that coast through a miss
                gate_log_det=(
                    np.linalg.slogdet(combined_s)[1]
                    if np.any(established_miss)
                    else np.zeros(tracks)
                ),
                gate_dim=self._q,
                visibility=codes,
                occluded=hidden,
            ),
        )

        # Per-detection assignment (by track number for now).
        numbers = np.full(len(z), -1, dtype=np.int64)
        numbers[pair_cols] = self._numbers[candidates[pair_rows]]
        self._hand_over(newly_confirmed, numbers)
        free = np.ones(len(z), dtype=bool)
        free[used] = False
        noises = (
            np.broadcast_to(self._noise, (len(z), self._q, self._q))
            if own_noise is None
            else own_noise
        )
        self._initiate(time, sensor_name, z, noises, free, numbers)
        return self._result(time, sensor_name, numbers)

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
            raise TrackingError(f"unknown sensor {sensor_name!r}; known: {list(self._views)}")
        if not math.isfinite(time):
            raise TrackingError(f"time must be finite, got {time!r}")
        z = np.asarray(measurements, dtype=np.float64)
        if z.size == 0:
            z = z.reshape(0, self._q)
        if z.ndim != 2 or z.shape[1] != self._q:
            raise TrackingError(f"measurements must have shape (m, {self._q}), got {z.shape}")
        if not np.all(np.isfinite(z)):
            raise TrackingError("measurements must be finite")
        own: FloatArray | None = None
        if measurement_covariances is not None:
            own = np.asarray(measurement_covariances, dtype=np.float64)
            if own.size == 0:
                own = own.reshape(0, self._q, self._q)
            if own.shape != (len(z), self._q, self._q):
                raise TrackingError(
                    f"measurement_covariances must have shape ({len(z)}, {self._q}, {self._q})"
                )
            if len(own):
                check_covariances(own, "measurement_covariances")
        elapsed = 0.0
        if self.time is not None:
            elapsed = time - self.time
            if elapsed < 0.0:
                raise TrackingError(
                    f"scan time {time!r} is before the previous scan's time {self.time!r}"
                )
        return z, own, sensor_name, elapsed

    def _check_range_rates(self, range_rates: ArrayLike | None, count: int) -> FloatArray | None:
        """Each detection's range-rate (NaN: none), or None; only with a ``range_rate`` model."""
        if range_rates is None:
            return None
        if self.config.range_rate is None:
            raise TrackingError("range_rates need a tracker configured with a range_rate model")
        if self._method == CHEAP_JPDA:
            raise TrackingError("cheap_jpda takes no range-rates")
        doppler = np.asarray(range_rates, dtype=np.float64).reshape(-1)
        if doppler.shape != (count,) or np.any(np.isinf(doppler)):
            raise TrackingError(f"range_rates must be {count} finite numbers (NaN: none)")
        return doppler

    # ---------------------------------------------------------- predict
    def _predict(self, elapsed: float) -> IMMPrediction:
        """Every track over the time since the previous scan, in one closed-form step
        (:meth:`IMMPredictor.predict`); none for a second scan at the same time."""
        state = self._state
        if elapsed == 0.0:
            return _as_prediction(self._h, self._noise, state)
        return self.predictor.predict(state, elapsed)

    def _can_be_hit(self, prediction: IMMPrediction) -> BoolArray:
        """Tracks a detection could keep alive: the largest hit increment they could get
        (distance 0, their most certain model, no measurement noise: ``log |H P_j Hᵀ|``)
        leaves their score above the delete threshold.

        A prediction so uncertain that no detection can (a scan after a long gap)
        is not associated: the track misses, its gate empties ([HZ] §4.2) and
        it is terminated, and the scan costs what any scan costs instead of
        gating every detection with every track.
        """
        score = self._life.score
        if len(score) == 0:
            return np.zeros(0, dtype=bool)
        sign, log_det = np.linalg.slogdet(prediction.innovation_covariances - self._noise)
        log_det = np.where(sign > 0.0, log_det, -np.inf).min(axis=1)
        best = self._score_model.hit_increment(np.zeros_like(log_det), log_det, self._q)
        return np.asarray(score + best > self._score_model.delete_threshold, dtype=np.bool_)

    def _visibility(
        self, positions: FloatArray, sensor: str
    ) -> tuple[IntArray, BoolArray, BoolArray]:
        """Coverage codes of every track, seen by the scan's sensor, occluded (by the
        confirmed and coasting tracks; :func:`core.lifecycle.visibility`)."""
        if self._q < 2:
            return everywhere(len(positions))
        positions = positions[:, :2]  # fields of view are planar: x, y of a 3-D track
        status = self._life.status
        occluders = positions[established(status)]
        return visibility(
            self._coverage,
            self._views[sensor],
            positions,
            occluders,
            self.config.life_cycle.occlusion_radius,
        )

    # ------------------------------------------------------- association
    def _hit_gain(self, distance: FloatArray, log_det: FloatArray) -> FloatArray:
        return self._score_model.hit_increment(distance, log_det, self._q)

    def _associate(
        self, sub: IMMPrediction, z: FloatArray, own_noise: FloatArray | None, first: BoolArray
    ) -> tuple[IMMUpdate, IntArray, IntArray, FloatArray, IntArray]:
        """Assignment by an association method, the ``first`` tracks (the established ones)
        before the others, which share the detections left (docs/algorithms.md §4,
        "Assignment"); returns the update, pairs, hit gains, used detections.

        A tentative track's first gate is wide (its velocity is a prior), so in one
        assignment on D it takes a target's detection from that target's own track;
        with min_points confirmation it is confirmed on it, and the target changes id.
        """
        leading, trailing = np.flatnonzero(first), np.flatnonzero(~first)
        if len(leading) == 0 or len(trailing) == 0:
            rows, cols, hit_gain = self._assign(sub, z, own_noise)
        else:
            rows, cols, gain = self._assign(_select_prediction(sub, leading), z, own_noise)
            left = np.setdiff1d(np.arange(len(z)), cols)
            later_rows, later_cols, later_gain = self._assign(
                _select_prediction(sub, trailing),
                z[left],
                None if own_noise is None else own_noise[left],
            )
            hit_gain = np.zeros(len(first))
            hit_gain[leading], hit_gain[trailing] = gain, later_gain
            rows = np.concatenate([leading[rows], trailing[later_rows]])
            cols = np.concatenate([cols, left[later_cols]])
        tracks = len(first)
        assigned = np.zeros((tracks, self._q))
        assigned[rows] = z[cols]
        detected = np.zeros(tracks, dtype=bool)
        detected[rows] = True
        noises = None
        if own_noise is not None:
            noises = np.broadcast_to(self._noise, (tracks, self._q, self._q)).copy()
            noises[rows] = own_noise[cols]
        update = self.updater.update(sub, assigned, detected, noises)
        return update, rows, cols, hit_gain, cols

    def _assign(
        self, sub: IMMPrediction, z: FloatArray, own_noise: FloatArray | None
    ) -> tuple[IntArray, IntArray, FloatArray]:
        """One association method's pairs of ``sub`` × ``z`` and each track's hit gain."""
        if len(z) == 0 or len(sub.means) == 0:  # nothing to pair: no method run
            return (
                np.zeros(0, dtype=np.int64),
                np.zeros(0, dtype=np.int64),
                np.zeros(len(sub.means)),
            )
        combined_z, combined_s = sub.combined_measurement()
        problem = TrackGatingProblem(
            known=Estimates(combined_z, combined_s, "tracks"),
            incoming=Estimates(z, own_noise, "detections"),
            distance=DistanceModel(covariance="innovation" if own_noise is None else "sum"),
            prediction=sub,
            measurement_covariances=own_noise,
            noise=self._noise,
            imm_distance=self.config.imm_distance,
            modified=self._modified if own_noise is None else self._modified_sum,
        )
        result = METHODS[self._method][1](problem, self._parsed_options)
        rows, cols = result.pair_known, result.pair_incoming
        hit_gain = np.zeros(len(combined_z))
        if len(rows):
            gated = problem.last["pairs"]
            keys = gated.pairs.rows * len(z) + gated.pairs.cols
            position = np.searchsorted(keys, rows * len(z) + cols)
            hit_gain[rows] = self._hit_gain(
                gated.plain_distance[position], gated.pairs.log_det[position]
            )
        return rows, cols, hit_gain

    def _jpda(
        self, sub: IMMPrediction, z: FloatArray, own_noise: FloatArray | None
    ) -> tuple[IMMUpdate, IntArray, IntArray, FloatArray, IntArray]:
        """The cheap JPDA baseline: soft weights over gated pairs, PDA update."""
        if own_noise is not None:
            raise TrackingError(
                "cheap_jpda uses the bank's R: detections must not carry covariances"
            )
        tracks = len(sub.means)
        gated = gate_pairs(
            sub, z, None, self._noise, self._jpda_gate, self.config.imm_distance, self._modified
        )
        rows, cols = gated.pairs.rows, gated.pairs.cols
        log_g = -0.5 * (
            gated.plain_distance + gated.pairs.log_det + self._q * math.log(2 * math.pi)
        )
        likelihoods = np.zeros((tracks, len(z)))
        likelihoods[rows, cols] = np.exp(log_g)
        weights, _ = cheap_jpda_weights(likelihoods, self._bias)
        pair_weights = weights[rows, cols]
        keep = pair_weights > 0.0
        update = pda_update(self.bank, sub, z, rows[keep], cols[keep], pair_weights[keep])
        hit_gain = np.zeros(tracks)
        best_rows = np.zeros(0, dtype=np.int64)
        best_cols = np.zeros(0, dtype=np.int64)
        if np.any(keep):
            # The most probable detection of each track scores it; each detection goes to its most probable track.
            best_col = np.argmax(weights, axis=1)
            has = weights.max(axis=1) > 0.0
            chosen = np.flatnonzero(has)
            keys = rows * len(z) + cols
            position = np.searchsorted(keys, chosen * len(z) + best_col[chosen])
            hit_gain[chosen] = self._hit_gain(
                gated.plain_distance[position], gated.pairs.log_det[position]
            )
            best_cols = np.flatnonzero(weights.max(axis=0) > 0.0)
            best_rows = np.argmax(weights[:, best_cols], axis=0).astype(np.int64)
        used = np.unique(cols)
        return update, best_rows, best_cols, hit_gain, used

    # -------------------------------------------------------- hand-over
    def _hand_over(self, newly_confirmed: BoolArray, numbers: IntArray) -> None:
        """Newly confirmed tracks that match a phantom give it their estimate ([HZ] §5.1)."""
        phantoms = np.flatnonzero(self._life.status == PHANTOM)
        fresh = np.flatnonzero(newly_confirmed)
        if len(phantoms) == 0 or len(fresh) == 0:
            return
        means, covariances = self._state.combined()
        decision = associate(
            (means[phantoms], covariances[phantoms]),
            (means[fresh], covariances[fresh]),
            "gnn",
            {"gate_probability": self.config.life_cycle.gate_probability},
            "sum",
        )
        if len(decision.pair_known) == 0:
            return
        keepers = phantoms[decision.pair_known]
        newcomers = fresh[decision.pair_incoming]
        state = self._state
        means_all, covs_all, log_mu = (
            state.means.copy(),
            state.covariances.copy(),
            state.log_mode_probabilities.copy(),
        )
        means_all[keepers] = state.means[newcomers]
        covs_all[keepers] = state.covariances[newcomers]
        log_mu[keepers] = state.log_mode_probabilities[newcomers]
        self._state = IMMState(means_all, covs_all, log_mu)
        self._life = hand_over(self._life, keepers, newcomers, StatusReason.MERGED_INTO_PHANTOM)
        if self.classifier is not None and self._classes is not None:
            # The newcomer's cumulative mass is one more piece of evidence for the keeper.
            merged = self.classifier.combine(
                self._classes.select(keepers), self._classes.masses[newcomers]
            )
            self._classes = self._classes.replace(keepers, merged)
        for keeper, newcomer in zip(keepers.tolist(), newcomers.tolist(), strict=True):
            numbers[numbers == self._numbers[newcomer]] = self._numbers[keeper]

    # -------------------------------------------------------- initiation
    def _initiate(
        self,
        time: float,
        sensor: str,
        z: FloatArray,
        noises: FloatArray,
        free: BoolArray,
        numbers: IntArray,
    ) -> None:
        """New tentative tracks from the detections nobody used (config Readings), each
        started and scored with its detections' own covariances ``noises`` (m, q, q)."""
        detections = np.flatnonzero(free)
        if self.config.initiation == "single_point":
            starts = detections
            state = single_point_initiation(
                self.bank, z[starts], self.config.initial_velocity_std, noises=noises[starts]
            )
            self._append(state, starts, numbers)
            return
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
                spread = self.config.initial_velocity_std**2 * interval**2
                pair_covariance = first_noises + noises[starts] + spread * np.eye(self._q)
                start_score = self._score_model.two_point_initial(
                    z[starts] - first, pair_covariance
                )
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
                self._append(state, starts, numbers, hits=2, score=start_score[order])
        remaining = np.setdiff1d(detections, starts)
        kept = ~older
        self._seeds = np.concatenate([self._seeds[kept], z[remaining]])
        self._seed_noises = np.concatenate([self._seed_noises[kept], noises[remaining]])
        self._seed_times = np.concatenate([self._seed_times[kept], np.full(len(remaining), time)])
        self._seed_sensors = np.concatenate(
            [self._seed_sensors[kept], np.full(len(remaining), sensor_index, dtype=np.int64)]
        )

    def _append(
        self,
        state: IMMState,
        detections: IntArray,
        numbers: IntArray,
        hits: int = 1,
        score: FloatArray | None = None,
    ) -> None:
        count = len(detections)
        if count == 0:
            return
        new_numbers = np.arange(self.next_number, self.next_number + count, dtype=np.int64)
        self.next_number += count
        numbers[detections] = new_numbers
        self._numbers = np.concatenate([self._numbers, new_numbers])
        start = self._score_model.initial if score is None else score
        self._life = self._life.concatenate(LifeState.new(count, start, hits))
        self._state = _concatenate(self._state, state)
        if self.classifier is not None and self._classes is not None:
            self._classes = self._classes.concatenate(self.classifier.initial(count))

    # ------------------------------------------------------------ output
    def _track_id(self, number: int) -> str:
        return f"{self.config.id_prefix}{number}"

    def _result(self, time: float, sensor: str, numbers: IntArray) -> TrackerStep:
        means, covariances = self._state.combined()
        mu = self._state.mode_probabilities
        order = np.argsort(self._numbers, kind="stable")
        classes = self._classes
        class_masses: list[MassFunction | None] = [None] * len(order)
        pignistic: list[FloatArray | None] = [None] * len(order)
        if self.classifier is not None and classes is not None:
            class_masses = list(self.classifier.class_mass_functions(classes))
            pignistic = [
                row_betp if defined else None
                for row_betp, defined in zip(
                    classes.pignistic, classes.defined.tolist(), strict=True
                )
            ]
        tracks = []
        life = self._life
        track_numbers, status, reason = (
            self._numbers.tolist(),
            life.status.tolist(),
            life.reason.tolist(),
        )
        score, hits = life.score.tolist(), life.hits.tolist()
        for row in order.tolist():
            tracks.append(
                LocalTrack(
                    id=self._track_id(track_numbers[row]),
                    status=STATUSES[status[row]],
                    reason=REASONS[reason[row]],
                    state=means[row],
                    covariance=covariances[row],
                    mode_probabilities=mu[row],
                    score=score[row],
                    hits=hits[row],
                    class_mass=class_masses[row],
                    pignistic=pignistic[row],
                )
            )
        live = life.status != TERMINATED
        self._keep(np.flatnonzero(live))
        self.time = time
        assignment = tuple(None if n < 0 else self._track_id(int(n)) for n in numbers.tolist())
        return TrackerStep(time=time, sensor=sensor, tracks=tuple(tracks), assignment=assignment)

    def _keep(self, rows: IntArray) -> None:
        self._numbers = self._numbers[rows]
        self._life = self._life.select(rows)
        self._state = self._state.select(rows)
        if self._classes is not None:
            self._classes = self._classes.select(rows)

    # ------------------------------------------------------- persistence
    def export(self) -> dict[str, Any]:
        """The whole state as plain data (lists, floats, ints, str, None; see :mod:`core.tracking.track`)."""
        tracks = []
        life = self._life
        for row in range(len(self._numbers)):
            entry: dict[str, Any] = {
                "number": int(self._numbers[row]),
                "status": STATUSES[int(life.status[row])].value,
                "reason": REASONS[int(life.reason[row])].value,
                "score": plain_floats(life.score[row]),
                "hits": int(life.hits[row]),
                "empty_gate_probability": plain_floats(life.empty_gate[row]),
                "phantom_since": plain_floats(life.phantom_since[row]),
                "means": plain_floats(self._state.means[row]),
                "covariances": plain_floats(self._state.covariances[row]),
                "log_mode_probabilities": plain_floats(self._state.log_mode_probabilities[row]),
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
            tracks.append(entry)
        return {
            "version": EXPORT_VERSION,
            "time": None if self.time is None else plain_floats(np.float64(self.time)),
            "next_number": self.next_number,
            "seeds": plain_floats(self._seeds),
            "seed_covariances": plain_floats(self._seed_noises),
            "seed_times": plain_floats(self._seed_times),
            "seed_sensors": self._seed_sensors.tolist(),
            "tracks": tracks,
        }

    @classmethod
    def restore(cls, config: LocalTrackerConfig, plain: dict[str, Any]) -> LocalTracker:
        """Rebuild a tracker from :meth:`export`'s output and the same configuration."""
        version = plain.get("version")
        if version not in (1, EXPORT_VERSION):
            raise TrackingError(f"unknown tracker export version {version!r}")
        tracker = cls(config)
        tracker.time = None if plain["time"] is None else float(float_array(plain["time"]))
        tracker.next_number = int(plain["next_number"])
        q = tracker._q
        tracker._seeds = float_array(plain["seeds"]).reshape(-1, q)
        tracker._seed_noises = (
            float_array(plain["seed_covariances"]).reshape(-1, q, q)
            if version == EXPORT_VERSION
            else np.broadcast_to(tracker._noise, (len(tracker._seeds), q, q)).copy()
        )
        tracker._seed_times = float_array(plain["seed_times"]).reshape(-1)
        tracker._seed_sensors = np.array(plain["seed_sensors"], dtype=np.int64).reshape(-1)
        entries = plain["tracks"]
        n, r = tracker.bank.state_dim, tracker.bank.n_models
        tracker._numbers = np.array([e["number"] for e in entries], dtype=np.int64)
        tracker._life = LifeState(
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
        )
        tracker._state = IMMState(
            float_array([e["means"] for e in entries]).reshape(-1, r, n),
            float_array([e["covariances"] for e in entries]).reshape(-1, r, n, n),
            float_array([e["log_mode_probabilities"] for e in entries]).reshape(-1, r),
        )
        if tracker.classifier is not None:
            tracker._classes = tracker.classifier.from_classifications(
                [tracker._classification(e["classification"]) for e in entries]
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
