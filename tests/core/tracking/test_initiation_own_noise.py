"""Tracks start from each detection's own covariance (a polar radar's thin ellipses).

The converted detection of a radar at range ρ has covariance
``T diag(σ_ρ², (ρσ_a)²) Tᵀ`` (T the rotation to the line of sight), written out
here by hand. A tracker that started its tracks from one isotropic reference R
(the largest converted noise over the coverage, ``(ρ_max σ_a)² I``) took 7.5
scans on average (10 at worst) to confirm a target 50 km out; started from
each detection's own covariance, the two-point velocity is as good as the two
detections make it, the first gates and hits are tighter, and the same targets
confirm within 6 scans on average. The seed's covariance is part of the
tracker's export (version 2 on); a version-1 export restores its seeds with the
bank's R.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from core.errors import TrackingError
from core.tracking import two_point_initiation
from core.tracking.config import LocalTrackerConfig
from core.tracking.initiator import single_point_initiation
from core.tracking.models import LinearMeasurementModel, ModelBank, constant_velocity
from core.tracking.tracker import LocalTracker

SIGMA_RANGE = 20.0
SIGMA_AZIMUTH = math.radians(0.2)
FAR = 50_000.0


def _radar_tracker() -> LocalTracker:
    """The tracker the service builds for a polar radar: one CV model, isotropic bank R."""
    reference = (FAR * SIGMA_AZIMUTH) ** 2
    bank = ModelBank(
        models=(constant_velocity(1.0, 1.0, axes=2, noise="continuous"),),
        measurement=LinearMeasurementModel.position(1.0, 4),
        mode_transition=np.ones((1, 1)),
    )
    return LocalTracker(
        LocalTrackerConfig.paper(
            bank=bank,
            measurement_noise=((reference, 0.0), (0.0, reference)),
        )
    )


def _converted(position: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A noisy polar detection of ``position`` (radar at 0) as a point and its covariance."""
    rho = math.hypot(*position) + rng.normal(0.0, SIGMA_RANGE)
    azimuth = math.atan2(position[0], position[1]) + rng.normal(0.0, SIGMA_AZIMUTH)
    along = np.array([math.sin(azimuth), math.cos(azimuth)])
    across = np.array([math.cos(azimuth), -math.sin(azimuth)])
    turn = np.stack([along, across], axis=1)
    covariance = turn @ np.diag([SIGMA_RANGE**2, (rho * SIGMA_AZIMUTH) ** 2]) @ turn.T
    return rho * along, covariance


def _confirmation_scan(tracker: LocalTracker, rng: np.random.Generator, own: bool) -> int:
    bearing = math.radians(rng.uniform(0.0, 360.0))
    heading = math.radians(rng.uniform(0.0, 360.0))
    start = FAR * np.array([math.sin(bearing), math.cos(bearing)])
    velocity = 200.0 * np.array([math.sin(heading), math.cos(heading)])
    for scan in range(30):
        point, covariance = _converted(start + velocity * scan, rng)
        step = tracker.step(float(scan), point[None], covariance[None] if own else None)
        if any(track.status.value == "confirmed" for track in step.tracks):
            return scan
    return 99


def test_a_far_polar_target_confirms_sooner_from_its_own_covariances() -> None:
    rng = np.random.default_rng(1)
    delays = [_confirmation_scan(_radar_tracker(), rng, own=True) for _ in range(20)]
    print(f"scans to confirm at 50 km: mean {np.mean(delays)}, max {max(delays)}")
    assert np.mean(delays) <= 6.5, delays
    assert max(delays) <= 8, delays


def test_two_point_start_is_the_difference_of_two_detections_with_their_own_noise() -> None:
    """Position z1 (R1), velocity (z1 − z0)/ΔT ((R0 + R1)/ΔT²), cross-covariance R1/ΔT."""
    bank = _radar_tracker().bank
    rng = np.random.default_rng(3)
    z0, r0 = _converted(np.array([30_000.0, 40_000.0]), rng)
    z1, r1 = _converted(np.array([30_400.0, 39_700.0]), rng)
    interval = 2.0
    state = two_point_initiation(
        bank, z0[None], z1[None], interval, first_noises=r0[None], second_noises=r1[None]
    )
    mean, covariance = state.combined()
    expected = np.zeros((4, 4))
    pos, vel = [0, 2], [1, 3]
    expected[np.ix_(pos, pos)] = r1
    expected[np.ix_(vel, vel)] = (r0 + r1) / interval**2
    expected[np.ix_(pos, vel)] = r1 / interval
    expected[np.ix_(vel, pos)] = r1 / interval
    np.testing.assert_allclose(covariance[0], expected, rtol=1e-12)
    np.testing.assert_allclose(mean[0, pos], z1, rtol=1e-12)
    np.testing.assert_allclose(mean[0, vel], (z1 - z0) / interval, rtol=1e-12)
    single, single_covariance = single_point_initiation(
        bank, z1[None], 300.0, noises=r1[None]
    ).combined()
    np.testing.assert_allclose(single_covariance[0][np.ix_(pos, pos)], r1, rtol=1e-12)
    np.testing.assert_allclose(single[0, pos], z1, rtol=1e-12)
    with pytest.raises(TrackingError, match="first_noises"):
        two_point_initiation(bank, z0[None], z1[None], interval, first_noises=r0)


def _scans(count: int) -> list[tuple[float, np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(5)
    targets = [np.array([20_000.0, 30_000.0]), np.array([-40_000.0, 10_000.0])]
    velocities = [np.array([-150.0, 0.0]), np.array([0.0, 220.0])]
    scans = []
    for scan in range(count):
        converted = [
            _converted(t + v * scan, rng) for t, v in zip(targets, velocities, strict=True)
        ]
        points = np.array([c[0] for c in converted])
        covariances = np.array([c[1] for c in converted])
        scans.append((float(scan), points, covariances))
    return scans


def test_seed_covariances_survive_export_and_restore_exactly() -> None:
    """Cut right after the seed scan: the restored tracker starts the same tracks."""
    scans = _scans(8)
    whole, first = _radar_tracker(), _radar_tracker()
    uninterrupted = [json.dumps(whole.step(*s).to_plain(), sort_keys=True) for s in scans]
    first.step(*scans[0])
    saved = json.loads(json.dumps(first.export()))
    assert saved["version"] == 4 and len(saved["seed_covariances"]) == 2
    restored = LocalTracker.restore(first.config, saved)
    continued = [json.dumps(restored.step(*s).to_plain(), sort_keys=True) for s in scans[1:]]
    assert continued == uninterrupted[1:]
    assert json.dumps(restored.export(), sort_keys=True) == json.dumps(
        whole.export(), sort_keys=True
    )


def test_a_version_1_export_restores_its_seeds_with_the_bank_noise() -> None:
    """Version 1 kept no seed covariance: its seeds had been started with the bank's R."""
    scans = _scans(6)
    seeded_with_bank_noise = _radar_tracker()
    seeded_with_bank_noise.step(scans[0][0], scans[0][1], None)
    old = seeded_with_bank_noise.export()
    old["version"] = 1
    del old["seed_covariances"]
    restored = LocalTracker.restore(seeded_with_bank_noise.config, json.loads(json.dumps(old)))
    outputs = [
        [json.dumps(t.step(*s).to_plain(), sort_keys=True) for s in scans[1:]]
        for t in (restored, seeded_with_bank_noise)
    ]
    assert outputs[0] == outputs[1]
    assert any("confirmed" in line for line in outputs[0])
    with pytest.raises(TrackingError, match="version"):
        LocalTracker.restore(seeded_with_bank_noise.config, {**old, "version": 5})
