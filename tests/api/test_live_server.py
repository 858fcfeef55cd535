"""Against a real uvicorn server on 127.0.0.1: the body-size limit and the metrics."""

from __future__ import annotations

import json
from collections.abc import Iterator

import httpx

from tests.api.conftest import ADMIN_TOKEN, LiveServer
from tests.api.examples import SESSION_CONFIG, TRACK_REPORT


def oversize_body(limit: int) -> bytes:
    """A valid-looking JSON body larger than ``limit``."""
    report = dict(TRACK_REPORT, padding="x" * (2 * limit))
    return json.dumps(report).encode()


def test_declared_oversize_body_is_413_naming_the_limit(live_server: LiveServer) -> None:
    limit = live_server.settings.max_body_bytes
    with httpx.Client(base_url=live_server.url) as client:
        response = client.post(
            "/v1/sessions",
            content=oversize_body(limit),
            headers={"Content-Type": "application/json"},
        )
        assert response.status_code == 413
        assert response.headers["content-type"].startswith("application/problem+json")
        problem = response.json()
        assert problem["limit"] == "max_body_bytes" and problem["maximum"] == limit
        assert problem["instance"] == "/v1/sessions"
        assert client.get("/healthz").status_code == 200


def test_chunked_oversize_body_is_413(live_server: LiveServer) -> None:
    limit = live_server.settings.max_body_bytes
    body = oversize_body(limit)

    def chunks() -> Iterator[bytes]:
        for start in range(0, len(body), 4096):
            yield body[start : start + 4096]

    with httpx.Client(base_url=live_server.url) as client:
        response = client.post(
            "/v1/sessions", content=chunks(), headers={"Content-Type": "application/json"}
        )
    assert response.status_code == 413
    assert response.json()["limit"] == "max_body_bytes"


def test_chunked_body_under_the_limit_reaches_the_route(live_server: LiveServer) -> None:
    body = json.dumps(SESSION_CONFIG).encode()

    def chunks() -> Iterator[bytes]:
        for start in range(0, len(body), 100):
            yield body[start : start + 100]

    with httpx.Client(base_url=live_server.url) as client:
        response = client.post(
            "/v1/sessions", content=chunks(), headers={"Content-Type": "application/json"}
        )
    assert response.status_code == 201, response.text


def test_metrics_count_requests_by_route_template(live_server: LiveServer) -> None:
    with httpx.Client(base_url=live_server.url) as client:
        created = client.post("/v1/sessions", json=SESSION_CONFIG).json()
        headers = {"Authorization": f"Bearer {created['token']}"}
        for _ in range(3):
            assert (
                client.get(f"/v1/sessions/{created['id']}/events", headers=headers).status_code
                == 200
            )
        client.get("/v1/sessions", headers={"Authorization": f"Bearer {ADMIN_TOKEN}"})
        metrics = client.get("/metrics")
    assert metrics.status_code == 200
    assert metrics.headers["content-type"].startswith("text/plain")
    text = metrics.text
    assert (
        'credal_http_requests_total{method="GET",route="/v1/sessions/{sid}/events",status="200"} 3.0'
        in text
    )
    assert created["id"] not in text
    assert "credal_sessions 1.0" in text
    assert (
        'credal_http_request_duration_seconds_count{method="POST",route="/v1/sessions"} 1.0' in text
    )
    for name in ("credal_inputs_total", "credal_fusion_step_seconds"):
        assert f"# TYPE {name.removesuffix('_total')}" in text


def _sample(text: str, series: str) -> float:
    """The value of one exposed series (its full name with labels)."""
    (line,) = [line for line in text.splitlines() if line.startswith(series + " ")]
    return float(line.rsplit(" ", 1)[1])


def test_engine_cpu_is_counted_per_applied_input(live_server: LiveServer) -> None:
    """Each applied input adds one engine-step CPU sample beside its apply step; a refused
    (stale) input adds none, to either."""
    with httpx.Client(base_url=live_server.url) as client:
        created = client.post("/v1/sessions", json=SESSION_CONFIG).json()
        headers = {"Authorization": f"Bearer {created['token']}"}
        path = f"/v1/sessions/{created['id']}/tracks"
        for time in (12.5, 13.5, 14.5):
            answer = client.post(path, json=TRACK_REPORT | {"time": time}, headers=headers)
            assert answer.status_code == 200, answer.text
        assert client.post(path, json=TRACK_REPORT, headers=headers).status_code == 409
        text = client.get("/metrics").text
    assert "# TYPE credal_fusion_engine_cpu_seconds histogram" in text
    for name in ("credal_fusion_engine_cpu_seconds", "credal_fusion_step_seconds"):
        assert _sample(text, f'{name}_count{{kind="tracks"}}') == 3.0
        assert _sample(text, f'{name}_sum{{kind="tracks"}}') > 0.0
