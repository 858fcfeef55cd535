"""Motion / measurement models, model banks from configuration, presets."""

from __future__ import annotations

import numpy as np
import pytest

from core.belief import Frame
from core.errors import InvalidInput, ModelConfigError
from core.tracking import (
    LinearMeasurementModel,
    ModelBank,
    acceleration_input,
    constant_velocity,
    input_matrix,
    mode_transition_matrix,
    speed_model,
)
from core.tracking.presets import GRAVITY, aircraft, pedestrian, preset


def test_acceleration_input_model_is_mtt_eq_24() -> None:
    model = acceleration_input(2.0, (3.0, -1.0), 0.005, "m")
    b = np.array([[2.0, 0.0], [2.0, 0.0], [0.0, 2.0], [0.0, 2.0]])
    f = np.array([[1, 2, 0, 0], [0, 1, 0, 0], [0, 0, 1, 2], [0, 0, 0, 1]], dtype=float)
    np.testing.assert_array_equal(input_matrix(2.0), b)
    np.testing.assert_array_equal(model.transition, f)
    np.testing.assert_allclose(model.input_offset, [6.0, 6.0, -2.0, -2.0])
    np.testing.assert_allclose(model.process_noise, 0.005 * b @ b.T)


def test_constant_velocity_has_no_input() -> None:
    model = constant_velocity(1.0, 0.1)
    np.testing.assert_array_equal(model.input_offset, np.zeros(4))


def test_speed_model_is_mtt_eq_26() -> None:
    model = speed_model(0.5, (6.0, 2.0), 0.0, "run")
    expected = np.array([[1, 3, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1]], dtype=float)
    np.testing.assert_array_equal(model.transition, expected)
    np.testing.assert_array_equal(model.process_noise, np.zeros((4, 4)))


def test_mode_transition_spreads_the_rest_evenly() -> None:
    matrix = mode_transition_matrix(13, 0.95)
    np.testing.assert_allclose(np.diag(matrix), 0.95)
    np.testing.assert_allclose(matrix[0, 1:], 0.05 / 12)
    np.testing.assert_allclose(matrix.sum(axis=1), 1.0)


def test_bank_from_config_matches_direct_construction() -> None:
    config = {
        "time_interval": 1.0,
        "measurement": {"variance": 0.2},
        "models": [
            {"kind": "constant_velocity", "name": "m1", "noise_intensity": 0.005},
            {
                "kind": "acceleration_input",
                "name": "m2",
                "acceleration": [2 * GRAVITY, 0],
                "noise_intensity": 0.005,
            },
            {"kind": "speed", "name": "walk", "speeds": [2, 0], "noise_intensity": 0.001},
        ],
        "mode_transition": {"stay": 0.9},
    }
    bank = ModelBank.from_config(config)
    assert bank.names == ("m1", "m2", "walk")
    np.testing.assert_allclose(bank.input_offsets[1], [GRAVITY, 2 * GRAVITY, 0, 0])
    np.testing.assert_allclose(bank.mode_transition, mode_transition_matrix(3, 0.9))
    np.testing.assert_array_equal(bank.measurement.matrix, [[1, 0, 0, 0], [0, 0, 1, 0]])


@pytest.mark.parametrize(
    "config",
    [
        {"models": [{"kind": "constant_velocity"}], "colour": "red"},
        {"models": [{"kind": "warp"}]},
        {"models": [{"kind": "speed", "speeds": [1, 2], "spin": 1}]},
        {"models": []},
        {"models": [{"kind": "constant_velocity", "noise_intensity": -1}]},
        {"models": [{"kind": "constant_velocity"}], "measurement": {"variance": 0}},
        {"models": [{"kind": "constant_velocity"}], "mode_transition": [[0.5]]},
        {
            "models": [
                {"kind": "constant_velocity", "name": "a"},
                {"kind": "constant_velocity", "name": "a"},
            ]
        },
    ],
)
def test_bad_bank_config_is_rejected(config: dict[str, object]) -> None:
    with pytest.raises(ModelConfigError):
        ModelBank.from_config(config)


def test_measurement_noise_must_be_positive_definite() -> None:
    with pytest.raises(InvalidInput):
        LinearMeasurementModel(np.eye(2, 4), np.array([[1.0, 2.0], [2.0, 1.0]]))


def test_aircraft_preset() -> None:
    p = aircraft()
    assert p.bank.n_models == 13
    np.testing.assert_allclose(p.bank.measurement.noise_covariance, 0.2 * np.eye(2))
    b = input_matrix(1.0)
    np.testing.assert_allclose(p.bank.process_noises, np.broadcast_to(0.005 * b @ b.T, (13, 4, 4)))
    accelerations = np.array(
        [np.linalg.lstsq(b, m.input_offset, rcond=None)[0] for m in p.bank.models]
    )
    assert sorted(map(tuple, np.round(accelerations / GRAVITY, 9).tolist()))[0] == (-4.0, -4.0)
    # Each behaviour holds exactly the inputs within its class limit ([MTT] eq 25: 0g, 2g, 4g).
    limit = np.abs(accelerations).max(axis=1) / GRAVITY
    for behaviour, bound in zip(p.behaviours.frame.labels, (0.0, 2.0, 4.0), strict=True):
        members = p.behaviours.membership[p.behaviours.frame.index(behaviour)]
        np.testing.assert_array_equal(members, limit <= bound + 1e-9)
    assert p.classes == Frame(["liner", "bomber", "fighter"])
    assert len({tuple(a) for a in accelerations.round(6).tolist()}) == 13


def test_preset_relation_matrices_are_the_printed_ones() -> None:
    # [MTT] §6.1.2 and §6.3.2 (rows: class subsets, columns: behaviour subsets, mask order).
    aircraft_matrix = np.zeros((8, 8))
    aircraft_matrix[0, 0] = aircraft_matrix[4, 4] = aircraft_matrix[6, 2] = aircraft_matrix[
        6, 6
    ] = 1
    aircraft_matrix[7, [1, 3, 5, 7]] = 1
    np.testing.assert_array_equal(aircraft().relation.matrix(), aircraft_matrix)
    pedestrian_matrix = np.zeros((4, 8))
    pedestrian_matrix[0, 0] = pedestrian_matrix[1, 1] = pedestrian_matrix[2, 4] = 1
    pedestrian_matrix[3, [2, 3, 5, 6, 7]] = 1
    np.testing.assert_array_equal(pedestrian().relation.matrix(), pedestrian_matrix)


def test_pedestrian_preset() -> None:
    p = pedestrian()
    assert p.bank.n_models == 7
    assert p.behaviours.frame.labels == ("static", "walking", "running")
    assert p.behaviours.membership.sum(axis=1).tolist() == [1, 3, 3]
    speeds = p.bank.transitions[:, [0, 2], [1, 3]]
    np.testing.assert_array_equal(speeds[6], [6.0, 6.0])
    assert p.velocity_convention == "heading"


def test_preset_by_name_and_options() -> None:
    assert preset("aircraft", stay=0.9).bank.mode_transition[0, 0] == 0.9
    with pytest.raises(ModelConfigError):
        preset("submarine")
    with pytest.raises(ModelConfigError):
        preset("aircraft", warp=1.0)
