"""Cheap JPDA weights ([DH] §2, eq 16) against a direct computation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from core.association import cheap_jpda_weights
from core.errors import OptionError


def test_weights_match_the_formula():
    # two tracks, three measurements, S = I (q = 2): G = exp(−|z − ẑ|²/2) / (2π)
    tracks = np.array([[0.0, 0.0], [2.0, 0.0]])
    measurements = np.array([[0.5, 0.0], [1.5, 0.0], [40.0, 0.0]])
    s = np.tile(np.eye(2), (2, 1, 1))
    bias = 0.05
    result = cheap_jpda_weights(tracks, s, measurements, bias=bias)
    g = np.array(
        [
            [math.exp(-0.5 * np.sum((z - t) ** 2)) / (2 * math.pi) for z in measurements]
            for t in tracks
        ]
    )
    g[:, 2] = 0.0  # far outside the 0.999 gate (D = 1600)
    beta = g / (g.sum(axis=1, keepdims=True) + g.sum(axis=0, keepdims=True) - g + bias)
    dense = np.zeros((2, 3))
    dense[result.rows, result.cols] = result.weights
    assert_allclose(dense, beta, rtol=1e-12)
    assert_allclose(result.none, 1 - beta.sum(axis=1), rtol=1e-12)
    nu = np.array(
        [sum(beta[t, j] * (measurements[j] - tracks[t]) for j in range(3)) for t in range(2)]
    )
    assert_allclose(result.innovation, nu, atol=1e-15)
    # symmetric layout: ν of track 0 is +x, of track 1 is −x
    assert result.innovation[0, 0] > 0 > result.innovation[1, 0]


def test_bias_is_validated():
    with pytest.raises(OptionError, match="'bias'"):
        cheap_jpda_weights(np.zeros((1, 2)), np.eye(2)[None], np.zeros((1, 2)), bias=-1.0)
