"""Issue 22, "tracks survive ordinary misses at any revisit": one straight-flying aircraft
seen by one of the real-traffic scene's 3-D radars (evaluation/traffic.py), through the
service with defaults plus the radar's data sheet, checked against the truth."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable
from typing import Any

import httpx
import numpy as np
import pymap3d
import pytest

from evaluation.service import live_service
from evaluation.traffic import (
    ORIGIN,
    RADARS,
    Flight,
    Radar,
    Scene,
    assess,
    run_service,
    session_config,
    simulate,
)

DURATION = 600.0


def straight_flight(start: tuple[float, float], velocity: tuple[float, float]) -> Flight:
    """An airliner at 10 km flying a straight line at constant speed (session ENU, m, m/s)."""
    times = np.arange(0.0, DURATION + 1.0)
    east = start[0] + velocity[0] * times
    north = start[1] + velocity[1] * times
    enu = np.stack([east, north, np.full_like(times, 10_000.0)], axis=-1)
    speed = np.tile([velocity[0], velocity[1], 0.0], (len(times), 1))
    geodetic = np.stack(pymap3d.enu2geodetic(*enu.T, *ORIGIN), axis=-1)
    return Flight("AFR1", "abc123", "airliner", times, enu, speed, geodetic)


def radar(name: str) -> Radar:
    return next(r for r in RADARS if r.id == name)


def without_coverage(scene: Scene, sensors: Iterable[str] | None) -> dict[str, Any]:
    """The scene's session with its radars not told their coverage volumes."""
    config = session_config(scene, sensors)
    for sensor in config["sensors"]:
        sensor.pop("coverage", None)
    return config


def held_once(
    scene: Scene,
    config: Callable[[Scene, Iterable[str] | None], dict[str, Any]] = session_config,
) -> tuple[int, float]:
    """The aircraft's extra fused ids and its coverage, the service run on ``scene`` with
    the session ``config`` (default the scene's)."""
    with live_service() as url, httpx.Client(base_url=url, timeout=60) as client:
        run = run_service(client, scene, config=config)
    score = assess(scene, run)
    return score.extra_ids["AFR1"], score.coverage["AFR1"]


def radar_e_scene(seed: int) -> Scene:
    """radar-e (12 s scans, 80 m / 0.2° / 0.35°, P_D 0.9, 30 false alarms a scan) 60–100 km
    from an airliner flying north at 230 m/s."""
    flight = straight_flight((10_000.0, -60_000.0), (0.0, 230.0))
    return simulate(
        seed=seed, duration=DURATION, flights=[flight], radars=(radar("radar-e"),), adsb=False
    )


def missed_scans(scene: Scene) -> list[float]:
    return [item.time for item in scene.inputs if len(item.truth_errors) == 0]


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_a_12_s_radars_straight_flyer_keeps_one_id_through_ordinary_misses(seed: int) -> None:
    scene = radar_e_scene(seed)
    missed = missed_scans(scene)
    assert len(missed) >= 2  # 50 scans at P_D 0.9; seeds 1, 3, 4 miss two scans in a row
    extra, coverage = held_once(scene)
    assert extra == 0
    assert coverage >= 0.95


def test_a_12_s_radars_track_is_not_taken_by_a_false_alarm_after_two_misses() -> None:
    """Seed 5 misses the scans at 543 and 555 s; at 555 s the track, predicted over 24 s by
    the aircraft bank's held 2g/4g inputs, gates (closest model) a false alarm 22 km from
    the aircraft; taken, it lost the track (a new id followed). Weighted by the probability
    that the 4g input held over the step, the false alarm is less likely the aircraft's than
    a miss and a false alarm, and the track misses instead (docs/algorithms.md §8.1, "A
    detection after a long gap")."""
    scene = radar_e_scene(5)
    assert missed_scans(scene)[-2:] == pytest.approx([542.7, 554.7])
    extra, _ = held_once(scene)
    assert extra == 0


def test_a_5_s_radars_track_survives_two_misses() -> None:
    """radar-sw (5 s scans), next to no clutter; the aircraft's detections removed at two
    scans in a row in the middle of the run (the scans around them have it)."""
    quiet = dataclasses.replace(radar("radar-sw"), clutter_per_scan=1e-6)
    flight = straight_flight((-40_000.0, -20_000.0), (150.0, 100.0))
    scene = simulate(seed=2, duration=DURATION, flights=[flight], radars=(quiet,), adsb=False)
    detected = [len(item.truth_errors) == 1 for item in scene.inputs]
    middle = len(detected) // 2
    k = next(
        k
        for k in range(middle, len(detected) - 2)
        if detected[k - 1] and detected[k] and detected[k + 1] and detected[k + 2]
    )
    inputs = list(scene.inputs)
    for j in (k, k + 1):
        body = dict(inputs[j].body, detections=[])
        inputs[j] = dataclasses.replace(inputs[j], body=body, truth_errors=np.zeros((0, 3)))
    extra, coverage = held_once(dataclasses.replace(scene, inputs=inputs))
    assert extra == 0
    assert coverage >= 0.95
