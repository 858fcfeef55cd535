"""Hypothesis strategies for random frames and mass functions."""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

from core.belief import Frame, MassFunction

LABELS = tuple("abcdefgh")


@st.composite
def frames(draw: st.DrawFn, max_size: int = 5) -> Frame:
    size = draw(st.integers(min_value=1, max_value=max_size))
    return Frame(LABELS[:size])


@st.composite
def mass_functions(
    draw: st.DrawFn, frame: Frame, *, allow_empty: bool = False, max_focal: int = 6
) -> MassFunction:
    """A valid mass function on ``frame``: unique focal masks, positive masses summing to 1."""
    lowest = 0 if allow_empty else 1
    masks = draw(
        st.lists(
            st.integers(min_value=lowest, max_value=frame.full),
            min_size=1,
            max_size=min(max_focal, frame.full + 1 - lowest),
            unique=True,
        )
    )
    weights = np.array(
        draw(st.lists(st.floats(0.01, 1.0), min_size=len(masks), max_size=len(masks)))
    )
    return MassFunction.from_masks(frame, masks, weights / weights.sum())


@st.composite
def mass_pairs(draw: st.DrawFn, max_size: int = 5) -> tuple[MassFunction, MassFunction]:
    frame = draw(frames(max_size))
    return draw(mass_functions(frame)), draw(mass_functions(frame))
