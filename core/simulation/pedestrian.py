"""The ``pedestrian`` scenario of [MTT] §6.3.3 (Fig 19–23).

Two pedestrians, ΔT = 1 s, one sensor with R = 0.05 I (the ``pedestrian``
preset's default) and P_D = 1. The state is ``[x, h_x, y, h_y]`` with
headings h = +1 (the convention of the speed models, [MTT] eq 26); each step
the position moves by ``s ΔT h`` with the speeds (s_x, s_y) of the phase:

- pedestrian 1: walks (2, 2) m/s during steps 1–39, runs (6, 6) during 40–59,
  stops (0, 0) from step 60 to the end (139 by default); with
  ``walk_again_at`` it walks (2, 2) again from that step ([MTT] Fig 22–23,
  which continue the simulation to step ~300 with walking near step 240);
- pedestrian 2: walks (2, 0) throughout, 50 m away.

"Evolutions in x direction are identical" to those in y ([MTT] §6.3.3).
**Reading:** the truth has no process noise by default (``speed_noise`` adds
Gaussian noise of that standard deviation to each step's speeds).
"""

from __future__ import annotations

import numpy as np

from core.errors import ScenarioError
from core.simulation.scenario import Manoeuvre, Scenario, TargetTruth, observe

WALK = (2.0, 2.0)
RUN = (6.0, 6.0)
STOP = (0.0, 0.0)


def pedestrian_scenario(
    seed: int = 0,
    *,
    n_steps: int | None = None,
    walk_again_at: int | None = None,
    time_interval: float = 1.0,
    measurement_variance: float = 0.05,
    speed_noise: float = 0.0,
) -> Scenario:
    """Build the ``pedestrian`` scenario (see the module docstring).

    ``n_steps`` defaults to 140, or 300 when ``walk_again_at`` is given.
    """
    steps = n_steps if n_steps is not None else (300 if walk_again_at is not None else 140)
    if steps < 61:
        raise ScenarioError("the pedestrian scenario needs at least 61 steps")
    if walk_again_at is not None and not 61 <= walk_again_at < steps:
        raise ScenarioError(f"walk_again_at must be in [61, {steps}), got {walk_again_at}")
    rng = np.random.default_rng(seed)
    windows = [
        Manoeuvre(1, 1, 39, "walk", WALK),
        Manoeuvre(1, 40, 59, "run", RUN),
        Manoeuvre(1, 60, (walk_again_at or steps) - 1, "stop", STOP),
    ]
    if walk_again_at is not None:
        windows.append(Manoeuvre(1, walk_again_at, steps - 1, "walk", WALK))
    windows.append(Manoeuvre(2, 1, steps - 1, "walk", (2.0, 0.0)))

    truths = []
    for target_id, start in ((1, (0.0, 1.0, 0.0, 1.0)), (2, (0.0, 1.0, 50.0, 1.0))):
        speeds = np.zeros((steps, 2))
        for window in windows:
            if window.target_id == target_id:
                speeds[window.first_step : window.last_step + 1] = window.value
        speeds[1:] += speed_noise * rng.standard_normal((steps - 1, 2))
        states = np.zeros((steps, 4))
        states[:, 1] = start[1]
        states[:, 3] = start[3]
        states[:, 0] = start[0] + np.cumsum(speeds[:, 0] * time_interval * start[1])
        states[:, 2] = start[2] + np.cumsum(speeds[:, 1] * time_interval * start[3])
        truths.append(TargetTruth(target_id, 0, states))
    noise = measurement_variance * np.eye(2)
    scans = observe(truths, steps, time_interval, noise, rng, sensor="camera")
    return Scenario(
        name="pedestrian",
        seed=seed,
        time_interval=time_interval,
        n_steps=steps,
        truths=tuple(truths),
        manoeuvres=tuple(windows),
        scans=tuple(scans),
        measurement_noise=noise,
    )
