"""Polar detections (range, azimuth[, elevation]) as converted Cartesian measurements.

A radar at a site reports range ``ρ`` (m), azimuth ``a`` (clockwise from
north at the site) and, in 3-D, elevation ``e`` above the site's horizontal
plane. The detection becomes a position in the session frame,

    x = x_s + ρ cos e sin a,   y = y_s + ρ cos e cos a,   z = z_s + ρ sin e,

with the covariance ``J diag(σ_ρ², σ_a², σ_e²) Jᵀ``, J the Jacobian of that
map at the measured point (the converted-measurement Kalman filter,
Bar-Shalom, Li & Kirubarajan 2001 §1.6 / Lerro & Bar-Shalom 1993). Every
layer downstream — gating, score, IMM update, credal classification — then
works with a linear position measurement and each detection's own R.

**Why not an EKF.** With the contract's sensors (σ_az ≈ 0.2°, ranges up to
50 km) the conversion's bias ``ρ(1 − e^{−σ_a²/2})`` is below 0.4 m against a
20 m range error, and ``ρσ_a²/σ_ρ`` (Lerro & Bar-Shalom's criterion) stays
under 0.03, where the converted filter and the EKF coincide to first order;
the conversion keeps the batched IMM linear, so every track × model is
updated in one vectorised pass. The range-bearing test holds our tracks
against Stone Soup's extended and unscented Kalman updaters on the same
detections.
"""

from __future__ import annotations

import numpy as np

from core.arrays import FloatArray


def polar_to_cartesian(
    ranges: FloatArray,
    azimuths_deg: FloatArray,
    sigmas: tuple[float, float],
    site: FloatArray,
    elevations_deg: FloatArray | None = None,
    sigma_elevation_deg: float | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Converted positions (N, d) and covariances (N, d, d) of polar detections.

    Parameters
    ----------
    ranges, azimuths_deg : arrays (N,)
    sigmas : (σ_range m, σ_azimuth degrees)
    site : (d,)
        The sensor's position in the session frame; d = 2, or 3 with elevations.
    elevations_deg, sigma_elevation_deg : 3-D only.
    """
    rho = np.asarray(ranges, dtype=np.float64)
    azimuth = np.radians(np.asarray(azimuths_deg, dtype=np.float64))
    sin_a, cos_a = np.sin(azimuth), np.cos(azimuth)
    sigma_range, sigma_azimuth = sigmas[0], np.radians(sigmas[1])
    if elevations_deg is None:
        positions = np.stack([rho * sin_a, rho * cos_a], axis=-1)
        # J = d(x, y)/d(ρ, a)
        jacobian = np.stack(
            [np.stack([sin_a, rho * cos_a], -1), np.stack([cos_a, -rho * sin_a], -1)], -2
        )
        noise = np.array([sigma_range**2, sigma_azimuth**2])
    else:
        assert sigma_elevation_deg is not None
        elevation = np.radians(np.asarray(elevations_deg, dtype=np.float64))
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
        noise = np.array([sigma_range**2, sigma_azimuth**2, np.radians(sigma_elevation_deg) ** 2])
    covariances = (jacobian * noise[None, None, :]) @ np.swapaxes(jacobian, -1, -2)
    covariances = 0.5 * (covariances + np.swapaxes(covariances, -1, -2))
    d = positions.shape[-1]
    return positions + np.asarray(site, dtype=np.float64)[:d], covariances
