"""Run a :class:`~core.tracking.tracker.LocalTracker` over a scenario and keep what the studies measure.

Shared by the tracker experiments ([MTT] §6.2, [DH] §5, [HZ] §6):
:func:`track_scenario` feeds every scan of a seeded scenario to a fresh
tracker (the detections' target ids are never shown to it) and records, per
scan, every live track's status, combined state and BetP, and the track each
detection was assigned to. :func:`road_config` is the tracker of the road
scenes ([HZ] §6, [DH] §5): a constant-velocity filter with the sensors'
rectangles as fields of view.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, fields

import numpy as np

from core.arrays import FloatArray, IntArray
from core.geometry import PolygonView
from core.lifecycle import LifeCycleConfig
from core.metrics import coverage, gospa, identity_switches, ospa
from core.simulation.scenario import CLUTTER, Region, Scenario
from core.tracking.config import LocalTrackerConfig
from core.tracking.models import ModelBank
from core.tracking.tracker import LocalTracker

NO_TERMINATION: Mapping[str, object] = {"termination_probability": 0.0, "score_ceiling": None}
"""[HZ] §6 "termination strategy switched off": no gate-emptiness test and the raw SPRT
(a long-lived track is then never deleted by a few dozen misses)."""


def rectangle(region: Region) -> PolygonView:
    """A scenario's axis-aligned rectangle as a polygon field of view."""
    (x0, x1), (y0, y1) = region
    return PolygonView(((x0, y0), (x1, y0), (x1, y1), (x0, y1)))


def road_bank(
    variance: float, noise_intensity: float = 1.0, time_interval: float = 0.1
) -> ModelBank:
    """A road-vehicle filter: constant velocity, process noise intensity ``noise_intensity`` (m²/s³)."""
    return ModelBank.from_config(
        {
            "time_interval": time_interval,
            "measurement": {"variance": variance},
            "models": [
                {"kind": "constant_velocity", "name": "cv", "noise_intensity": noise_intensity}
            ],
        }
    )


def road_config(scenario: Scenario, **options: object) -> LocalTrackerConfig:
    """The road scenes' tracker: their sensors' rectangles, clutter density ~1e-3 per m².

    ``options`` override any :class:`LocalTrackerConfig` or
    :class:`~core.lifecycle.LifeCycleConfig` field; ``noise_intensity``
    (default 1 m²/s³, σ_a = 1 m/s²) sets the road filter's process noise.
    """
    views = {name: rectangle(region) for name, region in scenario.sensor_regions.items()}
    intensity = float(options.pop("noise_intensity", 1.0))  # type: ignore[arg-type]
    settings: dict[str, object] = {
        "bank": road_bank(
            float(scenario.measurement_noise[0, 0]), intensity, scenario.time_interval
        ),
        "time_interval": scenario.time_interval,
        "fields_of_view": views,
        "max_speed": 30.0,
    }
    settings.update(options)
    settings["life_cycle"] = life_cycle(
        settings, false_target_density=1e-3, new_target_density=1e-4
    )
    return LocalTrackerConfig.paper(**settings)


def life_cycle(settings: dict[str, object], **defaults: object) -> LifeCycleConfig:
    """The paper life cycle (:meth:`LifeCycleConfig.paper`, 2-D) with the
    :class:`LifeCycleConfig` fields taken out of ``settings`` (over ``defaults``)."""
    names = {entry.name for entry in fields(LifeCycleConfig)}
    chosen = {**defaults, **{name: settings.pop(name) for name in list(settings) if name in names}}
    return LifeCycleConfig.paper(2, **chosen)


@dataclass(frozen=True)
class TrackedRun:
    """A tracker's outputs over one scenario, in plain arrays.

    Attributes
    ----------
    steps : ndarray of int64, shape (s,)
        The step of each scan (several scans per step with several sensors).
    track_ids : tuple of tuple of str
        The live tracks after each scan (terminated ones included in the scan that ends them).
    statuses, reasons : tuple of tuple of str
        Their status and its reason, aligned with ``track_ids``.
    states : tuple of ndarray, shapes (t, 4)
        Their combined estimates ``[x, ẋ, y, ẏ]``.
    pignistic : tuple of ndarray, shapes (t, c)
        Their class BetP (NaN rows: no classification or undefined).
    detection_steps : ndarray of int64, shape (m,)
        Step of every detection of the run.
    detection_targets : ndarray of int64, shape (m,)
        Its origin (``CLUTTER`` = −1 for false alarms).
    detection_tracks : tuple of str or None
        The track it was assigned to (None: unassigned or a seed).
    measurements : ndarray, shape (m, 2)
    scores : tuple of ndarray, shapes (t,)
        The live tracks' scores L ([MTT] eq 16), aligned with ``track_ids``.
    """

    steps: IntArray
    track_ids: tuple[tuple[str, ...], ...]
    statuses: tuple[tuple[str, ...], ...]
    reasons: tuple[tuple[str, ...], ...]
    states: tuple[FloatArray, ...]
    pignistic: tuple[FloatArray, ...]
    detection_steps: IntArray
    detection_targets: IntArray
    detection_tracks: tuple[str | None, ...]
    measurements: FloatArray
    scores: tuple[FloatArray, ...] = ()

    def assigned(
        self, target: int, first_step: int = 0, last_step: int | None = None
    ) -> list[str | None]:
        """The tracks the target's detections went to, within the steps given (inclusive)."""
        last = int(self.steps.max()) if last_step is None else last_step
        rows = np.flatnonzero(
            (self.detection_targets == target)
            & (self.detection_steps >= first_step)
            & (self.detection_steps <= last)
        )
        return [self.detection_tracks[row] for row in rows.tolist()]

    def track_of(
        self, target: int, first_step: int = 0, last_step: int | None = None
    ) -> str | None:
        """The track most of the target's detections went to in the steps given (None: none)."""
        counts = Counter(t for t in self.assigned(target, first_step, last_step) if t is not None)
        return counts.most_common(1)[0][0] if counts else None

    def false_assignments(
        self, target: int, own: str | None, first_step: int = 2
    ) -> tuple[int, int]:
        """(false, total): the target's detections from ``first_step`` on not given to ``own``."""
        chosen = self.assigned(target, first_step)
        return sum(track != own for track in chosen), len(chosen)

    def taken_by(self, track: str, origin: int, first_step: int = 0) -> IntArray:
        """Steps at which ``track`` took a detection of ``origin`` (a target id or ``CLUTTER``)."""
        rows = [
            row
            for row, chosen in enumerate(self.detection_tracks)
            if chosen == track
            and self.detection_targets[row] == origin
            and self.detection_steps[row] >= first_step
        ]
        return np.asarray(self.detection_steps[rows], dtype=np.int64)

    def trajectory(self, track: str, n_steps: int) -> FloatArray:
        """The track's state after the last scan of every step, shape (n_steps, 4); NaN when absent."""
        out = np.full((n_steps, 4), np.nan)
        for step, ids, states in zip(self.steps.tolist(), self.track_ids, self.states, strict=True):
            if track in ids:
                out[step] = states[ids.index(track)]
        return out

    def pignistic_of(self, track: str, n_steps: int, n_classes: int) -> FloatArray:
        """The track's BetP after every step, shape (n_steps, c); NaN when absent."""
        out = np.full((n_steps, n_classes), np.nan)
        for step, ids, betp in zip(
            self.steps.tolist(), self.track_ids, self.pignistic, strict=True
        ):
            if track in ids:
                out[step] = betp[ids.index(track)]
        return out

    def score_of(self, track: str, n_steps: int) -> FloatArray:
        """The track's score after the last scan of every step, shape (n_steps,); NaN when absent."""
        out = np.full(n_steps, np.nan)
        for step, ids, scores in zip(self.steps.tolist(), self.track_ids, self.scores, strict=True):
            if track in ids:
                out[step] = scores[ids.index(track)]
        return out

    def status_of(self, track: str) -> dict[int, tuple[str, str]]:
        """``{step: (status, reason)}`` of a track after the last scan of each step."""
        found: dict[int, tuple[str, str]] = {}
        for step, ids, statuses, reasons in zip(
            self.steps.tolist(), self.track_ids, self.statuses, self.reasons, strict=True
        ):
            if track in ids:
                row = ids.index(track)
                found[step] = (statuses[row], reasons[row])
        return found

    def confirmed_ids(self) -> set[str]:
        """Every track that was confirmed at some scan."""
        return {
            track
            for ids, statuses in zip(self.track_ids, self.statuses, strict=True)
            for track, status in zip(ids, statuses, strict=True)
            if status == "confirmed"
        }


@dataclass(frozen=True)
class TrackingScores:
    """EVALUATION's tracking metrics of one run, from the tracker's confirmed tracks.

    Attributes
    ----------
    ospa : float
        Time mean of the per-step OSPA (order 1, cut-off ``cutoff``) between the
        positions of the confirmed (and coasting) tracks and of the live truths.
    gospa : float
        Time mean of the per-step GOSPA (α = 2, order 1, same cut-off).
    identity_switches : int
        :func:`core.metrics.identity_switches` of the per-step coverage.
    cutoff : float
        The cut-off c (m), also the coverage radius.
    """

    ospa: float
    gospa: float
    identity_switches: int
    cutoff: float


def tracking_scores(
    scenario: Scenario, run: TrackedRun, cutoff: float, first_step: int = 2
) -> TrackingScores:
    """OSPA, GOSPA and identity switches of ``run`` from ``first_step`` on (after initiation)."""
    last_scan: dict[int, int] = {}
    for index, step in enumerate(run.steps.tolist()):
        last_scan[step] = index
    ospas: list[float] = []
    gospas: list[float] = []
    covered: list[dict[int, str | None]] = []
    for step in sorted(last_scan):
        if step < first_step:
            continue
        index = last_scan[step]
        ids, statuses, states = run.track_ids[index], run.statuses[index], run.states[index]
        rows = [r for r, status in enumerate(statuses) if status in ("confirmed", "coasting")]
        estimates = states[rows][:, [0, 2]].reshape(-1, 2)
        live = [truth for truth in scenario.truths if truth.alive(step)]
        truths = np.array([truth.state_at(step)[[0, 2]] for truth in live]).reshape(-1, 2)
        ospas.append(ospa(estimates, truths, cutoff))
        gospas.append(gospa(estimates, truths, cutoff).distance)
        covered.append(
            coverage(
                {truth.target_id: position for truth, position in zip(live, truths, strict=True)},
                {ids[r]: estimates[i] for i, r in enumerate(rows)},
                cutoff,
            )
        )
    return TrackingScores(
        ospa=float(np.mean(ospas)) if ospas else float("nan"),
        gospa=float(np.mean(gospas)) if gospas else float("nan"),
        identity_switches=identity_switches(covered),
        cutoff=cutoff,
    )


def track_scenario(scenario: Scenario, config: LocalTrackerConfig) -> TrackedRun:
    """Feed every scan of ``scenario`` to a fresh tracker and record its outputs."""
    tracker = LocalTracker(config)
    steps: list[int] = []
    ids: list[tuple[str, ...]] = []
    statuses: list[tuple[str, ...]] = []
    reasons: list[tuple[str, ...]] = []
    states: list[FloatArray] = []
    betps: list[FloatArray] = []
    det_steps: list[IntArray] = []
    det_targets: list[IntArray] = []
    det_tracks: list[str | None] = []
    measurements: list[FloatArray] = []
    scores: list[FloatArray] = []
    for scan in scenario.scans:
        sensor = scan.sensor if scan.sensor in config.fields_of_view else None
        output = tracker.step(scan.time, scan.measurements, sensor=sensor)
        steps.append(scan.step)
        ids.append(tuple(track.id for track in output.tracks))
        statuses.append(tuple(track.status.value for track in output.tracks))
        reasons.append(tuple(track.reason.value for track in output.tracks))
        states.append(np.array([track.state for track in output.tracks]).reshape(-1, 4))
        scores.append(np.array([track.score for track in output.tracks], dtype=np.float64))
        rows = [
            np.full(3, np.nan) if track.pignistic is None else track.pignistic
            for track in output.tracks
        ]
        width = max((len(row) for row in rows), default=3)
        betps.append(
            np.array(
                [row if len(row) == width else np.full(width, np.nan) for row in rows]
            ).reshape(-1, width)
        )
        det_steps.append(np.full(len(scan.target_ids), scan.step, dtype=np.int64))
        det_targets.append(scan.target_ids)
        det_tracks.extend(output.assignment)
        measurements.append(scan.measurements)
    return TrackedRun(
        steps=np.asarray(steps, dtype=np.int64),
        track_ids=tuple(ids),
        statuses=tuple(statuses),
        reasons=tuple(reasons),
        states=tuple(states),
        pignistic=tuple(betps),
        detection_steps=np.concatenate(det_steps),
        detection_targets=np.concatenate(det_targets).astype(np.int64),
        detection_tracks=tuple(det_tracks),
        measurements=np.concatenate(measurements).reshape(-1, 2),
        scores=tuple(scores),
    )


__all__ = [
    "CLUTTER",
    "NO_TERMINATION",
    "TrackedRun",
    "TrackingScores",
    "rectangle",
    "road_bank",
    "road_config",
    "track_scenario",
    "tracking_scores",
]
