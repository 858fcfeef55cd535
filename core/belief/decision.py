"""The pignistic decision, and when it admits doubt (docs/design.md "Decisions that admit doubt").

The decision is the class of largest BetP ([MTT] §2.3: decide on the
pignistic probability). It is not always a class:

- ``decided``: one class has the largest BetP, by more than :data:`TIE_TOLERANCE`;
- ``tied``: two or more classes share the largest BetP within
  :data:`TIE_TOLERANCE`; the decision is ``None`` (no class is preferred, and
  frame order is not evidence);
- ``undefined``: there is no BetP (total conflict); the decision is ``None``.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence

import numpy as np

from core.arrays import FloatArray

TIE_TOLERANCE = 1e-9
"""Top BetP values closer than this are a tie."""


class DecisionState(enum.StrEnum):
    """Whether the pignistic decision names a class, and why not."""

    DECIDED = "decided"
    TIED = "tied"
    UNDEFINED = "undefined"


def pignistic_decision(
    labels: Sequence[str], betp: FloatArray | None
) -> tuple[str | None, DecisionState]:
    """The class of largest BetP and the decision's state (``None`` unless ``decided``)."""
    if betp is None or len(betp) == 0:
        return None, DecisionState.UNDEFINED
    best = int(np.argmax(betp))
    contenders = int(np.count_nonzero(betp >= betp[best] - TIE_TOLERANCE))
    if contenders > 1:
        return None, DecisionState.TIED
    return labels[best], DecisionState.DECIDED
