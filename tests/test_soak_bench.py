"""``bench/soak.py --crowd``'s error-rate verdict: an increase of the honest client's error
rate beside the attacker fails only when it is significant. The one-sided p value is checked
against the hypergeometric tail summed by hand (``math.comb``), not against scipy. No timing
is asserted (the load itself is ``make soak``'s)."""

from __future__ import annotations

import math
import re
from types import ModuleType

import pytest

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
