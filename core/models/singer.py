"""Singer's model: a manoeuvre as a correlated acceleration (docs/algorithms.md §7.6).

Singer (1970) models a manned target's acceleration along each axis as a
first-order Gauss–Markov process of time constant ``τ`` (the manoeuvre time)
and variance ``σ_m²``::

    ȧ(t) = −α a(t) + w(t),   α = 1/τ,   E[w(t) w(t')] = 2 α σ_m² δ(t − t')

([Singer]; Li & Jilkov 2003, Part I, its section on the Singer model). The
block of one axis is ``[p, v, a]``; with ``x = αΔt`` and ``e = e^{−x}``, the
discrete transition and the covariance of its noise ([Singer]) are::

    F = [[1, Δt, (x − 1 + e)/α²],
         [0, 1,  (1 − e)/α],
         [0, 0,  e]]

and ``Q = 2 α σ_m² q̃`` with::

    q̃11 = (1 − e² + 2x + 2x³/3 − 2x² − 4x e) / (2α⁵)
    q̃12 = (e² + 1 − 2e + 2x e − 2x + x²) / (2α⁴)
    q̃13 = (1 − e² − 2x e) / (2α³)
    q̃22 = (4e − 3 − e² + 2x) / (2α³)
    q̃23 = (e² + 1 − 2e) / (2α²)
    q̃33 = (1 − e²) / (2α)

— ``Q = q ∫₀^Δt F(t) e₃ e₃ᵀ F(t)ᵀ dt`` with ``q = 2 α σ_m²`` (Stone Soup's
``Singer(damping_coeff=α, noise_diff_coeff=q)``, which integrates it
numerically; the tests hold the two, and Van Loan's matrix exponential, to
each other). The papers' equation and section numbers are not quoted: their
text was not at hand to check them. Each bracket cancels to its leading power of ``x``
(up to x⁵ for q̃11), so below ``|x| = 1`` the entries are evaluated from
their Taylor series instead, whose coefficients are worked exactly from the
exponential series when the module loads (:func:`_series`); above it the
closed form loses at most a few digits of 10⁻¹⁶. A long gap (``x`` large) is
the exponentials' limit: the acceleration forgotten (``e → 0``), F and Q
finite.

Defaults (aircraft, :data:`MANOEUVRE_TIME`, :data:`ACCELERATION_STD`):
``τ = 20 s``, Singer's evasive manoeuvre (he suggests about 60 s for a lazy
turn, 10–20 s for an evasive manoeuvre, about 1 s for atmospheric
turbulence), and Singer's ``σ_m² = A_max²/3 (1 + 4 P_max − P_0)`` (the
variance of his density: 0 with probability P_0, ±A_max with P_max each,
uniform between) with ``A_max = 4 g`` (the largest manoeuvre of the aircraft
preset's bank), ``P_max = 0.05`` and ``P_0 = 0.5``:
``σ_m = 0.483 A_max = 18.9 m/s²``.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from math import factorial

import numpy as np

from core.arrays import FloatArray
from core.errors import InvalidInput
from core.models.transition import Component

GRAVITY = 9.80665
"""Standard gravity g (m/s²)."""

MANOEUVRE_TIME = 20.0
"""Default τ (s): Singer's evasive manoeuvre (module docstring)."""

MAX_ACCELERATION = 4.0 * GRAVITY
"""Default A_max (m/s²): the aircraft preset's largest manoeuvre, 4 g."""

MAX_ACCELERATION_PROBABILITY = 0.05
NO_ACCELERATION_PROBABILITY = 0.5


def singer_acceleration_std(
    max_acceleration: float,
    max_probability: float = MAX_ACCELERATION_PROBABILITY,
    zero_probability: float = NO_ACCELERATION_PROBABILITY,
) -> float:
    """``σ_m = √(A_max²/3 (1 + 4 P_max − P_0))`` ([Singer] eq 2)."""
    return float(
        np.sqrt(max_acceleration**2 / 3.0 * (1.0 + 4.0 * max_probability - zero_probability))
    )


ACCELERATION_STD = singer_acceleration_std(MAX_ACCELERATION)
"""Default σ_m (m/s²): 18.9 (module docstring)."""

SERIES_BELOW = 1.0
"""Below this ``x = αΔt`` the entries come from their Taylor series."""

SERIES_TERMS = 20
"""Terms of each series: the first left out is below 1/20! ≈ 4e-19 of the sum at |x| < 1."""

_Q_POWERS = np.array([5.0, 4.0, 3.0, 3.0, 2.0, 1.0])
"""The power p of Δt of each entry of :data:`_ENTRIES` (q̃ = bracket / (2 α^p))."""

# Each bracket of the module docstring as terms (coefficient, m, k): c x^m e^{−k x},
# with the power p of x it is divided by (x^p / α^p = Δt^p).
Term = tuple[Fraction | int, int, int]
_BRACKETS: dict[tuple[int, int], tuple[tuple[Term, ...], int]] = {
    # Q entries: bracket / (2 α^p)
    (0, 0): (((1, 0, 0), (-1, 0, 2), (2, 1, 0), (Fraction(2, 3), 3, 0), (-2, 2, 0), (-4, 1, 1)), 5),
    (0, 1): (((1, 0, 2), (1, 0, 0), (-2, 0, 1), (2, 1, 1), (-2, 1, 0), (1, 2, 0)), 4),
    (0, 2): (((1, 0, 0), (-1, 0, 2), (-2, 1, 1)), 3),
    (1, 1): (((4, 0, 1), (-3, 0, 0), (-1, 0, 2), (2, 1, 0)), 3),
    (1, 2): (((1, 0, 2), (1, 0, 0), (-2, 0, 1)), 2),
    (2, 2): (((1, 0, 0), (-1, 0, 2)), 1),
}
_F13: tuple[tuple[Term, ...], int] = (((1, 1, 0), (-1, 0, 0), (1, 0, 1)), 2)  # (x − 1 + e) / α²


def _series(terms: tuple[Term, ...], power: int, halve: bool) -> FloatArray:
    """Taylor coefficients ``a_n`` of ``bracket(x) / x^power`` (halved for Q's ``1/2``):
    ``c x^m e^{−kx} = Σ_j c (−k)^j x^{m+j} / j!``, exactly in rationals."""
    coefficients = []
    for n in range(SERIES_TERMS):
        total = Fraction(0)
        for c, m, k in terms:
            j = n + power - m
            if j >= 0:
                total += Fraction(c) * Fraction((-k) ** j, factorial(j))
        coefficients.append(total / 2 if halve else total)
    return np.array([float(c) for c in coefficients])


_ENTRIES = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))
"""The upper triangle of Q, in the order of the columns of :data:`_SERIES`."""

_SERIES = np.stack(
    [_series(*_BRACKETS[entry], halve=True) for entry in _ENTRIES] + [_series(*_F13, halve=False)],
    axis=1,
)
"""Taylor coefficients (SERIES_TERMS, 7): the six q̃ entries over Δt^p, then F13 over Δt²."""


def _near(x: FloatArray) -> FloatArray:
    """The seven series at ``x`` of shape S + (7,) (one x per column), by Horner's rule:
    elementwise, so that an entry's bits do not depend on the batch it is computed in."""
    result = np.zeros_like(x)
    for row in _SERIES[::-1]:
        result = result * x + row
    return result


def _far(x: FloatArray) -> FloatArray:
    """The seven closed forms at ``x`` of shape S + (7,), |x| ≥ 1 (module docstring)."""
    e = np.exp(-x)
    e2 = e * e
    x2 = x * x
    x3 = x2 * x
    every = np.stack(  # (S, 7 columns of x, 7 formulas): each column keeps its own formula
        [
            (1 - e2 + 2 * x + 2 * x3 / 3 - 2 * x2 - 4 * x * e) / (2 * x2 * x3),
            (e2 + 1 - 2 * e + 2 * x * e - 2 * x + x2) / (2 * x2 * x2),
            (1 - e2 - 2 * x * e) / (2 * x3),
            (4 * e - 3 - e2 + 2 * x) / (2 * x3),
            (e2 + 1 - 2 * e) / (2 * x2),
            (1 - e2) / (2 * x),
            (x - 1 + e) / x2,
        ],
        axis=-1,
    )
    return np.diagonal(every, axis1=-2, axis2=-1)


@dataclass(frozen=True)
class Singer:
    """Singer's model of one axis (module docstring).

    Attributes
    ----------
    manoeuvre_time : float
        τ (s), the correlation time of the acceleration; α = 1/τ.
    acceleration_std : float
        σ_m (m/s²), the acceleration's standard deviation.
    """

    manoeuvre_time: float = MANOEUVRE_TIME
    acceleration_std: float = ACCELERATION_STD

    def __post_init__(self) -> None:
        for name in ("manoeuvre_time", "acceleration_std"):
            value = float(getattr(self, name))
            if not (np.isfinite(value) and value > 0.0):
                raise InvalidInput(f"motion {name} must be a positive number, got {value!r}")

    @property
    def components(self) -> tuple[Component, ...]:
        """Position, velocity and acceleration."""
        return ("position", "velocity", "acceleration")

    @property
    def damping(self) -> float:
        """α = 1/τ (Stone Soup's ``damping_coeff``)."""
        return 1.0 / self.manoeuvre_time

    @property
    def q(self) -> float:
        """2 α σ_m²: the spectral density of ``w`` (Stone Soup's ``noise_diff_coeff``)."""
        return 2.0 * self.damping * self.acceleration_std**2

    def matrices(self, dt: FloatArray) -> tuple[FloatArray, FloatArray]:
        """F(Δt) and Q(|Δt|) of ``[p, v, a]`` (module docstring)."""
        dt = np.asarray(dt, dtype=np.float64)
        alpha = self.damping
        span = np.abs(dt)
        x = alpha * span
        # the seven scaled entries: the six of Q at x = α|Δt|, F13 at the signed x = αΔt
        # (backwards, F(−Δt) = F(Δt)⁻¹); each by its series below 1, its closed form above
        signed = alpha * dt
        x = np.concatenate([np.repeat(x[..., None], 6, axis=-1), signed[..., None]], axis=-1)
        near = np.abs(x) < SERIES_BELOW
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            scaled = np.where(near, _near(np.where(near, x, 0.0)), _far(np.where(near, 1.0, x)))
            upper = self.q * span[..., None] ** _Q_POWERS * scaled[..., :6]
            noise = np.empty((*dt.shape, 3, 3))
            for column, (i, j) in enumerate(_ENTRIES):
                noise[..., i, j] = noise[..., j, i] = upper[..., column]
            transition = np.zeros((*dt.shape, 3, 3))
            transition[..., 0, 0] = transition[..., 1, 1] = 1.0
            transition[..., 0, 1] = dt
            transition[..., 0, 2] = dt**2 * scaled[..., 6]
            # (1 − e^{−αΔt})/α = −expm1(−αΔt)/α: exact to the last digits both ways
            transition[..., 1, 2] = -np.expm1(-signed) / alpha
            transition[..., 2, 2] = np.exp(-signed)
        return transition, noise
