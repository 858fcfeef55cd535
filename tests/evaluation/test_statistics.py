"""The statistics helpers of :mod:`evaluation.intervals` against scipy.stats on known cases.

Independent references: ``scipy.stats.binomtest(...).proportion_ci`` (Wilson,
Clopper–Pearson), the Poisson tail probabilities of ``scipy.stats.poisson``
at the interval's ends, ``scipy.stats.bootstrap``, ``scipy.stats.ttest_1samp``,
Holm's procedure written out as its definition (sequential rejection), and the
published worked examples of Newcombe's interval for a difference of rates.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy import stats

from evaluation.intervals import (
    bonferroni,
    clopper_pearson,
    count_interval,
    holm,
    paired_difference,
    poisson_interval,
    rate_difference,
    rate_interval,
    runs_for_power,
    wilson,
)

BINOMIAL_CASES = [(0, 20), (1, 20), (7, 20), (20, 20), (0, 630), (3, 1000), (50, 100)]


@pytest.mark.parametrize(("successes", "trials"), BINOMIAL_CASES)
def test_wilson_and_clopper_pearson_equal_scipy(successes: int, trials: int) -> None:
    result = stats.binomtest(successes, trials)
    for ours, method in ((wilson, "wilson"), (clopper_pearson, "exact")):
        reference = result.proportion_ci(confidence_level=0.95, method=method)
        assert ours(successes, trials) == pytest.approx((reference.low, reference.high), abs=1e-12)


@pytest.mark.parametrize("count", [0, 1, 2, 5, 17, 120])
def test_poisson_interval_has_the_exact_tails(count: int) -> None:
    low, high = poisson_interval(count)
    # Garwood: P(X ≥ k | low) = 0.025 and P(X ≤ k | high) = 0.025
    assert stats.poisson.cdf(count, high) == pytest.approx(0.025, abs=1e-10)
    if count == 0:
        assert low == 0.0
        assert high == pytest.approx(-np.log(0.025), rel=1e-12)  # 3.689
    else:
        assert stats.poisson.sf(count - 1, low) == pytest.approx(0.025, abs=1e-10)


def test_count_interval_never_below_zero_and_covers_scipys_bootstrap() -> None:
    zeros = count_interval(np.zeros(20))
    assert (zeros.estimate, zeros.low) == (0.0, 0.0)
    assert zeros.high == pytest.approx(-np.log(0.025) / 20, rel=1e-12)  # the Poisson end
    # mostly zeros, the case where a t interval went below 0 (0.75 [−0.71, 2.21])
    counts = np.array([0] * 17 + [1, 2, 12], dtype=float)
    t_low = counts.mean() - stats.t.ppf(0.975, 19) * counts.std(ddof=1) / np.sqrt(20)
    assert t_low < 0.0
    ours = count_interval(counts)
    assert ours.estimate == pytest.approx(0.75) and ours.low >= 0.0
    reference = stats.bootstrap(
        (counts,), np.mean, method="percentile", n_resamples=20_000, random_state=1
    ).confidence_interval
    # the hull contains scipy's percentile interval (up to the resampling noise)
    assert ours.low <= reference.low + 0.05 and ours.high >= reference.high - 0.1
    with pytest.raises(ValueError):
        count_interval([1.0, -1.0])


def test_rate_interval_stays_in_the_unit_interval() -> None:
    all_zero = rate_interval(np.zeros(10), 63)
    assert all_zero.low == 0.0 and all_zero.estimate == 0.0
    assert all_zero.high == pytest.approx(wilson(0, 630)[1])
    all_one = rate_interval(np.ones(10), 63)
    assert all_one.high == 1.0


def holm_by_definition(p: list[float], level: float = 0.05) -> set[int]:
    """Reject H_(1), H_(2), … while p_(i) ≤ level / (m − i + 1); stop at the first failure."""
    order = sorted(range(len(p)), key=lambda i: p[i])
    rejected: set[int] = set()
    for rank, index in enumerate(order):
        if p[index] > level / (len(p) - rank):
            break
        rejected.add(index)
    return rejected


def test_holm_rejects_what_the_definition_rejects() -> None:
    # [T2T] Fig 6's six tests (p of the distance-vs-class comparisons quoted before)
    six = [0.012, 0.023, 0.025, 4e-5, 0.17, 0.5]
    assert holm(six) == pytest.approx([0.06, 0.092, 0.092, 2.4e-4, 0.34, 0.5])
    assert bonferroni(six) == pytest.approx([0.072, 0.138, 0.15, 2.4e-4, 1.0, 1.0])
    rng = np.random.default_rng(0)
    for _ in range(200):
        p = list(rng.uniform(0, 0.06, size=int(rng.integers(1, 8))))
        assert set(np.flatnonzero(holm(p) <= 0.05)) == holm_by_definition(p)
    assert holm([]).size == 0


def test_paired_difference_is_scipys_paired_t() -> None:
    rng = np.random.default_rng(3)
    first, second = rng.normal(0.1, 1, 30), rng.normal(0, 1, 30)
    ours = paired_difference(first, second)
    reference = stats.ttest_rel(first, second)
    assert ours.p_value == pytest.approx(reference.pvalue, rel=1e-12)
    low, high = reference.confidence_interval(0.95)
    assert (ours.difference.low, ours.difference.high) == pytest.approx((low, high), rel=1e-12)


def test_constant_differences_get_the_exact_sign_test() -> None:
    # every run one better: no spread for a t test; the sign test's p is binomtest's
    for runs in (2, 5, 20):
        ours = paired_difference(np.ones(runs), np.zeros(runs))
        assert ours.p_value == pytest.approx(stats.binomtest(runs, runs).pvalue, rel=1e-12)
    assert paired_difference(np.zeros(4), np.zeros(4)).p_value == 1.0


def test_runs_for_power_reaches_the_power_by_simulation_free_check() -> None:
    # effect 0.5 σ at level 0.05, power 0.8: the textbook answer is n = 34 (paired t)
    n = runs_for_power(0.5, 1.0)
    assert n == 34
    for m, target in itertools.product((n - 1, n), (0.8,)):
        critical = stats.t.ppf(0.975, m - 1)
        power = stats.nct.sf(critical, m - 1, 0.5 * np.sqrt(m)) + stats.nct.cdf(
            -critical, m - 1, 0.5 * np.sqrt(m)
        )
        assert (power >= target) == (m == n)
    assert runs_for_power(0.5, 1.0, tests=6) > n  # a Bonferroni share of six tests


NEWCOMBE_TABLE_II = [
    # (a successes, a trials, b successes, b trials, low, high): Newcombe (1998), Stat Med
    # 17:873-890, Table II, method 10 (hybrid score, no continuity correction), for b − a
    (48, 80, 56, 70, 0.0524, 0.3339),
    (3, 10, 9, 10, 0.1705, 0.8090),
    (2, 7, 6, 7, 0.0582, 0.8062),
    (0, 29, 5, 56, -0.0381, 0.1926),
    (0, 20, 0, 10, -0.1611, 0.2775),
    (0, 10, 0, 10, -0.2775, 0.2775),
    (0, 20, 10, 10, 0.6791, 1.0000),
    (0, 10, 10, 10, 0.6075, 1.0000),
]


@pytest.mark.parametrize(("ka", "na", "kb", "nb", "low", "high"), NEWCOMBE_TABLE_II)
def test_rate_difference_is_newcombes_published_interval(
    ka: int, na: int, kb: int, nb: int, low: float, high: float
) -> None:
    interval = rate_difference(ka, na, kb, nb)
    assert interval.estimate == pytest.approx(kb / nb - ka / na, abs=1e-15)
    assert (interval.low, interval.high) == pytest.approx((low, high), abs=5e-5)
