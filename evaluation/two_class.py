"""[T2T] §4 scenario 2 (Fig 5–6): association on distance only vs distance + class.

Two nearby targets of different classes (:func:`core.simulation.two_class.t2t_two_class`);
sensor 1's estimates are matched to sensor 2's at every step
(:mod:`evaluation.pairing`, ``mean`` covariance of [T2T] eq 2).
"Mono-information" uses the distance only, "multi-information" adds the
class conflict of the two tracks' mass functions (ALGORITHMS.md §3.6:
``denoeux`` adds ln(1 − K) to its weight, ``hachour`` and ``mercier`` multiply
the pair's plausibility by 1 − K). ``gnn`` cannot use classes ([T2T] §4).

"In this simulation, optimal parameters λ and γ are used": λ of ``gnn`` and
of ``denoeux`` (γ = ln 2 / λ) is the one with the lowest mean mono-information
rate on a grid, and is kept for the multi-information run; the session
default (``denoeux``, gate 0.999, α 1, ``sum``, ALGORITHMS.md §3.7) is run
untuned beside it. ``hachour`` with
``likelihood="density"`` is run on the scene in metres and in kilometres
(its decisions depend on the unit, §3.3).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray
from core.simulation.two_class import t2t_two_class
from evaluation.pairing import ListPair, decision_error_rate, list_pairs

TUNING_THRESHOLDS = np.geomspace(1.0, 300.0, 16)


@dataclass(frozen=True)
class Variant:
    """One bar group of [T2T] Fig 6.

    Attributes
    ----------
    label : str
    method : str
    options : dict
        Fixed options (``gnn``/``denoeux`` get their tuned λ / γ added).
    scale : float
        Length scale applied to the scene (1e-3: kilometres).
    tuned : bool
        Whether λ (γ) is tuned on the mono-information rate.
    distance : str
        Covariance of the distance: ``mean`` ([T2T] eq 2) or ``sum`` (session default).
    """

    label: str
    method: str
    options: dict[str, object]
    scale: float = 1.0
    tuned: bool = False
    distance: str = "mean"


VARIANTS: tuple[Variant, ...] = (
    Variant("gnn", "gnn", {}, tuned=True),
    Variant("denoeux", "denoeux", {"alpha": 1.0}, tuned=True),
    Variant(
        "denoeux session default",
        "denoeux",
        {"gate_probability": 0.999, "alpha": 1.0},
        distance="sum",
    ),
    Variant("hachour density (m)", "hachour", {"likelihood": "density"}),
    Variant("hachour density (km)", "hachour", {"likelihood": "density"}, scale=1e-3),
    Variant("hachour relative", "hachour", {"likelihood": "relative"}),
    Variant("mercier", "mercier", {}),
)


@dataclass(frozen=True)
class ClassComparison:
    """False decision rates of [T2T] Fig 6, per variant and realisation.

    Attributes
    ----------
    seeds : tuple of int
    labels : tuple of str
        Variant labels, in :data:`VARIANTS` order.
    mono, multi : dict of str to ndarray, shape (len(seeds),)
        Rate per realisation without and with class information (``multi``
        has no ``gnn`` entry: it cannot use classes).
    thresholds : dict of str to float
        The tuned λ of ``gnn`` and ``denoeux``.
    position_sigma, separation : float
        The scene (m).
    """

    seeds: tuple[int, ...]
    labels: tuple[str, ...]
    mono: dict[str, FloatArray]
    multi: dict[str, FloatArray]
    thresholds: dict[str, float]
    position_sigma: float
    separation: float


def _tuned_options(method: str, threshold: float) -> dict[str, object]:
    if method == "gnn":
        return {"threshold": threshold}
    return {"gamma": math.log(2.0) / threshold, "alpha": 1.0}


def _best_threshold(
    realisations: Sequence[Sequence[ListPair]], method: str, grid: FloatArray
) -> float:
    rates = [
        np.mean(
            [
                decision_error_rate(pairs, method, _tuned_options(method, t))
                for pairs in realisations
            ]
        )
        for t in grid
    ]
    return float(grid[int(np.argmin(rates))])


def class_comparison(
    seeds: Sequence[int] = tuple(range(10)),
    n_steps: int = 20,
    position_sigma: float = 0.5,
    separation: float = 1.5,
    class_confidence: float = 0.9,
    class_error: float = 0.05,
    tuning_thresholds: Sequence[float] | FloatArray = TUNING_THRESHOLDS,
) -> ClassComparison:
    """Mono- and multi-information false decision rates of every variant of :data:`VARIANTS`.

    Parameters
    ----------
    seeds : sequence of int
        One noise (and class-mass) realisation per seed ([T2T]: 10).
    n_steps : int
        Steps per realisation (2 decisions each).
    position_sigma, separation, class_confidence, class_error : float
        The scene (:func:`core.simulation.two_class.t2t_two_class`).
    tuning_thresholds : sequence of float
        The λ grid the parameter-dependent methods are tuned on.
    """
    realisations = [
        list_pairs(scenario.reports, class_masses=scenario.class_masses)
        for scenario in (
            t2t_two_class(
                seed=seed,
                position_sigma=position_sigma,
                separation=separation,
                n_steps=n_steps,
                class_confidence=class_confidence,
                class_error=class_error,
            )
            for seed in seeds
        )
    ]
    grid = np.asarray(tuning_thresholds, dtype=np.float64)
    thresholds: dict[str, float] = {}
    mono: dict[str, FloatArray] = {}
    multi: dict[str, FloatArray] = {}
    for variant in VARIANTS:
        options = dict(variant.options)
        if variant.tuned:
            thresholds[variant.method] = _best_threshold(realisations, variant.method, grid)
            options.update(_tuned_options(variant.method, thresholds[variant.method]))
        scaled = [[pair.scaled(variant.scale) for pair in pairs] for pairs in realisations]
        mono[variant.label] = np.array(
            [
                decision_error_rate(pairs, variant.method, options, variant.distance)
                for pairs in scaled
            ]
        )
        if variant.method != "gnn":
            multi[variant.label] = np.array(
                [
                    decision_error_rate(
                        pairs, variant.method, options, variant.distance, use_classes=True
                    )
                    for pairs in scaled
                ]
            )
    return ClassComparison(
        seeds=tuple(seeds),
        labels=tuple(variant.label for variant in VARIANTS),
        mono=mono,
        multi=multi,
        thresholds=thresholds,
        position_sigma=position_sigma,
        separation=separation,
    )
