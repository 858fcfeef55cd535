"""The fused tracks' motion model against F and Q written out entry by entry (BLK §6.2.2)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from core.errors import InvalidInput
from core.fusion.motion import MotionKind, MotionModel, StateLayout

Q_DENSITY = 0.7


def reference(
    layout: StateLayout, kind: MotionKind, dt: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """F = [[1, Δt], [0, 1]] and Q = q [[|Δt|³/3, |Δt|²/2], [|Δt|²/2, |Δt|]] per axis."""
    d = layout.dim
    transition = np.broadcast_to(np.eye(d), (*dt.shape, d, d)).copy()
    noise = np.zeros((*dt.shape, d, d))
    span = np.abs(dt)
    for axis, p in enumerate(layout.position):
        if kind is MotionKind.CONSTANT_VELOCITY:
            v = layout.velocity[axis]
            transition[..., p, v] = dt
            noise[..., p, p] = Q_DENSITY * span**3 / 3
            noise[..., p, v] = noise[..., v, p] = Q_DENSITY * span**2 / 2
            noise[..., v, v] = Q_DENSITY * span
        else:
            noise[..., p, p] = Q_DENSITY * span
    return transition, noise


@pytest.mark.parametrize(
    ("kind", "layout"),
    [
        (MotionKind.CONSTANT_VELOCITY, StateLayout(5, (0, 2), (1, 3))),  # one passive component
        (MotionKind.CONSTANT_VELOCITY, StateLayout(4, (0, 1), (2, 3))),
        (MotionKind.CONSTANT_POSITION, StateLayout(3, (0, 2))),
    ],
)
def test_prediction_is_f_p_ft_plus_q(kind: MotionKind, layout: StateLayout) -> None:
    rng = np.random.default_rng(7)
    model = MotionModel(layout, kind, q=Q_DENSITY)
    states = rng.normal(size=(6, 3, layout.dim))
    factors = rng.normal(size=(6, 3, layout.dim, layout.dim))
    covariances = factors @ np.swapaxes(factors, -1, -2)
    states_before, covariances_before = states.copy(), covariances.copy()
    # Δt per (track, slot), per track (one estimate each) and one for all; backwards too
    cases = [
        (states, covariances, rng.normal(size=(6, 3)) * 5.0),
        (states[:, 0], covariances[:, 0], rng.normal(size=6) * 5.0),
        (states[:, 0], covariances[:, 0], np.float64(-2.5)),
    ]
    for batch_states, batch_covariances, dt in cases:
        transition, noise = reference(layout, kind, np.asarray(dt))
        predicted, predicted_covariance = model.predict(batch_states, batch_covariances, dt)
        expected_states = np.einsum("...ij,...j->...i", transition, batch_states)
        assert_allclose(predicted, expected_states, atol=1e-12)
        expected = transition @ batch_covariances @ np.swapaxes(transition, -1, -2) + noise
        assert_allclose(predicted_covariance, expected, rtol=1e-12, atol=1e-12)
        assert_allclose(model.matrices(dt)[0], transition)
        assert_allclose(model.matrices(dt)[1], noise, atol=1e-15)
    np.testing.assert_array_equal(states, states_before)  # inputs untouched
    np.testing.assert_array_equal(covariances, covariances_before)


def test_overflowing_prediction_names_the_time() -> None:
    model = MotionModel(StateLayout(4, (0, 2), (1, 3)), q=1.0)
    with pytest.raises(InvalidInput, match=r"^time: predicting"):
        model.predict(np.zeros((1, 4)), np.eye(4)[None], np.array([1e200]))
