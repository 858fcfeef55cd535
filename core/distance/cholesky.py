"""Batched Cholesky factorisation and Mahalanobis quadratic forms for small matrices.

The association distances need ``D = Δᵀ C⁻¹ Δ`` and ``log|C|`` for many pairs
of a small dimension q (2 to 6 in practice). LAPACK through ``np.linalg``
pays a per-matrix call overhead, so for small q the factorisation is written
out element by element, each step a vector operation over all pairs
("component-major" layout: ``C[i, j]`` is the array of entry (i, j) of every
pair). With ``C = L Lᵀ`` and ``y = L⁻¹ Δ``, ``D = |y|²`` and
``log|C| = 2 Σ log L_ii``.
"""

from __future__ import annotations

import numpy as np

from core.arrays import FloatArray

UNROLLED_MAX_DIMENSION = 8
"""Above this dimension the LAPACK path (``np.linalg``) is used instead."""


def quadratic_form_and_log_det(
    differences: FloatArray, covariances: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """``D = Δᵀ C⁻¹ Δ`` and ``log|C|`` for every pair of a batch.

    Parameters
    ----------
    differences : ndarray, shape (q, n)
        Component-major differences Δ (row i is component i of every pair).
    covariances : ndarray, shape (q, q, n)
        Component-major symmetric positive definite matrices C.

    Returns
    -------
    distance, log_det : ndarray, shape (n,)

    Notes
    -----
    The caller guarantees positive definiteness (each C is a positive
    combination of validated covariances), so pivots are not re-checked here.
    """
    q, n = differences.shape
    if q > UNROLLED_MAX_DIMENSION:
        matrices = np.moveaxis(covariances, -1, 0)
        lower = np.linalg.cholesky(matrices)
        solved = np.linalg.solve(lower, differences.T[:, :, None])[:, :, 0]
        diagonal = np.diagonal(lower, axis1=1, axis2=2)
        return (
            np.einsum("ni,ni->n", solved, solved),
            2.0 * np.log(diagonal).sum(axis=1),
        )
    factor: list[list[FloatArray]] = [[] for _ in range(q)]
    whitened: list[FloatArray] = []
    log_det = np.zeros(n)
    for j in range(q):
        pivot = covariances[j, j].copy()
        for k in range(j):
            pivot -= factor[j][k] * factor[j][k]
        root = np.sqrt(pivot)
        log_det += np.log(pivot)
        inverse_root = 1.0 / root
        for i in range(j + 1, q):
            entry = covariances[i, j].copy()
            for k in range(j):
                entry -= factor[i][k] * factor[j][k]
            factor[i].append(entry * inverse_root)
        factor[j].append(root)
        # forward substitution for y = L⁻¹ Δ, row j
        residual = differences[j].copy()
        for k in range(j):
            residual -= factor[j][k] * whitened[k]
        whitened.append(residual * inverse_root)
    distance = np.zeros(n)
    for component in whitened:
        distance += component * component
    return distance, log_det
