"""Behaviours as groups of IMM models, and their likelihoods / plausibilities ([MTT] §5).

A behaviour ``b_i`` is a set ``M_{b_i}`` of models of the IMM bank ([MTT] §5,
eq 17). From the IMM's mode probabilities μ_j and model likelihoods Λ_j of one
step, the behaviour likelihood ([MTT] eq 19, Bayesian) and the behaviour
plausibility ([MTT] eq 22, credal) are the same number::

    l_{b_i} = Pl({b_i}) = Σ_{j ∈ M_{b_i}} μ'_j Λ_j,   μ'_j = μ_j / Σ_{l ∈ M_{b_i}} μ_l   (eq 20)

Everything is computed in the log domain, vectorised over tracks.

- **Reading (``mode_probabilities``):** [MTT] §5.1.1 says "the *a posteriori*
  probability μ_j"; §5.2 says only "the IMM models probabilities". Both are
  defensible, and the caller chooses which μ it passes:
  ``"updated"`` (default) — the IMM's posterior μ_j of the step, which
  already holds that step's Λ_j (so eq 19 counts the step's likelihood
  twice); ``"predicted"`` — the mixed prior c̄_j of the step, before its
  measurement (eq 19 is then the behaviour's predictive likelihood).
- **Reading:** when every model of a behaviour has μ_j = 0 exactly (log μ = −inf),
  eq 20 is 0/0; we then take μ' uniform over the behaviour.
- **Reading (``likelihood_scale``):** Λ_j are densities, so Pl({b}) can exceed
  1; the GBT needs values in [0, 1]. ``"max"`` (default) divides by the largest
  behaviour value of the step; ``"clip"`` takes ``min(Pl, 1)``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from core.arrays import BoolArray, FloatArray
from core.belief import Frame
from core.errors import ClassificationError
from core.numerics import logsumexp

LikelihoodScale = Literal["max", "clip"]
LIKELIHOOD_SCALES: tuple[LikelihoodScale, ...] = ("max", "clip")
ModeProbabilities = Literal["updated", "predicted"]
MODE_PROBABILITY_READINGS: tuple[ModeProbabilities, ...] = ("updated", "predicted")
"""Which μ_j eq 19/22 weights with (module Reading): the step's posterior, or its prior."""


@dataclass(frozen=True)
class BehaviourModels:
    """Which models of a bank make each behaviour.

    Attributes
    ----------
    frame : Frame
        The behaviours B.
    model_names : tuple of str
        The bank's models, in bank order.
    membership : ndarray of bool, shape (|B|, r)
        ``membership[i, j]`` is True when model j belongs to behaviour i.
    """

    frame: Frame
    model_names: tuple[str, ...]
    membership: BoolArray

    @classmethod
    def from_mapping(
        cls,
        frame: Frame,
        model_names: Sequence[str],
        behaviours: Mapping[str, Iterable[str]],
    ) -> BehaviourModels:
        """Build from ``{behaviour: model names}``; every behaviour needs at least one model."""
        names = tuple(model_names)
        index = {name: j for j, name in enumerate(names)}
        unknown = sorted(set(behaviours) - set(frame.labels))
        if unknown:
            raise ClassificationError(f"behaviours outside the frame: {unknown}")
        membership = np.zeros((len(frame), len(names)), dtype=bool)
        for i, behaviour in enumerate(frame.labels):
            if behaviour not in behaviours:
                raise ClassificationError(f"behaviour {behaviour!r} has no models")
            for model in behaviours[behaviour]:
                if model not in index:
                    raise ClassificationError(
                        f"behaviour {behaviour!r} names model {model!r}, not in the bank {list(names)}"
                    )
                membership[i, index[model]] = True
            if not membership[i].any():
                raise ClassificationError(f"behaviour {behaviour!r} has no models")
        membership.flags.writeable = False
        return cls(frame, names, membership)

    def log_likelihoods(
        self, log_mode_probabilities: FloatArray, log_model_likelihoods: FloatArray
    ) -> FloatArray:
        """``log l_{b_i}`` of every track and behaviour ([MTT] eq 19/22 with eq 20).

        Parameters
        ----------
        log_mode_probabilities : ndarray, shape (T, r)
            log μ_j (updated, normalised or not: eq 20 renormalises).
        log_model_likelihoods : ndarray, shape (T, r)
            log Λ_j ([MTT] eq 18).

        Returns
        -------
        ndarray, shape (T, |B|)
        """
        log_mu = np.asarray(log_mode_probabilities, dtype=np.float64)
        log_lambda = np.asarray(log_model_likelihoods, dtype=np.float64)
        r = len(self.model_names)
        if log_mu.ndim != 2 or log_mu.shape[1] != r or log_lambda.shape != log_mu.shape:
            raise ClassificationError(
                f"need log mode probabilities and log likelihoods of shape (T, {r}), "
                f"got {log_mu.shape} and {log_lambda.shape}"
            )
        if np.any(np.isnan(log_mu)) or np.any(np.isnan(log_lambda)):
            raise ClassificationError("log mode probabilities and log likelihoods must not be NaN")
        member = self.membership[None, :, :]  # (1, B, r)
        grouped = np.where(member, log_mu[:, None, :], -np.inf)  # (T, B, r)
        group_total = logsumexp(grouped, axis=2)  # (T, B)
        defined = np.isfinite(group_total)
        uniform = -np.log(self.membership.sum(axis=1))[None, :, None]
        log_weights = np.where(
            defined[:, :, None],
            grouped - np.where(defined, group_total, 0.0)[:, :, None],
            np.where(member, uniform, -np.inf),
        )  # log μ'_j, eq 20
        terms = np.where(member, log_weights + log_lambda[:, None, :], -np.inf)
        return logsumexp(terms, axis=2)

    def plausibilities(
        self,
        log_mode_probabilities: FloatArray,
        log_model_likelihoods: FloatArray,
        likelihood_scale: LikelihoodScale = "max",
    ) -> FloatArray:
        """Behaviour plausibilities in [0, 1] for the GBT ([MTT] eq 22), shape (T, |B|).

        See the module Reading on ``likelihood_scale``. With ``"max"``, a
        track whose every behaviour has likelihood 0 gets all-zero
        plausibilities (its GBT mass is all on ∅).
        """
        log_pl = self.log_likelihoods(log_mode_probabilities, log_model_likelihoods)
        if likelihood_scale == "max":
            peak = np.max(log_pl, axis=1, keepdims=True)
            finite = np.isfinite(peak)
            return np.asarray(
                np.where(finite, np.exp(log_pl - np.where(finite, peak, 0.0)), 0.0),
                dtype=np.float64,
            )
        if likelihood_scale == "clip":
            return np.asarray(np.exp(np.minimum(log_pl, 0.0)), dtype=np.float64)
        raise ClassificationError(
            f"likelihood_scale must be one of {LIKELIHOOD_SCALES}, got {likelihood_scale!r}"
        )
