"""Converted polar detections (:meth:`core.models.measurement.Polar.converted`) against Stone Soup's range-bearing measurement models.

Stone Soup measures bearing counter-clockwise from the x axis; our azimuth is
clockwise from north, so ``bearing = 90° − azimuth``. The converted position
must be Stone Soup's ``inverse_function`` of the measurement, and the
converted covariance, mapped back through Stone Soup's own Jacobian of the
measurement function, must give the sensor's noise again.
"""

from __future__ import annotations

import numpy as np
from numpy.testing import assert_allclose
from stonesoup.models.measurement.nonlinear import (
    CartesianToBearingRange,
    CartesianToElevationBearingRange,
)
from stonesoup.types.detection import Detection
from stonesoup.types.state import State

from core.models.measurement import Polar


def assert_noise_recovered(mapped: np.ndarray, noise: np.ndarray) -> None:
    """``J C Jᵀ = R``, in units of R's standard deviations."""
    scale = 1.0 / np.sqrt(np.diag(noise))
    assert_allclose(mapped * np.outer(scale, scale), np.eye(len(noise)), rtol=0, atol=1e-6)


def measurement_jacobian(model: object, state: np.ndarray, mapping: list[int]) -> np.ndarray:
    """d h / d position of Stone Soup's measurement function, by central differences."""
    columns = []
    for index in mapping:
        step = np.zeros_like(state)
        step[index] = 1e-3
        plus = model.function(State(state + step), noise=False)  # type: ignore[attr-defined]
        minus = model.function(State(state - step), noise=False)  # type: ignore[attr-defined]
        columns.append(np.asarray(plus - minus, dtype=float).ravel() / 2e-3)
    return np.stack(columns, axis=-1)


def polar_to_cartesian(
    ranges: np.ndarray,
    azimuths_deg: np.ndarray,
    sigmas: tuple[float, float],
    site: np.ndarray,
    elevations_deg: np.ndarray | None = None,
    sigma_elevation_deg: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Positions and covariances of detections as the radar's model converts them."""
    columns = [ranges, np.radians(azimuths_deg)]
    variances = [sigmas[0] ** 2, np.radians(sigmas[1]) ** 2]
    if elevations_deg is not None and sigma_elevation_deg is not None:
        columns.append(np.radians(elevations_deg))
        variances.append(np.radians(sigma_elevation_deg) ** 2)
    positions, covariances, _ = Polar.of_axes(site, variances).converted(np.stack(columns, -1))
    return positions, covariances


SITE_2D = np.array([1500.0, -700.0])
SITE_3D = np.array([1500.0, -700.0, 35.0])


def test_two_dimensional_conversion_inverts_stone_soups_model() -> None:
    rng = np.random.default_rng(2)
    ranges = rng.uniform(100.0, 50_000.0, 30)
    azimuths = rng.uniform(-180.0, 360.0, 30)
    sigmas = (20.0, 0.2)
    positions, covariances = polar_to_cartesian(ranges, azimuths, sigmas, SITE_2D)
    noise = np.diag([np.radians(sigmas[1]) ** 2, sigmas[0] ** 2])
    model = CartesianToBearingRange(
        ndim_state=4, mapping=(0, 2), noise_covar=noise, translation_offset=SITE_2D[:, None]
    )
    for rho, azimuth, position, covariance in zip(
        ranges, azimuths, positions, covariances, strict=True
    ):
        bearing = np.radians(90.0 - azimuth)
        measured = Detection(np.array([[bearing], [rho]]), measurement_model=model)
        expected = model.inverse_function(measured).ravel()
        assert_allclose(position, expected[[0, 2]], rtol=0, atol=1e-6)
        state = np.array([[position[0]], [0.0], [position[1]], [0.0]])
        jacobian = measurement_jacobian(model, state, [0, 2])
        assert_noise_recovered(jacobian @ covariance @ jacobian.T, noise)


def test_three_dimensional_conversion_inverts_stone_soups_model() -> None:
    rng = np.random.default_rng(3)
    ranges = rng.uniform(500.0, 50_000.0, 20)
    azimuths = rng.uniform(0.0, 360.0, 20)
    elevations = rng.uniform(-5.0, 60.0, 20)
    positions, covariances = polar_to_cartesian(
        ranges, azimuths, (20.0, 0.2), SITE_3D, elevations, 0.3
    )
    noise = np.diag([np.radians(0.3) ** 2, np.radians(0.2) ** 2, 20.0**2])
    model = CartesianToElevationBearingRange(
        ndim_state=6, mapping=(0, 2, 4), noise_covar=noise, translation_offset=SITE_3D[:, None]
    )
    for rho, azimuth, elevation, position, covariance in zip(
        ranges, azimuths, elevations, positions, covariances, strict=True
    ):
        measured = Detection(
            np.array([[np.radians(elevation)], [np.radians(90.0 - azimuth)], [rho]]),
            measurement_model=model,
        )
        expected = model.inverse_function(measured).ravel()
        assert_allclose(position, expected[[0, 2, 4]], rtol=0, atol=1e-6)
        state = np.array([[position[0]], [0.0], [position[1]], [0.0], [position[2]], [0.0]])
        jacobian = measurement_jacobian(model, state, [0, 2, 4])
        assert_noise_recovered(jacobian @ covariance @ jacobian.T, noise)
