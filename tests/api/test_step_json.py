"""The hot-path serialiser of step results writes exactly what ``step_plain`` describes."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from api_schemas.config import SessionConfig
from api_schemas.reports import TrackReport
from api_schemas.results import StepResult as WireStepResult
from app.http.responses import dumps
from app.sessions.translate import (
    class_frame,
    core_track_report,
    fusion_config,
    step_json,
    step_plain,
)
from core.fusion.engine import SessionEngine
from core.fusion.reports import StepResult
from tests.api.scenario import reports, session_config


def steps(explain: bool) -> list[StepResult]:
    config = SessionConfig.model_validate(session_config())
    engine = SessionEngine(fusion_config(config))
    frame = class_frame(config.classes)
    return [
        engine.apply(core_track_report(TrackReport.model_validate(body), frame), explain=explain)
        for body in reports(8)
    ]


@pytest.mark.parametrize("explain", [False, True])
def test_step_json_equals_step_plain(explain: bool) -> None:
    for seq, step in enumerate(steps(explain), start=1):
        fast = json.loads(step_json(step, seq))
        assert fast == json.loads(dumps(step_plain(step, seq)))
        WireStepResult.model_validate(fast)
    assert any(track["classification"] for track in fast["tracks"])
    assert (fast["association"]["matrix"] is not None) == explain


def test_step_json_refuses_non_finite_numbers() -> None:
    step = steps(False)[-1]
    track = step.tracks[0]
    state = track.state.copy()
    state[0] = math.nan
    broken = replace(step, tracks=(replace(track, state=state), *step.tracks[1:]))
    with pytest.raises(ValueError, match="non-finite state"):
        step_json(broken, 1)
    last = step.tracks[-1]
    covariance = last.covariance.copy()
    covariance[1, 1] = math.inf
    broken = replace(step, tracks=(*step.tracks[:-1], replace(last, covariance=covariance)))
    with pytest.raises(ValueError, match=rf"fused track '{last.id}': non-finite covariance"):
        step_json(broken, 1)
    broken = replace(step, tracks=(replace(track, score=-math.inf), *step.tracks[1:]))
    with pytest.raises(ValueError, match="non-finite score"):
        step_json(broken, 1)
    transposed = replace(
        step, tracks=(replace(track, covariance=np.asfortranarray(track.covariance.T)),)
    )
    assert (
        json.loads(step_json(transposed, 1))["tracks"][0]["covariance"]
        == track.covariance.T.tolist()
    )
