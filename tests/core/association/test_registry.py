"""The registry of association methods: scopes, option declarations, gated pairs returned.

Each method is one :class:`MethodSpec`; these tests check what the registry
promises its readers (the engine, the local tracker, the wire) against
independent computations: defaults are the documented ones, a local-only
method is refused track-to-track, ``cheap_jpda``'s weights through the
registry are [DH] eq 16 computed by hand, and a method that gates its own way
runs in the local tracker (its result carries its pairs; no side channel).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from numpy.testing import assert_allclose

from core.association import REGISTRY, associate, associate_measurements, methods
from core.association.gnn import GnnOptions, associate_gnn
from core.association.problem import AssociationProblem
from core.association.result import AssociationResult
from core.association.spec import BOTH_SCOPES, MethodSpec, NumberOption
from core.errors import InvalidInput, OptionError
from core.simulation import overtaking_scenario
from core.tracking.config import LocalTrackerConfig
from core.tracking.models import ModelBank
from core.tracking.tracker import LocalTracker


def test_scopes() -> None:
    assert methods("track_to_track") == ("gnn", "denoeux", "hachour", "mercier", "dang_han")
    assert set(methods("local")) >= {*methods("track_to_track"), "cheap_jpda"}
    assert "cheap_jpda" not in methods("track_to_track")


def test_documented_defaults() -> None:
    """docs/algorithms.md §3.7 and each method module's docstring."""
    assert REGISTRY["gnn"].parse({}) == GnnOptions(None, 0.999)
    assert REGISTRY["gnn"].parse({"threshold": 3.0}) == GnnOptions(3.0, None)
    denoeux = REGISTRY["denoeux"].parse({})
    assert (denoeux.gamma, denoeux.gate_probability, denoeux.alpha) == (None, 0.999, 1.0)
    mercier = REGISTRY["mercier"].parse({})
    assert (mercier.alpha, mercier.gate_probability, mercier.evidence, mercier.scale) == (
        0.9,
        0.999,
        "fuzzy",
        "gate",
    )
    assert REGISTRY["dang_han"].parse({}).score == "belief"
    assert {name: spec.distance for name, spec in REGISTRY.items()}["denoeux"] == "sum"


@pytest.mark.parametrize("name", list(REGISTRY))
def test_the_shown_defaults_parse_to_the_defaults(name: str) -> None:
    """What a resolved configuration shows (``defaults``) means what giving nothing means."""
    spec = REGISTRY[name]
    assert spec.parse(spec.defaults({})) == spec.parse({})


def test_exclusive_options_and_ranges_are_refused_by_name() -> None:
    with pytest.raises(OptionError, match="threshold"):
        REGISTRY["gnn"].parse({"threshold": 1.0, "gate_probability": 0.9})
    with pytest.raises(OptionError, match="'score'"):
        REGISTRY["dang_han"].parse({"score": "plausibility"})
    with pytest.raises(OptionError, match="scale"):
        REGISTRY["mercier"].parse({"gate_probability": 1.0})
    assert REGISTRY["mercier"].parse({"gate_probability": 1.0, "scale": "fixed"}).scale == "fixed"


def test_a_local_method_is_refused_track_to_track() -> None:
    states = np.zeros((1, 2))
    covariances = np.eye(2)[None]
    with pytest.raises(InvalidInput, match="unknown association method 'cheap_jpda'"):
        associate((states, covariances), (states, covariances), "cheap_jpda", {"bias": 0.1})


def test_cheap_jpda_through_the_registry_is_eq_16() -> None:
    """Two tracks (S = I), three detections, one far: β_tj = G / (S_t + S_j − G + B)."""
    tracks = np.array([[0.0, 0.0], [2.0, 0.0]])
    z = np.array([[0.5, 0.0], [1.5, 0.0], [40.0, 0.0]])
    bias = 0.05
    result = associate_measurements(
        tracks, np.tile(np.eye(2), (2, 1, 1)), z, "cheap_jpda", {"bias": bias}
    )
    g = np.array(
        [[math.exp(-0.5 * np.sum((zj - t) ** 2)) / (2 * math.pi) for zj in z] for t in tracks]
    )
    g[:, 2] = 0.0  # D = 1600, outside the 0.999 gate
    beta = g / (g.sum(axis=1, keepdims=True) + g.sum(axis=0, keepdims=True) - g + bias)
    assert_allclose(result.scores.dense(), beta, rtol=1e-12)
    # each detection goes to its most probable track; the far one to none
    assert result.assignment() == {0: 0, 1: 1}
    assert result.new.tolist() == [2]
    assert result.gated is not None and len(result.gated) == 4
    with pytest.raises(OptionError, match="bias"):  # no clutter density known here
        associate_measurements(tracks, np.tile(np.eye(2), (2, 1, 1)), z, "cheap_jpda")


def _gnn_on_the_combined_prediction(
    problem: AssociationProblem, options: GnnOptions
) -> AssociationResult:
    """GNN gated on the model-combined ẑ, S directly, never asking the tracker's gating."""
    own = AssociationProblem(problem.known, problem.incoming, problem.distance)
    return associate_gnn(own, options)


def test_a_method_that_gates_its_own_way_runs_in_the_local_tracker(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Before the registry, the tracker read the pairs from a side channel of the tracker's
    gating (``problem.last["pairs"]``): this method, which never asks it, failed with a
    KeyError. Now the result carries the pairs; with one model the combined prediction is
    the model's, so the tracks are those of ``gnn`` itself."""
    spec: MethodSpec[Any] = MethodSpec(
        name="gnn_combined",
        scopes=BOTH_SCOPES,
        options=(NumberOption("gate_probability", 0.999, low=0.0, high=1.0, high_open=True),),
        build=lambda values: GnnOptions(None, values["gate_probability"]),
        run=_gnn_on_the_combined_prediction,
    )
    monkeypatch.setitem(REGISTRY, spec.name, spec)
    scenario = overtaking_scenario(seed=1)
    bank = ModelBank.from_config(
        {
            "time_interval": 0.1,
            "measurement": {"variance": 0.1},
            "models": [{"kind": "constant_velocity", "name": "cv", "noise_intensity": 1.0}],
        }
    )
    outputs = {}
    for name in ("gnn", "gnn_combined"):
        config = LocalTrackerConfig(
            bank=bank, time_interval=0.1, association_method=name, imm_distance="combined"
        )
        tracker = LocalTracker(config)
        outputs[name] = [
            tracker.step(scan.time, scan.measurements).assignment for scan in scenario.scans
        ]
    assert outputs["gnn_combined"] == outputs["gnn"]
    assert any(any(step) for step in outputs["gnn"])


def test_parsing_is_memoised_per_value_and_type() -> None:
    """``associate`` parses at every call: a configuration is parsed once, but ``True`` is not
    taken for the ``1`` it equals (a bool is refused where a number is due)."""
    spec = REGISTRY["mercier"]
    assert spec.parse({"alpha": 1}) is spec.parse({"alpha": 1})
    with pytest.raises(OptionError, match="must be a number"):
        spec.parse({"alpha": True})
