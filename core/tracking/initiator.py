"""Initiation of IMM tracks for the ``[x, ẋ, y, ẏ(, z, ż)]`` state: two-point and single-point.

Every axis is a ``(position, velocity)`` pair of the state (2 or 3 axes, or 1),
with its position measured (:mod:`core.tracking.models`).

From two successive measurements ``z₀, z₁`` of each track (ΔT apart) with
noise covariances R₀, R₁ (each detection's own, or both the bank's R), the
standard two-point difference gives position ``z₁`` (covariance R₁), velocity
``(z₁ − z₀)/ΔT`` (covariance (R₀ + R₁)/ΔT²) and their cross-covariance
R₁/ΔT (2R/ΔT² and R/ΔT when R₀ = R₁ = R). A polar radar's converted
detections are thin ellipses (σ_ρ along the line of sight, ρσ_a across it):
started from them, a track's first gates and hits are as tight as its
detections allow.

For the pedestrian speed models ([MTT] eq 26) the second and fourth state
components are headings: ``velocity="heading"`` sets them to the sign of the
displacement on each axis (0 when the target did not move), with variance
``heading_variance``; the convention may be given per axis (a 3-D
pedestrian's vertical axis is a velocity).

Single-point initiation ([HZ] §6 starts events from one observation and lets
the initiation stage confirm them): position ``z`` with covariance R (the
detection's own, or the bank's),
velocity 0 with a large variance ``velocity_std²`` per axis (no
cross-covariance), so that the first gate covers every speed up to a few
``velocity_std``.

:func:`pair_seeds` joins the unassigned detections of a scan with the seeds
(unassigned detections) of an earlier scan for two-point initiation: a
maximum-gain matching on the Euclidean distance, gated at the largest
distance a target at ``max_speed`` can travel plus a measurement-noise gate
(one bound for all pairs, or one per pair).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import numpy as np

from core.arrays import FloatArray, IntArray
from core.association.assignment import solve_dense
from core.errors import TrackingError
from core.tracking.imm import IMMState
from core.tracking.models import ModelBank, position_indices, velocity_indices

Convention = Literal["velocity", "heading"]


def _axes_of(bank: ModelBank, z: FloatArray, what: str) -> tuple[list[int], list[int]]:
    """Position and velocity indices of the bank's state, checked against measurements (T, q)."""
    axes = bank.axes
    pos = list(position_indices(axes))
    expected = np.zeros((len(pos), bank.state_dim))
    expected[np.arange(len(pos)), pos] = 1.0
    if bank.state_dim != 2 * axes or not np.array_equal(bank.measurement.matrix, expected):
        raise TrackingError(
            f"{what} is for the [x, ẋ, y, ẏ(, z, ż)] state with the positions measured"
        )
    if z.ndim != 2 or z.shape[1] != axes:
        raise TrackingError(f"need (T, {axes}) measurement arrays, got {z.shape}")
    return pos, list(velocity_indices(axes))


def _noises(bank: ModelBank, noises: FloatArray | None, tracks: int, what: str) -> FloatArray:
    """Each measurement's R, shape (T, q, q): ``noises`` or the bank's R for every one."""
    r = bank.measurement.noise_covariance
    if noises is None:
        return np.broadcast_to(r, (tracks, *r.shape))
    chosen = np.asarray(noises, dtype=np.float64)
    if chosen.shape != (tracks, *r.shape):
        raise TrackingError(f"{what} must have shape ({tracks}, {r.shape[0]}, {r.shape[1]})")
    return chosen


def two_point_initiation(
    bank: ModelBank,
    first: FloatArray,
    second: FloatArray,
    time_interval: float,
    *,
    first_noises: FloatArray | None = None,
    second_noises: FloatArray | None = None,
    velocity: Convention | Sequence[Convention] = "velocity",
    heading_variance: float = 0.01,
    mode_probabilities: FloatArray | None = None,
) -> IMMState:
    """IMM states of T new tracks from two measurements each, shapes (T, q) and (T, q).

    ``time_interval`` is the time between the two measurements;
    ``first_noises``, ``second_noises`` their covariances R₀, R₁ (T, q, q),
    by default the bank's R; ``velocity`` the convention of every axis, or one
    per axis. Every model starts from the same Gaussian; mode probabilities
    default to uniform.
    """
    z0 = np.atleast_2d(np.asarray(first, dtype=np.float64))
    z1 = np.atleast_2d(np.asarray(second, dtype=np.float64))
    if z0.shape != z1.shape:
        raise TrackingError(
            f"need two measurement arrays of one shape, got {z0.shape} and {z1.shape}"
        )
    pos, vel = _axes_of(bank, z1, "two-point initiation")
    if not (np.isfinite(time_interval) and time_interval > 0.0):
        raise TrackingError(f"time_interval must be positive, got {time_interval!r}")
    conventions = [velocity] * len(pos) if isinstance(velocity, str) else list(velocity)
    if len(conventions) != len(pos) or not set(conventions) <= {"velocity", "heading"}:
        raise TrackingError(
            f"velocity must be 'velocity' or 'heading', or one of them per axis, got {velocity!r}"
        )
    tracks, n = z0.shape[0], bank.state_dim
    r0 = _noises(bank, first_noises, tracks, "first_noises")
    r1 = _noises(bank, second_noises, tracks, "second_noises")
    mean = np.zeros((tracks, n))
    covariance = np.zeros((tracks, n, n))
    mean[:, pos] = z1
    covariance[np.ix_(range(tracks), pos, pos)] = r1
    moving = np.array([c == "velocity" for c in conventions])
    axis = np.flatnonzero(moving)
    heading = np.flatnonzero(~moving)
    if len(axis):
        p, v = [pos[a] for a in axis], [vel[a] for a in axis]
        rows = np.ix_(np.arange(tracks), axis, axis)
        block0, block1 = r0[rows], r1[rows]
        mean[:, v] = (z1[:, axis] - z0[:, axis]) / time_interval
        covariance[np.ix_(range(tracks), v, v)] = (block0 + block1) / time_interval**2
        covariance[np.ix_(range(tracks), p, v)] = block1 / time_interval
        covariance[np.ix_(range(tracks), v, p)] = np.swapaxes(block1, 1, 2) / time_interval
    if len(heading):
        h = [vel[a] for a in heading]
        mean[:, h] = np.sign(z1[:, heading] - z0[:, heading])
        covariance[:, h, h] = heading_variance
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
    noises: FloatArray | None = None,
    mode_probabilities: FloatArray | None = None,
) -> IMMState:
    """IMM states of T new tracks from one measurement each, shape (T, q) (module docstring);
    ``noises`` their covariances (T, q, q), by default the bank's R."""
    z = np.atleast_2d(np.asarray(measurements, dtype=np.float64))
    pos, vel = _axes_of(bank, z, "single-point initiation")
    if not (np.isfinite(velocity_std) and velocity_std > 0.0):
        raise TrackingError(f"velocity_std must be positive, got {velocity_std!r}")
    tracks, n = z.shape[0], bank.state_dim
    mean = np.zeros((tracks, n))
    mean[:, pos] = z
    covariance = np.zeros((tracks, n, n))
    covariance[np.ix_(range(tracks), pos, pos)] = _noises(bank, noises, tracks, "noises")
    covariance[:, vel, vel] = velocity_std**2
    mu = (
        np.full(bank.n_models, 1.0 / bank.n_models)
        if mode_probabilities is None
        else np.asarray(mode_probabilities, dtype=np.float64)
    )
    return IMMState.from_gaussian(mean, covariance, mu)


def pair_seeds(
    seeds: FloatArray, detections: FloatArray, max_distance: float | FloatArray
) -> tuple[IntArray, IntArray]:
    """Join seeds (k, q) with detections (m, q) closer than ``max_distance`` (module docstring).

    ``max_distance`` is one bound, or one per pair (k, m). Returns the matched
    ``(seed, detection)`` indices, sorted by seed; the matching minimises the
    total distance among pairs under their bounds.
    """
    if len(seeds) == 0 or len(detections) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty.copy()
    distance = np.linalg.norm(seeds[:, None, :] - detections[None, :, :], axis=-1)
    bound = np.broadcast_to(np.asarray(max_distance, dtype=np.float64), distance.shape)
    largest = float(bound.max())
    gain = np.where(distance <= bound, largest - distance + 1e-12, 0.0)
    return solve_dense(gain, solver="scipy")
