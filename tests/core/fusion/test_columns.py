"""A scan's tracks as columns (:class:`~core.tracking.track.LocalTracks`,
:class:`~core.fusion.reports.FusedTracks`) say what the tracks say one by one.

The oracle of :func:`~core.fusion.detections.local_track_report` is a track-by-track reading
of the scan's :class:`~core.tracking.track.LocalTrack` values: each kept track's estimate
(its headings turned into velocities, :func:`heading_to_velocity`, for the pedestrian
preset) copied entry by entry into the session's layout — exactly equal, not close.
"""

from __future__ import annotations

import numpy as np
import pytest

from core.belief import Frame
from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.detections import KEPT, heading_to_velocity, local_order, local_track_report
from core.fusion.engine import SessionEngine
from core.fusion.motion import MotionModel, StateLayout
from core.fusion.reports import DetectionReport, FusedTracks
from core.lifecycle import TrackStatus
from core.simulation import aircraft_scenario, pedestrian_scenario
from core.tracking.config import LocalTrackerConfig
from core.tracking.track import TrackerStep
from core.tracking.tracker import LocalTracker

LAYOUTS = [StateLayout(4, (0, 2), (1, 3)), StateLayout(4, (3, 1), (0, 2))]
"""The tracker's own order and a shuffled one."""


def one_by_one(
    tracker: LocalTracker, step: TrackerStep, layout: StateLayout, *, every: bool
) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """The reported tracks read track by track, placed entry by entry."""
    headings = tracker.preset is not None and tracker.preset.velocity_convention == "heading"
    order = local_order(layout)
    reported = []
    for track in step.tracks:
        if every:
            if track.status not in KEPT:
                continue
        elif track.status is not TrackStatus.CONFIRMED or track.id not in step.updated:
            continue
        state, covariance = track.state, track.covariance
        if headings:
            state, covariance = heading_to_velocity(
                tracker.bank, track.mode_probabilities, state, covariance
            )
        placed, placed_covariance = np.zeros(layout.dim), np.zeros((layout.dim, layout.dim))
        for i, at in enumerate(order):
            placed[at] = state[i]
            for j, other in enumerate(order):
                placed_covariance[at, other] = covariance[i, j]
        reported.append((track.id, placed, placed_covariance))
    return reported


@pytest.mark.parametrize("preset", ["aircraft", "pedestrian"])
def test_the_reported_tracks_are_the_kept_tracks_placed_on_the_layout(preset: str) -> None:
    scenario = aircraft_scenario(seed=3) if preset == "aircraft" else pedestrian_scenario(seed=3)
    tracker = LocalTracker(LocalTrackerConfig(preset=preset))
    reported_any = 0
    for scan in scenario.scans[:40]:
        step = tracker.step(scan.time, scan.measurements)
        for layout in LAYOUTS:
            for every in (False, True):
                got = local_track_report(tracker, step, layout, None, every=every)
                expected = one_by_one(tracker, step, layout, every=every)
                assert [track.id for track in got] == [track_id for track_id, _, _ in expected]
                for track, (_, state, covariance) in zip(got, expected, strict=True):
                    np.testing.assert_array_equal(track.state, state)
                    np.testing.assert_array_equal(track.covariance, covariance)
                    assert track.class_mass is None
                reported_any += len(got)
    assert reported_any > 0


def test_the_columns_of_a_scan_are_its_tracks_in_id_order() -> None:
    tracker = LocalTracker(LocalTrackerConfig(preset="aircraft"))
    scenario = aircraft_scenario(seed=1)
    for scan in scenario.scans[:15]:
        step = tracker.step(scan.time, scan.measurements)
    columns = step.columns
    assert len(step.tracks) == len(columns) > 0
    numbers = [int(track.id.removeprefix(tracker.config.id_prefix)) for track in step.tracks]
    assert numbers == sorted(numbers)
    for index, track in enumerate(step.tracks):
        assert track.id == columns.ids[index] and track.status is columns.statuses[index]
        np.testing.assert_array_equal(track.state, columns.states[index])
        assert track.class_mass is columns.class_masses[index]
    # the session's classes: each reported track carries its local track's class mass
    reported = local_track_report(tracker, step, LAYOUTS[0], Frame(["a", "b"]), every=True)
    for track in reported:
        assert track.class_mass is step.track(track.id).class_mass


def test_fused_columns_give_back_the_views_they_are_made_of() -> None:
    engine = SessionEngine(
        FusionConfig(
            motion=MotionModel(LAYOUTS[0], q=100.0),
            sensors=(SensorSpec("radar", tracker=LocalTrackerConfig(preset="aircraft")),),
        )
    )
    for scan in aircraft_scenario(seed=0).scans[:12]:
        step = engine.apply_detections(DetectionReport(scan.sensor, scan.time, scan.measurements))
    assert isinstance(step.tracks, FusedTracks) and len(step.tracks) > 0
    views = tuple(step.tracks)
    again = FusedTracks.of(views)
    assert FusedTracks.of(step.tracks) is step.tracks
    for index, view in enumerate(views):
        assert step.tracks[index].id == view.id == again.ids[index]
        assert again.statuses[index] is view.status and again.reasons[index] is view.reason
        np.testing.assert_array_equal(again.states[index], view.state)
        np.testing.assert_array_equal(again.covariances[index], view.covariance)
        assert again.sources[index] == view.sources and again.scores[index] == view.score
    assert [view.id for view in step.tracks[1:]] == [view.id for view in views[1:]]
    assert step.tracks[-1].id == views[-1].id
    assert len(FusedTracks.of(())) == 0
