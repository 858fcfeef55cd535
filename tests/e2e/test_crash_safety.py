"""Crash safety: a server on the sqlite store is killed with SIGKILL and restarted.

Every acknowledged input must be in the log after the restart, and the fused
state (``GET …/tracks``) must equal that of a run that was never interrupted,
bit for bit: the session is rebuilt from its latest snapshot plus the log
after it (snapshots every 3 inputs here, so both paths are exercised).
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import httpx

from api_schemas.reports import TrackReport
from tests.api.conftest import ADMIN_TOKEN
from tests.api.scenario import reports, session_config

ROOT = Path(__file__).resolve().parents[2]
START_TIMEOUT_S = 90.0
STEPS = 14
KILLED_AFTER = 8


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@contextmanager
def server(database: Path) -> Iterator[tuple[str, subprocess.Popen[bytes]]]:
    """``credal-fusion serve`` on the sqlite file ``database``, stopped (if alive) on exit."""
    port = free_port()
    environment = os.environ | {
        "CREDAL_ADMIN_TOKEN": ADMIN_TOKEN,
        "CREDAL_SNAPSHOT_EVERY": "3",
    }
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "app.cli",
            "serve",
            "--host",
            "127.0.0.1",
            "--port",
            str(port),
            "--store",
            f"sqlite:{database}",
        ],
        cwd=ROOT,
        env=environment,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + START_TIMEOUT_S
        while True:
            if process.poll() is not None:
                raise RuntimeError(
                    f"server exited: {process.stderr.read().decode() if process.stderr else ''}"
                )
            try:
                if httpx.get(f"{url}/healthz", timeout=1).status_code == 200:
                    break
            except httpx.TransportError:
                pass
            if time.monotonic() > deadline:
                raise RuntimeError("server did not start")
            time.sleep(0.05)
        yield url, process
    finally:
        if process.poll() is None:
            process.terminate()
            process.wait(timeout=START_TIMEOUT_S)
        if process.stderr is not None:
            process.stderr.close()


def post(url: str, sid: str, headers: dict[str, str], bodies: list[dict[str, Any]]) -> None:
    with httpx.Client(base_url=url, timeout=30) as client:
        for body in bodies:
            answer = client.post(f"/v1/sessions/{sid}/tracks", json=body, headers=headers)
            assert answer.status_code == 200, answer.text


def fused_tracks(url: str, sid: str, headers: dict[str, str]) -> Any:
    return httpx.get(f"{url}/v1/sessions/{sid}/tracks", headers=headers, timeout=30).json()


def test_acknowledged_inputs_survive_sigkill_and_the_state_is_exact(tmp_path: Path) -> None:
    bodies = reports(STEPS)
    with server(tmp_path / "reference.db") as (url, _):
        created = httpx.post(f"{url}/v1/sessions", json=session_config()).json()
        headers = {"Authorization": f"Bearer {created['token']}"}
        post(url, created["id"], headers, bodies[:KILLED_AFTER])
        reference_midway = fused_tracks(url, created["id"], headers)
        post(url, created["id"], headers, bodies[KILLED_AFTER:])
        reference = fused_tracks(url, created["id"], headers)

    database = tmp_path / "crashed.db"
    with server(database) as (url, process):
        created = httpx.post(f"{url}/v1/sessions", json=session_config()).json()
        sid, headers = created["id"], {"Authorization": f"Bearer {created['token']}"}
        post(url, sid, headers, bodies[:KILLED_AFTER])
        process.send_signal(signal.SIGKILL)
        process.wait(timeout=START_TIMEOUT_S)

    with server(database) as (url, _):
        events = httpx.get(f"{url}/v1/sessions/{sid}/events", headers=headers).json()
        assert [event["seq"] for event in events["events"]] == list(range(1, KILLED_AFTER + 1))
        logged = [TrackReport.model_validate(event["report"]) for event in events["events"]]
        assert logged == [TrackReport.model_validate(body) for body in bodies[:KILLED_AFTER]]
        summary = httpx.get(f"{url}/v1/sessions/{sid}", headers=headers).json()
        assert summary["seq"] == KILLED_AFTER
        assert fused_tracks(url, sid, headers) == reference_midway
        post(url, sid, headers, bodies[KILLED_AFTER:])
        assert fused_tracks(url, sid, headers) == reference


WRITERS = 6
ACKNOWLEDGED_BEFORE_KILL = 60


def test_concurrent_writers_lose_no_acknowledged_input_to_sigkill(tmp_path: Path) -> None:
    """Many sessions written at once share sqlite's commits (group commit); the server is
    killed while their inputs are in flight, and after the restart every input it
    acknowledged is logged, as it was sent, in its session's sequence, and each session's
    fused state (restored from its snapshot and log) equals that of a session of an
    uninterrupted server given the same inputs."""
    bodies = reports(200)
    database = tmp_path / "group.db"
    acknowledged: dict[str, int] = {}
    stop = threading.Event()
    with server(database) as (url, process):
        sessions = []
        for _ in range(WRITERS):
            created = httpx.post(f"{url}/v1/sessions", json=session_config()).json()
            sessions.append((created["id"], {"Authorization": f"Bearer {created['token']}"}))
            acknowledged[created["id"]] = 0

        def write(sid: str, headers: dict[str, str]) -> None:
            with httpx.Client(base_url=url, timeout=30) as client:
                for body in bodies:
                    if stop.is_set():
                        return
                    try:
                        answer = client.post(
                            f"/v1/sessions/{sid}/tracks", json=body, headers=headers
                        )
                    except httpx.TransportError:  # killed while this one was in flight
                        return
                    assert answer.status_code == 200, answer.text
                    acknowledged[sid] = answer.json()["seq"]

        threads = [threading.Thread(target=write, args=session) for session in sessions]
        for thread in threads:
            thread.start()
        while sum(acknowledged.values()) < ACKNOWLEDGED_BEFORE_KILL and any(
            thread.is_alive() for thread in threads
        ):
            time.sleep(0.005)
        process.send_signal(signal.SIGKILL)
        stop.set()
        for thread in threads:
            thread.join()
        process.wait(timeout=START_TIMEOUT_S)
    assert sum(acknowledged.values()) >= ACKNOWLEDGED_BEFORE_KILL

    restored: dict[str, tuple[int, Any]] = {}
    with server(database) as (url, _):
        for sid, headers in sessions:
            events = httpx.get(f"{url}/v1/sessions/{sid}/events", headers=headers).json()
            seqs = [event["seq"] for event in events["events"]]
            assert seqs == list(range(1, len(seqs) + 1))
            assert len(seqs) >= acknowledged[sid]
            logged = [TrackReport.model_validate(event["report"]) for event in events["events"]]
            assert logged == [TrackReport.model_validate(body) for body in bodies[: len(seqs)]]
            restored[sid] = (len(seqs), fused_tracks(url, sid, headers))

    with server(tmp_path / "reference.db") as (url, _):
        for count in sorted({count for count, _ in restored.values()}):
            created = httpx.post(f"{url}/v1/sessions", json=session_config()).json()
            headers = {"Authorization": f"Bearer {created['token']}"}
            post(url, created["id"], headers, bodies[:count])
            reference = fused_tracks(url, created["id"], headers)
            assert reference["seq"] == count and reference["tracks"]
            for logged_count, tracks in restored.values():
                if logged_count == count:
                    assert tracks == reference
