"""An export written before the engine kept its tracks as rows still loads and continues.

``exports/engine_v1.json`` was written by the engine of commit f7999d2
(before the life cycle moved onto the estimate table's rows and the report
times out of the sensor estimates) after the first 40 reports of the
restore-property scenario (seed 0, class masses, covariance intersection):
tentative, confirmed and phantom tracks. Restored by today's engine it must
export the same plain data again (the layout is unchanged, version 1) and
continue the remaining reports as an engine that ran them all uninterrupted:
the same ids, statuses, reasons, pairings and decisions, and every number
within 1e-9 (relative). Not bit for bit: the export was written on another
machine, and numpy's and OpenBLAS's kernels round differently on another
CPU (with AVX-512 the uninterrupted engine's history differs in the last bit
from the file's). On one machine a restore continues bit for bit
(``test_restore_property.py``). An export of an unknown version is refused
by name.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from numpy.testing import assert_allclose

from core.errors import InvalidInput
from core.fusion.engine import SessionEngine
from core.fusion.state import StateFusion
from core.lifecycle import LifeCycleConfig

from .engine_helpers import serialise
from .test_restore_property import VARIANTS, scenario, session_config

EXPORT = Path(__file__).parent / "exports" / "engine_v1.json"
WRITTEN_AFTER = 40
CONFIG = replace(
    session_config(StateFusion.COVARIANCE_INTERSECTION, VARIANTS["classes"]),
    # the life cycle it was written under: the paper profile's (the defaults before issue 22)
    management=LifeCycleConfig.paper(2, phantom_max_distance=80.0, phantom_min_speed=10.0),
)
RTOL = 1e-9


def assert_same_document(actual: Any, expected: Any, where: str = "") -> None:
    """Equal JSON documents, but for floats, which agree to :data:`RTOL`."""
    if isinstance(expected, float) or isinstance(actual, float):
        assert isinstance(actual, int | float) and isinstance(expected, int | float), where
        assert_allclose(actual, expected, rtol=RTOL, atol=1e-12, err_msg=where)
    elif isinstance(expected, dict):
        assert isinstance(actual, dict) and actual.keys() == expected.keys(), where
        for key, value in expected.items():
            assert_same_document(actual[key], value, f"{where}/{key}")
    elif isinstance(expected, list):
        assert isinstance(actual, list) and len(actual) == len(expected), where
        for index, (mine, theirs) in enumerate(zip(actual, expected, strict=True)):
            assert_same_document(mine, theirs, f"{where}/{index}")
    else:
        assert actual == expected, where


def test_an_old_export_loads_and_continues_like_an_uninterrupted_engine() -> None:
    old = json.loads(EXPORT.read_text())
    restored = SessionEngine.restore(CONFIG, old)
    again = restored.export()
    # since issue 22: each track's misses in a row (none in the old file), and the learned
    # revisits, which start unknown (§8.6); since issue 23 (version 2): the central tracker
    # (none in a session whose detecting sensors are not two or more), and (version 3) its
    # reorder buffer; (version 4) the recently ended tracks (§8.15), none in an old export
    assert [track.pop("misses") for track in again["tracks"]] == [0] * len(old["tracks"])
    assert "revisits" not in old
    assert again.pop("central") is None and again.pop("version") == 4
    assert again.pop("ended") == []
    assert json.dumps(again, sort_keys=True) == json.dumps(
        {key: value for key, value in old.items() if key != "version"} | {"revisits": {}},
        sort_keys=True,
    )
    statuses = {track.status.value for track in restored.tracks}
    assert {"tentative", "confirmed", "phantom"} <= statuses  # the life it carries is read

    reports = scenario(0, VARIANTS["classes"])
    uninterrupted = SessionEngine(CONFIG)
    for report in reports[:WRITTEN_AFTER]:
        uninterrupted.apply(report)
    for index, report in enumerate(reports[WRITTEN_AFTER:], start=WRITTEN_AFTER):
        expected = json.loads(serialise(uninterrupted.apply(report)))
        assert_same_document(json.loads(serialise(restored.apply(report))), expected, f"{index}")
    assert_same_document(restored.export(), uninterrupted.export())


def test_an_export_of_an_unknown_version_is_refused_by_name() -> None:
    old = json.loads(EXPORT.read_text())
    with pytest.raises(InvalidInput, match="unknown engine export version 5"):
        SessionEngine.restore(CONFIG, {**old, "version": 5})
