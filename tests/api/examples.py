"""The contract-by-example bodies of docs/design.md, shared by the API tests."""

from __future__ import annotations

from typing import Any

SESSION_CONFIG: dict[str, Any] = {
    "name": "harbour",
    "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
    "motion": {"model": "constant_velocity", "q": 0.5},
    "classes": ["liner", "bomber", "fighter"],
    "sensors": [
        {
            "id": "radar-1",
            "reliability": 0.9,
            "p_detect": 0.95,
            "fov": {
                "kind": "sector",
                "origin": [0, 0],
                "heading_deg": 90,
                "half_angle_deg": 60,
                "range": [0, 5000],
            },
            "measurement": {"r": [[25, 0], [0, 25]]},
        }
    ],
    "association": {"method": "denoeux", "options": {"gate_probability": 0.999}},
    "fusion": {"state": "covariance_intersection"},
    "tracking": {"preset": "aircraft"},
}

TRACK_REPORT: dict[str, Any] = {
    "sensor": "radar-1",
    "time": 12.5,
    "tracks": [
        {
            "id": "17",
            "state": [100.0, 3.0, 250.0, -1.0],
            "covariance": [[4, 0, 0, 0], [0, 1, 0, 0], [0, 0, 4, 0], [0, 0, 0, 1]],
            "classification": {
                "mass": [
                    {"set": ["bomber", "fighter"], "mass": 0.6},
                    {"set": ["liner", "bomber", "fighter"], "mass": 0.4},
                ]
            },
        }
    ],
}

LIKELIHOOD_EVIDENCE: dict[str, Any] = {"likelihoods": {"liner": 0.2, "bomber": 0.7, "fighter": 0.9}}

DETECTION_REPORT: dict[str, Any] = {
    "sensor": "radar-1",
    "time": 3.0,
    "detections": [{"z": [101.2, 249.0]}, {"z": [40.0, 12.5], "r": [[9, 0], [0, 9]]}],
}

STEP_RESULT: dict[str, Any] = {
    "seq": 7,
    "time": 12.5,
    "sensor": "radar-1",
    "tracks": [
        {
            "id": "F3",
            "status": "confirmed",
            "state": [100.0, 3.0, 250.0, -1.0],
            "covariance": [[4, 0, 0, 0], [0, 1, 0, 0], [0, 0, 4, 0], [0, 0, 0, 1]],
            "sources": [{"sensor": "radar-1", "track": "17", "time": 12.5}],
            "classification": {
                "state": "defined",
                "mass": [
                    {"set": ["bomber", "fighter"], "mass": 0.7},
                    {"set": ["liner", "bomber", "fighter"], "mass": 0.3},
                ],
                "pignistic": {"liner": 0.1, "bomber": 0.45, "fighter": 0.45},
                "belief": {"liner": 0.0, "bomber": 0.0, "fighter": 0.0},
                "plausibility": {"liner": 0.3, "bomber": 1.0, "fighter": 1.0},
                "conflict": 0.05,
                "decision": None,  # BetP 0.45 / 0.45: tied
                "decision_state": "tied",
            },
            "score": 12.3,
            "reason": None,
        }
    ],
    "association": {
        "method": "hachour",
        "pairs": [{"fused": "F3", "track": "17", "score": 0.93, "basis": "association"}],
        "new": ["21"],
        "missed": ["F5"],
        "matrix": None,
    },
}
