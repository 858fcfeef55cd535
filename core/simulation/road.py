"""Road scenes of [HZ] §6: ``accelerating`` (Fig 5), its ``stealing`` variant, ``overtaking``
(Fig 6); and ``road-four`` of [DH] §5 (:func:`road_four_scenario`, its own Reading).

Coordinates are relative to our vehicle: x lateral (m, right positive), y
ahead (m). ΔT = 0.1 s. Truth by [MTT] eq 24 (piecewise constant
accelerations) with a small process noise; detections with R = 0.1 I.

``accelerating``
    One forward sensor seeing ``x ∈ [−10, 10]``, ``y ∈ [0, 80]``. Vehicle 1
    (left lane, x = −1.75) pulls away gradually (+1 m/s); vehicle 2 (right
    lane, x = +1.75) pulls away at +0.5 m/s, then from step 40 accelerates
    at ``acceleration`` m/s² (6 by default, "deliberately chosen to exceed
    the expected maximum acceleration for the tracker"). Poisson clutter of
    mean ``clutter_rate`` (3, as in [HZ]) per frame, uniform over the sensor's
    area.
``stealing`` (:func:`stealing_scenario`)
    The ``accelerating`` scene with vehicle 1 two lanes to
    the left (x = −5.25, 7 m from vehicle 2), no clutter and 160 steps. The
    track of vehicle 2 loses lock early in the acceleration (a constant
    velocity filter with σ_a ≈ 1 m/s² cannot follow 6 m/s²) and coasts on at
    its last velocity, level with vehicle 1, while its covariance grows: the
    lost, large-gated event e₁ of [HZ] §3.1 Fig 1 next to the well-localised
    e₂. False alarms would reset the lost track's covariance at every hit
    (the "false alarm random walk" of [HZ] Fig 5b), so the scene has none, to
    show the stealing itself.
``overtaking``
    A rear sensor sees ``y ∈ [−40, −5]`` and a front sensor ``y ∈ [5, 60]``
    (both ``x ∈ [−10, 10]``); ``|y| < 5`` beside us is the blind zone.
    Vehicle 1 (x = −3.5) overtakes at +4 m/s from y = −30: it leaves the rear
    sensor, crosses the blind zone (2.5 s) and re-appears in the front
    sensor. Vehicle 2 (x = 0) is ahead at y = 40 and we close in on it at
    1 m/s. Each sensor has its own scans and Poisson clutter.

**Reading:** [HZ] gives no numbers but the clutter rate; positions, speeds,
sensor extents and ΔT are ours. The rectangles are simple coverage areas
for simulation (``Scenario.sensor_regions``), not the service's fields of view.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from core.arrays import FloatArray
from core.simulation.scenario import (
    Manoeuvre,
    Region,
    Scan,
    Scenario,
    TargetTruth,
    inside,
    observe,
    propagate,
)

TIME_INTERVAL = 0.1
MEASUREMENT_VARIANCE = 0.1
PROCESS_NOISE = 0.01


def _coverage(region: Region) -> Callable[[FloatArray], bool]:
    def visible(position: FloatArray) -> bool:
        return inside(region, position)

    return visible


def accelerating_scenario(
    seed: int = 0,
    *,
    n_steps: int = 80,
    acceleration: float = 6.0,
    clutter_rate: float = 3.0,
    manoeuvre_step: int = 40,
    lead: float = 0.0,
    speeds: tuple[float, float] = (1.0, 0.5),
    lanes: tuple[float, float] = (-1.75, 1.75),
    p_detect: float = 1.0,
) -> Scenario:
    """Build ``accelerating`` (see the module docstring).

    Parameters
    ----------
    seed : int
    n_steps : int
    acceleration : float
        Vehicle 2's acceleration (m/s², along y) from ``manoeuvre_step`` on.
    clutter_rate : float
        Mean number of false alarms per frame.
    manoeuvre_step : int
        First step of vehicle 2's acceleration (40 by default).
    lead : float
        How far ahead of vehicle 2 vehicle 1 starts (m, along y; 0 by default).
    speeds : (float, float)
        Initial speeds along y of vehicles 1 and 2 (m/s; (1, 0.5) by default).
    lanes : (float, float)
        Lateral positions x of vehicles 1 and 2 (m; adjacent lanes ±1.75 by default).
    p_detect : float
        Probability of detecting each vehicle at each frame ([HZ] §6's simulator
        has "missed targets" without a number: 1 by default, the experiments
        choose theirs).
    """
    rng = np.random.default_rng(seed)
    region: Region = ((-10.0, 10.0), (0.0, 80.0))
    window = Manoeuvre(2, manoeuvre_step, n_steps - 1, "accelerate", (0.0, acceleration))
    inputs = np.zeros((n_steps, 2))
    inputs[window.first_step :] = window.value
    truths = (
        TargetTruth(
            1,
            0,
            propagate(
                (lanes[0], 0.0, 15.0 + lead, speeds[0]),
                np.zeros((n_steps, 2)),
                TIME_INTERVAL,
                PROCESS_NOISE,
                rng,
            ),
        ),
        TargetTruth(
            2,
            0,
            propagate((lanes[1], 0.0, 15.0, speeds[1]), inputs, TIME_INTERVAL, PROCESS_NOISE, rng),
        ),
    )
    noise = MEASUREMENT_VARIANCE * np.eye(2)
    scans = observe(
        truths,
        n_steps,
        TIME_INTERVAL,
        noise,
        rng,
        sensor="front",
        p_detect=p_detect,
        clutter_rate=clutter_rate,
        region=region,
        visible=lambda position: inside(region, position),
    )
    return Scenario(
        name="accelerating",
        seed=seed,
        time_interval=TIME_INTERVAL,
        n_steps=n_steps,
        truths=truths,
        manoeuvres=(window,),
        scans=tuple(scans),
        measurement_noise=noise,
        sensor_regions={"front": region},
    )


def stealing_scenario(seed: int = 0, *, n_steps: int = 160) -> Scenario:
    """``accelerating`` set up for observation stealing ([HZ] §3.1; module docstring)."""
    return accelerating_scenario(seed, n_steps=n_steps, clutter_rate=0.0, lanes=(-5.25, 1.75))


def overtaking_scenario(
    seed: int = 0,
    *,
    n_steps: int = 120,
    clutter_rate: float = 1.0,
    p_detect: float = 1.0,
) -> Scenario:
    """Build ``overtaking`` (see the module docstring; ``p_detect`` as for ``accelerating``)."""
    rng = np.random.default_rng(seed)
    regions: dict[str, Region] = {
        "rear": ((-10.0, 10.0), (-40.0, -5.0)),
        "front": ((-10.0, 10.0), (5.0, 60.0)),
    }
    zeros = np.zeros((n_steps, 2))
    truths = (
        TargetTruth(
            1, 0, propagate((-3.5, 0.0, -30.0, 4.0), zeros, TIME_INTERVAL, PROCESS_NOISE, rng)
        ),
        TargetTruth(
            2, 0, propagate((0.0, 0.0, 40.0, -1.0), zeros, TIME_INTERVAL, PROCESS_NOISE, rng)
        ),
    )
    noise = MEASUREMENT_VARIANCE * np.eye(2)
    per_sensor: list[list[Scan]] = []
    for sensor, region in regions.items():
        per_sensor.append(
            observe(
                truths,
                n_steps,
                TIME_INTERVAL,
                noise,
                rng,
                sensor=sensor,
                p_detect=p_detect,
                clutter_rate=clutter_rate,
                region=region,
                visible=_coverage(region),
            )
        )
    scans = tuple(scan for step_scans in zip(*per_sensor, strict=True) for scan in step_scans)
    return Scenario(
        name="overtaking",
        seed=seed,
        time_interval=TIME_INTERVAL,
        n_steps=n_steps,
        truths=truths,
        manoeuvres=(),
        scans=scans,
        measurement_noise=noise,
        sensor_regions=regions,
    )


ROAD_FOUR_VARIANCE = 0.5
"""[DH] §5: "the deviation of the measurement noise has been selected as σ² = 0.5 m²"."""


def road_four_scenario(
    seed: int = 0,
    *,
    n_steps: int = 100,
    clutter_rate: float = 3.0,
    p_detect: float = 1.0,
    lane_change: tuple[int, int] = (40, 59),
) -> Scenario:
    """Build ``road-four`` ([DH] §5 Fig 1): four vehicles ahead of ours, in clutter.

    T = 0.1 s and R = 0.5 I m² as in [DH]; x lateral, y ahead, relative to
    our vehicle. **Reading:** [DH] takes its trajectories from its ref. [8]
    and gives no coordinates; ours are three lanes 3.5 m apart, 10 s:

    - vehicle 1, left lane (x = −3.5), y = 20 m, pulls away at +1 m/s;
    - vehicle 2, our lane (x = 0), y = 30 m, keeps its distance;
    - vehicle 3, right lane (x = +3.5), y = 12 m, +1 m/s, changes into our
      lane during steps ``lane_change`` (lateral ±1.75·(2/d)² m/s² for the two
      halves of the window, d its duration in s: 3.5 m across, behind vehicle 2);
    - vehicle 4, right lane, y = 45 m, approaches at −1 m/s.

    Clutter: Poisson, mean ``clutter_rate`` per frame, uniform over the
    sensor's area ``x ∈ [−10, 10]``, ``y ∈ [0, 60]`` (one forward sensor, "front").
    """
    rng = np.random.default_rng(seed)
    region: Region = ((-10.0, 10.0), (0.0, 60.0))
    first, last = lane_change
    half = (last - first + 1) // 2
    duration = 2 * half * TIME_INTERVAL
    lateral = 3.5 * 4.0 / duration**2  # a·(d/2)² = 3.5 m over the window
    inputs = np.zeros((n_steps, 2))
    inputs[first : first + half, 0] = -lateral
    inputs[first + half : first + 2 * half, 0] = lateral
    starts = (
        (-3.5, 0.0, 20.0, 1.0),
        (0.0, 0.0, 30.0, 0.0),
        (3.5, 0.0, 12.0, 1.0),
        (3.5, 0.0, 45.0, -1.0),
    )
    truths = tuple(
        TargetTruth(
            index + 1,
            0,
            propagate(
                start,
                inputs if index == 2 else np.zeros((n_steps, 2)),
                TIME_INTERVAL,
                PROCESS_NOISE,
                rng,
            ),
        )
        for index, start in enumerate(starts)
    )
    noise = ROAD_FOUR_VARIANCE * np.eye(2)
    scans = observe(
        truths,
        n_steps,
        TIME_INTERVAL,
        noise,
        rng,
        sensor="front",
        p_detect=p_detect,
        clutter_rate=clutter_rate,
        region=region,
        visible=_coverage(region),
    )
    return Scenario(
        name="road-four",
        seed=seed,
        time_interval=TIME_INTERVAL,
        n_steps=n_steps,
        truths=truths,
        manoeuvres=(Manoeuvre(3, first, first + 2 * half - 1, "lane change", (-lateral, 0.0)),),
        scans=tuple(scans),
        measurement_noise=noise,
        sensor_regions={"front": region},
    )
