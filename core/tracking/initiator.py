"""Initiation of IMM tracks for the ``[x, ẋ, y, ẏ]`` state: two-point and single-point.

From two successive measurements ``z₀, z₁`` of each track (ΔT apart) and the
measurement noise R, the standard two-point difference gives position ``z₁``
(covariance R), velocity ``(z₁ − z₀)/ΔT`` (covariance 2R/ΔT²) and their
cross-covariance R/ΔT.

For the pedestrian speed models ([MTT] eq 26) the second and fourth state
components are headings: ``velocity="heading"`` sets them to the sign of the
displacement on each axis (0 when the target did not move), with variance
``heading_variance``.

Single-point initiation ([HZ] §6 starts events from one observation and lets
the initiation stage confirm them): position ``z`` with covariance R,
velocity 0 with a large variance ``velocity_std²`` per axis (no
cross-covariance), so that the first gate covers every speed up to a few
``velocity_std``.

:func:`pair_seeds` joins the unassigned detections of a scan with the seeds
(unassigned detections) of an earlier scan for two-point initiation: a
maximum-gain matching on the Euclidean distance, gated at the largest
distance a target at ``max_speed`` can travel plus a measurement-noise gate.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from core.arrays import FloatArray, IntArray
from core.association.assignment import solve_dense
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


def single_point_initiation(
    bank: ModelBank,
    measurements: FloatArray,
    velocity_std: float,
    *,
    mode_probabilities: FloatArray | None = None,
) -> IMMState:
    """IMM states of T new tracks from one measurement each, shape (T, 2) (module docstring)."""
    z = np.atleast_2d(np.asarray(measurements, dtype=np.float64))
    if z.ndim != 2 or z.shape[1] != 2:
        raise TrackingError(f"need a (T, 2) measurement array, got {z.shape}")
    if bank.state_dim != 4 or bank.measurement.dim != 2:
        raise TrackingError(
            "single-point initiation is for the [x, ẋ, y, ẏ] state with x, y measured"
        )
    if not (np.isfinite(velocity_std) and velocity_std > 0.0):
        raise TrackingError(f"velocity_std must be positive, got {velocity_std!r}")
    tracks = z.shape[0]
    pos, vel = list(POSITION_INDICES), list(VELOCITY_INDICES)
    mean = np.zeros((tracks, 4))
    mean[:, pos] = z
    covariance = np.zeros((tracks, 4, 4))
    covariance[np.ix_(range(tracks), pos, pos)] = bank.measurement.noise_covariance
    covariance[:, vel, vel] = velocity_std**2
    mu = (
        np.full(bank.n_models, 1.0 / bank.n_models)
        if mode_probabilities is None
        else np.asarray(mode_probabilities, dtype=np.float64)
    )
    return IMMState.from_gaussian(mean, covariance, mu)


def pair_seeds(
    seeds: FloatArray, detections: FloatArray, max_distance: float
) -> tuple[IntArray, IntArray]:
    """Join seeds (k, q) with detections (m, q) closer than ``max_distance`` (module docstring).

    Returns the matched ``(seed, detection)`` indices, sorted by seed; the
    matching minimises the total distance among pairs under the bound.
    """
    if len(seeds) == 0 or len(detections) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty.copy()
    distance = np.linalg.norm(seeds[:, None, :] - detections[None, :, :], axis=-1)
    gain = np.where(distance <= max_distance, max_distance - distance + 1e-12, 0.0)
    return solve_dense(gain, solver="scipy")
