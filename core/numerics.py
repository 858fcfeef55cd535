"""Small numerical helpers shared by the core modules (log-domain arithmetic)."""

from __future__ import annotations

import numpy as np

from core.arrays import FloatArray
from core.errors import InvalidInput


def safe_log(values: FloatArray) -> FloatArray:
    """Natural log with log(0) = −inf and no warning."""
    with np.errstate(divide="ignore"):
        return np.asarray(np.log(values), dtype=np.float64)


def logsumexp(values: FloatArray, axis: int) -> FloatArray:
    """``log Σ exp(values)`` along ``axis``; −inf where every term is −inf."""
    peak = np.max(values, axis=axis, keepdims=True)
    finite_peak = np.where(np.isfinite(peak), peak, 0.0)
    with np.errstate(divide="ignore"):
        total = np.log(np.sum(np.exp(values - finite_peak), axis=axis, keepdims=True))
    return np.asarray(np.squeeze(total + finite_peak, axis=axis), dtype=np.float64)


MAX_MAGNITUDE = 1e12
"""Largest magnitude of a state component or a measurement the core accepts.

With times bounded by :data:`MAX_TIME` (so Δt ≤ 2e12 s) and covariances by
:data:`MAX_VARIANCE`, a constant-velocity prediction stays below ~1e49 plus
q·Δt³ (q the motion's noise density), and its squares, determinants and
inverses far from overflow: a state that entered a session can be predicted
and inverted, so an accepted input cannot make later inputs fail."""
MAX_VARIANCE = MAX_MAGNITUDE**2
"""Largest magnitude of a covariance entry (a standard deviation of ``MAX_MAGNITUDE``)."""
MIN_VARIANCE = 1e-12
"""Smallest variance (diagonal covariance entry) the core accepts: its inverse stays bounded."""
MAX_TIME = 1e12
"""Largest magnitude of a report time (s), about 31 700 years."""


def check_magnitudes(
    state: FloatArray,
    covariance: FloatArray,
    where: str,
    names: tuple[str, str] = ("state", "covariance"),
) -> None:
    """Refuse a state or covariance outside the documented bounds (names the field).

    Raises
    ------
    InvalidInput
        A component of ``{where}.state`` beyond :data:`MAX_MAGNITUDE`, an entry
        of ``{where}.covariance`` beyond :data:`MAX_VARIANCE`, or a variance
        below :data:`MIN_VARIANCE`.
    """
    state_name, covariance_name = names
    if state.size and float(np.max(np.abs(state))) > MAX_MAGNITUDE:
        component = int(np.argmax(np.abs(state)))
        raise InvalidInput(
            f"{where}.{state_name}[{component}]: magnitude {float(state.flat[component]):g} is beyond "
            f"the limit {MAX_MAGNITUDE:g}"
        )
    if covariance.size and float(np.max(np.abs(covariance))) > MAX_VARIANCE:
        raise InvalidInput(
            f"{where}.{covariance_name}: an entry of magnitude {float(np.max(np.abs(covariance))):g} "
            f"is beyond the limit {MAX_VARIANCE:g}"
        )
    if covariance.size and float(np.min(np.diagonal(covariance))) < MIN_VARIANCE:
        raise InvalidInput(
            f"{where}.{covariance_name}: a variance of {float(np.min(np.diagonal(covariance))):g} is "
            f"below the limit {MIN_VARIANCE:g}"
        )
