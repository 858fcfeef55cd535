"""The births shared by the sensors of a central tracker, per coverage cell
(docs/algorithms.md §8.9), on reduced scenes whose scores are worked by hand.

Two sensors, ``a`` (P_D 0.9) covering x ∈ [0, 2000] m and ``b`` (P_D 0.7) covering
x ∈ [1000, 3000] m (y ∈ [0, 2000] m for both): the cells are {a} (x < 1000), {a, b}
and {b} (x > 2000). β_NT = 10⁻⁶ per m² per ΔT = 1 s, β_FT = 10⁻⁵ per m² for both, a
velocity prior of 1 m/s (the plain Gaussian start, §8.3) and one constant-velocity model.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.geometry import PolygonView
from core.lifecycle import LifeCycleConfig
from core.tracking.config import LocalTrackerConfig, SensorPhysics
from core.tracking.models import LinearMeasurementModel, ModelBank, constant_velocity
from core.tracking.track import TrackerStep
from core.tracking.tracker import LocalTracker

P_A, P_B = 0.9, 0.7
BIRTH, CLUTTER = 1e-6, 1e-5
SIGMA_A, SIGMA_B = 2.0, 3.0
Q = 0.05
"""m²/s³, the continuous white-noise acceleration density of the one model."""
VELOCITY_STD = 1.0
L0 = math.log(BIRTH / CLUTTER)
"""A start's score with all of β_NT: ln(β_NT / β_FT)."""


def box(x0: float, x1: float) -> PolygonView:
    return PolygonView(((x0, 0.0), (x1, 0.0), (x1, 2000.0), (x0, 2000.0)))


B_VIEW = box(1000.0, 3000.0)


def central(b_view: PolygonView | None = B_VIEW) -> LocalTracker:
    """The central tracker of ``a`` and ``b`` (module docstring; ``b_view`` None: b's
    coverage not given)."""
    bank = ModelBank(
        models=(constant_velocity(1.0, Q, axes=2, noise="continuous"),),
        measurement=LinearMeasurementModel.position(SIGMA_B**2, 4),
        mode_transition=np.ones((1, 1)),
    )
    return LocalTracker(
        LocalTrackerConfig(
            bank=bank,
            time_interval=1.0,
            life_cycle=LifeCycleConfig(new_target_density=BIRTH),
            initial_velocity_std=VELOCITY_STD,
            sensor_physics={
                "a": SensorPhysics(P_A, CLUTTER, ((SIGMA_A**2, 0.0), (0.0, SIGMA_A**2))),
                "b": SensorPhysics(P_B, CLUTTER, None),
            },
            fields_of_view={"a": box(0.0, 2000.0), "b": b_view},
            classification=None,
            id_prefix="C",
        )
    )


def started(step: TrackerStep) -> list[float]:
    """The score of the track each detection of the scan started, in detection order."""
    scores = []
    for track_id in step.assignment:
        assert track_id is not None
        track = step.track(track_id)
        assert track.hits == 1  # a start of its own, no other track's hit
        scores.append(track.score)
    return scores


def test_each_cell_starts_its_tracks_with_the_births_no_scan_has_detected_there() -> None:
    """The cells' intensities by hand (units of β_NT; births 1 per ΔT, a scan of a sensor
    covering the cell detects P_D of it and leaves 1 − P_D):

    - t = 0, ``a``: cells {a} and {a, b} are new: 1/P_a each, ``a`` detects P_a · 1/P_a = 1;
    - t = 0.5, ``b``: {a, b} holds (1 − P_a)/P_a + 0.5, ``b`` detects P_b of it; {b} is new: 1;
    - t = 1, ``a``: {a} holds (1 − P_a)/P_a + 1 = 1/P_a (a sensor alone, every ΔT: 1 again);
      {a, b} holds (1 − P_b)((1 − P_a)/P_a + 0.5) + 0.5, ``a`` detects P_a of it.

    Every detection is hundreds of metres from the others: each starts its own track, whose
    score at its start is ln(share β_NT / β_FT)."""
    tracker = central()
    first = tracker.step(0.0, [[500.0, 500.0], [1500.0, 500.0]], sensor="a")
    second = tracker.step(0.5, [[1500.0, 1500.0], [2500.0, 500.0]], sensor="b")
    third = tracker.step(1.0, [[500.0, 1500.0], [1200.0, 1000.0]], sensor="a")
    shared = (1.0 - P_A) / P_A + 0.5
    expected = [
        [L0, L0],
        [L0 + math.log(P_B * shared), L0],
        [L0, L0 + math.log(P_A * ((1.0 - P_B) * shared + 0.5))],
    ]
    for step, scores in zip((first, second, third), expected, strict=True):
        assert started(step) == pytest.approx(scores, abs=1e-12)


def test_a_sensor_of_no_given_coverage_keeps_all_of_the_births() -> None:
    """``b`` without a field of view: where it looks is unknown, so its scans neither take
    a share of the births nor thin anyone's (the papers' baseline of sensors taken to see
    everywhere, [HZ] Fig 6 (a)): every start scores ln(β_NT / β_FT), a sensor alone's."""
    tracker = central(b_view=None)
    scores = []
    for time, sensor in ((0.0, "a"), (0.5, "b"), (1.0, "a"), (1.5, "b")):
        step = tracker.step(time, [[1500.0, 400.0 + 1000.0 * time]], sensor=sensor)
        scores += started(step)
    assert scores == pytest.approx([L0] * 4, abs=1e-12)


@pytest.mark.parametrize("offset", [0.0, 11.0])
def test_two_sensors_each_detecting_a_target_once_confirm_it(offset: float) -> None:
    """A target at rest at (1500, 1000), in both views, detected by ``a`` at t = 0 and by
    ``b`` at t = 1 (each once; b's detection ``offset`` m off in x), b's scan at t = 0.5
    empty. Its score by hand ([MTT] §4.3, eq 16): the start's L₀ = ln(β_NT / β_FT) (the
    cell's first detection), b's miss ln(1 − P_b), b's hit
    ΔL = ln(P_b / (2π β_FT √|S|)) − D/2 with D = offset² / S and, per axis,
    S = σ_a² + σ_v² Δt² + q Δt³/3 + σ_b² (the start's covariance diag(σ_a², σ_v²)
    predicted over Δt = 1 s with the continuous white-noise Q, plus R_b). The defaults
    confirm at the second hit with L ≥ 0 (``min_points`` 2, the SPRT's P(target) ≥ ½):
    at offset 0 the sum is 3.17, confirmed (its score then clamped at the ceiling 0); at
    11 m it is −1.14, still tentative with exactly that score."""
    tracker = central()
    tracker.step(0.0, [[1500.0, 1000.0]], sensor="a")
    tracker.step(0.5, np.zeros((0, 2)), sensor="b")
    step = tracker.step(1.0, [[1500.0 + offset, 1000.0]], sensor="b")
    s = SIGMA_A**2 + VELOCITY_STD**2 + Q / 3.0 + SIGMA_B**2
    hit = math.log(P_B / (2.0 * math.pi * CLUTTER * s)) - 0.5 * offset**2 / s
    expected = L0 + math.log(1.0 - P_B) + hit
    # b's detection also starts a track of its own (§8.3); the target's is the one of two hits
    (track,) = [track for track in step.tracks if track.hits == 2]
    if expected >= 0.0:
        assert track.status.value == "confirmed"
        assert track.score == 0.0  # the default score ceiling
    else:
        assert track.status.value == "tentative"
        assert track.score == pytest.approx(expected, abs=1e-9)


def test_a_sensors_silence_outside_its_view_does_not_count() -> None:
    """A tentative track at x = 500 (only ``a`` covers it) and one at x = 1500 (both do),
    each started by ``a`` at t = 0; ``b`` scans at t = 0.5 and detects nothing: the first
    keeps its start score, the second loses ln(1 − P_b) ([MTT] §4.3: a miss counts only
    where the scanning sensor could see, §8.9). And b's scan does not thin the births of
    cell {a}: ``a``'s next start there at t = 1 scores ln(β_NT / β_FT) (one sensor every
    ΔT), where b's silence would have taken ln(1 − P_b) off it."""
    tracker = central()
    tracker.step(0.0, [[500.0, 500.0], [1500.0, 500.0]], sensor="a")
    step = tracker.step(0.5, np.zeros((0, 2)), sensor="b")
    scores = [track.score for track in step.tracks]
    assert scores == pytest.approx([L0, L0 + math.log(1.0 - P_B)], abs=1e-12)
    later = tracker.step(1.0, [[500.0, 1500.0]], sensor="a")
    assert started(later) == pytest.approx([L0], abs=1e-12)


def test_the_births_export_and_restore_exactly() -> None:
    """The cells' intensities ride with the export (``births``): a tracker restored from
    it continues as the one exported, bit for bit; an export without them (an older
    one) restores with none."""
    scans = [
        (0.0, "a", [[500.0, 500.0], [1500.0, 500.0]]),
        (0.5, "b", [[1500.0, 1500.0], [2500.0, 500.0]]),
        (1.0, "a", [[500.0, 1500.0], [1200.0, 1000.0]]),
        (1.5, "b", [[2200.0, 1200.0], [1700.0, 300.0]]),
    ]
    whole = central()
    for time, sensor, z in scans:
        whole.step(time, z, sensor=sensor)
    half = central()
    for time, sensor, z in scans[:2]:
        half.step(time, z, sensor=sensor)
    plain = half.export()
    assert sorted(cell for cell, _ in plain["births"]) == [["a"], ["a", "b"], ["b"]]
    restored = LocalTracker.restore(half.config, plain)
    for time, sensor, z in scans[2:]:
        restored.step(time, z, sensor=sensor)
    assert restored.export() == whole.export()
    del plain["births"]
    assert LocalTracker.restore(half.config, plain).export()["births"] == []
