"""The estimate table against the padded reference fusion, and its kept results against a fresh table."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from core.arrays import FloatArray
from core.fusion.motion import MotionModel, StateLayout
from core.fusion.state import StateFusion, fuse_estimates
from core.fusion.table import EstimateTable

SENSORS = ["a", "b", "c"]
MOTION = MotionModel(StateLayout(dim=4, position=(0, 2), velocity=(1, 3)), q=0.5)


def random_spd(rng: np.random.Generator, dim: int = 4) -> FloatArray:
    root = rng.normal(size=(dim, dim))
    return root @ root.T + 0.1 * np.eye(dim)


def scene(seed: int, tracks: int = 30) -> tuple[FloatArray, FloatArray, FloatArray, np.ndarray]:
    """Estimates (tracks, sensors): states, covariances, times, present (every track has one)."""
    rng = np.random.default_rng(seed)
    states = rng.normal(size=(tracks, len(SENSORS), 4)) * 10
    covariances = np.array([[random_spd(rng) for _ in SENSORS] for _ in range(tracks)])
    times = rng.uniform(0.0, 2.0, size=(tracks, len(SENSORS)))
    present = rng.uniform(size=(tracks, len(SENSORS))) < 0.6
    present[~present.any(axis=1), 0] = True
    return states, covariances, times, present


def filled(
    states: FloatArray, covariances: FloatArray, times: FloatArray, present: np.ndarray, rule: str
) -> EstimateTable:
    table = EstimateTable(SENSORS, MOTION, StateFusion(rule))
    rows = table.add_rows(len(states))
    for slot, sensor in enumerate(SENSORS):
        chosen = rows[present[:, slot]]
        table.write(
            chosen,
            sensor,
            states[chosen, slot],
            covariances[chosen, slot],
            times[chosen, slot],
        )
    return table


def reference(
    states: FloatArray,
    covariances: FloatArray,
    times: FloatArray,
    present: np.ndarray,
    at: float,
    rule: str,
) -> tuple[FloatArray, FloatArray]:
    """Predict every present estimate with the motion model, pad, fuse with ``fuse_estimates``."""
    predicted = np.zeros_like(states)
    predicted_cov = np.tile(np.eye(4), (*present.shape, 1, 1))
    rows, slots = np.nonzero(present)
    predicted[rows, slots], predicted_cov[rows, slots] = MOTION.predict(
        states[rows, slots], covariances[rows, slots], at - times[rows, slots]
    )
    state, covariance, _ = fuse_estimates(predicted, predicted_cov, present, times, rule)
    return state, covariance


@pytest.mark.parametrize("rule", [rule.value for rule in StateFusion])
def test_fused_at_is_the_padded_fusion_of_the_predicted_estimates(rule: str) -> None:
    states, covariances, times, present = scene(1)
    table = filled(states, covariances, times, present, rule)
    rows = np.arange(len(states))
    state, covariance = table.fused_at(rows, 3.5)
    expected_state, expected_covariance = reference(states, covariances, times, present, 3.5, rule)
    assert_array_equal(state, expected_state)
    assert_array_equal(covariance, expected_covariance)
    # a subset, asked in another order, is the same rows
    subset = np.array([17, 3, 29, 0])
    sub_state, sub_covariance = table.fused_at(subset, 3.5)
    assert_array_equal(sub_state, expected_state[subset])
    assert_array_equal(sub_covariance, expected_covariance[subset])


Scene = tuple[FloatArray, FloatArray, FloatArray, np.ndarray]


def replace_estimates(
    table: EstimateTable, arrays: Scene, changed: np.ndarray, slot: int, time: float, seed: int
) -> None:
    """New estimates of ``changed`` from sensor ``SENSORS[slot]`` at ``time``: written to the
    table and to the scene's arrays (from which a fresh table is built to compare)."""
    rng = np.random.default_rng(seed)
    states, covariances, times, present = arrays
    new_states = rng.normal(size=(len(changed), 4))
    new_covariances = np.array([random_spd(rng) for _ in changed])
    table.write(changed, SENSORS[slot], new_states, new_covariances, time)
    states[changed, slot], covariances[changed, slot] = new_states, new_covariances
    times[changed, slot], present[changed, slot] = time, True


@pytest.mark.parametrize("rule", [rule.value for rule in StateFusion])
def test_replaced_estimates_fuse_to_the_bits_of_a_fresh_table(rule: str) -> None:
    """The kept predictions and inverses must not change a single bit (restore determinism)."""
    arrays = scene(2)
    table = filled(*arrays, rule)
    rows = np.arange(len(arrays[0]))
    table.fused_at(rows, 2.0)  # first look: every slot predicted and inverted at t = 2
    changed = np.array([1, 4, 5, 11, 20, 28])
    replace_estimates(table, arrays, changed, 1, 2.0, seed=3)  # a report at the fusion time
    kept_state, kept_covariance = table.fused_at(rows, 2.0)

    fresh_state, fresh_covariance = filled(*arrays, rule).fused_at(rows, 2.0)
    assert_array_equal(kept_state, fresh_state)
    assert_array_equal(kept_covariance, fresh_covariance)
    # rows fused alone give the same bits too
    alone_state, _ = filled(*arrays, rule).fused_at(changed[:2], 2.0)
    assert_array_equal(alone_state, fresh_state[changed[:2]])


def test_an_estimate_at_the_fusion_time_is_taken_as_it_is() -> None:
    """Δt = 0 is the identity: the state exactly, the covariance symmetrised (F = I, Q = 0)."""
    rng = np.random.default_rng(4)
    state = rng.normal(size=(1, 4))
    covariance = random_spd(rng)[None]
    covariance[0, 0, 1] += 1e-12  # not exactly symmetric, as a client may send
    table = EstimateTable(SENSORS, MOTION, StateFusion.COVARIANCE_INTERSECTION)
    row = table.add_rows(1)
    table.write(row, "c", state, covariance, 7.0)
    fused_state, fused_covariance = table.fused_at(row, 7.0)
    assert_array_equal(fused_state, state)
    assert_array_equal(fused_covariance[0], fused_covariance[0].T)
    assert_allclose(fused_covariance[0], (covariance[0] + covariance[0].T) / 2, rtol=0, atol=0)
    predicted, predicted_cov = MOTION.predict(state, covariance, np.zeros(1))
    assert_allclose(fused_state, predicted, rtol=1e-15)
    assert_allclose(fused_covariance, predicted_cov, rtol=1e-15)


def test_keep_renumbers_rows_and_growth_keeps_them() -> None:
    states, covariances, times, present = scene(5, tracks=5)
    table = filled(states, covariances, times, present, "covariance_intersection")
    before_state, before_covariance = table.fused_at(np.arange(5), 4.0)
    table.keep(np.array([4, 1, 2]))
    assert len(table) == 3
    after_state, after_covariance = table.fused_at(np.arange(3), 4.0)
    assert_array_equal(after_state, before_state[[4, 1, 2]])
    assert_array_equal(after_covariance, before_covariance[[4, 1, 2]])
    new_rows = table.add_rows(40)  # grows the arrays past their capacity
    assert_array_equal(new_rows, np.arange(3, 43))
    assert not table.present[new_rows].any()
    grown_state, _ = table.fused_at(np.arange(3), 4.0)
    assert_array_equal(grown_state, before_state[[4, 1, 2]])


@pytest.mark.parametrize("rule", [rule.value for rule in StateFusion])
def test_a_late_report_fuses_at_both_times_as_a_fresh_table(rule: str) -> None:
    """Looks at the fusion time and at a late report's time, a write, both times again."""
    arrays = scene(6)
    table = filled(*arrays, rule)
    rows = np.arange(len(arrays[0]))
    table.fused_at(rows, 5.0)  # the fusion time
    table.fused_at(rows, 4.0)  # a late report's time (kept too)
    replace_estimates(table, arrays, np.array([0, 2, 9, 15]), 0, 4.0, seed=7)
    at_fusion = table.fused_at(rows, 5.0)
    at_report = table.fused_at(rows, 4.0)
    table.fused_at(rows, 6.0)  # a third time: the least recently used one is dropped

    for at, result in ((5.0, at_fusion), (4.0, at_report)):
        fresh = filled(*arrays, rule).fused_at(rows, at)
        assert_array_equal(result[0], fresh[0])
        assert_array_equal(result[1], fresh[1])
    expected = reference(*arrays, 5.0, rule)
    assert_array_equal(table.fused_at(rows, 5.0)[0], expected[0])
