"""Building blocks shared by every wire model.

Every model derives from :class:`WireModel`: unknown keys are an error, types
are strict (a string is never silently read as a number), and floats must be
finite — a ``NaN`` or ``Infinity`` token in the JSON body is rejected at the
edge instead of reaching the algorithms.
"""

from __future__ import annotations

from datetime import datetime
from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, StringConstraints

FiniteFloat = Annotated[float, Field(allow_inf_nan=False)]
"""A finite float (NaN and ±Infinity rejected)."""

NonNegativeFloat = Annotated[float, Field(allow_inf_nan=False, ge=0.0)]
PositiveFloat = Annotated[float, Field(allow_inf_nan=False, gt=0.0)]
UnitFloat = Annotated[float, Field(allow_inf_nan=False, ge=0.0, le=1.0)]
"""A finite float in [0, 1]."""
OpenUnitFloat = Annotated[float, Field(allow_inf_nan=False, gt=0.0, lt=1.0)]
"""A finite float in the open interval (0, 1)."""

Vector = list[FiniteFloat]
Matrix = list[list[FiniteFloat]]

Label = Annotated[str, StringConstraints(min_length=1, max_length=64)]
"""A class label (an element of the session's class frame)."""

Identifier = Annotated[str, StringConstraints(min_length=1, max_length=64)]
"""A sensor, track or session identifier."""

Timestamp = Annotated[datetime, Field(strict=False)]
"""A UTC timestamp (ISO 8601 on the wire; parsed from text even in strict models)."""

MAX_CLASSES = 20
"""Class frames have at most 20 labels (docs/algorithms.md §1)."""


class WireModel(BaseModel):
    """Base of every request, response and message model."""

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)
