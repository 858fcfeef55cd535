"""A radar's coverage volume from its data sheet: instrumented range, elevation limits and
the 4/3-Earth radar horizon (docs/algorithms.md §8.11).

A 3-D radar at a site sees a position when, in the site's own East-North-Up
axes (``e, n, u`` from the antenna, metres):

- its slant range ``ρ = √(e² + n² + u²)`` is at most the instrumented range
  ``range_max``;
- its elevation ``ε = atan2(u, √(e² + n²))`` lies in ``[elevation_min_deg,
  elevation_max_deg]`` (what ``pymap3d.geodetic2aer`` gives at a geodetic site);
- with an ``antenna_height`` ``h_a`` (metres above the surface the horizon lies on:
  ground or sea), it is above the radar horizon of the 4/3-Earth model: its ground
  range ``d = √(e² + n²)`` is at most

      d_h = √(2 k R h_a) + √(2 k R h_t),   k = 4/3, R = 6 371 km   [SK] ch. 8, [FS]

  (the standard atmosphere's refraction bends rays as if the Earth's radius were
  k R and the rays straight; each term is the distance to the tangent point of an
  antenna, or a target, at that height, ``√(2 k R h)`` the first order of
  ``k R acos(k R / (k R + h))``). The target's height ``h_t`` (0 below the
  surface) is its geometric height above a sphere of radius R tangent to the
  surface below the antenna, ``h_t = √(e² + n² + (R + h_a + u)²) − R``: within a few
  metres of its WGS84 height at 150 km from the site (the sphere's curvature
  against the ellipsoid's, ``d²/2 · |1/R − 1/R_ellipsoid|``).

Every test is vectorised over positions. The session frame and the site's axes
are related by a rigid motion (both are ENU frames of the WGS84 ellipsoid, or
the site stands in a flat session's own axes), given here as the site's position
in the session frame and the rotation from the session's axes to the site's:
exact, as the service converts the radar's own detections.

[SK] M. I. Skolnik, *Introduction to Radar Systems*, 3rd ed., McGraw-Hill 2001, ch. 8
"Propagation of radar waves": the 4/3 effective Earth radius and the radar horizon.
[FS] Federal Standard 1037C (1996), "radar line-of-sight equation": the radar horizon range
``4.12 (√h + √a)`` km for an antenna at h and a target at a metres (``√(2 k R) = 4.12`` km
per √m at k = 4/3), second-order terms below 0.1 %.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from core.arrays import BoolArray, FloatArray
from core.errors import InvalidInput

EARTH_RADIUS = 6_371_000.0
"""R (m): the mean Earth radius (IUGG R1)."""
REFRACTION = 4.0 / 3.0
"""k: the effective Earth radius factor of the standard atmosphere ([SK] ch. 8)."""
MEASURE_NODES = 512
"""Slant ranges of :attr:`RadarVolume.measure`'s midpoint rule."""
BISECTIONS = 50
"""Bisections of the lowest visible elevation at each range (2⁻⁵⁰ π rad)."""


@dataclass(frozen=True)
class RadarVolume:
    """A radar's coverage volume (module docstring).

    Parameters
    ----------
    site : the antenna's position in the session frame (x, y, z).
    axes : the rotation from the session's axes to the site's East-North-Up axes
        (rows: the site's east, north and up in session axes); identity by default.
    range_max : the instrumented (slant) range, m; None: no limit.
    elevation_min_deg, elevation_max_deg : the elevation limits, degrees.
    antenna_height : the antenna's height above the surface of its horizon, m;
        None: no horizon.
    """

    site: tuple[float, float, float]
    axes: tuple[tuple[float, float, float], ...] = (
        (1.0, 0.0, 0.0),
        (0.0, 1.0, 0.0),
        (0.0, 0.0, 1.0),
    )
    range_max: float | None = None
    elevation_min_deg: float = -90.0
    elevation_max_deg: float = 90.0
    antenna_height: float | None = None

    def __post_init__(self) -> None:
        axes = np.asarray(self.axes, dtype=np.float64)
        if len(self.site) != 3 or not np.all(np.isfinite(self.site)):
            raise InvalidInput("a radar volume's site must be 3 finite coordinates")
        if axes.shape != (3, 3) or not np.allclose(axes @ axes.T, np.eye(3), atol=1e-9):
            raise InvalidInput("a radar volume's axes must be a 3 × 3 rotation")
        if self.range_max is not None and not (
            math.isfinite(self.range_max) and self.range_max > 0.0
        ):
            raise InvalidInput(f"range_max must be positive, got {self.range_max!r}")
        low, high = self.elevation_min_deg, self.elevation_max_deg
        if not (math.isfinite(low) and math.isfinite(high) and -90.0 <= low < high <= 90.0):
            raise InvalidInput(
                f"elevation limits must satisfy -90 <= min < max <= 90, got [{low}, {high}]"
            )
        height = self.antenna_height
        if height is not None and not (math.isfinite(height) and height >= 0.0):
            raise InvalidInput(f"antenna_height must be ≥ 0, got {height!r}")

    def local(self, positions: FloatArray) -> FloatArray:
        """``(e, n, u)`` of each session-frame position (N, 3) from the antenna."""
        points = np.asarray(positions, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] != 3:
            raise InvalidInput(f"a radar volume needs 3-D positions (N, 3), got {points.shape}")
        offsets = points - np.asarray(self.site, dtype=np.float64)
        return np.asarray(offsets @ np.asarray(self.axes, dtype=np.float64).T, dtype=np.float64)

    def in_range(self, positions: FloatArray) -> BoolArray:
        """Within the instrumented range, whatever the elevation or horizon."""
        local = self.local(positions)
        if self.range_max is None:
            return np.ones(len(local), dtype=np.bool_)
        return np.asarray(np.linalg.norm(local, axis=1) <= self.range_max, dtype=np.bool_)

    def contains(self, positions: FloatArray) -> BoolArray:
        """Inside the volume: range, elevation limits and above the horizon (module docstring)."""
        local = self.local(positions)
        east, north, up = local.T
        ground = np.hypot(east, north)
        inside = np.ones(len(local), dtype=np.bool_)
        if self.range_max is not None:
            inside &= np.sqrt(ground**2 + up**2) <= self.range_max
        if self.elevation_min_deg > -90.0 or self.elevation_max_deg < 90.0:
            elevation = np.degrees(np.arctan2(up, ground))
            inside &= (elevation >= self.elevation_min_deg) & (elevation <= self.elevation_max_deg)
        if self.antenna_height is not None:
            inside &= ground <= self.horizon(local)
        return np.asarray(inside, dtype=np.bool_)

    @property
    def measure(self) -> float:
        """The volume's size (m³) above the surface, or inf without a ``range_max``.

        The sets are symmetric about the antenna's vertical: in slant range ρ and
        elevation ε, ``V = ∫₀^ρmax 2π ρ² (sin ε_max − sin ε_low(ρ)) dρ``, with
        ``ε_low(ρ)`` the elevation minimum or, with an antenna height, the lowest
        elevation at ρ above the horizon and the surface (``h_t ≥ 0``: no target
        flies below it; :meth:`contains` does not ask), found by bisection (both
        tests pass from there up). Midpoint rule over :data:`MEASURE_NODES` ranges:
        without a horizon it is ``2π/3 ρ_max³ (sin ε_max − sin ε_min)`` to 1e-5.
        Used for the default birth density (docs/algorithms.md §8.12).
        """
        if self.range_max is None:
            return math.inf
        step = self.range_max / MEASURE_NODES
        slant = (np.arange(MEASURE_NODES) + 0.5) * step
        low = np.full(MEASURE_NODES, math.radians(self.elevation_min_deg))
        high = math.radians(self.elevation_max_deg)
        if self.antenna_height is not None:
            below = np.full(MEASURE_NODES, -math.pi / 2)  # not seen: the surface is above
            above = np.full(MEASURE_NODES, max(min(0.0, high), -math.pi / 2))
            for _ in range(BISECTIONS):
                middle = 0.5 * (below + above)
                local = np.stack(
                    [slant * np.cos(middle), np.zeros(MEASURE_NODES), slant * np.sin(middle)],
                    axis=1,
                )
                seen = (self.height(local) >= 0.0) & (local[:, 0] <= self.horizon(local))
                below, above = np.where(seen, below, middle), np.where(seen, middle, above)
            low = np.maximum(low, above)
        band = np.maximum(math.sin(high) - np.sin(low), 0.0)
        return float(2.0 * math.pi * np.sum(slant**2 * band) * step)

    def height(self, local: FloatArray) -> FloatArray:
        """The target height ``h_t`` (m) above the sphere tangent below the antenna of each
        site-ENU offset (N, 3) (module docstring; negative below it)."""
        assert self.antenna_height is not None
        east, north, up = np.asarray(local, dtype=np.float64).T
        base = EARTH_RADIUS + self.antenna_height + up
        # h_t = √(g² + b²) − R, written to keep its digits at small heights
        return np.asarray(
            (east**2 + north**2 + (self.antenna_height + up) * (base + EARTH_RADIUS))
            / (np.sqrt(east**2 + north**2 + base**2) + EARTH_RADIUS),
            dtype=np.float64,
        )

    def horizon(self, local: FloatArray) -> FloatArray:
        """The 4/3-Earth horizon distance ``d_h`` (m) of each site-ENU offset (N, 3)
        ([SK] ch. 8, [FS]; module docstring)."""
        assert self.antenna_height is not None
        target = self.height(local)
        effective = 2.0 * REFRACTION * EARTH_RADIUS
        return np.asarray(
            math.sqrt(effective * self.antenna_height)
            + np.sqrt(effective * np.maximum(target, 0.0)),
            dtype=np.float64,
        )
