"""A radar's data-sheet coverage through the service (docs/algorithms.md §8.11): an aircraft
that flies out of every radar's coverage and back keeps its one fused id — its track is not
ended by misses nobody could have made. Two of the real-traffic scene's 3-D radars
(evaluation/traffic.py), defaults plus their data sheets, a live uvicorn server, checked
against the truth (the simulator's own horizon test, pymap3d's geodetic2aer)."""

from __future__ import annotations

import dataclasses

import pymap3d
import pytest

from evaluation.traffic import ORIGIN, Scene, horizon_visible, simulate

from .test_traffic_revisit import DURATION, held_once, radar, straight_flight, without_coverage

OVERFLIGHT = 200.0
"""The airliner's speed (m/s) east over radar-n's site, 10 km up."""


def overflight_scene(seed: int) -> Scene:
    """radar-n (4 s, top elevation 30°) sees an airliner flying east over its site at 10 km
    but for the ~3 minutes it is above 30° (its cone of silence, within 17 km of the site);
    radar-e (12 s) reaches 60 km from its own site, 140 km away: it never sees the
    aircraft. Both are told their coverage (range, top elevation, antenna height)."""
    north = radar("radar-n")
    east, north_m, _ = pymap3d.geodetic2enu(north.lat, north.lon, north.alt, *ORIGIN)
    flight = straight_flight((east - 60_000.0, north_m), (OVERFLIGHT, 0.0))
    short = dataclasses.replace(radar("radar-e"), range_max=60_000.0)
    return simulate(
        seed=seed, duration=DURATION, flights=[flight], radars=(north, short), adsb=False
    )


@pytest.mark.parametrize("seed", [1, 2])
def test_an_aircraft_out_of_every_radars_coverage_and_back_keeps_one_fused_id(seed: int) -> None:
    scene = overflight_scene(seed)
    flight = scene.flights[0]
    sees = {r.id: horizon_visible(r, flight.geodetic) for r in scene.radars}
    assert not sees["radar-e"].any()
    blind = ~sees["radar-n"]
    assert 150 <= blind.sum() <= 200  # one stretch of ~3 minutes in the middle of the run
    assert not blind[:150].any() and not blind[-150:].any()
    extra, coverage = held_once(scene)
    assert extra == 0
    assert coverage >= 0.95


def test_without_its_coverage_the_overflight_loses_its_id() -> None:
    """The same scene with the radars not told their coverage: radar-n's silence in its
    cone of silence deletes the track and the aircraft comes back under a new id (the
    behaviour the coverage fields change, and the reason for them)."""
    extra, _ = held_once(overflight_scene(1), without_coverage)
    assert extra >= 1
