"""Restore-and-continue is bit-identical, wherever a session is interrupted.

The service keeps a session as a snapshot (:meth:`SessionEngine.export`, stored
as JSON text with sorted keys) plus the inputs applied since, and rebuilds the
engine from them after a restart, on another worker, or when a step fails. The
rebuilt session is the same session only if an engine restored at *any* point
continues exactly as one that was never interrupted.

Each case feeds random track lists of three sensors to two engines: one runs
uninterrupted; the other is rebuilt through sorted-key JSON before a random
third of the reports, is asked for pictures at other times, and is sent
reports it must refuse. After every report both return the same step JSON and
the same export, byte for byte; a refused report leaves the export as it was;
a peer rebuilt from the export draws the same pictures.

The scenarios hold what has broken restores before: late reports, equal times
across sensors (ties whose order a sorted-key store changes), -0.0 values,
fields of view and a region (blind zones, phantoms, hand-overs), terminations,
duplicate tracks merged, class masses, and refusals of reports whose tracks
cannot be predicted to the fusion time. Each case counts what it exercised and
asserts that everything it is meant to exercise happened (``EXERCISED`` and its
variant's ``exercises``), so that it cannot pass by testing nothing.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from dataclasses import dataclass, field, replace

import numpy as np
import pytest

from core.arrays import FloatArray
from core.belief import Frame, MassFunction
from core.errors import InvalidInput, StaleReport
from core.fusion.config import FusionConfig
from core.fusion.engine import LIVE, SessionEngine
from core.fusion.reports import (
    AssociationView,
    FusedTrackView,
    ReportedTrack,
    StepResult,
    TrackReport,
)
from core.fusion.state import StateFusion
from core.geometry import PolygonView, Sector
from core.lifecycle import LifeCycleConfig, StatusReason, TrackStatus

from .engine_helpers import make_config, serialise


def sector(origin: tuple[float, float], heading: float, half_angle: float, reach: float) -> Sector:
    return Sector(origin, heading, half_angle, range_min=0.0, range_max=reach)


SENSORS = ("s1", "s2", "s3")
"""The sensors that report; ``s4`` never does (its view lies inside s1's)."""
SILENT = "s4"
FOVS = {
    "s1": sector((0.0, 0.0), heading=0.0, half_angle=89.0, reach=170.0),
    "s2": sector((300.0, 0.0), heading=180.0, half_angle=89.0, reach=170.0),
    "s3": sector((150.0, 250.0), heading=270.0, half_angle=30.0, reach=300.0),
    SILENT: sector((0.0, 0.0), heading=0.0, half_angle=45.0, reach=60.0),
}
REGION = PolygonView(((-50.0, -200.0), (350.0, -200.0), (350.0, 150.0), (-50.0, 150.0)))
"""Views overlap in the middle; below them, between s1's and s2's, the region has a blind zone."""
MANAGEMENT = LifeCycleConfig(phantom_max_distance=80.0, phantom_min_speed=10.0)
"""A phantom lives 8 s: a fast target crosses the blind zone in time, a slow one does not."""
SIGMA = {"s1": 2.0, "s2": 3.0, "s3": 1.5}
CLASSES = Frame(["a", "b", "c"])

N_STEPS = 40
QUIET = 2.0
"""Targets appear from then on: the first reports are empty."""
N_TARGETS = 8
CLOCK_ADVANCES = (0.0, 0.25, 0.5, 1.0)
LATE_BY = (0.125, 0.25, 0.5, 1.0)
RESTORE_RATE = 0.3
PICTURE_RATE = 0.15
REFUSAL_RATE = 0.15
PICTURE_OFFSETS = (-1.0, -0.25, 0.0, 0.5, 2.0)


EXERCISED = (
    "restores",
    "pictures",
    "refusals",
    "refusals_with_no_live_track",
    "late",
    "equal_times",
    "negative_zeros",
    "phantoms",
    "terminations",
)
"""What every case must have done at least once (counted by :func:`run_twins`)."""
SEEDS = (0, 3)
"""Every seed tried exercises all of ``EXERCISED``; a duplicate is a narrow event (missed by
the association's gate, caught by the merge's), which these seeds' scenarios have."""


@dataclass(frozen=True)
class Variant:
    """What the reports carry besides states, and what that must exercise besides ``EXERCISED``.

    Attributes
    ----------
    classes : each track carries a class mass, which the association weighs
        (``denoeux``); s3 often names another class than s1 and s2.
    first_offset : a sensor's first report of each target is this far off in x;
        now and then it starts a second fused track, merged as a duplicate.
    exercises : what a case of the variant must have done too.
    """

    classes: bool = False
    first_offset: float = 0.0
    exercises: tuple[str, ...] = ()


VARIANTS = {
    "states": Variant(),
    "classes": Variant(classes=True, exercises=("classified",)),
    "duplicates": Variant(first_offset=15.0, exercises=("duplicates",)),
}


@dataclass(frozen=True)
class Target:
    """A true object at ``start`` at time ``first``, moving at constant velocity until ``last``."""

    start: FloatArray
    velocity: FloatArray
    first: float
    last: float
    label: str

    def position(self, time: float) -> FloatArray:
        return self.start + self.velocity * (time - self.first)


# ------------------------------------------------------------------ the scenario
def session_config(rule: StateFusion, variant: Variant) -> FusionConfig:
    """Three reporting sensors and a silent one, their views and the region."""
    config = make_config(
        [*SENSORS, SILENT],
        method="denoeux" if variant.classes else "gnn",
        options=None if variant.classes else {},
        fovs=FOVS,
        region=REGION,
        management=MANAGEMENT,
    )
    return replace(config, state_fusion=rule, classes=CLASSES if variant.classes else None)


def targets(rng: np.random.Generator) -> list[Target]:
    """Random targets in the region, and one that flies from s1's view through the blind zone."""
    crosser = Target(
        start=np.array([rng.uniform(20.0, 60.0), rng.uniform(-140.0, -125.0)]),
        velocity=np.array([rng.uniform(8.0, 14.0), 0.0]),
        first=QUIET,
        last=math.inf,
        label="a",
    )
    others = []
    for index in range(N_TARGETS - 1):
        first = rng.uniform(QUIET, QUIET + 8.0)
        others.append(
            Target(
                start=np.array([rng.uniform(0.0, 300.0), rng.uniform(-120.0, 120.0)]),
                velocity=np.array([rng.choice([-1.0, 1.0]) * rng.uniform(3.0, 10.0), rng.normal()]),
                first=first,
                last=first + rng.uniform(3.0, 20.0),
                label=CLASSES.labels[index % len(CLASSES)],
            )
        )
    return [crosser, *others]


def report_time(clock: float, rng: np.random.Generator) -> float:
    """The clock, often late by a fraction of a second, sometimes floored (equal times)."""
    time = clock
    if rng.uniform() < 0.3:
        time -= float(rng.choice(LATE_BY))
    if rng.uniform() < 0.2:
        time = float(math.floor(time))
    return time


def class_mass(sensor: str, target: Target, rng: np.random.Generator) -> MassFunction:
    """Mostly the target's class; s3 names the next class half of the time."""
    label = target.label
    if sensor == "s3" and rng.uniform() < 0.5:
        labels = CLASSES.labels
        label = labels[(labels.index(label) + 1) % len(labels)]
    return MassFunction.from_sets(CLASSES, [([label], 0.95), (CLASSES.labels, 0.05)])


@dataclass
class Reported:
    """What the sensors have reported so far: each one's last time, the targets each has
    reported, and how often it renumbered its track of each."""

    last: dict[str, float] = field(default_factory=dict)
    renumbered: Counter[tuple[str, int]] = field(default_factory=Counter)
    known: set[tuple[str, int]] = field(default_factory=set)


def scenario(seed: int, variant: Variant) -> list[TrackReport]:
    """The track lists of ``SENSORS`` on random targets, in arrival order.

    Each round of the clock, each sensor in a random order reports (85 %) at
    a time that may lag the clock, unless that would not be after its own
    previous report.
    """
    rng = np.random.default_rng(seed)
    truth = targets(rng)
    reported = Reported()
    reports = []
    clock = 0.0
    for _ in range(N_STEPS):
        clock += float(rng.choice(CLOCK_ADVANCES))
        for sensor in rng.permutation(SENSORS).tolist():
            time = report_time(clock, rng)
            if rng.uniform() < 0.15 or time <= reported.last.get(sensor, -math.inf):
                continue
            reported.last[sensor] = time
            tracks = track_list(sensor, time, truth, variant, reported, rng)
            reports.append(TrackReport(sensor, time, tracks))
    return reports


def track_list(
    sensor: str,
    time: float,
    truth: list[Target],
    variant: Variant,
    reported: Reported,
    rng: np.random.Generator,
) -> tuple[ReportedTrack, ...]:
    """``sensor``'s tracks at ``time``: the live targets in its view, each missed 10 % of the time.

    Its track ids are its own; now and then it renumbers a track, and half of
    those times its first report under the new id is far off.
    """
    tracks = []
    for number, target in enumerate(truth):
        position = target.position(time)
        if not target.first <= time < target.last or rng.uniform() < 0.1:
            continue
        if not FOVS[sensor].contains(position[None])[0]:
            continue
        key = (sensor, number)
        offset = 0.0 if key in reported.known else variant.first_offset
        reported.known.add(key)
        if rng.uniform() < 0.05:
            reported.renumbered[key] += 1
            if rng.uniform() < 0.5:
                offset += float(rng.normal(0.0, 30.0))
        state, covariance = noisy_estimate(target, position, SIGMA[sensor], rng)
        state[0] += offset
        mass = class_mass(sensor, target, rng) if variant.classes else None
        track_id = f"{sensor}-{number}-{reported.renumbered[key]}"
        tracks.append(ReportedTrack(track_id, state, covariance, class_mass=mass))
    return tuple(tracks)


def noisy_estimate(
    target: Target, position: FloatArray, sigma: float, rng: np.random.Generator
) -> tuple[FloatArray, FloatArray]:
    """A sensor's estimate of ``target``: a third of ``sigma`` of error, correlated x-y,
    and now and then a -0.0 (the y velocity, or the velocity cross-covariance)."""
    state = np.array(
        [
            position[0] + rng.normal(0.0, sigma / 3.0),
            target.velocity[0],
            position[1] + rng.normal(0.0, sigma / 3.0),
            target.velocity[1],
        ]
    )
    if rng.uniform() < 0.05:
        state[3] = -0.0
    covariance = np.diag([sigma**2, 1.0, (sigma * rng.uniform(0.5, 2.0)) ** 2, 1.0])
    covariance[0, 2] = covariance[2, 0] = rng.uniform(-0.3, 0.3) * sigma**2
    if rng.uniform() < 0.1:
        covariance[1, 3] = covariance[3, 1] = -0.0
    return state, covariance


# ------------------------------------------------------------ the two engines
def export_text(engine: SessionEngine) -> str:
    """The export as a store writes it: JSON text with sorted keys."""
    return json.dumps(engine.export(), sort_keys=True, allow_nan=False)


def through_store(engine: SessionEngine) -> SessionEngine:
    """``engine`` rebuilt from its export as a store keeps it."""
    return SessionEngine.restore(engine.config, json.loads(export_text(engine)))


def picture_text(time: float, views: tuple[FusedTrackView, ...]) -> str:
    """A picture as the JSON text of a step that shows it."""
    nothing = AssociationView(method="", pairs=(), new=(), missed=())
    return serialise(StepResult(seq=0, time=time, sensor="", tracks=views, association=nothing))


def check_pictures(engine: SessionEngine, rng: np.random.Generator) -> None:
    """Pictures at other times than the fusion time, alike on a peer rebuilt from the export."""
    assert engine.time is not None
    peer = through_store(engine)
    for offset in rng.choice(PICTURE_OFFSETS, size=int(rng.integers(1, 4))).tolist():
        time = engine.time + offset
        shown = picture_text(time, engine.picture(time))
        assert shown == picture_text(time, peer.picture(time)), time


def has_live_tracks(engine: SessionEngine) -> bool:
    return any(track.status in LIVE for track in engine.tracks)


def refused_reports(engine: SessionEngine) -> list[tuple[TrackReport, type[Exception], str]]:
    """Reports ``engine`` must refuse, with the error and message each must raise."""
    assert engine.time is not None
    sensor, last = min(engine.last_report.items())
    track = ReportedTrack("r", np.zeros(4), np.eye(4))
    not_finite = ReportedTrack("r", np.array([np.nan, 0.0, 0.0, 0.0]), np.eye(4))
    later = engine.time + 1.0
    refused = [
        (TrackReport("s9", later, (track,)), InvalidInput, "unknown sensor 's9'"),
        (TrackReport(sensor, later, (not_finite,)), InvalidInput, "state is not finite"),
        (TrackReport(sensor, last, (track,)), StaleReport, "not newer"),
        # times beyond the bound every prediction stays finite within (core.numerics)
        (TrackReport(SILENT, -1e300, (track,)), InvalidInput, "beyond the limit"),
        (TrackReport(sensor, 1e300, (track,)), InvalidInput, "beyond the limit"),
    ]
    return refused


def check_refusals(engine: SessionEngine, seen: Counter[str]) -> None:
    """Send ``engine`` reports it must refuse; each leaves its export as it was."""
    for report, error, message in refused_reports(engine):
        before = export_text(engine)
        with pytest.raises(error, match=message):
            engine.apply(report)
        assert export_text(engine) == before, (report.sensor, report.time)
        seen["refusals"] += 1
        seen["refusals_with_no_live_track"] += not has_live_tracks(engine)


def negative_zeros(values: FloatArray) -> int:
    return int(np.count_nonzero((values == 0.0) & np.signbit(values)))


def note_report(report: TrackReport, engine: SessionEngine, seen: Counter[str]) -> None:
    """Count what a report exercises: lateness, a time another sensor reported at, -0.0."""
    seen["late"] += engine.time is not None and report.time < engine.time
    seen["equal_times"] += any(
        time == report.time
        for sensor, time in engine.last_report.items()
        if sensor != report.sensor
    )
    seen["negative_zeros"] += sum(
        negative_zeros(track.state) + negative_zeros(track.covariance) for track in report.tracks
    )


def note_step(step: StepResult, seen: Counter[str]) -> None:
    """Count what a step exercises: phantoms, terminations, duplicates merged, classes."""
    for track in step.tracks:
        seen["phantoms"] += track.status is TrackStatus.PHANTOM
        seen["terminations"] += track.status is TrackStatus.TERMINATED
        seen["duplicates"] += track.reason is StatusReason.DUPLICATE
        seen["classified"] += track.classification is not None


def run_twins(
    config: FusionConfig, reports: list[TrackReport], rng: np.random.Generator
) -> Counter[str]:
    """Apply ``reports`` to an uninterrupted engine and to one restored at random points.

    ``rng`` chooses the interruptions. Asserts after every report that both
    gave the same step and have the same export; returns how often each
    exercised thing happened.
    """
    uninterrupted = SessionEngine(config)
    restored = SessionEngine(config)
    seen: Counter[str] = Counter()
    for index, report in enumerate(reports):
        if rng.uniform() < RESTORE_RATE:
            restored = through_store(restored)
            seen["restores"] += 1
        if restored.tracks and rng.uniform() < PICTURE_RATE:
            check_pictures(restored, rng)
            seen["pictures"] += 1
        # always while nothing is live: then only a late report's own tracks meet its horizon
        if restored.time is not None and (
            not has_live_tracks(restored) or rng.uniform() < REFUSAL_RATE
        ):
            check_refusals(restored, seen)
        note_report(report, uninterrupted, seen)
        expected = uninterrupted.apply(report)
        where = f"report {index}: {report.sensor} at {report.time}"
        assert serialise(restored.apply(report)) == serialise(expected), where
        assert export_text(restored) == export_text(uninterrupted), where
        note_step(expected, seen)
    return seen


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("rule", [rule.value for rule in StateFusion])
def test_a_session_restored_at_random_points_continues_bit_for_bit(
    rule: str, variant: str, seed: int
) -> None:
    chosen = VARIANTS[variant]
    config = session_config(StateFusion(rule), chosen)
    seen = run_twins(config, scenario(seed, chosen), np.random.default_rng(1000 + seed))
    missing = [name for name in (*EXERCISED, *chosen.exercises) if not seen[name]]
    assert not missing, f"the scenario exercised no {missing}: {dict(seen)}"
