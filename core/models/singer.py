"""The Singer model: a manoeuvre as an exponentially correlated acceleration.

Singer (1970) models a manned target's acceleration along each axis as a
first-order Gauss–Markov process of time constant ``τ`` (the manoeuvre time)
and variance ``σ_m²``::

    ȧ(t) = −α a(t) + w(t),   α = 1/τ,   E[w(t) w(t')] = 2 α σ_m² δ(t − t')

([Singer] eq 3–5; Bar-Shalom, Li & Kirubarajan 2001, §8.2.3; Li & Jilkov 2003,
§IV.A). The block of one axis is ``[p, v, a]``; with ``x = αΔt`` and
``e = e^{−x}`` ([Singer] eq 11; Li & Jilkov eq 40)::

    F = [[1, Δt, (x − 1 + e)/α²],
         [0, 1,  (1 − e)/α],
         [0, 0,  e]]

and ``Q = 2 α σ_m² q̃`` with ([Singer] eq 12–13; Li & Jilkov eq 41)::

    q̃11 = (1 − e² + 2x + 2x³/3 − 2x² − 4x e) / (2α⁵)
    q̃12 = (e² + 1 − 2e + 2x e − 2x + x²) / (2α⁴)
    q̃13 = (1 − e² − 2x e) / (2α³)
    q̃22 = (4e − 3 − e² + 2x) / (2α³)
    q̃23 = (e² + 1 − 2e) / (2α²)
    q̃33 = (1 − e²) / (2α)

(Stone Soup's ``Singer(damping_coeff=α, noise_diff_coeff=2 α σ_m²)``). Each
bracket cancels to its leading power of ``x`` (up to x⁵ for q̃11), so below
``x = 1`` the entries are evaluated from their Taylor series instead, whose
coefficients are worked exactly from the exponential series when the module
loads (:func:`_series`); above it the closed form loses at most a few digits
of 10⁻¹⁶. A long gap (``x`` large) is the exponentials' limit: the
acceleration forgotten (``e → 0``), F and Q finite.

Defaults (aircraft, :data:`MANOEUVRE_TIME`, :data:`ACCELERATION_STD`):
``τ = 20 s``, Singer's evasive manoeuvre ("lazy turn 60 s, evasive
manoeuvre 10–20 s, atmospheric turbulence 1 s", [Singer] §II), and
``σ_m² = A_max²/3 (1 + 4 P_max − P_0)`` ([Singer] eq 2) with
``A_max = 4 g`` (the largest manoeuvre of the aircraft preset's bank),
``P_max = 0.05`` and ``P_0 = 0.5``: ``σ_m = 0.483 A_max = 18.9 m/s²``.
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

SERIES_TERMS = 24
"""Terms of each series: the first left out is below 1/24! ≈ 1.6e-24 of the sum at x < 1."""

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


_Q_SERIES = {entry: _series(terms, power, True) for entry, (terms, power) in _BRACKETS.items()}
_F13_SERIES = _series(_F13[0], _F13[1], False)


def _polynomial(coefficients: FloatArray, x: FloatArray) -> FloatArray:
    result = np.zeros_like(x)
    for c in coefficients[::-1]:
        result = result * x + c
    return result


def _closed(entry: tuple[int, int], x: FloatArray, e: FloatArray) -> FloatArray:
    """The bracket of ``entry`` over ``2 x^p`` (module docstring), for x ≥ 1."""
    e2 = e * e
    if entry == (0, 0):
        return (1 - e2 + 2 * x + 2 * x**3 / 3 - 2 * x**2 - 4 * x * e) / (2 * x**5)
    if entry == (0, 1):
        return (e2 + 1 - 2 * e + 2 * x * e - 2 * x + x**2) / (2 * x**4)
    if entry == (0, 2):
        return (1 - e2 - 2 * x * e) / (2 * x**3)
    if entry == (1, 1):
        return (4 * e - 3 - e2 + 2 * x) / (2 * x**3)
    if entry == (1, 2):
        return (e2 + 1 - 2 * e) / (2 * x**2)
    return (1 - e2) / (2 * x)


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
        x = alpha * dt
        span = np.abs(dt)
        x_span = alpha * span
        near = x_span < SERIES_BELOW
        transition = np.zeros((*dt.shape, 3, 3))
        transition[..., 0, 0] = transition[..., 1, 1] = 1.0
        transition[..., 0, 1] = dt
        with np.errstate(over="ignore", invalid="ignore"):
            e = np.exp(-x)
            # (1 − e)/α = Δt (1 − e^{−x})/x; −expm1(−x)/x is exact to the last digits
            ratio = np.where(x == 0.0, 1.0, -np.expm1(-x) / np.where(x == 0.0, 1.0, x))
            transition[..., 1, 2] = dt * ratio
            far = np.where(np.abs(x) < SERIES_BELOW, 1.0, x)
            transition[..., 0, 2] = dt**2 * np.where(
                np.abs(x) < SERIES_BELOW,
                _polynomial(_F13_SERIES, x),
                (x - 1 + e) / far**2,
            )
            transition[..., 2, 2] = e
            e_span = np.exp(-x_span)
            far_span = np.where(near, 1.0, x_span)
            noise = np.empty((*dt.shape, 3, 3))
            for (i, j), coefficients in _Q_SERIES.items():
                power = 5 - i - j
                scaled = np.where(
                    near,
                    _polynomial(coefficients, x_span),
                    _closed((i, j), far_span, e_span),
                )
                noise[..., i, j] = noise[..., j, i] = self.q * span**power * scaled
        return transition, noise
