"""``bench/peers.py`` on one reduced Stone Soup scene: GOSPA of Stone Soup's GNN and ours.

Stone Soup's GNN, our local tracker and the service (REST, one session, one
detecting sensor) run here on the same scene made by Stone Soup's simulators,
and all are scored by Stone Soup's ``GOSPAMetric`` (c = 10σ, p = 1, α = 2).
No timing.
"""

from __future__ import annotations

import pytest

from tests.bench_scripts import load_bench


@pytest.fixture(scope="module")
def scores() -> tuple[object, object, object, float]:
    peers = load_bench("peers")
    scene = peers.simulated_scene("small", 10, 30, seed=1)  # the bench's ~10 scene, 30 scans
    stone_soup = peers.score(scene, peers.stone_soup_run(scene, "ss-gnn"), with_siap=False)
    ours = peers.score(scene, peers.local_run(scene), with_siap=False)
    with peers.live_service() as url:
        service = peers.score(scene, peers.rest_run(scene, url), with_siap=False)
    return stone_soup, ours, service, scene.mean_targets()


def test_the_scene_is_what_the_bench_says(scores) -> None:
    stone_soup, ours, service, targets = scores
    assert 7.0 < targets < 13.0  # "about 10 simultaneous targets"
    for result in (stone_soup, ours, service):  # GOSPA (p = 1) is the sum of its parts
        assert result.gospa == pytest.approx(result.localisation + result.missed + result.false)


def test_local_tracker_against_stone_soup_gnn(scores) -> None:
    stone_soup, ours, _, _ = scores
    # Seen: 19.05 against 19.51. Confirmed at the second hit like Stone Soup's
    # (late 1.1 scans against 1.05), ours is more accurate where it tracks.
    assert ours.gospa < stone_soup.gospa
    assert ours.late < stone_soup.late + 0.25
    assert ours.localisation < stone_soup.localisation


def test_the_service_with_one_sensor_is_as_accurate_as_its_local_tracker(scores) -> None:
    """The fused layer adds no delay: a local track is confirmed when it enters."""
    _, ours, service, _ = scores
    # Seen: 18.58 against 19.05, the same late and missed terms; the fused layer's
    # false term is lower (4.67 against 5.17), so it is never worse, not yet equal.
    assert service.late == pytest.approx(ours.late)
    assert service.missed == pytest.approx(ours.missed)
    assert service.gospa <= ours.gospa * 1.02
