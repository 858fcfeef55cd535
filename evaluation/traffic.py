"""Real traffic (issue 22, EVALUATION.md "Real traffic"): recorded flights, simulated sensors, the
service as a new user configures it.

**Truth.** Twenty aircraft recorded by ADS-B receivers around Paris on 7
October 2021 (the ``traffic`` package's ``quickstart`` sample, MIT; the
extract and its licence are in ``evaluation/data/``,
:mod:`evaluation.traffic_extract` writes it): records → WGS84 (barometric
altitude taken as height) → ECEF → ENU at :data:`ORIGIN` (pymap3d). Glitches
are dropped (a record that implies more than :data:`MAX_SPEED` horizontally or
:data:`MAX_CLIMB` vertically from the last one kept), gaps up to
:data:`MAX_GAP` are bridged, and the positions are smoothed on a 1 s grid by
a Savitzky–Golay filter (:data:`SMOOTHING` s, quadratic), whose derivative on
the grid is the velocity: ADS-B positions jitter by tens of metres along track.

**Sensors** (:data:`RADARS`, :data:`ADSB`). Three 3-D polar radars at
geodetic sites 20–100 km from most aircraft: range, azimuth from the site's
north and elevation in the site's own ENU (``pymap3d.geodetic2aer``, not the
service's conversion), Gaussian noise per radar, P_D 0.9, a target seen only
inside its range, under its top elevation and above its radar horizon (4/3
Earth radius: ``√(2kRh_site) + √(2kRh_target)``); Poisson clutter uniform in
the coverage volume; scan periods 4, 5 and 12 s, staggered. An ADS-B station
reports a geodetic track list every 2 s for half of the fleet (the other half
is non-cooperative): each report is dropped with probability
:data:`ADSB_DROP`, every equipped aircraft has one outage of 30–120 s, the
station one of a minute; airliners' reports carry their emitter category
("large") as class evidence {liner, bomber}.

**The session** (:func:`session_config`) is what a new user writes from the
sensors' data sheets: the origin, each radar's site, σ, P_D, clutter
density and coverage volume (:func:`radar_coverage`: range, top elevation,
antenna height), the scene's birth density, the ``aircraft`` preset with its
classes, and the ADS-B source by its id alone — no management knob.

**Metrics** (:func:`assess`), on the fused picture every
:data:`PICTURE_EVERY` s of scene time (``GET …/tracks?time=t``): confirmed or
coasting tracks are matched to the aircraft by a minimum-cost assignment
(3-D distance gated at :data:`MATCH_GATE`, plus :data:`SWITCH_PENALTY` for a
track that is not the aircraft's previous one); coverage of each aircraft
over the pictures where a sensor could see it; extra fused ids (distinct
ids an aircraft was held by, beyond the first) and false tracks (ids never
matched); 3-D RMSE of the matched tracks; class decisions per aircraft type;
and, from every step's answer, the confirmed ↔ coasting changes of each
fused track.
"""

from __future__ import annotations

import csv
import gzip
import io
import math
from collections import Counter, defaultdict
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pymap3d
from scipy.optimize import linear_sum_assignment
from scipy.signal import savgol_filter

from core.arrays import FloatArray

EXTRACT = Path(__file__).resolve().parent / "data" / "quickstart-paris-20.csv.gz"
ORIGIN = (48.85, 2.45, 100.0)
"""The session's origin (lat°, lon°, height m): between Paris' two airports."""
DURATION = 1800.0
"""Scene length (s)."""
FEET = 0.3048
MAX_SPEED = 400.0
"""A record implying more than this horizontal speed (m/s) from the last kept one is a glitch."""
MAX_CLIMB = 6000.0 * FEET / 60.0
"""… or more than this vertical speed (m/s): 6000 ft/min, 30.48 m/s.

A steady climb's rate is the specific excess power ``w = V (T − D) / W`` (the
climb equation; ``V`` true airspeed, ``T`` thrust, ``D`` drag, ``W`` weight).
A twin-jet airliner (A320, B737: thrust-to-weight ``T/W`` ≈ 0.3 at take-off thrust
and sea level, lift-to-drag ``L/D`` ≈ 17) at the 250 kt (129 m/s) limit below FL100
gets ``w = V (T/W − 1/(L/D)) ≈ 129 × (0.30 − 0.06) ≈ 31 m/s`` at full take-off
thrust at sea level, and less higher up, where the thrust lapses, or slower, where
the climb is flown; airline climbs and descents are 5–20 m/s and
the kept truth of the twenty flights never exceeds 19 m/s (``VLJ432T``, a
business jet). The light aircraft climb at a few m/s.

It was 60 m/s, and let in ``RYR43ZU``'s records after its approach to
Beauvais–Tillé: its position stops changing at 898 s (750 ft, on the final
approach to runway 30 six kilometres out; an ADS-B state vector repeats the last
position it decoded), the altitude jumps to 25 375 ft at 918 s and then descends
slowly. The filter compares a record with the last one it kept (917 s, 750 ft),
so the allowance grows with the time since: the record of 1032 s (23 350 ft,
59.9 m/s over 115 s) was kept — a 7 km "climb" in two minutes without any
horizontal movement, which became the truth. With 30.48 m/s the first record kept
after 917 s is that of 1109 s (19 450 ft, 29.7 m/s over 192 s), after a gap
longer than :data:`MAX_GAP`: the flight ends at 917 s, where its records stop
being an aircraft's."""
MAX_GAP = 120.0
"""Gaps in a flight's records up to this (s) are bridged; longer ones end the flight there."""
SMOOTHING = 21
"""Savitzky–Golay window (1 s samples) of the truth."""
EARTH_RADIUS = 6_371_000.0
REFRACTION = 4.0 / 3.0
"""The radar horizon's effective Earth radius factor."""
PICTURE_EVERY = 10.0
MATCH_GATE = 2000.0
"""Largest 3-D distance (m) at which a fused track holds an aircraft."""
SWITCH_PENALTY = 500.0
"""Added cost (m) of matching an aircraft to another track than its previous one."""
ADSB_PERIOD = 2.0
ADSB_DROP = 0.05
ADSB_SIGMA = (15.0, 10.0, 1.5)
"""ADS-B noise: horizontal and vertical position σ (m), velocity σ (m/s)."""
ADSB_STATION_OUTAGE = (900.0, 960.0)
LIVE = ("confirmed", "coasting")
AIRLINES = ("AFR", "RYR", "CCM", "VLG", "TAP", "TVF")
BUSINESS = ("VLJ", "MTO")
KINDS = ("airliner", "business jet", "private")
LARGE = {
    "mass": [
        {"set": ["liner", "bomber"], "mass": 0.9},
        {"set": ["liner", "bomber", "fighter"], "mass": 0.1},
    ]
}
"""The ADS-B class evidence of an airliner: emitter category A3 "large aircraft"."""


@dataclass(frozen=True)
class Radar:
    """A 3-D polar radar at a geodetic site."""

    id: str
    lat: float
    lon: float
    alt: float
    sigma_range: float
    sigma_azimuth_deg: float
    sigma_elevation_deg: float
    period: float
    offset: float
    p_detect: float = 0.9
    range_max: float = 150_000.0
    elevation_max_deg: float = 30.0
    clutter_per_scan: float = 30.0

    @property
    def volume(self) -> float:
        """The coverage volume (m³): ranges to ``range_max``, elevations 0 to the top."""
        return (
            2.0 * math.pi / 3.0 * self.range_max**3 * math.sin(math.radians(self.elevation_max_deg))
        )

    @property
    def clutter_density(self) -> float:
        """False detections per m³ per scan (what its data sheet and site survey give)."""
        return self.clutter_per_scan / self.volume


RADARS = (
    Radar("radar-n", 49.45, 2.10, 150.0, 40.0, 0.12, 0.25, 4.0, 0.0),
    Radar("radar-sw", 48.35, 1.95, 180.0, 60.0, 0.18, 0.30, 5.0, 1.3),
    Radar("radar-e", 48.80, 3.55, 200.0, 80.0, 0.20, 0.35, 12.0, 2.7),
)
ADSB = "adsb"


@dataclass(frozen=True)
class Flight:
    """One aircraft's smoothed truth on a 1 s grid (session ENU and geodetic)."""

    callsign: str
    icao24: str
    kind: str
    times: FloatArray
    enu: FloatArray
    velocity: FloatArray
    geodetic: FloatArray

    def present(self, t: float) -> bool:
        return bool(self.times[0] <= t <= self.times[-1])

    def at(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """ENU position, ENU velocity and geodetic (lat, lon, height) at ``t`` (interpolated)."""

        def interpolate(values: FloatArray) -> FloatArray:
            return np.array([np.interp(t, self.times, values[:, k]) for k in range(3)])

        return interpolate(self.enu), interpolate(self.velocity), interpolate(self.geodetic)


def kind_of(callsign: str) -> str:
    if callsign[:3] in AIRLINES:
        return "airliner"
    return "business jet" if callsign[:3] in BUSINESS else "private"


def load_flights(path: Path = EXTRACT, origin: tuple[float, float, float] = ORIGIN) -> list[Flight]:
    """The extract's flights as truth (module docstring), ordered by callsign."""
    text = gzip.decompress(path.read_bytes()).decode()
    records: dict[str, list[dict[str, str]]] = defaultdict(list)
    for row in csv.DictReader(io.StringIO(text)):
        records[row["callsign"]].append(row)
    flights = []
    for callsign in sorted(records):
        rows = records[callsign]
        t = np.array([float(r["t"]) for r in rows])
        lat = np.array([float(r["lat"]) for r in rows])
        lon = np.array([float(r["lon"]) for r in rows])
        height = np.array([float(r["alt_ft"]) for r in rows]) * FEET
        enu = np.stack(pymap3d.geodetic2enu(lat, lon, height, *origin), axis=-1)
        kept = _without_glitches(t, enu)
        t, enu = t[kept], enu[kept]
        gaps = np.flatnonzero(np.diff(t) > MAX_GAP)
        if len(gaps):  # the flight ends at its first long gap
            t, enu = t[: gaps[0] + 1], enu[: gaps[0] + 1]
        grid = np.arange(math.ceil(t[0]), math.floor(t[-1]) + 1.0)
        if len(grid) < SMOOTHING:
            continue
        raw = np.stack([np.interp(grid, t, enu[:, k]) for k in range(3)], axis=-1)
        smooth = savgol_filter(raw, SMOOTHING, 2, axis=0)
        velocity = np.gradient(smooth, axis=0)  # the truth's own derivative (1 s grid)
        geodetic = np.stack(pymap3d.enu2geodetic(*smooth.T, *origin), axis=-1)
        flights.append(
            Flight(callsign, rows[0]["icao24"], kind_of(callsign), grid, smooth, velocity, geodetic)
        )
    return flights


def _without_glitches(t: FloatArray, enu: FloatArray) -> np.ndarray:
    """Records kept: each within :data:`MAX_SPEED` / :data:`MAX_CLIMB` of the last one kept."""
    kept = [0]
    for k in range(1, len(t)):
        last = kept[-1]
        dt = t[k] - t[last]
        if dt <= 0.0:
            continue
        step = enu[k] - enu[last]
        if np.hypot(step[0], step[1]) <= MAX_SPEED * dt and abs(step[2]) <= MAX_CLIMB * dt:
            kept.append(k)
    return np.array(kept, dtype=np.int64)


# ------------------------------------------------------------------ sensors
def horizon_visible(radar: Radar, geodetic: FloatArray) -> np.ndarray:
    """Inside the radar's range and elevation, above its 4/3-Earth horizon; per point (n, 3)."""
    _az, el, slant = pymap3d.geodetic2aer(*geodetic.T, radar.lat, radar.lon, radar.alt)
    effective = 2.0 * REFRACTION * EARTH_RADIUS
    height = np.maximum(geodetic[:, 2], 0.0)
    horizon = math.sqrt(effective * max(radar.alt, 0.0)) + np.sqrt(effective * height)
    ground = slant * np.cos(np.radians(el))
    return np.asarray(
        (slant <= radar.range_max) & (el <= radar.elevation_max_deg) & (ground <= horizon)
    )


@dataclass(frozen=True)
class Input:
    """One input of the scene: a radar's detections or an ADS-B track list."""

    time: float
    sensor: str
    route: str
    body: dict[str, Any]
    truth_errors: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))
    """Radars: ENU errors (m) of the target detections (the radar's own measurement error)."""


@dataclass(frozen=True)
class Scene:
    """Flights, sensors and the inputs they send (:func:`simulate`)."""

    flights: list[Flight]
    radars: tuple[Radar, ...]
    equipped: frozenset[str]
    inputs: list[Input]
    adsb_outages: dict[str, tuple[float, float]]
    duration: float
    seed: int
    origin: tuple[float, float, float] = ORIGIN

    def visible(self, flight: Flight, t: float, sensors: Iterable[str] | None = None) -> bool:
        """Whether a sensor of the scene (or of ``sensors``) could see ``flight`` at ``t``."""
        chosen = None if sensors is None else set(sensors)
        _, _, geodetic = flight.at(t)
        for radar in self.radars:
            if (chosen is None or radar.id in chosen) and horizon_visible(radar, geodetic[None])[0]:
                return True
        if (chosen is not None and ADSB not in chosen) or flight.callsign not in self.equipped:
            return False
        start, stop = self.adsb_outages[flight.callsign]
        return not (start <= t <= stop or ADSB_STATION_OUTAGE[0] <= t <= ADSB_STATION_OUTAGE[1])

    @property
    def birth_density(self) -> float:
        """New aircraft per m³ per scan of the fastest radar: the scene's own count over its
        volume (250 km × 250 km × 12 km)."""
        per_second = len(self.flights) / self.duration
        return per_second * min(r.period for r in self.radars) / (250e3 * 250e3 * 12e3)


def simulate(
    seed: int = 0,
    duration: float = DURATION,
    flights: list[Flight] | None = None,
    radars: tuple[Radar, ...] = RADARS,
    adsb: bool = True,
) -> Scene:
    """The scene's inputs, seeded: radar scans and ADS-B lists, in time order."""
    flights = load_flights() if flights is None else flights
    rng = np.random.default_rng(seed)
    equipped = frozenset(f.callsign for f in flights[::2]) if adsb else frozenset()
    outages = {}
    for flight in flights:
        length = rng.uniform(30.0, 120.0)
        start = rng.uniform(flight.times[0], max(flight.times[0], flight.times[-1] - length))
        outages[flight.callsign] = (float(start), float(start + length))
    inputs: list[Input] = []
    for radar in radars:
        for t in np.arange(radar.offset, duration, radar.period):
            inputs.append(_radar_scan(radar, flights, float(t), rng))
    if adsb:
        for t in np.arange(0.5, duration, ADSB_PERIOD):
            if ADSB_STATION_OUTAGE[0] <= t <= ADSB_STATION_OUTAGE[1]:
                continue
            inputs.append(
                _adsb_list([f for f in flights if f.callsign in equipped], outages, float(t), rng)
            )
    order = {radar.id: k for k, radar in enumerate(radars)} | {ADSB: len(radars)}
    inputs.sort(key=lambda item: (item.time, order[item.sensor]))
    return Scene(list(flights), radars, equipped, inputs, outages, duration, seed)


def _radar_scan(
    radar: Radar, flights: Sequence[Flight], t: float, rng: np.random.Generator
) -> Input:
    detections, errors = [], []
    sigmas = np.array([radar.sigma_azimuth_deg, radar.sigma_elevation_deg, radar.sigma_range])
    for flight in flights:
        if not flight.present(t):
            continue
        enu, _, geodetic = flight.at(t)
        if not horizon_visible(radar, geodetic[None])[0] or rng.random() >= radar.p_detect:
            continue
        aer = np.array(pymap3d.geodetic2aer(*geodetic, radar.lat, radar.lon, radar.alt))
        measured = aer + rng.normal(0.0, sigmas)
        detections.append(_polar(measured))
        where = np.array(
            pymap3d.aer2enu(measured[0], measured[1], measured[2])
        )  # site ENU, then to the session's through ECEF
        ecef = pymap3d.enu2ecef(*where, radar.lat, radar.lon, radar.alt)
        errors.append(np.array(pymap3d.ecef2enu(*ecef, *ORIGIN)) - enu)
    count = rng.poisson(radar.clutter_per_scan)
    ranges = radar.range_max * rng.random(count) ** (1.0 / 3.0)
    azimuths = rng.uniform(0.0, 360.0, count)
    top = math.sin(math.radians(radar.elevation_max_deg))
    elevations = np.degrees(np.arcsin(rng.uniform(0.0, top, count)))
    for az, el, rho in zip(azimuths, elevations, ranges, strict=True):
        detections.append(_polar(np.array([az, el, max(rho, 1.0)])))
    order = rng.permutation(len(detections))
    body = {"sensor": radar.id, "time": t, "detections": [detections[k] for k in order]}
    return Input(t, radar.id, "detections", body, np.array(errors).reshape(-1, 3))


def _polar(aer: FloatArray) -> dict[str, float]:
    return {
        "range": float(aer[2]),
        "azimuth_deg": float(aer[0] % 360.0),
        "elevation_deg": float(np.clip(aer[1], -90.0, 90.0)),
    }


def _adsb_list(
    flights: Sequence[Flight],
    outages: dict[str, tuple[float, float]],
    t: float,
    rng: np.random.Generator,
) -> Input:
    sigma_h, sigma_v, sigma_speed = ADSB_SIGMA
    covariance = np.diag(
        [sigma_h**2, sigma_speed**2, sigma_h**2, sigma_speed**2, sigma_v**2, sigma_speed**2]
    )
    tracks = []
    for flight in flights:
        start, stop = outages[flight.callsign]
        if not flight.present(t) or start <= t <= stop or rng.random() < ADSB_DROP:
            continue
        _, velocity, geodetic = flight.at(t)
        lat, lon, height = geodetic
        offset = rng.normal(0.0, [sigma_h, sigma_h, sigma_v])
        noisy = np.array(pymap3d.enu2geodetic(*offset, lat, lon, height))
        # velocity: session ENU → ENU at the aircraft (both through ECEF)
        ecef = pymap3d.enu2uvw(*velocity, ORIGIN[0], ORIGIN[1])
        local = np.array(pymap3d.uvw2enu(*ecef, lat, lon)) + rng.normal(0.0, sigma_speed, 3)
        track: dict[str, Any] = {
            "id": flight.icao24,
            "state": [noisy[0], local[0], noisy[1], local[1], noisy[2], local[2]],
            "covariance": covariance.tolist(),
        }
        if flight.kind == "airliner":
            track["classification"] = LARGE
        tracks.append(track)
    body = {"sensor": ADSB, "time": t, "frame": "geodetic", "tracks": tracks}
    return Input(t, ADSB, "tracks", body)


# ------------------------------------------------------------------ the session
def radar_coverage(radar: Radar) -> dict[str, float]:
    """A radar's data-sheet coverage (``coverage`` of its sensor config): its instrumented
    range, top elevation and antenna height; the scene's horizon lies on the ellipsoid, so
    the antenna's height above it is the site's alt."""
    return {
        "range_max": radar.range_max,
        "elevation_max_deg": radar.elevation_max_deg,
        "antenna_height": radar.alt,
    }


def session_config(scene: Scene, sensors: Iterable[str] | None = None) -> dict[str, Any]:
    """The session a new user writes from the sensors' data sheets (module docstring)."""
    chosen = None if sensors is None else set(sensors)
    entries: list[dict[str, Any]] = [
        {
            "id": radar.id,
            "site": {"lat": radar.lat, "lon": radar.lon, "alt": radar.alt},
            "p_detect": radar.p_detect,
            "clutter_density": radar.clutter_density,
            "measurement": {
                "kind": "polar",
                "sigma_range": radar.sigma_range,
                "sigma_azimuth_deg": radar.sigma_azimuth_deg,
                "sigma_elevation_deg": radar.sigma_elevation_deg,
            },
            "coverage": radar_coverage(radar),
        }
        for radar in scene.radars
        if chosen is None or radar.id in chosen
    ]
    if scene.equipped and (chosen is None or ADSB in chosen):
        entries.append({"id": ADSB})
    lat, lon, alt = scene.origin
    return {
        "name": "real traffic",
        "state": {"dim": 6, "position": [0, 2, 4], "velocity": [1, 3, 5]},
        "origin": {"lat": lat, "lon": lon, "alt": alt},
        "classes": ["liner", "bomber", "fighter"],
        "sensors": entries,
        "tracking": {"preset": "aircraft"},
    }


@dataclass
class ServiceRun:
    """What the service answered: a picture every :data:`PICTURE_EVERY` s, and the status
    changes of each fused track over every step's answer."""

    sensors: tuple[str, ...]
    pictures: list[tuple[float, list[dict[str, Any]]]] = field(default_factory=list)
    changes: Counter[str] = field(default_factory=Counter)
    lifetimes: dict[str, list[float]] = field(default_factory=dict)
    seconds: float = 0.0


RESENDS = 30
"""How many times :func:`post_as_a_client_would` resends one refused input."""


def post_as_a_client_would(
    client: httpx.Client, url: str, body: dict[str, Any], headers: dict[str, str]
) -> httpx.Response:
    """POST ``body``; a 429 or 503 refusal with ``Retry-After`` (refused before any work,
    nothing applied: the README's limits table) is resent after the time it names, as a client
    following the service's documentation does. A replay faster than real time can meet
    the tenant's work budget per minute on a quiet machine."""
    import time

    for _ in range(RESENDS):
        answer = client.post(url, json=body, headers=headers)
        wait = answer.headers.get("Retry-After")
        if answer.status_code not in (429, 503) or wait is None:
            return answer
        time.sleep(float(wait))
    return answer


def run_service(
    client: httpx.Client,
    scene: Scene,
    sensors: Iterable[str] | None = None,
    config: Callable[[Scene, Iterable[str] | None], dict[str, Any]] = session_config,
) -> ServiceRun:
    """One session over REST with the scene's inputs of ``sensors`` (default all), in order."""
    import time

    chosen = (
        tuple(sorted(set(sensors)))
        if sensors is not None
        else tuple([r.id for r in scene.radars] + ([ADSB] if scene.equipped else []))
    )
    created = client.post("/v1/sessions", json=config(scene, chosen))
    created.raise_for_status()
    sid = created.json()["id"]
    headers = {"Authorization": f"Bearer {created.json()['token']}"}
    run = ServiceRun(chosen)
    last_status: dict[str, str] = {}
    inputs = [item for item in scene.inputs if item.sensor in chosen]
    pictures = np.arange(PICTURE_EVERY, scene.duration + 1e-9, PICTURE_EVERY)
    started = time.perf_counter()
    k = 0
    for when in pictures:
        while k < len(inputs) and inputs[k].time <= when:
            item = inputs[k]
            answer = post_as_a_client_would(
                client, f"/v1/sessions/{sid}/{item.route}", item.body, headers
            )
            if answer.status_code != 200:
                raise RuntimeError(
                    f"{item.sensor} at {item.time}: {answer.status_code} {answer.text[:300]}"
                )
            for track in answer.json()["tracks"]:
                status, before = track["status"], last_status.get(track["id"])
                if before in LIVE and status in LIVE and status != before:
                    run.changes[track["id"]] += 1
                last_status[track["id"]] = status
                span = run.lifetimes.setdefault(track["id"], [item.time, item.time])
                span[1] = item.time
            k += 1
        picture = client.get(f"/v1/sessions/{sid}/tracks", params={"time": when}, headers=headers)
        picture.raise_for_status()
        run.pictures.append((float(when), picture.json()["tracks"]))
    run.seconds = time.perf_counter() - started
    client.delete(f"/v1/sessions/{sid}", headers=headers)
    return run


# ------------------------------------------------------------------ metrics
@dataclass(frozen=True)
class TrafficScore:
    """The scene's metrics for one run (module docstring)."""

    coverage: dict[str, float]
    """Per callsign: pictures held over pictures where a sensor of the run could see it."""
    extra_ids: dict[str, int]
    false_tracks: int
    squared_errors: dict[str, dict[float, float]]
    """Per callsign: picture time → squared 3-D error of the matched track."""
    decisions: dict[str, Counter[str]]
    """Per aircraft kind: decision (or ``undecided``) over its held pictures."""
    status_changes: float
    """Confirmed ↔ coasting changes per fused track per hour of its life (mean over tracks)."""
    flickering_tracks: int
    """Fused tracks with more than one change per minute of their life."""

    @property
    def min_coverage(self) -> float:
        return min(self.coverage.values(), default=1.0)

    @property
    def mean_coverage(self) -> float:
        return float(np.mean(list(self.coverage.values()))) if self.coverage else 1.0

    @property
    def total_extra_ids(self) -> int:
        return sum(self.extra_ids.values())

    def rmse(self, callsigns: Iterable[str] | None = None) -> float:
        chosen = (
            self.squared_errors
            if callsigns is None
            else {c: self.squared_errors.get(c, {}) for c in callsigns}
        )
        values = [v for errors in chosen.values() for v in errors.values()]
        return math.sqrt(float(np.mean(values))) if values else math.nan

    def military_share(self, kind: str) -> float:
        """Share of the decided pictures of ``kind`` decided fighter or bomber."""
        tally = self.decisions.get(kind, Counter())
        decided = sum(n for label, n in tally.items() if label != "undecided")
        return (tally["fighter"] + tally["bomber"]) / decided if decided else 0.0


def decided_shares(score: TrafficScore, kind: str) -> tuple[float, float]:
    """Of ``kind``'s held pictures: the share decided at all, and the share decided fighter
    or bomber (with the preset's Γ, where no behaviour supports ``liner`` alone, kinematics
    can never decide an airliner ``liner``: its honest state is undecided)."""
    tally = score.decisions.get(kind, Counter())
    held = sum(tally.values())
    if not held:
        return 0.0, 0.0
    decided = held - tally["undecided"]
    return decided / held, (tally["fighter"] + tally["bomber"]) / held


def assess(scene: Scene, run: ServiceRun) -> TrafficScore:
    """Match every picture's live tracks to the aircraft and measure (module docstring)."""
    flights = scene.flights
    previous: dict[str, str] = {}
    held: Counter[str] = Counter()
    seen: Counter[str] = Counter()
    ids: dict[str, set[str]] = defaultdict(set)
    matched_ids: set[str] = set()
    shown_ids: set[str] = set()
    squared: dict[str, dict[float, float]] = defaultdict(dict)
    decisions: dict[str, Counter[str]] = defaultdict(Counter)
    for when, tracks in run.pictures:
        live = [track for track in tracks if track["status"] in LIVE]
        present = [f for f in flights if f.present(when)]
        visible = [f for f in present if scene.visible(f, when, run.sensors)]
        shown_ids.update(track["id"] for track in live if track["status"] == "confirmed")
        for flight in visible:
            seen[flight.callsign] += 1
        if not present or not live:
            continue
        truth = np.array([f.at(when)[0] for f in present])
        estimates = np.array([[t["state"][i] for i in (0, 2, 4)] for t in live])
        distance = np.linalg.norm(truth[:, None, :] - estimates[None, :, :], axis=-1)
        cost = distance + SWITCH_PENALTY * np.array(
            [[previous.get(f.callsign) != t["id"] for t in live] for f in present]
        )
        cost = np.where(distance <= MATCH_GATE, cost, 1e9)
        rows, cols = linear_sum_assignment(cost)
        for row, col in zip(rows.tolist(), cols.tolist(), strict=True):
            if distance[row, col] > MATCH_GATE:
                continue
            flight, track = present[row], live[col]
            previous[flight.callsign] = track["id"]
            ids[flight.callsign].add(track["id"])
            matched_ids.add(track["id"])
            squared[flight.callsign][when] = float(distance[row, col] ** 2)
            if flight in visible:
                held[flight.callsign] += 1
            kind = track.get("classification") or {}
            decision = kind.get("decision") if kind.get("decision_state") == "decided" else None
            decisions[flight.kind][decision or "undecided"] += 1
    rates = []
    flickering = 0
    for track_id, (first, last) in run.lifetimes.items():
        hours = max(last - first, PICTURE_EVERY) / 3600.0
        rates.append(run.changes[track_id] / hours)
        if run.changes[track_id] > max(1.0, (last - first) / 60.0):
            flickering += 1
    return TrafficScore(
        coverage={c: held[c] / n for c, n in seen.items() if n},
        extra_ids={f.callsign: max(len(ids[f.callsign]) - 1, 0) for f in flights},
        false_tracks=len(shown_ids - matched_ids),
        squared_errors=dict(squared),
        decisions=dict(decisions),
        status_changes=float(np.mean(rates)) if rates else 0.0,
        flickering_tracks=flickering,
    )


def paired_rmse(
    first: TrafficScore, second: TrafficScore, callsigns: Iterable[str]
) -> tuple[float, float]:
    """The RMSE of two runs over the (aircraft, picture) pairs both hold, of ``callsigns``."""
    one, two = [], []
    for callsign in callsigns:
        a, b = first.squared_errors.get(callsign, {}), second.squared_errors.get(callsign, {})
        for when in a.keys() & b.keys():
            one.append(a[when])
            two.append(b[when])
    if not one:
        return math.nan, math.nan
    return math.sqrt(float(np.mean(one))), math.sqrt(float(np.mean(two)))


def measurement_rmse(scene: Scene, radar: str) -> float:
    """3-D RMS error of a radar's own target detections (its measurement error, in the
    session frame)."""
    errors = np.concatenate([item.truth_errors for item in scene.inputs if item.sensor == radar])
    return math.sqrt(float(np.mean(np.sum(errors**2, axis=1)))) if len(errors) else math.nan
