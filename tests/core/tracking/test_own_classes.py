"""A session's own classes with a detecting sensor's behaviours (docs/algorithms.md §8.7):
Γ(b) is the set of the classes that allow b ([MTT] eq 23), worked as bit masks by hand
(class i is bit i of the class frame)."""

from __future__ import annotations

import numpy as np
import pytest

from core.errors import ModelConfigError
from core.tracking.presets import preset, with_classes


def test_the_preset_gamma_is_the_case_liner_b1_bomber_b1_b2_fighter_b1_b2_b3() -> None:
    aircraft = preset("aircraft")
    # liner = 1, bomber = 2, fighter = 4: Γ(b1) = all, Γ(b2) = bomber|fighter, Γ(b3) = fighter
    np.testing.assert_array_equal(aircraft.relation.images, [7, 6, 4])
    own = with_classes(
        aircraft, {"liner": ["b1"], "bomber": ["b1", "b2"], "fighter": ["b1", "b2", "b3"]}
    )
    np.testing.assert_array_equal(own.relation.images, aircraft.relation.images)


def test_own_class_names_take_the_behaviours_the_user_allows() -> None:
    own = with_classes(
        preset("aircraft"), {"drone": ["b1", "b2"], "jet": ["b1"], "missile": ["b2", "b3"]}
    )
    assert own.classes.labels == ("drone", "jet", "missile")
    # drone = 1, jet = 2, missile = 4: Γ(b1) = drone|jet, Γ(b2) = drone|missile, Γ(b3) = missile
    np.testing.assert_array_equal(own.relation.images, [3, 5, 4])


@pytest.mark.parametrize(
    ("allowed", "named"),
    [({"jet": ["b1", "b9"], "missile": ["b2", "b3"]}, "b9"), ({"jet": ["b1", "b2"]}, "b3")],
)
def test_an_unknown_or_unallowed_behaviour_is_refused(
    allowed: dict[str, list[str]], named: str
) -> None:
    with pytest.raises(ModelConfigError, match=named):
        with_classes(preset("aircraft"), allowed)
