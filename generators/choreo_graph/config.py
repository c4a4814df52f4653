"""ChoreoGraph configuration: sizes of the learnt parts, search weights and training budgets.

Times are in motion frames at 30 fps (the paper works at 20 fps motion / 60 fps mel; here every
sequence is at the motion rate so no model has to re-time its input). The networks are the
paper's shapes (conv/graph-conv blocks + GRU + linear; transformer + conv + deconv) at widths a
2-core CPU trains in minutes; the search constants are the paper's.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

from choreo.options import option

FPS = 30
NODE_FRAMES = FPS  # a graph node is one second of motion
WINDOW_FRAMES = 4 * FPS  # style and music tempo-density look at 4 s
CLIP_FRAMES = 8 * FPS  # repertoire clips are 8 s; their middle 4 s carry the style
NUM_JOINTS = 24


@dataclass(frozen=True, kw_only=True)
class StyleConfig:
    """Music and motion style encoders (paper 3.1) and the motion-beat-count predictor."""

    style_dim: int = 32
    n_mels: int = 96
    music_channels: tuple[int, ...] = (16, 32, 32, 48)  # four conv blocks
    motion_channels: tuple[int, ...] = (16, 32, 32, 48)  # four graph-conv blocks
    gru_hidden: int = 64
    gru_layers: int = 2
    beat_hidden: int = 64
    style_weight: float = 1.0  # lambda_es in eq. 1
    beat_weight: float = 0.1  # lambda_b in eq. 1
    contrast_weight: float = 1.0  # see losses.style_loss: eq. 1 alone is solved by a constant
    temperature: float = 1.0


@dataclass(frozen=True, kw_only=True)
class TempoConfig:
    """Tempo-density estimators (paper 3.2)."""

    width: int = 64
    content_dim: int = 128
    heads: int = 4
    music_layers: int = 2
    max_shift: int = 6  # frames the random time-warper moves a beat (0.2 s)
    content_weight: float = 1.0  # lambda_cm in eq. 2


# Beyond a clip's length a warp's smoothing only flattens it (a sigma of 1e308 or inf overflowed the
# Gaussian's kernel); costs' noise past 10 x their spread is a random walk (inf made every cost NaN).
MAX_WARP_SMOOTHING = float(CLIP_FRAMES)
MAX_TAKE_VARIATION = 10.0
GRAPH_BOUNDS = {"top_k": (1, math.inf), "dtw_stride": (1, math.inf), "blend_frames": (0, math.inf),
                "warp_smoothing": (0, MAX_WARP_SMOOTHING), "take_variation": (0, MAX_TAKE_VARIATION),
                "path_cost": (0, math.inf), "key_cost": (0, math.inf), "floor_radius": (0, math.inf),
                "floor_cost": (0, math.inf)}


@dataclass(frozen=True, kw_only=True)
class GraphConfig:
    """Selection, warping and the dynamic graph (paper 3.1-3.3)."""

    top_k: int = option(512, "Candidate clips per 4 s of music (the paper's K).", "--top-k", "-k")
    style_cost: float = 1.0  # lambda_s in eq. 4
    completeness_cost: float = 1.0  # lambda_c
    transition_cost: float = 4.0  # lambda_t (per squared metre of mean joint distance)
    completeness_scale: float = 5.0  # frames: the sigmoid's width in eq. 6
    dtw_stride: int = 2  # warp on every 2nd frame (15 fps), then interpolate the path
    blend_frames: int = 6  # cross-fade length where the graph jumps between segments
    # sigma (frames) of the Gaussian that smooths each DTW warp: the raw warps slide the feet (docs/results.md, "ChoreoGraph")
    warp_smoothing: float = option(8.0, "Sigma (frames) smoothing each clip's re-timing; 0 = the paper's raw DTW path "
                                        "(feet slide more, motion beats recur more regularly).")
    # Each second's costs get noise of this x their spread, drawn from the seed: every seed of a free dance is a take, 0
    # too (under constraints seed 0 is the greedy walk: graph.DynamicGraph). 0 here is the paper's deterministic greedy
    # walk, which plays the same few clips whatever the music (docs/results.md, "ChoreoGraph", "Every seed is a take").
    take_variation: float = option(0.1, "Noise, as a share of the costs' spread, that each second of the walk draws "
                                        "from --seed; 0 = the paper's deterministic greedy walk.")
    repeat_cost: float = 100.0  # not in the paper: replaying source frames danced recently (see graph.py)
    repeat_memory: int = 30  # seconds a played node's source frames stay "recent"
    path_cost: float = 4.0  # under constraints: per squared metre between a node's root and the given root
    key_cost: float = 4.0  # under constraints: per squared metre of mean joint distance from a given pose
    # Not in the paper: without a given root path, a node ending further than floor_radius metres from where the dance
    # started costs floor_cost per squared metre beyond it. Joined clips travel like a random walk, and real dancers
    # stay on their floor (docs/graph.md, "Staying on the floor").
    floor_radius: float = option(3.0, "Metres from its start beyond which a dance without a path prefers clips that "
                                      "head back (a soft edge: it may stray a metre past); 0: no floor, it wanders.")
    floor_cost: float = 4.0
    dynamic: bool = option(True, "The dynamic graph; --motion-graph: the paper's plain motion graph ablation (first "
                                 "node of each segment only).", "--dynamic-graph/--motion-graph")
    retempo: bool = option(True, "Re-time each clip onto the music; --no-retempo: the ablation using each clip's "
                                 "middle 4 s unwarped.", "--retempo/--no-retempo")

    @property
    def keeps_floor(self) -> bool:
        return self.floor_cost > 0 and self.floor_radius > 0

    def __post_init__(self):
        from choreo.errors import ParameterError

        for name, (low, high) in GRAPH_BOUNDS.items():
            value = getattr(self, name)
            if not low <= value <= high:  # NaN fails every comparison
                raise ParameterError(f"{name} must be {low:g} to {high:g}, got {str(value)[:24]}")


@dataclass(frozen=True, kw_only=True)
class TrainOptions:
    """What `choreo train graph` takes; None keeps TrainConfig's default."""

    steps: int | None = option(None, "Optimiser steps of each of the three stages.")
    batch_size: int | None = option(None, "Excerpts per step.")
    seed: int | None = option(None, "Seed of initialisation and batches.")

    @staticmethod
    def shown_defaults() -> dict:
        """What each None stands for, as help shows it."""
        config = TrainConfig()
        return {"steps": config.style_steps, "batch_size": config.batch_size, "seed": config.seed}


@dataclass(frozen=True, kw_only=True)
class TrainConfig:
    batch_size: int = 32
    learning_rate: float = 1e-3
    style_steps: int = 1200  # the bundled models' budget (docs/graph.md)
    motion_tempo_steps: int = 1200
    music_tempo_steps: int = 1200
    clip_stride: int = FPS  # 8 s training pairs start every second
    seed: int = 0


@dataclass(frozen=True, kw_only=True)
class ModelConfig:
    style: StyleConfig = field(default_factory=StyleConfig)
    tempo: TempoConfig = field(default_factory=TempoConfig)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> "ModelConfig":
        style = dict(data["style"])
        for key in ("music_channels", "motion_channels"):
            style[key] = tuple(style[key])
        return cls(style=StyleConfig(**style), tempo=TempoConfig(**data["tempo"]))
