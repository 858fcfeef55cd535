"""Measurement models against Stone Soup 1.9.1 and pymap3d.

Oracles: ``function`` and ``jacobian`` against Stone Soup's ``LinearGaussian``,
``CartesianToBearingRange``, ``CartesianToElevationBearingRange`` and
``CartesianToElevationBearingRangeRate`` on the same states, to 1e-12. Stone Soup
measures ``(elevation, bearing, range[, range-rate])`` with the bearing
counter-clockwise from its x axis; ours is ``(range, azimuth[, elevation][, range-rate])``
with the azimuth clockwise from north, which is Stone Soup's bearing when its x is our
north and its y our east (``mapping = (north, east[, up])``): the tests map one order to
the other. Stone Soup differentiates the two position-only models numerically
(``compute_jac``, off by up to 1e-3 relative on these states): our Jacobians are held to
its analytic ``CartesianToElevationBearingRangeRate``'s instead, whose elevation, bearing
and range rows are theirs (at up = 0 in 2-D). The inverse (a polar
measurement at a geodetic site → a position in the session's ENU frame) against pymap3d's
``aer2geodetic`` then ``geodetic2enu``, which share no formula with the model.
"""

from __future__ import annotations

import math
import typing

import numpy as np
import pymap3d
import pytest
from numpy.testing import assert_allclose
from stonesoup.models.measurement.linear import LinearGaussian as StoneSoupLinearGaussian
from stonesoup.models.measurement.nonlinear import (
    CartesianToBearingRange,
    CartesianToElevationBearingRange,
    CartesianToElevationBearingRangeRate,
)
from stonesoup.types.state import State

from api_schemas.config import MeasurementModel as WireMeasurementModel
from api_schemas.config import SessionConfig
from api_schemas.reports import DetectionReport as WireDetectionReport
from app.geo.geodesy import LocalFrame
from app.inputs.detections import core_detection_report
from app.sessions.translate import fusion_config, measurement_model
from core.errors import ModelConfigError
from core.models import MEASUREMENT_MODELS
from core.models.measurement import ConvertedModel, LinearGaussian, MeasurementModel, Polar
from tests.core.models.snapshot_scenes import geodetic_3d

RNG_STATES = 40


def _states(dim: int, seed: int) -> np.ndarray:
    """States ``[x, ẋ, y, ẏ(, z, ż)]`` of aircraft within 60 km of a site, (N, 2·dim)."""
    rng = np.random.default_rng(seed)
    states = np.zeros((RNG_STATES, 2 * dim))
    states[:, 0::2] = rng.uniform(-60_000.0, 60_000.0, (RNG_STATES, dim))
    states[:, 1::2] = rng.uniform(-300.0, 300.0, (RNG_STATES, dim))
    if dim == 3:
        states[:, 4] = rng.uniform(-500.0, 12_000.0, RNG_STATES)
    return states


SITE_2D = (1500.0, -700.0)
SITE_3D = (1500.0, -700.0, 35.0)
SIGMAS = (20.0**2, np.radians(0.2) ** 2, np.radians(0.3) ** 2, 1.5**2)


def _stone_soup_order(dim: int, rate: bool) -> list[int]:
    """Where each of Stone Soup's components (elevation, bearing, range, rate) is in ours."""
    order = [2, 1, 0] if dim == 3 else [1, 0]
    return order + ([dim] if rate else [])


def test_linear_gaussian_is_stone_soups() -> None:
    """H x, H and R of a position mapping of any dimension, against Stone Soup's."""
    rng = np.random.default_rng(1)
    for ndim_state, mapping in ((4, (0, 2)), (6, (0, 2, 4)), (9, (0, 3, 6)), (2, (0,))):
        noise = np.diag(rng.uniform(1.0, 50.0, len(mapping)))
        ours = LinearGaussian.mapped(ndim_state, mapping, noise)
        theirs = StoneSoupLinearGaussian(ndim_state=ndim_state, mapping=mapping, noise_covar=noise)
        states = rng.normal(0.0, 1000.0, (7, ndim_state))
        expected = np.stack([theirs.function(State(x[:, None])).ravel() for x in states])
        assert_allclose(ours.function(states), expected, rtol=1e-12, atol=0)
        assert_allclose(
            ours.jacobian(states), np.broadcast_to(theirs.matrix(), (7, *theirs.matrix().shape))
        )
        assert_allclose(ours.covar(), theirs.covar())
        assert (ours.ndim_meas, ours.ndim_state, ours.mapping) == (
            theirs.ndim_meas,
            ndim_state,
            mapping,
        )
        assert isinstance(ours, MeasurementModel) and not isinstance(ours, ConvertedModel)


@pytest.mark.parametrize("dim", [2, 3])
def test_polar_function_is_stone_soups(dim: int) -> None:
    """(ρ, a[, e]) of 40 states, against Stone Soup's range-bearing models on the same states."""
    site = SITE_2D if dim == 2 else SITE_3D
    ours = Polar.of_axes(site, SIGMAS[:dim])
    ss_mapping = (2, 0) if dim == 2 else (2, 0, 4)  # (north, east[, up]): bearing = azimuth
    order = _stone_soup_order(dim, rate=False)
    noise = np.diag(np.asarray(SIGMAS[:dim])[order])
    model = CartesianToBearingRange if dim == 2 else CartesianToElevationBearingRange
    translation = np.array(site)[[1, 0, 2][:dim]][:, None]
    theirs = model(
        ndim_state=2 * dim, mapping=ss_mapping, noise_covar=noise, translation_offset=translation
    )
    states = _states(dim, seed=dim)
    measured = ours.function(states)
    for state, ours_z in zip(states, measured, strict=True):
        expected = np.asarray(theirs.function(State(state[:, None])), dtype=float).ravel()
        # wrap Stone Soup's angles (−π, π] as ours are
        assert_allclose(ours_z[order], expected, rtol=1e-12, atol=1e-12)
    assert_allclose(ours.covar()[np.ix_(order, order)], theirs.covar(), rtol=1e-15)


@pytest.mark.parametrize("dim", [2, 3])
def test_polar_with_range_rate_and_its_jacobian_are_stone_soups(dim: int) -> None:
    """(ρ, a[, e], ṙ) and the analytic Jacobian of Stone Soup's
    ``CartesianToElevationBearingRangeRate`` (a planar radar is its 3-D one at up = 0 with
    no vertical velocity: its elevation row is dropped), to 1e-12."""
    site = SITE_2D if dim == 2 else SITE_3D
    ours = Polar.of_axes(site, (*SIGMAS[:dim], SIGMAS[3]))
    assert ours.ndim_meas == dim + 1
    noise = np.diag([SIGMAS[2], SIGMAS[1], SIGMAS[0], SIGMAS[3]])
    theirs = CartesianToElevationBearingRangeRate(
        ndim_state=6,
        mapping=(2, 0, 4),
        velocity_mapping=(3, 1, 5),
        noise_covar=noise,
        translation_offset=np.array([site[1], site[0], site[2] if dim == 3 else 0.0])[:, None],
    )
    states = _states(dim, seed=10 + dim)
    full = states if dim == 3 else np.concatenate([states, np.zeros((len(states), 2))], axis=1)
    rows = [0, 1, 2, 3] if dim == 3 else [1, 2, 3]  # Stone Soup's rows that we have
    columns = slice(None) if dim == 3 else slice(0, 4)
    order = _stone_soup_order(dim, rate=True)
    measured, jacobians = ours.function(states), ours.jacobian(states)
    for state, ours_z, ours_j in zip(full, measured, jacobians, strict=True):
        expected = np.asarray(theirs.function(State(state[:, None])), dtype=float).ravel()[rows]
        assert_allclose(ours_z[order], expected, rtol=1e-12, atol=1e-12)
        analytic = np.asarray(theirs.jacobian(State(state[:, None])), dtype=float)
        assert_allclose(ours_j[order], analytic[rows][:, columns], rtol=1e-12, atol=1e-15)


def test_rotated_site_measures_in_its_own_axes() -> None:
    """A site whose axes are turned: the model of the turned offset is the unturned model's
    of the offset expressed in the site's axes (h(x) = h₀(Rᵀ(p − s))), its Jacobian J₀ Rᵀ."""
    angle = np.radians(25.0)
    turn = np.array(
        [
            [np.cos(angle), -np.sin(angle), 0.0],
            [np.sin(angle), np.cos(angle), 0.0],
            [0.0, 0.0, 1.0],
        ]
    )
    turned = Polar.of_axes(SITE_3D, (*SIGMAS[:3], SIGMAS[3]), rotation=turn)
    plain = Polar.of_axes((0.0, 0.0, 0.0), (*SIGMAS[:3], SIGMAS[3]))
    states = _states(3, seed=5)
    local = states.copy()
    local[:, 0::2] = (states[:, 0::2] - np.array(SITE_3D)) @ turn
    local[:, 1::2] = states[:, 1::2] @ turn
    assert_allclose(turned.function(states), plain.function(local), rtol=1e-12, atol=1e-9)
    expected = plain.jacobian(local)
    expected[:, :3, 0::2] = expected[:, :3, 0::2] @ turn.T
    expected[:, 3, 0::2] = expected[:, 3, 0::2] @ turn.T
    expected[:, 3, 1::2] = expected[:, 3, 1::2] @ turn.T
    assert_allclose(turned.jacobian(states), expected, rtol=1e-10, atol=1e-15)


def test_geodetic_inverse_is_pymap3d() -> None:
    """A radar at a geodetic site, its measurements converted into the session's ENU frame
    at another origin: pymap3d's ``aer2geodetic`` then ``geodetic2enu``, to a millimetre;
    and ``function`` of the converted position gives the measurement back."""
    origin = (52.0, 4.0, 0.0)
    site = (52.2, 4.1, 40.0)
    frame = LocalFrame(*origin)
    position = frame.from_geodetic(site[0], site[1], site[2])
    rotation = frame.rotation_from(site[0], site[1])[0]
    model = Polar.of_axes(tuple(position[0]), SIGMAS[:3], rotation=rotation)
    rng = np.random.default_rng(7)
    ranges = rng.uniform(1_000.0, 80_000.0, 25)
    azimuths = rng.uniform(-np.pi, np.pi, 25)
    elevations = rng.uniform(-0.02, 0.6, 25)
    measurements = np.stack([ranges, azimuths, elevations], axis=-1)
    positions, covariances, rates = model.converted(measurements)
    assert rates is None
    for (rho, azimuth, elevation), converted in zip(measurements, positions, strict=True):
        target = pymap3d.aer2geodetic(
            np.degrees(azimuth), np.degrees(elevation), rho, *site, deg=True
        )
        expected = pymap3d.geodetic2enu(*target, *origin, deg=True)
        assert_allclose(converted, expected, rtol=0, atol=1e-3)
    states = np.insert(positions, [1, 2, 3], 0.0, axis=1)  # [x, 0, y, 0, z, 0]
    assert_allclose(model.function(states), measurements, rtol=1e-12, atol=1e-9)
    assert_allclose(model.inverse_function(measurements), positions)
    # the covariance mapped back through the model's Jacobian is the noise again
    jacobians = model.jacobian(states)[:, :, 0::2]
    back = jacobians @ covariances @ np.swapaxes(jacobians, -1, -2)
    scale = 1.0 / np.sqrt(np.asarray(SIGMAS[:3]))
    assert_allclose(
        back * np.outer(scale, scale), np.broadcast_to(np.eye(3), back.shape), atol=1e-9
    )


def test_range_rates_ride_with_the_conversion() -> None:
    """The range-rate column comes out as the detections' range-rates (NaN: none), None
    when no detection has one."""
    model = Polar.of_axes(SITE_2D, (*SIGMAS[:2], SIGMAS[3]))
    z = np.array([[1000.0, 0.1, -3.0], [2000.0, 0.2, np.nan]])
    rates = model.converted(z)[2]
    assert rates is not None
    assert_allclose(rates, [-3.0, np.nan])
    z[0, 2] = np.nan
    assert model.converted(z)[2] is None


def test_registry_builds_each_kind_from_the_wire_parameters() -> None:
    """The registry names the wire's kinds (every member of the wire's measurement union)
    and builds each from a site and the wire's parameters (angles in degrees there,
    radians in the model); a polar model refuses what it cannot measure."""
    members = typing.get_args(typing.get_args(WireMeasurementModel)[0])
    kinds = {
        typing.get_args(typing.get_args(member)[0].model_fields["kind"].annotation)[0]
        for member in members
    }
    assert set(MEASUREMENT_MODELS) == kinds == {"cartesian", "polar"}
    site = np.array(SITE_3D)
    radar = MEASUREMENT_MODELS["polar"](
        site,
        None,
        sigma_range=20.0,
        sigma_azimuth_deg=0.2,
        sigma_elevation_deg=0.3,
        sigma_range_rate=1.5,
    )
    assert isinstance(radar, ConvertedModel)
    assert_allclose(radar.covar(), np.diag(SIGMAS), rtol=1e-15)
    planar = MEASUREMENT_MODELS["polar"](site[:2], None, sigma_range=20.0, sigma_azimuth_deg=0.2)
    assert (planar.ndim_state, planar.ndim_meas, planar.mapping) == (4, 2, (0, 2))
    camera = MEASUREMENT_MODELS["cartesian"](site, None, r=np.eye(3).tolist())
    assert (camera.ndim_state, camera.ndim_meas, camera.mapping) == (6, 3, (0, 2, 4))
    with pytest.raises(ModelConfigError, match="sigma_elevation_deg"):
        MEASUREMENT_MODELS["polar"](site, None, sigma_range=20.0, sigma_azimuth_deg=0.2)
    with pytest.raises(ModelConfigError, match="2 or 3"):
        Polar.of_axes((0.0,), (1.0, 1.0))
    with pytest.raises(ModelConfigError, match="shape"):
        Polar(4, (0, 2), np.eye(3), np.zeros(2))
    with pytest.raises(ModelConfigError, match="lie in"):
        Polar(4, (0, 4), np.eye(2), np.zeros(2))
    with pytest.raises(ModelConfigError, match="diagonal"):
        Polar(4, (0, 2), np.array([[1.0, 0.1], [0.1, 1.0]]), np.zeros(2))


def test_a_detection_report_carries_its_sensors_model() -> None:
    """Wire detections of a geodetic radar become a core report whose model is the
    sensor's (built once with the engine's config, kept on its sensor entry), whose
    positions are that model's conversion of the measured range, azimuth, elevation and
    range-rate."""
    config, reports = geodetic_3d(central=False)
    session = SessionConfig.model_validate(config)
    engine_config = fusion_config(session)
    first, second = (
        core_detection_report(WireDetectionReport.model_validate(body), session, engine_config)
        for body in (reports[0], reports[2])  # the same radar, two scans
    )
    assert isinstance(first.model, Polar) and first.model is second.model
    assert first.model is engine_config.sensor(session.sensors[0].id).model
    assert first.model.velocity_mapping == (1, 3, 5)
    body = reports[0]["detections"][0]
    z = np.array(
        [
            body["range"],
            np.radians(body["azimuth_deg"]),
            np.radians(body["elevation_deg"]),
            body["range_rate"],
        ]
    )
    position, covariance, _ = first.model.converted(z[None, :])
    assert_allclose(first.measurements[0], position[0], rtol=0, atol=0)
    assert first.covariances is not None and first.range_rates is not None
    assert_allclose(first.covariances[0], covariance[0], rtol=0, atol=0)
    assert first.range_rates[0] == body["range_rate"]
    again = SessionConfig.model_validate(config)  # another session: its own model
    assert fusion_config(again).sensor(again.sensors[0].id).model is not first.model


@pytest.mark.parametrize(
    ("name", "sigma", "square"),
    [
        # IEEE doubles, by hand: 1e-170² = 1e-340 is below the least subnormal (4.9e-324), so
        # 0; 1e200² = 1e400 is beyond the largest double (1.8e308), so it overflows
        ("sigma_range", 1e-170, 0.0),
        ("sigma_range", 1e200, math.inf),
        ("sigma_azimuth_deg", 1e-170, 0.0),  # 1.7e-172 rad
        ("sigma_azimuth_deg", 1e200, math.inf),
        ("sigma_elevation_deg", 1e-170, 0.0),
        ("sigma_range_rate", 1e200, math.inf),
    ],
)
def test_a_sigma_without_a_usable_variance_is_refused_at_its_name(
    name: str, sigma: float, square: float
) -> None:
    """A σ whose square underflows to 0 or overflows gives no covariance: refused, located
    at the wire's parameter (the service prefixes the sensor's measurement)."""
    given = {
        "sigma_range": 20.0,
        "sigma_azimuth_deg": 0.2,
        "sigma_elevation_deg": 0.3,
        "sigma_range_rate": 1.5,
    }
    given[name] = sigma
    with pytest.raises(ModelConfigError, match=f"its square is {square!r}") as refused:
        Polar.for_sensor(np.array(SITE_3D), None, **given)
    assert refused.value.loc == (name,)


def test_a_planar_radar_at_a_geodetic_site_measures_what_pymap3d_places() -> None:
    """A 2-D session's radar at a geodetic site 84 km from the origin, built as the service
    builds it: the point pymap3d places at (ρ, a) and elevation 0 from the site
    (``aer2geodetic``, then ``geodetic2enu`` at the origin), in the session's plane, is the
    model's conversion, and the model's ``h`` of it is (ρ, a) again. The site's axes in the
    plane are the horizontal block of a 3-D rotation, not orthonormal (|RᵀR − I| ≈ 1e-4):
    ``h`` through ``rotationᵀ`` was off by up to 9 m and 0.005° here."""
    origin, site = (52.0, 4.0, 0.0), (52.5, 5.0, 0.0)
    session = SessionConfig.model_validate(
        {
            "origin": dict(zip(("lat", "lon", "alt"), origin, strict=True)),
            "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
            "sensors": [
                {
                    "id": "radar",
                    "site": dict(zip(("lat", "lon", "alt"), site, strict=True)),
                    "measurement": {"kind": "polar", "sigma_range": 20.0, "sigma_azimuth_deg": 0.2},
                }
            ],
        }
    )
    model = measurement_model(session, session.sensors[0])
    assert isinstance(model, Polar) and model.rotation is not None
    azimuths = np.radians([0.0, 45.0, 90.0, 135.0, 180.0, -90.0, -30.0])
    measurements = np.stack([np.full(len(azimuths), 50_000.0), azimuths], axis=-1)
    placed = np.array(
        [
            pymap3d.geodetic2enu(
                *pymap3d.aer2geodetic(np.degrees(a), 0.0, rho, *site, deg=True), *origin
            )[:2]
            for rho, a in measurements
        ]
    )
    assert_allclose(model.converted(measurements)[0], placed, rtol=0, atol=1e-3)
    states = np.insert(placed, [1, 2], 0.0, axis=1)  # [x, 0, y, 0]
    measured = model.function(states)
    assert_allclose(measured[:, 0], measurements[:, 0], rtol=0, atol=1e-3)
    turned = np.angle(np.exp(1j * (measured[:, 1] - measurements[:, 1])))  # 180° is −180°
    assert_allclose(turned, 0.0, rtol=0, atol=1e-9)
