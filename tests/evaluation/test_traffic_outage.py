"""Issue 22, a track-list source's silence (docs/algorithms.md §8.2): an ADS-B station that
goes silent and comes back does not cost its aircraft their fused ids while the radars hold
them. The real-traffic scene's radars and ADS-B station (evaluation/traffic.py, its station
outage 900–960 s) through the service with defaults plus the data sheets, checked against
the truth."""

from __future__ import annotations

import dataclasses

import numpy as np
import pymap3d
import pytest

from evaluation.traffic import ADSB, ADSB_STATION_OUTAGE, ORIGIN, Flight, Scene, simulate

from .test_traffic_revisit import held_once

DURATION = 1100.0
CLIMB = (600.0, 860.0)
"""The aircraft climbs at :data:`CLIMB_RATE` between these times (s), level before and after."""
CLIMB_RATE = 15.0


def climbing_flight() -> Flight:
    """An airliner at 120 m/s east, 10 km north of the session origin, climbing 3.9 km at
    15 m/s and levelling off 40 s before the ADS-B station's outage (as the seed-2 jet out
    of Le Bourget does on the full scene)."""
    times = np.arange(0.0, DURATION + 1.0)
    climbing = (times > CLIMB[0]) & (times < CLIMB[1])
    up = 3000.0 + CLIMB_RATE * np.clip(times - CLIMB[0], 0.0, CLIMB[1] - CLIMB[0])
    enu = np.stack([-60_000.0 + 120.0 * times, np.full_like(times, 10_000.0), up], axis=-1)
    speed = np.stack(
        [np.full_like(times, 120.0), np.zeros_like(times), np.where(climbing, CLIMB_RATE, 0.0)],
        axis=-1,
    )
    geodetic = np.stack(pymap3d.enu2geodetic(*enu.T, *ORIGIN), axis=-1)
    return Flight("AFR1", "abc123", "airliner", times, enu, speed, geodetic)


def outage_scene(seed: int) -> Scene:
    return simulate(seed=seed, duration=DURATION, flights=[climbing_flight()])


def without_list_after_return(scene: Scene) -> Scene:
    """The scene with the station's second list after the outage dropped (as 5 % of lists
    are): the report after the first one carries nothing."""
    stop = ADSB_STATION_OUTAGE[1]
    after = [k for k, item in enumerate(scene.inputs) if item.sensor == ADSB and item.time > stop]
    inputs = list(scene.inputs)
    second = after[1]
    inputs[second] = dataclasses.replace(inputs[second], body=dict(inputs[second].body, tracks=[]))
    return dataclasses.replace(scene, inputs=inputs)


@pytest.mark.parametrize("dropped", [False, True])
def test_an_aircraft_keeps_its_fused_id_through_the_adsb_stations_outage(dropped: bool) -> None:
    """The radars' track of the airliner keeps the climb's vertical velocity for a while after
    it levels off (the aircraft bank's vertical axis has the papers' small Q), so when ADS-B
    comes back at 960.5 s its first report, bound to the fused track by its id, lies a few
    hundred metres above the fused estimate and far outside its covariance: a hit ΔL below
    the delete threshold. The radars keep the track up to date all the while, so that
    report updates the track and does not delete it (before: a new fused id at 960.5 s);
    nor does the station's next list, dropped, end it (its silence is no miss while the
    radars are current: ``dropped``)."""
    scene = outage_scene(1)
    assert scene.equipped == {"AFR1"}
    lists = [item.time for item in scene.inputs if item.sensor == ADSB]
    start, stop = ADSB_STATION_OUTAGE
    assert not any(start <= t <= stop for t in lists)
    assert any(stop < t < stop + 2.0 for t in lists)  # it comes back
    if dropped:
        scene = without_list_after_return(scene)
    extra, coverage = held_once(scene)
    assert extra == 0
    assert coverage >= 0.95
