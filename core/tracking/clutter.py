"""Clutter density of a sensor estimated from its own detections (docs/algorithms.md §8.4).

When a sensor's ``clutter_density`` (β_FT) is not given, the local tracker
estimates it per sensor, scan by scan:

- **false alarms**: the detections of a scan that no established (confirmed
  or coasting) track claims;
- **region**: the axis-aligned bounding box of those detections so far (of
  every detection of a scan no track could claim), grown by ``3σ`` of the
  detections' largest noise σ on each side (a box around one detection is
  not empty): a confirmed target moving out of the clutter's region does not
  stretch it;
- **estimate**: ``β̂ = (n₀ λ₀ + Σ_k w_k c_k / V) / (n₀ + Σ_k w_k)``, with c_k the false
  alarms counted at scan k, V the current region's volume and w_k = (1 − 1/τ)^{K−k}
  an exponential forgetting of time constant τ = :data:`TIME_CONSTANT` scans; the
  prior is one false alarm per scan over the region grown by the first gate of a
  new track (λ₀ = 1 / V₀, V₀ the box grown by ``3 √(σ_v² ΔT² + σ²)`` on each side),
  weighted as n₀ = :data:`PRIOR_SCANS` scan, so that the first scans behave; a box of
  no volume (its detections' σ below the spacing of the doubles at them) gives λ₀ alone.

The detections of a target before its track is confirmed count as clutter
(a bias up by about births × scans to confirm, a few per cent on the peer
scenes); the bias runs the safe way: an estimate too high confirms fewer
tracks, so more detections stay unclaimed only while they are clutter,
where counting the detections of refuted starts (tried first) fed on
itself — clutter confirmed under a low estimate is never refuted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from core.arrays import FloatArray
from core.tracking.track import float_array, plain_floats

TIME_CONSTANT = 20.0
"""τ: scans over which the estimate forgets (a weight of 1/e after τ scans)."""
PRIOR_SCANS = 1.0
"""n₀: the prior's weight, in scans."""
BOX_SIGMAS = 3.0
"""Half-side of the smallest box around a detection, and of the prior's gate, in σ."""


@dataclass(frozen=True)
class ClutterEstimate:
    """One sensor's running estimate (module docstring); never changed in place.

    Attributes
    ----------
    false_alarms : the forgotten count of refuted detections, Σ w_k c_k.
    scans : Σ w_k, the forgotten number of scans.
    low, high : the bounding box of the sensor's detections (NaN before the first).
    """

    false_alarms: float
    scans: float
    low: FloatArray
    high: FloatArray

    @classmethod
    def empty(cls, dim: int) -> ClutterEstimate:
        return cls(0.0, 0.0, np.full(dim, np.nan), np.full(dim, np.nan))

    def widened(self, z: FloatArray, sigma: float) -> ClutterEstimate:
        """The box grown over the detections ``z`` (m, q), each at least ±3σ wide."""
        if len(z) == 0:
            return self
        margin = BOX_SIGMAS * sigma
        low = np.fmin(self.low, z.min(axis=0) - margin)
        high = np.fmax(self.high, z.max(axis=0) + margin)
        return ClutterEstimate(self.false_alarms, self.scans, low, high)

    def counted(self, false_alarms: int) -> ClutterEstimate:
        """After one more scan of the sensor, with ``false_alarms`` refuted detections."""
        keep = 1.0 - 1.0 / TIME_CONSTANT
        return ClutterEstimate(
            keep * self.false_alarms + false_alarms, keep * self.scans + 1.0, self.low, self.high
        )

    def density(self, gate: float) -> float:
        """β̂ per unit of position space per scan; ``gate`` is the prior's half-width
        growth of the box (3 √(σ_v² ΔT² + σ²))."""
        sides = self.high - self.low
        if not np.all(np.isfinite(sides)):
            raise ValueError("no detection yet: the region is unknown")
        volume = float(np.prod(sides))
        prior = 1.0 / float(np.prod(sides + 2.0 * gate))
        data = self.false_alarms / volume if volume > 0.0 else math.inf
        if not math.isfinite(data):
            # A degenerate box (``z ± 3σ`` rounded back to ``z``: a σ below the spacing of
            # the doubles at z) has no volume to spread the count over: the prior alone.
            return prior
        return (PRIOR_SCANS * prior + data) / (PRIOR_SCANS + self.scans)

    def to_plain(self) -> dict[str, Any]:
        return {
            "false_alarms": self.false_alarms,
            "scans": self.scans,
            "low": plain_floats(self.low),
            "high": plain_floats(self.high),
        }

    @classmethod
    def from_plain(cls, plain: dict[str, Any]) -> ClutterEstimate:
        return cls(
            float(plain["false_alarms"]),
            float(plain["scans"]),
            float_array(plain["low"]).reshape(-1),
            float_array(plain["high"]).reshape(-1),
        )


def prior_gate(velocity_std: float, interval: float, sigma: float) -> float:
    """The prior region's growth on each side: the first gate of a new track,
    ``3 √(σ_v² ΔT² + σ²)``."""
    return BOX_SIGMAS * math.sqrt((velocity_std * interval) ** 2 + sigma**2)
