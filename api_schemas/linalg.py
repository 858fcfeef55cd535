"""Structural checks of vectors and matrices (no algorithms, only shape and validity).

The functions raise :class:`ValueError` with a message that names the problem;
pydantic turns it into a validation error located at the field being checked.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from itertools import chain

import numpy as np

from core.distance import estimates
from core.distance.estimates import covariance_problems as covariance_problems_of_stack

SYMMETRY_TOLERANCE = estimates.SYMMETRY_TOLERANCE
"""Relative tolerance on ``|P - Pᵀ|`` (the core's: one check, one tolerance)."""
NOISE_VARIANCE_BOUNDS_M2 = (1e-6, 1e10)
"""A cartesian measurement noise R's eigenvalues (m²: the variance along each of its axes),
bounds included: (1 mm)² to (100 km)², a polar sensor's ``sigma_range`` bounds squared. No
sensor measures a position outside them; below them a detection's clutter box ``z ± 3σ``
rounds back to ``z`` (1e-60 m² did: a box of volume 0)."""
R_DESCRIPTION = (
    "R over the positions (m²): symmetric positive definite, every eigenvalue (the variance "
    "along one of its axes) from 1e-06 (1 mm)² to 1e+10 (100 km)²"
)


def check_square(
    matrix: Sequence[Sequence[float]],
    size: int | None = None,
    *,
    name: str = "matrix",
    vector: str | None = None,
) -> int:
    """Check that ``matrix`` is square (and ``size`` × ``size`` if given); return its size.

    The message says the shape expected in the wire's words ("covariance must be a list
    of 6 rows of 6 to match the 6-element state"): ``name`` is the matrix's field and
    ``vector`` the field whose length ``size`` is (the state, ``z``).
    """
    rows = len(matrix)
    wanted = rows if size is None else size
    match = "" if size is None or vector is None else f" to match the {size}-element {vector}"
    shape = f"{name} must be a list of {wanted} rows of {wanted}{match}"
    if rows == 0:
        raise ValueError(f"{shape}; got an empty list")
    if size is not None and rows != size:
        ragged = any(len(row) != rows for row in matrix)
        got = _rows(rows) if ragged else f"{_rows(rows)} of {rows}"
        hint = f" (or the {vector} must have {rows} elements)" if vector is not None else ""
        raise ValueError(f"{shape}; got {got}{hint}")
    for index, row in enumerate(matrix):
        if len(row) != rows:
            raise ValueError(f"{shape}; row {index} has {len(row)} entries")
    return rows


def _rows(count: int) -> str:
    return "1 row" if count == 1 else f"{count} rows"


def check_covariance(
    matrix: Sequence[Sequence[float]],
    size: int | None = None,
    *,
    name: str = "matrix",
    noise: bool = False,
) -> None:
    """Check that ``matrix`` is a square, symmetric, positive-definite covariance (and, as a
    measurement ``noise``, of variances within :data:`NOISE_VARIANCE_BOUNDS_M2`).

    For the many matrices of one input use :func:`covariance_problems` (one batch).
    """
    check_square(matrix, size, name=name)
    problem = (noise_problems if noise else covariance_problems)([matrix]).get(0)
    if problem is not None:
        raise ValueError(problem)


def covariance_problems(matrices: Sequence[Sequence[Sequence[float]]]) -> dict[int, str]:
    """What is wrong with each matrix that is not a symmetric positive-definite covariance.

    The matrices must already be square (:func:`check_square`); they may differ in
    size. Matrices of one size are stacked and checked together: one symmetry
    test and one batched Cholesky factorisation; only when that fails is each
    matrix of the batch factorised alone, to find which ones fail.

    Parameters
    ----------
    matrices : sequence of square matrices
        The covariances of one input, in input order.

    Returns
    -------
    dict of int to str
        Index in ``matrices`` → the problem (the message :func:`check_covariance`
        raises); empty when every matrix is a covariance.
    """
    problems: dict[int, str] = {}
    for size, indices in _by_size(matrices).items():
        group = matrices if len(indices) == len(matrices) else [matrices[i] for i in indices]
        entries = chain.from_iterable(chain.from_iterable(group))
        stack = np.fromiter(entries, dtype=float, count=len(indices) * size * size)
        for position, problem in _stack_problems(stack.reshape(len(indices), size, size)).items():
            problems[indices[position]] = problem
    return dict(sorted(problems.items()))


def noise_problems(matrices: Sequence[Sequence[Sequence[float]]]) -> dict[int, str]:
    """What is wrong with each matrix that is no measurement noise R: :func:`covariance_problems`,
    then an eigenvalue outside :data:`NOISE_VARIANCE_BOUNDS_M2` (one ``eigvalsh`` per size).

    The matrices must already be square; index in ``matrices`` → the problem, in index order.
    """
    problems = covariance_problems(matrices)
    low, high = NOISE_VARIANCE_BOUNDS_M2
    bounds = f"every variance of R (an eigenvalue, m²) must be from {low:g} to {high:g}"
    for size, indices in _by_size(matrices).items():
        kept = [index for index in indices if index not in problems]
        if not kept:
            continue
        stack = np.array([matrices[index] for index in kept], dtype=float).reshape(-1, size, size)
        eigenvalues = np.linalg.eigvalsh(stack)
        for index, smallest, largest in zip(
            kept, eigenvalues[:, 0].tolist(), eigenvalues[:, -1].tolist(), strict=True
        ):
            if smallest < low:
                problems[index] = (
                    f"{bounds} ((1 mm)² to (100 km)²): its smallest, {smallest:.3g} m² "
                    f"(σ {math.sqrt(smallest):.3g} m along that axis), is below {low:g}"
                )
            elif largest > high:
                problems[index] = (
                    f"{bounds} ((1 mm)² to (100 km)²): its largest, {largest:.3g} m² "
                    f"(σ {math.sqrt(largest):.3g} m along that axis), is above {high:g}"
                )
    return dict(sorted(problems.items()))


def _by_size(matrices: Sequence[Sequence[Sequence[float]]]) -> dict[int, list[int]]:
    """The indices of the matrices of each size, in input order."""
    by_size: dict[int, list[int]] = {}
    for index, matrix in enumerate(matrices):
        by_size.setdefault(len(matrix), []).append(index)
    return by_size


def _stack_problems(stack: np.ndarray) -> dict[int, str]:
    """:func:`covariance_problems` of a ``(k, n, n)`` stack, by position: the core's one check."""
    return covariance_problems_of_stack(stack)
