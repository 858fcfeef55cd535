"""[DH] §5 (Fig 1–4): four vehicles in clutter, RMS position and velocity error vs cheap JPDA.

Each Monte Carlo run of :func:`~core.simulation.road.road_four_scenario`
(T = 0.1 s, σ² = 0.5 m², Poisson clutter) is tracked by the
:class:`LocalTracker` with the road filter of
:func:`~evaluation.tracking.road_config` and one association method
per curve: the evidential method of [DH] itself (``dang_han``, its evidence
scale tied to its gate — the default — and, labelled, the former fixed scale
``s = exp(−D/2)``; :mod:`core.association.pairwise_evidence`), our
``gnn`` and ``denoeux`` (the session default) and the cheap JPDA baseline
([DH] eq 16, B = 0, PDA update). A vehicle's track is the one most of its
detections went to; the RMS error at step k is over the runs where that
track exists at k ([DH] eq 28, M = 50 runs), the time-mean error its mean
over the steps ([DH] eq 29). The share of (run, step) pairs where the track
does not exist, the track losses and the false (confirmed, never covering a
vehicle) tracks are reported next to it (:mod:`core.metrics`; cover radius
:data:`COVER_RADIUS`).

The paper's claim: "the proposed method can get a high tracking accuracy ...
compared with the cheap JPDAF method"; its Fig 2–5 draw the RMS errors of
each vehicle over time (position and velocity, [DH]'s method and cheap JPDA)
with each vehicle's time mean T_j printed in the panel — in our copy only
:data:`PAPER_TIME_MEANS` is legible.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray, IntArray
from core.metrics import coverage, false_tracks, track_losses
from core.simulation import road_four_scenario
from core.simulation.scenario import Scenario
from evaluation.intervals import bootstrap_interval
from evaluation.tracking import TrackedRun, road_config, track_scenario, tracking_scores

METHODS: Mapping[str, tuple[str, Mapping[str, object]]] = {
    "dang_han [DH]": ("dang_han", {}),
    "dang_han, fixed scale": ("dang_han", {"scale": "fixed"}),
    "gnn": ("gnn", {"gate_probability": 0.999}),
    "denoeux (default)": ("denoeux", {"gate_probability": 0.999}),
    "cheap JPDA": ("cheap_jpda", {"bias": 0.0}),
}
"""Curve label → (association method, options)."""
PAPER_TIME_MEANS: Mapping[tuple[str, str, int], float] = {("dang_han [DH]", "position", 2): 0.21}
"""(method, error kind, vehicle) → the T_j [DH] prints: Fig 2, vehicle 2 (unit not printed)."""
COVER_RADIUS = 3.0
"""A track covers a vehicle within this distance (m; ≈ 4σ of one detection)."""
SETTLE = 2
"""First step with a track (two-point initiation: seed at 0, track at 1)."""


@dataclass(frozen=True)
class RoadFourStudy:
    """Errors per method, run, vehicle and step.

    Attributes
    ----------
    seeds : tuple of int
    n_steps : int
    time_interval : float
    position_error, velocity_error : dict
        ``label → (runs, 4, steps)``: ‖x − x̂‖ of position and velocity of each
        vehicle's track (NaN where the track does not exist).
    false_assignments : dict
        ``label → (runs, 4)``: share of each vehicle's detections (from step
        2) not given to its track.
    losses, false_track_counts : dict
        ``label → (runs,)``: :func:`core.metrics.track_losses` and
        :func:`core.metrics.false_tracks` of each run.
    ospa, gospa, switches : dict
        ``label → (runs,)``: time-mean OSPA and GOSPA (order 1, c =
        :data:`COVER_RADIUS`) and identity switches of each run
        (:func:`~evaluation.tracking.tracking_scores`).
    """

    seeds: tuple[int, ...]
    n_steps: int
    time_interval: float
    position_error: Mapping[str, FloatArray]
    velocity_error: Mapping[str, FloatArray]
    false_assignments: Mapping[str, FloatArray]
    losses: Mapping[str, FloatArray]
    false_track_counts: Mapping[str, FloatArray]
    ospa: Mapping[str, FloatArray]
    gospa: Mapping[str, FloatArray]
    switches: Mapping[str, FloatArray]

    @property
    def labels(self) -> tuple[str, ...]:
        """The methods, in curve order."""
        return tuple(self.position_error)

    def errors(self, label: str, kind: str = "position") -> FloatArray:
        """‖x − x̂‖ of position or velocity, (runs, 4, steps), NaN where the track does not exist."""
        return (self.position_error if kind == "position" else self.velocity_error)[label]

    def rms(self, label: str, kind: str = "position") -> FloatArray:
        """RMS error per vehicle and step over the runs where the track exists ([DH] eq 28), (4, steps)."""
        return _rms(self.errors(label, kind))

    def time_mean(self, label: str, kind: str = "position") -> FloatArray:
        """Time-mean of the RMS error from step :data:`SETTLE` on, per vehicle ([DH] eq 29), (4,)."""
        return _time_mean(self.errors(label, kind))

    def time_mean_interval(
        self, label: str, kind: str = "position"
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """:meth:`time_mean` per vehicle and of the vehicles' mean (last entry), (5,) each,
        with its 95 % bootstrap interval over the runs (eq 28 pools the runs, so the
        runs are resampled: :func:`evaluation.intervals.bootstrap_interval`)."""
        errors = self.errors(label, kind)

        def statistic(rows: IntArray) -> FloatArray:
            per_vehicle = _time_mean(errors[rows])
            return np.append(per_vehicle, np.nanmean(per_vehicle))

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # a vehicle never tracked: NaN
            return bootstrap_interval(statistic, errors.shape[0])

    def run_mean_error(self, label: str, kind: str = "position") -> FloatArray:
        """Per run, the mean error over the vehicles and steps ≥ SETTLE with a track, (runs,).

        A per-run quantity, so that the runs give a t interval and methods a
        paired difference (the RMS of [DH] eq 28 pools the runs).
        """
        errors = self.errors(label, kind)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            return np.asarray(np.nanmean(errors[:, :, SETTLE:], axis=(1, 2)), dtype=np.float64)

    def missing(self, label: str) -> float:
        """Share of (run, vehicle, step ≥ SETTLE) without the vehicle's track."""
        return float(np.isnan(self.position_error[label][:, :, SETTLE:]).mean())


def _rms(errors: FloatArray) -> FloatArray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # steps without any track: NaN
        return np.asarray(np.sqrt(np.nanmean(errors**2, axis=0)), dtype=np.float64)


def _time_mean(errors: FloatArray) -> FloatArray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.asarray(np.nanmean(_rms(errors)[:, SETTLE:], axis=1), dtype=np.float64)


def _errors(scenario: Scenario, run: TrackedRun) -> tuple[FloatArray, FloatArray, FloatArray]:
    position = np.full((len(scenario.truths), scenario.n_steps), np.nan)
    velocity = np.full_like(position, np.nan)
    false = np.zeros(len(scenario.truths))
    for index, truth in enumerate(scenario.truths):
        own = run.track_of(truth.target_id)
        if own is None:
            false[index] = 1.0
            continue
        estimate = run.trajectory(own, scenario.n_steps)
        error = estimate - truth.states
        position[index] = np.hypot(error[:, 0], error[:, 2])
        velocity[index] = np.hypot(error[:, 1], error[:, 3])
        wrong, total = run.false_assignments(truth.target_id, own)
        false[index] = wrong / total if total else 0.0
    return position, velocity, false


def _cover(scenario: Scenario, run: TrackedRun) -> list[dict[int, str | None]]:
    """Per step: which confirmed track covers each vehicle (:func:`core.metrics.coverage`)."""
    found: list[dict[int, str | None]] = []
    for step, ids, statuses, states in zip(
        run.steps.tolist(), run.track_ids, run.statuses, run.states, strict=True
    ):
        tracks = {
            track: states[row, [0, 2]]
            for row, (track, status) in enumerate(zip(ids, statuses, strict=True))
            if status in ("confirmed", "coasting")
        }
        truths = {truth.target_id: truth.state_at(step)[[0, 2]] for truth in scenario.truths}
        found.append(coverage(truths, tracks, COVER_RADIUS))
    return found


def road_four_study(
    seeds: Sequence[int] = tuple(range(50)),
    *,
    n_steps: int = 100,
    methods: Mapping[str, tuple[str, Mapping[str, object]]] = METHODS,
    lane_change: tuple[int, int] = (40, 59),
) -> RoadFourStudy:
    """[DH] Fig 2–5: every method on the same M seeded runs (module docstring).

    The scene is :func:`~core.simulation.road_four_scenario` with its own
    clutter and geometry (one definition, as in the figure's plan view).
    """
    position: dict[str, FloatArray] = {}
    velocity: dict[str, FloatArray] = {}
    false: dict[str, FloatArray] = {}
    losses: dict[str, FloatArray] = {}
    false_counts: dict[str, FloatArray] = {}
    scores: dict[str, dict[str, FloatArray]] = {"ospa": {}, "gospa": {}, "switches": {}}
    scenarios = [
        road_four_scenario(seed, n_steps=n_steps, lane_change=lane_change) for seed in seeds
    ]
    for label, (method, options) in methods.items():
        rows = []
        measured = []
        for scenario in scenarios:
            config = road_config(
                scenario, association_method=method, association_options=dict(options)
            )
            run = track_scenario(scenario, config)
            covered = _cover(scenario, run)
            measured.append(tracking_scores(scenario, run, COVER_RADIUS, first_step=SETTLE))
            rows.append(
                (
                    *_errors(scenario, run),
                    track_losses(covered),
                    false_tracks(run.confirmed_ids(), covered),
                )
            )
        position[label] = np.stack([row[0] for row in rows])
        velocity[label] = np.stack([row[1] for row in rows])
        false[label] = np.stack([row[2] for row in rows])
        losses[label] = np.array([row[3] for row in rows], dtype=np.float64)
        false_counts[label] = np.array([row[4] for row in rows], dtype=np.float64)
        scores["ospa"][label] = np.array([m.ospa for m in measured])
        scores["gospa"][label] = np.array([m.gospa for m in measured])
        scores["switches"][label] = np.array([m.identity_switches for m in measured], dtype=float)
    return RoadFourStudy(
        seeds=tuple(seeds),
        n_steps=n_steps,
        time_interval=scenarios[0].time_interval,
        position_error=position,
        velocity_error=velocity,
        false_assignments=false,
        losses=losses,
        false_track_counts=false_counts,
        ospa=scores["ospa"],
        gospa=scores["gospa"],
        switches=scores["switches"],
    )
