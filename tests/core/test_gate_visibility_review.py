"""Review of §8.16 (the probability that a sensor sees a track) joined to §8.14 (the
several-sensor deletion shift): each test is worked by hand, or against Monte Carlo over the
geometry's own ``contains``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.geometry import Coverage, PolygonView, Sector
from core.lifecycle import COASTING, Evidence, LifeCycleConfig, LifeState, TrackStatus, advance
from core.pipeline.evidence import look
from core.pipeline.visibility import inside_probability
from core.tracking.config import LocalTrackerConfig, SensorPhysics
from core.tracking.models import LinearMeasurementModel, ModelBank, constant_velocity
from core.tracking.tracker import LocalTracker
from core.volume import RadarVolume

BASE = math.log(1e-3 / (1.0 - 1e-3))  # the default delete threshold, −6.9068
MISS = math.log(1.0 - 0.9)  # a full miss at P_D 0.9, −2.3026
SHIFT = -math.log(2.0)  # two sensors of one revisit (§8.14)


def _coasting(count: int, score: float, misses: int) -> LifeState:
    state = LifeState.new(count, score, hits=10)
    return LifeState(
        np.full(count, COASTING),
        state.reason,
        state.score,
        state.hits,
        state.empty_gate,
        state.phantom_since,
        np.full(count, misses),
    )


@pytest.mark.parametrize("other", [-math.inf, math.log(0.05 * (1.0 - 0.9))])
def test_the_gate_test_waits_in_full_misses_whatever_another_row_scores(other: float) -> None:
    """Hand-worked (§8.14): two radars of one revisit lower the threshold by ln 2 to −7.600;
    from the ceiling 0 that is ⌈7.600 / 2.3026⌉ = 4 full misses instead of ⌈6.907 / 2.3026⌉
    = 3, so a coasting track (row 0) missed a third time, its gate empty, is not ended by
    gate emptiness before its fourth miss. Row 1 is another track the step's sensor does not
    see: out of the region (p_region 0, ΔL ln 0 = −inf, as ``look`` scores it) or at its
    edge (p = p_region = 0.05: ln(0.05 · 0.1) = −5.30). Its ΔL is never added to any score,
    and it must not change row 0's wait."""
    assert math.ceil((-BASE - SHIFT) / -MISS) - math.ceil(-BASE / -MISS) == 1
    state = _coasting(2, 2 * MISS, 2)
    evidence = Evidence(
        time=10.0,
        detected=np.zeros(2, dtype=bool),
        hit_increment=np.zeros(2),
        seen=np.array([True, False]),
        miss_increment=np.array([MISS, other]),
        gate_log_det=np.full(2, 60.0),  # a gate of e^30 m³: empty-gate factor 0
        gate_dim=3,
        visibility=np.zeros(2, dtype=np.int64),
        occluded=np.zeros(2, dtype=bool),
        densities=(1e-9, 1e-9),
        deletion_shift=np.array([SHIFT, SHIFT]),
        full_miss_increment=MISS,
    )
    after, _ = advance(LifeCycleConfig(), state, evidence)
    assert after.empty_gate[0] == 0.0  # the gate test would fire at this miss
    assert after.misses[0] == 3
    assert after.status[0] == COASTING
    assert after.score[0] == pytest.approx(3 * MISS, abs=1e-12)  # −6.908 > −7.600


def test_look_scores_a_row_out_of_the_region_minus_infinity_unseen() -> None:
    """What makes row 1 above: a track far outside the explicit region (50 σ) is not seen and
    its p_region is 0, its ΔL ln(0 − 0) = −inf."""
    square = PolygonView(((0.0, 0.0), (1000.0, 0.0), (1000.0, 1000.0), (0.0, 1000.0)))
    coverage = Coverage((square,), region=square)
    positions = np.array([[500.0, 500.0], [3500.0, 500.0]])
    covariances = np.repeat((50.0**2 * np.eye(2))[None], 2, axis=0)
    sight = look(
        coverage, square, None, positions, covariances, np.full(2, COASTING), 0.0, 0.9, 13.8
    )
    assert sight.seen.tolist() == [True, False]
    assert sight.miss_increment[0] == pytest.approx(MISS, abs=1e-9)
    assert sight.miss_increment[1] == -math.inf


def _monte_carlo_sector(sector: Sector, mean: np.ndarray, covariance: np.ndarray) -> float:
    samples = np.random.default_rng(7).multivariate_normal(mean, covariance, size=200_000)
    return float(np.mean(sector.contains(samples)))


@pytest.mark.parametrize(
    ("half_angle", "mean"),
    [
        (170.0, (1000.0, 0.0)),  # on the axis of a wide sector: its sides are rays behind
        (120.0, (800.0, 300.0)),
        (150.0, (-500.0, -800.0)),
        (60.0, (400.0, 650.0)),  # near the +60° side, ahead: the line is the ray
    ],
)
def test_a_sectors_side_is_a_ray_from_the_apex_against_monte_carlo(
    half_angle: float, mean: tuple[float, float]
) -> None:
    """A sector's side is the ray from its apex at heading ± half-angle, not the whole line:
    past the apex (a wide sector's point ahead, a narrow sector's point behind it) the
    nearest point of the side is the apex. A wide sector of a half-angle over 90°: on the
    axis 1000 m ahead with σ 300 m the line through the apex at 170° is 174 m away (p 0.72),
    while the ray is 1000 m away and nearly every sample is inside (Monte Carlo). (A point
    near the apex or a non-convex corner is §8.16's approximation, not tested here.)"""
    sector = Sector((0.0, 0.0), 0.0, half_angle, 0.0, 50_000.0)
    covariance = np.diag([300.0**2, 300.0**2])
    expected = _monte_carlo_sector(sector, np.array(mean), covariance)
    p = inside_probability(sector, None, np.array([mean]), covariance[None])[0]
    assert abs(p - expected) <= 0.01 + 4.0 * math.sqrt(expected * (1 - expected) / 200_000)


def test_a_gate_behind_a_narrow_sectors_apex_is_not_seen() -> None:
    """Hand-worked: a sector of ±30° at the origin facing +x; a track 1500 m behind it, σ
    300 m each way. Its gate (γ = 13.82, 2-D 0.999) reaches √γ σ = 1115 m, short of the
    sector's nearest point (the apex, 1500 m away): the sensor does not see it, and a scan
    that does not detect it is no miss. The line through the apex at −30° is 750 m away
    (inside the gate) and would make it seen."""
    gate = 13.815510557964274
    assert math.sqrt(gate) * 300.0 < 1500.0 and 1500.0 * math.sin(math.radians(30.0)) < (
        math.sqrt(gate) * 300.0
    )
    sector = Sector((0.0, 0.0), 0.0, 30.0, 0.0, 50_000.0)
    coverage = Coverage((sector, sector))
    positions = np.array([[-1500.0, 0.0], [-1500.0, 1.0]])
    covariances = np.repeat((300.0**2 * np.eye(2))[None], 2, axis=0)
    sight = look(
        coverage, sector, None, positions, covariances, np.full(2, COASTING), 0.0, 0.9, gate
    )
    assert sight.seen.tolist() == [False, False]
    assert sight.probability == pytest.approx(
        [0.5 * math.erfc(1500.0 / 300.0 / math.sqrt(2.0))] * 2, rel=1e-3
    )


EARTH, HEIGHT = 6_371_000.0, 150.0
ANTENNA_HORIZON = math.sqrt(2.0 * 4.0 / 3.0 * EARTH * HEIGHT)  # a = 50 482 m, by hand


def _at(distance: float, height: float) -> tuple[float, float, float]:
    """The point ``distance`` east of the antenna at ``height`` above the sphere below it."""
    return (distance, 0.0, math.sqrt((EARTH + height) ** 2 - distance**2) - EARTH - HEIGHT)


@pytest.mark.parametrize(
    ("beyond", "height", "seed"),
    [(-300.0, 10.0, 21), (-1.0, 10.0, 22), (1.0, 10.0, 23), (300.0, 60.0, 24), (1.0, -5.0, 25)],
)
def test_the_horizon_at_the_antennas_own_horizon_distance_against_monte_carlo(
    beyond: float, height: float, seed: int
) -> None:
    """Inside the antenna's own horizon distance a = √(2kR h_a) every height is seen (the
    horizon there is d ≤ a + √(2kR h_t) with h_t ≥ 0 clamped), beyond it only h_t ≥
    (d − a)² / 2kR: the limit is the union of the two, which has a corner at (d = a,
    h_t = 0). A track predicted 10 m up a metre inside a, σ 300 m across and 80 m up, is
    outside only where it is both beyond a and under the surface: about ½ · Φ(−10/80), p
    0.78 (Monte Carlo) — not 1 a metre inside a and 0.55 a metre beyond it."""
    volume = RadarVolume(
        site=(0.0, 0.0, 0.0),
        range_max=150_000.0,
        elevation_min_deg=-2.0,
        elevation_max_deg=30.0,
        antenna_height=HEIGHT,
    )
    mean = np.array(_at(ANTENNA_HORIZON + beyond, height))
    covariance = np.diag([300.0**2, 300.0**2, 80.0**2])
    samples = np.random.default_rng(seed).multivariate_normal(mean, covariance, size=200_000)
    expected = float(np.mean(volume.contains(samples)))
    p = inside_probability(None, volume, mean[None], covariance[None])[0]
    assert abs(p - expected) <= 0.01 + 4.0 * math.sqrt(expected * (1 - expected) / 200_000)


def _box(x0: float, x1: float) -> PolygonView:
    return PolygonView(((x0, 0.0), (x1, 0.0), (x1, 2000.0), (x0, 2000.0)))


def test_a_sensor_hides_a_track_only_after_two_misses_none_detecting_it_since() -> None:
    """§8.16's hiding rule, by hand: two sensors ``a`` and ``b`` see x ≤ 3000 m of a region
    reaching x = 6000 m; a track held 4 m past that edge (p ≈ 0.02–0.07: seen by its gate,
    each miss tiny). ``a`` misses it at t = 4 and 5, but ``b`` detects it at t = 4.5 and
    misses it at 5.5: since the latest detection ``a`` has missed it once, not twice, so its
    scan at t = 6 judges it at p ≥ Φ(−√γ), not ½ — it is missed again (coasting), not
    hidden (a phantom, which no detection could take again)."""
    bank = ModelBank(
        models=(constant_velocity(1.0, 0.05, axes=2, noise="continuous"),),
        measurement=LinearMeasurementModel.position(3.0**2, 4),
        mode_transition=np.ones((1, 1)),
    )
    tracker = LocalTracker(
        LocalTrackerConfig(
            bank=bank,
            time_interval=1.0,
            life_cycle=LifeCycleConfig(new_target_density=1e-6),
            initial_velocity_std=1.0,
            sensor_physics={
                "a": SensorPhysics(0.9, 1e-5, None),
                "b": SensorPhysics(0.9, 1e-5, None),
            },
            fields_of_view={"a": _box(0.0, 3000.0), "b": _box(0.0, 3000.0)},
            region=_box(0.0, 6000.0),
            classification=None,
            id_prefix="C",
        )
    )
    seen, unseen = np.array([[3004.0, 1000.0]]), np.zeros((0, 2))
    scans = [("a", seen), ("b", seen)] * 4 + [
        ("a", unseen),  # t = 4: a's first miss
        ("b", seen),  # t = 4.5: b detects it
        ("a", unseen),  # t = 5: a's first miss since
        ("b", unseen),  # t = 5.5
        ("a", unseen),  # t = 6: a's second miss since
    ]
    for index, (sensor, detections) in enumerate(scans):
        step = tracker.step(0.5 * index, detections, sensor=sensor)
    track = step.track("C1")
    assert track.status == TrackStatus.COASTING
