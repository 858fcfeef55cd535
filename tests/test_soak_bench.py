"""``bench/soak.py --crowd``'s verdicts. The error rate: an increase of the honest client's
error rate beside the attacker fails only when it is significant; the one-sided p value is
checked against the hypergeometric tail summed by hand (``math.comb``), not against scipy.
The p99: its interval (a BCa bootstrap over pairs of phases) checked against
``scipy.stats.bootstrap`` and against the normal interval of a mean; the verdict fails only
when the interval is above 1.10. No timing is asserted (the load itself is ``make soak``'s)."""

from __future__ import annotations

import math
import os
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest
from scipy import stats

from evaluation.intervals import Interval
from tests.bench_scripts import load_bench


@pytest.fixture(scope="module")
def bench() -> ModuleType:
    return load_bench("soak")


def fisher_greater(failed_alone: int, alone: int, failed_attacked: int, attacked: int) -> float:
    """P(at least ``failed_attacked`` of the failures fall beside the attacker | the failures'
    total and each side's requests): the hypergeometric upper tail, term by term."""
    failures, total = failed_alone + failed_attacked, alone + attacked
    return sum(
        math.comb(attacked, k) * math.comb(alone, failures - k)
        for k in range(failed_attacked, min(failures, attacked) + 1)
    ) / math.comb(total, failures)


@pytest.mark.parametrize(
    ("counts", "ok"),
    [
        ((1, 1567, 1, 1205), True),  # one error each side: no evidence of an increase
        ((0, 1500, 0, 1500), True),
        ((3, 1500, 1, 1500), True),  # fewer beside the attacker
        ((0, 1646, 6, 1104), False),  # 0 → 6: significant
        ((2, 1500, 12, 1500), False),
    ],
)
def test_the_error_rate_fails_only_on_a_significant_increase(
    bench: ModuleType, counts: tuple[int, int, int, int], ok: bool
) -> None:
    verdict_ok, text = bench.error_verdict(*counts)
    assert verdict_ok is ok
    printed = re.search(r"Fisher exact p = (\S+):", text)
    assert printed is not None
    p_value = float(printed.group(1))
    assert p_value == pytest.approx(fisher_greater(*counts), rel=0.05)  # printed to 2 digits
    assert (p_value >= bench.SIGNIFICANCE) is ok
    assert ("FAILED" in text) is not ok
    assert f"{counts[0]}/{counts[1]} alone → {counts[2]}/{counts[3]}" in text


# The p99 rule: a BCa bootstrap over pairs of phases, checked against scipy.stats.bootstrap.


def phases(pairs: int, ratio: float, drift: float, seed: int) -> tuple[list[Any], list[Any]]:
    """``pairs`` alone and attacked phases of 400 lognormal latencies each (median 20 ms), each
    phase scaled by its own lognormal drift (sd ``drift``), the attacked ones by ``ratio``."""
    rng = np.random.default_rng(seed)

    def phase(scale: float) -> Any:
        return 0.02 * scale * math.exp(rng.normal(0, drift)) * rng.lognormal(0, 0.5, 400)

    return [phase(1.0) for _ in range(pairs)], [phase(ratio) for _ in range(pairs)]


def scipy_bca(
    statistic: Callable[[Any], float], pairs: int, resamples: int, level: float
) -> tuple[float, float]:
    """scipy's BCa interval of ``statistic`` over the indices of the pairs (the same bootstrap
    over pairs: scipy resamples the index array, its jackknife leaves out one index)."""
    result = stats.bootstrap(
        (np.arange(pairs),),
        lambda indices: statistic(indices.astype(int)),
        vectorized=False,
        n_resamples=resamples,
        method="BCa",
        confidence_level=level,
        rng=np.random.default_rng(7),
    )
    return float(result.confidence_interval.low), float(result.confidence_interval.high)


def test_the_pair_bootstrap_matches_scipy_on_a_ratio_of_means(bench: ModuleType) -> None:
    """A smooth statistic (the CPU-per-input kind: a ratio of sums over the pairs chosen): the
    two BCa intervals agree to within their resampling error (their seeds differ; the ends
    of 20 000 resamples move by ~0.5 % from seed to seed)."""
    rng = np.random.default_rng(3)
    cpu = rng.gamma(4, 0.5, (2, 8)) * np.array([[1.0], [1.3]])
    sent = rng.integers(400, 500, (2, 8)).astype(float)

    def ratio(pairs: Any) -> float:
        return float(
            (cpu[1, pairs].sum() / sent[1, pairs].sum())
            / (cpu[0, pairs].sum() / sent[0, pairs].sum())
        )

    mine = bench.pair_bootstrap(ratio, 8, resamples=20000)
    low, high = scipy_bca(ratio, 8, 20000, 0.95)
    assert mine.estimate == pytest.approx(ratio(np.arange(8)))
    assert mine.low == pytest.approx(low, rel=0.02)
    assert mine.high == pytest.approx(high, rel=0.02)


def test_the_pair_bootstrap_matches_scipy_on_a_ratio_of_p99s(bench: ModuleType) -> None:
    """The soak's own statistic (pooled p99 attacked / pooled p99 alone over the pairs chosen)
    on 8 drifting pairs: the two BCa intervals agree to within their resampling error (a
    quantile of a lumpy bootstrap distribution, other seeds: 3 %)."""
    alone, attacked = phases(8, 1.2, 0.15, seed=11)

    def ratio(pairs: Any) -> float:
        return float(
            bench.p99(np.concatenate([attacked[k] for k in pairs]))
            / bench.p99(np.concatenate([alone[k] for k in pairs]))
        )

    level = bench.expanded_level(8)  # as the soak asks it
    mine = bench.pair_bootstrap(ratio, 8, resamples=20000, level=level)
    low, high = scipy_bca(ratio, 8, 20000, level)
    assert mine.low == pytest.approx(low, rel=0.03)
    assert mine.high == pytest.approx(high, rel=0.03)
    assert mine.low < mine.estimate < mine.high


def test_the_pair_bootstrap_of_a_mean_is_the_normal_interval(bench: ModuleType) -> None:
    """A known case by hand: the mean of 400 normal values; its BCa interval is close to
    mean ± 1.96 s / √n (skewness nil, n large)."""
    values = np.random.default_rng(5).normal(10.0, 2.0, 400)
    interval = bench.pair_bootstrap(lambda pairs: float(values[pairs].mean()), 400, resamples=20000)
    half = 1.959964 * values.std() / math.sqrt(400)
    assert interval.low == pytest.approx(values.mean() - half, abs=0.05 * half)
    assert interval.high == pytest.approx(values.mean() + half, abs=0.05 * half)


def test_the_expanded_level_of_8_pairs() -> None:
    """By hand: t(7) at 0.975 is 2.364624 (tables); √(8/7) × 2.364624 = 2.527899; the two tails
    at Φ(−2.527899) = 0.0057365 each (erfc), so a 95 % interval over 8 pairs is computed at the
    98.853 % level."""
    tail = 0.5 * math.erfc(math.sqrt(8 / 7) * 2.364624 / math.sqrt(2))
    assert load_bench("soak").expanded_level(8) == pytest.approx(1 - 2 * tail, abs=1e-6)


def test_p99_is_the_printed_order_statistic(bench: ModuleType) -> None:
    latencies = np.random.default_rng(1).exponential(1.0, 1234)
    assert bench.p99(latencies) == sorted(latencies)[int(0.99 * 1233)]


@pytest.mark.parametrize(
    ("interval", "ok", "word"),
    [
        ((1.05, 0.98, 1.09), True, "ok"),
        ((1.10, 1.02, 1.10), True, "ok"),  # at the bound: within 10 %
        ((1.20, 1.12, 1.30), False, "FAILED"),
        ((1.18, 0.95, 1.40), True, "inconclusive"),  # 1.18 alone is no evidence
        ((1.15, 1.10, 1.21), True, "inconclusive"),  # the low end must be above 1.10
        ((0.90, 0.80, 1.15), True, "inconclusive"),
    ],
)
def test_the_p99_fails_only_when_significantly_above_ten_percent(
    bench: ModuleType, interval: tuple[float, float, float], ok: bool, word: str
) -> None:
    verdict_ok, text = bench.p99_verdict(Interval(*interval))
    assert verdict_ok is ok
    assert f": {word} " in text
    assert f"× {interval[0]:.2f} [{interval[1]:.2f}, {interval[2]:.2f}]" in text


def test_a_drift_between_phases_is_not_read_as_the_attackers(bench: ModuleType) -> None:
    """Monte Carlo: 40 runs of 8 pairs whose phases drift (sd 15 %, the spread a loaded
    machine gave) with no attacker effect at all. The old rule (pooled p99 ratio above 1.10)
    fails some runs; the interval's rule (at the soak's expanded level) fails none."""
    old = new = 0
    for seed in range(40):
        alone, attacked = phases(8, 1.0, 0.15, seed=100 + seed)

        def ratio(pairs: Any, alone: list[Any] = alone, attacked: list[Any] = attacked) -> float:
            return float(
                bench.p99(np.concatenate([attacked[k] for k in pairs]))
                / bench.p99(np.concatenate([alone[k] for k in pairs]))
            )

        old += ratio(np.arange(8)) > 1.10
        interval = bench.pair_bootstrap(ratio, 8, resamples=1000, level=bench.expanded_level(8))
        new += not bench.p99_verdict(interval)[0]
    assert old >= 3
    assert new == 0


def test_the_attacker_is_pinned_only_with_more_than_two_cores(
    bench: ModuleType, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Four usable cores: the attacker gets the last alone, the server and this process the
    other three; two cores: nothing is pinned, and the line says so."""
    pinned: dict[int, set[int]] = {}
    monkeypatch.setattr(bench, "pin_threads", lambda pid, cores: pinned.update({pid: cores}))
    monkeypatch.setattr(bench.os, "sched_getaffinity", lambda pid: {0, 1, 2, 3})
    core, line = bench.attacker_core(4242)
    assert core == 3
    assert pinned == {4242: {0, 1, 2}, os.getpid(): {0, 1, 2}}
    assert "pinned to core 3" in line
    pinned.clear()
    monkeypatch.setattr(bench.os, "sched_getaffinity", lambda pid: {0, 1})
    core, line = bench.attacker_core(4242)
    assert core is None and pinned == {}
    assert line.startswith("2 cores usable: the attacker is not pinned")


def allowed_cores(pid: int) -> dict[int, frozenset[int]]:
    """Each thread of ``pid`` → the cores the kernel lets it run on (``/proc``'s own list,
    e.g. ``0-1,3``)."""
    found = {}
    for task in Path(f"/proc/{pid}/task").iterdir():
        listed = re.search(r"^Cpus_allowed_list:\s*(\S+)", (task / "status").read_text(), re.M)
        assert listed is not None
        cores: set[int] = set()
        for part in listed[1].split(","):
            low, _, high = part.partition("-")
            cores.update(range(int(low), int(high or low) + 1))
        found[int(task.name)] = frozenset(cores)
    return found


@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="needs two usable cores")
def test_every_thread_of_the_server_is_pinned_not_only_its_first(
    bench: ModuleType, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Linux's sched_setaffinity(pid) sets the thread whose id is pid, not its process: the
    server has threads already when it is ready (4 on this machine: the loop's, the store's,
    the thread pool's), and each must leave the attacker's core. A child with a second
    thread, both held to core 1 first; ``attacker_core`` on cores {0, 1, 7} (the attacker on
    7) must let both run on 0-1 — read back from /proc/<pid>/task/*/status."""
    child = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import threading, time\n"
            "threading.Thread(target=time.sleep, args=(60,), daemon=True).start()\n"
            "print('ready', flush=True)\n"
            "time.sleep(60)\n",
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert child.stdout is not None and child.stdout.readline().strip() == "ready"
        first, second = sorted(os.sched_getaffinity(0))[:2]
        for thread in allowed_cores(child.pid):
            os.sched_setaffinity(thread, {second})
        assert len(allowed_cores(child.pid)) == 2
        mine = os.sched_getaffinity(0)
        monkeypatch.setattr(bench.os, "sched_getaffinity", lambda pid: {first, second, 7})
        try:
            core, _ = bench.attacker_core(child.pid)
        finally:
            os.sched_setaffinity(0, mine)
        assert core == 7
        assert set(allowed_cores(child.pid).values()) == {frozenset({first, second})}
    finally:
        child.kill()
        child.wait()


def test_a_statistic_outside_all_its_resamples_has_no_interval_and_is_inconclusive(
    bench: ModuleType,
) -> None:
    """Minus the number of distinct pairs drawn: the whole sample's (−10) is below every
    resample but the ~4000 · 10!/10¹⁰ ≈ 1.5 that draw each pair once, so z0 = Φ⁻¹(0) = −∞
    whenever none does — BCa is undefined (scipy's interval is NaN, checked here). The soak
    says so ("inconclusive", NaN ends), rather than stopping on a NaN quantile level."""

    def distinct(pairs: Any) -> float:
        return -float(len(np.unique(pairs)))

    with pytest.warns(Warning):
        low, high = scipy_bca(distinct, 10, 500, 0.95)
    assert math.isnan(low) and math.isnan(high)
    interval = bench.pair_bootstrap(distinct, 10, resamples=500)
    assert interval.estimate == -10.0
    assert math.isnan(interval.low) and math.isnan(interval.high)
    ok, line = bench.p99_verdict(interval)
    assert ok and "inconclusive" in line and "[nan, nan]" in line
