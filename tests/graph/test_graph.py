"""Tests of choreo_graph.graph.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

from __future__ import annotations

import math
from itertools import product
from types import SimpleNamespace

import numpy as np
import pytest
import torch

import choreo_graph.graph as graph
from choreo.motion import Motion
from choreo.motion.beats import motion_beats
from choreo.motion.stitch import crossfade, facing_yaw, placement_onto, turned_and_moved
from choreo_graph.config import NODE_FRAMES, GraphConfig, StyleConfig
from choreo_graph.graph import (
    DynamicGraph,
    MusicWindows,
    Node,
    assemble,
    completeness_cost,
    music_windows,
    played_clips,
    replayed_nodes,
    replaying,
    search_graph,
    select_candidates,
    source_spans,
    warp_candidates,
)
from choreo_graph.warp import warp_frames
from tests.graph.helpers import toy_repertoire

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


SECOND = 30  # frames of a graph node


# -- selection and warping of candidates ------------------------------------------------------------
class FakeModel:
    """Style = per-window sums, beats = the first mel value, tempo-density = the first mel band."""

    def __init__(self):
        self.batches = []

    def music_style(self, batch):
        self.batches.append(len(batch))
        return torch.stack([batch.sum((1, 2)), batch[:, :, 1].mean(1)], -1), batch[:, 0, 0]

    def music_tempo_density(self, batch):
        return batch[:, :, 0] * 2


@pytest.mark.survivor
@pytest.mark.parametrize("seconds", [range(0, 70), range(5, 9)])
def test_music_windows_are_4_s_from_each_second_holding_the_last_frame(seconds):
    mel = np.random.default_rng(0).random((2000, 2)).astype(np.float32)  # 66.7 s
    model = FakeModel()
    windows = music_windows(model, mel, seconds)
    assert max(model.batches) <= 64 and sum(model.batches) == len(seconds)
    assert windows.style.shape == (len(seconds), 2) and windows.tempo.shape == (len(seconds), 120)
    for row, t in enumerate(seconds):
        window = np.array([mel[min(t * 30 + f, len(mel) - 1)] for f in range(120)])
        np.testing.assert_allclose(windows.style[row], [window.sum(), window[:, 1].mean()], rtol=1e-5)
        assert windows.beats[row] == window[0, 0]
        np.testing.assert_array_equal(windows.tempo[row], window[:, 0] * 2)


@pytest.mark.survivor
@pytest.mark.parametrize("clips, cases", [
    (12, ((1, None), (2, None), (5, None), (12, None), (40, None), (1, "every third"), (3, "every third"),
          (40, "every third"))),
    (300, ((1, None), (5, None), (17, "every third"))),  # past numpy's small-array sort inside argpartition
])
def test_select_candidates_are_the_k_cheapest_by_eq_1(clips, cases):
    rng = np.random.default_rng(4)
    windows = MusicWindows(rng.random((20, 3)), rng.random(20) * 8, np.zeros((20, 120)))
    style, beat_counts = rng.random((clips, 3)), rng.random(clips) * 8
    repertoire = type("Clips", (), {"style": style, "beat_counts": beat_counts, "__len__": lambda self: clips})()
    weights = StyleConfig(style_weight=0.7, beat_weight=0.05)
    for top_k, mask in cases:
        allowed = None if mask is None else np.arange(clips) % 3 != 1
        chosen = select_candidates(windows, repertoire, top_k, weights, allowed)
        for n in range(20):
            costs = []
            for c in range(clips):
                if allowed is None or allowed[c]:
                    distance = sum((windows.style[n, d] - style[c, d]) ** 2 for d in range(3))
                    costs.append((0.7 * distance + 0.05 * (windows.beats[n] - beat_counts[c]) ** 2, c))
            assert chosen[n].tolist() == [c for _, c in sorted(costs)][:top_k]


@pytest.mark.survivor
def test_warp_candidates_retimes_every_pair_or_plays_the_middle(monkeypatch):
    rng = np.random.default_rng(5)
    windows = MusicWindows(np.zeros((3, 2)), np.zeros(3), rng.random((3, 120)))
    repertoire = SimpleNamespace(tempo=rng.random((5, 240)))
    candidates = np.array([[4, 0], [2, 2], [1, 3]])
    config = GraphConfig(dtw_stride=3, warp_smoothing=2.0)
    monkeypatch.setattr(graph, "WARP_CHUNK", 4)  # chunks of 4 pairs: the last one short
    frames = warp_candidates(windows, candidates, repertoire, config)
    assert frames.shape == (3, 2, 120)
    for n, k in product(range(3), range(2)):
        expected = warp_frames(windows.tempo[n : n + 1], repertoire.tempo[candidates[n, k]][None], 3, 2.0)[0]
        np.testing.assert_allclose(frames[n, k], expected, atol=1e-12)
    middle = warp_candidates(windows, candidates, repertoire, GraphConfig(retempo=False))
    assert middle.shape == (3, 2, 120) and middle.dtype == np.float64  # fractional clip frames, as warped ones
    assert (middle == np.arange(60, 180)).all()


# -- the graph: nodes, costs and the greedy walk --------------------------------------------------------
@pytest.mark.survivor
def test_node_continues_only_its_own_segment_one_second_on():
    frames = np.zeros(SECOND)
    a = Node((3, 1), 1, 7, frames)
    assert Node((3, 1), 2, 7, frames).continues(a)
    assert not Node((3, 1), 3, 7, frames).continues(a)
    assert not Node((3, 1), 1, 7, frames).continues(a)
    assert not Node((3, 0), 2, 7, frames).continues(a)
    assert not Node((4, 1), 2, 7, frames).continues(a)
    assert not a.continues(None)


def beat_recorder(monkeypatch, beats):
    seen = []

    def fake(poses):
        seen.append(np.array(poses))
        return np.array(beats)

    monkeypatch.setattr(graph, "motion_beats", fake)
    return seen


@pytest.mark.survivor
@pytest.mark.parametrize("beats, gap", [
    ([3, 12, 29, 30, 55], 1),  # the last beat before the seam (29) and the first from it (30)
    ([10, 40], 30), ([25, 60 - 1], 34), ([0, 59], 59),
    ([5, 20], 60), ([31, 50], 60), ([], 60),  # no beat on one side: the gap counts as two seconds
])
@pytest.mark.parametrize("scale, index", [(5.0, 1), (2.0, 2), (3.0, 0)])
def test_completeness_cost_is_the_sigmoid_of_the_gap_around_the_seam(monkeypatch, beats, gap, scale, index):
    seen = beat_recorder(monkeypatch, beats)
    poses = np.random.default_rng(0).random((2, 240, 3, 3)).astype(np.float16)
    repertoire = SimpleNamespace(poses=poses)
    warp = 20.1 + 1.25 * np.arange(120)  # fractional frames (never halves): rounded to the nearest
    current = Node((0, 0), index, 1, warp[30 * index : 30 * index + 30])
    value = completeness_cost(current, warp, repertoire, scale)
    assert value == pytest.approx(1 / (1 + math.exp(-(30 - gap) / scale)), rel=1e-12)
    frames = [int(np.floor(x + 0.5)) for x in warp[30 * index : 30 * index + 60]]  # this second and the next
    np.testing.assert_array_equal(seen[0], poses[1, frames].astype(np.float32))


@pytest.mark.survivor
def test_source_spans_and_replaying_by_hand():
    repertoire = SimpleNamespace(origins=(np.array([0, 0, 1]), np.array([0, 60, 0])))
    spans = source_spans(repertoire, np.array([1, 2]), np.array([3, 4]), np.array([10.5, 20.0]))
    np.testing.assert_array_equal(spans, [[0, 63, 70.5], [1, 4, 20]])
    np.testing.assert_array_equal(source_spans(repertoire, 1, 2.0, 5.0), [0, 62, 65])
    played = np.array([[0, 100, 130], [1, 40, 70]])
    candidates = np.array([
        [0, 123, 150],  # 7 frames shared: allowed
        [0, 122.75, 150],  # 7.25: a replay
        [0, 90, 108],  # 8: a replay
        [1, 100, 130],  # other motion, same frames: fine
        [1, 62, 90],  # 8 with the second played span
        [0, 40, 70],  # the second span's frames, but of motion 0
        [0, 131, 140],  # after it
    ])
    assert replaying(candidates, played).tolist() == [False, True, True, False, True, False, False]
    assert replaying(candidates, played[:0]).tolist() == [False] * 7


def random_warps(rng, count):
    start = rng.uniform(0, 50, (count, 1))
    return start + np.cumsum(rng.uniform(0.5, 1.5, (count, 120)), 1) - 1


class LiteralGraph:
    """The greedy walk of eq. 4 written out node by node: every active node's style, transition,
    completeness and repeat cost, the first cheapest wins."""

    def __init__(self, repertoire, config, seed=0):
        self.rep, self.config = repertoire, config
        self.rng = np.random.default_rng(seed) if config.take_variation > 0 else None
        self.segments, self.current, self.played = {}, None, []

    def step(self, t, music_style):
        config, rep, current = self.config, self.rep, self.current
        sources, starts = rep.origins
        nodes = []
        for s in sorted(self.segments):
            live = s <= t <= s + 3 if config.dynamic else s == t
            if live:
                clips, warps = self.segments[s]
                nodes += [(s, r, t - s, int(clips[r]), warps[r]) for r in range(len(clips))]
        self.played = [(when, span) for when, span in self.played if when > t - config.repeat_memory]
        costs = []
        for s, r, index, clip, warp in nodes:
            first = int(np.rint(warp[30 * index]))
            last = warp[30 * index + 29]
            cost = 0.0
            if config.dynamic:
                cost += config.style_cost * float(np.sum((rep.style[clip] - music_style) ** 2))
            if current is not None:
                here = rep.poses[current[2], int(round(current[3][-1]))].astype(np.float32)
                there = rep.poses[clip, first].astype(np.float32)
                cost += config.transition_cost * float(np.mean(np.sum((there - here) ** 2, -1)))
                if config.dynamic:
                    if (s, r) == current[0] and index == current[1] + 1:
                        a = current[1] * 30
                        frames = [int(np.rint(x)) for x in warp[a : a + 60]]
                        beats = motion_beats(rep.poses[clip, frames].astype(np.float32))
                        before, after = [b for b in beats if b < 30], [b for b in beats if b >= 30]
                        gap = after[0] - before[-1] if before and after else 60
                        cost += config.completeness_cost / (1 + math.exp(-(30 - gap) / config.completeness_scale))
                    else:
                        cost += config.completeness_cost
            if config.repeat_cost:
                span = (sources[clip], starts[clip] + first, starts[clip] + last)
                if any(p[0] == span[0] and min(p[2], span[2]) - max(p[1], span[1]) > 7 for _, p in self.played):
                    cost += config.repeat_cost
            costs.append(cost)
        costs = np.array(costs)
        if self.rng is not None:
            costs = costs + config.take_variation * costs.std() * self.rng.standard_normal(len(costs))
        s, r, index, clip, warp = nodes[int(np.argmin(costs))]
        frames = warp[30 * index : 30 * index + 30]
        self.current = ((s, r), index, clip, frames)
        self.played.append((t, (sources[clip], starts[clip] + frames[0], starts[clip] + frames[-1])))
        return self.current


def same_node(node, literal):
    return (node.segment, node.index, node.clip) == literal[:3] and np.array_equal(node.frames, literal[3])


CONFIGS = {
    "paper": GraphConfig(repeat_cost=0.0, take_variation=0.0),
    "all": GraphConfig(style_cost=0.3, transition_cost=2.0, completeness_cost=0.4, completeness_scale=3.0,
                       repeat_cost=0.5, repeat_memory=3),
    "transition": GraphConfig(style_cost=0.0, transition_cost=1.0, completeness_cost=0.0, repeat_cost=0.0),
    "completeness": GraphConfig(style_cost=0.05, transition_cost=0.0, completeness_cost=1.0, completeness_scale=8.0,
                                repeat_cost=0.0),
    "repeat": GraphConfig(style_cost=0.0, transition_cost=0.05, completeness_cost=0.0, repeat_cost=1.0, repeat_memory=4),
    "motion graph": GraphConfig(dynamic=False, transition_cost=1.0, repeat_cost=0.3, repeat_memory=5),
}


@pytest.mark.survivor
@pytest.mark.parametrize("name", list(CONFIGS))
@pytest.mark.parametrize("seed", [0, 7])
def test_search_graph_is_the_literal_greedy_walk(name, seed):
    config = CONFIGS[name]
    rng = np.random.default_rng(11)
    rep = toy_repertoire(1, clips=6)
    seconds, k = 12, 3
    candidates = rng.integers(0, 6, (seconds, k))
    warps = random_warps(rng, seconds * k).reshape(seconds, k, 120)
    windows = MusicWindows(rng.random((seconds, 2)), np.zeros(seconds), np.zeros((seconds, 120)))
    path = search_graph(windows, candidates, warps, rep, config, seed=seed)
    literal = LiteralGraph(rep, config, seed)
    assert len(path) == seconds
    for t, node in enumerate(path):
        literal.segments[t] = (candidates[t], warps[t])
        assert same_node(node, literal.step(t, windows.style[t])), (name, seed, t)
    if name == "all":  # the walk the literal one takes is not a trivial one
        assert len({n.segment for n in path}) > 2 and any(n.index > 0 for n in path)


@pytest.mark.survivor
def test_step_ties_go_to_the_oldest_segment_and_the_first_rank():
    rep = toy_repertoire(3, clips=2)
    rep.style[:] = 0
    g = DynamicGraph(rep, GraphConfig(completeness_cost=0.0, transition_cost=0.0, repeat_cost=0.0))
    warps = np.tile(np.arange(60.0, 180.0), (2, 1))
    g.insert(0, np.array([1, 0]), warps)
    g.insert(1, np.array([0, 1]), warps)
    assert g.step(1, np.zeros(2)).segment == (0, 0)


@pytest.mark.survivor
def test_repeat_cost_forgets_after_repeat_memory_seconds():
    rep = SimpleNamespace(origins=(np.array([0]), np.array([0])))
    g = DynamicGraph(rep, GraphConfig(repeat_cost=2.5, repeat_memory=3))
    g.remember(10, Node((10, 0), 0, 0, np.arange(40.0, 70.0)))
    spans = np.array([[0, 50, 80], [0, 61, 100], [1, 50, 80]], float)
    assert g.repeat_cost(12, spans).tolist() == [2.5, 2.5, 0.0]
    assert g.repeat_cost(13, spans).tolist() == [0.0, 0.0, 0.0] and not g.played
    assert DynamicGraph(rep, GraphConfig(repeat_cost=0.0)).repeat_cost(0, spans).tolist() == [0.0] * 3
    off = DynamicGraph(rep, GraphConfig(repeat_cost=0.0, repeat_memory=3))
    off.played.append((0, np.array([0, 50, 80.0])))
    assert off.repeat_cost(1, spans).tolist() == [0.0] * 3


@pytest.mark.survivor
def test_repeat_cost_counts_a_node_from_its_first_to_its_last_frame():
    rep = SimpleNamespace(style=np.array([[0.0], [1.0]]), poses=np.zeros((2, 240, 2, 3), np.float16),
                          origins=(np.array([0, 1]), np.array([0, 0])))
    config = GraphConfig(style_cost=1.0, transition_cost=0.0, completeness_cost=0.0, repeat_cost=10.0)
    for played_from, expected in ((21.0, 1), (22.0, 0)):  # clip 0's node plays 0..29: 8 frames shared, then 7
        g = DynamicGraph(rep, config)
        g.played.append((0, np.array([0, played_from, 60.0])))
        g.insert(1, np.array([0, 1]), np.tile(np.arange(120.0), (2, 1)))
        assert g.step(1, np.zeros(1)).clip == expected
    g = DynamicGraph(SimpleNamespace(origins=(np.array([0, 3]), np.array([0, 50]))), config)
    g.remember(4, Node((4, 0), 0, 1, np.arange(10.0, 40.0)))
    assert g.played[-1][0] == 4 and g.played[-1][1].tolist() == [3, 60, 89]


@pytest.mark.survivor
def test_every_seed_is_a_take_and_no_variation_is_the_papers_walk():
    rng = np.random.default_rng(12)
    rep = toy_repertoire(4, clips=6)
    candidates = rng.integers(0, 6, (8, 3))
    warps = random_warps(rng, 24).reshape(8, 3, 120)
    windows = MusicWindows(rng.random((8, 2)), np.zeros(8), np.zeros((8, 120)))

    def take(variation: float, seed: int) -> list:
        config = GraphConfig(take_variation=variation, repeat_cost=0.0)
        return [(n.segment, n.index) for n in search_graph(windows, candidates, warps, rep, config, seed)]

    assert take(5.0, 0) == take(5.0, 0)  # a take is repeatable
    assert take(5.0, 0) != take(0.0, 0)  # seed 0 is a take too
    assert take(5.0, 0) != take(5.0, 1)
    assert take(0.0, 0) == take(0.0, 1)  # without variation the seed changes nothing


@pytest.mark.survivor
def test_take_variation_needs_a_weight_and_under_constraints_a_seed():
    rep = toy_repertoire()
    assert DynamicGraph(rep, GraphConfig(), seed=0).rng is not None
    assert DynamicGraph(rep, GraphConfig(take_variation=0.0), seed=4).rng is None
    guide = SimpleNamespace(constrained=True)  # the walk is under constraints
    assert DynamicGraph(rep, GraphConfig(), seed=0, guide=guide).rng is None  # the greedy walk
    assert DynamicGraph(rep, GraphConfig(), seed=3, guide=guide).rng is not None
    floor_only = SimpleNamespace(constrained=False)  # a free walk kept on its floor is a take like any other
    assert DynamicGraph(rep, GraphConfig(), seed=0, guide=floor_only).rng is not None


def path_of(spec):
    return [Node(segment, index, clip, np.asarray(frames, float)) for segment, index, clip, frames in spec]


@pytest.mark.survivor
def test_played_runs_list_each_stretch_of_continuing_nodes():
    repertoire = SimpleNamespace(names=np.array(["sway@60", "plain", "a@b@0"]),
                                 origins=(np.array([1, 0, 2]), np.array([60, 0, 0])))
    path = path_of([
        ((0, 0), 0, 0, np.linspace(10.123, 39.5, 30)),
        ((0, 0), 1, 0, np.linspace(40, 70.4567, 30)),
        ((0, 0), 3, 0, np.linspace(90, 100, 30)),  # skips a second: a new run
        ((3, 1), 0, 2, np.linspace(5, 34, 30)),
        ((3, 1), 1, 2, np.linspace(35, 64, 30)),
        ((5, 0), 0, 1, np.linspace(7, 36, 30)),
    ])
    assert played_clips(path, repertoire) == [
        {"clip": "sway@60", "source": "sway", "source_frames": [70.12, 130.46], "output_frames": [0, 59]},
        {"clip": "sway@60", "source": "sway", "source_frames": [150.0, 160.0], "output_frames": [60, 89]},
        {"clip": "a@b@0", "source": "a@b", "source_frames": [5.0, 64.0], "output_frames": [90, 149]},
        {"clip": "plain", "source": "plain", "source_frames": [7.0, 36.0], "output_frames": [150, 179]},
    ]


@pytest.mark.survivor
def test_replayed_nodes_counts_replays_within_memory():
    repertoire = SimpleNamespace(origins=(np.array([0, 0, 1]), np.array([0, 100, 0])))
    path = path_of([
        ((0, 0), 0, 0, np.arange(100.0, 130.0)),  # motion 0, 100..129
        ((1, 0), 0, 1, np.arange(18.0, 48.0)),  # 118..147 of the same motion through clip 1: a replay
        ((2, 0), 0, 2, np.arange(0.0, 30.0)),  # motion 1
        ((3, 0), 0, 1, np.arange(40.0, 70.0)),  # motion 0, 140..169: new
        ((4, 0), 0, 0, np.arange(85.0, 115.0)),  # 85..114: replays the first node only, four nodes back
    ])
    assert replayed_nodes(path, repertoire, 30) == 2
    assert replayed_nodes(path, repertoire, 4) == 2
    assert replayed_nodes(path, repertoire, 3) == 1  # the first node is out of a 3-node memory
    assert replayed_nodes(path, repertoire, 1) == 1
    # from the first frame to the last: 8 frames shared is a replay, 7 is not
    shared = lambda a, b: replayed_nodes(path_of([((0, 0), 0, 0, np.arange(100.0, 130.0)),  # noqa: E731
                                                  ((1, 0), 0, 0, np.arange(a, b))]), repertoire, 30)
    assert shared(121.0, 151.0) == 1 and shared(122.0, 152.0) == 0


def swaying(seconds=8.0, phase=0.0):
    t = np.arange(int(seconds * 30)) / 30
    axis_angle = np.zeros((len(t), 24, 3))
    axis_angle[:, 16, 2] = 0.8 * np.sin(2 * np.pi * t + phase)
    axis_angle[:, 1, 0] = 0.3 * np.sin(np.pi * t + phase)
    axis_angle[:, 0, 1] = 0.2 * t + phase
    root = np.stack([0.3 * np.sin(0.5 * t) + phase, 0.95 + 0.02 * np.sin(4 * t), 0.2 * t - phase], -1)
    return Motion.from_axis_angle(root, axis_angle, fps=30)


@pytest.mark.survivor
@pytest.mark.parametrize("blend", [6, 3])
def test_assemble_places_runs_and_crossfades_jumps(blend):
    motions = [swaying(phase=0.0), swaying(phase=1.3), swaying(phase=2.1)]
    calls = []
    repertoire = SimpleNamespace(clip_motion=lambda i: calls.append(i) or motions[i])
    path = path_of([
        ((0, 0), 0, 0, np.arange(10.0, 40.0)),
        ((0, 0), 1, 0, np.linspace(40.5, 98.5, 30)),  # continues, twice as fast: the same placement
        ((1, 2), 0, 1, np.linspace(100, 158, 30)),  # a jump after a 2x node
        ((2, 0), 0, 2, np.concatenate([np.linspace(50, 70, 29), [70.0]])),  # ends on a standstill
        ((3, 1), 1, 0, np.arange(80.0, 110.0)),  # a jump after a stalled node: ahead at 0.5x
    ])
    out = assemble(path, repertoire, blend)
    assert sorted(set(calls)) == [0, 1, 2] and len(calls) == 3  # each clip fetched once
    assert out.num_frames == 150
    # literally: the first piece put at the origin facing +z, then each node by the rule
    pieces = []
    first = motions[0].sample_frames(path[0].frames)
    placement = placement_onto(first, np.zeros(3), 0.0)
    pieces.append(turned_and_moved(first, *placement))
    pieces.append(turned_and_moved(motions[0].sample_frames(path[1].frames), *placement))
    for previous, node in zip(path[1:], path[2:]):
        rate = previous.frames[-1] - previous.frames[-2]
        rate = 0.5 if rate < 0.5 else rate
        ahead = motions[previous.clip].sample_frames(previous.frames[-1] + rate * np.arange(1, blend + 1))
        ahead = turned_and_moved(ahead, *placement)
        piece = motions[node.clip].sample_frames(node.frames)
        placement = placement_onto(piece, ahead.root_positions[0],
                                   float(facing_yaw(ahead.slice_frames(0, 1).joint_positions()[0])))
        pieces.append(crossfade(ahead, turned_and_moved(piece, *placement)))
    expected = Motion.concatenate(pieces)
    np.testing.assert_allclose(out.root_positions, expected.root_positions, atol=1e-9)
    np.testing.assert_allclose(out.rotations, expected.rotations, atol=1e-9)
    # and what that means: the dance starts at the origin facing +z; a jump lands where the
    # previous node would have gone next (x, z), turned its way
    assert out.root_positions[0, [0, 2]] == pytest.approx([0.0, 0.0], abs=1e-9)
    assert facing_yaw(out.slice_frames(0, 1).joint_positions()[0]) == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(out.root_positions[:30, 1], motions[0].root_positions[10:40, 1], atol=1e-9)
    # the continuing node runs on rigidly from clip frame 39 to 40.5 (the root moves linearly)
    root = motions[0].root_positions
    assert np.linalg.norm(out.root_positions[30] - out.root_positions[29]) == pytest.approx(
        np.linalg.norm(0.5 * (root[40] + root[41]) - root[39]), abs=1e-9)


@pytest.mark.survivor
def test_a_negative_seed_is_a_take_as_in_generate():
    rep = toy_repertoire()
    assert DynamicGraph(rep, GraphConfig(), seed=-1).rng is not None  # numpy refused it (exit 70)
