"""The registry of association methods: every :class:`~core.association.spec.MethodSpec`.

One line per method: the core's entry points (:func:`core.association.associate`,
the local tracker, the fusion engine) and the wire schema
(``api_schemas.association``, generated from :data:`REGISTRY`) read it, nothing
else lists the methods. Adding a method: its module with a ``SPEC``, one line
here.
"""

from __future__ import annotations

from typing import Any

from core.association import cheap_jpda, dang_han, denoeux, gnn, hachour, jpda, mercier
from core.association.spec import MethodSpec, Scope
from core.errors import InvalidInput

REGISTRY: dict[str, MethodSpec[Any]] = {
    spec.name: spec
    for spec in (
        gnn.SPEC,
        denoeux.SPEC,
        hachour.SPEC,
        mercier.SPEC,
        dang_han.SPEC,
        cheap_jpda.SPEC,
        jpda.SPEC,
    )
}
"""Every association method by name, in the order the wire lists them."""


def methods(scope: Scope) -> tuple[str, ...]:
    """The names of the methods that may be chosen in ``scope``, in registry order."""
    return tuple(name for name, spec in REGISTRY.items() if scope in spec.scopes)


def method_spec(name: str, scope: Scope) -> MethodSpec[Any]:
    """The spec of method ``name``, refused by name when unknown or not for ``scope``.

    Raises
    ------
    InvalidInput
        ``name`` names no method of ``scope``.
    """
    spec = REGISTRY.get(name)
    if spec is None or scope not in spec.scopes:
        raise InvalidInput(
            f"unknown association method {name!r}; choose one of {list(methods(scope))}"
        )
    return spec
