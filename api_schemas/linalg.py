"""Structural checks of vectors and matrices (no algorithms, only shape and validity).

The functions raise :class:`ValueError` with a message that names the problem;
pydantic turns it into a validation error located at the field being checked.
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import chain

import numpy as np

from core.distance import estimates
from core.distance.estimates import covariance_problems as covariance_problems_of_stack

SYMMETRY_TOLERANCE = estimates.SYMMETRY_TOLERANCE
"""Relative tolerance on ``|P - Pᵀ|`` (the core's: one check, one tolerance)."""


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
    matrix: Sequence[Sequence[float]], size: int | None = None, *, name: str = "matrix"
) -> None:
    """Check that ``matrix`` is a square, symmetric, positive-definite covariance.

    For the many matrices of one input use :func:`covariance_problems` (one batch).
    """
    check_square(matrix, size, name=name)
    problem = covariance_problems([matrix]).get(0)
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
    by_size: dict[int, list[int]] = {}
    for index, matrix in enumerate(matrices):
        by_size.setdefault(len(matrix), []).append(index)
    problems: dict[int, str] = {}
    for size, indices in by_size.items():
        group = matrices if len(indices) == len(matrices) else [matrices[i] for i in indices]
        entries = chain.from_iterable(chain.from_iterable(group))
        stack = np.fromiter(entries, dtype=float, count=len(indices) * size * size)
        for position, problem in _stack_problems(stack.reshape(len(indices), size, size)).items():
            problems[indices[position]] = problem
    return dict(sorted(problems.items()))


def _stack_problems(stack: np.ndarray) -> dict[int, str]:
    """:func:`covariance_problems` of a ``(k, n, n)`` stack, by position: the core's one check."""
    return covariance_problems_of_stack(stack)
