"""The one exception tree of ``core``.

Every error the core raises on purpose derives from :class:`CredalError`.
Errors caused by the caller's input also derive from :class:`InvalidInput`
(and from :class:`ValueError`), so a service can map them to a 4xx answer and
everything else to a 5xx.
"""

from __future__ import annotations


class CredalError(Exception):
    """Base class of every error raised on purpose by ``core``."""


Location = tuple[str | int, ...]
"""Where in the caller's input a refused value is: ``("tracks", 3, "covariance")``."""


class InvalidInput(CredalError, ValueError):  # noqa: N818 - reads better as a category
    """The caller's input is invalid; the message names the field and the problem.

    ``loc`` locates the refused value in the caller's input when the core knows
    it (``("tracks", 3, "covariance")``), ``()`` otherwise; a service maps it to
    a field pointer.
    """

    def __init__(self, message: str, *, loc: Location = ()) -> None:
        super().__init__(message)
        self.loc = loc


class FrameError(InvalidInput):
    """A frame of discernment is invalid, or a label / subset is outside it."""


class MassError(InvalidInput):
    """A mass function is invalid (negative, non-finite, or not summing to 1)."""


class CovarianceError(InvalidInput):
    """A covariance matrix is not symmetric positive definite (or has the wrong shape)."""


class OptionError(InvalidInput):
    """A method option is unknown, missing, or out of its range; the message names it."""


class TotalConflict(CredalError):  # noqa: N818 - the name of the state in the papers
    """Dempster's rule is undefined: the conflict m(∅) is 1.

    Attributes
    ----------
    conflict : float
        The conflict mass that made normalisation impossible.
    """

    def __init__(self, conflict: float, message: str | None = None) -> None:
        self.conflict = conflict
        super().__init__(message or f"total conflict: m(∅) = {conflict!r}, normalisation undefined")


class StaleReport(CredalError):  # noqa: N818 - a state of the input, named as the API says
    """A report is not newer than the sensor's previous one (docs/algorithms.md §6.4).

    Attributes
    ----------
    sensor : str
    time : float
        The refused report's time.
    last_time : float
        The time of the sensor's previous accepted report (with ``window``: of the central
        tracker's latest scan).
    window : float or None
        The central tracker's reorder window the report is older than (§8.9), or None.
    """

    loc: Location = ("time",)
    """The refused field: the report's time."""

    def __init__(
        self, sensor: str, time: float, last_time: float, window: float | None = None
    ) -> None:
        self.sensor = sensor
        self.time = time
        self.last_time = last_time
        self.window = window
        super().__init__(stale_message(sensor, time, last_time, window))


def stale_message(sensor: str, time: float, last_time: float, window: float | None) -> str:
    """Why a report is stale: not newer than its sensor's previous report, or (``window``)
    older than the central tracker's latest scan by more than its reorder window (§8.9)."""
    if window is None:
        return (
            f"report of sensor {sensor!r} at time {time!r} is not newer than its previous "
            f"report at time {last_time!r}"
        )
    return (
        f"report of sensor {sensor!r} at time {time!r} is older than the central tracker's "
        f"latest scan at time {last_time!r} by more than its reorder window of {window:g} s"
    )


class ModelConfigError(InvalidInput):
    """A motion / measurement model or a model bank configuration is invalid."""


class TrackingError(InvalidInput):
    """Arrays handed to the tracker have the wrong shape or are not finite."""


class ClassificationError(InvalidInput):
    """A classifier option or its inputs (behaviours, relation, evidence) are invalid."""


class ScenarioError(InvalidInput):
    """A scenario generator was asked for something it cannot simulate."""
