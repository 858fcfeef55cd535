"""The session's ENU frame against PROJ (pyproj), an implementation independent of pymap3d.

Positions: geodetic → ENU → geodetic round trips, and ENU against PROJ's
``topocentric`` conversion, from the equator to 80° latitude and up to 12 km,
to 1 mm. Covariances: the rotation between two tangent planes against the
Jacobian of PROJ's own maps, by central differences.
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose
from pyproj import Transformer

from app.geo.geodesy import (
    LocalFrame,
    geodetic_to_session,
    heading_rotation,
    sensor_to_session,
)
from core.models.measurement import rotate_covariances
from tests.api.proj_oracle import proj_enu

ORIGINS = [(0.0, 0.0, 0.0), (45.2, 5.7, 210.0), (-33.9, 151.2, 40.0), (80.0, -120.0, 1500.0)]


def scatter(origin: tuple[float, float, float], count: int, seed: int) -> np.ndarray:
    """Points within about 100 km of the origin, altitudes 0–12 km: (lat, lon, alt)."""
    rng = np.random.default_rng(seed)
    lat0, lon0, _ = origin
    lat = np.clip(lat0 + rng.uniform(-0.9, 0.9, count), -89.9, 89.9)
    lon = lon0 + rng.uniform(-0.9, 0.9, count) / max(np.cos(np.radians(lat0)), 0.2)
    alt = rng.uniform(0.0, 12_000.0, count)
    return np.stack([lat, lon, alt], axis=-1)


@pytest.mark.parametrize("origin", ORIGINS)
def test_positions_match_proj_and_round_trip(origin: tuple[float, float, float]) -> None:
    frame = LocalFrame(*origin)
    points = scatter(origin, 200, seed=int(abs(origin[0]) * 10) + 7)
    enu = frame.from_geodetic(points[:, 0], points[:, 1], points[:, 2])
    expected = np.stack(proj_enu(origin).transform(points[:, 0], points[:, 1], points[:, 2]), -1)
    assert_allclose(enu, expected, rtol=0, atol=1e-3)
    back = frame.to_geodetic(enu)
    metres_per_degree = 111_320.0
    assert_allclose(back[:, :2] * metres_per_degree, points[:, :2] * metres_per_degree, atol=1e-3)
    assert_allclose(back[:, 2], points[:, 2], atol=1e-3)


def _proj_jacobian(transformer: Transformer, point: np.ndarray, step: float = 1e-7) -> np.ndarray:
    """d ENU / d (lat°, lon°, alt m) of a PROJ map, by central differences."""
    columns = []
    for axis, delta in enumerate((step, step, 1e-3)):
        offset = np.zeros(3)
        offset[axis] = delta
        plus = np.array(transformer.transform(*(point + offset)))
        minus = np.array(transformer.transform(*(point - offset)))
        columns.append((plus - minus) / (2 * delta))
    return np.stack(columns, axis=-1)


@pytest.mark.parametrize("origin", ORIGINS)
def test_covariance_rotation_is_the_jacobian_of_projs_maps(
    origin: tuple[float, float, float],
) -> None:
    frame = LocalFrame(*origin)
    points = scatter(origin, 5, seed=3)
    rotations = frame.rotation_from(points[:, 0], points[:, 1])
    to_session = proj_enu(origin)
    for point, rotation in zip(points, rotations, strict=True):
        to_local = proj_enu((float(point[0]), float(point[1]), float(point[2])))
        # local metres → session metres = J_session · J_local⁻¹ (chain rule through geodetic).
        jacobian = _proj_jacobian(to_session, point) @ np.linalg.inv(
            _proj_jacobian(to_local, point)
        )
        assert_allclose(rotation, jacobian, atol=2e-6)
    rng = np.random.default_rng(11)
    factors = rng.normal(size=(5, 3, 3))
    local = factors @ np.swapaxes(factors, -1, -2) * 100.0
    session = rotate_covariances(rotations, local)
    back = rotate_covariances(frame.rotation_to(points[:, 0], points[:, 1]), session)
    assert_allclose(back, local, rtol=0, atol=1e-9)
    # A rotation keeps the spread: equal eigenvalues.
    assert_allclose(np.linalg.eigvalsh(session), np.linalg.eigvalsh(local), rtol=1e-12)


def test_heading_rotation_points_forward_along_the_heading() -> None:
    # A sensor heading 90° (east): its forward axis (y) is session east, its right axis (x) south.
    turn = heading_rotation(90.0, 2)
    assert_allclose(turn @ np.array([0.0, 1.0]), [1.0, 0.0], atol=1e-15)
    assert_allclose(turn @ np.array([1.0, 0.0]), [0.0, -1.0], atol=1e-15)
    turn3 = heading_rotation(30.0, 3)
    forward = turn3 @ np.array([0.0, 1.0, 0.0])
    assert_allclose(forward, [np.sin(np.radians(30)), np.cos(np.radians(30)), 0.0], atol=1e-15)
    assert_allclose(turn3 @ np.array([0.0, 0.0, 5.0]), [0.0, 0.0, 5.0])


@pytest.mark.parametrize("bad", [(91.0, 0.0, 0.0), (float("nan"), 0.0, 0.0), (0.0, 0.0, np.inf)])
def test_origin_outside_the_earth_is_refused(bad: tuple[float, float, float]) -> None:
    with pytest.raises(ValueError, match=r"lat|alt"):
        LocalFrame(*bad)


def test_sensor_frame_tracks_worked_by_hand() -> None:
    # Sensor at (1000, 2000) heading 90° (east); layout [x, vx, y, vy].
    states = np.array([[10.0, 1.0, 20.0, 2.0]])
    covariances = np.diag([4.0, 0.1, 9.0, 0.2])[None]
    moved, turned = sensor_to_session(
        states, covariances, (0, 2), (1, 3), np.array([1e3, 2e3]), 90.0
    )
    # x_s = 1000 + y = 1020, y_s = 2000 − x = 1990; v = (vy, −vx) = (2, −1).
    assert_allclose(moved[0], [1020.0, 2.0, 1990.0, -1.0], atol=1e-12)
    assert_allclose(np.diag(turned[0]), [9.0, 0.2, 4.0, 0.1], atol=1e-12)


@pytest.mark.parametrize("origin", ORIGINS[1:])
def test_geodetic_tracks_move_like_projs_points(origin: tuple[float, float, float]) -> None:
    """A track's local ENU velocity, turned into the session frame, matches two PROJ positions."""
    frame = LocalFrame(*origin)
    point = scatter(origin, 1, seed=5)[0]
    velocity = np.array([120.0, -40.0, 5.0])  # east, north, up at the point (m/s)
    to_session = proj_enu(origin)
    lat0, lon0, h0 = (float(v) for v in point)
    local_inverse = proj_enu((lat0, lon0, h0))
    dt = 0.01
    later = np.array(local_inverse.transform(*(velocity * dt), direction="INVERSE"))
    start = np.array(to_session.transform(*point))
    end = np.array(to_session.transform(*later))
    states = np.array([[point[0], point[1], point[2], *velocity]])
    covariances = np.diag([25.0, 25.0, 100.0, 1.0, 1.0, 4.0])[None]
    moved, turned = geodetic_to_session(frame, states, covariances, (0, 1, 2), (3, 4, 5))
    assert_allclose(moved[0, :3], start, atol=1e-3)
    assert_allclose(moved[0, 3:], (end - start) / dt, atol=1e-4)
    # The position variance along the session's up axis is the local one turned: uᵀ R P Rᵀ u.
    rotation = frame.rotation_from(point[0], point[1])[0]
    assert_allclose(turned[0, :3, :3], rotation @ np.diag([25.0, 25.0, 100.0]) @ rotation.T)
