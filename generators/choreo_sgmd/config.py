"""Configurations of the SGMD backend: frozen dataclasses, stored in checkpoints as plain dicts."""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

from choreo.motion import FRAME_DIM
from choreo.music import FEATURE_DIM

STYLE_MODES = ("modulation", "concat", "none")  # paper's Style Modulation, its concat ablation, EDGE
STYLE_INITS = ("random", "zero")  # the style projection's initial weights (zero: the style branch starts as the identity)
PROMPT_KINDS = ("description", "name", "onehot")  # the paper's three kinds of style prompt
CONTACT_SOURCES = ("predicted", "target")  # whose foot contacts the foot term pins: the model's (EDGE) or the data's (MDM)
PREDICTIONS = ("x0", "v")  # what the network outputs: x0 itself (EDGE), or v, turned into x0 (model.py)


@dataclass(frozen=True, kw_only=True)
class ModelConfig:
    frame_dim: int = FRAME_DIM  # 4 contacts | 3 root | 24 x 6D
    music_dim: int = FEATURE_DIM  # the 35-d features; FEATURE_DIM + RHYTHM_DIM adds beat phase and tempo (`--rhythm`)
    style_dim: int = 384  # all-MiniLM-L6-v2 sentence embeddings; the number of genres for one-hot
    latent_dim: int = 512
    ff_dim: int = 1024
    num_layers: int = 8  # decoder layers
    num_heads: int = 8
    music_layers: int = 2  # music encoder layers
    dropout: float = 0.1
    style_mode: str = "modulation"
    style_init: str = "random"
    window_frames: int = 150  # 5 s at 30 fps (counted in model frames)
    frame_stride: int = 1  # the model dances every stride-th 30 fps frame (2: 15 fps; frame_rate.py)
    pace_condition: bool = False  # each window's pace along its ground track is a condition (docs/sgmd.md, "Pace")

    def __post_init__(self):
        sizes = {name: getattr(self, name) for name in ("frame_dim", "music_dim", "style_dim", "latent_dim", "ff_dim",
                                                        "num_layers", "num_heads", "music_layers", "window_frames",
                                                        "frame_stride")}
        bad = [f"{name}={value!r}" for name, value in sizes.items() if not isinstance(value, int) or not 0 < value <= 1 << 16]
        if bad:
            raise ValueError(f"model sizes must be whole numbers from 1 to 65536 ({', '.join(bad)})")
        if self.frame_stride > 4:
            raise ValueError(f"frame_stride must be 1 to 4 (30 to 7.5 fps), got {self.frame_stride}")
        if not 0.0 <= self.dropout < 1.0:
            raise ValueError(f"dropout must be in [0, 1), got {self.dropout}")
        if self.style_mode not in STYLE_MODES:
            raise ValueError(f"style_mode must be one of {STYLE_MODES}, got {self.style_mode!r}")
        if self.style_init not in STYLE_INITS:
            raise ValueError(f"style_init must be one of {STYLE_INITS}, got {self.style_init!r}")
        if self.latent_dim % self.num_heads or (self.latent_dim // self.num_heads) % 2:
            raise ValueError("latent_dim / num_heads must be an even integer (rotary embeddings)")


@dataclass(frozen=True, kw_only=True)
class DiffusionConfig:
    timesteps: int = 1000
    cosine_offset: float = 0.008  # s in Nichol & Dhariwal's cosine schedule
    max_beta: float = 0.999
    prediction: str = "x0"  # the network's output: "x0" (EDGE) or "v" (Salimans & Ho 2022; docs/results.md)
    sigma_data: float = 1.0  # with prediction "v": the data's standard deviation the skip assumes (1: plain v)
    snr_gamma: float = 0.0  # > 0: weigh each window's loss by min(SNR(t), snr_gamma) (min-SNR); 0: uniform
    music_dropout: float = 0.25  # classifier-free guidance: music replaced by a learned null
    style_dropout: float = 0.1  # so the model can also dance with no style given
    pace_dropout: float = 0.1  # with a pace condition: so the model can also dance at no pace given
    # Loss weights: x0 reconstruction, velocity, FK joint positions, foot contact. EDGE's, except the x0
    # term at 10 x EDGE's 0.636: the one term on every rotation, so the network reads the limbs (docs/results.md).
    reconstruction_weight: float = 6.36
    velocity_weight: float = 2.964
    joint_weight: float = 0.646
    foot_weight: float = 10.942
    contact_source: str = "predicted"  # contacts that pin the feet: the model's own (EDGE) or the data's ("target")
    stepping_weight: float = 0.0  # the feet's world speeds against the data's, in (m/s)^2 (docs/sgmd.md, "Feet")
    leg_weight: float = 1.0  # the legs' rotation channels' weight inside the reconstruction term
    root_speed_weight: float = 0.0  # the root's horizontal speed against the data's, in (m/s)^2, whatever the direction
    pace_weight: float = 0.0  # each window's pace along its smoothed floor path against the data's, in (m/s)^2
    legs_weight: float = 0.0  # knees, ankles and feet around the pelvis against the data's, weighted by alpha_bar(t)
    legs_speed_weight: float = 0.0  # each window's mean speed of those joints around the pelvis against the data's, (m/s)^2

    def __post_init__(self):
        if self.contact_source not in CONTACT_SOURCES:
            raise ValueError(f"contact_source must be one of {CONTACT_SOURCES}, got {self.contact_source!r}")
        terms = (self.stepping_weight, self.foot_weight, self.root_speed_weight, self.pace_weight, self.legs_weight,
                 self.legs_speed_weight)
        if min(terms) < 0 or self.leg_weight <= 0:
            raise ValueError("foot_weight, stepping_weight, root_speed_weight, pace_weight, legs_weight and "
                             "legs_speed_weight must be >= 0, leg_weight > 0")
        if not 0 < self.sigma_data <= 10:
            raise ValueError(f"sigma_data must be in (0, 10], got {self.sigma_data}")
        if self.snr_gamma < 0:
            raise ValueError(f"snr_gamma must be >= 0, got {self.snr_gamma}")
        if self.prediction not in PREDICTIONS:
            raise ValueError(f"prediction must be one of {PREDICTIONS}, got {self.prediction!r}")
        for name in ("music_dropout", "style_dropout", "pace_dropout"):
            if not 0.0 <= getattr(self, name) < 1.0:
                raise ValueError(f"{name} must be in [0, 1), got {getattr(self, name)}")


@dataclass(frozen=True, kw_only=True)
class TrainConfig:
    batch_size: int = 32
    learning_rate: float = 4e-4
    weight_decay: float = 0.02
    ema_decay: float = 0.999
    max_steps: int = 20_000
    window_stride_seconds: float = 0.5
    validation_every: int = 500
    checkpoint_every: int = 500
    seed: int = 0
    prompt_kind: str = "description"
    num_threads: int = 0  # 0: torch's default
    mirror: bool = False  # also train on every clip's mirror image (off: ballroom is chiral, docs/sgmd.md)
    stretch: tuple[float, ...] = (1.0,)  # also danced at these paces, music along (e.g. 0.85, 1, 1.18; docs/sgmd.md)
    turns: tuple[float, ...] = (0.0,)  # and facing these ways (degrees about the vertical; unmeasured, off)
    genre_balance: float = 0.0  # draw windows with weight (windows of their genre)^-genre_balance (0: uniform)
    held_out: tuple[str, ...] = ()  # train clips left out to validate on (M2D's validation clips; a resume keeps them out)

    def __post_init__(self):
        if self.prompt_kind not in PROMPT_KINDS:
            raise ValueError(f"prompt_kind must be one of {PROMPT_KINDS}, got {self.prompt_kind!r}")
        object.__setattr__(self, "stretch", tuple(float(f) for f in self.stretch))  # lists come back from checkpoints
        object.__setattr__(self, "turns", tuple(float(t) for t in self.turns))
        object.__setattr__(self, "held_out", tuple(str(n) for n in self.held_out))
        if not 0.0 <= self.genre_balance <= 1.0:
            raise ValueError(f"genre_balance must be in [0, 1], got {self.genre_balance}")


PRESETS: dict[str, ModelConfig] = {
    "paper": ModelConfig(),  # latent 512, 8 decoder layers, 8 heads: ~50 M parameters
    "small": ModelConfig(latent_dim=256, ff_dim=512, num_layers=4, num_heads=4, music_layers=1),
    "cpu": ModelConfig(latent_dim=128, ff_dim=256, num_layers=4, num_heads=4, music_layers=1),
    "cpu15": ModelConfig(latent_dim=128, ff_dim=256, num_layers=4, num_heads=4, music_layers=1,
                         window_frames=75, frame_stride=2),  # the cpu preset at 15 fps: 5 s windows, half the frames
    "tiny": ModelConfig(latent_dim=32, ff_dim=64, num_layers=2, num_heads=2, music_layers=1, dropout=0.0),
}


def model_config(name: str, **overrides) -> ModelConfig:
    if name not in PRESETS:
        raise ValueError(f"unknown model configuration {name!r} (known: {', '.join(PRESETS)})")
    return replace(PRESETS[name], **overrides)


def to_dict(config) -> dict:
    return asdict(config)
