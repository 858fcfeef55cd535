"""Running a sequence of service inputs, in this process or against a running server.

Both runners take the same wire bodies and return the same result JSON, so a
scenario, or an exported event log, gives identical results either way: the
engine is deterministic and the server is that engine behind HTTP.
"""

from __future__ import annotations

import contextlib
import json
from collections.abc import Callable, Iterable, Iterator
from datetime import UTC, datetime
from typing import Any

import httpx

from api_schemas.limits import MAX_SENSORS
from app.commands.errors import raise_for_problem
from app.inputs import parse_input
from app.outputs.json_results import step_json
from app.sessions.live import new_session, restore_snapshot
from app.stores import SessionRecord, Snapshot

Body = dict[str, Any]
Input = tuple[str, Body]
"""``(input kind tag, report)`` (:mod:`app.inputs`), or ``("snapshot", {"seq": n, "state": {...}})``
first, for a history whose older inputs were compacted behind a snapshot."""


def run_locally(config: Body, inputs: Iterable[Input]) -> Iterator[Body]:
    """The results of ``inputs`` applied by an engine in this process (as the server would:
    each input parsed by its kind and checked against the session's config first).

    A leading ``snapshot`` input restores the session's state at its ``seq``
    (nothing is yielded for it); the inputs after it continue from there.
    """
    record = SessionRecord(id="local", config=config, token_hash="", created_at=datetime.now(UTC))
    session = new_session(record)
    for kind, body in inputs:
        if kind == "snapshot":
            if session.seq:
                raise ValueError("a snapshot can only start a history")
            state = Snapshot(seq=int(body["seq"]), taken_at=record.created_at, state=body["state"])
            restore_snapshot(session, state)
            continue
        submitted = parse_input(kind, body)
        submitted.check(session.config)
        engine, _ = session.engine_for(submitted.sensor, MAX_SENSORS)
        applied = submitted.apply(engine, session.config, explain=False)  # a refusal ends the run
        session.engine = engine
        session.seq += 1
        yield json.loads(step_json(applied.step, session.seq))


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
