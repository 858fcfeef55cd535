"""The session engine on scenarios (issue "Track-to-track fusion and the session engine")."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from core.association import METHODS
from core.belief import Frame, MassFunction
from core.errors import InvalidInput, StaleReport
from core.fusion.classes import fuse_sensor_classes
from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.engine import STALE_REVISITS, SessionEngine
from core.fusion.motion import MotionModel, StateLayout
from core.fusion.reports import ReportedTrack, TrackReport
from core.geometry import PolygonView, Sector
from core.lifecycle import STATUS_CODES, LifeCycleConfig, StatusReason, TrackStatus
from core.simulation.tracklists import crossing_traffic, estimate_covariance, t2t_four

from .engine_helpers import fused_ids_of_targets, make_config, run, serialise

LOW_NOISE_CASES = [
    # (method, options, reported σ, motion q). hachour's default "density" likelihood
    # only matches when (2π)^q |C| is small (§3.3): the paper-like case has small
    # covariances; at half-metre covariances it needs likelihood="relative".
    ("gnn", {}, 0.5, 0.5),
    ("denoeux", {"gate_probability": 0.999, "alpha": 1.0}, 0.5, 0.5),
    ("hachour", {}, 0.2, 0.01),
    ("hachour", {"likelihood": "relative"}, 0.5, 0.5),
    ("hachour", {"maximise": "plausibility"}, 0.2, 0.01),
    ("mercier", {}, 0.5, 0.5),
    ("dang_han", {}, 0.5, 0.5),
]


@pytest.mark.parametrize(("method", "options", "sigma", "q"), LOW_NOISE_CASES)
def test_t2t_four_every_method_associates_correctly_at_low_noise(
    method: str, options: dict[str, object], sigma: float, q: float
) -> None:
    # Low noise: the actual errors are a fifth of the reported standard deviations.
    scenario = t2t_four(seed=3, position_sigma=sigma, noise=0.2)
    # Continuity off: the method decides every pairing at every report.
    config = make_config(scenario.sensors, method=method, options=options, continuity=False, q=q)
    steps = run(SessionEngine(config), scenario.reports)
    per_target, wrong, total = fused_ids_of_targets(scenario.reports, steps)
    assert total == 4 * (len(scenario.reports) - 1)  # every report after the first pairs all 4
    assert wrong == 0
    assert all(len(ids) == 1 for ids in per_target.values()), per_target
    assert len({next(iter(ids)) for ids in per_target.values()}) == 4


def test_every_api_method_has_a_low_noise_case() -> None:
    assert {case[0] for case in LOW_NOISE_CASES} == set(METHODS)


def test_t2t_four_fused_position_error_is_below_the_better_sensor() -> None:
    # Radar-like elongated errors: s1 is poor along x, s2 along y. CI takes the best of both.
    scenario = t2t_four(seed=5, position_sigma=2.0, elongation=3.0, separation=40.0, n_steps=40)
    engine = SessionEngine(make_config(scenario.sensors))
    steps = run(engine, scenario.reports)
    squared: dict[str, list[float]] = {"fused": [], "s1": [], "s2": []}
    owner: dict[str, int] = {}
    for report, step in zip(scenario.reports, steps, strict=True):
        target_of = dict(zip(report.track_ids, report.target_ids.tolist(), strict=True))
        for fused, track, _, _ in step.association.pairs:
            owner.setdefault(fused, target_of[track])
        for state, target in zip(report.states, report.target_ids, strict=True):
            truth = scenario.truths[target].state_at(report.step)
            truth_now = truth[[0, 2]] + truth[[1, 3]] * (report.time - report.step)
            squared[report.sensor].append(float(np.sum((state[[0, 2]] - truth_now) ** 2)))
        if report.sensor == "s2" and report.step >= 5:
            for track in step.tracks:
                truth = scenario.truths[owner[track.id]].state_at(report.step)
                truth_now = truth[[0, 2]] + truth[[1, 3]] * (report.time - report.step)
                squared["fused"].append(float(np.sum((track.state[[0, 2]] - truth_now) ** 2)))
    rmse = {name: float(np.sqrt(np.mean(values))) for name, values in squared.items()}
    assert rmse["fused"] <= min(rmse["s1"], rmse["s2"]), rmse


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_metre_scale_crossing_traffic_with_the_default_configuration(seed: int) -> None:
    # 20 targets, 3 sensors, σ = 5 m (25 m² per axis), P_D = 0.9, crossings.
    scenario = crossing_traffic(seed=seed)
    # These sensors drop each track from each list at random (P_D 0.9 per list): with the
    # default ceiling 0 three lists in a row without a target end its fused track (β per
    # report, ~4 of 3600 reports here); the ceiling at the confirm threshold waits for 6.
    # Association is what is measured here.
    keep = LifeCycleConfig(score_ceiling=LifeCycleConfig().confirm_threshold)
    engine = SessionEngine(make_config(scenario.sensors, management=keep))
    steps = run(engine, scenario.reports)
    per_target, wrong, total = fused_ids_of_targets(scenario.reports, steps)
    # Bound: continuity keeps every bound pair; only first contacts go to the method, and
    # its 0.999 gate admits a wrong partner only when two targets are within a few σ at a
    # sensor's first report — never in this geometry. So: no false association at all.
    assert total > 0.85 * 20 * 3 * 60 - 60
    assert wrong == 0
    assert sorted(per_target) == list(range(20))
    assert all(len(ids) == 1 for ids in per_target.values()), per_target


def test_same_inputs_give_byte_identical_results() -> None:
    scenario = crossing_traffic(seed=4, n_steps=15)
    first = [
        serialise(step)
        for step in run(SessionEngine(make_config(scenario.sensors)), scenario.reports)
    ]
    second = [
        serialise(step)
        for step in run(SessionEngine(make_config(scenario.sensors)), scenario.reports)
    ]
    assert first == second


def test_export_restore_continue_equals_an_uninterrupted_run() -> None:
    scenario = crossing_traffic(seed=6, n_steps=20)
    config = make_config(scenario.sensors)
    half = len(scenario.reports) // 2
    uninterrupted = SessionEngine(config)
    expected = [serialise(step) for step in run(uninterrupted, scenario.reports)]
    first_half = SessionEngine(config)
    run(first_half, scenario.reports[:half])
    exported = json.loads(json.dumps(first_half.export(), allow_nan=False))  # through JSON text
    restored = SessionEngine.restore(config, exported)
    continued = [serialise(step) for step in run(restored, scenario.reports[half:])]
    assert continued == expected[half:]
    assert restored.export() == uninterrupted.export()


def report(
    sensor: str, time: float, *tracks: tuple[str, list[float]], sigma: float = 2.0
) -> TrackReport:
    covariance = estimate_covariance(sigma, sigma / 2.0)
    return TrackReport(
        sensor,
        time,
        tuple(ReportedTrack(i, np.array(x, dtype=float), covariance) for i, x in tracks),
    )


def moving(x: float, t: float, speed: float = 10.0) -> list[float]:
    return [x + speed * t, speed, 0.0, 0.0]


def test_a_target_outside_a_sensors_view_is_not_penalised_by_its_reports() -> None:
    # s1 sees everything; s2 sees only x ≥ 200 (a sector at (300, 0) looking west, ±60°, 150 m).
    fov = Sector(
        origin=(300.0, 0.0), heading_deg=180.0, half_angle_deg=60.0, range_min=0.0, range_max=150.0
    )
    engine = SessionEngine(make_config(["s1", "s2"], fovs={"s2": fov}))
    engine.apply(report("s1", 0.0, ("a", [50.0, 0, 0, 0]), ("b", [250.0, 0, 0, 0])))
    engine.apply(report("s1", 1.0, ("a", [50.0, 0, 0, 0]), ("b", [250.0, 0, 0, 0])))
    engine.apply(report("s2", 1.2, ("x", [50.0, 0, 0, 0]), ("y", [250.0, 0, 0, 0])))
    before = {track.id: track.score for track in engine.tracks}
    # s2 reports nothing at 4.0, when s1 (revisit 1 s, last report at 1.0) is overdue on both
    # (§8.2: only then is s2's silence about a track it carried a miss)
    step = engine.apply(report("s2", 4.0))
    after = {track.id: track.score for track in engine.tracks}
    outside, inside = "F1", "F2"  # a at x = 50 (outside s2's view), b at x = 250 (inside)
    assert after[outside] == before[outside]
    # Control: the target inside s2's view is penalised by ln(1 − P_D) = ln 0.1.
    assert after[inside] == pytest.approx(before[inside] + np.log(0.1))
    assert set(step.association.missed) == {outside, inside}


def test_a_source_says_nothing_about_what_it_never_carried() -> None:
    """A cooperative source (ADS-B: no field of view, reports only equipped aircraft) never
    reports the radar-only target: its lists are no miss for that track (§8.2), which keeps
    its score and id through 60 lists, while the equipped target's track is kept too."""
    engine = SessionEngine(make_config(["radar", "adsb"]))
    scores = []
    for step in range(60):
        t = float(step)
        if step % 4 == 0:  # the radar every 4 s sees both
            engine.apply(
                report("radar", t, ("r1", moving(0.0, t)), ("r2", moving(0.0, t, speed=-10.0)))
            )
        result = engine.apply(report("adsb", t + 0.5, ("icao", moving(0.0, t + 0.5))))
        radar_only = [view for view in result.tracks if view.sources[0].sensor == "radar"]
        radar_only = [v for v in radar_only if {s.sensor for s in v.sources} == {"radar"}]
        if radar_only:
            scores.append(radar_only[0].score)
    ids = {track.id: {s for s in track.estimates} for track in engine.tracks}
    assert ids == {"F1": {"radar", "adsb"}, "F2": {"radar"}}
    # between radar scans the radar-only track's score never moves: three ADS-B lists say nothing
    assert len(scores) == 60
    assert all(scores[k] == scores[k - 1] for k in range(1, 60) if k % 4)


def test_a_source_that_left_a_track_long_ago_says_nothing_about_it() -> None:
    """§8.2: a radar that lost an aircraft (below its horizon) and still scans says nothing
    about it once it has not updated the track for STALE_REVISITS of its revisit; two
    ordinary misses of the source that holds it (ADS-B, every 2 s) then leave the track
    with its id. Control: while the radar left it only recently, its silence counts."""

    def run(lost_at: float) -> tuple[set[str], float, bool]:
        engine = SessionEngine(make_config(["radar", "adsb"]))
        ended = False
        for step in range(40):
            t = 2.0 * step
            seen = t < lost_at
            radar = engine.apply(report("radar", t, *([("r1", moving(0.0, t))] if seen else [])))
            held = not 60.0 <= t <= 62.0  # ADS-B misses the lists at 60.5 and 62.5
            adsb = engine.apply(
                report("adsb", t + 0.5, *([("a1", moving(0.0, t + 0.5))] if held else []))
            )
            for result in (radar, adsb):
                ended |= TrackStatus.TERMINATED in result.tracks.statuses
        return {track.id for track in engine.tracks}, engine.revisits["radar"], ended

    ids, revisit, ended = run(lost_at=20.0)  # the radar's last update at 18 s, 42 s before
    assert (60.5 - 18.0) / revisit > STALE_REVISITS
    assert ids == {"F1"} and not ended
    # control: the radar's last update at 54 s; at 64 s (5 revisits later) its silence is a
    # third miss in a row (ADS-B at 60.5 and 62.5: ln 0.1 × 3 ≤ the delete threshold): the
    # track ends (and its restart at ADS-B's next list takes its id back, §8.15)
    _, _, ended = run(lost_at=56.0)
    assert ended


def blind_zone_engine() -> SessionEngine:
    # s1 sees x ∈ [0, 100] (half-disc around the origin), s2 sees x ≥ 150 along the axis
    # (half-disc of radius 150 around (300, 0)); between them a blind zone inside the region.
    s1 = Sector(
        origin=(0.0, 0.0), heading_deg=0.0, half_angle_deg=89.0, range_min=0.0, range_max=100.0
    )
    s2 = Sector(
        origin=(300.0, 0.0), heading_deg=180.0, half_angle_deg=89.0, range_min=0.0, range_max=150.0
    )
    region = PolygonView(((-50.0, -200.0), (350.0, -200.0), (350.0, 200.0), (-50.0, 200.0)))
    return SessionEngine(make_config(["s1", "s2"], fovs={"s1": s1, "s2": s2}, region=region))


def test_a_target_crossing_a_blind_zone_is_a_phantom_and_keeps_its_id() -> None:
    engine = blind_zone_engine()
    statuses: list[tuple[float, str, str]] = []
    for second in range(25):  # x from 10 to 250 m: s1's view, the blind zone, s2's view
        x = 10.0 + 10.0 * second  # 10 m/s along y = 0
        s1_tracks = [("t", moving(10.0, second))] if x <= 100.0 else []
        step = engine.apply(report("s1", float(second), *s1_tracks, sigma=1.0))
        x_half = x + 5.0
        s2_tracks = [("u", moving(10.0, second + 0.5))] if x_half >= 150.0 else []
        step = engine.apply(report("s2", second + 0.5, *s2_tracks, sigma=1.0))
        statuses += [(second + 0.5, track.id, track.status.value) for track in step.tracks]
    f1 = [(time, status) for time, track, status in statuses if track == "F1"]
    assert "phantom" in {status for _, status in f1}, f1
    phantom_times = [time for time, status in f1 if status == "phantom"]
    # Phantom from the first report after x > 100 until s2's second report confirms a newcomer.
    assert phantom_times == [9.5, 10.5, 11.5, 12.5, 13.5, 14.5]
    # s2's first track is handed over to the phantom: F1 ends confirmed and fed by s2.
    final = engine.tracks
    assert [track.id for track in final] == ["F1"]
    assert final[0].status is TrackStatus.CONFIRMED and final[0].estimates["s2"].track == "u"
    assert any(track == "F2" and status == "terminated" for _, track, status in statuses), (
        "the newcomer of s2 should be merged into the phantom"
    )


def test_a_phantom_expires_after_its_maximum_time_in_the_blind_zone() -> None:
    engine = blind_zone_engine()
    # 20 m at 10 m/s: a phantom may stay 2 s in the blind zone.
    short = SessionEngine(
        make_config(
            ["s1", "s2"],
            fovs={
                name: sensor.fov
                for name, sensor in zip(("s1", "s2"), engine.config.sensors, strict=True)
                if sensor.fov is not None
            },
            region=engine.config.region,
            management=LifeCycleConfig(phantom_max_distance=20.0, phantom_min_speed=10.0),
        )
    )
    seen: list[tuple[float, str, TrackStatus, StatusReason]] = []
    for second in range(16):  # reported while in s1's view (x ≤ 100), then nothing
        tracks = [("t", moving(10.0, second))] if second <= 9 else []
        step = short.apply(report("s1", float(second), *tracks, sigma=1.0))
        seen += [(float(second), t.id, t.status, t.reason) for t in step.tracks]
    f1 = [(time, status, reason) for time, track, status, reason in seen if track == "F1"]
    phantom_since = min(time for time, status, _ in f1 if status is TrackStatus.PHANTOM)
    assert f1[-1] == (phantom_since + 3.0, TrackStatus.TERMINATED, StatusReason.PHANTOM_EXPIRED)
    assert short.tracks == []


def test_late_report_is_used_and_stale_report_is_refused_without_change() -> None:
    engine = SessionEngine(make_config(["s1", "s2"]))
    engine.apply(report("s1", 1.0, ("a", moving(0.0, 1.0))))
    engine.apply(report("s2", 2.0, ("b", moving(0.0, 2.0))))
    late = engine.apply(
        report("s1", 1.5, ("a", moving(0.0, 1.5)))
    )  # older than 2.0, newer than 1.0
    assert late.time == 2.0  # results are at the fusion time
    assert {source.sensor: source.time for source in engine.tracks[0].sources()}["s1"] == 1.5
    assert [(f, t) for f, t, _, _ in late.association.pairs] == [("F1", "a")]
    before = json.dumps(engine.export())
    with pytest.raises(StaleReport) as refused:
        engine.apply(report("s1", 1.2, ("a", moving(0.0, 1.2))))
    assert (refused.value.time, refused.value.last_time) == (1.2, 1.5)
    assert "1.2" in str(refused.value) and "1.5" in str(refused.value)
    assert json.dumps(engine.export()) == before


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        (report("s9", 1.0), "unknown sensor 's9'"),
        (report("s1", float("nan")), "time must be finite"),
        (
            TrackReport("s1", 1.0, (ReportedTrack("a", np.zeros(3), np.eye(3)),)),
            "state must have 4 components",
        ),
        (
            TrackReport("s1", 1.0, (ReportedTrack("a", np.zeros(4), np.diag([1.0, 1, 1, -1])),)),
            "not positive definite",
        ),
        (
            TrackReport(
                "s1",
                1.0,
                (
                    ReportedTrack("a", np.zeros(4), np.eye(4)),
                    ReportedTrack("a", np.ones(4), np.eye(4)),
                ),
            ),
            "ids repeat: \\['a'\\]",
        ),
        (
            TrackReport("s1", 1.0, (ReportedTrack("a", np.array([0, np.inf, 0, 0]), np.eye(4)),)),
            "tracks\\[0\\].state is not finite",
        ),
    ],
)
def test_bad_reports_are_refused_and_change_nothing(bad: TrackReport, message: str) -> None:
    engine = SessionEngine(make_config(["s1"]))
    engine.apply(report("s1", 0.5, ("a", moving(0.0, 0.5))))
    before = json.dumps(engine.export())
    with pytest.raises(InvalidInput, match=message):
        engine.apply(bad)
    assert json.dumps(engine.export()) == before


def test_class_fusion_in_the_engine_discounts_each_sensor_and_combines() -> None:
    frame = Frame(["liner", "bomber", "fighter"])
    base = make_config(["s1", "s2"])
    config = type(base)(
        motion=base.motion,
        sensors=(SensorSpec("s1", reliability=0.9), SensorSpec("s2", reliability=0.6)),
        classes=frame,
    )
    engine = SessionEngine(config)
    m1 = MassFunction.from_sets(frame, [(["bomber", "fighter"], 0.6), (frame.labels, 0.4)])
    m2 = MassFunction.from_sets(frame, [(["fighter"], 0.7), (["liner"], 0.3)])
    covariance = estimate_covariance(2.0, 1.0)
    engine.apply(
        TrackReport("s1", 0.0, (ReportedTrack("a", np.zeros(4), covariance, class_mass=m1),))
    )
    step = engine.apply(
        TrackReport("s2", 0.5, (ReportedTrack("b", np.zeros(4), covariance, class_mass=m2),))
    )
    expected = fuse_sensor_classes({"s1": m1, "s2": m2}, {"s1": 0.9, "s2": 0.6})
    assert expected is not None and expected.mass is not None
    fused = step.tracks[0].classification
    assert fused is not None and fused.mass is not None
    np.testing.assert_allclose(fused.pignistic, expected.pignistic, atol=1e-15)
    assert fused.conflict == pytest.approx(expected.conflict)
    # Worked by hand: conflict = m1'({b,f}) · m2'({l}) = (0.9·0.6) · (0.6·0.3) = 0.0972.
    assert fused.conflict == pytest.approx(0.0972)
    assert abs(float(np.sum(fused.mass.masses)) - 1.0) < 1e-12


@pytest.mark.parametrize(("radius", "penalised"), [(0.0, True), (2.0, False)])
def test_a_track_hidden_behind_another_is_not_penalised(radius: float, penalised: bool) -> None:
    # s2 looks north from the origin; A at (0, 50) hides B at (0, 100) when objects have a radius.
    fov = Sector(
        origin=(0.0, 0.0), heading_deg=90.0, half_angle_deg=30.0, range_min=0.0, range_max=500.0
    )
    engine = SessionEngine(
        make_config(
            ["s1", SensorSpec("s2", p_detect=0.9, fov=fov)],
            management=LifeCycleConfig(occlusion_radius=radius),
        )
    )
    a, b = [0.0, 0.0, 50.0, 0.0], [0.0, 0.0, 100.0, 0.0]
    engine.apply(report("s1", 0.0, ("a", a), ("b", b)))
    engine.apply(report("s1", 1.0, ("a", a), ("b", b)))
    engine.apply(report("s2", 1.2, ("x", a), ("y", b)))  # s2 has carried both
    before = {track.id: track.score for track in engine.tracks}
    engine.apply(report("s2", 4.0, ("x", a)))  # s2 sees A only; s1 is overdue on both
    after = {track.id: track.score for track in engine.tracks}
    assert (after["F2"] < before["F2"]) is penalised


def test_a_time_too_far_to_predict_to_is_refused_and_changes_nothing() -> None:
    engine = SessionEngine(make_config(["s1", "s2"]))
    engine.apply(report("s1", 1.0, ("a", moving(0.0, 1.0))))
    before = json.dumps(engine.export())
    with pytest.raises(InvalidInput, match=r"time: predicting the tracks over .* overflows"):
        engine.picture(1e200)
    with pytest.raises(InvalidInput, match=r"time: magnitude 1e\+200 is beyond the limit"):
        engine.apply(report("s2", 1e200, ("b", moving(0.0, 1.0))))
    assert json.dumps(engine.export()) == before


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"association_method": "nope"}, "unknown association method 'nope'"),
        ({"association_options": {"gate_probability": 2.0}}, "gate_probability"),
        ({"distance": "euclid"}, "distance must be one of"),
    ],
)
def test_a_bad_association_setting_is_refused_when_the_config_is_made(
    changes: dict[str, object], message: str
) -> None:
    """Not at the first step that runs the method: with continuity that may be never."""
    base = FusionConfig(
        motion=MotionModel(StateLayout(4, (0, 2), (1, 3))), sensors=(SensorSpec("a"),)
    )
    with pytest.raises(InvalidInput, match=message):
        replace(base, **changes)


def test_a_report_whose_fusion_time_cannot_be_reached_changes_nothing() -> None:
    """A late report so far back that its tracks would overflow when predicted to the fusion
    time: refused at the edge (its time is beyond the bound), nothing changes."""
    engine = SessionEngine(make_config(["s1", "s2"]))
    engine.apply(TrackReport("s1", 5.0, ()))
    before = json.dumps(engine.export(), sort_keys=True)
    far_back = TrackReport("s2", -1e300, (ReportedTrack("a", np.zeros(4), np.eye(4)),))
    with pytest.raises(InvalidInput, match="beyond the limit"):
        engine.apply(far_back)
    assert json.dumps(engine.export(), sort_keys=True) == before
    assert engine.seq == 1 and not engine.tracks and engine.last_report == {"s1": 5.0}


def test_a_coasting_track_gates_alike_after_a_restore_that_reorders_its_estimates() -> None:
    """Two sensors' estimates of one time: the newest is chosen by sensor id, not by the order
    the estimates were recorded in (a store writes them with sorted keys)."""
    config = make_config(["s1", "s2", "s3"], method="gnn", options={})

    def report(sensor: str, t: float, sigma: float, tracks: bool = True) -> TrackReport:
        covariance = np.diag([sigma**2, 1.0, sigma**2, 1.0])
        reported = ReportedTrack("a", np.array([10.0 * t, 10.0, 0.0, 0.0]), covariance)
        return TrackReport(sensor, t, (reported,) if tracks else ())

    uninterrupted = SessionEngine(config)
    for t, sensor in ((0.0, "s2"), (0.0, "s1"), (0.5, "s3"), (1.0, "s2"), (1.0, "s1")):
        uninterrupted.apply(report(sensor, t, 1.0 if sensor == "s2" else 5.0))
    restored = SessionEngine.restore(
        config, json.loads(json.dumps(uninterrupted.export(), sort_keys=True))
    )
    assert list(restored.tracks[0].estimates) != list(uninterrupted.tracks[0].estimates)
    for engine in (uninterrupted, restored):
        # s3, which carried it, misses it when s1 and s2 (revisit 1 s) are overdue: a
        # coasting miss, whose gate is the newest estimates' (§8.2)
        engine.apply(report("s3", 5.0, 1.0, tracks=False))
    assert uninterrupted.tracks[0].empty_gate_probability < 1.0
    assert json.dumps(restored.export(), sort_keys=True) == json.dumps(
        uninterrupted.export(), sort_keys=True
    )


def test_status_follows_the_sources_revisits_not_every_report() -> None:
    """§8.6: s1 reports target A every 4 s (its scan at 12 s misses A), s2 reports target B
    every second. Once confirmed, A's track is confirmed at every step until s1 is overdue
    — 2.5 revisits (10 s) after its last report of A, at 20 s — then coasting; B's
    reports never touch A's status. s1 stops after 20 s: after 5 revisits (20 s) without
    any source of A, s2's silence counts (§8.2) and the track ends."""
    engine = SessionEngine(make_config(["s1", "s2"]))
    statuses: list[tuple[float, TrackStatus]] = []
    for step in range(60):
        t = float(step)
        if step % 4 == 0 and step <= 20:
            a = () if step == 12 else (("a", moving(0.0, t)),)
            engine.apply(report("s1", t, *a))
        result = engine.apply(report("s2", t + 0.5, ("b", moving(5000.0, t + 0.5))))
        statuses += [(t + 0.5, view.status) for view in result.tracks if view.id == "F1"]
    confirmed = next(k for k, (_, status) in enumerate(statuses) if status is TrackStatus.CONFIRMED)
    assert statuses[confirmed][0] < 5.0
    for when, status in statuses[confirmed:]:
        if when <= 20.0 + 10.0:  # A's last hit at 20 s (s1's revisit 4 s)
            assert status is TrackStatus.CONFIRMED, when
        elif when < 20.0 + 20.0:
            assert status is TrackStatus.COASTING, when
    # stale after 40 s: s2's lists count misses (P_D 0.9: ln 0.1 each) until the score ends it
    assert statuses[-1][1] is TrackStatus.TERMINATED
    assert 40.0 < statuses[-1][0] < 50.0


def test_a_hand_over_to_a_younger_phantom_keeps_the_older_id() -> None:
    """The fused hand-over merges a phantom and a newly confirmed track under the older id
    (``_merge``'s ``older_keeps``, asked for explicitly, not implied by ``carried``). F1 (a's
    track, the older) and F2 (b's, the younger, made a phantom at F1's place) are one object
    no source is current on both of: F2 ends, F1 keeps its id and takes b's estimate."""
    engine = SessionEngine(make_config(["a", "b"]))
    covariance = np.diag([100.0, 1.0, 100.0, 1.0])
    here, there = np.array([0.0, 0.0, 0.0, 0.0]), np.array([0.0, 0.0, 5000.0, 0.0])
    engine.apply(TrackReport("a", 0.0, (ReportedTrack("x", here, covariance),)))
    engine.apply(TrackReport("b", 0.0, (ReportedTrack("y", there, covariance),)))
    assert [track.id for track in engine.tracks] == ["F1", "F2"]
    # F2 lost in a blind zone, its estimate predicted to where a's newcomer F1 is confirmed
    engine._table.write(np.array([1]), "b", here[None], covariance[None], 0.0)
    life = engine._rows.rows.life
    status = life.status.copy()
    status[:] = [STATUS_CODES[TrackStatus.CONFIRMED], STATUS_CODES[TrackStatus.PHANTOM]]
    engine._rows.rows = engine._rows.rows.living(replace(life, status=status))
    ended = engine._hand_over_to_phantoms(np.array([0]), np.zeros(0, dtype=np.int64))
    assert ended.tolist() == [1]  # F2's row
    assert engine._rows.rows.life.statuses()[0] is TrackStatus.CONFIRMED
    assert set(engine.tracks[0].estimates) == {"a", "b"}
