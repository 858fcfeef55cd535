"""docker/Dockerfile and docker/compose.yaml agree with the CLI, the settings and the stores.

Docker cannot run here, so the files are parsed: the image's CMD and the
compose service's command must be accepted by the real ``credal-fusion``
argument parser, their store URLs by :func:`parse_store_url`, the environment
must name real settings, and the health check (python's urllib) is executed
against a live server. The compose command itself is then run — against the
real Redis, on a free port — and must answer that health check and keep a
new session in Redis.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import subprocess
import sys
import time
import tomllib
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import httpx
import yaml

from app.cli import build_parser
from app.settings import Settings
from app.stores import RedisStore, parse_store_url
from tests.api.conftest import LiveServer
from tests.api.examples import SESSION_CONFIG
from tests.api.redis_support import REDIS_URL, redis_prefix, remaining_keys
from tests.test_serve import free_port

ROOT = Path(__file__).resolve().parents[2]
DOCKERFILE = ROOT / "docker" / "Dockerfile"
COMPOSE = ROOT / "docker" / "compose.yaml"
CONTAINER_PORT = 8000
SERVICE = "credal-fusion"
START_TIMEOUT_S = 90.0


def instructions() -> list[tuple[str, str]]:
    """The Dockerfile's instructions as (KEYWORD, arguments), continuation lines joined."""
    joined = re.sub(r"\\\n", " ", DOCKERFILE.read_text())
    parsed = []
    for line in joined.splitlines():
        line = line.strip()
        if line and not line.startswith("#"):
            keyword, _, arguments = line.partition(" ")
            parsed.append((keyword.upper(), arguments.strip()))
    return parsed


def instruction(keyword: str) -> list[str]:
    return [arguments for found, arguments in instructions() if found == keyword]


def exec_form(arguments: str) -> list[str]:
    """An instruction's JSON (exec) form; shell form is refused."""
    value = json.loads(arguments)
    assert isinstance(value, list) and all(isinstance(item, str) for item in value), arguments
    return value


def dockerfile_healthcheck() -> list[str]:
    [healthcheck] = instruction("HEALTHCHECK")
    options, _, command = healthcheck.partition("CMD ")
    assert "--interval" in options and "--timeout" in options
    return exec_form(command)


def compose() -> dict[str, Any]:
    document = yaml.safe_load(COMPOSE.read_text())
    assert isinstance(document, dict)
    return document


def serve_options(command: list[str]) -> Any:
    """The CLI's parse of a ``credal-fusion serve …`` command."""
    assert command[:2] == ["credal-fusion", "serve"], command
    return build_parser().parse_args(command[1:])


def test_dockerfile_image_user_port_and_command() -> None:
    assert instruction("FROM") == ["python:3.11-slim"]
    [user] = instruction("USER")
    assert user not in ("root", "0") and not user.startswith("0:")
    assert instruction("EXPOSE") == [str(CONTAINER_PORT)]
    [cmd] = instruction("CMD")
    options = serve_options(exec_form(cmd))
    assert (options.host, options.port) == ("0.0.0.0", CONTAINER_PORT)
    spec = parse_store_url(options.store)
    assert spec.kind == "sqlite" and spec.path == Path("/data/credal-fusion.db")
    assert any("/data" in volume for volume in instruction("VOLUME"))


def test_dockerfile_installs_the_project_from_pyproject() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    copied = {source for copy in instruction("COPY") for source in copy.split()[:-1]}
    assert {"pyproject.toml", project["project"]["readme"]} <= copied
    packages = project["tool"]["setuptools"]["packages"]["find"]["include"]
    assert {name.removesuffix("*") for name in packages} <= copied
    assert any("pip install ." in run for run in instruction("RUN"))
    ignored = set((ROOT / ".dockerignore").read_text().split())
    assert {".git", ".venv", "data"} <= ignored and not copied & ignored


def test_health_checks_use_python_not_curl() -> None:
    service = compose()["services"][SERVICE]
    for check in (dockerfile_healthcheck(), service["healthcheck"]["test"]):
        assert "curl" not in " ".join(check) and "wget" not in " ".join(check)
        assert check[-3:-1] == ["python", "-c"]
        assert f"127.0.0.1:{CONTAINER_PORT}/healthz" in check[-1]
    assert service["healthcheck"]["test"][-1] == dockerfile_healthcheck()[-1]
    assert compose()["services"]["redis"]["healthcheck"]["test"] == ["CMD", "redis-cli", "ping"]


def health_check_exit_code(port: int) -> int:
    code = dockerfile_healthcheck()[-1].replace(f":{CONTAINER_PORT}/", f":{port}/")
    return subprocess.run([sys.executable, "-c", code], capture_output=True).returncode


def test_the_health_check_passes_on_a_live_server_and_fails_without_one(
    live_server: LiveServer,
) -> None:
    assert health_check_exit_code(urlsplit(live_server.url).port or 0) == 0
    assert health_check_exit_code(free_port()) != 0


def test_compose_runs_the_service_on_the_redis_service() -> None:
    services = compose()["services"]
    assert set(services) == {SERVICE, "redis"}
    service = services[SERVICE]
    assert service["build"] == {"context": "..", "dockerfile": "docker/Dockerfile"}
    assert (
        ROOT / "docker" / service["build"]["context"] / service["build"]["dockerfile"]
    ).samefile(DOCKERFILE)
    options = serve_options([str(word) for word in service["command"]])
    spec = parse_store_url(options.store)
    assert spec.kind == "redis" and spec.url is not None
    assert urlsplit(spec.url).hostname == "redis"
    assert options.port == CONTAINER_PORT
    assert service["ports"] == [f"127.0.0.1:{CONTAINER_PORT}:{CONTAINER_PORT}"]
    assert service["depends_on"] == {"redis": {"condition": "service_healthy"}}
    environment = service["environment"]
    assert all(name.startswith("CREDAL_") for name in environment)
    settings_fields = {f"CREDAL_{name.upper()}" for name in Settings.model_fields}
    assert set(environment) <= settings_fields
    if "CREDAL_STORE" in environment:
        parse_store_url(environment["CREDAL_STORE"])
    settings = Settings.model_validate(
        {"redis_prefix": environment["CREDAL_REDIS_PREFIX"], "store": options.store}
    )
    assert settings.redis_prefix == "credal-fusion"
    redis_command = services["redis"]["command"]
    assert redis_command[redis_command.index("--appendfsync") + 1] == "always"


def test_the_compose_command_serves_with_the_redis_store() -> None:
    """The compose service's command, Redis on 127.0.0.1, a free port: healthy, sessions in Redis."""
    command = [str(word) for word in compose()["services"][SERVICE]["command"]]
    port = free_port()
    command[command.index("--port") + 1] = str(port)
    command[command.index("--host") + 1] = "127.0.0.1"
    command[command.index("--store") + 1] = REDIS_URL
    script = Path(sys.executable).with_name(command[0])
    with redis_prefix("compose") as prefix:
        server = subprocess.Popen(
            [str(script), *command[1:]],
            cwd=ROOT,
            env={**os.environ, "CREDAL_REDIS_PREFIX": prefix, "CREDAL_STORE": "memory"},
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
        )
        try:
            deadline = time.monotonic() + START_TIMEOUT_S
            while health_check_exit_code(port) != 0:
                assert server.poll() is None, f"{shlex.join(command)} exited"
                assert time.monotonic() < deadline, "the service did not become healthy"
                time.sleep(0.2)
            created = httpx.post(f"http://127.0.0.1:{port}/v1/sessions", json=SESSION_CONFIG)
            assert created.status_code == 201, created.text
            shared = RedisStore(REDIS_URL, prefix=prefix)
            stored = shared.get_session(created.json()["id"])
            shared.close()
            assert stored is not None and stored.config == created.json()["config"]
        finally:
            server.terminate()
            output = server.communicate(timeout=10)[0].decode()
        assert f"store: {REDIS_URL}" in output
    assert remaining_keys(prefix) == []
