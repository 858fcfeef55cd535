"""docs/algorithms.md §8.14 through the service: three radars of the real-traffic scene
(evaluation/traffic.py) that each miss an airliner at consecutive scans, a few seconds
apart, do not end its track — seen on seeds 1 and 2 of ``bench/traffic.py`` (AFR17YC,
VLG8018: the simulation's own P_D draws, every radar seeing the aircraft)."""

from __future__ import annotations

import dataclasses

import httpx
import numpy as np
import pymap3d

from evaluation.service import live_service
from evaluation.traffic import ORIGIN, RADARS, Flight, assess, run_service, simulate

DURATION = 300.0


def airliner() -> Flight:
    """At 10 km, 150 / 100 m/s east / north from 20 km south-west of the origin: 60–80 km
    from each radar, inside every one's range and above every horizon."""
    times = np.arange(0.0, DURATION + 1.0)
    enu = np.stack(
        [-20_000.0 + 150.0 * times, -20_000.0 + 100.0 * times, np.full_like(times, 10_000.0)],
        axis=-1,
    )
    velocity = np.tile([150.0, 100.0, 0.0], (len(times), 1))
    geodetic = np.stack(pymap3d.enu2geodetic(*enu.T, *ORIGIN), axis=-1)
    return Flight("AFR1", "abc123", "airliner", times, enu, velocity, geodetic)


def test_three_radars_missing_in_turn_keep_one_id() -> None:
    """Near no clutter, the aircraft's detections are removed from three consecutive scans
    of the three radars (the scans around them have it): three misses, 3 ln 0.1 = −6.908,
    below the single sensor's threshold −6.907 (the track's end before), above the
    threshold of a track the radars of 4, 5 and 12 s look at, −6.907 − ln 6.4 = −8.763."""
    quiet = tuple(dataclasses.replace(radar, clutter_per_scan=1e-6) for radar in RADARS)
    scene = simulate(seed=3, duration=DURATION, flights=[airliner()], radars=quiet, adsb=False)
    detected = [len(item.truth_errors) == 1 for item in scene.inputs]
    k = next(
        k
        for k in range(len(detected) // 2, len(detected) - 3)
        if all(detected[k - 1 : k + 4])
        and len({item.sensor for item in scene.inputs[k : k + 3]}) == 3
    )
    inputs = list(scene.inputs)
    assert inputs[k + 2].time - inputs[k].time < 5.0
    for j in (k, k + 1, k + 2):
        body = dict(inputs[j].body, detections=[])
        inputs[j] = dataclasses.replace(inputs[j], body=body, truth_errors=np.zeros((0, 3)))
    with live_service() as url, httpx.Client(base_url=url, timeout=60) as client:
        run = run_service(client, dataclasses.replace(scene, inputs=inputs))
    score = assess(scene, run)
    assert score.extra_ids["AFR1"] == 0
    assert score.coverage["AFR1"] >= 0.95
