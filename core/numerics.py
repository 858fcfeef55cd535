"""Small numerical helpers shared by the core modules (log-domain arithmetic)."""

from __future__ import annotations

import numpy as np

from core.arrays import FloatArray


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
