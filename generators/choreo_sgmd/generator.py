"""`SGMDGenerator`: a trained checkpoint turned into the core's Generator interface."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import torch

from choreo.constraints import Constraints, parse_style_schedule
from choreo.finishing.pace import target_pace
from choreo.errors import InputError, ParameterError
from choreo.options import parse_options
from choreo.generator import GenerationRequest, Generator
from choreo.generator.checkpoint import damaged_checkpoint
from choreo.motion import Motion, vector_to_motion

from .checkpoint import load_checkpoint
from .config import DiffusionConfig, ModelConfig
from .data import MusicScaler, music_input
from .frame_rate import frames_at_full_rate, known_at_model_rate, music_at_model_rate
from .model import Denoiser
from .normalizer import Normalizer
from .options import GENRE_TRAVEL_GUIDANCE, SamplingOptions
from .sampling import Inpainting, sample_independent, sample_long
from .schedule import NoiseSchedule
from .style import GENRES, Style, resolve_style


def check_weights_fit(config: ModelConfig, weights: dict, where: str = "checkpoint") -> None:
    """Refuse a checkpoint whose configuration and weights disagree, before anything is allocated:
    the model is first laid out on torch's meta device (shapes, no memory), so a forged config
    asking for 2^20-wide layers costs nothing."""
    with torch.device("meta"):
        layout = Denoiser(config).state_dict()
    if not isinstance(weights, dict):
        raise InputError(f"{where}: weights are not a dictionary of tensors")
    missing = sorted(set(layout) - set(weights))
    unexpected = sorted(set(weights) - set(layout))
    wrong = [k for k in layout if k in weights and tuple(getattr(weights[k], "shape", ())) != tuple(layout[k].shape)]
    if missing or unexpected or wrong:
        first = (missing or unexpected or wrong)[0]
        raise InputError(f"{where}: weights do not fit its configuration ({len(missing)} missing, "
                         f"{len(unexpected)} unexpected, {len(wrong)} of the wrong shape, e.g. {first})")


def trained_genres_of(state: dict) -> tuple[str, ...] | None:
    """The genres the checkpoint's training data held (None: not recorded, older checkpoints)."""
    genres = state.get("trained_genres")
    if genres is None:
        return None
    if not isinstance(genres, (list, tuple)) or not all(isinstance(g, str) and g in GENRES for g in genres):
        raise InputError("trained_genres must list known genres")
    return tuple(genres) or None


class SGMDGenerator(Generator):
    name = "sgmd"

    def __init__(self, checkpoint: str | Path, use_ema: bool = True):
        state = load_checkpoint(checkpoint)
        self.checkpoint = Path(checkpoint)
        if not use_ema and "state_dict" not in state:
            raise ParameterError(f"{checkpoint} holds EMA weights only (an inference checkpoint)")
        with damaged_checkpoint(checkpoint, "SGMD checkpoint"):
            self.model_config = ModelConfig(**state["model_config"])
            self.diffusion_config = DiffusionConfig(**state["diffusion_config"])
            self.prompt_kind = state["prompt_kind"]
            weights = state["ema_state_dict" if use_ema else "state_dict"]
            check_weights_fit(self.model_config, weights, str(checkpoint))
            self.schedule = NoiseSchedule(self.diffusion_config)
            self.model = Denoiser(self.model_config, self.diffusion_config.prediction, self.schedule.alphas_cumprod,
                                  self.diffusion_config.sigma_data).eval()
            self.model.load_state_dict(weights)
            self.normalizer = Normalizer.from_state_dict(state["normalizer"])
            self.music_scaler = MusicScaler.from_state_dict(state["music_scaler"])
            self.trained_steps = int(state["step"])
            self.trained_genres = trained_genres_of(state)

    def music_tensor(self, features: np.ndarray) -> torch.Tensor:
        """(..., Tm, music_dim) standardised model input from (..., T, 35) features at 30 fps (per
        window when stacked: rhythm channels are derived from each excerpt's own beats); Tm frames
        at the model's rate."""
        features = np.asarray(features)
        if features.ndim == 3:
            return torch.stack([self.music_tensor(window) for window in features])
        music = music_at_model_rate(music_input(features, self.model_config.music_dim), self.model_config.frame_stride)
        return self.music_scaler(torch.from_numpy(music).float())

    def at_full_rate(self, vectors: np.ndarray, num_frames: int) -> np.ndarray:
        """Sampled frame vectors (..., Tm, D) back at 30 fps, ``num_frames`` of them."""
        return frames_at_full_rate(vectors, self.model_config.frame_stride, num_frames)

    def sampling_options(self, request: GenerationRequest) -> SamplingOptions:
        """The request's options as SamplingOptions (its seed included), the music checked."""
        constrained = request.constraints is not None and not request.constraints.is_empty
        options = parse_options("sgmd", SamplingOptions, request.options).resolved(constrained)
        if request.seed is not None:
            options = replace(options, seed=request.seed)
        try:
            options = options.on_chain(self.diffusion_config.timesteps, request.options.get("steps") is not None)
        except ValueError as error:
            raise ParameterError(f"sgmd: {error}") from None
        if not request.music.timbre:
            raise ParameterError("sgmd reads the music's MFCC and chroma: analyse the song with them "
                                 "(Music.from_file(path), not timbre=False)")
        return options

    def for_genres(self, options: SamplingOptions, genres: list) -> SamplingOptions:
        """The options with what the dance's genres decide, where not given: the share of guidance its
        travel gets (its one genre's, else 1) and, for a pace-conditioned network, the pace it is asked
        for (the real pace of its one genre, of all genres for a free-text style or none; a schedule of
        styles gets none)."""
        genres = list(dict.fromkeys(genres))
        if options.travel_guidance is None:
            share = GENRE_TRAVEL_GUIDANCE.get(genres[0], 1.0) if len(genres) == 1 else 1.0
            options = replace(options, travel_guidance=share)
        if not self.model_config.pace_condition:
            if options.pace is not None:
                raise ParameterError(f"sgmd: {self.checkpoint.name} was not trained with a pace condition")
            return options
        if options.pace is not None or len(genres) > 1:
            return options
        return replace(options, pace=target_pace(genres[0] if genres else None))

    def generate(self, request: GenerationRequest, progress: Callable[[float], None] | None = None) -> Motion:
        options = self.sampling_options(request)
        num_frames = request.music.num_frames
        style, keep_style, genres, notices = self.style_conditioning(request.style, num_frames, request.music.fps)
        options = self.for_genres(options, genres)
        inpainting, known = self.inpainting(request.constraints, num_frames)
        music = self.music_tensor(request.music.features)
        x0, evaluations = sample_long(self.model, self.schedule, music, style, keep_style, self.model_config.frame_dim,
                                      self.model_config.window_frames, options, progress, inpainting)
        vectors = self.at_full_rate(self.normalizer.denormalize(x0).numpy(), num_frames)
        del x0  # an hour's samples: not kept while the motion is built
        if known is not None:  # exact, not merely within float32 normalisation error
            values, mask = known
            vectors[mask] = values[mask]
        motion, _ = vector_to_motion(vectors, fps=request.music.fps)
        del vectors
        motion.metadata = {
            "generator": "sgmd", "checkpoint": self.checkpoint.name, "style": request.style,
            "genre": genres[0] if len(genres) == 1 else (",".join(g or "free text" for g in genres) or None),
            "style_notice": "; ".join(notices) or None, "seed": options.seed, "steps": options.steps,
            "guidance": options.guidance, "style_guidance": options.style_guidance, "travel_guidance": options.travel_guidance,
            "sampler": options.sampler,
            **({"pace_asked": options.pace} if self.model_config.pace_condition else {}),
            "network_evaluations": evaluations,
            "trained_steps": self.trained_steps,
            "constrained_fraction": None if request.constraints is None else round(request.constraints.known_fraction(), 4),
        }  # fmt: skip
        return motion

    def generate_windows(self, requests: Sequence[GenerationRequest]) -> list[Motion]:
        """Every window sampled at once as one batch, each on its own (no stitching: how papers score
        5 s clips). The batch's noise comes from the one seed the requests share; they also share
        options and length, and either all carry constraints or none does. Styles are single
        prompts (no time schedule)."""
        if not requests:
            return []
        first = requests[0]
        if any(r.options != first.options or r.seed != first.seed or r.music.num_frames != first.music.num_frames
               for r in requests):
            raise ParameterError("windows danced as one batch share their options, seed and length")
        if len({r.constraints is None for r in requests}) > 1:
            raise ParameterError("windows danced as one batch are either all constrained or none is")
        options = self.sampling_options(first)
        num_frames = first.music.num_frames
        music = self.music_tensor(np.stack([r.music.features for r in requests]))
        resolved = [self.style_vector(r.style) for r in requests]
        options = self.for_genres(options, [style.genre for _, style in resolved])
        styles = torch.stack([vector for vector, _ in resolved])
        keep_style = torch.tensor([style.vector is not None for _, style in resolved])
        inpainting, known = None, None
        if first.constraints is not None:
            parts = [self.inpainting(r.constraints, num_frames) for r in requests]
            if any(part is None for part, _ in parts):
                raise ParameterError("windows danced as one batch are either all constrained or none is")
            inpainting = Inpainting(torch.stack([p.values for p, _ in parts]), torch.stack([p.mask for p, _ in parts]))
            known = tuple(np.stack(arrays) for arrays in zip(*(k for _, k in parts)))
        x0 = sample_independent(self.model, self.schedule, music, styles, keep_style, self.model_config.frame_dim,
                                options, inpainting)
        vectors = self.at_full_rate(self.normalizer.denormalize(x0).numpy(), num_frames)
        if known is not None:  # exact, as in generate
            values, mask = known
            vectors[mask] = values[mask]
        motions = [vector_to_motion(v, fps=r.music.fps)[0] for v, r in zip(vectors, requests)]
        for motion, (_, style) in zip(motions, resolved):
            motion.metadata = {"generator": "sgmd", "genre": style.genre}  # what finishing reads, as for a whole song
        return motions

    def style_vector(self, prompt: str | None) -> tuple[torch.Tensor, Style]:
        """The (S,) vector the model reads for one prompt (zeros where no style is given) and what it
        resolved to."""
        style = resolve_style(prompt, self.prompt_kind, known=self.trained_genres)
        if style.vector is None:
            return torch.zeros(self.model_config.style_dim), style
        return torch.from_numpy(style.vector).float(), style

    def style_conditioning(self, prompt: str | None, num_frames: int, fps: float):
        """(style (1 or T, S), keep (bool or (T,)), genres, notices) for a prompt or a time schedule."""
        schedule = parse_style_schedule(prompt, num_frames / fps) if prompt else None
        if schedule is None:
            vector, style = self.style_vector(prompt)
            return vector[None], style.vector is not None, [style.genre], [style.notice] if style.notice else []
        stride = self.model_config.frame_stride
        per_frame = torch.zeros(num_frames, self.model_config.style_dim)
        keep = torch.zeros(num_frames, dtype=torch.bool)
        genres, notices = [], []
        for start, stop, text in schedule:
            vector, style = self.style_vector(text)
            frames = slice(round(start * fps), num_frames if stop is None else round(stop * fps))
            if style.vector is not None:
                per_frame[frames] = vector
                keep[frames] = True
            genres.append(style.genre)
            notices += [style.notice] if style.notice else []
        return per_frame[::stride], keep[::stride], genres, notices

    def inpainting(self, constraints: Constraints | None, num_frames: int):
        if constraints is None or constraints.is_empty:
            return None, None
        if constraints.num_frames != num_frames:
            raise ParameterError(f"constraints cover {constraints.num_frames} frames, the song {num_frames}")
        values, mask = constraints.frame_vectors()
        model_values, model_mask = known_at_model_rate(values, mask, self.model_config.frame_stride)
        normalised = self.normalizer.normalize(torch.from_numpy(model_values).float())
        return Inpainting(normalised, torch.from_numpy(model_mask)), (values, mask)
