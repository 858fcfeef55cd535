"""Running a sequence of service inputs, in this process or against a running server.

Both runners take the same wire bodies and return the same result JSON, so a
scenario, or an exported event log, gives identical results either way: the
engine is deterministic and the server is that engine behind HTTP.
"""

from __future__ import annotations

import contextlib
import json
from collections.abc import Callable, Iterable, Iterator
from typing import Any

import httpx

from api_schemas.config import SessionConfig
from api_schemas.reports import DetectionReport, TrackReport
from app.commands.errors import http_failure
from app.http.responses import dumps
from app.sessions.live import engine_from_snapshot
from app.sessions.translate import (
    core_detection_report,
    fusion_config,
    session_frame_report,
    step_plain,
)
from core.fusion.engine import SessionEngine

Body = dict[str, Any]
Input = tuple[str, Body]
"""``("tracks" | "detections", report)``, or ``("snapshot", {"seq": n, "state": {...}})``
first, for a history whose older inputs were compacted behind a snapshot."""


def run_locally(config: Body, inputs: Iterable[Input]) -> Iterator[Body]:
    """The results of ``inputs`` applied by an engine in this process (as the server would).

    A leading ``snapshot`` input restores the session's state at its ``seq``
    (nothing is yielded for it); the inputs after it continue from there.
    """
    session = SessionConfig.model_validate(config)
    engine = SessionEngine(fusion_config(session))
    seq = 0
    for kind, body in inputs:
        if kind == "snapshot":
            if seq:
                raise ValueError("a snapshot can only start a history")
            _, restored = engine_from_snapshot(session, body["state"], engine.config)
            engine = restored if restored is not None else engine
            seq = int(body["seq"])
            continue
        seq += 1
        if kind == "tracks":
            step = engine.apply(session_frame_report(TrackReport.model_validate(body), session))
        else:
            step = engine.apply_detections(
                core_detection_report(DetectionReport.model_validate(body), session)
            )
        yield json.loads(dumps(step_plain(step, seq)))


def run_on_server(
    server: str,
    config: Body,
    inputs: Iterable[Input],
    *,
    on_session: Callable[[str, str], None] | None = None,
    keep: bool = True,
) -> Iterator[Body]:
    """Create a session on ``server`` and post every input; yields each result.

    ``on_session(id, token)`` is told the new session's id and bearer token.
    Unless ``keep``, the session is deleted when the run ends (or fails); a
    server that cannot be reached then leaves it to its idle timeout.
    """
    with httpx.Client(base_url=server.rstrip("/"), timeout=60.0) as client:
        created = client.post("/v1/sessions", json=config)
        raise_for_problem(created)
        session = created.json()
        if on_session is not None:
            on_session(session["id"], session["token"])
        headers = {"Authorization": f"Bearer {session['token']}"}
        try:
            for kind, body in inputs:
                if kind == "snapshot":
                    raise ValueError(
                        "this history starts from a snapshot (its older inputs were compacted): "
                        "replay it locally"
                    )
                answer = client.post(
                    f"/v1/sessions/{session['id']}/{kind}", json=body, headers=headers
                )
                raise_for_problem(answer)
                yield answer.json()
        finally:
            if not keep:
                with contextlib.suppress(httpx.TransportError):
                    client.delete(f"/v1/sessions/{session['id']}", headers=headers)


def raise_for_problem(answer: httpx.Response) -> None:
    """Raise a one-line :class:`CommandError` if ``answer`` is not a success."""
    if answer.is_success:
        return
    try:
        body = answer.json()
    except ValueError:
        body = answer.text
    raise http_failure(answer.request.method, answer.request.url.path, answer.status_code, body)
