"""``bench/peers.py`` on one reduced Stone Soup scene: GOSPA of Stone Soup's GNN and ours.

Both trackers run here on the same scene made by Stone Soup's simulators, and
both are scored by Stone Soup's ``GOSPAMetric`` (c = 10σ, p = 1, α = 2). No
timing. The goal of issue 13 is ours below Stone Soup's; today it is not (see
the last test), and the parts say where we lose.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import pytest

BENCH = Path(__file__).resolve().parents[1] / "bench"


def load_peers() -> ModuleType:
    sys.path.insert(0, str(BENCH))
    spec = importlib.util.spec_from_file_location("peers_bench", BENCH / "peers.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def scores() -> tuple[object, object, float]:
    peers = load_peers()
    scene = peers.simulated_scene("small", 10, 30, seed=1)  # the bench's ~10 scene, 30 scans
    stone_soup = peers.score(scene, peers.stone_soup_run(scene, "ss-gnn"), with_siap=False)
    ours = peers.score(scene, peers.local_run(scene), with_siap=False)
    return stone_soup, ours, scene.mean_targets()


def test_the_scene_is_what_the_bench_says(scores) -> None:
    stone_soup, ours, targets = scores
    assert 7.0 < targets < 13.0  # "about 10 simultaneous targets"
    for result in (stone_soup, ours):  # GOSPA (p = 1) is the sum of its parts
        assert result.gospa == pytest.approx(result.localisation + result.missed + result.false)


def test_local_tracker_against_stone_soup_gnn(scores) -> None:
    stone_soup, ours, _ = scores
    # Issue 13 wants ours.gospa < stone_soup.gospa. NOT TRUE TODAY (seen: 25.0 against
    # 19.5): ours is higher, and it loses on the missed-target term (12.8 against 4.0)
    # because its tracks come late (3.7 scans after a target's first scan, Stone Soup's
    # 1.0: initiation and confirmation), while its localisation term is lower (7.8
    # against 10.7). Flip these asserts when the tracker of issue 13 lands.
    assert ours.gospa > stone_soup.gospa
    assert ours.missed > 2.0 * stone_soup.missed
    assert ours.late > stone_soup.late + 1.0
    assert ours.localisation < stone_soup.localisation
