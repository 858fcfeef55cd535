"""One IMM step and one full tracker step with the 13-model aircraft bank.

For 10, 100 and 1000 tracks, times one step of :mod:`core.tracking.imm` on all
tracks at once and, in the same run, filterpy's ``IMMEstimator`` looped over
the same tracks with the same measurements. Prints the machine. Floor
(docs/algorithms.md / issue 4): 1000 tracks ≤ 50 ms per step.

Then one full :class:`~core.tracking.tracker.LocalTracker` scan (predict,
closest-model gating, GNN, update, score, life cycle, initiation) on the same
numbers of well-separated confirmed aircraft, with and without the credal
classification (:class:`~core.classification.batched.BatchedCredalClassifier`,
dense masses vectorised over tracks). The floor holds for both columns.

Then, with 1000 confirmed tracks and credal classes (issue 12): the IMM
prediction and the whole scan after a gap of 1 s, 3000 s and 1e6 s (one
closed-form step each). After 1e6 s no detection can keep a track alive
(``LocalTracker._can_be_hit``): nothing is gated, the scan costs less than
after 1 s. After 3000 s a hit could still, by the bound, but every gate covers
the whole scene: every detection gates with every track and the assignment
is dense (T × M), the slowest gap (docs/algorithms.md §7.5); scans at jittered times (k + U(−0.12, 0.12) s) against the
regular grid; and the same scan in 3-D (the preset's vertical axis added).

Run: ``.venv/bin/python bench/tracking.py`` (or ``make bench``).
"""

from __future__ import annotations

import os
import platform
import statistics
import time
from collections.abc import Callable

import numpy as np
from filterpy.kalman import IMMEstimator, KalmanFilter

from core.tracking import IMMPredictor, IMMState, IMMUpdater, ModelBank, two_point_initiation
from core.tracking.config import LocalTrackerConfig
from core.tracking.presets import aircraft
from core.tracking.tracker import LocalTracker

SEED = 20260101
TRACK_COUNTS = (10, 100, 1000)
FLOOR_MS = 50.0


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as cpuinfo:
            for line in cpuinfo:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def _median_ms(run: Callable[[], object], repeats: int) -> float:
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        samples.append((time.perf_counter() - start) * 1e3)
    return statistics.median(samples)


def _filterpy_estimators(bank: ModelBank, state: IMMState) -> list[IMMEstimator]:
    estimators = []
    for t in range(state.n_tracks):
        filters = []
        for j, model in enumerate(bank.models):
            kf = KalmanFilter(dim_x=4, dim_z=2)
            kf.x = state.means[t, j].reshape(4, 1).copy()
            kf.P = state.covariances[t, j].copy()
            kf.F = model.transition.copy()
            kf.Q = model.process_noise.copy()
            kf.B = model.input_offset.reshape(4, 1).copy()
            kf.H = bank.measurement.matrix.copy()
            kf.R = bank.measurement.noise_covariance.copy()
            filters.append(kf)
        estimators.append(
            IMMEstimator(filters, state.mode_probabilities[t].copy(), bank.mode_transition.copy())
        )
    return estimators


def main() -> None:
    bank = aircraft().bank
    predictor, updater = IMMPredictor(bank), IMMUpdater(bank)
    rng = np.random.default_rng(SEED)
    print(f"machine: {os.cpu_count()} logical cores, {_cpu_model()}")
    print(f"python {platform.python_version()}, numpy {np.__version__}; seed {SEED}")
    print("one IMM step (mixing + predict + update), 13-model aircraft bank, median ms")
    print(f"{'tracks':>7} {'batched':>10} {'filterpy':>10} {'ratio':>8} {'per track (µs)':>15}")
    batched_1000 = float("nan")
    for tracks in TRACK_COUNTS:
        first = rng.uniform(-5e4, 5e4, (tracks, 2))
        second = first + rng.uniform(-250, 250, (tracks, 2))
        state = two_point_initiation(bank, first, second, 1.0)
        # Warm the filter up a few steps so the mode probabilities are not uniform.
        for _ in range(5):
            z = state.combined()[0][:, [0, 2]] + rng.normal(0, 0.45, (tracks, 2))
            state = updater.update(predictor.predict(state), z).state
        z = state.combined()[0][:, [0, 2]] + rng.normal(0, 0.45, (tracks, 2))
        current = state

        def batched_step(current: IMMState = current, z: np.ndarray = z) -> object:
            return updater.update(predictor.predict(current), z)

        batched = _median_ms(batched_step, repeats=30 if tracks < 1000 else 15)
        estimators = _filterpy_estimators(bank, state)
        columns = [z[t].reshape(2, 1) for t in range(tracks)]

        def filterpy_step(
            estimators: list[IMMEstimator] = estimators, columns: list[np.ndarray] = columns
        ) -> object:
            unit = np.ones((1, 1))
            for estimator, measurement in zip(estimators, columns, strict=True):
                estimator.predict(u=unit)
                estimator.update(measurement)
            return estimators

        looped = _median_ms(filterpy_step, repeats=5 if tracks < 1000 else 3)
        if tracks == 1000:
            batched_1000 = batched
        print(
            f"{tracks:>7} {batched:>10.2f} {looped:>10.1f} {looped / batched:>7.0f}x "
            f"{1e3 * batched / tracks:>15.1f}"
        )
    verdict = "meets" if batched_1000 <= FLOOR_MS else "MISSES"
    print(f"floor: 1000 tracks <= {FLOOR_MS:.0f} ms per step -> {verdict} ({batched_1000:.2f} ms)")
    tracker_table(rng)


def _tracker_scans(
    rng: np.random.Generator,
    tracks: int,
    steps: int,
    times: np.ndarray | None = None,
    axes: int = 2,
) -> list[np.ndarray]:
    """Detections of ``tracks`` aircraft on a 2 km grid flying straight at 200 m/s, R = 0.2 I
    (at scan times ``times``, default 0, 1, 2, …; in 3-D at altitudes 1–10 km, climbing at 5 m/s)."""
    side = int(np.ceil(np.sqrt(tracks)))
    grid = np.stack(np.meshgrid(np.arange(side), np.arange(side)), axis=-1).reshape(-1, 2)
    start = 2000.0 * grid[:tracks].astype(np.float64)
    heading = rng.uniform(0, 2 * np.pi, tracks)
    velocity = 200.0 * np.stack([np.cos(heading), np.sin(heading)], axis=1)
    if axes == 3:
        start = np.column_stack([start, rng.uniform(1000.0, 10000.0, tracks)])
        velocity = np.column_stack([velocity, np.full(tracks, 5.0)])
    at = np.arange(steps, dtype=np.float64) if times is None else times
    return [start + t * velocity + rng.normal(0.0, np.sqrt(0.2), (tracks, axes)) for t in at]


def tracker_table(rng: np.random.Generator) -> None:
    """Median time of one full tracker scan with T confirmed tracks."""
    print()
    print("one LocalTracker scan (13-model aircraft IMM, gnn, closest model), median ms")
    print(f"{'tracks':>7} {'no classes':>11} {'credal':>10} {'per track (µs)':>15}")
    warm, timed = 6, 10
    kinematic_1000 = credal_1000 = float("nan")
    for tracks in TRACK_COUNTS:
        scans = _tracker_scans(rng, tracks, warm + timed)
        row = []
        for classification in (None, LocalTrackerConfig().classification):
            tracker = LocalTracker(
                LocalTrackerConfig(fields_of_view={"radar": None}, classification=classification)
            )
            samples = []
            for k, detections in enumerate(scans):
                start = time.perf_counter()
                output = tracker.step(float(k), detections)
                if k >= warm:
                    samples.append((time.perf_counter() - start) * 1e3)
            confirmed = sum(track.status.value == "confirmed" for track in output.tracks)
            if confirmed < tracks:
                raise SystemExit(f"bench setup: {confirmed} of {tracks} tracks confirmed")
            row.append(statistics.median(samples))
        if tracks == 1000:
            kinematic_1000, credal_1000 = row
        print(f"{tracks:>7} {row[0]:>11.2f} {row[1]:>10.2f} {1e3 * row[0] / tracks:>15.1f}")
    for label, value in (("no classes", kinematic_1000), ("credal classes", credal_1000)):
        verdict = "meets" if value <= FLOOR_MS else "MISSES"
        print(
            f"floor: 1000 tracks <= {FLOOR_MS:.0f} ms per tracker scan ({label}) -> "
            f"{verdict} ({value:.2f} ms)"
        )


def _confirmed_tracker(
    config: LocalTrackerConfig, scans: list[np.ndarray], times: np.ndarray
) -> LocalTracker:
    tracker = LocalTracker(config)
    for scan_time, detections in zip(times, scans, strict=True):
        output = tracker.step(float(scan_time), detections)
    confirmed = sum(track.status.value == "confirmed" for track in output.tracks)
    if confirmed < 0.99 * len(scans[0]):  # a 0.999 gate misses about one pair in a thousand
        raise SystemExit(f"bench setup: {confirmed} of {len(scans[0])} tracks confirmed")
    return tracker


def _scan_ms(
    config: LocalTrackerConfig, tracker: LocalTracker, scan_time: float, detections: np.ndarray
) -> float:
    """Median time of one scan at ``scan_time`` from the tracker's state (restored before each run)."""
    exported = tracker.export()
    samples = []
    for _ in range(7):
        fresh = LocalTracker.restore(config, exported)
        start = time.perf_counter()
        fresh.step(scan_time, detections)
        samples.append((time.perf_counter() - start) * 1e3)
    return statistics.median(samples)


def time_step_table(rng: np.random.Generator) -> None:
    """Gaps, jitter and 3-D with 1000 confirmed tracks and credal classes (module docstring)."""
    tracks, warm = 1000, 6
    config = LocalTrackerConfig(fields_of_view={"radar": None})
    print()
    print(f"time steps and dimensions, {tracks} confirmed tracks, credal classes, median ms")
    times = np.arange(warm, dtype=np.float64)
    scans = _tracker_scans(rng, tracks, warm + 1)
    tracker = _confirmed_tracker(config, scans[:warm], times)
    state = tracker._state  # the live tracks' IMM state
    predictor = tracker.predictor
    for label, gap in (("after 1 s", 1.0), ("after 3000 s", 3000.0), ("after 1e6 s", 1e6)):
        predict_ms = _median_ms(lambda gap=gap: predictor.predict(state, gap), repeats=15)
        scan_ms = _scan_ms(config, tracker, float(times[-1] + gap), scans[-1])
        print(f"  scan {label:<12} IMM predict {predict_ms:7.2f}   whole scan {scan_ms:7.2f}")
    jittered_times = np.arange(16, dtype=np.float64) + rng.uniform(-0.12, 0.12, 16)
    jittered_times[0] = 0.0
    for label, at in (
        ("regular grid", np.arange(16, dtype=np.float64)),
        ("jittered", jittered_times),
    ):
        scans = _tracker_scans(rng, tracks, 16, at)
        jittered = _confirmed_tracker(config, scans[:-1], at[:-1])
        print(
            f"  scan {label:<12} whole scan {_scan_ms(config, jittered, float(at[-1]), scans[-1]):7.2f}"
        )
    planar_ms = float("nan")
    for axes in (2, 3):
        config_axes = LocalTrackerConfig(
            fields_of_view={"radar": None},
            axes=axes,
            measurement_noise=tuple(tuple(row) for row in (0.2 * np.eye(axes)).tolist()),
        )
        scans = _tracker_scans(rng, tracks, warm + 1, axes=axes)
        spatial = _confirmed_tracker(config_axes, scans[:warm], times)
        scan_ms = _scan_ms(config_axes, spatial, float(warm), scans[-1])
        planar_ms = scan_ms if axes == 2 else planar_ms
        ratio = "" if axes == 2 else f"  ({scan_ms / planar_ms:.2f}x the 2-D scan)"
        print(f"  scan in {axes}-D{'':<8} whole scan {scan_ms:7.2f}{ratio}")


if __name__ == "__main__":
    main()
    time_step_table(np.random.default_rng(SEED + 1))
