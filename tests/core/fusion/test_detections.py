"""Sessions whose sensors send raw detections: local tracker → fusion step."""

from __future__ import annotations

import json

import numpy as np
import pytest

from core.belief import Frame
from core.errors import InvalidInput, StaleReport
from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.engine import SessionEngine
from core.fusion.motion import MotionModel
from core.fusion.reports import DetectionReport, StepResult
from core.simulation import aircraft_scenario
from core.tracking.config import LocalTrackerConfig

from .engine_helpers import LAYOUT, serialise

CLASSES = Frame(["liner", "bomber", "fighter"])


def aircraft_session() -> FusionConfig:
    # The fused tracks' white-acceleration density must cover 4g manoeuvres (~40 m/s²):
    # with q = 100 m²/s³ a one-second CV prediction error of ~20 m stays inside the gate.
    return FusionConfig(
        motion=MotionModel(LAYOUT, q=100.0),
        sensors=(SensorSpec("radar", tracker=LocalTrackerConfig(preset="aircraft")),),
        classes=CLASSES,
    )


def detections(scan_index: int) -> DetectionReport:
    scan = SCENARIO.scans[scan_index]
    return DetectionReport(scan.sensor, scan.time, scan.measurements)


SCENARIO = aircraft_scenario(seed=0)


def run_all(engine: SessionEngine, scans: range) -> list[StepResult]:
    return [engine.apply_detections(detections(index)) for index in scans]


def test_aircraft_detections_give_fused_tracks_with_the_paper_classes() -> None:
    engine = SessionEngine(aircraft_session())
    steps = run_all(engine, range(len(SCENARIO.scans)))
    # Target 2 (the manoeuvring one): its fused track ends classified as a fighter ([MTT] Fig 15).
    at_step_99 = steps[99]
    truth = SCENARIO.truth(2).state_at(99)
    nearest = min(
        at_step_99.tracks, key=lambda t: float(np.hypot(*(t.state[[0, 2]] - truth[[0, 2]])))
    )
    assert float(np.hypot(*(nearest.state[[0, 2]] - truth[[0, 2]]))) < 5.0
    assert nearest.classification is not None and nearest.classification.decision == "fighter"
    assert nearest.classification.pignistic[2] >= 0.9
    # Target 1 flies straight: liner, bomber and fighter stay undecided (BetP ≈ 1/3 each).
    truth_1 = SCENARIO.truth(1).state_at(99)
    straight = min(
        at_step_99.tracks, key=lambda t: float(np.hypot(*(t.state[[0, 2]] - truth_1[[0, 2]])))
    )
    assert straight.classification is not None
    np.testing.assert_allclose(straight.classification.pignistic, [1 / 3] * 3, atol=0.1)
    # Four aircraft at step 80 (targets 3 and 4 appeared at 30 and 70): four confirmed fused tracks.
    confirmed = [t for t in steps[80].tracks if t.status.value == "confirmed"]
    assert len(confirmed) == 4
    # Target 2 keeps one fused id through both manoeuvres (steps 50-54 and 70-75).
    ids_of_target_2 = set()
    for index in range(40, 100):
        truth_now = SCENARIO.truth(2).state_at(index)[[0, 2]]
        near = [
            t.id for t in steps[index].tracks if np.hypot(*(t.state[[0, 2]] - truth_now)) < 50.0
        ]
        ids_of_target_2.update(near)
    assert len(ids_of_target_2) == 1, ids_of_target_2


def test_detections_export_restore_continue_is_exact() -> None:
    config = aircraft_session()
    uninterrupted = SessionEngine(config)
    expected = [serialise(step) for step in run_all(uninterrupted, range(60))]
    first = SessionEngine(config)
    run_all(first, range(35))
    restored = SessionEngine.restore(config, json.loads(json.dumps(first.export())))
    assert [serialise(step) for step in run_all(restored, range(35, 60))] == expected[35:]


def test_detection_errors_change_nothing() -> None:
    engine = SessionEngine(aircraft_session())
    run_all(engine, range(3))
    before = json.dumps(engine.export())
    with pytest.raises(StaleReport):
        engine.apply_detections(DetectionReport("radar", SCENARIO.scans[1].time, np.zeros((1, 2))))
    with pytest.raises(InvalidInput, match="unknown sensor"):
        engine.apply_detections(DetectionReport("lidar", 10.0, np.zeros((1, 2))))
    with pytest.raises(InvalidInput):
        engine.apply_detections(
            DetectionReport("radar", SCENARIO.scans[3].time, np.full((1, 2), np.nan))
        )
    assert json.dumps(engine.export()) == before


def test_a_track_list_sensor_cannot_send_detections_and_layouts_are_checked() -> None:
    engine = SessionEngine(FusionConfig(motion=MotionModel(LAYOUT), sensors=(SensorSpec("s1"),)))
    with pytest.raises(InvalidInput, match="sends track lists"):
        engine.apply_detections(DetectionReport("s1", 1.0, np.zeros((1, 2))))
    with pytest.raises(InvalidInput, match="classifies into"):
        FusionConfig(
            motion=MotionModel(LAYOUT),
            sensors=(SensorSpec("radar", tracker=LocalTrackerConfig(preset="aircraft")),),
            classes=Frame(["car", "truck"]),
        )


def test_a_fusion_step_failing_after_the_local_tracker_ran_leaves_both_as_they_were(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Detections and their fusion are one transaction: a failure in the fusion part (after
    the local tracker's scan) leaves the tracker, and the whole export, as they were; the
    next scans then run as if the failed one had never been tried."""
    config = FusionConfig(
        motion=MotionModel(LAYOUT, q=100.0),
        sensors=(SensorSpec("radar", tracker=LocalTrackerConfig(preset="aircraft")),),
        classes=CLASSES,
    )
    engine, uninterrupted = SessionEngine(config), SessionEngine(config)
    real = SessionEngine._life_cycle
    for index in range(8):
        before = json.dumps(engine.export(), sort_keys=True)
        monkeypatch.setattr(SessionEngine, "_life_cycle", _raise)
        with pytest.raises(RuntimeError, match="injected"):
            engine.apply_detections(detections(index))
        monkeypatch.setattr(SessionEngine, "_life_cycle", real)
        assert json.dumps(engine.export(), sort_keys=True) == before
        assert serialise(engine.apply_detections(detections(index))) == serialise(
            uninterrupted.apply_detections(detections(index))
        )
    assert engine.export() == uninterrupted.export()
    assert any(track["status"] == "confirmed" for track in engine.export()["tracks"])


def _raise(*_: object, **__: object) -> None:
    raise RuntimeError("injected")
