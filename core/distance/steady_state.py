"""Steady-state covariances of a Kalman filter by iterating its Riccati equation.

The modified distance of [HZ] §4.1 compares a track's covariance with its
steady state, "for which no analytic solution is available in general": it
is the fixed point of the prediction/update recursion

    S = H P Hᵀ + R,   P⁺ = F (P − P Hᵀ S⁻¹ H P) Fᵀ + Q.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from core.arrays import FloatArray
from core.errors import InvalidInput


@dataclass(frozen=True, eq=False)
class SteadyState:
    """Steady state of a filter.

    Attributes
    ----------
    predicted : ndarray, shape (n, n)
        P_ss, the predicted state covariance at the fixed point.
    innovation : ndarray, shape (m, m)
        S_ss = H P_ss Hᵀ + R.
    iterations : int
    """

    predicted: FloatArray
    innovation: FloatArray
    iterations: int


def steady_state_covariance(
    transition: ArrayLike,
    process_noise: ArrayLike,
    observation: ArrayLike,
    measurement_noise: ArrayLike,
    *,
    tolerance: float = 1e-12,
    max_iterations: int = 100_000,
) -> SteadyState:
    """Iterate the Riccati equation from P = Q to its fixed point.

    Parameters
    ----------
    transition, process_noise : F and Q, shape (n, n)
    observation : H, shape (m, n)
    measurement_noise : R, shape (m, m)
    tolerance : float
        Stop when max |P⁺ − P| ≤ tolerance · max |P⁺|.

    Raises
    ------
    InvalidInput
        Shapes do not fit, or the iteration does not converge (an unstable
        mode that the sensor cannot observe has no steady state).
    """
    f, q, h, r = (
        np.asarray(x, dtype=np.float64)
        for x in (transition, process_noise, observation, measurement_noise)
    )
    n = f.shape[0]
    m = h.shape[0] if h.ndim == 2 else -1
    if f.shape != (n, n) or q.shape != (n, n) or h.shape != (m, n) or r.shape != (m, m):
        raise InvalidInput(
            f"steady state: shapes do not fit (F {f.shape}, Q {q.shape}, H {h.shape}, R {r.shape})"
        )
    if not all(np.isfinite(x).all() for x in (f, q, h, r)):
        raise InvalidInput("steady state: F, Q, H and R must be finite")
    predicted = q.copy()
    for iteration in range(1, max_iterations + 1):
        innovation = h @ predicted @ h.T + r
        gain = np.linalg.solve(innovation, h @ predicted).T  # P Hᵀ S⁻¹
        updated = predicted - gain @ h @ predicted
        following = f @ updated @ f.T + q
        following = 0.5 * (following + following.T)
        change = np.abs(following - predicted).max()
        predicted = following
        if change <= tolerance * np.abs(following).max():
            return SteadyState(predicted, h @ predicted @ h.T + r, iteration)
    raise InvalidInput(
        f"steady state: the Riccati iteration did not converge in {max_iterations} steps"
    )
