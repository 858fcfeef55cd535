"""A radar's data-sheet coverage through the service (docs/algorithms.md §8.11): an aircraft
that flies out of every radar's coverage and back keeps its one fused id — its track is not
ended by misses nobody could have made. Two of the real-traffic scene's 3-D radars
(evaluation/traffic.py), defaults plus their data sheets, a live uvicorn server, checked
against the truth (the simulator's own horizon test, pymap3d's geodetic2aer)."""

from __future__ import annotations

import dataclasses
from typing import Any

import httpx
import numpy as np
import pymap3d
import pytest

from evaluation.service import live_service
from evaluation.traffic import (
    ORIGIN,
    Flight,
    Scene,
    ServiceRun,
    assess,
    horizon_visible,
    run_service,
    simulate,
)

from .test_traffic_revisit import DURATION, held_once, radar, straight_flight, without_coverage

OVERFLIGHT = 200.0
"""The airliner's speed (m/s) east over radar-n's site, 10 km up."""


def overflight_scene(seed: int, alone: bool = False) -> Scene:
    """radar-n (4 s, top elevation 30°) sees an airliner flying east over its site at 10 km
    but for the ~3 minutes it is above 30° (its cone of silence, within 17 km of the site);
    radar-e (12 s) reaches 60 km from its own site, 140 km away: it never sees the
    aircraft. Both are told their coverage (range, top elevation, antenna height); the
    two are tracked centrally (§8.9), radar-n ``alone`` by its own tracker."""
    north = radar("radar-n")
    east, north_m, _ = pymap3d.geodetic2enu(north.lat, north.lon, north.alt, *ORIGIN)
    flight = straight_flight((east - 60_000.0, north_m), (OVERFLIGHT, 0.0))
    short = dataclasses.replace(radar("radar-e"), range_max=60_000.0)
    radars = (north,) if alone else (north, short)
    return simulate(seed=seed, duration=DURATION, flights=[flight], radars=radars, adsb=False)


@pytest.mark.parametrize(("seed", "alone"), [(1, False), (2, False), (1, True)])
def test_an_aircraft_out_of_every_radars_coverage_and_back_keeps_one_fused_id(
    seed: int, alone: bool
) -> None:
    """Inside the cone of silence the track is kept as a phantom ([HZ] §5.1: predicted, not
    seen, shown so) under its id, and confirmed again under that id once radar-n sees
    the aircraft again (alone: its own tracker's phantom hands over, and so does the
    fused layer's)."""
    scene = overflight_scene(seed, alone)
    flight = scene.flights[0]
    sees = {r.id: horizon_visible(r, flight.geodetic) for r in scene.radars}
    assert alone or not sees["radar-e"].any()
    blind = ~sees["radar-n"]
    assert 150 <= blind.sum() <= 200  # one stretch of ~3 minutes in the middle of the run
    assert not blind[:150].any() and not blind[-150:].any()
    with live_service() as url, httpx.Client(base_url=url, timeout=60) as client:
        run = run_service(client, scene)
    score = assess(scene, run)
    assert score.extra_ids[flight.callsign] == 0
    assert score.coverage[flight.callsign] >= 0.95
    first, last = flight.times[blind][[0, -1]]
    before = [when for when, _ in run.pictures if when < first]
    (held,) = {track["id"] for track in near(run, before[-1], flight)}
    # where no radar can see it, the track is a phantom (its prediction, however far it
    # drifts over 3 minutes, is no detection), never confirmed, under its id
    for when, tracks in run.pictures:
        if first + 20 <= when <= last - 20:
            shown = {track["id"]: track["status"] for track in tracks}
            assert shown.get(held) == "phantom", when
    # once radar-n sees it again: confirmed, near it, still under that id
    after = [when for when, _ in run.pictures if when >= last + 30]
    assert after
    for when in after:
        assert [(t["id"], t["status"]) for t in near(run, when, flight)] == [(held, "confirmed")]


def near(run: ServiceRun, when: float, flight: Flight) -> list[dict[str, Any]]:
    """The tracks of the picture at ``when`` within 2 km of the aircraft."""
    tracks = dict(run.pictures)[when]
    truth = flight.at(when)[0]
    return [t for t in tracks if np.linalg.norm(np.array(t["state"])[[0, 2, 4]] - truth) <= 2000]


def test_without_its_coverage_the_overflight_loses_its_id() -> None:
    """The same scene with the radars not told their coverage: radar-n's silence in its
    cone of silence deletes the track and the aircraft comes back under a new id (the
    behaviour the coverage fields change, and the reason for them)."""
    extra, _ = held_once(overflight_scene(1), without_coverage)
    assert extra >= 1
