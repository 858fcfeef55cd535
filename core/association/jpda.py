"""Joint Probabilistic Data Association by exact enumeration of each cluster's joint events.

(Fortmann, Bar-Shalom & Scheffe 1983; Bar-Shalom, Daum & Huang, "The probabilistic
data association filter", IEEE Control Systems 2009, eq 30–36; Stone Soup's ``JPDA``
with ``PDAHypothesiser``.) Measurement-to-track, local tracking only.

For a gated pair (track t, detection j) the likelihood ratio of "j is t's" against
"j is clutter" is ``L_tj = P_D N(z_j; ẑ_t, S_t) / λ`` (λ the clutter density,
false detections per unit of measurement space per scan); a track that takes no
detection weighs ``1 − P_D P_G``. A joint event θ gives each track at most one of
its gated detections, each detection at most one track::

    P(θ) ∝ Π_{(t,j) ∈ θ} L_tj · Π_{t unassigned in θ} (1 − P_D P_G)

The marginals ``β_tj = Σ_{θ ∋ (t,j)} P(θ)`` are the method's scores; the pairs
it returns are those of the most probable joint event (the MAP event, found in
the same enumeration). Events factor over the connected clusters of the gated
pairs, so each cluster is enumerated on its own (computed in logarithms).

Exact enumeration is for small clusters: a cluster whose events exceed
``max_events`` is refused, naming the option (choose ``gnn`` there).

Options
-------
p_detect : float in (0, 1), default 0.9
clutter_density : float > 0, default 1e-6 (one false detection per km² per scan in 2-D)
gate_probability : float in (0, 1), default 0.999 (P_G; the gate chi2.ppf(P_G, q))
max_events : float ≥ 1, default 100 000 (joint events per cluster)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from core.arrays import IntArray
from core.association.problem import AssociationProblem
from core.association.result import AssociationResult, Diagnostics, ScoreMatrix, build_result
from core.association.spec import LOCAL_ONLY, MethodSpec, NumberOption
from core.distance import threshold_from_probability
from core.errors import OptionError

METHOD = "jpda"
LOG_TWO_PI = math.log(2.0 * math.pi)


@dataclass(frozen=True)
class JpdaOptions:
    """Validated options of :func:`associate_jpda` (module docstring)."""

    p_detect: float = 0.9
    clutter_density: float = 1e-6
    gate_probability: float = 0.999
    max_events: float = 100_000.0


def _cluster_events(
    tracks: list[int], options: dict[int, list[tuple[int, float]]], log_missed: float
) -> tuple[list[float], list[list[tuple[int, int]]]]:
    """Every joint event of one cluster: its log weight and its (track, detection) pairs."""
    weights: list[float] = []
    events: list[list[tuple[int, int]]] = []
    chosen: list[tuple[int, int]] = []
    used: set[int] = set()

    def visit(index: int, log_weight: float) -> None:
        if index == len(tracks):
            weights.append(log_weight)
            events.append(list(chosen))
            return
        track = tracks[index]
        visit(index + 1, log_weight + log_missed)
        for detection, log_ratio in options[track]:
            if detection not in used:
                used.add(detection)
                chosen.append((track, detection))
                visit(index + 1, log_weight + log_ratio)
                chosen.pop()
                used.discard(detection)

    visit(0, 0.0)
    return weights, events


def _event_bound(tracks: list[int], options: dict[int, list[tuple[int, float]]]) -> float:
    """Π (1 + gated detections of t): at least the number of joint events."""
    return math.prod(1.0 + len(options[track]) for track in tracks)


def associate_jpda(problem: AssociationProblem, options: JpdaOptions) -> AssociationResult:
    """Marginal association probabilities and the MAP joint event, cluster by cluster."""
    gate = threshold_from_probability(options.gate_probability, problem.dimension, problem.distance)
    pairs = problem.pairs(gate)
    log_g = -0.5 * (pairs.plain_distance + pairs.log_det + problem.dimension * LOG_TWO_PI)
    log_ratio = math.log(options.p_detect) - math.log(options.clutter_density) + log_g
    log_missed = math.log1p(-options.p_detect * options.gate_probability)
    n, m = problem.n_known, problem.n_incoming
    graph = coo_matrix(
        (np.ones(len(pairs)), (pairs.rows, n + pairs.cols)), shape=(n + m, n + m)
    ).tocsr()
    _, label = connected_components(graph, directed=False)
    candidates: dict[int, list[tuple[int, float]]] = {}
    rows_list, cols_list = pairs.rows.tolist(), pairs.cols.tolist()
    for row, col, ratio in zip(rows_list, cols_list, log_ratio.tolist(), strict=True):
        candidates.setdefault(row, []).append((col, ratio))
    marginal: dict[tuple[int, int], float] = {}
    matched: list[tuple[int, int]] = []
    largest = 0
    clusters = 0
    for cluster in np.unique(label[list(candidates)]).tolist() if candidates else []:
        tracks = [row for row in candidates if label[row] == cluster]
        bound = _event_bound(tracks, candidates)
        if bound > options.max_events:
            raise OptionError(
                f"{METHOD}: a cluster of {len(tracks)} tracks has up to {bound:.0f} joint events, "
                f"more than option 'max_events' ({options.max_events:g}); exact enumeration is "
                "for small clusters"
            )
        weights, events = _cluster_events(tracks, candidates, log_missed)
        clusters += 1
        detections = {col for track in tracks for col, _ in candidates[track]}
        largest = max(largest, len(tracks) + len(detections))
        log_weights = np.asarray(weights)
        probability = np.exp(log_weights - np.logaddexp.reduce(log_weights))
        for event, p in zip(events, probability.tolist(), strict=True):
            for pair in event:
                marginal[pair] = marginal.get(pair, 0.0) + p
        matched += events[int(np.argmax(log_weights))]
    values = np.array([marginal.get(pair, 0.0) for pair in zip(rows_list, cols_list, strict=True)])
    clutter = np.ones(m)
    np.subtract.at(clutter, pairs.cols, values)
    scores = ScoreMatrix(
        kind="probability",
        rows=pairs.rows,
        cols=pairs.cols,
        values=values,
        new=np.clip(clutter, 0.0, 1.0),
        shape=(n, m),
        missing=0.0,
    )
    rows: IntArray = np.array([pair[0] for pair in matched], dtype=np.int64)
    cols: IntArray = np.array([pair[1] for pair in matched], dtype=np.int64)
    diagnostics = Diagnostics(
        candidate_pairs=len(pairs), clusters=clusters, largest_cluster=largest, gate=gate
    )
    return build_result(METHOD, rows, cols, scores, diagnostics, pairs)


def _values(values: dict[str, float | None]) -> JpdaOptions:
    return JpdaOptions(
        **{name: float(value) for name, value in values.items() if value is not None}
    )


SPEC = MethodSpec(
    name=METHOD,
    scopes=LOCAL_ONLY,
    options=(
        NumberOption("p_detect", 0.9, low=0.0, high=1.0, high_open=True, doc="P_D"),
        NumberOption(
            "clutter_density", 1e-6, low=0.0, doc="λ, false detections per unit volume per scan"
        ),
        NumberOption(
            "gate_probability", 0.999, low=0.0, high=1.0, high_open=True, doc="P_G; the gate"
        ),
        NumberOption(
            "max_events",
            100_000.0,
            low=1.0,
            low_open=False,
            doc="most joint events one cluster may have (exact enumeration)",
        ),
    ),
    build=_values,
    run=associate_jpda,
    summary="JPDA, exact enumeration of each cluster's joint events; pairs of the MAP event",
)
