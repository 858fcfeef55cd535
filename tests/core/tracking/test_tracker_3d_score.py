"""A 3-D target seen with per-detection covariances: confirmed, kept, scored by the SPRT.

Densities are per m^q: the 2-D default 1e-6 m⁻² read as 1e-6 m⁻³ is above the peak
likelihood of a σ = 60 m target, so no 3-D track could confirm; at the 3-D default
(:func:`~core.lifecycle.default_density`, 1e-9 m⁻³) every increment of the score is the
[MTT] §4.3 one, recomputed here with scipy's Gaussian log-density and a Kalman filter
written out by hand.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from core.lifecycle import LifeCycleConfig, default_density
from core.tracking.config import LocalTrackerConfig
from core.tracking.models import LinearMeasurementModel, ModelBank, constant_velocity
from core.tracking.tracker import LocalTracker

SIGMA = 60.0
Q_DENSITY = 1.0
VELOCITY = np.array([-200.0, 50.0, 10.0])
START = np.array([20_000.0, 1_000.0, 5_000.0])
CONFIRM = LifeCycleConfig().confirm_threshold


def _tracker(density: float, margin: float | None = 0.0) -> LocalTracker:
    """The paper profile's tracker, the score ceiling at confirm + ``margin`` (None: raw)."""
    # the bank of app.sessions.translate.local_tracker_config for a session without preset
    bank = ModelBank(
        models=(constant_velocity(1.0, Q_DENSITY, axes=3, noise="continuous"),),
        measurement=LinearMeasurementModel.position(1.0, 6),
        mode_transition=np.ones((1, 1)),
    )
    return LocalTracker(
        LocalTrackerConfig.paper(
            time_interval=1.0,
            bank=bank,
            measurement_noise=tuple(tuple(row) for row in (SIGMA**2 * np.eye(3)).tolist()),
            life_cycle=LifeCycleConfig.paper(
                3,
                false_target_density=density,
                new_target_density=density,
                score_ceiling=None if margin is None else CONFIRM + margin,
            ),
        )
    )


def _own_covariance(scan: int) -> np.ndarray:
    """A full, changing R_i (a rotated 40 × 60 × 80 m ellipsoid)."""
    angle = 0.3 * scan
    turn = np.array(
        [
            [math.cos(angle), -math.sin(angle), 0.0],
            [math.sin(angle), math.cos(angle), 0.0],
            [0, 0, 1],
        ]
    )
    return turn @ np.diag([40.0**2, 60.0**2, 80.0**2]) @ turn.T


def _expected_scores(scans: int, confirm: float) -> list[float]:
    """The score after each scan from scan 1, by hand: two-point start, then KF hits."""
    p_detect, beta = 0.9, default_density(3)
    r0, r1 = _own_covariance(0), _own_covariance(1)
    z = [START + VELOCITY * k for k in range(scans)]
    # two-point start: L0 + the hit of z1 − z0 under R0 + R1 + σ_v² ΔT² I ([MTT] §4.3),
    # each detection with its own covariance
    pair = r0 + r1 + 300.0**2 * np.eye(3)
    score = math.log(p_detect / beta) + multivariate_normal(np.zeros(3), pair).logpdf(z[1] - z[0])
    scores = [min(score, confirm)]
    # state [x, ẋ, y, ẏ, z, ż]: position z1 (cov R1), velocity difference
    # ((R0 + R1)/ΔT², cross R1/ΔT)
    x = np.zeros(6)
    p = np.zeros((6, 6))
    pos, vel = [0, 2, 4], [1, 3, 5]
    x[pos], x[vel] = z[1], z[1] - z[0]
    p[np.ix_(pos, pos)] = r1
    p[np.ix_(vel, vel)] = r0 + r1
    p[np.ix_(pos, vel)] = r1
    p[np.ix_(vel, pos)] = r1
    f_axis = np.array([[1.0, 1.0], [0.0, 1.0]])
    q_axis = Q_DENSITY * np.array([[1.0 / 3.0, 0.5], [0.5, 1.0]])
    f, q = np.kron(np.eye(3), f_axis), np.kron(np.eye(3), q_axis)
    h = np.zeros((3, 6))
    h[[0, 1, 2], pos] = 1.0
    for k in range(2, scans):
        x, p = f @ x, f @ p @ f.T + q
        r = _own_covariance(k)
        s = h @ p @ h.T + r
        hit = math.log(p_detect / beta) + multivariate_normal(h @ x, s).logpdf(z[k])
        score = min(scores[-1] + hit, confirm)
        scores.append(score)
        gain = p @ h.T @ np.linalg.inv(s)
        x = x + gain @ (z[k] - h @ x)
        p = (np.eye(6) - gain @ h) @ p
    return scores


@pytest.mark.parametrize("margin", [0.0, None])
def test_a_3d_track_with_its_detections_covariances_is_confirmed_kept_and_scored(
    margin: float | None,
) -> None:
    """With the default ceiling, and with the raw SPRT (every hit's ΔL checked)."""
    tracker = _tracker(default_density(3), margin)
    confirm = tracker.config.score.confirm_threshold if margin == 0.0 else math.inf
    expected = _expected_scores(20, confirm)
    statuses, scores, ids = [], [], set()
    for scan in range(20):
        step = tracker.step(
            float(scan), (START + VELOCITY * scan)[None], _own_covariance(scan)[None]
        )
        if scan == 0:
            assert step.tracks == ()
            continue
        (track,) = step.tracks
        statuses.append(track.status.value)
        scores.append(track.score)
        ids.add(track.id)
    assert ids == {"L1"}
    assert statuses.index("confirmed") <= 2  # confirmed by scan 3 (the start is scan 1)
    assert set(statuses[statuses.index("confirmed") :]) == {"confirmed"}
    np.testing.assert_allclose(scores, expected, rtol=0, atol=1e-6)
    # every hit raised the score until it reached the ceiling
    assert all(b > a for a, b in itertools.pairwise(scores) if a < confirm)


def test_at_one_false_alarm_per_cubic_metre_millionth_no_3d_track_confirms() -> None:
    """1e-6 m⁻³ (the 2-D default taken for 3-D): the SPRT says clutter, rightly."""
    tracker = _tracker(1e-6)
    for scan in range(10):
        step = tracker.step(
            float(scan), (START + VELOCITY * scan)[None], _own_covariance(scan)[None]
        )
        assert all(track.status.value != "confirmed" for track in step.tracks)
