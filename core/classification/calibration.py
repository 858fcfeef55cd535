"""Model likelihoods calibrated to the sensor's noise, for the kinematic classification (§8.5).

[MTT]'s behaviour evidence is the IMM's mode likelihoods Λ_j of each step
(eq 18, 22). Where the sensor resolves the models' predictions (the papers'
0.2 m² noise, 1 s scans: a 2g model predicts 10 m away, 20 σ), a model that
fits better is a manoeuvre. Where it does not (a radar at 50–100 km, 4–12 s
revisits: cross-range σ of 100–350 m, a 2g model 150 m away), the ratios Λ_j / Λ_ref
swing by noise alone, and since every step's mass is combined conjunctively
and nothing can support the straight-flying behaviour's classes alone
(Γ(b1) is every class), that noise piles up as evidence of manoeuvres: an
airliner ends up "fighter".

**Reading (noise calibration).** Per track and step, let b be the model that
fits the detection best (largest Λ). Were model j the true one, its innovation
would be ν_j ~ N(0, S_j) and the advantage of b over it

    ln(Λ_b / Λ_j)  ~  N(−d_j²/2, d_j²),   d_j² = δ_jᵀ S_j⁻¹ δ_j,   δ_j = ẑ_b − ẑ_j = ν_j − ν_b,

d_j being the *separability* of the two models at this sensor's noise and
revisit (S_j holds the detection's own R, δ_j the predictions over the
actual Δt). The part of that advantage that noise alone gives with
probability Φ(−κ) or more, ``τ_j = max(0, κ d_j − d_j²/2)``, is not evidence
against j:

    ln Λ'_j = ln Λ_b − max(0, ln(Λ_b/Λ_j) − τ_j).

Models the sensor cannot tell from the best one are then exactly as plausible
as it (their behaviours' plausibilities tie, the step's mass is vacuous); a
model that falls behind by more than noise explains keeps the excess; where
the models are resolved (d_j ≥ 2κ) τ_j = 0 and nothing changes: the papers'
scenes are as before. Under noise alone a step is vacuous but with
probability about Φ(−κ) per model, and a sustained manoeuvre shows as soon
as the models that ignore it fall out of the noise band. κ = :data:`SIGNIFICANCE`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from scipy.stats import chi2, norm

from core.arrays import BoolArray, FloatArray, IntArray

SIGNIFICANCE = 4.5
"""κ: a likelihood ratio counts as evidence beyond what noise gives with probability
Φ(−4.5) ≈ 3.4e-6 per model and step."""
SHARPNESS = 2.0
"""A step is evidence only where the best model's predicted position is at most this many
times as uncertain as the detection, per axis (:func:`sharp_predictions`)."""


def noise_calibrated_log_likelihoods(
    log_likelihoods: FloatArray,
    innovations: FloatArray,
    innovation_covariances: FloatArray,
    significance: float = SIGNIFICANCE,
) -> FloatArray:
    """ln Λ'_j of T tracks (module Reading), shape (T, r).

    Parameters
    ----------
    log_likelihoods : (T, r) ln Λ_j of the step (NaN on rows without a detection:
        returned as they are).
    innovations : (T, r, q) ν_j = z − ẑ_j.
    innovation_covariances : (T, r, q, q) S_j (with the detection's own R).
    significance : κ.
    """
    log_lambda = np.asarray(log_likelihoods, dtype=np.float64)
    out = log_lambda.copy()
    rows = np.flatnonzero(np.all(np.isfinite(log_lambda), axis=1))
    if len(rows) == 0:
        return out
    nu = np.asarray(innovations, dtype=np.float64)[rows]
    s = np.asarray(innovation_covariances, dtype=np.float64)[rows]
    own = log_lambda[rows]
    best = np.argmax(own, axis=1)
    at = np.arange(len(rows))
    delta = nu - nu[at, best][:, None, :]  # ẑ_b − ẑ_j, (R, r, q)
    solved = np.linalg.solve(s, delta[..., None])[..., 0]
    separability = np.sqrt(np.maximum(np.sum(delta * solved, axis=-1), 0.0))  # d_j
    tolerance = np.maximum(0.0, significance * separability - 0.5 * separability**2)
    top = own[at, best][:, None]
    out[rows] = top - np.maximum(0.0, (top - own) - tolerance)
    return out


def sharp_predictions(
    log_likelihoods: FloatArray,
    innovation_covariances: FloatArray,
    predicted_covariances: FloatArray,
    sharpness: float = SHARPNESS,
) -> np.ndarray:
    """Rows whose best-fitting model predicted the detection at most ``sharpness`` times as
    uncertainly as the detection itself, per axis: ``(|H P_b Hᵀ| / |R|)^(1/2q) ≤ sharpness``
    with R = S_b − H P_b Hᵀ (the detection's own noise).

    **Reading.** A bank whose model-conditioned states have spread far beyond the
    detection's noise — a track after a gap, or mixing at a revisit many times the
    bank's nominal period, where each acceleration model is held for the whole
    interval — compares the models over its own spread, not over one manoeuvre: its
    likelihood ratios are no evidence about the behaviour (measured on the
    real-traffic scene's 12 s radar: CV innovations of 5–40 km σ on the steps that
    decided airliners "fighter"). Rows without a detection (NaN) are False.
    """
    log_lambda = np.asarray(log_likelihoods, dtype=np.float64)
    out = np.zeros(len(log_lambda), dtype=bool)
    rows = np.flatnonzero(np.all(np.isfinite(log_lambda), axis=1))
    if len(rows) == 0:
        return out
    best = np.argmax(log_lambda[rows], axis=1)
    at = np.arange(len(rows))
    predicted = np.asarray(predicted_covariances, dtype=np.float64)[rows][at, best]
    noise = np.asarray(innovation_covariances, dtype=np.float64)[rows][at, best] - predicted
    q = predicted.shape[-1]
    _, log_predicted = np.linalg.slogdet(predicted)
    sign, log_noise = np.linalg.slogdet(noise)
    ratio = np.where(sign > 0, (log_predicted - log_noise) / (2 * q), np.inf)
    out[rows] = ratio <= np.log(sharpness)
    return out


def resolved_accelerations(
    times: FloatArray,
    positions: FloatArray,
    noises: FloatArray,
    significance: float = SIGNIFICANCE,
) -> BoolArray:
    """Rows whose last three detections show an acceleration beyond their noise.

    **Reading.** The model likelihoods compare predictions made from the
    track's state, and they are evidence of a manoeuvre only where that state
    is right. At a revisit of 12 s the papers' bank (held inputs of 2g and 4g,
    ``Q = 0.005 B Bᵀ``) can settle in a cycle that the likelihoods cannot see:
    a velocity wrong by ``e`` makes the model whose input ``u`` gives
    ``u Δt²/2 ≈ −e Δt`` fit best, which leaves the velocity wrong by ``−e``,
    the next step's opposite model fits, and so on, with the velocity's
    variance shrinking all the while (measured on the real-traffic scene's
    12 s radar: airliners flying straight, velocity errors of ±230 m/s per
    axis for minutes, the constant-velocity model at Mahalanobis distance
    250–1000 at every step). Such a cycle starts wherever the velocity is off
    by ``u Δt / 2``: a re-acquisition after a gap, a real turn. The
    detections themselves say whether the target accelerated, independently
    of the filter: over three detections at t₁ < t₂ < t₃ (Δ₁ = t₂ − t₁,
    Δ₂ = t₃ − t₂) the second divided difference

        â = 2 [(z₃ − z₂)/Δ₂ − (z₂ − z₁)/Δ₁] / (Δ₁ + Δ₂)

    is the acceleration of a target moving at constant acceleration, and zero
    in mean for one flying straight, with ``Cov(â) = Σ_k c_k² R_k``
    (c = 2/(Δ₁(Δ₁+Δ₂)), −2/(Δ₁Δ₂), 2/(Δ₂(Δ₁+Δ₂))). A step is evidence of a
    manoeuvre only where ``âᵀ Cov(â)⁻¹ â`` exceeds the χ²_q quantile that noise
    alone exceeds with probability Φ(−κ) (the significance of
    :func:`noise_calibrated_log_likelihoods`). The papers' 4g turn at 1 s and
    0.2 m² moves the third detection 20 m off a line whose noise is 1.1 m: it
    is resolved at its first step, as before.

    Parameters
    ----------
    times : (T, 3) detection times, oldest first (NaN: no such detection: False).
    positions : (T, 3, q) the detections.
    noises : (T, 3, q, q) their covariances R.
    significance : κ.
    """
    t = np.asarray(times, dtype=np.float64)
    z = np.asarray(positions, dtype=np.float64)
    r = np.asarray(noises, dtype=np.float64)
    out = np.zeros(len(t), dtype=bool)
    first, second = t[:, 1] - t[:, 0], t[:, 2] - t[:, 1]
    rows = np.flatnonzero(np.isfinite(first) & np.isfinite(second) & (first > 0) & (second > 0))
    if len(rows) == 0:
        return out
    d1, d2 = first[rows], second[rows]
    c = np.stack([2.0 / (d1 * (d1 + d2)), -2.0 / (d1 * d2), 2.0 / (d2 * (d1 + d2))], axis=1)
    acceleration = np.einsum("tk,tkq->tq", c, z[rows])
    covariance = np.einsum("tk,tkij->tij", c**2, r[rows])
    solved = np.linalg.solve(covariance, acceleration[..., None])[..., 0]
    statistic = np.sum(acceleration * solved, axis=-1)
    q = z.shape[-1]
    out[rows] = statistic > noise_quantile(significance, q)
    return out


@lru_cache(maxsize=16)
def noise_quantile(significance: float, q: int) -> float:
    """The χ²_q quantile that noise alone exceeds with probability Φ(−κ) (κ = ``significance``):
    a scipy call of ~0.2 ms, made once per (κ, q) rather than at every step."""
    return float(chi2.isf(norm.sf(significance), q))


@dataclass(frozen=True)
class RecentDetections:
    """The last two detections of T tracks (for :func:`resolved_accelerations`), oldest
    first; NaN times where a track has fewer. Never changed in place."""

    times: FloatArray
    """(T, 2)"""
    positions: FloatArray
    """(T, 2, q)"""
    noises: FloatArray
    """(T, 2, q, q)"""

    @classmethod
    def empty(cls, count: int, q: int) -> RecentDetections:
        return cls(np.full((count, 2), np.nan), np.zeros((count, 2, q)), np.zeros((count, 2, q, q)))

    @classmethod
    def first(cls, time: float, positions: FloatArray, noises: FloatArray) -> RecentDetections:
        """New tracks, each with one detection at ``time``."""
        count, q = positions.shape
        return cls.empty(count, q).pushed(np.arange(count), time, positions, noises)

    def __len__(self) -> int:
        return len(self.times)

    def select(self, rows: IntArray) -> RecentDetections:
        return RecentDetections(self.times[rows], self.positions[rows], self.noises[rows])

    def concatenate(self, other: RecentDetections) -> RecentDetections:
        return RecentDetections(
            np.concatenate([self.times, other.times]),
            np.concatenate([self.positions, other.positions]),
            np.concatenate([self.noises, other.noises]),
        )

    def replace(self, rows: IntArray, by: RecentDetections) -> RecentDetections:
        times, positions, noises = self.times.copy(), self.positions.copy(), self.noises.copy()
        times[rows], positions[rows], noises[rows] = by.times, by.positions, by.noises
        return RecentDetections(times, positions, noises)

    def with_detection(
        self, rows: IntArray, time: float, positions: FloatArray, noises: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The three detections of ``rows`` with the new ones: times (R, 3), positions
        (R, 3, q), noises (R, 3, q, q)."""
        return (
            np.concatenate([self.times[rows], np.full((len(rows), 1), time)], axis=1),
            np.concatenate([self.positions[rows], positions[:, None]], axis=1),
            np.concatenate([self.noises[rows], noises[:, None]], axis=1),
        )

    def pushed(
        self, rows: IntArray, time: float, positions: FloatArray, noises: FloatArray
    ) -> RecentDetections:
        """``rows`` detected at ``time``: their latest two detections move on."""
        times, z, r = self.with_detection(rows, time, positions, noises)
        return self.replace(rows, RecentDetections(times[:, 1:], z[:, 1:], r[:, 1:]))

    def latest_replaced(
        self, time: float, positions: FloatArray, noises: FloatArray
    ) -> RecentDetections:
        """These tracks with their latest detection replaced by these (a branch of a start
        that took another detection of the same scan)."""
        times, z, r = self.times.copy(), self.positions.copy(), self.noises.copy()
        times[:, 1], z[:, 1], r[:, 1] = time, positions, noises
        return RecentDetections(times, z, r)

    def to_plain(self, row: int) -> list[dict[str, Any]]:
        """One track's detections as plain data (oldest first; none for a NaN time)."""
        return [
            {
                "time": float(self.times[row, k]),
                "position": self.positions[row, k].tolist(),
                "noise": self.noises[row, k].tolist(),
            }
            for k in range(2)
            if np.isfinite(self.times[row, k])
        ]

    @classmethod
    def from_plain(cls, entries: list[list[dict[str, Any]]], q: int) -> RecentDetections:
        """:meth:`to_plain` of T tracks back (an entry of fewer than two keeps NaN ones first)."""
        out = cls.empty(len(entries), q)
        for row, detections in enumerate(entries):
            for item in detections[-2:]:
                out = out.pushed(
                    np.array([row]),
                    float(item["time"]),
                    np.array([item["position"]], dtype=np.float64).reshape(1, q),
                    np.array([item["noise"]], dtype=np.float64).reshape(1, q, q),
                )
        return out
