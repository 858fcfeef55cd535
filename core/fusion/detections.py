"""From a detecting sensor's local tracks to a track list for the fusion step.

A sensor that sends raw detections is tracked by the session itself
(:class:`~core.tracking.tracker.LocalTracker`, ALGORITHMS.md §4); its
*confirmed* local tracks — the ones updated by a detection in this scan —
then enter the same fusion step as a sensor's own track list (DESIGN.md "The
session engine"). Tentative tracks are not reported (they may be clutter),
nor coasting ones (a prediction is not an observation: the fused track counts
the miss instead).

The local tracker's state is ``[x, ẋ, y, ẏ]``; it is placed on the session's
state layout (two positions, two velocities). **Reading** for the pedestrian
models of [MTT] eq 26, whose second and fourth components are *headings*
scaled by each model's speed: the velocity is ``v = ŝ h`` with ŝ the
mode-weighted model speed, and the covariance follows the linearisation
``J P Jᵀ``, ``J = diag(1, ŝ_x, 1, ŝ_y)`` (the spread of the speeds between
models is not added).
"""

from __future__ import annotations

import numpy as np

from core.arrays import FloatArray
from core.belief import Frame
from core.errors import InvalidInput
from core.fusion.motion import StateLayout
from core.fusion.reports import ReportedTrack
from core.lifecycle import TrackStatus
from core.tracking.track import LocalTrack, TrackerStep
from core.tracking.tracker import LocalTracker


def check_layout_for_detections(layout: StateLayout) -> None:
    """A detecting sensor's local tracks need a 4-D layout with two positions and two velocities."""
    if layout.dim != 4 or len(layout.position) != 2 or len(layout.velocity) != 2:
        raise InvalidInput(
            "sensors that send detections need a state of dim 4 with 2 position and "
            f"2 velocity components (got dim {layout.dim}, position {list(layout.position)}, "
            f"velocity {list(layout.velocity)})"
        )


def _in_velocity_convention(
    tracker: LocalTracker, track: LocalTrack
) -> tuple[FloatArray, FloatArray]:
    """The local estimate ``[x, ẋ, y, ẏ]`` and its covariance (headings turned into velocities)."""
    preset = tracker.config.tracking_preset()
    if preset is None or preset.velocity_convention == "velocity":
        return track.state, track.covariance
    transitions = tracker.bank.transitions  # (r, 4, 4): x += s_x h_x ΔT
    interval = tracker.config.time_interval
    speed_x = float(track.mode_probabilities @ transitions[:, 0, 1]) / interval
    speed_y = float(track.mode_probabilities @ transitions[:, 2, 3]) / interval
    jacobian = np.diag([1.0, speed_x, 1.0, speed_y])
    return jacobian @ track.state, jacobian @ track.covariance @ jacobian.T


def local_track_report(
    tracker: LocalTracker, step: TrackerStep, layout: StateLayout, classes: Frame | None
) -> tuple[ReportedTrack, ...]:
    """The confirmed local tracks of a scan, on the session's layout, with their class mass."""
    order = (layout.position[0], layout.velocity[0], layout.position[1], layout.velocity[1])
    updated = {track_id for track_id in step.assignment if track_id is not None}
    reported = []
    for track in step.tracks:
        if track.status is not TrackStatus.CONFIRMED or track.id not in updated:
            continue
        local_state, local_covariance = _in_velocity_convention(tracker, track)
        state = np.zeros(layout.dim)
        covariance = np.zeros((layout.dim, layout.dim))
        state[list(order)] = local_state
        covariance[np.ix_(order, order)] = local_covariance
        mass = track.class_mass if classes is not None else None
        reported.append(ReportedTrack(track.id, state, covariance, class_mass=mass))
    return tuple(reported)
