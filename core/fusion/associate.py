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
from scipy.optimize import linear_sum_assignment

from core.arrays import BoolArray, FloatArray, IntArray
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
RENUMBERING_ODDS = 1e3
"""Odds at which a source's ids are taken to have changed their meaning (a source that
restarted and numbers its tracks afresh, a local id swap): the report's tracks fit the
fused tracks in another order this much better than in the order of their ids
(:func:`_renumbered`)."""


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
    established: BoolArray,
) -> Decision:
    """The report's tracks with the live fused tracks (``states``, ``covariances``: fused
    and predicted to the report time; ``established``: confirmed or coasting): continuity
    first (when on), then the session's method on what is left (the decision's rows index
    ``live``)."""
    incoming_states, incoming_covariances = incoming.states, incoming.covariances
    assert incoming_covariances is not None
    kept = _continuity(config, live, states, covariances, report, incoming, established)
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
    established: BoolArray,
) -> dict[int, int]:
    """Report tracks the sensor keeps reporting under the id it gave a fused track.

    ``{report column: fused row}`` for every report track whose (sensor, id)
    is the latest estimate of a live fused track, still passes the χ²
    gate (:data:`CONTINUITY_GATE_PROBABILITY`) on the ``sum`` distance and, for a source
    that posts track lists, where it binds an established track, is not renumbered
    (:func:`_renumbered`); empty when continuity is off.
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
    cols, rows = cols[passed], rows[passed]
    if config.source(report.sensor).tracker is not None or report.sensor == config.central_source:
        # the session's own trackers (a local one, the central one) never renumber behind
        # its back: their ids are not tested
        return dict(zip(cols.tolist(), rows.tolist(), strict=True))
    # a track-list source's ids are tested where they bind established tracks (a tentative
    # track's start may be off: its own next report joining it is the duplicate merge's)
    tested = np.flatnonzero(established[rows])
    among = np.flatnonzero(established)
    kept = np.ones(len(cols), dtype=bool)
    kept[tested] = ~_renumbered(
        states[among],
        covariances[among],
        incoming,
        cols[tested],
        np.searchsorted(among, rows[tested]),
    )
    return dict(zip(cols[kept].tolist(), rows[kept].tolist(), strict=True))


def _renumbered(
    states: FloatArray,
    covariances: FloatArray,
    incoming: Estimates,
    cols: IntArray,
    rows: IntArray,
) -> BoolArray:
    """The continuity pairs (report track ``cols[k]``, live fused track ``rows[k]``) whose ids
    no longer mean what they meant: a generalised likelihood-ratio test of "the ids kept
    their meaning" against the best pairing of the same report tracks with the live fused
    tracks (``states``, ``covariances``) by state.

    D_ids = Σ D of the pairs as the ids bind them, D_best the least Σ D of any pairing of
    those report tracks with distinct live fused tracks (``sum`` covariance; a linear
    assignment). Each pairing is a Gaussian hypothesis, so the best pairing is
    exp((D_ids − D_best)/2) times as likely (the determinants of its pairs differ little
    from the ids' pairs' and are left out); above :data:`RENUMBERING_ODDS` the pairs it
    moves are left to the association by state: a source that restarted and numbers its
    tracks from 1 again, a local tracker that swapped two ids. Two targets crossing, whose
    states fit either pairing, keep their ids.
    """
    count, live = len(cols), len(states)
    moved = np.zeros(count, dtype=bool)
    if count == 0 or live < 2:
        return moved
    assert incoming.covariances is not None
    by_col, by_row = np.repeat(cols, live), np.tile(np.arange(live), count)
    distances, _ = mahalanobis(
        incoming.states[by_col] - states[by_row],
        incoming.covariances[by_col] + covariances[by_row],
    )
    matrix = distances.reshape(count, live)  # [continuity pair, live fused track]
    pairs, best = linear_sum_assignment(matrix)
    kept = matrix[np.arange(count), rows].sum()
    if kept - matrix[pairs, best].sum() <= 2.0 * np.log(RENUMBERING_ODDS):
        return moved
    moved[pairs] = best != rows[pairs]
    return moved


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
