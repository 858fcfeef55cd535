"""A track is in a blind zone only when no sensor sees any of its gate (docs/algorithms.md
§8.11, §8.16): a 3-D track predicted a little under a radar's horizon, its gate reaching above
it, is visible — and then a miss of the radar that sees its gate — not a phantom; planar views
alike (the papers' profile keeps the test at the predicted position).

Oracle: the 4/3-Earth horizon worked by hand. An antenna 150 m up sees a target at ground
distance d when d ≤ 4121.81 m (√150 + √h_t), h_t the target's height above the sphere
(radius 6371 km) tangent below the antenna: at d = 60 km it needs h_t ≥ (60000/4121.81 −
12.2474)² = 5.33 m.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import chi2

from core.geometry import Coverage, PolygonView, Sector, Visibility
from core.pipeline.evidence import coverage_look, look
from core.volume import RadarVolume

EARTH, HEIGHT, DISTANCE = 6_371_000.0, 150.0, 60_000.0
NEEDED = (DISTANCE / 4121.81 - math.sqrt(HEIGHT)) ** 2
GATE = float(chi2.ppf(0.999, 3))


def _at_height(height: float) -> np.ndarray:
    """The point 60 km east of the antenna at ``height`` above the sphere below it."""
    up = math.sqrt((EARTH + height) ** 2 - DISTANCE**2) - EARTH - HEIGHT
    return np.array([[DISTANCE, 0.0, up]])


def _coverage() -> Coverage:
    radar = RadarVolume(site=(0.0, 0.0, 0.0), range_max=150_000.0, antenna_height=HEIGHT)
    return Coverage((None,), volumes=(radar,))


def test_the_hand_worked_height_the_horizon_needs_at_60_km() -> None:
    assert 5.2 < NEEDED < 5.5
    radar = _coverage().volumes[0]
    assert radar is not None
    assert radar.contains(_at_height(NEEDED + 0.1))[0]
    assert not radar.contains(_at_height(NEEDED - 0.1))[0]


def _sees(coverage: Coverage, position: np.ndarray, spread: np.ndarray) -> tuple[list[int], bool]:
    codes, _ = coverage_look(coverage, position, spread, GATE)
    sight = look(
        coverage, None, coverage.volumes[0], position, spread, np.zeros(1, int), 0.0, 0.9, GATE
    )
    return codes.tolist(), bool(sight.seen[0])


def test_a_track_whose_gate_reaches_over_the_horizon_is_seen_not_hidden() -> None:
    # at the surface (h_t = 0), under the horizon; σ_z 30 m: its gate reaches 4.03 σ = 121 m up
    position = _at_height(0.0)
    wide = np.diag([200.0**2, 200.0**2, 30.0**2])[None]
    assert _sees(_coverage(), position, wide) == ([int(Visibility.VISIBLE)], True)
    # σ 1 m: its gate stays within 4 m of the surface, under the 5.33 m the horizon needs
    narrow = np.eye(3)[None]
    assert _sees(_coverage(), position, narrow) == ([int(Visibility.BLIND_ZONE)], False)
    # a position the radar sees is seen
    assert _sees(_coverage(), _at_height(50.0), narrow) == ([int(Visibility.VISIBLE)], True)


def test_planar_views_are_judged_by_the_gate_too_and_the_papers_at_the_position() -> None:
    """A sector's range edge: 200 m out with σ 100 m across, the gate (4.03 σ) reaches in:
    visible and seen; 500 m out it does not: out of range. Without a covariance (the paper
    profile) the first is out of range already: [HZ]'s test at the predicted position."""
    sector = Sector(
        origin=(0.0, 0.0), heading_deg=0.0, half_angle_deg=30.0, range_min=0.0, range_max=1000.0
    )
    coverage = Coverage((sector,))
    spread = (1e4 * np.eye(3))[None]
    for distance, code, seen in (
        (1200.0, Visibility.VISIBLE, True),
        (1500.0, Visibility.OUT_OF_RANGE, False),
    ):
        position = np.array([[distance, 0.0, 0.0]])
        codes, _ = coverage_look(coverage, position, spread, GATE)
        sight = look(coverage, sector, None, position, spread, np.zeros(1, int), 0.0, 0.9, GATE)
        assert codes.tolist() == [int(code)] and sight.seen.tolist() == [seen]
    codes, _ = coverage_look(coverage, np.array([[1200.0, 0.0, 0.0]]), None, GATE)
    assert codes.tolist() == [int(Visibility.OUT_OF_RANGE)]


def test_a_row_missed_at_its_latest_scan_is_judged_at_one_half() -> None:
    """View: the half x ≤ 500 of a square region; σ_x 40 m. 21 m outside the half, p =
    Φ(−21/40) = 0.30 (by hand): its gate reaches in, visible; missed at its latest scan as
    well, it is more likely hidden than missed again: a blind zone of the square, and out of
    range when the half is all the region. 21 m inside (p = 0.70) it stays visible."""
    square = PolygonView(((0.0, 0.0), (1000.0, 0.0), (1000.0, 1000.0), (0.0, 1000.0)))
    half = PolygonView(((0.0, 0.0), (500.0, 0.0), (500.0, 1000.0), (0.0, 1000.0)))
    positions = np.array([[521.0, 500.0], [479.0, 500.0]])
    spread = np.repeat(np.diag([40.0**2, 30.0**2])[None], 2, axis=0)
    p = 0.5 * (1.0 + math.erf(-21.0 / 40.0 / math.sqrt(2.0)))
    assert 0.29 < p < 0.31
    gate = float(chi2.ppf(0.999, 2))
    visible, blind, out = (
        int(Visibility.VISIBLE),
        int(Visibility.BLIND_ZONE),
        int(Visibility.OUT_OF_RANGE),
    )
    region = Coverage((half,), region=square)
    fresh, missed = np.zeros(2, dtype=bool), np.ones(2, dtype=bool)
    assert coverage_look(region, positions, spread, gate, fresh)[0].tolist() == [visible] * 2
    assert coverage_look(region, positions, spread, gate, missed)[0].tolist() == [blind, visible]
    alone = Coverage((half,))
    assert coverage_look(alone, positions, spread, gate, missed)[0].tolist() == [out, visible]
    status = np.zeros(2, dtype=np.int64)
    sight = look(region, half, None, positions, spread, status, 0.0, 0.9, gate, missed)
    assert sight.seen.tolist() == [False, True]  # hidden: not a miss
