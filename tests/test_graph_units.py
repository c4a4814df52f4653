"""ChoreoGraph's graph, warper and tempo-density code, unit by unit, on tiny hand-made inputs (no
repertoire build, no training, no audio): every value is pinned by something that computes it
another way (a literal dynamic programme, a search over every path, a literal greedy walk, a
closed form), so the area's mutation run has tests fast enough to run once per mutant."""

from __future__ import annotations

import math
from itertools import product
from types import SimpleNamespace

import numpy as np
import pytest
import torch
from torch.nn import functional as F

import choreo_graph.graph as graph
import choreo_graph.tempo as tempo
from choreo.motion import Motion
from choreo.motion.beats import motion_beats
from choreo.motion.stitch import crossfade, facing_yaw, placement_onto, turned_and_moved
from choreo_graph.config import GraphConfig, StyleConfig, TempoConfig
from choreo_graph.graph import (DynamicGraph, MusicWindows, Node, assemble, completeness_cost, music_windows,
                                played_clips, replayed_nodes, replaying, search_graph, select_candidates,
                                source_spans, warp_candidates)
from choreo_graph.tempo import (MotionTempoEstimator, MusicTempoEstimator, down_blocks, pad_time, padded_length,
                                random_time_warp, tempo_autoencoder_loss, up_blocks)
from choreo_graph.warp import subsequence_dtw, warp_frames

SECOND = 30  # frames of a graph node
STEP_LIST = ((1, 1), (1, 2), (2, 1))  # (query, reference) advances, in librosa's tie order


# -- the warper: a literal dynamic programme and a search over every path --------------------------
def literal_dtw(query, reference):
    """Subsequence DTW cell by cell in float32 (librosa's recursion: free start and end in the
    reference, first step in STEP_LIST order wins a tie, first minimum of the last row ends)."""
    q, r = np.asarray(query, np.float32), np.asarray(reference, np.float32)
    n, m = len(q), len(r)
    total = np.full((n, m), np.inf, np.float32)
    step = np.zeros((n, m), int)
    for j in range(m):
        total[0, j] = abs(q[0] - r[j])
    for i in range(1, n):
        for j in range(m):
            best, which = np.float32(np.inf), 0
            for k, (di, dj) in enumerate(STEP_LIST):
                if i - di >= 0 and j - dj >= 0 and total[i - di, j - dj] < best:
                    best, which = total[i - di, j - dj], k
            total[i, j] = np.float32(abs(q[i] - r[j])) + best
            step[i, j] = which
    j = int(np.argmin(total[-1]))
    i = n - 1
    matched = [None] * n
    matched[i] = j
    while i > 0:
        di, dj = STEP_LIST[step[i, j]]
        i, j = i - di, j - dj
        matched[i] = j
    for row in range(n):  # a (2, 1) step skips a query row: halfway between its neighbours
        if matched[row] is None:
            matched[row] = 0.5 * (matched[row - 1] + matched[row + 1])
    return np.array(matched, float), float(total[-1].min())


def all_path_costs(query, reference):
    """The cost of every path from the first query row (any reference frame) to the last."""
    n, m = len(query), len(reference)
    cost = lambda i, j: abs(float(query[i]) - float(reference[j]))  # noqa: E731
    found = []

    def walk(i, j, so_far, cells):
        if i == n - 1:
            found.append((so_far, cells))
            return
        for di, dj in STEP_LIST:
            if i + di < n and j + dj < m:
                walk(i + di, j + dj, so_far + cost(i + di, j + dj), cells + [(i + di, j + dj)])

    for j in range(m):
        walk(0, j, cost(0, j), [(0, j)])
    return found


def test_subsequence_dtw_is_the_literal_programme_on_ties_and_on_random_curves():
    rng = np.random.default_rng(0)
    ties_q, ties_r = rng.integers(0, 3, (12, 9)), rng.integers(0, 3, (12, 17))  # small integers: many ties
    smooth_q, smooth_r = rng.random((6, 11)), rng.random((6, 23))
    for queries, references in ((ties_q, ties_r), (smooth_q, smooth_r)):
        ours = subsequence_dtw(queries, references)
        assert ours.shape == queries.shape
        for q, r, path in zip(queries, references, ours):
            np.testing.assert_array_equal(path, literal_dtw(q, r)[0])


def test_subsequence_dtw_takes_a_cheapest_of_all_paths():
    rng = np.random.default_rng(3)
    queries, references = rng.random((8, 6)).round(2), rng.random((8, 8)).round(2)
    for q, r, path in zip(queries, references, subsequence_dtw(queries, references)):
        paths = all_path_costs(q, r)
        cheapest = min(c for c, _ in paths)
        cells = [(i, int(j)) for i, j in enumerate(path) if j == int(j)]  # rows a (2, 1) step visited
        assert any(c_ == cells for _, c_ in paths)  # a path the three steps allow, end to end
        assert sum(abs(q[i] - r[j]) for i, j in cells) == pytest.approx(cheapest, abs=1e-5)
        skipped = [i for i, j in enumerate(path) if j != int(j)]
        for i in skipped:
            assert path[i] == 0.5 * (path[i - 1] + path[i + 1])


def test_subsequence_dtw_hand_cases():
    # the query is the reference's 3..6 played straight: matched frame by frame
    reference = np.array([9.0, 9, 9, 0, 1, 2, 3, 9, 9])
    np.testing.assert_array_equal(subsequence_dtw(np.array([[0.0, 1, 2, 3]]), reference[None])[0], [3, 4, 5, 6])
    # the query plays it at half speed: (2, 1) steps, the rows between halfway
    slow = subsequence_dtw(np.array([[0.0, 0.5, 1, 1.5, 2, 2.5, 3]]), reference[None])[0]
    np.testing.assert_array_equal(slow, [3, 3.5, 4, 4.5, 5, 5.5, 6])
    # twice as fast: (1, 2) steps
    fast = subsequence_dtw(np.array([[0.0, 2, 4]]), np.array([[9.0, 0, 1, 2, 3, 4, 9]]))[0]
    np.testing.assert_array_equal(fast, [1, 3, 5])
    # a one-frame query: the nearest reference frame, nothing walked back from it
    np.testing.assert_array_equal(subsequence_dtw(np.array([[2.0]]), np.array([[0.0, 1, 2, 3]]))[0], [2])
    # a flat curve: every cell ties; the last row's first finite cell (1, via one (2, 1) step) ends
    np.testing.assert_array_equal(subsequence_dtw(np.zeros((1, 3)), np.zeros((1, 5)))[0], [0, 0.5, 1])


def literal_warp(query, reference, stride, smoothing=0.0):
    """warp_frames one pair at a time: DTW on every stride-th frame, the path read at each
    query frame by linear interpolation (past the last matched frame: on at 1x), a literal
    edge-held Gaussian, clamped to the reference."""
    matched = literal_dtw(query[::stride], reference[::stride])[0] * stride
    last = len(matched) - 1
    frames = []
    for f in range(len(query)):
        position = f / stride
        lower = min(int(position), last)
        upper = min(lower + 1, last)
        slope = matched[upper] - matched[lower] if upper > lower else stride
        frames.append(matched[lower] + (position - lower) * slope)
    frames = np.array(frames)
    if smoothing > 0:
        radius = int(4.0 * smoothing + 0.5)
        kernel = np.exp(-0.5 * (np.arange(-radius, radius + 1) / smoothing) ** 2)
        kernel /= kernel.sum()
        padded = np.concatenate([np.full(radius, frames[0]), frames, np.full(radius, frames[-1])])
        frames = np.array([padded[f : f + 2 * radius + 1] @ kernel for f in range(len(frames))])
    return np.minimum(np.maximum(frames, 0), len(reference) - 1)


@pytest.mark.parametrize("stride, smoothing", [(1, 0.0), (2, 0.0), (3, 0.0), (2, 1.5), (1, 0.7)])
def test_warp_frames_is_the_literal_warp(stride, smoothing):
    rng = np.random.default_rng(stride)
    queries, references = rng.random((4, 21)), rng.random((4, 31))  # odd lengths: the last frame extrapolates
    ours = warp_frames(queries, references, stride, smoothing)
    assert ours.shape == (4, 21)
    for q, r, frames in zip(queries, references, ours):
        np.testing.assert_allclose(frames, literal_warp(q, r, stride, smoothing), atol=1e-9)


def test_warp_frames_clamps_to_the_reference():
    # every 2nd frame: the query's 0, 1, 2 match the reference's 4, (halfway), 6 at half speed;
    # the last query frame, past the last matched one, plays on at 1x to 7: clamped to frame 6
    reference = np.array([[5.0, 5, 5, 5, 0, 1, 2]])
    frames = warp_frames(np.array([[0.0, 0.5, 1, 1.5, 2, 2.5]]), reference, stride=2)[0]
    np.testing.assert_array_equal(frames, [4, 4.5, 5, 5.5, 6, 6])
    assert warp_frames(np.array([[0.0, 1, 2]]), np.array([[0.0, 1, 2]]), stride=2)[0].tolist() == [0, 1, 2]
    # the strided path takes a (1, 2) step (0 -> 4); the query frame after it plays on at 1x, not at 2x
    frames = warp_frames(np.array([[0.0, 0.5, 1, 1.5]]), np.array([[0.0, 5, 9, 5, 1, 5, 9, 9, 9]]), stride=2)[0]
    np.testing.assert_array_equal(frames, [0, 2, 4, 5])


def test_warp_frames_matches_every_frame_unless_told():
    rng = np.random.default_rng(8)
    queries, references = rng.random((3, 9)), rng.random((3, 20))
    ours = warp_frames(queries, references)
    for q, r, frames in zip(queries, references, ours):
        np.testing.assert_array_equal(frames, literal_warp(q, r, 1))


# -- tempo-density models: closed forms and a literal forward pass ----------------------------------
def test_padded_length_is_the_next_multiple_of_32():
    for frames in range(1, 130):
        assert padded_length(frames) == math.ceil(frames / 32) * 32


def test_pad_time_holds_the_last_frame_and_leaves_longer_input_alone():
    x = torch.arange(10.0).view(1, 2, 5)
    padded = pad_time(x, 8)
    assert padded.shape == (1, 2, 8)
    assert padded[0, 0].tolist() == [0, 1, 2, 3, 4, 4, 4, 4] and padded[0, 1].tolist() == [5, 6, 7, 8, 9, 9, 9, 9]
    assert torch.equal(pad_time(x, 5), x) and torch.equal(pad_time(x, 3), x)


def conv_params(c_in, c_out, kernel):
    return c_in * c_out * kernel + c_out


def count(module):
    return sum(p.numel() for p in module.parameters())


def transformer_params(w):  # attention in/out projections, a 2w feed-forward, two layer norms
    return (3 * w * w + 3 * w) + (w * w + w) + (w * 2 * w + 2 * w) + (2 * w * w + w) + 4 * w


def test_conv_blocks_halve_time_five_times_and_have_the_papers_shapes():
    torch.manual_seed(0)
    down, up = down_blocks(3, 8), up_blocks(8, 2)
    x = torch.randn(2, 3, 64)
    hidden = down(x)
    assert hidden.shape == (2, 8, 2)
    assert up(hidden).shape == (2, 2, 64)
    assert count(down) == conv_params(3, 8, 4) + 2 * 8 + 4 * (conv_params(8, 8, 4) + 2 * 8)
    assert count(up) == 5 * (conv_params(8, 8, 4) + 2 * 8) + conv_params(8, 2, 3)
    assert [m.num_groups for m in down if isinstance(m, torch.nn.GroupNorm)] == [8] * 5
    assert [m.num_groups for m in up if isinstance(m, torch.nn.GroupNorm)] == [8] * 5
    # each block is conv -> group norm -> GELU: the block's output is GELU of a normalised conv
    conv, norm = down[0], down[1]
    np.testing.assert_allclose(down[:3](x).detach(), F.gelu(F.group_norm(conv(x), 8, norm.weight, norm.bias)).detach(),
                               atol=1e-6)


TINY_TEMPO = TempoConfig(width=8, content_dim=8, heads=2, music_layers=2)


def literal_layer(layer, x):
    """A pre-norm transformer encoder layer (ReLU feed-forward, no dropout), by hand."""
    w = x.shape[-1]
    heads = layer.self_attn.num_heads
    h = F.layer_norm(x, (w,), layer.norm1.weight, layer.norm1.bias, layer.norm1.eps)
    q, k, v = (h @ layer.self_attn.in_proj_weight.T + layer.self_attn.in_proj_bias).chunk(3, -1)
    split = lambda t: t.view(t.shape[0], t.shape[1], heads, w // heads).transpose(1, 2)  # noqa: E731
    q, k, v = split(q), split(k), split(v)
    attention = torch.softmax(q @ k.transpose(-1, -2) / math.sqrt(w // heads), -1) @ v
    attention = attention.transpose(1, 2).reshape(x.shape)
    x = x + attention @ layer.self_attn.out_proj.weight.T + layer.self_attn.out_proj.bias
    h = F.layer_norm(x, (w,), layer.norm2.weight, layer.norm2.bias, layer.norm2.eps)
    return x + layer.linear2(torch.relu(layer.linear1(h)))


def hold(x, length):  # (B, C, T) -> (B, C, length), the last frame repeated
    return torch.cat([x, x[..., -1:].expand(-1, -1, length - x.shape[-1])], -1)


def linear_gelu_linear(sequential, x):
    first, second = [m for m in sequential if isinstance(m, torch.nn.Linear)]
    return second(F.gelu(first(x)))


def test_motion_tempo_estimator_is_the_literal_network():
    torch.manual_seed(1)
    model = MotionTempoEstimator(TINY_TEMPO, frames=40, features=6).train()  # train mode: dropout would show
    w, length = 8, 64
    bottleneck = w * length // 32
    assert model.frames == 40 and model.length == 64
    assert count(model.content_head) == (bottleneck * 16 + 16) + (16 * 8 + 8)
    assert count(model.decode_content) == (8 * 16 + 16) + (16 * bottleneck + bottleneck)
    assert count(model.attend) == count(model.decode_attend) == transformer_params(w)
    assert count(model) == ((6 * w + w) + 2 * transformer_params(w) + count(down_blocks(w, w)) + count(up_blocks(w, 1))
                            + count(model.content_head) + count(down_blocks(1, w)) + count(model.decode_content)
                            + count(up_blocks(w, w)) + (w * 6 + 6))
    motion = torch.randn(2, 40, 6)
    tempo_curve, content = model.encode_motion(motion)
    with torch.no_grad():
        hidden = literal_layer(model.attend, model.embed(motion)).transpose(1, 2)
        hidden = model.encode(hold(hidden, length))
        expected_tempo = model.tempo_head(hidden)[:, 0, :40]
        expected_content = linear_gelu_linear(model.content_head, hidden.reshape(2, -1))
    assert tempo_curve.shape == (2, 40) and content.shape == (2, 8)
    torch.testing.assert_close(tempo_curve, expected_tempo, atol=1e-5, rtol=1e-5)
    torch.testing.assert_close(content, expected_content, atol=1e-5, rtol=1e-5)
    rebuilt = model.decode(tempo_curve, content)
    with torch.no_grad():
        hidden = model.decode_tempo(hold(tempo_curve[:, None], length)) + linear_gelu_linear(model.decode_content, content).view(2, w, 2)
        hidden = model.decode_up(hidden)[:, :, :40].transpose(1, 2)
        expected = model.out(literal_layer(model.decode_attend, hidden))
    assert rebuilt.shape == (2, 40, 6)
    torch.testing.assert_close(rebuilt, expected, atol=1e-5, rtol=1e-5)
    # each clip of a batch is encoded on its own
    alone = model.encode_motion(motion[1:])
    torch.testing.assert_close(alone[0], tempo_curve[1:], atol=1e-5, rtol=1e-5)
    torch.testing.assert_close(alone[1], content[1:], atol=1e-5, rtol=1e-5)


def test_music_tempo_estimator_is_the_literal_network():
    torch.manual_seed(2)
    model = MusicTempoEstimator(TINY_TEMPO, frames=40, n_mels=5).train()
    assert model.length == 64 and len(model.attend.layers) == 2
    assert count(model) == (5 * 8 + 8) + 2 * transformer_params(8) + count(down_blocks(8, 8)) + count(up_blocks(8, 1))
    mel = torch.randn(3, 40, 5)
    out = model(mel)
    with torch.no_grad():
        hidden = model.embed(mel)
        for layer in model.attend.layers:
            hidden = literal_layer(layer, hidden)
        expected = model.decode(model.encode(hold(hidden.transpose(1, 2), 64)))[:, 0, :40]
    assert out.shape == (3, 40)
    torch.testing.assert_close(out, expected, atol=1e-5, rtol=1e-5)
    torch.testing.assert_close(model(mel[:1]), out[:1], atol=1e-5, rtol=1e-5)


def test_tempo_autoencoder_loss_is_eq_2_term_by_term():
    torch.manual_seed(3)
    model = MotionTempoEstimator(TINY_TEMPO, frames=40, features=6).eval()
    motion, warped = torch.randn(2, 40, 6), torch.randn(2, 40, 6)
    losses = tempo_autoencoder_loss(model, motion, warped, content_weight=0.3)
    with torch.no_grad():
        t, c = model.encode_motion(motion)
        tw, cw = model.encode_motion(warped)
        mse = lambda a, b: ((a - b) ** 2).mean()  # noqa: E731
        rebuild = (mse(model.decode(t, c), motion) + mse(model.decode(tw, cw), warped)
                   + mse(model.decode(t, cw), motion) + mse(model.decode(tw, c), warped))
        same = mse(c, cw)
    assert set(losses) == {"loss", "rebuild", "content"}
    torch.testing.assert_close(losses["rebuild"], rebuild, atol=1e-6, rtol=1e-5)
    torch.testing.assert_close(losses["content"], same, atol=1e-6, rtol=1e-5)
    torch.testing.assert_close(losses["loss"].detach(), rebuild + 0.3 * same, atol=1e-6, rtol=1e-5)
    assert losses["loss"].requires_grad and not losses["rebuild"].requires_grad and not losses["content"].requires_grad


class ScriptedRng:
    """Hands random_time_warp fixed draws and checks what it asks for."""

    def __init__(self, uniforms, shifts, max_shift):
        self.uniforms, self.shifts, self.max_shift = np.array(uniforms), np.array(shifts), max_shift

    def random(self, size):
        assert size == len(self.uniforms)
        return self.uniforms

    def integers(self, low, high, size):
        assert (low, high, size) == (-self.max_shift, self.max_shift + 1, len(self.shifts))
        return self.shifts


def piecewise(f, knots_x, knots_y):
    for k in range(len(knots_x) - 1):
        if knots_x[k] <= f <= knots_x[k + 1]:
            return knots_y[k] + (f - knots_x[k]) * (knots_y[k + 1] - knots_y[k]) / (knots_x[k + 1] - knots_x[k])
    raise AssertionError(f)


@pytest.mark.parametrize("uniforms, shifts, target, source", [
    # beats 5, 9, 14, 15 survive the edge filter; 5 and 14 are drawn (< 0.5) and moved by +2 and -1
    ([0.1, 0.9, 0.3, 0.7], [2, -1], [0, 7, 13, 19], [0, 5, 14, 19]),
    ([0.2, 0.4, 0.5, 0.6], [2, -1], [0, 7, 8, 19], [0, 5, 9, 19]),  # 0.5 is not drawn
    # 5 and 9 moved past each other: sorted by where they land, the one that would run backwards dropped
    ([0.2, 0.4, 0.9, 0.9], [3, -2], [0, 7, 19], [0, 9, 19]),
    ([0.2, 0.4, 0.9, 0.9], [2, -2], [0, 7, 19], [0, 5, 19]),  # both land on 7: the second dropped
    ([0.9, 0.9, 0.1, 0.2], [-3, 2], [0, 11, 17, 19], [0, 14, 15, 19]),  # neighbouring beats, both kept
    ([0.6, 0.7, 0.8, 0.9], [], [0, 19], [0, 19]),  # nothing drawn: the clip as it was
])
def test_random_time_warp_retimes_linearly_between_moved_beats(monkeypatch, uniforms, shifts, target, source):
    positions = np.random.default_rng(0).random((20, 2, 3))
    beats = np.array([1, 2, 3, 5, 9, 14, 15, 16, 17, 18])  # 1..3 and 16..18 are within max_shift of the ends

    def beats_of(p):
        assert p is positions
        return beats

    monkeypatch.setattr(tempo, "motion_beats", beats_of)
    warped = random_time_warp(positions, 3, ScriptedRng(uniforms, shifts, 3))
    assert warped.shape == positions.shape
    for f in range(20):
        s = piecewise(f, target, source)
        lower = int(np.floor(s))
        upper = min(lower + 1, 19)
        np.testing.assert_allclose(warped[f], (1 - (s - lower)) * positions[lower] + (s - lower) * positions[upper],
                                   atol=1e-12)


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


def toy_repertoire(seed=0, clips=5, joints=4):
    """Smooth random poses (so motion beats are spread out), clips cut from two motions 60 frames apart."""
    rng = np.random.default_rng(seed)
    t = np.arange(240)[None, :, None, None] / 30
    poses = np.sin(rng.uniform(0.5, 3, (clips, 1, joints, 3)) * 2 * np.pi * t + rng.uniform(0, 6, (clips, 1, joints, 3)))
    names = np.array([f"{'ab'[c % 2]}@{60 * (c // 2)}" for c in range(clips)])
    sources, starts = np.array([c % 2 for c in range(clips)]), np.array([60 * (c // 2) for c in range(clips)])
    return SimpleNamespace(style=rng.random((clips, 2)), poses=(0.3 * poses).astype(np.float16),
                           origins=(sources, starts), names=names)


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


def test_step_ties_go_to_the_oldest_segment_and_the_first_rank():
    rep = toy_repertoire(3, clips=2)
    rep.style[:] = 0
    g = DynamicGraph(rep, GraphConfig(completeness_cost=0.0, transition_cost=0.0, repeat_cost=0.0))
    warps = np.tile(np.arange(60.0, 180.0), (2, 1))
    g.insert(0, np.array([1, 0]), warps)
    g.insert(1, np.array([0, 1]), warps)
    assert g.step(1, np.zeros(2)).segment == (0, 0)


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


def test_take_variation_needs_a_weight_and_under_constraints_a_seed():
    rep = toy_repertoire()
    assert DynamicGraph(rep, GraphConfig(), seed=0).rng is not None
    assert DynamicGraph(rep, GraphConfig(take_variation=0.0), seed=4).rng is None
    guide = SimpleNamespace()  # any guide: the walk is under constraints
    assert DynamicGraph(rep, GraphConfig(), seed=0, guide=guide).rng is None  # the greedy walk
    assert DynamicGraph(rep, GraphConfig(), seed=3, guide=guide).rng is not None


def path_of(spec):
    return [Node(segment, index, clip, np.asarray(frames, float)) for segment, index, clip, frames in spec]


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


def test_a_query_too_long_for_its_reference_is_a_clear_error():
    """No monotone path of slopes 1/2 to 2 fits 6 query frames into 2 reference frames."""
    with pytest.raises(ValueError, match="no path through 2 reference frames"):
        subsequence_dtw(np.zeros((1, 6)), np.zeros((1, 2)))
    assert subsequence_dtw(np.zeros((1, 3)), np.zeros((1, 2))).shape == (1, 3)  # 3 into 2 still fits


# Issue 48, items 10 and 12: the graph's numbers bounded where they are defined ------------------------

@pytest.mark.parametrize("field, value", [("warp_smoothing", math.nan), ("warp_smoothing", math.inf), ("warp_smoothing", 1e308),
                                          ("take_variation", math.nan), ("take_variation", math.inf), ("top_k", 0)])
def test_graph_config_refuses_non_finite_and_huge_values_by_name(field, value):
    from choreo.errors import ParameterError

    with pytest.raises(ParameterError, match=f"^{field} must be"):
        GraphConfig(**{field: value})


def test_a_negative_seed_is_a_take_as_in_generate():
    rep = toy_repertoire()
    assert DynamicGraph(rep, GraphConfig(), seed=-1).rng is not None  # numpy refused it (exit 70)
