"""Fusion of several sensors' estimates of one object (docs/algorithms.md §6 step 4).

Each fused track keeps the latest estimate of every sensor that reports it;
its state is the fusion of those estimates (already predicted to a common
time). Three rules, named as in the API (``state_fusion``):

- ``covariance_intersection`` (default): ``P⁻¹ = Σ ω_i P_i⁻¹``,
  ``P⁻¹x = Σ ω_i P_i⁻¹ x_i``, Σ ω = 1, consistent whatever the
  cross-correlation of the errors (Julier & Uhlmann). The weights minimise
  tr P: exactly for two estimates (see :func:`optimal_ci_weight`), by the
  fast CI of Niehsen (2002), ω_i ∝ 1 / tr P_i, for three or more.
- ``independent``: the information sum (ω_i = 1); optimal for independent
  errors, overconfident when they correlate.
- ``latest``: the most recent estimate, unchanged (between estimates of one
  time, the sensor listed first in the session config: its slot in the engine).

Everything is batched over fused tracks: ``states`` (T, S, d),
``covariances`` (T, S, d, d) and a ``present`` mask (T, S) saying which
sensor slots hold an estimate.
"""

from __future__ import annotations

import enum

import numpy as np

from core.arrays import BoolArray, FloatArray
from core.errors import InvalidInput


class StateFusion(enum.StrEnum):
    """The state-fusion rules, by their API names."""

    COVARIANCE_INTERSECTION = "covariance_intersection"
    INDEPENDENT = "independent"
    LATEST = "latest"


_BISECTION_STEPS = 60  # 2⁻⁶⁰ < 1e-18: ω to machine precision


def optimal_ci_weight(first: FloatArray, second: FloatArray) -> FloatArray:
    """Trace-minimising covariance-intersection weight ω on the first of two estimates.

    With ``A = P₁⁻¹`` and ``B = P₂⁻¹ = L Lᵀ``, diagonalise ``L⁻¹ A L⁻ᵀ = U Λ Uᵀ``
    and let ``W = L⁻ᵀ U``. Then ``(ωA + (1−ω)B)⁻¹ = W diag(1 / (1 + ω(λ_i − 1))) Wᵀ``
    and ``tr P(ω) = Σ_i c_i / (1 + ω(λ_i − 1))`` with ``c_i = ‖W e_i‖²``: a convex
    scalar function whose derivative is found by bisection to machine precision
    for every track at once.

    Parameters
    ----------
    first, second : ndarray, shape (T, d, d)
        Covariances P₁, P₂ (symmetric positive definite).

    Returns
    -------
    ndarray, shape (T,)
        ω ∈ [0, 1] per track.
    """
    # B = P₂⁻¹ = L Lᵀ with L = M⁻ᵀ where P₂ = M Mᵀ: then L⁻¹ A L⁻ᵀ = Mᵀ P₁⁻¹ M and
    # W = M U. No inverse of P₂ is formed (the Cholesky factor of an explicit
    # inverse of an ill-conditioned P₂ failed: a 500 in issue 14).
    factor = np.linalg.cholesky((second + np.swapaxes(second, -1, -2)) / 2.0)
    whitened = np.swapaxes(factor, -1, -2) @ np.linalg.solve(first, factor)
    whitened = (whitened + np.swapaxes(whitened, -1, -2)) / 2.0
    eigenvalues, eigenvectors = np.linalg.eigh(whitened)
    basis = factor @ eigenvectors
    weights_c = np.sum(basis**2, axis=-2)  # c_i, shape (T, d)
    slope = eigenvalues - 1.0

    def derivative(omega: FloatArray) -> FloatArray:
        # d/dω tr P(ω) = −Σ c_i (λ_i − 1) / (1 + ω(λ_i − 1))², increasing in ω.
        denominator = 1.0 + omega[:, None] * slope
        return np.asarray(-np.sum(weights_c * slope / denominator**2, axis=-1), dtype=np.float64)

    low = np.zeros(len(first))
    high = np.ones(len(first))
    at_low, at_high = derivative(low), derivative(high)
    for _ in range(_BISECTION_STEPS):
        middle = (low + high) / 2.0
        rising = derivative(middle) > 0.0
        high = np.where(rising, middle, high)
        low = np.where(rising, low, middle)
    omega = (low + high) / 2.0
    # Boundary minima; where tr P(ω) is flat (P₁ = P₂) every ω is optimal: take ½.
    scale = np.sum(weights_c, axis=-1) * (1.0 + np.max(np.abs(slope), axis=-1)) * 1e-12
    flat = (np.abs(at_low) <= scale) & (np.abs(at_high) <= scale)
    omega = np.where(at_low > scale, 0.0, omega)
    omega = np.where(at_high < -scale, 1.0, omega)
    return np.asarray(np.where(flat, 0.5, omega), dtype=np.float64)


def fast_ci_weights(covariances: FloatArray, present: BoolArray) -> FloatArray:
    """Niehsen's fast CI weights ω_i ∝ 1 / tr P_i over the present estimates; shape (T, S)."""
    traces = np.trace(covariances, axis1=-2, axis2=-1)
    inverse_trace = np.where(present, 1.0 / np.where(present, traces, 1.0), 0.0)
    return np.asarray(inverse_trace / inverse_trace.sum(axis=1, keepdims=True), dtype=np.float64)


def fuse_information(
    states: FloatArray, information: FloatArray, weights: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """x, P from P⁻¹ = Σ ω_i P_i⁻¹ and P⁻¹ x = Σ ω_i P_i⁻¹ x_i, given the P_i⁻¹.

    ``information`` (T, S, d, d) holds P_i⁻¹ where ω_i > 0; what it holds
    elsewhere is ignored. One weighted sum per track, in slot order: a track's
    result does not depend on the other tracks of the batch.
    """
    weighted = np.where(weights[..., None, None] > 0.0, information, 0.0)
    weighted *= weights[..., None, None]
    information_state = (weighted @ states[..., None]).sum(axis=1)[..., 0]
    covariance = np.linalg.inv(weighted.sum(axis=1))
    covariance = (covariance + np.swapaxes(covariance, -1, -2)) / 2.0
    return (covariance @ information_state[..., None])[..., 0], covariance


def _information_sum(
    states: FloatArray, covariances: FloatArray, weights: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """x, P from P⁻¹ = Σ ω_i P_i⁻¹ and P⁻¹ x = Σ ω_i P_i⁻¹ x_i (absent slots have ω = 0).

    A track with a single weighted estimate (ω = 1 by every rule) keeps it as
    it is: no inverse is taken of it.
    """
    weighted = weights > 0.0
    single = weighted.sum(axis=1) == 1
    slot = np.argmax(weighted, axis=1)
    rows = np.arange(len(states))
    state = np.array(states[rows, slot])
    covariance = np.array(covariances[rows, slot])
    several = np.flatnonzero(~single)
    if len(several):
        dim = states.shape[-1]
        chosen = weights[several]
        safe = np.where(chosen[..., None, None] > 0.0, covariances[several], np.eye(dim))
        information = np.linalg.inv(safe)  # per matrix: the same bits whatever the batch
        state[several], covariance[several] = fuse_information(states[several], information, chosen)
    return state, covariance


def fusion_weights(
    covariances: FloatArray,
    present: BoolArray,
    times: FloatArray,
    rule: StateFusion | str = StateFusion.COVARIANCE_INTERSECTION,
) -> FloatArray:
    """The weight ω_i of every sensor slot's estimate, (T, S); 0 where absent.

    ``latest``: 1 on the most recent estimate (ties: the lowest slot);
    ``independent``: 1 on every estimate; ``covariance_intersection``: the
    exact trace-minimising ω for two estimates, Niehsen's for more.
    """
    rule = StateFusion(rule)
    if rule is StateFusion.LATEST:
        chosen = np.argmax(np.where(present, times, -np.inf), axis=1)
        weights = np.zeros(present.shape)
        weights[np.arange(len(present)), chosen] = 1.0
        return weights
    if rule is StateFusion.INDEPENDENT:
        return present.astype(np.float64)
    weights = fast_ci_weights(covariances, present)
    pairs = np.flatnonzero(present.sum(axis=1) == 2)
    if len(pairs):
        slots = np.argsort(~present[pairs], axis=1, kind="stable")[:, :2]
        omega = optimal_ci_weight(covariances[pairs, slots[:, 0]], covariances[pairs, slots[:, 1]])
        weights[pairs] = 0.0
        weights[pairs[:, None], slots] = np.stack([omega, 1.0 - omega], axis=1)
    return weights


def fuse_estimates(
    states: FloatArray,
    covariances: FloatArray,
    present: BoolArray,
    times: FloatArray,
    rule: StateFusion | str = StateFusion.COVARIANCE_INTERSECTION,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Fuse the sensors' estimates of every track.

    Parameters
    ----------
    states : (T, S, d)
    covariances : (T, S, d, d)
    present : (T, S) bool; every track needs at least one estimate.
    times : (T, S) report time of each estimate (``latest`` picks the largest;
        ties go to the lowest sensor slot, so the result is deterministic).
    rule : a :class:`StateFusion` or its name.

    Returns
    -------
    state : (T, d)
    covariance : (T, d, d)
    weights : (T, S) the weight of each sensor's estimate (0 where absent).
    """
    rule = StateFusion(rule)
    if states.ndim != 3 or covariances.shape != (*states.shape, states.shape[-1]):
        raise InvalidInput(
            f"states (T, S, d) and covariances (T, S, d, d) disagree: {states.shape}, {covariances.shape}"
        )
    if present.shape != states.shape[:2] or times.shape != states.shape[:2]:
        raise InvalidInput("present and times must have shape (T, S)")
    if len(states) and not present.any(axis=1).all():
        raise InvalidInput("every fused track needs at least one sensor estimate")
    weights = fusion_weights(covariances, present, times, rule)
    state, covariance = _information_sum(states, covariances, weights)
    return state, covariance, weights
