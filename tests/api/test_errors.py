"""Error mapping: service errors, core InvalidInput, HTTP errors and the unexpected all become problem+json."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from fastapi import FastAPI
from fastapi.testclient import TestClient

from app.http.errors import LimitExceeded, StaleReport, install_error_handlers
from core.distance.estimates import check_covariances
from core.errors import CovarianceError, MassError, TotalConflict

SECRET = "/srv/secret/path/and-a-password"


def build_failing_app() -> FastAPI:
    app = FastAPI()
    install_error_handlers(app)

    @app.get("/stale")
    def stale() -> None:
        raise StaleReport("radar-1", 3.0, 5.5)

    @app.get("/core-invalid")
    def core_invalid() -> None:
        raise MassError("masses sum to 0.7 for focal set {a}")

    @app.get("/core-located")
    def core_located() -> None:
        raise CovarianceError(
            "tracks[3].covariance is not symmetric", loc=("tracks", 3, "covariance")
        )

    @app.get("/core-internal")
    def core_internal() -> None:
        raise TotalConflict(1.0)

    @app.get("/crash")
    def crash() -> None:
        raise RuntimeError(f"cannot open {SECRET}")

    @app.get("/limit")
    def limit() -> None:
        raise LimitExceeded("max_tracks_per_input", 10, 11, what="tracks")

    return app


@pytest.fixture(scope="module")
def failing_client() -> Iterator[TestClient]:
    with TestClient(build_failing_app(), raise_server_exceptions=False) as client:
        yield client


def test_stale_report_is_409_with_both_times(failing_client: TestClient) -> None:
    response = failing_client.get("/stale")
    assert response.status_code == 409
    problem = response.json()
    assert problem["type"] == "urn:credal-fusion:problem:stale-report"
    assert (problem["time"], problem["last_time"], problem["sensor"]) == (3.0, 5.5, "radar-1")
    assert problem["instance"] == "/stale"


def test_core_invalid_input_is_422(failing_client: TestClient) -> None:
    response = failing_client.get("/core-invalid")
    assert response.status_code == 422
    assert response.headers["content-type"].startswith("application/problem+json")
    assert "masses sum to 0.7" in response.json()["detail"]


def test_core_errors_are_located_and_unlocated_ones_point_at_the_body(
    failing_client: TestClient,
) -> None:
    located = failing_client.get("/core-located").json()
    assert located["errors"] == [
        {
            "loc": ["body", "tracks", 3, "covariance"],
            "pointer": "#/tracks/3/covariance",
            "detail": "tracks[3].covariance is not symmetric",
            "type": "invalid_input",
        }
    ]
    unlocated = failing_client.get("/core-invalid").json()
    assert [error["pointer"] for error in unlocated["errors"]] == ["#"]


def test_core_covariance_check_names_the_field() -> None:
    """The core's one covariance check locates the matrix it refuses."""
    stack = np.stack([np.eye(2), np.array([[1.0, 2.0], [2.0, 1.0]])])
    with pytest.raises(CovarianceError) as refused:
        check_covariances(stack, "tracks")
    assert refused.value.loc == ("tracks", 1, "covariance")


@pytest.mark.parametrize("route", ["/crash", "/core-internal"])
def test_unexpected_errors_are_500_without_internals(
    failing_client: TestClient, route: str
) -> None:
    response = failing_client.get(route)
    assert response.status_code == 500
    assert response.headers["content-type"].startswith("application/problem+json")
    assert SECRET not in response.text and "Traceback" not in response.text
    assert response.json()["reference"] in response.json()["detail"]


def test_limit_names_the_limit(failing_client: TestClient) -> None:
    problem = failing_client.get("/limit").json()
    assert problem["status"] == 422
    assert (problem["limit"], problem["maximum"], problem["actual"]) == (
        "max_tracks_per_input",
        10,
        11,
    )


def test_unknown_route_and_method_are_problems(failing_client: TestClient) -> None:
    missing = failing_client.get("/nowhere")
    assert missing.status_code == 404
    assert missing.headers["content-type"].startswith("application/problem+json")
    assert failing_client.post("/stale").status_code == 405
