"""The set-up: `make run` installs only the service, `make test` what the tests need.

Read from ``make --dry-run --always-make`` (the commands each target would run,
none of them run) and by running the helper scripts of ``tools/`` for real.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.api.redis_support import REDIS_URL

ROOT = Path(__file__).resolve().parents[1]
TOOLS = ROOT / "tools"


def planned(target: str) -> list[str]:
    """The commands ``make target`` would run on a fresh clone, in order."""
    if shutil.which("make") is None:
        pytest.fail("make is missing: it is the README's command")
    done = subprocess.run(
        ["make", "--dry-run", "--always-make", target],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    return done.stdout.splitlines()


def pip_installs(commands: list[str]) -> list[str]:
    """What each ``pip install`` of ``commands`` installs (its last argument)."""
    return [command.split()[-1] for command in commands if "-m pip install" in command]


def test_make_run_installs_the_service_alone() -> None:
    commands = planned("run")
    assert pip_installs(commands) == ["pip", "."]  # pip's upgrade, then the project, no extra
    assert any("credal-fusion serve" in command for command in commands)


def test_make_test_installs_the_extras_and_the_system_prerequisites_first() -> None:
    commands = planned("test")
    assert "'.[dev,figures]'" in pip_installs(commands)
    prerequisites = commands.index("tools/test-prerequisites")
    lint = next(index for index, command in enumerate(commands) if "ruff check" in command)
    [pytest_run] = [command for command in commands if "-m pytest" in command]
    assert prerequisites < lint < commands.index(pytest_run)
    assert pytest_run.startswith("tools/with-test-redis ")


def test_every_pip_install_goes_through_the_heartbeat() -> None:
    installs = [command for command in planned("test") if "-m pip install" in command]
    assert installs and all("tools/heartbeat.py" in command for command in installs)


def test_ci_runs_make_test() -> None:
    ci_run = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    commands = [line for line in ci_run.splitlines() if line and not line.startswith("#")]
    assert commands[-1] == "exec make test"
    assert "apt-get" not in ci_run  # make test installs what it needs


def test_prerequisites_present_are_named_and_pass() -> None:
    done = subprocess.run([TOOLS / "test-prerequisites"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("==> test prerequisites present: /usr/bin/chromium, ")
    assert done.stdout.rstrip().endswith("redis-server")


def test_the_tests_run_with_the_redis_that_answers() -> None:
    show = "import os, sys; print(os.environ['CREDAL_TEST_REDIS_URL']); sys.exit(3)"
    done = subprocess.run(
        [TOOLS / "with-test-redis", sys.executable, sys.executable, "-c", show],
        capture_output=True,
        text=True,
        env={**os.environ, "CREDAL_TEST_REDIS_URL": REDIS_URL},
    )
    assert done.returncode == 3  # the command's own status
    assert done.stdout.splitlines() == [f"==> tests use the Redis at {REDIS_URL}", REDIS_URL]


def test_a_redis_url_that_does_not_answer_is_an_error() -> None:
    dead = "redis://127.0.0.1:1/0"
    done = subprocess.run(
        [TOOLS / "with-test-redis", sys.executable, "true"],
        capture_output=True,
        text=True,
        env={**os.environ, "CREDAL_TEST_REDIS_URL": dead},
    )
    assert done.returncode == 1
    assert done.stderr.strip() == f"error: no Redis answers at CREDAL_TEST_REDIS_URL={dead}"


def test_the_heartbeat_speaks_during_a_silence_and_keeps_the_status() -> None:
    """The command prints a line, then waits (silent) until the test has seen a heartbeat."""
    child = (
        "import sys; print('first', flush=True); sys.stdin.readline(); print('last'); sys.exit(4)"
    )
    runner = (
        "import runpy, sys; sys.argv = sys.argv[1:]; "
        "main = runpy.run_path(sys.argv[0])['main']; main.__globals__['SILENCE_S'] = 0.05; "
        "sys.exit(main(sys.argv[1:]))"
    )
    with subprocess.Popen(
        [sys.executable, "-c", runner, str(TOOLS / "heartbeat.py"), sys.executable, "-c", child],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    ) as process:
        assert process.stdin is not None and process.stdout is not None
        while (line := process.stdout.readline()) != "first\n":  # heartbeats while it starts
            assert line.startswith("    ... still working"), line
        heartbeat = process.stdout.readline()
        process.stdin.write("\n")
        process.stdin.flush()
        rest = process.stdout.read()
    assert re.fullmatch(r" {4}\.\.\. still working, \d+ s since: first\n", heartbeat), heartbeat
    assert rest.splitlines()[-1] == "last"
    assert process.returncode == 4
