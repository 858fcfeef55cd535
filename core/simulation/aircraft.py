"""The ``aircraft`` scenario of [MTT] §6.1.3 (Fig 10–15).

Four aircraft over steps 0–120 (ΔT = 1 s), one radar with R = 0.2 I, P_D = 1,
truth by [MTT] eq 24 with process noise ``Q = 0.005 B Bᵀ``:

- target 1: constant velocity throughout;
- target 2: constant velocity, then a medium acceleration (+2g along x) during
  steps 50–54, a sharp deceleration (−4g along x) during steps 70–75, and it
  disappears at step 100 (last state at 99);
- target 3 appears at step 30, target 4 at step 70, both constant velocity.

**Reading:** [MTT] gives no initial positions or speeds (Fig 10 is not in
the text); the ones below keep the aircraft kilometres apart.
"""

from __future__ import annotations

import numpy as np

from core.simulation.scenario import Manoeuvre, Scenario, TargetTruth, observe, propagate
from core.tracking.presets import GRAVITY

_INITIAL = {
    1: (-4000.0, 180.0, 3000.0, -20.0),
    2: (0.0, 200.0, 0.0, 30.0),
    3: (6000.0, -150.0, 9000.0, -60.0),
    4: (-6000.0, 120.0, -5000.0, 100.0),
}


def aircraft_scenario(
    seed: int = 0,
    *,
    n_steps: int = 121,
    time_interval: float = 1.0,
    noise_intensity: float = 0.005,
    measurement_variance: float = 0.2,
    p_detect: float = 1.0,
) -> Scenario:
    """Build the ``aircraft`` scenario (see the module docstring)."""
    rng = np.random.default_rng(seed)
    windows = (
        Manoeuvre(2, 50, 54, "2g", (2.0 * GRAVITY, 0.0)),
        Manoeuvre(2, 70, 75, "4g", (-4.0 * GRAVITY, 0.0)),
    )
    spans = {1: (0, n_steps), 2: (0, min(100, n_steps)), 3: (30, n_steps), 4: (70, n_steps)}
    truths = []
    for target_id, (first, end) in spans.items():
        if first >= end:
            continue
        accelerations = np.zeros((end - first, 2))
        for window in windows:
            if window.target_id == target_id:
                lo, hi = window.first_step - first, window.last_step - first + 1
                accelerations[max(lo, 0) : max(hi, 0)] = window.value
        states = propagate(_INITIAL[target_id], accelerations, time_interval, noise_intensity, rng)
        truths.append(TargetTruth(target_id, first, states))
    noise = measurement_variance * np.eye(2)
    scans = observe(truths, n_steps, time_interval, noise, rng, sensor="radar", p_detect=p_detect)
    return Scenario(
        name="aircraft",
        seed=seed,
        time_interval=time_interval,
        n_steps=n_steps,
        truths=tuple(truths),
        manoeuvres=windows,
        scans=tuple(scans),
        measurement_noise=noise,
    )
