"""Moving the measurement models into the core changed no output (issue #25).

The sha256 of every step result and of the final export of each scene of
:mod:`tests.core.models.snapshot_scenes`, recorded on main (5a97bc2) before the
change: a refactoring guard (the numbers were the service's before, and must be
its after), not an oracle — ``test_measurement.py`` holds the models against
Stone Soup and pymap3d.
"""

from __future__ import annotations

import pytest

from tests.core.models.snapshot_scenes import SCENES, run

RECORDED = {
    "linear_2d": {
        "steps": "4d9b92150734ce371448c7b9c5b826c6981aae70050d5a17e8e447e778a91072",
        "export": "ac73c5db2a822c69adfab6c431fd938554d266c92f0abc255c0ccb6ecf57f60d",
    },
    "polar_2d": {
        "steps": "f885afa5c6d5094f6a1c1e9a9cbdadb742379aa0fd2a4cb59dce2096d906cac9",
        "export": "0966c3cf29c5b679af90397e5ed22377ca3fa79e0b985d59e9097a21e2a2e94e",
    },
    "geodetic_3d_local": {
        "steps": "893927bf512ff3540dd42de464c234a89c8d8d682e66900185b6987e8ab34b48",
        "export": "dccd22ea47486ac2f8fd732e06b9b22e367f6a4836c7aab26a42d919436e5d85",
    },
    "geodetic_3d_central": {
        "steps": "e6f198cdbf1c8f66fc2b2efc92f37685995216ca2f457ff10667f8c72a958a5a",
        "export": "e1b021d9dcf77bc9e7b4b30d172aeccffc7a03135f5c8a7d8a4d26c9d20e1b63",
    },
}


@pytest.mark.parametrize("name", sorted(SCENES))
def test_outputs_bit_identical_to_main(name: str) -> None:
    """Every step's result text and the final export hash as on main before the change."""
    assert run(*SCENES[name]()) == RECORDED[name]
