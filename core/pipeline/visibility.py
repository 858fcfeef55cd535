"""The probability that a sensor sees a track (docs/algorithms.md §8.16).

A track's predicted position is not a point: it is ``N(x̂, P)``, ``P = HPHᵀ`` on
the position components. :func:`inside_probability` is the probability p that
that position lies inside what a sensor sees — its planar field of view and its
3-D radar volume (or, ``reach=True``, inside its range: the surveillance region
it contributes to, :class:`core.geometry.Coverage`). Each limit of the region is
taken as the straight edge (the tangent plane) nearest to x̂:

    p_limit = Φ(m / √(nᵀ P n)),

``m`` the signed distance of x̂ from the edge (positive inside) and ``n`` the
edge's unit normal; exact for a half-plane, and for a region of several limits
(a sector's ranges and sides, a volume's range, elevations and horizon) the
least of them, ``p = min_l p_l`` — the Fréchet upper bound of the probability of
the intersection, and the probability itself wherever one limit is near and the
others far. A polygon's nearest limit is its nearest edge. Without a covariance
(``None``) p is the indicator of x̂ inside, the papers' test.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ndtr

from core.arrays import FloatArray
from core.geometry import FieldOfView, PolygonView, Sector
from core.volume import EARTH_RADIUS, REFRACTION, RadarVolume


def _edge(margin: FloatArray, normal: FloatArray, covariances: FloatArray) -> FloatArray:
    """Φ(m / √(nᵀ P n)) of each row; a zero variance across: the indicator of m ≥ 0. With a
    normal of any length, ``m = f(x̂)`` and ``n = ∇f``: Φ(f / √(∇fᵀ P ∇f)), the limit
    ``f ≥ 0`` linearised at x̂."""
    spread = np.sqrt(np.maximum(np.einsum("ni,nij,nj->n", normal, covariances, normal), 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = margin / spread
    return np.asarray(np.where(spread > 0.0, ndtr(ratio), margin >= 0.0), dtype=np.float64)


def _unit(vectors: FloatArray, fallback: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The unit vectors of ``vectors`` (n, k) and their lengths; ``fallback`` where zero."""
    length = np.linalg.norm(vectors, axis=1)
    safe = np.where(length > 0.0, length, 1.0)[:, None]
    return np.where(length[:, None] > 0.0, vectors / safe, fallback), length


def _sector(sector: Sector, plane: FloatArray, covariances: FloatArray, reach: bool) -> FloatArray:
    offset = plane - np.asarray(sector.origin, dtype=np.float64)
    heading = math.radians(sector.heading_deg)
    axis = np.broadcast_to(np.array([math.cos(heading), math.sin(heading)]), offset.shape)
    radial, distance = _unit(offset, axis)
    probability = _edge(sector.range_max - distance, -radial, covariances)
    if reach:
        return probability
    if sector.range_min > 0.0:
        probability = np.minimum(
            probability, _edge(distance - sector.range_min, radial, covariances)
        )
    if sector.half_angle_deg < 180.0:
        # the nearer side: the ray from the origin at heading ± half-angle (its line where x̂
        # is abreast of it, m = ρ sin(half-angle − off-axis angle); the apex where x̂ is
        # behind it: a wide sector's point ahead, a narrow sector's point behind)
        half = math.radians(sector.half_angle_deg)
        bearing = np.arctan2(offset[:, 1], offset[:, 0])
        off_axis = np.abs((bearing - heading + math.pi) % (2 * math.pi) - math.pi)
        inside = np.where(off_axis <= half, 1.0, -1.0)
        nearest_distance = np.full(len(offset), np.inf)
        across = np.zeros_like(offset)
        for side in (1.0, -1.0):
            edge = heading + side * half
            along = np.array([math.cos(edge), math.sin(edge)])
            foot = np.maximum(offset @ along, 0.0)[:, None] * along
            normal = np.broadcast_to(
                np.array([side * math.sin(edge), -side * math.cos(edge)]), offset.shape
            )
            direction, gap = _unit(offset - foot, normal)
            nearer = gap < nearest_distance
            nearest_distance = np.where(nearer, gap, nearest_distance)
            across = np.where(nearer[:, None], direction, across)
        probability = np.minimum(probability, _edge(inside * nearest_distance, across, covariances))
    return probability


def _polygon(polygon: PolygonView, plane: FloatArray, covariances: FloatArray) -> FloatArray:
    vertices = np.asarray(polygon.vertices, dtype=np.float64)
    starts, ends = vertices, np.roll(vertices, -1, axis=0)
    along = ends - starts  # (E, 2)
    length2 = np.einsum("ei,ei->e", along, along)
    relative = plane[:, None, :] - starts[None, :, :]  # (n, E, 2)
    t = np.clip(np.einsum("nei,ei->ne", relative, along) / length2, 0.0, 1.0)
    nearest = starts[None] + t[:, :, None] * along[None]
    away = plane[:, None, :] - nearest
    closest = np.argmin(np.einsum("nei,nei->ne", away, away), axis=1)
    rows = np.arange(len(plane))
    # the edge's own inward normal (the polygon's orientation by its signed area)
    area = 0.5 * float(np.sum(starts[:, 0] * ends[:, 1] - ends[:, 0] * starts[:, 1]))
    turn = 1.0 if area > 0.0 else -1.0
    edge = along[closest]
    inward = turn * np.stack([-edge[:, 1], edge[:, 0]], axis=1) / np.sqrt(length2[closest])[:, None]
    sign = np.where(polygon.contains(plane), 1.0, -1.0)
    # across: the line from x̂ to the boundary's nearest point (the edge's normal when x̂ is
    # on it); only nᵀPn is read, whatever the sense of n
    direction, distance = _unit(away[rows, closest], inward)
    return _edge(sign * distance, direction, covariances)


def _planar(
    view: FieldOfView, plane: FloatArray, covariances: FloatArray, reach: bool
) -> FloatArray:
    if isinstance(view, Sector):
        return _sector(view, plane, covariances, reach)
    return _polygon(view, plane, covariances)


def _volume(
    volume: RadarVolume, positions: FloatArray, covariances: FloatArray, reach: bool
) -> FloatArray:
    local = volume.local(positions)
    axes = np.asarray(volume.axes, dtype=np.float64)
    turned = np.einsum("ij,njk,lk->nil", axes, covariances, axes)
    count = len(local)
    probability = np.ones(count)
    up = np.broadcast_to(np.array([0.0, 0.0, 1.0]), local.shape)
    radial, slant = _unit(local, up)
    if volume.range_max is not None:
        probability = np.minimum(probability, _edge(volume.range_max - slant, -radial, turned))
    if reach:
        if volume.antenna_height is not None:
            # no target is under the surface the horizon lies on: h_t ≥ 0
            probability = np.minimum(probability, _surface(volume, local, turned))
        return probability
    east, north, height = local.T
    flat = np.stack([east, north, np.zeros(count)], axis=1)
    across, ground = _unit(flat, np.broadcast_to(np.array([1.0, 0.0, 0.0]), local.shape))
    elevation = np.arctan2(height, ground)
    for limit, sense, bound in (
        (volume.elevation_max_deg, -1.0, volume.elevation_max_deg < 90.0),
        (volume.elevation_min_deg, 1.0, volume.elevation_min_deg > -90.0),
    ):
        if not bound:
            continue
        # the cone's tangent plane along x̂'s azimuth: normal towards higher elevations
        angle = math.radians(limit)
        normal = -math.sin(angle) * across + math.cos(angle) * up
        margin = sense * slant * np.sin(elevation - angle)
        probability = np.minimum(probability, _edge(margin, sense * normal, turned))
    if volume.antenna_height is not None:
        probability = np.minimum(probability, _horizon(volume, local, turned, across, ground))
    return probability


def _surface(volume: RadarVolume, local: FloatArray, covariances: FloatArray) -> FloatArray:
    """The surface ``h_t ≥ 0`` as a limit: Φ(h_t / σ) across it (∇h_t, the local vertical)."""
    assert volume.antenna_height is not None
    east, north, up = local.T
    toward_centre = np.stack([east, north, EARTH_RADIUS + volume.antenna_height + up], axis=1)
    vertical = toward_centre / np.linalg.norm(toward_centre, axis=1)[:, None]
    return _edge(volume.height(local), vertical, covariances)


def _horizon(
    volume: RadarVolume,
    local: FloatArray,
    covariances: FloatArray,
    across: FloatArray,
    ground: FloatArray,
) -> FloatArray:
    """The horizon ``d ≤ √(2kR h_a) + √(2kR h_t)`` as a limit: the union of ``d ≤ a``
    (``a = √(2kR h_a)``, the antenna's own horizon distance: every height is seen within
    it) and, beyond it, ``f = h_t − (d − a)² / (2kR) ≥ 0`` (smooth, its gradient
    ``∇h_t − (d − a)/(kR) ∇d``). Each is its straight edge; the target is outside only
    where it is outside both, taken as independent (the ground range across and the
    height up): ``p = 1 − (1 − p_a)(1 − p_f)`` — p_f beyond a by a few σ, 1 within it, and
    no jump at the corner ``(d = a, h_t = 0)``."""
    assert volume.antenna_height is not None
    effective = REFRACTION * EARTH_RADIUS
    reach = math.sqrt(2.0 * effective * volume.antenna_height)
    height = volume.height(local)
    east, north, up = local.T
    toward_centre = np.stack([east, north, EARTH_RADIUS + volume.antenna_height + up], axis=1)
    gradient_height = toward_centre / np.linalg.norm(toward_centre, axis=1)[:, None]
    beyond = np.maximum(ground - reach, 0.0)
    above = _edge(
        height - beyond**2 / (2.0 * effective),
        gradient_height - (beyond / effective)[:, None] * across,
        covariances,
    )
    within = _edge(reach - ground, -across, covariances)
    return np.asarray(1.0 - (1.0 - within) * (1.0 - above), dtype=np.float64)


def inside_probability(
    view: FieldOfView | None,
    volume: RadarVolume | None,
    positions: FloatArray,
    covariances: FloatArray | None,
    *,
    reach: bool = False,
) -> FloatArray:
    """p of each row: the probability that ``N(x̂, P)`` lies inside what a sensor sees (its
    field of view ``view`` and volume ``volume``; ``reach``: its range only), the least of
    its limits, each its nearest straight edge (module docstring).

    ``positions`` (n, q): planar views look at the first two components, a volume at three;
    ``covariances`` (n, q, q) P on them, or None: the indicator of x̂ inside (the sensors'
    own ``contains`` / ``in_range``).
    """
    points = np.asarray(positions, dtype=np.float64)
    count = len(points)
    if covariances is None:
        inside = np.ones(count, dtype=bool)
        if count and view is not None:
            plane = points[:, :2]
            inside &= view.in_range(plane) if reach else view.contains(plane)
        if count and volume is not None:
            inside &= volume.in_range(points) if reach else volume.contains(points)
        return inside.astype(np.float64)
    spread = np.asarray(covariances, dtype=np.float64)
    probability = np.ones(count)
    if count == 0:
        return probability
    if view is not None:
        plane = np.ascontiguousarray(points[:, :2])
        probability = np.minimum(probability, _planar(view, plane, spread[:, :2, :2], reach))
    if volume is not None:
        probability = np.minimum(probability, _volume(volume, points, spread, reach))
    return np.asarray(np.clip(probability, 0.0, 1.0), dtype=np.float64)
