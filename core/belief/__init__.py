"""Belief functions on finite frames (docs/algorithms.md §1).

Frames, sparse mass functions, Pl / Bel / BetP, the conjunctive and Dempster
rules, discounting, the GBT with its exact O(N²) pignistic probabilities,
multi-valued mappings between frames, and the pignistic decision (ties
admitted).
"""

from core.belief.combination import conflict, conjunctive, conjunctive_all, dempster
from core.belief.decision import TIE_TOLERANCE, DecisionState, pignistic_decision
from core.belief.frame import MAX_FRAME_SIZE, Frame, popcount
from core.belief.gbt import (
    gbt_betp,
    gbt_betp_rows,
    gbt_mass,
    pairwise_evidence_betp_rows,
)
from core.belief.mapping import Relation
from core.belief.mass import CONFLICT_TOLERANCE, MASS_TOLERANCE, MassFunction
from core.errors import FrameError, MassError, TotalConflict

__all__ = [
    "CONFLICT_TOLERANCE",
    "MASS_TOLERANCE",
    "MAX_FRAME_SIZE",
    "TIE_TOLERANCE",
    "DecisionState",
    "Frame",
    "FrameError",
    "MassError",
    "MassFunction",
    "Relation",
    "TotalConflict",
    "conflict",
    "conjunctive",
    "conjunctive_all",
    "dempster",
    "gbt_betp",
    "gbt_betp_rows",
    "gbt_mass",
    "pairwise_evidence_betp_rows",
    "pignistic_decision",
    "popcount",
]
