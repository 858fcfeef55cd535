"""WGS84 geodetic coordinates and the session's local East-North-Up frame.

A session with an ``origin`` (latitude, longitude in degrees, altitude in
metres above the WGS84 ellipsoid) works in the local tangent plane at that
point: x east, y north, z up, metres (DESIGN "Sensors in the world").
Everything here is vectorised over a whole report and rests on pymap3d's
WGS84 conversions; the tests check them against PROJ (pyproj).

Covariances and velocities given in the local ENU frame *at a reported
point* (an ADS-B or AIS track) are turned by the rotation between the two
tangent planes, ``R = R_origin · R_pointᵀ`` with ``R_p`` the rotation from
ECEF to the ENU axes at ``p``. That rotation is the exact Jacobian of the map
from local metres at the point to session metres (both are rigid motions of
ECEF), so ``P_session = R P_local Rᵀ`` and ``v_session = R v_local`` hold
with no linearisation error: both frames are Cartesian.

This lives at the service edge, not in ``core``: the core works in one
Cartesian frame and imports nothing but numpy, scipy, lapx and shapely.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pymap3d

from core.arrays import FloatArray
from core.models.measurement import rotate_covariances

LATITUDE_LIMIT = 90.0
"""|latitude| ≤ 90° (degrees)."""


def _column(values: FloatArray | float) -> FloatArray:
    return np.atleast_1d(np.asarray(values, dtype=np.float64))


def enu_axes(latitude_deg: FloatArray | float, longitude_deg: FloatArray | float) -> FloatArray:
    """``R_p``, shape (N, 3, 3): rows are the east, north and up unit vectors in ECEF."""
    lat = np.radians(_column(latitude_deg))
    lon = np.radians(_column(longitude_deg))
    sin_lat, cos_lat = np.sin(lat), np.cos(lat)
    sin_lon, cos_lon = np.sin(lon), np.cos(lon)
    zero = np.zeros_like(lat)
    east = np.stack([-sin_lon, cos_lon, zero], axis=-1)
    north = np.stack([-sin_lat * cos_lon, -sin_lat * sin_lon, cos_lat], axis=-1)
    up = np.stack([cos_lat * cos_lon, cos_lat * sin_lon, sin_lat], axis=-1)
    return np.stack([east, north, up], axis=-2)


@dataclass(frozen=True)
class LocalFrame:
    """The East-North-Up tangent plane at a WGS84 origin (degrees, metres).

    Attributes
    ----------
    lat, lon : float
        Origin latitude and longitude (degrees).
    alt : float
        Origin height above the ellipsoid (m).
    """

    lat: float
    lon: float
    alt: float = 0.0

    def __post_init__(self) -> None:
        for name in ("lat", "lon", "alt"):
            value = getattr(self, name)
            if not np.isfinite(value):
                raise ValueError(f"{name} must be finite, got {value!r}")
        if abs(self.lat) > LATITUDE_LIMIT:
            raise ValueError(f"lat must be in [-90, 90], got {self.lat!r}")

    def from_geodetic(
        self,
        latitude_deg: FloatArray | float,
        longitude_deg: FloatArray | float,
        altitude_m: FloatArray | float,
    ) -> FloatArray:
        """Session ENU positions, shape (N, 3), of geodetic points."""
        east, north, up = pymap3d.geodetic2enu(
            _column(latitude_deg),
            _column(longitude_deg),
            _column(altitude_m),
            self.lat,
            self.lon,
            self.alt,
        )
        return np.stack([east, north, up], axis=-1)

    def to_geodetic(self, positions: FloatArray) -> FloatArray:
        """Geodetic ``(lat°, lon°, alt m)``, shape (N, 3), of session ENU positions (N, 3)."""
        enu = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        lat, lon, alt = pymap3d.enu2geodetic(
            enu[:, 0], enu[:, 1], enu[:, 2], self.lat, self.lon, self.alt
        )
        return np.stack([_column(lat), _column(lon), _column(alt)], axis=-1)

    def rotation_from(
        self, latitude_deg: FloatArray | float, longitude_deg: FloatArray | float
    ) -> FloatArray:
        """``R = R_origin R_pᵀ``, shape (N, 3, 3): local ENU at each point → session ENU."""
        origin = enu_axes(np.array([self.lat]), np.array([self.lon]))[0]
        points = enu_axes(latitude_deg, longitude_deg)
        return np.asarray(origin @ np.swapaxes(points, -1, -2), dtype=np.float64)

    def rotation_to(
        self, latitude_deg: FloatArray | float, longitude_deg: FloatArray | float
    ) -> FloatArray:
        """The inverse rotation, session ENU → local ENU at each point (N, 3, 3)."""
        return np.swapaxes(self.rotation_from(latitude_deg, longitude_deg), -1, -2)


def heading_rotation(heading_deg: float, dimension: int) -> FloatArray:
    """Sensor frame → session frame for a sensor whose reference axis points ``heading_deg``.

    A sensor's own frame has its y axis along its reference direction
    (``heading_deg`` clockwise from north) and x 90° clockwise from it, z up:
    at heading 0 it is the session's ENU frame. Shape (d, d), d = 2 or 3.
    """
    theta = np.radians(heading_deg)
    c, s = np.cos(theta), np.sin(theta)
    # Sensor y (forward) = (sin θ, cos θ) in ENU; sensor x (right) = (cos θ, −sin θ).
    planar = np.array([[c, s], [-s, c]])
    if dimension == 2:
        return planar
    turned = np.eye(3)
    turned[:2, :2] = planar
    return turned


def block_transform(
    rotations: FloatArray,
    state_dim: int,
    position_indices: tuple[int, ...],
    velocity_indices: tuple[int, ...],
    acceleration_indices: tuple[int, ...] = (),
) -> FloatArray:
    """``T`` (N, n, n): each rotation (N, d, d) on the position, the velocity and the
    acceleration components."""
    count, d = rotations.shape[0], rotations.shape[-1]
    derivatives = (velocity_indices, acceleration_indices)
    if len(position_indices) != d or any(len(i) not in (0, d) for i in derivatives):
        raise ValueError(f"layout has {len(position_indices)} position components, rotation {d}")
    transform = np.broadcast_to(np.eye(state_dim), (count, state_dim, state_dim)).copy()
    for indices in (position_indices, *derivatives):
        if indices:
            block = np.ix_(range(count), indices, indices)
            transform[block] = rotations
    return transform


def sensor_to_session(
    states: FloatArray,
    covariances: FloatArray,
    position_indices: tuple[int, ...],
    velocity_indices: tuple[int, ...],
    site: FloatArray,
    heading_deg: float,
    acceleration_indices: tuple[int, ...] = (),
) -> tuple[FloatArray, FloatArray]:
    """Tracks in a sensor's own frame (origin at ``site``, turned by its heading) → session frame.

    ``x_s = site + H x``, ``v_s = H v``, ``a_s = H a``, ``P_s = T P Tᵀ`` with H of
    :func:`heading_rotation`; shapes (N, n) and (N, n, n).
    """
    d = len(position_indices)
    turn = np.broadcast_to(heading_rotation(heading_deg, d), (len(states), d, d))
    transform = block_transform(
        turn, states.shape[-1], position_indices, velocity_indices, acceleration_indices
    )
    moved = np.einsum("tij,tj->ti", transform, states)
    moved[:, list(position_indices)] += np.asarray(site, dtype=np.float64)[:d]
    return moved, rotate_covariances(transform, covariances)


def geodetic_to_session(
    frame: LocalFrame,
    states: FloatArray,
    covariances: FloatArray,
    position_indices: tuple[int, ...],
    velocity_indices: tuple[int, ...],
    acceleration_indices: tuple[int, ...] = (),
) -> tuple[FloatArray, FloatArray]:
    """Tracks whose positions are (lat°, lon°[, alt m]) → session frame.

    Velocities (and accelerations) are east/north/up at the point and the
    covariance is in the local ENU metres (and m/s, m/s²) at the point; all are
    turned by the rotation between the point's tangent plane and the
    session's. In a 2-D session
    (positions lat, lon) the point is taken at the origin's altitude and the
    horizontal block of the rotation is used: the vertical it drops is below
    1e-4 of the horizontal within 100 km of the origin.
    """
    d = len(position_indices)
    positions = states[:, list(position_indices)]
    altitude = positions[:, 2] if d == 3 else np.full(len(states), frame.alt)
    enu = frame.from_geodetic(positions[:, 0], positions[:, 1], altitude)
    rotation = frame.rotation_from(positions[:, 0], positions[:, 1])[:, :d, :d]
    transform = block_transform(
        rotation, states.shape[-1], position_indices, velocity_indices, acceleration_indices
    )
    moved = np.einsum("tij,tj->ti", transform, states)
    moved[:, list(position_indices)] = enu[:, :d]
    return moved, rotate_covariances(transform, covariances)
