"""Settings that protect users, and what the service does when it has a bug.

- session creation is atomic against ``max_sessions`` (1 001 were created of 1 000);
- CORS is off unless ``CREDAL_CORS_ORIGINS`` names origins;
- an internal error is a counted 500 problem that keeps the keep-alive connection;
- the admin token has a minimum length; an empty one means none.
"""

from __future__ import annotations

import http.client
import json
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import httpx
import pytest
from fastapi.testclient import TestClient

from app.main import create_app
from tests.api.conftest import ADMIN_TOKEN, make_settings, serving
from tests.api.examples import SESSION_CONFIG

ADMIN = {"Authorization": f"Bearer {ADMIN_TOKEN}"}


def test_concurrent_creations_never_exceed_the_session_limit(tmp_path: Path) -> None:
    """On sqlite (where counting and creating are two transactions of worker threads)."""
    limit, attempts = 5, 40
    settings = make_settings(
        max_sessions=limit, rate_limit="none", store=f"sqlite:{tmp_path / 'sessions.db'}"
    )
    with serving(settings) as server:

        def create(_: int) -> int:
            with httpx.Client(base_url=server.url, timeout=60) as client:
                return client.post("/v1/sessions", json=SESSION_CONFIG).status_code

        with ThreadPoolExecutor(max_workers=16) as pool:
            statuses = list(pool.map(create, range(attempts)))
        listed = httpx.get(f"{server.url}/v1/sessions", headers=ADMIN).json()["sessions"]
    assert statuses.count(201) == limit == len(listed)
    assert statuses.count(429) == attempts - limit


def test_cors_is_off_by_default() -> None:
    with TestClient(create_app(make_settings())) as client:
        preflight = client.options(
            "/v1/sessions",
            headers={"Origin": "https://evil.example", "Access-Control-Request-Method": "POST"},
        )
        plain = client.get("/healthz", headers={"Origin": "https://evil.example"})
    assert "access-control-allow-origin" not in preflight.headers
    assert "access-control-allow-origin" not in plain.headers


def test_cors_allows_only_the_configured_origins() -> None:
    settings = make_settings(cors_origins="https://viewer.example, https://ops.example")
    with TestClient(create_app(settings)) as client:
        allowed = client.get("/healthz", headers={"Origin": "https://ops.example"})
        other = client.get("/healthz", headers={"Origin": "https://evil.example"})
        preflight = client.options(
            "/v1/sessions",
            headers={
                "Origin": "https://viewer.example",
                "Access-Control-Request-Method": "POST",
                "Access-Control-Request-Headers": "authorization, content-type",
            },
        )
    assert allowed.headers["access-control-allow-origin"] == "https://ops.example"
    assert "access-control-allow-origin" not in other.headers
    assert preflight.status_code == 200
    assert preflight.headers["access-control-allow-origin"] == "https://viewer.example"


def test_an_internal_error_is_a_counted_500_problem_and_keeps_the_connection() -> None:
    settings = make_settings()
    app = create_app(settings)

    def crash() -> None:
        raise RuntimeError("a bug")

    app.add_api_route("/crash", crash)
    with serving(settings, app=app) as server:
        port = int(server.url.rsplit(":", 1)[1])
        connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
        try:
            for _ in range(2):
                connection.request("GET", "/crash")
                response = connection.getresponse()
                problem = json.loads(response.read())
                assert response.status == 500
                assert response.getheader("content-type") == "application/problem+json"
                assert problem["type"] == "urn:credal-fusion:problem:internal-error"
                assert "a bug" not in json.dumps(problem)  # no internals
            connection.request("GET", "/metrics")  # the same connection still answers
            metrics = connection.getresponse().read().decode()
        finally:
            connection.close()
    assert "credal_internal_errors_total 2.0" in metrics


def test_the_admin_token_has_a_minimum_length() -> None:
    with pytest.raises(ValueError, match="at least 32 characters"):
        make_settings(admin_token="x" * 31)
    assert make_settings(admin_token="x" * 32).admin_token is not None
    assert make_settings(admin_token="").admin_token is None  # CREDAL_ADMIN_TOKEN= : none
