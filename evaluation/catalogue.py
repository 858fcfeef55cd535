"""The names of the papers' figures, without the code that draws them.

:mod:`evaluation.figures` draws each entry (and needs the ``figures`` extra,
matplotlib); this module needs nothing, so the CLI can offer the names
(``credal-fusion reproduce NAME``) without importing any plotting code.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class FigureEntry:
    """One reproducible figure.

    Attributes
    ----------
    name : str
        Registry key and PNG file stem.
    paper : str
        The figures of the papers it reproduces.
    summary : str
        One line: what it shows.
    """

    name: str
    paper: str
    summary: str


CATALOGUE: dict[str, FigureEntry] = {
    entry.name: entry
    for entry in (
        FigureEntry(
            "t2t-four",
            "[T2T] Fig 3–4",
            "false decision rate vs λ (gnn), γ (denoeux) and hachour",
        ),
        FigureEntry(
            "t2t-two-class",
            "[T2T] Fig 5–6",
            "false decision rate with and without class information",
        ),
        FigureEntry(
            "aircraft",
            "[MTT] Fig 12–15",
            "target 2: behaviours, Bayesian vs credal classification",
        ),
        FigureEntry(
            "pedestrian",
            "[MTT] Fig 20–23",
            "pedestrian 1: standard vs instantaneous vs cumulative discounting",
        ),
        FigureEntry(
            "unit-study",
            "docs/algorithms.md §3.3",
            "hachour density vs relative vs gnn/denoeux in metres and kilometres",
        ),
        FigureEntry(
            "close-pair",
            "[MTT] Fig 16",
            "false assignment rate vs noise: closest-model, combined, gated-combined IMM distance",
        ),
        FigureEntry(
            "crossing",
            "[MTT] Fig 17–18",
            "a fighter crosses an unknown aircraft: false assignments and classes",
        ),
        FigureEntry(
            "road-four",
            "[DH] Fig 1–5",
            "RMS position/velocity error of four vehicles in clutter vs cheap JPDA",
        ),
        FigureEntry(
            "accelerating",
            "[HZ] Fig 5",
            "plain vs modified distance, with and without termination",
        ),
        FigureEntry(
            "overtaking",
            "[HZ] Fig 6",
            "identity through the blind zone with and without phantoms",
        ),
        FigureEntry(
            "mtt-scenes",
            "[MTT] Fig 4–5, 10–11, 19",
            "the four aircraft tracked, the track scores over time, the pedestrians",
        ),
        FigureEntry(
            "peers",
            "issue 13 (bench/peers.py)",
            "GOSPA, SIAP, id switches and per-scan time vs Stone Soup GNN and JPDA",
        ),
        FigureEntry(
            "real-traffic",
            "issue 22 (bench/traffic.py)",
            "20 recorded flights, three 3-D radars and ADS-B through the service: map and coverage",
        ),
        FigureEntry(
            "hz-scale",
            "[HZ] Fig 3",
            "scale factor of the Euclidean, Mahalanobis and modified distances vs |P|",
        ),
    )
}
"""Figure name → entry; :func:`evaluation.figures.reproduce` accepts exactly these names."""
