"""Plausibility rules: implausible but legal values, as warnings (README "Warnings").

The one place for them. Each :class:`Rule` looks at a session config or at
one input under its config and yields :class:`~api_schemas.warnings.FieldWarning`
entries located in the body that carried the value. A warning is an
annotation only: nothing here changes a config, an input or a step (the
service applies exactly what it would without the rules; a test proves it).

The thresholds, each a documented constant:

- :data:`FAR_M` (1 000 km): a site, a field of view's apex or a track this far
  from the session's origin (or a site this far from every other site, without
  an origin) is flagged; for a geodetic value the warning says which likely
  mistake would bring it near: lat/lon swapped, the origin in radians, the
  origin's lat/lon swapped, the value in radians;
- :data:`MIN_SIGMA_RANGE_M` (1 m): a radar's range σ below it looks like km; above
  :data:`MAX_SIGMA_RANGE_M` (1 km), like cm or mm;
- :data:`MIN_SIGMA_RANGE_RATE_MPS` (0.01 m/s) and :data:`MAX_SIGMA_RANGE_RATE_MPS` (100 m/s): a
  range-rate σ below looks like km/s, above like cm/s;
- :data:`MIN_SIGMA_ANGLE_DEG` (0.02°) and :data:`MAX_SIGMA_ANGLE_DEG` (10°):
  an angle σ below looks like radians, above like milliradians (every angle
  of the API is in degrees);
- :data:`MIN_RANGE_CELLS` (100): a radar's field of view reaching fewer
  range σs than this looks like a range in km;
- :data:`RADIAN_AZIMUTH_BATCH` (5): that many polar detections of one batch,
  every azimuth within ±2π, look like radians;
- a polar detection inside its sector's minimum range (the blind range), or
  nearer than one ``sigma_range``;
- :data:`MAX_WARNINGS` (20) per answer, then one that counts the rest.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from api_schemas.config import (
    GeodeticPoint,
    PolarMeasurement,
    SectorFieldOfView,
    SensorConfig,
    SessionConfig,
)
from api_schemas.reports import CartesianDetection, DetectionReport, PolarDetection, TrackReport
from api_schemas.warnings import FieldWarning, SitePlacement
from app.errors import pointer
from app.geo.geodesy import LocalFrame
from app.sessions.translate import sensor_site, session_origin

FAR_M = 1_000_000.0
"""A site, apex or track this far from the origin (m) is flagged (1 000 km)."""
MIN_SIGMA_RANGE_M = 1.0
"""A radar's range σ below this (m) looks like km (radars: metres to hundreds of metres)."""
MAX_SIGMA_RANGE_M = 1000.0
"""A radar's range σ above this (m) looks like cm or mm (the wire refuses it above 100 km)."""
MIN_SIGMA_RANGE_RATE_MPS = 0.01
"""A range-rate σ below this (m/s) looks like km/s (a Doppler σ: tenths of m/s to a few m/s)."""
MAX_SIGMA_RANGE_RATE_MPS = 100.0
"""A range-rate σ above this (m/s) looks like cm/s."""
MIN_SIGMA_ANGLE_DEG = 0.02
"""An angle σ below this (°) looks like radians (0.02 rad = 1.1°, a plausible radar σ)."""
MAX_SIGMA_ANGLE_DEG = 10.0
"""An angle σ above this (°) looks like milliradians (17 mrad = 1°)."""
MIN_RANGE_CELLS = 100.0
"""A radar's field of view reaching fewer range σs than this looks like a range in km."""
RADIAN_AZIMUTH_BATCH = 5
"""At least this many polar detections, every azimuth within ±2π (°): radians? (Detections
spread over a scan fall there together with probability (4π/360)^5 ≈ 5e-8.)"""
MAX_WARNINGS = 20
"""Warnings listed per answer; beyond, one more counts the rest (code ``more_warnings``)."""
EARTH_RADIUS_M = 6_371_000.0
"""Mean Earth radius: the great-circle distances that only choose a warning's hint."""

Location = tuple[str | int, ...]


def warning(loc: Location, code: str, message: str) -> FieldWarning:
    """A warning at ``loc`` in the body (its problem+json-style pointer)."""
    return FieldWarning(pointer=pointer(loc, code), code=code, message=message)


@dataclass(frozen=True)
class Rule:
    """One plausibility check: the codes it may give, what it flags, and the check."""

    codes: tuple[str, ...]
    flags: str
    check: Callable[..., Iterable[FieldWarning]]


CONFIG_RULES: list[Rule] = []
"""Rules of a session config: ``check(config, origin)``."""
INPUT_RULES: dict[str, list[Rule]] = {}
"""Input kind tag → rules of its inputs: ``check(report, config)``."""


def config_rule(
    *codes: str, flags: str
) -> Callable[[Callable[..., Iterable[FieldWarning]]], Callable[..., Iterable[FieldWarning]]]:
    """Register a config rule (a decorator)."""

    def register(check: Callable[..., Iterable[FieldWarning]]) -> Callable[..., Any]:
        CONFIG_RULES.append(Rule(codes, flags, check))
        return check

    return register


def input_rule(
    tag: str, *codes: str, flags: str
) -> Callable[[Callable[..., Iterable[FieldWarning]]], Callable[..., Iterable[FieldWarning]]]:
    """Register a rule of the inputs of kind ``tag`` (a decorator)."""

    def register(check: Callable[..., Iterable[FieldWarning]]) -> Callable[..., Any]:
        INPUT_RULES.setdefault(tag, []).append(Rule(codes, flags, check))
        return check

    return register


def capped(found: Iterable[FieldWarning]) -> list[FieldWarning]:
    """The first :data:`MAX_WARNINGS`, then one that counts the rest."""
    listed: list[FieldWarning] = []
    more = 0
    for entry in found:
        if len(listed) < MAX_WARNINGS:
            listed.append(entry)
        else:
            more += 1
    if more:
        listed.append(
            FieldWarning(pointer="#", code="more_warnings", message=f"and {more} more warnings")
        )
    return listed


def config_warnings(config: SessionConfig) -> list[FieldWarning]:
    """Every warning of a session config (pointers into ``POST /v1/sessions``'s body)."""
    origin = session_origin(config)
    return capped(entry for rule in CONFIG_RULES for entry in rule.check(config, origin))


def input_warnings(tag: str, report: Any, config: SessionConfig) -> list[FieldWarning]:
    """Every warning of an input of kind ``tag`` under its session's config (pointers into
    the input's body)."""
    rules = INPUT_RULES.get(tag, ())
    return capped(entry for rule in rules for entry in rule.check(report, config))


def site_placements(config: SessionConfig) -> list[SitePlacement]:
    """Each configured sensor's site in the session frame and its distance from the origin."""
    origin = session_origin(config)
    placements = []
    for sensor in config.sensors:
        position, heading = sensor_site(sensor, origin)
        placements.append(
            SitePlacement(
                sensor=sensor.id,
                position=[float(value) for value in position],
                distance=float(np.linalg.norm(position)),
                heading_deg=heading,
            )
        )
    return placements


# ------------------------------------------------------------------ distances and hints
def km(metres: float) -> str:
    """A distance for people: ``4812 km``, ``40.3 km``, ``850 m``."""
    if metres >= 100_000:
        return f"{metres / 1000:.0f} km"
    if metres >= 1000:
        return f"{metres / 1000:.1f} km"
    return f"{metres:.0f} m"


def great_circle(
    lat: np.ndarray | float, lon: np.ndarray | float, lat0: float, lon0: float
) -> np.ndarray:
    """Great-circle distance (m, haversine on the mean sphere) between points and a point (°)."""
    phi, phi0 = np.radians(lat), math.radians(lat0)
    half_dphi = (phi - phi0) / 2
    half_dlambda = np.radians(np.asarray(lon) - lon0) / 2
    a = np.sin(half_dphi) ** 2 + np.cos(phi) * math.cos(phi0) * np.sin(half_dlambda) ** 2
    return np.asarray(2 * EARTH_RADIUS_M * np.arcsin(np.sqrt(np.clip(a, 0.0, 1.0))))


def _hint(lat: float, lon: float, origin: GeodeticPoint) -> tuple[str, str] | None:
    """The likely mistake that would bring the far point ``(lat, lon)`` within :data:`FAR_M`
    of ``origin``: ``(code, words)``, or ``None``."""
    candidates: list[tuple[str, str, float, float, float, float]] = []
    if abs(lon) <= 90.0:
        candidates.append(
            ("lat_lon_swapped", "its lat/lon look swapped", lon, lat, origin.lat, origin.lon)
        )
    if abs(origin.lat) <= math.pi / 2 and abs(origin.lon) <= math.pi:
        as_degrees = math.degrees(origin.lat), math.degrees(origin.lon)
        candidates.append(
            (
                "origin_in_radians",
                f"the origin looks like radians (as degrees: {as_degrees[0]:.4f}, "
                f"{as_degrees[1]:.4f})",
                lat,
                lon,
                *as_degrees,
            )
        )
    if abs(origin.lon) <= 90.0:
        candidates.append(
            (
                "origin_lat_lon_swapped",
                "the origin's lat/lon look swapped",
                lat,
                lon,
                origin.lon,
                origin.lat,
            )
        )
    if abs(lat) <= math.pi / 2 and abs(lon) <= math.pi:
        candidates.append(
            (
                "in_radians",
                "its lat/lon look like radians",
                math.degrees(lat),
                math.degrees(lon),
                origin.lat,
                origin.lon,
            )
        )
    for code, words, plat, plon, olat, olon in candidates:
        fixed = float(great_circle(plat, plon, olat, olon))
        if fixed <= FAR_M:
            if code == "lat_lon_swapped" and abs(origin.lon) <= 90.0:
                alike = float(great_circle(lat, lon, origin.lon, origin.lat))
                words += " (or the origin's)" if alike <= FAR_M else ""
            return code, f"{words}: so corrected, it would be {km(fixed)} from the origin"
    return None


def _far_geodetic(
    loc: Location, lat: float, lon: float, distance: float, origin: GeodeticPoint, what: str
) -> FieldWarning:
    """A geodetic point ``distance`` m from the origin: ``far_from_origin``, or the code of
    the mistake that explains it."""
    message = f"{what} is {km(distance)} from the session's origin (more than {km(FAR_M)})"
    hint = _hint(lat, lon, origin)
    if hint is None:
        return warning(loc, "far_from_origin", f"{message}: check its lat/lon and the origin")
    code, words = hint
    code = "far_from_origin" if code.startswith("origin") else code
    return warning(loc, code, f"{message}; {words}")


# ------------------------------------------------------------------ config rules
@config_rule(
    "far_from_origin",
    "lat_lon_swapped",
    "in_radians",
    "far_apart",
    flags=f"a site more than {km(FAR_M)} from the origin (with the likely mistake: lat/lon "
    "swapped, the site in radians, the origin in radians or swapped); without an origin, "
    f"a site more than {km(FAR_M)} from every other site",
)
def _far_sites(config: SessionConfig, origin: LocalFrame | None) -> Iterator[FieldWarning]:
    sited = [(index, sensor) for index, sensor in enumerate(config.sensors) if sensor.site]
    positions = [sensor_site(sensor, origin)[0] for _, sensor in sited]
    for (index, sensor), position in zip(sited, positions, strict=True):
        site = sensor.site
        assert site is not None
        loc: Location = ("sensors", index, "site")
        what = f"the site of sensor {sensor.id!r}"
        if config.origin is not None:
            distance = float(np.linalg.norm(position))
            if distance <= FAR_M:
                continue
            if site.lat is not None and site.lon is not None:
                yield _far_geodetic(loc, site.lat, site.lon, distance, config.origin, what)
            else:
                yield warning(
                    (*loc, "position"),
                    "far_from_origin",
                    f"{what} is {km(distance)} from the session's origin (more than "
                    f"{km(FAR_M)}): is the position in metres?",
                )
        elif len(positions) > 1:
            nearest = min(
                float(np.linalg.norm(position - other))
                for other in positions
                if other is not position
            )
            if nearest > FAR_M:
                yield warning(
                    loc,
                    "far_apart",
                    f"{what} is {km(nearest)} from the nearest other site (more than "
                    f"{km(FAR_M)}): is its position in metres?",
                )


@config_rule(
    "origin_in_radians",
    "origin_lat_lon_swapped",
    flags=f"no geodetic site within {km(FAR_M)} of the origin, and every one would be with "
    "the origin read as radians (or swapped, for two sites or more)",
)
def _suspect_origin(config: SessionConfig, origin: LocalFrame | None) -> Iterator[FieldWarning]:
    point = config.origin
    if point is None or origin is None:
        return
    geodetic = [
        (sensor.id, sensor.site.lat, sensor.site.lon, sensor_site(sensor, origin)[0])
        for sensor in config.sensors
        if sensor.site is not None and sensor.site.lat is not None and sensor.site.lon is not None
    ]
    far = [(name, lat, lon) for name, lat, lon, at in geodetic if np.linalg.norm(at) > FAR_M]
    if not far or len(far) < len(geodetic):
        return  # a site near the origin vouches for it
    corrections = []
    if abs(point.lat) <= math.pi / 2 and abs(point.lon) <= math.pi:
        degrees = math.degrees(point.lat), math.degrees(point.lon)
        corrections.append(
            (
                "origin_in_radians",
                f"the origin looks like radians (as degrees: {degrees[0]:.4f}, {degrees[1]:.4f})",
                *degrees,
            )
        )
    if abs(point.lon) <= 90.0:
        corrections.append(
            ("origin_lat_lon_swapped", "the origin's lat/lon look swapped", point.lon, point.lat)
        )
    lats = np.array([lat for _, lat, _ in far])
    lons = np.array([lon for _, _, lon in far])
    names = ", ".join(repr(name) for name, _, _ in far)
    for code, words, lat0, lon0 in corrections:
        fixed = great_circle(lats, lons, lat0, lon0)
        # one site swapped or a swapped origin are alike: the origin is blamed for two or more
        ambiguous = code == "origin_lat_lon_swapped" and len(far) == 1
        if np.all(fixed <= FAR_M) and not ambiguous:
            yield warning(
                ("origin",),
                code,
                f"the sites of {names} are more than {km(FAR_M)} from the origin; {words}: so "
                f"corrected, they would be {', '.join(km(float(d)) for d in fixed)} from it "
                "(lat and lon are degrees)",
            )
            return


@config_rule(
    "far_from_origin",
    flags=f"a session-frame sector's apex more than {km(FAR_M)} from the origin (without an "
    "origin: from its sensor's site)",
)
def _far_sectors(config: SessionConfig, origin: LocalFrame | None) -> Iterator[FieldWarning]:
    for index, sensor in enumerate(config.sensors):
        fov = sensor.fov
        if not isinstance(fov, SectorFieldOfView) or fov.frame != "session" or not fov.origin:
            continue
        apex = np.asarray(fov.origin, dtype=np.float64)
        site = sensor_site(sensor, origin)[0][:2]
        reference = np.zeros(2) if config.origin is not None else site
        distance = float(np.linalg.norm(apex - reference))
        if distance > FAR_M:
            whence = "the session's origin" if config.origin is not None else "its sensor's site"
            yield warning(
                ("sensors", index, "fov", "origin"),
                "far_from_origin",
                f"the field of view's apex is {km(distance)} from {whence} (more than "
                f"{km(FAR_M)}): is it in metres?",
            )


@config_rule(
    "sigma_range_small",
    "sigma_range_large",
    "sigma_angle_small",
    "sigma_angle_large",
    "sigma_range_rate_small",
    "sigma_range_rate_large",
    "range_in_km",
    flags=f"a polar sensor's sigma_range below {MIN_SIGMA_RANGE_M:g} m (km?) or above "
    f"{MAX_SIGMA_RANGE_M:g} m (cm or mm?), an angle σ below {MIN_SIGMA_ANGLE_DEG:g}° (radians?) "
    f"or above {MAX_SIGMA_ANGLE_DEG:g}° (milliradians?), a sigma_range_rate below "
    f"{MIN_SIGMA_RANGE_RATE_MPS:g} m/s (km/s?) or above {MAX_SIGMA_RANGE_RATE_MPS:g} m/s (cm/s?), "
    f"a sector reaching fewer than {MIN_RANGE_CELLS:g} range σs (range in km?)",
)
def _polar_units(config: SessionConfig, origin: LocalFrame | None) -> Iterator[FieldWarning]:
    for index, sensor in enumerate(config.sensors):
        noise = sensor.measurement
        if not isinstance(noise, PolarMeasurement):
            continue
        loc: Location = ("sensors", index, "measurement")
        if noise.sigma_range < MIN_SIGMA_RANGE_M:
            yield warning(
                (*loc, "sigma_range"),
                "sigma_range_small",
                f"sigma_range {noise.sigma_range:g} m is below {MIN_SIGMA_RANGE_M:g} m (a radar's "
                f"is metres to hundreds of metres): is it in km? sigma_range is in metres",
            )
        elif noise.sigma_range > MAX_SIGMA_RANGE_M:
            yield warning(
                (*loc, "sigma_range"),
                "sigma_range_large",
                f"sigma_range {noise.sigma_range:g} m is above {MAX_SIGMA_RANGE_M:g} m (a radar's "
                f"is metres to hundreds of metres): is it in cm or mm? sigma_range is in metres",
            )
        rate = noise.sigma_range_rate
        if rate is not None and rate < MIN_SIGMA_RANGE_RATE_MPS:
            yield warning(
                (*loc, "sigma_range_rate"),
                "sigma_range_rate_small",
                f"sigma_range_rate {rate:g} m/s is below {MIN_SIGMA_RANGE_RATE_MPS:g} m/s: is it "
                f"in km/s ({rate:g} km/s = {rate * 1000:g} m/s)? it is in m/s",
            )
        elif rate is not None and rate > MAX_SIGMA_RANGE_RATE_MPS:
            yield warning(
                (*loc, "sigma_range_rate"),
                "sigma_range_rate_large",
                f"sigma_range_rate {rate:g} m/s is above {MAX_SIGMA_RANGE_RATE_MPS:g} m/s: is it "
                f"in cm/s ({rate:g} cm/s = {rate / 100:g} m/s)? it is in m/s",
            )
        for name in ("sigma_azimuth_deg", "sigma_elevation_deg"):
            sigma = getattr(noise, name)
            if sigma is not None and sigma < MIN_SIGMA_ANGLE_DEG:
                yield warning(
                    (*loc, name),
                    "sigma_angle_small",
                    f"{name} {sigma:g}° is below {MIN_SIGMA_ANGLE_DEG:g}°: is it in radians "
                    f"({sigma:g} rad = {math.degrees(sigma):.3g}°)? it is in degrees",
                )
            elif sigma is not None and sigma > MAX_SIGMA_ANGLE_DEG:
                yield warning(
                    (*loc, name),
                    "sigma_angle_large",
                    f"{name} {sigma:g}° is above {MAX_SIGMA_ANGLE_DEG:g}°: is it in milliradians "
                    f"({sigma:g} mrad = {math.degrees(sigma / 1000):.3g}°)? it is in degrees",
                )
        fov = sensor.fov
        if (
            isinstance(fov, SectorFieldOfView)
            and fov.range[1] < MIN_RANGE_CELLS * noise.sigma_range
        ):
            yield warning(
                ("sensors", index, "fov", "range"),
                "range_in_km",
                f"the field of view reaches {fov.range[1]:g} m, fewer than "
                f"{MIN_RANGE_CELLS:g} × sigma_range ({noise.sigma_range:g} m): is the range "
                "in km? it is in metres",
            )


# ------------------------------------------------------------------ input rules
def _blind_range(sensor: SensorConfig, origin: LocalFrame | None) -> float | None:
    """The sector's minimum range when its apex is the sensor's site (else ``None``)."""
    fov = sensor.fov
    if not isinstance(fov, SectorFieldOfView) or fov.range[0] <= 0.0:
        return None
    if fov.origin is not None:
        site = sensor_site(sensor, origin)[0][:2]
        apex = np.asarray(fov.origin, dtype=np.float64)
        if fov.frame == "session" and float(np.linalg.norm(apex - site)) > 1.0:
            return None
        if fov.frame == "sensor" and float(np.linalg.norm(apex)) > 1.0:
            return None
    return fov.range[0]


@input_rule(
    "detections",
    "blind_range",
    "range_in_km",
    "azimuth_radians",
    flags="a polar detection inside its sector's minimum range (apex at the site) or nearer "
    "than one sigma_range (km?); every range of a batch within the sector's reach / 1000 "
    f"(km?); {RADIAN_AZIMUTH_BATCH} or more detections with every azimuth within ±2π° "
    "(radians?)",
)
def _polar_detections(report: DetectionReport, config: SessionConfig) -> Iterator[FieldWarning]:
    sensor = config.sensor(report.sensor)
    if sensor is None or not isinstance(sensor.measurement, PolarMeasurement):
        return
    polar = [d for d in report.detections if isinstance(d, PolarDetection)]
    if not polar or len(polar) != len(report.detections):
        return
    ranges = np.fromiter((d.range for d in polar), dtype=np.float64, count=len(polar))
    azimuths = np.fromiter((d.azimuth_deg for d in polar), dtype=np.float64, count=len(polar))
    sigma = sensor.measurement.sigma_range
    fov = sensor.fov
    if isinstance(fov, SectorFieldOfView) and ranges.max() <= fov.range[1] / 1000.0:
        yield warning(
            ("detections",),
            "range_in_km",
            f"every range of the batch is at most {ranges.max():g} m while the field of view "
            f"reaches {fov.range[1]:g} m: are the ranges in km? range is in metres",
        )
    if len(polar) >= RADIAN_AZIMUTH_BATCH and np.all(np.abs(azimuths) <= 2 * math.pi):
        yield warning(
            ("detections",),
            "azimuth_radians",
            f"every azimuth of the {len(polar)} detections is within ±{2 * math.pi:.2f}°: are "
            "they in radians? azimuth_deg is in degrees, clockwise from north",
        )
    blind = _blind_range(sensor, session_origin(config))
    for index in np.flatnonzero(ranges < (blind or 0.0)).tolist():
        yield warning(
            ("detections", index, "range"),
            "blind_range",
            f"range {ranges[index]:g} m is inside the radar's blind range (its field of view "
            f"starts at {blind:g} m)",
        )
    for index in np.flatnonzero(ranges < sigma).tolist():
        yield warning(
            ("detections", index, "range"),
            "range_in_km",
            f"range {ranges[index]:g} m is nearer than one sigma_range ({sigma:g} m): is it in "
            "km? range is in metres",
        )


@input_rule(
    "detections",
    "blind_range",
    flags="a position detection nearer to its sensor's sector apex than the sector's minimum "
    "range (a session-frame sector, or a sensor-frame one with its apex at the site)",
)
def _cartesian_blind_range(
    report: DetectionReport, config: SessionConfig
) -> Iterator[FieldWarning]:
    sensor = config.sensor(report.sensor)
    fov = None if sensor is None else sensor.fov
    if sensor is None or not isinstance(fov, SectorFieldOfView) or fov.range[0] <= 0.0:
        return
    if isinstance(sensor.measurement, PolarMeasurement) or len(config.state.position) < 2:
        return
    if fov.frame == "session" and fov.origin is not None:
        apex = np.asarray(fov.origin, dtype=np.float64)
    elif fov.frame == "sensor" and fov.origin is None:
        apex = sensor_site(sensor, session_origin(config))[0][:2]
    else:
        return
    points = [
        (index, detection.z)
        for index, detection in enumerate(report.detections)
        if isinstance(detection, CartesianDetection) and len(detection.z) >= 2
    ]
    if not points:
        return
    planar = np.array([z[:2] for _, z in points], dtype=np.float64)
    distances = np.linalg.norm(planar - apex, axis=1)
    for position in np.flatnonzero(distances < fov.range[0]).tolist():
        yield warning(
            ("detections", points[position][0], "z"),
            "blind_range",
            f"the detection is {distances[position]:.0f} m from its sensor's field-of-view "
            f"apex, inside the minimum range {fov.range[0]:g} m (its blind range)",
        )


@input_rule(
    "tracks",
    "far_from_origin",
    "lat_lon_swapped",
    "in_radians",
    flags=f"in a session with an origin, a track more than {km(FAR_M)} from it (geodetic "
    "tracks: with the likely mistake, lat/lon swapped or in radians, or the origin's)",
)
def _far_tracks(report: TrackReport, config: SessionConfig) -> Iterator[FieldWarning]:
    origin = config.origin
    if origin is None or report.frame == "sensor" or not report.tracks:
        return
    position = config.state.position
    if report.frame == "geodetic":
        if len(position) < 2:
            return
        lat, lon = position[0], position[1]
        lats = np.fromiter((t.state[lat] for t in report.tracks), np.float64, len(report.tracks))
        lons = np.fromiter((t.state[lon] for t in report.tracks), np.float64, len(report.tracks))
        distances = great_circle(lats, lons, origin.lat, origin.lon)
        for index in np.flatnonzero(distances > FAR_M).tolist():
            track = report.tracks[index]
            yield _far_geodetic(
                ("tracks", index, "state"),
                float(lats[index]),
                float(lons[index]),
                float(distances[index]),
                origin,
                f"track {track.id!r}",
            )
        return
    states = np.array([[t.state[i] for i in position] for t in report.tracks], dtype=np.float64)
    distances = np.linalg.norm(states, axis=1)
    for index in np.flatnonzero(distances > FAR_M).tolist():
        yield warning(
            ("tracks", index, "state"),
            "far_from_origin",
            f"track {report.tracks[index].id!r} is {km(float(distances[index]))} from the "
            f"session's origin (more than {km(FAR_M)}): are its positions in metres of the "
            "session frame?",
        )


def rule_codes() -> list[str]:
    """Every code a rule may give (documented in the README), ``more_warnings`` last."""
    codes: list[str] = []
    for rule in [*CONFIG_RULES, *(r for rules in INPUT_RULES.values() for r in rules)]:
        codes.extend(code for code in rule.codes if code not in codes)
    return [*codes, "more_warnings"]


__all__: Sequence[str] = [
    "CONFIG_RULES",
    "INPUT_RULES",
    "Rule",
    "config_warnings",
    "input_warnings",
    "rule_codes",
    "site_placements",
]
