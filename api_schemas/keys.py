"""Which keys an object of a wire model allows, found from the model and an error's location.

An ``extra_forbidden`` error says which key is unknown; :func:`allowed_keys`
walks the model from the body's type along the error's location (object
keys, list indices, dict values, the tag of a discriminated union) to the
model that refused it, so the answer can list the keys it allows.
"""

from __future__ import annotations

import types
from collections.abc import Sequence
from typing import Annotated, Any, Literal, Union, get_args, get_origin

from pydantic import BaseModel, Tag


def _strip(annotation: Any) -> Any:
    while get_origin(annotation) is Annotated:
        annotation = get_args(annotation)[0]
    return annotation


def _tag_names(annotation: Any) -> dict[str, Any]:
    """The ``Tag`` names of a callable-discriminated union's members (``Annotated[M, Tag(n)]``)."""
    annotation = _strip(annotation)
    names: dict[str, Any] = {}
    if get_origin(annotation) in (Union, types.UnionType):
        for member in get_args(annotation):
            if get_origin(member) is Annotated:
                for extra in get_args(member)[1:]:
                    if isinstance(extra, Tag):
                        names[extra.tag] = _strip(member)
            names.update(_tag_names(member))
    return names


def _members(annotation: Any) -> list[Any]:
    annotation = _strip(annotation)
    if get_origin(annotation) in (Union, types.UnionType):
        return [
            flat
            for member in get_args(annotation)
            if member is not type(None)
            for flat in _members(member)
        ]
    return [annotation]


def _is_model(annotation: Any) -> bool:
    return isinstance(annotation, type) and issubclass(annotation, BaseModel)


def _tags(model: type[BaseModel]) -> set[object]:
    """The literal values of the model's fields (a discriminated union names a member by one)."""
    values: set[object] = set()
    for field in model.model_fields.values():
        annotation = _strip(field.annotation)
        if get_origin(annotation) is Literal:
            values.update(get_args(annotation))
    return values


def _tagged_member(current: Any, models: list[Any], part: str) -> Any | None:
    """The member of a union of models that ``part`` tags (a ``kind`` literal or a ``Tag``)."""
    if len(models) < 2:
        return None
    named = _tag_names(current).get(part)
    if named is not None:
        return named
    return next((model for model in models if part in _tags(model)), None)


def body_path(root: Any, loc: Sequence[str | int]) -> list[str | int]:
    """An error's location (relative to a body of type ``root``, after an optional ``body``
    or ``query`` prefix) without the tags pydantic puts in it for a discriminated union: the
    path of the value in the body as sent (``sensors/0/fov/range``, not ``…/fov/sector/…``)."""
    prefix = list(loc[:1]) if loc and loc[0] in ("body", "query") else []
    current: Any = root
    kept: list[str | int] = list(prefix)
    for part in loc[len(prefix) :]:
        members = _members(current)
        models = [member for member in members if _is_model(member)]
        if isinstance(part, str) and models:
            tagged = _tagged_member(current, models, part)
            if tagged is not None:
                current = tagged
                continue
            owner = next((model for model in models if part in model.model_fields), None)
            current = None if owner is None else owner.model_fields[part].annotation
        else:
            containers = [member for member in members if get_origin(member) in (list, dict)]
            container = containers[0] if containers else None
            if container is not None and get_origin(container) is list and isinstance(part, int):
                current = get_args(container)[0]
            elif container is not None and get_origin(container) is dict:
                current = get_args(container)[1]
            else:
                current = None
        kept.append(part)
    return kept


def allowed_keys(root: Any, path: Sequence[str | int]) -> list[str] | None:
    """The keys the object at ``path`` (relative to a body of type ``root``) allows, if known."""
    current: Any = root
    for part in path:
        members = _members(current)
        models = [member for member in members if _is_model(member)]
        if isinstance(part, str) and models:
            tagged = _tagged_member(current, models, part)
            if tagged is not None:
                current = tagged  # a union's tag in the location: stay on that member
                continue
            owner = next((model for model in models if part in model.model_fields), None)
            if owner is None:
                return None
            current = owner.model_fields[part].annotation
            continue
        containers = [member for member in members if get_origin(member) in (list, dict)]
        if not containers:
            return None
        container = containers[0]
        if get_origin(container) is list and isinstance(part, int):
            current = get_args(container)[0]
        elif get_origin(container) is dict and isinstance(part, str):
            current = get_args(container)[1]
        else:
            return None
    models = [member for member in _members(current) if _is_model(member)]
    if len(models) != 1:
        return None
    return sorted(models[0].model_fields)
