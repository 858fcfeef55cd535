"""``credal-fusion export``: a session's event log, as the JSON lines ``replay`` reads.

The format is described in :mod:`app.commands.replay`. This module imports
only httpx and the standard library: an export is a few GETs, and it starts
without loading the engine (numpy, scipy, the schemas) that ``replay`` needs.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Iterator
from typing import Any

import httpx

from app.commands.errors import raise_for_problem


def dumps(event: dict[str, Any]) -> str:
    """One line of the event file: compact JSON (what the server sent, re-encoded)."""
    return json.dumps(event, allow_nan=False, separators=(",", ":"))


def export_events(server: str, session: str, token: str) -> Iterator[str]:
    """The event file of a session of a running server, line by line."""
    headers = {"Authorization": f"Bearer {token}"}
    with httpx.Client(base_url=server.rstrip("/"), headers=headers, timeout=60.0) as client:
        summary = client.get(f"/v1/sessions/{session}")
        raise_for_problem(summary)
        yield dumps({"type": "session", "config": summary.json()["config"]})
        after = 0
        while True:
            page = client.get(f"/v1/sessions/{session}/events", params={"after": after})
            raise_for_problem(page)
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
