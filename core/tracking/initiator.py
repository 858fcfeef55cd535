"""Two-point initiation of IMM tracks for the ``[x, ẋ, y, ẏ]`` state.

From two successive measurements ``z₀, z₁`` of each track (ΔT apart) and the
measurement noise R, the standard two-point difference gives position ``z₁``
(covariance R), velocity ``(z₁ − z₀)/ΔT`` (covariance 2R/ΔT²) and their
cross-covariance R/ΔT.

For the pedestrian speed models ([MTT] eq 26) the second and fourth state
components are headings: ``velocity="heading"`` sets them to the sign of the
displacement on each axis (0 when the target did not move), with variance
``heading_variance``.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from core.arrays import FloatArray
from core.errors import TrackingError
from core.tracking.imm import IMMState
from core.tracking.models import POSITION_INDICES, ModelBank

VELOCITY_INDICES = (1, 3)


def two_point_initiation(
    bank: ModelBank,
    first: FloatArray,
    second: FloatArray,
    time_interval: float,
    *,
    velocity: Literal["velocity", "heading"] = "velocity",
    heading_variance: float = 0.01,
    mode_probabilities: FloatArray | None = None,
) -> IMMState:
    """IMM states of T new tracks from two measurements each, shapes (T, 2) and (T, 2).

    Every model starts from the same Gaussian; mode probabilities default to uniform.
    """
    z0 = np.atleast_2d(np.asarray(first, dtype=np.float64))
    z1 = np.atleast_2d(np.asarray(second, dtype=np.float64))
    if z0.shape != z1.shape or z0.ndim != 2 or z0.shape[1] != 2:
        raise TrackingError(f"need two (T, 2) measurement arrays, got {z0.shape} and {z1.shape}")
    if bank.state_dim != 4 or bank.measurement.dim != 2:
        raise TrackingError("two-point initiation is for the [x, ẋ, y, ẏ] state with x, y measured")
    if not (np.isfinite(time_interval) and time_interval > 0.0):
        raise TrackingError(f"time_interval must be positive, got {time_interval!r}")
    tracks = z0.shape[0]
    r = bank.measurement.noise_covariance
    mean = np.zeros((tracks, 4))
    covariance = np.zeros((tracks, 4, 4))
    pos, vel = list(POSITION_INDICES), list(VELOCITY_INDICES)
    mean[:, pos] = z1
    covariance[np.ix_(range(tracks), pos, pos)] = r
    if velocity == "velocity":
        mean[:, vel] = (z1 - z0) / time_interval
        covariance[np.ix_(range(tracks), vel, vel)] = 2.0 * r / time_interval**2
        covariance[np.ix_(range(tracks), pos, vel)] = r / time_interval
        covariance[np.ix_(range(tracks), vel, pos)] = r / time_interval
    elif velocity == "heading":
        mean[:, vel] = np.sign(z1 - z0)
        covariance[:, vel, vel] = heading_variance
    else:
        raise TrackingError(f"velocity must be 'velocity' or 'heading', got {velocity!r}")
    mu = (
        np.full(bank.n_models, 1.0 / bank.n_models)
        if mode_probabilities is None
        else np.asarray(mode_probabilities, dtype=np.float64)
    )
    return IMMState.from_gaussian(mean, covariance, mu)
