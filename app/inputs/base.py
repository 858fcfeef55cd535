"""What an input kind is: the one small protocol every kind of session input follows.

An input kind (a sensor's track list, its detections, ASTERIX data blocks …)
knows its ``tag`` (its route ``POST …/{tag}``, its WebSocket ``type``, its
log ``type``), its wire models, how many items an input holds (the size that
decides where the work runs), the checks it needs against the session's
config, and how it is applied to the session's engine (conversion to the core
included). :mod:`app.inputs` registers the kinds; routes, the WebSocket, the
log, replay, the CLI and the AsyncAPI file iterate that registry.

A kind whose body is not a JSON report (ASTERIX) decodes into inputs of the
JSON kinds, which are what is applied and logged.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Generic, TypeVar

from api_schemas.base import WireModel
from api_schemas.config import SessionConfig
from api_schemas.examples import Example
from api_schemas.issues import FieldIssue
from app.errors import InvalidFields, StaleReport
from app.outputs.text import dumps
from core.errors import StaleReport as CoreStaleReport
from core.fusion.engine import SessionEngine
from core.fusion.reports import StepResult

ReportT = TypeVar("ReportT", bound=WireModel)
ParametersT = TypeVar("ParametersT", bound=WireModel)
PlainObject = dict[str, Any]


@dataclass(frozen=True)
class Applied:
    """An input applied to an engine: the step's result and the engine's CPU time (thread)."""

    step: StepResult
    engine_cpu_s: float


class InputKind(ABC, Generic[ReportT]):
    """One kind of session input (module docstring). Subclasses set the class attributes."""

    tag: ClassVar[str]
    """Route ``POST /v1/sessions/{sid}/{tag}``, WebSocket message ``type``, log ``type``."""
    report_model: ClassVar[type[WireModel]]
    """The REST body (a JSON kind) and the ``report`` of its logged event."""
    message_model: ClassVar[type[WireModel]]
    """The WebSocket message: the report plus ``type`` and ``ref``."""
    event_model: ClassVar[type[WireModel]]
    """An accepted input as ``GET …/events`` gives it."""
    summary: ClassVar[str]
    """One line for the AsyncAPI file."""
    description: ClassVar[str]
    """What its route does (its OpenAPI description)."""
    examples: ClassVar[dict[str, Example]] = {}
    """Its route's request examples (:mod:`api_schemas.examples`)."""

    # ------------------------------------------------------------ wire
    def parse(self, body: PlainObject) -> ReportT:
        """A plain body validated as this kind's report."""
        report: ReportT = self.report_model.model_validate(body)  # type: ignore[assignment]
        return report

    def of_message(self, message: WireModel) -> ReportT:
        """The report a validated WebSocket message carries (without ``type``, ``ref``)."""
        fields = {name: getattr(message, name) for name in self.report_model.model_fields}
        report: ReportT = self.report_model.model_construct(**fields)  # type: ignore[assignment]
        return report

    def logged(self, report: ReportT) -> PlainObject:
        """The JSON the log keeps for an accepted input."""
        return {"type": self.tag, "report": report.model_dump(mode="json", exclude_none=True)}

    # ------------------------------------------------------------ session
    @abstractmethod
    def sensor(self, report: ReportT) -> str:
        """The sending sensor."""

    @abstractmethod
    def items(self, report: ReportT) -> int:
        """Items of the input (tracks, detections): the size that decides where work runs."""

    @abstractmethod
    def issues(self, report: ReportT, config: SessionConfig) -> list[FieldIssue]:
        """Every problem of the input under the session's config (located in the body)."""

    @abstractmethod
    def run(
        self, engine: SessionEngine, report: ReportT, config: SessionConfig, explain: bool
    ) -> Any:
        """Convert the input for the core, apply it; the engine's result (a ``StepResult``)."""

    def check(self, report: ReportT, config: SessionConfig) -> None:
        """Refuse (:class:`~app.errors.InvalidFields`) an input its session cannot take."""
        issues = self.issues(report, config)
        if issues:
            raise InvalidFields(issues)

    def apply(
        self, engine: SessionEngine, report: ReportT, config: SessionConfig, *, explain: bool
    ) -> Applied:
        """Apply a checked input to ``engine`` (a transaction: a refusal changes nothing)."""
        started = time.thread_time()
        try:
            step = self.run(engine, report, config, explain)
        except CoreStaleReport as stale:
            raise StaleReport(stale.sensor, stale.time, stale.last_time, stale.window) from None
        return Applied(step, time.thread_time() - started)


@dataclass(frozen=True)
class Input:
    """One input of a session: its kind and its validated wire report."""

    kind: InputKind[Any]
    report: Any

    @property
    def sensor(self) -> str:
        """The sending sensor."""
        return self.kind.sensor(self.report)

    @property
    def time(self) -> float | str:
        """Its ``time`` as given (seconds, or an RFC 3339 timestamp)."""
        time: float | str = self.report.time
        return time

    @property
    def items(self) -> int:
        """Tracks or detections in it."""
        return self.kind.items(self.report)

    def check(self, config: SessionConfig) -> None:
        """:meth:`InputKind.check`."""
        self.kind.check(self.report, config)

    def apply(self, engine: SessionEngine, config: SessionConfig, *, explain: bool) -> Applied:
        """:meth:`InputKind.apply`."""
        return self.kind.apply(engine, self.report, config, explain=explain)

    def logged(self) -> PlainObject:
        """:meth:`InputKind.logged`."""
        return self.kind.logged(self.report)


@dataclass(frozen=True)
class Decoded:
    """What a :class:`DecodedKind` made of a body: the inputs to apply, in order, and its
    account of the body (every record and what became of it: the answer's fields but the
    step results)."""

    inputs: tuple[Input, ...]
    account: PlainObject


class DecodedKind(ABC, Generic[ParametersT]):
    """A kind whose body is not a JSON report but bytes (a surveillance format): decoded into
    inputs of the JSON kinds, which are what the session applies and logs.

    ``POST /v1/sessions/{sid}/{tag}`` takes the bytes (``media_type``) with the query
    ``parameters``; a WebSocket ``stream`` takes them as a binary message, with the
    parameters in the connection's query. The answer is ``answer_model``: the account
    and one step result per input applied.
    """

    tag: ClassVar[str]
    media_type: ClassVar[str]
    parameters: ClassVar[type[WireModel]]
    answer_model: ClassVar[type[WireModel]]
    summary: ClassVar[str]
    description: ClassVar[str]

    @abstractmethod
    def decode(self, data: bytes, parameters: ParametersT, session: SessionView) -> Decoded:
        """The inputs ``data`` holds for the session (:class:`~app.errors.ServiceError` for
        data it cannot take: malformed, or not for this session)."""

    def answer(self, decoded: Decoded, results: Sequence[str]) -> str:
        """The answer's JSON text: the account and the step results (JSON texts already)."""
        account = dumps(decoded.account)
        return f'{account[:-1]},"results":[{",".join(results)}]}}'


@dataclass(frozen=True)
class SessionView:
    """What a decoder may read of its session: the config and each sensor's latest time."""

    config: SessionConfig
    last_time: Callable[[str], float | None]
