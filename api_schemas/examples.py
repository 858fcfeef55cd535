"""The request examples of ``openapi.json``: what "Try it out" in ``/docs`` sends.

One source: the routes put these under their body's media type
(``requestBody.content["application/json"].examples``, an OpenAPI Example
Object each: ``summary``, ``description``, ``value``), and
``tests/api/test_openapi_examples.py`` reads them back out of the app's
OpenAPI document and posts each to a live server. An input example goes with
the session example **of the same name** (``cartesian``, ``geodetic``): its
sensor is one that session configures.
"""

from __future__ import annotations

from typing import Any

Example = dict[str, Any]
"""An OpenAPI Example Object: ``summary``, ``description``, ``value``."""

COVARIANCE_4 = [[4, 0, 0, 0], [0, 1, 0, 0], [0, 0, 4, 0], [0, 0, 0, 1]]

SESSION_EXAMPLES: dict[str, Example] = {
    "cartesian": {
        "summary": "Three radars in a local x, y plane (metres)",
        "description": (
            "radar-1 and radar-2 send track lists (radar-1 trusted at 0.9), radar-3 raw "
            "detections of 5 m noise; the fused state is [x, vx, y, vy]. The `cartesian` "
            "examples of POST …/tracks and …/detections go with this session."
        ),
        "value": {
            "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
            "motion": {"model": "constant_velocity", "q": 1.0},
            "classes": ["liner", "bomber", "fighter"],
            "sensors": [
                {"id": "radar-1", "reliability": 0.9},
                {"id": "radar-2"},
                {"id": "radar-3", "measurement": {"r": [[25, 0], [0, 25]]}},
            ],
            "tracking": {"preset": "aircraft", "time_interval": 1.0},
        },
    },
    "geodetic": {
        "summary": "A polar radar at a WGS84 site and an ADS-B feed",
        "description": (
            "The session frame is East-North-Up at the origin (x east, y north, metres). "
            "radar-t measures range and azimuth every 4 s from its site; adsb sends "
            "geodetic track lists of the equipped aircraft only (a cooperative source: "
            "configured with its id alone). The `geodetic` examples of POST …/tracks and "
            "…/detections go with this session."
        ),
        "value": {
            "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
            "origin": {"lat": 43.6, "lon": 1.44, "alt": 150},
            "motion": {"model": "constant_velocity", "q": 1.0},
            "sensors": [
                {
                    "id": "radar-t",
                    "site": {"lat": 43.55, "lon": 1.40, "alt": 160},
                    "measurement": {
                        "kind": "polar",
                        "sigma_range": 20,
                        "sigma_azimuth_deg": 0.2,
                    },
                },
                {"id": "adsb"},
            ],
            "tracking": {"time_interval": 4.0},
        },
    },
}
"""``POST /v1/sessions``."""

TRACK_REPORT_EXAMPLES: dict[str, Example] = {
    "cartesian": {
        "summary": "radar-1's track list (for the `cartesian` session)",
        "description": (
            "One track: state [x, vx, y, vy] in m and m/s as the session's `state` layout "
            "orders it, its covariance, and a class mass function."
        ),
        "value": {
            "sensor": "radar-1",
            "time": 12,
            "tracks": [
                {
                    "id": "17",
                    "state": [100, 3, 250, -1],
                    "covariance": COVARIANCE_4,
                    "classification": {
                        "mass": [
                            {"set": ["bomber", "fighter"], "mass": 0.6},
                            {"set": ["liner", "bomber", "fighter"], "mass": 0.4},
                        ]
                    },
                }
            ],
        },
    },
    "geodetic": {
        "summary": "An ADS-B state in latitude and longitude (for the `geodetic` session)",
        "description": (
            'With `"frame": "geodetic"` the state keeps the session layout\'s slots: its '
            "position slots hold latitude, longitude (°), its velocity slots east, north "
            "(m/s): [lat, v_east, lon, v_north] here. The covariance is in metres (and m/s) "
            "of the East-North-Up plane at the point, ordered as the session frame's state "
            "[x east, vx, y north, vy]. `time` is an RFC 3339 timestamp here (seconds since "
            "the Unix epoch for the service); a number is seconds of any epoch."
        ),
        "value": {
            "sensor": "adsb",
            "time": "2026-12-03T08:00:00Z",
            "frame": "geodetic",
            "tracks": [
                {
                    "id": "3c6444",
                    "state": [43.63, 180, 1.48, 120],
                    "covariance": [
                        [100, 0, 0, 0],
                        [0, 4, 0, 0],
                        [0, 0, 100, 0],
                        [0, 0, 0, 4],
                    ],
                }
            ],
        },
    },
}
"""``POST /v1/sessions/{sid}/tracks``."""

DETECTION_REPORT_EXAMPLES: dict[str, Example] = {
    "cartesian": {
        "summary": "radar-3's detections (for the `cartesian` session)",
        "description": (
            "Positions `z` in the state's position order (x, y); each detection's noise is "
            "its sensor's `measurement.r` unless it gives its own `r`."
        ),
        "value": {
            "sensor": "radar-3",
            "time": 13,
            "detections": [{"z": [103, 249]}, {"z": [-40, 1200], "r": [[100, 0], [0, 100]]}],
        },
    },
    "geodetic": {
        "summary": "radar-t's plots in range and azimuth (for the `geodetic` session)",
        "description": (
            "A polar sensor's detections: `range` (m) and `azimuth_deg` (clockwise from "
            "north at its site). `time` is when the beam saw these plots (here an RFC 3339 "
            "timestamp): a rotating radar sends each plot, or each sector's plots, with its "
            "own time, not the scan's."
        ),
        "value": {
            "sensor": "radar-t",
            "time": "2026-12-03T08:00:00.5Z",
            "detections": [
                {"range": 12000, "azimuth_deg": 45},
                {"range": 30500, "azimuth_deg": 301.5},
            ],
        },
    },
}
"""``POST /v1/sessions/{sid}/detections``."""

ASSOCIATE_EXAMPLES: dict[str, Example] = {
    "two_lists": {
        "summary": "Two known tracks, two reported: one pair, one new track",
        "description": (
            "Associates `incoming` with `known` by `denoeux` (the default), with class "
            "evidence: the answer gives the pairs, the new and missed ids and the score matrix."
        ),
        "value": {
            "method": "denoeux",
            "classes": ["liner", "fighter"],
            "known": [
                {"id": "F1", "state": [100, 3, 250, -1], "covariance": COVARIANCE_4},
                {"id": "F2", "state": [900, 0, -400, 5], "covariance": COVARIANCE_4},
            ],
            "incoming": [
                {
                    "id": "a",
                    "state": [101.5, 3.1, 249.2, -0.8],
                    "covariance": COVARIANCE_4,
                    "classification": {"likelihoods": {"liner": 0.2, "fighter": 0.9}},
                },
                {"id": "b", "state": [5000, 0, 5000, 0], "covariance": COVARIANCE_4},
            ],
        },
    },
}
"""``POST /v1/associate``."""


def json_body_examples(examples: dict[str, Example]) -> dict[str, Any]:
    """The ``openapi_extra`` of a route whose JSON body has ``examples`` (merged by FastAPI
    into the operation's ``requestBody``)."""
    return {"requestBody": {"content": {"application/json": {"examples": examples}}}}
