"""Measurement-to-track gating of IMM tracks, for any association method (docs/algorithms.md §4).

An IMM track predicts one ẑ_j, S_j per model j. The pair (track t,
detection i) is gated and scored ([MTT] eq 15) with

- ``"closest_model"`` (default): the model with the smallest
  ``D_j = (z_i − ẑ_j)ᵀ S_j⁻¹ (z_i − ẑ_j)``, so that a manoeuvre the bank
  contains never falls outside the gate of the combined prediction;
- ``"combined"``: the model-combined ẑ, S of [MTT] §4;
- ``"gated_combined"``: gated by the closest model, ranked (the distance the
  association decides on) by the model-combined D, capped just under the gate
  so that every gated pair stays possible.

:class:`TrackGatingProblem` is an :class:`~core.association.AssociationProblem`
whose candidate pairs are computed that way (on the T × r model rows, with the
KD-tree gate of :func:`core.distance.gated_pairs`, then reduced to the closest
model per pair), so every association method of §3 runs on it unchanged. Its
pairs are part of one :class:`ScanGating` of the scan: the two assignment
passes (established tracks, then tentative ones on the detections left;
docs/algorithms.md §4 "Assignment") share one gating of every track with every
detection.

Detections that carry their own covariance R_i use ``C = H P_j Hᵀ + R_i``
(the ``sum`` covariance of :mod:`core.distance.pairwise` with the known side
``H P_j Hᵀ``); otherwise ``C = S_j`` (``innovation``). The modified distance of
[HZ] §4.1 scales each model row by its size against the steady state of the
same kind (S_ss, or H P_ss Hᵀ for the ``sum`` form). The plain D of every
kept pair is kept too: the track score uses it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from core.arrays import BoolArray, FloatArray, IntArray
from core.association.problem import AssociationProblem
from core.distance import CandidatePairs, DistanceModel, Estimates, ModifiedScale, gated_pairs
from core.numerics import logsumexp
from core.pipeline.gate import mahalanobis
from core.tracking.config import ImmDistance
from core.tracking.imm import IMMPrediction

_LOG_2PI = float(np.log(2.0 * np.pi))


@dataclass(frozen=True, eq=False)
class GatedPairs:
    """Candidate pairs reduced to one model per (track, detection).

    Attributes
    ----------
    pairs : CandidatePairs
        Rows are tracks, columns detections; ``distance`` is the distance the
        association decides on (modified when configured), ``log_det`` is
        log|C| of the chosen model, ``plain`` the unmodified D of each pair
        ([MTT] eq 15), for the track score.
    models : ndarray of int64, shape (P,)
        The model of each pair (−1 with the ``combined`` distance).
    """

    pairs: CandidatePairs
    models: IntArray

    @property
    def plain_distance(self) -> FloatArray:
        """The unmodified D of each pair ([MTT] eq 15)."""
        return self.pairs.plain_distance

    def restricted(self, tracks: IntArray, detections: IntArray) -> GatedPairs:
        """The pairs of ``tracks`` × ``detections`` (ascending indices), renumbered by their
        positions there: what gating those tracks and detections alone gives (every number
        is a pair's own), in the same (track, detection) order."""
        pairs = self.pairs
        if len(tracks) == pairs.n_known and len(detections) == pairs.n_incoming:
            return self  # all of them, ascending: the identity
        track_at = np.full(pairs.n_known, -1, dtype=np.int64)
        track_at[tracks] = np.arange(len(tracks))
        detection_at = np.full(pairs.n_incoming, -1, dtype=np.int64)
        detection_at[detections] = np.arange(len(detections))
        rows, cols = track_at[pairs.rows], detection_at[pairs.cols]
        keep = (rows >= 0) & (cols >= 0)
        return self._subset(keep, rows, cols, len(tracks), len(detections))

    def kept(self, keep: BoolArray) -> GatedPairs:
        """The pairs where ``keep`` is True, numbered as before."""
        pairs = self.pairs
        return self._subset(keep, pairs.rows, pairs.cols, pairs.n_known, pairs.n_incoming)

    def _subset(
        self, keep: BoolArray, rows: IntArray, cols: IntArray, n_known: int, n_incoming: int
    ) -> GatedPairs:
        """The pairs where ``keep`` is True, with ``rows``/``cols`` as their indices among
        ``n_known`` tracks and ``n_incoming`` detections."""
        pairs = self.pairs
        reduced = CandidatePairs(
            rows[keep],
            cols[keep],
            pairs.distance[keep],
            pairs.log_det[keep],
            n_known,
            n_incoming,
            pairs.dimension,
            self.plain_distance[keep],
        )
        return GatedPairs(reduced, self.models[keep])


def gate_pairs(
    prediction: IMMPrediction,
    measurements: FloatArray,
    measurement_covariances: FloatArray | None,
    noise: FloatArray,
    gate: float,
    imm_distance: ImmDistance,
    modified: ModifiedScale | None,
    floors: FloatArray | None = None,
) -> GatedPairs:
    """Every (track, detection) pair with D ≤ ``gate`` (module docstring), and, for the
    tracks with a finite ``floors`` entry, whose likelihood reaches it (:func:`_explained`).

    Parameters
    ----------
    prediction : IMMPrediction of T tracks
    measurements : ndarray, shape (m, q)
    measurement_covariances : ndarray, shape (m, q, q), or None (the bank's R)
    noise : ndarray, shape (q, q)
        The bank's R (subtracted from S for the ``sum`` form).
    gate : float
    imm_distance : "closest_model" | "combined"
    modified : ModifiedScale or None
    floors : ndarray, shape (T,), or None
        Per track, the least held-mixture log-likelihood ln Λ(z) of a detection it may take
        (−inf: none; :attr:`~core.lifecycle.ScoreModel.hit_floor`).
    """
    found = _gated(
        prediction, measurements, measurement_covariances, noise, gate, imm_distance, modified
    )
    if floors is None or not np.any(np.isfinite(floors[found.pairs.rows])):
        return found
    return found.kept(
        _explained(prediction, measurements, measurement_covariances, noise, found, floors)
    )


def _explained(
    prediction: IMMPrediction,
    measurements: FloatArray,
    measurement_covariances: FloatArray | None,
    noise: FloatArray,
    found: GatedPairs,
    floors: FloatArray,
) -> BoolArray:
    """Which ``found`` pairs stay: those of tracks without a floor, and those whose held
    mixture ``ln Λ(z) = ln Σ_j h_j N(z; ẑ_j, C_j)`` ([MTT] eq 18, each model weighted by
    the probability that it held over the step, :meth:`IMMPredictor.held`) reaches their
    track's floor (docs/algorithms.md §8.1, "A detection after a long gap")."""
    rows, cols = found.pairs.rows, found.pairs.cols
    keep = np.ones(len(rows), dtype=bool)
    tested = np.flatnonzero(np.isfinite(floors[rows]))
    tracks, detections = rows[tested], cols[tested]
    spreads = prediction.innovation_covariances[tracks]  # (P, r, q, q)
    if measurement_covariances is not None:
        spreads = spreads - noise + measurement_covariances[detections][:, None]
    innovations = measurements[detections][:, None, :] - prediction.measurement_means[tracks]
    q = measurements.shape[1]
    distance, log_det = mahalanobis(innovations.reshape(-1, q), spreads.reshape(-1, q, q))
    log_normal = -0.5 * (q * _LOG_2PI + log_det + distance).reshape(innovations.shape[:2])
    log_mixture = logsumexp(prediction.log_held[tracks] + log_normal, axis=1)
    keep[tested] = log_mixture >= floors[tracks]
    return keep


def _gated(
    prediction: IMMPrediction,
    measurements: FloatArray,
    measurement_covariances: FloatArray | None,
    noise: FloatArray,
    gate: float,
    imm_distance: ImmDistance,
    modified: ModifiedScale | None,
) -> GatedPairs:
    """Every (track, detection) pair with D ≤ ``gate`` (:func:`gate_pairs`)."""
    tracks, models = prediction.log_mode_probabilities.shape
    q = measurements.shape[1]
    if imm_distance == "combined":
        centres, spreads = prediction.combined_measurement()
        per_row = 1
    else:
        centres = prediction.measurement_means.reshape(tracks * models, q)
        spreads = prediction.innovation_covariances.reshape(tracks * models, q, q)
        per_row = models
    own_noise = measurement_covariances is not None
    known_cov = spreads - noise if own_noise else spreads
    known = Estimates(centres, known_cov, "tracks")
    incoming = Estimates(measurements, measurement_covariances, "detections")
    model = DistanceModel(covariance="sum" if own_noise else "innovation", modified=modified)
    found = gated_pairs(known, incoming, gate, model)
    rows, cols = found.rows, found.cols
    plain = found.distance
    if modified is not None and len(rows):
        plain = found.distance / modified.ratio(known_cov)[rows]
    if per_row > 1 and len(rows):
        track = rows // per_row
        order = np.lexsort((found.distance, cols, track))
        track, cols_sorted = track[order], cols[order]
        first = np.ones(len(order), dtype=bool)
        first[1:] = (track[1:] != track[:-1]) | (cols_sorted[1:] != cols_sorted[:-1])
        keep = order[first]
        chosen_models = (rows[keep] % per_row).astype(np.int64)
        distance = found.distance[keep]
        if imm_distance == "gated_combined":
            distance = _combined_distance(
                prediction,
                measurements,
                measurement_covariances,
                noise,
                track[first],
                cols_sorted[first],
                modified,
                gate,
            )
        reduced = CandidatePairs(
            track[first].astype(np.int64),
            cols_sorted[first].astype(np.int64),
            distance,
            found.log_det[keep],
            tracks,
            len(measurements),
            q,
            plain[keep],
        )
        return GatedPairs(reduced, chosen_models)
    chosen = np.zeros(len(rows), dtype=np.int64) if per_row > 1 else np.full(len(rows), -1)
    reduced = CandidatePairs(
        rows // per_row, cols, found.distance, found.log_det, tracks, len(measurements), q, plain
    )
    return GatedPairs(reduced, chosen.astype(np.int64))


RANK_CAP = 1.0 - 1e-6
"""``"gated_combined"``: a gated pair's combined distance is at most this share of the gate."""


def _combined_distance(
    prediction: IMMPrediction,
    measurements: FloatArray,
    measurement_covariances: FloatArray | None,
    noise: FloatArray,
    tracks: IntArray,
    cols: IntArray,
    modified: ModifiedScale | None,
    gate: float,
) -> FloatArray:
    """The model-combined D of the pairs (``tracks``, ``cols``) that the closest model gated,
    capped at :data:`RANK_CAP` × gate: the closest model decides that a pair is possible
    (a manoeuvre the bank contains stays in the gate), the combined ẑ, S rank the possible
    pairs (a neighbour that one unlikely model predicts ranks far behind the target's own
    detection)."""
    centres, spreads = prediction.combined_measurement()
    known = spreads if measurement_covariances is None else spreads - noise
    covariances = known[tracks]
    if measurement_covariances is not None:
        covariances = covariances + measurement_covariances[cols]
    innovations = measurements[cols] - centres[tracks]
    solved = np.linalg.solve(covariances, innovations[..., None])[..., 0]
    distance = np.einsum("pi,pi->p", innovations, solved)
    if modified is not None:
        distance = distance * modified.ratio(known)[tracks]
    return np.asarray(np.minimum(distance, RANK_CAP * gate), dtype=np.float64)


@dataclass(frozen=True, eq=False)
class ScanGating:
    """One scan's gating of the candidate tracks with the detections, shared by the
    assignment passes of the scan (module docstring).

    Each gate a method asks for is computed once, over every track × every detection
    (:func:`gate_pairs`); a pass reads the part of its tracks and detections
    (:meth:`GatedPairs.restricted`). ``combined`` is the model-combined ẑ, S of every
    track ([MTT] §4).
    """

    prediction: IMMPrediction
    measurements: FloatArray
    measurement_covariances: FloatArray | None
    noise: FloatArray
    imm_distance: ImmDistance
    modified: ModifiedScale | None
    floors: FloatArray | None = None
    combined: tuple[FloatArray, FloatArray] = field(init=False)
    _gated: dict[float, GatedPairs] = field(default_factory=dict, init=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "combined", self.prediction.combined_measurement())

    def pairs(self, gate: float, tracks: IntArray, detections: IntArray) -> GatedPairs:
        """The pairs of ``tracks`` × ``detections`` (ascending) with D ≤ gate."""
        found = self._gated.get(gate)
        if found is None:
            found = gate_pairs(
                self.prediction,
                self.measurements,
                self.measurement_covariances,
                self.noise,
                gate,
                self.imm_distance,
                self.modified,
                self.floors,
            )
            self._gated[gate] = found
        return found.restricted(tracks, detections)


@dataclass(frozen=True, eq=False)
class TrackGatingProblem(AssociationProblem):
    """An association problem of some ``tracks`` × ``detections`` of a :class:`ScanGating`.

    ``known`` holds the model-combined ẑ, S of each of the tracks (for the methods
    that only need sizes); :meth:`pairs` reads the scan's gating (its pairs carry
    the plain D the track score uses; a method's result returns the pairs it used).
    """

    gating: ScanGating | None = None
    tracks: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    detections: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    @classmethod
    def of(cls, gating: ScanGating, tracks: IntArray, detections: IntArray) -> TrackGatingProblem:
        """The problem of ``tracks`` × ``detections`` (ascending indices) of ``gating``."""
        own_noise = gating.measurement_covariances
        centres, spreads = gating.combined
        return cls(
            known=Estimates(centres[tracks], spreads[tracks], "tracks"),
            incoming=Estimates(
                gating.measurements[detections],
                None if own_noise is None else own_noise[detections],
                "detections",
            ),
            distance=DistanceModel(covariance="innovation" if own_noise is None else "sum"),
            gating=gating,
            tracks=tracks,
            detections=detections,
        )

    def pairs(self, gate: float) -> CandidatePairs:
        """Candidate pairs with D ≤ gate (closest model or combined)."""
        assert self.gating is not None
        return self.gating.pairs(gate, self.tracks, self.detections).pairs

    def smallest_log_det(self) -> float:
        """A lower bound of log|C| over every model row."""
        assert self.gating is not None
        if self.n_known == 0:
            return -np.inf
        spreads = self.gating.prediction.innovation_covariances[self.tracks]
        if self.gating.measurement_covariances is not None:
            spreads = spreads - self.gating.noise  # |H P Hᵀ + R_i| ≥ |H P Hᵀ|
        return float(np.linalg.slogdet(spreads)[1].min())
