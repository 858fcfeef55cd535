"""Transition models against hand-worked matrices, Stone Soup and Van Loan's integral.

Oracles: constant velocity and constant position against F and Q worked by hand and
against Stone Soup's ``ConstantVelocity`` / ``RandomWalk``; Singer against Stone Soup's
``Singer`` (its Q by numerical quadrature of ``∫ F(t) e₃ e₃ᵀ F(t)ᵀ dt``) where Stone
Soup's F is accurate (αΔt ≥ 0.05: its closed-form F cancels below), and everywhere
against Van Loan's matrix exponential (scipy's ``expm``), which shares no formula with
the closed form or its series; the mapping against Stone Soup's
``CombinedLinearGaussianTransitionModel`` with the state permuted.
"""

from __future__ import annotations

import datetime

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal
from scipy.linalg import expm
from stonesoup.models.transition.linear import (
    CombinedLinearGaussianTransitionModel,
    RandomWalk,
)
from stonesoup.models.transition.linear import (
    ConstantVelocity as StoneSoupConstantVelocity,
)
from stonesoup.models.transition.linear import (
    Singer as StoneSoupSinger,
)

from core.errors import InvalidInput
from core.fusion.motion import MotionKind
from core.models import (
    TRANSITION_MODELS,
    ConstantPosition,
    ConstantVelocity,
    MappedMotion,
    Singer,
    StateLayout,
    TransitionModel,
)
from core.models.singer import ACCELERATION_STD, GRAVITY, MANOEUVRE_TIME


def seconds(dt: float) -> datetime.timedelta:
    return datetime.timedelta(seconds=dt)


def test_constant_velocity_is_the_closed_form_worked_by_hand() -> None:
    # q = 0.7, Δt = 2: F = [[1, 2], [0, 1]], Q = 0.7 [[8/3, 2], [2, 2]]
    transition, noise = ConstantVelocity(q=0.7).matrices(np.array(2.0))
    assert_array_equal(transition, [[1.0, 2.0], [0.0, 1.0]])
    assert_allclose(noise, [[0.7 * 8 / 3, 1.4], [1.4, 1.4]], rtol=1e-15)
    # backwards: F(−2), Q(2)
    back_f, back_q = ConstantVelocity(q=0.7).matrices(np.array(-2.0))
    assert_array_equal(back_f, [[1.0, -2.0], [0.0, 1.0]])
    assert_array_equal(back_q, noise)


@pytest.mark.parametrize("dt", [0.0, 0.25, 1.0, 12.0, 3000.0])
def test_white_noise_models_match_stone_soup(dt: float) -> None:
    cv_f, cv_q = ConstantVelocity(q=3.5).matrices(np.array(dt))
    reference = StoneSoupConstantVelocity(noise_diff_coeff=3.5)
    assert_allclose(cv_f, reference.matrix(seconds(dt)), rtol=1e-15)
    assert_allclose(cv_q, reference.covar(seconds(dt)), rtol=1e-14)
    cp_f, cp_q = ConstantPosition(q=3.5).matrices(np.array(dt))
    walk = RandomWalk(noise_diff_coeff=3.5)
    assert_allclose(cp_f, walk.matrix(seconds(dt)), rtol=1e-15)
    assert_allclose(cp_q, walk.covar(seconds(dt)), rtol=1e-14)


def van_loan(model: Singer, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """F and Q of ``ẋ = A x + G w`` by Van Loan's exponential of [[−A, q G Gᵀ], [0, Aᵀ]] Δt."""
    alpha = 1.0 / model.manoeuvre_time
    a = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -alpha]])
    g = np.array([[0.0], [0.0], [1.0]])
    block = np.zeros((6, 6))
    block[:3, :3] = -a
    block[:3, 3:] = 2.0 * alpha * model.acceleration_std**2 * (g @ g.T)
    block[3:, 3:] = a.T
    exponential = expm(block * dt)
    transition = exponential[3:, 3:].T
    return transition, transition @ exponential[:3, 3:]


SINGERS = [Singer(), Singer(1.0, 5.0), Singer(60.0, 3.0), Singer(200.0, 30.0)]


@pytest.mark.parametrize(
    ("model", "dt"),
    [
        (model, dt)
        for model in SINGERS
        for dt in (1.0, 2.5, 7.0, 21.0, 60.0)
        if dt / model.manoeuvre_time >= 0.05  # Stone Soup's F cancels below (Van Loan covers it)
    ],
)
def test_singer_matches_stone_soup(model: Singer, dt: float) -> None:
    alpha = 1.0 / model.manoeuvre_time
    reference = StoneSoupSinger(damping_coeff=alpha, noise_diff_coeff=model.q)
    transition, noise = model.matrices(np.array(dt))
    assert_allclose(transition, reference.matrix(seconds(dt)), rtol=1e-12, atol=1e-300)
    assert_allclose(noise, reference.covar(seconds(dt)), rtol=1e-9)


@pytest.mark.parametrize(
    ("model", "dt"),
    [
        (model, dt)
        for model in SINGERS
        for dt in (1e-6, 1e-3, 0.05, 0.5, 0.99, 1.0, 1.01, 3.0, 19.9, 20.1, 40.0)
        # Van Loan's block holds e^{+αΔt}: exact to ~1e-12 up to αΔt = 2 (Stone Soup beyond)
        if dt / model.manoeuvre_time <= 2.0
    ],
)
def test_singer_matches_van_loan_on_both_sides_of_the_series(model: Singer, dt: float) -> None:
    expected_f, expected_q = van_loan(model, dt)
    transition, noise = model.matrices(np.array(dt))
    assert_allclose(transition, expected_f, rtol=1e-11, atol=1e-13 * np.abs(expected_f).max())
    # entries down to Δt⁵/20 ~ 1e-31: relative, per entry
    assert_allclose(noise, expected_q, rtol=1e-8, atol=0.0)
    # backwards: F(−Δt) undoes F(Δt); Q(|Δt|)
    back_f, back_q = model.matrices(np.array(-dt))
    assert_allclose(back_f @ transition, np.eye(3), atol=1e-9)
    assert_array_equal(back_q, noise)


def test_singer_defaults_are_the_documented_physics() -> None:
    # σ_m² = A_max²/3 (1 + 4 P_max − P_0), A_max = 4 g, P_max = 0.05, P_0 = 0.5:
    # (39.2266 m/s²)² × 0.7 / 3 = 359.03, σ_m = 18.948 m/s²
    assert pytest.approx(18.948248, abs=1e-6) == ACCELERATION_STD
    assert pytest.approx(np.sqrt((4 * GRAVITY) ** 2 * 0.7 / 3), rel=1e-15) == ACCELERATION_STD
    assert MANOEUVRE_TIME == 20.0
    assert Singer().q == pytest.approx(2.0 / 20.0 * ACCELERATION_STD**2, rel=1e-15)


def test_singer_long_gap_forgets_the_acceleration_and_stays_finite() -> None:
    transition, noise = Singer().matrices(np.array(1e6))
    assert transition[2, 2] == 0.0
    assert np.isfinite(noise).all()
    # the velocity's variance grows like 2 σ_m² τ Δt (a random walk of the velocity)
    assert noise[1, 1] == pytest.approx(2.0 * ACCELERATION_STD**2 * 20.0 * 1e6, rel=1e-4)


@pytest.mark.parametrize("model", [ConstantVelocity(0.3), ConstantPosition(0.3), Singer()])
def test_matrices_are_batched_over_any_shape_of_time_steps(model: TransitionModel) -> None:
    steps = np.array([[0.0, 0.4, -3.0], [12.0, 25.0, 0.9]])
    transition, noise = model.matrices(steps)
    k = len(model.components)
    assert transition.shape == noise.shape == (2, 3, k, k)
    for index in np.ndindex(steps.shape):
        one_f, one_q = model.matrices(steps[index])
        assert_array_equal(transition[index], one_f)
        assert_array_equal(noise[index], one_q)


def test_mapping_places_each_axis_block_like_stone_soups_combined_model() -> None:
    # session order [y, x, ẋ, a_y, ẏ, a_x, extra]: the blocks (x, ẋ, a_x) and (y, ẏ, a_y)
    layout = StateLayout(7, position=(1, 0), velocity=(2, 4), acceleration=(5, 3))
    model = Singer(15.0, 8.0)
    motion = MappedMotion(layout, model)
    reference = StoneSoupSinger(damping_coeff=1.0 / 15.0, noise_diff_coeff=model.q)
    combined = CombinedLinearGaussianTransitionModel([reference, reference])
    order = [1, 2, 5, 0, 4, 3]  # the combined model's [x, ẋ, a_x, y, ẏ, a_y] in the layout
    transition, noise = motion.matrices(np.array(4.0))
    assert_allclose(
        transition[np.ix_(order, order)], combined.matrix(time_interval=seconds(4.0)), rtol=1e-12
    )
    assert_allclose(
        noise[np.ix_(order, order)], combined.covar(time_interval=seconds(4.0)), rtol=1e-9
    )
    assert transition[6, 6] == 1.0 and not transition[6, :6].any() and not transition[:6, 6].any()
    assert not noise[6].any() and not noise[:, 6].any()


def test_a_layout_without_the_models_components_is_refused() -> None:
    with pytest.raises(InvalidInput, match="acceleration components"):
        MappedMotion(StateLayout(4, (0, 2), (1, 3)), Singer())
    with pytest.raises(InvalidInput, match="one acceleration component per velocity"):
        StateLayout(6, (0, 3), (1, 4), (2,))


def test_every_registered_model_has_defaults_and_starts_with_a_position() -> None:
    for name, build in TRANSITION_MODELS.items():
        model = build()
        assert isinstance(model, TransitionModel), name
        assert model.components[0] == "position", name


def test_the_sessions_model_names_are_the_registrys() -> None:
    assert {kind.value for kind in MotionKind} == set(TRANSITION_MODELS)
