"""From a detecting sensor's local tracks to a track list for the fusion step.

A sensor that sends raw detections is tracked by the session itself
(:class:`~core.tracking.tracker.LocalTracker`, docs/algorithms.md §4); its
*confirmed* local tracks — the ones updated by a detection in this scan —
then enter the same fusion step as a sensor's own track list (docs/design.md "The
session engine"). Tentative tracks are not reported (they may be clutter),
nor coasting ones (a prediction is not an observation: the fused track counts
the miss instead).

The local tracker's state is ``[x, ẋ, y, ẏ(, z, ż)]`` (one position/velocity
pair per axis, :mod:`core.tracking.models`); it is placed on the session's
state layout, which may order its components any way: local axis i goes to
``layout.position[i]`` and ``layout.velocity[i]`` (the detections' ``z``
lists the positions in that order). A detecting sensor's layout has exactly
one velocity per position and nothing else (``dim = 2 × positions``).

**Reading** for the pedestrian models of [MTT] eq 26, whose second and
fourth components are *headings* h scaled by each model's speed s: the
velocity reported for the track is its displacement over one nominal scan
ΔT per second, model by model: under model j, ``v_j = s_j h + w_j / ΔT``
with ``w_j`` the position part of model j's process noise over ΔT (variance
``Q_j,pp(ΔT)``), so ``[x, v]`` has mean ``J_j x̄`` and covariance
``J_j P Jᵀ_j + diag(0, Q_j,pp / ΔT²)``, ``J_j = diag(1, s_j)`` per axis; the
models are then moment-matched with the mode probabilities μ_j (the spread
of their velocities is added). The process-noise term keeps the covariance
positive definite when the likely models have a zero speed on an axis (a
pedestrian walking along x under ``(s_x, s_y) = (2, 0)``: under that model its
y velocity is exactly 0, and ``J P Jᵀ`` alone is singular).
"""

from __future__ import annotations

import numpy as np

from core.arrays import FloatArray
from core.belief import Frame
from core.errors import InvalidInput
from core.fusion.reports import ReportedTrack
from core.lifecycle import TrackStatus
from core.models import StateLayout
from core.tracking.models import ModelBank
from core.tracking.track import TrackerStep
from core.tracking.tracker import LocalTracker

KEPT = (TrackStatus.CONFIRMED, TrackStatus.COASTING, TrackStatus.PHANTOM)
"""The statuses of the tracks a central tracker keeps (and reports at every step)."""
DETECTION_AXES = (1, 2, 3)
"""Numbers of position components a detecting sensor's state may have."""


def check_layout_for_detections(layout: StateLayout) -> None:
    """A detecting sensor's local tracks need 1 to 3 positions, a velocity for each, nothing else."""
    axes = len(layout.position)
    if axes not in DETECTION_AXES or len(layout.velocity) != axes or layout.dim != 2 * axes:
        raise InvalidInput(
            "sensors that send detections need a state of 1 to 3 position components, one "
            "velocity component for each and nothing else (dim = 2 × positions); got dim "
            f"{layout.dim}, position {list(layout.position)}, velocity {list(layout.velocity)}"
        )


def local_order(layout: StateLayout) -> tuple[int, ...]:
    """Where each local component ``[x, ẋ, y, ẏ, …]`` goes in the session's state."""
    return tuple(
        index for pair in zip(layout.position, layout.velocity, strict=True) for index in pair
    )


def heading_to_velocity(
    bank: ModelBank,
    mode_probabilities: FloatArray,
    state: FloatArray,
    covariance: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """A heading-convention estimate as ``[x, v, …]`` (module Reading), moment-matched over models."""
    interval = bank.time_interval
    speeds = np.array([model.speeds for model in bank.models])  # (r, axes)
    n = bank.state_dim
    scales = np.ones((bank.n_models, n))
    scales[:, 1::2] = speeds
    floor = np.zeros((bank.n_models, n))
    position_noise = np.diagonal(bank.process_noises, axis1=1, axis2=2)[:, 0::2]  # Q_j,pp(ΔT)
    floor[:, 1::2] = position_noise / interval**2
    means = scales * state  # J_j x̄, (r, n)
    covariances = scales[:, :, None] * covariance[None] * scales[:, None, :]
    covariances[:, np.arange(n), np.arange(n)] += floor
    mu = np.asarray(mode_probabilities, dtype=np.float64)
    mean = mu @ means
    spread = means - mean
    combined = np.einsum("r,rij->ij", mu, covariances) + np.einsum(
        "r,ri,rj->ij", mu, spread, spread
    )
    return mean, 0.5 * (combined + combined.T)


def local_track_report(
    tracker: LocalTracker,
    step: TrackerStep,
    layout: StateLayout,
    classes: Frame | None,
    *,
    every: bool = False,
) -> tuple[ReportedTrack, ...]:
    """The confirmed local tracks updated in a scan, on the session's layout, with their
    class mass; ``every``: every track the tracker keeps (confirmed, coasting or phantom,
    updated or not: the central tracker's, docs/algorithms.md §8.9)."""
    order = np.array(local_order(layout), dtype=np.int64)
    preset = tracker.preset
    headings = preset is not None and preset.headings
    updated = set(step.updated)
    kept = [
        index
        for index, (track_id, status) in enumerate(
            zip(step.columns.ids, step.columns.statuses, strict=True)
        )
        if (status in KEPT if every else status is TrackStatus.CONFIRMED and track_id in updated)
    ]
    if not kept:
        return ()
    tracks = step.columns
    local_states, local_covariances = tracks.states[kept], tracks.covariances[kept]
    if headings:  # module Reading: each track's headings turned into velocities
        local = [
            heading_to_velocity(tracker.bank, tracks.mode_probabilities[index], state, covariance)
            for index, state, covariance in zip(kept, local_states, local_covariances, strict=True)
        ]
        local_states = np.stack([state for state, _ in local])
        local_covariances = np.stack([covariance for _, covariance in local])
    # every track placed on the layout at once (copies: no reported array is the tracker's)
    states = np.zeros((len(kept), layout.dim))
    covariances = np.zeros((len(kept), layout.dim, layout.dim))
    states[:, order] = local_states
    covariances[:, order[:, None], order[None, :]] = local_covariances
    return tuple(
        ReportedTrack(
            tracks.ids[index],
            state,
            covariance,
            class_mass=tracks.class_masses[index] if classes is not None else None,
        )
        for index, state, covariance in zip(kept, states, covariances, strict=True)
    )
