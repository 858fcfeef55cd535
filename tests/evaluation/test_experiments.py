"""Each experiment end to end on a reduced size, against the papers' qualitative claims."""

from __future__ import annotations

import numpy as np
import pytest

from core.simulation import aircraft_scenario
from evaluation.aircraft import aircraft_classification
from evaluation.four_targets import threshold_sweep
from evaluation.pedestrian import pedestrian_classification, stop_outcomes
from evaluation.two_class import class_comparison
from evaluation.units import noise_study, unit_sweep

RAMBLER, SPORTSMAN = 0, 1


def test_t2t_four_gnn_and_denoeux_fail_when_lambda_is_too_small() -> None:
    # [T2T] Fig 4: too small a λ (too large a γ) declares true partners new.
    sweep = threshold_sweep(seeds=(0, 1, 2), thresholds=(0.5, 4.0, 50.0), n_steps=8)
    assert sweep.gnn.shape == sweep.denoeux.shape == (3, 3)
    np.testing.assert_allclose(sweep.gammas, np.log(2.0) / np.array([0.5, 4.0, 50.0]))
    for rates in (sweep.gnn.mean(axis=0), sweep.denoeux.mean(axis=0)):
        assert rates[0] > 0.9
        assert rates[0] > rates[1] > rates[2]
        assert rates[2] < 0.15
    assert sweep.best("gnn")[0] == 50.0
    assert set(sweep.hachour) == {"density", "relative", "density, km"}
    assert all(rates.shape == (3,) for rates in sweep.hachour.values())


def test_t2t_two_class_class_information_lowers_the_false_decision_rate() -> None:
    # [T2T] Fig 6, for the credal method whose distance evidence works at this scale.
    comparison = class_comparison(
        seeds=(0, 1, 2, 3), n_steps=10, separation=1.0, tuning_thresholds=(8.0, 30.0)
    )
    assert "gnn" in comparison.mono and "gnn" not in comparison.multi
    assert set(comparison.thresholds) == {"gnn", "denoeux"}
    mono, multi = comparison.mono["denoeux"].mean(), comparison.multi["denoeux"].mean()
    assert multi < mono - 0.05
    assert multi < comparison.mono["gnn"].mean()


def test_unit_study_only_hachour_density_depends_on_the_unit() -> None:
    sweep = unit_sweep(seeds=(0, 1), scales=(1.0, 0.2, 1e-3), n_steps=6)
    for label in ("hachour relative", "gnn default", "denoeux default"):
        assert np.ptp(sweep.rates[label]) == 0.0
    assert np.ptp(sweep.rates["hachour density"]) > 0.3
    np.testing.assert_allclose(
        np.diff(sweep.implicit_gates),
        [8 * np.log(5.0), 8 * np.log(200.0)],  # ln|C| falls by 2q ln(1/s) = 8 ln(1/s)
    )

    study = noise_study(seeds=(0, 1), sigmas=(0.5, 2.0), n_steps=6, tuning_thresholds=(5.0, 40.0))
    for label in study.labels:
        metres, kilometres = study.rates[(label, "m")], study.rates[(label, "km")]
        if label == "hachour density":
            assert metres[0] > kilometres[0] + 0.3  # σ = 0.5 m: misses in m, fine in km
        else:
            np.testing.assert_array_equal(metres, kilometres)
    assert study.rates[("denoeux default", "m")][0] == 0.0
    assert set(study.best_thresholds) == {"gnn", "denoeux"}


def test_aircraft_credal_doubts_where_bayes_picks_a_side() -> None:
    # [MTT] Fig 14–15: both end on fighter; between the manoeuvres only the credal
    # classifier keeps bomber and fighter level.
    result = aircraft_classification(seeds=(0, 1))
    assert result.credal.shape == result.bayesian.shape == (2, len(result.steps), 3)
    assert result.doubt_gap("credal") < 0.05
    assert result.doubt_gap("bayesian") > 0.2
    for kind in ("credal", "bayesian"):
        assert 70 <= result.decision_step(kind) <= 76
    before = result.steps < 50
    np.testing.assert_allclose(result.credal[:, before], 1 / 3, atol=0.1)
    assert result.manoeuvres == ((50, 54, "2g"), (70, 75, "4g"))
    # The 20-run mean has no spread although each run has its own noise: the
    # behaviour plausibilities are 0 or 1 (decisive likelihood ratios at 0.2 m²).
    first, second = (aircraft_scenario(seed=seed).detections(2)[1] for seed in (0, 1))
    assert np.abs(first - second).max() > 0.1
    behaviours = result.behaviours[~np.isnan(result.behaviours)]
    assert np.mean((behaviours < 1e-9) | (behaviours > 1 - 1e-9)) > 0.99
    assert result.run_spread("credal") < 1e-6
    np.testing.assert_array_equal(result.decision_steps("credal"), [70.0, 70.0])
    # Fig 13, independently: Bayes' posterior is the normalised product of the steps'
    # behaviour likelihoods, and the scaled plausibilities are those likelihoods over a
    # per-step constant (coasting steps: no update).
    seen = np.where(np.isnan(result.behaviours), 1.0, result.behaviours)
    with np.errstate(divide="ignore"):
        log_product = np.cumsum(np.log(seen), axis=1)
    product = np.exp(log_product - log_product.max(axis=2, keepdims=True))
    expected = product / product.sum(axis=2, keepdims=True)
    np.testing.assert_allclose(result.bayesian_behaviours, expected, atol=1e-6)


def test_pedestrian_discounting_follows_the_class_changes() -> None:
    # [MTT]'s timing: the class change (the stop) at step 120.
    result = pedestrian_classification(seed=0)
    standard = result.traces["standard"]
    assert np.isnan(standard.first_step_above(RAMBLER, after=120))  # Fig 20: never follows the stop
    # "cannot even compute the pignistic probabilities after 120": the stop's evidence is in
    # (all but) total conflict with the run's — 1 − K below 1e-9 (0: BetP undefined).
    after = standard.steps >= 120
    assert np.min(1.0 - standard.step_conflicts[after]) < 1e-9
    sportsman = standard.probabilities[after, SPORTSMAN]
    assert np.all(np.isnan(sportsman) | (sportsman > 0.99))  # stuck on the run's class
    instantaneous = result.traces["instantaneous 0.3"]
    assert instantaneous.first_step_above(SPORTSMAN, after=40) < 50  # Fig 21: the run
    assert 120 < instantaneous.first_step_above(RAMBLER, after=120) < 239  # … and the stop
    cumulative = result.traces["cumulative 0.9, walks again"]
    assert cumulative.first_step_above(RAMBLER, after=120) <= 125  # forgets the run at once
    assert cumulative.probabilities[-1, RAMBLER] == pytest.approx(0.5, abs=0.05)  # Fig 22
    again = result.traces["instantaneous 0.9, walks again"]
    assert again.probabilities[-1, RAMBLER] > 0.99  # Fig 23
    assert [phase[:2] for phase in result.phases[:4]] == [
        (1, 39),
        (40, 119),
        (120, 239),
        (240, 299),
    ]
    assert [phase[2] for phase in result.phases] == ["walk", "run", "stop", "walk"]


def test_the_stop_is_never_followed_without_discounting_over_realisations() -> None:
    outcomes = stop_outcomes(seeds=(0, 1))
    assert not outcomes.follows.any()
    assert np.all(outcomes.closest_to_total < 1e-9)
    assert np.all((outcomes.rambler_from > 120) & (outcomes.rambler_from < 239))
