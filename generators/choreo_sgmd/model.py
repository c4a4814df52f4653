"""The SGMD denoiser: a transformer that predicts clean motion x0 from noisy motion, music and style.

Shape of the network (EDGE's, plus the paper's Style Modulation):
- music encoder: linear projection of the 35-d features, then self-attention layers;
- conditioning vector c = MLP(sinusoidal(t)) + MLP(mean over music tokens), applied by FiLM;
- decoder layers (pre-norm): self-attention over motion frames, cross-attention to the music,
  Style Modulation (paper eq. 5: x + RMSNorm(x) * FC(s), one FC shared by every layer),
  feed-forward; each residual branch modulated by FiLM, (1 + scale) * h + shift;
- rotary position embeddings on queries and keys, so attention sees relative time only (windows
  of any offset in a long song look alike).
Deviation from EDGE, by choice: the diffusion step enters through FiLM only; EDGE also appends two
time tokens to the cross-attention memory, which under rotary embeddings would sit at arbitrary
positions relative to every frame.
"""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F
from torch import nn

from .config import ModelConfig


class RotaryEmbedding(nn.Module):
    """Rotates pairs of query/key channels by angles proportional to the token's position."""

    def __init__(self, head_dim: int, base: float = 10_000.0):
        super().__init__()
        self.register_buffer("inv_freq", 1.0 / base ** (torch.arange(0, head_dim, 2).float() / head_dim), persistent=False)

    def forward(self, x: torch.Tensor, positions: torch.Tensor) -> torch.Tensor:
        """x (B, H, N, D), positions (N,) -> x rotated."""
        angles = positions[:, None].float() * self.inv_freq[None]  # (N, D/2)
        cos, sin = angles.cos().repeat_interleave(2, -1), angles.sin().repeat_interleave(2, -1)
        pairs = x.unflatten(-1, (-1, 2))
        rotated_half = torch.stack([-pairs[..., 1], pairs[..., 0]], dim=-1).flatten(-2)
        return x * cos.to(x.dtype) + rotated_half * sin.to(x.dtype)


class Attention(nn.Module):
    """Multi-head attention with rotary positions on queries and keys."""

    def __init__(self, dim: int, heads: int, dropout: float):
        super().__init__()
        self.heads, self.dropout = heads, dropout
        self.query, self.key_value = nn.Linear(dim, dim), nn.Linear(dim, 2 * dim)
        self.out = nn.Linear(dim, dim)
        self.rotary = RotaryEmbedding(dim // heads)

    def forward(self, x: torch.Tensor, memory: torch.Tensor | None = None) -> torch.Tensor:
        memory = x if memory is None else memory
        q = self.query(x).unflatten(-1, (self.heads, -1)).transpose(1, 2)
        k, v = self.key_value(memory).unflatten(-1, (2, self.heads, -1)).permute(2, 0, 3, 1, 4)
        q = self.rotary(q, torch.arange(q.shape[2], device=x.device))
        k = self.rotary(k, torch.arange(k.shape[2], device=x.device))
        attended = F.scaled_dot_product_attention(q, k, v, dropout_p=self.dropout if self.training else 0.0)
        return self.out(attended.transpose(1, 2).flatten(-2))


class FeedForward(nn.Sequential):
    def __init__(self, dim: int, hidden: int, dropout: float):
        super().__init__(nn.Linear(dim, hidden), nn.GELU(), nn.Dropout(dropout), nn.Linear(hidden, dim))


class FiLM(nn.Module):
    """(1 + scale) * h + shift, with scale and shift predicted from the conditioning vector."""

    def __init__(self, dim: int):
        super().__init__()
        self.project = nn.Sequential(nn.SiLU(), nn.Linear(dim, 2 * dim))
        nn.init.zeros_(self.project[1].weight)  # starts as the identity
        nn.init.zeros_(self.project[1].bias)

    def forward(self, h: torch.Tensor, condition: torch.Tensor) -> torch.Tensor:
        scale, shift = self.project(condition)[:, None].chunk(2, dim=-1)
        return (1 + scale) * h + shift


class StyleModulation(nn.Module):
    """Paper eq. 5: x + x / (||x|| r) * FC(s), i.e. an RMS-normalised copy of x scaled per channel by
    the style. ``project`` (the FC) is shared by all decoder layers and passed in."""

    def __init__(self, dim: int):
        super().__init__()
        self.norm = nn.RMSNorm(dim, elementwise_affine=False)

    def forward(self, x: torch.Tensor, style_scale: torch.Tensor) -> torch.Tensor:
        return x + self.norm(x) * style_scale[:, None]


class EncoderLayer(nn.Module):
    def __init__(self, config: ModelConfig):
        super().__init__()
        d = config.latent_dim
        self.norm1, self.norm2 = nn.LayerNorm(d), nn.LayerNorm(d)
        self.attention = Attention(d, config.num_heads, config.dropout)
        self.feed_forward = FeedForward(d, config.ff_dim, config.dropout)
        self.dropout = nn.Dropout(config.dropout)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = x + self.dropout(self.attention(self.norm1(x)))
        return x + self.dropout(self.feed_forward(self.norm2(x)))


class DecoderLayer(nn.Module):
    def __init__(self, config: ModelConfig):
        super().__init__()
        d = config.latent_dim
        self.norms = nn.ModuleList(nn.LayerNorm(d) for _ in range(3))
        self.self_attention = Attention(d, config.num_heads, config.dropout)
        self.cross_attention = Attention(d, config.num_heads, config.dropout)
        self.feed_forward = FeedForward(d, config.ff_dim, config.dropout)
        self.films = nn.ModuleList(FiLM(d) for _ in range(3))
        self.style_modulation = StyleModulation(d) if config.style_mode == "modulation" else None
        self.dropout = nn.Dropout(config.dropout)

    def forward(self, x, memory, condition, style_scale):
        x = x + self.films[0](self.dropout(self.self_attention(self.norms[0](x))), condition)
        x = x + self.films[1](self.dropout(self.cross_attention(self.norms[1](x), memory)), condition)
        if self.style_modulation is not None:
            x = self.style_modulation(x, style_scale)
        return x + self.films[2](self.dropout(self.feed_forward(self.norms[2](x))), condition)


def timestep_embedding(t: torch.Tensor, dim: int, max_period: float = 10_000.0) -> torch.Tensor:
    """(B,) diffusion steps -> (B, dim) sinusoidal features."""
    half = dim // 2
    frequencies = torch.exp(-math.log(max_period) * torch.arange(half, device=t.device) / half)
    angles = t.float()[:, None] * frequencies[None]
    return torch.cat([angles.cos(), angles.sin()], dim=-1)


class Denoiser(nn.Module):
    """x0 = f(x_t, t, music, style). Shapes: x_t (B, T, 151), t (B,), music (B, T, 35), style (B, S)."""

    def __init__(self, config: ModelConfig):
        super().__init__()
        self.config = config
        d = config.latent_dim
        self.motion_in, self.motion_out = nn.Linear(config.frame_dim, d), nn.Linear(d, config.frame_dim)
        self.music_in = nn.Linear(config.music_dim, d)
        self.music_encoder = nn.ModuleList(EncoderLayer(config) for _ in range(config.music_layers))
        self.time_mlp = nn.Sequential(nn.Linear(d, d), nn.SiLU(), nn.Linear(d, d))
        self.music_pool_mlp = nn.Sequential(nn.LayerNorm(d), nn.Linear(d, d), nn.SiLU(), nn.Linear(d, d))
        self.null_music = nn.Parameter(torch.randn(1, 1, d) * 0.02)  # stands in for "no music"
        self.null_style = nn.Parameter(torch.zeros(1, config.style_dim))
        self.layers = nn.ModuleList(DecoderLayer(config) for _ in range(config.num_layers))
        self.final_norm = nn.LayerNorm(d)
        self.style_project = None if config.style_mode == "none" else nn.Linear(config.style_dim, d)

    def encode_music(self, music: torch.Tensor, keep_music: torch.Tensor) -> torch.Tensor:
        """(B, T, d) music tokens; rows where keep_music is False become the learned null."""
        tokens = self.music_in(music)
        tokens = torch.where(keep_music[:, None, None], tokens, self.null_music.expand_as(tokens))
        for layer in self.music_encoder:
            tokens = layer(tokens)
        return tokens

    def forward(self, x_t: torch.Tensor, t: torch.Tensor, music: torch.Tensor, style: torch.Tensor,
                keep_music: torch.Tensor | None = None, keep_style: torch.Tensor | None = None) -> torch.Tensor:
        batch = x_t.shape[0]
        keep_music = torch.ones(batch, dtype=torch.bool, device=x_t.device) if keep_music is None else keep_music
        keep_style = torch.ones(batch, dtype=torch.bool, device=x_t.device) if keep_style is None else keep_style
        memory = self.encode_music(music, keep_music)
        condition = self.time_mlp(timestep_embedding(t, self.config.latent_dim)) + self.music_pool_mlp(memory.mean(1))
        style = torch.where(keep_style[:, None], style, self.null_style.expand_as(style))
        style_scale = None
        if self.config.style_mode == "modulation":
            style_scale = self.style_project(style)
        elif self.config.style_mode == "concat":  # ablation: style as one more token to attend to
            memory = torch.cat([memory, self.style_project(style)[:, None]], dim=1)
        h = self.motion_in(x_t)
        for layer in self.layers:
            h = layer(h, memory, condition, style_scale)
        return self.motion_out(self.final_norm(h))


def count_parameters(module: nn.Module) -> int:
    return sum(p.numel() for p in module.parameters())
