"""An export written before the engine kept its tracks as rows still loads and continues.

``exports/engine_v1.json`` was written by the engine of commit f7999d2
(before the life cycle moved onto the estimate table's rows and the report
times out of the sensor estimates) after the first 40 reports of the
restore-property scenario (seed 0, class masses, covariance intersection):
tentative, confirmed and phantom tracks. Restored by today's engine it must
export the same plain data again (the layout is unchanged, version 1) and
continue the remaining reports exactly as an engine that ran them all
uninterrupted; an export of an unknown version is refused by name.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from core.errors import InvalidInput
from core.fusion.engine import SessionEngine
from core.fusion.state import StateFusion

from .engine_helpers import serialise
from .test_restore_property import VARIANTS, scenario, session_config

EXPORT = Path(__file__).parent / "exports" / "engine_v1.json"
WRITTEN_AFTER = 40
CONFIG = session_config(StateFusion.COVARIANCE_INTERSECTION, VARIANTS["classes"])


def test_an_old_export_loads_and_continues_like_an_uninterrupted_engine() -> None:
    old = json.loads(EXPORT.read_text())
    restored = SessionEngine.restore(CONFIG, old)
    assert json.dumps(restored.export(), sort_keys=True) == json.dumps(old, sort_keys=True)
    statuses = {track.status.value for track in restored.tracks}
    assert {"tentative", "confirmed", "phantom"} <= statuses  # the life it carries is read

    reports = scenario(0, VARIANTS["classes"])
    uninterrupted = SessionEngine(CONFIG)
    for report in reports[:WRITTEN_AFTER]:
        uninterrupted.apply(report)
    for index, report in enumerate(reports[WRITTEN_AFTER:], start=WRITTEN_AFTER):
        expected = serialise(uninterrupted.apply(report))
        assert serialise(restored.apply(report)) == expected, index
    assert json.dumps(restored.export(), sort_keys=True) == json.dumps(
        uninterrupted.export(), sort_keys=True
    )


def test_an_export_of_an_unknown_version_is_refused_by_name() -> None:
    old = json.loads(EXPORT.read_text())
    with pytest.raises(InvalidInput, match="unknown engine export version 2"):
        SessionEngine.restore(CONFIG, {**old, "version": 2})
