"""Fields of view, blind zones and occlusion ([HZ] §2.1, §5; docs/algorithms.md §4).

A sensor sees a region of the plane: a *sector* (origin, heading, half-angle,
minimum and maximum range) or a *polygon*. For a track position the
:class:`Coverage` of all sensors says why it may be invisible:

- ``VISIBLE``: inside at least one field of view;
- ``BLIND_ZONE``: inside the surveillance region but outside every field of view;
- ``OUT_OF_RANGE``: outside the surveillance region.

**Reading.** [HZ] defines the blind zone as "within the normal detection
range of a multi-sensor system" that no sensor sees. Unless a surveillance
region is given explicitly, it is the union of each sensor's *range*: the
disc of radius ``range_max`` around a sector's origin (whatever the heading),
and the polygon itself for a polygon field of view.

All functions are vectorised over positions (``points`` of shape (N, 2)).
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import shapely

from core.arrays import BoolArray, FloatArray, IntArray
from core.errors import InvalidInput
from core.volume import RadarVolume


class Visibility(enum.IntEnum):
    """Why a position is, or is not, seen by the sensors ([HZ] §2.1)."""

    VISIBLE = 0
    BLIND_ZONE = 1
    OUT_OF_RANGE = 2


def _as_points(points: FloatArray) -> FloatArray:
    array = np.asarray(points, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 2:
        raise InvalidInput(f"positions must have shape (N, 2), got {array.shape}")
    return array


@dataclass(frozen=True)
class Sector:
    """A sector field of view.

    Parameters
    ----------
    origin : (x, y) of the sensor.
    heading_deg : direction of the sector's axis, degrees counter-clockwise from +x.
    half_angle_deg : half the opening, in (0, 180]; 180 is a full disc.
    range_min, range_max : radial limits, 0 ≤ range_min < range_max.
    """

    origin: tuple[float, float]
    heading_deg: float
    half_angle_deg: float
    range_min: float
    range_max: float

    def __post_init__(self) -> None:
        values = (
            *self.origin,
            self.heading_deg,
            self.half_angle_deg,
            self.range_min,
            self.range_max,
        )
        if not all(np.isfinite(values)):
            raise InvalidInput("sector field of view: every number must be finite")
        if not 0.0 < self.half_angle_deg <= 180.0:
            raise InvalidInput(
                f"sector half_angle_deg must be in (0, 180], got {self.half_angle_deg}"
            )
        if not 0.0 <= self.range_min < self.range_max:
            raise InvalidInput(
                f"sector range must satisfy 0 <= min < max, got [{self.range_min}, {self.range_max}]"
            )

    def _polar(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        offset = _as_points(points) - np.asarray(self.origin)
        distance = np.hypot(offset[:, 0], offset[:, 1])
        bearing = np.degrees(np.arctan2(offset[:, 1], offset[:, 0]))
        off_axis = np.abs((bearing - self.heading_deg + 180.0) % 360.0 - 180.0)
        return distance, off_axis

    def contains(self, points: FloatArray) -> BoolArray:
        """True where a position is inside the sector (boundaries included)."""
        distance, off_axis = self._polar(points)
        inside = (distance >= self.range_min) & (distance <= self.range_max)
        return np.asarray(inside & (off_axis <= self.half_angle_deg), dtype=np.bool_)

    def in_range(self, points: FloatArray) -> BoolArray:
        """True where a position is within ``range_max`` of the origin, whatever its bearing."""
        distance, _ = self._polar(points)
        return np.asarray(distance <= self.range_max, dtype=np.bool_)


@dataclass(frozen=True)
class PolygonView:
    """A polygonal field of view (simple polygon, vertices in order)."""

    vertices: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        if len(self.vertices) < 3:
            raise InvalidInput(
                f"polygon field of view needs at least 3 vertices, got {len(self.vertices)}"
            )
        if not np.all(np.isfinite(np.asarray(self.vertices, dtype=np.float64))):
            raise InvalidInput("polygon field of view: every vertex must be finite")
        if not shapely.Polygon(self.vertices).is_valid:
            raise InvalidInput("polygon field of view is not a simple polygon (edges cross)")

    @cached_property
    def _shape(self) -> shapely.Polygon:
        """The polygon, built and prepared once per view (not once per step: a session
        keeps its views)."""
        polygon = shapely.Polygon(self.vertices)
        shapely.prepare(polygon)
        return polygon

    def contains(self, points: FloatArray) -> BoolArray:
        """True where a position is inside the polygon or on its boundary."""
        array = _as_points(points)
        inside = shapely.intersects_xy(self._shape, array[:, 0], array[:, 1])
        return np.asarray(inside, dtype=np.bool_)

    def in_range(self, points: FloatArray) -> BoolArray:
        """A polygon's range is the polygon itself."""
        return self.contains(points)


FieldOfView = Sector | PolygonView


@dataclass(frozen=True)
class Coverage:
    """The fields of view of all sensors, and the surveillance region.

    Parameters
    ----------
    views : one field of view per sensor, or ``None`` for a sensor that sees everywhere.
    region : optional explicit surveillance region; by default the union of
        the sensors' ranges (see the module's **Reading**).
    volumes : a 3-D radar's coverage volume per sensor (:class:`~core.volume.RadarVolume`,
        None: none), in the order of ``views``; a sensor with one sees where both its
        field of view and its volume do, and its range is also within the volume's
        instrumented range. Empty (default): no volumes.
    """

    views: tuple[FieldOfView | None, ...]
    region: PolygonView | None = None
    volumes: tuple[RadarVolume | None, ...] = ()

    def _volume(self, index: int) -> RadarVolume | None:
        return self.volumes[index] if index < len(self.volumes) else None

    def sees(self, points: FloatArray) -> BoolArray:
        """``sees[s, i]``: sensor ``s`` has position ``i`` in its field of view (and volume).

        ``points`` (N, 2), or (N, 3) where a sensor has a volume: fields of view are planar
        and look at the first two coordinates."""
        array = np.asarray(points, dtype=np.float64)
        plane = _as_points(array[:, :2] if array.ndim == 2 else array)
        rows = []
        for index, view in enumerate(self.views):
            row = np.ones(len(plane), dtype=np.bool_) if view is None else view.contains(plane)
            volume = self._volume(index)
            if volume is not None:
                row = row & volume.contains(array)
            rows.append(row)
        return np.asarray(rows, dtype=np.bool_).reshape(len(self.views), len(plane))

    def visibility(self, points: FloatArray) -> IntArray:
        """:class:`Visibility` code of every position ((N, 2), or (N, 3): :meth:`sees`)."""
        array = np.asarray(points, dtype=np.float64)
        plane = _as_points(array[:, :2] if array.ndim == 2 else array)
        if any(  # a sensor that sees everywhere
            view is None and self._volume(index) is None for index, view in enumerate(self.views)
        ):
            return np.full(len(plane), int(Visibility.VISIBLE), dtype=np.int64)
        sees = self.sees(array)
        visible = sees.any(axis=0)
        if self.region is not None:
            surveyed = self.region.contains(plane)
        else:
            ranges = []
            for index, (view, seen) in enumerate(zip(self.views, sees, strict=True)):
                # a polygon's range is what it sees: not looked up twice
                if isinstance(view, PolygonView) and self._volume(index) is None:
                    ranges.append(seen)
                    continue
                reach = (
                    np.ones(len(plane), dtype=np.bool_) if view is None else view.in_range(plane)
                )
                volume = self._volume(index)
                ranges.append(reach if volume is None else reach & volume.in_range(array))
            stacked = np.asarray(ranges, dtype=np.bool_).reshape(len(self.views), len(plane))
            surveyed = np.asarray(stacked.any(axis=0), dtype=np.bool_)
        codes = np.where(
            visible,
            Visibility.VISIBLE,
            np.where(surveyed, Visibility.BLIND_ZONE, Visibility.OUT_OF_RANGE),
        )
        return np.asarray(codes, dtype=np.int64)


def occluded(
    origin: Sequence[float], points: FloatArray, occluders: FloatArray, radius: float
) -> BoolArray:
    """True where a known object hides a position from a sensor at ``origin``.

    Each occluder is a disc of ``radius`` around its position; it hides every
    position farther away whose bearing passes through that disc ([HZ] §2.1,
    "occlusion by a known event"). An object never occludes itself: a
    position at the occluder's own place is not hidden by it.
    """
    targets = _as_points(points) - np.asarray(origin, dtype=np.float64)
    blockers = _as_points(occluders) - np.asarray(origin, dtype=np.float64)
    if len(targets) == 0 or len(blockers) == 0:
        return np.zeros(len(targets), dtype=np.bool_)
    target_range = np.hypot(targets[:, 0], targets[:, 1])
    blocker_range = np.hypot(blockers[:, 0], blockers[:, 1])
    target_bearing = np.arctan2(targets[:, 1], targets[:, 0])
    blocker_bearing = np.arctan2(blockers[:, 1], blockers[:, 0])
    separation = np.abs(
        (target_bearing[:, None] - blocker_bearing[None, :] + np.pi) % (2 * np.pi) - np.pi
    )
    with np.errstate(divide="ignore"):
        half_width = np.arcsin(np.clip(radius / np.maximum(blocker_range, radius), 0.0, 1.0))
    behind = target_range[:, None] > blocker_range[None, :] + radius
    return np.asarray((behind & (separation <= half_width[None, :])).any(axis=1), dtype=np.bool_)
