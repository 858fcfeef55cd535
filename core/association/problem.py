"""One association problem: the two sides, the distance, optional classes, the solver."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray
from core.association.assignment import Solver
from core.association.classes import class_conflict
from core.belief import MassFunction
from core.distance import CandidatePairs, DistanceModel, Estimates, gated_pairs
from core.distance.pairwise import COVARIANCE_WEIGHTS


@dataclass(frozen=True, eq=False)
class AssociationProblem:
    """Known items (rows) and incoming items (columns) to associate.

    Attributes
    ----------
    known, incoming : Estimates
    distance : DistanceModel
    known_classes, incoming_classes : sequences of MassFunction, or None
    solver : {"lapjv", "scipy"}
    cluster : bool
        Solve connected components separately (False: one dense problem).
    """

    known: Estimates
    incoming: Estimates
    distance: DistanceModel
    known_classes: Sequence[MassFunction] | None = None
    incoming_classes: Sequence[MassFunction] | None = None
    solver: Solver = "lapjv"
    cluster: bool = True

    @property
    def n_known(self) -> int:
        return len(self.known)

    @property
    def n_incoming(self) -> int:
        return len(self.incoming)

    @property
    def dimension(self) -> int:
        """q, the dimension of the compared vectors."""
        return self.known.dimension if self.n_known else self.incoming.dimension

    @property
    def has_classes(self) -> bool:
        return self.known_classes is not None and self.incoming_classes is not None

    def pairs(self, gate: float) -> CandidatePairs:
        """Candidate pairs with D ≤ gate."""
        return gated_pairs(self.known, self.incoming, gate, self.distance)

    def class_plausibility(self, pairs: CandidatePairs) -> FloatArray | None:
        """pl_class = 1 − K per pair (§3.6), or None without class information."""
        if self.known_classes is None or self.incoming_classes is None:
            return None
        return 1.0 - class_conflict(
            self.known_classes, self.incoming_classes, pairs.rows, pairs.cols
        )

    def smallest_log_det(self) -> float:
        """A lower bound of log|C| over all pairs (|A + B| ≥ max(|A|, |B|) for A, B ≻ 0)."""
        w_known, w_incoming = COVARIANCE_WEIGHTS[self.distance.covariance]
        q = self.dimension
        bounds = []
        for weight, covariances in (
            (w_known, self.known.covariances),
            (w_incoming, self.incoming.covariances),
        ):
            if weight > 0 and covariances is not None and len(covariances):
                bounds.append(q * np.log(weight) + float(np.linalg.slogdet(covariances)[1].min()))
        return max(bounds) if bounds else -np.inf
