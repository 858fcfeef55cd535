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

from api_schemas.config import SensorConfig, SessionConfig, TrackingConfig, TrackThresholds
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
    """The service passes the wire values on; with none given, both layers get the defaults."""
    config = SessionConfig.model_validate(
        {
            "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
            "sensors": [{"id": "radar", "measurement": {"r": [[1.0, 0.0], [0.0, 1.0]]}}],
        }
    )
    fusion = fusion_config(config)
    assert fusion.management == LifeCycleConfig().for_dimension(2)
    tracker = fusion.sensor("radar").tracker
    assert tracker is not None and tracker.life_cycle == LifeCycleConfig().for_dimension(2)
    assert life_cycle_config(TrackThresholds(), None) == LifeCycleConfig()


def test_a_3d_session_defaults_to_one_false_alarm_and_one_birth_per_cubic_kilometre() -> None:
    config = SessionConfig.model_validate(
        {
            "state": {"dim": 6, "position": [0, 2, 4], "velocity": [1, 3, 5]},
            "sensors": [{"id": "radar", "measurement": {"r": np.eye(3).tolist()}}],
        }
    )
    fusion = fusion_config(config)
    tracker = fusion.sensor("radar").tracker
    assert tracker is not None
    for life in (tracker.life_cycle, fusion.management):
        assert life.false_target_density == pytest.approx(1e-9, rel=1e-12)
        assert life.new_target_density == pytest.approx(1e-9, rel=1e-12)


def test_the_wire_densities_and_initiation_default_to_the_core_s() -> None:
    """``sensors[i].clutter_density``, ``tracking.birth_density`` and ``tracking.initiation``."""
    tracker = LocalTrackerConfig()
    assert SensorConfig(id="s").clutter_density is None  # the dimension's default_density
    tracking = TrackingConfig()
    assert tracking.birth_density is None
    assert tracking.initiation.kind == tracker.initiation
    assert tracking.initiation.max_speed == tracker.max_speed
    assert tracking.initiation.velocity_std == tracker.initial_velocity_std
    single = TrackingConfig.model_validate({"initiation": {"kind": "single_point"}})
    assert single.initiation.velocity_std == tracker.initial_velocity_std


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
                "thresholds": {"score_margin": -6.0, "min_points": 2},
            },
        }
    )
    fusion = fusion_config(config)
    (radar,) = fusion.sensors
    assert radar.tracker is not None
    life = radar.tracker.life_cycle
    assert (life.false_target_density, life.new_target_density) == (3e-5, 2e-7)
    assert (life.score_margin, life.min_points) == (-6.0, 2)
    assert (radar.tracker.initiation, radar.tracker.initial_velocity_std) == ("single_point", 4.0)
    assert fusion.management.new_target_density == 2e-7
    assert fusion.management.false_target_density == 1e-6  # one per km² (2-D default)


def test_a_ceiling_under_the_delete_threshold_is_refused_naming_the_field() -> None:
    with pytest.raises(ValidationError) as refused:
        TrackThresholds.model_validate({"score_margin": -14.0})  # confirm 6.9, delete −6.9
    assert "score_margin" in str(refused.value)


BANK_3D = ModelBank(
    models=(constant_velocity(1.0, 1.0, axes=3, noise="continuous"),),
    measurement=LinearMeasurementModel.position(1.0, 6),
    mode_transition=np.ones((1, 1)),
)


@pytest.mark.parametrize(
    "library",
    [
        LocalTrackerConfig(axes=3),
        LocalTrackerConfig(axes=3, life_cycle=LifeCycleConfig(min_points=3)),
        LocalTrackerConfig(bank=BANK_3D),
    ],
    ids=["preset", "thresholds-only", "bank"],
)
def test_the_library_the_service_and_the_wire_default_a_3d_tracker_alike(
    library: LocalTrackerConfig,
) -> None:
    """A LocalTrackerConfig used directly in 3-D gets the 3-D densities (1e-9 m⁻³, one per
    km³), as the service's tracker of a 3-D session whose wire densities are null."""
    assert (library.life_cycle.false_target_density, library.life_cycle.new_target_density) == (
        1e-9,
        1e-9,
    )
    wire = SessionConfig.model_validate(
        {
            "state": {"dim": 6, "position": [0, 2, 4], "velocity": [1, 3, 5]},
            "sensors": [{"id": "radar", "measurement": {"r": np.eye(3).tolist()}}],
        }
    )
    assert wire.sensors[0].clutter_density is None and wire.tracking.birth_density is None
    service = fusion_config(wire).sensor("radar").tracker
    assert service is not None
    assert service.life_cycle.densities == library.life_cycle.densities
    assert LocalTrackerConfig().life_cycle.densities == (1e-6, 1e-6)  # 2-D: one per km²
    # an explicit density is kept in any dimension
    explicit = LocalTrackerConfig(axes=3, life_cycle=LifeCycleConfig(false_target_density=2e-8))
    assert explicit.life_cycle.densities == (2e-8, 1e-9)
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
