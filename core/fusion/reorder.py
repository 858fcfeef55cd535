"""The central tracker's scans in time order, whatever order they arrive in (docs/algorithms.md §8.9).

Sensors whose reports interleave — radars that stamp a plot when they see it and send it
when their sector is done, links of different latency, network jitter — deliver scans a
little older than the central tracker's latest. :class:`ReorderBuffer` keeps the scans of
the last :data:`REORDER_WINDOW` seconds of tracker time, each with the tracker's state
before it (:meth:`~core.tracking.tracker.LocalTracker.checkpoint`: references, no copy).
A scan older than the tracker's latest but within the window is put in its place: the
tracker goes back to the state before the first buffered scan later than it, takes it, and
takes the later scans again (**retrodiction by re-processing**). The tracker's state is
then exactly what the scans in time order would have given (ties: in the order they
arrived), so the result does not depend on how the sensors' reports interleaved within the
window. A scan older than the window is refused (:class:`~core.errors.StaleReport`, 409).

Deterministic: the same scans in the same order give the same buffer and tracker. The
buffer exports with the tracker: the tracker's state before the oldest buffered scan, and
the buffered scans (:meth:`ReorderBuffer.export`); :meth:`ReorderBuffer.restore` re-runs
them, which gives the tracker's state bit for bit (the tracker's restore is exact).
"""

from __future__ import annotations

import bisect
import copy
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from core.belief import MassFunction
from core.errors import InvalidInput, StaleReport
from core.models.measurement import MeasurementModel
from core.tracking.track import TrackerStep, float_array, mass_to_plain, plain_floats
from core.tracking.tracker import LocalTracker

REORDER_WINDOW = 5.0
"""Seconds of tracker time a scan may lag the central tracker's latest and still be put in
its place (the ASTERIX sample recording's radars lag each other by about 1.5 s; a scan
of a rotating radar can lag by up to its antenna period). An older scan is refused: the
buffer, and the re-processing a late scan costs, stay bounded."""


@dataclass(frozen=True, eq=False)
class BufferedScan:
    """One scan as the tracker took it, and the tracker's state before it."""

    time: float
    sensor: str
    measurements: np.ndarray
    covariances: np.ndarray | None
    range_rates: np.ndarray | None
    class_masses: tuple[MassFunction | None, ...] | None
    before: dict[str, Any]
    model: MeasurementModel | None = None

    def run(self, tracker: LocalTracker) -> tuple[BufferedScan, TrackerStep]:
        """This scan through ``tracker`` from its current state; the scan with that state."""
        before = tracker.checkpoint()
        step = tracker.step(
            self.time,
            self.measurements,
            self.covariances,
            sensor=self.sensor,
            range_rates=self.range_rates,
            class_masses=self.class_masses,
            model=self.model,
        )
        return _with_before(self, before), step

    def to_plain(self) -> dict[str, Any]:
        return {
            "time": self.time,
            "sensor": self.sensor,
            "measurements": plain_floats(self.measurements),
            "covariances": None if self.covariances is None else plain_floats(self.covariances),
            "range_rates": None if self.range_rates is None else plain_floats(self.range_rates),
            "class_masses": None
            if self.class_masses is None
            else [None if mass is None else mass_to_plain(mass) for mass in self.class_masses],
        }


def _with_before(scan: BufferedScan, before: dict[str, Any]) -> BufferedScan:
    return BufferedScan(
        scan.time,
        scan.sensor,
        scan.measurements,
        scan.covariances,
        scan.range_rates,
        scan.class_masses,
        before,
        scan.model,
    )


class ReorderBuffer:
    """The scans of the last :data:`REORDER_WINDOW` seconds of one central tracker (module
    docstring). ``scans`` is replaced, never changed in place: a caller's transaction keeps
    the reference and puts it back."""

    def __init__(self, window: float = REORDER_WINDOW) -> None:
        self.window = window
        self.scans: tuple[BufferedScan, ...] = ()

    def step(
        self,
        tracker: LocalTracker,
        time: float,
        sensor: str,
        measurements: Any,
        covariances: Any | None = None,
        range_rates: Any | None = None,
        class_masses: Sequence[MassFunction | None] | None = None,
        model: MeasurementModel | None = None,
    ) -> TrackerStep:
        """``sensor``'s scan at ``time`` through ``tracker``, in its place in time order
        (``model``: the one its detections were measured by, the report's).

        Raises
        ------
        StaleReport
            The scan is older than the tracker's latest by more than the window, or the
            buffer has a scan of ``sensor`` at that time already.
        """
        latest = tracker.time
        if latest is not None and time < latest - self.window:
            raise StaleReport(sensor, time, latest, window=self.window)
        if any(scan.sensor == sensor and scan.time == time for scan in self.scans):
            raise StaleReport(sensor, time, time)
        scan = BufferedScan(
            float(time),
            sensor,
            np.asarray(measurements, dtype=np.float64),
            None if covariances is None else np.asarray(covariances, dtype=np.float64),
            None if range_rates is None else np.asarray(range_rates, dtype=np.float64),
            None if class_masses is None else tuple(class_masses),
            {},
            model,
        )
        # after every buffered scan of its time or earlier: the order of arrival breaks ties
        at = bisect.bisect_right([buffered.time for buffered in self.scans], scan.time)
        later = self.scans[at:]
        if later:
            tracker.rollback(later[0].before)
        done = []
        step: TrackerStep | None = None
        for pending in (scan, *later):
            ran, step = pending.run(tracker)
            done.append(ran)
        assert step is not None and tracker.time is not None
        kept = (*self.scans[:at], *done)
        oldest = tracker.time - self.window
        self.scans = tuple(buffered for buffered in kept if buffered.time >= oldest)
        return step

    # ------------------------------------------------------- persistence
    def export(self, tracker: LocalTracker) -> dict[str, Any]:
        """The tracker's state before the oldest buffered scan, and the buffered scans."""
        base = tracker
        if self.scans:
            base = copy.copy(tracker)
            base.rollback(self.scans[0].before)
        return {"tracker": base.export(), "scans": [scan.to_plain() for scan in self.scans]}

    @classmethod
    def restore(
        cls,
        tracker: LocalTracker,
        plain: dict[str, Any],
        models: Mapping[str, MeasurementModel | None] | None = None,
        window: float = REORDER_WINDOW,
    ) -> ReorderBuffer:
        """Re-run the exported scans through ``tracker`` (restored from ``plain["tracker"]``),
        each measured by its sensor's model of ``models`` (the session's, by sensor id: a
        scan exports its measurements, not its model)."""
        buffer = cls(window)
        frame = None if tracker.classifier is None else tracker.classifier.frame
        done = []
        for entry in plain["scans"]:
            masses = entry["class_masses"]
            if masses is not None and frame is None:
                raise InvalidInput("exported central scan has class evidence, the tracker none")
            scan = BufferedScan(
                float(entry["time"]),
                str(entry["sensor"]),
                float_array(entry["measurements"]),
                None if entry["covariances"] is None else float_array(entry["covariances"]),
                None if entry["range_rates"] is None else float_array(entry["range_rates"]),
                None
                if masses is None
                else tuple(
                    None
                    if mass is None
                    else MassFunction(
                        frame,  # type: ignore[arg-type]
                        np.array(mass["masks"], dtype=np.int64),
                        np.array(mass["masses"], dtype=np.float64),
                    )
                    for mass in masses
                ),
                {},
                None if models is None else models.get(str(entry["sensor"])),
            )
            ran, _ = scan.run(tracker)
            done.append(ran)
        buffer.scans = tuple(done)
        return buffer
