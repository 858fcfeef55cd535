"""The Generalized Bayesian Theorem and exact pignistic probabilities in O(N²).

GBT ([MTT] eq 10, [T2T] eq 6): from singleton plausibilities ``p_k``,
``m(A) = Π_{k∈A} p_k Π_{k∉A} (1 − p_k)``.

That mass is the law of a random set containing each element independently
with probability ``p_k``, so (ALGORITHMS.md §1.1)

    BetP(k) ∝ p_k ∫₀¹ Π_{j≠k} (1 − p_j + p_j t) dt,

a polynomial of degree N − 1 integrated exactly by Gauss–Legendre with
⌈N/2⌉ nodes; prefix and suffix products give every leave-one-out product per
node without division. The normaliser is the sum of the numerators, which
equals ``1 − m(∅) = 1 − Π(1 − p_k)`` exactly, without its cancellation.

The same device gives the BetP of the pairwise-evidence mass of [DH] §3.4
(:func:`pairwise_evidence_betp`).

Elements with plausibility 0 are removed before any product is formed: they
cost nothing.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from core.arrays import BoolArray, FloatArray
from core.belief.frame import Frame
from core.belief.mass import MassFunction
from core.errors import MassError


@lru_cache(maxsize=256)
def _gauss_legendre_01(n_nodes: int) -> tuple[FloatArray, FloatArray]:
    """Nodes and weights of ``n_nodes``-point Gauss–Legendre on [0, 1].

    Exact for polynomials of degree ≤ 2 n_nodes − 1.
    """
    nodes, weights = np.polynomial.legendre.leggauss(max(n_nodes, 1))
    return (nodes + 1.0) / 2.0, weights / 2.0


def leave_one_out_products(factors: FloatArray) -> FloatArray:
    """``out[..., j] = Π_{k≠j} factors[..., k]`` by prefix/suffix products (no division)."""
    ones = np.ones((*factors.shape[:-1], 1))
    prefix = np.cumprod(np.concatenate([ones, factors[..., :-1]], axis=-1), axis=-1)
    suffix = np.cumprod(np.concatenate([ones, factors[..., :0:-1]], axis=-1), axis=-1)[..., ::-1]
    return np.asarray(prefix * suffix, dtype=np.float64)


def _check_probabilities(values: FloatArray, name: str) -> None:
    if not np.all(np.isfinite(values)):
        raise MassError(f"{name} must be finite")
    if np.any(values < 0.0) or np.any(values > 1.0):
        raise MassError(
            f"{name} must lie in [0, 1] (got min {values.min()!r}, max {values.max()!r})"
        )


def _compress_rows(keep: BoolArray) -> tuple[np.ndarray, int]:
    """Column order that moves each row's kept entries first, and the widest row's count."""
    order = np.argsort(~keep, axis=1, kind="stable")
    width = int(keep.sum(axis=1).max(initial=0))
    return order, width


def gbt_mass(frame: Frame, plausibility: FloatArray) -> MassFunction:
    """Materialise the (unnormalised) GBT mass on a class-size frame ([MTT] eq 10).

    Elements with ``p = 1`` are in every focal set and those with ``p = 0`` in
    none, so only the 2^F subsets of the F fractional elements are formed.
    m(∅) = Π(1 − p_k) is kept: it is the conflict of the evidence.
    """
    p = np.asarray(plausibility, dtype=np.float64)
    if p.shape != (len(frame),):
        raise MassError(
            f"need one plausibility per label of the frame ({len(frame)}), got shape {p.shape}"
        )
    _check_probabilities(p, "plausibilities")
    bit = np.int64(1) << np.arange(len(frame), dtype=np.int64)
    always = int(bit[p == 1.0].sum())
    fractional = np.flatnonzero((p > 0.0) & (p < 1.0))
    subsets = np.arange(1 << len(fractional), dtype=np.int64)
    member = (subsets[:, None] >> np.arange(len(fractional), dtype=np.int64)) & 1 == 1
    pf = p[fractional]
    masses = np.prod(np.where(member, pf, 1.0 - pf), axis=1)
    masks = (member * bit[fractional]).sum(axis=1).astype(np.int64) | always
    return MassFunction.aggregate(frame, masks, masses)


def gbt_betp_rows(plausibility: FloatArray) -> tuple[FloatArray, BoolArray]:
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
    _check_probabilities(p, "plausibilities")
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


def gbt_betp(plausibility: FloatArray) -> FloatArray | None:
    """Exact BetP of the GBT mass built from singleton plausibilities ``p``.

    O(N²) for N elements of non-zero plausibility (§1.1). Returns ``None``
    when every ``p_k`` is 0 (all mass on ∅: BetP undefined).
    """
    p = np.asarray(plausibility, dtype=np.float64)
    if p.ndim != 1:
        raise MassError(f"plausibilities must be a 1-D array, got shape {p.shape}")
    betp, defined = gbt_betp_rows(p[None, :])
    return betp[0] if defined[0] else None


def pairwise_evidence_betp_rows(
    support: FloatArray, refute: FloatArray, ignorance: FloatArray
) -> tuple[FloatArray, BoolArray]:
    """Exact BetP of the pairwise-evidence mass of [DH] §3.4, row by row.

    Each row is one item with n candidate partners. For candidate k,
    ``a_k`` (``support``) is the mass on Y_k ("comes from k"), ``b_k``
    (``refute``) the mass on ¬Y_k and ``c_k`` (``ignorance``) the mass on Θ.
    Their conjunctive combination over k lives on Θ = {Y_1 .. Y_n, *}.
    With ``g_k(t) = b_k + c_k t`` (ALGORITHMS.md §1.1)::

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
    for values, name in ((a, "support"), (b, "refute"), (c, "ignorance")):
        _check_probabilities(values, name)
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
