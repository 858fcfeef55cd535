"""The paper scenarios as service inputs: a session config and the wire bodies to post.

Every scenario of ``core.simulation`` becomes what a client would send, so the
same run can go through the engine in this process or through a running
server (``credal-fusion simulate … --server URL``): detection scenarios give
one sensor per scanning sensor, with its measurement model (and field of view
where the scenario has one); track-list scenarios give the sensors' track
lists (with class masses for ``t2t-two-class``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from core.arrays import FloatArray
from core.belief import MassFunction
from core.simulation import SCENARIOS, ClassifiedTrackListScenario, Scenario, t2t_two_class
from core.simulation.tracklists import TrackListScenario, crossing_traffic, t2t_four

Body = dict[str, Any]

PRESET_OF = {"aircraft": "aircraft", "crossing": "aircraft", "pedestrian": "pedestrian"}
"""Tracking preset of each detection scenario (the others track with one CV model)."""

PRESETS = ("aircraft", "pedestrian", "none")
"""Presets a detection scenario can be tracked with (``--preset``; "none": one CV model)."""

CLASSES_OF = {"aircraft": ["liner", "bomber", "fighter"], "pedestrian": ["rambler", "sportsman"]}
"""The session classes of each preset (its class frame)."""

MOTION_Q = {"aircraft": 100.0, "crossing": 100.0, "close-pair": 100.0}
"""White-acceleration density of the fused tracks: it must cover the targets' manoeuvres."""


@dataclass(frozen=True)
class TruthAt:
    """True positions (targets × 2) and target ids at the time of one input."""

    time: float
    positions: FloatArray
    target_ids: tuple[int, ...]


@dataclass(frozen=True)
class ScenarioRun:
    """A scenario as a session: its config, its inputs in order, and the truth at each input."""

    name: str
    seed: int
    config: Body
    inputs: tuple[tuple[str, Body], ...]  # ("tracks" | "detections", body)
    truth: tuple[TruthAt, ...]
    cutoff: float  # OSPA cut-off for the summary


def _state_layout() -> Body:
    return {"dim": 4, "position": [0, 2], "velocity": [1, 3]}


def _surveyed(scenario: Scenario) -> Body | None:
    """With sensor regions: the box around them all, so the gaps between them are blind zones."""
    if not scenario.sensor_regions:
        return None
    xs = [x for (xr, _) in scenario.sensor_regions.values() for x in xr]
    ys = [y for (_, yr) in scenario.sensor_regions.values() for y in yr]
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    return {"kind": "polygon", "vertices": [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]}


def _detection_run(name: str, scenario: Scenario, tracking_preset: str | None) -> ScenarioRun:
    sensors = sorted({scan.sensor for scan in scenario.scans})
    r = np.asarray(scenario.measurement_noise).tolist()
    sensor_configs = []
    for sensor in sensors:
        config: Body = {"id": sensor, "p_detect": 0.9, "measurement": {"r": r}}
        region = scenario.sensor_regions.get(sensor)
        if region is not None:
            (x0, x1), (y0, y1) = region
            config["fov"] = {
                "kind": "polygon",
                "vertices": [[x0, y0], [x1, y0], [x1, y1], [x0, y1]],
            }
        sensor_configs.append(config)
    preset = PRESET_OF.get(name) if tracking_preset is None else tracking_preset
    preset = None if preset == "none" else preset
    surveyed = _surveyed(scenario)
    session: Body = {
        "name": f"{name} (seed {scenario.seed})",
        "state": _state_layout(),
        "motion": {"model": "constant_velocity", "q": MOTION_Q.get(name, 10.0)},
        "sensors": sensor_configs,
        "tracking": {"profile": "paper", "preset": preset, "time_interval": scenario.time_interval},
    }
    if surveyed is not None:
        session["region"] = surveyed
    if preset is not None:
        session["classes"] = CLASSES_OF[preset]
    inputs = []
    truth = []
    for scan in scenario.scans:
        inputs.append(
            (
                "detections",
                {
                    "sensor": scan.sensor,
                    "time": scan.time,
                    "detections": [{"z": z.tolist()} for z in scan.measurements],
                },
            )
        )
        alive = [t for t in scenario.truths if t.alive(scan.step)]
        truth.append(
            TruthAt(
                scan.time,
                np.array([t.state_at(scan.step)[[0, 2]] for t in alive]).reshape(-1, 2),
                tuple(t.target_id for t in alive),
            )
        )
    cutoff = 10.0 * float(np.sqrt(np.trace(scenario.measurement_noise)))
    return ScenarioRun(name, scenario.seed, session, tuple(inputs), tuple(truth), cutoff)


def _track_list_run(
    name: str,
    scenario: TrackListScenario | ClassifiedTrackListScenario,
    masses: tuple[tuple[MassFunction, ...], ...] | None = None,
) -> ScenarioRun:
    session: Body = {
        "name": f"{name} (seed {scenario.seed})",
        "state": _state_layout(),
        "motion": {"model": "constant_velocity", "q": 0.5},
        "sensors": [{"id": sensor} for sensor in scenario.sensors],
    }
    if isinstance(scenario, ClassifiedTrackListScenario):
        session["classes"] = list(scenario.classes.labels)
    inputs = []
    truth = []
    for index, report in enumerate(scenario.reports):
        tracks = []
        for k, track_id in enumerate(report.track_ids):
            track: Body = {
                "id": track_id,
                "state": report.states[k].tolist(),
                "covariance": report.covariances[k].tolist(),
            }
            if masses is not None:
                mass = masses[index][k]
                track["classification"] = {
                    "mass": [
                        {"set": list(labels), "mass": value} for labels, value in mass.focal_sets()
                    ]
                }
            tracks.append(track)
        inputs.append(("tracks", {"sensor": report.sensor, "time": report.time, "tracks": tracks}))
        # Track lists estimate the truth at the report time (CV truth; these scenarios use ΔT = 1 s).
        alive = [t for t in scenario.truths if t.alive(report.step)]
        positions = np.array(
            [
                t.state_at(report.step)[[0, 2]]
                + t.state_at(report.step)[[1, 3]] * (report.time - report.step)
                for t in alive
            ]
        ).reshape(-1, 2)
        truth.append(TruthAt(report.time, positions, tuple(t.target_id for t in alive)))
    cutoff = 10.0 * float(np.sqrt(scenario.reports[0].covariances[0][0, 0]))
    return ScenarioRun(name, scenario.seed, session, tuple(inputs), tuple(truth), cutoff)


def _two_class_run(name: str, seed: int) -> ScenarioRun:
    scenario = t2t_two_class(seed)
    return _track_list_run(name, scenario, scenario.class_masses)


def build(name: str, seed: int, preset: str | None = None) -> ScenarioRun:
    """The scenario ``name`` (an EVALUATION.md id, or ``crossing-traffic``) with ``seed``.

    ``preset`` (one of :data:`PRESETS`) replaces the tracking preset of a
    detection scenario (default: :data:`PRESET_OF`); track-list scenarios
    have no local tracking and ignore it.
    """
    if preset is not None and preset not in PRESETS:
        raise ValueError(f"unknown preset {preset!r}; choose one of {list(PRESETS)}")
    if tracks_locally(name):
        return _detection_run(name, SCENARIOS[name](seed), preset)
    track_lists: dict[str, Callable[[int], ScenarioRun]] = {
        "t2t-four": lambda s: _track_list_run(name, t2t_four(s)),
        "crossing-traffic": lambda s: _track_list_run(name, crossing_traffic(s)),
        "t2t-two-class": lambda s: _two_class_run(name, s),
    }
    if name not in track_lists:
        raise ValueError(f"unknown scenario {name!r}; choose one of {names()}")
    return track_lists[name](seed)


def tracks_locally(name: str) -> bool:
    """Whether the scenario ``name`` sends detections, tracked in the session (so a
    ``preset`` applies), rather than track lists."""
    return name in SCENARIOS


def names() -> list[str]:
    """Every scenario ``simulate`` knows."""
    return sorted([*SCENARIOS, "t2t-four", "t2t-two-class", "crossing-traffic"])
