"""The tracker's defaults with the physics only (docs/algorithms.md §8): starts without velocity
knowledge, plain misses at a long revisit, the clutter density estimated from the data.

Every scene is drawn here with numpy (seeded): straight targets, P_D 0.9, Poisson clutter
uniform over a square; the expectations come from the scene itself (its targets, its
clutter count), never from an earlier output of the tracker.
"""

from __future__ import annotations

import numpy as np
import pytest

from core.lifecycle import LifeCycleConfig
from core.tracking.config import LocalTrackerConfig
from core.tracking.models import LinearMeasurementModel, ModelBank, constant_velocity
from core.tracking.tracker import LocalTracker

SIGMA = 5.0
SIDE = 4000.0
P_DETECT = 0.9


def _bank(interval: float = 1.0, q: float = 1.0) -> ModelBank:
    return ModelBank(
        (constant_velocity(interval, q, noise="continuous"),),
        LinearMeasurementModel(np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]]), SIGMA**2 * np.eye(2)),
        np.ones((1, 1)),
    )


def _scans(
    velocities: list[tuple[float, float]],
    clutter_per_scan: float,
    scans: int,
    seed: int,
    interval: float = 1.0,
    missed: frozenset[int] = frozenset(),
    p_detect: float = P_DETECT,
) -> tuple[list[np.ndarray], list[list[int]], int]:
    """Detections per scan (targets first, then clutter, shuffled), the row of each target's
    detection (−1: missed), and the number of clutter detections drawn."""
    rng = np.random.default_rng(seed)
    starts = rng.uniform(-SIDE / 4, SIDE / 4, size=(len(velocities), 2))
    out, rows, clutter_total = [], [], 0
    for k in range(scans):
        truth = starts + np.array(velocities) * k * interval
        seen = rng.random(len(velocities)) < p_detect
        if k in missed:
            seen[:] = False
        targets = truth[seen] + rng.normal(0.0, SIGMA, size=(int(seen.sum()), 2))
        clutter = rng.uniform(-SIDE / 2, SIDE / 2, size=(rng.poisson(clutter_per_scan), 2))
        clutter_total += len(clutter)
        z = np.vstack([targets, clutter])
        order = rng.permutation(len(z))
        z = z[order]
        where = np.full(len(velocities), -1)
        where[np.flatnonzero(seen)] = np.argsort(order)[: int(seen.sum())]
        out.append(z)
        rows.append(where.tolist())
    return out, rows, clutter_total


def _first_confirmed(
    tracker: LocalTracker, scans: list[np.ndarray], rows: list[list[int]]
) -> list[int]:
    """Per target, the first scan at which its detection went to a confirmed track."""
    first = [-1] * len(rows[0])
    for k, z in enumerate(scans):
        step = tracker.step(float(k), z)
        confirmed = {t.id for t in step.tracks if t.status.value == "confirmed"}
        for target, row in enumerate(rows[k]):
            if first[target] < 0 and row >= 0 and step.assignment[row] in confirmed:
                first[target] = k
    return first


@pytest.mark.parametrize("speed", [1.0, 30.0, 300.0])
def test_a_target_is_confirmed_without_a_velocity_prior_at_most_two_scans_late(
    speed: float,
) -> None:
    """σ 5 m, 1 s scans, ten false alarms per scan over 4 km × 4 km (given): with no velocity
    prior a target of 1, 30 or 300 m/s is confirmed at most two scans after the tracker
    given its true speed as the prior (σ_v = speed)."""
    velocities = [(speed, 0.0), (0.0, -speed), (-0.6 * speed, 0.8 * speed)]
    scans, rows, _ = _scans(velocities, 10.0, 12, seed=int(speed))
    life = LifeCycleConfig(false_target_density=10.0 / SIDE**2, new_target_density=1e-7)
    unknown = LocalTrackerConfig(bank=_bank(), life_cycle=life, classification=None)
    known = LocalTrackerConfig(
        bank=_bank(), life_cycle=life, classification=None, initial_velocity_std=speed
    )
    without = _first_confirmed(LocalTracker(unknown), scans, rows)
    given = _first_confirmed(LocalTracker(known), scans, rows)
    assert min(without) >= 0 and min(given) >= 0, (without, given)
    assert all(late <= early + 2 for late, early in zip(without, given, strict=True)), (
        without,
        given,
    )
    assert max(without) <= 5  # a third detection at P_D 0.9, and a miss or two


def test_a_5_s_track_survives_two_missed_scans() -> None:
    """5 s scans, a 250 m/s target, clutter density left to the estimate, the tracker's
    default P_D 0.9: confirmed, then two scans without its detection (clutter only), then
    seen again: one track all along."""
    missed = frozenset({8, 9})
    scans, rows, _ = _scans(
        [(250.0, 0.0)], 5.0, 14, seed=5, interval=5.0, missed=missed, p_detect=1.0
    )
    tracker = LocalTracker(
        LocalTrackerConfig(bank=_bank(5.0, 10.0), time_interval=5.0, classification=None)
    )
    owners = []
    for k, z in enumerate(scans):
        step = tracker.step(5.0 * k, z)
        if k in missed:
            statuses = {t.id: t.status.value for t in step.tracks}
            assert statuses[owners[-1]] == "coasting", (k, statuses)
        else:
            owner = step.assignment[rows[k][0]]
            assert owner is not None
            status = step.track(owner).status.value
            owners.append(owner if status == "confirmed" else "")
    # confirmed by its 3rd detection, then one id through the two misses to the end
    assert all(owners[2:]) and len(set(owners[2:])) == 1, owners


def test_the_clutter_estimate_is_near_the_scene_s_own_count() -> None:
    """Twenty false alarms per scan over 4 km × 4 km and five targets, no density given: after
    60 scans the estimate is within 15 % of the clutter drawn per m² per scan (counted from
    the scene, not from the tracker)."""
    velocities = [(20.0, 5.0), (-15.0, 10.0), (0.0, -25.0), (12.0, 12.0), (-8.0, -3.0)]
    scans, _, drawn = _scans(velocities, 20.0, 60, seed=3)
    tracker = LocalTracker(LocalTrackerConfig(bank=_bank(), classification=None))
    for k, z in enumerate(scans):
        step = tracker.step(float(k), z)
    truth = drawn / len(scans) / SIDE**2
    assert step.clutter_density == pytest.approx(truth, rel=0.15)
    assert tracker.clutter_density("sensor") == pytest.approx(truth, rel=0.15)
    tally = tracker.tallies["sensor"]
    assert tally.detections == sum(len(z) for z in scans)
    assert tally.confirmed >= len(velocities)
