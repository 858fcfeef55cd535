"""Every preset through every scenario of ``credal-fusion simulate`` runs to the end (issue 12).

Reduced size for ``make test``: the first :data:`REDUCED_INPUTS` inputs of each
run (the pedestrian preset used to fail from the third), 20 seeds in process,
a few through a live server (which must give the same results). The full
runs are the command itself (``credal-fusion simulate NAME --preset P --seed S``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from app.commands.runner import run_locally, run_on_server
from app.commands.scenarios import PRESETS, build, names
from app.commands.simulate import covering_tracks
from core.simulation import SCENARIOS
from tests.api.conftest import LiveServer, live_server

__all__ = ["live_server"]

REDUCED_INPUTS = 4
SEEDS = range(20)
SERVER_SEEDS = range(1)


def _presets(name: str) -> tuple[str | None, ...]:
    """Detection scenarios take every preset; track lists have no local tracking."""
    return PRESETS if name in SCENARIOS else (None,)


def _check_results(results: list[dict[str, Any]], expected: int) -> None:
    assert len(results) == expected
    for result in results:
        for track in result["tracks"]:
            assert np.all(np.isfinite(track["state"]))
            assert np.all(np.isfinite(track["covariance"]))


@pytest.mark.parametrize("name", names())
def test_every_preset_runs_every_seed_to_the_end_in_process(name: str) -> None:
    for preset in _presets(name):
        for seed in SEEDS:
            run = build(name, seed, preset)
            inputs = run.inputs[:REDUCED_INPUTS]
            _check_results(list(run_locally(run.config, inputs)), len(inputs))


def test_every_preset_runs_through_the_server(live_server: LiveServer) -> None:
    for name in names():
        for preset in _presets(name):
            for seed in SERVER_SEEDS:
                run = build(name, seed, preset)
                inputs = run.inputs[:REDUCED_INPUTS]
                served = list(run_on_server(live_server.url, run.config, inputs))
                _check_results(served, len(inputs))
                assert served == list(run_locally(run.config, inputs))


def test_pedestrian_preset_runs_its_whole_scenario_through_the_server(
    live_server: LiveServer,
) -> None:
    """The run the issue saw refused from the third post: every input accepted, both tracked."""
    run = build("pedestrian", 0)
    results = list(run_on_server(live_server.url, run.config, run.inputs))
    _check_results(results, len(run.inputs))
    final = [t for t in results[-1]["tracks"] if t["status"] == "confirmed"]
    assert len(final) == 2


@pytest.mark.parametrize("seed", [0, 3])
def test_aircraft_defaults_follow_both_manoeuvres(seed: int) -> None:
    """[MTT] §6.1 target 2 (+2g, then −4g) posted as detections with ``tracking.preset:
    aircraft`` and no ``motion`` block: one fused id throughout, and it ends as a fighter."""
    run = build("aircraft", seed)
    config = {key: value for key, value in run.config.items() if key != "motion"}
    results = list(run_locally(config, run.inputs))
    ids: set[str] = set()
    for result, truth in zip(results, run.truth, strict=True):
        if 2 in truth.target_ids and result["time"] >= 10.0:
            covering = covering_tracks(result, truth.positions, truth.target_ids)[2]
            assert covering is not None, result["time"]
            ids.add(covering)
    assert len(ids) == 1, ids
    (fused,) = ids
    last = [t for r in results for t in r["tracks"] if t["id"] == fused][-1]
    assert last["classification"]["decision"] == "fighter"
