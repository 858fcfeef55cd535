"""What an association method is: its name, scopes, options and ``run`` (docs/algorithms.md §3).

A :class:`MethodSpec` is everything the rest of the system knows of a method:
the core parses options with it (:meth:`MethodSpec.parse`), the engine and the
local tracker run it (:attr:`MethodSpec.run` returns an
:class:`~core.association.AssociationResult` that carries the gated pairs it
decided on, :attr:`AssociationResult.gated`), and the wire schema
(``api_schemas.association``) is generated from the registry of specs
(:mod:`core.association.registry`). A new method is one module defining a
``SPEC`` plus one line in the registry.

Options are declared, not parsed by hand: a :class:`NumberOption` (a real in an
interval, ends open or closed) or a :class:`ChoiceOption` (a string among
choices), each with its default; ``exclusive`` groups are options that say the
same thing two ways (give at most one; the group's defaults apply only when
none is given: ``gnn`` with a ``threshold`` has no ``gate_probability``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Generic, Literal, TypeVar

from core.association.options import Options, check_keys, choice, exclusive, number
from core.association.problem import AssociationProblem
from core.association.result import AssociationResult

Scope = Literal["track_to_track", "local"]
"""``track_to_track``: fused tracks with report tracks (the engine, ``/v1/associate``);
``local``: a local tracker's tracks with detections (measurement-to-track)."""
BOTH_SCOPES: frozenset[Scope] = frozenset({"track_to_track", "local"})
LOCAL_ONLY: frozenset[Scope] = frozenset({"local"})

Parsed = TypeVar("Parsed")
MEMO_SIZE = 64
"""Parsed configurations a spec keeps (:meth:`MethodSpec.parse`)."""


@dataclass(frozen=True)
class NumberOption:
    """A real option in the interval (low, high] (ends open or closed as told); ``None``
    default: unset unless given."""

    name: str
    default: float | None
    low: float
    high: float = math.inf
    low_open: bool = True
    high_open: bool = False
    doc: str = ""

    def read(self, method: str, options: Options, defaulted: bool = True) -> float | None:
        """The option's value in ``options`` (its default when absent and ``defaulted``)."""
        return number(
            method,
            options,
            self.name,
            self.default if defaulted else None,
            low=self.low,
            high=self.high,
            low_open=self.low_open,
            high_open=self.high_open,
        )


@dataclass(frozen=True)
class ChoiceOption:
    """A string option among ``choices``; ``pluggable``: a callable is taken as it is (a
    caller's own model, core only)."""

    name: str
    default: str
    choices: tuple[str, ...]
    doc: str = ""
    pluggable: bool = False

    def read(self, method: str, options: Options, defaulted: bool = True) -> object:
        """The option's value in ``options`` (its default when absent: a choice always has one)."""
        value = options.get(self.name, self.default)
        if self.pluggable and callable(value):
            return value
        return choice(method, options, self.name, self.default, self.choices)


OptionSpec = NumberOption | ChoiceOption


@dataclass(frozen=True)
class MethodSpec(Generic[Parsed]):
    """One association method (module docstring).

    Attributes
    ----------
    name : the method's name in configurations and on the wire.
    scopes : where it may be chosen (:data:`Scope`).
    options : its options, in the order they are checked.
    build : the method's parsed options object from the option values (defaults filled);
        it may refuse a combination (:class:`~core.errors.OptionError`).
    run : the method on a problem; its result carries the gated pairs it decided on.
    distance : the track-to-track distance (``mean`` or ``sum``) when the caller names none.
    exclusive : groups of options of which at most one may be given.
    soft : the method weighs every gated detection of a track (a PDA-style update in local
        tracking) instead of assigning one; its ``scores`` are the weights.
    summary : one line for the wire's documentation.
    """

    name: str
    scopes: frozenset[Scope]
    options: tuple[OptionSpec, ...]
    build: Callable[[dict[str, Any]], Parsed]
    run: Callable[[AssociationProblem, Parsed], AssociationResult]
    distance: Literal["mean", "sum"] = "mean"
    exclusive: tuple[tuple[str, ...], ...] = ()
    soft: bool = False
    summary: str = ""

    def __post_init__(self) -> None:
        names = tuple(option.name for option in self.options)
        object.__setattr__(self, "option_names", names)
        object.__setattr__(self, "_memo", {})

    option_names: tuple[str, ...] = field(init=False, repr=False, compare=False)
    """The options' names, in declaration order."""
    _memo: dict[tuple[tuple[str, type, object], ...], Parsed] = field(
        init=False, repr=False, compare=False
    )

    def option(self, name: str) -> OptionSpec:
        """The option called ``name`` (KeyError when the method has none)."""
        for option in self.options:
            if option.name == name:
                return option
        raise KeyError(name)

    def _grouped(self, name: str) -> bool:
        return any(name in group for group in self.exclusive)

    def parse(self, options: Mapping[str, object]) -> Parsed:
        """The method's options object from ``options`` by their names, defaults filled in.

        Parsing is pure and its result immutable: each configuration is parsed once
        (:data:`MEMO_SIZE` of them per method; ``associate`` parses at every call).

        Raises
        ------
        OptionError
            Unknown option, two of an exclusive group, a value out of range or choice.
        """
        try:
            key = tuple(sorted((name, type(value), value) for name, value in options.items()))
            hash(key)
        except TypeError:  # a value that cannot be a key: parse it every time
            return self._parse(options)
        parsed = self._memo.get(key)
        if parsed is None:
            parsed = self._parse(options)
            if len(self._memo) < MEMO_SIZE:
                self._memo[key] = parsed
        return parsed

    def _parse(self, options: Mapping[str, object]) -> Parsed:
        check_keys(self.name, options, self.option_names)
        for group in self.exclusive:
            exclusive(self.name, options, group)
        values: dict[str, Any] = {
            option.name: option.read(self.name, options, not self._grouped(option.name))
            for option in self.options
        }
        values.update(self.group_defaults(values))
        return self.build(values)

    def group_defaults(self, given: Mapping[str, object]) -> dict[str, object]:
        """The defaults of the exclusive groups none of whose options is set in ``given``."""
        filled: dict[str, object] = {}
        for group in self.exclusive:
            if all(given.get(name) is None for name in group):
                for name in group:
                    default = self.option(name).default
                    if default is not None:
                        filled[name] = default
        return filled

    def defaults(self, given: Mapping[str, object]) -> dict[str, object]:
        """The option values a resolved configuration shows: ``given`` with every default the
        method fills in (an exclusive group's only when none of it is given)."""
        filled = dict(given)
        for option in self.options:
            grouped = self._grouped(option.name)
            if option.name not in filled and not grouped and option.default is not None:
                filled[option.name] = option.default
        for name, value in self.group_defaults(given).items():
            filled.setdefault(name, value)
        return filled
