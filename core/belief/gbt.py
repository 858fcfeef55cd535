"""The Generalized Bayesian Theorem and exact pignistic probabilities in O(N²).

GBT ([MTT] eq 10, [T2T] eq 6): from singleton plausibilities ``p_k``,
``m(A) = Π_{k∈A} p_k Π_{k∉A} (1 − p_k)``.

That mass is the law of a random set containing each element independently
with probability ``p_k``, so (docs/algorithms.md §1.1)

    BetP(k) ∝ p_k ∫₀¹ Π_{j≠k} (1 − p_j + p_j t) dt,

a polynomial of degree N − 1 integrated exactly by Gauss–Legendre with
⌈N/2⌉ nodes; prefix and suffix products give every leave-one-out product per
node without division. The normaliser is the sum of the numerators, which
equals ``1 − m(∅) = 1 − Π(1 − p_k)`` exactly, without its cancellation.

The same device gives the BetP of the pairwise-evidence mass of [DH] §3.4
(:func:`pairwise_evidence_betp_rows`).

Speed on large frames: the exact order ⌈N/2⌉ is rarely needed. The integrands
are polynomials whose roots are real and ≤ 0, so their size on the Bernstein
ellipse E_ρ is bounded from Σ p alone, and Gauss–Legendre's error bound on
E_ρ gives, per row, the fewest nodes with a *proven* BetP error ≤ 1e-15
(:func:`gauss_order`; 105 nodes instead of 500 for 1000 candidates at Pl ≈ 1,
8 at Pl ≈ 0.02). The leave-one-out products are then the full product over one
factor (each factor is ≥ t > 0 at every node), one matrix product per block.

Dense rows (Σ p in the hundreds) are cheaper still: with u = 1 − t every factor
is ``1 − p u ≤ e^{−p u}``, so the integrands decay like ``e^{−S u}`` and the part
of [0, 1] beyond a per-row ``U`` (:func:`truncation`) adds less than half the
tolerance; on [0, U] the substitution u = U s turns each factor into one of
plausibility ``U p`` (the same polynomials, ``growth`` scaled by U), so 18 nodes
do where 105 did. Rows with ``U = 1`` are computed exactly as without it.

Elements with plausibility 0 are removed before any product is formed: they
cost nothing.
"""

from __future__ import annotations

import math
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


NODE_BUDGET = 1 << 22
"""Largest rows × nodes × width of one temporary of the quadrature (32 MB of floats)."""

BETP_TOLERANCE = 1e-15
"""Proven bound on the quadrature error of every BetP (absolute), when fewer nodes than
the exact order are used (:func:`gauss_order`)."""

_RHO = 1.0 + np.geomspace(1e-3, 1e3, 64)
_SEMI_AXIS = (_RHO + 1.0 / _RHO) / 2.0  # ρ' = semi-major axis of the Bernstein ellipse E_ρ


def gauss_order(log_factor: FloatArray, growth: FloatArray, exact: int) -> int:
    """Fewest Gauss–Legendre nodes on [0, 1] whose error is provably ≤ BETP_TOLERANCE.

    For an integrand analytic in the Bernstein ellipse E_ρ (foci the ends of
    the interval, ρ > 1) and bounded there by M, L-point Gauss–Legendre on
    [0, 1] errs by at most (32/15) M ρ^{−2L} / (ρ² − 1) (Trefethen, SIAM Review
    50 (2008), Thm 4.5, halved for the length of [0, 1]). Each row supplies the
    bound of its BetP error as ``exp(log_factor + growth (ρ' − 1))`` times that
    (ρ' the ellipse's semi-major axis); the order is the smallest L meeting the
    tolerance for some ρ of a grid, for the worst row, and never above ``exact``
    (the order that integrates the polynomials exactly).
    """
    if exact <= 1 or len(growth) == 0:
        return max(exact, 1)
    log_bound = (
        math.log(32.0 / 15.0)
        + log_factor[:, None]
        + growth[:, None] * (_SEMI_AXIS[None, :] - 1.0)
        - np.log(_RHO**2 - 1.0)[None, :]
        - math.log(BETP_TOLERANCE)
    )
    needed = np.min(np.maximum(log_bound, 0.0) / (2.0 * np.log(_RHO))[None, :], axis=1)
    if not np.all(np.isfinite(needed)):
        return exact
    return int(min(exact, max(1, math.ceil(float(needed.max())))))


def leave_one_out_sums(terms: FloatArray) -> FloatArray:
    """``out[..., j] = Σ_{k≠j} terms[..., k]`` by prefix/suffix sums (no subtraction).

    Made for logarithms (terms ≤ 0, some −inf): −inf minus −inf never occurs.
    """
    zeros = np.zeros((*terms.shape[:-1], 1))
    prefix = np.cumsum(np.concatenate([zeros, terms[..., :-1]], axis=-1), axis=-1)
    suffix = np.cumsum(np.concatenate([zeros, terms[..., :0:-1]], axis=-1), axis=-1)[..., ::-1]
    return np.asarray(prefix + suffix, dtype=np.float64)


def truncation(decay: FloatArray, width: int, tolerance: float) -> FloatArray:
    """Per row, the ``U ∈ (0, 1]`` past which the integrals may be dropped (module docstring).

    Every integrand of a row is ``t^s Π h_k`` over all factors but at most one,
    with ``h_k = 1 − q_k u ≤ e^{−q_k u}`` (u = 1 − t), so its part over u > U is
    at most ``e^{−D U} / D`` with ``D = decay`` (Σ q minus the largest q), while
    the integral itself is ≥ ``∫ (1 − u)^w du = 1/(w + 1)``: the relative error
    of dropping it is ≤ ``(w + 1) e^{−D U} / D``, ``tolerance`` at the U returned
    (1 where no U < 1 reaches it).
    """
    positive = np.maximum(decay, 1e-300)
    cut = (math.log((width + 1.0) / tolerance) - np.log(positive)) / positive
    return np.where(decay > 0.0, np.minimum(cut, 1.0), 1.0)


def _leave_one_out_integrals(
    q: FloatArray, n_nodes: int, times_t: bool, upper: FloatArray | None = None
) -> tuple[FloatArray, FloatArray]:
    """``∫ Π_k h_k`` and every ``∫ t^s Π_{k≠j} h_k`` (s = 1 if ``times_t``), ``h_k = 1 − q_k + q_k t``.

    Over ``t ∈ [1 − U, 1]``, U = ``upper`` per row (None: U = 1, all of [0, 1]).
    With u = 1 − t = U s the factors become ``1 − (U q_k) s`` and t becomes
    ``1 − U s``: the same integrals on [0, 1] of plausibilities U q, times U.
    ``n_nodes``-point Gauss–Legendre; each leave-one-out product is the full
    product divided by its own factor: ``h_k(t) ≥ t > 0`` at every node, so the
    division is exact to rounding. Where the full product underflows, the true
    integrand is below 1e-300 / t₁ while every integral is ≥ 1/(w + 1):
    negligible. Shapes: q (B, w) → (B,), (B, w).
    """
    nodes, weights = _gauss_legendre_01(n_nodes)
    rows, width = q.shape
    full_integral = np.empty(rows)
    loo = np.empty((rows, width))
    step = max(1, NODE_BUDGET // max(n_nodes * width, 1))  # rows per (B, L, w) temporary
    for start in range(0, rows, step):
        part = slice(start, start + step)
        block_upper = None if upper is None else upper[part]
        scaled = q[part] if block_upper is None else q[part] * block_upper[:, None]
        factors = 1.0 + scaled[:, None, :] * (nodes[None, :, None] - 1.0)  # (B, L, w)
        full = np.prod(factors, axis=2)  # (B, L)
        if block_upper is None:
            node_weights = np.broadcast_to(weights * nodes if times_t else weights, full.shape)
        else:  # t = 1 − U s = 1 − U + U t' at the node t' of the scaled integral
            at_node = 1.0 + block_upper[:, None] * (nodes[None, :] - 1.0)
            node_weights = block_upper[:, None] * (weights * at_node if times_t else weights)
        loo[part] = np.matmul((node_weights * full)[:, None, :], 1.0 / factors)[:, 0, :]
        full_integral[part] = (
            full @ weights if block_upper is None else (full @ weights) * block_upper
        )
    return full_integral, loo


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
    # Error bound (gauss_order): on E_ρ, |1 − p + p t| ≤ 1 + p (ρ' − 1)/2 ≤ exp(p (ρ' − 1)/2),
    # so |Π_{j≠k}| ≤ exp(S (ρ' − 1)/2), S = Σ p; the numerators err by p_k times the
    # quadrature error and BetP by at most 2 Σ_k (that) / (1 − m(∅)), 1 − m(∅) ≥ max p.
    total = pc.sum(axis=1)
    largest = pc.max(axis=1)
    positive = largest > 0.0
    log_factor = np.log(4.0 * total[positive] / largest[positive])
    # truncation: BetP errs by at most twice the integrals' relative error, so a quarter
    # of the tolerance there, and half of it left for the quadrature
    upper = truncation(total - largest, width, BETP_TOLERANCE / 4.0)
    truncated = bool(np.any(upper < 1.0))
    if truncated:
        log_factor = log_factor + np.log(2.0 * upper[positive])
    growth = total[positive] / 2.0 if not truncated else (total * upper)[positive] / 2.0
    order_needed = gauss_order(log_factor, growth, (width + 1) // 2)
    _, integrals = _leave_one_out_integrals(
        pc, order_needed, times_t=False, upper=upper if truncated else None
    )
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
    # With w_k = b_k + c_k = 1 − a_k and q_k = c_k / w_k, g_k = w_k h_k, h_k = 1 − q_k + q_k t:
    # the integrals are those of the GBT path, times the exact Π_{k≠j} w_k.
    # Scale: Π_k w_k has one factor per candidate (≈ 0.1 each on a dense 1000-candidate
    # frame, 1e-1000 in all): every product of w is formed as a sum of logarithms and
    # divided by the row's largest term before exponentiating. BetP is a ratio, so the
    # common factor cancels; the largest term becomes 1 and nothing underflows that matters.
    # Error bound (gauss_order): on E_ρ, |h_k| ≤ 1 + q_k (ρ' − 1)/2 ≤ exp(q_k (ρ' − 1)/2) and
    # |t| ≤ (1 + ρ')/2 ≤ exp((ρ' − 1)/2); the normaliser is exact and ≥ Π w_k, so every BetP
    # errs by at most the quadrature bound of exp((Σ q + 1)(ρ' − 1)/2).
    weight = bc + cc
    with np.errstate(divide="ignore"):  # log 0 = −inf: a certain support (w = 0) or a = 0
        log_weight = np.log(weight)
        log_support = np.log(ac)
    log_at_one = leave_one_out_sums(log_weight)  # log Π_{k≠j} w_k
    log_full_at_one = log_weight.sum(axis=1)  # log Π_k w_k
    log_singles = log_support + log_at_one  # log m(Y_j) = log a_j Π_{k≠j}(1 − a_k)
    log_scale = np.maximum(log_singles.max(axis=1, initial=-np.inf), log_full_at_one)
    # 1 − m(∅) > 0 exactly when some term is > 0: the test is on logarithms, not on products
    defined = log_scale > -np.inf
    shift = np.where(defined, log_scale, 0.0)[:, None]
    singles = np.exp(log_singles - shift)
    at_one = np.exp(log_at_one - shift)  # ≤ 1 / max(a_j, w_j) ≤ 2: no overflow
    full_at_one = np.exp(log_full_at_one - shift[:, 0])
    normaliser = singles.sum(axis=1) + full_at_one  # (1 − m(∅)) / scale ≥ 1 on defined rows
    shared = np.zeros((rows, width))
    star = np.zeros(rows)
    # A defined row with some w_k = 0 (a_k = 1) has exactly one: every focal set but {Y_k}
    # then holds a factor b_k or c_k = 0, so BetP(Y_k) = 1 from ``singles`` alone.
    scaled = defined & np.all(weight > 0.0, axis=1)
    if scaled.any():
        q = cc[scaled] / weight[scaled]
        exact_order = (width + 2) // 2  # degree width
        q_total = q.sum(axis=1)
        # truncation: each BetP errs by at most the integrals' relative error (their terms
        # are ≤ the normaliser): half the tolerance there, half for the quadrature
        upper = truncation(q_total - q.max(axis=1, initial=0.0), width, BETP_TOLERANCE / 2.0)
        truncated = bool(np.any(upper < 1.0))
        log_factor = np.log(2.0 * upper) if truncated else np.zeros(len(q))
        growth = (q_total + 1.0) / 2.0 if not truncated else upper * (q_total + 1.0) / 2.0
        order_needed = gauss_order(log_factor, growth, exact_order)
        full_integral, loo_integral = _leave_one_out_integrals(
            q, order_needed, times_t=True, upper=upper if truncated else None
        )
        shared[scaled] = cc[scaled] * at_one[scaled] * loo_integral
        star[scaled] = full_at_one[scaled] * full_integral
    safe = np.where(defined, normaliser, 1.0)[:, None]
    scores = np.where(defined[:, None], (singles + shared) / safe, 0.0)
    np.put_along_axis(betp[:, :n], columns, scores, axis=1)
    betp[:, n] = np.where(defined, star / safe[:, 0], 0.0)
    return betp, defined
