"""Unit study: is the "parameterless" ``hachour`` unit-free? (docs/algorithms.md §3.3, EVALUATION.md).

[T2T] eq 4 turns a Mahalanobis distance D into the Gaussian density
``G = exp(−D/2) / sqrt((2π)^q |C|)`` and uses it as a plausibility. D does not
depend on the length unit; |C| does (×s^{2q} when lengths are multiplied by
s). Since a pair is matched only when its plausibility exceeds 1/2 and every
G ≥ 1 is clipped to 1 (``likelihood="density"``), the method

- matches a pair only if ``D < 2 ln 2 + 2 ln G₀`` (G₀ the peak density), and
- cannot tell apart pairs with ``D < 2 ln G₀`` (all have Pl = 1):

its usable band of D is 2 ln 2 ≈ 1.39 wide and sits where the unit puts it.
``likelihood="relative"`` (G₀ = 1) is unit-free but gates at D < 2 ln 2.

The scene is :func:`core.simulation.tracklists.t2t_four` (four targets,
square of side ``separation``) with each sensor missing each track
independently with probability ``unseen`` — partially observed targets are
what a gate is for. Two studies:

- :func:`unit_sweep`: false decision rate against the length unit (the
  scene scaled by s), every method;
- :func:`noise_study`: across noise levels (position σ), in metres and in
  kilometres: hachour ``density`` and ``relative``, ``gnn`` and ``denoeux``
  at their best λ (tuned per noise level on a grid, over realisations other
  than the reported ones), and the defaults
  (``gnn`` gate 0.999 with the ``mean`` covariance; the session default
  ``denoeux`` gate 0.999, α 1, ``sum`` covariance).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray, IntArray
from core.simulation.tracklists import t2t_four
from evaluation.pairing import (
    TIE_PROBES,
    ListPair,
    Outcome,
    decision_outcome,
    list_pairs,
    partially_observed,
)

METHODS: dict[str, tuple[str, dict[str, object], str]] = {
    "hachour density": ("hachour", {"likelihood": "density"}, "mean"),
    "hachour relative": ("hachour", {"likelihood": "relative"}, "mean"),
    "gnn default": ("gnn", {"gate_probability": 0.999}, "mean"),
    "denoeux default": ("denoeux", {"gate_probability": 0.999, "alpha": 1.0}, "sum"),
}
"""Label → (method, options, distance) of the methods without a tuned parameter."""

TUNED = ("gnn", "denoeux")
SCALES = {"m": 1.0, "km": 1e-3}
TUNING_THRESHOLDS = np.geomspace(2.0, 200.0, 12)
UNIT_SCALES = np.geomspace(10.0, 1e-4, 16)
"""Length scale factors s of :func:`unit_sweep`: lengths × 10 down to lengths × 1e-4."""


Realisations = list[tuple[int, list[ListPair]]]
"""(seed, association problems) of each realisation."""


def scene(
    seeds: Sequence[int], n_steps: int, position_sigma: float, separation: float, unseen: float
) -> Realisations:
    """The association problems of each realisation (one per seed), in metres."""
    realisations = []
    for seed in seeds:
        scenario = t2t_four(
            seed=seed, position_sigma=position_sigma, separation=separation, n_steps=n_steps
        )
        rng = np.random.default_rng([seed, 7])  # the misses: their own stream, same seed
        realisations.append((seed, partially_observed(list_pairs(scenario.reports), unseen, rng)))
    return realisations


def _tuned_options(method: str, threshold: float) -> dict[str, object]:
    if method == "gnn":
        return {"threshold": threshold}
    return {"gamma": math.log(2.0) / threshold, "alpha": 1.0}


def _outcomes(
    realisations: Realisations,
    method: str,
    options: dict[str, object],
    distance: str,
    scale: float = 1.0,
    order: int = 0,
    tie_probes: int = TIE_PROBES,
) -> list[Outcome]:
    """One outcome per realisation, the lists in a random order (:mod:`evaluation.pairing`)."""
    return [
        decision_outcome(
            [pair.scaled(scale) for pair in pairs],
            method,
            options,
            distance,
            seed=seed,
            order=order,
            tie_probes=tie_probes,
        )
        for seed, pairs in realisations
    ]


def _mean_rate(outcomes: Sequence[Outcome]) -> float:
    return float(np.mean([outcome.rate for outcome in outcomes]))


@dataclass(frozen=True)
class UnitSweep:
    """False decision rate against the length unit.

    Attributes
    ----------
    seeds : tuple of int
    scales : ndarray, shape (k,)
        Lengths are multiplied by s (s = 1e-3: the scene in kilometres).
    rates : dict of str to ndarray, shape (k,)
        Mean rate over the realisations per method label (:data:`METHODS`).
    run_rates, ties : dict of str to ndarray, shape (len(seeds), k)
        The rate and the tie rate of each realisation.
    decisions : ndarray of int, shape (len(seeds),)
        Decisions per realisation.
    implicit_gates : ndarray, shape (k,)
        hachour-density's implicit gate on D at each scale (scene covariances).
    position_sigma, separation, unseen : float
    """

    seeds: tuple[int, ...]
    scales: FloatArray
    rates: dict[str, FloatArray]
    run_rates: dict[str, FloatArray]
    ties: dict[str, FloatArray]
    decisions: IntArray
    implicit_gates: FloatArray
    position_sigma: float
    separation: float
    unseen: float


def implicit_gate(position_sigma: float, scale: float = 1.0, dimension: int = 4) -> float:
    """hachour-density's gate on D for the scenes' round covariances (``mean``: C = P).

    ``2 ln 2 − q ln 2π − ln|C|`` with position σ ``position_sigma × scale`` and
    velocity σ half of it.
    """
    position, velocity = position_sigma * scale, position_sigma * scale / 2.0
    log_det = 2.0 * (2.0 * math.log(position) + 2.0 * math.log(velocity))
    return 2.0 * math.log(2.0) - dimension * math.log(2.0 * math.pi) - log_det


def unit_sweep(
    seeds: Sequence[int] = tuple(range(10)),
    scales: Sequence[float] | FloatArray = UNIT_SCALES,
    n_steps: int = 20,
    position_sigma: float = 0.5,
    separation: float = 2.0,
    unseen: float = 0.2,
    order: int = 0,
) -> UnitSweep:
    """Rate of every method of :data:`METHODS` on the same scene expressed at each scale."""
    realisations = scene(seeds, n_steps, position_sigma, separation, unseen)
    factors = np.asarray(scales, dtype=np.float64)
    run_rates: dict[str, FloatArray] = {}
    ties: dict[str, FloatArray] = {}
    decisions = np.zeros(len(seeds), dtype=np.int64)
    for label, (method, options, distance) in METHODS.items():
        outcomes = [_outcomes(realisations, method, options, distance, s, order) for s in factors]
        run_rates[label] = np.array([[o.rate for o in at] for at in outcomes]).T
        ties[label] = np.array([[o.tie_rate for o in at] for at in outcomes]).T
        decisions[:] = [o.decisions for o in outcomes[0]]
    return UnitSweep(
        seeds=tuple(seeds),
        scales=factors,
        rates={label: values.mean(axis=0) for label, values in run_rates.items()},
        run_rates=run_rates,
        ties=ties,
        decisions=decisions,
        implicit_gates=np.array([implicit_gate(position_sigma, s) for s in factors]),
        position_sigma=position_sigma,
        separation=separation,
        unseen=unseen,
    )


@dataclass(frozen=True)
class NoiseStudy:
    """False decision rates across noise levels, in metres and kilometres.

    Attributes
    ----------
    seeds : tuple of int
    sigmas : ndarray, shape (k,)
        Position σ (m) of the reported covariances and actual errors.
    rates : dict of (str, str) to ndarray, shape (k,)
        ``(label, unit)`` → mean rate; labels of :data:`METHODS` plus
        ``"gnn tuned"`` and ``"denoeux tuned"``; units ``"m"``, ``"km"``.
    ties : dict of (str, str) to ndarray, shape (k,)
        Mean tie rate, keyed as ``rates``.
    run_rates : dict of (str, str) to ndarray, shape (len(seeds), k)
        The rate of each realisation, keyed as ``rates``.
    decisions : ndarray of int, shape (len(seeds), k)
        Decisions per realisation and noise level.
    best_thresholds : dict of str to ndarray, shape (k,)
        The tuned λ per noise level of ``gnn`` and ``denoeux``.
    separation, unseen : float
    """

    seeds: tuple[int, ...]
    sigmas: FloatArray
    rates: dict[tuple[str, str], FloatArray]
    ties: dict[tuple[str, str], FloatArray]
    run_rates: dict[tuple[str, str], FloatArray]
    decisions: IntArray
    best_thresholds: dict[str, FloatArray]
    separation: float
    unseen: float

    @property
    def labels(self) -> tuple[str, ...]:
        """Method labels, in insertion order."""
        return tuple(dict.fromkeys(label for label, _ in self.rates))


def noise_study(
    seeds: Sequence[int] = tuple(range(10)),
    sigmas: Sequence[float] | FloatArray = (0.1, 0.2, 0.5, 1.0, 2.0, 4.0),
    n_steps: int = 20,
    separation: float = 10.0,
    unseen: float = 0.2,
    tuning_thresholds: Sequence[float] | FloatArray = TUNING_THRESHOLDS,
    order: int = 0,
    tuning_seeds: Sequence[int] | None = None,
) -> NoiseStudy:
    """Every method in metres and kilometres at each noise level (module docstring).

    The tuned λ of each noise level is chosen on ``tuning_seeds`` (default:
    each seed + 100), never on the runs it is reported on.
    """
    tuning_seeds = [seed + 100 for seed in seeds] if tuning_seeds is None else tuning_seeds
    levels = np.asarray(sigmas, dtype=np.float64)
    grid = np.asarray(tuning_thresholds, dtype=np.float64)
    rates: dict[tuple[str, str], FloatArray] = {}
    ties: dict[tuple[str, str], FloatArray] = {}
    run_rates: dict[tuple[str, str], FloatArray] = {}
    decisions = np.zeros((len(seeds), len(levels)), dtype=np.int64)
    best: dict[str, FloatArray] = {method: np.empty(len(levels)) for method in TUNED}
    for unit in SCALES:
        for label in (*METHODS, *(f"{method} tuned" for method in TUNED)):
            rates[(label, unit)] = np.empty(len(levels))
            ties[(label, unit)] = np.empty(len(levels))
            run_rates[(label, unit)] = np.empty((len(seeds), len(levels)))
    for index, sigma in enumerate(levels):
        realisations = scene(seeds, n_steps, float(sigma), separation, unseen)
        tuning = scene(tuning_seeds, n_steps, float(sigma), separation, unseen)
        for method in TUNED:
            on_grid = [
                _mean_rate(  # rates only: no tie probes (pairing.decision_outcome)
                    _outcomes(
                        tuning,
                        method,
                        _tuned_options(method, t),
                        "mean",
                        order=order,
                        tie_probes=0,
                    )
                )
                for t in grid
            ]
            best[method][index] = grid[int(np.argmin(on_grid))]
        for unit, scale in SCALES.items():
            runs: dict[str, tuple[str, dict[str, object], str]] = dict(METHODS)
            for method in TUNED:
                tuned = _tuned_options(method, float(best[method][index]))
                runs[f"{method} tuned"] = (method, tuned, "mean")
            for label, (method, options, distance) in runs.items():
                outcomes = _outcomes(realisations, method, options, distance, scale, order)
                rates[(label, unit)][index] = _mean_rate(outcomes)
                ties[(label, unit)][index] = np.mean([o.tie_rate for o in outcomes])
                run_rates[(label, unit)][:, index] = [o.rate for o in outcomes]
                decisions[:, index] = [o.decisions for o in outcomes]
    return NoiseStudy(
        seeds=tuple(seeds),
        sigmas=levels,
        rates=rates,
        ties=ties,
        run_rates=run_rates,
        decisions=decisions,
        best_thresholds=best,
        separation=separation,
        unseen=unseen,
    )
