"""``credal-fusion replay`` (and the format ``credal-fusion export`` writes): a session's inputs
as JSON lines.

An event file (``EVENTS.jsonl``) is one JSON object per line: first
``{"type": "session", "config": {...}}`` (the resolved session config), then
every accepted input in order, ``{"type": <input kind>, "seq": n,
"report": {...}}`` (a tag of :mod:`app.inputs`: ``tracks``, ``detections``) (the items of ``GET /v1/sessions/{sid}/events``). When the
server had compacted the session's older inputs behind a snapshot, the
session line is followed by ``{"type": "snapshot", "seq": n, "state": {...}}``
and the inputs after ``n``: a local replay restores it, then continues.

``replay`` applies them in order, through an engine in this process or
through a running server, and prints one result per line: since the engine
is deterministic, the results are exactly those the session produced.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any, TextIO

from pydantic import BaseModel, ValidationError

from api_schemas.config import SessionConfig
from app.commands.errors import CommandError, pydantic_line
from app.commands.progress import shown as progress
from app.commands.runner import Input, run_locally, run_on_server
from app.inputs import INPUT_KINDS
from app.outputs.text import dumps

Body = dict[str, Any]


EVENT_LINE = '{"type": <input kind>, "seq": n, "report": {...}}'


def read_events(lines: TextIO) -> tuple[Body, list[Input]]:
    """The session config and the inputs of an event file, each line checked.

    Raises
    ------
    ValueError
        Naming the first malformed line and what it lacks.
    """
    config: Body | None = None
    inputs: list[Input] = []
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            event = json.loads(line)
        except ValueError as error:
            raise ValueError(f"line {number} is not JSON ({error})") from None
        kind = event.get("type") if isinstance(event, dict) else None
        if kind == "session":
            config = _checked(number, event, "config", SessionConfig)
        elif kind in INPUT_KINDS:
            inputs.append((kind, _checked(number, event, "report", INPUT_KINDS[kind].report_model)))
        elif kind == "snapshot" and not inputs:
            inputs.append((kind, {"seq": event["seq"], "state": event["state"]}))
        else:
            raise ValueError(
                f"line {number}: unknown event type {kind!r} (expected 'session', "
                f"then one {EVENT_LINE} per input)"
            )
    if config is None:
        raise ValueError('the event file has no session line ({"type": "session", "config": …})')
    return config, inputs


def _checked(number: int, event: Body, key: str, model: type[BaseModel]) -> Body:
    """``event[key]``, validated by ``model`` (the plain body is kept: it is what is sent)."""
    if not isinstance(event.get(key), dict):
        raise ValueError(f"line {number}: a {event['type']!r} event needs a {key!r} object")
    body: Body = event[key]
    try:
        model.model_validate(body)
    except ValidationError as error:
        raise ValueError(f"line {number}: invalid {key}: {pydantic_line(error)}") from None
    return body


def replay_command(args: argparse.Namespace) -> int:
    with Path(args.events).open(encoding="utf-8") as events:
        try:
            config, inputs = read_events(events)
        except ValueError as error:
            raise CommandError(
                f"{args.events}: {error}; replay reads the JSON lines `credal-fusion export` writes"
            ) from None
    if args.server and inputs and inputs[0][0] == "snapshot":
        print(
            f"{args.events} starts from a snapshot (the server had compacted the older inputs): "
            "a server cannot be given a state, replay it locally (without --server)",
            file=sys.stderr,
        )
        return 2
    shown = progress(inputs, "replay", args.quiet)
    results = (
        run_on_server(args.server, config, shown, on_session=_tell_session)
        if args.server
        else run_locally(config, shown)
    )
    for result in results:
        print(dumps(result))
    return 0


def _tell_session(session: str, token: str) -> None:
    print(f"replaying into session {session} (token {token}), left open", file=sys.stderr)
