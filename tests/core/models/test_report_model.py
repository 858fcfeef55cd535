"""The core uses the measurement model each detection report carries (issue #25).

The range-rate update takes its site and σ from the scan's model (the report's,
``LocalTracker.step(model=…)``), not from a copy in the tracker's configuration: held
against filterpy's EKF at the site of whichever model the scan carries. A central
tracker's reorder buffer re-runs restored scans with their sensor's model (the one
kept on the engine config's sensor entry). A model's arrays are read-only copies.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import orjson
import pytest
from filterpy.kalman import ExtendedKalmanFilter

from api_schemas.config import SessionConfig
from api_schemas.reports import DetectionReport
from app.inputs.detections import core_detection_report
from app.outputs.json_results import step_json
from app.sessions.translate import fusion_config
from core.errors import InvalidInput
from core.fusion.engine import SessionEngine
from core.models.measurement import LinearGaussian, Polar
from core.tracking.config import LocalTrackerConfig
from core.tracking.tracker import LocalTracker
from tests.core.models.snapshot_scenes import geodetic_3d

SIGMA_RATE = 0.5


def _rate_row(x: np.ndarray, site: np.ndarray) -> tuple[float, np.ndarray]:
    """ṙ = (p − s)·v / |p − s| of ``x = [x, ẋ, y, ẏ]`` and its gradient, by central
    differences (independent of the model's analytic row)."""

    def rate(state: np.ndarray) -> float:
        offset = state[[0, 2]] - site
        return float(offset @ state[[1, 3]] / np.linalg.norm(offset))

    columns = []
    for i in range(len(x)):
        up, down = x.copy(), x.copy()
        up[i] += 1e-4
        down[i] -= 1e-4
        columns.append((rate(up) - rate(down)) / 2e-4)
    return rate(x), np.array([columns])


def _tracks(tracker: LocalTracker) -> list[dict[str, Any]]:
    tracks: list[dict[str, Any]] = tracker.export()["tracks"]
    return tracks


@pytest.mark.parametrize("site", [(0.0, 0.0), (25_000.0, -8_000.0)])
def test_the_range_rate_update_is_at_the_site_of_the_scan_s_model(
    site: tuple[float, float],
) -> None:
    """Each model of the track after a scan with a range-rate is filterpy's EKF update, at
    the site and with the σ of the model the scan carries, of the same scan without it."""
    model = Polar.of_axes(site, (30.0**2, np.radians(0.2) ** 2, SIGMA_RATE**2))
    tracker = LocalTracker(LocalTrackerConfig())
    tracker.step(0.0, np.array([[10_000.0, 5_000.0]]))
    scanned = tracker.checkpoint()
    z = np.array([[10_150.0, 4_920.0]])
    measured = -60.0
    assert tracker.step(1.0, z).assignment == ("L1",)
    before, *starts = _tracks(tracker)
    tracker.rollback(scanned)
    tracker.step(1.0, z, range_rates=[measured], model=model)
    after, *same_starts = _tracks(tracker)
    assert before["number"] == after["number"] == 1
    assert same_starts == starts  # the detection's own start takes its position only
    assert len(before["means"]) > 1  # every model of the IMM
    for mean, covariance, got, got_covariance in zip(
        before["means"], before["covariances"], after["means"], after["covariances"], strict=True
    ):
        x = np.array(mean)
        predicted, row = _rate_row(x, np.array(site))
        ekf = ExtendedKalmanFilter(dim_x=4, dim_z=1)
        ekf.x, ekf.P, ekf.R = x.copy(), np.array(covariance), np.eye(1) * SIGMA_RATE**2
        ekf.update(np.array([measured]), lambda _x, h=row: h, lambda _x, v=predicted: np.array([v]))
        assert np.abs(np.array(got) - x).max() > 1.0  # the range-rate moved it
        np.testing.assert_allclose(got, ekf.x, rtol=1e-7, atol=1e-6)
        np.testing.assert_allclose(got_covariance, ekf.P, rtol=1e-6, atol=1e-6)


def test_a_restored_reorder_buffer_reruns_its_scans_with_their_sensors_models() -> None:
    """A central tracker exported with range-rate scans in its reorder buffer and restored
    goes on exactly as the engine that was never exported (results and export, bit for bit):
    the restored scans take their sensor's model from the engine config."""
    config, reports = geodetic_3d(central=True)
    session = SessionConfig.model_validate(config)
    engine = SessionEngine(fusion_config(session))
    cut = 14  # after the late report, put in its place by the buffer
    texts: list[str] = []
    restored: SessionEngine | None = None
    restored_texts: list[str] = []
    for seq, body in enumerate(reports, start=1):
        wire = DetectionReport.model_validate(body)
        texts.append(
            step_json(
                engine.apply_detections(core_detection_report(wire, session, engine.config)), seq
            )
        )
        if restored is not None:
            result = restored.apply_detections(
                core_detection_report(wire, session, restored.config)
            )
            restored_texts.append(step_json(result, seq))
        if seq == cut:
            scans = engine.reorder.scans
            assert scans and all(scan.range_rates is not None for scan in scans)
            state = orjson.loads(orjson.dumps(engine.export(), option=orjson.OPT_SERIALIZE_NUMPY))
            restored = SessionEngine.restore(fusion_config(session), state)
    assert restored is not None
    assert restored_texts == texts[cut:]
    assert orjson.dumps(restored.export(), option=orjson.OPT_SERIALIZE_NUMPY) == orjson.dumps(
        engine.export(), option=orjson.OPT_SERIALIZE_NUMPY
    )


def test_a_range_rate_needs_a_preset_with_velocities_at_session_creation() -> None:
    """A radar with a range-rate on the pedestrian preset (headings, not velocities) is
    refused with the engine config, before any detection."""
    config, _ = geodetic_3d(central=False)
    config["tracking"] = {"preset": "pedestrian"}
    config["state"] = {"dim": 4, "position": [0, 2], "velocity": [1, 3]}
    for sensor in config["sensors"]:
        sensor["measurement"] = {
            key: value
            for key, value in sensor["measurement"].items()
            if key != "sigma_elevation_deg"
        }
    with pytest.raises(InvalidInput, match="headings"):
        fusion_config(SessionConfig.model_validate(config))


def test_a_model_s_arrays_are_its_own_and_read_only() -> None:
    """covar() and the other arrays cannot be written through, and a caller's array given
    to a model stays the caller's (writable, not aliased)."""
    noise = np.diag([4.0, 4.0])
    linear = LinearGaussian.mapped(4, (0, 2), noise)
    site, turn = np.array([10.0, 20.0]), np.array([[1.0, 0.001], [-0.001, 1.0]])
    polar = Polar.of_axes(site, (4.0, 1e-6, 0.25), rotation=turn)
    assert polar.rotation is not None
    arrays = [linear.covar(), linear.matrix, polar.covar(), polar.translation_offset]
    arrays.append(polar.rotation)
    for array in arrays:
        with pytest.raises(ValueError, match="read-only"):
            array[0, ...] = 0.0
    noise[0, 0] = site[0] = turn[0, 0] = 7.0  # the caller's arrays stay writable
    assert linear.covar()[0, 0] == 4.0
    assert polar.translation_offset[0] == 10.0 and polar.rotation[0, 0] == 1.0
