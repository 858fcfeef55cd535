"""Class fusion from sensor reports (docs/algorithms.md §5 "From sensor reports", §6 step 6).

A sensor track may carry a class mass function (the sensor's own cumulative
belief) or class likelihoods (one step of evidence). Per fused track:

- a mass report replaces that sensor's latest mass;
- a likelihood report goes through the GBT ([MTT] eq 10) and is accumulated
  conjunctively with that sensor's previous evidence ([MTT] eq 11), kept
  normalised (Dempster's rule is associative, so nothing is lost but the
  running conflict, which is kept);
- the fused class mass is the conjunctive combination of every contributing
  sensor's latest mass, each discounted by that sensor's reliability
  ([MTT] eq 7). It is reported normalised, with the conflict that
  normalisation removed: information about disagreeing sensors, not an error.

**Bound.** Every mass kept or fused has at most
:data:`~core.belief.summary.MAX_FUSED_FOCAL_SETS` focal sets: a larger one is
summarized ([LGS86], :mod:`core.belief.summary`: the largest focal sets kept,
the rest of the mass on their union — a weakening, never a stronger claim).
A fused assessment says ``summarized`` when its combination was cut; a
likelihood step over more than 5 fractional classes (2^F > 32 focal sets)
is always built summarized.

**Reading.** Likelihood values are plausibilities for the GBT and must lie in
[0, 1]; a sensor that has densities must scale them (the local classifier's
``likelihood_scale`` does that for the service's own tracks).
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray
from core.belief import (
    DecisionState,
    Frame,
    MassFunction,
    conjunctive,
    pignistic_decision,
)
from core.belief.summary import bounded_gbt_mass, summarize
from core.errors import TotalConflict


class ClassState(enum.StrEnum):
    """Whether a fused class assessment could be normalised."""

    DEFINED = "defined"
    TOTAL_CONFLICT = "total_conflict"


@dataclass(frozen=True)
class ClassAssessment:
    """What the service says about one track's class.

    Attributes
    ----------
    state : DEFINED, or TOTAL_CONFLICT (then ``mass`` is None and the arrays are empty).
    mass : the normalised fused mass function.
    pignistic, belief, plausibility : BetP, Bel({c}) and Pl({c}) per class, in frame order.
    conflict : m(∅) of the unnormalised combination.
    decision : the class of largest BetP; None when BetP is tied or undefined.
    decision_state : DECIDED, TIED (top BetP within 1e-9) or UNDEFINED (no BetP):
        see :mod:`core.belief.decision`.
    """

    state: ClassState
    mass: MassFunction | None
    pignistic: FloatArray
    belief: FloatArray
    plausibility: FloatArray
    conflict: float
    decision: str | None
    decision_state: DecisionState
    summarized: bool = False
    """Whether the fused mass was summarized to its bound (:mod:`core.belief.summary`)."""


def assess(combined: MassFunction, summarized: bool = False) -> ClassAssessment:
    """Normalise an (unnormalised) combined mass and summarise it."""
    try:
        normalised = combined.normalized()
    except TotalConflict:
        empty = np.zeros(0)
        return ClassAssessment(
            ClassState.TOTAL_CONFLICT,
            None,
            empty,
            empty,
            empty,
            combined.conflict,
            None,
            DecisionState.UNDEFINED,
            summarized,
        )
    betp = normalised.pignistic()
    assert betp is not None  # a normalised mass has m(∅) = 0
    decision, decision_state = pignistic_decision(combined.frame.labels, betp)
    return ClassAssessment(
        state=ClassState.DEFINED,
        mass=normalised,
        pignistic=betp,
        belief=normalised.singleton_belief(),
        plausibility=normalised.singleton_plausibility(),
        conflict=combined.conflict,
        decision=decision,
        decision_state=decision_state,
        summarized=summarized,
    )


def accumulate_likelihoods(
    previous: MassFunction | None, frame: Frame, likelihoods: FloatArray
) -> tuple[MassFunction, float]:
    """One step of likelihood evidence: GBT, then conjunctive accumulation, normalised.

    Returns the new normalised mass and the conflict of this step.

    Raises
    ------
    TotalConflict
        If the step's evidence contradicts the previous mass totally.
    """
    step, _ = bounded_gbt_mass(frame, np.asarray(likelihoods, dtype=np.float64))
    combined = step if previous is None else summarize(conjunctive(previous, step))[0]
    return combined.normalized(), combined.conflict


def fuse_sensor_classes(
    masses: Mapping[str, MassFunction], reliabilities: Mapping[str, float]
) -> ClassAssessment | None:
    """Fuse the latest class mass of each sensor, discounted by its reliability.

    Sensors are combined in sorted id order (the rule is commutative, but the
    floating-point sums are then reproducible). Returns ``None`` when no
    sensor carries class information.
    """
    if not masses:
        return None
    discounted = [masses[sensor].discount(reliabilities[sensor]) for sensor in sorted(masses)]
    fused, summarized = summarize(discounted[0])
    for mass in discounted[1:]:
        fused, cut = summarize(conjunctive(fused, mass))
        summarized = summarized or cut
    return assess(fused, summarized)
