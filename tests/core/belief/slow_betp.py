"""The straightforward O(N²) BetP paths, kept as the reference of the fast ones.

These are the implementations of ``core/belief/gbt.py`` before the node count
was bounded and the leave-one-out products became divisions: Gauss–Legendre of
the exact order (``ceil(N/2)`` / ``floor(N/2) + 1`` nodes) and prefix/suffix
products, no division. Tests only.
"""

from __future__ import annotations

import numpy as np

from core.arrays import BoolArray, FloatArray
from core.belief.gbt import _compress_rows, _gauss_legendre_01
from core.errors import MassError


def leave_one_out_products(factors: FloatArray) -> FloatArray:
    """``out[..., j] = Π_{k≠j} factors[..., k]`` by prefix/suffix products (no division)."""
    ones = np.ones((*factors.shape[:-1], 1))
    prefix = np.cumprod(np.concatenate([ones, factors[..., :-1]], axis=-1), axis=-1)
    suffix = np.cumprod(np.concatenate([ones, factors[..., :0:-1]], axis=-1), axis=-1)[..., ::-1]
    return np.asarray(prefix * suffix, dtype=np.float64)


def slow_gbt_betp_rows(plausibility: FloatArray) -> tuple[FloatArray, BoolArray]:
    """Exact BetP of the GBT mass of every row of ``plausibility`` (shape B × N).

    Returns
    -------
    betp : ndarray, shape (B, N)
        Each defined row sums to 1; an undefined row is all zeros.
    defined : ndarray of bool, shape (B,)
        False where every plausibility of the row is 0 (m(∅) = 1).
    """
    p = np.asarray(plausibility, dtype=np.float64)
    if p.ndim != 2:
        raise MassError(
            f"plausibilities must be a 2-D array (rows × elements), got shape {p.shape}"
        )
    betp = np.zeros_like(p)
    if p.size == 0:
        return betp, np.zeros(p.shape[0], dtype=bool)
    order, width = _compress_rows(p > 0.0)
    if width == 0:
        return betp, np.zeros(p.shape[0], dtype=bool)
    columns = order[:, :width]
    pc = np.take_along_axis(p, columns, axis=1)  # zero padding: factor 1, numerator 0
    nodes, weights = _gauss_legendre_01((width + 1) // 2)  # degree width − 1
    factors = 1.0 - pc[:, None, :] + pc[:, None, :] * nodes[None, :, None]
    integrals = np.einsum("l,bln->bn", weights, leave_one_out_products(factors))
    numerators = pc * integrals
    normaliser = numerators.sum(axis=1)  # = 1 − Π(1 − p), no cancellation
    defined = normaliser > 0.0
    safe = np.where(defined, normaliser, 1.0)
    np.put_along_axis(betp, columns, numerators / safe[:, None], axis=1)
    return betp, defined


def slow_pairwise_evidence_betp_rows(
    support: FloatArray, refute: FloatArray, ignorance: FloatArray
) -> tuple[FloatArray, BoolArray]:
    """Exact BetP of the pairwise-evidence mass of [DH] §3.4, row by row.

    Each row is one item with n candidate partners. For candidate k,
    ``a_k`` (``support``) is the mass on Y_k ("comes from k"), ``b_k``
    (``refute``) the mass on ¬Y_k and ``c_k`` (``ignorance``) the mass on Θ.
    Their conjunctive combination over k lives on Θ = {Y_1 .. Y_n, *}.
    With ``g_k(t) = b_k + c_k t`` (docs/algorithms.md §1.1)::

        BetP(*)   ∝ ∫ Π_k g_k(t) dt
        BetP(Y_j) ∝ a_j Π_{k≠j} (b_k + c_k) + c_j ∫ t Π_{k≠j} g_k(t) dt

    normalised by 1 − m(∅) = Σ_j a_j Π_{k≠j}(1 − a_k) + Π_k (b_k + c_k).

    Returns
    -------
    betp : ndarray, shape (B, n + 1)
        Columns Y_1 .. Y_n, then ``*``. Undefined rows are zeros.
    defined : ndarray of bool, shape (B,)
        False where the combination is in total conflict.
    """
    a, b, c = (np.asarray(x, dtype=np.float64) for x in (support, refute, ignorance))
    if a.ndim != 2 or a.shape != b.shape or a.shape != c.shape:
        raise MassError(
            f"support, refute and ignorance must be 2-D of one shape, got {a.shape}, {b.shape}, {c.shape}"
        )
    if np.any(np.abs(a + b + c - 1.0) > 1e-9):
        raise MassError("support + refute + ignorance must be 1 for every pair")
    rows, n = a.shape
    betp = np.zeros((rows, n + 1))
    if rows == 0:
        return betp, np.zeros(0, dtype=bool)
    # Candidates with Pl(Y_k) = a_k + c_k = 0 are certain refutations: g_k ≡ 1.
    order, width = _compress_rows((a + c) > 0.0)
    columns = order[:, :width]
    ac, bc, cc = (np.take_along_axis(x, columns, axis=1) for x in (a, b, c))
    # Entries past a row's kept count are refutations (a = c = 0, b = 1): g ≡ 1, score 0.
    nodes, weights = _gauss_legendre_01((width + 2) // 2)  # degree width
    factors = bc[:, None, :] + cc[:, None, :] * nodes[None, :, None]  # (B, L, w)
    full = np.prod(factors, axis=2)  # (B, L)
    loo = leave_one_out_products(factors)  # (B, L, w)
    star = full @ weights
    at_one = leave_one_out_products(bc + cc)  # Π_{k≠j}(b_k + c_k)
    singles = ac * at_one
    shared = cc * np.einsum("l,bln->bn", weights * nodes, loo)
    full_at_one = np.prod(bc + cc, axis=1)
    normaliser = singles.sum(axis=1) + full_at_one
    defined = normaliser > 0.0  # exact products: any positive normaliser is meaningful
    safe = np.where(defined, normaliser, 1.0)[:, None]
    scores = np.where(defined[:, None], (singles + shared) / safe, 0.0)
    np.put_along_axis(betp[:, :n], columns, scores, axis=1)
    betp[:, n] = np.where(defined, star / safe[:, 0], 0.0)
    return betp, defined
