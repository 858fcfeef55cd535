"""[HZ] §6 Fig 6: a vehicle overtakes through the blind zone between a rear and a front sensor.

Vehicle 1 is seen by the rear sensor (``y ∈ [−40, −5]``), crosses the blind
zone ``|y| < 5`` beside us (2.5 s) and re-appears in the front sensor, where
vehicle 2 is ahead; each sensor has Poisson clutter
(:func:`~core.simulation.road.overtaking_scenario`). The surveillance region
covers the blind zone, so a track inside it is in a blind zone, not out of
range. As [HZ] §6 describes the simulator, targets are also missed
(**Reading:** P_D = :data:`P_DETECT`; the paper gives no number). Cases
(``CASES``), as in [HZ] Fig 6:

(a) plain distance, no blind-zone strategy, and — as the paper's baseline —
    no knowledge of the sensors' fields of view (every sensor is taken to see
    everywhere, so the track in the blind zone is expected to be detected
    and counts misses);
(b) modified distance, no blind-zone strategy, no field-of-view knowledge;
(a′), (b′) as (a), (b) but with the fields of view known (a departure from
    the paper's baseline, labelled: the track coasts through the zone
    unpenalised since no sensor should see it);
(c) modified distance and phantoms ([HZ] §5.1: the track becomes a phantom,
    is never matched with detections, and hands over to the first track
    confirmed in front of it);
(d) plain distance and phantoms (the tracker's default);
(e) as (d) but with the default surveillance region, the union of the
    sensors' ranges: the blind zone is then *out of range* and the track is
    terminated there ([HZ] §5.1 table), so vehicle 1 comes back under a new id.

Per run: is vehicle 1's identity kept (its rear detections, steps < 60, and
its front detections, steps ≥ 95, went mostly to the same track)? How many
of vehicle 2's detections and of the false alarms did vehicle 1's track take?

The paper's claim: (a) the lost overtaking track steals observations and
the track in front wanders off with false alarms; (b) the modified distance
prevents the stealing but false alarms take the overtaking track away; (c)
with both, the overtaking track "matches correctly with the observations as
they re-appear in the front sensor".
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray
from core.simulation import CLUTTER, overtaking_scenario
from evaluation.tracking import rectangle, road_config, track_scenario, tracking_scores

BLIND: Mapping[str, object] = {"fields_of_view": {"rear": None, "front": None}}
"""No field-of-view knowledge: each sensor is taken to see everywhere."""
CASES: Mapping[str, Mapping[str, object]] = {
    "(a) plain, no phantoms": {"distance": "plain", "phantoms": False, **BLIND},
    "(b) modified, no phantoms": {"distance": "modified", "phantoms": False, **BLIND},
    "(a′) as (a), fields of view known": {"distance": "plain", "phantoms": False},
    "(b′) as (b), fields of view known": {"distance": "modified", "phantoms": False},
    "(c) modified + phantoms": {"distance": "modified", "phantoms": True},
    "(d) plain + phantoms": {"distance": "plain", "phantoms": True},
    "(e) region = sensor ranges": {"distance": "plain", "phantoms": True, "region": None},
}
"""Case label → tracker options (on top of :func:`road_config`)."""
REGION = ((-10.0, 10.0), (-40.0, 60.0))
"""The surveillance region: both sensors and the blind zone between them."""
P_DETECT = 0.9
"""[HZ]'s simulator misses targets; its P_D is not printed (Reading)."""
BEFORE, AFTER = 60, 95
"""Vehicle 1 is in the rear sensor before step 60 and in the front one from step 95."""


OSPA_CUTOFF = 3.0
"""OSPA cut-off and coverage radius (m), as ``road-four``'s."""


@dataclass(frozen=True)
class OvertakingOutcome:
    """One run of one case.

    Attributes
    ----------
    kept : bool
        Vehicle 1's rear and front detections went to the same track.
    stolen : int
        Detections of vehicle 2 taken by vehicle 1's (rear) track.
    false_alarms : int
        False alarms taken by vehicle 1's track.
    phantom_steps : int
        Steps vehicle 1's track spent as a phantom.
    ospa : float
        Time-mean OSPA of the run (order 1, c = :data:`OSPA_CUTOFF`; a
        phantom is not a confirmed track, so a vehicle in the blind zone counts as missed).
    identity_switches : int
        Of both vehicles (:func:`~evaluation.tracking.tracking_scores`).
    """

    kept: bool
    stolen: int
    false_alarms: int
    phantom_steps: int
    ospa: float
    identity_switches: int


@dataclass(frozen=True)
class OvertakingStudy:
    """Per case and run.

    Attributes
    ----------
    seeds : tuple of int
    outcomes : dict
        ``case → tuple of OvertakingOutcome``.
    example : dict
        ``case → (steps, 4)`` trajectory of vehicle 1's rear track, seed ``seeds[0]``.
    truths : ndarray, shape (2, steps, 4)
    """

    seeds: tuple[int, ...]
    outcomes: Mapping[str, tuple[OvertakingOutcome, ...]]
    example: Mapping[str, FloatArray]
    truths: FloatArray

    def kept_share(self, case: str) -> float:
        """Share of the runs where vehicle 1 keeps its identity."""
        return float(np.mean([outcome.kept for outcome in self.outcomes[case]]))

    def values(self, case: str, field: str) -> FloatArray:
        """One outcome field per run, for intervals."""
        return np.array([float(getattr(o, field)) for o in self.outcomes[case]])

    def total(self, case: str, field: str) -> float:
        """Sum over the runs of one outcome field."""
        return float(sum(getattr(outcome, field) for outcome in self.outcomes[case]))


def overtaking_study(
    seeds: Sequence[int] = tuple(range(20)),
    cases: Mapping[str, Mapping[str, object]] = CASES,
    *,
    p_detect: float = P_DETECT,
    clutter_rate: float = 1.0,
) -> OvertakingStudy:
    """[HZ] Fig 6 over seeds and cases (module docstring)."""
    outcomes: dict[str, tuple[OvertakingOutcome, ...]] = {}
    example: dict[str, FloatArray] = {}
    for case, options in cases.items():
        found = []
        for seed in seeds:
            scenario = overtaking_scenario(seed=seed, p_detect=p_detect, clutter_rate=clutter_rate)
            settings = {"region": rectangle(REGION), **options}
            run = track_scenario(scenario, road_config(scenario, **settings))
            scores = tracking_scores(scenario, run, OSPA_CUTOFF)
            rear = run.track_of(1, 1, BEFORE - 1)
            front = run.track_of(1, AFTER)
            if rear is None:
                found.append(
                    OvertakingOutcome(False, 0, 0, 0, scores.ospa, scores.identity_switches)
                )
                continue
            phantom = sum(status == "phantom" for status, _ in run.status_of(rear).values())
            found.append(
                OvertakingOutcome(
                    kept=front == rear,
                    stolen=len(run.taken_by(rear, 2)),
                    false_alarms=len(run.taken_by(rear, CLUTTER)),
                    phantom_steps=phantom,
                    ospa=scores.ospa,
                    identity_switches=scores.identity_switches,
                )
            )
            if seed == seeds[0]:
                example[case] = run.trajectory(rear, scenario.n_steps)
        outcomes[case] = tuple(found)
    scenario = overtaking_scenario(seed=seeds[0], p_detect=p_detect, clutter_rate=clutter_rate)
    return OvertakingStudy(
        seeds=tuple(seeds),
        outcomes=outcomes,
        example=example,
        truths=np.stack([truth.states for truth in scenario.truths]),
    )
