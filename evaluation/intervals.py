"""95 % intervals over Monte Carlo runs, multiple tests, and the paired comparison of two methods.

Runs are the unit of replication: the decisions of one run share its noise
realisation and are not independent. Each interval respects its quantity:

- a **rate** (a share of decisions, in [0, 1]): the hull of the Student-t
  interval of the per-run rates (honest about the correlation within a run)
  and the Wilson score interval of the pooled decisions (never of zero width),
  clipped to [0, 1] (:func:`rate_interval`); a share of runs: Wilson or
  Clopper–Pearson (:func:`wilson`, :func:`clopper_pearson`); the difference of two
  independent rates: Newcombe's hybrid score interval (:func:`rate_difference`);
- a **count per run** (identity switches, false tracks, stolen detections —
  mostly zeros): the hull of the exact (Garwood) Poisson interval of the
  total count over the runs and the percentile bootstrap of the per-run mean,
  both ≥ 0 (:func:`count_interval`) — never a t interval, whose lower end
  goes below 0 when most runs count 0;
- an **error** (a continuous per-run quantity): its t interval
  (:func:`mean_interval`).

Two methods run on the same realisations are compared by the paired
difference of their per-run values: its mean, t interval and the two-sided p
value of the paired t test. The tests of one figure are corrected together
by Holm's step-down procedure (:func:`holm`; :func:`bonferroni` for the
single-step bound), and :func:`runs_for_power` says how many runs a paired
claim needs.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy import stats

from core.arrays import FloatArray, IntArray

LEVEL = 0.95
Z = float(stats.norm.ppf(0.5 + LEVEL / 2))


@dataclass(frozen=True)
class Interval:
    """An estimate and its 95 % interval."""

    estimate: float
    low: float
    high: float

    @property
    def half_width(self) -> float:
        """The larger distance from the estimate to an end of the interval."""
        return max(self.estimate - self.low, self.high - self.estimate)

    def __contains__(self, value: float) -> bool:
        return self.low <= value <= self.high

    def __str__(self) -> str:
        return f"{self.estimate:.3f} [{self.low:.3f}, {self.high:.3f}]"


def _t_interval(values: np.ndarray) -> tuple[float, float]:
    mean = float(values.mean())
    if values.size < 2:
        return mean, mean
    half = float(stats.t.ppf(0.5 + LEVEL / 2, values.size - 1)) * float(
        values.std(ddof=1) / math.sqrt(values.size)
    )
    return mean - half, mean + half


def wilson(successes: float, trials: float) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion."""
    if trials <= 0:
        return 0.0, 1.0
    share = successes / trials
    z2 = Z * Z
    centre = (share + z2 / (2 * trials)) / (1 + z2 / trials)
    half = (
        Z * math.sqrt(share * (1 - share) / trials + z2 / (4 * trials * trials)) / (1 + z2 / trials)
    )
    return max(0.0, centre - half), min(1.0, centre + half)


def clopper_pearson(successes: float, trials: float) -> tuple[float, float]:
    """Exact (Clopper–Pearson) 95 % interval of a binomial proportion."""
    if trials <= 0:
        return 0.0, 1.0
    tail = (1 - LEVEL) / 2
    low = 0.0 if successes <= 0 else float(stats.beta.ppf(tail, successes, trials - successes + 1))
    high = (
        1.0
        if successes >= trials
        else float(stats.beta.ppf(1 - tail, successes + 1, trials - successes))
    )
    return low, high


def rate_difference(
    successes_a: float, trials_a: float, successes_b: float, trials_b: float
) -> Interval:
    """Rate b − rate a of two independent binomial samples, with Newcombe's hybrid score 95 %
    interval (Newcombe 1998, Stat Med 17:873, method 10: each rate's Wilson interval,
    combined in quadrature; defined at zero counts, never wider than [−1, 1])."""
    rate_a = successes_a / trials_a if trials_a > 0 else 0.0
    rate_b = successes_b / trials_b if trials_b > 0 else 0.0
    low_a, high_a = wilson(successes_a, trials_a)
    low_b, high_b = wilson(successes_b, trials_b)
    difference = rate_b - rate_a
    return Interval(
        difference,
        difference - math.hypot(rate_b - low_b, high_a - rate_a),
        difference + math.hypot(high_b - rate_b, rate_a - low_a),
    )


def poisson_interval(count: float) -> tuple[float, float]:
    """Exact (Garwood) 95 % interval of a Poisson mean from one observed count (≥ 0)."""
    tail = (1 - LEVEL) / 2
    low = 0.0 if count <= 0 else float(stats.chi2.ppf(tail, 2 * count)) / 2
    return low, float(stats.chi2.ppf(1 - tail, 2 * count + 2)) / 2


def rate_interval(per_run: ArrayLike, decisions_per_run: ArrayLike) -> Interval:
    """A rate over runs: the decision-weighted mean, with the hull of the t and Wilson intervals."""
    rates = np.asarray(per_run, dtype=np.float64).ravel()
    counts = np.broadcast_to(np.asarray(decisions_per_run, dtype=np.float64), rates.shape)
    trials = float(counts.sum())
    estimate = float((rates * counts).sum() / trials) if trials > 0 else float(rates.mean())
    t_low, t_high = _t_interval(rates)
    w_low, w_high = wilson(estimate * trials, trials)
    return Interval(estimate, max(0.0, min(t_low, w_low)), min(1.0, max(t_high, w_high)))


def mean_interval(per_run: ArrayLike, *, floor: float | None = None) -> Interval:
    """The mean of a continuous per-run quantity (an error) with its t interval; ``floor``:
    the least value the quantity can take (0 for an error, a GOSPA term, a time), where the
    interval is cut (the t interval of a mean near it reaches below what the mean can be).

    Not for counts or rates (module docstring): :func:`count_interval`, :func:`rate_interval`.
    """
    values = np.asarray(per_run, dtype=np.float64).ravel()
    low, high = _t_interval(values)
    if floor is not None:
        low, high = max(low, floor), max(high, floor)
    return Interval(float(values.mean()), low, high)


def count_interval(per_run: ArrayLike, *, seed: int = 0) -> Interval:
    """Mean count per run, with the hull of the Poisson and bootstrap intervals (≥ 0).

    The Poisson interval (:func:`poisson_interval` of the total, divided by the
    runs) is exact when the counts are Poisson; the percentile bootstrap of
    the mean (:data:`BOOTSTRAP_RESAMPLES`, seeded) covers overdispersed
    counts. All zeros give [0, 3.69 / runs].
    """
    counts = np.asarray(per_run, dtype=np.float64).ravel()
    if counts.size == 0 or np.any(counts < 0) or not np.all(np.isfinite(counts)):
        raise ValueError("count_interval needs at least one finite count ≥ 0")
    runs = counts.size
    low, high = (value / runs for value in poisson_interval(float(counts.sum())))
    rng = np.random.default_rng(seed)
    means = counts[rng.integers(0, runs, size=(BOOTSTRAP_RESAMPLES, runs))].mean(axis=1)
    tail = 100 * (1 - LEVEL) / 2
    b_low, b_high = np.percentile(means, [tail, 100 - tail])
    return Interval(float(counts.mean()), min(low, float(b_low)), max(high, float(b_high)))


def holm(p_values: ArrayLike) -> FloatArray:
    """Holm's step-down adjusted p values (reject where adjusted ≤ 0.05), in the given order.

    Sorted ascending, ``p_(i)`` becomes ``max_{j ≤ i} min(1, (m − j + 1) p_(j))``:
    it controls the family-wise error rate like Bonferroni, and rejects at
    least as much.
    """
    p = np.asarray(p_values, dtype=np.float64).ravel()
    m = p.size
    order = np.argsort(p, kind="stable")
    scaled = np.minimum(1.0, (m - np.arange(m)) * p[order])
    adjusted = np.empty(m)
    adjusted[order] = np.maximum.accumulate(scaled)
    return adjusted


def bonferroni(p_values: ArrayLike) -> FloatArray:
    """Bonferroni-adjusted p values: ``min(1, m p)``."""
    p = np.asarray(p_values, dtype=np.float64).ravel()
    return np.minimum(1.0, p.size * p)


def runs_for_power(difference: float, spread: float, *, power: float = 0.8, tests: int = 1) -> int:
    """Runs a two-sided paired t test needs to detect ``difference`` with ``power``.

    ``spread`` is the standard deviation of the per-run differences; the level
    is 0.05 / ``tests`` (a Bonferroni share of the figure's tests). The
    smallest n whose noncentral-t power reaches ``power``.
    """
    if difference == 0.0 or spread <= 0.0:
        raise ValueError("runs_for_power needs a non-zero difference and a positive spread")
    alpha = (1 - LEVEL) / tests
    effect = abs(difference) / spread
    for n in range(2, 100_000):
        critical = float(stats.t.ppf(1 - alpha / 2, n - 1))
        shift = effect * math.sqrt(n)
        reached = float(
            stats.nct.sf(critical, n - 1, shift) + stats.nct.cdf(-critical, n - 1, shift)
        )
        if reached >= power:
            return n
    raise ValueError("more than 100 000 runs needed")


@dataclass(frozen=True)
class PairedDifference:
    """``first − second`` over the same runs."""

    difference: Interval
    p_value: float
    spread: float = math.nan
    """Standard deviation of the per-run differences."""
    runs: int = 0

    def __str__(self) -> str:
        return f"{self.difference} (paired t, p = {self.p_value:.2g})"


def paired_difference(
    first: ArrayLike, second: ArrayLike, bounds: tuple[float, float] | None = None
) -> PairedDifference:
    """Mean paired difference of two per-run series, its t interval and the paired t test.

    ``bounds``: the range the difference can take (``(−1, 1)`` for two rates);
    the interval is clipped to it.
    """
    differences = (
        np.asarray(first, dtype=np.float64).ravel() - np.asarray(second, dtype=np.float64).ravel()
    )
    interval = mean_interval(differences)
    if bounds is not None:
        interval = Interval(
            interval.estimate,
            max(bounds[0], interval.low),
            min(bounds[1], interval.high),
        )
    if differences.size < 2 or float(differences.std(ddof=1)) == 0.0:
        # every run differs by the same amount: no t test; the exact two-sided sign test
        # (n runs all on one side: p = 2 · 2^−n), 1 when they are all equal
        same = float(np.abs(differences).max(initial=0.0)) == 0.0
        p_value = 1.0 if same else min(1.0, 2.0 * 0.5**differences.size)
    else:
        p_value = float(stats.ttest_1samp(differences, 0.0).pvalue)
    spread = float(differences.std(ddof=1)) if differences.size > 1 else math.nan
    return PairedDifference(interval, p_value, spread, int(differences.size))


BOOTSTRAP_RESAMPLES = 1000


def bootstrap_interval(
    statistic: Callable[[IntArray], FloatArray],
    runs: int,
    *,
    resamples: int = BOOTSTRAP_RESAMPLES,
    seed: int = 0,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Estimate and percentile-bootstrap 95 % interval of a statistic that pools the runs.

    For quantities that are not means of per-run values — an RMS over the runs
    ([DH] eq 28) and its time mean (eq 29) — the runs are resampled with
    replacement (seeded), ``statistic(rows)`` is recomputed on each resample
    and the 2.5 / 97.5 percentiles of the results are the interval.

    Parameters
    ----------
    statistic : callable (rows of the runs, int64) → ndarray
        The statistic of the runs at ``rows`` (any shape; NaN where undefined).
    runs : int
        Number of runs; ``statistic(arange(runs))`` is the estimate.

    Returns
    -------
    estimate, low, high : ndarray
        Shaped as the statistic's value.
    """
    estimate = np.asarray(statistic(np.arange(runs)), dtype=np.float64)
    rng = np.random.default_rng(seed)
    values = np.stack(
        [statistic(rng.integers(0, runs, size=runs)) for _ in range(resamples)]
    ).astype(np.float64)
    tail = 100 * (1 - LEVEL) / 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN cells stay NaN
        low, high = np.nanpercentile(values, [tail, 100 - tail], axis=0)
    return estimate, np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64)


def corrected(tests: Mapping[str, PairedDifference], family: str) -> str:
    """The figure's tests, each with its Holm-adjusted p (a family-wise 5 % level).

    One line per test: ``name: difference [interval] (p raw, p Holm over m tests)``
    and whether it survives; the header names the family and its size.
    """
    names = list(tests)
    adjusted = holm([tests[name].p_value for name in names])
    lines = [f"{family}: Holm over {len(names)} paired tests (family-wise 5 %)"]
    for name, p_holm in zip(names, adjusted, strict=True):
        test = tests[name]
        verdict = "significant" if p_holm <= 1 - LEVEL else "not significant"
        power = ""
        if p_holm > 1 - LEVEL and test.difference.estimate != 0.0 and test.spread > 0.0:
            needed = runs_for_power(test.difference.estimate, test.spread, tests=len(names))
            power = f"; 80 % power at this difference and spread needs {needed} runs"
        lines.append(
            f"  {name}: {test.difference} (paired t, p = {test.p_value:.2g}; "
            f"Holm p = {p_holm:.2g}, {verdict}{power})"
        )
    return "\n".join(lines)
