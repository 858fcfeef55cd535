"""Measurement models: what a sensor measures of a state, as an interface.

As Stone Soup's (``stonesoup.models.measurement``), a measurement model maps a
state of ``ndim_state`` components to a measurement of ``ndim_meas``
(:class:`MeasurementModel`): ``function(x)`` is ``h(x)``, ``jacobian(x)`` its
derivative ``∂h/∂x``, ``covar()`` the noise ``R`` of ``z = h(x) + v``, and
``mapping`` the state components of the position it sees. Both take a batch
of states of any shape ``S + (n,)``. A :class:`Detection`'s measurements carry
their model, as Stone Soup's ``Detection.measurement_model``.

- :class:`LinearGaussian` — ``z = H x + v`` ([MTT] eq 13), a position mapping
  of any dimension (or any H a model bank gives).
- :class:`Polar` — a radar at a site: range ρ, azimuth ``a`` (clockwise from
  north, radians) and, in 3-D, elevation ``e`` above the site's horizontal
  plane, optionally the range-rate ``ṙ``; the vector is ``(ρ, a[, e][, ṙ])``,
  the order of the wire (Stone Soup's is the reverse: elevation, bearing,
  range, range-rate; its bearing is counter-clockwise from x, which is our
  azimuth when its x is our north: the tests map one to the other).

The trackers are linear in the position (docs/algorithms.md §4): a model
that can be inverted to a position gives its measurements as **converted**
positions and covariances (:meth:`Polar.converted`, the converted-measurement
Kalman filter) and its range-rate as a sequential extended update
(:mod:`core.tracking.range_rate`, with :meth:`Polar.range_rate`).

:data:`MEASUREMENT_MODELS` builds them by the wire's ``measurement.kind``
from a sensor's site and the wire's parameters: a new measurement type is its
class here (or its module) with its ``for_sensor`` and one line there, plus
its wire model (``api_schemas.config``) and how its detections' fields make a
measurement vector (``app.inputs.detections``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from core.arrays import FloatArray
from core.errors import ModelConfigError


def check_covariance(matrix: FloatArray, name: str, *, definite: bool) -> None:
    """Refuse a matrix that is not symmetric, or not positive (semi-)definite."""
    if not np.allclose(matrix, matrix.T, rtol=1e-12, atol=1e-12):
        raise ModelConfigError(f"{name} must be symmetric")
    smallest = float(np.linalg.eigvalsh(matrix).min())
    scale = max(float(np.abs(matrix).max()), 1.0)
    if definite and smallest <= 0.0:
        raise ModelConfigError(f"{name} must be positive definite (smallest eigenvalue {smallest})")
    if not definite and smallest < -1e-12 * scale:
        raise ModelConfigError(f"{name} must be positive semi-definite (eigenvalue {smallest})")


def rotate_covariances(rotations: FloatArray, covariances: FloatArray) -> FloatArray:
    """``R P Rᵀ`` for stacks (N, k, k), symmetrised so the result is exactly symmetric."""
    turned = rotations @ covariances @ np.swapaxes(rotations, -1, -2)
    return np.asarray(0.5 * (turned + np.swapaxes(turned, -1, -2)), dtype=np.float64)


def read_only(array: ArrayLike) -> FloatArray:
    """A read-only float64 copy of ``array``: a model's arrays are its own and stay as
    built (a caller's array is not frozen, nor can a caller write into a model's)."""
    frozen = np.array(array, dtype=np.float64)
    frozen.setflags(write=False)
    return frozen


def _freeze(model: object, *names: str) -> None:
    """Replace the frozen dataclass ``model``'s arrays ``names`` (those not None) by
    :func:`read_only` copies."""
    for name in names:
        value = getattr(model, name)
        if value is not None:
            object.__setattr__(model, name, read_only(value))


def _variance(name: str, sigma: float, *, angle: bool = False) -> float:
    """σ² of the wire's ``name`` (an angle's σ in degrees, its variance in radians²), refused
    (located at ``name``) unless a positive finite number: a σ whose square underflows to 0
    or overflows gives no covariance."""
    try:
        with np.errstate(over="ignore", under="ignore"):
            variance = float(np.radians(sigma) ** 2) if angle else sigma**2
    except OverflowError:  # a Python float's square raises where numpy's is inf
        variance = math.inf
    if not (math.isfinite(variance) and variance > 0.0):
        raise ModelConfigError(
            f"{name} {sigma!r} has no usable variance: its square is {variance!r}, not a "
            "positive finite number",
            loc=(name,),
        )
    return variance


@runtime_checkable
class MeasurementModel(Protocol):
    """``z = h(x) + v``, ``v ~ N(0, R)`` of a state of ``ndim_state`` components."""

    @property
    def ndim_state(self) -> int:
        """n, the components of the state it measures."""
        ...

    @property
    def ndim_meas(self) -> int:
        """q, the components of a measurement."""
        ...

    @property
    def mapping(self) -> tuple[int, ...]:
        """The state components of the position the sensor sees."""
        ...

    def function(self, states: FloatArray) -> FloatArray:
        """``h(x)`` of states ``S + (n,)``: shape ``S + (q,)``."""
        ...

    def jacobian(self, states: FloatArray) -> FloatArray:
        """``∂h/∂x`` at states ``S + (n,)``: shape ``S + (q, n)``."""
        ...

    def covar(self) -> FloatArray:
        """R, shape (q, q)."""
        ...


@runtime_checkable
class ConvertedModel(MeasurementModel, Protocol):
    """A model whose measurements the trackers take as converted positions."""

    def converted(
        self, measurements: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray | None]:
        """Positions (N, d), their covariances (N, d, d) and range-rates (N,) or None."""
        ...


@dataclass(frozen=True, eq=False)
class LinearGaussian:
    """``z = H x + v``, ``v ~ N(0, R)`` ([MTT] eq 13), shared by every model of a bank.

    Attributes
    ----------
    matrix : ndarray, shape (q, n)
        H.
    noise_covariance : ndarray, shape (q, q)
        R, symmetric positive definite.

    Both are kept as read-only copies.
    """

    matrix: FloatArray
    noise_covariance: FloatArray

    def __post_init__(self) -> None:
        _freeze(self, "matrix", "noise_covariance")
        if self.matrix.ndim != 2:
            raise ModelConfigError("measurement matrix H must be 2-D")
        q = self.matrix.shape[0]
        if self.noise_covariance.shape != (q, q):
            raise ModelConfigError(
                f"measurement noise R must have shape ({q}, {q}), got {self.noise_covariance.shape}"
            )
        if not (np.all(np.isfinite(self.matrix)) and np.all(np.isfinite(self.noise_covariance))):
            raise ModelConfigError("measurement model must be finite")
        check_covariance(self.noise_covariance, "measurement noise R", definite=True)

    @classmethod
    def position(
        cls,
        variance: float,
        state_dim: int = 4,
        position_indices: Sequence[int] | None = None,
    ) -> LinearGaussian:
        """H picks the positions (every even component by default), ``R = variance · I``
        ([MTT] §6.1.1: variance 0.2)."""
        var = float(variance)
        if not np.isfinite(var) or var <= 0.0:
            raise ModelConfigError(
                f"measurement variance must be a positive finite number, got {var!r}"
            )
        indices = list(range(0, state_dim, 2) if position_indices is None else position_indices)
        return cls.mapped(state_dim, indices, var * np.eye(len(indices)))

    @classmethod
    def mapped(
        cls, ndim_state: int, mapping: Sequence[int], noise_covariance: FloatArray
    ) -> LinearGaussian:
        """H selects the state components ``mapping`` (Stone Soup's ``LinearGaussian``)."""
        h = np.zeros((len(mapping), ndim_state))
        h[np.arange(len(mapping)), list(mapping)] = 1.0
        return cls(h, np.asarray(noise_covariance, dtype=np.float64))

    @classmethod
    def for_sensor(
        cls, site: FloatArray, rotation: FloatArray | None, *, r: Sequence[Sequence[float]]
    ) -> LinearGaussian:
        """A Cartesian sensor of the ``[x, ẋ, …]`` state of ``len(site)`` axes: its
        detections are the positions, in the tracker's frame (its site and axes unused),
        with noise ``r`` (:data:`MEASUREMENT_MODELS`)."""
        state_dim = 2 * len(site)
        return cls.mapped(state_dim, range(0, state_dim, 2), np.asarray(r, dtype=np.float64))

    @property
    def dim(self) -> int:
        """Measurement dimension q."""
        return int(self.matrix.shape[0])

    @property
    def ndim_meas(self) -> int:
        """q."""
        return self.dim

    @property
    def ndim_state(self) -> int:
        """n."""
        return int(self.matrix.shape[1])

    @property
    def mapping(self) -> tuple[int, ...]:
        """The component each row of H weighs most (the one it selects, for a mapping)."""
        return tuple(int(column) for column in np.argmax(np.abs(self.matrix), axis=1))

    def function(self, states: FloatArray) -> FloatArray:
        """``H x``."""
        return np.asarray(np.asarray(states, dtype=np.float64) @ self.matrix.T, dtype=np.float64)

    def jacobian(self, states: FloatArray) -> FloatArray:
        """H at every state."""
        shape = np.shape(states)[:-1]
        return np.broadcast_to(self.matrix, (*shape, *self.matrix.shape)).copy()

    def covar(self) -> FloatArray:
        """R."""
        return self.noise_covariance


@dataclass(frozen=True, eq=False)
class Polar:
    """A radar at a site: ``(ρ, a[, e][, ṙ])`` of the position ``mapping`` (module docstring).

    Attributes
    ----------
    ndim_state : int
    mapping : tuple of 2 or 3 ints
        The state components of east, north (and up), in the tracker's frame:
        2 → range and azimuth, 3 → range, azimuth and elevation.
    noise_covar : ndarray (q, q)
        R, diagonal: σ_ρ², σ_a², [σ_e²,] [σ_ṙ²] (radians for the angles).
    translation_offset : ndarray (d,)
        The site, in the tracker's frame.
    rotation : ndarray (d, d), optional
        The site's axes in the tracker's frame (a site's ENU axes at another
        point of the Earth, ``app.geo.geodesy``): a vector ``w`` in the site's
        axes is ``rotation @ w`` in the tracker's. None: the same axes.
    velocity_mapping : tuple of d ints, optional
        The velocity components: with them the last component is the range-rate.

    The arrays are kept as read-only copies.
    """

    ndim_state: int
    mapping: tuple[int, ...]
    noise_covar: FloatArray
    translation_offset: FloatArray
    rotation: FloatArray | None = None
    velocity_mapping: tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        _freeze(self, "noise_covar", "translation_offset", "rotation")
        d = self._axes
        if d not in (2, 3):
            raise ModelConfigError(f"a polar model measures 2 or 3 positions, got {d}")
        if self.velocity_mapping is not None and len(self.velocity_mapping) != d:
            raise ModelConfigError(f"a polar model's velocity_mapping needs {d} components")
        used = (*self.mapping, *(self.velocity_mapping or ()))
        if any(not 0 <= index < self.ndim_state for index in used):
            raise ModelConfigError(
                f"state components {list(used)} must lie in [0, {self.ndim_state})"
            )
        q = self.ndim_meas
        if np.shape(self.noise_covar) != (q, q):
            raise ModelConfigError(f"polar noise must have shape ({q}, {q})")
        if np.any(self.noise_covar != np.diag(np.diagonal(self.noise_covar))):
            raise ModelConfigError("polar noise must be diagonal (independent σ per component)")
        if np.shape(self.translation_offset) != (d,) or not np.all(
            np.isfinite(self.translation_offset)
        ):
            raise ModelConfigError(f"the polar site must be {d} finite coordinates")
        if self.rotation is not None and np.shape(self.rotation) != (d, d):
            raise ModelConfigError(f"the polar rotation must be {d} × {d}")
        check_covariance(np.asarray(self.noise_covar), "polar noise", definite=True)

    @classmethod
    def of_axes(
        cls,
        site: Sequence[float] | FloatArray,
        variances: Sequence[float],
        rotation: FloatArray | None = None,
    ) -> Polar:
        """A radar at ``site`` (d = 2 or 3 coordinates) measuring the ``[x, ẋ, y, ẏ(, z, ż)]``
        state of d axes, with noise ``diag(variances)``: ``σ_ρ², σ_a²[, σ_e²]`` and, with
        one more, the range-rate's ``σ_ṙ²``."""
        d = len(site)
        with_rate = len(variances) > d
        return cls(
            ndim_state=2 * d,
            mapping=tuple(range(0, 2 * d, 2)),
            noise_covar=np.diag(np.asarray(variances, dtype=np.float64)),
            translation_offset=np.asarray(site, dtype=np.float64),
            rotation=rotation,
            velocity_mapping=tuple(range(1, 2 * d, 2)) if with_rate else None,
        )

    @classmethod
    def for_sensor(
        cls,
        site: FloatArray,
        rotation: FloatArray | None,
        *,
        sigma_range: float,
        sigma_azimuth_deg: float,
        sigma_elevation_deg: float | None = None,
        sigma_range_rate: float | None = None,
    ) -> Polar:
        """A radar at ``site`` (2 or 3 coordinates: the axes it measures) with its axes
        ``rotation``, its σ as the wire gives them (angles in degrees): the elevation's
        in 3-D only, with ``sigma_range_rate`` the range-rate (:data:`MEASUREMENT_MODELS`)."""
        variances = [
            _variance("sigma_range", sigma_range),
            _variance("sigma_azimuth_deg", sigma_azimuth_deg, angle=True),
        ]
        if len(site) == 3:
            if sigma_elevation_deg is None:
                raise ModelConfigError(
                    "a 3-D polar sensor needs sigma_elevation_deg", loc=("sigma_elevation_deg",)
                )
            variances.append(_variance("sigma_elevation_deg", sigma_elevation_deg, angle=True))
        if sigma_range_rate is not None:
            variances.append(_variance("sigma_range_rate", sigma_range_rate))
        return cls.of_axes(site, variances, rotation)

    @property
    def _axes(self) -> int:
        return len(self.mapping)

    @property
    def ndim_meas(self) -> int:
        """2 or 3 positions' worth, and one more with the range-rate."""
        return self._axes + (self.velocity_mapping is not None)

    def covar(self) -> FloatArray:
        """R."""
        return self.noise_covar

    @cached_property
    def _to_site(self) -> FloatArray | None:
        """``rotation⁻¹``: a vector in the tracker's axes in the site's. Not ``rotationᵀ``: a
        planar session's rotation is the horizontal block of a geodetic site's 3-D one
        (``app.sessions.translate.site_axes``), which is not orthonormal (|RᵀR − I| ≈ 1e-4
        at 80 km from the origin: 9 m of range at 50 km), and ``h`` must invert
        :meth:`converted`."""
        return None if self.rotation is None else read_only(np.linalg.inv(self.rotation))

    def _offsets(self, states: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``p − s`` in the tracker's axes and in the site's (``rotation⁻¹ (p − s)``)."""
        offset = np.asarray(states, dtype=np.float64)[..., list(self.mapping)]
        offset = offset - self.translation_offset
        turn = self._to_site
        local = offset if turn is None else offset @ turn.T
        return offset, local

    def function(self, states: FloatArray) -> FloatArray:
        """``ρ = |w|``, ``a = atan2(w_e, w_n)``, ``e = atan2(w_u, √(w_e² + w_n²))`` of the
        site-axes offset ``w``, and ``ṙ`` (:meth:`range_rate`)."""
        _, local = self._offsets(states)
        east, north = local[..., 0], local[..., 1]
        parts = [np.sqrt(np.sum(local * local, axis=-1)), np.arctan2(east, north)]
        if self._axes == 3:
            parts.append(np.arctan2(local[..., 2], np.hypot(east, north)))
        if self.velocity_mapping is not None:
            parts.append(self.range_rate(states)[1])
        return np.stack(parts, axis=-1)

    def jacobian(self, states: FloatArray) -> FloatArray:
        """``∂(ρ, a, e)/∂p = J_w rotation⁻¹`` with, for ``w = (x, y, z)`` (x east, y north):
        ``∂ρ/∂w = w/ρ``, ``∂a/∂w = (y, −x, 0)/(x² + y²)``,
        ``∂e/∂w = (−xz/(hρ²), −yz/(hρ²), h/ρ²)``, ``h = √(x² + y²)``; the range-rate's row
        from :meth:`range_rate`."""
        states = np.asarray(states, dtype=np.float64)
        _, local = self._offsets(states)
        x, y = local[..., 0], local[..., 1]
        horizontal2 = x * x + y * y
        rho2 = np.sum(local * local, axis=-1)
        rho = np.sqrt(rho2)
        rows = [local / rho[..., None]]
        zero = np.zeros_like(x)
        if self._axes == 2:
            rows.append(np.stack([y / horizontal2, -x / horizontal2], axis=-1))
        else:
            z = local[..., 2]
            horizontal = np.sqrt(horizontal2)
            rows.append(np.stack([y / horizontal2, -x / horizontal2, zero], axis=-1))
            scale = horizontal * rho2
            rows.append(np.stack([-x * z / scale, -y * z / scale, horizontal / rho2], axis=-1))
        block = np.stack(rows, axis=-2)  # (…, d, d): d(ρ, a[, e]) / dw
        turn = self._to_site
        if turn is not None:
            block = block @ turn
        jacobian = np.zeros((*states.shape[:-1], self.ndim_meas, self.ndim_state))
        jacobian[..., : self._axes, list(self.mapping)] = block
        if self.velocity_mapping is not None:
            jacobian[..., -1, :] = self.range_rate(states)[2]
        return jacobian

    def range_rate(self, states: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The range ``ρ``, the range-rate ``ṙ = uᵀ v`` (``u = (p − s)/ρ``) and its row of the
        Jacobian, ``∂ṙ/∂p = (v − ṙ u)/ρ``, ``∂ṙ/∂v = u``; shapes S, S, S + (n,). In the
        tracker's axes (ṙ does not depend on the site's). Nan at the site itself."""
        assert self.velocity_mapping is not None, "a polar model without range-rate"
        states = np.asarray(states, dtype=np.float64)
        offset, _ = self._offsets(states)
        distance = np.linalg.norm(offset, axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            line = offset / distance[..., None]
            velocity = states[..., list(self.velocity_mapping)]
            rate = np.sum(line * velocity, axis=-1)
            row = np.zeros_like(states)
            row[..., list(self.mapping)] = (velocity - rate[..., None] * line) / distance[..., None]
        row[..., list(self.velocity_mapping)] = line
        return distance, rate, row

    def inverse_function(self, measurements: FloatArray) -> FloatArray:
        """The positions ``s + rotation w`` of measurements ``(…, q)``, the inverse of
        ``h`` (Stone Soup's ``inverse_function``, without the velocity)."""
        return self.converted(measurements)[0]

    def converted(
        self, measurements: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray | None]:
        """Converted positions (N, d), their covariances (N, d, d) and range-rates (N,) of
        measurements ``(N, q)`` (NaN range-rate: none; None when none has one).

        In the site's axes ``w = ρ (cos e sin a, cos e cos a, sin e)`` (2-D:
        ``ρ (sin a, cos a)``) with the covariance ``J diag(σ_ρ², σ_a², σ_e²) Jᵀ``, J the
        Jacobian of that map at the measured point (the converted-measurement Kalman
        filter, Bar-Shalom, Li & Kirubarajan 2001 §1.6 / Lerro & Bar-Shalom 1993); then
        turned into the tracker's axes and placed at the site. Why not an EKF:
        docs/algorithms.md §7.7.
        """
        z = np.asarray(measurements, dtype=np.float64).reshape(-1, self.ndim_meas)
        rho = z[:, 0]
        azimuth = z[:, 1]
        sin_a, cos_a = np.sin(azimuth), np.cos(azimuth)
        noise = np.diagonal(self.noise_covar)[: self._axes]
        if self._axes == 2:
            positions = np.stack([rho * sin_a, rho * cos_a], axis=-1)
            # J = d(x, y)/d(ρ, a)
            jacobian = np.stack(
                [np.stack([sin_a, rho * cos_a], -1), np.stack([cos_a, -rho * sin_a], -1)], -2
            )
        else:
            elevation = z[:, 2]
            sin_e, cos_e = np.sin(elevation), np.cos(elevation)
            positions = np.stack([rho * cos_e * sin_a, rho * cos_e * cos_a, rho * sin_e], axis=-1)
            # J = d(x, y, z)/d(ρ, a, e)
            jacobian = np.stack(
                [
                    np.stack([cos_e * sin_a, rho * cos_e * cos_a, -rho * sin_e * sin_a], -1),
                    np.stack([cos_e * cos_a, -rho * cos_e * sin_a, -rho * sin_e * cos_a], -1),
                    np.stack([sin_e, np.zeros_like(rho), rho * cos_e], -1),
                ],
                -2,
            )
        covariances = (jacobian * noise[None, None, :]) @ np.swapaxes(jacobian, -1, -2)
        covariances = 0.5 * (covariances + np.swapaxes(covariances, -1, -2))
        if self.rotation is not None:
            positions = positions @ self.rotation.T
            covariances = rotate_covariances(
                np.broadcast_to(self.rotation, covariances.shape), covariances
            )
        rates = None
        if self.velocity_mapping is not None and not np.all(np.isnan(z[:, -1])):
            rates = z[:, -1].copy()
        return positions + self.translation_offset, covariances, rates


MEASUREMENT_MODELS: Mapping[str, Callable[..., MeasurementModel]] = {
    "cartesian": LinearGaussian.for_sensor,
    "polar": Polar.for_sensor,
}
"""The measurement model of a detecting sensor by the wire's ``measurement.kind``: each
takes the sensor's site and axes in the tracker's frame (``site`` of as many coordinates as
the state has axes, ``rotation`` or None) and the wire's parameters of that kind by keyword."""
