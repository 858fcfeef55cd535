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


@dataclass(frozen=True)
class FieldIssue:
    """One problem: where (a path of keys and indices), what, and the offending value."""

    loc: Location
    message: str
    value: object = None
    kind: str = "value_error"


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
