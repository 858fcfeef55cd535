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
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy.stats import chi2

from core.arrays import BoolArray, FloatArray, IntArray
from core.association import method_spec
from core.association.assignment import max_gain_matching
from core.association.cheap_jpda import CheapJpdaOptions
from core.association.gnn import GnnOptions
from core.distance import ModifiedScale, steady_state_covariance
from core.errors import InvalidInput, TrackingError
from core.lifecycle import ScoreModel
from core.pipeline.gate import pair_positions
from core.tracking.config import LocalTrackerConfig
from core.tracking.gating import ScanGating, TrackGatingProblem
from core.tracking.imm import IMMPrediction, IMMState, IMMUpdate, IMMUpdater
from core.tracking.jpda import clutter_bias, pda_update
from core.tracking.models import ModelBank, position_indices, velocity_indices


@dataclass(frozen=True)
class Association:
    """One scan's association of the tracks a detection may hit (``sub``) with the detections.

    Attributes
    ----------
    update : the updated state of every track of ``sub`` (``update.detected``: hit).
    rows, cols : each assigned detection ``cols[k]`` and its track ``rows[k]`` (of ``sub``).
    hit_gain : ΔL of each hit track of ``sub`` (0 elsewhere).
    used : the detections the association used (no track starts from them).
    branches : the starts' other gated detections (:class:`Branches`), or None.
    """

    update: IMMUpdate
    rows: IntArray
    cols: IntArray
    hit_gain: FloatArray
    used: IntArray
    branches: Branches | None = None


@dataclass(frozen=True)
class Branches:
    """Tracks split off single-point starts (docs/algorithms.md §8.3): one per other
    gated detection of a start, each that start updated with it.

    Attributes
    ----------
    rows : the start each branch comes from (a row of ``sub``).
    cols : its detection.
    gain : its hit ΔL.
    state : its updated IMM state.
    """

    rows: IntArray
    cols: IntArray
    gain: FloatArray
    state: IMMState


VELOCITY_SCALES: tuple[tuple[float, float], ...] = ((1.0, 1 / 3), (0.1, 1 / 3), (0.01, 1 / 3))
"""(scale s_k of σ_v, weight w_k) of the velocity prior's scale mixture without a velocity
prior (``core.tracking.config`` Readings)."""
MAX_BRANCHES = 8
"""Most hypotheses one single-point start carries into its second scan (its closest
gated detections): bounds the tentative tracks a dense scene makes."""
BRANCH_GATE_PROBABILITY = 0.999
"""The gate of a single-point start's second detections (as a χ² probability)."""


def z_rows(measurements: FloatArray, cols: IntArray) -> FloatArray:
    """The measurements ``cols`` as a (k, q) array."""
    return np.asarray(measurements[cols], dtype=np.float64).reshape(
        len(cols), measurements.shape[1]
    )


class DetectionAssociator:
    """The association method of a :class:`LocalTrackerConfig`, parsed once."""

    def __init__(
        self,
        config: LocalTrackerConfig,
        bank: ModelBank,
        score: ScoreModel,
        velocities: bool = True,
    ) -> None:
        self.config = config
        self.bank = bank
        self.updater = IMMUpdater(bank)
        self._score = score
        self._scan = score
        self._branch_gate = float(chi2.ppf(BRANCH_GATE_PROBABILITY, bank.measurement.dim))
        # no velocity prior: a start's second detection is scored under a scale mixture
        self._velocity_scales: tuple[tuple[float, float], ...] = (
            VELOCITY_SCALES if config.initial_velocity_std is None and velocities else ()
        )
        # per scale: 1 − s_k² and ln w_k, kept for every scan (the terms of _mixture_gain)
        self._mixture_terms = (
            np.array([1.0 - scale**2 for scale, _ in self._velocity_scales]),
            np.array([math.log(weight) for _, weight in self._velocity_scales]),
        )
        self._positions = position_indices(bank.axes)
        self._velocities = velocity_indices(bank.axes)
        self._h = bank.measurement.matrix
        self._noise = bank.measurement.noise_covariance
        self._q = bank.measurement.dim
        try:
            self._spec = method_spec(config.association_method, "local")
        except InvalidInput as error:
            raise TrackingError(str(error)) from None
        self._parsed_options: Any = self._spec.parse(dict(config.association_options))
        # the established tracks of several sensors' detections are assigned on the track
        # score (docs/algorithms.md §8.9): GNN's gate, the hit evidence's floor
        self._on_score = (
            isinstance(self._parsed_options, GnnOptions)
            and len(config.sensors) > 1
            and config.life_cycle.hit_evidence
        )
        if isinstance(self._parsed_options, CheapJpdaOptions) and self._parsed_options.bias is None:
            probability = self._parsed_options.gate_probability
            bias = clutter_bias(score.false_target_density, config.p_detect, probability)
            self._parsed_options = replace(self._parsed_options, bias=bias)
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

    @property
    def soft(self) -> bool:
        """The method weighs every gated detection (``cheap_jpda``): a PDA update, no hard
        pairs to branch on or to read a range-rate from."""
        return self._spec.soft

    def associate(
        self,
        sub: IMMPrediction,
        z: FloatArray,
        own_noise: FloatArray | None,
        first: BoolArray | IntArray,
        score: ScoreModel | None = None,
        branching: int | None = None,
    ) -> Association:
        """Associate and update the tracks of ``sub`` with the detections ``z`` (own R or None),
        in passes: the ``first`` tracks (the established ones) before the others, or, given
        integer ranks, rank 0 first, then 1, … on the detections left (cheap JPDA: soft
        over all); hits are scored by ``score`` (the scan's sensor's; default the
        configuration's). The tracks of rank ``branching`` (single-point starts) are not
        assigned: each takes its closest gated detection of those left, and each other
        one makes a branch (:class:`Branches`); their detections stay free."""
        self._scan = self._score if score is None else score
        if self._spec.soft:
            return self._jpda(sub, z, own_noise)
        return self._method_and_update(sub, z, own_noise, first, branching)

    def _hit_gain(self, distance: FloatArray, log_det: FloatArray) -> FloatArray:
        return self._scan.hit_increment(distance, log_det, self._q)

    def _method_and_update(
        self,
        sub: IMMPrediction,
        z: FloatArray,
        own_noise: FloatArray | None,
        first: BoolArray | IntArray,
        branching: int | None = None,
    ) -> Association:
        """Assignment by an association method, the ``first`` tracks before the others,
        which share the detections left (docs/algorithms.md §4, "Assignment"); then the
        IMM update of the assigned pairs.

        A tentative track's first gate is wide (its velocity is a prior), so in one
        assignment on D it takes a target's detection from that target's own track;
        with min_points confirmation it is confirmed on it, and the target changes id.
        """
        rank = np.asarray(first)
        if rank.dtype == np.bool_:
            rank = np.where(rank, 0, 1)
        gating = ScanGating(
            sub,
            z,
            own_noise,
            self._noise,
            self.config.imm_distance,
            self._modified if own_noise is None else self._modified_sum,
            # §8.1: an established track takes a detection only if the hit is at least as
            # likely as a miss and a false alarm
            np.where(rank == 0, self._scan.hit_floor, -np.inf)
            if self.config.life_cycle.hit_evidence
            else None,
        )
        left = np.ones(len(z), dtype=bool)
        found_rows, found_cols, found_gain = [], [], []
        for level in np.unique(rank[rank != branching]).tolist():
            assign = self._assign_on_score if level == 0 and self._on_score else self._assign
            rows, cols, gain = assign(gating, np.flatnonzero(rank == level), np.flatnonzero(left))
            left[cols] = False
            found_rows.append(rows)
            found_cols.append(cols)
            found_gain.append(gain)
        used = np.concatenate([np.zeros(0, dtype=np.int64), *found_cols])
        split = None
        if branching is not None and np.any(rank == branching):
            own, split = self._branch(
                gating, sub, np.flatnonzero(rank == branching), np.flatnonzero(left), own_noise
            )
            found_rows.append(own[0])
            found_cols.append(own[1])
            found_gain.append(own[2])
        rows = np.concatenate([np.zeros(0, dtype=np.int64), *found_rows])
        cols = np.concatenate([np.zeros(0, dtype=np.int64), *found_cols])
        hit_gain = np.zeros(len(first))
        hit_gain[rows] = np.concatenate([np.zeros(0), *found_gain])
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
        return Association(update, rows, cols, hit_gain, used, split)

    def _branch(
        self,
        gating: ScanGating,
        sub: IMMPrediction,
        starts: IntArray,
        detections: IntArray,
        own_noise: FloatArray | None,
    ) -> tuple[tuple[IntArray, IntArray, FloatArray], Branches]:
        """Every gated pair of ``starts`` × ``detections`` (the scan's 0.999 gate): each
        start's closest detection (smallest D) is its own hit, each other pair a branch
        (at most :data:`MAX_BRANCHES` per start, the closest)."""
        gated = gating.pairs(self._branch_gate, starts, detections)
        pairs = gated.pairs
        rows, cols = starts[pairs.rows], detections[pairs.cols]
        if self._velocity_scales:
            gain = self._mixture_gain(sub, gating.measurements, own_noise, rows, cols)
        else:
            gain = self._hit_gain(gated.plain_distance, pairs.log_det)
        order = np.lexsort((cols, gated.plain_distance, rows))  # by start, closest first
        rows, cols, gain = rows[order], cols[order], gain[order]
        rank_in_start = np.arange(len(rows)) - np.searchsorted(rows, rows, side="left")
        own = rank_in_start == 0
        extra = (rank_in_start > 0) & (rank_in_start < MAX_BRANCHES)
        branch_rows, branch_cols = rows[extra], cols[extra]
        copies = IMMPrediction(
            sub.means[branch_rows],
            sub.covariances[branch_rows],
            sub.log_mode_probabilities[branch_rows],
            sub.measurement_means[branch_rows],
            sub.innovation_covariances[branch_rows],
        )
        noises = None if own_noise is None else own_noise[branch_cols]
        updated = self.updater.update(
            copies, z_rows(gating.measurements, branch_cols), None, noises
        )
        branches = Branches(branch_rows, branch_cols, gain[extra], updated.state)
        return (rows[own], cols[own], gain[own]), branches

    def _mixture_gain(
        self,
        sub: IMMPrediction,
        z: FloatArray,
        own_noise: FloatArray | None,
        rows: IntArray,
        cols: IntArray,
    ) -> FloatArray:
        """The hit ΔL of a start's second detection under the scale mixture of its velocity
        prior (``core.tracking.config`` Readings): ``ln P_D − ln β_FT + ln Σ_k w_k N(ν; 0, S_k)``,
        ``S_k = S − (1 − s_k²) H P_pv P_vv⁻¹ P_vp Hᵀ`` (the part of S the velocity prior
        makes, scaled by s_k²), on the bank's first model."""
        if len(rows) == 0:
            return np.zeros(0)
        position, velocity = list(self._positions), list(self._velocities)
        covariance = sub.covariances[rows, 0]
        cross = covariance[:, position][:, :, velocity]
        spread = cross @ np.linalg.solve(
            covariance[:, velocity][:, :, velocity], np.swapaxes(cross, 1, 2)
        )
        s = sub.innovation_covariances[rows, 0]
        if own_noise is not None:
            s = s - self._noise + own_noise[cols]
        innovation = z[cols] - sub.measurement_means[rows, 0]
        # every scale at once (k, p, q, q): one solve and one slogdet, not one per scale
        shrink, log_weight = self._mixture_terms
        s_k = s - shrink[:, None, None, None] * spread
        nu = np.broadcast_to(innovation, s_k.shape[:-1])
        distance = np.einsum("kpi,kpi->kp", nu, np.linalg.solve(s_k, nu[..., None])[..., 0])
        log_det = np.linalg.slogdet(s_k)[1]
        terms = log_weight[:, None] - 0.5 * (self._q * math.log(2.0 * math.pi) + log_det + distance)
        mixed = np.logaddexp.reduce(terms, axis=0)
        score = self._scan
        return np.asarray(
            math.log(score.p_detect) - math.log(score.false_target_density) + mixed,
            dtype=np.float64,
        )

    def _assign_on_score(
        self, gating: ScanGating, tracks: IntArray, detections: IntArray
    ) -> tuple[IntArray, IntArray, FloatArray]:
        """The established tracks' pairs of several sensors' detections (docs/algorithms.md
        §8.9, "assigned on the score"): GNN's gated pairs (D ≤ T) that pass the hit floor,
        matched to maximise the summed score Σ (ΔL_hit − ΔL_miss) of [MTT] §4.3 eq 16 —
        the most likely single hypothesis of the tracks' scores — instead of Σ (T − D),
        which compares a gate that coasted through other sensors' scans with a narrow one
        on D alone (a 35 m jump of a young track's wide gate beats a 4 m miss of a kept
        track's narrow one). ``hit_floor`` makes every such pair's gain ≥ 0."""
        if len(tracks) == 0 or len(detections) == 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0)
        problem = TrackGatingProblem.of(gating, tracks, detections)
        gated = gating.pairs(self._parsed_options.resolve_threshold(problem), tracks, detections)
        pairs = gated.pairs
        gain = self._hit_gain(gated.plain_distance, pairs.log_det)
        matching = max_gain_matching(
            pairs.rows,
            pairs.cols,
            gain - self._scan.miss_increment,
            problem.n_known,
            problem.n_incoming,
            solver=problem.solver,
            cluster=problem.cluster,
        )
        rows, cols = matching.rows, matching.cols
        position = pair_positions(pairs.rows, pairs.cols, len(detections), rows, cols)
        return tracks[rows], detections[cols], gain[position]

    def _assign(
        self, gating: ScanGating, tracks: IntArray, detections: IntArray
    ) -> tuple[IntArray, IntArray, FloatArray]:
        """One association method's pairs of ``tracks`` × ``detections`` (ascending indices
        of the scan's ``gating``, which the pairs are given in) and each pair's hit gain."""
        if len(tracks) == 0 or len(detections) == 0:  # nothing to pair: no method run
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0)
        problem = TrackGatingProblem.of(gating, tracks, detections)
        result = self._spec.run(problem, self._parsed_options)
        rows, cols = result.pair_known, result.pair_incoming
        gain = np.zeros(0)
        if len(rows):
            gated = result.gated
            assert gated is not None  # every registered method returns its gated pairs
            position = pair_positions(gated.rows, gated.cols, len(detections), rows, cols)
            gain = self._hit_gain(gated.plain_distance[position], gated.log_det[position])
        return tracks[rows], detections[cols], gain

    def _jpda(self, sub: IMMPrediction, z: FloatArray, own_noise: FloatArray | None) -> Association:
        """The cheap JPDA baseline ([DH] §2): soft weights over gated pairs, PDA update."""
        if own_noise is not None:
            raise TrackingError(
                "cheap_jpda uses the bank's R: detections must not carry covariances",
                loc=("measurement_covariances", 0),
            )
        tracks = len(sub.means)
        gating = ScanGating(sub, z, None, self._noise, self.config.imm_distance, self._modified)
        everything = TrackGatingProblem.of(
            gating, np.arange(tracks, dtype=np.int64), np.arange(len(z), dtype=np.int64)
        )
        result = self._spec.run(everything, self._parsed_options)
        gated = result.gated
        assert gated is not None  # every registered method returns its gated pairs
        rows, cols = gated.rows, gated.cols
        weights = result.scores.dense()
        pair_weights = result.scores.values
        keep = pair_weights > 0.0
        update = pda_update(self.bank, sub, z, rows[keep], cols[keep], pair_weights[keep])
        hit_gain = np.zeros(tracks)
        if np.any(keep):
            # The most probable detection of each track scores it.
            best_col = np.argmax(weights, axis=1)
            has = weights.max(axis=1) > 0.0
            chosen = np.flatnonzero(has)
            position = pair_positions(rows, cols, len(z), chosen, best_col[chosen])
            hit_gain[chosen] = self._hit_gain(
                gated.plain_distance[position], gated.log_det[position]
            )
        # each detection goes to its most probable track, in detection order
        by_detection = np.argsort(result.pair_incoming, kind="stable")
        return Association(
            update,
            result.pair_known[by_detection],
            result.pair_incoming[by_detection],
            hit_gain,
            np.unique(cols),
        )
