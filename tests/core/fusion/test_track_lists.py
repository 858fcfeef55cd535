"""Sources that post track lists (issue 23): fused ids that survive a source's restart."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.fusion.config import SensorSpec
from core.fusion.engine import SessionEngine
from core.fusion.reports import ReportedTrack, TrackReport

from .engine_helpers import make_config

TARGETS = np.array([[0.0, 1.0, 0.0, 0.0], [12.0, 1.0, 0.0, 0.0], [24.0, 1.0, 0.0, 0.0]])
"""Three targets 12 m apart in a row, 1 m/s east: (x, vx, y, vy)."""
REPORTED = np.diag([4.0, 1.0, 4.0, 1.0])
"""Each source's track covariance (σ 2 m, 1 m/s)."""


def truth(t: float) -> np.ndarray:
    moved: np.ndarray = TARGETS + t * TARGETS[:, [1, 1, 3, 3]] * np.array([1.0, 0.0, 1.0, 0.0])
    return moved


@pytest.mark.parametrize("sources", [("s0", "s1"), ("s0",)])
@pytest.mark.parametrize(
    "renumbered",
    [
        ("s0:4", "s0:5", "s0:6"),  # every id new at once
        ("s0:3", "s0:1", "s0:2"),  # numbered from 1 again, in another order: ids reused
    ],
)
def test_a_source_that_restarts_and_renumbers_its_tracks_keeps_the_fused_ids(
    sources: tuple[str, ...], renumbered: tuple[str, ...]
) -> None:
    """s0 restarts at 10 s and reports the same three targets under other ids. Every fused
    track still follows the target it followed before (checked against the truth), and no
    fused id is made. At main (before issue 23) the reused ids bound two fused tracks to
    the wrong targets by continuity (they passed its loose gate, 12 m apart) and a fourth
    fused id was started."""
    rng = np.random.default_rng(5)
    engine = SessionEngine(make_config(list(sources)))
    owner: dict[str, int] = {}
    for step in range(20):
        for offset, sensor in enumerate(sources):
            t = step + offset / 2
            ids = [f"{sensor}:{k + 1}" for k in range(3)]
            if sensor == "s0" and step >= 10:
                ids = list(renumbered)
            states = truth(t) + rng.normal(0.0, 1.0, (3, 4)) * np.array([1.0, 0.3, 1.0, 0.3])
            result = engine.apply(
                TrackReport(
                    sensor,
                    t,
                    tuple(
                        ReportedTrack(i, state, REPORTED)
                        for i, state in zip(ids, states, strict=True)
                    ),
                )
            )
            shown = [view for view in result.tracks if view.status.value == "confirmed"]
            positions = truth(t)[:, [0, 2]]
            for view in shown:
                nearest = int(np.argmin(np.hypot(*(positions - view.state[[0, 2]]).T)))
                assert owner.setdefault(view.id, nearest) == nearest, (t, view.id)
    assert sorted(owner) == ["F1", "F2", "F3"]
    assert {track.id for track in engine.tracks} == {"F1", "F2", "F3"}


def test_a_track_its_source_coasts_is_that_sources_miss() -> None:
    """The target dies at 10 s. s0 (P_D 0.9) drops it from its lists; s1 (P_D 0.7) keeps
    posting its coasting prediction, flagged ``coasted``. Each such report is s1's miss,
    ln(1 − 0.7), and each of s0's lists without it s0's miss, ln(1 − 0.9), once s1 no
    longer keeps the track up to date: the score falls from the ceiling 0 by exactly those
    sums (hand-worked below), and the track ends when it reaches ln(β / (1 − α)).
    Before issue 23 a coasted track was an estimate like any other: s1 kept the fused
    track current and confirmed for as long as it coasted."""
    config = make_config(
        [SensorSpec("s0", p_detect=0.9), SensorSpec("s1", p_detect=0.7)],
    )
    engine = SessionEngine(config)
    covariance = np.diag([4.0, 1.0, 4.0, 1.0])

    def state(t: float) -> np.ndarray:
        return np.array([t, 1.0, 0.0, 0.0])

    scores: list[tuple[float, str, float]] = []
    for step in range(16):
        t = float(step)
        alive = t < 10.0
        s0 = (ReportedTrack("a", state(t), covariance),) if alive else ()
        engine.apply(TrackReport("s0", t, s0))
        s1 = (ReportedTrack("b", state(t + 0.5), covariance, coasted=not alive),)
        result = engine.apply(TrackReport("s1", t + 0.5, s1))
        for view in result.tracks:
            scores.append((t + 0.5, view.status.value, view.score))
    delete = math.log(1e-3 / (1.0 - 1e-3))
    expected, score = [], 0.0
    for t in np.arange(10.5, 16.0):
        # s0's list at t − 0.5 (once s1 is overdue: its last update 9.5 s, revisit 1 s,
        # overdue after 2.5 s) and s1's coasted report at t
        if t - 0.5 - 9.5 > 2.5:
            score += math.log(1.0 - 0.9)
        score += math.log(1.0 - 0.7)
        expected.append(score)
        if score <= delete:
            break
    after = [entry for entry in scores if entry[0] >= 10.5]
    assert [entry[2] for entry in after] == pytest.approx(expected)
    assert after[-1][1] == "terminated" and all(e[1] != "terminated" for e in after[:-1])


def test_a_sources_off_track_that_started_a_second_fused_track_joins_the_first() -> None:
    """One target. s1's first report is 8 m off with a 1 m σ (a local track that lags) and
    its later ones close in on the target (0.7× the offset a second): outside the
    association's gate, the first starts a second fused track, which s1's next report
    confirms (min_points) and keeps by continuity — each report fits it about as well as
    the first track. The two are one object that no source reports twice: the younger
    joins the older, whose id (F1) the target keeps to the end with both sources'
    estimates. Before issue 23 two established tracks never merged: F2 followed the same
    target to the end."""
    engine = SessionEngine(make_config(["s0", "s1"]))
    tight = np.diag([1.0, 0.25, 1.0, 0.25])

    def state(t: float) -> np.ndarray:
        return np.array([2.0 * t, 2.0, 0.0, 0.0])

    shown: list[set[str]] = []
    for step in range(12):
        t = float(step)
        engine.apply(TrackReport("s0", t, (ReportedTrack("a", state(t), tight),)))
        if step >= 3:
            off = np.array([0.0, 0.0, 8.0 * 0.7 ** (step - 3), 0.0])
            s1 = (ReportedTrack("b", state(t + 0.5) + off, tight),)
            result = engine.apply(TrackReport("s1", t + 0.5, s1))
            shown.append({view.id for view in result.tracks if view.status.value == "confirmed"})
    assert engine.next_number == 3  # s1's first report did start a second fused track
    assert shown[-5:] == [{"F1"}] * 5
    (track,) = engine.tracks
    assert track.id == "F1" and set(track.estimates) == {"s0", "s1"}
    assert track.estimates["s1"].track == "b"
