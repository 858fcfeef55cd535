"""A step is a transaction: a failure anywhere inside it, or a refused input, changes nothing.

Hypothesis drives a session (three sensors with views, a region, classes; the
scenario of ``test_restore_property``) and, before some reports, either makes
a step fail — a ``RuntimeError`` raised at the n-th call of one of the step's
parts, chosen at random — or sends a report the engine must refuse (bad
shapes, a stale time, all-zero class likelihoods, an overflowing state, a time
beyond the bound, an unknown sensor). After each, the export is byte-identical
to before (nothing logged: the step's result never came out); then the session
continues and must match, step for step and byte for byte, a twin that never
saw the failures. A second test does the same through a sensor's local tracker
(detections).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import partial
from typing import Any
from unittest import mock

import numpy as np
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

import core.fusion.engine as engine_module
import core.tracking.tracker as tracker_module
from core.errors import InvalidInput, StaleReport
from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.engine import SessionEngine
from core.fusion.motion import MotionModel
from core.fusion.reports import DetectionReport, ReportedTrack, TrackReport
from core.fusion.state import StateFusion
from core.fusion.table import EstimateTable
from core.fusion.track import FusedTrack
from core.simulation import aircraft_scenario
from core.tracking.associate import DetectionAssociator
from core.tracking.config import LocalTrackerConfig
from core.tracking.tracker import LocalTracker

from .engine_helpers import LAYOUT, serialise
from .test_restore_property import VARIANTS, scenario, session_config

ENGINE_PARTS: list[tuple[Any, str]] = [
    (SessionEngine, name)
    for name in (
        "_check",
        "_record",
        "_start",
        "_life_cycle",
        "_gate_log_dets",
        "_hand_over_to_phantoms",
        "_absorb_duplicates",
        "_merge",
        "_classify",
        "_result",
        "_keep",
    )
] + [
    (engine_module, "advance"),
    (engine_module, "hand_over"),
    (engine_module, "associate_report"),
    (engine_module, "initiated"),
    (engine_module, "hand_over_pairs"),
    (EstimateTable, "fused_at"),
    (EstimateTable, "write"),
    (EstimateTable, "add_rows"),
    (EstimateTable, "keep"),
    (FusedTrack, "set_estimate"),
    (FusedTrack, "remember"),
]
"""Where a failure may be injected: every part a step runs, in the engine and its state."""
TRACKER_PARTS: list[tuple[Any, str]] = (
    [(LocalTracker, name) for name in ("_update", "_hand_over", "_initiate", "_result")]
    + [
        (tracker_module, name)
        for name in ("predict_bank", "look", "seen_by", "advance", "hand_over_pairs")
    ]
    + [(DetectionAssociator, "associate"), (engine_module, "local_track_report")]
)
REFUSALS = ("shape", "stale", "zero_likelihoods", "overflow_state", "far_time", "unknown_sensor")
CONFIG = session_config(StateFusion.COVARIANCE_INTERSECTION, VARIANTS["classes"])
REPORTS = scenario(3, VARIANTS["classes"])[:45]


PHASES = (Phase.explicit, Phase.reuse, Phase.generate)
"""No shrinking: a failing example is reported as found (shrinking a session takes minutes)."""


class InjectedError(RuntimeError):
    pass


@contextmanager
def failing(owner: Any, name: str, at_call: int) -> Iterator[None]:
    """``owner.name`` raises :class:`InjectedError` at its ``at_call``-th call (1-based)."""
    real = getattr(owner, name)
    calls = 0

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        nonlocal calls
        calls += 1
        if calls == at_call:
            raise InjectedError(f"{name} call {calls}")
        return real(*args, **kwargs)

    with mock.patch.object(owner, name, wrapper):
        yield


def export_text(engine: SessionEngine) -> str:
    return json.dumps(engine.export(), sort_keys=True, allow_nan=False)


def refused(engine: SessionEngine, kind: str) -> tuple[TrackReport, type[Exception]]:
    assert engine.time is not None
    sensor, last = min(engine.last_report.items())
    later = engine.time + 0.5
    good = ReportedTrack("r", np.array([10.0, 1.0, 10.0, 0.0]), np.eye(4))
    tracks = {
        "shape": (ReportedTrack("r", np.zeros(3), np.eye(3)),),
        "zero_likelihoods": (
            good,
            ReportedTrack("z", np.zeros(4), np.eye(4), class_likelihoods=np.zeros(3)),
        ),
        "overflow_state": (ReportedTrack("o", np.array([1.7e308, 1e308, 0.0, 0.0]), np.eye(4)),),
    }.get(kind, (good,))
    time = {"stale": last, "far_time": 1e300}.get(kind, later)
    who = "s9" if kind == "unknown_sensor" else sensor
    return TrackReport(who, time, tracks), StaleReport if kind == "stale" else InvalidInput


def check_unchanged(engine: SessionEngine, attempt: Callable[[], object]) -> type[Exception] | None:
    """Run ``attempt``; if it raised, the export must be as before. Returns what it raised."""
    before = export_text(engine)
    try:
        attempt()
    except (InjectedError, InvalidInput, StaleReport) as error:
        assert export_text(engine) == before
        return type(error)
    return None


Action = tuple[str, int, int]
ACTIONS = st.lists(
    st.tuples(
        st.sampled_from(["none", "none", "inject", "refuse"]),
        st.integers(0, 10**6),
        st.integers(1, 3),
    ),
    min_size=len(REPORTS),
    max_size=len(REPORTS),
)


@settings(
    max_examples=6,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
    derandomize=True,
    phases=PHASES,
)
@given(actions=ACTIONS)
def test_failures_and_refusals_inside_track_list_steps_change_nothing(
    actions: list[Action],
) -> None:
    engine, twin = SessionEngine(CONFIG), SessionEngine(CONFIG)
    for report, (action, choice, at_call) in zip(REPORTS, actions, strict=True):
        if action == "inject":
            owner, name = ENGINE_PARTS[choice % len(ENGINE_PARTS)]
            with failing(owner, name, at_call):
                raised = check_unchanged(engine, partial(engine.apply, report))
            if raised is None:  # the part was called fewer times: the step went through
                twin.apply(report)
                assert export_text(engine) == export_text(twin)
                continue
        elif action == "refuse" and engine.time is not None:
            bad, error = refused(engine, REFUSALS[choice % len(REFUSALS)])
            raised = check_unchanged(engine, partial(engine.apply, bad))
            assert raised is not None and issubclass(raised, error)
        assert serialise(engine.apply(report)) == serialise(twin.apply(report))
        assert export_text(engine) == export_text(twin)
    assert engine.tracks


DETECTIONS = aircraft_scenario(seed=0)
DETECTION_CONFIG = FusionConfig(
    motion=MotionModel(LAYOUT, q=100.0),
    sensors=(SensorSpec("radar", tracker=LocalTrackerConfig(preset="aircraft")),),
)


def detections(index: int) -> DetectionReport:
    scan = DETECTIONS.scans[index]
    return DetectionReport(scan.sensor, scan.time, scan.measurements)


@settings(
    max_examples=4,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
    derandomize=True,
    phases=PHASES,
)
@given(
    actions=st.lists(
        st.tuples(st.booleans(), st.integers(0, 10**6), st.integers(1, 2)),
        min_size=12,
        max_size=12,
    )
)
def test_failures_inside_detection_steps_change_nothing(
    actions: list[tuple[bool, int, int]],
) -> None:
    engine, twin = SessionEngine(DETECTION_CONFIG), SessionEngine(DETECTION_CONFIG)
    parts = TRACKER_PARTS + ENGINE_PARTS
    for index, (inject, choice, at_call) in enumerate(actions):
        report = detections(index)
        if inject:
            owner, name = parts[choice % len(parts)]
            with failing(owner, name, at_call):
                raised = check_unchanged(engine, partial(engine.apply_detections, report))
            if raised is None:
                twin.apply_detections(report)
                assert export_text(engine) == export_text(twin)
                continue
        assert serialise(engine.apply_detections(report)) == serialise(
            twin.apply_detections(report)
        )
        assert export_text(engine) == export_text(twin)
    assert any(track["status"] == "confirmed" for track in engine.export()["tracks"])
