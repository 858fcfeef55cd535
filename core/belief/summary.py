"""Bounded mass functions: summarization ([LGS86]) and a GBT built within the bound.

The fused class mass of a track combines every sensor's evidence; the
conjunctive rule multiplies the numbers of focal sets, and the GBT of
likelihoods over F fractional classes has 2^F of them (a million for a
20-class frame). 32 focal sets keep a 2 000-track result of a 20-class frame
near 10 MB and its step within a second of numpy. To keep every step bounded, a mass with more than
:data:`MAX_FUSED_FOCAL_SETS` focal sets is *summarized* (Lowrance, Garvey &
Strat 1986, "A framework for evidential-reasoning systems", §summarization):
the ``k − 1`` focal sets of largest mass are kept and the rest of the mass
goes to the union of the dropped focal sets. Every dropped focal set is a
subset of that union, so the summary is a weakening of the mass: Bel never
grows and Pl never shrinks — it claims no more than the evidence does. m(∅)
(the conflict) is always kept as it is. Results say ``summarized: true``
where this happened; below the bound every mass is exact.
"""

from __future__ import annotations

import numpy as np

from core.arrays import FloatArray
from core.belief.frame import Frame
from core.belief.mass import MassFunction

MAX_FUSED_FOCAL_SETS = 32
"""Focal sets a fused (or accumulated) class mass keeps at most."""


def summarize(mass: MassFunction, limit: int = MAX_FUSED_FOCAL_SETS) -> tuple[MassFunction, bool]:
    """``mass`` with at most ``limit`` focal sets (≥ 2), and whether it had to be summarized.

    Ties in mass are broken by focal-set mask (the masks are sorted): deterministic.
    """
    if len(mass) <= limit:
        return mass, False
    masks, masses = mass.masks, mass.masses
    order = np.argsort(-masses, kind="stable")
    empty = np.flatnonzero(masks == 0)
    if len(empty):  # the conflict stays where it is
        order = np.concatenate([empty, order[order != empty[0]]])
    keep, drop = order[: limit - 1], order[limit - 1 :]
    union = int(np.bitwise_or.reduce(masks[drop]))
    summary = MassFunction.aggregate(
        mass.frame,
        np.append(masks[keep], union),
        np.append(masses[keep], float(np.sum(masses[drop]))),
    )
    return summary, True


def bounded_gbt_mass(
    frame: Frame, plausibility: FloatArray, limit: int = MAX_FUSED_FOCAL_SETS
) -> tuple[MassFunction, bool]:
    """The GBT mass of ``plausibility`` ([MTT] eq 10), summarized to ``limit`` focal sets.

    The GBT mass is the conjunctive combination over the classes c of
    m_c(Ω) = p_c, m_c(Ω \\ {c}) = 1 − p_c (the product form of eq 10); it is built
    class by class and summarized after each class, so no more than 2 × ``limit``
    focal sets ever exist. Exact (and equal to :func:`~core.belief.gbt.gbt_mass`)
    when the 2^F subsets of the F fractional classes fit in ``limit``.
    """
    p = np.asarray(plausibility, dtype=np.float64)
    bit = np.int64(1) << np.arange(len(frame), dtype=np.int64)
    start = int(bit[p > 0.0].sum())
    mass = MassFunction.aggregate(frame, np.array([start], dtype=np.int64), np.array([1.0]))
    summarized = False
    for element in np.flatnonzero((p > 0.0) & (p < 1.0)).tolist():
        keep = ~bit[element]
        combined = MassFunction.aggregate(
            frame,
            np.concatenate([mass.masks, mass.masks & keep]),
            np.concatenate([mass.masses * p[element], mass.masses * (1.0 - p[element])]),
        )
        mass, cut = summarize(combined, limit)
        summarized = summarized or cut
    return mass, summarized
