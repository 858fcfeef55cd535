"""The output formats, in one registry (:class:`~app.outputs.base.OutputFormat`).

Step results (REST and the WebSocket ``stream``), the ``subscribe`` stream
and ``GET …/tracks`` are written by the :class:`~app.outputs.base.Output` that
:func:`output_for` chooses from the ``format`` and ``frame`` asked, in this one
place; ``openapi.json`` lists each format's media type and models. Adding a
format is one module and one :func:`register_output_format` call below.
"""

from __future__ import annotations

from api_schemas.issues import FieldIssue
from app.errors import InvalidFields
from app.geo.geojson import GeodeticOutput
from app.outputs.base import Output, OutputFormat
from app.outputs.geojson import GeoJsonFormat
from app.outputs.json_results import JsonFormat

OUTPUT_FORMATS: dict[str, OutputFormat] = {}
"""Name → output format, in registration order (the first is the default)."""
FRAMES = ("session", "geodetic")
"""``frame``: positions in the session frame, or with each track's geodetic position too."""


def register_output_format(output_format: OutputFormat) -> None:
    """Add ``output_format`` to the registry (its name must be new)."""
    if output_format.name in OUTPUT_FORMATS:
        raise ValueError(f"output format {output_format.name!r} is registered already")
    OUTPUT_FORMATS[output_format.name] = output_format


def output_for(
    geodetic: GeodeticOutput | None, format: str = "json", frame: str = "session"
) -> Output:
    """The output of the ``format`` and ``frame`` asked of a session whose geodetic output is
    ``geodetic`` (``None``: it has no origin); a 422 at ``query/format`` or ``query/frame``
    for an unknown value, or a geodetic output the session cannot give."""
    chosen = OUTPUT_FORMATS.get(format)
    if chosen is None:
        raise InvalidFields(
            [FieldIssue(("format",), f"format is one of {list(OUTPUT_FORMATS)}", format)],
            prefix="query",
        )
    if frame not in FRAMES:
        raise InvalidFields(
            [FieldIssue(("frame",), f"frame is one of {list(FRAMES)}", frame)], prefix="query"
        )
    wanted = chosen.needs_geodetic or frame == "geodetic"
    if not wanted:
        return Output(chosen)
    if geodetic is None:
        parameter = "format" if chosen.needs_geodetic else "frame"
        raise InvalidFields(
            [FieldIssue((parameter,), "the session has no origin: geodetic output needs one")],
            prefix="query",
        )
    return Output(chosen, geodetic)


register_output_format(JsonFormat())
register_output_format(GeoJsonFormat())

JSON = Output(OUTPUT_FORMATS["json"])
"""The default output: the contract's JSON in the session frame (what the log's readers,
Redis fan-out and replay use)."""

__all__ = ["FRAMES", "JSON", "OUTPUT_FORMATS", "Output", "OutputFormat", "output_for"]
