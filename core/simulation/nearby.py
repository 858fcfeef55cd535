"""Nearby targets of [MTT] §6.2: ``close-pair`` (Fig 16) and ``crossing`` (Fig 17–18).

Both use the aircraft dynamics ([MTT] eq 24, ΔT = 1 s, Q = 0.005 B Bᵀ) and one
sensor with P_D = 1.

``close-pair``
    Two targets flying in parallel ``separation`` metres apart (along y) at
    the same velocity. [MTT] §6.2.1 varies the "noise variance" "from 0 % to
    200 % of the distance between the two targets". **Reading**
    (``noise_reading``): ``"variance"`` (default, the text's letter) — the
    variance per axis is ``noise_ratio × separation`` in m² (a distance read
    as a number of m²: σ = √(r d)); ``"std"`` — the standard deviation per
    axis is ``noise_ratio × separation`` (the percentage of a distance
    applied to a distance). No process noise
    in the truth by default (``noise_intensity``): two independent random
    walks would drift apart by metres and the pair would not stay close.
``crossing``
    Target 1 (a fighter) flies at constant velocity, accelerates at (4g, 4g)
    during steps 23–24 and decelerates at (−4g, −4g) during steps 35–36;
    target 2 flies at constant velocity. Target 1 starts behind, passes target
    2 around step 34 and they then fly ``final_separation`` metres apart per
    axis ("the scenario is the same in x direction" as in y, Fig 17).
    **Reading:** positions and speeds are ours; Fig 17 is not in the text. The
    truth has no process noise by default (``noise_intensity``) so the pair
    stays ``final_separation`` apart instead of drifting by a random walk.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from core.errors import ScenarioError
from core.simulation.scenario import Manoeuvre, Scenario, TargetTruth, observe, propagate
from core.tracking.presets import GRAVITY

NoiseReading = Literal["variance", "std"]
NOISE_READINGS: tuple[NoiseReading, ...] = ("variance", "std")
"""[MTT] §6.2.1's "noise variance … % of the distance" (module docstring)."""


def close_pair_variance(noise_ratio: float, separation: float, reading: NoiseReading) -> float:
    """The measurement variance per axis (m²) of ``close-pair`` under ``reading``."""
    if reading == "variance":
        return noise_ratio * separation
    return (noise_ratio * separation) ** 2


def close_pair_scenario(
    seed: int = 0,
    *,
    noise_ratio: float = 0.5,
    separation: float = 10.0,
    n_steps: int = 60,
    noise_intensity: float = 0.0,
    noise_reading: NoiseReading = "variance",
) -> Scenario:
    """Build ``close-pair`` (see the module docstring)."""
    if not (np.isfinite(noise_ratio) and noise_ratio >= 0.0):
        raise ScenarioError(f"noise_ratio must be >= 0, got {noise_ratio!r}")
    if noise_reading not in NOISE_READINGS:
        raise ScenarioError(f"noise_reading must be one of {NOISE_READINGS}, got {noise_reading!r}")
    if not (np.isfinite(separation) and separation > 0.0):
        raise ScenarioError(f"separation must be positive, got {separation!r}")
    rng = np.random.default_rng(seed)
    truths = tuple(
        TargetTruth(
            target_id,
            0,
            propagate((0.0, 150.0, offset, 0.0), np.zeros((n_steps, 2)), 1.0, noise_intensity, rng),
        )
        for target_id, offset in ((1, 0.0), (2, separation))
    )
    noise = close_pair_variance(noise_ratio, separation, noise_reading) * np.eye(2)
    scans = observe(truths, n_steps, 1.0, noise, rng, sensor="radar")
    return Scenario(
        name="close-pair",
        seed=seed,
        time_interval=1.0,
        n_steps=n_steps,
        truths=truths,
        manoeuvres=(),
        scans=tuple(scans),
        measurement_noise=noise,
    )


def crossing_scenario(
    seed: int = 0,
    *,
    n_steps: int = 60,
    final_separation: float = 5.0,
    noise_intensity: float = 0.0,
    measurement_variance: float = 0.2,
) -> Scenario:
    """Build ``crossing`` (see the module docstring)."""
    if n_steps < 40:
        raise ScenarioError("the crossing scenario needs at least 40 steps")
    rng = np.random.default_rng(seed)
    windows = (
        Manoeuvre(1, 23, 24, "4g", (4.0 * GRAVITY, 4.0 * GRAVITY)),
        Manoeuvre(1, 35, 36, "4g", (-4.0 * GRAVITY, -4.0 * GRAVITY)),
    )
    inputs = np.zeros((n_steps, 2))
    for window in windows:
        inputs[window.first_step : window.last_step + 1] = window.value
    start_1 = (0.0, 40.0, 0.0, 40.0)
    nominal = propagate(start_1, inputs, 1.0, 0.0, rng)
    # Target 2 flies at 40 m/s and is `final_separation` behind target 1 once it has slowed.
    offset = nominal[36, 0] - final_separation - 40.0 * 36
    start_2 = (offset, 40.0, offset, 40.0)
    truths = (
        TargetTruth(1, 0, propagate(start_1, inputs, 1.0, noise_intensity, rng)),
        TargetTruth(2, 0, propagate(start_2, np.zeros((n_steps, 2)), 1.0, noise_intensity, rng)),
    )
    noise = measurement_variance * np.eye(2)
    scans = observe(truths, n_steps, 1.0, noise, rng, sensor="radar")
    return Scenario(
        name="crossing",
        seed=seed,
        time_interval=1.0,
        n_steps=n_steps,
        truths=truths,
        manoeuvres=windows,
        scans=tuple(scans),
        measurement_noise=noise,
    )
