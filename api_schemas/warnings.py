"""Warnings: implausible but legal values, and where each sensor stands.

A warning never changes what the service does with a value: it is an
annotation of the answer (the session's creation answer and summary, each
step result), saying where the value is (``pointer``, the JSON pointer of
problem+json's ``errors[].pointer``, into the body that carried it), which
plausibility rule it tripped (``code``) and what looks wrong, in plain words.
The rules and their thresholds are in :mod:`app.plausibility` (README
"Warnings").
"""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from api_schemas.base import FiniteFloat, Identifier, WireModel


class FieldWarning(WireModel):
    """One implausible but legal value (module docstring): accepted and used as given."""

    pointer: str = Field(
        description="JSON pointer (URI fragment) into the body that carried the value: the "
        "session config (POST /v1/sessions) or the input of the step"
    )
    code: str = Field(description="the plausibility rule (README 'Warnings' lists them)")
    message: str = Field(description="what looks wrong and the likely mistake, in plain words")


class SitePlacement(WireModel):
    """Where a configured sensor stands in the session frame (east/north/up with an ``origin``)."""

    sensor: Identifier
    position: Annotated[list[FiniteFloat], Field(min_length=3, max_length=3)] = Field(
        description="x, y, z (m) in the session frame: east, north, up of the origin in a "
        "geodetic session; the origin itself for a sensor without a site"
    )
    distance: FiniteFloat = Field(
        description="straight-line distance from the session frame's origin (m)"
    )
    heading_deg: FiniteFloat


Warnings = Annotated[list[FieldWarning], Field(max_length=64)]
