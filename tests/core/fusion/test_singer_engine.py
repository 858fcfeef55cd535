"""An engine predicting with Singer's model keeps the engine's promises: the same inputs give
byte-identical results, and export → JSON → restore → continue equals an uninterrupted run."""

from __future__ import annotations

import dataclasses
import json

import numpy as np

from core.fusion.config import FusionConfig
from core.fusion.engine import SessionEngine
from core.fusion.motion import MotionModel, StateLayout
from core.fusion.reports import ReportedTrack, TrackReport
from core.simulation.tracklists import crossing_traffic

from .engine_helpers import make_config, serialise, to_report

# [x, ẋ, ẍ, y, ẏ, ÿ]: the scenario's [x, ẋ, y, ẏ] with zero accelerations of variance 4
LAYOUT = StateLayout(6, position=(0, 3), velocity=(1, 4), acceleration=(2, 5))
PLACES = [0, 1, 3, 4]


def with_accelerations(report: TrackReport) -> TrackReport:
    tracks = []
    for track in report.tracks:
        state = np.zeros(6)
        state[PLACES] = track.state
        covariance = np.diag([0.0, 0.0, 4.0, 0.0, 0.0, 4.0])
        covariance[np.ix_(PLACES, PLACES)] = track.covariance
        tracks.append(ReportedTrack(track.id, state, covariance))
    return dataclasses.replace(report, tracks=tuple(tracks))


def singer_session(sensors: tuple[str, ...]) -> FusionConfig:
    config = make_config(sensors)
    return dataclasses.replace(config, motion=MotionModel(LAYOUT, "singer", manoeuvre_time=10.0))


def reports(seed: int) -> tuple[tuple[str, ...], list[TrackReport]]:
    scenario = crossing_traffic(seed=seed, n_steps=16)
    return scenario.sensors, [with_accelerations(to_report(r)) for r in scenario.reports]


def test_a_singer_engine_is_deterministic_and_restores_exactly() -> None:
    sensors, inputs = reports(seed=6)
    config = singer_session(sensors)
    uninterrupted = SessionEngine(config)
    expected = [serialise(uninterrupted.apply(report)) for report in inputs]
    again = SessionEngine(singer_session(sensors))
    assert [serialise(again.apply(report)) for report in inputs] == expected
    half = len(inputs) // 2
    first_half = SessionEngine(config)
    for report in inputs[:half]:
        first_half.apply(report)
    exported = json.loads(json.dumps(first_half.export(), allow_nan=False))
    restored = SessionEngine.restore(config, exported)
    assert [serialise(restored.apply(report)) for report in inputs[half:]] == expected[half:]
    assert restored.export() == uninterrupted.export()
    # the fused tracks carry accelerations the model moved: not all left at zero
    last = uninterrupted.apply(dataclasses.replace(inputs[-1], time=inputs[-1].time + 3.0))
    assert any(np.any(track.state[[2, 5]] != 0.0) for track in last.tracks)
