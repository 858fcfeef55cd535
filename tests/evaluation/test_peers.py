"""evaluation.peers draws the bench's own scenes: its first seed rebuilds ``bench/peers.py``'s.

On the two small scenes (the larger ones take Stone Soup's simulators most of
a minute; they are built by the same function from :data:`SCENE_SIZES`)."""

from __future__ import annotations

import numpy as np
import pytest

from evaluation.peers import first_seed, load_bench, scene


@pytest.mark.parametrize("name", ["~10", "crossing"])
def test_the_first_seed_is_the_benchs_scene(name: str) -> None:
    bench = load_bench()
    ours = scene(name, first_seed(name))
    (theirs,) = [build() for label, build in bench.SCENES if label == name]
    assert (ours.side, ours.clutter_rate, len(ours.scans)) == (
        theirs.side,
        theirs.clutter_rate,
        len(theirs.scans),
    )
    for (when, detections), (then, others) in zip(ours.scans, theirs.scans, strict=True):
        assert when == then
        np.testing.assert_array_equal(bench._positions(detections), bench._positions(others))
