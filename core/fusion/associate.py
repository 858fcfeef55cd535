"""Track-to-track association of one report with the live fused tracks
(docs/algorithms.md §6.3, §3, §3.6).

Continuity first: a report track the sensor keeps reporting under the id it
gave a live fused track stays with it while it passes a loose χ² gate; then
the session's method (:mod:`core.association`) on what is left, with class
information when the report carries it. The engine's step
(:class:`core.fusion.engine.SessionEngine`) records the pairs, starts tracks
from the new columns and counts the missed rows.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray, IntArray
from core.association import ScoreMatrix, associate
from core.belief import MassFunction
from core.distance import Estimates, chi2_quantile
from core.errors import TotalConflict
from core.fusion.classes import ClassAssessment, accumulate_likelihoods
from core.fusion.config import FusionConfig
from core.fusion.reports import TrackReport
from core.fusion.track import FusedTrack
from core.pipeline.gate import mahalanobis

Classify = Callable[[FusedTrack], ClassAssessment | None]
"""A fused track's class assessment (the engine's class fusion), for §3.6."""

CONTINUITY_GATE_PROBABILITY = 1.0 - 1e-9
"""Gate of track continuity: a sensor's own track id is strong evidence, so the
gate only catches a sensor that reuses an id for another object (not the
1-in-1000 noise excursion a 0.999 gate rejects at every thousandth report)."""


@dataclass(frozen=True)
class Decision:
    """One step's association by row (live fused track) and column (report track) index.

    ``pairs`` holds (row, col, score, basis): basis ``"continuity"`` (the sensor
    kept its track id; no method score) or ``"association"`` (the method's
    score). ``scores`` is the method's (sparse) matrix over ``matrix_rows ×
    matrix_cols``, made dense only when a step is explained; ``None`` when
    one side was empty after continuity and the method did not run.
    """

    method: str
    pairs: list[tuple[int, int, float | None, str]]
    new: list[int]
    missed: list[int]
    matrix_rows: IntArray
    matrix_cols: IntArray
    scores: ScoreMatrix | None


def associate_report(
    config: FusionConfig,
    live: list[FusedTrack],
    states: FloatArray,
    covariances: FloatArray,
    report: TrackReport,
    incoming: Estimates,
    classify: Classify,
) -> Decision:
    """The report's tracks with the live fused tracks (``states``, ``covariances``: fused
    and predicted to the report time): continuity first (when on), then the session's
    method on what is left (the decision's rows index ``live``)."""
    incoming_states, incoming_covariances = incoming.states, incoming.covariances
    assert incoming_covariances is not None
    kept = _continuity(config, live, states, covariances, report, incoming)
    kept_rows = set(kept.values())
    rows = np.array([row for row in range(len(live)) if row not in kept_rows], dtype=np.int64)
    cols = np.array([col for col in range(len(report.tracks)) if col not in kept], dtype=np.int64)
    pairs: list[tuple[int, int, float | None, str]] = sorted(
        (row, col, None, "continuity") for col, row in kept.items()
    )
    if len(rows) == 0 or len(cols) == 0:  # nothing left to decide: no method run
        return Decision(
            method=config.association_method,
            pairs=pairs,
            new=cols.tolist(),
            missed=rows.tolist(),
            matrix_rows=rows,
            matrix_cols=cols,
            scores=None,
        )
    known_classes, incoming_classes = _association_classes(config, live, report, classify)
    result = associate(  # not checked again: the report by _check, the fused side by construction
        Estimates(states[rows], covariances[rows], "known"),
        Estimates(incoming_states[cols], incoming_covariances[cols], "incoming"),
        config.association_method,
        config.association_options,
        config.distance or "sum",
        None if known_classes is None else [known_classes[row] for row in rows],
        None if incoming_classes is None else [incoming_classes[col] for col in cols],
    )
    pairs += [
        (int(rows[k]), int(cols[i]), float(score), "association")
        for k, i, score in zip(
            result.pair_known, result.pair_incoming, result.pair_score, strict=True
        )
    ]
    pairs.sort(key=lambda pair: (pair[0], pair[1]))
    return Decision(
        method=result.method,
        pairs=pairs,
        new=[int(cols[i]) for i in result.new],
        missed=[int(rows[k]) for k in result.missed],
        matrix_rows=rows,
        matrix_cols=cols,
        scores=result.scores,
    )


def _continuity(
    config: FusionConfig,
    live: list[FusedTrack],
    states: FloatArray,
    covariances: FloatArray,
    report: TrackReport,
    incoming: Estimates,
) -> dict[int, int]:
    """Report tracks the sensor keeps reporting under the id it gave a fused track.

    ``{report column: fused row}`` for every report track whose (sensor, id)
    is the latest estimate of a live fused track and still passes the χ²
    gate (:data:`CONTINUITY_GATE_PROBABILITY`) on the ``sum`` distance;
    empty when continuity is off.
    """
    if not config.track_continuity:
        return {}
    bound = {
        fused.estimates[report.sensor].track: row
        for row, fused in enumerate(live)
        if report.sensor in fused.estimates
    }
    pairs = [(col, bound[t.id]) for col, t in enumerate(report.tracks) if t.id in bound]
    if not pairs:
        return {}
    cols = np.array([col for col, _ in pairs], dtype=np.int64)
    rows = np.array([row for _, row in pairs], dtype=np.int64)
    assert incoming.covariances is not None
    distance, _ = mahalanobis(
        incoming.states[cols] - states[rows], incoming.covariances[cols] + covariances[rows]
    )
    gate = chi2_quantile(CONTINUITY_GATE_PROBABILITY, config.dim)
    passed = distance <= gate
    return dict(zip(cols[passed].tolist(), rows[passed].tolist(), strict=True))


def _association_classes(
    config: FusionConfig, live: list[FusedTrack], report: TrackReport, classify: Classify
) -> tuple[list[MassFunction] | None, list[MassFunction] | None]:
    """Class masses of both sides when the report carries class evidence (§3.6)."""
    frame = config.classes
    if frame is None or not any(
        t.class_mass is not None or t.class_likelihoods is not None for t in report.tracks
    ):
        return None, None
    vacuous = MassFunction.vacuous(frame)
    incoming = []
    for track in report.tracks:
        if track.class_mass is not None:
            incoming.append(_normalised_or_vacuous(track.class_mass))
        elif track.class_likelihoods is not None:
            try:
                incoming.append(accumulate_likelihoods(None, frame, track.class_likelihoods)[0])
            except TotalConflict:
                incoming.append(vacuous)
        else:
            incoming.append(vacuous)
    known = []
    for fused in live:
        assessment = classify(fused)
        known.append(vacuous if assessment is None or assessment.mass is None else assessment.mass)
    return known, incoming


def _normalised_or_vacuous(mass: MassFunction) -> MassFunction:
    try:
        return mass.normalized()
    except TotalConflict:
        return MassFunction.vacuous(mass.frame)
