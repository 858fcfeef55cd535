"""Multi-valued mapping between frames ([MTT] §5.2.1, eq 23).

A relation Γ sends each element b of a frame B to a subset Γ(b) of a frame C
(e.g. behaviours → the classes that can show them). It extends to subsets by
``Γ(A) = ∪_{b∈A} Γ(b)``, ``Γ(∅) = ∅``, and transfers mass functions by
``m^C(S) = Σ_{A : Γ(A) = S} m^B(A)``. The matrices M̄ printed in [MTT]
§6.1.2 and §6.3.2 are this transfer written for every subset: see
:meth:`Relation.matrix`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray, IntArray
from core.belief.frame import Frame
from core.belief.mass import MassFunction
from core.errors import FrameError


@dataclass(frozen=True)
class Relation:
    """The relation Γ from ``source`` to ``target``.

    Attributes
    ----------
    source, target : Frame
    images : ndarray of int64
        ``images[i]`` is the mask of Γ(source.labels[i]) in ``target``.
    """

    source: Frame
    target: Frame
    images: IntArray

    @classmethod
    def from_mapping(
        cls, source: Frame, target: Frame, relation: Mapping[str, Iterable[str]]
    ) -> Relation:
        """Build Γ from ``{source label: target labels}``; every source label needs an image.

        Raises
        ------
        FrameError
            A label is unknown, a source label has no image, or an image is empty.
        """
        unknown = sorted(set(relation) - set(source.labels))
        if unknown:
            raise FrameError(f"relation names labels outside the source frame: {unknown}")
        images = np.zeros(len(source), dtype=np.int64)
        for i, label in enumerate(source.labels):
            if label not in relation:
                raise FrameError(f"relation gives no image for {label!r}")
            images[i] = target.mask(relation[label])
            if images[i] == 0:
                raise FrameError(f"relation maps {label!r} to the empty set")
        images.flags.writeable = False
        return cls(source, target, images)

    def image(self, masks: IntArray) -> IntArray:
        """Γ(A) for every mask A of the source frame (vectorised)."""
        masks = np.asarray(masks, dtype=np.int64)
        member = self.source.bits(masks)
        return np.asarray(
            np.bitwise_or.reduce(np.where(member, self.images, 0), axis=-1), dtype=np.int64
        )

    def transfer(self, mass: MassFunction) -> MassFunction:
        """m^C(S) = Σ_{Γ(A) = S} m^B(A)  ([MTT] eq 23)."""
        if mass.frame != self.source:
            raise FrameError(
                f"mass function is on {list(mass.frame.labels)}, the relation starts from "
                f"{list(self.source.labels)}"
            )
        return MassFunction.aggregate(self.target, self.image(mass.masks), mass.masses)

    def matrix(self) -> FloatArray:
        """The conditioning matrix M̄ (2^|C| × 2^|B|): ``M̄[Γ(A), A] = 1``, subsets in mask order."""
        columns = np.arange(1 << len(self.source), dtype=np.int64)
        matrix = np.zeros((1 << len(self.target), len(columns)))
        matrix[self.image(columns), columns] = 1.0
        return matrix
