"""The fused tracks' motion model on the session's state layout.

A session names which state components are positions and which are their
velocities (docs/design.md "Session config"). Between reports the fused tracks
are predicted with, per position axis, the discretised continuous white-noise
acceleration model of spectral density ``q`` (Bar-Shalom, Li & Kirubarajan
§6.2.2): ``F = [[1, Δt], [0, 1]]``, ``Q = q [[Δt³/3, Δt²/2], [Δt²/2, Δt]]``.
``constant_position`` uses ``F = I`` and ``Q = q Δt`` on the positions.
This is the one meaning of the session's ``motion.q`` (Stone Soup's
``ConstantVelocity(noise_diff_coeff=q)``), shared by the local
constant-velocity model of a session that tracks detections without a preset
(:mod:`core.tracking.models`, ``noise="continuous"``). Every Δt is one
closed-form step.
Components that are neither positions nor velocities are kept constant.

Prediction backwards in time (a late report, docs/algorithms.md §6.4) uses
``F(Δt)`` with Δt < 0 and adds ``Q(|Δt|)``: the uncertainty grows in both
directions.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from core.arrays import FloatArray
from core.errors import InvalidInput


class MotionKind(enum.StrEnum):
    """Motion models by their API names."""

    CONSTANT_VELOCITY = "constant_velocity"
    CONSTANT_POSITION = "constant_position"


@dataclass(frozen=True)
class StateLayout:
    """Dimension of the state and the indices of its positions and velocities."""

    dim: int
    position: tuple[int, ...]
    velocity: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        indices = (*self.position, *self.velocity)
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


@dataclass(frozen=True)
class MotionModel:
    """Predicts states and covariances of the session's layout."""

    layout: StateLayout
    kind: MotionKind = MotionKind.CONSTANT_VELOCITY
    q: float = 1.0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.q) and self.q > 0.0):
            raise InvalidInput(f"motion q must be a positive number, got {self.q!r}")
        if self.kind is MotionKind.CONSTANT_VELOCITY and not self.layout.velocity:
            raise InvalidInput(
                "constant_velocity motion needs velocity components in the state layout"
            )

    def matrices(self, dt: FloatArray) -> tuple[FloatArray, FloatArray]:
        """F and Q for every Δt (shape (T,) → (T, d, d) each)."""
        dt = np.asarray(dt, dtype=np.float64)
        d = self.layout.dim
        shift, powers, basis = self._structure
        transition = np.eye(d) + dt[..., None, None] * shift
        span = np.abs(dt)[..., None]
        noise = (span**powers / powers) @ basis.reshape(len(basis), d * d)
        return transition, self.q * noise.reshape(*dt.shape, d, d)

    @cached_property
    def _structure(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``E`` of ``F = I + Δt E``, and the terms of ``Q = q Σ_k |Δt|^{n_k} / n_k B_k``:
        the powers ``n_k`` and the matrices ``B_k``."""
        d = self.layout.dim
        position, velocity = list(self.layout.position), list(self.layout.velocity)
        shift = np.zeros((d, d))
        if self.kind is MotionKind.CONSTANT_POSITION:
            basis = np.zeros((1, d, d))
            basis[0, position, position] = 1.0
            return shift, np.array([1.0]), basis
        shift[position, velocity] = 1.0
        basis = np.zeros((3, d, d))
        basis[0, position, position] = 1.0  # |Δt|³/3
        basis[1, position, velocity] = basis[1, velocity, position] = 1.0  # |Δt|²/2
        basis[2, velocity, velocity] = 1.0  # |Δt|
        return shift, np.array([3.0, 2.0, 1.0]), basis

    def predict(
        self, states: FloatArray, covariances: FloatArray, dt: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """x ← F x, P ← F P Fᵀ + Q for every estimate, each with its own Δt.

        Raises
        ------
        InvalidInput
            The prediction is not finite (a time so far from the estimates, or a
            ``q`` so large, that the numbers overflow): the time is refused.
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
