"""p, the probability that a sensor sees a track's predicted position N(x̂, P), and the miss it
scores, ln(p_region − P_D p) (docs/algorithms.md §8.16).

Oracles, none of them the code under test: scipy's bivariate normal CDF over a rectangle
(``multivariate_normal.cdf`` with lower limits) for polygons, the noncentral χ² for a disc
with an isotropic covariance, seeded Monte Carlo over the geometry's own ``contains`` for
sectors and 3-D radar volumes, the normal CDF worked by hand (``math.erf``) for the miss.
Where the region's nearest limit is a straight edge and every other limit far, p is exact;
near a curved limit (the range circle) or a corner it is an approximation, bounded here.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from scipy.stats import chi2, multivariate_normal, ncx2

from core.geometry import Coverage, PolygonView, Sector, Visibility
from core.pipeline.evidence import coverage_look, look
from core.pipeline.visibility import inside_probability
from core.volume import RadarVolume

GATE_2D = float(chi2.ppf(0.999, 2))
SAMPLES = 400_000


def _phi(value: float) -> float:
    return 0.5 * (1.0 + math.erf(value / math.sqrt(2.0)))


def _monte_carlo(
    contains: Callable[[np.ndarray], np.ndarray],
    mean: np.ndarray,
    covariance: np.ndarray,
    seed: int,
) -> float:
    samples = np.random.default_rng(seed).multivariate_normal(mean, covariance, size=SAMPLES)
    return float(np.mean(contains(samples)))


def _tolerance(p: float) -> float:
    """Four standard errors of a Monte Carlo estimate of ``p`` (and a floor of 1e-3)."""
    return max(4.0 * math.sqrt(p * (1.0 - p) / SAMPLES), 1e-3)


COVARIANCE_2D = np.array([[900.0, 420.0], [420.0, 400.0]])  # σ 30 / 20 m, correlation 0.7


@pytest.mark.parametrize(
    "mean",
    [
        (995.0, 500.0),
        (1030.0, 480.0),
        (400.0, 12.0),
        (520.0, -40.0),
        (300.0, 760.0),
        (500.0, 500.0),
    ],
)
def test_a_rectangle_against_scipys_bivariate_normal_cdf(mean: tuple[float, float]) -> None:
    rectangle = PolygonView(((0.0, 0.0), (1000.0, 0.0), (1000.0, 800.0), (0.0, 800.0)))
    exact = multivariate_normal(mean=mean, cov=COVARIANCE_2D).cdf(
        np.array([1000.0, 800.0]), lower_limit=np.array([0.0, 0.0])
    )
    p = inside_probability(rectangle, None, np.array([mean]), COVARIANCE_2D[None])[0]
    assert p == pytest.approx(exact, abs=2e-4)


@pytest.mark.parametrize("offset", [-60.0, -25.0, 0.0, 15.0, 40.0, 90.0])
def test_a_turned_rectangle_against_scipys_cdf_in_its_own_axes(offset: float) -> None:
    """The rectangle turned by 35° about a corner: in its own axes it is the box of scipy's
    CDF and the covariance turns with it (RᵀPR); the mean ``offset`` metres inside its long
    edge (negative: outside)."""
    angle = math.radians(35.0)
    turn = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
    corner = np.array([200.0, -100.0])
    box = np.array([[0.0, 0.0], [2000.0, 0.0], [2000.0, 1500.0], [0.0, 1500.0]])
    polygon = PolygonView(tuple((float(x), float(y)) for x, y in (corner + box @ turn.T)))
    own = np.array([1000.0, offset])  # in the rectangle's axes
    mean = corner + turn @ own
    exact = multivariate_normal(mean=own, cov=turn.T @ COVARIANCE_2D @ turn).cdf(
        np.array([2000.0, 1500.0]), lower_limit=np.array([0.0, 0.0])
    )
    p = inside_probability(polygon, None, mean[None], COVARIANCE_2D[None])[0]
    assert p == pytest.approx(exact, abs=2e-4)


@pytest.mark.parametrize(("distance", "sigma"), [(950.0, 30.0), (1000.0, 20.0), (1060.0, 40.0)])
def test_a_discs_range_against_the_noncentral_chi_square(distance: float, sigma: float) -> None:
    """A full-circle sector (half-angle 180°) of radius 1000 m, isotropic σ: P(|x| ≤ r) is
    the noncentral χ² (2 degrees, λ = |x̂|²/σ²) at r²/σ². The straight edge misses the
    circle's curvature, of order σ/r: within 0.01 here."""
    disc = Sector((0.0, 0.0), 0.0, 180.0, 0.0, 1000.0)
    exact = ncx2.cdf(1000.0**2 / sigma**2, 2, distance**2 / sigma**2)
    p = inside_probability(disc, None, np.array([[distance, 0.0]]), (sigma**2 * np.eye(2))[None])
    assert p[0] == pytest.approx(exact, abs=0.01)


SECTOR = Sector((0.0, 0.0), 30.0, 40.0, 100.0, 1000.0)


@pytest.mark.parametrize("distance", [92.0, 100.0, 106.0])
def test_a_minimum_range_against_the_noncentral_chi_square(distance: float) -> None:
    """Outside the minimum range 100 m (σ 5 m isotropic, on the sector's axis): P(|x| ≥ 100)
    = 1 − the noncentral χ² (2 degrees, λ = |x̂|²/σ²) at 100²/σ²."""
    exact = 1.0 - ncx2.cdf(100.0**2 / 25.0, 2, distance**2 / 25.0)
    angle = math.radians(30.0)
    mean = np.array([[distance * math.cos(angle), distance * math.sin(angle)]])
    p = inside_probability(SECTOR, None, mean, (25.0 * np.eye(2))[None])
    assert p[0] == pytest.approx(exact, abs=0.01)


@pytest.mark.parametrize(
    ("mean", "seed"),
    [
        ((700.0, 600.0), 1),  # near the +70° side
        ((300.0, 0.0), 2),  # near the −10° side
        ((960.0, 500.0), 3),  # near the range edge (curved: a looser bound)
        ((640.0, 670.0), 5),  # just outside the +70° side
    ],
)
def test_a_sector_against_monte_carlo(mean: tuple[float, float], seed: int) -> None:
    covariance = np.array([[400.0, 150.0], [150.0, 900.0]])
    expected = _monte_carlo(SECTOR.contains, np.array(mean), covariance, seed)
    p = inside_probability(SECTOR, None, np.array([mean]), covariance[None])[0]
    assert abs(p - expected) <= _tolerance(expected) + 0.01


EARTH, HEIGHT = 6_371_000.0, 150.0
VOLUME = RadarVolume(
    site=(0.0, 0.0, 0.0),
    range_max=150_000.0,
    elevation_min_deg=-2.0,
    elevation_max_deg=30.0,
    antenna_height=HEIGHT,
)


def _at(distance: float, height: float) -> tuple[float, float, float]:
    """The point ``distance`` east of the antenna at ``height`` above the sphere below it."""
    return (distance, 0.0, math.sqrt((EARTH + height) ** 2 - distance**2) - EARTH - HEIGHT)


@pytest.mark.parametrize(
    ("mean", "covariance", "seed"),
    [
        (_at(60_000.0, 0.0), np.diag([200.0**2, 200.0**2, 30.0**2]), 11),  # horizon
        (_at(60_000.0, 20.0), np.diag([5.0**2, 5.0**2, 80.0**2]), 12),
        (
            _at(60_000.0, -20.0),
            np.array([[900.0, 0.0, 300.0], [0.0, 100.0, 0.0], [300.0, 0.0, 400.0]]),
            13,
        ),
        (_at(90_000.0, 200.0), np.diag([300.0**2, 300.0**2, 120.0**2]), 14),
        ((149_900.0, 0.0, 20_000.0), np.diag([300.0**2, 300.0**2, 300.0**2]), 15),  # range
        ((10_000.0, 0.0, 5_700.0), np.diag([200.0**2, 200.0**2, 80.0**2]), 16),  # top elevation
        ((10_000.0, 1_000.0, -360.0), np.diag([200.0**2, 200.0**2, 80.0**2]), 17),  # bottom
    ],
)
def test_a_radar_volume_against_monte_carlo(
    mean: tuple[float, float, float], covariance: np.ndarray, seed: int
) -> None:
    expected = _monte_carlo(VOLUME.contains, np.array(mean), covariance, seed)
    p = inside_probability(None, VOLUME, np.array([mean]), covariance[None])[0]
    assert abs(p - expected) <= _tolerance(expected) + 0.005


@pytest.mark.parametrize(("height", "seed"), [(-30.0, 21), (0.0, 22), (25.0, 23), (60.0, 24)])
def test_a_radars_region_ends_at_the_surface_against_monte_carlo(height: float, seed: int) -> None:
    """The region a radar contributes (``reach``): its slant range, and above the surface its
    horizon lies on (h_t ≥ 0: no target flies under it), against Monte Carlo of both tests."""

    def region(points: np.ndarray) -> np.ndarray:
        local = VOLUME.local(points)
        return np.asarray(VOLUME.in_range(points) & (VOLUME.height(local) >= 0.0))

    mean = np.array(_at(40_000.0, height))
    covariance = np.diag([150.0**2, 150.0**2, 40.0**2])
    expected = _monte_carlo(region, mean, covariance, seed)
    p = inside_probability(None, VOLUME, mean[None], covariance[None], reach=True)[0]
    assert abs(p - expected) <= _tolerance(expected) + 0.005


def test_on_the_hand_worked_horizon_p_is_one_half() -> None:
    """At 60 km an antenna 150 m up sees down to h_t = (60000/4121.81 − √150)² = 5.33 m (the
    4/3-Earth horizon by hand): a track predicted there is on the edge, p = Φ(0)."""
    needed = (60_000.0 / 4121.81 - math.sqrt(HEIGHT)) ** 2
    covariance = np.diag([100.0**2, 100.0**2, 40.0**2])[None]
    p = inside_probability(None, VOLUME, np.array([_at(60_000.0, needed)]), covariance)[0]
    assert p == pytest.approx(0.5, abs=2e-3)


def test_without_a_covariance_p_is_the_papers_test_at_the_position() -> None:
    """No covariance: p is 1 inside and 0 outside, by the sensors' own ``contains``, and the
    coverage codes are :meth:`Coverage.visibility`'s."""
    rng = np.random.default_rng(7)
    plane = rng.uniform(-1500.0, 1500.0, size=(500, 2))
    polygon = PolygonView(((-1000.0, -800.0), (200.0, -900.0), (600.0, 300.0), (-300.0, 700.0)))
    for view in (SECTOR, polygon):
        p = inside_probability(view, None, plane, None)
        assert p.tolist() == view.contains(plane).astype(float).tolist()
    coverage = Coverage((SECTOR, polygon))
    codes, _ = coverage_look(coverage, plane, None, GATE_2D)
    assert codes.tolist() == coverage.visibility(plane).tolist()
    points = np.column_stack(
        [rng.uniform(0, 160_000.0, 300), np.zeros(300), rng.uniform(-2e3, 3e4, 300)]
    )
    p = inside_probability(None, VOLUME, points, None)
    assert p.tolist() == VOLUME.contains(points).astype(float).tolist()


def test_a_miss_scores_ln_of_p_region_minus_p_d_p_by_hand() -> None:
    """Sensor a: the square [0, 1000]²; sensor b: the half x ≤ 500 of it. A track at x̂ =
    (480, 500), σ_x 40 m: b sees it with p = Φ(20/40) = 0.6915 and the region (a's square)
    holds it wholly: b's miss scores ln(1 − 0.8 × 0.6915). Alone, b is also the region: its
    miss there scores ln(p − 0.8 p) = ln(0.2 p). On b's edge, p = ½: ln(0.5 − 0.4)."""
    square = PolygonView(((0.0, 0.0), (1000.0, 0.0), (1000.0, 1000.0), (0.0, 1000.0)))
    half = PolygonView(((0.0, 0.0), (500.0, 0.0), (500.0, 1000.0), (0.0, 1000.0)))
    covariance = np.diag([40.0**2, 30.0**2])[None]
    status = np.zeros(1, dtype=np.int64)
    position = np.array([[480.0, 500.0]])
    p = _phi(20.0 / 40.0)
    both = look(
        Coverage((square, half)), half, None, position, covariance, status, 0.0, 0.8, GATE_2D
    )
    assert both.probability[0] == pytest.approx(p, abs=1e-12)
    assert both.miss_increment[0] == pytest.approx(math.log(1.0 - 0.8 * p), abs=1e-12)
    alone = look(Coverage((half,)), half, None, position, covariance, status, 0.0, 0.8, GATE_2D)
    assert alone.miss_increment[0] == pytest.approx(math.log(0.2 * p), abs=1e-12)
    edge = look(
        Coverage((half,)),
        half,
        None,
        np.array([[500.0, 500.0]]),
        covariance,
        status,
        0.0,
        0.8,
        GATE_2D,
    )
    assert edge.miss_increment[0] == pytest.approx(math.log(0.5 - 0.4), abs=1e-12)
    # the paper profile: inside, a miss is ln(1 − P_D)
    paper = look(Coverage((half,)), half, None, position, None, status, 0.0, 0.8, GATE_2D)
    assert paper.miss_increment[0] == pytest.approx(math.log(0.2), abs=1e-12)


def test_a_track_is_seen_while_its_gate_reaches_the_view() -> None:
    """The gate {d : dᵀP⁻¹d ≤ γ} reaches √γ σ_n across a straight edge (σ_n² = nᵀPn): a mean
    just under that outside the half of test above is seen (and a miss), just over it not,
    and then it is in a blind zone of the square (out of range outside the square)."""
    square = PolygonView(((0.0, 0.0), (1000.0, 0.0), (1000.0, 1000.0), (0.0, 1000.0)))
    half = PolygonView(((0.0, 0.0), (500.0, 0.0), (500.0, 1000.0), (0.0, 1000.0)))
    covariance = np.array([[1600.0, 500.0], [500.0, 900.0]])[None]  # σ_n along x: 40 m
    reach = math.sqrt(GATE_2D) * 40.0
    status = np.zeros(2, dtype=np.int64)
    positions = np.array([[500.0 + reach - 0.5, 500.0], [500.0 + reach + 0.5, 500.0]])
    spread = np.repeat(covariance, 2, axis=0)
    coverage = Coverage((square, half))
    sight = look(coverage, half, None, positions, spread, status, 0.0, 0.8, GATE_2D)
    assert sight.seen.tolist() == [True, False]
    codes, _ = coverage_look(Coverage((half,)), positions, spread, GATE_2D)
    assert codes.tolist() == [int(Visibility.VISIBLE), int(Visibility.OUT_OF_RANGE)]
    codes, _ = coverage_look(Coverage((half,), region=square), positions, spread, GATE_2D)
    assert codes.tolist() == [int(Visibility.VISIBLE), int(Visibility.BLIND_ZONE)]
