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
    states: FloatArray,
    covariances: FloatArray,
    where: str,
    names: tuple[str, str] = ("state", "covariance"),
) -> None:
    """Refuse states (n, d) or covariances (n, d, d) outside the documented bounds.

    Raises
    ------
    InvalidInput
        Naming the first offending field: a component of ``{where}[i].{state}``
        beyond :data:`MAX_MAGNITUDE`, an entry of ``{where}[i].{covariance}``
        beyond :data:`MAX_VARIANCE`, or a variance below :data:`MIN_VARIANCE`.
    """
    if len(states) == 0:
        return
    state_name, covariance_name = names
    largest = np.abs(states).max(axis=1)
    if largest.max() > MAX_MAGNITUDE:
        row = int(np.argmax(largest > MAX_MAGNITUDE))
        component = int(np.argmax(np.abs(states[row])))
        raise InvalidInput(
            f"{where}[{row}].{state_name}[{component}]: magnitude "
            f"{float(states[row, component]):g} is beyond the limit {MAX_MAGNITUDE:g}",
            loc=(where, row, state_name, component),
        )
    entries = np.abs(covariances).reshape(len(covariances), -1).max(axis=1)
    if entries.max() > MAX_VARIANCE:
        row = int(np.argmax(entries > MAX_VARIANCE))
        raise InvalidInput(
            f"{where}[{row}].{covariance_name}: an entry of magnitude {float(entries[row]):g} "
            f"is beyond the limit {MAX_VARIANCE:g}",
            loc=(where, row, covariance_name),
        )
    variances = np.diagonal(covariances, axis1=1, axis2=2).min(axis=1)
    if variances.min() < MIN_VARIANCE:
        row = int(np.argmax(variances < MIN_VARIANCE))
        raise InvalidInput(
            f"{where}[{row}].{covariance_name}: a variance of {float(variances[row]):g} is "
            f"below the limit {MIN_VARIANCE:g}",
            loc=(where, row, covariance_name),
        )
