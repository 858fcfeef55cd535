"""The explain matrix of ``hachour`` over a live server: [T2T] Table 1 with its ``*`` rows."""

from __future__ import annotations

import math
from typing import Any

import httpx
import numpy as np
import pytest

from tests.api.conftest import LiveServer
from tests.api.scenario import CLASSES, reports, session_config
from tests.core.association.brute_force import best_matching, distances, hachour_table

KNOWN = [
    ([0.0, 0.0], 1.0, {"liner": 0.7}),
    ([1.5, 0.5], 0.5, {"fighter": 0.9}),
    ([9.0, 9.0], 2.0, {}),
]
INCOMING = [([0.4, 0.1], 0.8, {"fighter": 0.6}), ([1.2, 0.9], 0.3, {}), ([30.0, -4.0], 1.0, {})]


def side(prefix: str, tracks: list[tuple[list[float], float, dict[str, float]]]) -> list[Any]:
    """Tracks with isotropic covariances; class mass on the named singletons, the rest on Θ."""
    body = []
    for index, (state, variance, singletons) in enumerate(tracks):
        track: dict[str, Any] = {
            "id": f"{prefix}{index}",
            "state": state,
            "covariance": [[variance, 0.0], [0.0, variance]],
        }
        if singletons:
            rest = 1.0 - sum(singletons.values())
            mass = [{"set": [label], "mass": value} for label, value in singletons.items()]
            track["classification"] = {"mass": [*mass, {"set": CLASSES, "mass": rest}]}
        body.append(track)
    return body


def as_dicts(tracks: list[tuple[list[float], float, dict[str, float]]]) -> list[Any]:
    masses = []
    for _, _, singletons in tracks:
        mass = {frozenset([label]): value for label, value in singletons.items()}
        mass[frozenset(CLASSES)] = 1.0 - sum(singletons.values())
        masses.append(mass)
    return masses


@pytest.mark.parametrize("likelihood", ["density", "relative"])
def test_associate_matrix_is_table_one(live_server: LiveServer, likelihood: str) -> None:
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        answer = client.post(
            "/v1/associate",
            json={
                "method": "hachour",
                "options": {"likelihood": likelihood, "distance": "mean"},
                "classes": CLASSES,
                "known": side("k", KNOWN),
                "incoming": side("i", INCOMING),
            },
        )
    assert answer.status_code == 200, answer.text
    matrix = answer.json()["matrix"]
    assert matrix["rows"] == ["k0", "k1", "k2", "*:i0", "*:i1", "*:i2"]
    assert matrix["cols"] == ["i0", "i1", "i2"]
    known_x = np.array([state for state, _, _ in KNOWN])
    known_p = np.array([v * np.eye(2) for _, v, _ in KNOWN])
    incoming_x = np.array([state for state, _, _ in INCOMING])
    incoming_p = np.array([v * np.eye(2) for _, v, _ in INCOMING])
    d, log_det = distances(known_x, known_p, incoming_x, incoming_p, "mean")
    expected = hachour_table(d, log_det, as_dicts(KNOWN), as_dicts(INCOMING), likelihood)
    values = np.array(
        [[math.nan if value is None else value for value in row] for row in matrix["values"]]
    )
    # cells below the default plausibility floor (1e-12) are not stored: 0
    np.testing.assert_allclose(values, expected, atol=1e-11)
    n, m = d.shape

    def objective(matching: list[tuple[int, int]]) -> float:  # [T2T] eq 7
        matched = {t: ell for ell, t in matching}
        return sum(expected[matched.get(t, n + t), t] for t in range(m))

    best, _, _ = best_matching(n, m, objective)
    pairs = {(pair["known"], pair["incoming"]) for pair in answer.json()["pairs"]}
    assert pairs == {(f"k{ell}", f"i{t}") for ell, t in best}
    assert "i2" in answer.json()["new"]  # far from everything
    assert (likelihood == "relative") == bool(pairs)  # density: C ~ 1 m², G < 1/2


def test_session_explain_has_a_star_row_per_report_track(live_server: LiveServer) -> None:
    config = session_config() | {
        "association": {"method": "hachour", "options": {"likelihood": "relative"}}
    }
    first, second = reports(2)
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        created = client.post("/v1/sessions", json=config)
        assert created.status_code == 201, created.text
        sid, token = created.json()["id"], created.json()["token"]
        headers = {"Authorization": f"Bearer {token}"}
        assert client.post(f"/v1/sessions/{sid}/tracks", json=first, headers=headers).is_success
        explained = client.post(
            f"/v1/sessions/{sid}/tracks", params={"explain": "true"}, json=second, headers=headers
        )
    assert explained.status_code == 200, explained.text
    association = explained.json()["association"]
    matrix = association["matrix"]
    cols = matrix["cols"]
    assert cols == [track["id"] for track in second["tracks"]]
    fused = matrix["rows"][: len(matrix["rows"]) - len(cols)]
    assert matrix["rows"][len(fused) :] == [f"*:{col}" for col in cols]
    values = matrix["values"]
    for t in range(len(cols)):
        star_row = values[len(fused) + t]
        assert [cell is not None for cell in star_row] == [k == t for k in range(len(cols))]
        column = [row[t] for row in values if row[t] is not None]
        assert math.fsum(column) == pytest.approx(1.0, abs=1e-9)  # BetP over the frame
    assert {pair["track"] for pair in association["pairs"]} | set(association["new"]) == set(cols)
