"""``bench/manoeuvre.py`` on a reduced run: its flight is the 3 g coordinated turn it names,
Singer's model follows the turn better than constant velocity, and our Kalman filter with
Singer's model is Stone Soup's (its own ``Singer``, predictor and updater) on the same
measurements. No timing (the bench prints it)."""

from __future__ import annotations

import numpy as np

from core.models.singer import GRAVITY, Singer
from core.models.transition import ConstantVelocity
from tests.bench_scripts import load_bench


def test_the_flight_is_a_3g_turn_between_straight_legs() -> None:
    bench = load_bench("manoeuvre")
    truth = bench.flight()
    speeds = np.linalg.norm(truth.velocities, axis=1)
    np.testing.assert_allclose(speeds, bench.SPEED, rtol=1e-12)
    # centripetal acceleration of the turn's circle, from three positions on it
    inside = np.flatnonzero((truth.times > truth.turn[0]) & (truth.times < truth.turn[1]))[:3]
    a, b, c = truth.positions[inside]
    area = 0.5 * abs((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))
    radius = np.linalg.norm(b - a) * np.linalg.norm(c - b) * np.linalg.norm(c - a) / (4 * area)
    assert abs(bench.SPEED**2 / radius - 3.0 * GRAVITY) < 1e-6 * GRAVITY
    # and it comes back: the last leg flies the other way
    np.testing.assert_allclose(truth.velocities[-1], [-bench.SPEED, 0.0], atol=1e-9)


def test_singer_follows_the_turn_better_than_constant_velocity_and_is_stone_soups() -> None:
    bench = load_bench("manoeuvre")
    truth = bench.flight()
    rng = np.random.default_rng(2)
    runs = [truth.positions + rng.normal(0.0, bench.SIGMA, truth.positions.shape) for _ in range(5)]
    turning = (truth.times >= truth.turn[0]) & (truth.times <= truth.turn[1] + bench.AFTER_TURN)

    def turn_rmse(estimates: list[np.ndarray]) -> float:
        errors = [np.linalg.norm(e - truth.positions, axis=1)[turning] for e in estimates]
        return float(np.sqrt(np.mean(np.concatenate(errors) ** 2)))

    singer = [bench.run_ours(Singer(), bench.SINGER_LAYOUT, truth, z) for z in runs]
    aircraft_cv = ConstantVelocity(342.1728)  # the default q derived from the aircraft preset
    cv = [bench.run_ours(aircraft_cv, bench.CV_LAYOUT, truth, z) for z in runs]
    assert turn_rmse(singer) < turn_rmse(cv) - 1.0
    stone_soup = bench.run_stone_soup(Singer(), truth, runs[0])
    np.testing.assert_allclose(singer[0], stone_soup, atol=1e-8, rtol=0.0)
