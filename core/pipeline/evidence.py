"""What one step says about every row, for the life cycle (docs/algorithms.md §4, §6.5, §7.3).

A step's assembly hands :func:`core.lifecycle.advance` an
:class:`~core.lifecycle.Evidence`: which rows were hit and the ΔL of each
hit ([MTT] §4.3, eq 16), which ones the step's sensor should have seen (in
its field of view, not occluded: [HZ] §2.1; by default by their gate) and
the ΔL of their miss (ln(p_region − P_D p), §8.16), the coverage code of each
([HZ] §5.1), and log|S| of the established rows that miss (their gate
volume A_G, [HZ] §4.2). Both layers build it with these functions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

from core.arrays import BoolArray, FloatArray, IntArray
from core.geometry import Coverage, FieldOfView, Sector, Visibility, occluded
from core.lifecycle import established, everywhere, sensor_view
from core.pipeline.visibility import inside_probability
from core.volume import RadarVolume

HIDING_MISSES = 3
"""The misses in a row (the local tracker: of the step's sensor, none detecting the track
meanwhile) after which a track that no sensor sees with p ≥ ½ is hidden (a phantom) or
gone rather than missed again (docs/algorithms.md §8.16). The local tracker reads the
two latest scans of each sensor for it (``LocalTracker._scan_times``): 3 is built in there."""


def hits(count: int, rows: IntArray, increments: FloatArray) -> tuple[BoolArray, FloatArray]:
    """``detected`` and ``hit_increment`` of ``count`` rows, hit at ``rows`` by ΔL ``increments``."""
    detected = np.zeros(count, dtype=bool)
    detected[rows] = True
    hit_increment = np.zeros(count)
    hit_increment[rows] = increments
    return detected, hit_increment


def coasting_misses(status: IntArray, seen: BoolArray, detected: BoolArray) -> BoolArray:
    """Established rows the sensor should have seen and did not detect: whose gate
    volume A_G the life cycle reads ([HZ] §4.2)."""
    return np.asarray(seen & ~detected & established(status), dtype=np.bool_)


def sensor_miss_runs(runs: IntArray, column: int, seen: BoolArray, detected: BoolArray) -> IntArray:
    """Each row's misses in a row of every sensor (n, sensors) after a scan of the sensor
    ``column``: 0 where it detected the row, one more where it should have seen the row
    (``seen``: its field of view, not occluded) and did not (docs/algorithms.md §8.9)."""
    after = runs.copy()
    after[:, column] = np.where(detected, 0, runs[:, column] + (seen & ~detected))
    return after


def seen_by(
    view: FieldOfView | None,
    positions: FloatArray,
    status: IntArray,
    radius: float,
    volume: RadarVolume | None = None,
) -> tuple[BoolArray, BoolArray]:
    """Seen by the step's sensor, and occluded, of each row ([HZ] §2.1).

    ``positions`` (n, q) are the position components; fields of view are
    planar (x, y of a 3-D track); with fewer than two there is no plane and
    every row is seen. The occluders are the established rows (``status``).
    A 3-D radar's ``volume`` (:mod:`core.volume`) sees only inside its range,
    elevation limits and horizon (docs/algorithms.md §8.11).
    """
    count = len(positions)
    if positions.shape[1] < 2:
        _, seen, hidden = everywhere(count)
        return seen, hidden
    if count == 0:
        return np.zeros(0, dtype=bool), np.zeros(0, dtype=bool)
    plane = positions[:, :2]
    seen, hidden = sensor_view(view, plane, plane[established(status)], radius)
    if volume is not None:
        seen = seen & volume.contains(positions)
    return seen, hidden


@dataclass(frozen=True)
class Look:
    """What a step's sensor could see of each row (docs/algorithms.md §8.16).

    Attributes
    ----------
    codes : :class:`~core.geometry.Visibility` code of each row: visible where some
        sensor sees its gate, else a blind zone where the surveillance region holds its
        gate, else out of range.
    seen : the step's sensor sees the row's gate (p ≥ Φ(−√γ)) and no known track hides it:
        not detected, it is a miss.
    hidden : occluded: in the sensor's view but hidden by a known track ([HZ] §2.1).
    miss_increment : ΔL of a miss of each row, ``ln(p_region − P_D p)``.
    probability : p, the probability that the sensor sees the row's position.
    """

    codes: IntArray
    seen: BoolArray
    hidden: BoolArray
    miss_increment: FloatArray
    probability: FloatArray


def coverage_look(
    coverage: Coverage,
    positions: FloatArray,
    covariances: FloatArray | None,
    gate: float,
    missed: BoolArray | None = None,
) -> tuple[IntArray, FloatArray]:
    """The :class:`~core.geometry.Visibility` code of each row at ``positions`` (n, q), P =
    ``covariances`` on them, and p_region, the probability that it lies in the surveillance
    region (docs/algorithms.md §8.16).

    Visible where some sensor sees its gate of ``gate`` (on D: p ≥ Φ(−√γ) for a straight
    edge), else a blind zone where the region holds its gate, else out of range; a row
    ``missed`` before (the caller's: by the step's sensor at its previous scan) is judged
    at p ≥ ½ instead (missed again where no sensor sees it more likely than not, it is
    more likely hidden, or gone, than missed). p_region:
    the explicit region's p, or the largest of the sensors' ranges' (1 where a sensor sees
    everywhere). ``covariances`` None: the papers' test at the predicted position
    (:meth:`Coverage.visibility <core.geometry.Coverage.visibility>`).
    """
    count = len(positions)
    views = coverage.views
    if positions.shape[1] < 2 or count == 0:
        return everywhere(count)[0], np.ones(count)
    if any(
        view is None and _volume_of(coverage, index) is None for index, view in enumerate(views)
    ):
        return np.full(count, int(Visibility.VISIBLE), dtype=np.int64), np.ones(count)
    threshold = _threshold(gate)
    sees = sensor_probabilities(coverage, positions, covariances).max(axis=0, initial=0.0)
    if coverage.region is not None:
        region = inside_probability(coverage.region, None, positions, covariances)
    else:
        region = np.zeros(count)
        for index, view in enumerate(views):
            volume = _volume_of(coverage, index)
            reach = inside_probability(view, volume, positions, covariances, reach=True)
            region = np.maximum(region, reach)
    # a row missed at its latest scan is judged at p = ½ (for a straight edge: its predicted
    # position): missed again, it is more likely hidden, or gone, than seen and missed
    limit = threshold if missed is None else np.where(missed, 0.5, threshold)
    codes = np.where(
        sees >= limit,
        int(Visibility.VISIBLE),
        np.where(region >= limit, int(Visibility.BLIND_ZONE), int(Visibility.OUT_OF_RANGE)),
    )
    return np.asarray(codes, dtype=np.int64), region


def gates_seen(
    coverage: Coverage, positions: FloatArray, covariances: FloatArray | None, gate: float
) -> BoolArray:
    """Whether each sensor of ``coverage`` (first axis, in its order) sees the gate of
    ``gate`` (on D) of each row at ``positions`` (second axis), P = ``covariances`` on them:
    p ≥ Φ(−√γ) (docs/algorithms.md §8.16); ``covariances`` None: the predicted position
    inside. With fewer than two components there is no plane and every sensor sees."""
    count, sensors = len(positions), len(coverage.views)
    if count == 0 or positions.shape[1] < 2:
        return np.ones((sensors, count), dtype=bool)
    seen = sensor_probabilities(coverage, positions, covariances) >= _threshold(gate)
    return np.asarray(seen, dtype=bool)


def sensor_probabilities(
    coverage: Coverage, positions: FloatArray, covariances: FloatArray | None
) -> FloatArray:
    """p of each sensor of ``coverage`` (first axis, in its order) for each row at
    ``positions`` (second axis), P = ``covariances`` on them
    (:func:`~core.pipeline.visibility.inside_probability`, docs/algorithms.md §8.16)."""
    rows = [
        inside_probability(view, _volume_of(coverage, index), positions, covariances)
        for index, view in enumerate(coverage.views)
    ]
    return np.asarray(rows, dtype=np.float64).reshape(len(rows), len(positions))


def look(
    coverage: Coverage,
    view: FieldOfView | None,
    volume: RadarVolume | None,
    positions: FloatArray,
    covariances: FloatArray | None,
    status: IntArray,
    radius: float,
    p_detect: float,
    gate: float,
    missed: BoolArray | None = None,
) -> Look:
    """What a step's sensor (its field of view ``view`` and volume ``volume``) sees of each
    row at ``positions`` (n, q), P = ``covariances`` on them (docs/algorithms.md §8.16).

    p = :func:`~core.pipeline.visibility.inside_probability`; p_region of
    :func:`coverage_look`, at least p. A row is seen where its gate of ``gate`` (on D)
    reaches the view — for a straight edge exactly p ≥ Φ(−√γ) — and the miss of a seen row
    scores ``ln(p_region − P_D p)``: no detection and the target still in the region,
    against no target (a false track is never detected). ``covariances`` None: the papers'
    test at the predicted position (p and p_region 0 or 1, a miss ln(1 − P_D)). The
    occluders are the established rows (``status``); planar views look at the first two
    components; with fewer than two there is no plane and every row is seen. ``missed``:
    the rows judged at p ≥ ½ (:func:`coverage_look`; the tracker's: missed by the step's
    sensor at its previous scan and detected by none since); a row it hides is not seen.
    """
    count = len(positions)
    if positions.shape[1] < 2 or count == 0:
        codes, seen, hidden = everywhere(count)
        miss = np.full(count, math.log1p(-p_detect))
        return Look(codes, seen, hidden, miss, np.ones(count))
    probability = inside_probability(view, volume, positions, covariances)
    codes, region = coverage_look(coverage, positions, covariances, gate, missed)
    region = np.maximum(region, probability)
    seen = (probability >= _threshold(gate)) & (codes == Visibility.VISIBLE)
    hidden = np.zeros(count, dtype=bool)
    if radius > 0.0 and isinstance(view, Sector):
        plane = positions[:, :2]
        hidden = seen & occluded(view.origin, plane, plane[established(status)], radius)
        seen = seen & ~hidden
    with np.errstate(divide="ignore"):
        # ln(p_region − P_D p) = ln p_region + ln(1 − P_D p / p_region): exactly
        # ln(1 − P_D) at p = p_region = 1
        share = np.divide(probability, region, out=np.zeros(count), where=region > 0.0)
        miss = np.log(region) + np.log1p(-p_detect * share)
    return Look(codes, np.asarray(seen, dtype=np.bool_), hidden, miss, probability)


def _threshold(gate: float) -> float:
    """Φ(−√γ): the least p of a row whose gate of ``gate`` (on D) reaches a straight edge."""
    return float(ndtr(-math.sqrt(gate)))


def _volume_of(coverage: Coverage, index: int) -> RadarVolume | None:
    return coverage.volumes[index] if index < len(coverage.volumes) else None
