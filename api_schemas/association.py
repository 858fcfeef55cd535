"""Association methods and their options (docs/algorithms.md §3).

One options model holds every option name the API knows; which ones apply
depends on the method (:data:`METHOD_OPTIONS`). Giving an option that does
not apply to the chosen method is an error, and the resolved configuration
fills in each method's documented defaults (:data:`METHOD_DEFAULTS`).
"""

from __future__ import annotations

from typing import Literal

from api_schemas.base import OpenUnitFloat, PositiveFloat, UnitFloat, WireModel
from api_schemas.issues import FieldIssue, Location, raise_issues
from core.tracking.config import DEFAULT_IMM_DISTANCE

AssociationMethod = Literal["gnn", "denoeux", "hachour", "mercier", "dang_han"]
"""Track-to-track association methods."""

LocalAssociationMethod = Literal["gnn", "denoeux", "hachour", "mercier", "dang_han", "cheap_jpda"]
"""Measurement-to-track association methods (local tracking adds the ``cheap_jpda`` baseline)."""

DistanceKind = Literal["mean", "sum", "modified"]
LikelihoodKind = Literal["density", "relative"]
MaximiseKind = Literal["betp", "plausibility"]
ImmDistanceKind = Literal["closest_model", "combined", "gated_combined"]


class AssociationOptions(WireModel):
    """Every association option; ``null`` means unset or not applicable to the method."""

    threshold: PositiveFloat | None = None
    gate_probability: OpenUnitFloat | None = None
    gamma: PositiveFloat | None = None
    alpha: UnitFloat | None = None
    distance: DistanceKind | None = None
    likelihood: LikelihoodKind | None = None
    maximise: MaximiseKind | None = None
    bias: PositiveFloat | None = None
    imm_distance: ImmDistanceKind | None = None


METHOD_OPTIONS: dict[str, frozenset[str]] = {
    "gnn": frozenset({"threshold", "gate_probability", "distance", "imm_distance"}),
    "denoeux": frozenset({"gamma", "gate_probability", "alpha", "distance", "imm_distance"}),
    "hachour": frozenset({"likelihood", "maximise", "distance", "imm_distance"}),
    "mercier": frozenset({"alpha", "distance", "imm_distance"}),
    "dang_han": frozenset({"alpha", "distance", "imm_distance"}),
    "cheap_jpda": frozenset({"bias", "gate_probability", "imm_distance"}),
}
"""The options each method accepts."""

EXCLUSIVE_OPTIONS: dict[str, tuple[str, str]] = {
    "gnn": ("threshold", "gate_probability"),
    "denoeux": ("gamma", "gate_probability"),
}
"""Pairs of options that say the same thing two ways: give one, not both."""

METHOD_DEFAULTS: dict[str, dict[str, object]] = {
    "gnn": {"gate_probability": 0.999, "distance": "mean"},
    "denoeux": {"gate_probability": 0.999, "alpha": 1.0, "distance": "sum"},
    "hachour": {"likelihood": "density", "maximise": "betp", "distance": "mean"},
    "mercier": {"alpha": 0.9, "distance": "mean"},
    "dang_han": {"alpha": 0.9, "distance": "mean"},
    "cheap_jpda": {"gate_probability": 0.999},
}
"""Defaults filled into a resolved configuration (docs/algorithms.md §3, §3.7).

A default that is one of an exclusive pair is filled only when its partner
is unset (``gnn`` with a ``threshold`` gets no ``gate_probability``).
"""

LOCAL_ONLY_OPTIONS = frozenset({"imm_distance"})
"""Options that only make sense for measurement-to-track association."""

LOCAL_ONLY_DISTANCES = frozenset({"modified"})
"""Distances that need a local tracker's steady-state covariance ([HZ] §4.1)."""


def resolve_options(
    method: str, options: AssociationOptions, *, local: bool, loc: Location = ()
) -> AssociationOptions:
    """Check ``options`` against ``method`` and return them with the defaults filled in."""
    given = options.model_dump(exclude_none=True)
    allowed = METHOD_OPTIONS[method] if local else METHOD_OPTIONS[method] - LOCAL_ONLY_OPTIONS
    issues = [
        FieldIssue(
            (*loc, "options", name),
            f"option {name!r} does not apply to method {method!r} (accepted: {', '.join(sorted(allowed))})",
            value,
        )
        for name, value in given.items()
        if name not in allowed
    ]
    distance = given.get("distance")
    if not local and distance in LOCAL_ONLY_DISTANCES:
        issues.append(
            FieldIssue(
                (*loc, "options", "distance"),
                f"distance {distance!r} is for measurement-to-track association only "
                f"(track-to-track: mean or sum)",
                distance,
            )
        )
    pair = EXCLUSIVE_OPTIONS.get(method)
    if pair is not None and all(name in given for name in pair):
        issues.append(
            FieldIssue(
                (*loc, "options", pair[0]),
                f"give {pair[0]!r} or {pair[1]!r}, not both",
                given[pair[0]],
            )
        )
    if issues:
        raise_issues("AssociationOptions", issues)
    filled = dict(given)
    for name, value in METHOD_DEFAULTS[method].items():
        if name not in allowed or name in filled:
            continue
        if pair is not None and name in pair and any(other in filled for other in pair):
            continue
        filled[name] = value
    if local and "imm_distance" in allowed:
        filled.setdefault("imm_distance", DEFAULT_IMM_DISTANCE)
    return AssociationOptions.model_validate(filled)
