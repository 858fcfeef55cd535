"""Fields of view, visibility and occlusion, worked by hand."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from core.errors import InvalidInput
from core.geometry import Coverage, PolygonView, Sector, Visibility, occluded


def test_sector_contains_by_bearing_and_range() -> None:
    # North-facing sector, ±60°, ranges [10, 100].
    sector = Sector(
        origin=(0.0, 0.0), heading_deg=90.0, half_angle_deg=60.0, range_min=10.0, range_max=100.0
    )
    points = np.array(
        [
            [0.0, 50.0],  # on the axis
            [50.0, 0.0],  # 90° off axis
            [np.cos(np.radians(31)) * 50, np.sin(np.radians(31)) * 50],  # 59° off: inside
            [np.cos(np.radians(29)) * 50, np.sin(np.radians(29)) * 50],  # 61° off: outside
            [0.0, 5.0],  # closer than range_min
            [0.0, 101.0],  # beyond range_max
        ]
    )
    assert_array_equal(sector.contains(points), [True, False, True, False, False, False])


def test_sector_wraps_around_the_heading() -> None:
    west = Sector(
        origin=(10.0, 0.0), heading_deg=180.0, half_angle_deg=10.0, range_min=0.0, range_max=50.0
    )
    assert_array_equal(
        west.contains(np.array([[-20.0, 1.0], [-20.0, -1.0], [20.0, 0.0]])), [True, True, False]
    )


def test_polygon_view() -> None:
    square = PolygonView(vertices=((0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)))
    assert_array_equal(
        square.contains(np.array([[5.0, 5.0], [10.0, 5.0], [11.0, 5.0]])), [True, True, False]
    )


def test_visibility_distinguishes_blind_zone_from_out_of_range() -> None:
    # Rear and front sensors of a vehicle at the origin ([HZ] §6 overtaking): the sides are blind.
    front = Sector((0.0, 0.0), 0.0, 30.0, 0.0, 100.0)
    rear = Sector((0.0, 0.0), 180.0, 30.0, 0.0, 100.0)
    coverage = Coverage((front, rear))
    points = np.array([[50.0, 0.0], [-50.0, 0.0], [0.0, 20.0], [300.0, 0.0]])
    assert_array_equal(
        coverage.visibility(points),
        [Visibility.VISIBLE, Visibility.VISIBLE, Visibility.BLIND_ZONE, Visibility.OUT_OF_RANGE],
    )
    assert_array_equal(
        coverage.sees(points), [[True, False, False, False], [False, True, False, False]]
    )


def test_explicit_region_and_unlimited_sensor() -> None:
    region = PolygonView(((-10.0, -10.0), (10.0, -10.0), (10.0, 10.0), (-10.0, 10.0)))
    narrow = Sector((0.0, 0.0), 0.0, 5.0, 0.0, 1000.0)
    coverage = Coverage((narrow,), region=region)
    assert_array_equal(
        coverage.visibility(np.array([[5.0, 0.0], [0.0, 5.0], [0.0, 50.0]])),
        [Visibility.VISIBLE, Visibility.BLIND_ZONE, Visibility.OUT_OF_RANGE],
    )
    assert_array_equal(Coverage((None,)).visibility(np.array([[1e6, -1e6]])), [Visibility.VISIBLE])


def test_occlusion_by_a_known_object() -> None:
    # Occluder of radius 2 at (0, 50): hides (0, 100) and (1, 100); not (0, 30) (in front),
    # not (20, 100) (bearing outside asin(2/50) ≈ 2.3°), not the occluder itself.
    points = np.array([[0.0, 100.0], [1.0, 100.0], [0.0, 30.0], [20.0, 100.0], [0.0, 50.0]])
    assert_array_equal(
        occluded((0.0, 0.0), points, np.array([[0.0, 50.0]]), radius=2.0),
        [True, True, False, False, False],
    )
    assert_array_equal(occluded((0.0, 0.0), points, np.zeros((0, 2)), radius=2.0), [False] * 5)


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: Sector((0.0, 0.0), 0.0, 0.0, 0.0, 1.0), "half_angle_deg must be in \\(0, 180\\]"),
        (lambda: Sector((0.0, 0.0), 0.0, 10.0, 5.0, 1.0), "0 <= min < max"),
        (lambda: Sector((0.0, float("nan")), 0.0, 10.0, 0.0, 1.0), "must be finite"),
        (lambda: PolygonView(((0.0, 0.0), (1.0, 1.0))), "at least 3 vertices"),
        (lambda: PolygonView(((0, 0), (1, 1), (1, 0), (0, 1))), "not a simple polygon"),
    ],
)
def test_invalid_fields_of_view(build: object, message: str) -> None:
    with pytest.raises(InvalidInput, match=message):
        build()  # type: ignore[operator]
