"""[MTT] §6.2.2 (Fig 17–18): a fighter crosses an unknown aircraft; identities and classes.

Target 1 (a fighter) flies straight, accelerates at (4g, 4g) during steps
23–24, decelerates during steps 35–36 after passing target 2, and the two
then fly 5 m apart per axis (:func:`~core.simulation.nearby.crossing_scenario`).
Target 2 only ever flies straight. Each run is tracked by the
:class:`LocalTracker` (13-model aircraft IMM, GNN, credal classification)
with R equal to the simulated noise. A target's track is the one its
detections of steps 2–20 went to (before the crossing); every later
detection given to another track is a false assignment.

**Paper first** (:data:`PAPER_CASE`): the measurement variance of [MTT] §6.1,
0.2 m² per axis (§6.2 states no other), and the model-combined ẑ, S of
[MTT] §4 (``imm_distance="combined"``). **Our variant**
(:data:`VARIANT_CASE`): 10 m² and ``closest_model`` (the tracker's default
distance before issue 13), because Fig 17's false assignment at step 38
shows in our geometry only at a noise of a few m² against the 7 m final
separation (and the combined distance loses the fighter at its 4g
manoeuvre). **Our default** (:data:`DEFAULT_CASE`): the paper's 0.2 m² with
the tracker's default since issue 13, ``gated_combined`` (docs/algorithms.md
§4). **Reading:** the paper gives no positions; the study sweeps the
variance between the two, for each of the three distances.

The paper's claim (Fig 18): target 1 is classified fighter after its first
strong manoeuvre and "its classification is not influenced by the false
assignment"; target 2 should stay in perfect doubt, but the false assignment
"misleads the classifier ... advantaging the third and second classes over
the first one".
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray
from core.metrics import time_to_decision
from core.simulation import crossing_scenario
from core.tracking.config import DEFAULT_IMM_DISTANCE, PAPER_CLASSIFICATION, LocalTrackerConfig
from core.tracking.presets import aircraft
from evaluation.tracking import TrackedRun, track_scenario, tracking_scores

IDENTITY_STEPS = (2, 20)
"""Steps whose detections name each target's own track (before the crossing)."""

PAPER_CASE = (0.2, "combined")
"""[MTT]'s stated values: σ² = 0.2 m² (§6.1) and the model-combined distance (§4)."""

VARIANT_CASE = (10.0, "closest_model")
"""Our harder variant: the noise at which Fig 17's false assignment shows here."""

DEFAULT_CASE = (PAPER_CASE[0], DEFAULT_IMM_DISTANCE)
"""The paper's noise with the tracker's default distance (``gated_combined`` since issue 13)."""

OSPA_CUTOFF = 10.0
"""OSPA/GOSPA cut-off and coverage radius (m): above the 7 m final separation."""

FIGHTER_FROM = 23
"""Target 1's first 4g step: its time to decision counts from here."""


@dataclass(frozen=True)
class CrossingRun:
    """One tracked run of ``crossing`` (the example drawn as Fig 17).

    Attributes
    ----------
    variance : float
        Measurement noise variance per axis (m²).
    imm_distance : str
    seed : int
    truth_y : ndarray, shape (steps, 2)
        True y of targets 1 and 2.
    detection_steps, detection_y : ndarrays, shape (m,)
    detection_targets : ndarray of int64, shape (m,)
    detection_owner : ndarray of int64, shape (m,)
        Which target's track the detection went to (1, 2, 0 for another track, −1 none).
    """

    variance: float
    imm_distance: str
    seed: int
    truth_y: FloatArray
    detection_steps: FloatArray
    detection_y: FloatArray
    detection_targets: FloatArray
    detection_owner: FloatArray


@dataclass(frozen=True)
class CrossingStudy:
    """Per measurement variance, IMM distance and run.

    Attributes
    ----------
    variances : ndarray, shape (v,)
    seeds : tuple of int
    classes : tuple of str
        liner, bomber, fighter.
    first_false : dict
        ``imm_distance → (v, runs)``: first step of a false assignment (NaN: none).
    false_counts : dict
        ``imm_distance → (v, runs)``: false assignments of both targets.
    betp : dict
        ``imm_distance → (v, runs, 2, steps, 3)``: BetP of each target's own
        track over time (NaN once it is gone).
    ospa, gospa : dict
        ``imm_distance → (v, runs)``: time-mean OSPA / GOSPA (c = :data:`OSPA_CUTOFF`).
    switches : dict
        ``imm_distance → (v, runs)``: identity switches (:func:`core.metrics.identity_switches`).
    fighter_delay : dict
        ``imm_distance → (v, runs)``: steps from :data:`FIGHTER_FROM` until target 1's
        own track keeps BetP(fighter) ≥ 0.9 to the end (NaN: never, or the track is lost).
    examples : tuple of CrossingRun
        The paper's case, our variant, then our default (Fig 17).
    manoeuvres : tuple of (int, int, str)
    """

    variances: FloatArray
    seeds: tuple[int, ...]
    classes: tuple[str, ...]
    first_false: Mapping[str, FloatArray]
    false_counts: Mapping[str, FloatArray]
    betp: Mapping[str, FloatArray]
    ospa: Mapping[str, FloatArray]
    gospa: Mapping[str, FloatArray]
    switches: Mapping[str, FloatArray]
    fighter_delay: Mapping[str, FloatArray]
    examples: tuple[CrossingRun, ...]
    manoeuvres: tuple[tuple[int, int, str], ...]

    def swapped_share(self, imm_distance: str) -> FloatArray:
        """Share of runs with at least one false assignment, per variance."""
        return np.asarray(np.mean(~np.isnan(self.first_false[imm_distance]), axis=1))

    def final_betp(self, imm_distance: str, target: int) -> FloatArray:
        """Mean BetP of the target's track at the last step, per variance, shape (v, 3)."""
        return np.asarray(np.nanmean(self.betp[imm_distance][:, :, target - 1, -1], axis=1))

    def alive_at_end(self, imm_distance: str, target: int) -> FloatArray:
        """Share of runs whose track of the target still exists at the last step."""
        last = self.betp[imm_distance][:, :, target - 1, -1, 0]
        return np.asarray(np.mean(~np.isnan(last), axis=1))


def _config(variance: float, imm_distance: str) -> LocalTrackerConfig:
    return LocalTrackerConfig.paper(
        measurement_noise=((variance, 0.0), (0.0, variance)),
        imm_distance=imm_distance,
        fields_of_view={"radar": None},
        classification=PAPER_CLASSIFICATION,  # [MTT]'s own experiment
    )


def _own_tracks(run: TrackedRun) -> dict[int, str | None]:
    return {target: run.track_of(target, *IDENTITY_STEPS) for target in (1, 2)}


def crossing_run(seed: int, variance: float, imm_distance: str = "combined") -> CrossingRun:
    """One run in the form of Fig 17 (each detection coloured by the target whose track took it)."""
    scenario = crossing_scenario(seed=seed, measurement_variance=variance)
    run = track_scenario(scenario, _config(variance, imm_distance))
    own = _own_tracks(run)
    owner_of = {track: target for target, track in own.items() if track is not None}
    owners = np.array(
        [-1 if track is None else owner_of.get(track, 0) for track in run.detection_tracks],
        dtype=np.float64,
    )
    return CrossingRun(
        variance=variance,
        imm_distance=imm_distance,
        seed=seed,
        truth_y=np.stack([truth.states[:, 2] for truth in scenario.truths], axis=1),
        detection_steps=run.detection_steps.astype(np.float64),
        detection_y=run.measurements[:, 1],
        detection_targets=run.detection_targets.astype(np.float64),
        detection_owner=owners,
    )


def crossing_study(
    seeds: Sequence[int] = tuple(range(20)),
    variances: Sequence[float] = (0.2, 1.0, 4.0, 10.0, 25.0),
    *,
    imm_distances: Sequence[str] = ("combined", "closest_model", DEFAULT_IMM_DISTANCE),
    examples: Sequence[tuple[int, float, str]] = (
        (0, *PAPER_CASE),
        (0, *VARIANT_CASE),
        (0, *DEFAULT_CASE),
    ),
    final_separation: float = 5.0,
) -> CrossingStudy:
    """[MTT] Fig 17–18 over seeds and measurement variances (module docstring)."""
    classes = aircraft().classes.labels
    first_false: dict[str, FloatArray] = {}
    false_counts: dict[str, FloatArray] = {}
    betps: dict[str, FloatArray] = {}
    scores: dict[str, dict[str, FloatArray]] = {
        name: {} for name in ("ospa", "gospa", "switches", "fighter_delay")
    }
    n_steps = crossing_scenario(seed=0).n_steps
    for kind in imm_distances:
        first = np.full((len(variances), len(seeds)), np.nan)
        counts = np.zeros((len(variances), len(seeds)))
        betp = np.full((len(variances), len(seeds), 2, n_steps, len(classes)), np.nan)
        table = {name: np.full(counts.shape, np.nan) for name in scores}
        for v, variance in enumerate(variances):
            for r, seed in enumerate(seeds):
                scenario = crossing_scenario(
                    seed=seed, measurement_variance=variance, final_separation=final_separation
                )
                run = track_scenario(scenario, _config(variance, kind))
                own = _own_tracks(run)
                steps: list[int] = []
                for target, track in own.items():
                    wrong = [
                        step
                        for step, chosen in zip(
                            run.detection_steps[run.detection_targets == target].tolist(),
                            run.assigned(target),
                            strict=True,
                        )
                        if step >= IDENTITY_STEPS[0] and chosen != track
                    ]
                    steps.extend(wrong)
                    counts[v, r] += len(wrong)
                    if track is not None:
                        betp[v, r, target - 1] = run.pignistic_of(track, n_steps, len(classes))
                if steps:
                    first[v, r] = min(steps)
                measured = tracking_scores(scenario, run, OSPA_CUTOFF)
                table["ospa"][v, r] = measured.ospa
                table["gospa"][v, r] = measured.gospa
                table["switches"][v, r] = measured.identity_switches
                table["fighter_delay"][v, r] = float(
                    time_to_decision(
                        betp[v, r, 0], classes.index("fighter"), level=0.9, start=FIGHTER_FROM
                    )
                )
        first_false[kind], false_counts[kind], betps[kind] = first, counts, betp
        for name, values in table.items():
            scores[name][kind] = values
    scenario = crossing_scenario(seed=0)
    return CrossingStudy(
        variances=np.asarray(variances, dtype=np.float64),
        seeds=tuple(seeds),
        classes=classes,
        first_false=first_false,
        false_counts=false_counts,
        betp=betps,
        ospa=scores["ospa"],
        gospa=scores["gospa"],
        switches=scores["switches"],
        fighter_delay=scores["fighter_delay"],
        examples=tuple(crossing_run(seed, variance, kind) for seed, variance, kind in examples),
        manoeuvres=tuple((m.first_step, m.last_step, m.label) for m in scenario.manoeuvres),
    )
