"""Credal classification of many tracks at once, on dense mass vectors ([MTT] §5.2).

:class:`BatchedCredalClassifier` computes exactly what
:class:`~core.classification.credal.CredalClassifier` computes (same options,
same Readings: see :mod:`core.classification.credal`), for T tracks in a
handful of numpy operations instead of a Python loop over
:class:`~core.belief.MassFunction` objects.

Behaviour and class frames are tiny (3 behaviours, 2–3 classes in the presets
of docs/algorithms.md §4), so each track's mass lives in a **dense** row over the
2^n subsets of the frame, in bit-mask order (docs/algorithms.md §1 forbids 2^n
arrays only where an operation does not need them: these frames are capped
by :data:`MAX_DENSE_FRAME`). Per step, vectorised over tracks:

1. GBT on the behaviours ([MTT] eq 10): ``m(A) = Π_{k∈A} p_k Π_{k∉A} (1 − p_k)``
   for every mask A, the product taken in frame order;
2. mapping Γ to the classes ([MTT] eq 23) by a precomputed image table
   (``accumulation="classes"``);
3. discounting ([MTT] eq 7) of the step mass (``"instantaneous"``) or of the
   cumulative one (``"cumulative"``);
4. conjunctive combination ([MTT] eq 5, eq 11) by a precomputed intersection
   table ``A ∩ B`` over all pairs of masks;
5. normalisation with the running conflict ``Σ_k log(1 − K_k)`` and the
   ``total_conflict`` state (``1 − K_k ≤`` :data:`~core.belief.CONFLICT_TOLERANCE`);
6. mapping to the classes (``accumulation="behaviours"``) and BetP ([MTT] eq 8).

Every sum is accumulated in the same order as the sparse reference (ascending
masks, then ascending pairs of masks), so for the preset frames the results
are the reference's to the last bit; the tests hold them to 1e-12.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import pairwise

import numpy as np

from core.arrays import BoolArray, FloatArray, IntArray
from core.belief import CONFLICT_TOLERANCE, Frame, MassFunction, Relation, popcount
from core.classification.behaviours import BehaviourModels, LikelihoodScale
from core.classification.credal import (
    Accumulation,
    CredalClassification,
    CredalClassifier,
    Discount,
    Status,
)
from core.errors import ClassificationError

MAX_DENSE_FRAME = 10
"""Largest behaviour or class frame held densely (2^10 subsets per track)."""


def _frozen(array: np.ndarray) -> np.ndarray:
    array.flags.writeable = False
    return array


@dataclass(frozen=True, eq=False)
class CredalBatch:
    """The credal class knowledge of T tracks (one row per track).

    Attributes
    ----------
    masses : ndarray, shape (T, 2^n)
        Cumulative mass on the accumulation frame, dense in mask order,
        normalised; the row is m(∅) = 1 in the ``total_conflict`` state.
    class_masses : ndarray, shape (T, 2^|C|)
        The same on the classes (``masses`` itself when accumulating on classes).
    pignistic : ndarray, shape (T, |C|)
        BetP per class; zeros where undefined (see ``defined``).
    defined : ndarray of bool, shape (T,)
        False in the ``total_conflict`` state (no BetP).
    step_conflicts : ndarray, shape (T,)
        K of each track's last combination (0 before any evidence).
    log_normalisers : ndarray, shape (T,)
        Σ_k log(1 − K_k) per track (−inf after a total conflict).
    steps : ndarray of int64, shape (T,)
        Steps of evidence received.
    """

    masses: FloatArray
    class_masses: FloatArray
    pignistic: FloatArray
    defined: BoolArray
    step_conflicts: FloatArray
    log_normalisers: FloatArray
    steps: IntArray

    @property
    def n_tracks(self) -> int:
        """T."""
        return len(self.steps)

    @property
    def conflicts(self) -> FloatArray:
        """Running conflict ``1 − Π_k (1 − K_k)`` per track."""
        return np.asarray(-np.expm1(self.log_normalisers), dtype=np.float64)

    def status(self, row: int) -> Status:
        """``"ok"`` or ``"total_conflict"`` of one track."""
        return "ok" if bool(self.defined[row]) else "total_conflict"

    def select(self, rows: IntArray) -> CredalBatch:
        """The tracks of ``rows``, in that order."""
        return CredalBatch(*(_frozen(np.asarray(field[rows])) for field in self._fields()))

    def replace(self, rows: IntArray, values: CredalBatch) -> CredalBatch:
        """A copy whose tracks ``rows`` are the tracks of ``values``, in order."""
        fields = []
        for old, new in zip(self._fields(), values._fields(), strict=True):
            merged = old.copy()
            merged[rows] = new
            fields.append(_frozen(merged))
        return CredalBatch(*fields)

    def concatenate(self, other: CredalBatch) -> CredalBatch:
        """These tracks followed by ``other``'s."""
        return CredalBatch(
            *(
                _frozen(np.concatenate([first, second]))
                for first, second in zip(self._fields(), other._fields(), strict=True)
            )
        )

    def _fields(self) -> tuple[np.ndarray, ...]:
        return (
            self.masses,
            self.class_masses,
            self.pignistic,
            self.defined,
            self.step_conflicts,
            self.log_normalisers,
            self.steps,
        )


def dense_to_mass(frame: Frame, row: FloatArray) -> MassFunction:
    """The canonical sparse :class:`MassFunction` of one dense row (focal sets: mass > 0)."""
    masks = np.flatnonzero(row > 0.0).astype(np.int64)
    return MassFunction(frame, masks, np.asarray(row[masks], dtype=np.float64))


def mass_to_dense(mass: MassFunction) -> FloatArray:
    """The dense row (2^n masses in mask order) of a sparse mass function."""
    row = np.zeros(mass.frame.full + 1)
    row[mass.masks] = mass.masses
    return row


class BatchedCredalClassifier:
    """:class:`~core.classification.credal.CredalClassifier` vectorised over tracks.

    Same parameters, validation and results (module docstring); the state of
    T tracks is one :class:`CredalBatch`.

    Parameters
    ----------
    behaviours : BehaviourModels
    relation : Relation
        Γ from ``behaviours.frame`` to the classes.
    likelihood_scale : "max" | "clip"
    discount : "none" | "instantaneous" | "cumulative"
    reliability : float, optional
        λ; default per ``discount``.
    accumulation : "classes" | "behaviours"

    Raises
    ------
    ClassificationError
        As :class:`CredalClassifier`, or a frame larger than :data:`MAX_DENSE_FRAME`.
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
        reference = CredalClassifier(
            behaviours,
            relation,
            likelihood_scale=likelihood_scale,
            discount=discount,
            reliability=reliability,
            accumulation=accumulation,
        )
        for frame in (behaviours.frame, relation.target):
            if len(frame) > MAX_DENSE_FRAME:
                raise ClassificationError(
                    f"batched credal classification holds frames of at most {MAX_DENSE_FRAME} "
                    f"labels densely, got {len(frame)}"
                )
        self.reference = reference
        self.behaviours = behaviours
        self.relation = relation
        self.likelihood_scale: LikelihoodScale = reference.likelihood_scale
        self.discount: Discount = reference.discount
        self.reliability = reference.reliability
        self.accumulation: Accumulation = reference.accumulation
        n_behaviours = len(behaviours.frame)
        behaviour_masks = np.arange(1 << n_behaviours, dtype=np.int64)
        self._gbt_member = behaviours.frame.bits(behaviour_masks)  # (2^|B|, |B|)
        self._image = relation.image(behaviour_masks)  # Γ(A) per behaviour mask
        size = self.frame.full + 1
        first, second = np.divmod(np.arange(size * size, dtype=np.int64), size)
        # Intersection table: pair (a, b) in the reference's order lands on a ∩ b.
        self._pairs = [
            (int(a), int(b), int(a & b))
            for a, b in zip(first.tolist(), second.tolist(), strict=True)
        ]
        class_masks = np.arange(self.classes.full + 1, dtype=np.int64)
        cardinality = popcount(class_masks).astype(np.float64)
        cardinality[0] = np.inf  # ∅ takes no share of BetP
        self._class_members = [np.flatnonzero(bits) for bits in self.classes.bits(class_masks)]
        self._inverse_cardinality = 1.0 / cardinality

    # ---------------------------------------------------------------- frames
    @property
    def classes(self) -> Frame:
        """The class frame."""
        return self.relation.target

    @property
    def frame(self) -> Frame:
        """The accumulation frame (classes or behaviours)."""
        return self.classes if self.accumulation == "classes" else self.behaviours.frame

    # ------------------------------------------------------------- states
    def initial(self, count: int) -> CredalBatch:
        """Total ignorance for ``count`` tracks: the vacuous mass ([MTT] §2.4)."""
        masses = np.zeros((count, self.frame.full + 1))
        masses[:, -1] = 1.0
        return self._batch(
            masses, np.zeros(count), np.zeros(count), np.zeros(count, dtype=np.int64)
        )

    def from_classifications(self, states: Sequence[CredalClassification]) -> CredalBatch:
        """The batch of reference states (e.g. restored or built by :class:`CredalClassifier`)."""
        size = self.frame.full + 1
        masses = np.zeros((len(states), size))
        for row, state in enumerate(states):
            if state.mass.frame != self.frame:
                raise ClassificationError("a state is not on the accumulation frame")
            masses[row, state.mass.masks] = state.mass.masses
        return self._batch(
            masses,
            np.array([s.step_conflict for s in states], dtype=np.float64),
            np.array([s.log_normaliser for s in states], dtype=np.float64),
            np.array([s.steps for s in states], dtype=np.int64),
        )

    def classification(self, batch: CredalBatch, row: int) -> CredalClassification:
        """The reference :class:`CredalClassification` of one track."""
        mass = dense_to_mass(self.frame, batch.masses[row])
        class_mass = (
            mass
            if self.accumulation == "classes"
            else dense_to_mass(self.classes, batch.class_masses[row])
        )
        defined = bool(batch.defined[row])
        return CredalClassification(
            mass=mass,
            class_mass=class_mass,
            pignistic=batch.pignistic[row].copy() if defined else None,
            step_conflict=float(batch.step_conflicts[row]),
            log_normaliser=float(batch.log_normalisers[row]),
            status="ok" if defined else "total_conflict",
            steps=int(batch.steps[row]),
        )

    def class_mass_functions(self, batch: CredalBatch) -> list[MassFunction]:
        """The class mass of every track as a sparse :class:`MassFunction`."""
        present = batch.class_masses > 0.0
        rows, masks = np.nonzero(present)
        values = batch.class_masses[rows, masks]
        bounds = np.concatenate([[0], np.cumsum(present.sum(axis=1))]).tolist()
        frame = self.classes
        masks = masks.astype(np.int64)
        return [
            MassFunction(frame, masks[start:stop], values[start:stop])
            for start, stop in pairwise(bounds)
        ]

    # ----------------------------------------------------------- evidence
    def step_masses(self, plausibilities: FloatArray) -> FloatArray:
        """m_k(·|z) of T tracks on the accumulation frame, shape (T, 2^n).

        GBT on the behaviours ([MTT] eq 10), mapped to the classes by Γ
        ([MTT] eq 23) when accumulating on classes.
        """
        p = np.asarray(plausibilities, dtype=np.float64)
        n_behaviours = len(self.behaviours.frame)
        if p.ndim != 2 or p.shape[1] != n_behaviours:
            raise ClassificationError(
                f"need plausibilities of shape (T, {n_behaviours}), got {p.shape}"
            )
        if not np.all((p >= 0.0) & (p <= 1.0)):
            raise ClassificationError("plausibilities must be in [0, 1]")
        factors = np.where(self._gbt_member[None, :, :], p[:, None, :], 1.0 - p[:, None, :])
        behaviour_mass = factors[:, :, 0].copy()
        for k in range(1, n_behaviours):
            behaviour_mass *= factors[:, :, k]
        if self.accumulation == "behaviours":
            return behaviour_mass
        class_mass = np.zeros((len(p), self.classes.full + 1))
        for mask, image in enumerate(self._image.tolist()):
            class_mass[:, image] += behaviour_mass[:, mask]
        return class_mass

    def _discounted(self, masses: FloatArray) -> FloatArray:
        out = self.reliability * masses
        out[:, -1] += 1.0 - self.reliability
        return out

    def _conjunctive(self, first: FloatArray, second: FloatArray) -> FloatArray:
        """Unnormalised conjunctive rule row by row ([MTT] eq 5), pairs in mask order."""
        out = np.zeros_like(first)
        for a, b, target in self._pairs:
            out[:, target] += first[:, a] * second[:, b]
        return out

    @staticmethod
    def _row_sum(values: FloatArray) -> FloatArray:
        """Σ over columns, left to right (the order of the sparse reference's sums)."""
        total = values[:, 0].copy()
        for column in range(1, values.shape[1]):
            total += values[:, column]
        return total

    def _to_classes(self, masses: FloatArray) -> FloatArray:
        if self.accumulation == "classes":
            return masses
        out = np.zeros((len(masses), self.classes.full + 1))
        for mask, image in enumerate(self._image.tolist()):
            out[:, image] += masses[:, mask]
        return out

    def _batch(
        self,
        masses: FloatArray,
        step_conflicts: FloatArray,
        log_normalisers: FloatArray,
        steps: IntArray,
    ) -> CredalBatch:
        class_masses = self._to_classes(masses)
        # BetP ([MTT] eq 8) as MassFunction.pignistic: shares of the non-empty sets.
        # Sums in mask order, row by row: a track's result never depends on the batch.
        normaliser = self._row_sum(class_masses[:, 1:])
        defined = normaliser > CONFLICT_TOLERANCE
        shares = class_masses * self._inverse_cardinality
        betp = np.zeros((len(class_masses), len(self.classes)))
        for mask, members in enumerate(self._class_members):
            if mask:
                betp[:, members] += shares[:, mask, None]
        total = self._row_sum(betp)
        betp = np.where(defined[:, None], betp / np.where(defined, total, 1.0)[:, None], 0.0)
        return CredalBatch(
            _frozen(masses),
            _frozen(class_masses),
            _frozen(betp),
            _frozen(defined),
            _frozen(step_conflicts),
            _frozen(log_normalisers),
            _frozen(steps),
        )

    def combine(self, prior: CredalBatch, step: FloatArray) -> CredalBatch:
        """One accumulation step of every track of ``prior`` (eq 11, configured discounting).

        Parameters
        ----------
        prior : CredalBatch of T tracks
        step : ndarray, shape (T, 2^n)
            Step masses on the accumulation frame (e.g. :meth:`step_masses`,
            or another track's cumulative mass at a phantom hand-over).
        """
        previous = prior.masses
        step = np.asarray(step, dtype=np.float64)
        if step.shape != previous.shape:
            raise ClassificationError(
                f"step masses must have shape {previous.shape}, got {step.shape}"
            )
        if self.discount == "instantaneous":
            step = self._discounted(step)
        elif self.discount == "cumulative":
            previous = self._discounted(previous)
        combined = self._conjunctive(previous, step)
        conflict = combined[:, 0].copy()
        kept = self._row_sum(combined[:, 1:])  # 1 − K as the sum of the non-empty masses
        total = kept <= CONFLICT_TOLERANCE
        safe = np.where(total, 1.0, kept)
        normalised = combined / safe[:, None]
        normalised[:, 0] = 0.0
        normalised[total] = 0.0
        normalised[total, 0] = 1.0
        with np.errstate(divide="ignore"):
            log_kept = np.log(np.where(total, 1.0, kept))
        log_normalisers = np.where(total, -np.inf, prior.log_normalisers + log_kept)
        return self._batch(normalised, conflict, log_normalisers, prior.steps + 1)

    def update(
        self,
        batch: CredalBatch,
        log_mode_probabilities: FloatArray,
        log_model_likelihoods: FloatArray,
        detected: BoolArray | None = None,
    ) -> CredalBatch:
        """Classify T tracks one step from their IMM update (as :meth:`CredalClassifier.update`).

        Parameters
        ----------
        batch : CredalBatch of T tracks
        log_mode_probabilities, log_model_likelihoods : ndarray, shape (T, r)
            The IMM's **updated** log μ_j and log Λ_j of this step.
        detected : ndarray of bool, shape (T,), optional
            Tracks without a measurement keep their state (no evidence).
        """
        tracks = batch.n_tracks
        hit = np.ones(tracks, dtype=bool) if detected is None else np.asarray(detected, dtype=bool)
        if hit.shape != (tracks,):
            raise ClassificationError(f"detected must have shape ({tracks},), got {hit.shape}")
        log_mu = np.asarray(log_mode_probabilities, dtype=np.float64)
        log_lambda = np.asarray(log_model_likelihoods, dtype=np.float64)
        if log_mu.shape[:1] != (tracks,) or log_lambda.shape[:1] != (tracks,):
            raise ClassificationError(f"need one row of IMM output per track ({tracks})")
        rows = np.flatnonzero(hit)
        if rows.size == 0:
            return batch
        plausibilities = self.behaviours.plausibilities(
            log_mu[rows], log_lambda[rows], self.likelihood_scale
        )
        if rows.size == tracks:
            return self.combine(batch, self.step_masses(plausibilities))
        updated = self.combine(batch.select(rows), self.step_masses(plausibilities))
        return batch.replace(rows, updated)
