"""hachour with classes: the full [T2T] Table 1 (``*`` rows included) against enumeration.

The reference applies §3.6 from its definitions: the class conflict K of each
pair by intersecting focal sets, Pl(ℓ) = min(G, 1)(1 − K) (the class factor
after the clipping), Pl(*) = 1 − max_ℓ min(G, 1) (the class source says
nothing against "new"), the GBT mass by enumeration of subsets, BetP by its
definition, and the decision by enumerating every partial matching.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from core.association import associate
from core.belief import Frame, MassFunction

from .brute_force import best_matching, distances, hachour_table

LABELS = ("liner", "bomber", "fighter")
FRAME = Frame(list(LABELS))
TIE = 1e-9


def random_masses(rng: np.random.Generator, count: int) -> list[dict[frozenset[str], float]]:
    """Class masses as dictionaries: up to three random focal sets each."""
    subsets = [
        frozenset(label for bit, label in enumerate(LABELS) if mask >> bit & 1)
        for mask in range(1, 8)
    ]
    masses = []
    for _ in range(count):
        chosen = rng.choice(len(subsets), size=int(rng.integers(1, 4)), replace=False)
        weights = rng.dirichlet(np.ones(len(chosen)))
        masses.append({subsets[int(k)]: float(w) for k, w in zip(chosen, weights, strict=True)})
    return masses


def as_mass_function(mass: dict[frozenset[str], float]) -> MassFunction:
    return MassFunction.from_sets(FRAME, [(sorted(focal), value) for focal, value in mass.items()])


def instance(seed: int):
    rng = np.random.default_rng(seed)
    n, m = (int(v) for v in rng.integers(1, 5, size=2))
    scale = float(rng.choice([0.005, 0.05, 1.0]))  # small: G > 1, clipped

    def covariances(count: int) -> np.ndarray:
        a = rng.normal(size=(count, 2, 2)) * math.sqrt(scale)
        return a @ a.transpose(0, 2, 1) + scale * 0.3 * np.eye(2)

    box = float(rng.choice([1.0, 3.0])) * math.sqrt(scale)
    known = (rng.uniform(0, box, size=(n, 2)), covariances(n))
    incoming = (rng.uniform(0, box, size=(m, 2)), covariances(m))
    return known, incoming, random_masses(rng, n), random_masses(rng, m)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 2**32 - 1),
    likelihood=st.sampled_from(["density", "relative"]),
)
def test_table_with_classes_equals_enumeration(seed, likelihood):
    known, incoming, known_masses, incoming_masses = instance(seed)
    d, log_det = distances(*known, *incoming, kind="sum")
    expected = hachour_table(d, log_det, known_masses, incoming_masses, likelihood)
    n, m = d.shape
    result = associate(
        known,
        incoming,
        "hachour",
        {"likelihood": likelihood, "plausibility_floor": 0.0},
        known_classes=[as_mass_function(mass) for mass in known_masses],
        incoming_classes=[as_mass_function(mass) for mass in incoming_masses],
    )
    known_ids = [f"k{ell}" for ell in range(n)]
    incoming_ids = [f"i{t}" for t in range(m)]
    rows, cols, table = result.scores.table(known_ids, incoming_ids)
    assert rows == (*known_ids, *(f"*:{t}" for t in incoming_ids))
    assert cols == tuple(incoming_ids)
    np.testing.assert_allclose(table, expected, atol=1e-12)  # NaN where forbidden, both sides

    def objective(matching):  # eq 7: each column takes a known row or its own * row
        matched = {t: ell for ell, t in matching}
        return sum(
            expected[matched[t], t] if t in matched else expected[n + t, t] for t in range(m)
        )

    best, top, second = best_matching(n, m, objective)
    assume(top - second > TIE)
    assert set(result.assignment().items()) == best


def test_class_evidence_survives_clipping():
    """The vetoed track sits on the item, the right one farther; the factor acts after clipping.

    1-D, variances 0.001 (``sum``: C = 0.002): k0 (liner) at D = 0, G = 1/sqrt(2π·0.002) = 8.92;
    k1 (fighter) placed so that G = 0.9. The item is a fighter at 0.8: K(k0) = 0.8,
    K(k1) = 0. Pl(k0) = min(8.92, 1)·0.2 = 0.2, Pl(k1) = 0.9, Pl(*) = 1 − 1 = 0: k1.
    Factor before clipping, min(8.92·0.2, 1) = 1 > 0.9 would keep the vetoed k0.
    """
    variance = 0.001
    combined = 2 * variance
    offset = math.sqrt(-2 * combined * math.log(0.9 * math.sqrt(2 * math.pi * combined)))
    known = (np.array([[0.0], [offset]]), np.full((2, 1, 1), variance))
    incoming = (np.array([[0.0]]), np.full((1, 1, 1), variance))
    liner = MassFunction.from_sets(FRAME, [(["liner"], 1.0)])
    fighter = MassFunction.from_sets(FRAME, [(["fighter"], 1.0)])
    mostly_fighter = MassFunction.from_sets(FRAME, [(["fighter"], 0.8), (list(LABELS), 0.2)])
    result = associate(
        known,
        incoming,
        "hachour",
        {"maximise": "plausibility"},
        known_classes=[liner, fighter],
        incoming_classes=[mostly_fighter],
    )
    np.testing.assert_allclose(result.scores.dense()[:, 0], [0.2, 0.9], atol=1e-12)
    assert result.scores.new[0] == 0.0
    assert result.assignment() == {1: 0}
