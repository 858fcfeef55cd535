"""Structural checks of vectors and matrices (no algorithms, only shape and validity).

The functions raise :class:`ValueError` with a message that names the problem;
pydantic turns it into a validation error located at the field being checked.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

SYMMETRY_TOLERANCE = 1e-9
"""Relative tolerance on ``|P - Pᵀ|`` (relative to the largest entry, at least 1)."""


def check_square(matrix: Sequence[Sequence[float]], size: int | None = None) -> int:
    """Check that ``matrix`` is square (and ``size`` × ``size`` if given); return its size."""
    rows = len(matrix)
    if rows == 0:
        raise ValueError("matrix is empty")
    for index, row in enumerate(matrix):
        if len(row) != rows:
            raise ValueError(
                f"matrix is not square: row {index} has {len(row)} entries, expected {rows}"
            )
    if size is not None and rows != size:
        raise ValueError(f"matrix is {rows}x{rows}, expected {size}x{size}")
    return rows


def check_covariance(matrix: Sequence[Sequence[float]], size: int | None = None) -> None:
    """Check that ``matrix`` is a square, symmetric, positive-definite covariance."""
    check_square(matrix, size)
    values = np.asarray(matrix, dtype=float)
    # ndarray methods, not np.max(...): the checks run once per track of every input
    scale = max(1.0, float(np.abs(values).max()))
    asymmetry = float(np.abs(values - values.T).max())
    if asymmetry > SYMMETRY_TOLERANCE * scale:
        raise ValueError(f"covariance is not symmetric (largest |P - Pᵀ| = {asymmetry:.3g})")
    try:
        np.linalg.cholesky(values)
    except np.linalg.LinAlgError:
        raise ValueError("covariance is not positive definite (Cholesky failed)") from None
