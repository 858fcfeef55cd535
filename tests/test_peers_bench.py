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
    # Seen (defaults + physics, no velocity prior since issue 22): 17.6 against 19.5. Ours
    # is more accurate where it tracks and starts fewer false tracks (confirmed at L ≥ 0,
    # late 1.3 scans against 1.05).
    assert ours.gospa < 0.95 * stone_soup.gospa
    assert ours.late < stone_soup.late + 0.5
    assert ours.localisation < stone_soup.localisation
    assert ours.false < stone_soup.false


def test_local_tracker_against_stone_soup_jpda() -> None:
    peers = load_bench("peers")
    scene = peers.simulated_scene("small", 10, 30, seed=1)
    jpda = peers.score(scene, peers.stone_soup_run(scene, "ss-jpda"), with_siap=False)
    ours = peers.score(scene, peers.local_run(scene), with_siap=False)
    # Seen: 17.6 against 24.7.
    assert ours.gospa < jpda.gospa


def test_the_service_with_one_sensor_is_as_accurate_as_its_local_tracker(scores) -> None:
    """With one detecting sensor the fused tracks are its local tracks (issue 13: within 2 %)."""
    _, ours, service, _ = scores
    # Seen: equal (17.63 both). Before, the service was 2.5 % better: a tentative
    # track stole a confirmed track's detection, the local tracker then held two
    # tracks on one target and the fused layer joined them into one.
    assert service.late == pytest.approx(ours.late)
    assert service.missed == pytest.approx(ours.missed)
    assert service.gospa == pytest.approx(ours.gospa, rel=0.02)


def test_fused_sensors_are_better_than_each_sensor_alone() -> None:
    """Three Stone Soup detection simulators on one truth (σ 1 / 2 / 1.5 m, P_D 0.9 /
    0.7 / 0.8), through the service: each alone, then all in one session."""
    peers = load_bench("peers")
    sensors = peers.multi_sensor_scenes(10, 30, seed=4)
    first = sensors[0]
    for other in sensors[1:]:  # one truth: the same states at every scan
        for (when, _), (also, _) in zip(first.scans, other.scans, strict=True):
            assert when == also
            assert sorted(s.state_vector.ravel().tolist() for _, s in first.truth_states(when)) == (
                sorted(s.state_vector.ravel().tolist() for _, s in other.truth_states(also))
            )
    with peers.live_service() as url:
        alone = [
            peers.score(first, peers.rest_run(sensor, url), with_siap=False) for sensor in sensors
        ]
        fused = peers.score(first, peers.rest_run(sensors, url, "rest-fused"), with_siap=False)
    # Seen: alone 19.9 / 32.7 / 27.6, fused 15.9.
    assert fused.gospa < min(result.gospa for result in alone)
    assert fused.localisation < min(result.localisation for result in alone)


def test_siap_of_an_id_that_skips_scans() -> None:
    """A fused id handed back after a restart (docs/algorithms.md §8.15) skips scans; Stone
    Soup's SIAP looks a track up at every time of its association, so the bench scores each
    unbroken run of an id as its own track. Estimates exactly on one truth, its id absent at
    scans 4 and 5: position accuracy 0, completeness = the scans held / the scans that truth
    exists among all truths' (worked from the scene's own truth table), no error."""
    peers = load_bench("peers")
    scene = peers.simulated_scene("gap", 2, 12, seed=1)
    path = scene.truths[0]
    estimates = []
    held = 0
    for scan, (when, _) in enumerate(scene.scans):
        here = path[0].timestamp <= when <= path[-1].timestamp and scan not in (4, 5)
        state = path[when].state_vector if here else None
        held += here
        estimates.append([("F1", state.ravel().astype(float))] if here else [])
    run = peers.Run("gapped", estimates, [0.0] * len(estimates))
    siap = peers.siap_metrics(scene, run)
    assert siap["position"] == pytest.approx(0.0, abs=1e-9)
    truth_scans = sum(len(scene.truth_states(when)) for when, _ in scene.scans)
    assert siap["completeness"] == pytest.approx(held / truth_scans)
    assert siap["spuriousness"] == pytest.approx(0.0)
