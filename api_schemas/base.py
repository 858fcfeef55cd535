"""Building blocks shared by every wire model.

Every model derives from :class:`WireModel`: unknown keys are an error, types
are strict (a string is never silently read as a number), and floats must be
finite — a ``NaN`` or ``Infinity`` token in the JSON body is rejected at the
edge instead of reaching the algorithms.
"""

from __future__ import annotations

import math
from datetime import datetime
from typing import Annotated

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, StringConstraints
from pydantic_core import PydanticCustomError

FiniteFloat = Annotated[float, Field(allow_inf_nan=False)]
"""A finite float (NaN and ±Infinity rejected)."""

NonNegativeFloat = Annotated[float, Field(allow_inf_nan=False, ge=0.0)]
PositiveFloat = Annotated[float, Field(allow_inf_nan=False, gt=0.0)]
UnitFloat = Annotated[float, Field(allow_inf_nan=False, ge=0.0, le=1.0)]
"""A finite float in [0, 1]."""
OpenUnitFloat = Annotated[float, Field(allow_inf_nan=False, gt=0.0, lt=1.0)]
"""A finite float in the open interval (0, 1)."""

Vector = list[FiniteFloat]


def rows_expected(value: object) -> object:
    """A matrix given as one flat list of numbers is one error that says rows are expected
    ("a list of 4 rows of 4"), not one "not a list" error per number."""
    if not isinstance(value, list) or not value or isinstance(value[0], list):
        return value
    if not any(isinstance(row, list) for row in value):
        count = len(value)
        side = math.isqrt(count)
        shape = (
            f"a list of {side} rows of {side}"
            if side * side == count
            else "a list of rows (each a list of numbers)"
        )
        raise PydanticCustomError(
            "matrix_rows",
            "must be {shape} (each row a list); got a flat list of {count} entries",
            {"shape": shape, "count": count},
        )
    return value


Matrix = Annotated[list[list[FiniteFloat]], BeforeValidator(rows_expected)]
"""A matrix: a list of rows (a flat list is refused with one error naming the shape)."""

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
