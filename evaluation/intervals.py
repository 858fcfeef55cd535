"""95 % intervals over Monte Carlo runs, and the paired comparison of two methods.

Runs are the unit of replication: the decisions of one run share its noise
realisation and are not independent. So a rate's interval is the hull of

- the Student-t interval of the per-run rates (honest about the correlation
  within a run), and
- the Wilson score interval of the pooled decisions (never of zero width, as
  the t interval is when every run gives the same rate),

and an error's interval is the t interval of its per-run values. Two methods
run on the same realisations are compared by the paired difference of their
per-run values: its mean, t interval and the two-sided p value of the paired
t test.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
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


def rate_interval(per_run: ArrayLike, decisions_per_run: ArrayLike) -> Interval:
    """A rate over runs: the decision-weighted mean, with the hull of the t and Wilson intervals."""
    rates = np.asarray(per_run, dtype=np.float64).ravel()
    counts = np.broadcast_to(np.asarray(decisions_per_run, dtype=np.float64), rates.shape)
    trials = float(counts.sum())
    estimate = float((rates * counts).sum() / trials) if trials > 0 else float(rates.mean())
    t_low, t_high = _t_interval(rates)
    w_low, w_high = wilson(estimate * trials, trials)
    return Interval(estimate, max(0.0, min(t_low, w_low)), min(1.0, max(t_high, w_high)))


def mean_interval(per_run: ArrayLike) -> Interval:
    """The mean of a per-run quantity (an error, a count) with its t interval."""
    values = np.asarray(per_run, dtype=np.float64).ravel()
    low, high = _t_interval(values)
    return Interval(float(values.mean()), low, high)


@dataclass(frozen=True)
class PairedDifference:
    """``first − second`` over the same runs."""

    difference: Interval
    p_value: float

    def __str__(self) -> str:
        return f"{self.difference} (paired t, p = {self.p_value:.2g})"


def paired_difference(first: ArrayLike, second: ArrayLike) -> PairedDifference:
    """Mean paired difference of two per-run series, its t interval and the paired t test."""
    differences = (
        np.asarray(first, dtype=np.float64).ravel() - np.asarray(second, dtype=np.float64).ravel()
    )
    interval = mean_interval(differences)
    if differences.size < 2 or float(differences.std(ddof=1)) == 0.0:
        p_value = 1.0 if float(np.abs(differences).max(initial=0.0)) == 0.0 else 0.0
    else:
        p_value = float(stats.ttest_1samp(differences, 0.0).pvalue)
    return PairedDifference(interval, p_value)


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
