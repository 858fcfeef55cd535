"""A state layout and the motion of a whole state from one block per axis.

A session names which state components are positions, and which are their
velocities and accelerations (docs/design.md "Session config"). A
:class:`~core.models.transition.TransitionModel` gives the block of one axis
(its components in order: position, then velocity, then acceleration as the
model carries them); :class:`MappedMotion` places that block at each axis's
components (Stone Soup's ``mapping``): ``F`` and ``Q`` of the whole state are
the blocks on their indices, and components that belong to no block are kept
constant (``F = 1``, ``Q = 0``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from core.arrays import FloatArray, IntArray
from core.errors import InvalidInput
from core.models.transition import Component, TransitionModel


@dataclass(frozen=True)
class StateLayout:
    """Dimension of the state and the indices of its positions, velocities and accelerations."""

    dim: int
    position: tuple[int, ...]
    velocity: tuple[int, ...] = ()
    acceleration: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        indices = (*self.position, *self.velocity, *self.acceleration)
        if self.dim < 1:
            raise InvalidInput(f"state dim must be >= 1, got {self.dim}")
        if not self.position:
            raise InvalidInput("state layout needs at least one position component")
        if any(not 0 <= index < self.dim for index in indices):
            raise InvalidInput(f"state components {list(indices)} must lie in [0, {self.dim})")
        if len(set(indices)) != len(indices):
            raise InvalidInput(f"state components repeat: {list(indices)}")
        if self.velocity and len(self.velocity) != len(self.position):
            raise InvalidInput("give one velocity component per position component, or none")
        if self.acceleration and len(self.acceleration) != len(self.velocity):
            raise InvalidInput("give one acceleration component per velocity component, or none")

    def components(self, kind: Component) -> tuple[int, ...]:
        """The indices of the components of one kind, axis by axis."""
        return getattr(self, kind)  # type: ignore[no-any-return]

    def blocks(self, components: tuple[Component, ...]) -> IntArray:
        """The state indices of each axis's block of ``components``, shape (axes, k).

        Raises
        ------
        InvalidInput
            The layout lacks a kind of component the block needs.
        """
        for kind in components:
            if not self.components(kind):
                raise InvalidInput(f"the motion model needs {kind} components in the state layout")
        return np.array([self.components(kind) for kind in components], dtype=np.int64).T


@dataclass(frozen=True)
class MappedMotion:
    """A transition model on every axis of a state layout (module docstring)."""

    layout: StateLayout
    model: TransitionModel

    def __post_init__(self) -> None:
        self.layout.blocks(self.model.components)  # refuses a layout without the block's parts

    @cached_property
    def _indices(self) -> tuple[IntArray, IntArray]:
        """Row and column state indices of every block entry, shape (axes, k, k) each."""
        blocks = self.layout.blocks(self.model.components)
        return blocks[:, :, None], blocks[:, None, :]

    def matrices(self, dt: FloatArray) -> tuple[FloatArray, FloatArray]:
        """F and Q of the whole state for every Δt: shape S → S + (d, d) each."""
        dt = np.asarray(dt, dtype=np.float64)
        d = self.layout.dim
        block_f, block_q = self.model.matrices(dt)
        rows, cols = self._indices
        transition = np.broadcast_to(np.eye(d), (*dt.shape, d, d)).copy()
        noise = np.zeros((*dt.shape, d, d))
        transition[..., rows, cols] = block_f[..., None, :, :]
        noise[..., rows, cols] = block_q[..., None, :, :]
        return transition, noise

    def predict(
        self, states: FloatArray, covariances: FloatArray, dt: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """x ← F x, P ← F P Fᵀ + Q for every estimate, each with its own Δt.

        Raises
        ------
        InvalidInput
            The prediction is not finite (a time so far from the estimates, or a
            noise so large, that the numbers overflow): the time is refused.
        """
        with np.errstate(over="ignore", invalid="ignore"):
            transition, noise = self.matrices(dt)
            predicted = (transition @ states[..., None])[..., 0]
            covariance = transition @ covariances @ np.swapaxes(transition, -1, -2) + noise
            covariance = (covariance + np.swapaxes(covariance, -1, -2)) / 2.0
        if not (np.isfinite(predicted).all() and np.isfinite(covariance).all()):
            horizon = float(np.max(np.abs(dt))) if np.size(dt) else 0.0
            raise InvalidInput(
                f"time: predicting the tracks over {horizon:.6g} s overflows; "
                "give a time closer to the session's"
            )
        return np.asarray(predicted, dtype=np.float64), np.asarray(covariance, dtype=np.float64)
