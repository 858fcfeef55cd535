"""The engine's fused state on [T2T] scenario 1 (``t2t-four``), against numpy (docs/algorithms.md §6.4).

Each two-source fused track is recomputed from the sensors' latest reported
estimates alone: both predicted to the step time with the CV model of §7.1
written out here, then covariance intersection by a scan of ω (and scipy's
Brent search), or the information sum ``P⁻¹ = P₁⁻¹ + P₂⁻¹``.

Why the default trail zig-zags when both sensors report the same covariance
P: the older estimate, predicted 1 ms forward, has P + Q(Δt) ⪰ P, so the
trace-minimising ω gives it no weight and the fused track *is* the newest
sensor's estimate, with its covariance (CI cannot shrink nested covariances:
it must allow for fully correlated errors). That is CI as specified, checked
below; ``independent`` averages and halves P.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from numpy.testing import assert_allclose

from core.fusion.engine import SessionEngine
from core.fusion.state import StateFusion
from core.simulation.tracklists import t2t_four

from .engine_helpers import make_config, to_report
from .test_state_fusion import brute_force_weight

Q_DENSITY = 0.5  # make_config's motion density, as in the t2t-four session of `simulate`


def predicted(state: np.ndarray, covariance: np.ndarray, dt: float) -> tuple[np.ndarray, ...]:
    """x ← F x, P ← F P Fᵀ + Q, per axis F = [[1, Δt], [0, 1]], Q = q [[Δt³/3, Δt²/2], [Δt²/2, Δt]]."""
    axis_f = np.array([[1.0, dt], [0.0, 1.0]])
    axis_q = Q_DENSITY * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
    f, q = np.zeros((4, 4)), np.zeros((4, 4))
    for block in ([0, 1], [2, 3]):
        f[np.ix_(block, block)], q[np.ix_(block, block)] = axis_f, axis_q
    return f @ state, f @ covariance @ f.T + q


def information_form(estimates, weights) -> tuple[np.ndarray, np.ndarray]:
    """P⁻¹ = Σ ω_i P_i⁻¹, P⁻¹ x = Σ ω_i P_i⁻¹ x_i."""
    information = sum(w * np.linalg.inv(p) for (_, p), w in zip(estimates, weights, strict=True))
    vector = sum(w * np.linalg.solve(p, x) for (x, p), w in zip(estimates, weights, strict=True))
    covariance = np.linalg.inv(information)
    return covariance @ vector, covariance


@pytest.mark.parametrize("elongation", [1.0, 3.0])
@pytest.mark.parametrize("rule", [StateFusion.COVARIANCE_INTERSECTION, StateFusion.INDEPENDENT])
def test_two_source_tracks_are_the_fusion_of_the_sensors_latest_estimates(
    rule: StateFusion, elongation: float
) -> None:
    scenario = t2t_four(seed=0, n_steps=4, elongation=elongation)
    config = dataclasses.replace(make_config(scenario.sensors), state_fusion=rule)
    assert make_config(scenario.sensors).state_fusion is StateFusion.COVARIANCE_INTERSECTION
    engine = SessionEngine(config)
    latest: dict[tuple[str, str], tuple[float, np.ndarray, np.ndarray]] = {}
    checked = 0
    for report in scenario.reports:
        step = engine.apply(to_report(report))
        for k, track_id in enumerate(report.track_ids):
            latest[(report.sensor, track_id)] = (
                report.time,
                report.states[k],
                report.covariances[k],
            )
        for track in step.tracks:
            if len(track.sources) != 2:
                continue
            inputs = [latest[(source.sensor, source.track)] for source in track.sources]
            estimates = [predicted(x, p, report.time - time) for time, x, p in inputs]
            if rule is StateFusion.INDEPENDENT:
                state, covariance = information_form(estimates, (1.0, 1.0))
            else:
                omega, _ = brute_force_weight(estimates[0][1], estimates[1][1])
                state, covariance = information_form(estimates, (omega, 1.0 - omega))
            assert_allclose(track.state, state, rtol=1e-6, atol=1e-6)
            assert_allclose(track.covariance, covariance, rtol=1e-6, atol=1e-9)
            newest = max(range(2), key=lambda i: inputs[i][0])
            if rule is StateFusion.INDEPENDENT:  # below both inputs (half of P 1 ms apart)
                assert np.trace(covariance) < min(np.trace(p) for _, p in estimates)
            elif elongation == 1.0:  # nested covariances: the newest estimate, as reported
                assert omega == pytest.approx(1.0 - newest, abs=1e-9)
                assert_allclose(track.state, inputs[newest][1], rtol=0.0, atol=1e-9)
                assert_allclose(track.covariance, inputs[newest][2], rtol=0.0, atol=1e-9)
            else:  # crossed ellipses: CI shrinks the trace below both inputs
                assert np.trace(covariance) < 0.9 * min(np.trace(p) for _, p in estimates)
            checked += 1
    assert checked == 4 * (2 * 4 - 1)  # every track, from the second report on
