"""Track life cycle: status, reasons, SPRT score and gate-emptiness termination.

Shared by the local tracker (ALGORITHMS.md §4) and the fusion engine (§6).

Track score ([MTT] §4.3, eq 16; Blackman & Popoli pp. 327-334), a sequential
probability ratio test on "true track" vs "false track":

- a new track starts at ``L₀ = ln(β_NT / β_FT)``;
- a hit adds ``ΔL = ln[P_D / ((2π)^{q/2} β_FT √|S|)] − D/2``;
- a miss adds ``ΔL = ln(1 − P_D)``;
- confirm when ``L ≥ ln((1 − β) / α)``, delete when ``L ≤ ln(β / (1 − α))``,

with α = P(false track confirmed) and β = P(true track deleted). The papers
call the thresholds T1 / T2 and swap them between texts; here they are only
ever called *confirm* and *delete*.

Termination by gate emptiness ([HZ] §4.2): while a track coasts, the
probability of having found nothing in its gate is
``P = Π_k [1 − (ρ_FA + ρ_NT) A_G(k)]`` (each factor clipped at 0), with gate
volume ``A_G = c_q γ^{q/2} √|S|`` (c_q the volume of the unit q-ball, γ the
gate on D). The track is terminated when P falls below
``termination_probability`` (0.5 in [HZ] §6).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from core.arrays import FloatArray
from core.errors import InvalidInput


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


def _check_probability(value: float, name: str, *, open_interval: bool = True) -> None:
    low_ok = value > 0.0 if open_interval else value >= 0.0
    high_ok = value < 1.0 if open_interval else value <= 1.0
    if not (math.isfinite(value) and low_ok and high_ok):
        interval = "(0, 1)" if open_interval else "[0, 1]"
        raise InvalidInput(f"{name} must be in {interval}, got {value!r}")


@dataclass(frozen=True)
class ScoreModel:
    """Parameters of the SPRT track score.

    Attributes
    ----------
    p_detect : P_D, probability of detection.
    false_target_density : β_FT, false alarms per unit volume of measurement space per scan.
    new_target_density : β_NT, new targets per unit volume per scan.
    false_confirmation : α, P(a false track is confirmed).
    true_deletion : β, P(a true track is deleted).
    """

    p_detect: float = 0.9
    false_target_density: float = 1e-6
    new_target_density: float = 1e-6
    false_confirmation: float = 1e-3
    true_deletion: float = 1e-2

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

    @property
    def confirm_threshold(self) -> float:
        """Confirm when L ≥ ln((1 − β) / α)."""
        return math.log((1.0 - self.true_deletion) / self.false_confirmation)

    @property
    def delete_threshold(self) -> float:
        """Delete when L ≤ ln(β / (1 − α))."""
        return math.log(self.true_deletion / (1.0 - self.false_confirmation))

    @property
    def miss_increment(self) -> float:
        """ΔL on a miss: ln(1 − P_D)."""
        return math.log1p(-self.p_detect)

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
