"""Validated lists of estimates (states with covariances) or of measurements.

One side of an association problem: N state vectors of dimension q and,
for estimates, their N covariance matrices. Measurements (the incoming side
of measurement-to-track association) have no covariance of their own: the
innovation covariance S of the known side carries it ([MTT] eq 15).
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from core.arrays import FloatArray
from core.errors import CovarianceError, InvalidInput

SYMMETRY_TOLERANCE = 1e-9
"""Largest |P − Pᵀ| accepted, relative to the largest |P_ij| of the matrix."""

PIVOT_TOLERANCE = 1e-12
"""A Cholesky pivot at or below this fraction of the largest diagonal entry means singular."""


@dataclass(frozen=True, eq=False)
class Estimates:
    """N estimates of dimension q, validated.

    Build with :meth:`of` (validates); the constructor trusts its arguments.

    Attributes
    ----------
    states : ndarray, shape (N, q)
    covariances : ndarray, shape (N, q, q), or None for measurements
    name : str
        How error messages call this side ("known", "incoming").
    """

    states: FloatArray
    covariances: FloatArray | None
    name: str = "estimates"

    @classmethod
    def of(
        cls,
        states: ArrayLike,
        covariances: ArrayLike | None,
        *,
        name: str = "estimates",
        dimension: int | None = None,
    ) -> Estimates:
        """Validate and wrap states (N × q) and covariances (N × q × q, or None).

        Raises
        ------
        InvalidInput
            Wrong shapes, or a non-finite number (the message names the item).
        CovarianceError
            A covariance is not symmetric, or not positive definite (singular
            or with a negative eigenvalue); the message names the item.
        """
        state_array = np.asarray(states, dtype=np.float64)
        if state_array.ndim == 1 and state_array.size == 0:
            state_array = state_array.reshape(0, dimension or 0)
        if state_array.ndim != 2:
            raise InvalidInput(
                f"{name}: states must be a list of vectors (N × q), got shape {state_array.shape}"
            )
        n, q = state_array.shape
        if dimension is not None and q != dimension and n > 0:
            raise InvalidInput(f"{name}: states have dimension {q}, expected {dimension}")
        bad_rows = np.flatnonzero(~np.isfinite(state_array).all(axis=1))
        if len(bad_rows):
            raise InvalidInput(
                f"{name}[{int(bad_rows[0])}].state is not finite: {state_array[bad_rows[0]].tolist()}"
            )
        if covariances is None:
            return cls(state_array, None, name)
        covariance_array = np.asarray(covariances, dtype=np.float64)
        if n == 0 and covariance_array.size == 0:
            return cls(state_array, np.zeros((0, q, q)), name)
        if covariance_array.shape != (n, q, q):
            raise InvalidInput(
                f"{name}: covariances must have shape {(n, q, q)} to match the states, "
                f"got {covariance_array.shape}"
            )
        check_covariances(covariance_array, name)
        return cls(state_array, covariance_array, name)

    def __len__(self) -> int:
        return int(self.states.shape[0])

    @property
    def dimension(self) -> int:
        """q, the dimension of each state."""
        return int(self.states.shape[1])


def check_covariances(covariances: FloatArray, name: str) -> None:
    """Raise unless every matrix of the stack is finite, symmetric and positive definite.

    The error is located at the first refused matrix (``loc = (name, index,
    "covariance")``); the checks are those of :func:`covariance_problems`.
    """
    bad = np.flatnonzero(~np.isfinite(covariances).all(axis=(1, 2)))
    if len(bad):
        index = int(bad[0])
        raise InvalidInput(
            f"{name}[{index}].covariance is not finite", loc=(name, index, "covariance")
        )
    problems = covariance_problems(covariances)
    if problems:
        index, problem = next(iter(problems.items()))
        raise CovarianceError(f"{name}[{index}].{problem}", loc=(name, index, "covariance"))


def covariance_problems(covariances: FloatArray) -> dict[int, str]:
    """What is wrong with each matrix of a finite ``(k, n, n)`` stack that is not a covariance.

    The one covariance check of the project (the API's schema uses it too):
    symmetric within :data:`SYMMETRY_TOLERANCE` relative to the matrix's
    largest entry, and positive definite with every Cholesky pivot above
    :data:`PIVOT_TOLERANCE` times the largest diagonal entry (numerically
    singular matrices are refused too). Returns index → message, in index order.
    """
    problems: dict[int, str] = {}
    if not len(covariances):
        return problems
    scale = np.abs(covariances).max(axis=(1, 2))
    asymmetry = np.abs(covariances - np.swapaxes(covariances, 1, 2)).max(axis=(1, 2))
    for index in np.flatnonzero(
        asymmetry > SYMMETRY_TOLERANCE * np.maximum(scale, 1e-300)
    ).tolist():
        problems[index] = (
            f"covariance is not symmetric (max |P − Pᵀ| = {asymmetry[index]:.3g}, "
            f"tolerance {SYMMETRY_TOLERANCE:g} × largest entry)"
        )
    pivots = _pivots(covariances)
    largest = np.diagonal(covariances, axis1=1, axis2=2).max(axis=1, initial=0.0)
    failing = (pivots <= PIVOT_TOLERANCE * np.maximum(largest, 1e-300)[:, None]).any(axis=1)
    for index in np.flatnonzero(failing).tolist():
        if index in problems:
            continue
        eigenvalues = np.linalg.eigvalsh(covariances[index])
        problems[index] = (
            f"covariance is not positive definite (smallest eigenvalue {eigenvalues[0]:.3g}, "
            f"largest {eigenvalues[-1]:.3g}): singular or indefinite covariances cannot be "
            "used for a Mahalanobis distance"
        )
    return dict(sorted(problems.items()))


def _pivots(covariances: FloatArray) -> FloatArray:
    """Cholesky pivots ``L_jj²`` of every matrix (shape (n, q)); 0 where the factorisation fails.

    LAPACK factorises each matrix on its own, so a matrix gets the same
    pivots (and the same verdict) whatever else is in the stack; the stack is
    retried matrix by matrix only when some matrix is not positive definite.
    """
    try:
        lower = np.linalg.cholesky(covariances)
    except np.linalg.LinAlgError:
        pivots = np.zeros(covariances.shape[:2])
        for index, matrix in enumerate(covariances):
            with contextlib.suppress(np.linalg.LinAlgError):  # not positive definite: stays 0
                pivots[index] = np.diagonal(np.linalg.cholesky(matrix)) ** 2
        return pivots
    return np.asarray(np.diagonal(lower, axis1=1, axis2=2) ** 2, dtype=np.float64)
