"""What one step says about every row, for the life cycle (docs/algorithms.md §4, §6.5, §7.3).

A step's assembly hands :func:`core.lifecycle.advance` an
:class:`~core.lifecycle.Evidence`: which rows were hit and the ΔL of each
hit ([MTT] §4.3, eq 16), which ones the step's sensor should have seen (in
its field of view, not occluded: [HZ] §2.1), the coverage code of each
([HZ] §5.1), and log|S| of the established rows that miss (their gate
volume A_G, [HZ] §4.2). Both layers build it with these functions.
"""

from __future__ import annotations

import numpy as np

from core.arrays import BoolArray, FloatArray, IntArray
from core.geometry import Coverage, FieldOfView, Visibility
from core.lifecycle import established, everywhere, sensor_view
from core.volume import RadarVolume


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


def coverage_codes(coverage: Coverage, positions: FloatArray) -> IntArray:
    """:class:`~core.geometry.Visibility` code of each row's position (n, q) ([HZ] §5.1)."""
    count = len(positions)
    if positions.shape[1] < 2 or count == 0:
        return np.full(count, int(Visibility.VISIBLE), dtype=np.int64)
    return np.asarray(coverage.visibility(positions), dtype=np.int64)


def gate_coverage(
    coverage: Coverage, positions: FloatArray, gates: FloatArray, gate: float
) -> tuple[IntArray, BoolArray]:
    """Coverage codes of rows seen by their gate, where the coverage has 3-D radar volumes
    (docs/algorithms.md §8.11).

    A row whose predicted position no sensor sees is visible when a sensor sees its gate —
    one of the 2q ends of the gate's principal axes ``ν = ±√(gate λ_i) e_i`` (``gates``: S
    on the positions, n × q × q; ``gate``: the gate on D) — and not only in a blind zone
    or out of range: a track predicted a σ under a radar's horizon while the target is above
    it is not hidden. Returns the codes (:func:`coverage_codes` elsewhere) and
    ``sees[s, i]``: sensor ``s`` sees row ``i``'s gate where no sensor sees its position
    (False elsewhere), so that a sensor that sees its gate and does not detect it misses
    it: a track is seen, missed, or hidden, never none of the three.
    """
    codes = coverage_codes(coverage, positions)
    sees = np.zeros((len(coverage.views), len(positions)), dtype=np.bool_)
    hidden = codes != Visibility.VISIBLE
    if positions.shape[1] != 3 or not hidden.any():
        return codes, sees
    if all(volume is None for volume in coverage.volumes):
        return codes, sees
    rows = np.flatnonzero(hidden)
    values, vectors = np.linalg.eigh(gates[rows])  # (k, q), (k, q, q): columns e_i
    reach = vectors * np.sqrt(gate * np.maximum(values, 0.0))[:, None, :]
    ends = np.concatenate([reach, -reach], axis=2).transpose(0, 2, 1)  # (k, 2q, q)
    points = (positions[rows][:, None, :] + ends).reshape(-1, 3)
    seen = coverage.sees(points).reshape(len(coverage.views), len(rows), -1).any(axis=2)
    sees[:, rows] = seen
    codes[rows[seen.any(axis=0)]] = int(Visibility.VISIBLE)
    return codes, sees
