"""What an output format is, and the output an answer is written in (a format and a frame).

An :class:`OutputFormat` writes a step result, a picture of fused tracks,
and a plain JSON step result (one forwarded by another instance) as text of
its media type; its ``step_model``/``picture_model`` document the shape
(``api_schemas.results``) and are what ``openapi.json`` lists under its media
type. An :class:`Output` is one format in one frame: the session frame, or
with geodetic positions (``frame=geodetic``, or a format that ``needs_geodetic``).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from api_schemas.base import WireModel
from api_schemas.warnings import FieldWarning
from app.geo.geojson import GeodeticOutput
from core.fusion.reports import FusedTrackView
from core.fusion.reports import StepResult as CoreStepResult

PlainObject = dict[str, Any]


class OutputFormat(ABC):
    """One output format (module docstring). Subclasses set the class attributes."""

    name: ClassVar[str]
    """The ``format`` query value."""
    media_type: ClassVar[str]
    step_model: ClassVar[type[WireModel]]
    picture_model: ClassVar[type[WireModel]]
    needs_geodetic: ClassVar[bool]
    """Whether it is always geodetic (then the session needs an ``origin``)."""
    description: ClassVar[str]

    @abstractmethod
    def step(
        self,
        step: CoreStepResult,
        seq: int,
        geodetic: GeodeticOutput | None,
        warnings: Sequence[FieldWarning] = (),
    ) -> str:
        """A step result numbered ``seq``, with its input's ``warnings``
        (:mod:`app.plausibility`)."""

    @abstractmethod
    def picture(
        self,
        seq: int,
        time: float | None,
        views: Sequence[FusedTrackView],
        geodetic: GeodeticOutput | None,
    ) -> str:
        """The fused tracks ``views`` at ``time``, after input ``seq``."""

    @abstractmethod
    def from_plain(self, result: PlainObject, geodetic: GeodeticOutput | None) -> str:
        """A step result given as the plain data of its JSON text (session frame)."""


@dataclass(frozen=True)
class Output:
    """What an answer is written as: a format, in the session frame or with geodetic positions."""

    format: OutputFormat
    geodetic: GeodeticOutput | None = None

    @property
    def media_type(self) -> str:
        """The answer's media type."""
        return self.format.media_type

    @property
    def name(self) -> str:
        """The same in every process: the format's name, ``/geodetic`` with geodetic positions."""
        return self.format.name + ("/geodetic" if self.geodetic is not None else "")

    def step(self, step: CoreStepResult, seq: int, warnings: Sequence[FieldWarning] = ()) -> str:
        """:meth:`OutputFormat.step`."""
        return self.format.step(step, seq, self.geodetic, warnings)

    def picture(self, seq: int, time: float | None, views: Sequence[FusedTrackView]) -> str:
        """:meth:`OutputFormat.picture`."""
        return self.format.picture(seq, time, views, self.geodetic)

    def from_plain(self, result: PlainObject) -> str:
        """:meth:`OutputFormat.from_plain`."""
        return self.format.from_plain(result, self.geodetic)
