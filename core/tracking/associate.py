"""Detections to the local tracker's tracks: one association method, the update, the hit ΔL
(docs/algorithms.md §3, §4 "Assignment").

:class:`DetectionAssociator` runs, on the predicted tracks a detection may
hit, either a method of :mod:`core.association` on the closest-model or
combined distance, plain or modified (:mod:`core.tracking.gating`), followed
by the IMM update, or the ``cheap_jpda`` baseline of [DH] §2 (soft weights,
PDA update). Either way it returns the updated state of those tracks, the
(track, detection) pairs for the step's assignment, each hit track's score
increment ΔL ([MTT] §4.3, eq 16, from the pair's D and log|S|) and the
detections it used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.stats import chi2

from core.arrays import BoolArray, FloatArray, IntArray
from core.association.associate import METHODS
from core.distance import ModifiedScale, steady_state_covariance
from core.errors import TrackingError
from core.lifecycle import ScoreModel
from core.pipeline.gate import pair_positions
from core.tracking.config import CHEAP_JPDA, LocalTrackerConfig
from core.tracking.gating import ScanGating, TrackGatingProblem, gate_pairs
from core.tracking.imm import IMMPrediction, IMMUpdate, IMMUpdater
from core.tracking.jpda import cheap_jpda_weights, clutter_bias, pda_update
from core.tracking.models import ModelBank


@dataclass(frozen=True)
class Association:
    """One scan's association of the tracks a detection may hit (``sub``) with the detections.

    Attributes
    ----------
    update : the updated state of every track of ``sub`` (``update.detected``: hit).
    rows, cols : each assigned detection ``cols[k]`` and its track ``rows[k]`` (of ``sub``).
    hit_gain : ΔL of each hit track of ``sub`` (0 elsewhere).
    used : the detections the association used (no track starts from them).
    """

    update: IMMUpdate
    rows: IntArray
    cols: IntArray
    hit_gain: FloatArray
    used: IntArray


class DetectionAssociator:
    """The association method of a :class:`LocalTrackerConfig`, parsed once."""

    def __init__(self, config: LocalTrackerConfig, bank: ModelBank, score: ScoreModel) -> None:
        self.config = config
        self.bank = bank
        self.updater = IMMUpdater(bank)
        self._score = score
        self._h = bank.measurement.matrix
        self._noise = bank.measurement.noise_covariance
        self._q = bank.measurement.dim
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
                    "bias", clutter_bias(score.false_target_density, config.p_detect, probability)
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
            first = bank.models[0]
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

    def associate(
        self, sub: IMMPrediction, z: FloatArray, own_noise: FloatArray | None, first: BoolArray
    ) -> Association:
        """Associate and update the tracks of ``sub`` with the detections ``z`` (own R or None),
        the ``first`` tracks (the established ones) before the others (cheap JPDA: soft
        over all)."""
        if self._method == CHEAP_JPDA:
            return self._jpda(sub, z, own_noise)
        return self._method_and_update(sub, z, own_noise, first)

    def _hit_gain(self, distance: FloatArray, log_det: FloatArray) -> FloatArray:
        return self._score.hit_increment(distance, log_det, self._q)

    def _method_and_update(
        self, sub: IMMPrediction, z: FloatArray, own_noise: FloatArray | None, first: BoolArray
    ) -> Association:
        """Assignment by an association method, the ``first`` tracks before the others,
        which share the detections left (docs/algorithms.md §4, "Assignment"); then the
        IMM update of the assigned pairs.

        A tentative track's first gate is wide (its velocity is a prior), so in one
        assignment on D it takes a target's detection from that target's own track;
        with min_points confirmation it is confirmed on it, and the target changes id.
        """
        gating = ScanGating(
            sub,
            z,
            own_noise,
            self._noise,
            self.config.imm_distance,
            self._modified if own_noise is None else self._modified_sum,
        )
        rows, cols, gain = self._assign(gating, np.flatnonzero(first), np.arange(len(z)))
        left = np.ones(len(z), dtype=bool)
        left[cols] = False
        later_rows, later_cols, later_gain = self._assign(
            gating, np.flatnonzero(~first), np.flatnonzero(left)
        )
        rows, cols = np.concatenate([rows, later_rows]), np.concatenate([cols, later_cols])
        hit_gain = np.zeros(len(first))
        hit_gain[rows] = np.concatenate([gain, later_gain])
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
        return Association(update, rows, cols, hit_gain, cols)

    def _assign(
        self, gating: ScanGating, tracks: IntArray, detections: IntArray
    ) -> tuple[IntArray, IntArray, FloatArray]:
        """One association method's pairs of ``tracks`` × ``detections`` (ascending indices
        of the scan's ``gating``, which the pairs are given in) and each pair's hit gain."""
        if len(tracks) == 0 or len(detections) == 0:  # nothing to pair: no method run
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0)
        problem = TrackGatingProblem.of(gating, tracks, detections)
        result = METHODS[self._method][1](problem, self._parsed_options)
        rows, cols = result.pair_known, result.pair_incoming
        gain = np.zeros(0)
        if len(rows):
            gated = problem.last["pairs"]
            position = pair_positions(
                gated.pairs.rows, gated.pairs.cols, len(detections), rows, cols
            )
            gain = self._hit_gain(gated.plain_distance[position], gated.pairs.log_det[position])
        return tracks[rows], detections[cols], gain

    def _jpda(self, sub: IMMPrediction, z: FloatArray, own_noise: FloatArray | None) -> Association:
        """The cheap JPDA baseline ([DH] §2): soft weights over gated pairs, PDA update."""
        if own_noise is not None:
            raise TrackingError(
                "cheap_jpda uses the bank's R: detections must not carry covariances",
                loc=("measurement_covariances", 0),
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
            position = pair_positions(rows, cols, len(z), chosen, best_col[chosen])
            hit_gain[chosen] = self._hit_gain(
                gated.plain_distance[position], gated.pairs.log_det[position]
            )
            best_cols = np.flatnonzero(weights.max(axis=0) > 0.0)
            best_rows = np.argmax(weights[:, best_cols], axis=0).astype(np.int64)
        return Association(update, best_rows, best_cols, hit_gain, np.unique(cols))
