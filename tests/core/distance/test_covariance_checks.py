"""Covariance validation: the matrices eigvalsh calls bad are refused, whatever else is in the stack."""

from __future__ import annotations

import numpy as np
import pytest

from core.distance import check_covariances
from core.distance.estimates import PIVOT_TOLERANCE
from core.errors import CovarianceError, InvalidInput

STACK_SIZES = [1, 5, 300]


def valid_stack(n: int, q: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, q, q))
    return a @ a.transpose(0, 2, 1) + 0.5 * np.eye(q)


BAD_MATRICES = {
    # smallest eigenvalue < 0
    "indefinite": np.array([[1.0, 2.0], [2.0, 1.0]]),
    # smallest eigenvalue ≈ 1e-14 of a unit matrix: LAPACK factorises it,
    # but its last pivot is below PIVOT_TOLERANCE, so it is numerically singular
    "numerically singular": np.array([[1.0, 1.0], [1.0, 1.0 + 1e-14]]),
}


@pytest.mark.parametrize("n", STACK_SIZES[1:])
@pytest.mark.parametrize("kind", sorted(BAD_MATRICES))
def test_the_first_bad_matrix_is_named(n: int, kind: str) -> None:
    bad = BAD_MATRICES[kind]
    # independent verdict: eigenvalues relative to the largest diagonal entry
    assert np.linalg.eigvalsh(bad)[0] <= PIVOT_TOLERANCE * bad.diagonal().max()
    stack = valid_stack(n, 2)
    stack[3] = bad
    stack[n - 1] = bad
    with pytest.raises(CovarianceError, match=r"known\[3\]\.covariance is not positive definite"):
        check_covariances(stack, "known")


def verdict(stack: np.ndarray) -> bool:
    try:
        check_covariances(stack, "known")
    except CovarianceError:
        return False
    return True


def test_a_borderline_matrix_gets_the_same_verdict_in_any_stack() -> None:
    """Acceptance near PIVOT_TOLERANCE must not depend on the other matrices of the input."""
    rng = np.random.default_rng(3)
    borderline = []
    for scale in rng.uniform(0.5, 2.0, size=200):
        gap = scale * PIVOT_TOLERANCE * rng.uniform(0.5, 1.5)
        borderline.append(scale * np.array([[1.0, 1.0], [1.0, 1.0 + gap]]))
    # the review's example, refused by one path and accepted by another before
    value = 0.9995994237810748
    borderline.append(np.array([[value, value], [value, 0.9995994237820744]]))
    verdicts = {verdict(matrix[None]) for matrix in borderline}
    assert verdicts == {True, False}  # the set really straddles the tolerance
    for matrix in borderline:
        alone = verdict(matrix[None])
        for n in STACK_SIZES[1:]:
            stack = valid_stack(n, 2, seed=n)
            stack[n // 2] = matrix
            assert verdict(stack) is alone


@pytest.mark.parametrize("n", STACK_SIZES)
def test_valid_stacks_pass_and_other_defects_are_named(n: int) -> None:
    stack = valid_stack(n, 4)
    check_covariances(stack, "known")  # no exception
    index = n - 1
    asymmetric = stack.copy()
    asymmetric[index, 0, 1] += 1e-3
    with pytest.raises(CovarianceError, match=rf"known\[{index}\]\.covariance is not symmetric"):
        check_covariances(asymmetric, "known")
    infinite = stack.copy()
    infinite[index, 0, 0] = np.inf
    with pytest.raises(InvalidInput, match=rf"known\[{index}\]\.covariance is not finite"):
        check_covariances(infinite, "known")
