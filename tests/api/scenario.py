"""A small deterministic two-sensor scene for the service tests: bodies only, no service code
(the wire models name the fields a result carries)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from api_schemas.results import FusedClassification, FusedTrack

CLASSES = ["liner", "bomber", "fighter"]
SENSORS = ["radar-1", "radar-2"]
TARGETS = 3
COVARIANCE = [[4.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 4.0, 0], [0, 0, 0, 1.0]]
MASSES = [
    [{"set": ["bomber", "fighter"], "mass": 0.6}, {"set": CLASSES, "mass": 0.4}],
    [{"set": ["liner"], "mass": 0.7}, {"set": CLASSES, "mass": 0.3}],
    [{"set": ["fighter"], "mass": 0.5}, {"set": ["bomber", "fighter"], "mass": 0.5}],
]


def session_config(sensors: list[str] | None = None) -> dict[str, Any]:
    """A session of ``sensors`` (default: two radars) seeing everywhere, with the class frame."""
    return {
        "name": "two radars",
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "motion": {"model": "constant_velocity", "q": 0.5},
        "classes": CLASSES,
        "sensors": [
            {"id": sensor, "reliability": 0.9, "p_detect": 0.95} for sensor in sensors or SENSORS
        ],
    }


def truth(target: int, time: float) -> list[float]:
    """Target ``target``'s true state at ``time``: straight lines 2 km apart."""
    x0, y0 = 2000.0 * target, 1000.0
    vx, vy = 10.0 + target, -5.0
    return [x0 + vx * time, vx, y0 + vy * time, vy]


def track_report(sensor: str, time: float, seed: int, targets: int = TARGETS) -> dict[str, Any]:
    """``sensor``'s track list at ``time``: every target, noisy, with the target's class mass."""
    rng = np.random.default_rng(seed)
    tracks = []
    for target in range(targets):
        noise = rng.normal(0.0, [2.0, 1.0, 2.0, 1.0])
        state = [
            round(value + delta, 6) for value, delta in zip(truth(target, time), noise, strict=True)
        ]
        tracks.append(
            {
                "id": f"{sensor}/{target}",
                "state": state,
                "covariance": COVARIANCE,
                "classification": {"mass": MASSES[target % len(MASSES)]},
            }
        )
    return {"sensor": sensor, "time": time, "tracks": tracks}


def reports(steps: int, sensors: list[str] | None = None) -> list[dict[str, Any]]:
    """``steps`` track lists, the sensors taking turns (sensor k reports at t + k / n)."""
    names = sensors or SENSORS
    return [
        track_report(
            names[index % len(names)],
            1.0 + index // len(names) + (index % len(names)) / len(names),
            seed=index,
        )
        for index in range(steps)
    ]


FUSED_TRACK_KEYS = set(FusedTrack.model_fields) - {"geodetic"}
"""What every fused track carries (``geodetic`` only with ``frame=geodetic``)."""
CLASSIFICATION_KEYS = set(FusedClassification.model_fields)


def check_fused_track(track: dict[str, Any]) -> None:
    """A fused track carries the contract's fields; its mass and BetP each sum to 1."""
    assert set(track) == FUSED_TRACK_KEYS
    assert track["status"] in {"tentative", "confirmed", "coasting", "phantom", "terminated"}
    assert len(track["state"]) == 4 and len(track["covariance"]) == 4
    assert all({"sensor", "track", "time"} == set(source) for source in track["sources"])
    classification = track["classification"]
    assert set(classification) == CLASSIFICATION_KEYS
    assert classification["state"] == "defined"
    assert math.isclose(math.fsum(f["mass"] for f in classification["mass"]), 1.0, abs_tol=1e-9)
    assert math.isclose(math.fsum(classification["pignistic"].values()), 1.0, abs_tol=1e-9)
    assert set(classification["pignistic"]) == set(CLASSES)
    assert (classification["decision"] in CLASSES) == (
        classification["decision_state"] == "decided"
    )
    for label in CLASSES:
        assert classification["belief"][label] <= classification["pignistic"][label] + 1e-12
        assert classification["pignistic"][label] <= classification["plausibility"][label] + 1e-12
