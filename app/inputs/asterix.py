"""The ``asterix`` input kind: EUROCONTROL ASTERIX data blocks for one sensor of a session.

``POST /v1/sessions/{sid}/asterix?sensor=ID[&source=SAC/SIC]`` with the raw
data blocks (``application/octet-stream``, as a radar or an ADS-B ground
station sends them over UDP), or a binary message on the WebSocket
``stream`` (``…/stream?sensor=ID[&source=SAC/SIC]``). The blocks are framed
here (category, length) and their records decoded by ``asterix-decoder`` (in a
child process: :mod:`app.inputs.asterix_decoder`);
each record of the ``source`` (default: the one source the data holds) becomes:

- CAT048 (monoradar target reports) → a polar detection of the sensor (its
  measurement must be ``polar``): RHO (slant range) and THETA (azimuth
  from north), and from the flight level (I048/090) the elevation in a 3-D
  session, the ground range in a 2-D one (flat earth, no refraction; the
  flight level, a pressure altitude, is taken as height above the site's
  datum). The Mode S address (I048/220) is kept in the answer as a hint.
- CAT034 (monoradar service messages) → the scan timing: north markers
  split the plots into scans, and the antenna period (I034/041) is reported.
- CAT021 (ADS-B target reports) → a geodetic track list of the sensor (a
  track-list sensor of a session with an ``origin``): position (I021/130 or
  /131), geometric height (I021/140, else 0), velocity east/north from the
  ground vector (I021/160), σ from NACp/NACv (I021/090), track id the
  target address (I021/080).

Time: the time of day (UTC seconds since midnight) is the session time.
The plots of one scan go to the session as one detection input at the
median of their times (the core takes one time per scan); a scan is what
lies between two north markers of the source, or, without them, a run of
plots shorter than the antenna period (I034/041, else the session's
``tracking.time_interval``). CAT021 reports of one time form one track list.

Every record is accounted for in the answer: the input it went into, or
why it did not (another source, a duplicate of a record already in the body,
no position, older than the sensor's latest input). A block of a category this
kind does not read is one ``unsupported_category`` entry, never decoded. The
decoder's C code crashes on some malformed blocks: it runs in a child process,
and a block it dies on is refused like any malformed data. Malformed data (a block longer than the body, a record the
decoder cannot read) is a 422 ``malformed-asterix`` problem with its byte
``offset``; nothing is applied.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterator
from dataclasses import dataclass, field
from http import HTTPStatus
from typing import Annotated, Any, Literal

from pydantic import Field

from api_schemas.base import Identifier, WireModel
from api_schemas.config import PolarMeasurement, SensorConfig, SessionConfig
from api_schemas.issues import FieldIssue
from api_schemas.results import StepResult
from app.errors import InvalidFields, ServiceError, located
from app.inputs.asterix_decoder import IsolatedDecoder
from app.inputs.base import Decoded, DecodedKind, Input, SessionView
from app.inputs.detections import Detections
from app.inputs.tracks import Tracks
from app.sessions.translate import sensor_site, session_origin

MEDIA_TYPE = "application/octet-stream"
NM = 1852.0
FOOT = 0.3048
NACP_EPU_M = {11: 3.0, 10: 10.0, 9: 30.0, 8: 92.6, 7: 185.2, 6: 555.6, 5: 926.0, 4: 1852.0}
"""Estimated position uncertainty (95 %) of each NACp (DO-260B); below 4 the report is not used."""
NACV_EPU_MS = {4: 0.3, 3: 1.0, 2: 3.0, 1: 10.0}
"""Horizontal velocity error (95 %) of each NACv (DO-260B)."""
DEFAULT_NACP, DEFAULT_NACV = 8, 1
"""What a report without quality indicators is taken to have (a common transponder's)."""
TWO_D_95 = 2.4477
"""A 2-D Gaussian holds 95 % of its mass within 2.4477 σ: σ = EPU / 2.4477."""
SOURCE_PATTERN = r"^\d{1,3}/\d{1,3}$"
CATEGORIES = (21, 34, 48)
"""The categories this kind reads (and hands to the decoder)."""
DECODER = IsolatedDecoder()
"""``asterix-decoder``, in a child process (:mod:`app.inputs.asterix_decoder`)."""

Outcome = Literal[
    "detection",
    "track",
    "scan_timing",
    "other_source",
    "duplicate",
    "no_position",
    "stale",
    "unsupported_category",
]


class AsterixParameters(WireModel):
    """Whose data it is: the session's sensor, and the ASTERIX source to read (``SAC/SIC``)."""

    sensor: Identifier = Field(description="the session's sensor the data is for")
    source: Annotated[str, Field(pattern=SOURCE_PATTERN)] | None = Field(
        default=None,
        description="SAC/SIC of the records to read (default: the one source the data holds)",
    )


class AsterixRecord(WireModel):
    """One record of the body and what became of it."""

    offset: int = Field(description="byte offset of the record in the body")
    category: int
    source: str | None = Field(description="SAC/SIC")
    time: float | None = Field(description="time of day (s, UTC)")
    outcome: Outcome
    input: int | None = Field(
        default=None, description="index in `results` of the input it went into"
    )
    mode_s: str | None = Field(default=None, description="Mode S address (hex), a hint")
    track_number: int | None = None


class AsterixAnswer(WireModel):
    """What a body of ASTERIX data became: every record accounted for, one result per input."""

    sensor: Identifier
    source: str | None
    blocks: int
    records: list[AsterixRecord]
    counts: dict[str, int] = Field(description="records per outcome")
    antenna_period: float | None = Field(description="I034/041 (s), if the data gives it")
    north_markers: list[float] = Field(description="times of the source's north markers")
    results: list[StepResult]


class MalformedAsterix(ServiceError):  # noqa: N818 - HTTP vocabulary
    """Data that is not well-formed ASTERIX: where (byte ``offset``) and why."""

    status = HTTPStatus.UNPROCESSABLE_ENTITY
    slug = "malformed-asterix"
    title = "Malformed ASTERIX data"

    def __init__(self, offset: int, reason: str) -> None:
        super().__init__(f"malformed ASTERIX data at byte {offset}: {reason}", offset=offset)
        self.offset = offset

    def field_errors(self) -> list[Any]:
        return [located((), self.detail, "asterix_malformed")]


@dataclass
class _Record:
    offset: int
    category: int
    items: dict[str, Any]
    raw: bytes
    answer: dict[str, Any] = field(default_factory=dict)

    @property
    def source(self) -> str | None:
        sac_sic = self.items.get("I010")
        if sac_sic is None:
            return None
        return f"{sac_sic['SAC']['val']}/{sac_sic['SIC']['val']}"

    def value(self, item: str, name: str) -> Any:
        found = self.items.get(item)
        if found is None or name not in found:
            return None
        return found[name]["val"]


def blocks(data: bytes) -> Iterator[tuple[int, int, bytes]]:
    """``(offset, category, block)`` of every data block (CAT, LEN, records); malformed framing
    raises :class:`MalformedAsterix` at its offset."""
    offset = 0
    while offset < len(data):
        if len(data) - offset < 3:
            raise MalformedAsterix(offset, f"{len(data) - offset} bytes left, a block needs 3")
        length = int.from_bytes(data[offset + 1 : offset + 3], "big")
        if length < 4:
            raise MalformedAsterix(offset, f"block length {length} (at least 4)")
        if offset + length > len(data):
            raise MalformedAsterix(
                offset, f"block length {length} runs past the end ({len(data) - offset} bytes left)"
            )
        yield offset, data[offset], data[offset : offset + length]
        offset += length


def records(data: bytes) -> tuple[int, list[_Record]]:
    """The number of blocks and every record of ``data``, decoded (module docstring)."""
    found: list[_Record] = []
    count = 0
    for offset, category, block in blocks(data):
        count += 1
        if category not in CATEGORIES:
            # not decoded (the decoder crashes on some malformed blocks of categories this
            # kind does not read): the block is accounted for as one unread record
            found.append(_Record(offset, category, {}, block))
            continue
        decoded = DECODER.parse(block)
        if decoded is None:
            raise MalformedAsterix(offset, f"the decoder cannot read this CAT{category:03d} block")
        position = offset + 3
        for record in decoded:
            length = int(record.get("len", 0))
            items = {key: value for key, value in record.items() if key.startswith("I")}
            if not items or length <= 0 or position + length > offset + len(block):
                raise MalformedAsterix(position, f"a CAT{category:03d} record cannot be decoded")
            found.append(_Record(position, category, items, data[position : position + length]))
            position += length
        if position != offset + len(block):
            raise MalformedAsterix(position, f"a CAT{category:03d} record cannot be decoded")
    return count, found


class Asterix(DecodedKind[AsterixParameters]):
    """ASTERIX CAT048, CAT034 and CAT021 (module docstring)."""

    tag = "asterix"
    media_type = MEDIA_TYPE
    parameters = AsterixParameters
    answer_model = AsterixAnswer
    summary = (
        "ASTERIX data blocks (a binary message; the connection's query names the `sensor`, "
        "and the `source` SAC/SIC if the data holds several); answered by one "
        "`asterix_result`, or `error` (`malformed-asterix` with the byte `offset`)."
    )
    description = """ASTERIX data blocks of one sensor → one fused result per input they hold.

    CAT048 plots become the (polar) sensor's detections, a scan per input;
    CAT034 north markers split the scans; CAT021 ADS-B reports become a
    geodetic track list per report time. The answer accounts for every
    record (``records``: what it became or why not, with its byte offset)
    and gives the step result of each input in order. Malformed data is a
    422 ``malformed-asterix`` problem with the byte ``offset``; then nothing
    is applied.
    """

    def decode(self, data: bytes, parameters: AsterixParameters, session: SessionView) -> Decoded:
        config = session.config
        sensor = _configured(config, parameters.sensor)
        count, found = records(data)
        source = parameters.source or _only_source(found)
        timing = _scan_timing(found, source)
        seen: set[tuple[int, bytes]] = set()
        plots: list[_Record] = []
        reports: list[_Record] = []
        for record in found:
            record.answer = {
                "offset": record.offset,
                "category": record.category,
                "source": record.source,
                "time": None,
                "outcome": "unsupported_category",
            }
            if record.category not in CATEGORIES:
                continue
            if record.source != source:
                record.answer["outcome"] = "other_source"
            elif (record.category, record.raw) in seen:
                record.answer["outcome"] = "duplicate"
            elif record.category == 34:
                record.answer["outcome"] = "scan_timing"
                record.answer["time"] = record.value("I030", "ToD")
            else:
                (plots if record.category == 48 else reports).append(record)
            seen.add((record.category, record.raw))
        inputs = [
            *_scans(plots, sensor, config, timing, parameters.sensor),
            *_track_lists(reports, sensor, config, parameters.sensor),
        ]
        inputs.sort(key=lambda made: made[0].report.time)
        applied: list[Input] = []
        last = session.last_time(parameters.sensor)
        for made, members in inputs:
            if last is not None and made.report.time <= last:
                for record in members:
                    record.answer["outcome"] = "stale"
                continue
            made.check(config)
            for record in members:
                record.answer["input"] = len(applied)
            applied.append(made)
            last = made.report.time
        answers = [record.answer for record in found]
        counts: dict[str, int] = defaultdict(int)
        for answer in answers:
            counts[answer["outcome"]] += 1
        return Decoded(
            tuple(applied),
            {
                "sensor": parameters.sensor,
                "source": source,
                "blocks": count,
                "records": answers,
                "counts": dict(sorted(counts.items())),
                "antenna_period": timing.period,
                "north_markers": timing.north,
            },
        )


@dataclass(frozen=True)
class _Timing:
    north: list[float]
    period: float | None


def _configured(config: SessionConfig, sensor: str) -> SensorConfig | None:
    """The configured sensor (an open session takes any id: then ``None``)."""
    found = config.sensor(sensor)
    if found is None and config.sensors:
        known = ", ".join(repr(entry.id) for entry in config.sensors)
        raise InvalidFields(
            [FieldIssue(("sensor",), f"unknown sensor {sensor!r} (configured: {known})", sensor)],
            prefix="query",
        )
    return found


def _only_source(found: list[_Record]) -> str | None:
    """The one SAC/SIC of the records this kind reads (422 at ``query/source`` for several)."""
    sources = sorted({r.source for r in found if r.category in CATEGORIES and r.source})
    if len(sources) > 1:
        raise InvalidFields(
            [
                FieldIssue(
                    ("source",),
                    f"the data holds several sources ({', '.join(sources)}): name one as SAC/SIC",
                    None,
                )
            ],
            prefix="query",
        )
    return sources[0] if sources else None


def _scan_timing(found: list[_Record], source: str | None) -> _Timing:
    """North markers (CAT034 message type 1) and the antenna period of ``source``."""
    north: list[float] = []
    period = None
    for record in found:
        if record.category != 34 or record.source != source:
            continue
        if record.value("I000", "MsgTyp") == 1:
            time = record.value("I030", "ToD")
            if time is not None and time not in north:
                north.append(float(time))
            rotation = record.value("I041", "RotS")
            if rotation:
                period = float(rotation)
    return _Timing(sorted(north), period)


def _scans(
    plots: list[_Record],
    sensor: SensorConfig | None,
    config: SessionConfig,
    timing: _Timing,
    sensor_id: str,
) -> Iterator[tuple[Input, list[_Record]]]:
    """One detection input per scan of the plots (module docstring)."""
    if not plots:
        return
    measurement = None if sensor is None else sensor.measurement
    if not isinstance(measurement, PolarMeasurement):
        raise InvalidFields(
            [
                FieldIssue(
                    ("sensor",),
                    f"CAT048 plots are a polar radar's: sensor {sensor_id!r} has no polar measurement",
                    sensor_id,
                )
            ],
            prefix="query",
        )
    assert sensor is not None
    dim = len(config.state.position)
    site, _ = sensor_site(sensor, session_origin(config))
    site_height = float(site[2]) if dim == 3 else _site_height(sensor, config)
    positioned: list[tuple[float, _Record, dict[str, float]]] = []
    for record in plots:
        time = record.value("I140", "ToD")
        rho, theta = record.value("I040", "RHO"), record.value("I040", "THETA")
        record.answer["time"] = time
        record.answer["mode_s"] = record.value("I220", "ACAddr")
        record.answer["track_number"] = record.value("I161", "Tn")
        if time is None or rho is None or theta is None or rho <= 0:
            record.answer["outcome"] = "no_position"
            continue
        detection = _polar(
            float(rho) * NM, float(theta), record.value("I090", "FL"), site_height, dim
        )
        if detection is None:
            record.answer["outcome"] = "no_position"
            continue
        record.answer["outcome"] = "detection"
        positioned.append((float(time), record, detection))
    positioned.sort(key=lambda entry: entry[0])
    period = timing.period or config.tracking.time_interval
    scan: list[tuple[float, _Record, dict[str, float]]] = []
    for entry in positioned:
        if scan and _new_scan(scan[0][0], entry[0], timing.north, period):
            yield _scan_input(scan, sensor_id)
            scan = []
        scan.append(entry)
    if scan:
        yield _scan_input(scan, sensor_id)


def _new_scan(start: float, time: float, north: list[float], period: float) -> bool:
    """Whether a plot at ``time`` starts a new scan after one started at ``start``."""
    if north:
        return any(start < marker <= time for marker in north)
    return time - start >= period


def _scan_input(
    scan: list[tuple[float, _Record, dict[str, float]]], sensor_id: str
) -> tuple[Input, list[_Record]]:
    times = sorted(time for time, _, _ in scan)
    body = {
        "sensor": sensor_id,
        "time": times[(len(times) - 1) // 2],  # the median (lower middle): one of the times
        "detections": [detection for _, _, detection in scan],
    }
    kind = Detections()
    return Input(kind, kind.parse(body)), [record for _, record, _ in scan]


def _site_height(sensor: SensorConfig, config: SessionConfig) -> float:
    """The site's height (m) on the datum flight levels are read against."""
    site = sensor.site
    origin_alt = 0.0 if config.origin is None else config.origin.alt
    if site is None:
        return origin_alt
    if site.position is not None:
        return origin_alt + (site.position[2] if len(site.position) > 2 else 0.0)
    return origin_alt if site.alt is None else site.alt


def _polar(
    slant: float, azimuth: float, flight_level: float | None, site_height: float, dim: int
) -> dict[str, float] | None:
    """A polar detection (module docstring); ``None`` in 3-D without a flight level."""
    if dim == 3:
        if flight_level is None:
            return None
        rise = float(flight_level) * 100.0 * FOOT - site_height
        sine = max(-1.0, min(1.0, rise / slant))
        return {
            "range": slant,
            "azimuth_deg": azimuth,
            "elevation_deg": math.degrees(math.asin(sine)),
        }
    if flight_level is not None:
        rise = float(flight_level) * 100.0 * FOOT - site_height
        if abs(rise) < slant:
            return {"range": math.sqrt(slant * slant - rise * rise), "azimuth_deg": azimuth}
    return {"range": slant, "azimuth_deg": azimuth}


def _track_lists(
    reports: list[_Record], sensor: SensorConfig | None, config: SessionConfig, sensor_id: str
) -> Iterator[tuple[Input, list[_Record]]]:
    """One geodetic track list per report time of the CAT021 reports (module docstring)."""
    if not reports:
        return
    problem = None
    if sensor is not None and sensor.measurement is not None:
        problem = f"CAT021 reports are a track list: sensor {sensor_id!r} sends detections"
    elif config.origin is None:
        problem = "CAT021 reports are geodetic: the session needs an 'origin'"
    elif len(config.state.velocity) != len(config.state.position) or config.state.dim != 2 * len(
        config.state.position
    ):
        problem = "CAT021 reports give positions and velocities only: the state must be just those"
    if problem is not None:
        raise InvalidFields([FieldIssue(("sensor",), problem, sensor_id)], prefix="query")
    by_time: dict[float, list[tuple[_Record, dict[str, Any]]]] = defaultdict(list)
    for record in reports:
        time = _first(record, TIME_ITEMS)
        record.answer["time"] = time
        record.answer["mode_s"] = record.value("I080", "TAddr")
        record.answer["track_number"] = record.value("I161", "TrackN")
        track = _adsb_track(record, config)
        if time is None or track is None:
            record.answer["outcome"] = "no_position"
            continue
        record.answer["outcome"] = "track"
        by_time[float(time)].append((record, track))
    for time, entries in sorted(by_time.items()):
        latest: dict[str, tuple[_Record, dict[str, Any]]] = {}
        for record, track in entries:
            if track["id"] in latest:
                latest[track["id"]][0].answer["outcome"] = "duplicate"
            latest[track["id"]] = (record, track)
        body = {
            "sensor": sensor_id,
            "time": time,
            "frame": "geodetic",
            "tracks": [track for _, track in latest.values()],
        }
        kind = Tracks()
        yield Input(kind, kind.parse(body)), [record for record, _ in latest.values()]


TIME_ITEMS = (
    ("I071", "time_applicability_position"),
    ("I073", "time_reception_position"),
    ("I077", "time_report_transmission"),
)
"""A CAT021 report's time: of applicability for the position, else of its reception, else
of the report's transmission."""


def _first(record: _Record, items: tuple[tuple[str, str], ...]) -> float | None:
    """The first of ``items`` the record has."""
    for item, name in items:
        value = record.value(item, name)
        if value is not None:
            return float(value)
    return None


def _adsb_track(record: _Record, config: SessionConfig) -> dict[str, Any] | None:
    """A CAT021 report as a geodetic track of the session's layout, or ``None`` without a
    usable position (none, or NACp below 4)."""
    lat = record.value("I131", "Lat")
    lon = record.value("I131", "Lon")
    if lat is None or lon is None:
        lat, lon = record.value("I130", "Lat"), record.value("I130", "Lon")
    if lat is None or lon is None:
        return None
    nacp = record.value("I090", "NACp")
    nacv = record.value("I090", "NUCr_or_NACv")
    epu = NACP_EPU_M.get(DEFAULT_NACP if nacp is None else int(nacp))
    if epu is None:
        return None
    velocity_epu = NACV_EPU_MS.get(DEFAULT_NACV if nacv is None else int(nacv), 10.0)
    speed = record.value("I160", "GS")
    angle = record.value("I160", "TA")
    east = north = 0.0
    speed_sigma = velocity_epu / TWO_D_95
    if speed is None or angle is None:
        speed_sigma = 300.0  # no ground vector: the velocity is unknown
    else:
        east = float(speed) * NM * math.sin(math.radians(float(angle)))
        north = float(speed) * NM * math.cos(math.radians(float(angle)))
    height = record.value("I140", "geometric_height")
    layout = config.state
    axes = len(layout.position)
    positions = [float(lat), float(lon), 0.0 if height is None else float(height) * FOOT][:axes]
    velocities = [east, north, 0.0][:axes]
    state = [0.0] * layout.dim
    variances = [0.0] * layout.dim
    sigma = epu / TWO_D_95
    for index, component in enumerate(layout.position):
        state[component] = positions[index]
        variances[component] = sigma**2 if index < 2 else (2.0 * sigma) ** 2
    for index, component in enumerate(layout.velocity):
        state[component] = velocities[index]
        variances[component] = speed_sigma**2
    covariance = [
        [variances[row] if row == col else 0.0 for col in range(layout.dim)]
        for row in range(layout.dim)
    ]
    address = record.value("I080", "TAddr")
    number = record.value("I161", "TrackN")
    track_id = str(address) if address is not None else f"tn{number}"
    return {"id": track_id, "state": state, "covariance": covariance}
