"""The ``pedestrian`` scenario of [MTT] §6.3.3 (Fig 19–23).

Two pedestrians, ΔT = 1 s, one sensor with R = 0.05 I (the ``pedestrian``
preset's default) and P_D = 1. The state is ``[x, h_x, y, h_y]`` with
headings h = +1 (the convention of the speed models, [MTT] eq 26); each step
the position moves by ``s ΔT h`` with the speeds (s_x, s_y) of the phase:

- pedestrian 1: walks (2, 2) m/s during steps 1–39, runs (6, 6) from step 40
  and stops (0, 0) from ``stop_at`` (120, where [MTT] §6.3.3 puts the class
  change: "suddenly at time step 120 the likelihoods are associated to another
  class") to the end (239 by default); with ``walk_again_at`` it walks (2, 2)
  again from that step ([MTT] Fig 22–23, which continue the simulation to
  step ~300 with walking "near time step 240");
- pedestrian 2: walks (2, 0) throughout, 50 m away.

"Evolutions in x direction are identical" to those in y ([MTT] §6.3.3).
**Reading:** the start of the run (step 40) and the speeds are ours; the
truth has no process noise by default (``speed_noise`` adds Gaussian noise of
that standard deviation to each step's speeds). A shorter run (``stop_at=60``,
``n_steps=140``) keeps the same phases for quick tests.
"""

from __future__ import annotations

import numpy as np

from core.errors import ScenarioError
from core.simulation.scenario import Manoeuvre, Scenario, TargetTruth, observe

WALK = (2.0, 2.0)
RUN = (6.0, 6.0)
STOP = (0.0, 0.0)
RUN_AT = 40
"""First step of the run (after walking from step 1)."""
STOP_AT = 120
"""[MTT] §6.3.3: the class change (sportsman → rambler) at time step 120."""


def pedestrian_scenario(
    seed: int = 0,
    *,
    n_steps: int | None = None,
    stop_at: int = STOP_AT,
    walk_again_at: int | None = None,
    time_interval: float = 1.0,
    measurement_variance: float = 0.05,
    speed_noise: float = 0.0,
) -> Scenario:
    """Build the ``pedestrian`` scenario (see the module docstring).

    ``n_steps`` defaults to ``2 stop_at`` (240: as long stopped as moving),
    or ``walk_again_at + 60`` (300) when ``walk_again_at`` is given.
    """
    if stop_at <= RUN_AT:
        raise ScenarioError(f"stop_at must be after the run starts at {RUN_AT}, got {stop_at}")
    default = 2 * stop_at if walk_again_at is None else walk_again_at + 60
    steps = n_steps if n_steps is not None else default
    if steps <= stop_at:
        raise ScenarioError(f"the pedestrian scenario needs more than {stop_at} steps")
    if walk_again_at is not None and not stop_at < walk_again_at < steps:
        raise ScenarioError(f"walk_again_at must be in ({stop_at}, {steps}), got {walk_again_at}")
    rng = np.random.default_rng(seed)
    windows = [
        Manoeuvre(1, 1, RUN_AT - 1, "walk", WALK),
        Manoeuvre(1, RUN_AT, stop_at - 1, "run", RUN),
        Manoeuvre(1, stop_at, (walk_again_at or steps) - 1, "stop", STOP),
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
