"""Linear motion and measurement models over any time step, and model banks built from configuration.

State layout is ``[x, ẋ, y, ẏ]`` ([MTT] §6.1.1), or ``[x, ẋ, y, ẏ, z, ż]`` in
3-D (one ``(position, velocity)`` pair per axis, axes in order) for every
model built here; the measurement model picks positions.

Every model is a **function of the time step** Δt ≥ 0, in closed form and in
constant time whatever Δt (:meth:`MotionModel.at`, :meth:`ModelBank.at`), per
axis with the axis's input ``u`` and speed factor ``s``:

- ``F(Δt) = [[1, s Δt], [0, 1]]``;
- ``B(Δt) u = [u Δt²/2, u Δt]`` ([MTT] eq 24, ``B`` of the axis);
- ``Q(Δt)`` in one of two forms of the noise intensity ``q``:

  ``"discrete"`` — ``q B(Δt) B(Δt)ᵀ = q [[Δt⁴/4, Δt³/2], [Δt³/2, Δt²]]``,
  the form of [MTT] eq 24 (the discrete white-noise acceleration model of
  Bar-Shalom, Li & Kirubarajan §6.3.2: one acceleration per sampling
  interval, here the interval Δt since the track's previous scan). It is the
  paper's Q exactly at Δt = ΔT; F and Bu compose exactly over split steps,
  Q does not (one draw over Δt is not two over Δt/2).

  ``"continuous"`` — ``q [[Δt³/3, Δt²/2], [Δt²/2, Δt]]``, the continuous
  white-noise acceleration of spectral density ``q`` (Bar-Shalom et al.
  §6.2.2; Stone Soup's ``ConstantVelocity(noise_diff_coeff=q)``): the meaning
  of the session's ``motion.q``, and exact over split steps (predicting once
  by Δt equals predicting k times by Δt/k).

- :func:`acceleration_input` — constant acceleration input ([MTT] eq 24).
- :func:`constant_velocity` — the same with ``u = 0``.
- :func:`speed_model` — the pedestrian speed models ([MTT] eq 26):
  ``x_k = A(s_x, s_y) x_{k−1} + w``.

The **nominal scan period** ΔT (``time_interval``) is kept by each model only
where a formula needs one period: the matrices at ΔT (:attr:`MotionModel.transition`,
``process_noise``, ``input_offset``), and through them the steady state
S_ss of the modified distance (``core.tracking.tracker``), the velocity of a
heading track as its displacement per scan (``core.fusion.detections``) and
a preset's manoeuvre density (``core.tracking.presets``); and the **mode
transitions**, which are per nominal scan: over Δt the bank uses ``Π(Δt) = Π^{Δt/ΔT}`` (the
continuous-time Markov chain whose one-scan transition is Π), exactly Π at
Δt = ΔT. With the ``stay`` family (``stay`` on the diagonal, the rest spread
evenly), ``Π = λ I + (1 − λ) 11ᵀ/r`` with ``λ = stay − (1 − stay)/(r − 1)``
and ``Π^p = λ^p I + (1 − λ^p) 11ᵀ/r``. An explicit matrix takes its power
from its eigendecomposition; one without positive real eigenvalues has no
such power and is refused.

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

import functools
import math
import threading
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Literal

import numpy as np

from core.arrays import FloatArray
from core.errors import ModelConfigError
from core.models.measurement import LinearGaussian

LinearMeasurementModel = LinearGaussian
"""The banks' name of the linear measurement model (:mod:`core.models.measurement`)."""

NoiseForm = Literal["discrete", "continuous"]
NOISE_FORMS: tuple[NoiseForm, ...] = ("discrete", "continuous")

STATE_DIM = 4
"""Dimension of the 2-D ``[x, ẋ, y, ẏ]`` state."""

POSITION_INDICES = (0, 2)
"""Indices of the positions in the 2-D state."""

AXES = (1, 2, 3)
"""Numbers of position axes a model may have."""

KEPT_STEPS = 16
"""Time steps whose stacked bank matrices :meth:`ModelBank.at` keeps, for every tracker of
one bank together (each sensor's scan interval, and their jitter)."""

KEPT_BANKS = 64
"""Distinct banks (models and mode transitions) whose computed parts are kept and shared."""


def position_indices(axes: int) -> tuple[int, ...]:
    """Indices of the positions in the state of ``axes`` axes: ``(0, 2[, 4])``."""
    return tuple(range(0, 2 * axes, 2))


def velocity_indices(axes: int) -> tuple[int, ...]:
    """Indices of the velocities (or headings) in the state of ``axes`` axes: ``(1, 3[, 5])``."""
    return tuple(range(1, 2 * axes, 2))


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


def _check_positive(value: float, name: str) -> float:
    value = float(value)
    if not np.isfinite(value) or value <= 0.0:
        raise ModelConfigError(f"{name} must be a positive finite number, got {value!r}")
    return value


def _check_step(dt: float) -> float:
    step = float(dt)
    if not np.isfinite(step) or step < 0.0:
        raise ModelConfigError(f"time step must be finite and >= 0, got {dt!r}")
    return step


def _check_noise_intensity(noise_intensity: float, name: str) -> float:
    q = float(noise_intensity)
    if not np.isfinite(q) or q < 0.0:
        raise ModelConfigError(f"model {name!r}: noise_intensity must be >= 0, got {q!r}")
    return q


@dataclass(frozen=True)
class MotionMatrices:
    """A model (or a bank: stacked on a leading axis) at one time step Δt.

    Attributes
    ----------
    transition : F(Δt), shape (n, n) or (r, n, n)
    input_offset : B(Δt) u, shape (n,) or (r, n)
    process_noise : Q(Δt), shape (n, n) or (r, n, n)
    """

    transition: FloatArray
    input_offset: FloatArray
    process_noise: FloatArray


def _structure(
    speeds: FloatArray, accelerations: FloatArray, intensities: FloatArray, forms: Sequence[str]
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Coefficients of the closed forms (module docstring) of r models at once.

    Returns ``E`` (r, n, n) with ``F = I + Δt E``; ``b1, b2`` (r, n) with
    ``B u = Δt b1 + Δt² b2``; ``C`` (r, 4, n, n) with ``Q = Σ_k Δt^{k+1} C_k``.
    """
    models, axes = speeds.shape
    n = 2 * axes
    pos, vel = np.arange(0, n, 2), np.arange(1, n, 2)
    shift = np.zeros((models, n, n))
    shift[:, pos, vel] = speeds
    b1 = np.zeros((models, n))
    b2 = np.zeros((models, n))
    b1[:, vel] = accelerations
    b2[:, pos] = accelerations / 2.0
    noise = np.zeros((models, 4, n, n))
    for j, form in enumerate(forms):
        q = intensities[j]
        # (power of Δt) − 1 of the pp, pv, vv terms, and their coefficients
        if form == "discrete":  # q [[Δt⁴/4, Δt³/2], [Δt³/2, Δt²]]
            terms = ((3, q / 4.0), (2, q / 2.0), (1, q))
        else:  # q [[Δt³/3, Δt²/2], [Δt²/2, Δt]]
            terms = ((2, q / 3.0), (1, q / 2.0), (0, q))
        (k_pp, c_pp), (k_pv, c_pv), (k_vv, c_vv) = terms
        noise[j, k_pp, pos, pos] = c_pp
        noise[j, k_pv, pos, vel] = c_pv
        noise[j, k_pv, vel, pos] = c_pv
        noise[j, k_vv, vel, vel] = c_vv
    return shift, b1, b2, noise


def _evaluate(
    structure: tuple[FloatArray, FloatArray, FloatArray, FloatArray], dt: float
) -> MotionMatrices:
    shift, b1, b2, noise = structure
    n = shift.shape[-1]
    powers = np.array([dt, dt**2, dt**3, dt**4])
    transition = np.eye(n) + dt * shift
    offset = dt * b1 + dt**2 * b2
    covariance = np.einsum("k,rkij->rij", powers, noise)
    for array in (transition, offset, covariance):
        array.flags.writeable = False
    return MotionMatrices(transition, offset, covariance)


@dataclass(frozen=True)
class MotionModel:
    """A linear Gaussian motion model ``x_k = F(Δt) x_{k−1} + B(Δt) u + w``, ``w ~ N(0, Q(Δt))``.

    Attributes
    ----------
    name : str
    time_interval : float
        The nominal scan period ΔT (s) of :attr:`transition` and friends.
    acceleration : tuple of float
        The input ``u`` per axis (m/s², zeros for none).
    speeds : tuple of float
        The speed factor ``s`` per axis: F has ``s Δt`` where a constant-velocity
        F has Δt (1: the second component of the axis is a velocity; eq 26:
        a heading scaled by the speed).
    noise_intensity : float
        q (module docstring).
    noise : "discrete" | "continuous"
        The form of Q(Δt) (module docstring).
    """

    name: str
    time_interval: float
    acceleration: tuple[float, ...]
    speeds: tuple[float, ...]
    noise_intensity: float
    noise: NoiseForm = "discrete"

    def __post_init__(self) -> None:
        _check_positive(self.time_interval, f"model {self.name!r} time_interval")
        axes = len(self.speeds)
        if axes not in AXES or len(self.acceleration) != axes:
            raise ModelConfigError(
                f"model {self.name!r}: need 1 to 3 axes, one speed and one acceleration each "
                f"(got {len(self.speeds)} speeds, {len(self.acceleration)} accelerations)"
            )
        if not all(math.isfinite(v) for v in (*self.acceleration, *self.speeds)):
            raise ModelConfigError(f"model {self.name!r}: accelerations and speeds must be finite")
        _check_noise_intensity(self.noise_intensity, self.name)
        if self.noise not in NOISE_FORMS:
            raise ModelConfigError(f"model {self.name!r}: noise must be one of {NOISE_FORMS}")

    @property
    def axes(self) -> int:
        """Number of position axes."""
        return len(self.speeds)

    @property
    def dim(self) -> int:
        """State dimension n = 2 × axes."""
        return 2 * self.axes

    @cached_property
    def _structure(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        return _structure(
            np.array([self.speeds], dtype=np.float64),
            np.array([self.acceleration], dtype=np.float64),
            np.array([self.noise_intensity], dtype=np.float64),
            [self.noise],
        )

    def at(self, dt: float) -> MotionMatrices:
        """F(Δt), B(Δt) u and Q(Δt) in closed form (module docstring)."""
        stacked = _evaluate(self._structure, _check_step(dt))
        return MotionMatrices(
            stacked.transition[0], stacked.input_offset[0], stacked.process_noise[0]
        )

    @cached_property
    def _nominal(self) -> MotionMatrices:
        return self.at(self.time_interval)

    @property
    def transition(self) -> FloatArray:
        """F(ΔT) ([MTT] eq 12, 24) or A(s_x, s_y) (eq 26)."""
        return self._nominal.transition

    @property
    def input_offset(self) -> FloatArray:
        """B(ΔT) u (zeros when the model has no input)."""
        return self._nominal.input_offset

    @property
    def process_noise(self) -> FloatArray:
        """Q(ΔT)."""
        return self._nominal.process_noise


def input_matrix(time_interval: float, axes: int = 2) -> FloatArray:
    """B of [MTT] eq 24 for the state ``[x, ẋ, y, ẏ(, z, ż)]`` and input ``[a_x, a_y(, a_z)]``."""
    dt = _check_positive(time_interval, "time_interval")
    b = np.zeros((2 * axes, axes))
    for axis in range(axes):
        b[2 * axis, axis] = dt**2 / 2
        b[2 * axis + 1, axis] = dt
    return b


def _finite_axes(values: Any, name: str) -> tuple[float, ...]:
    """One finite number per axis, 1 to 3 of them (plain Python: a preset builds 13 models)."""
    try:
        items = tuple(float(v) for v in values)
    except (TypeError, ValueError):
        raise ModelConfigError(f"{name} must be a finite vector") from None
    if not all(math.isfinite(v) for v in items):
        raise ModelConfigError(f"{name} must be a finite vector")
    if len(items) not in AXES:
        raise ModelConfigError(f"{name} must have 1 to 3 components, got shape ({len(items)},)")
    return items


def acceleration_input(
    time_interval: float,
    acceleration: Sequence[float],
    noise_intensity: float,
    name: str,
    noise: NoiseForm = "discrete",
) -> MotionModel:
    """Constant velocity driven by a constant acceleration input ([MTT] eq 24).

    Parameters
    ----------
    time_interval : float
        The nominal ΔT (s).
    acceleration : (a_x, a_y) or (a_x, a_y, a_z)
        The input u (m/s²); its length is the number of axes.
    noise_intensity : float
        q ([MTT] §6.1.1 uses 0.005 in ``Q = q B Bᵀ``).
    name : str
    noise : the form of Q(Δt) (module docstring).
    """
    _check_positive(time_interval, "time_interval")
    values = _finite_axes(acceleration, f"model {name!r} acceleration")
    return MotionModel(
        name=name,
        time_interval=float(time_interval),
        acceleration=values,
        speeds=(1.0,) * len(values),
        noise_intensity=_check_noise_intensity(noise_intensity, name),
        noise=noise,
    )


def constant_velocity(
    time_interval: float,
    noise_intensity: float,
    name: str = "cv",
    *,
    axes: int = 2,
    noise: NoiseForm = "discrete",
) -> MotionModel:
    """Constant velocity: eq 24 with ``u = 0`` (``noise="continuous"``: the ``motion.q`` model)."""
    return acceleration_input(time_interval, (0.0,) * axes, noise_intensity, name, noise)


def speed_model(
    time_interval: float,
    speeds: Sequence[float],
    noise_intensity: float,
    name: str,
) -> MotionModel:
    """Pedestrian speed model ``x_k = A(s_x, s_y) x_{k−1} + w`` ([MTT] eq 26).

    ``A`` has ``s_x ΔT`` and ``s_y ΔT`` where a constant-velocity F has ``ΔT``;
    the second and fourth state components are headings (see the module
    Reading). ``Q = q B Bᵀ`` with B of eq 24. A third speed of 1 makes the
    vertical axis a plain constant velocity.
    """
    _check_positive(time_interval, "time_interval")
    values = _finite_axes(speeds, f"model {name!r} speeds")
    return MotionModel(
        name=name,
        time_interval=float(time_interval),
        acceleration=(0.0,) * len(values),
        speeds=values,
        noise_intensity=_check_noise_intensity(noise_intensity, name),
    )


def mode_transition_matrix(n_models: int, stay: float = 0.95) -> FloatArray:
    """``stay`` on the diagonal, the rest spread evenly over the other modes (docs/algorithms.md §4)."""
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


def _power_basis(transition: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(w, V, V⁻¹)`` with ``Π = V diag(w) V⁻¹`` and every ``w ≥ 0`` real, so that
    ``Π^p = V diag(w^p) V⁻¹`` is real for every p ≥ 0 (module docstring)."""
    if np.allclose(transition, transition.T, rtol=0.0, atol=1e-15):
        values, vectors = np.linalg.eigh(transition)
        inverse = vectors.T
    else:
        complex_values, complex_vectors = np.linalg.eig(transition)
        if np.max(np.abs(complex_values.imag), initial=0.0) > 1e-12:
            raise ModelConfigError(
                "mode transition has complex eigenvalues: it has no power for a fractional "
                "number of scans (give a matrix with real non-negative eigenvalues)"
            )
        values, vectors = complex_values.real, complex_vectors.real
        try:
            inverse = np.linalg.inv(vectors)
        except np.linalg.LinAlgError:
            raise ModelConfigError("mode transition is not diagonalisable") from None
    if np.min(values) < -1e-12:
        raise ModelConfigError(
            f"mode transition has a negative eigenvalue ({float(np.min(values)):.3g}): it has no "
            "power for a fractional number of scans (with 'stay', use stay ≥ 1/r)"
        )
    return np.clip(values, 0.0, None), vectors, inverse


class _BankCore:
    """What a bank computes from its models and mode transitions alone: the closed forms'
    coefficients, the eigenbasis of Π, the matrices at ΔT and the last :data:`KEPT_STEPS`
    steps asked for. Banks of the same models and Π share one (:func:`_bank_core`): a
    tracker rebuilt from its configuration (a restored session) builds none of it again.
    """

    def __init__(self, models: tuple[MotionModel, ...], transition: FloatArray) -> None:
        self.structure = _structure(
            np.array([m.speeds for m in models], dtype=np.float64),
            np.array([m.acceleration for m in models], dtype=np.float64),
            np.array([m.noise_intensity for m in models], dtype=np.float64),
            [m.noise for m in models],
        )
        self.mode_transition = transition
        self.power = _power_basis(transition)
        self.nominal = _evaluate(self.structure, models[0].time_interval)
        self.kept: OrderedDict[float, tuple[MotionMatrices, FloatArray]] = OrderedDict()
        self.lock = threading.Lock()  # shared by every tracker of one configuration

    def at(self, step: float, interval: float) -> tuple[MotionMatrices, FloatArray]:
        """The models and ``Π(Δt)`` at the checked step Δt (``interval``: the nominal ΔT)."""
        with self.lock:
            kept = self.kept
            found = kept.get(step)
            if found is not None:
                kept.move_to_end(step)
                return found
            matrices = _evaluate(self.structure, step)
            found = (matrices, self._transition_power(step / interval))
            kept[step] = found
            if len(kept) > KEPT_STEPS:
                kept.popitem(last=False)
            return found

    def _transition_power(self, scans: float) -> FloatArray:
        if scans == 1.0:
            power = np.array(self.mode_transition, dtype=np.float64)
        elif scans == 0.0:
            power = np.eye(len(self.mode_transition))
        else:
            values, vectors, inverse = self.power
            with np.errstate(under="ignore"):
                power = (vectors * values**scans) @ inverse
            power = np.clip(power, 0.0, None)
            power /= power.sum(axis=1, keepdims=True)
        power.flags.writeable = False
        return power


@functools.lru_cache(maxsize=KEPT_BANKS)
def _bank_core(models: tuple[MotionModel, ...], parameters: bytes, transition: bytes) -> _BankCore:
    del parameters  # part of the key only
    r = len(models)
    matrix = np.frombuffer(transition, dtype=np.float64).reshape(r, r).copy()
    matrix.flags.writeable = False
    return _BankCore(models, matrix)


@dataclass(frozen=True)
class ModelBank:
    """The models of an IMM with their shared measurement model and mode transitions.

    Attributes
    ----------
    models : tuple of MotionModel
        r models on one state space, with one nominal ΔT.
    measurement : LinearMeasurementModel
    mode_transition : ndarray, shape (r, r)
        ``mode_transition[i, j] = P(m_j at k | m_i at k−1)`` per nominal scan; rows sum to 1.
    transitions, input_offsets, process_noises : ndarray
        The models stacked at the nominal ΔT, shapes (r, n, n), (r, n), (r, n, n)
        (:meth:`at` gives them at any Δt).
    """

    models: tuple[MotionModel, ...]
    measurement: LinearMeasurementModel
    mode_transition: FloatArray
    transitions: FloatArray = field(init=False, repr=False, compare=False)
    input_offsets: FloatArray = field(init=False, repr=False, compare=False)
    process_noises: FloatArray = field(init=False, repr=False, compare=False)
    _core: _BankCore = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not self.models:
            raise ModelConfigError("a model bank needs at least one model")
        names = [model.name for model in self.models]
        if len(set(names)) != len(names):
            raise ModelConfigError(f"model names repeat: {names}")
        n = self.models[0].dim
        if any(model.dim != n for model in self.models):
            raise ModelConfigError("every model of a bank must have the same state dimension")
        interval = self.models[0].time_interval
        if any(model.time_interval != interval for model in self.models):
            raise ModelConfigError("every model of a bank must have the same time_interval")
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
        parameters = np.array(
            [(m.time_interval, m.noise_intensity, *m.acceleration, *m.speeds) for m in self.models],
            dtype=np.float64,
        )
        # the parameters' bytes keep apart what == would not (0.0 and −0.0)
        core = _bank_core(self.models, parameters.tobytes(), transition.tobytes())
        object.__setattr__(self, "_core", core)
        object.__setattr__(self, "transitions", core.nominal.transition)
        object.__setattr__(self, "input_offsets", core.nominal.input_offset)
        object.__setattr__(self, "process_noises", core.nominal.process_noise)

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

    @property
    def axes(self) -> int:
        """Number of position axes (n / 2)."""
        return self.state_dim // 2

    @property
    def time_interval(self) -> float:
        """The nominal scan period ΔT of the bank's models."""
        return self.models[0].time_interval

    def at(self, dt: float) -> MotionMatrices:
        """Every model at the time step Δt, stacked: F (r, n, n), B u (r, n), Q (r, n, n).

        Built in closed form in constant time whatever Δt; the last
        :data:`KEPT_STEPS` steps asked for are kept (one per scan interval).
        """
        return self._at(dt)[0]

    def mode_transition_at(self, dt: float) -> FloatArray:
        """``Π(Δt) = Π^{Δt/ΔT}`` (module docstring): Π itself at Δt = ΔT, I at Δt = 0."""
        return self._at(dt)[1]

    def _at(self, dt: float) -> tuple[MotionMatrices, FloatArray]:
        return self._core.at(_check_step(dt), self.time_interval)

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

        ``measurement`` is ``{"variance": v}`` (H picks the positions; R = v I) or
        ``{"matrix": H, "noise_covariance": R}``; ``mode_transition`` is
        ``{"stay": p}`` or an explicit r × r matrix; ``time_interval`` is the
        nominal ΔT. A ``constant_velocity`` model may give ``axes`` (default 2)
        and ``noise`` (``"discrete"`` or ``"continuous"``, module docstring).
        """
        _reject_unknown(config, {"time_interval", "measurement", "models", "mode_transition"}, "")
        dt = _check_positive(config.get("time_interval", 1.0), "time_interval")
        models_config = config.get("models")
        if not isinstance(models_config, Sequence) or not models_config:
            raise ModelConfigError("'models' must be a non-empty list")
        models = tuple(_model_from_config(dt, entry, i) for i, entry in enumerate(models_config))
        measurement = _measurement_from_config(
            config.get("measurement", {"variance": 1.0}), models[0].dim
        )
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
        _reject_unknown(entry, {"kind", "name", "noise_intensity", "axes", "noise"}, where)
        return constant_velocity(
            dt, q, name, axes=int(entry.get("axes", 2)), noise=entry.get("noise", "discrete")
        )
    if kind == "acceleration_input":
        _reject_unknown(entry, {"kind", "name", "noise_intensity", "acceleration"}, where)
        return acceleration_input(dt, entry.get("acceleration", (0.0, 0.0)), q, name)
    if kind == "speed":
        _reject_unknown(entry, {"kind", "name", "noise_intensity", "speeds"}, where)
        return speed_model(dt, entry.get("speeds", (0.0, 0.0)), q, name)
    raise ModelConfigError(
        f"{where}kind must be 'constant_velocity', 'acceleration_input' or 'speed', got {kind!r}"
    )


def _measurement_from_config(entry: Any, state_dim: int) -> LinearMeasurementModel:
    _reject_unknown(entry, {"variance", "matrix", "noise_covariance"}, "measurement.")
    if "variance" in entry:
        if "matrix" in entry or "noise_covariance" in entry:
            raise ModelConfigError(
                "measurement: give either 'variance' or 'matrix' + 'noise_covariance'"
            )
        return LinearMeasurementModel.position(float(entry["variance"]), state_dim)
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
