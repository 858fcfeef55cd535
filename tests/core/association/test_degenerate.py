"""Degenerate inputs and option validation."""

from __future__ import annotations

import numpy as np
import pytest

from core.association import associate, associate_measurements
from core.errors import CovarianceError, InvalidInput, OptionError

METHODS = ["gnn", "denoeux", "hachour", "mercier", "dang_han"]


def side(states, variance=1.0):
    states = np.asarray(states, dtype=float).reshape(-1, 2)
    return states, np.tile(variance * np.eye(2), (len(states), 1, 1))


@pytest.mark.parametrize("method", METHODS)
def test_empty_sides(method):
    empty = (np.zeros((0, 2)), np.zeros((0, 2, 2)))
    some = side([[0.0, 0.0], [5.0, 5.0]])
    result = associate(empty, some, method)
    assert result.pairs == []
    np.testing.assert_array_equal(result.new, [0, 1])
    assert len(result.missed) == 0
    result = associate(some, empty, method)
    np.testing.assert_array_equal(result.missed, [0, 1])
    assert len(result.new) == 0
    result = associate(empty, empty, method)
    assert result.pairs == [] and result.scores.dense().shape == (0, 0)


@pytest.mark.parametrize("method", METHODS)
def test_one_item_identical_states(method):
    # D = 0: every method matches; denoeux's w stays finite (pl(0) floored)
    one = side([[1.0, 2.0]], 0.01)
    result = associate(one, one, method)
    assert result.assignment() == {0: 0}
    assert np.isfinite(result.pair_score).all()


@pytest.mark.parametrize("method", METHODS)
def test_duplicate_known_items_are_deterministic(method):
    known = side([[0.0, 0.0], [0.0, 0.0]], 0.01)
    incoming = side([[0.01, 0.0]], 0.01)
    first = associate(known, incoming, method)
    second = associate(known, incoming, method)
    assert first.assignment() == second.assignment()
    assert len(first.pairs) <= 1


@pytest.mark.parametrize(
    ("covariance", "message"),
    [
        ([[1.0, 1.0], [1.0, 1.0]], "not positive definite"),  # singular
        ([[1.0, 0.0], [0.0, -2.0]], "not positive definite"),  # indefinite
        ([[1.0, 0.5], [0.0, 1.0]], "not symmetric"),
        ([[0.0, 0.0], [0.0, 0.0]], "not positive definite"),
    ],
)
def test_bad_covariance_is_a_clear_error(covariance, message):
    good = side([[0.0, 0.0], [1.0, 1.0]])
    bad = (good[0], np.array([np.eye(2), covariance]))
    with pytest.raises(CovarianceError, match=rf"incoming\[1\]\.covariance is {message}"):
        associate(good, bad, "denoeux")
    with pytest.raises(CovarianceError, match=rf"known\[1\]\.covariance is {message}"):
        associate(bad, good, "gnn")


def test_nan_is_a_clear_error():
    good = side([[0.0, 0.0], [1.0, 1.0]])
    with pytest.raises(InvalidInput, match=r"incoming\[1\]\.state is not finite"):
        associate(good, (np.array([[0.0, 0.0], [np.nan, 1.0]]), good[1]), "hachour")
    covariances = good[1].copy()
    covariances[0, 0, 1] = np.inf
    with pytest.raises(InvalidInput, match=r"known\[0\]\.covariance is not finite"):
        associate((good[0], covariances), good, "hachour")


def test_shape_errors():
    good = side([[0.0, 0.0]])
    with pytest.raises(InvalidInput, match="dimension"):
        associate(good, (np.zeros((1, 3)), np.eye(3)[None]), "gnn")
    with pytest.raises(InvalidInput, match="covariances must have shape"):
        associate(good, (np.zeros((1, 2)), np.eye(2)), "gnn")
    with pytest.raises(InvalidInput, match="covariances are required"):
        associate(good, (np.zeros((1, 2)), None), "gnn")


@pytest.mark.parametrize(
    ("method", "options", "message"),
    [
        ("gnn", {"threshold": -1.0}, "'threshold' must lie in"),
        ("gnn", {"threshold": 3.0, "gate_probability": 0.9}, "at most one"),
        ("gnn", {"gate_probability": 1.0}, "'gate_probability' must lie in"),
        ("gnn", {"gamma": 1.0}, "unknown option"),
        ("denoeux", {"alpha": 1.5}, "'alpha' must lie in"),
        ("denoeux", {"gamma": "big"}, "'gamma' must be a number"),
        ("hachour", {"likelihood": "pdf"}, "'likelihood' must be one of"),
        ("hachour", {"maximise": "belief"}, "'maximise' must be one of"),
        ("mercier", {"evidence": "other"}, "'evidence' must be one of"),
        ("dang_han", {"score": "max"}, "'score' must be one of"),
        ("dang_han", {"alpha": 0.0}, "'alpha' must lie in"),
    ],
)
def test_option_errors_name_the_option(method, options, message):
    good = side([[0.0, 0.0]])
    with pytest.raises(OptionError, match=message) as error:
        associate(good, good, method, options)
    assert method in str(error.value)


def test_unknown_method_and_distance():
    good = side([[0.0, 0.0]])
    with pytest.raises(InvalidInput, match="unknown association method"):
        associate(good, good, "jpda")
    with pytest.raises(InvalidInput, match="distance must be one of"):
        associate(good, good, "gnn", distance="euclid")


def test_measurement_to_track():
    # tracks ẑ = (0,0), (10,0) with S = I; measurements z = (0.5, 0), (30, 0)
    # D = 0.25 for (0, 0); every other pair is beyond chi2.ppf(0.999, 2) = 13.8155
    result = associate_measurements(
        np.array([[0.0, 0.0], [10.0, 0.0]]),
        np.tile(np.eye(2), (2, 1, 1)),
        np.array([[0.5, 0.0], [30.0, 0.0]]),
    )
    assert result.method == "gnn"
    assert result.pairs == [(0, 0, pytest.approx(0.25))]
    np.testing.assert_array_equal(result.new, [1])
    np.testing.assert_array_equal(result.missed, [1])


def test_dang_han_best_partner_rule_by_hand() -> None:
    """Highest score above ``*`` and > 0, ties to the lowest partner; total conflict chooses ``*``."""
    from core.association.dang_han import best_partner

    items = np.array([0, 0, 0, 1, 1, 2, 3], dtype=np.int64)
    partners = np.array([4, 2, 7, 1, 0, 5, 6], dtype=np.int64)
    values = np.array([0.3, 0.3, 0.1, 0.2, 0.25, 0.4, 0.9])
    star = np.array([0.1, 0.22, 0.5, 0.0])
    defined = np.array([True, True, True, False])
    chosen = best_partner(items, partners, values, star, defined, 5)
    # item 0: a tie at 0.3 between partners 4 and 2 -> 2; item 1: only 0.25 is above * -> 0;
    # item 2: below * -> none; item 3: total conflict -> none; item 4: no pairs -> none
    np.testing.assert_array_equal(chosen, [2, 0, -1, -1, -1])
