"""Linear motion and measurement models, and model banks built from configuration.

State layout is ``[x, ẋ, y, ẏ]`` ([MTT] §6.1.1) for every model built here;
the measurement model picks positions.

- :func:`acceleration_input` — constant acceleration input ([MTT] eq 24):
  ``x_k = F x_{k−1} + B u + w``, ``Q = q B Bᵀ``.
- :func:`constant_velocity` — the same with ``u = 0``.
- :func:`speed_model` — the pedestrian speed models ([MTT] eq 26):
  ``x_k = A(s_x, s_y) x_{k−1} + w``.

**Reading (eq 26):** ``A(s_x, s_y)`` multiplies the second and fourth state
components by the speeds ``s_x, s_y`` (m/s), so with these models those
components are *headings* (unitless, ±1 along an axis), not velocities: the
position advances by ``s ΔT × heading``. We keep the equation literal; the
process noise is ``q B Bᵀ`` with the ``B`` of eq 24 ("the structure of the
dynamical models is close to the one used in the previous aircraft
example", [MTT] §6.3.1), which lets the headings wander slowly.

A :class:`ModelBank` stacks the models of an IMM: one shared measurement model
(H, R) and a mode transition matrix ``transition[i, j] = P(m_j at k | m_i at
k−1)`` (rows sum to 1; the same convention as filterpy's ``IMMEstimator.M``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from core.arrays import FloatArray
from core.errors import ModelConfigError

STATE_DIM = 4
"""Dimension of the ``[x, ẋ, y, ẏ]`` state of the models built here."""

POSITION_INDICES = (0, 2)
"""Indices of the positions in the state."""


def _as_matrix(values: Any, shape: tuple[int, ...], name: str) -> FloatArray:
    try:
        array = np.array(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ModelConfigError(f"{name} is not numeric: {exc}") from None
    if array.shape != shape:
        raise ModelConfigError(f"{name} must have shape {shape}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ModelConfigError(f"{name} must be finite")
    array.flags.writeable = False
    return array


def _check_covariance(matrix: FloatArray, name: str, *, definite: bool) -> None:
    if not np.allclose(matrix, matrix.T, rtol=1e-12, atol=1e-12):
        raise ModelConfigError(f"{name} must be symmetric")
    smallest = float(np.linalg.eigvalsh(matrix).min())
    scale = max(float(np.abs(matrix).max()), 1.0)
    if definite and smallest <= 0.0:
        raise ModelConfigError(f"{name} must be positive definite (smallest eigenvalue {smallest})")
    if not definite and smallest < -1e-12 * scale:
        raise ModelConfigError(f"{name} must be positive semi-definite (eigenvalue {smallest})")


def _check_positive(value: float, name: str) -> float:
    value = float(value)
    if not np.isfinite(value) or value <= 0.0:
        raise ModelConfigError(f"{name} must be a positive finite number, got {value!r}")
    return value


@dataclass(frozen=True)
class MotionModel:
    """A linear Gaussian motion model ``x_k = F x_{k−1} + B u + w``, ``w ~ N(0, Q)``.

    Attributes
    ----------
    name : str
    transition : ndarray, shape (n, n)
        F ([MTT] eq 12, 24) or A(s_x, s_y) (eq 26).
    input_offset : ndarray, shape (n,)
        The deterministic input term ``B u`` (zeros when the model has none).
    process_noise : ndarray, shape (n, n)
        Q.
    """

    name: str
    transition: FloatArray
    input_offset: FloatArray
    process_noise: FloatArray

    def __post_init__(self) -> None:
        n = self.transition.shape[0] if self.transition.ndim == 2 else -1
        if n < 1 or self.transition.shape != (n, n):
            raise ModelConfigError(f"model {self.name!r}: transition must be square")
        if self.input_offset.shape != (n,) or self.process_noise.shape != (n, n):
            raise ModelConfigError(
                f"model {self.name!r}: input offset must have shape ({n},) and process noise ({n}, {n})"
            )
        for array, label in (
            (self.transition, "transition"),
            (self.input_offset, "input offset"),
            (self.process_noise, "process noise"),
        ):
            if not np.all(np.isfinite(array)):
                raise ModelConfigError(f"model {self.name!r}: {label} must be finite")
        _check_covariance(self.process_noise, f"model {self.name!r} process noise", definite=False)


def input_matrix(time_interval: float) -> FloatArray:
    """B of [MTT] eq 24 for the state ``[x, ẋ, y, ẏ]`` and input ``[a_x, a_y]``."""
    dt = _check_positive(time_interval, "time_interval")
    return np.array([[dt**2 / 2, 0.0], [dt, 0.0], [0.0, dt**2 / 2], [0.0, dt]])


def _constant_velocity_matrix(dt: float, speeds: tuple[float, float] = (1.0, 1.0)) -> FloatArray:
    return np.array(
        [
            [1.0, speeds[0] * dt, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, speeds[1] * dt],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def _check_noise_intensity(noise_intensity: float, name: str) -> float:
    q = float(noise_intensity)
    if not np.isfinite(q) or q < 0.0:
        raise ModelConfigError(f"model {name!r}: noise_intensity must be >= 0, got {q!r}")
    return q


def acceleration_input(
    time_interval: float,
    acceleration: Sequence[float],
    noise_intensity: float,
    name: str,
) -> MotionModel:
    """Constant velocity driven by a constant acceleration input ([MTT] eq 24).

    Parameters
    ----------
    time_interval : float
        ΔT (s).
    acceleration : (a_x, a_y)
        The input u (m/s²).
    noise_intensity : float
        q in ``Q = q B Bᵀ`` ([MTT] §6.1.1 uses 0.005).
    name : str
    """
    dt = _check_positive(time_interval, "time_interval")
    u = _as_matrix(acceleration, (2,), f"model {name!r} acceleration")
    q = _check_noise_intensity(noise_intensity, name)
    b = input_matrix(dt)
    return MotionModel(
        name=name,
        transition=_constant_velocity_matrix(dt),
        input_offset=b @ u,
        process_noise=q * b @ b.T,
    )


def constant_velocity(
    time_interval: float, noise_intensity: float, name: str = "cv"
) -> MotionModel:
    """Constant velocity: eq 24 with ``u = 0`` and ``Q = q B Bᵀ``."""
    return acceleration_input(time_interval, (0.0, 0.0), noise_intensity, name)


def speed_model(
    time_interval: float,
    speeds: Sequence[float],
    noise_intensity: float,
    name: str,
) -> MotionModel:
    """Pedestrian speed model ``x_k = A(s_x, s_y) x_{k−1} + w`` ([MTT] eq 26).

    ``A`` has ``s_x ΔT`` and ``s_y ΔT`` where a constant-velocity F has ``ΔT``;
    the second and fourth state components are headings (see the module
    Reading). ``Q = q B Bᵀ`` with B of eq 24.
    """
    dt = _check_positive(time_interval, "time_interval")
    s = _as_matrix(speeds, (2,), f"model {name!r} speeds")
    q = _check_noise_intensity(noise_intensity, name)
    b = input_matrix(dt)
    return MotionModel(
        name=name,
        transition=_constant_velocity_matrix(dt, (float(s[0]), float(s[1]))),
        input_offset=np.zeros(STATE_DIM),
        process_noise=q * b @ b.T,
    )


@dataclass(frozen=True)
class LinearMeasurementModel:
    """``z = H x + v``, ``v ~ N(0, R)`` ([MTT] eq 13), shared by every model of a bank.

    Attributes
    ----------
    matrix : ndarray, shape (q, n)
        H.
    noise_covariance : ndarray, shape (q, q)
        R, symmetric positive definite.
    """

    matrix: FloatArray
    noise_covariance: FloatArray

    def __post_init__(self) -> None:
        if self.matrix.ndim != 2:
            raise ModelConfigError("measurement matrix H must be 2-D")
        q = self.matrix.shape[0]
        if self.noise_covariance.shape != (q, q):
            raise ModelConfigError(
                f"measurement noise R must have shape ({q}, {q}), got {self.noise_covariance.shape}"
            )
        if not (np.all(np.isfinite(self.matrix)) and np.all(np.isfinite(self.noise_covariance))):
            raise ModelConfigError("measurement model must be finite")
        _check_covariance(self.noise_covariance, "measurement noise R", definite=True)

    @property
    def dim(self) -> int:
        """Measurement dimension q."""
        return int(self.matrix.shape[0])

    @classmethod
    def position(
        cls,
        variance: float,
        state_dim: int = STATE_DIM,
        position_indices: Sequence[int] = POSITION_INDICES,
    ) -> LinearMeasurementModel:
        """H picks the positions, ``R = variance · I`` ([MTT] §6.1.1: variance 0.2)."""
        var = _check_positive(variance, "measurement variance")
        h = np.zeros((len(position_indices), state_dim))
        h[np.arange(len(position_indices)), list(position_indices)] = 1.0
        return cls(h, var * np.eye(len(position_indices)))


def mode_transition_matrix(n_models: int, stay: float = 0.95) -> FloatArray:
    """``stay`` on the diagonal, the rest spread evenly over the other modes (ALGORITHMS.md §4)."""
    if n_models < 1:
        raise ModelConfigError("a model bank needs at least one model")
    if not (np.isfinite(stay) and 0.0 <= stay <= 1.0):
        raise ModelConfigError(f"mode transition 'stay' must be in [0, 1], got {stay!r}")
    if n_models == 1:
        return np.ones((1, 1))
    off = (1.0 - stay) / (n_models - 1)
    matrix = np.full((n_models, n_models), off)
    np.fill_diagonal(matrix, stay)
    return matrix


@dataclass(frozen=True)
class ModelBank:
    """The models of an IMM with their shared measurement model and mode transitions.

    Attributes
    ----------
    models : tuple of MotionModel
        r models on one state space.
    measurement : LinearMeasurementModel
    mode_transition : ndarray, shape (r, r)
        ``mode_transition[i, j] = P(m_j at k | m_i at k−1)``; rows sum to 1.
    transitions, input_offsets, process_noises : ndarray
        The models stacked, shapes (r, n, n), (r, n), (r, n, n).
    """

    models: tuple[MotionModel, ...]
    measurement: LinearMeasurementModel
    mode_transition: FloatArray
    transitions: FloatArray = field(init=False, repr=False, compare=False)
    input_offsets: FloatArray = field(init=False, repr=False, compare=False)
    process_noises: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not self.models:
            raise ModelConfigError("a model bank needs at least one model")
        names = [model.name for model in self.models]
        if len(set(names)) != len(names):
            raise ModelConfigError(f"model names repeat: {names}")
        n = self.models[0].transition.shape[0]
        if any(model.transition.shape != (n, n) for model in self.models):
            raise ModelConfigError("every model of a bank must have the same state dimension")
        if self.measurement.matrix.shape[1] != n:
            raise ModelConfigError(
                f"measurement matrix has {self.measurement.matrix.shape[1]} columns, state has {n}"
            )
        r = len(self.models)
        transition = np.asarray(self.mode_transition, dtype=np.float64)
        if transition.shape != (r, r) or not np.all(np.isfinite(transition)):
            raise ModelConfigError(f"mode transition must be a finite ({r}, {r}) matrix")
        if np.any(transition < 0.0) or np.any(np.abs(transition.sum(axis=1) - 1.0) > 1e-9):
            raise ModelConfigError("mode transition rows must be non-negative and sum to 1")
        stacked = {
            "transitions": np.stack([m.transition for m in self.models]),
            "input_offsets": np.stack([m.input_offset for m in self.models]),
            "process_noises": np.stack([m.process_noise for m in self.models]),
        }
        for key, array in stacked.items():
            array.flags.writeable = False
            object.__setattr__(self, key, array)

    @property
    def names(self) -> tuple[str, ...]:
        """Model names, in bank order."""
        return tuple(model.name for model in self.models)

    @property
    def n_models(self) -> int:
        """r."""
        return len(self.models)

    @property
    def state_dim(self) -> int:
        """n."""
        return int(self.transitions.shape[1])

    @classmethod
    def from_config(cls, config: Mapping[str, Any]) -> ModelBank:
        """Build a bank from plain configuration (unknown keys are an error).

        Example::

            {"time_interval": 1.0,
             "measurement": {"variance": 0.2},
             "models": [{"kind": "constant_velocity", "name": "m1", "noise_intensity": 0.005},
                        {"kind": "acceleration_input", "name": "m2",
                         "acceleration": [19.62, 0], "noise_intensity": 0.005},
                        {"kind": "speed", "name": "walk", "speeds": [2, 0],
                         "noise_intensity": 0.005}],
             "mode_transition": {"stay": 0.95}}

        ``measurement`` is ``{"variance": v}`` (H picks x, y; R = v I) or
        ``{"matrix": H, "noise_covariance": R}``; ``mode_transition`` is
        ``{"stay": p}`` or an explicit r × r matrix.
        """
        _reject_unknown(config, {"time_interval", "measurement", "models", "mode_transition"}, "")
        dt = _check_positive(config.get("time_interval", 1.0), "time_interval")
        models_config = config.get("models")
        if not isinstance(models_config, Sequence) or not models_config:
            raise ModelConfigError("'models' must be a non-empty list")
        models = tuple(_model_from_config(dt, entry, i) for i, entry in enumerate(models_config))
        measurement = _measurement_from_config(config.get("measurement", {"variance": 1.0}))
        transition_config = config.get("mode_transition", {"stay": 0.95})
        if isinstance(transition_config, Mapping):
            _reject_unknown(transition_config, {"stay"}, "mode_transition.")
            transition = mode_transition_matrix(len(models), float(transition_config["stay"]))
        else:
            transition = _as_matrix(
                transition_config, (len(models), len(models)), "mode_transition"
            )
        return cls(models, measurement, transition)


def _reject_unknown(config: Mapping[str, Any], allowed: set[str], where: str) -> None:
    if not isinstance(config, Mapping):
        raise ModelConfigError(f"{where or 'configuration'} must be a mapping")
    unknown = sorted(set(config) - allowed)
    if unknown:
        raise ModelConfigError(
            f"unknown key(s) {[where + key for key in unknown]}; allowed: {sorted(allowed)}"
        )


def _model_from_config(dt: float, entry: Any, position: int) -> MotionModel:
    where = f"models[{position}]."
    if not isinstance(entry, Mapping):
        raise ModelConfigError(f"models[{position}] must be a mapping")
    kind = entry.get("kind")
    name = str(entry.get("name", f"m{position + 1}"))
    q = float(entry.get("noise_intensity", 0.0))
    if kind == "constant_velocity":
        _reject_unknown(entry, {"kind", "name", "noise_intensity"}, where)
        return constant_velocity(dt, q, name)
    if kind == "acceleration_input":
        _reject_unknown(entry, {"kind", "name", "noise_intensity", "acceleration"}, where)
        return acceleration_input(dt, entry.get("acceleration", (0.0, 0.0)), q, name)
    if kind == "speed":
        _reject_unknown(entry, {"kind", "name", "noise_intensity", "speeds"}, where)
        return speed_model(dt, entry.get("speeds", (0.0, 0.0)), q, name)
    raise ModelConfigError(
        f"{where}kind must be 'constant_velocity', 'acceleration_input' or 'speed', got {kind!r}"
    )


def _measurement_from_config(entry: Any) -> LinearMeasurementModel:
    _reject_unknown(entry, {"variance", "matrix", "noise_covariance"}, "measurement.")
    if "variance" in entry:
        if "matrix" in entry or "noise_covariance" in entry:
            raise ModelConfigError(
                "measurement: give either 'variance' or 'matrix' + 'noise_covariance'"
            )
        return LinearMeasurementModel.position(float(entry["variance"]))
    if "matrix" not in entry or "noise_covariance" not in entry:
        raise ModelConfigError(
            "measurement needs 'variance', or both 'matrix' and 'noise_covariance'"
        )
    h = np.array(entry["matrix"], dtype=np.float64)
    if h.ndim != 2:
        raise ModelConfigError("measurement.matrix must be 2-D")
    r = _as_matrix(
        entry["noise_covariance"], (h.shape[0], h.shape[0]), "measurement.noise_covariance"
    )
    return LinearMeasurementModel(_as_matrix(h, h.shape, "measurement.matrix"), r)
