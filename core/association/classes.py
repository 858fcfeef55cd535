"""Class information as association evidence ([T2T] §2 Fig 2, §4 Fig 6; docs/algorithms.md §3.6).

When both sides carry class mass functions on one class frame, their conflict
``K = (m₁ ∩ m₂)(∅)`` is evidence against the association of the pair:
``pl_class(ℓ, t) = 1 − K``. It is computed for the gated pairs only, all pairs
at once on padded focal-set arrays.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from core.arrays import FloatArray, IntArray
from core.belief import MassFunction
from core.errors import InvalidInput

BLOCK_PAIRS = 1 << 14


def _padded(masses: Sequence[MassFunction]) -> tuple[IntArray, FloatArray]:
    width = max((len(m) for m in masses), default=1)
    masks = np.zeros((len(masses), width), dtype=np.int64)
    values = np.zeros((len(masses), width))
    for index, mass in enumerate(masses):
        masks[index, : len(mass)] = mass.masks
        values[index, : len(mass)] = mass.masses
    return masks, values


def check_classes(
    known_classes: Sequence[MassFunction] | None,
    incoming_classes: Sequence[MassFunction] | None,
    n_known: int,
    n_incoming: int,
) -> bool:
    """Validate class information; True when both sides carry it."""
    if known_classes is None and incoming_classes is None:
        return False
    if known_classes is None or incoming_classes is None:
        raise InvalidInput(
            "class information must be given for both sides (known_classes and incoming_classes) or neither"
        )
    for side, masses, expected in (
        ("known_classes", known_classes, n_known),
        ("incoming_classes", incoming_classes, n_incoming),
    ):
        if len(masses) != expected:
            raise InvalidInput(
                f"{side}: need one mass function per item ({expected}), got {len(masses)}"
            )
        for index, mass in enumerate(masses):
            if not isinstance(mass, MassFunction):
                raise InvalidInput(f"{side}[{index}] is not a MassFunction")
    frames = {m.frame for m in (*known_classes, *incoming_classes)}
    if len(frames) > 1:
        raise InvalidInput("class mass functions must all be on the same class frame")
    return True


def class_conflict(
    known_classes: Sequence[MassFunction],
    incoming_classes: Sequence[MassFunction],
    rows: IntArray,
    cols: IntArray,
) -> FloatArray:
    """K(ℓ, t) = (m_ℓ ∩ m_t)(∅) for every pair (ℓ, t) = (rows[i], cols[i])."""
    known_masks, known_masses = _padded(known_classes)
    incoming_masks, incoming_masses = _padded(incoming_classes)
    conflict = np.empty(len(rows))
    for start in range(0, len(rows), BLOCK_PAIRS):
        r = rows[start : start + BLOCK_PAIRS]
        c = cols[start : start + BLOCK_PAIRS]
        disjoint = (known_masks[r][:, :, None] & incoming_masks[c][:, None, :]) == 0
        weight = known_masses[r][:, :, None] * incoming_masses[c][:, None, :]
        conflict[start : start + BLOCK_PAIRS] = np.where(disjoint, weight, 0.0).sum(axis=(1, 2))
    return np.clip(conflict, 0.0, 1.0)
