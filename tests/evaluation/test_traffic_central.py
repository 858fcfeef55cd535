"""Issue 22 on the central path (docs/algorithms.md §8.9): a radar that cannot see an
aircraft, and is not told so (no ``coverage``), does not end its track. Three of the
real-traffic scene's radars (evaluation/traffic.py) through the service with defaults plus
their data sheets, checked against the truth."""

from __future__ import annotations

import dataclasses

import pytest

from evaluation.traffic import Scene, horizon_visible, simulate

from .test_traffic_revisit import DURATION, held_once, radar, straight_flight, without_coverage


def blind_radar_scene(seed: int) -> Scene:
    """radar-n (4 s) and radar-e (12 s) see an airliner flying east at 150 m/s, 28–106 km
    from each; radar-sw (5 s) reaches only 30 km from its site, 75 km or more from the
    aircraft, so every one of its scans misses it — the session is given its site, σ, P_D
    and clutter density, not its range (:func:`without_coverage`)."""
    short = dataclasses.replace(radar("radar-sw"), range_max=30_000.0)
    flight = straight_flight((-20_000.0, 20_000.0), (150.0, 0.0))
    radars = (radar("radar-n"), short, radar("radar-e"))
    return simulate(seed=seed, duration=DURATION, flights=[flight], radars=radars, adsb=False)


@pytest.mark.parametrize("seed", [1, 2])
def test_a_non_cooperative_aircraft_keeps_one_id_beside_a_radar_that_cannot_see_it(
    seed: int,
) -> None:
    scene = blind_radar_scene(seed)
    flight = scene.flights[0]
    sees = {r.id: horizon_visible(r, flight.geodetic) for r in scene.radars}
    assert sees["radar-n"].all() and sees["radar-e"].all() and not sees["radar-sw"].any()
    sw = [item for item in scene.inputs if item.sensor == "radar-sw"]
    assert all(len(item.truth_errors) == 0 for item in sw)  # every sw scan is a miss
    extra, coverage = held_once(scene, without_coverage)
    assert extra == 0
    assert coverage >= 0.95
