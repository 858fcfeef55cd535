"""Detections of several sensors tracked together: the central tracker (docs/algorithms.md §8.9)."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from core.errors import InvalidInput, StaleReport
from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.engine import SessionEngine
from core.fusion.motion import MotionModel
from core.fusion.reorder import REORDER_WINDOW
from core.fusion.reports import DetectionReport, ReportedTrack, StepResult, TrackReport
from core.geometry import PolygonView, Sector
from core.lifecycle import LifeCycleConfig, StatusReason, TrackStatus
from core.metrics import coverage, identity_switches
from core.tracking.config import LocalTrackerConfig
from core.tracking.models import LinearMeasurementModel, ModelBank, constant_velocity
from core.tracking.tracker import LocalTracker

from .engine_helpers import LAYOUT

CLUTTER = 1e-7
"""β_FT of every sensor here (given: no estimate differs between sessions)."""
SIGMA = 10.0
STARTS = np.array([[0.0, 0.0], [0.0, 5000.0]])
VELOCITIES = np.array([[100.0, 0.0], [50.0, -80.0]])


def tracker(
    name: str, p_detect: float = 0.9, sigma: float = SIGMA, fov: Sector | None = None
) -> LocalTrackerConfig:
    """A sensor's own tracker configuration, as the service builds it (one sensor each)."""
    return LocalTrackerConfig(
        preset="aircraft",
        measurement_noise=((sigma**2, 0.0), (0.0, sigma**2)),
        p_detect=p_detect,
        life_cycle=LifeCycleConfig(false_target_density=CLUTTER),
        fields_of_view={name: fov},
        id_prefix=f"{name}:",
    )


def session(*sensors: SensorSpec) -> FusionConfig:
    return FusionConfig(motion=MotionModel(LAYOUT, q=100.0), sensors=sensors)


def detecting(name: str, local: bool = False, **options: object) -> SensorSpec:
    return SensorSpec(name, tracker=tracker(name, **options), local_tracker=local)  # type: ignore[arg-type]


def scans(count: int, seed: int = 0) -> list[np.ndarray]:
    """Each second, both targets detected (σ 10 m) and three false detections in 10 km²."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(count):
        truth = STARTS + VELOCITIES * k
        clutter = rng.uniform([-2000.0, -2000.0], [3000.0, 7000.0], size=(3, 2))
        out.append(np.concatenate([truth + rng.normal(0.0, SIGMA, truth.shape), clutter]))
    return out


def feed(engine: SessionEngine, names: list[str], measured: list[np.ndarray]) -> list[StepResult]:
    return [
        engine.apply_detections(DetectionReport(names[k % len(names)], float(k), z))
        for k, z in enumerate(measured)
    ]


def first_confirmation(steps: list[StepResult], target: int) -> int:
    """The first step with a confirmed fused track within 50 m of ``target``."""
    for k, step in enumerate(steps):
        truth = STARTS[target] + VELOCITIES[target] * k
        for track in step.tracks:
            near = np.hypot(*(track.state[[0, 2]] - truth)) < 50.0
            if near and track.status.value == "confirmed":
                return k
    raise AssertionError(f"target {target} never confirmed")


def test_two_detecting_sensors_are_tracked_centrally_unless_flagged() -> None:
    both = session(detecting("a"), detecting("b"))
    assert both.central_tracker is not None
    assert both.central_tracker.sensors == ("a", "b")
    assert both.sources == ("a", "b", "central")
    engine = SessionEngine(both)
    assert engine.local_trackers == {} and engine.tracker_of("a") is engine.central
    flagged = session(detecting("a"), detecting("b", local=True))
    assert flagged.central_tracker is None  # one detecting sensor left: nothing to fuse centrally
    assert set(SessionEngine(flagged).local_trackers) == {"a", "b"}
    # a sensor called "central" keeps its id; the central source takes another
    named = session(detecting("central"), detecting("b"))
    assert named.central_source == "central~"


def test_a_target_seen_alternately_by_two_sensors_confirms_as_early_as_by_one() -> None:
    measured = scans(8)
    alone = feed(SessionEngine(session(detecting("a"))), ["a"], measured)
    central = feed(SessionEngine(session(detecting("a"), detecting("b"))), ["a", "b"], measured)
    local = feed(
        SessionEngine(session(detecting("a", local=True), detecting("b", local=True))),
        ["a", "b"],
        measured,
    )
    for target in (0, 1):
        # the defaults confirm at the second hit (docs/algorithms.md §8.3): the second scan
        assert first_confirmation(alone, target) == 1
        assert first_confirmation(central, target) == 1
        # each local tracker needs two of its own scans (steps 2 and 3) before it reports
        assert first_confirmation(local, target) >= 2


def test_fusing_a_sensor_with_itself_changes_nothing() -> None:
    """The scans of one sensor, sent alternately as two sensors of the same physics: the
    central tracker's tracks are the single sensor's local tracker's, bit for bit."""
    measured = scans(20, seed=1)
    single = SessionEngine(session(detecting("a")))
    twice = SessionEngine(session(detecting("a"), detecting("b")))
    alone, central = feed(single, ["a"], measured), feed(twice, ["a", "b"], measured)
    mine, theirs = single.tracker_of("a"), twice.central
    assert mine is not None and theirs is not None
    # every field but each sensor's own record of the track (one column per sensor, §8.9)
    tracks = [theirs.export()["tracks"], mine.export()["tracks"]]
    for track in tracks[0] + tracks[1]:
        del track["sensor_misses"], track["sensor_detected_last"]
    assert json.dumps(tracks[0]) == json.dumps(tracks[1])
    assert theirs.next_number == mine.next_number
    # and the fused pictures agree on the targets' tracks at every step (a false track that
    # coasts is shown predicted by the fused layer's model alone, by the central tracker's
    # IMM in the other: its tracker state is the same, above)
    for k, (one, two) in enumerate(zip(alone, central, strict=True)):
        truth = STARTS + VELOCITIES * k
        for target in (0, 1):
            near = [
                [
                    (t.id, t.status.value, *np.round(t.state, 6))
                    for t in step.tracks
                    if np.hypot(*(t.state[[0, 2]] - truth[target])) < 50.0
                ]
                for step in (one, two)
            ]
            assert near[1] == near[0]


def test_misses_count_only_where_the_scanning_sensor_could_see() -> None:
    """A track outside sensor b's field of view keeps its score through b's empty scans; a
    sensor b that sees everywhere, and has detected the track, costs it ln(1 − P_D of b)
    per empty scan ([MTT] §4.3)."""
    far = Sector(
        origin=(0.0, -50_000.0),
        heading_deg=-90.0,
        half_angle_deg=10.0,
        range_min=0.0,
        range_max=5e3,
    )
    for fov, expected in ((far, 0.0), (None, math.log(1.0 - 0.7))):
        engine = SessionEngine(session(detecting("a"), detecting("b", p_detect=0.7, fov=fov)))
        central = engine.central
        assert central is not None
        truth = STARTS[:1]
        for k in range(4):
            engine.apply_detections(DetectionReport("a", float(k), truth + VELOCITIES[:1] * k))
            if k == 2 and fov is None:  # b carries the track: it detected it (§8.9)
                engine.apply_detections(on_target("b", 2.5))
        before = {t["number"]: t for t in central.export()["tracks"]}
        confirmed = [n for n, t in before.items() if t["status"] == "confirmed"]
        assert len(confirmed) == 1
        engine.apply_detections(DetectionReport("b", 3.5, np.zeros((0, 2))))
        after = {t["number"]: t for t in central.export()["tracks"]}[confirmed[0]]
        assert after["score"] - before[confirmed[0]]["score"] == pytest.approx(expected, abs=1e-12)


def test_each_sensor_scores_with_its_own_noise() -> None:
    """A detection of the noisier sensor b is gated and updated with b's R: the central
    track after one b update is the Kalman update under R_b (independent computation)."""
    engine = SessionEngine(session(detecting("a"), detecting("b", sigma=40.0)))
    central = engine.central
    assert central is not None
    for k in range(3):
        engine.apply_detections(DetectionReport("a", float(k), STARTS[:1] + VELOCITIES[:1] * k))
    predicted = central.predictor.predict(central._state, 1.0)
    z = STARTS[:1] + VELOCITIES[:1] * 3 + np.array([[30.0, -20.0]])
    engine.apply_detections(DetectionReport("b", 3.0, z))
    h = central.bank.measurement.matrix
    r_b = np.eye(2) * 1600.0
    state = central.export()["tracks"][0]
    for model in range(central.bank.n_models):
        mean, covariance = predicted.means[0, model], predicted.covariances[0, model]
        s = h @ covariance @ h.T + r_b
        gain = covariance @ h.T @ np.linalg.inv(s)
        expected = mean + gain @ (z[0] - h @ mean)
        np.testing.assert_allclose(state["means"][model], expected, rtol=1e-9, atol=1e-9)


def test_central_export_restore_continues_exactly() -> None:
    config = session(detecting("a"), detecting("b", p_detect=0.8, sigma=20.0))
    measured = scans(16, seed=2)
    uninterrupted = SessionEngine(config)
    feed(uninterrupted, ["a", "b"], measured)
    engine = SessionEngine(config)
    feed(engine, ["a", "b"], measured[:9])
    restored = SessionEngine.restore(config, json.loads(json.dumps(engine.export())))
    for k in range(9, 16):
        restored.apply_detections(DetectionReport("ab"[k % 2], float(k), measured[k]))
    assert json.dumps(restored.export()) == json.dumps(uninterrupted.export())
    assert restored.export()["version"] == 4 and restored.export()["central"] is not None


def test_central_time_order_same_instant_and_refusals() -> None:
    engine = SessionEngine(session(detecting("a"), detecting("b")))
    engine.apply_detections(DetectionReport("a", 1.0, STARTS))
    engine.apply_detections(DetectionReport("b", 1.0, STARTS))  # the same instant: fine
    engine.apply_detections(DetectionReport("a", 7.0, STARTS))
    before = json.dumps(engine.export())
    with pytest.raises(StaleReport):
        engine.apply_detections(DetectionReport("a", 7.0, STARTS))  # a's own time again
    with pytest.raises(StaleReport, match="reorder window of 5 s") as refused:
        # older than the tracker's latest by more than the window
        engine.apply_detections(DetectionReport("b", 7.0 - REORDER_WINDOW - 0.5, STARTS))
    assert refused.value.window == REORDER_WINDOW and refused.value.last_time == 7.0
    with pytest.raises(InvalidInput, match="central tracker's source"):
        engine.apply(TrackReport("central", 2.0, (ReportedTrack("x", np.zeros(4), np.eye(4)),)))
    assert json.dumps(engine.export()) == before


def staggered(seconds: int, seed: int) -> list[tuple[str, float, np.ndarray]]:
    """Three sensors scanning once a second, 1/3 s apart, in time order: (sensor, time, z)."""
    measured = scans(3 * seconds, seed=seed)
    return [("abc"[k % 3], k / 3.0, z / 1.0) for k, z in enumerate(measured)]


def jittered(inputs: list[tuple[str, float, np.ndarray]]) -> list[tuple[str, float, np.ndarray]]:
    """The same scans in an arrival order where sensor c's reach the centre 2 s late and b's
    1 s late, each sensor's own in its time order (sorted by arrival, ties by time)."""
    delay = {"a": 0.0, "b": 1.0, "c": 2.0}
    return sorted(inputs, key=lambda scan: (scan[1] + delay[scan[0]], scan[1]))


def central_session() -> FusionConfig:
    return session(detecting("a"), detecting("b", p_detect=0.7, sigma=20.0), detecting("c"))


def test_late_scans_within_the_window_give_the_tracker_of_the_scans_in_time_order() -> None:
    """Reports that interleave out of time order (by up to 2 s) are taken, not refused, and the
    central tracker ends where the same scans in time order take it (independent run)."""
    inputs = staggered(12, seed=3)
    arrival = jittered(inputs)
    assert arrival != inputs  # some scans do come late
    in_order, late = SessionEngine(central_session()), SessionEngine(central_session())
    for sensor, time, z in inputs:
        in_order.apply_detections(DetectionReport(sensor, time, z))
    for sensor, time, z in arrival:
        late.apply_detections(DetectionReport(sensor, time, z))
    assert late.central is not None and in_order.central is not None
    assert json.dumps(late.central.export()) == json.dumps(in_order.central.export())
    # and both targets are confirmed fused tracks at the end
    truth = STARTS + VELOCITIES * (len(inputs) - 1)  # scans(): k-th scan at k s of motion
    shown = [t for t in late.picture() if t.status.value == "confirmed"]
    for target in truth:
        assert any(np.hypot(*(t.state[[0, 2]] - target)) < 50.0 for t in shown)


def test_export_restore_with_scans_in_the_buffer_continues_exactly() -> None:
    arrival = jittered(staggered(10, seed=4))
    uninterrupted = SessionEngine(central_session())
    for sensor, time, z in arrival:
        uninterrupted.apply_detections(DetectionReport(sensor, time, z))
    engine = SessionEngine(central_session())
    for sensor, time, z in arrival[:17]:
        engine.apply_detections(DetectionReport(sensor, time, z))
    exported = json.loads(json.dumps(engine.export()))
    assert exported["central"]["scans"]  # the buffer travels with the export
    restored = SessionEngine.restore(central_session(), exported)
    assert json.dumps(restored.export()) == json.dumps(engine.export())
    for sensor, time, z in arrival[17:]:
        restored.apply_detections(DetectionReport(sensor, time, z))
    assert json.dumps(restored.export()) == json.dumps(uninterrupted.export())


def test_a_refused_late_scan_changes_nothing() -> None:
    engine = SessionEngine(central_session())
    for sensor, time, z in staggered(8, seed=5):
        engine.apply_detections(DetectionReport(sensor, time, z))
    before = json.dumps(engine.export())
    with pytest.raises(StaleReport):
        engine.apply_detections(DetectionReport("b", 1.0, STARTS))
    with pytest.raises(StaleReport):  # b's scan of that time is in the buffer already
        engine.apply_detections(DetectionReport("b", 7.0 + 1 / 3, STARTS))
    with pytest.raises(InvalidInput):  # a bad late scan rolls the re-processing back
        engine.apply_detections(DetectionReport("c", 6.5, np.full((1, 2), np.nan)))
    assert json.dumps(engine.export()) == before


def test_a_version_2_export_restores_its_central_tracker_with_an_empty_buffer() -> None:
    engine = SessionEngine(central_session())
    for sensor, time, z in staggered(6, seed=6):
        engine.apply_detections(DetectionReport(sensor, time, z))
    assert engine.central is not None
    old = json.loads(json.dumps(engine.export())) | {
        "version": 2,
        "central": json.loads(json.dumps(engine.central.export())),
    }
    restored = SessionEngine.restore(central_session(), old)
    assert restored.central is not None and restored.reorder.scans == ()
    assert json.dumps(restored.central.export()) == json.dumps(engine.central.export())
    # its next scan in time order continues as the uninterrupted engine's
    z = scans(1, seed=7)[0]
    for one in (engine, restored):
        one.apply_detections(DetectionReport("a", 6.0, z))
    assert json.dumps(restored.central.export()) == json.dumps(engine.central.export())


def central_target(engine: SessionEngine) -> dict[str, Any]:
    """The central track with the most hits (a start's branches may live beside it)."""
    assert engine.central is not None
    tracks: list[dict[str, Any]] = engine.central.export()["tracks"]
    return max(tracks, key=lambda track: (track["hits"], -track["number"]))


def on_target(sensor: str, time: float) -> DetectionReport:
    return DetectionReport(sensor, time, STARTS[:1] + VELOCITIES[:1] * time)


def test_a_sensor_that_stops_detecting_a_track_stops_counting_after_its_run() -> None:
    """Sensor a detects a target at every scan; sensor c (P_D 0.9, no field of view) scans
    between them and detects it once, then never. Each of c's first
    ⌈ln(β/(1 − α)) / ln(1 − P_D)⌉ = 3 misses costs the track ln(1 − 0.9) ([MTT] §4.3,
    from the score a's hit left); after them c has shown it does not see the target and
    its silence costs nothing, while a's own miss still does (§8.9)."""
    engine = SessionEngine(session(detecting("a"), detecting("c")))
    limit = -math.log(1e-3 / (1.0 - 1e-3)) / -math.log(1.0 - 0.9)
    assert math.ceil(limit) == 3
    engine.apply_detections(on_target("a", 0.0))
    engine.apply_detections(on_target("c", 0.5))
    costs = []
    for k in range(1, 7):
        engine.apply_detections(on_target("a", float(k)))
        before = central_target(engine)
        engine.apply_detections(DetectionReport("c", k + 0.5, np.zeros((0, 2))))
        after = central_target(engine)
        assert after["number"] == before["number"] and before["status"] == "confirmed"
        costs.append(after["score"] - before["score"])
    assert after["status"] == "confirmed"  # c's fourth to sixth misses do not coast it
    assert costs == pytest.approx([math.log(0.1)] * 3 + [0.0] * 3, abs=1e-12)
    engine.apply_detections(DetectionReport("a", 7.0, np.zeros((0, 2))))
    missed = central_target(engine)
    assert missed["number"] == after["number"]
    assert missed["score"] - after["score"] == pytest.approx(math.log(0.1), abs=1e-12)
    assert missed["status"] == "coasting"


PAIR_SENSORS = {"a": (1.0, 0.9), "b": (2.0, 0.7), "c": (1.5, 0.8)}
"""σ (m) and P_D of the close pair's three sensors (issue 23's)."""
PAIR_CLUTTER = 5.0 / 400.0**2
"""β_FT of the close pair's sensors: five false detections per scan on a 400 m square."""


def pair_tracker(name: str) -> LocalTrackerConfig:
    """A sensor of the close pair: the true CV model, R, P_D, β_FT and β_NT (no velocity
    prior, no management knob: defaults plus physics)."""
    sigma, p_detect = PAIR_SENSORS[name]
    bank = ModelBank(
        (constant_velocity(1.0, 0.05, noise="continuous"),),
        LinearMeasurementModel(np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]]), np.eye(2) * sigma**2),
        np.ones((1, 1)),
    )
    return LocalTrackerConfig(
        bank=bank,
        p_detect=p_detect,
        life_cycle=LifeCycleConfig(
            false_target_density=PAIR_CLUTTER, new_target_density=0.2 / 400.0**2
        ),
        classification=None,
        fields_of_view={name: None},
        id_prefix=f"{name}:",
    )


def close_pair_switches(seed: int, apart: float, stagger: float) -> tuple[int, int]:
    """Two targets ``apart`` m apart on parallel courses at 2 m/s, seen for 10 s by the three
    sensors of :data:`PAIR_SENSORS` each second, ``stagger`` s after each other, with clutter:
    the id switches of the fused picture against the truth (:func:`core.metrics.coverage`
    at 10 m, :func:`core.metrics.identity_switches`), and the most confirmed tracks of one
    step (2: one per target)."""
    rng = np.random.default_rng(seed)
    config = FusionConfig(
        motion=MotionModel(LAYOUT, q=0.05),
        sensors=tuple(
            SensorSpec(name, p_detect=PAIR_SENSORS[name][1], tracker=pair_tracker(name))
            for name in PAIR_SENSORS
        ),
    )
    engine = SessionEngine(config)
    starts = np.array([[-30.0, 0.0], [-30.0, apart]])
    velocity = np.array([2.0, 0.5])
    assigned, most = [], 0
    for second in range(10):
        for k, (name, (sigma, p_detect)) in enumerate(PAIR_SENSORS.items()):
            time = second + k * stagger
            truth = starts + velocity * time
            seen = truth[rng.random(2) < p_detect]
            seen = seen + rng.normal(0.0, sigma, seen.shape)
            clutter = rng.uniform(-200.0, 200.0, (rng.poisson(5), 2))
            step = engine.apply_detections(
                DetectionReport(name, time, np.concatenate([seen, clutter]))
            )
        live = {
            t.id: t.state[[0, 2]]
            for t in step.tracks
            if t.status.value in ("confirmed", "coasting")
        }
        most = max(most, len(live))
        assigned.append(coverage({0: truth[0], 1: truth[1]}, live, cutoff=10.0))
    return identity_switches(assigned), most


def test_a_close_pair_seen_by_three_sensors_at_one_instant_keeps_its_ids() -> None:
    """Three sensors' detections of one instant measure no velocity: a tentative track's
    detections of one instant are positions of it, tested at its next instant
    (docs/algorithms.md §8.3), so a close pair 30 m apart keeps its ids and gets no
    duplicate track (checked against the truth; before, a target confirmed at one instant
    took its neighbour's detection when its own was missed)."""
    results = [close_pair_switches(seed, apart=30.0, stagger=0.0) for seed in range(6)]
    assert sum(switches for switches, _ in results) == 0, results
    assert max(most for _, most in results) == 2, results


def test_a_sensor_that_never_detected_a_track_says_nothing_about_it_once_it_is_held() -> None:
    """Sensor d never detects the target a detects at every scan. While the track is young
    (at most ``initiation_hits`` = 3 hits) d's empty scan costs it ln(1 − 0.9), as every
    scan that could see it; once a has held it for four hits, d's silence costs nothing
    (§8.9)."""
    engine = SessionEngine(session(detecting("a"), detecting("d")))
    costs = []
    for k in range(5):
        engine.apply_detections(on_target("a", float(k)))
        before = central_target(engine)
        engine.apply_detections(DetectionReport("d", k + 0.5, np.zeros((0, 2))))
        after = central_target(engine)
        assert after["number"] == before["number"]
        costs.append((before["hits"], after["score"] - before["score"]))
    assert after["status"] == "confirmed"
    assert costs == [
        (1, pytest.approx(math.log(0.1), abs=1e-12)),
        (2, pytest.approx(math.log(0.1), abs=1e-12)),
        (3, pytest.approx(math.log(0.1), abs=1e-12)),
        (4, 0.0),
        (5, 0.0),
    ]


def test_a_track_another_sensor_just_detected_waits_for_its_next_scan() -> None:
    """Sensor e (a slow radar: scans at 0.5 and 4.5 s, revisit 4 s) detected the target at
    its latest scan; sensor a (1 s) then misses it. Both look at the track, so its delete
    threshold is ln(β/(1 − α)) + ln(T_c/T_max) (§8.14; T_c = 1/(1 + 1/4) = 0.8 s, T_max =
    4 s): −6.907 − 1.609 = −8.517. a's three misses, 3 ln(1 − 0.9) = −6.908, end a track a
    alone carries ([MTT] §4.3), not this one. a's fourth is no miss (a run of three, a's
    limit, says a does not see the target, §8.9); e alone looks at the track then, its
    threshold is −6.907 again, which −6.908 passes, but e detected it at its latest scan:
    the score waits at the threshold (§8.9) for e's next scan, whose miss ends it."""
    engine = SessionEngine(session(detecting("a"), detecting("e")))
    engine.apply_detections(on_target("a", 0.0))
    engine.apply_detections(on_target("e", 0.5))
    for k in range(1, 5):
        engine.apply_detections(on_target("a", float(k)))
    engine.apply_detections(on_target("e", 4.5))
    number = central_target(engine)["number"]
    base = math.log(1e-3 / (1.0 - 1e-3))
    assert base + math.log(0.8 / 4.0) < 3 * math.log(0.1) < base
    scores = []
    for k in range(5, 9):
        engine.apply_detections(DetectionReport("a", float(k), np.zeros((0, 2))))
        scores.append(central_target(engine)["score"])
    assert scores == pytest.approx([*(k * math.log(0.1) for k in (1, 2, 3)), base], abs=1e-12)
    waiting = central_target(engine)
    assert waiting["number"] == number and waiting["status"] == "coasting"
    assert waiting["sensor_misses"] == [4, 0]  # a run of 4 scans, past its limit 3
    assert engine.central is not None
    engine.apply_detections(DetectionReport("e", 8.5, np.zeros((0, 2))))
    assert number not in [t["number"] for t in engine.central.export()["tracks"]]
    assert engine.central.tallies["e"].ended_reasons == {"score_deleted": 1}
    # a alone (e never detected it, so e does not carry it): the third miss ends it
    alone = SessionEngine(session(detecting("a"), detecting("e")))
    for k in range(4):
        alone.apply_detections(on_target("a", float(k)))
    for k in range(4, 7):
        alone.apply_detections(DetectionReport("a", float(k), np.zeros((0, 2))))
    assert alone.central is not None
    assert alone.central.tallies["a"].ended_reasons == {"score_deleted": 1}


def test_a_clutter_born_tentative_track_is_refuted_by_every_sensor_that_could_see_it() -> None:
    """One false detection of sensor a starts a tentative track at L₀ = ln(β_NT/β_FT) = 0
    (β_NT unset: β_FT); the empty scans of b, c and a that follow, which never detected
    it, each cost ln(1 − 0.9): the third takes it to 3 ln 0.1 = −6.908 ≤ ln(β/(1 − α)) =
    −6.907 and deletes it ([MTT] §4.3) — a tentative track is tested by every scan that
    could see it (§8.9), not only by its own sensor's."""
    engine = SessionEngine(session(detecting("a"), detecting("b"), detecting("c")))
    central = engine.central
    assert central is not None
    engine.apply_detections(DetectionReport("a", 0.0, np.array([[1000.0, 2000.0]])))
    (started,) = central.export()["tracks"]
    assert started["status"] == "tentative" and started["score"] == 0.0
    scores = []
    for sensor, time in (("b", 1 / 3), ("c", 2 / 3)):
        engine.apply_detections(DetectionReport(sensor, time, np.zeros((0, 2))))
        (track,) = central.export()["tracks"]
        scores.append(track["score"])
    assert scores == pytest.approx([math.log(0.1), 2 * math.log(0.1)], abs=1e-12)
    engine.apply_detections(DetectionReport("a", 1.0, np.zeros((0, 2))))
    assert central.export()["tracks"] == []
    assert central.tallies["a"].refuted == 1


def test_a_track_hits_count_the_instants_it_was_detected_at() -> None:
    """A tentative track's hits are the instants it was detected at, not its detections:
    the three sensors of one instant add one hit, so ``min_points`` 3 confirms at the third
    instant (hand-counted: instants 0, 1, 2), where counting detections (3, 5, 6 hits)
    confirmed at the second; and a sensor's branch of an instant already counted adds none.
    """
    configs = {name: pair_tracker(name) for name in PAIR_SENSORS}
    life = replace(configs["a"].life_cycle, min_points=3)
    configs = {name: replace(config, life_cycle=life) for name, config in configs.items()}
    central = LocalTracker(LocalTrackerConfig.central(configs))
    target = np.array([[10.0, -20.0]])
    seen = {0.0: ("a", "b", "c"), 1.0: ("a", "b"), 2.0: ("a",)}
    hits, statuses = [], []
    for instant, (time, sensors) in enumerate(seen.items()):
        for name in sensors:
            step = central.step(time, target + 0.5 * time, sensor=name)
            track = next(t for t in step.tracks if t.id == "C1")  # the target's first start
            hits.append((instant, track.hits))
        statuses.append(track.status.value)
    assert hits == [(0, 1), (0, 1), (0, 1), (1, 2), (1, 2), (2, 3)]
    assert statuses == ["tentative", "tentative", "confirmed"]


def _blind_zone_session() -> SessionEngine:
    """Two radars ``a`` and ``b`` (sectors of 1 km, 3 km apart, facing each other: a blind
    zone between them) and a track-list source ``lists`` (P_D 0.9) that sees everywhere."""
    a = Sector(
        origin=(0.0, 0.0), heading_deg=0.0, half_angle_deg=45.0, range_min=0.0, range_max=1000.0
    )
    b = Sector(
        origin=(3000.0, 0.0),
        heading_deg=180.0,
        half_angle_deg=45.0,
        range_min=0.0,
        range_max=1000.0,
    )
    region = PolygonView(((-500.0, -1500.0), (3500.0, -1500.0), (3500.0, 1500.0), (-500.0, 1500.0)))
    return SessionEngine(
        FusionConfig(
            motion=MotionModel(LAYOUT, q=100.0),
            sensors=(
                SensorSpec("a", tracker=tracker("a", fov=a)),
                SensorSpec("b", tracker=tracker("b", fov=b)),
                SensorSpec("lists", p_detect=0.9),
            ),
            region=region,
        )
    )


def test_a_central_phantom_is_no_report_of_the_object() -> None:
    """A target leaves radar a's sector for the gap before radar b's (inside the session's
    region: a blind zone, docs/algorithms.md §8.9): the central tracker keeps it as a
    phantom, reported at every step. A track-list source ``lists`` (P_D 0.9, sees
    everywhere) that carried it and now sends empty lists is the only source that could
    see it: its silence is a miss (§8.2), ln(1 − 0.9) from the score ceiling 0 each, and
    the third crosses the delete threshold ln(β/(1 − α)) = ln(1e-3/0.999) (3 × −2.3026 =
    −6.908 ≤ −6.907, by hand). The phantom, a prediction, does not hold the track, nor
    start another one."""
    engine = _blind_zone_session()
    central = engine.central
    assert central is not None
    rng = np.random.default_rng(3)
    covariance = np.diag([100.0, 25.0, 100.0, 25.0])
    start, velocity = np.array([500.0, 0.0]), np.array([50.0, 0.0])
    silent_from, steps = None, []
    for k in range(30):
        truth = start + velocity * k
        seen = np.hypot(*truth) <= 1000.0
        z = truth[None] + rng.normal(0.0, SIGMA, (1, 2)) if seen else np.zeros((0, 2))
        engine.apply_detections(DetectionReport("a", float(k), z))
        engine.apply_detections(DetectionReport("b", k + 0.5, np.zeros((0, 2))))
        if silent_from is None and central.phantoms:
            silent_from = k + 2  # lists still reports it twice after the phantom starts
        state = np.array([truth[0] + velocity[0] * 0.75, velocity[0], truth[1], velocity[1]])
        tracks = (ReportedTrack("t", state, covariance),)
        if silent_from is not None and k >= silent_from:
            tracks = ()
        steps.append(engine.apply(TrackReport("lists", k + 0.75, tracks)))
        if silent_from is not None and k >= silent_from + 3:
            break
    assert silent_from is not None, "the central track never became a phantom"
    first = steps[0].tracks[0].id
    history = [
        [(track.status, track.reason, track.score) for track in step.tracks if track.id == first]
        for step in steps
    ]
    # the precondition: lists' last hit left the track at the score ceiling, 0
    assert history[silent_from - 1][0][2] == 0.0
    scores = [history[silent_from + m][0][2] for m in range(2)]
    assert scores == pytest.approx([math.log(0.1), 2 * math.log(0.1)], abs=1e-12)
    ended = history[silent_from + 2]
    assert ended == [(TrackStatus.TERMINATED, StatusReason.SCORE_DELETED, ended[0][2])]
    assert ended[0][2] == pytest.approx(3 * math.log(0.1), abs=1e-12)
    # nor does the phantom, still reported by the central tracker, start a fused track again
    assert central.phantoms
    assert list(steps[silent_from + 3].tracks) == []


def test_a_source_that_never_carried_a_central_phantom_does_not_delete_it() -> None:
    """The blind zone of the test above, with a track-list source ``lists`` (P_D 0.9, sees
    everywhere) that never reports the target (an ADS-B station and an unequipped aircraft):
    its empty lists say nothing about it (§8.2: a source that never carried a track), while
    the radars' tracker holds it. The central tracker still reports its phantom at every step:
    it carries the track, which is not stale (every source left it), so the fused track keeps
    its id and its score through the gap (§8.11), shown ``phantom``. Were the phantom no
    report at all (``_reporting`` in place of ``_current`` for the stale rule), the track
    would be stale from its first phantom step and lists' third silence would delete it,
    3 ln(1 − 0.9) = −6.908 ≤ ln(1e-3/0.999) = −6.907 (by hand). The phantom keeps nothing up to
    date either way (``others``, tested above)."""
    engine = _blind_zone_session()
    central = engine.central
    assert central is not None
    rng = np.random.default_rng(3)
    start, velocity = np.array([500.0, 0.0]), np.array([50.0, 0.0])
    phantom_from, steps = None, []
    for k in range(30):
        truth = start + velocity * k
        seen = np.hypot(*truth) <= 1000.0
        z = truth[None] + rng.normal(0.0, SIGMA, (1, 2)) if seen else np.zeros((0, 2))
        engine.apply_detections(DetectionReport("a", float(k), z))
        engine.apply_detections(DetectionReport("b", k + 0.5, np.zeros((0, 2))))
        if phantom_from is None and central.phantoms:
            phantom_from = k
        steps.append(engine.apply(TrackReport("lists", k + 0.75, ())))
        if phantom_from is not None and k >= phantom_from + 5:
            break
    assert phantom_from is not None, "the central track never became a phantom"
    (first,) = steps[phantom_from - 1].tracks.ids  # the one fused track, confirmed
    history = [
        [(track.status, track.score) for track in step.tracks if track.id == first]
        for step in steps
    ]
    before = history[phantom_from - 1]
    assert len(before) == 1 and before[0][0] == TrackStatus.CONFIRMED
    # lists' six silences in the gap: no miss, the same score, the track held as a phantom
    for m in range(6):
        assert history[phantom_from + m] == [(TrackStatus.PHANTOM, before[0][1])]
