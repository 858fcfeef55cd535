"""One fusion step of the session engine: 3 sensors, n spread targets, default method.

Prints the median time of ``SessionEngine.apply`` for one sensor's report once
every target has a fused track fed by all three sensors; then a 20-target
report into sessions of 1 and 8 sensors (CPU time: the machine is shared).
Never asserts a time.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from machine import describe_machine

from core.fusion.config import FusionConfig, SensorSpec
from core.fusion.engine import SessionEngine
from core.fusion.motion import MotionModel, StateLayout
from core.fusion.reports import ReportedTrack, TrackReport
from core.simulation.tracklists import estimate_covariance

SENSORS = ("s1", "s2", "s3")
SIGMA = 5.0


def spread_targets(n: int, rng: np.random.Generator) -> np.ndarray:
    """Targets on a jittered grid 200 m apart, 5-15 m/s in random directions (each has ~1 candidate)."""
    side = int(np.ceil(np.sqrt(n)))
    cells = np.stack(np.meshgrid(np.arange(side), np.arange(side)), axis=-1).reshape(-1, 2)[:n]
    positions = cells * 200.0 + rng.uniform(-30.0, 30.0, (n, 2))
    speed = rng.uniform(5.0, 15.0, n)
    heading = rng.uniform(0.0, 2.0 * np.pi, n)
    return np.column_stack(
        [positions[:, 0], speed * np.cos(heading), positions[:, 1], speed * np.sin(heading)]
    )


def sensor_report(
    sensor: str, time_s: float, truth: np.ndarray, rng: np.random.Generator
) -> TrackReport:
    covariance = estimate_covariance(SIGMA, SIGMA / 2.0)
    root = np.linalg.cholesky(covariance)
    moved = truth.copy()
    moved[:, 0] += truth[:, 1] * time_s
    moved[:, 2] += truth[:, 3] * time_s
    noisy = moved + rng.standard_normal(truth.shape) @ root.T
    return TrackReport(
        sensor,
        time_s,
        tuple(ReportedTrack(f"{sensor}-{k}", noisy[k], covariance) for k in range(len(truth))),
    )


def main() -> None:
    print(describe_machine())
    config = FusionConfig(
        motion=MotionModel(StateLayout(4, (0, 2), (1, 3)), q=0.5),
        sensors=tuple(SensorSpec(sensor) for sensor in SENSORS),
    )
    print(
        f"\nOne track-list report into a session (default: {config.association_method}, "
        f"{config.state_fusion.value}), 3 sensors, spread targets; median ms per report"
    )
    print(f"{'targets':>8} {'first contact':>14} {'steady':>10} {'fused tracks':>13}")
    for n in (10, 100, 1000):
        rng = np.random.default_rng(n)
        truth = spread_targets(n, rng)
        engine = SessionEngine(config)
        reports = [
            sensor_report(sensor, step + k / 3.0, truth, rng)
            for step in range(8)
            for k, sensor in enumerate(SENSORS)
        ]
        first: list[float] = []
        steady: list[float] = []
        for index, report in enumerate(reports):
            t0 = time.perf_counter()
            engine.apply(report)
            elapsed = (time.perf_counter() - t0) * 1e3
            (first if index < len(SENSORS) else steady).append(elapsed)
        # The same steady report applied to restored copies, for more samples.
        extra_report = sensor_report("s1", 8.0, truth, rng)
        state = engine.export()
        for _ in range(5):
            clone = SessionEngine.restore(config, state)
            t0 = time.perf_counter()
            clone.apply(extra_report)
            steady.append((time.perf_counter() - t0) * 1e3)
        print(
            f"{n:>8} {np.median(first):>14.2f} {np.median(steady):>10.2f} {len(engine.tracks):>13}"
        )
    print("floor: 1000 targets <= 100 ms per report (steady)")


def service_sized() -> None:
    """A service-sized report (20 targets) into sessions of 1 and of 8 sensors reporting in
    turn: median CPU ms per report once every track is fed by every sensor (the step the
    WebSocket p50 of the service spends in the engine)."""
    print("\n20-target report, sensors reporting in turn; median CPU ms per report")
    print(f"{'sensors':>8} {'per report':>11}")
    for count in (1, 8):
        names = [f"s{k}" for k in range(count)]
        config = FusionConfig(
            motion=MotionModel(StateLayout(4, (0, 2), (1, 3)), q=0.5),
            sensors=tuple(SensorSpec(name) for name in names),
        )
        rng = np.random.default_rng(count)
        truth = spread_targets(20, rng)
        engine = SessionEngine(config)
        reports = [
            sensor_report(name, step + k / count, truth, rng)
            for step in range(40)
            for k, name in enumerate(names)
        ]
        samples = []
        for index, report in enumerate(reports):
            t0 = time.thread_time()
            engine.apply(report)
            if index >= len(reports) // 2:
                samples.append((time.thread_time() - t0) * 1e3)
        print(f"{count:>8} {np.median(samples):>11.3f}")


if __name__ == "__main__":
    main()
    service_sized()
