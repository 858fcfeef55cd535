"""``bench/multisensor.py`` on a reduced scene: its detections are what it says, the same
every run, and the sessions it builds run the path it names. No timing, no Stone Soup
tracker (the bench runs those)."""

from __future__ import annotations

import numpy as np

from tests.bench_scripts import load_bench


def test_the_scene_is_deterministic_and_each_sensor_sees_its_own_cover() -> None:
    bench = load_bench("multisensor")
    first = bench.build_scene("~10", 10, 6, "sectors")
    again = bench.build_scene("~10", 10, 6, "sectors")
    assert len(first.scans) == 6 * bench.SUBSTEPS
    for one, two in zip(first.scans, again.scans, strict=True):
        assert one.sensor == two.sensor and one.time == two.time
        np.testing.assert_array_equal(one.z, two.z)
        low, high = first.covers[one.sensor]  # true detections: noise may cross the edge
        margin = 5.0 * bench.SENSORS[one.sensor][0]
        assert np.all((one.z[:, 0] >= low - margin) & (one.z[:, 0] <= high + margin))
    # staggered: sensor k scans at whole seconds + k/3 s
    assert [round(scan.time * 3) % 3 for scan in first.scans[:3]] == [0, 1, 2]
    central = bench.session_run(first, [0, 1, 2])
    local = bench.session_run(first, [0, 1, 2], local=True)
    assert len(central) == len(local) == 6  # one picture a second
    lists = bench.track_list_run(first, restarts={0: 3.0})
    assert len(lists) == 6
