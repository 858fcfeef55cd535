"""``credal-fusion export`` and ``credal-fusion replay``: a session's inputs as JSON lines.

An event file (``EVENTS.jsonl``) is one JSON object per line: first
``{"type": "session", "config": {...}}`` (the resolved session config), then
every accepted input in order, ``{"type": "tracks" | "detections", "seq": n,
"report": {...}}`` (the items of ``GET /v1/sessions/{sid}/events``). When the
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
from collections.abc import Iterator
from pathlib import Path
from typing import Any, TextIO

import httpx
from tqdm import tqdm

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
        elif kind == "snapshot" and not inputs:
            inputs.append((kind, {"seq": event["seq"], "state": event["state"]}))
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
            body = page.json()
            snapshot, events = body.get("snapshot"), body["events"]
            if snapshot is not None:  # the inputs up to it were compacted
                yield dumps(
                    {"type": "snapshot", "seq": snapshot["seq"], "state": snapshot["state"]}
                )
                after = snapshot["seq"]
            if not events:
                if snapshot is None:
                    return
                continue
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
    if args.server and inputs and inputs[0][0] == "snapshot":
        print(
            f"{args.events} starts from a snapshot (the server had compacted the older inputs): "
            "a server cannot be given a state, replay it locally (without --server)",
            file=sys.stderr,
        )
        return 2
    shown = tqdm(inputs, desc="replay", unit="input", file=sys.stderr, disable=args.quiet)
    results = (
        run_on_server(args.server, config, shown) if args.server else run_locally(config, shown)
    )
    for result in results:
        print(dumps(result))
    return 0
