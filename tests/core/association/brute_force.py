"""Independent reference implementations for small problems (enumeration, no core shortcuts).

Every score is computed from the definitions: distances with numpy.linalg,
mass functions as dictionaries of frozensets, combinations by enumeration,
BetP by its definition, and the decision by enumerating every partial matching.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator

import numpy as np

STAR = "*"


def distances(known_x, known_p, incoming_x, incoming_p, kind="sum"):
    """D[ℓ, t] and log|C|[ℓ, t] straight from numpy.linalg."""
    w1, w2 = {"mean": (0.5, 0.5), "sum": (1.0, 1.0), "innovation": (1.0, 0.0)}[kind]
    n, m = len(known_x), len(incoming_x)
    d = np.zeros((n, m))
    log_det = np.zeros((n, m))
    for i in range(n):
        for j in range(m):
            c = w1 * known_p[i] + (w2 * incoming_p[j] if w2 else 0.0)
            delta = known_x[i] - incoming_x[j]
            d[i, j] = delta @ np.linalg.inv(c) @ delta
            log_det[i, j] = math.log(np.linalg.det(c))
    return d, log_det


def partial_matchings(n: int, m: int) -> Iterator[list[tuple[int, int]]]:
    """Every partial matching between range(n) and range(m)."""
    for size in range(min(n, m) + 1):
        for rows in itertools.combinations(range(n), size):
            for cols in itertools.permutations(range(m), size):
                yield list(zip(rows, cols, strict=True))


def best_matching(n: int, m: int, value) -> tuple[set[tuple[int, int]], float, float]:
    """The matching maximising ``value(matching)``; also the best and runner-up values."""
    scored = sorted(((value(mt), mt) for mt in partial_matchings(n, m)), key=lambda v: -v[0])
    best_value, best = scored[0]
    runner_up = next((v for v, mt in scored[1:] if set(mt) != set(best)), -math.inf)
    return set(best), best_value, runner_up


def conjunctive(first: dict, second: dict) -> dict:
    out: dict = {}
    for a, x in first.items():
        for b, y in second.items():
            out[a & b] = out.get(a & b, 0.0) + x * y
    return out


def betp(mass: dict, elements) -> dict:
    empty = mass.get(frozenset(), 0.0)
    out = dict.fromkeys(elements, 0.0)
    for focal, value in mass.items():
        for element in focal:
            out[element] += value / (len(focal) * (1.0 - empty))
    return out


def gbt(plausibility: dict) -> dict:
    """GBT by enumeration of every subset ([T2T] eq 6)."""
    elements = list(plausibility)
    mass = {}
    for size in range(len(elements) + 1):
        for subset in itertools.combinations(elements, size):
            value = 1.0
            for element in elements:
                p = plausibility[element]
                value *= p if element in subset else 1.0 - p
            mass[frozenset(subset)] = value
    return mass


def pairwise_mass(frame_elements, partner, a, b, c) -> dict:
    """The pairwise source on Θ = {Y_1..Y_n, *}: a on {Y_j}, b on Θ∖{Y_j}, c on Θ."""
    theta = frozenset(frame_elements)
    return {frozenset([partner]): a, theta - {partner}: b, theta: c}


def fuzzy(d: float, alpha: float, gamma: float = 0.5) -> tuple[float, float, float]:
    """[DH]'s fuzzy reading with s = exp(−γ d) (γ = 1/2: the fixed scale; ln 2 / gate: the gate's)."""
    s = math.exp(-gamma * d)
    a = alpha * max(0.0, 2 * s - 1)
    b = alpha * max(0.0, 1 - 2 * s)
    return a, b, 1 - a - b


def likelihood(d: float, alpha: float, gamma: float = 0.5) -> tuple[float, float, float]:
    s = math.exp(-gamma * d)
    return alpha * s, alpha * (1 - s), 1 - alpha


def combined_pairwise(partners, evidence) -> dict:
    """Conjunctive combination of the pairwise sources of one item, by enumeration."""
    elements = [*partners, STAR]
    mass = {frozenset(elements): 1.0}
    for partner in partners:
        mass = conjunctive(mass, pairwise_mass(elements, partner, *evidence[partner]))
    return mass


def conflict(first: dict[frozenset[str], float], second: dict[frozenset[str], float]) -> float:
    return sum(x * y for a, x in first.items() for b, y in second.items() if not a & b)


def hachour_table(d, log_det, known_masses, incoming_masses, likelihood, dimension=2):
    """[T2T] Table 1 of hachour with classes (§3.6), from the definitions.

    (n + m) × m: BetP of every known item, then the ``*_t`` rows (NaN off their
    column). Pl(ℓ) = min(G, 1)(1 − K) with K from intersecting focal sets,
    Pl(*) = 1 − max_ℓ min(G, 1); GBT and BetP by enumeration.

    An item whose every plausibility is 0 (Pl(*) = 0, every known item vetoed) has
    all its mass on ∅: its column is 0.
    """
    n, m = d.shape
    if likelihood == "relative":
        g = np.exp(-d / 2)
    else:
        g = np.exp(-d / 2) / np.sqrt((2 * math.pi) ** dimension * np.exp(log_det))
    table = np.full((n + m, m), np.nan)
    for t in range(m):
        plausibility: dict[object, float] = {
            ell: min(g[ell, t], 1.0) * (1.0 - conflict(known_masses[ell], incoming_masses[t]))
            for ell in range(n)
        }
        plausibility[STAR] = 1.0 - min(g[:, t].max(), 1.0)
        if max(plausibility.values()) == 0.0:  # m(∅) = 1: BetP undefined, scored 0
            table[:n, t] = 0.0
            table[n + t, t] = 0.0
            continue
        values = betp(gbt(plausibility), list(plausibility))
        table[:n, t] = [values[ell] for ell in range(n)]
        table[n + t, t] = values[STAR]
    return table
