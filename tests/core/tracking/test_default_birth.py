"""The default birth density (docs/algorithms.md §8.12): one new target a minute in a sensor's
coverage volume, never above its clutter density.

Oracles: the coverage volume's size in closed form (a spherical sector) and by a Monte Carlo
count of points that pass the volume's definition written out here (4/3-Earth horizon, a
spherical Earth); the start score ``L₀ = ln(β_NT/β_FT)`` worked by hand; and the number of
tracks a radar that sees only clutter confirms, worked by hand as a Poisson count from the
SPRT's increments and thresholds ([MTT] §4.3 eq 16).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import chi2, poisson

from core.lifecycle import BIRTH_RATE, LifeCycleConfig, default_birth_density
from core.tracking.config import LocalTrackerConfig
from core.tracking.models import LinearMeasurementModel, ModelBank, constant_velocity
from core.tracking.tracker import LocalTracker
from core.volume import RadarVolume

EARTH = 6_371_000.0


def test_a_volume_without_horizon_measures_its_spherical_sector() -> None:
    # V = 2π/3 ρ³ (sin ε_max − sin ε_min)
    for low, high in ((0.0, 30.0), (-10.0, 60.0), (-90.0, 90.0)):
        volume = RadarVolume(
            site=(1.0, 2.0, 3.0), range_max=80_000.0, elevation_min_deg=low, elevation_max_deg=high
        )
        band = math.sin(math.radians(high)) - math.sin(math.radians(low))
        exact = 2.0 * math.pi / 3.0 * 80_000.0**3 * band
        assert volume.measure == pytest.approx(exact, rel=1e-5)
    assert RadarVolume(site=(0.0, 0.0, 0.0)).measure == math.inf


def test_a_volume_with_a_horizon_measures_what_a_monte_carlo_count_gives() -> None:
    """Points uniform in the range sphere, kept when above the ground of a spherical Earth
    (centre 6371 km + h_a below the antenna), under the top elevation and within the
    4/3-Earth horizon 4121.81 m (√h_a + √h_t) of the antenna's vertical."""
    height, reach, top = 150.0, 150_000.0, 30.0
    volume = RadarVolume(
        site=(0.0, 0.0, 0.0), range_max=reach, elevation_max_deg=top, antenna_height=height
    )
    rng = np.random.default_rng(5)
    count = 1_000_000
    direction = rng.normal(size=(count, 3))
    direction /= np.linalg.norm(direction, axis=1)[:, None]
    points = direction * (reach * rng.uniform(size=count) ** (1 / 3))[:, None]
    east, north, up = points.T
    ground = np.hypot(east, north)
    above = np.sqrt(east**2 + north**2 + (EARTH + height + up) ** 2) - EARTH
    kept = (
        (above >= 0.0)
        & (np.degrees(np.arctan2(up, ground)) <= top)
        & (ground <= 4121.81 * (math.sqrt(height) + np.sqrt(np.maximum(above, 0.0))))
    )
    sphere = 4.0 / 3.0 * math.pi * reach**3
    share = kept.mean()
    error = math.sqrt(share * (1 - share) / count)
    assert volume.measure == pytest.approx(share * sphere, abs=4 * error * sphere)
    # the horizon adds a sliver under elevation 0 to the 0–30° sector (2π/3 ρ³ sin 30°)
    assert 1.0 < volume.measure / (math.pi / 3.0 * reach**3) < 1.03


def test_the_default_birth_density_is_a_new_target_a_minute_in_the_coverage() -> None:
    volume = 3.6e15
    clutter = 30.0 / volume  # 30 false alarms a scan in the coverage
    # a 12 s radar: 0.2 births a scan over 30 false alarms, L₀ = ln(0.2 / 30) = −5.01
    birth = default_birth_density(clutter, volume, 12.0)
    assert birth == pytest.approx(0.2 / volume)
    assert math.log(birth / clutter) == pytest.approx(-5.0106, abs=1e-4)
    score = LifeCycleConfig().scan_score(0.9, clutter, volume, 12.0)
    assert score.initial == pytest.approx(math.log(0.2 / 30.0))
    # never above β_FT: a quiet sensor (0.01 false alarms a scan) keeps prior odds 1
    assert default_birth_density(0.01 / volume, volume, 12.0) == 0.01 / volume
    # a sensor's first scan (no previous one): every target is new to it, β_FT
    assert default_birth_density(clutter, volume, math.inf) == clutter
    # no coverage volume: β_FT, as before; a given birth density wins
    assert LifeCycleConfig().scan_score(0.9, clutter).initial == 0.0
    given = LifeCycleConfig(new_target_density=1e-17).scan_score(0.9, clutter, volume, 12.0)
    assert given.new_target_density == 1e-17
    assert BIRTH_RATE == 1.0 / 60.0


SIGMA, VELOCITY_STD, PERIOD, REACH, FALSE_ALARMS, SCANS = 200.0, 50.0, 12.0, 100_000.0, 30, 40
RADAR = RadarVolume(
    site=(0.0, 0.0, 0.0), range_max=REACH, elevation_min_deg=0.0, elevation_max_deg=30.0
)


def _radar(birth_density: float | None) -> LocalTracker:
    """A 3-D radar (σ 200 m per axis, 12 s scans, a velocity prior of 50 m/s) told its
    coverage and its clutter density, 30 false alarms a scan; defaults otherwise."""
    bank = ModelBank(
        models=(constant_velocity(PERIOD, 1.0, axes=3, noise="continuous"),),
        measurement=LinearMeasurementModel.position(1.0, 6),
        mode_transition=np.ones((1, 1)),
    )
    return LocalTracker(
        LocalTrackerConfig(
            time_interval=PERIOD,
            axes=3,
            bank=bank,
            measurement_noise=tuple(tuple(row) for row in (SIGMA**2 * np.eye(3)).tolist()),
            initial_velocity_std=VELOCITY_STD,
            classification=None,
            life_cycle=LifeCycleConfig(
                false_target_density=FALSE_ALARMS / RADAR.measure,
                new_target_density=birth_density,
            ),
            fields_of_view={"radar": None},
            volumes={"radar": RADAR},
        )
    )


def _clutter(rng: np.random.Generator) -> np.ndarray:
    """A Poisson number of false alarms, uniform in the sector (ρ³, sin ε, azimuth uniform)."""
    count = rng.poisson(FALSE_ALARMS)
    reach = REACH * rng.uniform(size=count) ** (1 / 3)
    rise = rng.uniform(0.0, 0.5, count)
    azimuth = rng.uniform(0.0, 2 * math.pi, count)
    flat = reach * np.sqrt(1 - rise**2)
    return np.stack([flat * np.sin(azimuth), flat * np.cos(azimuth), reach * rise], axis=1)


def _confirmed(birth_density: float | None, seeds: range) -> int:
    total = 0
    for seed in seeds:
        rng = np.random.default_rng(seed)
        tracker, confirmed = _radar(birth_density), set()
        for scan in range(SCANS):
            step = tracker.step(scan * PERIOD, _clutter(rng), sensor="radar")
            confirmed |= {t.id for t in step.tracks if t.status.value == "confirmed"}
        total += len(confirmed)
    return total


def _pairs(clutter: float, start: float, scans: int) -> float:
    """Expected false alarms, ``scans`` scans after a start of score ``start`` (which missed
    the scans between), that bring it to L ≥ 0: those in the ellipsoid D ≤ D* = 2(ΔL_max +
    start), within the 0.999 gate, of S = (2σ² + σ_v²Δt² + qΔt³/3) I, Δt = scans × 12 s
    (Poisson: β_FT × its volume (4π/3) D*^{3/2} √|S|)."""
    interval = scans * PERIOD
    spread = 2 * SIGMA**2 + VELOCITY_STD**2 * interval**2 + interval**3 / 3
    root_det = spread**1.5
    best = math.log(0.9 / ((2 * math.pi) ** 1.5 * clutter * root_det))
    reach = min(max(2 * (best + start), 0.0), chi2.ppf(0.999, 3))
    return clutter * 4 * math.pi / 3 * reach**1.5 * root_det


def test_a_radar_seeing_only_clutter_confirms_what_the_poisson_count_gives() -> None:
    """By hand. β_FT = 30/V, V = 2π/3 (100 km)³ sin 30° = 1.047e15 m³. A start (one
    detection, L₀ = ln(0.2/30) = −5.01) that misses falls to L₀ + ln 0.1 = −7.31, below the
    delete threshold ln(β/(1 − α)) = −6.91: only its next scan's detections can confirm it.
    A hit adds ΔL = ln[P_D / ((2π)^{3/2} β_FT √|S|)] − D/2, so min_points (two hits, L ≥ 0)
    confirms the pairs at D ≤ D* = 2(ΔL_max + L₀) = 7.6 (:func:`_pairs`): 7.4e-4 a start,
    30 starts a scan, 39 scans to a run: 0.87 a run. The first scan's starts are at prior
    odds 1 (everything is new to a sensor's first look): they confirm with a false alarm
    anywhere in their gate one scan later, or, having missed one or two scans (L = −2.3,
    −4.6), in their wider gates two or three scans later: 0.34 a run. Pairs that stay under
    0 and a third detection in their gate add a few %. With prior odds 1 at every scan (the
    rule before) every start lives through two misses: several times more."""
    clutter = FALSE_ALARMS / RADAR.measure
    start = math.log(BIRTH_RATE * PERIOD / FALSE_ALARMS)
    assert start + math.log(0.1) < math.log(1e-3 / (1 - 1e-3))
    per_run = FALSE_ALARMS * (SCANS - 1) * _pairs(clutter, start, 1)
    assert per_run == pytest.approx(0.87, rel=0.05)
    first = FALSE_ALARMS * sum(_pairs(clutter, k * math.log(0.1), k + 1) for k in range(3))
    assert first == pytest.approx(0.34, rel=0.05)
    runs = range(6)
    expected = len(runs) * (per_run + first)
    found = _confirmed(None, runs)
    low, high = poisson.ppf([0.001, 0.999], expected * 1.1)
    assert low <= found <= high
    # the rule before (prior odds 1) confirms clutter the Poisson count above cannot explain
    assert _confirmed(clutter, runs) > high
