"""Fused tracks as GeoJSON (RFC 7946) and with geodetic positions.

``GET …/tracks?format=geojson`` answers a FeatureCollection of Point
features, coordinates ``[lon°, lat°, alt m]`` (RFC 7946 §3.1.1 order) on
WGS84, with the track's id, status, decision, its ``decision_state``, BetP,
the ids of the sensors that contributed (``sources``), velocity and 2-σ
position ellipse as properties. The velocity is east/north/up in m/s *at the
track's point* (the session-frame velocity turned into the point's tangent
plane), the same convention as a geodetic track-list report; so is the
ellipse, from the position covariance turned likewise (``R P Rᵀ``) and cut to
its east/north block.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from app.geo.geodesy import LocalFrame
from core.models.measurement import rotate_covariances

GEOJSON_MEDIA_TYPE = "application/geo+json"
ELLIPSE_SIGMA = 2.0
"""The position ellipse's size in standard deviations (the viewer draws the same 2-σ ellipse)."""
CIRCLE = 1e-9
"""Eigenvalues this close (relative) are a circle: no axis to orient (``orientation_deg`` 0)."""

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


def horizontal_ellipses(covariances: np.ndarray) -> dict[str, np.ndarray]:
    """The 2-σ ellipses of east/north covariance blocks ``[[ee, en], [en, nn]]`` (N, 2, 2):
    semi-axes ``ELLIPSE_SIGMA·√λ`` (m) of the block's eigenvalues λ₁ ≥ λ₂, and the major
    axis' direction in degrees clockwise from north, in [0, 180) (an axis, not an arrow;
    0 for a circle: axes equal to 1e-9 relative, what rounding leaves of one). Closed form of a symmetric 2×2 eigenproblem, vectorised over tracks:
    λ = (ee + nn)/2 ± √(((ee − nn)/2)² + en²), major axis at ½·atan2(2en, ee − nn) from east."""
    ee, en, nn = covariances[:, 0, 0], covariances[:, 0, 1], covariances[:, 1, 1]
    mean, spread = (ee + nn) / 2, np.hypot((ee - nn) / 2, en)
    from_east = 0.5 * np.degrees(np.arctan2(2 * en, ee - nn))
    bearing = np.where(spread > CIRCLE * mean, np.mod(90.0 - from_east, 180.0), 0.0)
    return {
        "semi_major_m": ELLIPSE_SIGMA * np.sqrt(np.maximum(mean + spread, 0.0)),
        "semi_minor_m": ELLIPSE_SIGMA * np.sqrt(np.maximum(mean - spread, 0.0)),
        "orientation_deg": bearing,
    }


def _position_blocks(tracks: Sequence[PlainTrack], indices: tuple[int, ...]) -> np.ndarray:
    """The position block of each track's covariance as ENU (N, 3, 3), zero-padded."""
    blocks = np.zeros((len(tracks), 3, 3))
    if len(tracks) and indices:
        covariances = np.asarray([track["covariance"] for track in tracks], dtype=np.float64)
        chosen = list(indices)
        blocks[:, : len(chosen), : len(chosen)] = covariances[:, chosen][:, :, chosen]
    return blocks


def _sensor_ids(sources: Sequence[Any]) -> list[str]:
    """The ids of the sensors among a track's sources (plain ``{sensor, …}`` or ``Source``),
    each once, in the sources' order."""
    ids = (source["sensor"] if isinstance(source, dict) else source.sensor for source in sources)
    return list(dict.fromkeys(ids))


def feature_collection(tracks: Sequence[PlainTrack], geodetic: GeodeticOutput) -> dict[str, Any]:
    """A FeatureCollection of the tracks' positions (module docstring); each track has its
    ``state``, ``covariance``, ``sources`` and ``classification`` (plain, or ``None``)."""
    states = [track["state"] for track in tracks]
    frame, velocity_indices = geodetic.frame, geodetic.velocity
    positions = frame.to_geodetic(_columns(states, geodetic.position))
    rotations = frame.rotation_to(positions[:, 0], positions[:, 1])
    velocities = _columns(states, velocity_indices)
    local = np.einsum("tij,tj->ti", rotations, velocities)
    turned = rotate_covariances(rotations, _position_blocks(tracks, geodetic.position))
    ellipses = {key: values.tolist() for key, values in horizontal_ellipses(turned).items()}
    features = []
    for n, (track, (lat, lon, alt), velocity) in enumerate(
        zip(tracks, positions.tolist(), local.tolist(), strict=True)
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
                    "sources": _sensor_ids(track["sources"]),
                    "decision": classification.get("decision"),
                    "decision_state": classification.get("decision_state"),
                    "pignistic": classification.get("pignistic"),
                    "velocity_enu": velocity[: max(len(velocity_indices), 2)],
                    "position_ellipse": {
                        "sigma": ELLIPSE_SIGMA,
                        **{key: values[n] for key, values in ellipses.items()},
                    },
                },
            }
        )
    return {"type": "FeatureCollection", "features": features}
