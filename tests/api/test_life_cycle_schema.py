"""The wire's life-cycle thresholds and the core's life cycle are one fact: names, defaults, ranges.

``api_schemas.config.TrackThresholds`` is what a client posts, ``core.lifecycle.LifeCycleConfig``
what both layers run; a default or a bound changed on one side only fails here.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from pydantic import ValidationError

from api_schemas.config import (
    SensorConfig,
    SessionConfig,
    TrackingConfig,
    TrackThresholds,
    TwoPointInitiation,
)
from app.sessions.translate import fusion_config, life_cycle_config
from core.errors import InvalidInput
from core.lifecycle import LifeCycleConfig
from core.tracking.config import LocalTrackerConfig
from core.tracking.models import LinearMeasurementModel, ModelBank, constant_velocity
from core.tracking.tracker import LocalTracker

CORE_DEFAULTS = {field.name: field.default for field in dataclasses.fields(LifeCycleConfig)}
PROBES: dict[str, list[object]] = {
    "float": [-1.0, -1e-300, 0.0, 1e-300, 1e-3, 0.5, 1.0 - 1e-16, 1.0, 1.5, math.nan, math.inf],
    "int": [-1, 0, 1, 2, 99, 100, 101, 10**6, None],
}


def test_every_wire_threshold_is_a_life_cycle_field_with_the_same_default() -> None:
    wire = TrackThresholds()
    assert set(TrackThresholds.model_fields) <= set(CORE_DEFAULTS)
    for name in TrackThresholds.model_fields:
        assert getattr(wire, name) == CORE_DEFAULTS[name], name


@pytest.mark.parametrize("name", sorted(TrackThresholds.model_fields))
def test_the_wire_and_the_core_accept_the_same_values(name: str) -> None:
    kind = "int" if name == "min_points" else "float"
    for value in PROBES[kind]:
        try:
            TrackThresholds.model_validate({name: value})
            wire_accepts = True
        except ValidationError:
            wire_accepts = False
        try:
            LifeCycleConfig(**{name: value})  # type: ignore[arg-type]
            core_accepts = True
        except InvalidInput:
            core_accepts = False
        assert wire_accepts == core_accepts, (name, value, wire_accepts, core_accepts)


def test_a_session_without_thresholds_runs_the_core_defaults_in_both_layers() -> None:
    """The service passes the wire values on; with none given, both layers get the defaults:
    the local tracker estimates its clutter density, the fused layer takes one per km²."""
    config = SessionConfig.model_validate(
        {
            "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
            "sensors": [{"id": "radar", "measurement": {"r": [[1.0, 0.0], [0.0, 1.0]]}}],
        }
    )
    fusion = fusion_config(config)
    assert fusion.management == LifeCycleConfig().for_dimension(2)
    tracker = fusion.sensor("radar").tracker
    assert tracker is not None and tracker.life_cycle == LifeCycleConfig()
    assert tracker.physics("radar") == (0.9, None)  # None: estimated from the detections
    assert life_cycle_config(TrackThresholds(), None) == LifeCycleConfig()


def test_a_3d_session_s_fused_layer_defaults_to_one_false_alarm_per_cubic_kilometre() -> None:
    config = SessionConfig.model_validate(
        {
            "state": {"dim": 6, "position": [0, 2, 4], "velocity": [1, 3, 5]},
            "sensors": [{"id": "radar", "measurement": {"r": np.eye(3).tolist()}}],
        }
    )
    fusion = fusion_config(config)
    tracker = fusion.sensor("radar").tracker
    assert tracker is not None and tracker.physics("radar") == (0.9, None)  # estimated
    assert fusion.management.false_target_density == pytest.approx(1e-9, rel=1e-12)
    assert fusion.management.new_target_density == pytest.approx(1e-9, rel=1e-12)


def test_the_paper_profile_fills_the_papers_values_and_its_resolved_config_round_trips() -> None:
    body = {
        "state": {"dim": 6, "position": [0, 2, 4], "velocity": [1, 3, 5]},
        "sensors": [{"id": "radar", "measurement": {"r": np.eye(3).tolist()}}],
        "tracking": {"profile": "paper", "thresholds": {"min_points": 3}},
    }
    config = SessionConfig.model_validate(body)
    tracking = config.tracking
    assert tracking.initiation.kind == "two_point"
    assert tracking.thresholds.min_points == 3  # given: kept
    assert tracking.thresholds.score_ceiling == pytest.approx(math.log(0.999 / 0.001))
    again = SessionConfig.model_validate(config.model_dump())
    assert again == config
    tracker = fusion_config(config).sensor("radar").tracker
    assert tracker is not None
    assert tracker.life_cycle == LifeCycleConfig.paper(3, min_points=3)
    assert (tracker.initiation, tracker.initial_velocity_std) == ("two_point", 300.0)


def test_the_wire_densities_and_initiation_default_to_the_core_s() -> None:
    """``sensors[i].clutter_density``, ``tracking.birth_density`` and ``tracking.initiation``."""
    tracker = LocalTrackerConfig()
    assert SensorConfig(id="s").clutter_density is None  # estimated
    tracking = TrackingConfig()
    assert tracking.birth_density is None
    assert tracking.initiation.kind == tracker.initiation == "single_point"
    assert tracking.initiation.velocity_std is tracker.initial_velocity_std is None
    paper = LocalTrackerConfig.paper()
    two_point = TrackingConfig.model_validate({"initiation": {"kind": "two_point"}}).initiation
    assert isinstance(two_point, TwoPointInitiation)
    assert (two_point.max_speed, two_point.velocity_std) == (
        paper.max_speed,
        paper.initial_velocity_std,
    )


def test_the_densities_and_initiation_reach_the_local_tracker() -> None:
    config = SessionConfig.model_validate(
        {
            "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
            "sensors": [
                {
                    "id": "radar",
                    "clutter_density": 3e-5,
                    "measurement": {"r": [[1.0, 0.0], [0.0, 1.0]]},
                }
            ],
            "tracking": {
                "birth_density": 2e-7,
                "initiation": {"kind": "single_point", "velocity_std": 4.0},
                "thresholds": {"score_ceiling": 2.0, "min_points": 3},
            },
        }
    )
    fusion = fusion_config(config)
    (radar,) = fusion.sensors
    assert radar.tracker is not None
    life = radar.tracker.life_cycle
    assert (life.false_target_density, life.new_target_density) == (3e-5, 2e-7)
    assert (life.score_ceiling, life.min_points) == (2.0, 3)
    assert (radar.tracker.initiation, radar.tracker.initial_velocity_std) == ("single_point", 4.0)
    assert fusion.management.new_target_density == 2e-7
    assert fusion.management.false_target_density == 1e-6  # one per km² (2-D default)
    assert radar.tracker.physics("radar") == (0.9, 3e-5)


def test_a_ceiling_under_the_delete_threshold_is_refused_naming_the_field() -> None:
    with pytest.raises(ValidationError) as refused:
        TrackThresholds.model_validate({"score_ceiling": -7.0})  # delete −6.9
    assert "score_ceiling" in str(refused.value)


BANK_3D = ModelBank(
    models=(constant_velocity(1.0, 1.0, axes=3, noise="continuous"),),
    measurement=LinearMeasurementModel.position(1.0, 6),
    mode_transition=np.ones((1, 1)),
)


def test_the_library_the_service_and_the_wire_default_a_3d_tracker_alike() -> None:
    """A LocalTrackerConfig used directly in 3-D, and the service's tracker of a 3-D session
    whose wire densities are null, both estimate β_FT and take β_NT = β_FT; the paper
    profile's are one per km³ (1e-9 m⁻³)."""
    wire = SessionConfig.model_validate(
        {
            "state": {"dim": 6, "position": [0, 2, 4], "velocity": [1, 3, 5]},
            "sensors": [{"id": "radar", "measurement": {"r": np.eye(3).tolist()}}],
        }
    )
    assert wire.sensors[0].clutter_density is None and wire.tracking.birth_density is None
    service = fusion_config(wire).sensor("radar").tracker
    assert service is not None
    library = LocalTrackerConfig(bank=BANK_3D)
    assert service.life_cycle == library.life_cycle == LifeCycleConfig()
    assert LocalTrackerConfig.paper(axes=3).life_cycle.densities == (1e-9, 1e-9)
    assert LocalTrackerConfig.paper(bank=BANK_3D).life_cycle.densities == (1e-9, 1e-9)
    assert LocalTrackerConfig.paper().life_cycle.densities == (1e-6, 1e-6)  # 2-D: one per km²
    with pytest.raises(InvalidInput, match="for_dimension"):
        LifeCycleConfig().score_model(0.9)


def test_a_3d_tracker_with_the_library_defaults_confirms_a_target() -> None:
    """At the 2-D default read as m⁻³ no 3-D hit raised the score (tests/core/tracking/
    test_tracker_3d_score.py); with the library's own default the target confirms."""
    tracker = LocalTracker(
        LocalTrackerConfig(bank=BANK_3D, measurement_noise=tuple(map(tuple, 900.0 * np.eye(3))))
    )
    start, velocity = np.array([20_000.0, 1_000.0, 5_000.0]), np.array([-200.0, 50.0, 10.0])
    statuses = [
        [t.status.value for t in tracker.step(float(k), (start + velocity * k)[None]).tracks]
        for k in range(8)
    ]
    assert ["confirmed"] in statuses, statuses
