"""The modified Mahalanobis distance of [HZ] §4.1, against observation stealing.

A track whose covariance has grown (lost lock) has a large gate and small
Mahalanobis distances to everything: it "steals" observations from
well-localised tracks ([HZ] §3.1, Fig 1). The modified distance stays close to
the Mahalanobis distance while the covariance is near its steady state and
tends to a scaled Euclidean distance as it grows.

**Reading** (docs/algorithms.md §2; [HZ] writes the relation with raw
determinants, ``x = k (y / (β|P_ss|))^α + y / |P_ss|``, whose units do not
match): the size of a covariance S relative to its steady state S_ss is

    u = (|S| / |S_ss|)^(1/q),

the scale v solves ``u = k (v/β)^α + v`` (increasing in v, one root in
(0, u]) and ``D_mod = D · u / v``. Defaults β = 10, k = 1, α = 4. For u ≈ 1,
v ≈ u and D_mod ≈ D; for large u, v ≈ β (u/k)^(1/α) grows far slower than u.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from core.arrays import FloatArray
from core.distance.estimates import check_covariances
from core.errors import InvalidInput

BISECTION_STEPS = 80
"""Bisection halvings of the bracket (0, v_max]: far below float resolution."""


@dataclass(frozen=True, eq=False)
class ModifiedScale:
    """Parameters of the modified distance ([HZ] §4.1).

    Attributes
    ----------
    steady_state : ndarray, shape (q, q) or (N_known, q, q)
        S_ss: the steady-state covariance of each known item (one shared
        matrix, or one per item), of the same kind as the known covariances
        (innovation covariance for measurement-to-track, state covariance for
        track-to-track). :func:`core.distance.steady_state_covariance` computes
        it from a filter model.
    beta, k, alpha : float
        β, k, α of the scale relation; all > 0.
    """

    steady_state: FloatArray
    beta: float = 10.0
    k: float = 1.0
    alpha: float = 4.0

    @classmethod
    def of(
        cls, steady_state: ArrayLike, *, beta: float = 10.0, k: float = 1.0, alpha: float = 4.0
    ) -> ModifiedScale:
        """Validated construction (S_ss symmetric positive definite, parameters > 0)."""
        matrices = np.asarray(steady_state, dtype=np.float64)
        if matrices.ndim == 2:
            matrices = matrices[None]
        if matrices.ndim != 3 or matrices.shape[1] != matrices.shape[2]:
            raise InvalidInput(
                f"modified distance: steady_state must be q × q or N × q × q, got {matrices.shape}"
            )
        check_covariances(matrices, "steady_state")
        for value, option in ((beta, "beta"), (k, "k"), (alpha, "alpha")):
            if not (np.isfinite(value) and value > 0):
                raise InvalidInput(
                    f"modified distance: {option} must be finite and > 0, got {value!r}"
                )
        return cls(matrices, float(beta), float(k), float(alpha))

    def ratio(self, known_covariances: FloatArray) -> FloatArray:
        """u/v for every known item: the factor that multiplies its distances."""
        n, q, _ = known_covariances.shape
        if self.steady_state.shape[1:] != (q, q) or self.steady_state.shape[0] not in (1, n):
            raise InvalidInput(
                f"modified distance: steady_state has shape {self.steady_state.shape}, "
                f"expected ({q}, {q}) or ({n}, {q}, {q})"
            )
        u = size_ratio(known_covariances, self.steady_state)
        return u / scale_factor(u, beta=self.beta, k=self.k, alpha=self.alpha)


def size_ratio(covariances: FloatArray, steady_state: FloatArray) -> FloatArray:
    """u = (|S| / |S_ss|)^(1/q) per matrix, from log-determinants (no overflow)."""
    q = covariances.shape[-1]
    _, log_det = np.linalg.slogdet(covariances)
    _, log_det_ss = np.linalg.slogdet(steady_state)
    return np.asarray(np.exp((log_det - log_det_ss) / q), dtype=np.float64)


def scale_factor(
    ratio: FloatArray, *, beta: float = 10.0, k: float = 1.0, alpha: float = 4.0
) -> FloatArray:
    """Solve ``u = k (v/β)^α + v`` for v ≥ 0, elementwise (bisection, vectorised).

    The left side is increasing in v, negative at 0 and ≥ 0 at
    ``min(u, β (u/k)^(1/α))``, so that bracket holds the only root.
    """
    u = np.asarray(ratio, dtype=np.float64)
    low = np.zeros_like(u)
    high = np.minimum(u, beta * (u / k) ** (1.0 / alpha))
    for _ in range(BISECTION_STEPS):
        middle = 0.5 * (low + high)
        above = k * (middle / beta) ** alpha + middle >= u
        high = np.where(above, middle, high)
        low = np.where(above, low, middle)
    return 0.5 * (low + high)


def modified_distance(
    distance: FloatArray,
    ratio: FloatArray,
    *,
    beta: float = 10.0,
    k: float = 1.0,
    alpha: float = 4.0,
) -> FloatArray:
    """``D_mod = D · u / v`` ([HZ] §4.1 with the Reading above), elementwise."""
    u = np.asarray(ratio, dtype=np.float64)
    return np.asarray(distance, dtype=np.float64) * u / scale_factor(u, beta=beta, k=k, alpha=alpha)
