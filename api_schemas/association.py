"""Association methods and their options, generated from the core's registry (docs/algorithms.md §3).

Nothing here lists a method or an option: the method enums, the options model
and its ranges, which options apply to which method, the exclusive pairs and
the defaults a resolved configuration shows all come from the core's
:data:`core.association.REGISTRY` (one :class:`~core.association.MethodSpec`
per method). One options model holds every option name the methods know, each
typed by the loosest range any method gives it; giving an option that does not
apply to the chosen method, or a value out of that method's own range, is an
error naming the option, and the resolved configuration fills in the method's
defaults. ``distance`` and ``imm_distance`` are the wire's own (the engine's
distance argument and the local tracker's IMM distance), not method options.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import Field, create_model

from api_schemas.base import WireModel
from api_schemas.issues import FieldIssue, Location, raise_issues
from core.association import REGISTRY, MethodSpec, methods
from core.association.spec import ChoiceOption, NumberOption, OptionSpec
from core.errors import OptionError
from core.tracking.config import DEFAULT_IMM_DISTANCE

TRACK_TO_TRACK_METHODS = methods("track_to_track")
LOCAL_METHODS = methods("local")

if TYPE_CHECKING:
    AssociationMethod = str
    LocalAssociationMethod = str
    AnyAssociationMethod = str
else:
    AssociationMethod = Literal[TRACK_TO_TRACK_METHODS]
    LocalAssociationMethod = Literal[LOCAL_METHODS]
    AnyAssociationMethod = Literal[tuple(REGISTRY)]
"""Track-to-track methods; measurement-to-track methods of local tracking; every method."""

DistanceKind = Literal["mean", "sum", "modified"]
ImmDistanceKind = Literal["closest_model", "combined", "gated_combined"]

WIRE_OPTIONS = ("distance", "imm_distance")
"""Options of the wire that are not method options (module docstring)."""
LOCAL_ONLY_OPTIONS = frozenset({"imm_distance"})
"""Options that only make sense for measurement-to-track association."""
LOCAL_ONLY_DISTANCES = frozenset({"modified"})
"""Distances that need a local tracker's steady-state covariance ([HZ] §4.1)."""


def _declared() -> dict[str, list[tuple[str, OptionSpec]]]:
    """Every option name, in registry order, with the (method, declaration) pairs of it."""
    found: dict[str, list[tuple[str, OptionSpec]]] = {}
    for spec in REGISTRY.values():
        for option in spec.options:
            found.setdefault(option.name, []).append((spec.name, option))
    return found


def _wire_type(declarations: list[tuple[str, OptionSpec]]) -> Any:
    """The loosest type of an option over the methods that declare it."""
    numbers = [option for _, option in declarations if isinstance(option, NumberOption)]
    choices = [option for _, option in declarations if isinstance(option, ChoiceOption)]
    if numbers and choices:
        raise TypeError(
            f"option {numbers[0].name!r} is a number for one method, a choice for another"
        )
    if choices:
        values = tuple(dict.fromkeys(value for option in choices for value in option.choices))
        return Literal[values]
    low = min(option.low for option in numbers)
    high = max(option.high for option in numbers)
    constraints: dict[str, float] = {
        ("gt" if all(o.low_open for o in numbers if o.low == low) else "ge"): low
    }
    if math.isfinite(high):
        constraints["lt" if all(o.high_open for o in numbers if o.high == high) else "le"] = high
    return Annotated[float, Field(allow_inf_nan=False, **constraints)]  # type: ignore[call-overload]


def _description(declarations: list[tuple[str, OptionSpec]]) -> str:
    """Each method's own words for the option: ``doc (method, method); doc (method)``."""
    users: dict[str, list[str]] = {}
    for method, option in declarations:
        users.setdefault(option.doc, []).append(method)
    return "; ".join(f"{doc} ({', '.join(methods)})" for doc, methods in users.items())


class WireOptions(WireModel):
    """What the code reads of :data:`AssociationOptions` by name: the wire's own options
    (:data:`WIRE_OPTIONS`); the method options are read by ``model_dump``."""

    distance: DistanceKind | None = None
    imm_distance: ImmDistanceKind | None = None


_OPTION_FIELDS: dict[str, Any] = {
    name: (
        _wire_type(declarations) | None,
        Field(default=None, description=_description(declarations)),
    )
    for name, declarations in _declared().items()
}
_OPTION_FIELDS["distance"] = (
    DistanceKind | None,
    Field(default=None, description="track-to-track covariance (default: the method's)"),
)
_OPTION_FIELDS["imm_distance"] = (
    ImmDistanceKind | None,
    Field(default=None, description="local tracking: the IMM distance the gate uses"),
)

if TYPE_CHECKING:
    AssociationOptions = WireOptions
else:
    AssociationOptions = create_model(
        "AssociationOptions",
        __base__=WireModel,
        __doc__="Every association option; ``null`` means unset or not applicable to the method.",
        __module__=__name__,
        **_OPTION_FIELDS,
    )


def allowed_options(spec: MethodSpec[Any], *, local: bool) -> frozenset[str]:
    """The options a method accepts on the wire: its own, the distance (not for a soft
    method: it weighs likelihoods), the IMM distance in local tracking."""
    wire = {"distance"} if not spec.soft else set()
    if local:
        wire |= LOCAL_ONLY_OPTIONS
    return frozenset(spec.option_names) | wire


def _value_issue(spec: MethodSpec[Any], name: str, value: object) -> str | None:
    """Why ``value`` is out of the method's own range or choices for option ``name``."""
    option = spec.option(name)
    try:
        option.read(spec.name, {name: value})
    except OptionError as error:
        return str(error)
    return None


def resolve_options(
    method: str, options: AssociationOptions, *, local: bool, loc: Location = ()
) -> AssociationOptions:
    """Check ``options`` against ``method`` and return them with the defaults filled in."""
    spec = REGISTRY[method]
    given = options.model_dump(exclude_none=True)
    allowed = allowed_options(spec, local=local)
    issues = [
        FieldIssue(
            (*loc, "options", name),
            f"option {name!r} does not apply to method {method!r} (accepted: {', '.join(sorted(allowed))})",
            value,
        )
        for name, value in given.items()
        if name not in allowed
    ]
    issues += [
        FieldIssue((*loc, "options", name), problem, value)
        for name, value in given.items()
        if name in spec.option_names and (problem := _value_issue(spec, name, value)) is not None
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
    for group in spec.exclusive:
        both = [name for name in group if name in given]
        if len(both) > 1:
            issues.append(
                FieldIssue(
                    (*loc, "options", both[0]),
                    f"give {both[0]!r} or {both[1]!r}, not both",
                    given[both[0]],
                )
            )
    if not issues:
        try:  # what the method itself refuses of a combination (mercier: scale vs gate)
            spec.parse({name: value for name, value in given.items() if name not in WIRE_OPTIONS})
        except OptionError as error:
            issues.append(FieldIssue((*loc, "options"), str(error), given))
    if issues:
        raise_issues("AssociationOptions", issues)
    filled = spec.defaults({name: given[name] for name in given if name not in WIRE_OPTIONS})
    filled.update({name: given[name] for name in WIRE_OPTIONS if name in given})
    if "distance" in allowed:
        filled.setdefault("distance", spec.distance)
    if local:
        filled.setdefault("imm_distance", DEFAULT_IMM_DISTANCE)
    return AssociationOptions.model_validate(filled)
