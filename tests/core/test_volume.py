"""A radar's coverage volume (core/volume.py) against an independent computation: pymap3d's
geodetic2aer at the radar's geodetic site for range and elevation, and the 4/3-Earth radar
horizon worked by hand (``√(2kRh_a) + √(2kRh_t)``, k = 4/3, R = 6371 km) on the targets'
WGS84 heights. The volume gets only the site's place and axes in the session frame, made
here with pymap3d (not the service's geodesy)."""

from __future__ import annotations

import math

import numpy as np
import pymap3d
import pytest

from core.errors import InvalidInput
from core.geometry import Coverage, Visibility
from core.volume import RadarVolume

ORIGIN = (48.85, 2.45, 100.0)
SITE = (49.45, 2.10, 150.0)  # ~71 km north-north-west of the origin: 0.64° of tilt

# by hand: √(2 · 4/3 · 6 371 000 m) = 4121.81 m per √m
PER_ROOT_METRE = 4121.81


def site_volume(**limits: float | None) -> RadarVolume:
    """The radar at SITE in the session frame at ORIGIN: its place, and its ENU axes (the
    rows) written in the session's axes (each unit vector to ECEF at the site, back at the
    origin)."""
    place = pymap3d.geodetic2enu(*SITE, *ORIGIN)
    rows = []
    for unit in np.eye(3):
        ecef = pymap3d.enu2uvw(*unit, SITE[0], SITE[1])
        rows.append(tuple(float(x) for x in pymap3d.uvw2enu(*ecef, ORIGIN[0], ORIGIN[1])))
    return RadarVolume(site=tuple(float(x) for x in place), axes=tuple(rows), **limits)  # type: ignore[arg-type]


def targets(count: int, seed: int, spread: float = 4.0) -> tuple[np.ndarray, np.ndarray]:
    """Random WGS84 points within ``spread``° of latitude of the site (as far in longitude)
    at 0–13 km, and their session ENU."""
    rng = np.random.default_rng(seed)
    lat = SITE[0] + rng.uniform(-spread, spread, count)
    lon = SITE[1] + rng.uniform(-1.5 * spread, 1.5 * spread, count)
    height = rng.uniform(0.0, 13_000.0, count)
    enu = np.stack(pymap3d.geodetic2enu(lat, lon, height, *ORIGIN), axis=-1)
    return np.stack([lat, lon, height], axis=-1), enu


def test_the_hand_worked_horizon_of_an_antenna_at_150_m() -> None:
    # √(2kR · 150) = 4121.81 · 12.2474 = 50 481 m; √(2kR · 10 000) = 412 181 m
    assert PER_ROOT_METRE * math.sqrt(150.0) == pytest.approx(50_481.0, abs=2.0)
    volume = RadarVolume(site=(0.0, 0.0, 0.0), antenna_height=150.0)
    # straight above the antenna, 9850 m up: 10 km above its surface
    horizon = volume.horizon(np.array([[0.0, 0.0, 9850.0]]))[0]
    assert horizon == pytest.approx(50_481.0 + 412_181.0, abs=5.0)
    # at the surface itself the target's own term vanishes
    assert volume.horizon(np.array([[0.0, 0.0, -150.0]]))[0] == pytest.approx(50_481.0, abs=2.0)


@pytest.mark.parametrize("seed", [1, 2])
def test_range_and_elevation_limits_match_pymap3d_geodetic2aer(seed: int) -> None:
    geodetic, enu = targets(4000, seed, spread=1.6)
    volume = site_volume(range_max=150_000.0, elevation_min_deg=-1.0, elevation_max_deg=30.0)
    _, elevation, slant = pymap3d.geodetic2aer(*geodetic.T, *SITE)
    expected = (slant <= 150_000.0) & (elevation >= -1.0) & (elevation <= 30.0)
    # away from the limits by more than rounding (1 mm, 1e-6°)
    clear = (
        (np.abs(slant - 150_000.0) > 1e-3)
        & (np.abs(elevation + 1.0) > 1e-6)
        & (np.abs(elevation - 30.0) > 1e-6)
    )
    assert 0.2 < expected.mean() < 0.8  # both sides of the limits are tested
    np.testing.assert_array_equal(volume.contains(enu)[clear], expected[clear])
    np.testing.assert_array_equal(volume.in_range(enu), slant <= 150_000.0)


@pytest.mark.parametrize("seed", [1, 2])
def test_the_horizon_matches_the_4_3_earth_formula_on_wgs84_heights(seed: int) -> None:
    geodetic, enu = targets(4000, seed)
    volume = site_volume(antenna_height=SITE[2])  # the horizon's surface: the ellipsoid
    _, elevation, slant = pymap3d.geodetic2aer(*geodetic.T, *SITE)
    ground = slant * np.cos(np.radians(elevation))
    horizon = PER_ROOT_METRE * (math.sqrt(SITE[2]) + np.sqrt(geodetic[:, 2]))
    expected = ground <= horizon
    clear = np.abs(ground / horizon - 1.0) > 0.01  # the sphere's heights: metres off WGS84's
    assert 0.2 < expected[clear].mean() < 0.8
    assert clear.mean() > 0.9
    np.testing.assert_array_equal(volume.contains(enu)[clear], expected[clear])


def test_a_radar_without_limits_sees_everywhere_and_limits_are_checked() -> None:
    _, enu = targets(50, 3)
    assert RadarVolume(site=(0.0, 0.0, 0.0)).contains(enu).all()
    for bad in (
        {"range_max": 0.0},
        {"range_max": math.inf},
        {"elevation_min_deg": 10.0, "elevation_max_deg": 10.0},
        {"elevation_max_deg": 91.0},
        {"antenna_height": -1.0},
    ):
        with pytest.raises(InvalidInput):
            RadarVolume(site=(0.0, 0.0, 0.0), **bad)  # type: ignore[arg-type]
    with pytest.raises(InvalidInput):
        RadarVolume(site=(0.0, 0.0, 0.0)).contains(enu[:, :2])


def test_coverage_codes_of_a_volume_blind_zone_and_out_of_range() -> None:
    """[HZ] §2.1 with volumes: seen inside the volume; within its instrumented range but
    under its horizon (or above its top elevation): a blind zone; beyond it: out of range."""
    volume = RadarVolume(
        site=(0.0, 0.0, 0.0), range_max=150_000.0, elevation_max_deg=30.0, antenna_height=150.0
    )
    points = np.array(
        [
            [80_000.0, 0.0, 9000.0],  # in view
            [0.0, 2000.0, 9000.0],  # 77° up: above the top elevation
            [140_000.0, 0.0, -1700.0],  # 140 km away, on the surface (1538 m down): unseen
            [200_000.0, 0.0, 9000.0],  # beyond the instrumented range
        ]
    )
    codes = Coverage((None,), None, (volume,)).visibility(points)
    assert codes.tolist() == [
        Visibility.VISIBLE,
        Visibility.BLIND_ZONE,
        Visibility.BLIND_ZONE,
        Visibility.OUT_OF_RANGE,
    ]
    # a sensor without a volume or a field of view sees everywhere
    assert (Coverage((None, None), None, (volume, None)).visibility(points) == 0).all()
