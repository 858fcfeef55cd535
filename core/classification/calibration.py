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

import numpy as np

from core.arrays import FloatArray

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
