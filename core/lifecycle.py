"""Track life cycle: status, reasons, SPRT score and gate-emptiness termination.

Shared by the local tracker (docs/algorithms.md §4) and the fusion engine (§6).

Track score ([MTT] §4.3, eq 16; Blackman & Popoli pp. 327-334), a sequential
probability ratio test on "true track" vs "false track":

- a new track starts at ``L₀ = ln(β_NT / β_FT)`` (its first detection); a
  two-point track, made of two detections, starts at ``L₀`` plus the second
  detection's hit ΔL (:meth:`ScoreModel.two_point_initial`);
- a hit adds ``ΔL = ln[P_D / ((2π)^{q/2} β_FT √|S|)] − D/2``;
- a miss adds ``ΔL = ln(1 − P_D)``, only at a scan of a sensor that should have
  seen the track (docs/algorithms.md §8.1);
- confirm when ``L ≥ ln((1 − β) / α)``, delete when ``L ≤ ln(β / (1 − α))``,

with α = P(false track confirmed) and β = P(true track deleted). The papers
call the thresholds T1 / T2 and swap them between texts; here they are only
ever called *confirm* and *delete*.

Termination by gate emptiness ([HZ] §4.2): while a track coasts, the
probability of having found nothing in its gate is
``P = Π_k [1 − (ρ_FA + ρ_NT) A_G(k)]`` (each factor clipped at 0), with gate
volume ``A_G = c_q γ^{q/2} √|S|`` (c_q the volume of the unit q-ball, γ the
gate on D). The track is terminated when P falls below
``termination_probability`` (0.5 in [HZ] §6) — by default only once it has
missed ``termination_misses`` scans in a row (3), so that one or two plain
misses in a large gate (a 3-D radar at a 4–5 s revisit) never end a track
(docs/algorithms.md §8.1; [HZ] tests from the first miss).

The defaults are for real sensors (§8); :meth:`LifeCycleConfig.paper` is the
life cycle of the papers' experiments.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from core.arrays import BoolArray, FloatArray, IntArray
from core.distance.pairwise import chi2_quantile
from core.errors import InvalidInput
from core.geometry import Coverage, FieldOfView, Sector, Visibility, occluded


class TrackStatus(enum.StrEnum):
    """Where a track is in its life ([HZ] §2.1 for phantom)."""

    TENTATIVE = "tentative"
    CONFIRMED = "confirmed"
    COASTING = "coasting"
    PHANTOM = "phantom"
    TERMINATED = "terminated"


class StatusReason(enum.StrEnum):
    """Why a track's status last changed; reported on every track."""

    INITIATED = "initiated"
    SCORE_CONFIRMED = "score_confirmed"
    MIN_POINTS = "min_points"
    SECOND_SENSOR = "second_sensor"
    LOCAL_CONFIRMED = "local_confirmed"
    REACQUIRED = "reacquired"
    MISSED = "missed"
    BLIND_ZONE = "blind_zone"
    OCCLUDED = "occluded"
    OUT_OF_RANGE = "out_of_range"
    SCORE_DELETED = "score_deleted"
    GATE_EMPTINESS = "gate_emptiness"
    PHANTOM_EXPIRED = "phantom_expired"
    MERGED_INTO_PHANTOM = "merged_into_phantom"
    DUPLICATE = "duplicate"


def _check_probability(value: float, name: str, *, closed_low: bool = False) -> None:
    low_ok = value >= 0.0 if closed_low else value > 0.0
    if not (math.isfinite(value) and low_ok and value < 1.0):
        interval = "[0, 1)" if closed_low else "(0, 1)"
        raise InvalidInput(f"{name} must be in {interval}, got {value!r}")


def default_density(dim: int) -> float:
    """One false alarm (or new target) per km^q per scan, in m^-q: 1e-6 in 2-D, 1e-9 in 3-D.

    A density is per unit of the q-dimensional position space, so one number
    cannot serve every q: 1e-6 m⁻³ is a thousand false alarms per km³ and
    above the peak density (2π)^{-3/2} |S|^{-1/2} of a target seen with
    σ ≈ 60 m (about 1.6e-7 m⁻³), so that every hit lowers the score of
    [MTT] §4.3 and a 3-D track is never confirmed.
    """
    return float(10.0 ** (-3 * dim))


BIRTH_RATE = 1.0 / 60.0
"""New targets per second in a sensor's coverage volume of the default birth density: one a
minute (docs/algorithms.md §8.12)."""


def default_birth_density(
    clutter_density: float, coverage_volume: float | None, interval: float
) -> float:
    """β_NT when the user gave none: the :data:`BIRTH_RATE` of new targets over the
    ``interval`` (s) since the sensor last looked, spread over its coverage volume V, never
    above β_FT — ``min(β_FT, BIRTH_RATE · interval / V)``; β_FT (prior odds 1) when V is
    unknown or infinite, or the interval is (the sensor's first scan: every target in its
    coverage is new to it) (docs/algorithms.md §8.12).

    The start score ``L₀ = ln(β_NT/β_FT)`` is then ``ln(births / false alarms)`` of one scan
    in the coverage: a 12 s radar with 30 false alarms a scan starts at ln(0.2/30) = −5.0,
    so a pair of its clutter detections reaches L ≥ 0 (min_points) only where they fit each
    other at D ≲ 6 instead of anywhere in the gate.
    """
    if coverage_volume is None or not math.isfinite(coverage_volume) or coverage_volume <= 0.0:
        return clutter_density
    return min(clutter_density, BIRTH_RATE * interval / coverage_volume)


def confirm_threshold(false_confirmation: float, true_deletion: float) -> float:
    """The SPRT's confirm threshold ``ln((1 − β) / α)`` ([MTT] §4.3; Wald)."""
    return math.log((1.0 - true_deletion) / false_confirmation)


def delete_threshold(false_confirmation: float, true_deletion: float) -> float:
    """The SPRT's delete threshold ``ln(β / (1 − α))``."""
    return math.log(true_deletion / (1.0 - false_confirmation))


@dataclass(frozen=True)
class ScoreModel:
    """Parameters of the SPRT track score of one sensor (built by :meth:`LifeCycleConfig.score_model`).

    Attributes
    ----------
    p_detect : P_D, probability of detection.
    false_target_density : β_FT, false alarms per unit volume of measurement space per scan.
    new_target_density : β_NT, new targets per unit volume per scan.
    false_confirmation : α, P(a false track is confirmed).
    true_deletion : β, P(a true track is deleted).
    """

    p_detect: float
    false_target_density: float
    new_target_density: float
    false_confirmation: float
    true_deletion: float

    def __post_init__(self) -> None:
        _check_probability(self.p_detect, "p_detect")
        _check_probability(self.false_confirmation, "false_confirmation")
        _check_probability(self.true_deletion, "true_deletion")
        for name in ("false_target_density", "new_target_density"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise InvalidInput(f"{name} must be a positive number, got {value!r}")

    @property
    def initial(self) -> float:
        """L₀ = ln(β_NT / β_FT)."""
        return math.log(self.new_target_density / self.false_target_density)

    def two_point_initial(
        self, displacement: FloatArray, pair_covariance: FloatArray
    ) -> FloatArray:
        """Start scores of two-point tracks: L₀ + the second detection's hit ΔL, vectorised.

        Given the first detection z₀, a true target's second detection z₁ is
        Gaussian about z₀ with covariance ``pair_covariance`` (R₀ + R₁ + Σ_v ΔT²:
        both measurement noises and the velocity prior over the interval; one
        (q, q) for every pair or one per pair, (T, q, q)); the hit ΔL of
        ``z₁ − z₀`` (``displacement``, shape (T, q)) under it is the same SPRT
        increment as any hit (Blackman & Popoli pp. 328-330). Without it a
        two-point track would start one detection short of its evidence.
        """
        d = np.atleast_2d(np.asarray(displacement, dtype=np.float64))
        s = np.broadcast_to(np.asarray(pair_covariance, dtype=np.float64), (*d.shape, d.shape[1]))
        distance = np.einsum("ti,ti->t", d, np.linalg.solve(s, d[:, :, None])[:, :, 0])
        log_det = np.linalg.slogdet(s)[1]
        increment = self.hit_increment(distance, log_det, d.shape[1])
        return np.asarray(self.initial + increment, dtype=np.float64)

    @property
    def confirm_threshold(self) -> float:
        """Confirm when L ≥ ln((1 − β) / α)."""
        return confirm_threshold(self.false_confirmation, self.true_deletion)

    @property
    def delete_threshold(self) -> float:
        """Delete when L ≤ ln(β / (1 − α))."""
        return delete_threshold(self.false_confirmation, self.true_deletion)

    @property
    def miss_increment(self) -> float:
        """ΔL on a miss: ln(1 − P_D)."""
        return math.log1p(-self.p_detect)

    @property
    def hit_floor(self) -> float:
        """The least likelihood ln Λ(z) of a detection that an established track may take
        (docs/algorithms.md §8.1, "A detection after a long gap"): where
        ``P_D Λ(z) ≥ (1 − P_D) β_FT`` the hit's ΔL = ln(P_D Λ / β_FT) is at least the
        miss's ln(1 − P_D) ([MTT] §4.3, eq 16) — "the target made z" is at least as likely
        as "the target was missed and z is a false alarm"."""
        return self.miss_increment + math.log(self.false_target_density / self.p_detect)

    def hit_increment(
        self, distance: FloatArray, log_det_innovation: FloatArray, dim: int
    ) -> FloatArray:
        """ΔL on a hit, vectorised: ln[P_D / ((2π)^{q/2} β_FT √|S|)] − D/2."""
        return np.asarray(
            math.log(self.p_detect)
            - 0.5 * dim * math.log(2.0 * math.pi)
            - math.log(self.false_target_density)
            - 0.5 * np.asarray(log_det_innovation)
            - 0.5 * np.asarray(distance),
            dtype=np.float64,
        )


def unit_ball_volume(dim: int) -> float:
    """c_q = π^{q/2} / Γ(q/2 + 1)."""
    return float(math.pi ** (dim / 2.0) / math.gamma(dim / 2.0 + 1.0))


def gate_volume(gate: float, log_det_innovation: FloatArray, dim: int) -> FloatArray:
    """A_G = c_q γ^{q/2} √|S| ([HZ] §4.2), vectorised over tracks."""
    return np.asarray(
        unit_ball_volume(dim) * gate ** (dim / 2.0) * np.exp(0.5 * np.asarray(log_det_innovation)),
        dtype=np.float64,
    )


def gate_emptiness_factor(
    clutter_density: float, new_target_density: float, volume: FloatArray
) -> FloatArray:
    """One scan's factor 1 − (ρ_FA + ρ_NT) A_G, clipped at 0 ([HZ] §4.2)."""
    return np.asarray(np.clip(1.0 - (clutter_density + new_target_density) * volume, 0.0, 1.0))


def several_sensors_shift(revisits: FloatArray) -> FloatArray:
    """The shift ``ln(T_c / T_max) = −ln Σ_i T_max / T_i`` (≤ 0) of each track's delete
    threshold, ``revisits`` (n, sensors) the revisit T_i of each sensor that looks at the
    track (carries it and sees it, docs/algorithms.md §8.14), +inf where one does not.

    A run of misses of probability p under "the target is there" starts by chance at a
    rate p Σ_i 1/T_i = p / T_c (the track's combined scans); alone, its slowest sensor
    reaches β at the rate β / T_max. Deleting at ``p ≤ β T_c / T_max`` keeps a true
    track's false deletions per second at most those of any one of its sensors alone,
    however many sensors add scans. 0 where fewer than two sensors look.
    """
    revisits = np.asarray(revisits, dtype=np.float64)
    if revisits.size == 0:
        return np.zeros(len(revisits))
    looking = np.isfinite(revisits)
    several = looking.sum(axis=1) >= 2
    # ln Σ_i T_max/T_i summed in logs: the ratio of a fast and a slow sensor's revisits may
    # overflow a float (1e300 / 1e-10), its log does not (a −∞ shift would never delete)
    logs = np.log(np.where(looking, revisits, 1.0))
    top = np.where(several, np.max(np.where(looking, logs, -np.inf), axis=1), 0.0)
    bottom = np.where(several, np.min(np.where(looking, logs, np.inf), axis=1), 0.0)
    # ln Σ_i e^(ln T_max − ln T_i) = ln(T_max/T_min) + ln Σ_i T_min/T_i, each term ≤ 1
    fractions = np.where(looking, np.exp(np.minimum(bottom[:, None] - logs, 0.0)), 0.0)
    ratio = top - bottom + np.log(np.maximum(fractions.sum(axis=1), 1.0))
    return np.asarray(np.where(several, -ratio, 0.0))


def misses_to_delete(drop: FloatArray, miss_increment: float) -> IntArray:
    """Misses in a row that lower a score by ``drop`` (≥ 0): ⌈drop / −ln(1 − P_D)⌉."""
    per_miss = -miss_increment
    if not (math.isfinite(per_miss) and per_miss > 0.0):
        return np.zeros(np.shape(drop), dtype=np.int64)
    return np.asarray(np.ceil(np.asarray(drop) / per_miss - 1e-9), dtype=np.int64)


# ------------------------------------------------------------------ configuration
MAX_MIN_POINTS = 100
"""Largest ``min_points`` (the wire's bound too)."""
DEFAULT_ALPHA = DEFAULT_BETA = 1e-3
"""The default α (false confirmation) and β (true deletion)."""
PLAIN_MISSES = 2
"""Misses in a row that never end a track by gate emptiness (§8.1: a true target at
P_D 0.9 shows them)."""


@dataclass(frozen=True)
class LifeCycleConfig:
    """The track life cycle of both layers: one type, one set of defaults.

    The local tracker (``LocalTrackerConfig.life_cycle``), the fusion engine
    (``FusionConfig.management``) and the wire schema
    (``api_schemas.config.TrackThresholds``, pinned by a test) share it. The
    defaults are for real sensors (docs/algorithms.md §8); :meth:`paper` is
    the life cycle of the papers' experiments.

    Attributes
    ----------
    false_confirmation : α, P(a false track is confirmed), in (0, 1).
    true_deletion : β, P(a true track is deleted), in (0, 1).
    false_target_density : β_FT (= ρ_FA), false alarms per unit of position space per scan;
        None (the default): the local tracker estimates it per sensor from its own
        detections (``core.tracking.clutter``); the fused layer takes
        :func:`default_density` of its dimension (:meth:`for_dimension`).
    new_target_density : β_NT (= ρ_NT), new targets per unit of position space per scan;
        None (the default): :func:`default_birth_density` of the scan's β_FT and its
        sensor's coverage volume (one new target a minute in it, at most β_FT), β_FT
        (prior odds 1, L₀ = 0) for a sensor without one.
    termination_probability : gate-emptiness threshold ([HZ] §4.2) in [0, 1); 0 turns it off.
    termination_misses : the gate-emptiness test runs only on a track that has missed at
        least this many scans in a row (default :data:`PLAIN_MISSES` + 1: one or two plain
        misses never end a track, whatever its gate; [HZ] tests from the first, 1).
    gate_probability : γ of the gate volume A_G (as a χ² probability) and of the
        hand-over to phantoms, in (0, 1).
    min_points : confirm a tentative track after this many hits while its score is
        not below 0 (P(target) ≥ ½: docs/algorithms.md §7.2), 1 to
        :data:`MAX_MIN_POINTS` (None: score only). Default 2.
    initiation_hits : a tentative track hit in a scan is not deleted by its score while
        it has at most this many hits: a start is tested by its later detections, not
        by a prior it could not know (§8.3); 0: the SPRT as written.
    score_ceiling : an established track's score is clamped at this value, so a
        long-lived track is still deleted after a few misses where it should have been
        seen (``core.tracking.config`` Readings); None keeps the raw SPRT. Default 0: the
        test restarts once a track is established (P(target) = ½), and a run of misses
        deletes it when it reaches the delete threshold ln(β/(1 − α)) from there — 3 at
        P_D 0.9, the run a true target shows with probability β per scan. A tentative
        track is scored up to its confirm threshold whatever the ceiling. The paper
        profile: the confirm threshold (6 misses at P_D 0.9).
    hit_evidence : the local tracker's established tracks take a detection only where the
        hit is at least as likely as a miss and a false alarm (:attr:`ScoreModel.hit_floor`,
        each model of the bank weighted by the probability that it held over the step:
        docs/algorithms.md §8.1, "A detection after a long gap"). The paper profile: off,
        the gate alone decides ([MTT] §4.2; mtt-scenes' coasting track takes target 4's
        detection, the event of [MTT] Fig 4–5).
    occlusion_radius : radius of a known track as an occluder ([HZ] §2.1); 0: no occlusion.
    phantom_max_distance, phantom_min_speed : a phantom lives at most
        ``max_distance / min_speed`` seconds ([HZ] §5.1).
    phantoms : the blind-zone strategy on (default) or off (a hidden track then
        coasts and is terminated by score or gate emptiness).
    gate_visibility : a track is seen by a sensor, and in a blind zone or out of range,
        by its gate, and its miss scores ``ln(p_region − P_D p)`` with p the probability
        that the sensor sees its predicted position (docs/algorithms.md §8.16; default).
        The paper profile: off, [HZ] §2.1's test at the predicted position, a miss
        ln(1 − P_D).
    """

    false_confirmation: float = DEFAULT_ALPHA
    true_deletion: float = DEFAULT_BETA
    false_target_density: float | None = None
    new_target_density: float | None = None
    termination_probability: float = 0.5
    termination_misses: int = PLAIN_MISSES + 1
    gate_probability: float = 0.999
    min_points: int | None = 2
    initiation_hits: int = 3
    score_ceiling: float | None = 0.0
    hit_evidence: bool = True
    occlusion_radius: float = 0.0
    phantom_max_distance: float = 500.0
    phantom_min_speed: float = 1.0
    phantoms: bool = True
    gate_visibility: bool = True

    @classmethod
    def paper(cls, dim: int = 2, **options: Any) -> LifeCycleConfig:
        """The life cycle of the papers' experiments (the first two editions' defaults) for
        ``dim`` position axes: both densities one per km^q (:func:`default_density`),
        [HZ]'s gate emptiness from the first miss, score-only confirmation, no start exempt
        from the SPRT, the score ceiling at the confirm threshold, the gate alone deciding
        which detection a track may take; ``options`` override any field."""
        settings: dict[str, Any] = {
            "false_target_density": default_density(dim),
            "new_target_density": default_density(dim),
            "termination_misses": 1,
            "min_points": None,
            "initiation_hits": 0,
            "hit_evidence": False,
            "gate_visibility": False,
        }
        settings.update(options)
        if "score_ceiling" not in options:
            alpha = float(settings.get("false_confirmation", DEFAULT_ALPHA))
            beta = float(settings.get("true_deletion", DEFAULT_BETA))
            settings["score_ceiling"] = confirm_threshold(alpha, beta)
        return cls(**settings)

    def __post_init__(self) -> None:
        _check_probability(self.false_confirmation, "false_confirmation")
        _check_probability(self.true_deletion, "true_deletion")
        _check_probability(self.termination_probability, "termination_probability", closed_low=True)
        _check_probability(self.gate_probability, "gate_probability")
        for name in (
            "false_target_density",
            "new_target_density",
            "phantom_max_distance",
            "phantom_min_speed",
        ):
            value = getattr(self, name)
            if value is None and name.endswith("density"):
                continue
            if not (math.isfinite(value) and value > 0.0):
                raise InvalidInput(f"{name} must be a positive number, got {value!r}")
        if self.score_ceiling is not None and not (
            math.isfinite(self.score_ceiling) and self.score_ceiling > self.delete_threshold
        ):
            raise InvalidInput(
                f"score_ceiling must be above the delete threshold {self.delete_threshold:.4g}, "
                f"or None; got {self.score_ceiling!r}"
            )
        if not (math.isfinite(self.occlusion_radius) and self.occlusion_radius >= 0.0):
            raise InvalidInput(f"occlusion_radius must be >= 0, got {self.occlusion_radius!r}")
        if self.min_points is not None and not 1 <= self.min_points <= MAX_MIN_POINTS:
            raise InvalidInput(
                f"min_points must be in [1, {MAX_MIN_POINTS}] or None, got {self.min_points}"
            )
        for name in ("termination_misses", "initiation_hits"):
            value = getattr(self, name)
            if not 0 <= value <= MAX_MIN_POINTS:
                raise InvalidInput(f"{name} must be in [0, {MAX_MIN_POINTS}], got {value!r}")

    def for_dimension(self, dim: int) -> LifeCycleConfig:
        """This life cycle with every unset density filled for a layer of ``dim`` positions
        whose inputs give no clutter estimate (the fused layer): β_FT at
        :func:`default_density`, β_NT at β_FT."""
        clutter = (
            default_density(dim) if self.false_target_density is None else self.false_target_density
        )
        birth = clutter if self.new_target_density is None else self.new_target_density
        return dataclasses.replace(self, false_target_density=clutter, new_target_density=birth)

    @property
    def densities(self) -> tuple[float, float]:
        """``(β_FT, β_NT)`` of a life cycle set for its dimension (:meth:`for_dimension`)."""
        clutter, birth = self.false_target_density, self.new_target_density
        if clutter is None or birth is None:
            raise InvalidInput(
                "the life cycle's densities depend on the position dimension: "
                "call for_dimension(dim) first"
            )
        return clutter, birth

    def score_model(self, p_detect: float) -> ScoreModel:
        """The SPRT score of a sensor with detection probability ``p_detect`` (built once)."""
        return _score_model(self, p_detect)

    def report_score(self, p_detect: float, source_clutter: float | None) -> ScoreModel:
        """The fused layer's SPRT score of a source's track report (docs/algorithms.md §8.1).

        β_FT is the layer's (set for its dimension), or the density of false tracks of the
        source, ``source_clutter``, where that is smaller: a local tracker's track is a
        detection of its sensor that passed the sensor's SPRT, so its false tracks are at
        most as dense as the sensor's false detections (β_FT of its scans, given or
        estimated). Without it, one false track per km³ (the layer's default in 3-D) makes
        a true track's hit lower the score wherever the report and the fused prediction are
        a few hundred metres uncertain (a 3-D radar at 50–100 km, a 12 s revisit), and three
        such hits delete a fused track that every source holds.
        """
        score = self.score_model(p_detect)
        if source_clutter is None or not source_clutter < score.false_target_density:
            return score
        return dataclasses.replace(score, false_target_density=source_clutter)

    def scan_score(
        self,
        p_detect: float,
        clutter_density: float,
        coverage_volume: float | None = None,
        interval: float = 1.0,
    ) -> ScoreModel:
        """The SPRT score of one scan of a sensor with its own P_D and β_FT (given or
        estimated); β_NT is the configured one, or when unset :func:`default_birth_density`
        of that β_FT, the sensor's ``coverage_volume`` (m^q; None: unknown) and the
        ``interval`` (s) since its previous scan."""
        birth = (
            default_birth_density(clutter_density, coverage_volume, interval)
            if self.new_target_density is None
            else self.new_target_density
        )
        return ScoreModel(
            p_detect=p_detect,
            false_target_density=clutter_density,
            new_target_density=birth,
            false_confirmation=self.false_confirmation,
            true_deletion=self.true_deletion,
        )

    @property
    def confirm_threshold(self) -> float:
        """ln((1 − β) / α): it depends on α and β only."""
        return confirm_threshold(self.false_confirmation, self.true_deletion)

    @property
    def delete_threshold(self) -> float:
        """ln(β / (1 − α))."""
        return delete_threshold(self.false_confirmation, self.true_deletion)

    @property
    def ceiling(self) -> float:
        """Largest score an established track keeps (+inf without a ceiling)."""
        return math.inf if self.score_ceiling is None else self.score_ceiling

    def sensor_misses(self, p_detect: float) -> int | None:
        """The misses in a row of one sensor of detection probability ``p_detect`` that take
        an established track from the score ceiling to the delete threshold:
        ``⌈(ceiling − ln(β/(1 − α))) / −ln(1 − P_D)⌉`` ([MTT] §4.3; 3 at P_D 0.9 with the
        ceiling 0, 6 with the paper profile's), None without a ceiling.

        A sensor whose misses in a row reach it while the track lives (other sensors kept
        it) has shown that it does not see the target — below its horizon, out of its
        range, a target it never detected — and its further silence says nothing about
        it until it detects it again (docs/algorithms.md §8.9). Alone, a sensor's run
        this long has deleted the track: a single sensor's misses always count.
        """
        if self.score_ceiling is None:
            return None
        drop = self.score_ceiling - self.delete_threshold
        return max(1, math.ceil(drop / -math.log1p(-p_detect) - 1e-9))

    @property
    def phantom_lifetime(self) -> float:
        """Longest time in a blind zone: the maximum distance at the minimum speed ([HZ] §5.1)."""
        return self.phantom_max_distance / self.phantom_min_speed


@lru_cache(maxsize=64)
def _score_model(config: LifeCycleConfig, p_detect: float) -> ScoreModel:
    clutter, _ = config.densities  # set for the dimension: β_NT is the configured one
    return config.scan_score(p_detect, clutter)


# ------------------------------------------------------------------ state
STATUSES: tuple[TrackStatus, ...] = tuple(TrackStatus)
REASONS: tuple[StatusReason, ...] = tuple(StatusReason)
TENTATIVE = STATUSES.index(TrackStatus.TENTATIVE)
CONFIRMED = STATUSES.index(TrackStatus.CONFIRMED)
COASTING = STATUSES.index(TrackStatus.COASTING)
PHANTOM = STATUSES.index(TrackStatus.PHANTOM)
TERMINATED = STATUSES.index(TrackStatus.TERMINATED)
STATUS_CODES: dict[TrackStatus, int] = {status: code for code, status in enumerate(STATUSES)}
"""The integer code of each status in :class:`LifeState` arrays."""
REASON_CODES: dict[StatusReason, int] = {reason: code for code, reason in enumerate(REASONS)}
"""The integer code of each reason in :class:`LifeState` arrays."""


def established(status: IntArray) -> BoolArray:
    """Tracks that are confirmed or coasting (the occluders and the tracks a miss coasts)."""
    return np.asarray((status == CONFIRMED) | (status == COASTING), dtype=np.bool_)


def reason_code(reason: StatusReason) -> int:
    """The integer code of ``reason`` in :class:`LifeState` arrays."""
    return REASON_CODES[reason]


@dataclass(frozen=True)
class LifeState:
    """The life of n tracks as arrays (codes index :data:`STATUSES` / :data:`REASONS`).

    Never changed in place: every function here returns a new one.
    ``phantom_since`` is NaN for a track that is not a phantom; ``misses`` counts the
    scans in a row that should have seen the track and did not detect it.
    """

    status: IntArray
    reason: IntArray
    score: FloatArray
    hits: IntArray
    empty_gate: FloatArray
    phantom_since: FloatArray
    misses: IntArray

    @classmethod
    def empty(cls) -> LifeState:
        return cls.new(0, 0.0)

    @classmethod
    def new(cls, count: int, score: float | FloatArray, hits: int | IntArray = 1) -> LifeState:
        """``count`` tentative tracks just initiated with ``score`` and ``hits`` (one, or one
        each)."""
        return cls(
            status=np.full(count, TENTATIVE, dtype=np.int64),
            reason=np.full(count, reason_code(StatusReason.INITIATED), dtype=np.int64),
            score=np.full(count, score, dtype=np.float64),
            hits=np.full(count, hits, dtype=np.int64),
            empty_gate=np.ones(count),
            phantom_since=np.full(count, np.nan),
            misses=np.zeros(count, dtype=np.int64),
        )

    def __len__(self) -> int:
        return len(self.status)

    def select(self, rows: IntArray) -> LifeState:
        return LifeState(*(getattr(self, name)[rows] for name in LIFE_ARRAYS))

    def concatenate(self, other: LifeState) -> LifeState:
        return LifeState(
            *(np.concatenate([getattr(self, name), getattr(other, name)]) for name in LIFE_ARRAYS)
        )

    def statuses(self) -> list[TrackStatus]:
        return [STATUSES[code] for code in self.status.tolist()]

    def reasons(self) -> list[StatusReason]:
        return [REASONS[code] for code in self.reason.tolist()]


LIFE_ARRAYS = ("status", "reason", "score", "hits", "empty_gate", "phantom_since", "misses")
"""The arrays of a :class:`LifeState`, in field order."""


def initiated(
    config: LifeCycleConfig,
    count: int,
    score: float | FloatArray,
    hits: int | IntArray = 1,
    *,
    confirmed_below: bool = False,
) -> LifeState:
    """The life of ``count`` tracks that start in this step.

    Tentative (``initiated``) with ``score`` (one, or one each) and ``hits``;
    or, ``confirmed_below``, tracks the layer below has already confirmed (a
    local tracker's, where no second test could add anything: the session's
    only sensor): confirmed at once (``local_confirmed``) at the confirm
    threshold, clamped at the score ceiling.
    """
    if not confirmed_below:
        return LifeState.new(count, score, hits)
    life = LifeState.new(count, min(config.ceiling, config.confirm_threshold), hits)
    return LifeState(
        np.full(count, CONFIRMED, dtype=np.int64),
        np.full(count, reason_code(StatusReason.LOCAL_CONFIRMED), dtype=np.int64),
        life.score,
        life.hits,
        life.empty_gate,
        life.phantom_since,
        life.misses,
    )


@dataclass(frozen=True)
class Evidence:
    """What one scan or report says about each of n tracks, for :func:`advance`.

    Attributes
    ----------
    time : the scan time (phantom expiry and entry).
    detected : the track got a hit in this step.
    hit_increment : ΔL of that hit (read only where ``detected``).
    seen : the step's sensor should have seen the track (in its field of view,
        not occluded): not detected, it is a miss.
    miss_increment : ΔL of a miss, ln(1 − P_D), or one per track (ln(p_region − P_D p),
        docs/algorithms.md §8.16).
    gate_log_det : log|S| of each track's gate on the position components (read
        only on a coasting miss, for A_G).
    gate_dim : the number of position components.
    visibility : :class:`~core.geometry.Visibility` code of each track (the coverage).
    occluded : inside the sensor's field of view but hidden by a known track.
    sensors : how many sensors report each track (second-sensor confirmation);
        None for a single-sensor layer.
    densities : the step's (ρ_FA, ρ_NT) for the gate volume ([HZ] §4.2), or None for
        the configuration's.
    velocity_measured : whether each track's detections have measured its velocity (a
        tentative track that has not, e.g. of several sensors' detections of one instant,
        is not confirmed: docs/algorithms.md §8.3); None: every track's.
    vouched : tracks another sensor detected at its latest scan, which is not overdue
        (a central tracker's, docs/algorithms.md §8.9): an established one is not ended
        by its score or its empty gate before that sensor's next scan, and its score
        stays at the delete threshold at least; None: none.
    repeated : tracks detected at this instant already (another sensor's detection of one
        instant, docs/algorithms.md §8.3): the hit adds nothing to their ``hits``, which
        count the instants a track was detected at; None: none.
    deletion_shift : per track, ``ln(T_c / T_max)`` ≤ 0 of the sensors that look at it
        (:func:`several_sensors_shift`, docs/algorithms.md §8.14): an established track's
        delete threshold is lowered by it, and its gate-emptiness test waits for as many
        more misses as its score then tolerates; None: 0 for every track.
    full_miss_increment : ln(1 − P_D), the ΔL of a full miss (p = p_region = 1) that
        §8.14's extra misses are counted in; None: ``miss_increment`` (its least value where
        it is one per track).
    """

    time: float
    detected: BoolArray
    hit_increment: FloatArray
    seen: BoolArray
    miss_increment: float | FloatArray
    gate_log_det: FloatArray
    gate_dim: int
    visibility: IntArray
    occluded: BoolArray
    sensors: IntArray | None = None
    densities: tuple[float, float] | None = None
    velocity_measured: BoolArray | None = None
    vouched: BoolArray | None = None
    repeated: BoolArray | None = None
    deletion_shift: FloatArray | None = None
    full_miss_increment: float | None = None


# ------------------------------------------------------------------ visibility
def sensor_view(
    view: FieldOfView | None, positions: FloatArray, occluders: FloatArray, radius: float
) -> tuple[BoolArray, BoolArray]:
    """Seen by the step's sensor, and occluded ([HZ] §2.1), of each planar position (n, 2).

    ``occluders`` are the positions of the known (confirmed or coasting) tracks,
    a disc of ``radius`` each, effective only for a sector ``view``. A position
    inside ``view`` but hidden is occluded and not seen.
    """
    count = len(positions)
    seen = np.ones(count, dtype=bool) if view is None else view.contains(positions)
    hidden = np.zeros(count, dtype=bool)
    if radius > 0.0 and isinstance(view, Sector) and count:
        hidden = seen & occluded(view.origin, positions, occluders, radius)
        seen = seen & ~hidden
    return np.asarray(seen, dtype=bool), np.asarray(hidden, dtype=bool)


def visibility(
    coverage: Coverage,
    view: FieldOfView | None,
    positions: FloatArray,
    occluders: FloatArray,
    radius: float,
) -> tuple[IntArray, BoolArray, BoolArray]:
    """Coverage code (:class:`~core.geometry.Visibility`), seen, occluded of each position."""
    if len(positions) == 0:
        return everywhere(0)
    return (coverage.visibility(positions), *sensor_view(view, positions, occluders, radius))


def everywhere(count: int) -> tuple[IntArray, BoolArray, BoolArray]:
    """Visibility of ``count`` tracks where there is no plane to look in (1-D states)."""
    return (
        np.full(count, int(Visibility.VISIBLE), dtype=np.int64),
        np.ones(count, dtype=bool),
        np.zeros(count, dtype=bool),
    )


# ------------------------------------------------------------------ transitions
def advance(
    config: LifeCycleConfig, state: LifeState, evidence: Evidence
) -> tuple[LifeState, BoolArray]:
    """One step of the life cycle of every track; returns the new state and the newly confirmed.

    1. score: a hit adds its ΔL, a miss (seen, not detected, not a phantom)
       its ``miss_increment`` (ln(1 − P_D); by default ln(p_region − P_D p),
       docs/algorithms.md §8.16) and one to the track's misses in a row; clamped at
       :attr:`LifeCycleConfig.score_ceiling`; an established track ``vouched`` for
       by another sensor not below the delete threshold;
    2. a coasting track that is hit is confirmed again (``reacquired``); a
       confirmed one that misses coasts (``missed``); a coasting miss multiplies
       the empty-gate probability by ``1 − (ρ_FA + ρ_NT) A_G`` ([HZ] §4.2);
    3. the table of [HZ] §5.1, first reason found wins:

       ======================================  =============  ==================
       condition                               new status     reason
       ======================================  =============  ==================
       out of range of every sensor            terminated     out_of_range
       phantom older than the lifetime         terminated     phantom_expired
       (other phantoms stay phantoms)
       undetected in a blind zone, established phantom        blind_zone
       undetected in a blind zone, tentative   terminated     blind_zone
       occluded, established                   phantom        occluded
       occluded, tentative                     terminated     occluded
       score ≤ delete threshold (+ the        terminated     score_deleted
       track's ``deletion_shift``; not a
       start hit with ≤ initiation_hits
       hits, not vouched for)
       coasting, empty gate < termination p.,  terminated     gate_emptiness
       ≥ termination_misses misses in a row
       (+ the shift's misses), not vouched for
       (the confirmations: only of a track whose velocity is measured, when given)
       tentative, reported by ≥ 2 sensors      confirmed      second_sensor
       tentative, min_points hits and L ≥ 0    confirmed      min_points
       tentative, score ≥ confirm threshold    confirmed      score_confirmed
       ======================================  =============  ==================

       (established = confirmed or coasting; the two phantom rows only with
       ``config.phantoms``).
    """
    status = state.status
    is_phantom = status == PHANTOM
    detected = evidence.detected & ~is_phantom
    missed = evidence.seen & ~detected & ~is_phantom
    score = state.score + np.where(detected, evidence.hit_increment, 0.0)
    # A tentative track is never held below its confirm threshold (a ceiling under it
    # restarts the test of established tracks only).
    ceiling = np.where(
        status == TENTATIVE,
        max(config.ceiling, config.confirm_threshold),
        config.ceiling,
    )
    score = np.minimum(score + np.where(missed, evidence.miss_increment, 0.0), ceiling)
    # §8.14: an established track that several sensors look at is deleted at a lower
    # threshold (its false deletions per second those of one of its sensors alone), and its
    # gate-emptiness test waits as many more misses as its score then tolerates
    threshold: float | FloatArray = config.delete_threshold
    later: int | IntArray = 0
    if evidence.deletion_shift is not None and np.any(evidence.deletion_shift < 0.0):
        shift = np.where(established(status), evidence.deletion_shift, 0.0)
        threshold = config.delete_threshold + shift
        if math.isfinite(config.ceiling):
            drop = config.ceiling - config.delete_threshold
            # counted in full misses, ln(1 − P_D) (p = p_region = 1): a partial miss of
            # §8.16 would stretch the wait without bound as p → 0, and the least ΔL of the
            # rows is another row's (−inf for one out of the region: no wait at all)
            full_miss = (
                float(np.min(evidence.miss_increment))
                if evidence.full_miss_increment is None
                else evidence.full_miss_increment
            )
            later = misses_to_delete(drop - shift, full_miss) - misses_to_delete(
                np.full(len(status), drop), full_miss
            )
    held = np.zeros(len(status), dtype=bool)
    if evidence.vouched is not None:
        held = evidence.vouched & established(status)
        score = np.where(held, np.maximum(score, threshold), score)
    # a track's hits are the instants it was detected at (§8.3)
    counted = detected if evidence.repeated is None else detected & ~evidence.repeated
    hits = state.hits + counted.astype(np.int64)
    misses = np.where(detected, 0, state.misses + missed.astype(np.int64))
    reason = state.reason

    def changed(mask: BoolArray, new_status: int, why: StatusReason) -> tuple[IntArray, IntArray]:
        if not mask.any():  # the arrays are never changed in place: they may be shared
            return status, reason
        return np.where(mask, new_status, status), np.where(mask, reason_code(why), reason)

    status, reason = changed(detected & (status == COASTING), CONFIRMED, StatusReason.REACQUIRED)
    empty_gate = np.where(detected, 1.0, state.empty_gate)
    status, reason = changed(missed & (status == CONFIRMED), COASTING, StatusReason.MISSED)
    coasting_miss = missed & (status == COASTING)
    if coasting_miss.any():
        gate = chi2_quantile(config.gate_probability, evidence.gate_dim)
        volume = gate_volume(
            gate, np.where(coasting_miss, evidence.gate_log_det, 0.0), evidence.gate_dim
        )
        densities = config.densities if evidence.densities is None else evidence.densities
        factor = gate_emptiness_factor(*densities, volume)
        empty_gate = np.where(coasting_miss, empty_gate * factor, empty_gate)

    undecided = np.ones(len(status), dtype=bool)
    phantom_since = state.phantom_since

    def decide(mask: BoolArray, new_status: int, why: StatusReason) -> None:
        nonlocal status, reason, undecided
        chosen = mask & undecided
        if chosen.any():  # most rules match no track in most steps
            status, reason = changed(chosen, new_status, why)
            undecided = undecided & ~chosen

    decide(evidence.visibility == Visibility.OUT_OF_RANGE, TERMINATED, StatusReason.OUT_OF_RANGE)
    expired = is_phantom & (evidence.time - phantom_since > config.phantom_lifetime)
    decide(expired, TERMINATED, StatusReason.PHANTOM_EXPIRED)
    undecided &= ~is_phantom
    if config.phantoms:
        established_rows = established(status)
        for hidden, why in (
            ((evidence.visibility == Visibility.BLIND_ZONE) & ~detected, StatusReason.BLIND_ZONE),
            (evidence.occluded & ~detected, StatusReason.OCCLUDED),
        ):
            entering = hidden & established_rows & undecided
            phantom_since = np.where(entering, evidence.time, phantom_since)
            decide(entering, PHANTOM, why)
            decide(hidden & (status == TENTATIVE), TERMINATED, why)
    # a start hit in this scan is tested by its next detections, not deleted (§8.3)
    starting = (status == TENTATIVE) & detected & (hits <= config.initiation_hits)
    decide(
        (score <= threshold) & ~starting & ~held,
        TERMINATED,
        StatusReason.SCORE_DELETED,
    )
    if config.termination_probability > 0.0:
        decide(
            (status == COASTING)
            & (empty_gate < config.termination_probability)
            & (misses >= config.termination_misses + later)
            & ~held,
            TERMINATED,
            StatusReason.GATE_EMPTINESS,
        )
    tentative = status == TENTATIVE
    if evidence.velocity_measured is not None:  # a position alone is no track yet (§8.3)
        tentative = tentative & evidence.velocity_measured
    if evidence.sensors is not None:
        decide(tentative & (evidence.sensors >= 2), CONFIRMED, StatusReason.SECOND_SENSOR)
    if config.min_points is not None:
        # by its hits only while it is more likely a target than a false one (L ≥ 0)
        decide(
            tentative & (hits >= config.min_points) & (score >= 0.0),
            CONFIRMED,
            StatusReason.MIN_POINTS,
        )
    decide(tentative & (score >= config.confirm_threshold), CONFIRMED, StatusReason.SCORE_CONFIRMED)
    confirmed = tentative & (status == CONFIRMED)
    # an established track is under the ceiling from the scan that confirms it
    score = np.where(confirmed, np.minimum(score, config.ceiling), score)
    new = LifeState(status, reason, score, hits, empty_gate, phantom_since, misses)
    return new, np.asarray(confirmed, dtype=bool)


def hand_over(
    state: LifeState, keepers: IntArray, newcomers: IntArray, why: StatusReason
) -> LifeState:
    """Each newcomer joins its keeper ([HZ] §5.1 hand-over; a duplicate's merge).

    The keeper (a phantom, or an established track) keeps its id, becomes (or
    stays) confirmed — ``reacquired`` when it was not — with the better score,
    both hit counts, a fresh empty-gate probability and no phantom time; the
    newcomer is terminated with ``why``. The callers move the estimates.
    """
    if len(keepers) == 0:
        return state
    status, reason = state.status.copy(), state.reason.copy()
    score, hits = state.score.copy(), state.hits.copy()
    empty_gate, phantom_since = state.empty_gate.copy(), state.phantom_since.copy()
    misses = state.misses.copy()
    rejoined = keepers[status[keepers] != CONFIRMED]
    status[rejoined], reason[rejoined] = CONFIRMED, reason_code(StatusReason.REACQUIRED)
    score[keepers] = np.maximum(score[keepers], score[newcomers])
    hits[keepers] += hits[newcomers]
    empty_gate[keepers] = 1.0
    phantom_since[keepers] = np.nan
    misses[keepers] = 0
    status[newcomers], reason[newcomers] = TERMINATED, reason_code(why)
    return LifeState(status, reason, score, hits, empty_gate, phantom_since, misses)
