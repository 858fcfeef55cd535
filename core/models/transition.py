"""Transition models: the motion of one position axis, as an interface.

A transition model describes one position axis by its **components** — the
position and the derivatives it carries, in order (``("position",)``,
``("position", "velocity")`` or ``("position", "velocity", "acceleration")``)
— and gives, for a batch of time steps Δt of any shape ``S``, the transition
``F(Δt)`` and the process noise ``Q(|Δt|)`` of that block, shapes ``S + (k, k)``
(:meth:`TransitionModel.matrices`). A state of several axes, in whatever
order a session lays its components out, is built from one block per axis by
:class:`core.models.layout.MappedMotion` (Stone Soup's ``mapping``).

A negative Δt predicts backwards (a late report, docs/algorithms.md §6.4):
``F(Δt)`` with Δt < 0, and ``Q(|Δt|)``: the uncertainty grows in both
directions.

Implementations:

- :class:`ConstantVelocity` — the discretised continuous white-noise
  acceleration model of spectral density ``q`` (Bar-Shalom, Li & Kirubarajan
  2001, §6.2.2): ``F = [[1, Δt], [0, 1]]``,
  ``Q = q [[Δt³/3, Δt²/2], [Δt²/2, Δt]]`` (Stone Soup's
  ``ConstantVelocity(noise_diff_coeff=q)``).
- :class:`ConstantPosition` — ``F = 1``, ``Q = q Δt`` (Stone Soup's
  ``RandomWalk``).
- :class:`~core.models.singer.Singer` — the acceleration an exponentially
  correlated (first-order Gauss–Markov) process, ``ȧ = −α a + w`` with
  ``α = 1/τ`` (Singer 1970). ``F`` and ``Q`` are exponentials in ``αΔt``, not
  polynomials in Δt (module :mod:`core.models.singer`).

The papers' IMM banks (:mod:`core.tracking.models`) are polynomial models of
the same interface over the whole ``[x, ẋ, y, ẏ(, z, ż)]`` state.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Protocol, runtime_checkable

import numpy as np

from core.arrays import FloatArray
from core.errors import InvalidInput

Component = Literal["position", "velocity", "acceleration"]
"""What a component of one axis's block is."""

CONSTANT_VELOCITY_POWERS = np.array([3.0, 2.0, 1.0])
"""The powers n of the Q terms |Δt|^n / n of :class:`ConstantVelocity` (pp, pv, vv)."""


@runtime_checkable
class TransitionModel(Protocol):
    """The motion of one position axis (module docstring)."""

    @property
    def components(self) -> tuple[Component, ...]:
        """The block's components, in order: the position first."""
        ...

    @property
    def q(self) -> float:
        """The spectral density of the white noise that drives the block's last component."""
        ...

    def matrices(self, dt: FloatArray) -> tuple[FloatArray, FloatArray]:
        """F(Δt) and Q(|Δt|) of the block for every Δt: shape S → S + (k, k) each."""
        ...


def _positive(value: float, name: str) -> float:
    number = float(value)
    if not (np.isfinite(number) and number > 0.0):
        raise InvalidInput(f"{name} must be a positive number, got {value!r}")
    return number


@dataclass(frozen=True)
class ConstantVelocity:
    """Continuous white-noise acceleration of spectral density ``q`` (module docstring)."""

    q: float = 1.0

    def __post_init__(self) -> None:
        _positive(self.q, "motion q")

    @property
    def components(self) -> tuple[Component, ...]:
        """Position and velocity."""
        return ("position", "velocity")

    def matrices(self, dt: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``F = [[1, Δt], [0, 1]]``, ``Q = q [[|Δt|³/3, |Δt|²/2], [|Δt|²/2, |Δt|]]``
        (Bar-Shalom et al. §6.2.2)."""
        dt = np.asarray(dt, dtype=np.float64)
        transition = np.zeros((*dt.shape, 2, 2))
        transition[..., 0, 0] = transition[..., 1, 1] = 1.0
        transition[..., 0, 1] = dt
        span = np.abs(dt)[..., None]
        terms = self.q * (span**CONSTANT_VELOCITY_POWERS / CONSTANT_VELOCITY_POWERS)
        noise = np.empty((*dt.shape, 2, 2))
        noise[..., 0, 0] = terms[..., 0]
        noise[..., 0, 1] = noise[..., 1, 0] = terms[..., 1]
        noise[..., 1, 1] = terms[..., 2]
        return transition, noise


@dataclass(frozen=True)
class ConstantPosition:
    """A random walk of the position: ``F = 1``, ``Q = q |Δt|``."""

    q: float = 1.0

    def __post_init__(self) -> None:
        _positive(self.q, "motion q")

    @property
    def components(self) -> tuple[Component, ...]:
        """The position alone."""
        return ("position",)

    def matrices(self, dt: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``F = 1``, ``Q = q |Δt|``."""
        dt = np.asarray(dt, dtype=np.float64)
        transition = np.ones((*dt.shape, 1, 1))
        return transition, (self.q * np.abs(dt))[..., None, None]
