"""Credal classification from kinematics ([MTT] §5.2, docs/algorithms.md §5).

At each step where a track is updated with a measurement:

1. behaviour plausibilities ``Pl({b_i}) = Σ_{j∈M_{b_i}} μ'_j Λ_j`` from the IMM's
   updated mode probabilities and model likelihoods ([MTT] eq 22, eq 20),
   scaled into [0, 1] by ``likelihood_scale`` (see
   :mod:`core.classification.behaviours`) — vectorised over tracks;
2. GBT mass on the behaviours ([MTT] eq 10), ``m_k(·|z)``;
3. accumulation ``m_k = m_k(·|z) ∩ m_{k−1}`` from the vacuous mass ([MTT] eq 11),
   optionally discounted ([MTT] eq 7, §6.3.3);
4. mapping to classes through the relation Γ ([MTT] eq 23) and BetP (eq 8).

The cumulative mass is kept normalised after each step and the conflict that
normalisation removes is kept: the step conflict ``K_k`` and the running
conflict ``1 − Π_k (1 − K_k)`` (the m(∅) of the unnormalised accumulation).
With ``discount="none"`` or ``"instantaneous"`` this leaves BetP unchanged:
the conjunctive rule is bilinear, so scaling the prior's non-empty focal sets
scales the result's, and BetP divides by 1 − m(∅). With
``discount="cumulative"`` it does not: discounting moves a fixed 1 − λ to Ω,
not a share proportional to the mass, so normalising before discounting
changes the result. There the classifier is, by definition, the accumulation
normalised at every step (``tests/core/classification/test_normalisation.py``
checks both statements against a brute force). When a
step's conflict is total (``1 − K_k ≤ 1e-12``) the state becomes
``total_conflict``: the cumulative mass is m(∅) = 1 and there is no BetP. Under
the conjunctive rule that state is absorbing, as in [MTT] Fig 20;
``discount="cumulative"`` can leave it (discounting m(∅) = 1 gives mass to Ω).

This is the reference implementation (a Python loop over sparse
:class:`~core.belief.MassFunction` objects); the tracker runs
:class:`~core.classification.batched.BatchedCredalClassifier`, which computes
the same on dense arrays for all tracks at once.

Tracks without a measurement this step (coasting) receive no evidence: their
mass does not change. ([MTT] §6.1.3 feeds the coasting track its predicted
measurement, which leaves the behaviour likelihoods "still constant"; a
prediction is not evidence about the behaviour, so we add none.)

Options and readings
--------------------
``likelihood_scale`` : ``"max"`` (default) | ``"clip"``
    See :mod:`core.classification.behaviours`.
``discount`` : ``"none"`` (default, the standard algorithm) | ``"instantaneous"`` | ``"cumulative"``
    ``"instantaneous"`` discounts the step mass m_k(·|z) before combining
    ([MTT] Fig 21); ``"cumulative"`` discounts m_{k−1} ([MTT] Fig 22).
``reliability`` : λ of [MTT] eq 7 (1 keeps the source, 0 makes it vacuous)
    Default 0.3 with ``"instantaneous"`` (Fig 21) and 0.9 with
    ``"cumulative"`` (Fig 22).
``accumulation`` : ``"classes"`` (default) | ``"behaviours"``
    **Reading:** [MTT] §5.2 combines with eq 11 and projects to classes with
    eq 23 without saying which frame the accumulation lives on; the two differ
    because Γ(A ∩ B) ⊆ Γ(A) ∩ Γ(B) only. ``"classes"`` maps each step mass
    to the classes first and accumulates there: walking (→ {rambler,
    sportsman}) then running (→ {sportsman}) is no conflict, which is what
    [MTT] Fig 20–21 show (the failure happens at the stop, not when the run
    starts). ``"behaviours"`` accumulates on B and maps the result.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from core.arrays import BoolArray, FloatArray
from core.belief import (
    CONFLICT_TOLERANCE,
    Frame,
    MassFunction,
    Relation,
    conjunctive,
    gbt_mass,
    pignistic_decision,
)
from core.classification.behaviours import LIKELIHOOD_SCALES, BehaviourModels, LikelihoodScale
from core.errors import ClassificationError

Discount = Literal["none", "instantaneous", "cumulative"]
DISCOUNTS: tuple[Discount, ...] = ("none", "instantaneous", "cumulative")
Accumulation = Literal["classes", "behaviours"]
ACCUMULATIONS: tuple[Accumulation, ...] = ("classes", "behaviours")
DEFAULT_RELIABILITY: dict[Discount, float] = {
    "none": 1.0,
    "instantaneous": 0.3,  # [MTT] Fig 21
    "cumulative": 0.9,  # [MTT] Fig 22
}

Status = Literal["ok", "total_conflict"]


@dataclass(frozen=True)
class CredalClassification:
    """The class knowledge of one track.

    Attributes
    ----------
    mass : MassFunction
        Cumulative mass on the accumulation frame, normalised; m(∅) = 1 in
        the ``total_conflict`` state.
    class_mass : MassFunction
        The same on the classes (equal to ``mass`` when accumulating on classes).
    pignistic : ndarray or None
        BetP of each class in frame order; None in the ``total_conflict`` state.
    step_conflict : float
        K of the last combination (0 before any evidence).
    log_normaliser : float
        Σ_k log(1 − K_k): the log of the mass the accumulation kept.
    status : "ok" | "total_conflict"
    steps : int
        Number of steps of evidence received.
    """

    mass: MassFunction
    class_mass: MassFunction
    pignistic: FloatArray | None
    step_conflict: float
    log_normaliser: float
    status: Status
    steps: int

    @property
    def conflict(self) -> float:
        """Running conflict ``1 − Π_k (1 − K_k)`` (m(∅) of the unnormalised accumulation)."""
        return float(-np.expm1(self.log_normaliser))

    def decision(self) -> str | None:
        """The class of largest BetP (None when BetP is undefined or tied: core.belief.decision)."""
        return pignistic_decision(self.class_mass.frame.labels, self.pignistic)[0]


class CredalClassifier:
    """Credal kinematic classifier of many tracks (see the module docstring).

    Parameters
    ----------
    behaviours : BehaviourModels
    relation : Relation
        Γ from ``behaviours.frame`` to the classes.
    likelihood_scale : "max" | "clip"
    discount : "none" | "instantaneous" | "cumulative"
    reliability : float, optional
        λ; default per ``discount`` (:data:`DEFAULT_RELIABILITY`).
    accumulation : "classes" | "behaviours"
    """

    def __init__(
        self,
        behaviours: BehaviourModels,
        relation: Relation,
        *,
        likelihood_scale: LikelihoodScale = "max",
        discount: Discount = "none",
        reliability: float | None = None,
        accumulation: Accumulation = "classes",
    ) -> None:
        if relation.source != behaviours.frame:
            raise ClassificationError("the relation must start from the behaviour frame")
        if likelihood_scale not in LIKELIHOOD_SCALES:
            raise ClassificationError(
                f"likelihood_scale must be one of {LIKELIHOOD_SCALES}, got {likelihood_scale!r}"
            )
        if discount not in DISCOUNTS:
            raise ClassificationError(f"discount must be one of {DISCOUNTS}, got {discount!r}")
        if accumulation not in ACCUMULATIONS:
            raise ClassificationError(
                f"accumulation must be one of {ACCUMULATIONS}, got {accumulation!r}"
            )
        lam = DEFAULT_RELIABILITY[discount] if reliability is None else float(reliability)
        if not (np.isfinite(lam) and 0.0 <= lam <= 1.0):
            raise ClassificationError(f"reliability must be in [0, 1], got {reliability!r}")
        self.behaviours = behaviours
        self.relation = relation
        self.likelihood_scale: LikelihoodScale = likelihood_scale
        self.discount: Discount = discount
        self.reliability = lam
        self.accumulation: Accumulation = accumulation

    @property
    def classes(self) -> Frame:
        """The class frame."""
        return self.relation.target

    @property
    def _frame(self) -> Frame:
        return self.classes if self.accumulation == "classes" else self.behaviours.frame

    def initial(self) -> CredalClassification:
        """Total ignorance: the vacuous mass ([MTT] §2.4)."""
        return self._state(MassFunction.vacuous(self._frame), 0.0, 0.0, 0)

    def _state(
        self, mass: MassFunction, step_conflict: float, log_normaliser: float, steps: int
    ) -> CredalClassification:
        class_mass = mass if self.accumulation == "classes" else self.relation.transfer(mass)
        betp = class_mass.pignistic()
        return CredalClassification(
            mass=mass,
            class_mass=class_mass,
            pignistic=betp,
            step_conflict=step_conflict,
            log_normaliser=log_normaliser,
            status="ok" if betp is not None else "total_conflict",
            steps=steps,
        )

    def step_mass(self, plausibilities: FloatArray) -> MassFunction:
        """m_k(·|z) of one track on the accumulation frame: GBT (eq 10), mapped if needed (eq 23)."""
        behaviour_mass = gbt_mass(self.behaviours.frame, plausibilities)
        if self.accumulation == "classes":
            return self.relation.transfer(behaviour_mass)
        return behaviour_mass

    def combine(self, prior: CredalClassification, step: MassFunction) -> CredalClassification:
        """One accumulation step (eq 11, with the configured discounting)."""
        previous = prior.mass
        if self.discount == "instantaneous":
            step = step.discount(self.reliability)
        elif self.discount == "cumulative":
            previous = previous.discount(self.reliability)
        combined = conjunctive(previous, step)
        conflict = combined.conflict
        kept = float(np.sum(combined.masses[combined.masks != 0]))  # 1 − K, no cancellation
        if kept <= CONFLICT_TOLERANCE:
            empty = MassFunction(self._frame, np.array([0], dtype=np.int64), np.array([1.0]))
            return self._state(empty, conflict, -np.inf, prior.steps + 1)
        return self._state(
            combined.normalized(),
            conflict,
            prior.log_normaliser + float(np.log(kept)),
            prior.steps + 1,
        )

    def update(
        self,
        states: Sequence[CredalClassification],
        log_mode_probabilities: FloatArray,
        log_model_likelihoods: FloatArray,
        detected: BoolArray | None = None,
    ) -> list[CredalClassification]:
        """Classify T tracks one step from their IMM update.

        Parameters
        ----------
        states : sequence of CredalClassification, length T
        log_mode_probabilities, log_model_likelihoods : ndarray, shape (T, r)
            The IMM's **updated** log μ_j and log Λ_j of this step
            (:class:`core.tracking.imm.IMMUpdate`).
        detected : ndarray of bool, shape (T,), optional
            Tracks without a measurement keep their state (no evidence).
        """
        tracks = len(states)
        hit = np.ones(tracks, dtype=bool) if detected is None else np.asarray(detected, dtype=bool)
        if hit.shape != (tracks,):
            raise ClassificationError(f"detected must have shape ({tracks},), got {hit.shape}")
        log_mu = np.asarray(log_mode_probabilities, dtype=np.float64)
        log_lambda = np.asarray(log_model_likelihoods, dtype=np.float64)
        if log_mu.shape[:1] != (tracks,) or log_lambda.shape[:1] != (tracks,):
            raise ClassificationError(f"need one row of IMM output per track ({tracks})")
        updated = list(states)
        rows = np.flatnonzero(hit)
        if rows.size == 0:
            return updated
        plausibilities = self.behaviours.plausibilities(
            log_mu[rows], log_lambda[rows], self.likelihood_scale
        )
        for row, pl in zip(rows.tolist(), plausibilities, strict=True):
            updated[row] = self.combine(states[row], self.step_mass(pl))
        return updated
