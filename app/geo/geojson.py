"""Fused tracks as GeoJSON (RFC 7946) and with geodetic positions.

``GET …/tracks?format=geojson`` answers a FeatureCollection of Point
features, coordinates ``[lon°, lat°, alt m]`` (RFC 7946 §3.1.1 order) on
WGS84, with the track's id, status, decision, BetP and velocity as
properties. The velocity is east/north/up in m/s *at the track's point* (the
session-frame velocity turned into the point's tangent plane), the same
convention as a geodetic track-list report.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from app.geo.geodesy import LocalFrame

GEOJSON_MEDIA_TYPE = "application/geo+json"

PlainTrack = dict[str, Any]


State = np.ndarray | Sequence[float]


def _columns(states: Sequence[State], indices: tuple[int, ...]) -> np.ndarray:
    """State components ``indices`` of every state as ENU columns (N, 3), zero-padded: a
    2-D session's tracks sit at the origin's height (z = 0) and move horizontally."""
    columns = np.zeros((len(states), 3))
    if len(states) and indices:
        columns[:, : len(indices)] = np.asarray(states, dtype=np.float64)[:, list(indices)]
    return columns


@dataclass(frozen=True)
class GeodeticOutput:
    """``?frame=geodetic``: the session's origin frame and which state components are the
    position (and the velocity); :meth:`points` gives each state's ``geodetic: {lat, lon, alt}``."""

    frame: LocalFrame
    position: tuple[int, ...]
    velocity: tuple[int, ...] = ()

    def points(self, states: Sequence[State]) -> list[dict[str, float]]:
        """``{lat, lon, alt}`` of each state's position, in one vectorised conversion."""
        return [
            {"lat": lat, "lon": lon, "alt": alt}
            for lat, lon, alt in self.frame.to_geodetic(_columns(states, self.position)).tolist()
        ]


def with_geodetic(tracks: Sequence[PlainTrack], geodetic: GeodeticOutput) -> list[PlainTrack]:
    """The tracks with ``geodetic: {lat, lon, alt}`` added (``?frame=geodetic``)."""
    points = geodetic.points([track["state"] for track in tracks])
    return [{**track, "geodetic": point} for track, point in zip(tracks, points, strict=True)]


def feature_collection(tracks: Sequence[PlainTrack], geodetic: GeodeticOutput) -> dict[str, Any]:
    """A FeatureCollection of the tracks' positions (module docstring)."""
    states = [track["state"] for track in tracks]
    frame, velocity_indices = geodetic.frame, geodetic.velocity
    positions = frame.to_geodetic(_columns(states, geodetic.position))
    velocities = _columns(states, velocity_indices)
    local = np.einsum("tij,tj->ti", frame.rotation_to(positions[:, 0], positions[:, 1]), velocities)
    features = []
    for track, (lat, lon, alt), velocity in zip(
        tracks, positions.tolist(), local.tolist(), strict=True
    ):
        classification = track.get("classification") or {}
        features.append(
            {
                "type": "Feature",
                "id": track["id"],
                "geometry": {"type": "Point", "coordinates": [lon, lat, alt]},
                "properties": {
                    "id": track["id"],
                    "status": track["status"],
                    "decision": classification.get("decision"),
                    "pignistic": classification.get("pignistic"),
                    "velocity_enu": velocity[: max(len(velocity_indices), 2)],
                },
            }
        )
    return {"type": "FeatureCollection", "features": features}
