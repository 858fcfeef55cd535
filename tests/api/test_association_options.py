"""The wire's association methods and options are the core registry's (one source).

Before the registry the wire kept its own tables, and the core's Mercier
``evidence`` / ``scale`` and Dang–Han ``score`` options could not be
expressed. Now every option a method's spec declares is accepted for that
method, reaches the core unchanged, and is refused for another method or out
of the method's own range with a 4xx naming the field.
"""

from __future__ import annotations

from typing import Any

import httpx
import numpy as np
import pytest
from pydantic import ValidationError

from api_schemas.config import AssociationConfig, LocalAssociationConfig
from app.sessions.translate import method_options
from core.association import REGISTRY, associate, methods
from core.association.spec import ChoiceOption, NumberOption
from tests.api.conftest import LiveServer


def a_value(option: NumberOption | ChoiceOption) -> object:
    """A valid value other than the default."""
    if isinstance(option, ChoiceOption):
        return option.choices[-1]
    high = option.high if np.isfinite(option.high) else option.low + 2.0
    return (option.low + high) / 2.0


CASES = [
    (name, option.name, a_value(option))
    for name, spec in REGISTRY.items()
    for option in spec.options
]


@pytest.mark.parametrize(("method", "name", "value"), CASES)
def test_every_core_option_is_expressible_and_reaches_the_core(
    method: str, name: str, value: object
) -> None:
    local = "track_to_track" not in REGISTRY[method].scopes
    model = LocalAssociationConfig if local else AssociationConfig
    given = {name: value}
    if name == "gate_probability" and method in ("gnn", "denoeux"):
        given = {name: 0.5}
    config = model.model_validate({"method": method, "options": given})
    core_options = method_options(config.options)
    assert core_options[name] == given[name]
    spec = REGISTRY[method]
    assert spec.parse(core_options) == spec.parse(spec.defaults(given))


def test_methods_on_the_wire_are_the_registrys() -> None:
    for method in methods("local"):
        LocalAssociationConfig.model_validate({"method": method})
    for method in methods("track_to_track"):
        AssociationConfig.model_validate({"method": method})
    with pytest.raises(ValidationError):
        AssociationConfig.model_validate({"method": "cheap_jpda"})


@pytest.mark.parametrize(
    ("method", "options", "field"),
    [
        ("hachour", {"score": "betp"}, ("options", "score")),  # another method's option
        ("gnn", {"gate_probability": 1.0}, ("options", "gate_probability")),  # gnn: (0, 1)
        ("gnn", {"threshold": 2.0, "gate_probability": 0.9}, ("options", "threshold")),
        ("mercier", {"gate_probability": 1.0}, ("options",)),  # scale 'gate' needs p < 1
        ("dang_han", {"score": "pignistic"}, ("options", "score")),
    ],
)
def test_refused_options_name_the_field(
    method: str, options: dict[str, Any], field: tuple[str, ...]
) -> None:
    with pytest.raises(ValidationError) as refused:
        AssociationConfig.model_validate({"method": method, "options": options})
    assert [tuple(error["loc"]) for error in refused.value.errors()] == [field]


def test_dang_han_score_over_the_wire(live_server: LiveServer) -> None:
    """``POST /v1/associate`` with Dang–Han's ``score: betp`` decides as the core does with it,
    and its matrix is not the default ``belief``'s: the option reaches the method."""
    rng = np.random.default_rng(4)
    known = rng.uniform(0.0, 6.0, size=(6, 2))
    incoming = known + rng.normal(0.0, 0.7, size=known.shape)

    def body(states: np.ndarray, prefix: str) -> list[dict[str, Any]]:
        return [
            {"id": f"{prefix}{i}", "state": s.tolist(), "covariance": [[1.0, 0.0], [0.0, 1.0]]}
            for i, s in enumerate(states)
        ]

    covariances = np.tile(np.eye(2), (6, 1, 1))
    matrices = {}
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        for score in ("belief", "betp"):
            answer = client.post(
                "/v1/associate",
                json={
                    "method": "dang_han",
                    "options": {"score": score},
                    "known": body(known, "k"),
                    "incoming": body(incoming, "i"),
                },
            )
            assert answer.status_code == 200, answer.text
            core = associate(
                (known, covariances), (incoming, covariances), "dang_han", {"score": score}, "mean"
            )
            pairs = {(pair["known"], pair["incoming"]) for pair in answer.json()["pairs"]}
            assert pairs == {(f"k{k}", f"i{i}") for k, i in core.assignment().items()}
            values = answer.json()["matrix"]["values"]
            matrices[score] = np.array(
                [[np.nan if v is None else v for v in row] for row in values]
            )
            n = len(known)
            np.testing.assert_allclose(matrices[score][:n], core.scores.dense(), rtol=1e-12)
    assert not np.allclose(matrices["belief"], matrices["betp"], equal_nan=True)
