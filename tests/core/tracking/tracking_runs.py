"""Run a LocalTracker over a scenario and keep what the tracker tests check."""

from __future__ import annotations

from collections import Counter, defaultdict
from dataclasses import dataclass, field

from core.geometry import PolygonView
from core.simulation import CLUTTER, Region, Scan, Scenario
from core.tracking.config import LocalTrackerConfig
from core.tracking.track import TrackerStep
from core.tracking.tracker import LocalTracker


def rectangle(region: Region) -> PolygonView:
    """A scenario's axis-aligned rectangle as a polygon field of view."""
    (x0, x1), (y0, y1) = region
    return PolygonView(((x0, y0), (x1, y0), (x1, y1), (x0, y1)))


@dataclass
class TrackerRun:
    """Per-step outputs of a tracker over a scenario.

    Attributes
    ----------
    outputs : the TrackerStep of every scan, in order, with the scan's step.
    status : ``status[track_id][step]`` = (status, reason) at the end of that step's last scan.
    owners : ``owners[track_id]`` counts the target ids of the detections assigned to it.
    assigned : ``assigned[target_id]`` lists (step, track id or None) per detection of the target.
    """

    outputs: list[tuple[int, TrackerStep]] = field(default_factory=list)
    status: dict[str, dict[int, tuple[str, str]]] = field(default_factory=lambda: defaultdict(dict))
    owners: dict[str, Counter[int]] = field(default_factory=lambda: defaultdict(Counter))
    assigned: dict[int, list[tuple[int, str | None]]] = field(
        default_factory=lambda: defaultdict(list)
    )

    def track_of(self, target_id: int) -> str:
        """The track most of the target's detections went to."""
        counts = Counter(track for _, track in self.assigned[target_id] if track is not None)
        return counts.most_common(1)[0][0]

    def first_step(self, track_id: str, status: str) -> int:
        """First step at which the track had ``status``."""
        return min(step for step, (s, _) in self.status[track_id].items() if s == status)


def sensor_of(config: LocalTrackerConfig, scan: Scan) -> str | None:
    """The scan's sensor when the configuration names it, else the default sensor."""
    return scan.sensor if scan.sensor in config.fields_of_view else None


def run_tracker(scenario: Scenario, config: LocalTrackerConfig) -> TrackerRun:
    """Feed every scan of ``scenario`` to a fresh tracker (target ids are never shown to it)."""
    tracker = LocalTracker(config)
    run = TrackerRun()
    for scan in scenario.scans:
        output = tracker.step(scan.time, scan.measurements, sensor=sensor_of(config, scan))
        run.outputs.append((scan.step, output))
        for track in output.tracks:
            run.status[track.id][scan.step] = (track.status.value, track.reason.value)
        for target, track_id in zip(scan.target_ids.tolist(), output.assignment, strict=True):
            if target != CLUTTER:
                run.assigned[target].append((scan.step, track_id))
                if track_id is not None:
                    run.owners[track_id][target] += 1
    return run


def false_assignment_rate(run: TrackerRun, targets: tuple[int, ...]) -> tuple[int, int]:
    """(false, total) assignments after initiation ([MTT] §6.2.1's false decision rate).

    A target's track is the one most of its detections went to; a detection
    assigned to any other track (or to none) after the first two scans
    (two-point initiation) is a false assignment.
    """
    false = total = 0
    for target in targets:
        own = run.track_of(target)
        for _, track in run.assigned[target][2:]:
            total += 1
            false += track != own
    return false, total
