"""The cheap JPDA baseline of [DH] §2 (Fitzgerald), as an IMM update (docs/algorithms.md §3.5).

Soft association weights ([DH] eq 16)::

    β_tj = G_tj / (S_t + S_j − G_tj + B),   S_t = Σ_j G_tj,   S_j = Σ_t G_tj,

with G_tj the Gaussian likelihood of detection j for track t inside the gate
(0 outside) and B the bias (clutter density term, option ``bias``, ≥ 0); the weights
and the method's spec are :mod:`core.association.cheap_jpda`'s.
The probability that none of the detections is the track's is
``β_t0 = 1 − Σ_j β_tj`` (clipped at 0).

**Clutter term.** [DH] leaves B open. By default it is the PDA's
(:func:`clutter_bias`): ``B = λ (1 − P_D P_G) / P_D`` with λ the sensor's
clutter density (false detections per unit of measurement space per scan,
the life cycle's β_FT), P_D its detection probability and P_G the gate
probability. With one track (S_j = G_tj) the weights are then exactly the
PDA's ``β_j = L_j / (1 − P_D P_G + Σ_l L_l)``, ``L_j = P_D G_j / λ``
(Bar-Shalom & Tse 1975; Stone Soup's ``PDAHypothesiser``): a track
surrounded by clutter trusts each detection less, and a missed detection
keeps the weight ``1 − P_D P_G`` it has in the PDA.

Each model m of the track is updated with the combined innovation
([DH] eq 5–11, the PDA update)::

    ν_m = Σ_j β_tj ν_jm,  ν_jm = z_j − ẑ_m,  K_m = P_m Hᵀ S_m⁻¹
    x_m ← x_m + K_m ν_m
    P_m ← β_t0 P_m + (1 − β_t0)(I − K_m H) P_m + K_m (Σ_j β_tj ν_jm ν_jmᵀ − ν_m ν_mᵀ) K_mᵀ

**Reading (IMM).** [DH] uses one Kalman filter per track. With an IMM the
weights are computed once per track (G from the distance the tracker gates
with: closest model or combined, :mod:`core.tracking.gating`) and shared by
the models; the mode likelihood is the β-weighted mixture of the model's
likelihoods of the gated detections,
``Λ_m = Σ_j β_tj N(ν_jm; 0, S_m) / Σ_j β_tj`` (log domain). A track with no
gated detection coasts.
"""

from __future__ import annotations

import math

import numpy as np

from core.arrays import FloatArray, IntArray
from core.errors import TrackingError
from core.numerics import safe_log
from core.tracking.imm import IMMPrediction, IMMState, IMMUpdate, posterior_log_modes
from core.tracking.models import ModelBank

_LOG_2PI = math.log(2.0 * math.pi)


def clutter_bias(clutter_density: float, p_detect: float, gate_probability: float) -> float:
    """B = λ (1 − P_D P_G) / P_D: the PDA's clutter term in [DH] eq 16 (module docstring)."""
    for name, value in (("p_detect", p_detect), ("gate_probability", gate_probability)):
        if not (math.isfinite(value) and 0.0 < value < 1.0):
            raise TrackingError(f"{name} must be in (0, 1), got {value!r}")
    if not (math.isfinite(clutter_density) and clutter_density > 0.0):
        raise TrackingError(f"clutter_density must be positive, got {clutter_density!r}")
    return clutter_density * (1.0 - p_detect * gate_probability) / p_detect


def pda_update(
    bank: ModelBank,
    prediction: IMMPrediction,
    measurements: FloatArray,
    rows: IntArray,
    cols: IntArray,
    weights: FloatArray,
) -> IMMUpdate:
    """PDA update of every model of T tracks with sparse weights (module docstring).

    Parameters
    ----------
    bank : ModelBank
    prediction : IMMPrediction of T tracks
    measurements : ndarray, shape (m, q)
    rows, cols : ndarray of int64, shape (P,)
        Track and detection of each weighted pair.
    weights : ndarray, shape (P,)
        β_tj of each pair (> 0).
    """
    tracks, models = prediction.log_mode_probabilities.shape
    q = bank.measurement.dim
    h = bank.measurement.matrix
    weight_total = np.bincount(rows, weights=weights, minlength=tracks)
    hit = weight_total > 0.0
    missed = np.clip(1.0 - weight_total, 0.0, 1.0)

    s = prediction.innovation_covariances  # (T, r, q, q)
    s_inv = np.linalg.inv(s)
    gain = prediction.covariances @ h.T @ s_inv  # (T, r, n, q)
    pair_innovations = (
        measurements[cols][:, None, :] - prediction.measurement_means[rows]
    )  # (P, r, q)
    weighted = weights[:, None, None] * pair_innovations
    combined = np.zeros((tracks, models, q))
    np.add.at(combined, rows, weighted)
    spread = np.zeros((tracks, models, q, q))
    np.add.at(spread, rows, weighted[..., :, None] * pair_innovations[..., None, :])
    spread -= combined[..., :, None] * combined[..., None, :]

    means = prediction.means + (gain @ combined[..., None])[..., 0]
    updated = prediction.covariances - gain @ s @ np.swapaxes(gain, -1, -2)
    beta0 = missed[:, None, None, None]
    covariances = (
        beta0 * prediction.covariances
        + (1.0 - beta0) * updated
        + gain @ spread @ np.swapaxes(gain, -1, -2)
    )
    covariances = 0.5 * (covariances + np.swapaxes(covariances, -1, -2))

    # Mode likelihoods: β-weighted mixture of N(ν_jm; 0, S_m), in the log domain.
    solved = np.einsum("prkl,prl->prk", s_inv[rows], pair_innovations)
    distances = np.sum(solved * pair_innovations, axis=-1)  # (P, r)
    _, log_det = np.linalg.slogdet(s)  # (T, r)
    pair_log = safe_log(weights)[:, None] - 0.5 * (distances + log_det[rows] + q * _LOG_2PI)
    peak = np.full((tracks, models), -np.inf)
    np.maximum.at(peak, rows, pair_log)
    finite_peak = np.where(np.isfinite(peak), peak, 0.0)
    total = np.zeros((tracks, models))
    np.add.at(total, rows, np.exp(pair_log - finite_peak[rows]))
    log_likelihoods = finite_peak + safe_log(total)
    log_likelihoods = np.where(
        hit[:, None], log_likelihoods - safe_log(np.where(hit, weight_total, 1.0))[:, None], np.nan
    )
    joint = prediction.log_mode_probabilities + np.where(hit[:, None], log_likelihoods, 0.0)
    log_mu = posterior_log_modes(prediction.log_mode_probabilities, joint, hit)
    means = np.where(hit[:, None, None], means, prediction.means)
    covariances = np.where(hit[:, None, None, None], covariances, prediction.covariances)
    return IMMUpdate(
        state=IMMState(means, covariances, log_mu),
        detected=hit,
        innovations=np.where(hit[:, None, None], combined, np.nan),
        innovation_covariances=s,
        log_likelihoods=log_likelihoods,
    )
