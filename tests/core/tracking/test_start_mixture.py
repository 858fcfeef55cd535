"""A single-point start's second detection without a velocity prior: its state is the
posterior under the scale mixture of the velocity prior that scores it (docs/algorithms.md
§8.3), checked against an independent computation of the mixture, component by component."""

from __future__ import annotations

import numpy as np
from scipy.stats import multivariate_normal

from core.lifecycle import LifeCycleConfig
from core.tracking.associate import VELOCITY_SCALES
from core.tracking.config import UNKNOWN_VELOCITY_STD, LocalTrackerConfig
from core.tracking.models import LinearMeasurementModel, ModelBank, constant_velocity
from core.tracking.tracker import LocalTracker

SIGMA = 1.5
Q = 0.05
DT = 1.0 / 3.0


def tracker() -> LocalTracker:
    bank = ModelBank(
        models=(constant_velocity(1.0, Q, axes=2, noise="continuous"),),
        measurement=LinearMeasurementModel.position(SIGMA**2, 4),
        mode_transition=np.ones((1, 1)),
    )
    return LocalTracker(
        LocalTrackerConfig(
            bank=bank,
            life_cycle=LifeCycleConfig(false_target_density=1e-4, new_target_density=1e-5),
            fields_of_view={"s": None},
            classification=None,
        )
    )


def expected(first: np.ndarray, second: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mixture posterior by hand: the start x = [z₀, 0], P = diag(R, σ_v²) per axis
    ([x, ẋ, y, ẏ]), predicted over Δt (F, continuous white-noise Q); per scale s_k the
    velocity prior's part of P, C P_vv⁻¹ Cᵀ (C = P's velocity columns), scaled by s_k²;
    a Kalman update each, weighted by w_k N(z₁; H x, S_k); then the mixture's mean and
    covariance (its spread included)."""
    f1 = np.array([[1.0, DT], [0.0, 1.0]])
    q1 = Q * np.array([[DT**3 / 3.0, DT**2 / 2.0], [DT**2 / 2.0, DT]])
    f, q = np.kron(np.eye(2), f1), np.kron(np.eye(2), q1)
    h = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
    r = SIGMA**2 * np.eye(2)
    x0 = np.array([first[0], 0.0, first[1], 0.0])
    p0 = np.diag([SIGMA**2, UNKNOWN_VELOCITY_STD**2, SIGMA**2, UNKNOWN_VELOCITY_STD**2])
    x, p = f @ x0, f @ p0 @ f.T + q
    velocity = [1, 3]
    c = p[:, velocity]
    prior_part = c @ np.linalg.inv(p[np.ix_(velocity, velocity)]) @ c.T
    means, covariances, weights = [], [], []
    for scale, weight in VELOCITY_SCALES:
        p_k = p - (1.0 - scale**2) * prior_part
        s_k = h @ p_k @ h.T + r
        gain = p_k @ h.T @ np.linalg.inv(s_k)
        means.append(x + gain @ (second - h @ x))
        i_kh = np.eye(4) - gain @ h
        covariances.append(i_kh @ p_k @ i_kh.T + gain @ r @ gain.T)
        weights.append(weight * multivariate_normal(h @ x, s_k).pdf(second))
    w = np.array(weights) / sum(weights)
    mean = sum(wk * m for wk, m in zip(w, means, strict=True))
    covariance = sum(
        wk * (pk + np.outer(m - mean, m - mean))
        for wk, m, pk in zip(w, means, covariances, strict=True)
    )
    return np.asarray(mean), np.asarray(covariance)


def test_a_starts_second_detection_updates_it_under_the_velocity_prior_mixture() -> None:
    """Pairs 1/3 s apart: a slow one (0.4 m, the 1 and 10 m/s components share it) keeps a
    velocity near 0 with a spread that covers both — not the two-point difference of two
    σ 1.5 m detections (1.2 m/s); a fast one (20 m, 60 m/s: the wide component alone) keeps
    the two-point velocity, as before."""
    for displacement in (np.array([0.4, 0.0]), np.array([20.0, 0.0])):
        first = np.array([100.0, 200.0])
        second = first + displacement
        local = tracker()
        local.step(0.0, [first])
        step = local.step(DT, [second])
        # the second detection also starts a track of its own (§8.3): the pair's has two hits
        (track,) = [track for track in step.tracks if track.hits == 2]
        mean, covariance = expected(first, second)
        np.testing.assert_allclose(track.state, mean, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(track.covariance, covariance, rtol=1e-9, atol=1e-9)
    slow = expected(np.array([100.0, 200.0]), np.array([100.4, 200.0]))[0]
    assert abs(slow[1]) < 0.5 * 0.4 / DT  # shrunk well below the two-point 1.2 m/s
    fast = expected(np.array([100.0, 200.0]), np.array([120.0, 200.0]))[0]
    assert abs(fast[1] - 20.0 / DT) < 1.0
