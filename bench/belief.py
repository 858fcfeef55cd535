"""Belief-function core: fast exact BetP vs enumeration, and the conjunctive rule.

Run with ``make bench`` (or ``python bench/belief.py``). Prints tables; never
asserts a time.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from machine import describe_machine, median_ms

from core.belief import Frame, MassFunction, conjunctive, gbt_betp


def enumeration_betp(p: np.ndarray) -> np.ndarray:
    """BetP of the GBT mass by enumerating all 2^N subsets (vectorised in chunks)."""
    n = len(p)
    betp = np.zeros(n)
    total = 0.0
    chunk = 1 << 16
    shifts = np.arange(n, dtype=np.int64)
    for start in range(1, 1 << n, chunk):
        masks = np.arange(start, min(start + chunk, 1 << n), dtype=np.int64)
        member = (masks[:, None] >> shifts) & 1 == 1
        mass = np.prod(np.where(member, p, 1.0 - p), axis=1)
        total += mass.sum()
        betp += (mass / member.sum(axis=1)) @ member
    return betp / total


def random_mass(frame: Frame, focal: int, rng: np.random.Generator) -> MassFunction:
    masks = rng.choice(np.arange(1, frame.full + 1), size=focal, replace=False)
    weights = rng.random(focal)
    return MassFunction.from_masks(frame, masks, weights / weights.sum())


def main() -> None:
    rng = np.random.default_rng(0)
    print(describe_machine())
    print("\nExact BetP of a GBT mass (ms, median)")
    print(f"{'N':>6} {'fast O(N²)':>12} {'enumeration':>12} {'max |diff|':>12}")
    for n in (10, 14, 16, 18, 20, 100, 1000):
        p = rng.uniform(0.0, 1.0, n)
        fast_ms = median_ms(lambda p=p: gbt_betp(p))
        if n <= 20:
            enum_ms = median_ms(lambda p=p: enumeration_betp(p), repeat=3, budget_s=0.0)
            fast = gbt_betp(p)
            assert fast is not None
            diff = float(np.max(np.abs(fast - enumeration_betp(p))))
            print(f"{n:>6} {fast_ms:>12.3f} {enum_ms:>12.3f} {diff:>12.1e}")
        else:
            print(f"{n:>6} {fast_ms:>12.3f} {'-':>12} {'-':>12}")

    print("\nConjunctive rule, two mass functions with F focal sets each (ms, median)")
    print(f"{'|Ω|':>4} {'F':>6} {'ms':>10} {'result focal sets':>18}")
    for size in (3, 8, 16):
        frame = Frame([f"c{i}" for i in range(size)])
        for focal in (10, 100, 1000):
            f = min(focal, frame.full)  # a frame of 3 labels has only 7 non-empty subsets
            first, second = random_mass(frame, f, rng), random_mass(frame, f, rng)
            ms = median_ms(lambda a=first, b=second: conjunctive(a, b))
            shown = f"{f}" if f == focal else f"{f}*"
            print(f"{size:>4} {shown:>6} {ms:>10.3f} {len(conjunctive(first, second)):>18}")
    print("(* capped at the number of non-empty subsets of the frame)")


if __name__ == "__main__":
    main()
