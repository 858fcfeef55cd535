"""Validation problems located at a field path.

A check that looks at several fields at once (a sensor's noise matrix against
the state layout, a report against the session config) still reports the
exact field at fault: it collects :class:`FieldIssue` objects and raises them
as one pydantic ``ValidationError`` whose locations nest under the model
being validated.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import NoReturn

from pydantic import ValidationError
from pydantic_core import InitErrorDetails, PydanticCustomError

Location = tuple[str | int, ...]

CORE_FIELDS: dict[str, Location] = {
    "class_mass": ("classification", "mass"),
    "class_likelihoods": ("classification", "likelihoods"),
}
"""Fields of a core track (``core.fusion.reports.ReportedTrack``) and where they are on the wire."""
DETECTION_ARRAYS = {
    "measurements": "z",
    "measurement_covariances": "r",
    "covariances": "r",
    "class_masses": "classification",
}
"""Arrays of a core detection report (a row per detection) and the wire field of a detection
that holds the row."""


@dataclass(frozen=True)
class FieldIssue:
    """One problem: where (a path of keys and indices), what, and the offending value."""

    loc: Location
    message: str
    value: object = None
    kind: str = "value_error"


def wire_location(loc: Location) -> Location:
    """Where a value the core refused (``InvalidInput.loc``) is in the request body.

    The core names its own inputs (``("tracks", 3, "class_likelihoods")``,
    ``("measurements", 2)``); the wire nests class evidence under
    ``classification`` and gives each detection its ``z`` and ``r``.
    """
    if loc and isinstance(loc[0], str) and loc[0] in DETECTION_ARRAYS:
        if len(loc) == 1:
            return ("detections",)
        # a row of the array, then its component (a covariance check adds "covariance")
        inner = [part for part in loc[2:] if part != "covariance"]
        return ("detections", loc[1], DETECTION_ARRAYS[loc[0]], *inner)
    located: list[str | int] = []
    for part in loc:
        located.extend(CORE_FIELDS.get(part, (part,)) if isinstance(part, str) else (part,))
    return tuple(located)


def raise_issues(title: str, issues: Sequence[FieldIssue]) -> NoReturn:
    """Raise ``issues`` as a pydantic ``ValidationError`` (locations relative to the model)."""
    details = [
        InitErrorDetails(
            type=PydanticCustomError(issue.kind, "{message}", {"message": issue.message}),
            loc=issue.loc,
            input=issue.value,
        )
        for issue in issues
    ]
    raise ValidationError.from_exception_data(title, details)
