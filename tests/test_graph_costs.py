"""ChoreoGraph's cost terms, each isolated on a hand-made repertoire: style (eq. 4's first term),
transition (its last), action completeness (eq. 6's sigmoid). Each test fails if its term is
dropped, its sign flipped or its scale changed."""

from types import SimpleNamespace

import numpy as np
import pytest

import choreo_graph.graph as graph
from choreo_graph.config import NODE_FRAMES, GraphConfig
from choreo_graph.graph import DynamicGraph, Node, completeness_cost

CLIP_FRAMES = 240


def repertoire(styles, first_poses=None):
    """Clips whose every frame is one pose (so a clip's transition distance is known), each from
    its own source motion (so the repeat cost never fires)."""
    styles = np.asarray(styles, dtype=np.float32)
    count = len(styles)
    poses = np.zeros((count, CLIP_FRAMES, 24, 3), np.float32)
    if first_poses is not None:
        poses[:] = np.asarray(first_poses, np.float32)[:, None, None, :]
    return SimpleNamespace(style=styles, poses=poses, origins=(np.arange(count), np.zeros(count, int)))


def identity_warps(count):
    return np.tile(np.arange(4 * NODE_FRAMES, dtype=float), (count, 1))


def only(**weights):
    base = dict(style_cost=0.0, transition_cost=0.0, completeness_cost=0.0, repeat_cost=0.0)
    return GraphConfig(**(base | weights))


def test_style_cost_picks_the_clip_nearest_the_music_style():
    rep = repertoire([[0.0, 0.0], [1.0, 1.0], [3.0, 0.0]])
    g = DynamicGraph(rep, only(style_cost=1.0))
    g.insert(0, np.arange(3), identity_warps(3))
    assert g.step(0, np.array([0.9, 1.2])).clip == 1
    g = DynamicGraph(rep, only())  # without the term every clip costs the same: the first wins
    g.insert(0, np.arange(3), identity_warps(3))
    assert g.step(0, np.array([0.9, 1.2])).clip == 0


def test_transition_cost_picks_the_pose_nearest_the_last_one():
    rep = repertoire(np.zeros((3, 2)), first_poses=[[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.3, 0.0, 0.0]])
    g = DynamicGraph(rep, only(transition_cost=1.0))
    g.current = Node((0, 0), 3, 0, np.full(NODE_FRAMES, 100.0))  # the dancer stands in clip 0's pose
    g.insert(5, np.array([1, 2]), identity_warps(2))
    assert g.step(5, np.zeros(2)).clip == 2
    rep.poses[2] += [5.0, 0.0, 0.0]  # now clip 1 is the nearer pose
    g.current = Node((0, 0), 3, 0, np.full(NODE_FRAMES, 100.0))
    g.insert(5, np.array([1, 2]), identity_warps(2))
    assert g.step(5, np.zeros(2)).clip == 1


@pytest.mark.parametrize("gap", [10, 30, 45])
def test_completeness_is_the_papers_sigmoid_of_the_beat_gap(monkeypatch, gap):
    # motion beats on either side of the seam at NODE_FRAMES, gap frames apart
    beats = np.array([NODE_FRAMES - gap // 2, NODE_FRAMES - gap // 2 + gap])
    monkeypatch.setattr(graph, "motion_beats", lambda poses: beats)
    rep = repertoire(np.zeros((1, 2)))
    current = Node((0, 0), 0, 0, np.arange(NODE_FRAMES, dtype=float))
    value = completeness_cost(current, np.arange(4 * NODE_FRAMES, dtype=float), rep, scale=5.0)
    assert value == pytest.approx(1 / (1 + np.exp(-(NODE_FRAMES - gap) / 5.0)))


def test_completeness_cost_favours_continuing_an_action_that_runs_across_the_seam(monkeypatch):
    monkeypatch.setattr(graph, "motion_beats", lambda poses: np.array([25, 60]))  # a long action: sigmoid 0.27
    rep = repertoire([[0.5, 0.0], [0.0, 0.0]])
    for weight, expected in ((1.0, 0), (0.0, 1)):
        g = DynamicGraph(rep, only(style_cost=1.0, completeness_cost=weight))
        g.insert(0, np.arange(2), identity_warps(2))
        assert g.step(0, np.array([0.5, 0.0])).clip == 0  # the music asks for clip 0's style
        g.insert(1, np.array([1]), identity_warps(1))
        # now the music prefers clip 1 by 0.25 of style cost; continuing clip 0's action costs
        # the sigmoid (0.27) where any other node costs 1: with the term, clip 0 goes on
        assert g.step(1, np.zeros(2)).clip == expected
