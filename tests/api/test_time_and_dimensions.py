"""Over the real API: 3-D scenes from detections and from track lists, jittered scan times, a
1e6 s gap, and the fused layer's default motion for a preset (issue 12)."""

from __future__ import annotations

from typing import Any

import httpx
import numpy as np
import pytest

from .conftest import LiveServer

SCANS = 36
WARM = 9  # scans before both targets have confirmed fused tracks
SIGMA = 5.0  # m, per position axis
ALTITUDES = (1000.0, 3000.0)


def _truth(time: float, layout_order: tuple[int, ...]) -> list[np.ndarray]:
    """Two aircraft crossing over the origin at t = 20 s, 2 km apart in altitude.

    Each state is returned in ``layout_order``: the session index of x, vx, y, vy, z, vz.
    """
    states = []
    for start, velocity in (
        ((-2000.0, 0.0, ALTITUDES[0]), (100.0, 0.0, 0.0)),
        ((0.0, -2000.0, ALTITUDES[1]), (0.0, 100.0, 0.0)),
    ):
        local = np.zeros(6)
        local[0::2] = np.add(start, np.multiply(velocity, time))
        local[1::2] = velocity
        state = np.zeros(6)
        state[list(layout_order)] = local
        states.append(state)
    return states


def _scan_times(rng: np.random.Generator) -> np.ndarray:
    times = np.arange(SCANS, dtype=np.float64) + rng.uniform(-0.15, 0.15, SCANS)
    times[0] = 0.0
    return times


def _session(client: httpx.Client, config: dict[str, Any]) -> tuple[str, dict[str, str]]:
    created = client.post("/v1/sessions", json=config)
    assert created.status_code == 201, created.text
    return created.json()["id"], {"Authorization": f"Bearer {created.json()['token']}"}


def _covering_ids(
    results: list[dict[str, Any]], times: np.ndarray, order: tuple[int, ...]
) -> list[set[str]]:
    """For each target, the ids of the nearest confirmed fused track at every step after the
    first confirmations (within 20 σ in position)."""
    position = [order[0], order[2], order[4]]
    covering: list[set[str]] = [set(), set()]
    for result, time in zip(results[WARM:], times[WARM:], strict=True):
        confirmed = [t for t in result["tracks"] if t["status"] == "confirmed"]
        for target, truth in enumerate(_truth(float(time), order)):
            distances = [
                float(np.linalg.norm(np.asarray(t["state"])[position] - truth[position]))
                for t in confirmed
            ]
            assert distances and min(distances) < 20 * SIGMA
            covering[target].add(confirmed[int(np.argmin(distances))]["id"])
    return covering


@pytest.mark.parametrize(
    ("preset", "order"),
    [
        ("aircraft", (0, 1, 2, 3, 4, 5)),  # [x, vx, y, vy, z, vz]
        (None, (0, 3, 1, 4, 2, 5)),  # [x, y, z, vx, vy, vz]
    ],
)
def test_3d_detections_keep_ids_through_a_crossing(
    live_server: LiveServer, preset: str | None, order: tuple[int, ...]
) -> None:
    """The issue's refused session: ``state {dim 6, position [0, 2, 4], velocity [1, 3, 5]}``
    with a detecting sensor (and the same with the positions first), scans at jittered times,
    then a scan 1e6 s later. ``z`` lists the positions in the order of ``state.position``."""
    position = [order[0], order[2], order[4]]
    config: dict[str, Any] = {
        "state": {"dim": 6, "position": position, "velocity": [order[1], order[3], order[5]]},
        "sensors": [
            {"id": "radar", "measurement": {"r": (SIGMA**2 * np.eye(3)).tolist()}},
        ],
        "tracking": {"preset": preset},
    }
    if preset is not None:
        config["classes"] = ["liner", "bomber", "fighter"]
    rng = np.random.default_rng(12)
    times = _scan_times(rng)
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        sid, headers = _session(client, config)
        results = []
        for time in times:
            detections = [
                {"z": (truth[position] + rng.normal(0.0, SIGMA, 3)).tolist()}
                for truth in _truth(float(time), order)
            ]
            body = {"sensor": "radar", "time": float(time), "detections": detections}
            answer = client.post(f"/v1/sessions/{sid}/detections", json=body, headers=headers)
            assert answer.status_code == 200, answer.text
            results.append(answer.json())
        covering = _covering_ids(results, times, order)
        assert all(len(ids) == 1 for ids in covering), covering
        assert covering[0] != covering[1]
        altitudes = sorted(track["state"][order[4]] for track in results[-1]["tracks"])
        np.testing.assert_allclose(altitudes, ALTITUDES, atol=4 * SIGMA)
        climb = [track["state"][order[5]] for track in results[-1]["tracks"]]
        np.testing.assert_allclose(climb, [0.0, 0.0], atol=5.0)

        later = float(times[-1]) + 1e6
        body = {
            "sensor": "radar",
            "time": later,
            "detections": [{"z": truth[position].tolist()} for truth in _truth(later, order)],
        }
        answer = client.post(f"/v1/sessions/{sid}/detections", json=body, headers=headers)
        assert answer.status_code == 200, answer.text
        assert answer.json()["time"] == later


def test_3d_track_lists_keep_ids_in_another_layout(live_server: LiveServer) -> None:
    """Two sensors' track lists on ``[x, y, z, vx, vy, vz]`` at jittered, interleaved times."""
    order = (0, 3, 1, 4, 2, 5)  # x, vx, y, vy, z, vz in the session's layout
    config = {
        "state": {"dim": 6, "position": [0, 1, 2], "velocity": [3, 4, 5]},
        "motion": {"q": 1.0},
        "sensors": [{"id": "a"}, {"id": "b"}],
    }
    covariance = np.diag([SIGMA**2] * 3 + [4.0] * 3)
    rng = np.random.default_rng(7)
    times = _scan_times(rng)
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        sid, headers = _session(client, config)
        results = []
        for k, time in enumerate(times):
            sensor = "ab"[k % 2]
            tracks = []
            for target, truth in enumerate(_truth(float(time), order)):
                noisy = truth + rng.multivariate_normal(np.zeros(6), covariance)
                tracks.append(
                    {
                        "id": f"{sensor}{target}",
                        "state": noisy.tolist(),
                        "covariance": covariance.tolist(),
                    }
                )
            body = {"sensor": sensor, "time": float(time), "tracks": tracks}
            answer = client.post(f"/v1/sessions/{sid}/tracks", json=body, headers=headers)
            assert answer.status_code == 200, answer.text
            results.append(answer.json())
        covering = _covering_ids(results, times, order)
        assert all(len(ids) == 1 for ids in covering), covering
        assert covering[0] != covering[1]
        final = results[-1]["tracks"]
        assert sorted(t["status"] for t in final) == ["confirmed", "confirmed"]
        assert all({s["sensor"] for s in t["sources"]} == {"a", "b"} for t in final)
