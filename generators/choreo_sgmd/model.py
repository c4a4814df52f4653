"""The SGMD denoiser: a transformer that predicts clean motion x0 from noisy motion, music and style.

Shape of the network (EDGE's, plus the paper's Style Modulation):
- music encoder: linear projection of the 35-d features, then self-attention layers;
- conditioning vector c = MLP(sinusoidal(t)) + MLP(mean over music tokens) [+ MLP(pace)], applied by FiLM;
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
from dataclasses import dataclass

import torch
import torch.nn.functional as F
from torch import nn

from .config import ModelConfig


class RotaryEmbedding(nn.Module):
    """Rotates pairs of query/key channels (0,1), (2,3), ... by angles proportional to the token's
    position: one complex multiplication per pair, with the rotations cached per length."""

    def __init__(self, head_dim: int, base: float = 10_000.0):
        super().__init__()
        # computed on the CPU even under torch.device("meta") (check_weights_fit): arithmetic on meta
        # tensors imports torch's reference decompositions and sympy, seconds in every fresh process
        steps = torch.arange(0, head_dim, 2, device="cpu").float()
        self.register_buffer("inv_freq", 1.0 / base ** (steps / head_dim), persistent=False)
        self._cache: dict[tuple[int, torch.device], torch.Tensor] = {}

    def rotations(self, length: int, device: torch.device) -> torch.Tensor:
        key = (length, device)
        if key not in self._cache:
            angles = torch.arange(length, device=device).float()[:, None] * self.inv_freq.to(device)[None]
            self._cache[key] = torch.polar(torch.ones_like(angles), angles)  # (N, D/2) complex
        return self._cache[key]

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """x (B, H, N, D) -> x with token n's channel pairs rotated by n * inv_freq."""
        pairs = torch.view_as_complex(x.float().unflatten(-1, (-1, 2)).contiguous())
        return torch.view_as_real(pairs * self.rotations(x.shape[-2], x.device)).flatten(-2).to(x.dtype)


class Attention(nn.Module):
    """Multi-head attention with rotary positions on queries and keys."""

    def __init__(self, dim: int, heads: int, dropout: float):
        super().__init__()
        self.heads, self.dropout = heads, dropout
        self.query, self.key_value = nn.Linear(dim, dim), nn.Linear(dim, 2 * dim)
        self.out = nn.Linear(dim, dim)
        self.rotary = RotaryEmbedding(dim // heads)

    def keys_values(self, memory: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(B, H, M, D) rotated keys and values of ``memory``; constant across diffusion steps for the music."""
        k, v = self.key_value(memory).unflatten(-1, (2, self.heads, -1)).permute(2, 0, 3, 1, 4)
        return self.rotary(k), v

    def forward(self, x: torch.Tensor, memory: torch.Tensor | None = None,
                keys_values: tuple[torch.Tensor, torch.Tensor] | None = None) -> torch.Tensor:
        q = self.rotary(self.query(x).unflatten(-1, (self.heads, -1)).transpose(1, 2))
        k, v = keys_values if keys_values is not None else self.keys_values(x if memory is None else memory)
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

    def forward(self, x, memory_keys_values, condition, style_scale):
        x = x + self.films[0](self.dropout(self.self_attention(self.norms[0](x))), condition)
        x = x + self.films[1](self.dropout(self.cross_attention(self.norms[1](x), keys_values=memory_keys_values)), condition)
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
    """x0 = f(x_t, t, music, style). Shapes: x_t (B, T, 151), t (B,), music (B, T, 35), style (B, S).

    With ``prediction="v"`` the network's output v is turned into x0 = c_skip x - c_out v, where
    x = x_t / sqrt(a) is the noisy motion at unit scale (a: the schedule's alpha-bar at t), sigma^2
    = (1 - a) / a its noise, c_skip = s^2 / (sigma^2 + s^2) and c_out = sigma s / sqrt(sigma^2 + s^2)
    for a data standard deviation s (Karras et al. 2022's preconditioning; s = 1 is Salimans and
    Ho's v-prediction, x0 = sqrt(a) x_t - sqrt(1 - a) v). Why: an x0 network trained on
    40 minutes of dance learned to ignore x_t and t and to recall x0 from the music alone (at small t
    its error was larger than that of returning x_t itself; docs/results.md, "Why the dances are
    timid"). Here a nearly clean x_t
    reaches the output through the skip whatever the network does.
    """

    def __init__(self, config: ModelConfig, prediction: str = "x0", alphas_cumprod: torch.Tensor | None = None,
                 sigma_data: float = 1.0):
        super().__init__()
        self.config, self.prediction, self.sigma_data = config, prediction, sigma_data
        if prediction == "v":
            if alphas_cumprod is None:
                raise ValueError("a v-predicting model needs its schedule's alphas_cumprod")
            self.register_buffer("alphas_cumprod", alphas_cumprod.float(), persistent=False)  # from the config, not the weights
        d = config.latent_dim
        self.motion_in, self.motion_out = nn.Linear(config.frame_dim, d), nn.Linear(d, config.frame_dim)
        self.music_in = nn.Linear(config.music_dim, d)
        self.music_encoder = nn.ModuleList(EncoderLayer(config) for _ in range(config.music_layers))
        self.time_mlp = nn.Sequential(nn.Linear(d, d), nn.SiLU(), nn.Linear(d, d))
        self.music_pool_mlp = nn.Sequential(nn.LayerNorm(d), nn.Linear(d, d), nn.SiLU(), nn.Linear(d, d))
        self.null_music = nn.Parameter(torch.empty(1, 1, d))  # stands in for "no music"
        if self.null_music.device.type != "meta":  # a layout only (check_weights_fit): drawing there
            nn.init.normal_(self.null_music, std=0.02)  # imports sympy, seconds per process; = randn * 0.02
        self.null_style = nn.Parameter(torch.zeros(1, config.style_dim))
        self.layers = nn.ModuleList(DecoderLayer(config) for _ in range(config.num_layers))
        self.final_norm = nn.LayerNorm(d)
        self.style_project = None if config.style_mode == "none" else nn.Linear(config.style_dim, d)
        if self.style_project is not None and config.style_init == "zero":
            # Created last and zeroed after its draw, so every other weight matches the no-style model's
            # and the network starts as that model: the style only enters where training finds it helps.
            nn.init.zeros_(self.style_project.weight)
            nn.init.zeros_(self.style_project.bias)
        self.pace_mlp = self.null_pace = None
        if config.pace_condition:
            # Created last, its output layer zeroed: a network fine-tuned into taking a pace starts as it was.
            self.pace_mlp = nn.Sequential(nn.Linear(1, d), nn.SiLU(), nn.Linear(d, d))
            nn.init.zeros_(self.pace_mlp[-1].weight)
            nn.init.zeros_(self.pace_mlp[-1].bias)
            self.null_pace = nn.Parameter(torch.zeros(1, d))  # stands in for "no pace given"

    def encode_music(self, music: torch.Tensor, keep_music: torch.Tensor) -> torch.Tensor:
        """(B, T, d) music tokens; rows where keep_music is False become the learned null."""
        tokens = self.music_in(music)
        tokens = torch.where(keep_music[:, None, None], tokens, self.null_music.expand_as(tokens))
        for layer in self.music_encoder:
            tokens = layer(tokens)
        return tokens

    def pace_embedding(self, pace: torch.Tensor | None, batch: int, device) -> torch.Tensor:
        """(B, d) for paces (B,) in m/s along the ground track; NaN (or no tensor) where none is given."""
        pace = torch.full((batch,), float("nan"), device=device) if pace is None else pace.to(device).float()
        embedded = self.pace_mlp(torch.nan_to_num(pace)[:, None])
        return torch.where(torch.isnan(pace)[:, None], self.null_pace.expand_as(embedded), embedded)

    def condition(self, music: torch.Tensor, style: torch.Tensor, keep_music: torch.Tensor | None = None,
                  keep_style: torch.Tensor | None = None, pace: torch.Tensor | None = None) -> "Conditioning":
        """Everything that depends on music, style and pace only: computed once per song when sampling.
        ``pace`` (B,) m/s, NaN where none is given; read only by a network with a pace condition."""
        batch = music.shape[0]
        keep_music = torch.ones(batch, dtype=torch.bool, device=music.device) if keep_music is None else keep_music
        keep_style = torch.ones(batch, dtype=torch.bool, device=music.device) if keep_style is None else keep_style
        memory = self.encode_music(music, keep_music)
        pooled = self.music_pool_mlp(memory.mean(1))
        if self.pace_mlp is not None:
            pooled = pooled + self.pace_embedding(pace, batch, music.device)
        style = torch.where(keep_style[:, None], style, self.null_style.expand_as(style))
        style_scale = None
        if self.config.style_mode == "modulation":
            style_scale = self.style_project(style)
        elif self.config.style_mode == "concat":  # ablation: style as one more token to attend to
            memory = torch.cat([memory, self.style_project(style)[:, None]], dim=1)
        keys_values = [layer.cross_attention.keys_values(memory) for layer in self.layers]
        return Conditioning(pooled, style_scale, keys_values)

    def denoise(self, x_t: torch.Tensor, t: torch.Tensor, conditioning: "Conditioning") -> torch.Tensor:
        condition = self.time_mlp(timestep_embedding(t, self.config.latent_dim)) + conditioning.pooled_music
        h = self.motion_in(x_t)
        for layer, keys_values in zip(self.layers, conditioning.keys_values):
            h = layer(h, keys_values, condition, conditioning.style_scale)
        output = self.motion_out(self.final_norm(h))
        if self.prediction == "x0":
            return output
        alpha_bar = self.alphas_cumprod[t].to(output.dtype).view(-1, 1, 1)
        variance, data = (1 - alpha_bar) / alpha_bar, self.sigma_data**2  # sigma^2 and s^2
        skip = data / (variance + data)
        return skip * x_t / alpha_bar.sqrt() - (variance * data / (variance + data)).sqrt() * output

    def forward(self, x_t: torch.Tensor, t: torch.Tensor, music: torch.Tensor, style: torch.Tensor,
                keep_music: torch.Tensor | None = None, keep_style: torch.Tensor | None = None,
                pace: torch.Tensor | None = None) -> torch.Tensor:
        return self.denoise(x_t, t, self.condition(music, style, keep_music, keep_style, pace))


@dataclass
class Conditioning:
    """The music and style side of the network for a batch of windows."""

    pooled_music: torch.Tensor  # (B, d), added to the step embedding (the pace's embedding included)
    style_scale: torch.Tensor | None  # (B, d), Style Modulation's FC(s)
    keys_values: list[tuple[torch.Tensor, torch.Tensor]]  # per decoder layer: cross-attention keys and values

    def rows(self, index: torch.Tensor) -> "Conditioning":
        """The conditioning of the windows at ``index`` (some blocks of a guided batch)."""
        if len(index) == len(self.pooled_music) and bool((index == torch.arange(len(index))).all()):
            return self
        scale = None if self.style_scale is None else self.style_scale[index]
        return Conditioning(self.pooled_music[index], scale, [(k[index], v[index]) for k, v in self.keys_values])

    @staticmethod
    def cat(parts: list["Conditioning"]) -> "Conditioning":
        scales = None if parts[0].style_scale is None else torch.cat([p.style_scale for p in parts])
        layers = zip(*(p.keys_values for p in parts))
        return Conditioning(torch.cat([p.pooled_music for p in parts]), scales,
                            [(torch.cat([k for k, _ in kv]), torch.cat([v for _, v in kv])) for kv in layers])


def count_parameters(module: nn.Module) -> int:
    return sum(p.numel() for p in module.parameters())
