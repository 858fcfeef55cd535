"""``credal-fusion export`` and ``credal-fusion replay``: a session's inputs as JSON lines.

An event file (``EVENTS.jsonl``) is one JSON object per line: first
``{"type": "session", "config": {...}}`` (the resolved session config), then
every accepted input in order, ``{"type": "tracks" | "detections", "seq": n,
"report": {...}}`` (the items of ``GET /v1/sessions/{sid}/events``).

``replay`` applies them in order, through an engine in this process or
through a running server, and prints one result per line: since the engine
is deterministic, the results are exactly those the session produced.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any, TextIO

import httpx

from app.commands.progress import shown as progress
from app.commands.runner import Input, run_locally, run_on_server
from app.responses import dumps

Body = dict[str, Any]


def read_events(lines: TextIO) -> tuple[Body, list[Input]]:
    """The session config and the inputs of an event file."""
    config: Body | None = None
    inputs: list[Input] = []
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        event = json.loads(line)
        kind = event.get("type")
        if kind == "session":
            config = event["config"]
        elif kind in ("tracks", "detections"):
            inputs.append((kind, event["report"]))
        else:
            raise ValueError(f"line {number}: unknown event type {kind!r}")
    if config is None:
        raise ValueError("the event file has no session line")
    return config, inputs


def export_events(server: str, session: str, token: str) -> Iterator[str]:
    """The event file of a session of a running server, line by line."""
    headers = {"Authorization": f"Bearer {token}"}
    with httpx.Client(base_url=server.rstrip("/"), headers=headers, timeout=60.0) as client:
        summary = client.get(f"/v1/sessions/{session}")
        summary.raise_for_status()
        yield dumps({"type": "session", "config": summary.json()["config"]})
        after = 0
        while True:
            page = client.get(f"/v1/sessions/{session}/events", params={"after": after})
            page.raise_for_status()
            events = page.json()["events"]
            if not events:
                return
            for event in events:
                yield dumps({"type": event["type"], "seq": event["seq"], "report": event["report"]})
            after = events[-1]["seq"]


def export_command(args: argparse.Namespace) -> int:
    for line in export_events(args.server, args.session, args.token):
        print(line)
    return 0


def replay_command(args: argparse.Namespace) -> int:
    with Path(args.events).open(encoding="utf-8") as events:
        config, inputs = read_events(events)
    shown = progress(inputs, "replay", args.quiet)
    results = (
        run_on_server(args.server, config, shown) if args.server else run_locally(config, shown)
    )
    for result in results:
        print(dumps(result))
    return 0
