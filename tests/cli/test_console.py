"""The installed ``credal-fusion`` console script, run as a subprocess against a live server.

Failures are one line on stderr (what failed, what to do) with a non-zero
exit status and no traceback unless ``--debug``; ``simulate --server`` tells
the session, its token and the viewer URL that opens it.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
from pathlib import Path
from urllib.parse import parse_qs, urlsplit

import httpx
import pytest

from app.cli import build_parser, main
from app.commands.errors import CommandError
from app.commands.export import export_events
from tests.api.conftest import ADMIN_TOKEN, LiveServer, live_server
from tests.api.examples import SESSION_CONFIG, TRACK_REPORT

__all__ = ["live_server"]

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = Path(sys.executable).with_name("credal-fusion")
TIMEOUT_S = 120.0


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(SCRIPT), *args],
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        check=False,
        env={**os.environ, "COLUMNS": "200"},
    )


def one_line_failure(done: subprocess.CompletedProcess[str]) -> str:
    """The single stderr line of a failed run (asserting there is exactly one, and no traceback)."""
    assert done.returncode != 0, done.stdout
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert "Traceback" not in done.stderr
    return lines[0]


def session(server: LiveServer) -> tuple[str, str]:
    created = httpx.post(f"{server.url}/v1/sessions", json=SESSION_CONFIG).json()
    return created["id"], created["token"]


def test_export_with_a_wrong_token_says_so_in_one_line(live_server: LiveServer) -> None:
    sid, _ = session(live_server)
    done = cli("export", "--server", live_server.url, "--session", sid, "--token", "wrong")
    line = one_line_failure(done)
    # 404, as for an unknown session: a token cannot tell which sessions exist
    assert line.startswith(f"credal-fusion export: GET /v1/sessions/{sid} answered 404")
    assert "--token" in line
    assert done.stdout == ""


def test_a_server_that_is_not_running_is_named_with_what_to_do() -> None:
    with socket.socket() as probe:  # a port nobody listens on: bound, never listening
        probe.bind(("127.0.0.1", 0))
        url = f"http://127.0.0.1:{probe.getsockname()[1]}"
        done = cli("simulate", "t2t-four", "--server", url, "--quiet")
    line = one_line_failure(done)
    assert line.startswith(f"credal-fusion simulate: cannot connect to {url}")
    assert "credal-fusion serve" in line
    assert done.stdout == ""


def test_serve_with_a_store_it_cannot_open_says_so_before_serving(tmp_path: Path) -> None:
    # a directory is no sqlite file (an unreachable Redis is an outage: the service starts,
    # tests/e2e/test_store_outage.py)
    done = cli("serve", "--store", f"sqlite:{tmp_path}", "--port", "0")
    line = one_line_failure(done)
    assert line.startswith(f"credal-fusion serve: cannot use the store sqlite:{tmp_path}")
    assert "--store" in line


def test_replay_of_a_malformed_line_names_the_line(live_server: LiveServer, tmp_path: Path) -> None:
    sid, token = session(live_server)
    posted = httpx.post(
        f"{live_server.url}/v1/sessions/{sid}/tracks",
        json=TRACK_REPORT,
        headers={"Authorization": f"Bearer {token}"},
    )
    assert posted.status_code == 200
    session_line, input_line = export_events(live_server.url, sid, token)
    broken = json.loads(input_line)
    del broken["report"]
    events = tmp_path / "events.jsonl"
    events.write_text(f"{session_line}\n{json.dumps(broken)}\n")
    line = one_line_failure(cli("replay", str(events), "--quiet"))
    assert line == (
        f"credal-fusion replay: {events}: line 2: a 'tracks' event needs a 'report' object; "
        "replay reads the JSON lines `credal-fusion export` writes"
    )
    with pytest.raises(CommandError, match="line 2: a 'tracks' event needs a 'report'"):
        main(["replay", str(events), "--quiet", "--debug"])  # --debug: the exception itself


def test_debug_goes_before_or_after_the_command() -> None:
    parser = build_parser()
    assert parser.parse_args(["--debug", "replay", "e.jsonl"]).debug
    assert parser.parse_args(["replay", "e.jsonl", "--debug"]).debug
    assert not parser.parse_args(["replay", "e.jsonl"]).debug


def test_simulate_against_a_server_tells_the_session_and_its_viewer(
    live_server: LiveServer, capsys: pytest.CaptureFixture[str]
) -> None:
    kept = cli("simulate", "t2t-four", "--server", live_server.url, "--keep", "--quiet")
    assert kept.returncode == 0, kept.stderr
    lines = kept.stdout.splitlines()
    assert lines[0].startswith("session ") and lines[1].startswith("viewer: ")
    sid, token = lines[0].split()[1], lines[0].split("(token ")[1].rstrip(")")
    viewer = urlsplit(lines[1].removeprefix("viewer: "))
    assert f"{viewer.scheme}://{viewer.netloc}{viewer.path}" == f"{live_server.url}/"
    assert parse_qs(viewer.fragment) == {"session": [sid], "token": [token]}
    assert "identity switches: 0" in kept.stdout
    assert lines[-1].startswith(f"session {sid} left open")
    # The printed token opens the session, which holds all 40 inputs of t2t-four.
    summary = httpx.get(
        f"{live_server.url}/v1/sessions/{sid}", headers={"Authorization": f"Bearer {token}"}
    )
    assert summary.status_code == 200 and summary.json()["seq"] == 40

    # Without --keep (in process, to spare a start-up): deleted at the end, and it says so.
    assert main(["simulate", "t2t-four", "--server", live_server.url, "--quiet"]) == 0
    deleted = capsys.readouterr().out.splitlines()
    other = deleted[0].split()[1]
    assert deleted[-1] == f"session {other} deleted at the end of the run (--keep leaves it open)"
    admin = {"Authorization": f"Bearer {ADMIN_TOKEN}"}
    listed = httpx.get(f"{live_server.url}/v1/sessions", headers=admin).json()
    ids = {entry["id"] for entry in listed["sessions"]}
    assert sid in ids and other not in ids


# ---------------------------------------------------------------- issue 27: the CLI as met
def test_a_server_without_a_scheme_is_read_as_http(live_server: LiveServer) -> None:
    sid, token = session(live_server)
    bare = live_server.url.removeprefix("http://")
    done = cli("export", "--server", bare, "--session", sid, "--token", token)
    assert done.returncode == 0, done.stderr
    [first] = done.stdout.splitlines()  # the session line (no input yet)
    assert json.loads(first)["config"]["name"] == SESSION_CONFIG["name"]


def test_a_server_url_of_another_scheme_is_refused_naming_http() -> None:
    done = cli("export", "--server", "ws://127.0.0.1:8000", "--session", "s", "--token", "t")
    assert done.returncode == 2
    assert "starts with http:// or https://, not ws://" in done.stderr


@pytest.mark.parametrize(
    ("flags", "says"),
    [
        (
            ["--speed", "1"],
            "--speed paces the inputs for a server's live viewer: it needs --server",
        ),
        (["--keep"], "--keep leaves the server's session open: it needs --server"),
        (["--preset", "aircraft"], "t2t-four is a track-list scenario (no local tracking)"),
    ],
)
def test_a_flag_that_would_do_nothing_is_refused(flags: list[str], says: str) -> None:
    done = cli("simulate", "t2t-four", "--quiet", *flags)
    assert done.returncode == 2
    assert done.stdout == ""
    assert done.stderr.startswith("credal-fusion simulate: ") and says in done.stderr
    assert len(done.stderr.splitlines()) == 1


def test_serve_on_a_busy_port_is_one_line_and_no_banner() -> None:
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        done = cli("serve", "--port", str(port), "--store", "memory")
    line = one_line_failure(done)
    assert line == (
        f"credal-fusion serve: 127.0.0.1:{port} is in use (another credal-fusion serve?): "
        "stop it, or choose another port with --port"
    )
    assert done.stdout == ""  # no banner


def test_serve_refuses_workers_that_cannot_share_the_memory_store() -> None:
    done = cli("serve", "--port", "0", "--store", "memory", "--workers", "2")
    assert one_line_failure(done) == (
        "credal-fusion serve: the memory store is one process's: it cannot be shared by 2 "
        "workers; use --workers 1, or a sqlite or redis store"
    )
    assert done.stdout == ""


HEAVY = ("numpy", "scipy", "core", "pydantic", "app.sessions", "app.main")


def test_export_loads_neither_the_engine_nor_numpy(live_server: LiveServer) -> None:
    """The real export, then the modules it had loaded: a few GETs need httpx alone."""
    sid, token = session(live_server)
    probe = (
        "import sys; from app.cli import main; status = main(sys.argv[1:]); "
        f"heavy = sorted(m for m in sys.modules if m.startswith({HEAVY!r})); "
        "print(heavy, file=sys.stderr); sys.exit(status)"
    )
    export = ["export", "--server", live_server.url, "--session", sid, "--token", token]
    done = subprocess.run(
        [sys.executable, "-c", probe, *export],
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip() == "[]"
    assert json.loads(done.stdout.splitlines()[0])["type"] == "session"


def test_reproduce_writes_outside_the_tracked_tree_by_default(tmp_path: Path) -> None:
    done = subprocess.run(
        [str(SCRIPT), "reproduce", "aircraft", "--reduced"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        check=False,
        env={**os.environ, "MPLBACKEND": "Agg"},
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-1] == "out/figures/aircraft.png"
    assert [path.relative_to(tmp_path) for path in tmp_path.rglob("*.png")] == [
        Path("out/figures/aircraft.png")
    ]
    ignored = subprocess.run(
        ["git", "check-ignore", "-q", "out/figures/aircraft.png"], cwd=ROOT, check=False
    )
    assert ignored.returncode == 0, "out/ must be ignored by git in a checkout"
