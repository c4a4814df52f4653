"""Tests of choreo_graph.config.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from choreo_graph.config import GraphConfig
from choreo_graph.graph import (
    DynamicGraph,
)
from tests.graph.helpers import toy_repertoire


@pytest.mark.survivor
def test_step_ignores_segments_not_yet_inserted_and_drops_old_ones():
    rep = toy_repertoire(2, clips=4)
    warps = np.tile(np.arange(60.0, 180.0), (1, 1))
    config = GraphConfig(style_cost=1.0, transition_cost=0.0, completeness_cost=0.0, repeat_cost=0.0)
    g = DynamicGraph(rep, config)
    g.insert(0, np.array([0]), warps)
    g.insert(1, np.array([1]), warps)  # the future: not a node yet
    node = g.step(0, rep.style[1])
    assert (node.segment, node.index, node.clip) == ((0, 0), 0, 0)
    assert sorted(g.segments) == [0, 1]
    assert g.step(3, rep.style[0]).segment == (0, 0)  # second 0's segment still runs at 3
    node = g.step(4, rep.style[0])  # ...not at 4
    assert (node.segment, node.index, node.clip) == ((1, 0), 3, 1) and sorted(g.segments) == [1]
    np.testing.assert_array_equal(node.frames, np.arange(150.0, 180.0))


@pytest.mark.survivor
@pytest.mark.parametrize("field, value", [("warp_smoothing", math.nan), ("warp_smoothing", math.inf), ("warp_smoothing", 1e308),
                                          ("take_variation", math.nan), ("take_variation", math.inf), ("top_k", 0)])
def test_graph_config_refuses_non_finite_and_huge_values_by_name(field, value):
    from choreo.errors import ParameterError

    with pytest.raises(ParameterError, match=f"^{field} must be"):
        GraphConfig(**{field: value})
