"""A radar's range-rate as a sequential extended Kalman update after the position update.

A polar sensor at site ``s`` that measures the range-rate ``ṙ`` of a
detection (its Doppler, m/s) sees, for the state ``[x, ẋ, y, ẏ(, z, ż)]``
with position ``p`` and velocity ``v``,

    h(x) = uᵀ v,   u = (p − s) / ρ,   ρ = |p − s|,

with the Jacobian ``∂h/∂p = (v − h u) / ρ``, ``∂h/∂v = u``
(:meth:`core.models.measurement.Polar.range_rate`). The position (the
converted measurement, :meth:`~core.models.measurement.Polar.converted`) and the range-rate have
independent noises, so the update of both is the position update
(:class:`~core.tracking.imm.IMMUpdater`) followed by this scalar EKF update,
linearised at the position-updated estimate of every model of every track:
``S = H P Hᵀ + σ²``, ``K = P Hᵀ / S``, ``x += K (ṙ − h(x))`` and Joseph's
``P = (I − K H) P (I − K H)ᵀ + σ² K Kᵀ``. The model likelihoods get the
range-rate factor ``N(ṙ; h(x_j), S_j)`` too, so the mode probabilities and
the credal classification see the Doppler; the track score (gating and
ΔL) stays on the position: a clutter density in range-rate space is not part
of the SPRT of [MTT] §4.3.

The range-rate's line of sight is a direction in the tracker's frame; in a
planar session it is the horizontal one (the radar's slant range-rate is taken
for the horizontal one, as its range is). Tracks whose position is at the site
(ρ below a millimetre) are not updated by it. A track's start (two-point or
single-point) takes no range-rate: it enters from the track's first update.
"""

from __future__ import annotations

import math

import numpy as np

from core.arrays import FloatArray, IntArray
from core.errors import TrackingError
from core.models.measurement import Polar
from core.numerics import logsumexp
from core.tracking.imm import IMMState, IMMUpdate
from core.tracking.models import position_indices, velocity_indices
from core.tracking.presets import TrackingPreset

MIN_RANGE = 1e-3
"""Smallest distance from the site (m) at which a track's range-rate is updated."""

_LOG_2PI = math.log(2.0 * math.pi)


def require_velocities(preset: TrackingPreset | None) -> None:
    """A range-rate updates the velocity along the line of sight: the state needs velocities,
    not a preset's headings ([MTT] eq 26). The one check, for a session's sensor when it is
    configured and for a scan's range-rates at the tracker (None: an explicit bank, velocities)."""
    if preset is not None and preset.headings:
        raise TrackingError(
            f"a range-rate needs velocities in the state, not the headings of the {preset.name!r} "
            "preset"
        )


def range_rate_update(
    update: IMMUpdate,
    rows: IntArray,
    range_rates: FloatArray,
    model: Polar,
    axes: int,
) -> IMMUpdate:
    """``update`` with the range-rates ``range_rates`` (k,) of its tracks ``rows`` (k,) applied.

    Every model of each of those tracks is updated (module docstring); the
    other tracks are unchanged. ``axes`` is the number of position axes of
    the ``[x, ẋ, …]`` state.
    """
    layout = (tuple(position_indices(axes)), tuple(velocity_indices(axes)))
    if (model.mapping, model.velocity_mapping) != layout:
        raise TrackingError(f"the range-rate model needs the [x, ẋ, …] state of {axes} axes")
    state = update.state
    means, covariances = state.means[rows], state.covariances[rows]  # (k, r, n), (k, r, n, n)
    distance, predicted, jacobian = model.range_rate(means)  # (k, r), (k, r), (k, r, n)
    usable = distance >= MIN_RANGE
    jacobian = np.where(usable[..., None], jacobian, 0.0)
    p_ht = np.einsum("krij,krj->kri", covariances, jacobian)
    variance = model.noise_covar[-1, -1]
    innovation_variance = np.einsum("kri,kri->kr", jacobian, p_ht) + variance
    gain = p_ht / innovation_variance[..., None]
    innovation = np.where(usable, np.asarray(range_rates)[:, None] - predicted, 0.0)
    new_means = means + gain * innovation[..., None]
    identity = np.eye(means.shape[-1])
    i_kh = identity - gain[..., :, None] * jacobian[..., None, :]
    new_covariances = i_kh @ covariances @ np.swapaxes(i_kh, -1, -2) + variance * (
        gain[..., :, None] * gain[..., None, :]
    )
    new_covariances = 0.5 * (new_covariances + np.swapaxes(new_covariances, -1, -2))
    log_likelihood = np.where(
        usable,
        -0.5 * (innovation**2 / innovation_variance + np.log(innovation_variance) + _LOG_2PI),
        0.0,
    )
    log_mu = state.log_mode_probabilities[rows] + log_likelihood
    log_mu = log_mu - logsumexp(log_mu, axis=1)[:, None]

    all_means, all_covariances = state.means.copy(), state.covariances.copy()
    all_log_mu, all_log_likelihoods = (
        state.log_mode_probabilities.copy(),
        update.log_likelihoods.copy(),
    )
    all_means[rows], all_covariances[rows], all_log_mu[rows] = new_means, new_covariances, log_mu
    all_log_likelihoods[rows] = update.log_likelihoods[rows] + log_likelihood
    return IMMUpdate(
        state=IMMState(all_means, all_covariances, all_log_mu),
        detected=update.detected,
        innovations=update.innovations,
        innovation_covariances=update.innovation_covariances,
        log_likelihoods=all_log_likelihoods,
    )
