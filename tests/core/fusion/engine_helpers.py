"""Building engines and feeding them scenario reports, for the engine tests."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterable, Mapping
from enum import Enum
from typing import Any

import numpy as np

from core.belief import MassFunction
from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.engine import SessionEngine
from core.fusion.motion import MotionModel, StateLayout
from core.fusion.reports import ReportedTrack, StepResult, TrackReport
from core.geometry import FieldOfView, PolygonView
from core.lifecycle import LifeCycleConfig
from core.simulation.tracklists import SensorTrackList

LAYOUT = StateLayout(dim=4, position=(0, 2), velocity=(1, 3))


def make_config(
    sensors: Iterable[str | SensorSpec],
    *,
    method: str = "denoeux",
    options: Mapping[str, object] | None = None,
    continuity: bool = True,
    fovs: Mapping[str, FieldOfView] | None = None,
    region: PolygonView | None = None,
    management: LifeCycleConfig | None = None,
    q: float = 0.5,
) -> FusionConfig:
    specs = tuple(
        sensor
        if isinstance(sensor, SensorSpec)
        else SensorSpec(sensor, p_detect=0.9, fov=(fovs or {}).get(sensor))
        for sensor in sensors
    )
    chosen_options: Mapping[str, object] = (
        options
        if options is not None
        else ({"gate_probability": 0.999, "alpha": 1.0} if method == "denoeux" else {})
    )
    return FusionConfig(
        motion=MotionModel(LAYOUT, q=q),
        sensors=specs,
        association_method=method,
        association_options=chosen_options,
        track_continuity=continuity,
        region=region,
        management=management or LifeCycleConfig(),
    )


def to_report(track_list: SensorTrackList) -> TrackReport:
    return TrackReport(
        sensor=track_list.sensor,
        time=track_list.time,
        tracks=tuple(
            ReportedTrack(track_id, state, covariance)
            for track_id, state, covariance in zip(
                track_list.track_ids, track_list.states, track_list.covariances, strict=True
            )
        ),
    )


def _canonical(value: object) -> object:
    """What ``json`` cannot write itself of a step: arrays, enums, mass functions."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, MassFunction):
        return value.focal_sets()
    raise TypeError(f"no canonical form for {type(value).__name__}")


def serialise(step: StepResult) -> str:
    """Every field of the step as canonical JSON text (the determinism checks compare these;
    the wire's shape is the service's business: ``app.sessions.translate.step_json``)."""
    return json.dumps(dataclasses.asdict(step), default=_canonical, sort_keys=True, allow_nan=False)


def run(engine: SessionEngine, reports: Iterable[SensorTrackList]) -> list[StepResult]:
    return [engine.apply(to_report(report)) for report in reports]


def fused_ids_of_targets(
    reports: Iterable[SensorTrackList], steps: Iterable[StepResult]
) -> tuple[dict[int, set[str]], int, int]:
    """Per true target, the fused ids its sensor tracks were paired with; and (wrong, total).

    A pairing is wrong when the fused track's owner — the target most of its
    pairings come from — is not the report track's target.
    """
    pairings: list[tuple[str, int]] = []
    for report, step in zip(reports, steps, strict=True):
        target_of = dict(zip(report.track_ids, report.target_ids.tolist(), strict=True))
        pairings += [(fused, target_of[track]) for fused, track, _, _ in step.association.pairs]
    votes: dict[str, dict[int, int]] = {}
    for fused, target in pairings:
        votes.setdefault(fused, {}).setdefault(target, 0)
        votes[fused][target] += 1
    owner = {fused: max(counts, key=lambda t: (counts[t], -t)) for fused, counts in votes.items()}
    per_target: dict[int, set[str]] = {}
    for fused, target in pairings:
        per_target.setdefault(target, set()).add(fused)
    wrong = sum(owner[fused] != target for fused, target in pairings)
    return per_target, wrong, len(pairings)


def position_errors(step: StepResult, truth_positions: dict[str, Any]) -> list[float]:
    errors = []
    for track in step.tracks:
        if track.id in truth_positions:
            errors.append(float(np.hypot(*(track.state[[0, 2]] - truth_positions[track.id]))))
    return errors
