"""Hand-over: newly confirmed rows matched to the rows that keep their identity
(docs/algorithms.md §4 "Invisibility", [HZ] §5.1).

A track confirmed in this step may be an old target coming out of a blind
zone or an occlusion: it is compared with the phantoms (the fusion engine
also compares a sensor's new track with the established tracks it may
duplicate). Global nearest neighbour on the ``sum`` distance of the full
state, gated at the life cycle's ``gate_probability``; each matched keeper
then takes the newcomer's estimate and :func:`core.lifecycle.hand_over`
moves the life.
"""

from __future__ import annotations

from core.arrays import FloatArray, IntArray
from core.association import associate


def hand_over_pairs(
    keepers: tuple[FloatArray, FloatArray],
    newcomers: tuple[FloatArray, FloatArray],
    gate_probability: float,
) -> tuple[IntArray, IntArray]:
    """(keeper index, newcomer index) of each matched pair; ``keepers`` and ``newcomers``
    are (means (n, d), covariances (n, d, d)), neither empty."""
    decision = associate(keepers, newcomers, "gnn", {"gate_probability": gate_probability}, "sum")
    return decision.pair_known, decision.pair_incoming
