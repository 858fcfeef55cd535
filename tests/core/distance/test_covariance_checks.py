"""Covariance validation: both factorisation paths refuse exactly the matrices eigvalsh calls bad."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from core.distance import check_covariances
from core.distance.cholesky import UNROLLED_MIN_STACK, spd_inverse
from core.distance.estimates import LAPACK_MAX_STACK, PIVOT_TOLERANCE
from core.errors import CovarianceError, InvalidInput


def valid_stack(n: int, q: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, q, q))
    return a @ a.transpose(0, 2, 1) + 0.5 * np.eye(q)


BAD_MATRICES = {
    # smallest eigenvalue < 0: LAPACK and the unrolled pivots both fail
    "indefinite": np.array([[1.0, 2.0], [2.0, 1.0]]),
    # smallest eigenvalue ≈ 1e-14 of a unit matrix: LAPACK factorises it,
    # but its last pivot is below PIVOT_TOLERANCE, so it is numerically singular
    "numerically singular": np.array([[1.0, 1.0], [1.0, 1.0 + 1e-14]]),
}


@pytest.mark.parametrize("n", [5, LAPACK_MAX_STACK + 40])  # the LAPACK and the unrolled path
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


@pytest.mark.parametrize("n", [5, LAPACK_MAX_STACK + 40])
def test_valid_stacks_pass_and_other_defects_are_named(n: int) -> None:
    stack = valid_stack(n, 4)
    check_covariances(stack, "known")  # no exception
    asymmetric = stack.copy()
    asymmetric[2, 0, 1] += 1e-3
    with pytest.raises(CovarianceError, match=r"known\[2\]\.covariance is not symmetric"):
        check_covariances(asymmetric, "known")
    infinite = stack.copy()
    infinite[1, 0, 0] = np.inf
    with pytest.raises(InvalidInput, match=r"known\[1\]\.covariance is not finite"):
        check_covariances(infinite, "known")


@pytest.mark.parametrize("q", [1, 2, 4, 6])
@pytest.mark.parametrize("n", [3, UNROLLED_MIN_STACK + 5])  # LAPACK and unrolled paths
def test_spd_inverse_matches_numpy(n: int, q: int) -> None:
    stack = valid_stack(n, q, seed=q)
    inverse = spd_inverse(stack)
    assert_allclose(inverse, np.linalg.inv(stack), rtol=1e-9, atol=1e-12)
    assert_allclose(inverse, np.swapaxes(inverse, 1, 2), rtol=1e-12, atol=1e-15)
