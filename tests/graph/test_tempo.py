"""Tests of choreo_graph.tempo.

Markers say where a test came from: survivor (pyproject.toml, tests/README.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch
from torch.nn import functional as F

import choreo_graph.tempo as tempo
from choreo_graph.config import TempoConfig
from choreo_graph.tempo import (
    MotionTempoEstimator,
    MusicTempoEstimator,
    down_blocks,
    pad_time,
    padded_length,
    random_time_warp,
    tempo_autoencoder_loss,
    up_blocks,
)
from tests.graph.helpers import count


# -- tempo-density models: closed forms and a literal forward pass ----------------------------------
@pytest.mark.survivor
def test_padded_length_is_the_next_multiple_of_32():
    for frames in range(1, 130):
        assert padded_length(frames) == math.ceil(frames / 32) * 32


@pytest.mark.survivor
def test_pad_time_holds_the_last_frame_and_leaves_longer_input_alone():
    x = torch.arange(10.0).view(1, 2, 5)
    padded = pad_time(x, 8)
    assert padded.shape == (1, 2, 8)
    assert padded[0, 0].tolist() == [0, 1, 2, 3, 4, 4, 4, 4] and padded[0, 1].tolist() == [5, 6, 7, 8, 9, 9, 9, 9]
    assert torch.equal(pad_time(x, 5), x) and torch.equal(pad_time(x, 3), x)


def conv_params(c_in, c_out, kernel):
    return c_in * c_out * kernel + c_out


def transformer_params(w):  # attention in/out projections, a 2w feed-forward, two layer norms
    return (3 * w * w + 3 * w) + (w * w + w) + (w * 2 * w + 2 * w) + (2 * w * w + w) + 4 * w


@pytest.mark.survivor
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


@pytest.mark.survivor
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


@pytest.mark.survivor
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


@pytest.mark.survivor
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


@pytest.mark.survivor
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
